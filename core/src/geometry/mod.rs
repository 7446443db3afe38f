//! Geometry and numerics the stages share: the correctly rounded square root, the exact
//! 3-D DDA voxel walk, a voxel's Gaussian and its prepared inverse, and the camera side
//! (pinhole, depth images, pixel to point, pose checks).

pub(crate) mod dda;
pub(crate) mod sqrt;

pub(crate) mod gaussian;

pub(crate) mod camera;
