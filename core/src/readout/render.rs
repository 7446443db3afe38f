//! Rendering: the label and distance image a pinhole camera at a pose would see in the
//! map, by drawing every Gaussian over the pixels it covers instead of walking a ray per
//! pixel.
//!
//! Each occupied surface voxel is culled against the view by a ball around its mean that
//! holds its ellipsoid; a survivor is prepared once ([`Prep`]: the inverse covariance with
//! the eigenvalue floor, the offset to the camera, its class), its footprint in the image
//! is computed (`splat.rs`: at most two column spans per row), and each pixel of the
//! footprint gets the ray test [`Map::raycast`] uses, keeping the nearest hit in the
//! distance buffer (a z-buffer). The result is the first Gaussian each pixel's ray enters,
//! which is what [`Map::raycast`] returns too: its walk examines the 3x3x3 neighbourhood of
//! every voxel it passes, and with the default render radius an ellipsoid never leaves
//! that neighbourhood. Two Gaussians entered at exactly the same distance are decided by
//! [`Map::raycast`] for that pixel (it breaks the tie by key).

use crate::error::Error;
use crate::geometry::camera::{validate_pose, Pinhole};
use crate::geometry::gaussian::floor_abs;
use crate::geometry::sqrt::sqrt;
use crate::key::VoxelKey;
use crate::readout::raycast::{Lanes3, Prep, LANES};
use crate::readout::splat::{pixel_to_ray, Footprint};
use crate::storage::block::bits;
use crate::storage::map::Map;
use crate::storage::table::Entry;
use crate::storage::voxel::argmax;
use nalgebra::{Isometry3, Point3, Rotation3, Vector3};

/// Label written by [`Map::render`] where a ray hits nothing (free space or unknown).
pub const INVALID_LABEL: u8 = 255;

/// What a render needs to know about the camera, fixed for the whole image.
struct View {
    origin: Vector3<f32>,
    rot: Rotation3<f32>,
    camera: Pinhole,
    /// First row of the image held by the buffers, and one past the last.
    rows: (u32, u32),
    /// World ray of pixel coordinate `(X, Y)`: `t (X, Y, 1)`.
    t: [Vector3<f64>; 3],
    /// Inward normals (camera axes, unit) of the four planes through the centre and the
    /// edges of the rendered rows: left, right, top, bottom.
    planes: [Vector3<f32>; 4],
    r2: f32,
    max_t: f32,
}

impl View {
    fn new(pose: &Isometry3<f32>, camera: &Pinhole, rows: (u32, u32), r2: f32, max_t: f32) -> View {
        let rot = pose.rotation.to_rotation_matrix();
        let c = camera;
        let (xl, xr) = (-c.cx / c.fx, (c.width as f32 - c.cx) / c.fx);
        let (yt, yb) = ((rows.0 as f32 - c.cy) / c.fy, (rows.1 as f32 - c.cy) / c.fy);
        let planes = [
            Vector3::new(1.0, 0.0, -xl),
            Vector3::new(-1.0, 0.0, xr),
            Vector3::new(0.0, 1.0, -yt),
            Vector3::new(0.0, -1.0, yb),
        ]
        .map(|n| n / n.norm());
        View {
            origin: pose.translation.vector,
            t: pixel_to_ray(rot.matrix(), [c.fx, c.fy, c.cx, c.cy]),
            rot,
            camera: *camera,
            rows,
            planes,
            r2,
            max_t,
        }
    }

    /// Whether a ball of radius `radius` around `mean` lies outside the rendered view.
    fn culls(&self, mean: &Vector3<f32>, radius: f32) -> bool {
        let m = mean - self.origin;
        let dist = m.norm();
        let margin = radius * 1.01 + dist * 1e-5;
        let mc = self.rot.inverse_transform_vector(&m);
        // Behind the camera, beyond the range, or outside one of the side planes.
        mc.z <= -margin
            || dist - margin > self.max_t
            || self.planes.iter().any(|n| n.dot(&mc) < -margin)
    }

