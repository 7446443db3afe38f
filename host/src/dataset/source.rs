//! The interface every dataset reader implements, and the options readers take.

use super::frame::{Frame, FrameId};
use anyhow::Result;

/// A source of frames.
pub trait Dataset: Send + Sync {
    /// One line about what was opened (layout, split, frame count).
    fn describe(&self) -> String;

    /// All frames, ordered by trajectory then index.
    fn frames(&self) -> &[FrameId];

    /// Reads one frame.
    fn load(&self, id: &FrameId) -> Result<Frame>;

    /// When the frame was recorded, nanoseconds, if the dataset knows (ROS 2 bags).
    fn stamp(&self, _id: &FrameId) -> Option<u64> {
        None
    }

    /// Frames grouped by trajectory (`scene/cam`), in order.
    fn trajectories(&self) -> Vec<(String, Vec<FrameId>)> {
        let mut out: Vec<(String, Vec<FrameId>)> = Vec::new();
        for id in self.frames() {
            let t = id.trajectory();
            match out.last_mut() {
                Some((name, v)) if *name == t => v.push(id.clone()),
                _ => out.push((t, vec![id.clone()])),
            }
        }
        out
    }
}

/// Every `step`-th frame of each trajectory of another dataset (frames `0, step, 2 step,
/// ...`): a whole trajectory's walk with fewer frames.
///
/// ```
/// use sndt_host::dataset::{Dataset, Every};
/// use sndt_host::dataset::{open_spec};
/// let d = Every::new(open_spec("synthetic:1:10", &Default::default()).unwrap(), 4);
/// let idx: Vec<u32> = d.frames().iter().map(|f| f.index).collect();
/// assert_eq!(idx, [0, 4, 8]);
/// ```
pub struct Every {
    inner: Box<dyn Dataset>,
    frames: Vec<FrameId>,
    step: u32,
}

impl Every {
    /// Wraps `inner`, keeping every `step`-th frame (`step` 0 counts as 1).
    pub fn new(inner: Box<dyn Dataset>, step: u32) -> Every {
        let step = step.max(1);
        let frames = inner
            .frames()
            .iter()
            .filter(|f| f.index % step == 0)
            .cloned()
            .collect();
        Every {
            inner,
            frames,
            step,
        }
    }
}

impl Dataset for Every {
    fn describe(&self) -> String {
        format!(
            "{} (frames 0, {}, ...: {} frames)",
            self.inner.describe(),
            self.step,
            self.frames.len()
        )
    }

    fn frames(&self) -> &[FrameId] {
        &self.frames
    }

    fn load(&self, id: &FrameId) -> Result<Frame> {
        self.inner.load(id)
    }
}

/// Options for [`open`](crate::dataset::open::open).
#[derive(Clone, Debug, Default)]
pub struct OpenOptions {
    /// Split name of the prepared layout (default `test`).
    pub split: Option<String>,
    /// Prepared layout: use the authors' v0.3.1 intrinsics (fx = 886.81, fy = 927.06) to
    /// reproduce the paper, instead of the correct fy.
    pub paper_fy: bool,
    /// Directory of ESANet `.npy` predictions (`<dir>/<scene>/<cam>/<NNNN>.npy`);
    /// default: `<root>/<split>/esanet` when it exists.
    pub predictions: Option<std::path::PathBuf>,
    /// How to read a ROS 2 bag (`.mcap`): topics, world frame, sync tolerance.
    pub bag: BagOptions,
}

/// How to read a ROS 2 bag (`crate::ros::bag`).
#[derive(Clone, Debug, Default)]
pub struct BagOptions {
    /// Frame the poses are in (default `world`).
    pub world_frame: Option<String>,
    /// A `geometry_msgs/msg/PoseStamped` (the depth camera's pose) or `nav_msgs/msg/Odometry`
    /// (the pose of its `child_frame_id`, chained to the camera by `/tf_static`) topic; its
    /// poses replace the `/tf` and `/tf_static` transforms of the frame they pose.
    pub pose_topic: Option<String>,
    /// Label ids of the bag to NYU40 classes: `(id, class)`; ids not listed become void.
    /// Empty: labels are NYU40 already.
    pub label_map: Vec<(u8, u8)>,
    /// Depth topic (default: the image topic with `16UC1` or `32FC1` images).
    pub depth_topic: Option<String>,
    /// Labels topic (default: the image topic with `mono8` or `8UC1` images, if any).
    pub labels_topic: Option<String>,
    /// Camera-info topic (default: the one whose frame is the depth image's).
    pub camera_info_topic: Option<String>,
    /// Largest stamp difference of labels or camera info paired with a depth image, ns.
    pub sync_tolerance_ns: u64,
}
