//! Phase 3 of a frame: free space along the rays.
//!
//! One ray per unique end voxel, to the mean of its points with the end voxel excluded
//! (it got its hit in phase 2), and one per unique truncated end, end included; the rays
//! go in the order of the sorted frame list, so the result does not depend on point
//! order. Every voxel a ray traverses (exact 3-D DDA) gets at most one miss per frame. With
//! [`MissModel::NdtOm`] a voxel with a valid Gaussian gets a miss weighted by how close the
//! ray passes to the Gaussian, and none when the ray ends before its closest approach, so
//! grazing rays do not erase thin surfaces.

use crate::block::bits;
use crate::config::{to_fixed, Config, MissModel};
use crate::dda::Dda;
use crate::frame::FrameState;
use crate::gaussian::{PrepCache, Prepared};
use crate::key::VoxelKey;
use crate::map::Map;
use crate::table::{Entry, NIL};
use crate::voxel::Voxel;
use nalgebra::Vector3;

/// Prepared-Gaussian cache of phase 3 (voxel statistics no longer change then).
type GaussCache = PrepCache<32>;

/// A free-space ray in world metres.
struct Ray {
    origin: [f32; 3],
    dir: [f32; 3],
    len: f32,
    /// True when the ray ends at a measured point (false for max-range truncation).
    measured: bool,
}

impl<const V: usize, const B: usize, const C: usize> Map<V, B, C> {
    /// Casts the frame's rays, block by block along the sorted frame list starting at
    /// `head`: to every hit voxel, then to every truncated end that got no points.
    pub(crate) fn clear_free_space(&mut self, f: &mut FrameState, head: u32) {
        let mut cache = GaussCache::new();
        let mut i = head;
        while i != NIL {
            let bs = (i - 1) as usize;
            let b = self.blocks.slots[bs];
            for cell in bits(b.hit) {
                let key = VoxelKey::from_block_cell(b.packed_key(), cell);
                let target = match self.voxels.find(key.packed()) {
                    Some(vs) => mean_in_voxel(&self.voxels.slots[vs], &key, f.qscale),
                    None => centre(&key),
                };
                self.cast(f, &mut cache, target, &key, false);
            }
            for cell in bits(b.far & !b.hit) {
                let key = VoxelKey::from_block_cell(b.packed_key(), cell);
                self.cast(f, &mut cache, centre(&key), &key, true);
            }
            i = b.frame_next;
        }
    }

    /// Exact voxel traversal (Amanatides & Woo) from the sensor to `target` (in voxel
    /// units), giving each traversed voxel its miss; `end` itself only if `include_end`.
    fn cast(
        &mut self,
        f: &mut FrameState,
        cache: &mut GaussCache,
        target: [f32; 3],
        end: &VoxelKey,
        include_end: bool,
    ) {
        f.report.rays += 1;
        let o = f.origin_s;
        let d = [target[0] - o[0], target[1] - o[1], target[2] - o[2]];
        let len_s = libm::sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        let ray = Ray {
            origin: f.origin,
            dir: if len_s > 0.0 {
                [d[0] / len_s, d[1] / len_s, d[2] / len_s]
            } else {
                [0.0, 0.0, 1.0]
            },
            len: len_s * f.h,
            measured: !include_end,
        };
        let start = [
            f.origin_key.x as i32,
            f.origin_key.y as i32,
            f.origin_key.z as i32,
        ];
        let e = [end.x as i32, end.y as i32, end.z as i32];
        traverse(o, target, start, e, include_end, |k| {
            self.miss(f, cache, &ray, &k)
        });
    }

    /// The miss of the voxel with key components `k` for `ray`, once per frame.
    fn miss(&mut self, f: &mut FrameState, cache: &mut GaussCache, ray: &Ray, k: &[i32; 3]) {
        let Some(key) = VoxelKey::from_ints(k[0], k[1], k[2]) else {
            return;
        };
        let Some(bs) = self.frame_block(f, key.block(), false) else {
            f.report.dropped_misses = f.report.dropped_misses.saturating_add(1);
            return;
        };
        let cell = key.cell();
        let bit = 1u64 << cell;
        let b = &self.blocks.slots[bs];
        if b.missed & bit != 0 {
            return;
        }
        let cfg = &self.config;
        let mut delta = to_fixed(cfg.miss);
        if b.surface & bit != 0 && cfg.miss_model == MissModel::NdtOm {
            if let Some(vs) = self.voxels.find(key.packed()) {
                let v = &self.voxels.slots[vs];
                if v.n >= cfg.n_min {
                    let g = cache.get(vs, || v.prepared(cfg));
                    match ndt_om_miss(cfg, ray, &g) {
                        Some(l) => delta = to_fixed(l),
                        None => return,
                    }
                }
            }
        }
        let (lo, hi) = (to_fixed(cfg.clamp_min), to_fixed(cfg.clamp_max));
        let b = &mut self.blocks.slots[bs];
        b.missed |= bit;
        b.add_logodds(cell, delta, lo, hi);
    }
}