    /// The unit rays of pixels `col..col + LANES` of row `row` (NaN for a ray that has
    /// none), computed as [`Map::raycast`] gets them from [`View::ray`]: the same bits.
    #[inline(always)]
    fn unit_rays(&self, col: u32, row: u32) -> Lanes3 {
        let c = &self.camera;
        let m = self.rot.matrix();
        let y = (row as f32 + 0.5 - c.cy) / c.fy;
        let mut u = [[0f32; LANES]; 3];
        let mut n = [0f32; LANES];
        for l in 0..LANES {
            let x = (col.wrapping_add(l as u32) as f32 + 0.5 - c.cx) / c.fx;
            for (i, ui) in u.iter_mut().enumerate() {
                ui[l] = m[(i, 0)] * x + m[(i, 1)] * y + m[(i, 2)];
            }
            n[l] = u[0][l] * u[0][l] + u[1][l] * u[1][l] + u[2][l] * u[2][l];
        }
        for nl in n.iter_mut() {
            *nl = sqrt(*nl);
        }
        for l in 0..LANES {
            let valid = n[l].is_finite() && n[l] > 0.0;
            for ui in u.iter_mut() {
                ui[l] = if valid { ui[l] / n[l] } else { f32::NAN };
            }
        }
        u
    }

    #[inline(always)]
    fn ray(&self, col: u32, row: u32) -> Vector3<f32> {
        let r = self.camera.ray(col, row);
        self.rot * Vector3::new(r[0], r[1], r[2])
    }
}

