//! ROS 2 recordings as a dataset: depth, labels, camera info and transforms read from MCAP
//! files (CDR-encoded ROS 2 messages, as `ros2 bag record` writes them).
//!
//! - [`msgs`]: the ROS 2 message types sndt reads and writes, and their CDR encoding;
//! - [`tf`]: a transform buffer (`/tf`, `/tf_static`) that answers camera poses;
//! - [`metadata`]: rosbag2's bag folder (`metadata.yaml` beside the MCAP files it lists)
//!   and the QoS profiles rosbag2 records per topic;
//! - [`bag`]: the bag reader, which pairs depth with labels, camera info and a pose and
//!   yields [`Frame`](crate::dataset::Frame)s.
//!
//! The writers (bags of frames and of maps) are in [`crate::output::ros`].

pub mod bag;
pub mod metadata;
pub mod msgs;
pub mod tf;
