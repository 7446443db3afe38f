//! Phase 1 in batches of up to [`BATCH`] points, two stages per batch:
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

use crate::camera::{DepthImage, DepthKind, PixelRays};
use crate::config::Config;
use crate::frame::{accumulator_index, FrameState};
use crate::key::VoxelKey;
use crate::labels::{LabeledPoint, Labels};
use crate::map::Map;
use crate::votes::{takes_vote, vote_hash, voting_classes};
use crate::voxel::packed_offsets;

/// Points per batch: large enough that the per-batch work vanishes, small enough for a
/// microcontroller's stack (a batch is about 4 KiB).
pub(crate) const BATCH: usize = 64;

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
    /// Packed voxel keys in two halves: biased x, and biased y and z (valid for `FAST`
    /// points; see [`Batch::key`]).
    key_x: [u32; BATCH],
    key_yz: [u32; BATCH],
    /// Quantised offsets in the voxel (x, y, z; valid for `FAST` points), and their packed
    /// contribution to the voxel's sums (`packed_offsets`).
    q: [[i32; BATCH]; 3],
    w: [[u64; BATCH]; 3],
    /// The class a point votes for (0: none).
    vote: [u8; BATCH],
    /// Vote-sampling hashes of the sensor points ([`crate::vote_hash`]), when computed.
    hash: [u32; BATCH],
    status: [u8; BATCH],
}

impl Batch {
    pub(crate) fn new() -> Self {
        Batch {
            len: 0,
            p: [[0.0; BATCH]; 3],
            key_x: [0; BATCH],
            key_yz: [0; BATCH],
            q: [[0; BATCH]; 3],
            w: [[0; BATCH]; 3],
            vote: [0; BATCH],
            hash: [0; BATCH],
            status: [FAST; BATCH],
        }
    }

    /// Loads `points` (at most [`BATCH`]).
    pub(crate) fn load_points(&mut self, points: &[LabeledPoint]) {
        self.len = points.len().min(BATCH);
        for (j, lp) in points.iter().take(BATCH).enumerate() {
            self.p[0][j] = lp.position.x;
            self.p[1][j] = lp.position.y;
            self.p[2][j] = lp.position.z;
            self.status[j] = FAST;
        }
    }

    /// Loads `n <= BATCH` pixels of image row `row` from column `col0` on, at the image's
    /// stride, as [`crate::depth_point`] turns them into points.
    pub(crate) fn load_pixels(
        &mut self,
        image: &DepthImage<'_>,
        rays: &PixelRays,
        (row, col0, n): (usize, usize, usize),
    ) {
        let stride = image.stride as usize;
        let first = row * image.camera.width as usize + col0;
        let depth = image.depth.get(first..).unwrap_or(&[]);
        let y = rays.y(row);
        let n = n.min(BATCH);
        match (image.kind, stride) {
            (DepthKind::Planar, 1) => self.load_row(depth.iter().take(n), |j| rays.x(col0 + j), y),
            (DepthKind::Planar, _) => self.load_row(
                depth.iter().step_by(stride).take(n),
                |j| rays.x(col0 + j * stride),
                y,
            ),
            (DepthKind::Range, _) => {
                self.load_row(
                    depth.iter().step_by(stride).take(n),
                    |j| rays.x(col0 + j * stride),
                    y,
                );
                for j in 0..self.len {
                    // Undo the planar scaling: scale = d / |ray| instead of d.
                    let (x, d) = (rays.x(col0 + j * stride), self.p[2][j]);
                    let scale = d / libm::sqrtf(x * x + y * y + 1.0);
                    self.p[0][j] = x * scale;
                    self.p[1][j] = y * scale;
                    self.p[2][j] = scale;
                }
            }
        }
    }

