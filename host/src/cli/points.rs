//! `sndt points`: the sensor origin and world points of a dataset's first frames as a raw
//! binary file, the input `scripts/bench-peers.sh` gives OctoMap.
//!
//! The file (little-endian; [`crate::output::points`] has the details): magic
//! `SNDTPTS1`, `u32` frame count, then per frame `3 x f32` sensor origin, `u32` point
//! count `n` and `n x 3 x f32` world points, one per measured pixel (row-major), as
//! the core integrates them (`frame.pose * depth_point`, in `f32`; points beyond
//! `max_range` kept).

use crate::cli::open_args::OpenArgs;
use crate::dataset::open::open_spec;
use crate::output::points::write_points;
use anyhow::Result;
use std::path::PathBuf;

/// Arguments of `sndt points`.
#[derive(clap::Args, Clone, Debug)]
pub struct PointsArgs {
    /// Dataset directory (prepared layout or raw Hypersim), or `synthetic[:SCENES:FRAMES]`.
    pub dataset: String,
    /// Output file (`SNDTPTS1` format).
    #[arg(long)]
    pub out: PathBuf,
    /// Export only the first N frames in dataset order (trajectory, then index); default:
    /// every frame.
    #[arg(long)]
    pub frames: Option<usize>,
    /// How to open the dataset.
    #[command(flatten)]
    pub open: OpenArgs,
}

/// Runs `sndt points` and prints what it wrote.
pub fn run(a: &PointsArgs) -> Result<()> {
    let data = open_spec(&a.dataset, &a.open.options()?)?;
    let all = data.frames();
    let ids = &all[..a.frames.unwrap_or(all.len()).min(all.len())];
    println!("{}", write_points(data.as_ref(), ids, &a.out)?);
    Ok(())
}
