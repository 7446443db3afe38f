//! Phase 1 in batches of up to [`BATCH`] points (for a depth image, one tile of
//! [`TILE_COLS`] x `BATCH / TILE_COLS` pixels), two stages per batch:
//!
//! 1. **convert** ([`Phase::Points`](crate::Phase::Points)): pixels to sensor points, world
//!    coordinates, voxel keys and quantised offsets, in structure-of-arrays loops without
//!    branches, which the compiler vectorises. They perform the same IEEE operations in
//!    the same order as the scalar path ([`crate::depth_point`], `FrameState::to_world`,
//!    `FrameState::quantise`), so the map is bit-identical;
//! 2. **accumulate** ([`Phase::Accumulate`](crate::Phase::Accumulate), `accumulate.rs`): integer
//!    sums per voxel and votes, one voxel lookup per voxel of the batch.

use crate::config::Config;
use crate::geometry::camera::{mm_to_metres, Depth, DepthImage, DepthKind, LabelImage, PixelRays};
use crate::geometry::sqrt::sqrt;
#[cfg(doc)]
use crate::integrate::frame::Accumulator;
use crate::integrate::frame::FrameState;
#[cfg(doc)]
use crate::key::VoxelKey;
use crate::key::KEY_LIMIT;
use crate::labels::{LabeledPoint, Labels};
use crate::storage::votes::{vote_hash, voting_classes};
use crate::storage::voxel::packed_offsets;

/// Points per batch: large enough that the per-batch work vanishes, small enough for a
/// microcontroller's stack (a batch is about 4 KiB).
pub(crate) const BATCH: usize = 64;

/// Image columns per tile: a depth image goes through phase 1 in tiles of `TILE_COLS`
/// columns by `BATCH / TILE_COLS` rows, one batch each. A tile covers few voxels, which
/// stay in their accumulators from one tile to the next along a strip of rows; batches of
/// one row would look every voxel of a row up again for the next row.
pub(crate) const TILE_COLS: usize = 8;

/// The common case: finite, inside max range and the key range, labels that fit the map
/// with at most one voting class.
pub(crate) const FAST: u8 = 0;
/// Otherwise fast, but a label above the class count (counted as `rejected_label`).
pub(crate) const BAD_LABEL: u8 = 1;
/// Anything else: handled point by point by `Map::add_point`.
pub(crate) const SLOW: u8 = 2;
/// A pixel without a depth measurement (counted as `rejected_depth`).
pub(crate) const NO_DEPTH: u8 = 3;

/// Whether the accumulation takes points one by one (32-bit targets, see `accumulate.rs`) and
/// packs them itself ([`Batch::packed`]); the conversion then leaves the 64-bit lanes.
pub(crate) const PACK_PER_POINT: bool = cfg!(target_pointer_width = "32");

/// Entries of [`Batch::vote_key`]: none where points are packed one by one.
const VOTE_KEYS: usize = if PACK_PER_POINT { 0 } else { BATCH };

/// One batch of points in structure-of-arrays form.
pub(crate) struct Batch {
    pub(crate) len: usize,
    /// Sensor-frame points (x, y, z).
    p: [[f32; BATCH]; 3],
    /// Packed voxel keys ([`VoxelKey::packed`]; valid for `FAST` points), and their two
    /// halves: biased x, and biased y and z.
    pub(crate) key: [u64; BATCH],
    key_x: [u32; BATCH],
    key_yz: [u32; BATCH],
    /// Quantised offsets in the voxel (x, y, z; valid for `FAST` points), and their packed
    /// contribution to the voxel's sums (`packed_offsets`).
    q: [[i32; BATCH]; 3],
    pub(crate) w: [[u64; BATCH]; 3],
    /// Where the points came from (see [`Source::index`]), and whether they are pixels
    /// (whose depth is checked).
    pub(crate) source: Source,
    from_depth: bool,
    /// The class a point votes for (0: none).
    pub(crate) vote: [u8; BATCH],
    /// Whether a point votes, as a number to compare: half its vote-sampling hash
    /// ([`crate::vote_hash`]) if it votes for a class, else `u32::MAX`. A point votes
    /// in a voxel if `vote_key <= vote_max >> 1` ([`Accumulator::vote_key_max`]), which
    /// is `hash <= vote_max` (`vote_max` is `2^k - 1`) for the points with a class and
    /// never true for the others. Not kept on targets that accumulate point by point
    /// ([`PACK_PER_POINT`]; the array is empty there): they find a point's vote key
    /// only when its voxel samples votes ([`Batch::votes_in`]).
    pub(crate) vote_key: [u32; VOTE_KEYS],
    pub(crate) status: [u8; BATCH],
}

