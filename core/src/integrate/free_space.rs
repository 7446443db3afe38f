//! Phase 3 of a frame: free space along the rays.
//!
//! One ray per unique end voxel, to the mean of its points with the end voxel excluded
//! (it got its hit in phase 2), and one per unique truncated end, end included; the rays
//! go in the order of the sorted frame list, so the result does not depend on point
//! order. Every voxel a ray traverses (exact 3-D DDA) gets at most one miss per frame. With
//! [`MissModel::NdtOm`] a voxel with a valid Gaussian gets a miss weighted by how close the
//! ray passes to the Gaussian, and none when the ray ends before its closest approach, so
//! grazing rays do not erase thin surfaces. With [`Config::see_through_miss`] on, a
//! surface voxel that got no points this frame takes that stronger miss from a ray through
//! the middle of its Gaussian, or, in a depth frame, when the pixel its mean projects to
//! saw beyond it.

use crate::config::{to_fixed, Config, MissModel};
use crate::geometry::camera::{DepthImage, DepthKind};
use crate::geometry::dda::{lane_keys, traverse, Dda, LANES, LANE_STEPS};
use crate::geometry::gaussian::{PrepCache, Prepared};
use crate::geometry::sqrt::sqrt;
use crate::integrate::frame::FrameState;
use crate::key::{
    block_of_packed, cell_of_packed, key_of, VoxelKey, KEY_LIMIT, X_FIELD, Y_FIELD, Z_FIELD,
};
use crate::storage::block::bits;
use crate::storage::map::Map;
use crate::storage::table::Entry;
use crate::storage::voxel::{argmax, Voxel};
use nalgebra::Vector3;

/// Prepared-Gaussian cache of phase 3 (voxel statistics no longer change then).
type GaussCache = PrepCache<32>;

/// A free-space ray in voxel units: `o` to `target`, from the sensor's voxel `start` to
/// the end voxel `end`, which gets a miss only if `include_end`.
#[derive(Clone, Copy, Default)]
struct Segment {
    o: [f32; 3],
    target: [f32; 3],
    start: [i32; 3],
    end: [i32; 3],
    include_end: bool,
}

impl Segment {
    /// The segment from the frame's sensor to `target` (voxel units) in voxel `end`.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    fn new(f: &FrameState, target: [f32; 3], end: &VoxelKey, include_end: bool) -> Segment {
        let k = f.origin_key;
        Segment {
            o: f.origin_s,
            target,
            start: [k.x as i32, k.y as i32, k.z as i32],
            end: [end.x as i32, end.y as i32, end.z as i32],
            include_end,
        }
    }

    /// The steps of its walk: one per voxel boundary between `start` and `end`.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    #[cfg_attr(not(target_pointer_width = "64"), inline)]
    fn steps(&self) -> u32 {
        (0..3)
            .map(|a| (self.end[a] - self.start[a]).unsigned_abs())
            .sum()
    }

    /// Whether the walk may leave the key range: overshooting the end by a few voxels
    /// stays in range unless an end is near its limit.
    #[inline]
    fn near_limit(&self) -> bool {
        (self.start.iter().chain(&self.end)).any(|c| c.unsigned_abs() > KEY_LIMIT as u32 - 8)
    }

    /// The walk's start: voxel `start`, boundaries along `target - o`.
    #[inline]
    fn dda(&self) -> Dda {
        let (o, target) = (self.o, self.target);
        Dda::new(o, [0, 1, 2].map(|a| target[a] - o[a]), self.start)
    }

    /// The segment as a ray in world metres, for an NDT-OM miss. Built when a miss needs
    /// it, not per segment: most rays meet no Gaussian, and on a Cortex-M4 the square
    /// root is a software call.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    fn ray(&self, f: &FrameState) -> Ray {
        let (o, target) = (self.o, self.target);
        let d = [target[0] - o[0], target[1] - o[1], target[2] - o[2]];
        let len_s = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        Ray {
            origin: f.origin,
            dir: if len_s > 0.0 {
                [d[0] / len_s, d[1] / len_s, d[2] / len_s]
            } else {
                [0.0, 0.0, 1.0]
            },
            len: len_s * f.h,
            measured: !self.include_end,
        }
    }
}

/// The ray parameter beyond which a walk stops: the end is at 1, and the margin keeps a
/// walk from stopping short on rounding.
///
/// The margin is wide enough that a free-space walk never meets this stop before its
/// last step (which ends it anyway), so [`Map::walk`] leaves the check out (three
/// instructions of each step on a Cortex-M4). Before the last step some axis `a` still
/// has a boundary to cross towards the end voxel, and the walk's next parameter is at
/// most that axis's `t_a`. Exactly, `t_a < 1`: the target lies inside the end voxel, at
/// least 0.01 voxel from its faces ([`mean_in_voxel`], [`centre`]), farther than
/// `o + d` rounds away from it. The computed `t_a` is the start parameter plus at most
/// [`Config::MAX_RAY_CELLS`] (4096) additions of `t_delta` (a ray is at most that many
/// cells long), each rounding by at most `2^-24` of a value near 1; the start and
/// `t_delta` add a few more such units: at most about `4101 * 2^-24 = 2.5e-4` in all,
/// below the margin. A test walks random segments of that length and checks that the
/// stop never fires early. The stop remains for [`voxels_on_segment`]'s segments, which
/// may be longer.
///
/// [`voxels_on_segment`]: crate::voxels_on_segment
const T_END: f32 = 1.0 + 1e-3;

/// Whether rays are walked [`LANES`] at a time: on 64-bit targets, whose out-of-order
/// cores lose most of a scalar walk's time to mispredicted branches. A Cortex-M has no
/// such predictor to lose, and its stack is small.
const LANES_PAY: bool = cfg!(target_pointer_width = "64");

/// The most rays waiting to be walked: none on 32-bit targets, which walk every ray at
/// once.
const PENDING: usize = if LANES_PAY { LANES } else { 0 };