impl<const V: usize, const B: usize, const C: usize> Map<V, B, C> {
    /// Renders what a pinhole camera at `pose` (camera to world, OpenCV axes) sees:
    /// per pixel the class of the first Gaussian hit (0 void, [`INVALID_LABEL`] for
    /// nothing) and its distance in metres along the ray (0 for nothing). Rays end at
    /// `config.max_range`. Each pixel gets what [`Map::raycast`] returns for its ray (see
    /// the module documentation for the one exception, radii above the default).
    ///
    /// ```
    /// use sndt_core::*;
    /// // 5 cm between pixels at 2 m: several points per 10 cm voxel.
    /// let cam = Pinhole { fx: 40.0, fy: 40.0, cx: 4.0, cy: 3.0, width: 8, height: 6 };
    /// let depth = [2.0f32; 48];
    /// let labels = [7u8; 48];
    /// let img = DepthImage { camera: cam, depth: Depth::Metres(&depth), kind: DepthKind::Planar,
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
        if camera.pixels() != Some(labels.len()) {
            return Err(Error::InvalidImage);
        }
        self.render_rows(pose, camera, 0, labels, distance)
    }

    /// [`Map::render`] for the rows `first_row..` of the image only: `labels` and
    /// `distance` hold whole rows of `camera.width` pixels, as many as fit in the image.
    /// The pixels are exactly those of the whole render, so bands of rows can be rendered
    /// on several threads.
    ///
    /// ```
    /// use sndt_core::*;
    /// let cam = Pinhole { fx: 40.0, fy: 40.0, cx: 4.0, cy: 3.0, width: 8, height: 6 };
    /// let img = DepthImage { camera: cam, depth: Depth::Metres(&[2.0f32; 48]), kind: DepthKind::Planar,
    ///                        labels: LabelImage::Top1(&[7u8; 48]), stride: 1 };
    /// let mut map: Map<256, 64, 40> = Map::new(Config::DEFAULT);
    /// map.integrate_depth(&Isometry3::identity(), &img).unwrap();
    /// let (mut all, mut dist) = ([0u8; 48], [0f32; 48]);
    /// map.render(&Isometry3::identity(), &cam, &mut all, &mut dist).unwrap();
    /// let (mut rows, mut dist) = ([0u8; 16], [0f32; 16]);
    /// map.render_rows(&Isometry3::identity(), &cam, 2, &mut rows, &mut dist).unwrap();
    /// assert_eq!(rows, all[16..32]);
    /// ```
    pub fn render_rows(
        &self,
        pose: &Isometry3<f32>,
        camera: &Pinhole,
        first_row: u32,
        labels: &mut [u8],
        distance: &mut [f32],
    ) -> Result<(), Error> {
        camera.pixels().ok_or(Error::InvalidImage)?;
        let w = camera.width as usize;
        let n = labels.len();
        let rows = n.checked_div(w).unwrap_or(0);
        let fits = (first_row as usize)
            .checked_add(rows)
            .is_some_and(|end| end <= camera.height as usize);
        if !camera.valid() || distance.len() != n || rows * w != n || !fits {
            return Err(Error::InvalidImage);
        }
        validate_pose(pose)?;
        let cfg = &self.config;
        let r2 = cfg.render_radius * cfg.render_radius;
        let band = (first_row, first_row + rows as u32);
        let view = View::new(pose, camera, band, r2, cfg.max_range);
        labels.fill(INVALID_LABEL);
        distance.fill(f32::INFINITY);
        let o = view.origin;
        // A ray from outside the key range hits nothing (as `raycast` says).
        if self.voxel_key(&[o.x, o.y, o.z]).is_some() {
            self.draw_all(&view, labels, distance);
        }
        self.resolve(&view, labels, distance);
        Ok(())
    }

    /// Draws every occupied surface voxel that may be seen into the z-buffer `distance`.
    fn draw_all(&self, view: &View, labels: &mut [u8], distance: &mut [f32]) {
        let cfg = &self.config;
        let (h, step) = (cfg.cell_size, cfg.quant_step());
        let fa = floor_abs(h);
        for bs in self.blocks.live() {
            let Some(blk) = self.blocks.slots.get(bs) else {
                continue;
            };
            let block = blk.packed_key();
            for cell in bits(blk.surface) {
                if blk.cells.get(cell as usize).is_none_or(|&l| l <= 0) {
                    continue;
                }
                let key = VoxelKey::from_block_cell(block, cell);
                let Some(v) = self
                    .voxels
                    .find(key.packed())
                    .and_then(|vs| self.voxels.slots.get(vs))
                else {
                    continue;
                };
                if v.n < cfg.n_min {
                    continue;
                }
                let g = v.gaussian(h, step);
                // Every floored eigenvalue is at most |cov|_F (+ the floor), so the
                // ellipsoid lies in this ball.
                let f = g.covariance.norm();
                let radius = cfg.render_radius * sqrt(f + (f * cfg.eigen_ratio).max(fa));
                if view.culls(&g.mean, radius) {
                    continue;
                }
                let class = argmax(&v.hist).map_or(0, |(c, _)| c);
                let prepared = g.prepare(cfg.eigen_ratio, fa);
                if let Some(p) = Prep::new(&prepared, class, &view.origin, view.r2) {
                    draw(view, &p, labels, distance);
                }
            }
        }
    }

    /// Turns the z-buffer into the output: no hit is (`INVALID_LABEL`, 0); a pixel where
    /// two Gaussians tied (flagged by a negative distance) is cast by [`Map::raycast`].
    fn resolve(&self, view: &View, labels: &mut [u8], distance: &mut [f32]) {
        // `max(1)`: a view has pixels (checked), and a division by 0 would panic.
        let w = (view.camera.width as usize).max(1);
        let origin = Point3::from(view.origin);
        for (i, (l, d)) in labels.iter_mut().zip(distance.iter_mut()).enumerate() {
            if *d == f32::INFINITY {
                *l = INVALID_LABEL;
                *d = 0.0;
            } else if d.is_sign_negative() {
                let (col, row) = ((i % w) as u32, view.rows.0 + (i / w) as u32);
                let hit = self.raycast(&origin, &view.ray(col, row), view.max_t);
                *l = hit.map_or(INVALID_LABEL, |h| h.class);
                *d = hit.map_or(0.0, |h| h.t);
            }
        }
    }
}