/// Where the points of a batch come from: point `j` is item
/// `first + (j / cols) * row_step + (j % cols) * col_step` of the image's pixels (a tile),
/// or of the slice of points.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Source {
    first: usize,
    cols: usize,
    row_step: usize,
    col_step: usize,
}

impl Source {
    /// Points in slice order.
    const POINTS: Source = Source {
        first: 0,
        cols: BATCH,
        row_step: 0,
        col_step: 1,
    };

    /// The pixel (or point) index of point `j` (only needed off the fast path).
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    pub(crate) fn index(&self, j: usize) -> usize {
        let (row, col) = (j / self.cols.max(1), j % self.cols.max(1));
        self.first + row * self.row_step + col * self.col_step
    }
}

impl Batch {
    pub(crate) fn new() -> Self {
        Batch {
            len: 0,
            p: [[0.0; BATCH]; 3],
            key: [0; BATCH],
            key_x: [0; BATCH],
            key_yz: [0; BATCH],
            q: [[0; BATCH]; 3],
            w: [[0; BATCH]; 3],
            source: Source::POINTS,
            from_depth: false,
            vote: [0; BATCH],
            vote_key: [u32::MAX; VOTE_KEYS],
            status: [FAST; BATCH],
        }
    }

    /// Loads `points` (at most [`BATCH`]).
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    pub(crate) fn load_points(&mut self, points: &[LabeledPoint]) {
        self.len = points.len().min(BATCH);
        self.source = Source::POINTS;
        self.from_depth = false;
        for (j, lp) in points.iter().take(BATCH).enumerate() {
            self.p[0][j] = lp.position.x;
            self.p[1][j] = lp.position.y;
            self.p[2][j] = lp.position.z;
            self.vote[j] = 0;
        }
    }

