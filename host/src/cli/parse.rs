//! Value parsers for options, so that a bad value is refused where it is parsed, with the
//! option's name and the reason (clap prints `invalid value 'X' for '--cell <CELL>': ...`
//! and exits with status 2).

/// A finite number greater than 0 (sizes, lengths, standard deviations).
///
/// ```
/// use sndt_host::cli::parse::positive;
/// assert_eq!(positive("0.1"), Ok(0.1));
/// for bad in ["0", "-3", "NaN", "inf", "x"] {
///     assert!(positive(bad).is_err(), "{bad}");
/// }
/// ```
pub fn positive(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        Ok(_) => Err("must be a finite number > 0".into()),
        Err(_) => Err("not a number".into()),
    }
}

/// A finite number of at least 0 (tolerances).
///
/// ```
/// use sndt_host::cli::parse::non_negative;
/// assert_eq!(non_negative("0"), Ok(0.0));
/// assert!(non_negative("-0.5").is_err() && non_negative("inf").is_err());
/// ```
pub fn non_negative(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        Ok(_) => Err("must be a finite number >= 0".into()),
        Err(_) => Err("not a number".into()),
    }
}

/// A whole number of at least 1 (counts of frames).
///
/// ```
/// use sndt_host::cli::parse::at_least_one;
/// assert_eq!(at_least_one("3"), Ok(3));
/// assert!(at_least_one("0").is_err() && at_least_one("-1").is_err());
/// ```
pub fn at_least_one(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(v) if v >= 1 => Ok(v),
        Ok(_) => Err("must be at least 1, not 0".into()),
        Err(_) => Err("not a whole number >= 1".into()),
    }
}

/// Parses `--frames` ([`super::open_args::FramesArgs`]): `N` = the first N (`0..N`), `A..B`, or
/// `A..` (to the end), within `0..len`; `None` (option not given) is all frames.
///
/// ```
/// use sndt_host::cli::parse::frame_range;
/// assert_eq!(frame_range(Some("20"), 100).unwrap(), 0..20);
/// assert_eq!(frame_range(Some("10..30"), 100).unwrap(), 10..30);
/// assert_eq!(frame_range(Some("90.."), 100).unwrap(), 90..100);
/// assert_eq!(frame_range(None, 100).unwrap(), 0..100);
/// assert!(frame_range(Some("30..10"), 100).is_err());
/// assert!(frame_range(Some("200"), 100).is_err());
/// ```
pub fn frame_range(spec: Option<&str>, len: usize) -> anyhow::Result<std::ops::Range<usize>> {
    use anyhow::Context;
    let parse = |s: &str| -> anyhow::Result<usize> {
        s.trim()
            .parse()
            .with_context(|| format!("--frames: {s:?} is not a frame number"))
    };
    let range = match spec {
        None => 0..len,
        Some(s) => match s.split_once("..") {
            None => 0..parse(s)?,
            Some((a, b)) if b.trim().is_empty() => parse(a)?..len,
            Some((a, b)) => parse(a)?..parse(b)?,
        },
    };
    if range.start >= range.end || range.end > len {
        anyhow::bail!(
            "--frames {}: need a non-empty range within the {len} frames",
            spec.unwrap_or("")
        );
    }
    Ok(range)
}

/// Checks a config built from options, naming the option behind a refused field:
/// `options` pairs each field an option sets with the option as typed (`--cell 0.001`).
/// A field no option sets is named as the field.
///
/// ```
/// use sndt_core::{Config, ConfigField};
/// use sndt_host::cli::parse::check_config;
/// let fields = [(ConfigField::CellSize, "--cell 0.001"), (ConfigField::RayCells, "--cell 0.001")];
/// let e = check_config(&Config::with_cell_size(0.001), &fields).unwrap_err();
/// assert_eq!(
///     e.to_string(),
///     "--cell 0.001: invalid config: max_range / cell_size must be at most 4096 cells \
///      (one ray's length in voxels); max_range 20 m is 20000 cells of 0.001 m"
/// );
/// assert!(check_config(&Config::DEFAULT, &fields).is_ok());
/// ```
pub fn check_config(
    config: &sndt_core::Config,
    options: &[(sndt_core::ConfigField, &str)],
) -> anyhow::Result<()> {
    use sndt_core::{ConfigField, Error};
    let Err(e) = config.validate() else {
        return Ok(());
    };
    let Error::InvalidConfig(field) = e else {
        anyhow::bail!("config: {e}");
    };
    let detail = match field {
        ConfigField::RayCells => format!(
            "; max_range {} m is {:.0} cells of {} m",
            config.max_range,
            config.max_range / config.cell_size,
            config.cell_size
        ),
        _ => String::new(),
    };
    match options.iter().find(|(f, _)| *f == field) {
        Some((_, option)) => anyhow::bail!("{option}: {e}{detail}"),
        None => anyhow::bail!("config: {e}{detail}"),
    }
}

/// [`check_config`] for a config whose cell size comes from `--cell`: the option is named
/// for the cell size and for the ray length in cells (which the cell size sets).
///
/// ```
/// use sndt_core::Config;
/// use sndt_host::cli::parse::check_cell_config;
/// let e = check_cell_config(&Config::with_cell_size(0.0), 0.0).unwrap_err();
/// assert!(e.to_string().starts_with("--cell 0: invalid config: cell_size"));
/// assert!(check_cell_config(&Config::with_cell_size(0.1), 0.1).is_ok());
/// ```
pub fn check_cell_config(config: &sndt_core::Config, cell: f32) -> anyhow::Result<()> {
    use sndt_core::ConfigField;
    let option = format!("--cell {cell}");
    check_config(
        config,
        &[
            (ConfigField::CellSize, &option),
            (ConfigField::RayCells, &option),
        ],
    )
}
