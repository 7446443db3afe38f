//! `sndt testvector`: write or check the firmware's cross-architecture test vector
//! (`targets/cortex-m4f/vector`, see [`crate::embedded::testvector`]), run its spill run or
//! merge the firmware's record stream of it ([`crate::embedded::spill`]).

use crate::embedded::spill;
use crate::embedded::testvector::{
    generate, parse_crc, run as integrate, summary, write, TestVector,
};
use anyhow::{anyhow, bail, ensure, Context, Result};
use std::path::{Path, PathBuf};

/// Arguments of `sndt testvector`.
#[derive(clap::Args, Clone, Debug)]
#[command(after_help = "Examples:
  sndt testvector --out targets/cortex-m4f/vector
  sndt testvector --check targets/cortex-m4f/vector/frames.bin
  sndt testvector --spill targets/cortex-m4f/vector/frames.bin
  sndt testvector --merge-stream uart.bin")]
pub struct TestvectorArgs {
    /// Directory to write frames.bin and its expected_*crc.txt files into.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// A vector to integrate and check (against expected_crc.txt beside it).
    #[arg(long)]
    pub check: Option<PathBuf>,
    /// A vector to run the spill run on: the firmware's map at 9 cm cells, every evicted
    /// record merged into a larger map (checked against expected_spill_crc.txt beside it).
    #[arg(long)]
    pub spill: Option<PathBuf>,
    /// The firmware's record stream (its UART output) to check and merge into a larger map.
    #[arg(long, value_name = "FILE")]
    pub merge_stream: Option<PathBuf>,
}

/// Runs `sndt testvector` and prints the summary.
pub fn run(a: &TestvectorArgs) -> Result<()> {
    println!("{}", testvector(a)?);
    Ok(())
}

/// `--out DIR` writes `DIR/frames.bin` and its expected CRCs; `--check FILE` integrates a
/// vector and returns the summary (last line `crc 0x........`), failing when
/// `expected_crc.txt` or `expected_render_crc.txt` beside it is missing or disagrees, or a
/// probe misses; `--spill FILE` runs the spill run (last line `spill crc 0x........`),
/// failing when `expected_spill_crc.txt` beside it is missing or disagrees;
/// `--merge-stream FILE` checks and merges a record stream (last line `spill crc`).
pub fn testvector(a: &TestvectorArgs) -> Result<String> {
    match (&a.out, &a.check, &a.spill, &a.merge_stream) {
        (Some(dir), None, None, None) => write_vector(dir),
        (None, Some(file), None, None) => check_vector(file),
        (None, None, Some(file), None) => spill_vector(file),
        (None, None, None, Some(file)) => merge_stream(file),
        _ => bail!(
            "give exactly one of --out DIR, --check FILE, --spill FILE or --merge-stream FILE"
        ),
    }
}

/// Writes the vector and its expected CRCs (the spill run's too) into `dir`; the summary
/// ends with the files written.
fn write_vector(dir: &Path) -> Result<String> {
    let r = write(dir)?;
    let v = generate();
    let spill_run = spill::own_run(&v)?;
    let txt = dir.join(SPILL_CRC_FILE);
    crate::atomic::write_bytes(&txt, format!("{:#010x}\n", spill_run.global.2))?;
    Ok(format!(
        "{}{}wrote {}, {} and {}",
        summary(&v, &r),
        spill::summary(&spill_run),
        dir.join("frames.bin").display(),
        dir.join("expected_crc.txt").display(),
        txt.display()
    ))
}

/// The spill run's expected CRC, beside the vector.
const SPILL_CRC_FILE: &str = "expected_spill_crc.txt";

/// Runs the spill run on the vector in `file` and checks its CRC against
/// `expected_spill_crc.txt` beside it.
fn spill_vector(file: &Path) -> Result<String> {
    let shown = file.display();
    let bytes = std::fs::read(file).with_context(|| format!("reading {shown}"))?;
    let v = TestVector::parse(&bytes).map_err(|e| anyhow!("{shown}: {e:#}"))?;
    let txt = file.with_file_name(SPILL_CRC_FILE);
    let text = std::fs::read_to_string(&txt).with_context(|| {
        format!(
            "reading {}: the expected spill CRC of {shown} (written by --out)",
            txt.display()
        )
    })?;
    let want = parse_crc(&text).map_err(|e| anyhow!("{}: {e:#}", txt.display()))?;
    let r = spill::own_run(&v).map_err(|e| anyhow!("{shown}: {e:#}"))?;
    let s = spill::summary(&r);
    ensure!(
        r.global.2 == want,
        "{s}{shown}: spill CRC {:#010x} differs from {} ({want:#010x})",
        r.global.2,
        txt.display()
    );
    Ok(s.trim_end().to_string())
}

/// Checks the record stream in `file` whole, then merges it into a global map.
fn merge_stream(file: &Path) -> Result<String> {
    let shown = file.display();
    let bytes = std::fs::read(file).with_context(|| format!("reading {shown}"))?;
    let (global, s) = spill::merge_stream(&bytes).map_err(|e| anyhow!("{shown}: {e}"))?;
    Ok(spill::stream_summary(&global, &s).trim_end().to_string())
}

/// Integrates the vector in `file` and checks its probes and its snapshot and render CRCs
/// against `expected_crc.txt` and `expected_render_crc.txt` beside it (both written by
/// `--out`). A missing or unreadable CRC file, a probe that misses and a CRC that differs
/// are errors; every error names the file it concerns.
fn check_vector(file: &Path) -> Result<String> {
    let shown = file.display();
    let bytes = std::fs::read(file).with_context(|| format!("reading {shown}"))?;
    let v = TestVector::parse(&bytes).map_err(|e| anyhow!("{shown}: {e:#}"))?;
    let expected = [
        ("expected_crc.txt", "snapshot"),
        ("expected_render_crc.txt", "render"),
    ]
    .map(|(name, what)| (file.with_file_name(name), what));
    for (txt, what) in &expected {
        ensure!(
            txt.is_file(),
            "{}: no such file: the expected {what} CRC of {shown} (written by --out) is needed to check it",
            txt.display()
        );
    }
    let r = integrate(&v).map_err(|e| anyhow!("{shown}: {e:#}"))?;
    let s = summary(&v, &r);
    if let Some(p) = r.probes.iter().find(|p| !p.ok()) {
        bail!("{s}{shown}: probe {:?} is wrong", p.pixel);
    }
    for ((txt, what), got) in expected.iter().zip([r.crc, r.view.crc]) {
        let text =
            std::fs::read_to_string(txt).with_context(|| format!("reading {}", txt.display()))?;
        let want = parse_crc(&text).map_err(|e| anyhow!("{}: {e:#}", txt.display()))?;
        ensure!(
            want == got,
            "{s}{shown}: {what} CRC {got:#010x} differs from {} ({want:#010x})",
            txt.display()
        );
    }
    Ok(s.trim_end().to_string())
}