    /// Loads a tile of the image: `n <= TILE_COLS` pixels (at the image's stride) from
    /// column `col0` on, in each of the `rows` from `row0` on (as many as fit), as
    /// [`crate::depth_point`] turns them into points, with their one-class labels (if
    /// the image has those).
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    pub(crate) fn load_tile(
        &mut self,
        image: &DepthImage<'_>,
        rays: &PixelRays,
        (row0, rows): (usize, usize),
        (col0, n): (usize, usize),
    ) {
        // `max(1)`: a validated image has stride >= 1; step_by(0) would panic.
        let stride = (image.stride as usize).max(1);
        let width = image.camera.width as usize;
        let n = n.min(TILE_COLS);
        let mut xs = [0.0f32; TILE_COLS];
        for (j, x) in xs.iter_mut().enumerate().take(n) {
            *x = rays.x(col0 + j * stride);
        }
        self.source = Source {
            first: row0 * width + col0,
            cols: n,
            row_step: stride * width,
            col_step: stride,
        };
        self.len = 0;
        for r in 0..rows.min(BATCH / n.max(1)) {
            let row = row0 + r * stride;
            let first = row * width + col0;
            let start = self.len.min(BATCH);
            let y = rays.y(row);
            let end = self.put_depth_row(&image.depth, first, stride, (&xs, n), y, start);
            self.len = end;
            let Some(votes) = self.vote.get_mut(start..end) else {
                break;
            };
            match image.labels {
                LabelImage::Top1(l) => {
                    let l = l.get(first..).unwrap_or(&[]);
                    match (stride, l.get(..votes.len())) {
                        // A fixed-size copy: a single move, where a slice copy calls memcpy.
                        (1, Some(l)) if l.len() == TILE_COLS => {
                            if let (Ok(v), Ok(l)) = (
                                <&mut [u8; TILE_COLS]>::try_from(&mut *votes),
                                <&[u8; TILE_COLS]>::try_from(l),
                            ) {
                                *v = *l;
                            }
                        }
                        (1, Some(l)) => votes.copy_from_slice(l),
                        _ => {
                            for (v, i) in votes.iter_mut().zip((0..).step_by(stride)) {
                                *v = l.get(i).copied().unwrap_or(0);
                            }
                        }
                    }
                }
                _ => votes.fill(0),
            }
            if image.kind == DepthKind::Range {
                let [p0, p1, p2] = &mut self.p;
                let (p0, p1, p2) = (
                    lanes(p0, start, end),
                    lanes(p1, start, end),
                    lanes(p2, start, end),
                );
                let points = xs.iter().zip(p0).zip(p1).zip(p2);
                for (((&x, p0), p1), p2) in points {
                    // Undo the planar scaling: scale = d / |ray| instead of d.
                    let scale = *p2 / sqrt(x * x + y * y + 1.0);
                    *p0 = x * scale;
                    *p1 = y * scale;
                    *p2 = scale;
                }
            }
        }
        self.from_depth = true;
    }

    /// Writes the points of one row of a tile: `n` depths at `stride` from index `first`
    /// on, along the rays `xs` and `y`, from point `start` on; returns the end of the
    /// points written. Millimetres are converted to metres first, a row at a time.
    #[inline]
    fn put_depth_row(
        &mut self,
        depth: &Depth<'_>,
        first: usize,
        stride: usize,
        (xs, n): (&[f32; TILE_COLS], usize),
        y: f32,
        start: usize,
    ) -> usize {
        let n = n.min(TILE_COLS);
        match depth {
            Depth::Metres(d) => {
                let depth = d.get(first..).unwrap_or(&[]);
                match (stride, depth.get(..n)) {
                    (1, Some(depth)) if n == TILE_COLS => self.put_full_row(xs, y, depth, start),
                    (1, _) => self.put_row(&xs[..n], y, depth.iter(), start),
                    _ => self.put_row(&xs[..n], y, depth.iter().step_by(stride), start),
                }
            }
            Depth::Millimetres(d) => {
                let src = d.get(first..).unwrap_or(&[]);
                let mut row = [0f32; TILE_COLS];
                let mut m = 0;
                for (r, &v) in row.iter_mut().zip(src.iter().step_by(stride)).take(n) {
                    *r = mm_to_metres(v);
                    m += 1;
                }
                if m == TILE_COLS {
                    self.put_full_row(xs, y, &row, start)
                } else {
                    self.put_row(&xs[..n], y, row.iter().take(m), start)
                }
            }
        }
    }

    /// [`Batch::put_row`] for a whole row of a tile, in fixed-size arrays that compile
    /// to a few vector instructions.
    #[inline]
    fn put_full_row(
        &mut self,
        xs: &[f32; TILE_COLS],
        y: f32,
        depth: &[f32],
        start: usize,
    ) -> usize {
        let end = start + TILE_COLS;
        let [p0, p1, p2] = &mut self.p;
        let (Some(p0), Some(p1), Some(p2), Ok(depth)) = (
            p0.get_mut(start..end),
            p1.get_mut(start..end),
            p2.get_mut(start..end),
            <&[f32; TILE_COLS]>::try_from(depth),
        ) else {
            return start;
        };
        for j in 0..TILE_COLS {
            let d = depth[j];
            p0[j] = xs[j] * d;
            p1[j] = y * d;
            p2[j] = d;
        }
        end
    }

