//! The dataset-opening options `map` and `experiment` share (`--split`, `--paper-fy`,
//! `--predictions`, and for ROS 2 bags the topics, world frame and sync tolerance).

use crate::dataset::source::OpenOptions;
use std::path::PathBuf;

/// How to open a dataset directory (shared by `map` and `experiment`).
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
    /// ROS 2 bag: frame the camera poses are in.
    #[arg(long, default_value = "world")]
    pub world_frame: String,
    /// ROS 2 bag: depth topic (default: the 16UC1 / 32FC1 image topic).
    #[arg(long)]
    pub depth_topic: Option<String>,
    /// ROS 2 bag: labels topic (default: the mono8 / 8UC1 image topic, if any).
    #[arg(long)]
    pub labels_topic: Option<String>,
    /// ROS 2 bag: camera-info topic (default: the one in the depth image's frame).
    #[arg(long)]
    pub camera_info_topic: Option<String>,
    /// ROS 2 bag: largest stamp difference (seconds) of labels or camera info paired with a
    /// depth image (0: exact stamps).
    #[arg(long, default_value_t = 0.0)]
    pub sync_tolerance: f64,
}

impl OpenArgs {
    /// The options the dataset readers take.
    pub fn options(&self) -> OpenOptions {
        OpenOptions {
            split: Some(self.split.clone()),
            paper_fy: self.paper_fy,
            predictions: self.predictions.clone(),
            bag: crate::dataset::source::BagOptions {
                world_frame: Some(self.world_frame.clone()),
                depth_topic: self.depth_topic.clone(),
                labels_topic: self.labels_topic.clone(),
                camera_info_topic: self.camera_info_topic.clone(),
                sync_tolerance_ns: (self.sync_tolerance.max(0.0) * 1e9) as u64,
            },
        }
    }
}