/// Tests the pixels of `p`'s footprint and keeps the nearer hits. A hit at exactly the
/// distance already kept flags the pixel (negative distance) for `resolve`: ties
/// are decided by key, which the z-buffer does not hold.
fn draw(view: &View, p: &Prep, labels: &mut [u8], distance: &mut [f32]) {
    let fp = Footprint::new(&p.inv, &p.d, view.r2, &view.t, view.rows, view.camera.width);
    let w = view.camera.width as usize;
    for row in fp.rows.0..fp.rows.1 {
        let base = (row - view.rows.0) as usize * w;
        for (start, end) in fp.spans(row) {
            for col in (start..end).step_by(LANES) {
                let t = p.enter_lanes(&view.unit_rays(col, row), view.r2, view.max_t);
                let i = base + col as usize;
                let n = ((end - col) as usize).min(LANES);
                let (Some(ds), Some(ls)) = (distance.get_mut(i..i + n), labels.get_mut(i..i + n))
                else {
                    continue;
                };
                for ((d, l), &t) in ds.iter_mut().zip(ls.iter_mut()).zip(t.iter()) {
                    let kept = d.abs();
                    if t < kept {
                        *d = t;
                        *l = p.class;
                    } else if t == kept {
                        *d = -t;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use crate::geometry::gaussian::PrepCache;
    use crate::readout::raycast::tests::reference_raycast;
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

    /// Buffers that are not whole rows of the image, or rows beyond its bottom, a broken
    /// camera or pose: a typed error, never a panic.
    #[test]
    fn render_rows_rejects_bad_buffers() {
        let map: Map<64, 16, 4> = Map::new(Config::DEFAULT);
        let cam = Pinhole {
            fx: 10.0,
            fy: 10.0,
            cx: 4.0,
            cy: 3.0,
            width: 8,
            height: 6,
        };
        let id = Isometry3::identity();
        let (mut l, mut d) = ([0u8; 48], [0f32; 48]);
        let bad = Err(Error::InvalidImage);
        assert_eq!(
            map.render_rows(&id, &cam, 0, &mut l[..47], &mut d[..47]),
            bad
        );
        assert_eq!(
            map.render_rows(&id, &cam, 0, &mut l[..16], &mut d[..8]),
            bad
        );
        assert_eq!(
            map.render_rows(&id, &cam, 5, &mut l[..16], &mut d[..16]),
            bad
        );
        assert_eq!(
            map.render_rows(&id, &cam, u32::MAX, &mut l[..8], &mut d[..8]),
            bad
        );
        let flat = Pinhole { fx: 0.0, ..cam };
        assert_eq!(map.render_rows(&id, &flat, 0, &mut l, &mut d), bad);
        let empty = Pinhole { width: 0, ..cam };
        assert_eq!(
            map.render_rows(&id, &empty, 0, &mut l[..0], &mut d[..0]),
            Ok(())
        );
        let mut pose = id;
        pose.translation.vector.x = f32::NAN;
        assert_eq!(
            map.render(&pose, &cam, &mut l, &mut d),
            Err(Error::InvalidPose)
        );
        // The last row alone, and no rows at all, are fine.
        assert_eq!(
            map.render_rows(&id, &cam, 5, &mut l[..8], &mut d[..8]),
            Ok(())
        );
        assert_eq!(
            map.render_rows(&id, &cam, 6, &mut l[..0], &mut d[..0]),
            Ok(())
        );
        assert!(l[..8].iter().all(|&c| c == INVALID_LABEL) && d[..8] == [0.0; 8]);
    }

    /// Regression: `render` passes `config.max_range` as `max_t`; a valid `max_range = 1e9` hits the
    /// same overflow.
    #[test]
    fn render_with_large_valid_max_range() {
        let mut cfg = Config::DEFAULT;
        cfg.max_range = 1e9;
        assert_eq!(
            cfg.validate(),
            Err(Error::InvalidConfig(ConfigField::MaxRange))
        );
        // The largest valid max range at 10 cm (`MAX_RAY_CELLS` cells) still renders.
        cfg.max_range = Config::MAX_RAY_CELLS as f32 * cfg.cell_size;
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
