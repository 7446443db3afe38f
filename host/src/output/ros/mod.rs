//! ROS 2 bags written by sndt (MCAP, CDR-encoded messages): trajectories of frames
//! ([`mod@write`], for `sndt synth --mcap`) and maps as point clouds and ellipsoid markers
//! ([`export`], for Foxglove and RViz). The messages are [`crate::dataset::ros::msgs`].

pub mod export;
pub mod write;
