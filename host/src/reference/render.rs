//! Rendering the reference: [`RenderIndex`], the occupied voxels with their prepared
//! Gaussians, cast and rendered in `f64` as the core casts its rays.

use crate::dataset::frame::{Frame, Rays};
use crate::mapping::LabelView;
use crate::reference::key::{Key, KeyMap};
use anyhow::anyhow;
use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;
use sndt_core::{Config, Error, Isometry3, INVALID_LABEL, KEY_LIMIT};

/// Where a ray first enters an occupied Gaussian of the reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefHit {
    /// Distance from the ray origin, metres.
    pub t: f64,
    /// The voxel's class (1-based), 0 without votes (void).
    pub class: u8,
    /// The voxel hit.
    pub key: Key,
}

/// One renderable voxel: its mean, its inverse covariance (eigenvalue floor applied) and
/// its class.
#[derive(Clone, Copy, Debug)]
pub(super) struct Renderable {
    pub(super) mean: Vector3<f64>,
    pub(super) inv: Matrix3<f64>,
    pub(super) class: u8,
}

/// The renderable voxels of a [`RefMap`](crate::reference::map::RefMap) (occupied,
/// `n >= n_min`) with their prepared Gaussians: ray casting and rendering in `f64`.
///
/// ```
/// use sndt_host::reference::RefMap;
/// use sndt_core::{Config, Isometry3, LabeledPoint, Labels, Point3};
/// let mut map = RefMap::new(Config::DEFAULT, 40);
/// let pts: Vec<_> = (0..100)
///     .map(|i| LabeledPoint::new(
///         Point3::new((i % 10) as f32 * 0.01, (i / 10) as f32 * 0.01, 1.05), Labels::top1(3)))
///     .collect();
/// map.integrate(&Isometry3::identity(), &pts).unwrap();
/// let index = map.render_index();
/// let hit = index.raycast(&[0.05, 0.05, 0.0], &[0.0, 0.0, 1.0], 3.0).unwrap();
/// assert_eq!((hit.class, hit.key), (3, [0, 0, 10]));
/// assert!((hit.t - 1.05).abs() < 0.01);
/// assert!(index.raycast(&[0.05, 0.05, 0.0], &[0.0, 0.0, -1.0], 3.0).is_none());
/// ```
#[derive(Clone, Debug)]
pub struct RenderIndex {
    h: f64,
    radius: f64,
    max_range: f64,
    entries: KeyMap<Renderable>,
}

impl RenderIndex {
    /// The index of `entries`, rendered with `config`'s cell size, render radius and
    /// maximum range.
    pub(super) fn new(config: &Config, entries: KeyMap<Renderable>) -> RenderIndex {
        RenderIndex {
            h: config.cell_size as f64,
            radius: config.render_radius as f64,
            max_range: config.max_range as f64,
            entries,
        }
    }

