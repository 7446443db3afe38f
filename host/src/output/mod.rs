//! Everything sndt writes for people and other tools: PNG pictures, SVG charts, PLY
//! point clouds and ellipsoid meshes, raw world points for other mappers, the occupancy
//! layer as an OctoMap ([`octomap`]), ROS 2 bags of frames and maps ([`ros`]), and progress
//! bars. Files are written with [`crate::atomic`].

pub mod chart;
pub mod export;
pub mod legend;
pub mod octomap;
pub mod picture;
pub mod ply;
pub mod points;
pub mod progress;
pub mod ros;
