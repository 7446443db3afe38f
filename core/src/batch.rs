//! Phase 1 in batches of up to [`BATCH`] points (for a depth image, one tile of
//! [`TILE_COLS`] x `BATCH / TILE_COLS` pixels), two stages per batch:
//!
//! 1. **convert** ([`Phase::Points`](crate::Phase::Points)): pixels to sensor points, world
//!    coordinates, voxel keys and quantised offsets, in structure-of-arrays loops without
//!    branches, which the compiler vectorises. They perform the same IEEE operations in
//!    the same order as the scalar path ([`crate::depth_point`], `FrameState::to_world`,
//!    `FrameState::quantise`), so the map is bit-identical;
//! 2. **accumulate** ([`Phase::Accumulate`](crate::Phase::Accumulate)): one voxel lookup per
//!    run of consecutive points in the same voxel (a key comparison for the others),
//!    integer sums in registers, votes. A point that is not the common case (beyond max
//!    range, outside the key range, non-finite) goes through the scalar `Map::add_point`,
//!    which handles and counts every case.

use crate::camera::{DepthImage, DepthKind, LabelImage, PixelRays};
use crate::config::Config;
#[cfg(doc)]
use crate::frame::Accumulator;
use crate::frame::{accumulator_index, FrameState};
use crate::key::VoxelKey;
use crate::labels::{LabeledPoint, Labels};
use crate::map::Map;
use crate::votes::{vote_hash, voting_classes};
use crate::voxel::packed_offsets;

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
const FAST: u8 = 0;
/// Otherwise fast, but a label above the class count (counted as `rejected_label`).
const BAD_LABEL: u8 = 1;
/// Anything else: handled point by point by `Map::add_point`.
const SLOW: u8 = 2;
/// A pixel without a depth measurement (counted as `rejected_depth`).
const NO_DEPTH: u8 = 3;

