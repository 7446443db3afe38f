//! The interface every dataset reader implements, the options readers take, and
//! [`usable_frames`]: a trajectory's frames read for a run that skips the bad ones.

use super::frame::{key_range_error, Frame, FrameId};
use anyhow::Result;
use std::fmt;
use std::path::PathBuf;

/// A source of frames.
pub trait Dataset: Send + Sync {
    /// One line about what was opened (layout, split, frame count).
    fn describe(&self) -> String;

    /// All frames, ordered by trajectory then index.
    fn frames(&self) -> &[FrameId];

    /// Reads one frame. An error in the frame's own files (unreadable, corrupt, values out
    /// of range) is a [`BadFrame`], which a run may skip ([`usable_frames`]); any other
    /// error (the dataset's or a camera's files) is not.
    fn load(&self, id: &FrameId) -> Result<Frame>;

    /// `None` when the frames carry predicted labels; else where they were looked for
    /// (for the message of a run that needs them).
    fn missing_predictions(&self) -> Option<String> {
        Some("this kind of dataset has no predicted labels".into())
    }

    /// The file a frame's pose was read from, for messages about the pose.
    fn pose_file(&self, _id: &FrameId) -> Option<PathBuf> {
        None
    }

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

    fn missing_predictions(&self) -> Option<String> {
        self.inner.missing_predictions()
    }

    fn pose_file(&self, id: &FrameId) -> Option<PathBuf> {
        self.inner.pose_file(id)
    }

    fn stamp(&self, id: &FrameId) -> Option<u64> {
        self.inner.stamp(id)
    }
}

/// A frame whose own input is bad: one of its files is missing, unreadable or corrupt, or
/// holds a value out of range. A run can skip the frame and use the others. Readers return
/// it from [`Dataset::load`] inside an `anyhow::Error`; `why` names the file and says what
/// is wrong.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BadFrame {
    /// The frame.
    pub id: FrameId,
    /// What is wrong, naming the file.
    pub why: String,
}

impl BadFrame {
    /// `error` of frame `id` (a reader's message naming the file) as a bad frame.
    ///
    /// ```
    /// use sndt_host::dataset::{source::BadFrame, FrameId};
    /// let id = FrameId::parse("room/cam_00/0002").unwrap();
    /// let e = BadFrame::wrap(&id, anyhow::anyhow!("0002.png: not a readable PNG"));
    /// assert_eq!(BadFrame::of(&e).unwrap().why, "0002.png: not a readable PNG");
    /// assert!(BadFrame::of(&anyhow::anyhow!("other")).is_none());
    /// ```
    pub fn wrap(id: &FrameId, error: anyhow::Error) -> anyhow::Error {
        anyhow::Error::new(BadFrame {
            id: id.clone(),
            why: format!("{error:#}"),
        })
    }

    /// The bad frame `error` is (or was caused by), if any.
    pub fn of(error: &anyhow::Error) -> Option<&BadFrame> {
        error.chain().find_map(|e| e.downcast_ref::<BadFrame>())
    }
}

impl fmt::Display for BadFrame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.why)
    }
}

impl std::error::Error for BadFrame {}

/// The frames `ids` of `dataset`, read in order for a run that can do without some of
/// them (`sndt map`): a [`BadFrame`], and a frame whose camera position lies outside the
/// key range of a map of `cell_size` cells (the map would refuse it), is skipped with a
/// `warning:` line on stderr naming the file, and added to `skipped`. Any other error is
/// passed on and stops the run.
///
/// ```
/// use sndt_host::dataset::{open_spec, source::usable_frames, Dataset};
/// let d = open_spec("synthetic:1:3", &Default::default()).unwrap();
/// let mut skipped = Vec::new();
/// let n = usable_frames(d.as_ref(), d.frames(), 0.1, &mut skipped).count();
/// assert_eq!((n, skipped.len()), (3, 0));
/// ```
pub fn usable_frames<'a>(
    dataset: &'a dyn Dataset,
    ids: &'a [FrameId],
    cell_size: f32,
    skipped: &'a mut Vec<BadFrame>,
) -> impl Iterator<Item = Result<Frame>> + 'a {
    ids.iter().filter_map(move |id| {
        let frame =
            dataset
                .load(id)
                .and_then(|frame| match key_range_error(&frame.pose, cell_size) {
                    None => Ok(frame),
                    Some(why) => {
                        let file = dataset
                            .pose_file(id)
                            .map_or(format!("frame {id}"), |p| p.display().to_string());
                        Err(BadFrame::wrap(id, anyhow::anyhow!("{file}: {why}")))
                    }
                });
        match frame {
            Ok(frame) => Some(Ok(frame)),
            Err(e) => match BadFrame::of(&e) {
                Some(bad) => {
                    eprintln!("warning: skipping frame {id}: {}", bad.why);
                    skipped.push(bad.clone());
                    None
                }
                None => Some(Err(e)),
            },
        }
    })
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
    /// How to read a ROS 2 bag (`.mcap` file or rosbag2 folder): topics, world frame, sync tolerance.
    pub bag: BagOptions,
}

/// How to read a ROS 2 bag (`crate::dataset::ros::bag`).
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
