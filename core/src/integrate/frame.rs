//! The state of one frame being integrated: the sensor pose in key units, the frame's
//! stamp, the list of blocks it touches, lookup caches and the [`FrameReport`] it fills.
//!
//! Blocks keep per-frame masks (`hit`, `missed`, `far`) that are valid while their stamp
//! equals the frame's; the first touch of a block in a frame resets them and links the
//! block into the frame's list, which phases 2 and 3 walk in key order.

use crate::config::to_fixed;
use crate::error::Error;
use crate::geometry::camera::{validate_pose, DepthImage};
use crate::key::{axis_key, floor_i32, VoxelKey, KEY_LIMIT};
use crate::storage::block::Block;
use crate::storage::map::Map;
use crate::storage::record::RecordSink;
use crate::storage::table::{Entry, NIL};
#[cfg(doc)]
use crate::storage::votes::vote_max;
use crate::storage::voxel::PackedSums;
use nalgebra::{Isometry3, Matrix3};

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
    /// Records of evicted voxels and blocks the sink took
    /// ([`Map::integrate_spilling`]); 0 without a sink.
    pub records_spilled: u32,
    /// Records of evicted voxels and blocks the sink refused: lost. 0 without a sink
    /// (then evictions are only counted in `voxels_evicted` and `blocks_evicted`).
    pub records_dropped: u32,
}

/// A step of a frame's integration, reported at its start to the observer of
/// [`Map::integrate_depth_observed`] and [`Map::integrate_observed`] (for example to time
/// the steps: the time until the next report belongs to this step).
///
/// Phase 1 alternates between [`Phase::Points`] and [`Phase::Accumulate`] once per batch
/// of up to 64 points; the other phases are reported once per frame.
///
/// ```
/// use sndt_core::{Config, Isometry3, LabeledPoint, Labels, Map, Phase, Point3};
/// let mut map: Map<64, 16, 4> = Map::new(Config::DEFAULT);
/// let pts = [LabeledPoint::new(Point3::new(0.0, 0.0, 1.0), Labels::top1(1))];
/// let mut seen = Vec::new();
/// map.integrate_observed(&Isometry3::identity(), &pts, |p| seen.push(p)).unwrap();
/// assert_eq!(
///     seen,
///     [Phase::Points, Phase::Accumulate, Phase::EndVoxels, Phase::FreeSpace, Phase::Done]
/// );
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Phase {
    /// Phase 1, conversion: pixels to points, world coordinates, voxel keys and offsets.
    Points,
    /// Phase 1, accumulation: voxel lookup, integer sums and votes.
    Accumulate,
    /// Phase 2: one update per touched voxel (decay, hit, next vote sampling).
    EndVoxels,
    /// Phase 3: rays to the unique end voxels, misses.
    FreeSpace,
    /// The frame is complete.
    Done,
}

/// The vector instructions the code that integrates a frame runs with. It chooses one
/// thing, how phase 1 sums a batch's points per voxel (`accumulate.rs`), and every choice
/// gives the same map bits; only the speed differs.
///
/// A crate built for a CPU with AVX2 (`-C target-cpu=native` or `x86-64-v3`) sums by voxel
/// anyway. A program built for baseline x86-64 gets the same speed by calling
/// [`Map::integrate_depth_with`] with [`Vectors::Wide`] from a function compiled with
/// AVX2 enabled (`#[target_feature(enable = "avx2")]`) after checking the CPU at run time,
/// which is what the `sndt-dispatch` crate does.
///
/// ```
/// use sndt_core::*;
/// let cam = Pinhole { fx: 4.0, fy: 4.0, cx: 4.0, cy: 3.0, width: 8, height: 6 };
/// let depth = [2.0f32; 48];
/// let img = DepthImage { camera: cam, depth: Depth::Metres(&depth), kind: DepthKind::Planar,
///                        labels: LabelImage::None, stride: 1 };
/// let mut a: Map<256, 64, 4> = Map::new(Config::DEFAULT);
/// let mut b: Map<256, 64, 4> = Map::new(Config::DEFAULT);
/// a.integrate_depth(&Isometry3::identity(), &img).unwrap();
/// b.integrate_depth_with(&Isometry3::identity(), &img, None, Vectors::Wide).unwrap();
/// assert_eq!(a.checksum(), b.checksum());
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Vectors {
    /// Those this crate was compiled for: sums by voxel where `target_feature = "avx2"`.
    #[default]
    AsBuilt,
    /// Vectors of 256 bits or more (AVX2, AVX-512) in the calling code: sums by voxel on
    /// 64-bit targets. Without them that path is correct but slow.
    Wide,
}

