//! ROS 2 recordings: reading depth, labels, camera info and transforms from MCAP files
//! (CDR-encoded ROS 2 messages, as `ros2 bag record` writes them) and writing them.

pub mod bag;
pub mod export;
pub mod msgs;
pub mod tf;
pub mod write;