/// Rays of phase 3 waiting to be walked, and the voxels [`lane_keys`] finds for them.
struct Pending {
    segments: [Segment; PENDING],
    len: usize,
    keys: [[u64; LANES]; LANE_STEPS + 1],
    /// The steps of one walk not known to be missed already.
    todo: [u16; LANE_STEPS + 1],
}

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
    /// `head`: to every hit voxel, then to every truncated end that got no points. On
    /// 64-bit targets the rays go [`LANES`] at a time through [`lane_keys`] and are then
    /// walked one by one, in the same order.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    pub(crate) fn clear_free_space(&mut self, f: &mut FrameState, head: u32) {
        let mut cache = GaussCache::new();
        let mut pending = Pending {
            segments: [Segment::default(); PENDING],
            len: 0,
            keys: [[0; LANES]; LANE_STEPS + 1],
            todo: [0; LANE_STEPS + 1],
        };
        self.for_each_frame_block(head, |map, _, b| {
            for cell in bits(b.hit) {
                let key = VoxelKey::from_block_cell(b.packed_key(), cell);
                let found = map.voxels.find(key.packed());
                let target = match found.and_then(|vs| map.voxels.get(vs)) {
                    Some(v) => mean_in_voxel(v, &key, f.qscale),
                    None => centre(&key),
                };
                map.cast(f, &mut cache, &mut pending, target, &key, false);
            }
            for cell in bits(b.far & !b.hit) {
                let key = VoxelKey::from_block_cell(b.packed_key(), cell);
                map.cast(f, &mut cache, &mut pending, centre(&key), &key, true);
            }
        });
        self.walk_pending(f, &mut cache, &mut pending);
    }

    /// Exact voxel traversal (Amanatides & Woo) from the sensor to `target` (in voxel
    /// units), giving each traversed voxel its miss; `end` itself only if `include_end`.
    /// Walked now on 32-bit targets, else with the rays pending before it, once
    /// [`LANES`] are pending.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    fn cast(
        &mut self,
        f: &mut FrameState,
        cache: &mut GaussCache,
        pending: &mut Pending,
        target: [f32; 3],
        end: &VoxelKey,
        include_end: bool,
    ) {
        f.report.rays += 1;
        let seg = Segment::new(f, target, end, include_end);
        if !LANES_PAY {
            self.walk_one(f, cache, &seg);
            return;
        }
        if let Some(slot) = pending.segments.get_mut(pending.len) {
            *slot = seg;
            pending.len += 1;
        }
        if pending.len == PENDING {
            self.walk_pending(f, cache, pending);
        }
    }

    /// Walks the pending rays in order, the voxels of their walks (up to [`LANE_STEPS`]
    /// steps) found for all of them at once.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    fn walk_pending(&mut self, f: &mut FrameState, cache: &mut GaussCache, pending: &mut Pending) {
        let segments = pending.segments.get(..pending.len).unwrap_or(&[]);
        if segments.is_empty() {
            return;
        }
        let lanes = |seg: &Segment| !seg.near_limit() && seg.steps() as usize <= LANE_STEPS;
        let lane = |l: usize| segments.get(l).copied().unwrap_or_default();
        let walks: [Dda; LANES] = core::array::from_fn(|l| lane(l).dda());
        let start = core::array::from_fn(|l| key_of(lane(l).start).packed());
        let in_lanes: [bool; LANES] = core::array::from_fn(|l| segments.get(l).is_some_and(lanes));
        let limit = core::array::from_fn(|l| match in_lanes[l] {
            true => lane(l).steps(),
            false => 0,
        });
        let steps = lane_keys(&walks, start, limit, T_END, &mut pending.keys);
        let taken = segments.iter().zip(in_lanes).zip(&steps).enumerate();
        for (l, ((seg, in_lanes), &n)) in taken {
            if in_lanes {
                let keys = pending.keys.get(..=n as usize).unwrap_or(&[]);
                self.walk_keys(f, cache, seg, (keys, l), &mut pending.todo);
            } else {
                self.walk_one(f, cache, seg);
            }
        }
        pending.len = 0;
    }

    /// The misses of a walk through the voxels with packed keys `keys[..][lane]`, in the
    /// key range (from [`lane_keys`]). Most of them have their miss already: a first
    /// pass rules those out without branches (a block's `missed` mask, from the frame's
    /// block cache, only grows during a frame) and lists the rest in `todo`; the second
    /// goes through that list as the scalar walk would, block lookups and all.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    fn walk_keys(
        &mut self,
        f: &mut FrameState,
        cache: &mut GaussCache,
        seg: &Segment,
        (keys, lane): (&[[u64; LANES]], usize),
        todo: &mut [u16; LANE_STEPS + 1],
    ) {
        let mut count = 0;
        for (n, row) in keys.iter().enumerate() {
            let key = row.get(lane).copied().unwrap_or(0);
            let missed = Self::cached_missed(f, block_of_packed(key));
            if let Some(t) = todo.get_mut(count) {
                *t = n as u16;
            }
            count += ((missed >> cell_of_packed(key)) & 1 == 0) as usize;
        }
        let last = seg.steps() as usize;
        for &n in todo.iter().take(count) {
            let n = n as usize;
            let key = keys
                .get(n)
                .and_then(|row| row.get(lane))
                .copied()
                .unwrap_or(0);
            let (block, cell) = (block_of_packed(key), cell_of_packed(key));
            let (at, missed) = self.enter_block(f, block);
            if !has_cell(missed, cell)
                && self
                    .walk_visit(f, cache, seg, at, (block, cell), n == last)
                    .is_none()
            {
                return;
            }
        }
    }

    /// Walks one segment, checking the key range only where it may be left.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    fn walk_one(&mut self, f: &mut FrameState, cache: &mut GaussCache, seg: &Segment) {
        if seg.near_limit() {
            self.walk_checked(f, cache, seg);
        } else {
            self.walk(f, cache, seg);
        }
    }

    /// The traversal of [`traverse`] (same voxels, same order), specialised for misses,
    /// for a segment that stays in the key range. The walk keeps only what a step needs
    /// in registers: the cell index in the current block, the block's `missed` mask and
    /// the word of it that holds the cell's bit ([`mask_word`]), and per axis the boundary
    /// parameter. A voxel that already has its miss (most visits: the rays of a frame
    /// share their start) costs one bit test and one step; the voxel key is rebuilt from
    /// block and cell only for a miss and at the end. The end voxel can only be reached
    /// with the last of the `|end - start|_1` steps, so the loop counts steps instead of
    /// comparing keys. Each axis steps with its own constants, so a step inside the block
    /// is one addition. The walk ends with its last step: it never reaches the `T_END`
    /// stop before that (see [`T_END`]).
    ///
    /// The cell index is kept "in the direction of travel": the 2-bit field of an axis
    /// walked downwards holds `3 - x` (`flip` has those fields set), so every step adds
    /// one to a field, and a field at 3 means the step leaves the block (the field wraps
    /// to 0 and the block key steps). Masks and increments are then constants, which
    /// leaves registers for the rest on 32-bit targets.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    fn walk(&mut self, f: &mut FrameState, cache: &mut GaussCache, seg: &Segment) {
        let start = seg.start;
        let dda = seg.dda();
        let [d0, d1, d2] = dda.t_delta;
        let [mut t0, mut t1, mut t2] = dda.t_max;
        let Some(key) = VoxelKey::from_ints(start[0], start[1], start[2]) else {
            return;
        };
        let down = |a: usize| dda.step[a] < 0;
        let flip =
            (down(0) as u32 * X_FIELD) | (down(1) as u32 * Y_FIELD) | (down(2) as u32 * Z_FIELD);
        // The step of the packed block key per axis: +-1 in that axis's 16-bit field.
        let block_step = |a: usize, at: u32| ((dda.step[a] as i64) << at) as u64;
        let (b0, b1, b2) = (block_step(0, 32), block_step(1, 16), block_step(2, 0));
        let mut block = key.block();
        let mut walked = key.cell() ^ flip;
        let mut remaining = seg.steps();
        let (mut at, mut missed) = self.enter_block(f, block);
        let mut word = mask_word(missed, walked ^ flip);
        loop {
            let cell = walked ^ flip;
            if !has_bit(word, cell) {
                match self.walk_visit(f, cache, seg, at, (block, cell), remaining == 0) {
                    Some(m) => {
                        missed = m;
                        word = mask_word(m, cell);
                    }
                    None => return,
                }
            }
            if remaining == 0 {
                return;
            }
            remaining -= 1;
            // The next boundary: the lowest axis on ties, as `Dda::next_axis`.
            let y = t1 < t0;
            let t01 = if y { t1 } else { t0 };
            let z = t2 < t01;
            let (field, step) = if z {
                t2 += d2;
                if walked & Z_FIELD != Z_FIELD {
                    walked += 1 << 4;
                    word = mask_word(missed, walked ^ flip);
                    continue;
                }
                (Z_FIELD, b2)
            } else if y {
                t1 += d1;
                if walked & Y_FIELD != Y_FIELD {
                    walked += 1 << 2;
                    continue;
                }
                (Y_FIELD, b1)
            } else {
                t0 += d0;
                if walked & X_FIELD != X_FIELD {
                    walked += 1;
                    continue;
                }
                (X_FIELD, b0)
            };
            walked &= !field;
            block = block.wrapping_add(step);
            (at, missed) = self.enter_block(f, block);
            word = mask_word(missed, walked ^ flip);
        }
    }

    /// [`Map::visit`] for the walk's voxel in cell `cell` of block `block`, unless it is
    /// the excluded end (`None`: the walk stops). Out of line on 32-bit targets: most
    /// steps do not visit, and the walk's loop needs every register there.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    #[cfg_attr(not(target_pointer_width = "64"), inline(never))]
    fn walk_visit(
        &mut self,
        f: &mut FrameState,
        cache: &mut GaussCache,
        seg: &Segment,
        at: Option<usize>,
        (block, cell): (u64, u32),
        last: bool,
    ) -> Option<u64> {
        if last && !seg.include_end && VoxelKey::from_block_cell(block, cell) == key_of(seg.end) {
            return None;
        }
        Some(self.visit(f, cache, seg, at, (block, cell)))
    }

    /// [`Map::walk`] for a segment that may leave the key range: the voxel-by-voxel
    /// [`traverse`], stopping at the first voxel outside the range (an axis moves
    /// monotonically, so nothing valid follows).
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    fn walk_checked(&mut self, f: &mut FrameState, cache: &mut GaussCache, seg: &Segment) {
        traverse(
            seg.o,
            seg.target,
            seg.start,
            seg.end,
            seg.include_end,
            |k| {
                let Some(voxel) = VoxelKey::from_ints(k[0], k[1], k[2]) else {
                    return false;
                };
                let (block, cell) = (voxel.block(), voxel.cell());
                let (at, missed) = self.enter_block(f, block);
                if !has_cell(missed, cell) {
                    self.visit(f, cache, seg, at, (block, cell));
                }
                true
            },
        );
    }

    /// A traversed voxel without its miss yet this frame, cell `cell` of the block with
    /// packed key `block`, in block slot `at` (`None`: the map had no room for the block,
    /// the miss is dropped): gives it the miss and returns the block's new `missed` mask.
    #[inline(always)]
    fn visit(
        &mut self,
        f: &mut FrameState,
        cache: &mut GaussCache,
        seg: &Segment,
        at: Option<usize>,
        (block, cell): (u64, u32),
    ) -> u64 {
        match at {
            Some(bs) => {
                self.miss(f, cache, seg, (block, cell), bs);
                self.blocks.get(bs).map_or(0, |b| b.missed)
            }
            None => {
                f.report.dropped_misses = f.report.dropped_misses.saturating_add(1);
                0
            }
        }
    }

    /// The slot of the block with packed key `block` (`None` when the map has no room for
    /// it), and the block's `missed` mask. The walk's voxels are in the key range (it
    /// stops before leaving it), so the key is valid.
    #[inline(always)]
    fn enter_block(&mut self, f: &mut FrameState, block: u64) -> (Option<usize>, u64) {
        let at = self.frame_block(f, block, false);
        let missed = at
            .and_then(|bs| self.blocks.get(bs))
            .map_or(0, |b| b.missed);
        (at, missed)
    }

    /// The miss of cell `cell` of the block with packed key `block` (in slot `bs`,
    /// without a miss yet this frame) for the segment `seg`: the constant miss, or
    /// [`Map::surface_miss`] for a voxel on the surface.
    #[inline(always)]
    fn miss(
        &mut self,
        f: &mut FrameState,
        cache: &mut GaussCache,
        seg: &Segment,
        (block, cell): (u64, u32),
        bs: usize,
    ) {
        let Some(surface) = self.blocks.get(bs).map(|b| b.surface) else {
            return;
        };
        let mut seen = None;
        let delta = if has_cell(surface, cell) && self.config.miss_model == MissModel::NdtOm {
            let key = VoxelKey::from_block_cell(block, cell);
            match self.surface_miss(f, cache, seg, (key, bs, cell)) {
                Some((delta, true)) => {
                    seen = Some(key);
                    delta
                }
                Some((delta, false)) => delta,
                None => return,
            }
        } else {
            f.miss
        };
        let bit = 1u64 << (cell & 63);
        let (lo, hi) = f.clamp;
        if let Some(b) = self.blocks.get_mut(bs) {
            b.missed |= bit;
            b.add_logodds(cell, delta, lo, hi);
        }
        if LANES_PAY {
            Self::note_missed(f, block, bit);
        }
        if let Some(key) = seen {
            self.spread_see_through(f, &key, delta);
        }
    }

    /// After surface voxel `key` took see-through miss `delta` (fixed point) in a depth
    /// frame: each face neighbour (+x, -x, +y, -y, +z, -z) with a valid Gaussian and the
    /// same class, occupied, that got neither points nor a miss this frame and whose mean
    /// the image shows hidden behind something ([`pixel_hides`]) takes
    /// [`SPREAD_SHARE`] of it. An object that is gone where the camera sees it goes
    /// where it is hidden too: the side of a replaced night stand behind a table edge,
    /// which no ray or pixel of the walk sees through, clears in 10 frames, not 25.
    fn spread_see_through(&mut self, f: &mut FrameState, key: &VoxelKey, delta: i32) {
        let class = match self
            .voxels
            .find(key.packed())
            .and_then(|vs| self.voxels.get(vs))
        {
            Some(v) => argmax(&v.hist).map(|c| c.0),
            None => return,
        };
        let (x, y, z) = (i32::from(key.x), i32::from(key.y), i32::from(key.z));
        let around = [
            (1, 0, 0),
            (-1, 0, 0),
            (0, 1, 0),
            (0, -1, 0),
            (0, 0, 1),
            (0, 0, -1),
        ];
        for (dx, dy, dz) in around {
            let Some(n) = VoxelKey::from_ints(x + dx, y + dy, z + dz) else {
                continue;
            };
            let (block, cell) = (n.block(), n.cell());
            if self.blocks.find(block).is_none() {
                continue;
            }
            let Some(bs) = self.frame_block(f, block, false) else {
                continue;
            };
            let bit = 1u64 << (cell & 63);
            let Some(b) = self.blocks.get(bs) else {
                continue;
            };
            let occupied = b.cells[cell as usize & 63] > 0;
            if b.surface & bit == 0 || (b.hit | b.missed) & bit != 0 || !occupied {
                continue;
            }
            let cfg = &self.config;
            let mean = match self
                .voxels
                .find(n.packed())
                .and_then(|vs| self.voxels.get(vs))
            {
                Some(v) if v.n >= cfg.n_min && argmax(&v.hist).map(|c| c.0) == class => {
                    v.gaussian(cfg.cell_size, cfg.quant_step()).mean
                }
                _ => continue,
            };
            let hidden = f
                .image
                .as_ref()
                .is_some_and(|i| pixel_hides(cfg, f, i, &mean));
            if !hidden {
                continue;
            }
            let (lo, hi) = f.clamp;
            if let Some(b) = self.blocks.get_mut(bs) {
                b.missed |= bit;
                b.add_logodds(cell, delta / SPREAD_SHARE, lo, hi);
            }
            if LANES_PAY {
                Self::note_missed(f, block, bit);
            }
        }
    }

    /// The miss (fixed point) of voxel `key` (cell `cell` of the block in slot `bs`), on
    /// the surface, for the segment `seg`: for a valid Gaussian the see-through miss when
    /// the voxel got no points this frame (not in its block's `hit` mask) and
    /// [`Config::see_through_miss`] is on (in full when a depth frame saw through its mean,
    /// [`seen_through`]), else the NDT-OM miss; the constant miss without a valid
    /// Gaussian; `None` when the ray ends before its closest approach (or, for the
    /// see-through miss, near it). Out of line on 32-bit targets: few misses need it, and
    /// its floating point would make every miss save registers.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    #[cfg_attr(not(target_pointer_width = "64"), inline(never))]
    fn surface_miss(
        &self,
        f: &FrameState,
        cache: &mut GaussCache,
        seg: &Segment,
        (key, bs, cell): (VoxelKey, usize, u32),
    ) -> Option<(i32, bool)> {
        let cfg = &self.config;
        let found = self.voxels.find(key.packed());
        match found.and_then(|vs| Some((vs, self.voxels.get(vs)?))) {
            Some((vs, v)) if v.n >= cfg.n_min => {
                let g = cache.get(vs, || v.prepared(cfg));
                // The block is read here, not in every miss: few misses reach a Gaussian.
                let block = self.blocks.get(bs);
                let hit = block.is_none_or(|b| has_cell(b.hit, cell));
                if hit || cfg.see_through_miss == 0.0 {
                    ndt_om_miss(cfg, &seg.ray(f), &g).map(|l| (to_fixed(l), false))
                } else {
                    if f.image
                        .as_ref()
                        .is_some_and(|i| seen_through(cfg, f, i, &g.mean))
                    {
                        return Some((to_fixed(cfg.see_through_miss), true));
                    }
                    let l = block.map_or(0, |b| i32::from(b.cells[cell as usize & 63]));
                    let doubted = l < f.clamp.1 - to_fixed(SEE_THROUGH_DOUBT);
                    see_through_miss(cfg, &seg.ray(f), &g, doubted).map(|l| (to_fixed(l), true))
                }
            }
            _ => Some((f.miss, false)),
        }
    }
}