/// One batch of points in structure-of-arrays form.
pub(crate) struct Batch {
    len: usize,
    /// Sensor-frame points (x, y, z).
    p: [[f32; BATCH]; 3],
    /// Packed voxel keys ([`VoxelKey::packed`]; valid for `FAST` points), and their two
    /// halves: biased x, and biased y and z.
    key: [u64; BATCH],
    key_x: [u32; BATCH],
    key_yz: [u32; BATCH],
    /// Quantised offsets in the voxel (x, y, z; valid for `FAST` points), and their packed
    /// contribution to the voxel's sums (`packed_offsets`).
    q: [[i32; BATCH]; 3],
    w: [[u64; BATCH]; 3],
    /// Where the points came from (see [`Source::index`]).
    pub(crate) source: Source,
    /// The class a point votes for (0: none).
    vote: [u8; BATCH],
    /// Whether a point votes, as a number to compare: half its vote-sampling hash
    /// ([`crate::vote_hash`]) if it votes for a class, else `u32::MAX`. A point votes
    /// in a voxel if `vote_key <= vote_max >> 1`, which is `hash <= vote_max`
    /// ([`Accumulator::vote_max`] is `2^k - 1`) for the points with a class and never
    /// true for the others.
    vote_key: [u32; BATCH],
    status: [u8; BATCH],
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
            vote: [0; BATCH],
            vote_key: [u32::MAX; BATCH],
            status: [FAST; BATCH],
        }
    }

    /// Loads `points` (at most [`BATCH`]).
    pub(crate) fn load_points(&mut self, points: &[LabeledPoint]) {
        self.len = points.len().min(BATCH);
        self.source = Source::POINTS;
        for (j, lp) in points.iter().take(BATCH).enumerate() {
            self.p[0][j] = lp.position.x;
            self.p[1][j] = lp.position.y;
            self.p[2][j] = lp.position.z;
            self.status[j] = FAST;
        }
    }

    /// Loads a tile of the image: `n <= TILE_COLS` pixels (at the image's stride) from
    /// column `col0` on, in each of the `rows` from `row0` on (as many as fit), as
    /// [`crate::depth_point`] turns them into points, with their one-class labels (if
    /// the image has those) and their status; `classes` is the map's class count.
    pub(crate) fn load_tile(
        &mut self,
        image: &DepthImage<'_>,
        rays: &PixelRays,
        (row0, rows): (usize, usize),
        (col0, n): (usize, usize),
        classes: usize,
    ) {
        let stride = image.stride as usize;
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
        for row in (row0..).step_by(stride).take(rows) {
            let first = row * width + col0;
            let depth = image.depth.get(first..).unwrap_or(&[]);
            let start = self.len.min(BATCH);
            let y = rays.y(row);
            let end = match (stride, depth.get(..n)) {
                (1, Some(depth)) if n == TILE_COLS => self.put_full_row(&xs, y, depth, start),
                (1, _) => self.put_row(&xs[..n], y, depth.iter(), start),
                _ => self.put_row(&xs[..n], y, depth.iter().step_by(stride), start),
            };
            self.len = end;
            let votes = &mut self.vote[start..end];
            match image.labels {
                LabelImage::Top1(l) => {
                    let l = l.get(first..).unwrap_or(&[]);
                    match (stride, l.get(..votes.len())) {
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
                for j in start..end {
                    // Undo the planar scaling: scale = d / |ray| instead of d.
                    let (x, d) = (xs[j - start], self.p[2][j]);
                    let scale = d / libm::sqrtf(x * x + y * y + 1.0);
                    self.p[0][j] = x * scale;
                    self.p[1][j] = y * scale;
                    self.p[2][j] = scale;
                }
            }
        }
        self.set_status(classes);
    }

    /// The status of every loaded point before conversion: `NO_DEPTH`, `BAD_LABEL` (a
    /// vote above the class count) or `FAST`. z is the depth (or has its sign and
    /// finiteness); written so that NaN fails: the same test as `depth_point`.
    fn set_status(&mut self, classes: usize) {
        let n = self.len.min(BATCH);
        let statuses = self.status[..n].iter_mut().zip(&self.vote[..n]);
        for ((status, &vote), &z) in statuses.zip(&self.p[2][..n]) {
            let bad_label = if vote as usize > classes {
                BAD_LABEL
            } else {
                FAST
            };
            *status = if z > 0.0 && z < f32::INFINITY {
                bad_label
            } else {
                NO_DEPTH
            };
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

    /// World coordinates, voxel keys, offsets and the status of every loaded point.
    pub(crate) fn convert(&mut self, f: &FrameState) {
        let r = &f.rot;
        let max2 = f.max_range * f.max_range;
        let n = self.len.min(BATCH);
        for j in 0..n {
            let (x, y, z) = (self.p[0][j], self.p[1][j], self.p[2][j]);
            let r2 = x * x + y * y + z * z;
            let mut fast = r2 > 0.0 && r2 <= max2;
            let mut k = [0u32; 3];
            let mut q = [0i32; 3];
            for i in 0..3 {
                let w = r[(i, 0)] * x + r[(i, 1)] * y + r[(i, 2)] * z + f.origin[i];
                let t = w * f.inv_quantum;
                fast &= t >= f.t_min && t < f.t_max;
                let m = floor_small(t);
                k[i] = ((m >> f.quant_bits) + 32768) as u32 & 0xffff;
                q[i] = (m & f.quant_mask) - f.qhalf + ((t - m as f32) >= 0.5) as i32;
            }
            for (axis, qi) in self.q.iter_mut().zip(q) {
                axis[j] = qi;
            }
            self.key_x[j] = k[0];
            self.key_yz[j] = (k[1] << 16) | k[2];
            // NO_DEPTH stays, FAST becomes SLOW unless every check passed.
            self.status[j] = self.status[j].max(if fast { FAST } else { SLOW });
        }
        // 64-bit lanes from here on (the loop above runs in 32-bit lanes, twice as many
        // per vector instruction).
        for j in 0..n {
            self.key[j] = ((self.key_x[j] as u64) << 32) | self.key_yz[j] as u64;
            let w = packed_offsets([self.q[0][j], self.q[1][j], self.q[2][j]]);
            for (axis, wi) in self.w.iter_mut().zip(w) {
                axis[j] = wi;
            }
        }
    }

    /// Labels from `labels(pixel)` for every point (see [`Source::index`]), checked against
    /// the map's class count and turned into the class each votes for; a point with several
    /// voting classes takes the scalar path.
    pub(crate) fn set_labels(
        &mut self,
        labels: impl Fn(usize) -> Labels,
        config: &Config,
        classes: usize,
    ) {
        for j in 0..self.len.min(BATCH) {
            let l = labels(self.source.index(j));
            let voting = voting_classes(&l, config);
            self.vote[j] = voting.first().copied().unwrap_or(0);
            if self.status[j] == FAST {
                if !l.fits(classes) {
                    self.status[j] = BAD_LABEL;
                } else if voting.len() > 1 {
                    self.status[j] = SLOW;
                }
            }
        }
    }

    /// The vote keys of the loaded points ([`Batch::vote_key`]), from their votes:
    /// `labelled` is false when no point can vote (the batch has no labels).
    pub(crate) fn set_vote_keys(&mut self, labelled: bool) {
        let n = self.len.min(BATCH);
        if !labelled {
            self.vote_key[..n].fill(u32::MAX);
            return;
        }
        for j in 0..n {
            let hash = vote_hash(&[self.p[0][j], self.p[1][j], self.p[2][j]]);
            self.vote_key[j] = if self.vote[j] != 0 {
                hash >> 1
            } else {
                u32::MAX
            };
        }
    }

    fn point(&self, j: usize) -> [f32; 3] {
        [self.p[0][j], self.p[1][j], self.p[2][j]]
    }
}

/// The accumulator index of a run whose voxel could not be created (the map is full).
const DROPPED: usize = usize::MAX;

impl<const V: usize, const B: usize, const C: usize> Map<V, B, C> {
    /// The accumulation stage for a converted batch with its labels set; `labels(index)`
    /// gives the labels of a point (see [`Source::index`]) for the scalar path. Every
    /// point ends in exactly one counter of the frame's report.
    ///
    /// Consecutive `FAST` points of one voxel (a run) are summed in registers and added to
    /// the voxel's accumulator once; a new run costs a key comparison with its accumulator
    /// and, rarely, a voxel lookup.
    #[inline]
    pub(crate) fn accumulate(
        &mut self,
        f: &mut FrameState,
        batch: &Batch,
        labels: impl Fn(usize) -> Labels,
    ) {
        let mut run = Run::NONE;
        for j in 0..batch.len.min(BATCH) {
            match batch.status[j] {
                FAST => {}
                NO_DEPTH => {
                    f.report.rejected_depth += 1;
                    continue;
                }
                BAD_LABEL => {
                    f.report.rejected_label += 1;
                    continue;
                }
                _ => {
                    // The scalar path uses the accumulators: the run goes in first.
                    self.end_run(f, &mut run);
                    let labels = labels(batch.source.index(j));
                    self.add_point(f, batch.point(j), &labels);
                    continue;
                }
            }
            let key = batch.key[j];
            if key != run.key {
                self.end_run(f, &mut run);
                self.start_run(f, &mut run, key);
            }
            run.n += 1;
            run.w[0] += batch.w[0][j];
            run.w[1] += batch.w[1][j];
            run.w[2] += batch.w[2][j];
            // The run's votes are counted per class and taken at once.
            let class = batch.vote[j];
            let votes = batch.vote_key[j] <= run.vote_key_max;
            if votes & (class != run.class) {
                self.take_run_votes(&mut run);
                run.class = class;
            }
            run.votes += votes as u32;
        }
        self.end_run(f, &mut run);
    }

    /// Starts a run of points in voxel `key`: its accumulator, unless that holds another
    /// voxel (then [`Map::open_run`]).
    #[inline(always)]
    fn start_run(&mut self, f: &mut FrameState, run: &mut Run, key: u64) {
        let a = accumulator_index(key);
        run.key = key;
        (run.acc, run.slot, run.vote_key_max) = match f.acc.get(a) {
            Some(acc) if acc.key == key => (a, acc.slot, acc.vote_max >> 1),
            _ => self.open_run(f, key, a),
        };
    }

    /// [`Map::start_run`] when accumulator `a` holds another voxel: finds or creates voxel
    /// `key` and opens the accumulator for it; returns the run's accumulator, slot and
    /// `vote_key_max`, or marks the run `DROPPED` (its points are counted as dropped and take
    /// no votes) when the map is full. (The run stays in registers: it is not passed.)
    #[inline(never)]
    fn open_run(&mut self, f: &mut FrameState, key: u64, a: usize) -> (usize, usize, u32) {
        match self.point_voxel(f, &VoxelKey::unpack(key)) {
            Some(vs) => {
                self.open_accumulator(f, a, vs, key);
                (a, vs, f.acc.get(a).map_or(0, |acc| acc.vote_max >> 1))
            }
            None => (DROPPED, usize::MAX, 0),
        }
    }

    /// Gives the run's voxel the votes the run counted so far.
    #[inline(always)]
    fn take_run_votes(&mut self, run: &mut Run) {
        if run.votes > 0 {
            if let Some(v) = self.voxels.slots.get_mut(run.slot) {
                v.take_votes(run.class, run.votes);
            }
            run.votes = 0;
        }
    }

    /// Adds a run's points to its accumulator (or counts them as dropped), gives its
    /// voxel its votes and ends it.
    #[inline(always)]
    fn end_run(&mut self, f: &mut FrameState, run: &mut Run) {
        self.take_run_votes(run);
        if run.n > 0 {
            if run.acc == DROPPED {
                f.report.dropped_points += run.n;
            } else {
                self.add_to_accumulator(f, run.acc, &run.w, run.n);
                f.report.points_used += run.n;
            }
        }
        *run = Run::NONE;
    }
}

/// The points of one voxel that phase 1 is summing in registers.
struct Run {
    /// The voxel's packed key (0, never a valid key, for no run).
    key: u64,
    /// Its accumulator (`DROPPED` if the voxel could not be created) and slot.
    acc: usize,
    slot: usize,
    /// The run's points and the sum of their [`packed_offsets`].
    n: u32,
    w: [u64; 3],
    /// Points vote if their [`Batch::vote_key`] is at most this: the voxel's
    /// [`Accumulator::vote_max`] halved.
    vote_key_max: u32,
    /// The run's voting points so far, all for `class`.
    votes: u32,
    class: u8,
}

impl Run {
    const NONE: Run = Run {
        key: 0,
        acc: DROPPED,
        slot: usize::MAX,
        n: 0,
        w: [0; 3],
        vote_key_max: 0,
        votes: 0,
        class: 0,
    };
}
/// `floor(t)` for `|t| < 2^22` (the key range in quanta is within `2^21`), equal to the
/// scalar path's `floor_i32` there, in operations that vectorise: adding `1.5 * 2^23`
/// rounds `t` to the nearest integer, which the float's low mantissa bits then hold; one
/// comparison turns rounding into floor. Other inputs give an unspecified value (such
/// points are not `FAST`).
#[inline]
fn floor_small(t: f32) -> i32 {
    const MAGIC: f32 = 12_582_912.0; // 1.5 * 2^23
    let rounded = ((t + MAGIC).to_bits() as i32).wrapping_sub(MAGIC.to_bits() as i32);
    rounded - ((rounded as f32 > t) as i32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::key::floor_i32;

    #[test]
    fn floor_small_is_floor_on_the_key_range() {
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
            assert_eq!(floor_small(t), floor_i32(t), "t = {t:e}");
        }
    }
}
