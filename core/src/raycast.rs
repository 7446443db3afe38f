//! Ray casting against the map's Gaussians and rendering of label/depth images.
//!
//! A ray walks the grid by DDA; around every traversed voxel it examines the 3x3x3
//! neighbourhood (each neighbour exactly once per ray, by adding only the 9 cells of the new
//! face at each step) for occupied voxels with a valid Gaussian and computes where the ray
//! enters the ellipsoid of Mahalanobis radius `r`: with `a = u^T S^-1 u`,
//! `b = 2 u^T S^-1 (s - mu)`, `c = (s - mu)^T S^-1 (s - mu)`, the ray's squared distance is
//! `a t^2 + b t + c`, minimal `D2 = c - b^2 / 4a` at `t* = -b / 2a`, and it enters at
//! `t = t* - sqrt((r^2 - D2) / a)`. Ellipsoids that contain the origin are skipped.

use crate::block::Block;
use crate::dda::Dda;
use crate::integrate::Pinhole;
use crate::key::VoxelKey;
use crate::map::{argmax, Map};
use crate::table::Table;
use crate::voxel::PrepCache;
use crate::Error;
use nalgebra::{Isometry3, Point3, Vector3};

/// Where a ray first enters an occupied Gaussian.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RayHit {
    /// Distance from the ray origin in metres.
    pub t: f32,
    /// The voxel's class (1-based), or 0 when it has no votes (void).
    pub class: u8,
    /// The voxel hit.
    pub key: VoxelKey,
}

/// Label written by [`Map::render`] where a ray hits nothing (free space or unknown).
pub const INVALID_LABEL: u8 = 255;

impl<const V: usize, const B: usize, const C: usize> Map<V, B, C> {
    /// The first occupied Gaussian the ray from `origin` along `dir` enters within `max_t`
    /// metres. `dir` need not be normalised; a zero or non-finite input gives `None`.
    ///
    /// ```
    /// use sndt_core::*;
    /// let mut map: Map<64, 16, 4> = Map::new(Config::DEFAULT);
    /// let pts: Vec<_> = (0..100)
    ///     .map(|i| LabeledPoint::new(
    ///         Point3::new((i % 10) as f32 * 0.01, (i / 10) as f32 * 0.01, 1.05), Labels::top1(3)))
    ///     .collect();
    /// map.integrate(&Isometry3::identity(), &pts).unwrap();
    /// let hit = map.raycast(&Point3::new(0.05, 0.05, 0.0), &Vector3::z(), 3.0).unwrap();
    /// assert_eq!(hit.class, 3);
    /// assert!((hit.t - 1.05).abs() < 0.01);
    /// assert!(map.raycast(&Point3::new(0.05, 0.05, 0.0), &-Vector3::z(), 3.0).is_none());
    /// ```
    pub fn raycast(&self, origin: &Point3<f32>, dir: &Vector3<f32>, max_t: f32) -> Option<RayHit> {
        self.raycast_cached(&mut PrepCache::<8>::new(), origin, dir, max_t)
    }