/// Where a ray passes a Gaussian: the ray parameter `t` of its closest approach (in the
/// Mahalanobis sense) and `p_z`, the likelihood that the ray's measured end lies there
/// (range noise; 0 for a ray truncated at max range). `Err(())` when the Gaussian's
/// inverse gives no direction (`a <= 0`, NaN), `Ok(None)` when the closest approach lies
/// beyond the ray's end.
#[allow(clippy::result_unit_err)]
#[cfg_attr(target_pointer_width = "64", inline(always))]
fn closest_approach(cfg: &Config, ray: &Ray, g: &Prepared) -> Result<Option<(f32, f32)>, ()> {
    let u = Vector3::new(ray.dir[0], ray.dir[1], ray.dir[2]);
    let s = Vector3::new(ray.origin[0], ray.origin[1], ray.origin[2]);
    let w = g.inv * u;
    let a = u.dot(&w);
    if a.is_nan() || a <= 0.0 {
        return Err(());
    }
    let t = w.dot(&(g.mean - s)) / a;
    if t > ray.len {
        return Ok(None);
    }
    let p_z = if ray.measured {
        let sigma = cfg.noise_base + cfg.noise_quadratic * ray.len * ray.len;
        let dz = ray.len - t;
        libm::expf(-0.5 * dz * dz / (sigma * sigma))
    } else {
        0.0
    };
    Ok(Some((t, p_z)))
}