impl Vectors {
    /// Whether phase 1 sums a batch's points by voxel where it does not sum them one by
    /// one (32-bit targets do, whatever this says: see `accumulate.rs`).
    pub(crate) fn by_voxel(self) -> bool {
        cfg!(target_feature = "avx2") || self == Vectors::Wide
    }
}

/// Open voxel accumulators per frame (see [`Accumulator`]).
pub(crate) const ACCUMULATORS: usize = 64;

/// The points a frame put into one voxel so far, summed on the stack and added to the
/// voxel when the accumulator is needed for another voxel or the frame's points end
/// (integer sums: the same result as adding point by point, in any grouping).
///
/// Accumulators are indexed by the low two bits of each key component
/// ([`accumulator_index`]), so the voxels of any 4x4x4 neighbourhood never compete: a
/// surface that straddles a voxel boundary sends consecutive pixels back and forth
/// between voxels, and each of them keeps its accumulator.
#[derive(Clone, Copy)]
pub(crate) struct Accumulator {
    pub(crate) sums: PackedSums,
    /// The voxel's slot.
    pub(crate) slot: usize,
    /// The voxel's packed key (0, never a valid key, when unused).
    pub(crate) key: u64,
    /// Its points vote if their vote key (half their hash, see `Batch::vote_key`) is at
    /// most this: [`vote_max`] of the voxel's vote-sampling exponent (fixed during a
    /// frame), halved.
    pub(crate) vote_key_max: u32,
    /// Votes taken for a class and not yet in the voxel's histogram, as (class, count),
    /// on targets that accumulate point by point: a voxel's points mostly vote for one
    /// class, and counting them here saves a histogram update per point. (The bins and
    /// the votes-taken count saturate, so when votes arrive does not matter.)
    pub(crate) votes: (u8, u32),
}

impl Accumulator {
    /// An unused accumulator.
    pub(crate) const NONE: Accumulator = Accumulator {
        sums: PackedSums::EMPTY,
        slot: usize::MAX,
        key: 0,
        vote_key_max: 0,
        votes: (0, 0),
    };
}

/// The accumulator of a packed voxel key: its cell index in a 4x4x4 block.
#[inline]
pub(crate) fn accumulator_index(key: u64) -> usize {
    ((key & 0x3) | ((key >> 14) & 0xc) | ((key >> 28) & 0x30)) as usize
}

/// Entries of the frame's block cache: rays and points revisit the blocks around the
/// sensor many times per frame, and a hash lookup costs a cache miss or two. A frame
/// touches thousands of blocks at fine cells (2,243 per frame at 5 cm on the synthetic
/// living room: with 128 entries a quarter of the rays' block entries missed the cache,
/// with 2,048 about 1 %), so 64-bit targets get 2,048 entries (32 KiB of stack); 32-bit
/// targets, microcontrollers with a few tens of KiB of stack, 128 (2 KiB).
pub(crate) const BLOCK_CACHE: usize = if cfg!(target_pointer_width = "64") {
    2048
} else {
    128
};

