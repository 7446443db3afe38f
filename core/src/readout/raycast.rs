//! Ray casting against the map's Gaussians: [`Map::raycast`], one ray at a time.
//!
//! A ray walks the grid by DDA; around every traversed voxel it examines the 3x3x3
//! neighbourhood (each neighbour exactly once per ray, by adding only the 9 cells of the new
//! face at each step) for occupied voxels with a valid Gaussian and computes where the ray
//! enters the ellipsoid of Mahalanobis radius `r` ([`Prep::enter`]). Ellipsoids that
//! contain the origin are skipped. The hit is the smallest `(t, key)`, so the order in
//! which candidates are examined does not matter, and the walk stops 2.5 cells beyond the
//! best hit so far. A face is intersected with the `surface` masks of the at most four
//! blocks it touches, so only cells that hold an NDT voxel are looked at.
//!
//! Whole images are rendered differently (`render.rs`: every visible Gaussian drawn over
//! the pixels it covers), with the per-pixel test [`Prep::enter`] shared, so both give the
//! same distances.

use crate::geometry::dda::Dda;
use crate::geometry::gaussian::Prepared;
use crate::geometry::sqrt::sqrt;
use crate::key::{VoxelKey, KEY_LIMIT};
use crate::storage::block::bits;
use crate::storage::map::Map;
use crate::storage::voxel::argmax;
use nalgebra::{Matrix3, Point3, Vector3};

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

/// Prepared-Gaussian cache entries of one `raycast`.
const RAY_PREPS: usize = 4;

/// A voxel's Gaussian prepared for rays from one origin.
#[derive(Clone, Copy)]
pub(crate) struct Prep {
    /// Inverse covariance (eigenvalue floor applied).
    pub(crate) inv: Matrix3<f32>,
    /// Origin minus mean.
    pub(crate) d: Vector3<f32>,
    /// Class of the voxel (0 = void).
    pub(crate) class: u8,
}

impl Prep {
    /// `g` seen from `origin`, or `None` when its ellipsoid of squared radius `r2` contains
    /// the origin (such a Gaussian is never hit).
    #[inline]
    pub(crate) fn new(g: &Prepared, class: u8, origin: &Vector3<f32>, r2: f32) -> Option<Prep> {
        let d = origin - g.mean;
        let c = d.dot(&(g.inv * d));
        // NaN falls through to the ray test, which rejects it.
        if matches!(
            c.partial_cmp(&r2),
            Some(core::cmp::Ordering::Less | core::cmp::Ordering::Equal)
        ) {
            return None;
        }
        Some(Prep {
            inv: g.inv,
            d,
            class,
        })
    }

    /// Where the ray from the origin along the unit vector `u` enters the ellipsoid of
    /// squared Mahalanobis radius `r2`, if that is within `0..=max_t`: with
    /// `a = u^T S^-1 u` and `b = 2 u^T S^-1 d`, the closest approach is at `t* = -b / 2a`
    /// with squared distance `D2`, and the ray enters at `t* - sqrt((r2 - D2) / a)`.
    #[inline(always)]
    pub(crate) fn enter(&self, u: &Vector3<f32>, r2: f32, max_t: f32) -> Option<f32> {
        let w = self.inv * u;
        let a = u.dot(&w);
        let bq = 2.0 * w.dot(&self.d);
        if a.is_nan() || a <= 0.0 {
            return None;
        }
        // `D2` evaluated at the closest point (e = d + t* u) rather than as `c - b^2/4a`:
        // for thin surface Gaussians `c` reaches ~1e7 and the subtraction cancels to noise
        // in f32 (the f64 reference showed it flipping hits at 5 cm).
        let t_star = -bq / (2.0 * a);
        let e = self.d + u * t_star;
        let d2 = e.dot(&(self.inv * e));
        if d2 > r2 {
            return None;
        }
        let t = t_star - sqrt((r2 - d2) / a);
        if !(t >= 0.0 && t <= max_t) {
            return None;
        }
        Some(t)
    }

