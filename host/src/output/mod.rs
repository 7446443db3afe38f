//! Everything sndt writes for people and other tools: PNG pictures, SVG charts, PLY
//! point clouds and ellipsoid meshes.

pub mod chart;
pub mod export;
pub mod picture;
pub mod ply;
pub mod progress;