/// The see-through miss log-odds ([`Config::see_through_miss`]) for a ray past a voxel's
/// Gaussian: `see_through_miss * (1 - p_z)` when the ray passes through the Gaussian's
/// ellipsoid of radius [`SEE_THROUGH_SURFACE`] ([`SEE_THROUGH_HALO`] for a voxel already
/// `doubted`) and ends well beyond it (`p_z < 1/2`); `None` otherwise (a ray past the
/// ellipsoid, one ending near it or before it): the voxel waits for the frame's next ray.
#[cfg_attr(target_pointer_width = "64", inline(always))]
fn see_through_miss(cfg: &Config, ray: &Ray, g: &Prepared, doubted: bool) -> Option<f32> {
    match closest_approach(cfg, ray, g) {
        Err(()) => Some(cfg.miss),
        Ok(Some((t, p_z))) if p_z < 0.5 => {
            let u = Vector3::new(ray.dir[0], ray.dir[1], ray.dir[2]);
            let s = Vector3::new(ray.origin[0], ray.origin[1], ray.origin[2]);
            let dx = s + u * t - g.mean;
            let r = if doubted {
                SEE_THROUGH_HALO
            } else {
                SEE_THROUGH_SURFACE
            };
            let inside = dx.dot(&(g.inv * dx)) <= r * r;
            inside.then_some(cfg.see_through_miss * (1.0 - p_z))
        }
        Ok(_) => None,
    }
}
/// The Mahalanobis radius of the ellipsoid a ray must pass through to see through a
/// surface voxel at its clamp: 2, through the patch its points cover. Rays through the
/// ellipsoid's outer shell pass beside the surface, not through it: with 4 (or 3) for
/// every voxel, the far edges of thin objects the camera could not see for a while
/// (clothes on a chair behind its backrest) went free, and the default synthetic split at
/// 10 cm lost 0.96 (0.73) points of mIoU at a see-through miss of -3; with 2 it loses
/// 0.07, but a moved chair's outline, which few of a frame's rays (one per end voxel)
/// pierce, stays for 96 frames (dynamic room, half-size camera).
const SEE_THROUGH_SURFACE: f32 = 2.0;