/// Exact voxel traversal (Amanatides & Woo) of the segment from `o` to `target` (voxel
/// units) starting in voxel `start` and ending in `end`, visiting `end` only if
/// `include_end`. Axis ties step the lowest axis first; at most the Manhattan distance
/// between the keys plus one voxels are visited.
fn traverse(
    o: [f32; 3],
    target: [f32; 3],
    start: [i32; 3],
    end: [i32; 3],
    include_end: bool,
    mut visit: impl FnMut([i32; 3]),
) {
    let d = [target[0] - o[0], target[1] - o[1], target[2] - o[2]];
    let mut dda = Dda::new(o, d, start);
    let steps: u32 = (0..3).map(|a| (end[a] - start[a]).unsigned_abs()).sum();
    for _ in 0..=steps {
        if dda.k == end {
            if include_end {
                visit(end);
            }
            return;
        }
        visit(dda.k);
        let (a, t) = dda.next_axis();
        if t > 1.0 + 1e-4 {
            return;
        }
        dda.advance(a);
    }
}

/// Visits every voxel the segment from `from` to `to` (metres) passes through, in order,
/// both end voxels included: the same traversal the map uses for free space. Returns
/// `false` (visiting nothing) when an end is outside the key range.
///
/// ```
/// use sndt_core::{voxels_on_segment, VoxelKey};
/// let mut seen = Vec::new();
/// assert!(voxels_on_segment(&[0.05, 0.05, 0.05], &[0.35, 0.15, 0.05], 0.1, |k| seen.push(k)));
/// assert_eq!(seen.first(), Some(&VoxelKey { x: 0, y: 0, z: 0 }));
/// assert_eq!(seen.last(), Some(&VoxelKey { x: 3, y: 1, z: 0 }));
/// assert_eq!(seen.len(), 5);
/// ```
pub fn voxels_on_segment(
    from: &[f32; 3],
    to: &[f32; 3],
    cell_size: f32,
    mut visit: impl FnMut(VoxelKey),
) -> bool {
    let (Some(a), Some(b)) = (
        VoxelKey::from_point(from, cell_size),
        VoxelKey::from_point(to, cell_size),
    ) else {
        return false;
    };
    let o = [
        from[0] / cell_size,
        from[1] / cell_size,
        from[2] / cell_size,
    ];
    let t = [to[0] / cell_size, to[1] / cell_size, to[2] / cell_size];
    let ka = [a.x as i32, a.y as i32, a.z as i32];
    let kb = [b.x as i32, b.y as i32, b.z as i32];
    traverse(o, t, ka, kb, true, |k| {
        if let Some(key) = VoxelKey::from_ints(k[0], k[1], k[2]) {
            visit(key);
        }
    });
    true
}

/// NDT-OM miss log-odds for a ray through a voxel's Gaussian, or `None` when the point of
/// the ray closest to the Gaussian lies beyond the ray's end.
fn ndt_om_miss(cfg: &Config, ray: &Ray, g: &Prepared) -> Option<f32> {
    let u = Vector3::new(ray.dir[0], ray.dir[1], ray.dir[2]);
    let s = Vector3::new(ray.origin[0], ray.origin[1], ray.origin[2]);
    let w = g.inv * u;
    let a = u.dot(&w);
    if a.is_nan() || a <= 0.0 {
        return Some(cfg.miss);
    }
    let t = w.dot(&(g.mean - s)) / a;
    if t > ray.len {
        return None;
    }
    let x = s + u * t;
    let dx = x - g.mean;
    let p_n = libm::expf(-0.5 * dx.dot(&(g.inv * dx)));
    let p_z = if ray.measured {
        let sigma = cfg.noise_base + cfg.noise_quadratic * ray.len * ray.len;
        let dz = ray.len - t;
        libm::expf(-0.5 * dz * dz / (sigma * sigma))
    } else {
        0.0
    };
    let p = 0.5 - cfg.lambda * p_n * (1.0 - p_z);
    Some(libm::logf(p / (1.0 - p)))
}

/// Centre of a voxel in voxel units.
fn centre(key: &VoxelKey) -> [f32; 3] {
    [key.x as f32 + 0.5, key.y as f32 + 0.5, key.z as f32 + 0.5]
}

/// Mean of a voxel's points in voxel units, kept strictly inside the voxel.
fn mean_in_voxel<const C: usize>(v: &Voxel<C>, key: &VoxelKey, qscale: f32) -> [f32; 3] {
    let n = v.n.max(1) as f32;
    let k = [key.x as f32, key.y as f32, key.z as f32];
    let mut m = [0.0; 3];
    for i in 0..3 {
        let off = 0.5 + v.s1[i] as f32 / n / qscale;
        m[i] = k[i] + off.clamp(0.01, 0.99);
    }
    m
}