/// Copies of `missed` masks in a [`FrameState`]: one per block cache entry on 64-bit
/// targets, none on 32-bit ones (whose walks do not read them).
const MISSED_COPIES: usize = if cfg!(target_pointer_width = "64") {
    BLOCK_CACHE
} else {
    0
};

/// The block cache entry of a packed block key: a multiplicative hash, as the blocks
/// along one ray (up to dozens in a row on one axis) must not evict each other.
#[inline]
fn block_cache_index(packed: u64) -> usize {
    if cfg!(target_pointer_width = "64") {
        hash_in_u64(packed, BLOCK_CACHE.trailing_zeros())
    } else {
        hash_in_u32(packed, BLOCK_CACHE.trailing_zeros())
    }
}

/// The top `bits` bits of `packed` times a 64-bit odd constant.
#[inline(always)]
fn hash_in_u64(packed: u64, bits: u32) -> usize {
    (packed.wrapping_mul(0x9e37_79b9_7f4a_7c15) >> (64 - bits)) as usize
}

/// [`hash_in_u64`] in 32-bit multiplications, for 32-bit targets (where a 64-bit one
/// takes three): x, the high word, is spread over the low word (y and z) first. On the
/// Cortex-M4F firmware's frames it also keeps more blocks: 3,638 block cache misses in the
/// 4 frames, against 8,580 for the 64-bit hash.
#[inline(always)]
fn hash_in_u32(packed: u64, bits: u32) -> usize {
    let (yz, x) = (packed as u32, (packed >> 32) as u32);
    let mixed = yz.wrapping_add(x.wrapping_mul(0x85eb_ca6b));
    (mixed.wrapping_mul(0x9e37_79b9) >> (32 - bits)) as usize
}

/// Per-frame state; lives on the stack during one integration.
pub(crate) struct FrameState<'s> {
    pub(crate) rot: Matrix3<f32>,
    pub(crate) origin: [f32; 3],
    pub(crate) origin_s: [f32; 3],
    pub(crate) origin_key: VoxelKey,
    pub(crate) stamp: u16,
    pub(crate) h: f32,
    pub(crate) inv_h: f32,
    /// `2^Q / h`: world metres to quanta.
    pub(crate) inv_quantum: f32,
    /// Key range in quanta: `[-32767 * 2^Q, 32768 * 2^Q)`.
    pub(crate) t_min: f32,
    pub(crate) t_max: f32,
    pub(crate) quant_bits: u32,
    pub(crate) quant_mask: i32,
    pub(crate) qscale: f32,
    pub(crate) qhalf: i32,
    pub(crate) max_range: f32,
    /// Whether every point within max range of the sensor has its voxel in the key range,
    /// so that phase 1 need not check its key (true unless the sensor is within max range
    /// of the key range's edge; see [`keys_in_range`]).
    pub(crate) keys_in_range: bool,
    /// The constant miss and the log-odds clamps in fixed point.
    pub(crate) miss: i32,
    pub(crate) clamp: (i32, i32),
    pub(crate) head: u32,
    /// Blocks this frame has touched, by [`block_cache_index`]: (packed key, slot). They
    /// cannot be evicted during the frame, so entries never go stale.
    pub(crate) block_cache: [(u64, u32); BLOCK_CACHE],
    /// Beside each block cache entry, a copy of its block's `missed` mask, for the
    /// free-space walks of 64-bit targets (none on 32-bit ones): a copy may lag behind
    /// the block, never run ahead (the mask only grows during a frame).
    pub(crate) missed_copy: [u64; MISSED_COPIES],
    pub(crate) voxel_cache: (u64, usize),
    /// Open voxel accumulators of phase 1.
    pub(crate) acc: [Accumulator; ACCUMULATORS],
    pub(crate) voxels_exhausted: bool,
    pub(crate) blocks_exhausted: bool,
    pub(crate) report: FrameReport,
    pub(crate) evicted_before: (u64, u64),
    /// Where evicted entries go as records, if the caller gave a sink.
    pub(crate) sink: Option<&'s mut dyn RecordSink>,
    /// A depth frame's image: phase 3 looks up where a surface voxel's mean projects.
    pub(crate) image: Option<DepthImage<'s>>,
    /// Whether phase 1 sums a batch's points by voxel ([`Vectors::by_voxel`]).
    pub(crate) by_voxel: bool,
}