/// The radius for a voxel already doubted (see [`SEE_THROUGH_DOUBT`]): 4. Once a ray has
/// pierced a moved object's surface, rays past its outline finish it: the chair clears in
/// 29 frames instead of 96 (14 at full size), and the static split loses 0.14 points
/// instead of 0.07 (2.5 until doubted: 0.67).
const SEE_THROUGH_HALO: f32 = 4.0;

/// A see-through miss spreads to a hidden neighbour as one `SPREAD_SHARE`th of it (fixed
/// point, rounded towards 0). A spread voxel, once doubted, spreads on from its own
/// see-through misses, so a spread runs along a hidden surface over the frames: in full
/// or halved it cleared the night stand in 8 frames, but ate the hidden backs of
/// standing figures and boxes on the default synthetic split at 10 cm (82.77 and 82.84 %
/// mIoU against 82.91 %); a quarter clears it in 10 frames for 82.85 %.
const SPREAD_SHARE: i32 = 4;

/// A voxel is doubted when its log-odds lie more than this below `clamp_max`: a static
/// surface the camera sees sits at the clamp, one that a see-through miss has hit does
/// not (0.5 and 1 gave the same figures).
const SEE_THROUGH_DOUBT: f32 = 1.0;

/// NDT-OM miss log-odds for a ray through a voxel's Gaussian, or `None` when the point of
/// the ray closest to the Gaussian lies beyond the ray's end.
#[cfg_attr(target_pointer_width = "64", inline(always))]
fn ndt_om_miss(cfg: &Config, ray: &Ray, g: &Prepared) -> Option<f32> {
    let (t, p_z) = match closest_approach(cfg, ray, g) {
        Err(()) => return Some(cfg.miss),
        Ok(None) => return None,
        Ok(Some(tz)) => tz,
    };
    let u = Vector3::new(ray.dir[0], ray.dir[1], ray.dir[2]);
    let s = Vector3::new(ray.origin[0], ray.origin[1], ray.origin[2]);
    let dx = s + u * t - g.mean;
    let p_n = libm::expf(-0.5 * dx.dot(&(g.inv * dx)));
    let p = 0.5 - cfg.lambda * p_n * (1.0 - p_z);
    Some(libm::logf(p / (1.0 - p)))
}

/// Whether a depth frame saw through the point `mean` (world metres): the pixel `mean`
/// projects to (the sampled one at or before it, with the image's stride) measured a depth
/// beyond it by more than a cell plus twice the range noise there. That pixel looked at
/// the middle of the voxel's surface and found it gone; a frame's rays (one per end voxel)
/// are too sparse to pierce a thin Gaussian's middle often: with this test a moved chair
/// clears in 2 frames, not 14. A surface still there gives the pixel its own depth (a
/// plane through the mean meets the pixel's ray at the mean), one hidden behind something
/// gives a nearer depth: neither passes.
#[cfg_attr(target_pointer_width = "64", inline(always))]
fn seen_through(cfg: &Config, f: &FrameState, image: &DepthImage<'_>, mean: &Vector3<f32>) -> bool {
    pixel_depth(cfg, f, image, mean)
        .is_some_and(|(measured, along, margin)| measured > along + margin)
}

/// Whether the pixel `mean` projects to hides it: measured nearer than the mean by more
/// than a cell plus twice the range noise (false outside the image and for a pixel
/// without a depth).
#[cfg_attr(target_pointer_width = "64", inline(always))]
fn pixel_hides(cfg: &Config, f: &FrameState, image: &DepthImage<'_>, mean: &Vector3<f32>) -> bool {
    pixel_depth(cfg, f, image, mean)
        .is_some_and(|(measured, along, margin)| measured < along - margin)
}

/// The depth measured at the pixel `mean` projects to, the mean's own depth along that
/// pixel's ray, and the margin a cell plus twice the range noise; `None` outside the
/// image or without a finite depth.
#[cfg_attr(target_pointer_width = "64", inline(always))]
fn pixel_depth(
    cfg: &Config,
    f: &FrameState,
    image: &DepthImage<'_>,
    mean: &Vector3<f32>,
) -> Option<(f32, f32, f32)> {
    let d = [
        mean.x - f.origin[0],
        mean.y - f.origin[1],
        mean.z - f.origin[2],
    ];
    // Camera coordinates: the transpose of the pose's rotation.
    let m = &f.rot;
    let p: [f32; 3] =
        core::array::from_fn(|i| m[(0, i)] * d[0] + m[(1, i)] * d[1] + m[(2, i)] * d[2]);
    if p[2].is_nan() || p[2] <= 0.0 {
        return None;
    }
    let cam = &image.camera;
    let u = cam.fx * p[0] / p[2] + cam.cx;
    let v = cam.fy * p[1] / p[2] + cam.cy;
    // False for NaN too.
    let inside = u >= 0.0 && v >= 0.0 && u < cam.width as f32 && v < cam.height as f32;
    if !inside {
        return None;
    }
    let s = image.stride.max(1) as usize;
    let (col, row) = (u as usize / s * s, v as usize / s * s);
    let measured = image.depth.metres(row * cam.width as usize + col)?;
    let along = match image.kind {
        DepthKind::Planar => p[2],
        DepthKind::Range => sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]),
    };
    let sigma = cfg.noise_base + cfg.noise_quadratic * along * along;
    measured
        .is_finite()
        .then_some((measured, along, cfg.cell_size + 2.0 * sigma))
}

