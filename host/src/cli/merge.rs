//! `sndt merge`: merges saved maps and record streams into one map.

use crate::mapping::{check_stream, GlobalMap};
use anyhow::{bail, Context, Result};
use std::path::PathBuf;

/// Arguments of `sndt merge`.
#[derive(clap::Args, Clone, Debug)]
#[command(after_help = "Examples:
  sndt merge out/a/maps/floor.sndt out/b/maps/floor.sndt --sndt out/both.sndt
  sndt merge uart.bin --sndt out/device.sndt")]
pub struct MergeArgs {
    /// Map snapshots (`.sndt`, as `sndt map --save-maps` writes) or record streams (the
    /// COBS-framed records a device sends over a UART), merged in this order. All must
    /// have the same config.
    #[arg(required = true, num_args = 1..)]
    pub inputs: Vec<PathBuf>,
    /// Output map snapshot file (`.sndt`) of the merged map.
    #[arg(long)]
    pub sndt: PathBuf,
}

/// Runs `sndt merge`: reads and checks every input, merges them in order into a map that
/// grows as needed, writes the snapshot and prints its counts and CRC.
pub fn run(a: &MergeArgs) -> Result<()> {
    let mut merged: Option<GlobalMap> = None;
    for path in &a.inputs {
        let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
        let what = |e: anyhow::Error| e.context(path.display().to_string());
        if bytes.starts_with(b"SNDT") {
            let map = GlobalMap::from_snapshot(&bytes).map_err(what)?;
            println!(
                "{}: map of {} voxels, {} blocks, {} frames",
                path.display(),
                map.len(),
                map.block_count(),
                map.frames()
            );
            match merged.as_mut() {
                None => merged = Some(map),
                Some(m) => m.merge_global(&map).map_err(what)?,
            }
        } else {
            let stream = check_stream(&bytes).map_err(|e| what(e.into()))?;
            println!(
                "{}: record stream of {} voxel and {} block records, {} frames (sender's map CRC 0x{:08x}, {} records dropped)",
                path.display(),
                stream.voxels,
                stream.blocks,
                stream.end.frames,
                stream.end.checksum,
                stream.end.dropped
            );
            if merged.is_none() {
                merged = Some(GlobalMap::new(stream.header.config).map_err(what)?);
            }
            if let Some(m) = merged.as_mut() {
                m.merge_stream(&bytes).map_err(|e| what(e.into()))?;
            }
        }
    }
    let Some(map) = merged else {
        bail!("nothing to merge");
    };
    crate::atomic::write_bytes(&a.sndt, map.snapshot()?)?;
    println!(
        "merged: {} voxels, {} blocks, {} frames; map of tier {} ({:.0} MiB); crc 0x{:08x}; wrote {}",
        map.len(),
        map.block_count(),
        map.frames(),
        map.tier(),
        map.memory_bytes() as f64 / (1 << 20) as f64,
        map.checksum(),
        a.sndt.display()
    );
    Ok(())
}