impl FrameState<'_> {
    /// A sensor-frame point in world coordinates (`f32`, the key convention).
    #[inline]
    pub(crate) fn to_world(&self, p: &[f32; 3]) -> [f32; 3] {
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
    pub(crate) fn quantise(&self, w: &[f32; 3]) -> Option<(VoxelKey, [i32; 3])> {
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

impl<const V: usize, const B: usize, const C: usize> Map<V, B, C> {
    /// Starts a frame at `pose` (sensor to world): checks the pose, keys the sensor origin
    /// and stamps the frame. Nothing in the map changes on an error.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    pub(crate) fn begin_frame<'s>(
        &mut self,
        pose: &Isometry3<f32>,
    ) -> Result<FrameState<'s>, Error> {
        validate_pose(pose)?;
        let t = pose.translation.vector;
        let h = self.config.cell_size;
        let origin = [t.x, t.y, t.z];
        let inv_h = 1.0 / h;
        let origin_s = [t.x * inv_h, t.y * inv_h, t.z * inv_h];
        let origin_key = origin_key(&origin_s).ok_or(Error::PoseOutOfRange)?;
        let stamp = self.next_stamp();
        let qscale = (1u32 << self.config.quant_bits) as f32;
        Ok(FrameState {
            rot: *pose.rotation.to_rotation_matrix().matrix(),
            origin,
            origin_s,
            origin_key,
            stamp,
            h,
            inv_h,
            inv_quantum: inv_h * qscale,
            t_min: -(KEY_LIMIT as f32) * qscale,
            t_max: (KEY_LIMIT + 1) as f32 * qscale,
            quant_bits: self.config.quant_bits as u32,
            quant_mask: (1 << self.config.quant_bits) - 1,
            qscale,
            qhalf: 1 << (self.config.quant_bits - 1),
            max_range: self.config.max_range,
            keys_in_range: keys_in_range(&origin_s, self.config.max_range * inv_h),
            miss: to_fixed(self.config.miss),
            clamp: (
                to_fixed(self.config.clamp_min),
                to_fixed(self.config.clamp_max),
            ),
            head: NIL,
            block_cache: [(0, 0); BLOCK_CACHE],
            missed_copy: [0; MISSED_COPIES],
            voxel_cache: (0, 0),
            acc: [Accumulator::NONE; ACCUMULATORS],
            voxels_exhausted: false,
            blocks_exhausted: false,
            report: FrameReport::default(),
            evicted_before: (self.stats.voxels_evicted, self.stats.blocks_evicted),
            sink: None,
            image: None,
            by_voxel: Vectors::AsBuilt.by_voxel(),
        })
    }

    /// The stamp of the next frame. Stamps run 1..=65535; whenever they start over (also
    /// when the u32 frame count wraps, or after loading a snapshot), all old stamps are
    /// forgotten, so no block's masks can look current by accident.
    fn next_stamp(&mut self) -> u16 {
        let stamp = (self.stats.frames % 65535) as u16 + 1;
        if stamp == 1 {
            for b in self.blocks.slots.iter_mut() {
                b.stamp = 0;
            }
        }
        stamp
    }

    /// The block with packed key `packed`, created if missing, with per-frame masks
    /// current. `link` puts a newly touched block on the frame's list (phase 1).
    ///
    /// The frame's block cache is checked inline (the free-space walk enters a block
    /// every four steps or so); the rest is out of line.
    #[inline(always)]
    pub(crate) fn frame_block(
        &mut self,
        f: &mut FrameState,
        packed: u64,
        link: bool,
    ) -> Option<usize> {
        match f.block_cache.get(block_cache_index(packed)) {
            Some(&(key, slot)) if key == packed => Some(slot as usize),
            _ => self.frame_block_uncached(f, packed, link),
        }
    }

    /// The `missed` mask of the block with packed key `packed` if the frame's block cache
    /// holds the block, else 0 (nothing known). No branch on the answer: callers use it to
    /// rule out voxels that certainly have their miss, many in a row.
    ///
    /// The mask is the cache's copy (see [`FrameState::missed_copy`]), which lives in
    /// the cache's own cache lines, not the block's.
    #[inline(always)]
    pub(crate) fn cached_missed(f: &FrameState, packed: u64) -> u64 {
        let c = block_cache_index(packed);
        let key = f.block_cache.get(c).map_or(0, |e| e.0);
        let missed = f.missed_copy.get(c).copied().unwrap_or(0);
        missed & ((key == packed) as u64).wrapping_neg()
    }

    /// Records in the frame's block cache that cell `bit` (a one-bit mask) of the block
    /// with packed key `packed` got its miss.
    #[inline(always)]
    pub(crate) fn note_missed(f: &mut FrameState, packed: u64, bit: u64) {
        let c = block_cache_index(packed);
        if f.block_cache.get(c).is_some_and(|e| e.0 == packed)
            && let Some(m) = f.missed_copy.get_mut(c)
        {
            *m |= bit;
        }
    }

    /// [`Map::frame_block`] for a block not in the frame's block cache.
    #[inline(never)]
    fn frame_block_uncached(
        &mut self,
        f: &mut FrameState,
        packed: u64,
        link: bool,
    ) -> Option<usize> {
        let c = block_cache_index(packed);
        let bs = match self.blocks.find(packed) {
            Some(bs) => bs,
            None => {
                if self.blocks.is_full() && !f.blocks_exhausted {
                    f.blocks_exhausted = self.evict_blocks(f) == 0;
                    f.voxel_cache = (0, 0);
                }
                let bs = self.blocks.insert(Block::new(packed)).ok()?;
                f.report.blocks_created += 1;
                bs
            }
        };
        let b = self.blocks.get_mut(bs)?;
        if b.touch(f.stamp) && link {
            b.frame_next = f.head;
            f.head = bs as u32 + 1;
        }
        let missed = b.missed;
        if let Some(entry) = f.block_cache.get_mut(c) {
            *entry = (packed, bs as u32);
        }
        if let Some(m) = f.missed_copy.get_mut(c) {
            *m = missed;
        }
        Some(bs)
    }

    /// Calls `visit(map, slot, block)` for every block on the frame's list from `head`, in
    /// list order, with a copy of the block as it is when reached.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    pub(crate) fn for_each_frame_block(
        &mut self,
        head: u32,
        mut visit: impl FnMut(&mut Self, usize, Block),
    ) {
        let mut i = head;
        while i != NIL {
            let bs = (i - 1) as usize;
            let Some(&b) = self.blocks.slots.get(bs) else {
                return;
            };
            visit(self, bs, b);
            i = b.frame_next;
        }
    }

    /// Bottom-up merge sort of the frame's block list by packed key (no allocation).
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    pub(crate) fn sort_frame_list(&mut self, head: u32) -> u32 {
        // A damaged link ends a run (`next`) and sorts last (`key`) instead of halting.
        let key = |m: &Self, i: u32| m.blocks.linked(i).map_or(u64::MAX, Entry::packed_key);
        let next = |m: &Self, i: u32| m.blocks.linked(i).map_or(NIL, |b| b.frame_next);
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
                    match self.blocks.linked_mut(tail) {
                        Some(t) => t.frame_next = e,
                        None => list = e,
                    }
                    tail = e;
                }
                p = q;
            }
            if let Some(t) = self.blocks.linked_mut(tail) {
                t.frame_next = NIL;
            }
            if merges <= 1 {
                return list;
            }
            insize *= 2;
        }
    }

    /// Ends the frame: counts it and its losses in the map's totals, and completes its
    /// report with the evictions it caused.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    pub(crate) fn close_frame(&mut self, f: &mut FrameState) -> FrameReport {
        self.stats.frames = self.stats.frames.wrapping_add(1);
        self.stats.dropped_points += f.report.dropped_points as u64;
        self.stats.dropped_misses += f.report.dropped_misses as u64;
        f.report.voxels_evicted = (self.stats.voxels_evicted - f.evicted_before.0) as u32;
        f.report.blocks_evicted = (self.stats.blocks_evicted - f.evicted_before.1) as u32;
        f.report
    }
}