    /// Writes the planar points `d * (xs[j], y, 1)` of the depths `depth` from point
    /// `start` on, one per ray in `xs` while depths last and the batch has room; returns
    /// the end of the points written.
    #[inline]
    fn put_row<'a>(
        &mut self,
        xs: &[f32],
        y: f32,
        depth: impl Iterator<Item = &'a f32>,
        start: usize,
    ) -> usize {
        let end = (start + xs.len()).min(BATCH);
        let mut written = start;
        let [p0, p1, p2] = &mut self.p;
        let points = p0[start..end].iter_mut().zip(&mut p1[start..end]);
        let points = points.zip(&mut p2[start..end]);
        for ((x, ((p0, p1), p2)), &d) in xs.iter().zip(points).zip(depth) {
            *p0 = x * d;
            *p1 = y * d;
            *p2 = d;
            written += 1;
        }
        written
    }

    /// World coordinates, voxel keys, offsets, vote keys and the status of every loaded point, for
    /// a map with `classes` classes (a vote above is a bad label; votes set later are
    /// checked when they are set). Keys are checked against the key range only when the
    /// frame's sensor is near its edge (`FrameState::keys_in_range`): a point within max
    /// range of it cannot leave the range otherwise (on a Cortex-M4F, the checks cost about 7
    /// instructions per point).
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    pub(crate) fn convert(&mut self, f: &FrameState, classes: usize) {
        if f.keys_in_range {
            self.convert_checking::<false>(f, classes);
        } else {
            self.convert_checking::<true>(f, classes);
        }
    }

    /// [`Batch::convert`], checking every key against the key range if `CHECK_KEYS`.
    #[inline(always)]
    fn convert_checking<const CHECK_KEYS: bool>(&mut self, f: &FrameState, classes: usize) {
        // What the loops read, in locals, and the batch split into its arrays: stores
        // into the batch then cannot change what the loops read, and the compiler
        // vectorises without run-time overlap checks. The loops run over every lane (a
        // fixed trip count); lanes past `len` hold stale values that nobody reads.
        let r: [[f32; 3]; 3] = core::array::from_fn(|i| core::array::from_fn(|c| f.rot[(i, c)]));
        let (origin, inv_quantum) = (f.origin, f.inv_quantum);
        let max2_bits = (f.max_range * f.max_range).to_bits();
        let (quant_bits, quant_mask, qhalf) = (f.quant_bits, f.quant_mask, f.qhalf);
        let classes = classes.min(u8::MAX as usize) as u8;
        let from_depth = self.from_depth;
        let Batch {
            p,
            key_x,
            key_yz,
            q: offsets,
            vote,
            vote_key,
            status,
            ..
        } = self;
        for j in 0..BATCH {
            let (x, y, z) = (p[0][j], p[1][j], p[2][j]);
            // A pixel's z is its depth (or has its sign and finiteness): it must be
            // positive and finite, as in `depth_point`. As float bits that is
            // 1..=0x7f7f_ffff (0, negatives, infinity and NaN are outside), one integer
            // comparison where two float comparisons cost a flag transfer each on a
            // Cortex-M.
            let no_depth = from_depth && z.to_bits().wrapping_sub(1) >= 0x7f7f_ffff;
            let bad_label = vote[j] > classes;
            // Votes known now (one-class label images; others set theirs with the labels).
            if !PACK_PER_POINT {
                let hash = vote_hash(&[x, y, z]);
                vote_key[j] = if vote[j] != 0 { hash >> 1 } else { u32::MAX };
            }
            // `0 < r2 <= max2` (NaN fails) in float bits, as above; `max2` is positive.
            let r2 = x * x + y * y + z * z;
            let mut fast = r2.to_bits().wrapping_sub(1) < max2_bits;
            let mut k = [0u32; 3];
            let mut q = [0i32; 3];
            for i in 0..3 {
                let w = r[i][0] * x + r[i][1] * y + r[i][2] * z + origin[i];
                let t = w * inv_quantum;
                let (m, half_up) = floor_and_half(t);
                // The key range `t_min <= t < t_max` as a range of keys `m >> Q` (both
                // ends are multiples of 2^Q): -32767..=32767. Exact for a point within
                // max range, whose |t| is below 2^22 (see `floor_and_half`); other points
                // are not fast anyway.
                let key = m >> quant_bits;
                if CHECK_KEYS {
                    fast &= (key + KEY_LIMIT) as u32 <= 2 * KEY_LIMIT as u32;
                }
                k[i] = (key + 32768) as u32 & 0xffff;
                q[i] = (m & quant_mask) - qhalf + half_up as i32;
            }
            for (axis, qi) in offsets.iter_mut().zip(q) {
                axis[j] = qi;
            }
            key_x[j] = k[0];
            key_yz[j] = (k[1] << 16) | k[2];
            // The first that applies of NO_DEPTH, SLOW (unless every check passed),
            // BAD_LABEL and FAST (the scalar path counts a bad label after the depth).
            status[j] = if no_depth {
                NO_DEPTH
            } else if !fast {
                SLOW
            } else if bad_label {
                BAD_LABEL
            } else {
                FAST
            };
        }
        // Targets that accumulate point by point (32-bit ones) pack each point as they
        // add it instead (`Batch::packed`): storing the lanes and loading them again
        // costs more there than it saves.
        if !PACK_PER_POINT {
            self.fill_wide_lanes();
        }
    }

    /// The packed keys and [`packed_offsets`] of every lane, from the 32-bit lanes, in
    /// 64-bit lanes (the conversion runs in 32-bit lanes, twice as many per vector
    /// instruction).
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    fn fill_wide_lanes(&mut self) {
        let Batch {
            key,
            key_x,
            key_yz,
            q: offsets,
            w: sums,
            ..
        } = self;
        for j in 0..BATCH {
            key[j] = ((key_x[j] as u64) << 32) | key_yz[j] as u64;
            let w = packed_offsets([offsets[0][j], offsets[1][j], offsets[2][j]]);
            for (axis, wi) in sums.iter_mut().zip(w) {
                axis[j] = wi;
            }
        }
    }

    /// Labels from `labels(pixel)` for every point (see [`Source::index`]), checked against
    /// the map's class count and turned into the class each votes for; a point with several
    /// voting classes takes the scalar path.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    pub(crate) fn set_labels(
        &mut self,
        labels: impl Fn(usize) -> Labels,
        config: &Config,
        classes: usize,
    ) {
        for j in 0..self.len.min(BATCH) {
            let l = labels(self.source.index(j));
            let voting = voting_classes(&l, config);
            let vote = voting.first().copied().unwrap_or(0);
            self.vote[j] = vote;
            if !PACK_PER_POINT {
                let key = if vote != 0 {
                    vote_hash(&self.point(j)) >> 1
                } else {
                    u32::MAX
                };
                if let Some(k) = self.vote_key.get_mut(j) {
                    *k = key;
                }
            }
            if self.status[j] == FAST {
                if !l.fits(classes) {
                    self.status[j] = BAD_LABEL;
                } else if voting.len() > 1 {
                    self.status[j] = SLOW;
                }
            }
        }
    }

    /// The packed key and [`packed_offsets`] of point `j` (a `FAST` one), from the 32-bit
    /// lanes: what the 64-bit lanes hold when the conversion fills them.
    #[inline(always)]
    pub(crate) fn packed(&self, j: usize) -> (u64, [u64; 3]) {
        let (Some(&x), Some(&yz)) = (self.key_x.get(j), self.key_yz.get(j)) else {
            return (0, [0; 3]);
        };
        let q = [0, 1, 2].map(|a| self.q[a].get(j).copied().unwrap_or(0));
        (((x as u64) << 32) | yz as u64, packed_offsets(q))
    }

    /// Whether point `j` votes in a voxel whose points vote up to vote key
    /// `vote_key_max` (see [`Batch::vote_key`]), for targets that accumulate point by
    /// point: the vote hash is only computed when the voxel samples its votes (most
    /// voxels take every vote: then `vote_key_max` is `u32::MAX >> 1`, above every vote
    /// key).
    #[inline(always)]
    pub(crate) fn votes_in(&self, j: usize, vote_key_max: u32) -> bool {
        let votes_for_a_class = self.vote.get(j).is_some_and(|&v| v != 0);
        votes_for_a_class
            && (vote_key_max >= u32::MAX >> 1 || vote_hash(&self.point(j)) >> 1 <= vote_key_max)
    }

    /// The sensor point of point `j`.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    pub(crate) fn point(&self, j: usize) -> [f32; 3] {
        [self.p[0][j], self.p[1][j], self.p[2][j]]
    }
}

