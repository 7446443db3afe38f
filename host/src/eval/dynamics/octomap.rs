//! OctoMap's side of the dynamics report: liboctomap's `OcTree` with its default sensor
//! model, run by `scripts/octomap/octomap_dynamics.cpp` on the world points sndt
//! integrates, read at the same voxels after every frame.
//!
//! The query file (`SNDTQRY1`, little-endian): magic, `u32` count `m`, then `m` voxel
//! centres as `3 x f32` world metres. The program answers with a header line and one
//! line of `m` characters per frame: `1` occupied, `0` free, `?` unknown.

use crate::atomic::write_atomic;
use anyhow::{bail, Context, Result};
use sndt_core::VoxelKey;
use std::path::Path;
use std::process::Command;

/// The query file's magic.
const MAGIC: &[u8; 8] = b"SNDTQRY1";

/// Writes the centres of `keys` (cell `cell`) as a query file.
///
/// ```
/// let path = std::env::temp_dir().join(format!("sndt-q-{}.bin", std::process::id()));
/// let k = sndt_core::VoxelKey { x: 1, y: -1, z: 0 };
/// sndt_host::eval::dynamics::octomap::write_queries(&path, &[k], 0.1).unwrap();
/// let bytes = std::fs::read(&path).unwrap();
/// assert_eq!(&bytes[..12], b"SNDTQRY1\x01\0\0\0");
/// assert_eq!(f32::from_le_bytes(bytes[12..16].try_into().unwrap()), 0.15);
/// # std::fs::remove_file(&path).unwrap();
/// ```
pub fn write_queries(path: &Path, keys: &[VoxelKey], cell: f32) -> Result<()> {
    let count = u32::try_from(keys.len()).context("too many queries")?;
    let mut bytes = MAGIC.to_vec();
    bytes.extend_from_slice(&count.to_le_bytes());
    for k in keys {
        for v in k.center(cell) {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    write_atomic(path, |tmp| {
        std::fs::write(tmp, &bytes).with_context(|| format!("{}: writing", tmp.display()))
    })
}

/// Runs `tool` on the points file `points` and the queries `queries` at `cell`, writing
/// its answer to `out`, and returns whether each query was occupied after each frame.
pub fn run(
    tool: &Path,
    points: &Path,
    queries: &Path,
    cell: f32,
    out: &Path,
) -> Result<Vec<Vec<bool>>> {
    let status = Command::new(tool)
        .arg(points)
        .arg(queries)
        .arg(cell.to_string())
        .arg(out)
        .status()
        .with_context(|| format!("running {}", tool.display()))?;
    if !status.success() {
        bail!("{} failed ({status})", tool.display());
    }
    let text =
        std::fs::read_to_string(out).with_context(|| format!("{}: reading", out.display()))?;
    parse(&text).with_context(|| format!("{}", out.display()))
}

/// Reads the program's answer: after each frame, whether each query was occupied.
///
/// ```
/// let text = "octomap_dynamics cell=0.1 frames=2 queries=3\n1?0\n001\n";
/// let t = sndt_host::eval::dynamics::octomap::parse(text).unwrap();
/// assert_eq!(t, [[true, false, false], [false, false, true]]);
/// assert!(sndt_host::eval::dynamics::octomap::parse("octomap_dynamics cell=0.1 frames=1 queries=2\n1\n").is_err());
/// ```
pub fn parse(text: &str) -> Result<Vec<Vec<bool>>> {
    let mut lines = text.lines();
    let header = lines.next().unwrap_or_default();
    let field = |name: &str| -> Result<usize> {
        let value = header
            .split_whitespace()
            .find_map(|w| w.strip_prefix(name)?.strip_prefix('='));
        let value = value.with_context(|| format!("header {header:?}: no {name}"))?;
        value
            .parse()
            .with_context(|| format!("header {header:?}: {name}"))
    };
    if !header.starts_with("octomap_dynamics ") {
        bail!("not an octomap_dynamics answer: {header:?}");
    }
    let (frames, queries) = (field("frames")?, field("queries")?);
    let rows: Vec<Vec<bool>> = lines
        .map(|l| {
            if l.len() != queries || !l.bytes().all(|c| matches!(c, b'0' | b'1' | b'?')) {
                bail!(
                    "a frame's line of {} characters, not {queries} of 0, 1, ?",
                    l.len()
                );
            }
            Ok(l.bytes().map(|c| c == b'1').collect())
        })
        .collect::<Result<_>>()?;
    if rows.len() != frames {
        bail!("{} frames, the header says {frames}", rows.len());
    }
    Ok(rows)
}
