//! The dataset options commands share: how to open a dataset ([`OpenArgs`]: `--split`,
//! `--paper-fy`, `--predictions`, and for ROS 2 bags the topics, world frame and sync
//! tolerance) and which of its frames to map ([`EveryArgs`]: `--every`).

use crate::dataset::source::{Dataset, Every, OpenOptions};
use std::path::PathBuf;

/// How to open a dataset directory (shared by `map`, `export`, `experiment`, `points` and
/// `info`).
#[derive(clap::Args, Clone, Debug)]
pub struct OpenArgs {
    /// Split of the prepared layout.
    #[arg(long, default_value = "test")]
    pub split: String,
    /// Use the authors' v0.3.1 fy = 927.06 (prepared layout without intrinsics).
    #[arg(long)]
    pub paper_fy: bool,
    /// Directory of ESANet `.npy` predictions.
    #[arg(long)]
    pub predictions: Option<PathBuf>,
    /// ROS 2 bag: frame the camera poses are in. A map written as a bag (`--mcap`) is
    /// attached to this frame.
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

impl OpenArgs {
    /// The options the dataset readers take.
    pub fn options(&self) -> anyhow::Result<OpenOptions> {
        let label_map = match &self.label_map {
            Some(path) => read_label_map(path)?,
            None => Vec::new(),
        };
        Ok(OpenOptions {
            split: Some(self.split.clone()),
            paper_fy: self.paper_fy,
            predictions: self.predictions.clone(),
            bag: crate::dataset::source::BagOptions {
                world_frame: Some(self.world_frame.clone()),
                pose_topic: self.pose_topic.clone(),
                label_map,
                depth_topic: self.depth_topic.clone(),
                labels_topic: self.labels_topic.clone(),
                camera_info_topic: self.camera_info_topic.clone(),
                sync_tolerance_ns: (self.sync_tolerance.max(0.0) * 1e9) as u64,
            },
        })
    }
}

/// Which frames of a dataset to map (`--every`, shared by `map` and `export`; `experiment`
/// has the same option).
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