/// Whether bit `cell` (0..64) of a block mask is set; on 32-bit targets a test of one
/// 32-bit half, not a 64-bit shift.
#[inline(always)]
fn has_cell(mask: u64, cell: u32) -> bool {
    has_bit(mask_word(mask, cell), cell)
}

/// The word of block mask `mask` that holds the bit of cell `cell`: the whole mask on
/// 64-bit targets; on 32-bit ones its 32-bit half, which changes only with the cell's z
/// (cells 32..64 have z >= 2), so a walk picks it again only on z steps.
#[inline(always)]
fn mask_word(mask: u64, cell: u32) -> usize {
    if cfg!(target_pointer_width = "64") || cell & 32 == 0 {
        mask as usize
    } else {
        (mask >> 32) as usize
    }
}

/// Whether the bit of cell `cell` is set in `word`, from [`mask_word`].
#[inline(always)]
fn has_bit(word: usize, cell: u32) -> bool {
    (word >> (cell as usize & (usize::BITS as usize - 1))) & 1 != 0
}

/// Centre of a voxel in voxel units.
#[cfg_attr(target_pointer_width = "64", inline(always))]
fn centre(key: &VoxelKey) -> [f32; 3] {
    [key.x as f32 + 0.5, key.y as f32 + 0.5, key.z as f32 + 0.5]
}