/// Whether every point within `range` voxels of the sensor at `s` (voxel units) is in
/// the key range: the sensor is more than [`key_reach`] voxels from the range's edge.
fn keys_in_range(s: &[f32; 3], range: f32) -> bool {
    s.iter()
        .all(|s| s.abs() + key_reach(range) < KEY_LIMIT as f32)
}

/// How far (voxels) from the sensor a point within `range` voxels may get its key, with
/// room for a pose whose rotation is up to 0.1 % off unit length (as `validate_pose`
/// allows) and for rounding: 1 % and two voxels.
pub(crate) fn key_reach(range: f32) -> f32 {
    range * 1.01 + 2.0
}

/// The key of the sensor's voxel from its position in voxel units, or `None` outside the
/// key range.
fn origin_key(s: &[f32; 3]) -> Option<VoxelKey> {
    let ok = |s: f32| axis_key(s).map(|k| k as i32);
    match (ok(s[0]), ok(s[1]), ok(s[2])) {
        (Some(x), Some(y), Some(z)) => VoxelKey::from_ints(x, y, z),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use crate::testutil::*;
    use crate::*;

    /// Both block cache hashes (at the cache sizes of 32- and 64-bit targets) give the
    /// blocks of a straight run along any axis distinct entries: 24 blocks in a row at 128
    /// entries, 64 at 2,048, from 2,000 random starts in the key range per axis.
    #[test]
    fn blocks_in_a_row_do_not_share_a_cache_entry() {
        let mut rng = Lcg(5);
        for _ in 0..2000 {
            let start: [i16; 3] = core::array::from_fn(|_| (rng.next() * 16000.0) as i16 - 8000);
            for axis in 0..3 {
                for (hash, bits, run) in [
                    (hash_in_u32 as fn(u64, u32) -> usize, 7, 24),
                    (hash_in_u64, 11, 64),
                ] {
                    let mut seen = std::collections::BTreeSet::new();
                    for n in 0..run {
                        let mut b = start;
                        b[axis] += n;
                        seen.insert(hash(key(b[0], b[1], b[2]).packed(), bits));
                    }
                    assert_eq!(
                        seen.len(),
                        run as usize,
                        "start {start:?}, axis {axis}, {bits} bits"
                    );
                }
            }
        }
    }

    #[test]
    fn quantised_offsets_reach_but_never_exceed_half_range() {
        // A point on a voxel's lower corner quantises to -2^(Q-1) on every axis, the largest
        // f32 below the upper corner to +2^(Q-1), for every allowed Q.
        for qb in 1..=Config::MAX_QUANT_BITS {
            let mut cfg = Config::with_cell_size(0.125);
            cfg.quant_bits = qb;
            let mut map: Map<16, 16, 1> = Map::try_new(cfg).unwrap();
            let lo = 1.0f32; // voxel 8
            let hi = f32::from_bits(1.125f32.to_bits() - 1); // still voxel 8
            let pts = [lp(lo, lo, lo, 1), lp(hi, hi, hi, 1)];
            map.integrate(&Isometry3::identity(), &pts).unwrap();
            let half = 1i32 << (qb - 1);
            let v = voxel(&map, &key(8, 8, 8));
            assert_eq!(v.n, 2);
            assert_eq!(v.s1, [0, 0, 0], "Q={qb}");
            assert_eq!(v.s2, [2 * half * half; 6], "Q={qb}");
            let mut map2: Map<16, 16, 1> = Map::try_new(cfg).unwrap();
            map2.integrate(&Isometry3::identity(), &pts[..1]).unwrap();
            assert_eq!(voxel(&map2, &key(8, 8, 8)).s1, [-half; 3], "Q={qb}");
        }
    }

    /// Regression: Frame stamps are `frames % 65535 + 1`, and old stamps are only forgotten when the
    /// stamp is 1 and `frames > 0`. When `frames` wraps from u32::MAX to 0 (a snapshot may
    /// carry any frame count), two consecutive frames both get stamp 1 without a reset:
    /// the second frame's blocks look already touched, are never put on the frame list,
    /// and their voxels get no decay, no hit and no rays. `n` then exceeds `n_max` (with
    /// n_max = 65535 and full frames, S2 overflows i32 in the next frame), and the map
    /// writes a snapshot it cannot read back.
    #[test]
    fn frame_counter_wrap_skips_decay_and_hits() {
        let mut cfg = Config::DEFAULT;
        cfg.n_min = 2;
        cfg.n_max = 2;
        let mut map: Map<16, 64, 1> = Map::try_new(cfg).unwrap();
        let mut s = snapshot(&map);
        s[76..80].copy_from_slice(&u32::MAX.to_le_bytes());
        fix_crc(&mut s);
        map.read_snapshot(&s).unwrap();
        assert_eq!(map.stats().frames, u32::MAX);
        let p = lp(0.05, 0.05, 1.05, 1);
        let k = key(0, 0, 10);
        let r1 = map.integrate(&Isometry3::identity(), &[p]).unwrap();
        assert_eq!(r1.end_voxels, 1);
        let r2 = map.integrate(&Isometry3::identity(), &[p; 3]).unwrap();
        let n = map.gaussian(&k).unwrap().count;
        let ok_decay = n <= 2;
        let ok_hit = r2.end_voxels == 1 && map.log_odds(&k) == 2.0 * 870.0 / 1024.0;
        let mut copy: Map<16, 64, 1> = Map::new(Config::DEFAULT);
        let ok_snapshot = copy.read_snapshot(&snapshot(&map)).is_ok();
        assert!(
            ok_decay && ok_hit && ok_snapshot,
            "n = {n} (n_max 2), end_voxels {}, log-odds {}, snapshot readable {ok_snapshot}",
            r2.end_voxels,
            map.log_odds(&k)
        );
    }

    /// Regression: The consequence of the stamp wrap-around at the documented bounds: with
    /// `n_max = 65535`, three full frames of worst-case points (|q| = 32 on every axis) into
    /// one voxel, the middle one without decay, give `S2 = 2.13e6 * 1024 > i32::MAX`:
    /// overflow (debug panic; release wraps S2 negative).
    #[test]
    fn frame_counter_wrap_overflows_sums() {
        let mut cfg = Config::with_cell_size(0.125);
        cfg.n_max = 65535;
        let mut map: std::boxed::Box<Map<16, 64, 1>> =
            std::boxed::Box::new(Map::try_new(cfg).unwrap());
        map.stats.frames = u32::MAX; // what a snapshot may carry (see the test above)
                                     // The lower corner of voxel (8, 8, 8): q = -32 on every axis.
        let pts = std::vec![lp(1.0, 1.0, 1.0, 1); MAX_FRAME_POINTS];
        for _ in 0..3 {
            map.integrate(&Isometry3::identity(), &pts).unwrap();
        }
        let v = voxel(&*map, &key(8, 8, 8));
        assert!(v.n <= 65535 && v.s2[0] > 0, "n {} s2 {:?}", v.n, v.s2);
    }
}
