//! The options commands share, each declared once here so that it is spelled, documented
//! and checked the same way in every command that has it.
//!
//! Every command that takes a dataset flattens [`OpenArgs`]: how to open a directory
//! ([`LayoutArgs`]: `--split`, `--paper-fy`) and a ROS 2 bag ([`BagArgs`]: topics, world
//! frame, label map, sync tolerance). `sndt info` reads bags only and flattens
//! [`BagArgs`] alone. The commands that can map predicted labels add
//! [`PredictionsArgs`] (`--predictions`). Which frames and pixels to use: [`EveryArgs`]
//! (`--every`), [`FramesArgs`] (`--frames`), [`StrideArgs`] (`--stride`).

use crate::dataset::source::{BagOptions, Dataset, Every, OpenOptions};
use std::ops::Range;
use std::path::PathBuf;

/// How to open a dataset: a directory's options and a bag's (shared by every command that
/// takes a dataset).
#[derive(clap::Args, Clone, Debug, Default)]
pub struct OpenArgs {
    /// How to open a directory.
    #[command(flatten)]
    pub layout: LayoutArgs,
    /// How to open a ROS 2 bag.
    #[command(flatten)]
    pub bag: BagArgs,
}

impl OpenArgs {
    /// The options the dataset readers take, without predictions.
    pub fn options(&self) -> anyhow::Result<OpenOptions> {
        self.options_with(&PredictionsArgs::default())
    }

    /// The options the dataset readers take, with the predictions `predictions` names.
    pub fn options_with(&self, predictions: &PredictionsArgs) -> anyhow::Result<OpenOptions> {
        Ok(OpenOptions {
            split: Some(self.layout.split.clone()),
            paper_fy: self.layout.paper_fy,
            predictions: predictions.predictions.clone(),
            bag: self.bag.options()?,
        })
    }
}

/// How to open a dataset directory (prepared layout or raw Hypersim).
#[derive(clap::Args, Clone, Debug)]
pub struct LayoutArgs {
    /// Split of the prepared layout.
    #[arg(long, default_value = "test")]
    pub split: String,
    /// Use the authors' v0.3.1 fy = 927.06 (prepared layout without intrinsics).
    #[arg(long)]
    pub paper_fy: bool,
}

impl Default for LayoutArgs {
    /// The command line's defaults.
    fn default() -> Self {
        LayoutArgs {
            split: "test".into(),
            paper_fy: false,
        }
    }
}

/// Where a dataset directory's predicted labels are (for the commands that can map them).
#[derive(clap::Args, Clone, Debug, Default)]
pub struct PredictionsArgs {
    /// Directory of ESANet `.npy` predictions.
    #[arg(long)]
    pub predictions: Option<PathBuf>,
}

/// How to read a ROS 2 bag: its topics, world frame, label map and sync tolerance.
#[derive(clap::Args, Clone, Debug)]
pub struct BagArgs {
    /// ROS 2 bag: frame the camera poses are in (and the frame a map bag written with
    /// `--mcap` is attached to).
    #[arg(long, default_value = "world")]
    pub world_frame: String,
    /// ROS 2 bag: depth topic (default: the 16UC1 / 32FC1 image topic).
    #[arg(long)]
    pub depth_topic: Option<String>,
    /// ROS 2 bag: labels topic (default: the mono8 / 8UC1 image topic, if any).
    #[arg(long)]
    pub labels_topic: Option<String>,
    /// ROS 2 bag: pose topic (PoseStamped of the depth camera, or Odometry of a body that
    /// /tf_static links to the camera) instead of /tf.
    #[arg(long)]
    pub pose_topic: Option<String>,
    /// ROS 2 bag: CSV of `id,class` lines mapping the bag's label ids to NYU40 classes
    /// (ids not listed become void, 0).
    #[arg(long)]
    pub label_map: Option<PathBuf>,
    /// ROS 2 bag: camera-info topic (default: the one in the depth image's frame).
    #[arg(long)]
    pub camera_info_topic: Option<String>,
    /// ROS 2 bag: largest stamp difference (seconds) of labels or camera info paired with a
    /// depth image (0: exact stamps).
    #[arg(long, default_value_t = 0.0, value_parser = super::parse::non_negative)]
    pub sync_tolerance: f64,
}

impl Default for BagArgs {
    /// The command line's defaults.
    fn default() -> Self {
        BagArgs {
            world_frame: "world".into(),
            depth_topic: None,
            labels_topic: None,
            pose_topic: None,
            label_map: None,
            camera_info_topic: None,
            sync_tolerance: 0.0,
        }
    }
}