    /// Number of renderable voxels.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// True when nothing can be hit.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The first Gaussian the ray from `origin` along `dir` (any length) enters within
    /// `max_t` metres: the smallest `t >= 0` with `(s + t u - mu)^T S^-1 (s + t u - mu) =
    /// r^2` over the voxels in the 3x3x3 neighbourhoods of the voxels the ray walks
    /// through; ellipsoids containing the origin are skipped, ties go to the smaller key.
    /// The walk stops 2.5 cells beyond `max_t` or the best hit so far (as the core).
    pub fn raycast(&self, origin: &[f64; 3], dir: &[f64; 3], max_t: f64) -> Option<RefHit> {
        let norm = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
        if !(origin.iter().all(|x| x.is_finite()) && norm.is_finite() && norm > 0.0)
            || max_t.is_nan()
            || max_t <= 0.0
        {
            return None;
        }
        let u = Vector3::new(dir[0], dir[1], dir[2]) / norm;
        let s = Vector3::new(origin[0], origin[1], origin[2]);
        let h = self.h;
        let o = [0, 1, 2].map(|i| origin[i] / h);
        if o.iter().any(|&x| x.abs() > KEY_LIMIT as f64) {
            return None;
        }
        let mut k = o.map(|x| x.floor() as i32);
        let mut best: Option<RefHit> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    self.examine(&[k[0] + dx, k[1] + dy, k[2] + dz], &s, &u, max_t, &mut best);
                }
            }
        }
        let mut step = [0; 3];
        let mut t_next = [f64::INFINITY; 3];
        let mut t_delta = [f64::INFINITY; 3];
        for a in 0..3 {
            if u[a] > 0.0 {
                step[a] = 1;
                t_next[a] = (k[a] as f64 + 1.0 - o[a]) / u[a];
                t_delta[a] = 1.0 / u[a];
            } else if u[a] < 0.0 {
                step[a] = -1;
                t_next[a] = (k[a] as f64 - o[a]) / u[a];
                t_delta[a] = -1.0 / u[a];
            }
        }
        let max_steps = (max_t / h).min(1e7) as u64 * 3 + 12;
        for _ in 0..max_steps {
            let mut a = 0;
            for b in 1..3 {
                if t_next[b] < t_next[a] {
                    a = b;
                }
            }
            let t_enter = t_next[a] * h;
            if t_enter > max_t + 2.5 * h || best.is_some_and(|b| t_enter > b.t + 2.5 * h) {
                break;
            }
            k[a] += step[a];
            t_next[a] += t_delta[a];
            // The 3x3x3 neighbourhood moved by one along `a`: its new face.
            let (b, c) = ((a + 1) % 3, (a + 2) % 3);
            for db in -1..=1 {
                for dc in -1..=1 {
                    let mut cell = k;
                    cell[a] += step[a];
                    cell[b] += db;
                    cell[c] += dc;
                    self.examine(&cell, &s, &u, max_t, &mut best);
                }
            }
        }
        best
    }

    fn examine(
        &self,
        key: &Key,
        s: &Vector3<f64>,
        u: &Vector3<f64>,
        max_t: f64,
        best: &mut Option<RefHit>,
    ) {
        let Some(g) = self.entries.get(key) else {
            return;
        };
        let d = s - g.mean;
        let w = g.inv * u;
        let a = u.dot(&w);
        if a.is_nan() || a <= 0.0 {
            return;
        }
        let b = 2.0 * w.dot(&d);
        let c = d.dot(&(g.inv * d));
        let r2 = self.radius * self.radius;
        let d2 = c - b * b / (4.0 * a);
        if d2 > r2 || c <= r2 {
            return;
        }
        let t = -b / (2.0 * a) - ((r2 - d2) / a).sqrt();
        if !(t >= 0.0 && t <= max_t) {
            return;
        }
        if best.is_none_or(|h| t < h.t || (t == h.t && *key < h.key)) {
            *best = Some(RefHit {
                t,
                class: g.class,
                key: *key,
            });
        }
    }

    /// Renders what a camera at `pose` (camera to world, OpenCV axes) with pixel rays
    /// `rays` sees, as the core's `Map::render`: per pixel the class of the first Gaussian
    /// hit (0 void, [`INVALID_LABEL`] for nothing) and its distance along the ray (0 for
    /// nothing); rays end at `max_range`. Rows in parallel.
    pub fn render(
        &self,
        pose: &Isometry3<f32>,
        rays: &Rays,
        labels: &mut [u8],
        distance: &mut [f32],
    ) -> Result<(), Error> {
        let (w, h) = (rays.width() as usize, rays.height() as usize);
        if labels.len() != w * h || distance.len() != w * h {
            return Err(Error::InvalidImage);
        }
        let r = pose.rotation.to_rotation_matrix().matrix().cast::<f64>();
        let t = pose.translation.vector.cast::<f64>();
        let origin = [t.x, t.y, t.z];
        labels
            .par_chunks_mut(w.max(1))
            .zip(distance.par_chunks_mut(w.max(1)))
            .enumerate()
            .for_each(|(row, (labels, distance))| {
                for (col, (l, d)) in labels.iter_mut().zip(distance.iter_mut()).enumerate() {
                    let c = rays.ray(col as u32, row as u32);
                    let dir = r * Vector3::new(c[0] as f64, c[1] as f64, c[2] as f64);
                    match self.raycast(&origin, &[dir.x, dir.y, dir.z], self.max_range) {
                        Some(hit) => {
                            *l = hit.class;
                            *d = hit.t as f32;
                        }
                        None => {
                            *l = INVALID_LABEL;
                            *d = 0.0;
                        }
                    }
                }
            });
        Ok(())
    }
}

/// The reference's back-projection: [`RenderIndex::render`] into the frame's camera.
impl LabelView for RenderIndex {
    fn render_frame(&self, frame: &Frame) -> anyhow::Result<Vec<u8>> {
        let n = frame.pixels();
        let (mut labels, mut distance) = (vec![0u8; n], vec![0f32; n]);
        self.render(&frame.pose, &frame.rays, &mut labels, &mut distance)
            .map_err(|e| anyhow!("{}: reference render: {e:?}", frame.id))?;
        Ok(labels)
    }
}
