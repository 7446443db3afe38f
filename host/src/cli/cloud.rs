//! `sndt cloud`: one frame's world points, coloured by label, as a PLY point cloud.

use crate::cli::open_args::OpenArgs;
use crate::dataset::frame::FrameId;
use crate::dataset::open::open_spec;
use crate::dataset::source::OpenOptions;
use crate::output::ply::{write_frame_cloud, CloudSummary};
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

/// Arguments of `sndt cloud`.
#[derive(clap::Args, Clone, Debug)]
#[command(after_help = "Examples:
  sndt cloud data/synth --frame synth_00_living/cam_00/0000 --ply out/frame.ply
  sndt cloud robot.mcap --world-frame odom --frame robot/cam_00/0010 --ply out/frame.ply")]
pub struct CloudArgs {
    /// Dataset: a directory (prepared layout or raw Hypersim), a ROS 2 bag (`.mcap` file or rosbag2 folder),
    /// `synthetic[:SCENES:FRAMES]` or `synthetic:floor[:WALK[:FRAMES]]` (rendered on the
    /// fly).
    pub dataset: String,
    /// The frame, as `<scene>/<cam>/<NNNN>`.
    #[arg(long)]
    pub frame: String,
    /// Output PLY file.
    #[arg(long)]
    pub ply: PathBuf,
    /// How to open the dataset.
    #[command(flatten)]
    pub open: OpenArgs,
}

/// Runs `sndt cloud` and prints what it wrote.
pub fn run(a: &CloudArgs) -> Result<()> {
    let root = Path::new(&a.dataset);
    println!("{}", cloud(root, &a.frame, &a.ply, &a.open.options()?)?);
    Ok(())
}

/// Opens the dataset `root` ([`open_spec`]: a directory, a bag or `synthetic[:S:F]`), loads frame `frame` (`scene/cam/NNNN`) and
/// writes its coloured world points to `out` ([`write_frame_cloud`]), creating `out`'s
/// directory.
pub fn cloud(root: &Path, frame: &str, out: &Path, options: &OpenOptions) -> Result<CloudSummary> {
    let data = open_spec(&root.to_string_lossy(), options)?;
    let id = FrameId::parse(frame)?;
    let frame = data
        .load(&id)
        .with_context(|| format!("loading frame {id} of {}", root.display()))?;
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    write_frame_cloud(&frame, out)
}
