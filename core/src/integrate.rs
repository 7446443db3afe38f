//! Frame integration: points into voxel statistics and histograms, one hit per end voxel,
//! free space by exact 3-D DDA with NDT-OM misses.
//!
//! A frame runs in three phases so its result does not depend on point order:
//! 1. every point goes into its voxel's integer sums, and votes in its histogram if the
//!    voxel's vote sample takes it (see [`crate::Config::votes_per_frame`]); the first
//!    point of a voxel in the frame makes room in its histogram, marks it in its block's
//!    `hit` mask and links the block into the frame's block list (points beyond max range
//!    mark a `far` cell instead);
//! 2. the block list is sorted by key; each hit voxel decays to `n_max`, gets one hit and
//!    sets its vote sampling for the next frame from the votes it took in this one;
//! 3. one ray per unique end voxel (to the mean of its points, end voxel excluded) and per
//!    unique truncated end (end included), in sorted order, gives every traversed voxel at
//!    most one miss.

use crate::block::{bits, Block};
use crate::camera::{validate_pose, DepthImage};
use crate::config::{to_fixed, MissModel};
use crate::dda::Dda;
use crate::error::Error;
use crate::gaussian::{PrepCache, Prepared};
use crate::key::{axis_key, floor_i32, VoxelKey};
use crate::labels::{LabeledPoint, Labels};
use crate::map::Map;
use crate::table::{Entry, NIL};
use crate::votes::has_vote;
use crate::voxel::{PointSums, Voxel};
use nalgebra::{Isometry3, Matrix3, Vector3};

/// Most points one frame may hold. With `quant_bits <= 6` and `n_max <= 65535` this bounds a
/// voxel's count at `65535 + 2^20`, so `|S2| <= 2^10 (65535 + 2^20) < 2^31`: no overflow.
pub const MAX_FRAME_POINTS: usize = 1 << 20;

/// What one frame did. Every point is accounted for exactly once in `points_used`,
/// `truncated` or one of the `rejected_*`/`dropped_points` counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FrameReport {
    /// Points folded into voxel statistics.
    pub points_used: u32,
    /// Points beyond max range: they only cleared free space up to max range.
    pub truncated: u32,
    /// NaN/inf coordinates, or zero/negative/NaN/inf depth.
    pub rejected_depth: u32,
    /// A label above the class count, or more than 3 labels.
    pub rejected_label: u32,
    /// Points outside the key range.
    pub rejected_out_of_range: u32,
    /// Points lost because the map was full and nothing could be evicted.
    pub dropped_points: u32,
    /// Free-space updates lost because the map was full and nothing could be evicted.
    pub dropped_misses: u32,
    /// Unique end voxels this frame (= hit updates = rays to surfaces).
    pub end_voxels: u32,
    /// Rays cast (end voxels + unique truncated ends).
    pub rays: u32,
    /// NDT voxels created.
    pub voxels_created: u32,
    /// Occupancy blocks created.
    pub blocks_created: u32,
    /// NDT voxels evicted to make room.
    pub voxels_evicted: u32,
    /// Occupancy blocks evicted to make room.
    pub blocks_evicted: u32,
}

/// Per-frame state; lives on the stack during one integration.
struct Frame {
    rot: Matrix3<f32>,
    origin: [f32; 3],
    origin_s: [f32; 3],
    origin_key: VoxelKey,
    stamp: u16,
    h: f32,
    inv_h: f32,
    /// `2^Q / h`: world metres to quanta.
    inv_quantum: f32,
    /// Key range in quanta: `[-32767 * 2^Q, 32768 * 2^Q)`.
    t_min: f32,
    t_max: f32,
    quant_bits: u32,
    quant_mask: i32,
    qscale: f32,
    qhalf: i32,
    max_range: f32,
    head: u32,
    block_cache: (u64, usize),
    voxel_cache: (u64, usize),
    /// Points of the current run, and the slot of the voxel they are in.
    run: PointSums,
    run_slot: usize,
    voxels_exhausted: bool,
    blocks_exhausted: bool,
    report: FrameReport,
    evicted_before: (u64, u64),
}

impl Frame {
    /// A sensor-frame point in world coordinates (`f32`, the key convention).
    #[inline]
    fn to_world(&self, p: &[f32; 3]) -> [f32; 3] {
        let m = &self.rot;
        let mut w = [0.0f32; 3];
        for (i, wi) in w.iter_mut().enumerate() {
            *wi = m[(i, 0)] * p[0] + m[(i, 1)] * p[1] + m[(i, 2)] * p[2] + self.origin[i];
        }
        w
    }