/// Mean of a voxel's points in voxel units, kept strictly inside the voxel.
#[cfg_attr(target_pointer_width = "64", inline(always))]
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

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use crate::testutil::*;
    use crate::*;
    use std::vec::Vec;

    /// The NDT-OM miss for an isotropic Gaussian (variance `var`, m^2) in f64, straight from
    /// its definition (closest point `t` on the ray, `p = 0.5 - lambda pN (1 - pz)`, logit);
    /// `None` when the closest point lies beyond the ray's end.
    fn ndt_om_f64(
        cfg: &Config,
        s: [f64; 3],
        end: [f64; 3],
        measured: bool,
        mu: [f64; 3],
        var: f64,
    ) -> Option<f64> {
        let d: [f64; 3] = core::array::from_fn(|i| end[i] - s[i]);
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let u: [f64; 3] = core::array::from_fn(|i| d[i] / len);
        let t: f64 = (0..3).map(|i| u[i] * (mu[i] - s[i])).sum();
        if t > len {
            return None;
        }
        let dist2: f64 = (0..3).map(|i| (s[i] + t * u[i] - mu[i]).powi(2)).sum();
        let p_n = (-0.5 * dist2 / var).exp();
        let p_z = if measured {
            let sigma = cfg.noise_base as f64 + cfg.noise_quadratic as f64 * len * len;
            (-0.5 * (len - t).powi(2) / (sigma * sigma)).exp()
        } else {
            0.0
        };
        let p = 0.5 - cfg.lambda as f64 * p_n * (1.0 - p_z);
        Some((p / (1.0 - p)).ln())
    }

    /// Six points at +-16 quanta on each axis around the centre of voxel `k` (h = 1/8):
    /// mean = centre, isotropic variance 6 * 512 / 30 quanta^2.
    fn isotropic_points(k: &VoxelKey, origin: [f32; 3]) -> Vec<LabeledPoint> {
        let c = k.center(0.125);
        let a = 16.0 / 512.0;
        let mut v = Vec::new();
        for axis in 0..3 {
            for sign in [-1.0f32, 1.0] {
                let mut p = c;
                p[axis] += sign * a;
                v.push(lp(p[0] - origin[0], p[1] - origin[1], p[2] - origin[2], 1));
            }
        }
        v
    }

    /// A wall of points `z` metres ahead of a sensor at the origin, 1.2 m square, 3 cm
    /// apart (every voxel of it gets points).
    fn wall(z: f32) -> Vec<LabeledPoint> {
        let mut v = Vec::new();
        for i in 0..40 {
            for j in 0..40 {
                let (x, y) = (
                    -0.6 + 0.03 * i as f32 + 0.001,
                    -0.6 + 0.03 * j as f32 + 0.001,
                );
                v.push(LabeledPoint::new(Point3::new(x, y, z), Labels::top1(1)));
            }
        }
        v
    }

    /// The see-through miss on a wall that moved 1 m back, seen head-on: the ray through
    /// the old wall's centre voxel crosses its flat Gaussian at the middle (inside the
    /// ellipsoid) and ends 1 m behind it (`p_z` = 0 in f32), so the voxel at the clamp
    /// (3.5) gets the full miss: 3.5 - 3 = 0.5 after one frame, the clamp -2 after two.
    /// Off (the default), the same voxel gets NDT-OM's at most `logit(0.4)` = -0.405 a
    /// frame. A wall that stays, seen every frame, keeps its clamp with the miss on.
    #[test]
    fn see_through_miss_clears_a_moved_wall() {
        let centre = key(0, 0, 20);
        for (see, after_one, after_two) in [(-3.0f32, 0.5f32, -2.0f32), (0.0, 3.1, 2.7)] {
            let mut cfg = Config::DEFAULT;
            cfg.see_through_miss = see;
            let mut map: Map<4096, 1024, 2> = Map::try_new(cfg).unwrap();
            let pose = Isometry3::identity();
            for _ in 0..6 {
                map.integrate(&pose, &wall(2.05)).unwrap();
            }
            assert_eq!(map.log_odds(&centre), 3.5);
            map.integrate(&pose, &wall(3.05)).unwrap();
            let one = map.log_odds(&centre);
            map.integrate(&pose, &wall(3.05)).unwrap();
            let two = map.log_odds(&centre);
            if see < 0.0 {
                assert!((one - after_one).abs() <= 1.0 / 1024.0, "{one}");
                assert_eq!(two, after_two);
            } else {
                // NDT-OM: at most -0.405 a frame, and at least a little.
                assert!(one >= 3.5 - 0.406 && one < after_one + 0.35, "{one}");
                assert!(
                    two >= one - 0.406 && two < one && two < after_two + 0.35,
                    "{two}"
                );
            }
            // The new wall is at the clamp after 4 frames more, either way.
            for _ in 0..4 {
                map.integrate(&pose, &wall(3.05)).unwrap();
            }
            assert_eq!(map.log_odds(&key(0, 0, 30)), 3.5);
        }
    }

    #[test]
    fn ndt_om_miss_hand_computed() {
        let h = 0.125f32;
        // NDT-OM as published: no see-through miss.
        let cfg = Config {
            see_through_miss: 0.0,
            ..Config::with_cell_size(h)
        };
        let mut map: Map<64, 64, 2> = Map::try_new(cfg).unwrap();
        let o = [0.0625f32, 0.0625, 0.0];
        let pose = at(o[0], o[1], o[2]);
        let v = key(0, 0, 8);
        map.integrate(&pose, &isotropic_points(&v, o)).unwrap();
        assert_eq!(fixed(&map, &v), 870);
        let var = 102.4 / (512.0 * 512.0);
        let g = map.gaussian(&v).unwrap();
        assert!(rel_close(g.covariance[(0, 0)] as f64, var, 1e-6, 0.0));
        assert!(rel_close(g.covariance[(2, 2)] as f64, var, 1e-6, 0.0));

        // Measured ray to a point in voxel (0, 0, 16), 20 quanta off-centre in x: it passes
        // the Gaussian of (0, 0, 8) about 2 cm away.
        let end = [0.0625f32 + 20.0 / 512.0, 0.0625, 2.0625];
        map.integrate(&pose, &[lp(end[0] - o[0], end[1] - o[1], end[2] - o[2], 1)])
            .unwrap();
        let mu = [0.0625, 0.0625, 1.0625];
        let l = ndt_om_f64(
            &cfg,
            [0.0625, 0.0625, 0.0],
            end.map(|x| x as f64),
            true,
            mu,
            var,
        )
        .unwrap();
        // The hand computation: 2.01 cm from a 1.98 cm Gaussian, p_z ~ 0.
        assert!((l - (-0.23944)).abs() < 2e-4, "l = {l}");
        let want = 870 + libm::round(l * 1024.0) as i32;
        let got = fixed(&map, &v);
        assert!((got - want).abs() <= 1, "got {got}, want {want}");
        // A voxel without a Gaussian on the same ray gets the constant miss on top of the
        // first frame's constant miss.
        assert_eq!(fixed(&map, &key(0, 0, 4)), -820);

        // Truncated ray (p_z = 0): a point 40 m away clears free space to max range along a
        // ray from a sensor 3 quanta off the Gaussian's axis.
        let mut map: Map<64, 512, 2> = Map::try_new(cfg).unwrap();
        map.integrate(&pose, &isotropic_points(&v, o)).unwrap();
        let o2 = [0.0625f32 + 3.0 / 512.0, 0.0625, 0.0];
        let r = map
            .integrate(&at(o2[0], o2[1], o2[2]), &[lp(0.0, 0.0, 40.0, 1)])
            .unwrap();
        assert_eq!((r.truncated, r.rays), (1, 1));
        // The ray ends at the centre of the truncated end voxel (0, 0, 160).
        let far = key(0, 0, 160).center(h).map(|x| x as f64);
        let l = ndt_om_f64(&cfg, o2.map(|x| x as f64), far, false, mu, var).unwrap();
        let want = 870 + libm::round(l * 1024.0) as i32;
        let got = fixed(&map, &v);
        assert!((got - want).abs() <= 1, "got {got}, want {want} (l = {l})");
        assert!(
            want < 870 - 300,
            "a near-central ray must clear strongly: {want}"
        );
    }

    #[test]
    fn ndt_om_skips_gaussian_beyond_ray_end() {
        // Voxel (0, 0, 15) holds a Gaussian stretched along (1, 0, 1) whose Mahalanobis-closest
        // point to a vertical ray lies at z ~ 2.0155, beyond the ray's end (z ~ 2.00125 in voxel
        // (0, 0, 16)). The ray traverses the voxel, but NDT-OM leaves it alone; a constant
        // miss model does not.
        let h = 0.125f32;
        let run = |model: MissModel| {
            let mut cfg = Config::with_cell_size(h);
            cfg.miss_model = model;
            let mut map: Map<64, 64, 2> = Map::try_new(cfg).unwrap();
            let q = |v: i32| v as f32 / 512.0;
            // Points x = 0, 8, 16 quanta, z = centre - 8, centre, centre + 8 quanta.
            let zc = 15.0 * 0.125 + 0.0625;
            let pts = [
                lp(q(0), 0.0625, zc - q(8), 1),
                lp(q(8), 0.0625, zc, 1),
                lp(q(16), 0.0625, zc + q(8), 1),
            ];
            let sensor = at(0.09375, 0.0625, 0.0);
            let rel: Vec<_> = pts
                .iter()
                .map(|p| {
                    lp(
                        p.position.x - 0.09375,
                        p.position.y - 0.0625,
                        p.position.z,
                        1,
                    )
                })
                .collect();
            map.integrate(&sensor, &rel).unwrap();
            let v = key(0, 0, 15);
            assert_eq!(map.gaussian(&v).unwrap().count, 3);
            let before = fixed(&map, &v);
            // End point on the lower face of voxel (0, 0, 16), straight above the sensor.
            let r = map.integrate(&sensor, &[lp(0.0, 0.0, 2.0, 1)]).unwrap();
            assert_eq!(r.rays, 1);
            (before, fixed(&map, &v), fixed(&map, &key(0, 0, 14)))
        };
        let (before, after, below) = run(MissModel::NdtOm);
        assert_eq!(before, 870);
        assert_eq!(
            after, 870,
            "Gaussian beyond the ray end must not be cleared"
        );
        assert_eq!(below, -820); // an ordinary voxel on the same ray was cleared twice
        let (before, after, _) = run(MissModel::Constant);
        assert_eq!((before, after), (870, 870 - 410));
    }

    /// How the test walks a ray.
    #[derive(Clone, Copy, PartialEq)]
    enum Walk {
        /// [`Map::walk`], the scalar walk of 32-bit targets.
        Scalar,
        /// [`Map::walk_checked`], voxel by voxel with key checks.
        Checked,
        /// [`Map::cast`]: on 64-bit targets, in batches through `lane_keys`.
        Cast,
    }

    /// 300 rays from near the origin (target, end voxel, whether the end is included);
    /// every 15th is long: up to 640 steps, most beyond a batch's 256.
    fn test_rays(rng: &mut Lcg) -> Vec<([f32; 3], VoxelKey, bool)> {
        (0..300)
            .map(|i| {
                let (u, v, w) = (rng.next(), rng.next(), rng.next());
                let reach = if i % 15 == 3 { 150.0 } else { 15.0 };
                let target = [
                    ((u * 2.0 - 1.0) * reach) as f32,
                    ((v * 2.0 - 1.0) * reach) as f32,
                    (w * 40.0 - 5.0) as f32,
                ];
                let end = key(
                    libm::floorf(target[0]) as i16,
                    libm::floorf(target[1]) as i16,
                    libm::floorf(target[2]) as i16,
                );
                (target, end, i % 3 == 0)
            })
            .collect()
    }

    /// The fast walks and the checked `traverse` give every voxel the same miss, ray
    /// after ray, in a map with Gaussians (NDT-OM misses), with and without the end
    /// voxel, in a map too small for the blocks the rays cross (dropped misses), and for
    /// rays too long for a batch among short ones.
    #[test]
    fn walk_is_the_checked_traverse() {
        fn run<const B: usize>(how: Walk, seed: u64) -> (FrameReport, Vec<u8>) {
            let mut rng = Lcg(seed);
            let cfg = Config::with_cell_size(0.1);
            let mut map: Map<2048, B, 4> = Map::try_new(cfg).unwrap();
            // A wall of points 2-3 m away gives voxels with Gaussians.
            let wall: Vec<_> = (0..400)
                .map(|_| {
                    let (u, v, w) = (rng.next(), rng.next(), rng.next());
                    lp(
                        u as f32 * 2.0 - 1.0,
                        v as f32 * 2.0 - 1.0,
                        2.0 + w as f32,
                        1,
                    )
                })
                .collect();
            map.integrate(&at(0.03, 0.07, 0.0), &wall).unwrap();
            let mut f = map.begin_frame(&at(0.13, -0.21, 0.05)).unwrap();
            let mut cache = GaussCache::new();
            let mut pending = Pending {
                segments: [Segment::default(); PENDING],
                len: 0,
                keys: [[0; LANES]; LANE_STEPS + 1],
                todo: [0; LANE_STEPS + 1],
            };
            let rays = test_rays(&mut rng);
            // In a frame the end voxels' blocks exist before the rays (they got the hits
            // or the far ends).
            for (_, end, _) in &rays {
                map.frame_block(&mut f, end.block(), false);
            }
            for &(target, end, include_end) in &rays {
                let seg = Segment::new(&f, target, &end, include_end);
                match how {
                    Walk::Scalar => map.walk(&mut f, &mut cache, &seg),
                    Walk::Checked => map.walk_checked(&mut f, &mut cache, &seg),
                    Walk::Cast => {
                        map.cast(&mut f, &mut cache, &mut pending, target, &end, include_end);
                    }
                }
            }
            map.walk_pending(&mut f, &mut cache, &mut pending);
            if how == Walk::Cast {
                assert_eq!(f.report.rays, 300);
                f.report.rays = 0;
            }
            (f.report, snapshot(&map))
        }
        fn check_seed(seed: u64) {
            let checked = run::<4096>(Walk::Checked, seed);
            assert_eq!(checked.0.dropped_misses, 0);
            for how in [Walk::Scalar, Walk::Cast] {
                assert!(run::<4096>(how, seed) == checked, "seed {seed}");
            }
            let checked = run::<40>(Walk::Checked, seed);
            assert!(checked.0.dropped_misses > 0);
            for how in [Walk::Scalar, Walk::Cast] {
                let got = run::<40>(how, seed);
                assert_eq!(got.0, checked.0, "seed {seed}, full map, {}", how as u8);
                assert!(got == checked, "seed {seed}, full map, {}", how as u8);
            }
        }
        // A debug build moves the ~0.9 MB map through its stack more than once (about
        // 2 MB in all, the default test thread's whole stack): run on a thread with room.
        big_stack(|| {
            for seed in [1, 2, 3] {
                check_seed(seed);
            }
        });
    }

    /// The `T_END` stop never fires before the last step of a free-space segment, which
    /// is at most `MAX_RAY_CELLS` voxels long on each axis (so `walk` leaves it out):
    /// random segments anywhere in the key range, from any point of the start voxel to a
    /// target 0.01 to 0.99 voxel inside the end voxel on each axis (as `mean_in_voxel`
    /// keeps it), each at the longest length on one axis.
    #[test]
    fn end_stop_never_fires_before_the_last_step() {
        let mut rng = Lcg(11);
        let mut highest = 0.0f32;
        for i in 0..3000 {
            let mut r = || rng.next() as f32;
            let start: [i32; 3] = core::array::from_fn(|_| (r() * 56000.0) as i32 - 28000);
            let len = Config::MAX_RAY_CELLS as f32;
            let end: [i32; 3] = core::array::from_fn(|a| {
                let n = if a == i % 3 { len } else { r() * len };
                start[a] + if r() < 0.5 { n as i32 } else { -(n as i32) }
            });
            let o: [f32; 3] = core::array::from_fn(|a| start[a] as f32 + r());
            let target: [f32; 3] =
                core::array::from_fn(|a| end[a] as f32 + (0.01 + 0.98 * r()).clamp(0.01, 0.99));
            let seg = Segment {
                o,
                target,
                start,
                end,
                include_end: false,
            };
            let mut dda = seg.dda();
            for step in 0..seg.steps() {
                let (a, t) = dda.next_axis();
                assert!(t <= T_END, "segment {i}, step {step} of {}", seg.steps());
                highest = highest.max(t);
                dda.advance(a);
            }
        }
        // The walks came within a hair of the end, where rounding could matter.
        assert!(highest > 0.999_99, "{highest}");
    }

    /// Regression: `lambda = 0.5` is valid. A truncated ray (p_z = 0) through a Gaussian's mean gives
    /// p_N = 1, p = 0.5 - 0.5 = 0, logit = -inf, `to_fixed` = i32::MIN, and the second such
    /// miss computes `-2048 + i32::MIN`: overflow (debug panic); in release the sum wraps
    /// and clamps to `clamp_max`, turning a cleared voxel into a fully occupied one.
    #[test]
    fn ndt_om_lambda_half_overflows_log_odds() {
        // lambda = 0.5 allowed p = 0 (logit -inf); now lambda <= 0.49, so p >= 0.01.
        let mut cfg = Config::with_cell_size(0.125);
        cfg.lambda = 0.5;
        assert_eq!(
            cfg.validate(),
            Err(Error::InvalidConfig(ConfigField::Lambda))
        );
        cfg.lambda = 0.49;
        assert!(cfg.validate().is_ok());
        let mut map: Map<16, 256, 1> = Map::try_new(cfg).unwrap();
        let pose = at(0.0625, 0.0625, 0.0);
        // Three points on the z axis of voxel (0, 0, 8): mean exactly on the ray.
        let pts = [
            lp(0.0, 0.0, 1.03125, 1),
            lp(0.0, 0.0, 1.0625, 1),
            lp(0.0, 0.0, 1.09375, 1),
        ];
        map.integrate(&pose, &pts).unwrap();
        let v = key(0, 0, 8);
        assert_eq!(map.log_odds(&v), 870.0 / 1024.0);
        let far = [lp(0.0, 0.0, 40.0, 1)];
        map.integrate(&pose, &far).unwrap();
        assert_eq!(map.log_odds(&v), -2.0);
        map.integrate(&pose, &far).unwrap();
        assert_eq!(map.log_odds(&v), -2.0);
    }
}
