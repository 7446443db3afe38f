//! `sndt points`: the sensor origin and world points of a dataset's frames (all, or those
//! `--frames` selects) as a raw binary file, the input `scripts/bench-peers.sh` gives
//! OctoMap.
//!
//! The file (little-endian; [`crate::output::points`] has the details): magic
//! `SNDTPTS1`, `u32` frame count, then per frame `3 x f32` sensor origin, `u32` point
//! count `n` and `n x 3 x f32` world points, one per measured pixel (row-major), as
//! the core integrates them (`frame.pose * depth_point`, in `f32`; points beyond
//! `max_range` kept).

use crate::cli::open_args::{FramesArgs, OpenArgs};
use crate::dataset::open::open_spec;
use crate::output::points::write_points;
use anyhow::Result;
use std::path::PathBuf;

/// Arguments of `sndt points`.
#[derive(clap::Args, Clone, Debug)]
#[command(after_help = "Example:
  sndt points data/synth --frames 0..12 --points-file out/points.bin")]
pub struct PointsArgs {
    /// Dataset: a directory (prepared layout or raw Hypersim), a ROS 2 bag (`.mcap` file or rosbag2 folder),
    /// `synthetic[:SCENES:FRAMES]` or `synthetic:floor[:WALK[:FRAMES]]` (rendered on the
    /// fly).
    pub dataset: String,
    /// Output points file (`SNDTPTS1` format).
    #[arg(long, value_name = "FILE")]
    pub points_file: PathBuf,
    /// Which frames of the dataset.
    #[command(flatten)]
    pub frames: FramesArgs,
    /// How to open the dataset.
    #[command(flatten)]
    pub open: OpenArgs,
}

/// Runs `sndt points` and prints what it wrote.
pub fn run(a: &PointsArgs) -> Result<()> {
    let data = open_spec(&a.dataset, &a.open.options()?)?;
    let all = data.frames();
    let ids = &all[a.frames.range(all.len())?];
    println!("{}", write_points(data.as_ref(), ids, &a.points_file)?);
    Ok(())
}
