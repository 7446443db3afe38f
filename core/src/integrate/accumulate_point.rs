//! Phase 1's accumulation ([`Phase::Accumulate`](crate::Phase::Accumulate)) one point at a
//! time: every point goes into the sums of its end voxel. The batches of `accumulate.rs`
//! send the points they do not handle themselves here, and use the voxel lookup and the
//! accumulators defined here.
//!
//! A point is checked (finite, non-zero, labels that fit the map), moved to world
//! coordinates and quantised to its voxel key and offset. The first point of a voxel in the
//! frame finds or creates the voxel, marks it in its block's `hit` mask (which links the
//! block into the frame's list) and makes room in its histogram; later points find it
//! through the frame's caches. Consecutive points of one voxel are summed in registers (a
//! run) and added to the voxel once. A point votes if its labels do and the voxel's vote
//! sample takes it. Points beyond max range only mark their truncated ray end (`far`).

use crate::geometry::sqrt::sqrt;
use crate::integrate::frame::{accumulator_index, Accumulator, FrameState};
use crate::key::{axis_key, VoxelKey};
use crate::labels::Labels;
use crate::storage::map::Map;
use crate::storage::votes::{vote_max, voting_classes};
use crate::storage::voxel::{packed_offsets, PackedSums, Voxel};

impl<const V: usize, const B: usize, const C: usize> Map<V, B, C> {
    /// Phase 1 for one point `p` in the sensor frame; every point ends in exactly one
    /// counter of the frame's report.
    #[inline]
    pub(crate) fn add_point(&mut self, f: &mut FrameState, p: [f32; 3], labels: &Labels) {
        let r2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
        if !(r2.is_finite() && r2 > 0.0) {
            f.report.rejected_depth += 1;
            return;
        }
        if !labels.fits(C) {
            f.report.rejected_label += 1;
            return;
        }
        let w = f.to_world(&p);
        if r2 > f.max_range * f.max_range {
            self.add_truncated(f, &w, sqrt(r2));
            return;
        }
        let Some((key, q)) = f.quantise(&w) else {
            f.report.rejected_out_of_range += 1;
            return;
        };
        let Some(vs) = self.point_voxel(f, &key) else {
            f.report.dropped_points += 1;
            return;
        };
        self.accumulate_point(f, vs, key.packed(), q);
        let classes = voting_classes(labels, &self.config);
        if let (false, Some(v)) = (classes.is_empty(), self.voxels.get_mut(vs)) {
            v.vote(&p, &classes);
        }
        f.report.points_used += 1;
    }

    /// The slot of the voxel `key` for a point of this frame: through the frame's caches,
    /// or set up by [`Map::first_point`]. `None` when the map is full.
    #[inline]
    pub(crate) fn point_voxel(&mut self, f: &mut FrameState, key: &VoxelKey) -> Option<usize> {
        let bs = self.frame_block(f, key.block(), true)?;
        let bit = 1u64 << key.cell();
        let packed = key.packed();
        let vs = if self.blocks.get(bs)?.hit & bit == 0 {
            self.first_point(f, bs, key)?
        } else if f.voxel_cache.0 == packed {
            f.voxel_cache.1
        } else {
            self.voxels.find(packed)?
        };
        f.voxel_cache = (packed, vs);
        Some(vs)
    }

    /// Sets up voxel `key` (in block slot `bs`) for its first point of the frame: found
    /// (when the block says it has one) or created, marked hit and on the surface, with
    /// room in its histogram for this frame's votes.
    fn first_point(&mut self, f: &mut FrameState, bs: usize, key: &VoxelKey) -> Option<usize> {
        let bit = 1u64 << key.cell();
        let vs = if self.blocks.get(bs)?.surface & bit != 0 {
            self.voxels.find(key.packed())
        } else {
            None
        };
        let vs = match vs {
            Some(vs) => {
                // A new voxel's histogram is empty: room enough.
                self.voxels
                    .get_mut(vs)?
                    .make_vote_room(self.config.votes_per_frame);
                vs
            }
            None => self.create_voxel(f, key)?,
        };
        let b = self.blocks.get_mut(bs)?;
        b.hit |= bit;
        b.surface |= bit;
        Some(vs)
    }

    /// Adds a point's offset to the accumulator of voxel slot `vs` (packed key `key`).
    #[inline]
    fn accumulate_point(&mut self, f: &mut FrameState, vs: usize, key: u64, q: [i32; 3]) {
        let a = accumulator_index(key);
        if f.acc[a].key != key {
            self.open_accumulator(f, a, vs, key);
        }
        self.add_to_accumulator(f, a, &packed_offsets(q), 1);
    }