/// Lanes `start..end` of one coordinate of a batch (none if out of range).
#[cfg_attr(target_pointer_width = "64", inline(always))]
fn lanes(p: &mut [f32; BATCH], start: usize, end: usize) -> &mut [f32] {
    p.get_mut(start..end).unwrap_or(&mut [])
}

/// `floor(t)` and whether `t - floor(t) >= 0.5` (the scalar path's `floor_i32` and
/// half-up rounding of the offset) for `|t| < 2^22`: [`floor_and_half_by_magic`] where
/// the conversion is vectorised, [`floor_and_half_by_trunc`] on 32-bit targets. Both
/// give the same values on that range (a test checks them against `floor_i32`).
#[inline(always)]
fn floor_and_half(t: f32) -> (i32, bool) {
    if PACK_PER_POINT {
        floor_and_half_by_trunc(t)
    } else {
        floor_and_half_by_magic(t)
    }
}

/// [`floor_and_half`] from `floor(2t)`, whose high bits are `floor(t)` and whose lowest
/// bit is the half: `2t` is exact, and its conversion to `i32` truncates towards zero,
/// which is one instruction on a Cortex-M4 (whose conversion saturates, as Rust's `as`
/// does). Truncation is `floor` unless `2t` is negative with a fraction; then the
/// truncated value, converted back exactly (it is below `2^23`), is above `2t`. Other
/// inputs give unspecified values.
#[inline]
fn floor_and_half_by_trunc(t: f32) -> (i32, bool) {
    let t2 = t * 2.0;
    let truncated = t2 as i32;
    let floor2 = truncated.wrapping_sub((truncated as f32 > t2) as i32);
    (floor2 >> 1, floor2 & 1 != 0)
}