impl BagArgs {
    /// The options the bag reader takes (reading the `--label-map` file).
    pub fn options(&self) -> anyhow::Result<BagOptions> {
        let label_map = match &self.label_map {
            Some(path) => read_label_map(path)?,
            None => Vec::new(),
        };
        Ok(BagOptions {
            world_frame: Some(self.world_frame.clone()),
            pose_topic: self.pose_topic.clone(),
            label_map,
            depth_topic: self.depth_topic.clone(),
            labels_topic: self.labels_topic.clone(),
            camera_info_topic: self.camera_info_topic.clone(),
            sync_tolerance_ns: (self.sync_tolerance.max(0.0) * 1e9) as u64,
        })
    }
}

/// Which frames of a dataset to map: every k-th of each trajectory.
#[derive(clap::Args, Clone, Debug)]
pub struct EveryArgs {
    /// Use every k-th frame of each trajectory (frames 0, k, 2k, ...; 1 = all, as the
    /// paper).
    #[arg(long, value_name = "K", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub every: u32,
}

impl EveryArgs {
    /// `dataset`, or every k-th frame of it ([`Every`]) with `--every` above 1.
    ///
    /// ```
    /// use sndt_host::cli::open_args::EveryArgs;
    /// let d = sndt_host::dataset::open_spec("synthetic:1:6", &Default::default()).unwrap();
    /// assert_eq!(EveryArgs { every: 2 }.apply(d).frames().len(), 3);
    /// ```
    pub fn apply(&self, dataset: Box<dyn Dataset>) -> Box<dyn Dataset> {
        if self.every > 1 {
            Box::new(Every::new(dataset, self.every))
        } else {
            dataset
        }
    }
}

/// Which frames to use, as a range of the frames in the order they are used.
#[derive(clap::Args, Clone, Debug)]
pub struct FramesArgs {
    /// Which frames, counted from 0 in the order they are used (trajectory, then index):
    /// `N` (the first N), `A..B` or `A..` (default: all).
    #[arg(long, value_name = "N|A..B")]
    pub frames: Option<String>,
}

impl FramesArgs {
    /// The range `--frames` selects of `len` frames ([`super::parse::frame_range`]).
    ///
    /// ```
    /// use sndt_host::cli::open_args::FramesArgs;
    /// assert_eq!(FramesArgs { frames: Some("2..5".into()) }.range(10).unwrap(), 2..5);
    /// assert_eq!(FramesArgs { frames: None }.range(10).unwrap(), 0..10);
    /// ```
    pub fn range(&self, len: usize) -> anyhow::Result<Range<usize>> {
        super::parse::frame_range(self.frames.as_deref(), len)
    }
}

/// Which pixels of a frame to integrate.
#[derive(clap::Args, Clone, Debug)]
pub struct StrideArgs {
    /// Use every stride-th pixel in both directions of each frame integrated (1 = all, as
    /// the paper).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub stride: u32,
}

/// Reads a label map: `id,class` lines (both 0..=255; `#` comments and blank lines
/// ignored).
///
/// ```
/// let p = std::env::temp_dir().join(format!("sndt-labelmap-{}.csv", std::process::id()));
/// std::fs::write(&p, "# cityscapes-like ids\n7,2\n11, 1\n").unwrap();
/// assert_eq!(sndt_host::cli::open_args::read_label_map(&p).unwrap(), vec![(7, 2), (11, 1)]);
/// std::fs::write(&p, "7;2\n").unwrap();
/// assert!(sndt_host::cli::open_args::read_label_map(&p).is_err());
/// ```
pub fn read_label_map(path: &std::path::Path) -> anyhow::Result<Vec<(u8, u8)>> {
    use anyhow::Context;
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let mut map = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let pair = line
            .split_once(',')
            .and_then(|(a, b)| Some((a.trim().parse::<u8>().ok()?, b.trim().parse::<u8>().ok()?)));
        let (id, class) = pair.with_context(|| {
            format!(
                "{} line {}: expected `id,class` with both in 0..=255, got {line:?}",
                path.display(),
                n + 1
            )
        })?;
        map.push((id, class));
    }
    Ok(map)
}

#[cfg(test)]
mod tests {
    use super::{OpenArgs, PredictionsArgs};
    use clap::Parser;

    /// A command line of nothing but the shared dataset options.
    #[derive(Parser)]
    struct Probe {
        #[command(flatten)]
        open: OpenArgs,
        #[command(flatten)]
        predictions: PredictionsArgs,
    }

    /// `Default` (what library callers and doctests use) is what the command line gives when
    /// no option is set: the two are written separately, so they are compared here.
    #[test]
    fn defaults_are_the_command_lines() {
        let parsed = Probe::parse_from(["probe"]);
        assert_eq!(
            format!("{:?}", parsed.open),
            format!("{:?}", OpenArgs::default())
        );
        assert_eq!(
            format!("{:?}", parsed.predictions),
            format!("{:?}", PredictionsArgs::default())
        );
    }
}