    /// Adds the sum `w` of the [`packed_offsets`] of `n <= 64` points to accumulator
    /// `a`, which must hold their voxel; an accumulator that could overflow is added to
    /// its voxel first.
    #[inline]
    pub(crate) fn add_to_accumulator(
        &mut self,
        f: &mut FrameState,
        a: usize,
        w: &[u64; 3],
        n: u32,
    ) {
        if let Some(acc) = f.acc.get_mut(a) {
            self.add_sums(acc, w, n);
        }
    }

    /// [`Map::add_to_accumulator`] for the accumulator itself.
    #[inline(always)]
    fn add_sums(&mut self, acc: &mut Accumulator, w: &[u64; 3], n: u32) {
        if acc.sums.n + n > PackedSums::MAX_POINTS {
            if let Some(v) = self.voxels.slots.get_mut(acc.slot) {
                v.merge(&acc.sums.unbias());
            }
            acc.sums = PackedSums::EMPTY;
        }
        acc.sums.add(w, n);
    }

    /// Makes accumulator `a` hold voxel slot `vs` (packed key `key`), adding the points
    /// of the voxel it held to that voxel.
    #[inline]
    pub(crate) fn open_accumulator(&mut self, f: &mut FrameState, a: usize, vs: usize, key: u64) {
        let Some(acc) = f.acc.get_mut(a) else {
            return;
        };
        self.flush(acc);
        *acc = Accumulator {
            sums: PackedSums::EMPTY,
            slot: vs,
            key,
            vote_key_max: vote_max(self.voxels.slots.get(vs).map_or(0, Voxel::vote_exponent)) >> 1,
            votes: (0, 0),
        };
    }

