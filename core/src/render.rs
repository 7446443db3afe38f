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

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use crate::gaussian::PrepCache;
    use crate::raycast::tests::*;
    use crate::testutil::*;
    use crate::*;
    use std::vec::Vec;

    /// The original `render`: row-major, one ray per pixel.
    fn reference_render<const V: usize, const B: usize, const C: usize>(
        map: &Map<V, B, C>,
        pose: &Isometry3<f32>,
        camera: &Pinhole,
    ) -> (Vec<u8>, Vec<f32>) {
        let n = (camera.width * camera.height) as usize;
        let (mut labels, mut distance) = (std::vec![0u8; n], std::vec![0f32; n]);
        let rot = pose.rotation.to_rotation_matrix();
        let origin = Point3::from(pose.translation.vector);
        let w = camera.width as usize;
        let mut cache = PrepCache::<128>::new();
        for (i, (l, d)) in labels.iter_mut().zip(distance.iter_mut()).enumerate() {
            let r = camera.ray((i % w) as u32, (i / w) as u32);
            let dir = rot * Vector3::new(r[0], r[1], r[2]);
            match reference_raycast(map, &mut cache, &origin, &dir, map.config.max_range) {
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
        (labels, distance)
    }

    fn assert_same_render(map: &RoomMap, pose: &Isometry3<f32>, cam: &Pinhole) -> usize {
        let n = (cam.width * cam.height) as usize;
        let (want_l, want_d) = reference_render(map, pose, cam);
        let (mut l, mut d) = (std::vec![0u8; n], std::vec![0f32; n]);
        map.render(pose, cam, &mut l, &mut d).unwrap();
        for i in 0..n {
            assert!(
                l[i] == want_l[i] && d[i].to_bits() == want_d[i].to_bits(),
                "pixel {i}: got ({}, {}) want ({}, {})",
                l[i],
                d[i],
                want_l[i],
                want_d[i]
            );
        }
        l.iter().filter(|&&c| c != INVALID_LABEL).count()
    }

    /// Renders of the box room at 5, 10 and 20 cm from mapped poses, poses between them, a
    /// pose outside the room and one looking straight down, at a resolution that is not a
    /// multiple of the tile size: every pixel bit-identical to the reference.
    #[test]
    fn render_matches_reference() {
        big_stack(|| {
            let odd = Pinhole {
                fx: 70.0,
                fy: 70.0,
                cx: 50.0,
                cy: 37.5,
                width: 100,
                height: 75,
            };
            let mut poses = orbit(4);
            poses.extend(orbit(7).into_iter().skip(1).step_by(3));
            poses.push(look_at([-1.5, -1.0, 2.0], [3.0, 2.5, 1.0]));
            poses.push(look_at([2.0, 2.0, 2.5], [2.01, 2.0, 0.0]));
            for cell in [0.05f32, 0.10, 0.20] {
                let map = room_map(cell, 8);
                let mut hits = 0;
                for pose in &poses {
                    hits += assert_same_render(&map, pose, &odd);
                }
                hits += assert_same_render(&map, &poses[0], &CAM);
                assert!(hits > poses.len() * 7000 / 2, "{cell}: only {hits} hits");
            }
        });
    }

    /// Regression: `render` passes `config.max_range` as `max_t`; a valid `max_range = 1e9` hits the
    /// same overflow.
    #[test]
    fn render_with_large_valid_max_range() {
        let mut cfg = Config::DEFAULT;
        cfg.max_range = 1e9;
        assert_eq!(cfg.validate(), Err(Error::InvalidConfig));
        cfg.max_range = 1e4; // the largest valid max range still renders
        assert!(cfg.validate().is_ok());
        let mut map: Map<512, 256, 2> = Map::try_new(cfg).unwrap();
        let mut pts = [lp(0.0, 0.0, 0.0, 1); 400];
        for (i, p) in pts.iter_mut().enumerate() {
            let (u, v) = ((i % 20) as f32 / 20.0 - 0.5, (i / 20) as f32 / 20.0 - 0.5);
            p.position = Point3::new(u, v, 2.02);
        }
        map.integrate(&Isometry3::identity(), &pts).unwrap();
        let cam = Pinhole {
            fx: 10.0,
            fy: 10.0,
            cx: 0.5,
            cy: 0.5,
            width: 1,
            height: 1,
        };
        let (mut l, mut d) = ([0u8], [0f32]);
        map.render(&at(0.05, 0.05, 0.0), &cam, &mut l, &mut d)
            .unwrap();
        assert_eq!(l[0], 1);
    }
}