    /// The voxel key of a world point and its quantised offset, or `None` outside the key
    /// range. Works in quanta (`t = w / h * 2^Q`, an exact power-of-two scaling of
    /// `w / h`): one float-to-int conversion per axis gives both the key
    /// (`floor(t) >> Q`) and the offset (round half up of `t - 2^Q k - 2^(Q-1)`).
    #[inline]
    fn quantise(&self, w: &[f32; 3]) -> Option<(VoxelKey, [i32; 3])> {
        let mut key_i = [0i32; 3];
        let mut q = [0i32; 3];
        for i in 0..3 {
            let t = w[i] * self.inv_quantum;
            if !(t >= self.t_min && t < self.t_max) {
                return None;
            }
            let m = floor_i32(t);
            key_i[i] = m >> self.quant_bits;
            q[i] = (m & self.quant_mask) - self.qhalf + ((t - m as f32) >= 0.5) as i32;
        }
        let key = VoxelKey {
            x: key_i[0] as i16,
            y: key_i[1] as i16,
            z: key_i[2] as i16,
        };
        Some((key, q))
    }
}

/// Prepared-Gaussian cache of phase 3 (voxel statistics no longer change then).
type GaussCache = PrepCache<32>;

impl<const V: usize, const B: usize, const C: usize> Map<V, B, C> {
    /// Integrates one frame of labelled points given in the sensor frame at `pose`
    /// (sensor to world). Per-point problems are counted in the report; a bad pose or an
    /// oversized frame is an error and leaves the map untouched.
    ///
    /// Unless the map had to evict or drop updates during the frame, the result does not
    /// depend on the order of `points`.
    ///
    /// ```
    /// use sndt_core::*;
    /// let mut map: Map<64, 16, 4> = Map::new(Config::DEFAULT);
    /// let pts = [
    ///     LabeledPoint::new(Point3::new(0.0, 0.0, 1.0), Labels::top1(1)),
    ///     LabeledPoint::new(Point3::new(0.0, 0.0, f32::NAN), Labels::top1(1)),
    ///     LabeledPoint::new(Point3::new(0.0, 0.0, 1.0), Labels::top1(9)),
    /// ];
    /// let r = map.integrate(&Isometry3::identity(), &pts).unwrap();
    /// assert_eq!((r.points_used, r.rejected_depth, r.rejected_label), (1, 1, 1));
    /// ```
    pub fn integrate(
        &mut self,
        pose: &Isometry3<f32>,
        points: &[LabeledPoint],
    ) -> Result<FrameReport, Error> {
        if points.len() > MAX_FRAME_POINTS {
            return Err(Error::FrameTooLarge);
        }
        let mut f = self.begin(pose)?;
        for p in points {
            let q = [p.position.x, p.position.y, p.position.z];
            self.add_point(&mut f, q, &p.labels);
        }
        Ok(self.finish(f))
    }

    /// Integrates a depth image with labels (see [`DepthImage`]); invalid depths are
    /// counted in `rejected_depth`.
    pub fn integrate_depth(
        &mut self,
        pose: &Isometry3<f32>,
        image: &DepthImage<'_>,
    ) -> Result<FrameReport, Error> {
        image.validate()?;
        if image.samples() > MAX_FRAME_POINTS {
            return Err(Error::FrameTooLarge);
        }
        let mut f = self.begin(pose)?;
        f.report.rejected_depth += image.for_each_point(|p, l| self.add_point(&mut f, p, &l));
        Ok(self.finish(f))
    }

    fn begin(&mut self, pose: &Isometry3<f32>) -> Result<Frame, Error> {
        validate_pose(pose)?;
        let t = pose.translation.vector;
        let h = self.config.cell_size;
        let origin = [t.x, t.y, t.z];
        let inv_h = 1.0 / h;
        let origin_s = [t.x * inv_h, t.y * inv_h, t.z * inv_h];
        let ok = |s: f32| axis_key(s).map(|k| k as i32);
        let origin_key = match (ok(origin_s[0]), ok(origin_s[1]), ok(origin_s[2])) {
            (Some(x), Some(y), Some(z)) => VoxelKey::from_ints(x, y, z),
            _ => None,
        }
        .ok_or(Error::PoseOutOfRange)?;

        // Frame stamps run 1..=65535; whenever they start over (also when the u32 frame
        // count wraps, or after loading a snapshot), forget all old stamps.
        let stamp = (self.stats.frames % 65535) as u16 + 1;
        if stamp == 1 {
            for b in self.blocks.slots.iter_mut() {
                b.stamp = 0;
            }
        }
        let qscale = (1u32 << self.config.quant_bits) as f32;
        Ok(Frame {
            rot: *pose.rotation.to_rotation_matrix().matrix(),
            origin,
            origin_s,
            origin_key,
            stamp,
            h,
            inv_h,
            inv_quantum: inv_h * qscale,
            t_min: -(crate::key::KEY_LIMIT as f32) * qscale,
            t_max: (crate::key::KEY_LIMIT + 1) as f32 * qscale,
            quant_bits: self.config.quant_bits as u32,
            quant_mask: (1 << self.config.quant_bits) - 1,
            qscale,
            qhalf: 1 << (self.config.quant_bits - 1),
            max_range: self.config.max_range,
            head: NIL,
            block_cache: (0, 0),
            voxel_cache: (0, 0),
            run: PointSums::EMPTY,
            run_slot: usize::MAX,
            voxels_exhausted: false,
            blocks_exhausted: false,
            report: FrameReport::default(),
            evicted_before: (self.stats.voxels_evicted, self.stats.blocks_evicted),
        })
    }