    /// Planar points `d * (x(j), y, 1)` for the depths `depths`.
    #[inline]
    fn load_row<'a>(
        &mut self,
        depths: impl Iterator<Item = &'a f32>,
        x: impl Fn(usize) -> f32,
        y: f32,
    ) {
        let mut n = 0;
        for (j, &d) in depths.enumerate() {
            let rx = x(j);
            self.p[0][j] = rx * d;
            self.p[1][j] = y * d;
            self.p[2][j] = d;
            // Written so that NaN fails: the same test as `depth_point`.
            self.status[j] = if d > 0.0 && d < f32::INFINITY {
                FAST
            } else {
                NO_DEPTH
            };
            n = j + 1;
        }
        self.len = n;
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
        for j in 0..n {
            let w = packed_offsets([self.q[0][j], self.q[1][j], self.q[2][j]]);
            for (axis, wi) in self.w.iter_mut().zip(w) {
                axis[j] = wi;
            }
        }
    }

    /// Labels of pixels with one class each: `labels` from the batch's first pixel on, at
    /// `stride`. A class id is the class it votes for (0, void, votes for nothing).
    pub(crate) fn set_top1_labels(&mut self, labels: &[u8], stride: usize, classes: usize) {
        let n = self.len.min(BATCH);
        for (j, &c) in labels.iter().step_by(stride.max(1)).take(n).enumerate() {
            self.vote[j] = c;
            if c as usize > classes && self.status[j] == FAST {
                self.status[j] = BAD_LABEL;
            }
        }
    }

    /// Labels from `labels(j)` for every point, checked against the map's class count and
    /// turned into the class each votes for; a point with several voting classes takes the
    /// scalar path.
    pub(crate) fn set_labels(
        &mut self,
        labels: impl Fn(usize) -> Labels,
        config: &Config,
        classes: usize,
    ) {
        for j in 0..self.len.min(BATCH) {
            let l = labels(j);
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

    /// No labels: no point votes.
    pub(crate) fn clear_labels(&mut self) {
        self.vote = [0; BATCH];
    }

    /// The vote-sampling hash of every loaded point (needed when the points have labels).
    pub(crate) fn hash_points(&mut self) {
        let n = self.len.min(BATCH);
        for j in 0..n {
            self.hash[j] = vote_hash(&[self.p[0][j], self.p[1][j], self.p[2][j]]);
        }
    }

    /// The packed voxel key of point `j` (a `FAST` one).
    #[inline]
    fn key(&self, j: usize) -> u64 {
        ((self.key_x[j] as u64) << 32) | self.key_yz[j] as u64
    }

    fn point(&self, j: usize) -> [f32; 3] {
        [self.p[0][j], self.p[1][j], self.p[2][j]]
    }
}

impl<const V: usize, const B: usize, const C: usize> Map<V, B, C> {
    /// The accumulation stage for a converted batch with its labels set; `labels(j)` gives
    /// the labels of point `j` for the scalar path. Every point ends in exactly one counter
    /// of the frame's report.
    #[inline]
    pub(crate) fn accumulate(
        &mut self,
        f: &mut FrameState,
        batch: &Batch,
        labels: impl Fn(usize) -> Labels,
    ) {
        let mut used = 0;
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
                    self.add_point(f, batch.point(j), &labels(j));
                    continue;
                }
            }
            let key = batch.key(j);
            let a = accumulator_index(key);
            if f.acc[a].key != key {
                let Some(vs) = self.point_voxel(f, &VoxelKey::unpack(key)) else {
                    f.report.dropped_points += 1;
                    continue;
                };
                self.open_accumulator(f, a, vs, key);
            }
            let w = [batch.w[0][j], batch.w[1][j], batch.w[2][j]];
            self.add_to_accumulator(f, a, &w);
            let class = batch.vote[j];
            if class != 0 && takes_vote(batch.hash[j], f.acc[a].vote_exponent) {
                if let Some(v) = self.voxels.slots.get_mut(f.acc[a].slot) {
                    v.take_vote(&[class]);
                }
            }
            used += 1;
        }
        f.report.points_used += used;
    }
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