    /// [`Prep::enter`] for [`LANES`] rays at once (`u[axis][lane]`, NaN for no ray): the
    /// same operations in the same order, so the same bits, written lane by lane so that
    /// the compiler can use vector instructions. NaN where a ray does not enter.
    #[inline(always)]
    pub(crate) fn enter_lanes(&self, u: &Lanes3, r2: f32, max_t: f32) -> [f32; LANES] {
        let m = |i: usize, j: usize| self.inv[(i, j)];
        let (mut t_star, mut q, mut ok) = ([0f32; LANES], [0f32; LANES], [false; LANES]);
        for l in 0..LANES {
            let (x, y, z) = (u[0][l], u[1][l], u[2][l]);
            let w = [0, 1, 2].map(|i| m(i, 0) * x + m(i, 1) * y + m(i, 2) * z);
            let a = x * w[0] + y * w[1] + z * w[2];
            let bq = 2.0 * (w[0] * self.d.x + w[1] * self.d.y + w[2] * self.d.z);
            let ts = -bq / (2.0 * a);
            let e = [self.d.x + x * ts, self.d.y + y * ts, self.d.z + z * ts];
            let ie = [0, 1, 2].map(|i| m(i, 0) * e[0] + m(i, 1) * e[1] + m(i, 2) * e[2]);
            let d2 = e[0] * ie[0] + e[1] * ie[1] + e[2] * ie[2];
            t_star[l] = ts;
            q[l] = (r2 - d2) / a;
            ok[l] = a > 0.0 && (d2 <= r2 || d2.is_nan());
        }
        let mut out = [f32::NAN; LANES];
        for l in 0..LANES {
            let t = t_star[l] - sqrt(q[l]);
            if ok[l] && t >= 0.0 && t <= max_t {
                out[l] = t;
            }
        }
        out
    }
}

/// Rays tested together by [`Prep::enter_lanes`].
pub(crate) const LANES: usize = 8;

/// [`LANES`] vectors by axis: `v[axis][lane]`.
pub(crate) type Lanes3 = [[f32; LANES]; 3];

/// Caches of one ray: prepared Gaussians and the blocks of the walk.
struct Scratch {
    /// `((block slot + 1) << 6 | cell, prepared or None when it cannot be hit)`.
    preps: [(u64, Option<Prep>); RAY_PREPS],
    /// `(packed block key, slot + 1 or 0 when absent, surface mask)` by the parity of the
    /// block coordinates: the blocks of a 2x2x2 neighbourhood never evict each other.
    blocks: [(u64, u32, u64); 8],
}

/// Per-ray state.
struct Ray {
    origin: Vector3<f32>,
    u: Vector3<f32>,
    max_t: f32,
    r2: f32,
    best: Option<RayHit>,
}

/// Packed key of the block at block coordinates `b`, if it holds any valid voxel key.
#[inline]
fn block_packed(b: [i32; 3]) -> Option<u64> {
    // Cell 3 of the block is valid iff some cell of the block is: block -8192 holds
    // -32768 (invalid) to -32765, block 8191 ends at 32767.
    let c = |v: i32| v.saturating_mul(4).saturating_add(3);
    VoxelKey::from_ints(c(b[0]), c(b[1]), c(b[2])).map(|k| k.block())
}

