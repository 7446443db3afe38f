//! `sndt testvector`: write or check the firmware's cross-architecture test vector
//! (`targets/cortex-m4f/vector`, see [`crate::embedded::testvector`]).

use crate::embedded::testvector::{
    generate, parse_crc, run as integrate, summary, write, TestVector,
};
use anyhow::{anyhow, bail, ensure, Context, Result};
use std::path::{Path, PathBuf};

/// Arguments of `sndt testvector`.
#[derive(clap::Args, Clone, Debug)]
#[command(after_help = "Examples:
  sndt testvector --out targets/cortex-m4f/vector
  sndt testvector --check targets/cortex-m4f/vector/frames.bin")]
pub struct TestvectorArgs {
    /// Directory to write frames.bin and expected_crc.txt into.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// A vector to integrate and check (against expected_crc.txt beside it).
    #[arg(long)]
    pub check: Option<PathBuf>,
}

/// Runs `sndt testvector` and prints the summary.
pub fn run(a: &TestvectorArgs) -> Result<()> {
    println!("{}", testvector(a.out.as_deref(), a.check.as_deref())?);
    Ok(())
}

/// `--out DIR` writes `DIR/frames.bin` and `DIR/expected_crc.txt`; `--check FILE`
/// integrates a vector and returns the summary (last line `crc 0x........`), failing when
/// `expected_crc.txt` or `expected_render_crc.txt` beside it is missing or disagrees, or a
/// probe misses.
pub fn testvector(out: Option<&Path>, check: Option<&Path>) -> Result<String> {
    match (out, check) {
        (Some(dir), None) => write_vector(dir),
        (None, Some(file)) => check_vector(file),
        _ => bail!("give exactly one of --out DIR or --check FILE"),
    }
}

/// Writes the vector into `dir`; the summary ends with the two files written.
fn write_vector(dir: &Path) -> Result<String> {
    let r = write(dir)?;
    let v = generate();
    Ok(format!(
        "{}wrote {} and {}",
        summary(&v, &r),
        dir.join("frames.bin").display(),
        dir.join("expected_crc.txt").display()
    ))
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