/// [`floor_and_half`] in operations that vectorise and need one float-to-integer
/// transfer: adding `1.5 * 2^23` rounds `t` to the nearest integer `n` (ties to even),
/// which the float's low mantissa bits then hold, and subtracting it again gives `n` as
/// a float exactly. `d = t - n` is exact and in `[-0.5, 0.5]`: `floor(t)` is `n - 1`
/// when `d < 0`, and `t - floor(t)` is `d + 1` (at least 0.5) then, else `d`. Other
/// inputs give unspecified values (such points are not `FAST`: the key range in quanta
/// is within `2^21` plus max range, at most 4,096 cells of at most 64 quanta,
/// `Config::MAX_RAY_CELLS`).
#[inline]
fn floor_and_half_by_magic(t: f32) -> (i32, bool) {
    const MAGIC: f32 = 12_582_912.0; // 1.5 * 2^23
    let s = t + MAGIC;
    let nearest = (s.to_bits() as i32).wrapping_sub(MAGIC.to_bits() as i32);
    let d = t - (s - MAGIC);
    let below = d < 0.0;
    (nearest.wrapping_sub(below as i32), below | (d >= 0.5))
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use crate::key::floor_i32;
    use crate::labels::LabeledPoint;
    use crate::Map;
    use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};

    /// A frame that skips the key range check (`keys_in_range`) cannot put a point within
    /// max range outside the range: sensors just inside the zone where it skips, with the
    /// most scaled rotation a pose may have, and points at max range towards the nearest
    /// edge get the keys the checked path gives them, all in range. A sensor a voxel
    /// nearer the edge is checked.
    #[test]
    fn unchecked_keys_stay_in_range() {
        for cell in [0.1f32, 0.013] {
            let mut cfg = Config::with_cell_size(cell);
            cfg.max_range = Config::MAX_RAY_CELLS as f32 * cell;
            let mut map: std::boxed::Box<Map<64, 16, 4>> = std::boxed::Box::new(Map::new(cfg));
            let reach = crate::integrate::frame::key_reach(Config::MAX_RAY_CELLS as f32);
            let zone_edge = (KEY_LIMIT as f32 - reach) * cell;
            // A quaternion 0.05 % longer than a unit one (a rotation scaled by 1.001).
            let turn = UnitQuaternion::from_euler_angles(0.3, -0.2, 0.7).into_inner();
            let rotation = UnitQuaternion::new_unchecked(turn * 1.000_499);
            for axis in 0..3 {
                for sign in [1.0f32, -1.0] {
                    let mut o = Vector3::zeros();
                    o[axis] = sign * (zone_edge - 0.5 * cell);
                    let pose = Isometry3::from_parts(Translation3::from(o), rotation);
                    let f = map.begin_frame(&pose).unwrap();
                    assert!(f.keys_in_range, "cell {cell}, axis {axis}, sign {sign}");
                    // Points at max range in the sensor frame, towards the edge in the world.
                    let mut towards = Vector3::zeros();
                    towards[axis] = sign;
                    let d = turn.conjugate() * Quaternion::from_imag(towards) * turn;
                    let points: std::vec::Vec<LabeledPoint> = [0.999_99f32, 0.99, 0.5]
                        .iter()
                        .map(|k| {
                            let p = d.imag() * (k * cfg.max_range);
                            crate::testutil::lp(p.x, p.y, p.z, 1)
                        })
                        .collect();
                    let mut batch = Batch::new();
                    batch.load_points(&points);
                    batch.convert(&f, 4);
                    for (j, lp) in points.iter().enumerate() {
                        let p = [lp.position.x, lp.position.y, lp.position.z];
                        let (key, _) = f.quantise(&f.to_world(&p)).expect("in range");
                        assert_eq!(batch.status[j], FAST, "cell {cell}, axis {axis}, {j}");
                        assert_eq!(batch.packed(j).0, key.packed());
                    }
                    let mut nearer = o;
                    nearer[axis] += sign * cell;
                    let pose = Isometry3::from_parts(Translation3::from(nearer), rotation);
                    assert!(!map.begin_frame(&pose).unwrap().keys_in_range);
                }
            }
        }
    }

    #[test]
    fn floor_and_half_match_the_scalar_path_on_the_key_range() {
        // The key range in quanta for Q = 6, its edges, halves, tiny and negative values,
        // and a pseudo-random sweep of float bit patterns inside the range.
        let edge = [
            -2_097_088.0f32,
            2_097_151.9,
            -0.0,
            0.0,
            0.5,
            -0.5,
            1.5,
            2.5,
            -2.5,
            1e-30,
            -1e-30,
            0.999_999_9,
            -0.999_999_9,
            4_194_303.5,
            -4_194_303.5,
        ];
        let mut x = 0x1234_5678u32;
        let sweep = core::iter::from_fn(|| {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            Some(f32::from_bits(x))
        })
        .filter(|t| t.abs() < 4_194_304.0)
        .take(200_000);
        for t in edge.into_iter().chain(sweep) {
            let m = floor_i32(t);
            let want = (m, (t - m as f32) >= 0.5);
            assert_eq!(floor_and_half_by_magic(t), want, "magic, t = {t:e}");
            assert_eq!(floor_and_half_by_trunc(t), want, "trunc, t = {t:e}");
        }
    }
}