    fn raycast_cached<const N: usize>(
        &self,
        cache: &mut PrepCache<N>,
        origin: &Point3<f32>,
        dir: &Vector3<f32>,
        max_t: f32,
    ) -> Option<RayHit> {
        let n = dir.norm();
        let finite = origin.coords.iter().all(|x| x.is_finite());
        if !(finite && n.is_finite() && n > 0.0 && max_t > 0.0) {
            return None;
        }
        let u = dir / n;
        let cfg = &self.config;
        let h = cfg.cell_size;
        let start = self.voxel_key(&[origin.x, origin.y, origin.z])?;
        let inv = 1.0 / h;
        let o = [origin.x * inv, origin.y * inv, origin.z * inv];
        let k = [start.x as i32, start.y as i32, start.z as i32];
        let mut dda = Dda::new(o, [u.x, u.y, u.z], k);
        let mut probe = Probe {
            blocks: &self.blocks,
            cache,
            block_cache: [(0, 0); 8],
            best: None,
            origin: Vector3::new(origin.x, origin.y, origin.z),
            u,
            max_t,
        };
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    self.examine(&mut probe, [k[0] + dx, k[1] + dy, k[2] + dz]);
                }
            }
        }
        // No ray can walk farther than across the whole key range.
        let max_t = max_t.min(h * 4.0 * (crate::KEY_LIMIT + 1) as f32);
        let max_steps = ((max_t / h) as u32).saturating_mul(3).saturating_add(12);
        for _ in 0..max_steps {
            let (a, t) = dda.next_axis();
            let t_enter = t * h;
            if t_enter > max_t + 2.5 * h {
                break;
            }
            if let Some(best) = probe.best {
                if t_enter > best.t + 2.5 * h {
                    break;
                }
            }
            dda.advance(a);
            // Only the 9 cells of the neighbourhood's new face are unseen.
            let (b, c) = ((a + 1) % 3, (a + 2) % 3);
            for db in -1..=1 {
                for dc in -1..=1 {
                    let mut cell = dda.k;
                    cell[a] += dda.step(a);
                    cell[b] += db;
                    cell[c] += dc;
                    self.examine(&mut probe, cell);
                }
            }
        }
        probe.best
    }

    fn examine<const N: usize>(&self, p: &mut Probe<'_, B, N>, k: [i32; 3]) {
        let Some(key) = VoxelKey::from_ints(k[0], k[1], k[2]) else {
            return;
        };
        let packed = key.block();
        // Blocks of a 2x2x2 neighbourhood differ in the parity of some coordinate, so a
        // cache indexed by the three parity bits never thrashes inside one (misses too).
        let i = (((k[0] >> 2) & 1) | (((k[1] >> 2) & 1) << 1) | (((k[2] >> 2) & 1) << 2)) as usize;
        let (tag, found) = p.block_cache[i];
        let found = if tag == packed {
            found
        } else {
            let f = p.blocks.find(packed).map_or(0, |s| s as u32 + 1);
            p.block_cache[i] = (packed, f);
            f
        };
        if found == 0 {
            return;
        }
        let bs = (found - 1) as usize;
        let b = &p.blocks.slots[bs];
        let cell = key.cell();
        if b.surface & (1u64 << cell) == 0 || b.cells[cell as usize] <= 0 {
            return;
        }
        let Some(vs) = self.voxels.find(key.packed()) else {
            return;
        };
        let v = &self.voxels.slots[vs];
        let cfg = &self.config;
        if v.n < cfg.n_min {
            return;
        }
        let g = p.cache.get(vs, v, cfg);
        let d = p.origin - g.mean;
        let w = g.inv * p.u;
        let a = p.u.dot(&w);
        let bq = 2.0 * w.dot(&d);
        let c = d.dot(&(g.inv * d));
        if a.is_nan() || a <= 0.0 {
            return;
        }
        let r2 = cfg.render_radius * cfg.render_radius;
        let d2 = c - bq * bq / (4.0 * a);
        if d2 > r2 || c <= r2 {
            // Missed, or the origin is inside the ellipsoid.
            return;
        }
        let t = -bq / (2.0 * a) - libm::sqrtf((r2 - d2) / a);
        if !(t >= 0.0 && t <= p.max_t) {
            return;
        }
        if p.best
            .is_none_or(|best| t < best.t || (t == best.t && key < best.key))
        {
            let class = argmax(&v.hist).map_or(0, |(c, _)| c);
            p.best = Some(RayHit { t, class, key });
        }
    }

    /// Renders what a pinhole camera at `pose` (camera to world, OpenCV axes) sees:
    /// per pixel the class of the first Gaussian hit (0 void, [`INVALID_LABEL`] for
    /// nothing) and its distance in metres along the ray (0 for nothing). Rays end at
    /// `config.max_range`.
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
        let t = pose.translation.vector;
        let q = pose.rotation.quaternion();
        if !t.iter().chain(q.coords.iter()).all(|x| x.is_finite())
            || (q.norm_squared() - 1.0).abs() > 1e-3
        {
            return Err(Error::InvalidPose);
        }
        let rot = pose.rotation.to_rotation_matrix();
        let origin = Point3::from(t);
        let w = camera.width as usize;
        // Neighbouring pixels examine the same voxels: keep their prepared Gaussians.
        let mut cache = PrepCache::<128>::new();
        for (i, (l, d)) in labels.iter_mut().zip(distance.iter_mut()).enumerate() {
            let r = camera.ray((i % w) as u32, (i / w) as u32);
            let dir = rot * Vector3::new(r[0], r[1], r[2]);
            match self.raycast_cached(&mut cache, &origin, &dir, self.config.max_range) {
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
        Ok(())
    }
}

struct Probe<'a, const B: usize, const N: usize> {
    blocks: &'a Table<Block, B>,
    cache: &'a mut PrepCache<N>,
    /// `(packed block key, slot + 1 or 0 when absent)` by coordinate parity.
    block_cache: [(u64, u32); 8],
    best: Option<RayHit>,
    origin: Vector3<f32>,
    u: Vector3<f32>,
    max_t: f32,
}