/// Cells of a block whose coordinates lie in `lo..=hi` (block-local) on every axis.
#[inline]
fn box_mask(lo: [i32; 3], hi: [i32; 3]) -> u64 {
    // Contiguous bit run `[l * w, (h + 1) * w)` with `0 <= l`, `h <= 3`, `w * 4 <= 64`.
    let run = |l: i32, h: i32, w: u32| -> u64 {
        let (l, h) = (l.clamp(0, 3) as u32, h.clamp(0, 3) as u32);
        if l > h {
            return 0;
        }
        (u64::MAX >> (64 - (h + 1) * w)) & (u64::MAX << (l * w))
    };
    let x = run(lo[0], hi[0], 1) * 0x1111_1111_1111_1111;
    let y = run(lo[1], hi[1], 4) * 0x0001_0001_0001_0001;
    let z = run(lo[2], hi[2], 16);
    x & y & z
}

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
        let mut s = Scratch {
            preps: [(0, None); RAY_PREPS],
            blocks: [(0, 0, 0); 8],
        };
        let mut ray = Ray {
            origin: Vector3::new(origin.x, origin.y, origin.z),
            u,
            max_t,
            r2: cfg.render_radius * cfg.render_radius,
            best: None,
        };
        self.examine_box(&mut s, &mut ray, k.map(|v| v - 1), k.map(|v| v + 1));
        // No ray can walk farther than across the whole key range.
        let max_t = max_t.min(h * 4.0 * (KEY_LIMIT + 1) as f32);
        let max_steps = ((max_t / h) as u32).saturating_mul(3).saturating_add(12);
        let reach = 2.5 * h;
        for _ in 0..max_steps {
            let (a, t) = dda.next_axis();
            let t_enter = t * h;
            if t_enter > max_t + reach {
                break;
            }
            if let Some(best) = ray.best
                && t_enter > best.t + reach
            {
                break;
            }
            dda.advance(a);
            // Only the 9 cells of the neighbourhood's new face are unseen.
            let (mut lo, mut hi) = (dda.k.map(|v| v - 1), dda.k.map(|v| v + 1));
            let f = dda.k[a] + dda.step(a);
            lo[a] = f;
            hi[a] = f;
            self.examine_box(&mut s, &mut ray, lo, hi);
        }
        ray.best
    }

    /// Examines every surface cell in the box `lo..=hi` (voxel keys, at most 2 blocks wide
    /// on each axis).
    fn examine_box(&self, s: &mut Scratch, ray: &mut Ray, lo: [i32; 3], hi: [i32; 3]) {
        let (b0, b1) = (lo.map(|v| v >> 2), hi.map(|v| v >> 2));
        for bz in b0[2]..=b1[2] {
            for by in b0[1]..=b1[1] {
                for bx in b0[0]..=b1[0] {
                    let b = [bx, by, bz];
                    let Some((slot, surface)) = self.block_in(s, b) else {
                        continue;
                    };
                    let base = b.map(|v| v * 4);
                    let mask = surface
                        & box_mask(
                            [lo[0] - base[0], lo[1] - base[1], lo[2] - base[2]],
                            [hi[0] - base[0], hi[1] - base[1], hi[2] - base[2]],
                        );
                    for cell in bits(mask) {
                        let k = [
                            base[0] + (cell & 3) as i32,
                            base[1] + ((cell >> 2) & 3) as i32,
                            base[2] + ((cell >> 4) & 3) as i32,
                        ];
                        if let Some(key) = VoxelKey::from_ints(k[0], k[1], k[2]) {
                            self.examine(s, ray, slot, cell, key);
                        }
                    }
                }
            }
        }
    }

    /// Slot and surface mask of the block at block coordinates `b`, through the parity cache.
    #[inline]
    fn block_in(&self, s: &mut Scratch, b: [i32; 3]) -> Option<(usize, u64)> {
        let packed = block_packed(b)?;
        let i = ((b[0] & 1) | ((b[1] & 1) << 1) | ((b[2] & 1) << 2)) as usize;
        let e = s.blocks.get_mut(i)?;
        if e.0 != packed {
            let slot = self.blocks.find(packed);
            let surface = slot
                .and_then(|sl| self.blocks.slots.get(sl))
                .map_or(0, |blk| blk.surface);
            *e = (packed, slot.map_or(0, |sl| sl as u32 + 1), surface);
        }
        if e.1 == 0 {
            return None;
        }
        Some(((e.1 - 1) as usize, e.2))
    }

    /// Tests the surface cell `cell` of the block in `slot` (voxel `key`) against the ray.
    fn examine(&self, s: &mut Scratch, ray: &mut Ray, slot: usize, cell: u32, key: VoxelKey) {
        let Some(blk) = self.blocks.slots.get(slot) else {
            return;
        };
        if blk.cells.get(cell as usize).is_none_or(|&l| l <= 0) {
            return;
        }
        let tag = ((slot as u64 + 1) << 6) | cell as u64;
        let Some(entry) = s.preps.get_mut(tag as usize % RAY_PREPS) else {
            return;
        };
        if entry.0 != tag {
            *entry = (tag, self.prep(&key, &ray.origin, ray.r2));
        }
        let Some(p) = &entry.1 else {
            return;
        };
        let Some(t) = p.enter(&ray.u, ray.r2, ray.max_t) else {
            return;
        };
        if ray
            .best
            .is_none_or(|best| t < best.t || (t == best.t && key < best.key))
        {
            ray.best = Some(RayHit {
                t,
                class: p.class,
                key,
            });
        }
    }

    /// The Gaussian of voxel `key` prepared for rays from `origin`, if it can be hit.
    fn prep(&self, key: &VoxelKey, origin: &Vector3<f32>, r2: f32) -> Option<Prep> {
        let v = self
            .voxels
            .find(key.packed())
            .and_then(|vs| self.voxels.slots.get(vs))?;
        if v.n < self.config.n_min {
            return None;
        }
        let class = argmax(&v.hist).map_or(0, |(c, _)| c);
        Prep::new(&v.prepared(&self.config), class, origin, r2)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    extern crate std;

    use super::*;
    use crate::geometry::gaussian::PrepCache;
    use crate::storage::block::Block;
    use crate::storage::table::Table;
    use crate::testutil::*;
    use crate::*;
    use std::boxed::Box;
    use std::vec::Vec;

    struct Probe<'a, const B: usize, const N: usize> {
        blocks: &'a Table<Block, B>,
        cache: &'a mut PrepCache<N>,
        block_cache: [(u64, u32); 8],
        best: Option<RayHit>,
        origin: Vector3<f32>,
        u: Vector3<f32>,
        max_t: f32,
    }

    pub(crate) fn reference_raycast<
        const V: usize,
        const B: usize,
        const C: usize,
        const N: usize,
    >(
        map: &Map<V, B, C>,
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
        let cfg = &map.config;
        let h = cfg.cell_size;
        let start = map.voxel_key(&[origin.x, origin.y, origin.z])?;
        let inv = 1.0 / h;
        let o = [origin.x * inv, origin.y * inv, origin.z * inv];
        let k = [start.x as i32, start.y as i32, start.z as i32];
        let mut dda = Dda::new(o, [u.x, u.y, u.z], k);
        let mut probe = Probe {
            blocks: &map.blocks,
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
                    reference_examine(map, &mut probe, [k[0] + dx, k[1] + dy, k[2] + dz]);
                }
            }
        }
        let max_t = max_t.min(h * 4.0 * (crate::KEY_LIMIT + 1) as f32);
        let max_steps = ((max_t / h) as u32).saturating_mul(3).saturating_add(12);
        for _ in 0..max_steps {
            let (a, t) = dda.next_axis();
            let t_enter = t * h;
            if t_enter > max_t + 2.5 * h {
                break;
            }
            if let Some(best) = probe.best
                && t_enter > best.t + 2.5 * h
            {
                break;
            }
            dda.advance(a);
            let (b, c) = ((a + 1) % 3, (a + 2) % 3);
            for db in -1..=1 {
                for dc in -1..=1 {
                    let mut cell = dda.k;
                    cell[a] += dda.step(a);
                    cell[b] += db;
                    cell[c] += dc;
                    reference_examine(map, &mut probe, cell);
                }
            }
        }
        probe.best
    }

    fn reference_examine<const V: usize, const B: usize, const C: usize, const N: usize>(
        map: &Map<V, B, C>,
        p: &mut Probe<'_, B, N>,
        k: [i32; 3],
    ) {
        let Some(key) = VoxelKey::from_ints(k[0], k[1], k[2]) else {
            return;
        };
        let packed = key.block();
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
        let Some(b) = p.blocks.linked(found) else {
            return;
        };
        let cell = key.cell();
        if b.surface & (1u64 << cell) == 0 || b.cells[cell as usize] <= 0 {
            return;
        }
        let Some(vs) = map.voxels.find(key.packed()) else {
            return;
        };
        let Some(v) = map.voxels.get(vs) else {
            return;
        };
        let cfg = &map.config;
        if v.n < cfg.n_min {
            return;
        }
        let g = p.cache.get(vs, || v.prepared(cfg));
        let d = p.origin - g.mean;
        let w = g.inv * p.u;
        let a = p.u.dot(&w);
        let bq = 2.0 * w.dot(&d);
        let c = d.dot(&(g.inv * d));
        if a.is_nan() || a <= 0.0 {
            return;
        }
        let r2 = cfg.render_radius * cfg.render_radius;
        let t_star = -bq / (2.0 * a);
        let e = d + p.u * t_star;
        let d2 = e.dot(&(g.inv * e));
        if d2 > r2 || c <= r2 {
            return;
        }
        let t = t_star - libm::sqrtf((r2 - d2) / a);
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

    /// Single rays from inside and outside the room in many directions, with short `max_t`.
    #[test]
    fn raycast_matches_reference() {
        big_stack(|| {
            let map = room_map(0.1, 6);
            let mut cache = PrepCache::<8>::new();
            let mut state = 12345u32;
            let mut rnd = move || {
                state ^= state << 13;
                state ^= state >> 17;
                state ^= state << 5;
                state as f32 / u32::MAX as f32
            };
            let mut hits = 0;
            // 800 rays: a quarter of them with an unbounded max_t, which the reference
            // walks to the end of the key range when they miss (most of the test's time).
            for i in 0..800 {
                let o = Point3::new(rnd() * 8.0 - 1.0, rnd() * 7.0 - 1.0, rnd() * 4.0 - 0.6);
                let d = Vector3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5);
                let max_t = [20.0, 1.0, 0.3, f32::INFINITY][i % 4];
                let want = reference_raycast(&map, &mut cache, &o, &d, max_t);
                let got = map.raycast(&o, &d, max_t);
                assert_eq!(
                    got.map(|h| (h.t.to_bits(), h.class, h.key)),
                    want.map(|h| (h.t.to_bits(), h.class, h.key)),
                    "ray {i}"
                );
                hits += got.is_some() as usize;
            }
            assert!(hits > 160, "{hits}");
        });
    }

    /// Surfaces at both ends of the key range: blocks whose cells are partly outside it.
    #[test]
    fn raycast_matches_reference_at_key_limit() {
        let mut map: Box<Map<4096, 1024, 4>> = Box::new(Map::new(Config::with_cell_size(1.0)));
        for x in [-32766.5f32, 32766.5] {
            let mut pts = Vec::new();
            for i in 0..400 {
                let (u, v) = ((i % 20) as f32 * 0.25 - 2.5, (i / 20) as f32 * 0.25 - 2.5);
                pts.push(LabeledPoint::new(
                    Point3::new(x + (i % 3) as f32 * 0.3, u, v),
                    Labels::top1(2),
                ));
            }
            let origin = Isometry3::translation(x.signum() * 32760.0, 0.3, 0.2);
            let pts: Vec<_> = pts
                .iter()
                .map(|p| LabeledPoint::new(origin.inverse() * p.position, p.labels))
                .collect();
            map.integrate(&origin, &pts).unwrap();
        }
        let mut cache = PrepCache::<8>::new();
        let mut hits = 0;
        for sx in [-1.0f32, 1.0] {
            for i in 0..200 {
                let a = i as f32 * 0.031;
                let o = Point3::new(sx * 32762.0, 0.3 * libm::cosf(a), 0.2 * libm::sinf(a));
                let d = Vector3::new(sx, 0.4 * libm::sinf(a * 3.0), 0.4 * libm::cosf(a * 2.0));
                let want = reference_raycast(&map, &mut cache, &o, &d, 50.0);
                assert_eq!(map.raycast(&o, &d, 50.0), want, "ray {sx} {i}");
                hits += want.is_some() as usize;
            }
        }
        assert!(hits > 100, "{hits}");
    }

    /// Regression: `raycast` computes `(max_t / h) as u32 * 3 + 12`: `max_t = inf` (accepted, only
    /// `max_t > 0` is checked) saturates the cast and overflows the product (debug panic);
    /// in release the step count wraps to 9 and a wall 2 m away is missed.
    #[test]
    fn raycast_with_infinite_max_t() {
        let mut map: Map<512, 256, 2> = Map::new(Config::DEFAULT);
        let mut pts = [lp(0.0, 0.0, 0.0, 1); 400];
        for (i, p) in pts.iter_mut().enumerate() {
            let (u, v) = ((i % 20) as f32 / 20.0 - 0.5, (i / 20) as f32 / 20.0 - 0.5);
            p.position = Point3::new(u, v, 2.02);
        }
        map.integrate(&Isometry3::identity(), &pts).unwrap();
        let hit = map.raycast(&Point3::new(0.05, 0.05, 0.0), &Vector3::z(), f32::INFINITY);
        assert!(hit.is_some_and(|h| (h.t - 2.02).abs() < 0.05));
    }

    #[test]
    fn nalgebra_norm_is_libm_sqrt() {
        // The core's only transcendental through nalgebra is sqrt (`norm`, quaternion from
        // matrix). In test builds num-traits' `std` feature (from proptest) routes it to
        // `f32::sqrt`, in firmware builds to `libm::sqrtf`; both are correctly rounded, so they
        // must agree bit for bit.
        let mut rng = Lcg(17);
        for i in 0..20000 {
            let e = i % 40 - 20;
            let s = libm::ldexpf(1.0, e);
            let v = Vector3::new(
                (rng.next() as f32 - 0.5) * s,
                (rng.next() as f32 - 0.5) * s,
                (rng.next() as f32 - 0.5) * s,
            );
            assert_eq!(
                v.norm().to_bits(),
                libm::sqrtf(v.norm_squared()).to_bits(),
                "{v}"
            );
        }
    }
}