    /// Phase 1 for one point `p` in the sensor frame.
    #[inline]
    fn add_point(&mut self, f: &mut Frame, p: [f32; 3], labels: &Labels) {
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
            self.add_truncated(f, &w, libm::sqrtf(r2));
            return;
        }
        let Some((key, q)) = f.quantise(&w) else {
            f.report.rejected_out_of_range += 1;
            return;
        };
        let packed_block = key.block();
        let bs = if f.block_cache.0 == packed_block {
            f.block_cache.1
        } else {
            match self.frame_block(f, packed_block, true) {
                Some(bs) => bs,
                None => {
                    f.report.dropped_points += 1;
                    return;
                }
            }
        };
        let bit = 1u64 << key.cell();
        let packed = key.packed();
        let vs = if self.blocks.slots[bs].hit & bit == 0 {
            // First point of this voxel in this frame.
            let vs = if self.blocks.slots[bs].surface & bit != 0 {
                self.voxels.find(packed)
            } else {
                None
            };
            let vs = match vs {
                Some(vs) => vs,
                None => match self.create_voxel(f, &key) {
                    Some(vs) => vs,
                    None => {
                        f.report.dropped_points += 1;
                        return;
                    }
                },
            };
            let b = &mut self.blocks.slots[bs];
            b.hit |= bit;
            b.surface |= bit;
            self.voxels.slots[vs].make_vote_room(self.config.votes_per_frame);
            vs
        } else if f.voxel_cache.0 == packed {
            f.voxel_cache.1
        } else {
            match self.voxels.find(packed) {
                Some(vs) => vs,
                None => {
                    f.report.dropped_points += 1;
                    return;
                }
            }
        };
        if f.run_slot != vs {
            self.flush_run(f);
            f.run_slot = vs;
        }
        f.voxel_cache = (packed, vs);
        f.run.add(q);
        if has_vote(labels, &self.config) {
            self.voxels.slots[vs].vote(&p, labels, &self.config);
        }
        f.report.points_used += 1;
    }

    fn add_truncated(&mut self, f: &mut Frame, w: &[f32; 3], range: f32) {
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
        match self.frame_block(f, key.block(), true) {
            Some(bs) => {
                self.blocks.slots[bs].far |= 1u64 << key.cell();
                f.report.truncated += 1;
            }
            None => f.report.dropped_points += 1,
        }
    }

    fn create_voxel(&mut self, f: &mut Frame, key: &VoxelKey) -> Option<usize> {
        if self.voxels.is_full() && !f.voxels_exhausted {
            // Within a frame the evictable set only shrinks: once a scan finds nothing,
            // later inserts of this frame skip the O(capacity) scan.
            f.voxels_exhausted = self.evict_voxels(&f.origin_key, f.stamp) == 0;
            f.voxel_cache = (0, 0);
        }
        let vs = self.voxels.insert(Voxel::new(key)).ok()?;
        f.report.voxels_created += 1;
        Some(vs)
    }

    /// The block with packed key `packed`, created if missing, with per-frame masks
    /// current. `link` puts a newly touched block on the frame's list (phase 1).
    fn frame_block(&mut self, f: &mut Frame, packed: u64, link: bool) -> Option<usize> {
        if f.block_cache.0 == packed {
            return Some(f.block_cache.1);
        }
        let bs = match self.blocks.find(packed) {
            Some(bs) => bs,
            None => {
                if self.blocks.is_full() && !f.blocks_exhausted {
                    f.blocks_exhausted = self.evict_blocks(&f.origin_key, f.stamp) == 0;
                    f.voxel_cache = (0, 0);
                }
                let bs = self.blocks.insert(Block::new(packed)).ok()?;
                f.report.blocks_created += 1;
                bs
            }
        };
        let b = &mut self.blocks.slots[bs];
        if b.touch(f.stamp) && link {
            b.frame_next = f.head;
            f.head = bs as u32 + 1;
        }
        f.block_cache = (packed, bs);
        Some(bs)
    }

    /// Adds the pending run of points (consecutive points in one voxel, summed in
    /// registers) to its voxel. Integer sums make this exact.
    fn flush_run(&mut self, f: &mut Frame) {
        if f.run.n > 0 {
            if let Some(v) = self.voxels.slots.get_mut(f.run_slot) {
                v.merge(&f.run);
            }
        }
        f.run = PointSums::EMPTY;
        f.run_slot = usize::MAX;
    }

    fn finish(&mut self, mut f: Frame) -> FrameReport {
        self.flush_run(&mut f);
        let head = self.sort_frame_list(f.head);
        let cfg = self.config;
        let (lo, hi) = (to_fixed(cfg.clamp_min), to_fixed(cfg.clamp_max));
        let hit = to_fixed(cfg.hit);

        // Phase 2: decay and one hit per end voxel.
        let mut i = head;
        while i != NIL {
            let bs = (i - 1) as usize;
            let b = self.blocks.slots[bs];
            for cell in bits(b.hit) {
                let key = VoxelKey::from_block_cell(b.packed_key(), cell);
                if let Some(vs) = self.voxels.find(key.packed()) {
                    let v = &mut self.voxels.slots[vs];
                    v.decay(cfg.n_max);
                    v.end_vote_sample(cfg.votes_per_frame);
                }
                self.blocks.slots[bs].add_logodds(cell, hit, lo, hi);
                f.report.end_voxels += 1;
            }
            i = b.frame_next;
        }

        // Phase 3: rays in sorted order.
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
                self.cast(&mut f, &mut cache, target, &key, false);
            }
            for cell in bits(b.far & !b.hit) {
                let key = VoxelKey::from_block_cell(b.packed_key(), cell);
                self.cast(&mut f, &mut cache, centre(&key), &key, true);
            }
            i = b.frame_next;
        }

        self.stats.frames = self.stats.frames.wrapping_add(1);
        self.stats.dropped_points += f.report.dropped_points as u64;
        self.stats.dropped_misses += f.report.dropped_misses as u64;
        f.report.voxels_evicted = (self.stats.voxels_evicted - f.evicted_before.0) as u32;
        f.report.blocks_evicted = (self.stats.blocks_evicted - f.evicted_before.1) as u32;
        f.report
    }

    /// Exact voxel traversal (Amanatides & Woo) from the sensor to `target` (in voxel
    /// units), giving each traversed voxel its miss; `end` itself only if `include_end`.
    fn cast(
        &mut self,
        f: &mut Frame,
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

    fn miss(&mut self, f: &mut Frame, cache: &mut GaussCache, ray: &Ray, k: &[i32; 3]) {
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

    /// Bottom-up merge sort of the frame's block list by packed key (no allocation).
    fn sort_frame_list(&mut self, head: u32) -> u32 {
        let key = |m: &Self, i: u32| m.blocks.slots[(i - 1) as usize].packed_key();
        let next = |m: &Self, i: u32| m.blocks.slots[(i - 1) as usize].frame_next;
        let mut list = head;
        let mut insize = 1usize;
        loop {
            let mut p = list;
            list = NIL;
            let mut tail = NIL;
            let mut merges = 0;
            while p != NIL {
                merges += 1;
                let mut q = p;
                let mut psize = 0;
                for _ in 0..insize {
                    psize += 1;
                    q = next(self, q);
                    if q == NIL {
                        break;
                    }
                }
                let mut qsize = insize;
                while psize > 0 || (qsize > 0 && q != NIL) {
                    let e;
                    if psize == 0 {
                        e = q;
                        q = next(self, q);
                        qsize -= 1;
                    } else if qsize == 0 || q == NIL || key(self, p) <= key(self, q) {
                        e = p;
                        p = next(self, p);
                        psize -= 1;
                    } else {
                        e = q;
                        q = next(self, q);
                        qsize -= 1;
                    }
                    if tail == NIL {
                        list = e;
                    } else {
                        self.blocks.slots[(tail - 1) as usize].frame_next = e;
                    }
                    tail = e;
                }
                p = q;
            }
            if tail != NIL {
                self.blocks.slots[(tail - 1) as usize].frame_next = NIL;
            }
            if merges <= 1 {
                return list;
            }
            insize *= 2;
        }
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

/// A free-space ray in world metres.
struct Ray {
    origin: [f32; 3],
    dir: [f32; 3],
    len: f32,
    /// True when the ray ends at a measured point (false for max-range truncation).
    measured: bool,
}

/// NDT-OM miss log-odds for a ray through a voxel's Gaussian, or `None` when the point of
/// the ray closest to the Gaussian lies beyond the ray's end.
fn ndt_om_miss(cfg: &crate::Config, ray: &Ray, g: &Prepared) -> Option<f32> {
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
