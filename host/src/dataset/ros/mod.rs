//! ROS 2 recordings as a dataset: depth, labels, camera info and transforms read from MCAP
//! files (CDR-encoded ROS 2 messages, as `ros2 bag record` writes them), one file or a
//! rosbag2 folder of split files.
//!
//! - [`msgs`]: the ROS 2 message types sndt reads and writes, and their CDR encoding;
//! - [`mcap_read`]: MCAP files walked record by record and messages read back from where
//!   they are, never the whole file in memory;
//! - [`index`]: one pass over a recording: topics, transforms, camera infos, poses, and
//!   where each image is;
//! - [`tf`]: a transform buffer (`/tf`, `/tf_static`) that answers camera poses;
//! - [`metadata`]: rosbag2's bag folder (`metadata.yaml` beside the MCAP files it lists)
//!   and the QoS profiles rosbag2 records per topic;
//! - [`bag`]: the bag reader, which pairs depth with labels, camera info and a pose and
//!   yields [`Frame`](crate::dataset::Frame)s.
//!
//! The writers (bags of frames and of maps) are in [`crate::output::ros`].

pub mod bag;
pub mod index;
pub mod mcap_read;
pub mod metadata;
pub mod msgs;
pub mod tf;

/// A stamp in nanoseconds as exact decimal seconds (nine digits after the point; no
/// rounding through a float).
///
/// ```
/// use sndt_host::dataset::ros::stamp_text;
/// assert_eq!(stamp_text(1_700_000_000_123_456_789), "1700000000.123456789");
/// assert_eq!(stamp_text(5), "0.000000005");
/// ```
pub fn stamp_text(ns: u64) -> String {
    format!("{}.{:09}", ns / 1_000_000_000, ns % 1_000_000_000)
}
