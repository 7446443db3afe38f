//! Rendering: the label and distance image a pinhole camera at a pose would see in the
//! map, one [`Map::raycast`] per pixel with caches shared by the whole image (its rays
//! share one origin), walked in 8x8 pixel tiles whose rays visit nearly the same voxels.

use crate::camera::{validate_pose, Pinhole};
use crate::error::Error;
use crate::map::Map;
use crate::raycast::Scratch;
use nalgebra::{Isometry3, Point3, Vector3};

/// Label written by [`Map::render`] where a ray hits nothing (free space or unknown).
pub const INVALID_LABEL: u8 = 255;

/// Side of the square pixel tiles [`Map::render`] walks (cache locality only).
const TILE: u32 = 8;

/// Prepared-Gaussian cache entries of one render (64 bytes each).
const RENDER_PREPS: usize = 512;
/// Dilated-surface-mask cache entries of one render (16 bytes each).
const RENDER_DILATED: usize = 512;

impl<const V: usize, const B: usize, const C: usize> Map<V, B, C> {
    /// Renders what a pinhole camera at `pose` (camera to world, OpenCV axes) sees:
    /// per pixel the class of the first Gaussian hit (0 void, [`INVALID_LABEL`] for
    /// nothing) and its distance in metres along the ray (0 for nothing). Rays end at
    /// `config.max_range`. Each pixel gets exactly what [`Map::raycast`] returns for its ray.
    ///
    /// ```
    /// use sndt_core::*;
    /// // 5 cm between pixels at 2 m: several points per 10 cm voxel.
    /// let cam = Pinhole { fx: 40.0, fy: 40.0, cx: 4.0, cy: 3.0, width: 8, height: 6 };
    /// let depth = [2.0f32; 48];
    /// let labels = [7u8; 48];
    /// let img = DepthImage { camera: cam, depth: &depth, kind: DepthKind::Planar,
    ///                        labels: LabelImage::Top1(&labels), stride: 1 };
    /// let mut map: Map<256, 64, 40> = Map::new(Config::DEFAULT);
    /// map.integrate_depth(&Isometry3::identity(), &img).unwrap();
    /// let (mut out, mut dist) = ([0u8; 48], [0f32; 48]);
    /// map.render(&Isometry3::identity(), &cam, &mut out, &mut dist).unwrap();
    /// assert!(out.iter().filter(|&&c| c == 7).count() > 30);
    /// assert!(out.iter().all(|&c| c == 7 || c == INVALID_LABEL));
    /// ```
    pub fn render(
        &self,
        pose: &Isometry3<f32>,
        camera: &Pinhole,
        labels: &mut [u8],
        distance: &mut [f32],
    ) -> Result<(), Error> {
        let n = camera.pixels().ok_or(Error::InvalidImage)?;
        if !camera.valid() || labels.len() != n || distance.len() != n {
            return Err(Error::InvalidImage);
        }
        validate_pose(pose)?;
        let t = pose.translation.vector;
        let rot = pose.rotation.to_rotation_matrix();
        let origin = Point3::from(t);
        let (w, h) = (camera.width, camera.height);
        // The origin is fixed for the whole image: prepared Gaussians and dilated masks stay
        // valid (about 41 KiB of stack: 512 x 64 B Gaussians, 512 x 16 B masks; host use).
        let mut s = Scratch::<RENDER_PREPS, RENDER_DILATED>::new();
        for ty in (0..h).step_by(TILE as usize) {
            for tx in (0..w).step_by(TILE as usize) {
                for row in ty..h.min(ty.saturating_add(TILE)) {
                    for col in tx..w.min(tx.saturating_add(TILE)) {
                        let i = row as usize * w as usize + col as usize;
                        let (Some(l), Some(d)) = (labels.get_mut(i), distance.get_mut(i)) else {
                            continue;
                        };
                        let r = camera.ray(col, row);
                        let dir = rot * Vector3::new(r[0], r[1], r[2]);
                        match self.raycast_in(&mut s, &origin, &dir, self.config.max_range) {
                            Some(hit) => {
                                *l = hit.class;
                                *d = hit.t;
                            }
                            None => {
                                *l = INVALID_LABEL;
                                *d = 0.0;
                            }
                        }
                    }
                }
            }
        }
        Ok(())
    }
}