    /// Adds every open accumulator to its voxel.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    pub(crate) fn flush_accumulators(&mut self, f: &mut FrameState) {
        for acc in f.acc.iter_mut() {
            self.flush(acc);
        }
    }

    /// Adds an accumulator's points to its voxel and empties it.
    #[inline]
    fn flush(&mut self, acc: &mut Accumulator) {
        if let Some(v) = self.voxels.slots.get_mut(acc.slot) {
            if acc.sums.n > 0 {
                v.merge(&acc.sums.unbias());
            }
            let (class, count) = acc.votes;
            if count > 0 {
                v.take_votes(class, count);
            }
        }
        *acc = Accumulator::NONE;
    }

    /// One point with [`packed_offsets`] `w` into accumulator `a` (see
    /// [`Map::add_to_accumulator`]), and its vote for `class` (0: none), which the
    /// accumulator counts while its class stays the same (see [`Accumulator::votes`]).
    #[inline(always)]
    pub(crate) fn add_voting_point(
        &mut self,
        f: &mut FrameState,
        a: usize,
        w: &[u64; 3],
        class: u8,
    ) {
        let Some(acc) = f.acc.get_mut(a) else {
            return;
        };
        let (pending, count) = acc.votes;
        if class != 0 {
            if pending == class || count == 0 {
                acc.votes = (class, count + 1);
            } else {
                if let Some(v) = self.voxels.slots.get_mut(acc.slot) {
                    v.take_votes(pending, count);
                }
                acc.votes = (class, 1);
            }
        }
        self.add_sums(acc, w, 1);
    }

    /// A point at world position `w`, `range` metres from the sensor, beyond max range:
    /// marks the voxel where its ray reaches max range as a truncated end (`far`).
    fn add_truncated(&mut self, f: &mut FrameState, w: &[f32; 3], range: f32) {
        let scale = f.max_range / range;
        let mut k = [0i16; 3];
        for i in 0..3 {
            let e = f.origin[i] + (w[i] - f.origin[i]) * scale;
            match axis_key(e * f.inv_h) {
                Some(v) => k[i] = v,
                None => {
                    f.report.rejected_out_of_range += 1;
                    return;
                }
            }
        }
        let key = VoxelKey {
            x: k[0],
            y: k[1],
            z: k[2],
        };
        match self
            .frame_block(f, key.block(), true)
            .and_then(|bs| self.blocks.get_mut(bs))
        {
            Some(b) => {
                b.far |= 1u64 << key.cell();
                f.report.truncated += 1;
            }
            None => f.report.dropped_points += 1,
        }
    }

    /// Inserts a new voxel, evicting far voxels when the table is full.
    fn create_voxel(&mut self, f: &mut FrameState, key: &VoxelKey) -> Option<usize> {
        if self.voxels.is_full() && !f.voxels_exhausted {
            // Within a frame the evictable set only shrinks: once a scan finds nothing,
            // later inserts of this frame skip the O(capacity) scan.
            f.voxels_exhausted = self.evict_voxels(f) == 0;
            f.voxel_cache = (0, 0);
        }
        let vs = self.voxels.insert(Voxel::new(key)).ok()?;
        f.report.voxels_created += 1;
        Some(vs)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use crate::testutil::*;
    use crate::*;
    use std::vec::Vec;

    #[test]
    fn integrated_gaussian_exact_for_known_quanta() {
        // h = 1/8 and points on binary fractions: every quantised offset is known exactly
        // (a quarter quantum above the quantum's centre, far from any rounding tie).
        let h = 0.125f32;
        let mut cfg = Config::with_cell_size(h);
        cfg.n_max = 65535;
        let mut map: Map<16, 16, 2> = Map::try_new(cfg).unwrap();
        let k = key(-3, 5, 12);
        let qs = [
            [-20, 3, 0],
            [7, -9, 14],
            [31, 31, -31],
            [0, 0, 1],
            [-32, 12, 5],
        ];
        let pts: Vec<_> = qs
            .iter()
            .map(|q| {
                let c = |ki: i16, qi: i32| (ki as f32 * 64.0 + 32.0 + qi as f32 + 0.25) / 512.0;
                lp(c(k.x, q[0]), c(k.y, q[1]), c(k.z, q[2]), 1)
            })
            .collect();
        let r = map.integrate(&Isometry3::identity(), &pts).unwrap();
        assert_eq!(r.points_used, 5);
        let v = voxel(&map, &k);
        let s1: [i32; 3] = core::array::from_fn(|i| qs.iter().map(|q| q[i]).sum());
        assert_eq!(v.s1, s1);
        assert_eq!(v.n, 5);
        let g = map.gaussian(&k).unwrap();
        let (mean, cov) = gaussian_f64(&qs, &k, 0.125, 0.125 / 64.0);
        assert_gaussian_exact(&g, mean, cov);
    }

    #[test]
    fn integrated_gaussian_close_to_raw_points() {
        // Arbitrary points in one voxel at h = 0.1: mean within half a quantum (plus f32
        // rounding), covariance within the quantisation error of a sample covariance.
        let h = 0.1f64;
        let step = h / 64.0;
        let k = key(2, -3, 10);
        let mut rng = Lcg(7);
        let mut raw = Vec::new();
        for _ in 0..60 {
            let p: [f64; 3] = core::array::from_fn(|i| {
                let ki = [k.x, k.y, k.z][i] as f64;
                // Spread over the middle of the voxel, more along x than z.
                let spread = [0.8, 0.5, 0.2][i];
                (ki + 0.5 + spread * (rng.next() - 0.5)) * h
            });
            raw.push(p);
        }
        let pts: Vec<_> = raw
            .iter()
            .map(|p| lp(p[0] as f32, p[1] as f32, p[2] as f32, 2))
            .collect();
        let mut map: Map<16, 16, 2> = Map::new(Config::DEFAULT);
        let r = map.integrate(&Isometry3::identity(), &pts).unwrap();
        assert_eq!(r.points_used, 60);
        let g = map.gaussian(&k).unwrap();
        assert_eq!(g.count, 60);
        let n = raw.len() as f64;
        let mean: [f64; 3] = core::array::from_fn(|i| raw.iter().map(|p| p[i]).sum::<f64>() / n);
        let mut cov = [[0.0; 3]; 3];
        for p in &raw {
            for i in 0..3 {
                for j in 0..3 {
                    cov[i][j] += (p[i] - mean[i]) * (p[j] - mean[j]) / (n - 1.0);
                }
            }
        }
        let dev: [f64; 3] = core::array::from_fn(|i| {
            raw.iter()
                .map(|p| (p[i] - mean[i]).abs())
                .fold(0.0, f64::max)
        });
        for i in 0..3 {
            assert!(
                (g.mean[i] as f64 - mean[i]).abs() <= 0.5 * step + 1e-6,
                "mean[{i}] {} vs {}",
                g.mean[i],
                mean[i]
            );
            for j in 0..3 {
                // Each offset moves by e, |e| <= step/2 per axis, so the sample covariance moves
                // by at most step/2 (max|dx_i| + max|dx_j|) + step^2/4, times n/(n-1), plus f32
                // rounding.
                let bound = (0.5 * step * (dev[i] + dev[j]) + 0.25 * step * step) * n / (n - 1.0)
                    + 1e-6 * cov[i][i].max(cov[j][j]);
                assert!(
                    (g.covariance[(i, j)] as f64 - cov[i][j]).abs() <= bound,
                    "cov[{i}{j}] {} vs {} (bound {bound})",
                    g.covariance[(i, j)],
                    cov[i][j]
                );
            }
        }
        // And the covariance really carries the anisotropy of the points.
        assert!(g.covariance[(0, 0)] > 4.0 * g.covariance[(2, 2)]);
    }
}
