//! The surface (NDT) voxel: integer-quantised point sums, the Gaussian they define, and
//! the `u8` class histogram (its vote sampling lives in `votes.rs`).
//!
//! A point `p` in voxel `k` contributes `q = round_half_up((p / h - k - 1/2) 2^Q)` (so
//! `|q_i| <= 2^(Q-1)`) to `S1 = sum q` and `S2 = sum q q^T`. A voxel holds at most `n_max`
//! points between frames and one frame adds at most [`crate::MAX_FRAME_POINTS`], so with
//! `n_max <= 65535` and `Q <= 6`: `n <= 65535 + 2^20`, `|S1_i| <= 2^5 n < 2^26` and
//! `|S2_ij| <= 2^10 n = 1,140,849,664 < 2^31`: the sums fit `i32` exactly (see
//! `sums_cannot_overflow` in the tests) and do not depend on point order.

use crate::config::Config;
use crate::gaussian::{floor_abs, Gaussian, Prepared};
use crate::key::{join_key, split_key, VoxelKey};
use crate::table::Entry;
use nalgebra::{Matrix3, Vector3};

/// A surface (NDT) voxel: point sums, class histogram, table link.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Voxel<const C: usize> {
    /// `S2` entries xx, xy, xz, yy, yz, zz in quanta squared.
    pub(crate) s2: [i32; 6],
    /// `S1` in quanta.
    pub(crate) s1: [i32; 3],
    /// Point count; 0 only for an empty slot.
    pub(crate) n: u32,
    pub(crate) chain: u32,
    /// Head of hash bucket `slot` (see `table.rs`).
    pub(crate) head: u32,
    /// Packed key split in three `u16` (keeps the struct 4-byte aligned).
    pub(crate) key: [u16; 3],
    /// Vote sampling: bits 12..16 hold the exponent `k` (this frame's sample keeps one
    /// voting point in `2^k`), bits 0..12 the votes taken this frame (saturating at
    /// `VOTES_TAKEN_MAX`; 0 between frames). Read and written by `votes.rs` only.
    pub(crate) tally: u16,
    /// Class votes; bin `i` is class `i + 1`.
    pub(crate) hist: [u8; C],
}

impl<const C: usize> Entry for Voxel<C> {
    const EMPTY: Self = Voxel {
        s2: [0; 6],
        s1: [0; 3],
        n: 0,
        chain: 0,
        head: 0,
        key: [0; 3],
        tally: 0,
        hist: [0; C],
    };
    fn packed_key(&self) -> u64 {
        join_key(self.key)
    }
    fn chain(&self) -> u32 {
        self.chain
    }
    fn set_chain(&mut self, next: u32) {
        self.chain = next;
    }
    fn head(&self) -> u32 {
        self.head
    }
    fn set_head(&mut self, head: u32) {
        self.head = head;
    }
}

/// Sums `n, S1, S2` of quantised offsets not yet added to a voxel. Integration sums runs
/// of consecutive points that fall into the same voxel here, in registers, and adds a run
/// to the voxel once (integer sums: the result is the same as adding point by point).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PointSums {
    pub(crate) n: u32,
    pub(crate) s1: [i32; 3],
    pub(crate) s2: [i32; 6],
}

impl PointSums {
    pub(crate) const EMPTY: PointSums = PointSums {
        n: 0,
        s1: [0; 3],
        s2: [0; 6],
    };

    /// Adds one quantised offset.
    #[inline]
    pub(crate) fn add(&mut self, q: [i32; 3]) {
        self.n += 1;
        self.s1[0] += q[0];
        self.s1[1] += q[1];
        self.s1[2] += q[2];
        self.s2[0] += q[0] * q[0];
        self.s2[1] += q[0] * q[1];
        self.s2[2] += q[0] * q[2];
        self.s2[3] += q[1] * q[1];
        self.s2[4] += q[1] * q[2];
        self.s2[5] += q[2] * q[2];
    }
}

impl<const C: usize> Voxel<C> {
    pub(crate) fn new(key: &VoxelKey) -> Self {
        let mut v = Self::EMPTY;
        v.key = split_key(key.packed());
        v
    }

    pub(crate) fn voxel_key(&self) -> VoxelKey {
        VoxelKey::unpack(self.packed_key())
    }

    /// Adds one quantised offset (integration adds runs of points instead, see
    /// [`PointSums`]).
    #[cfg(test)]
    pub(crate) fn add(&mut self, q: [i32; 3]) {
        let mut run = PointSums::EMPTY;
        run.add(q);
        self.merge(&run);
    }

    /// Adds points summed elsewhere.
    pub(crate) fn merge(&mut self, run: &PointSums) {
        self.n += run.n;
        for i in 0..3 {
            self.s1[i] += run.s1[i];
        }
        for i in 0..6 {
            self.s2[i] += run.s2[i];
        }
    }

    /// Halves the count (rounding up, so it never reaches 0) until `n <= n_max` and scales
    /// the sums by the same factor `n' / n` (rounded to nearest in `i64`), so mean and
    /// covariance are kept (old data decays). Rounding each sum on its own may leave the
    /// scatter matrix `n S2 - S1 S1^T` slightly indefinite (by about `n (2^(Q-1) + 1/2)`);
    /// [`Voxel::gaussian`] clamps variances at 0 and the eigenvalue floor absorbs the rest.
    pub(crate) fn decay(&mut self, n_max: u32) {
        if self.n <= n_max {
            return;
        }
        let mut m = self.n;
        while m > n_max {
            m = m.div_ceil(2);
        }
        let (n, m) = (self.n as i64, m as i64);
        for s in self.s1.iter_mut().chain(self.s2.iter_mut()) {
            let v = *s as i64 * m;
            // Round half away from zero; |v / n| <= |s|, so the result fits.
            let r = if v >= 0 {
                (2 * v + n) / (2 * n)
            } else {
                -((-2 * v + n) / (2 * n))
            };
            *s = r as i32;
        }
        self.n = m as u32;
    }

    /// Mean and covariance in metres (covariance needs `n >= 2`).
    pub(crate) fn gaussian(&self, h: f32, step: f32) -> Gaussian {
        let key = self.voxel_key();
        let c = key.center(h);
        let n = self.n.max(1) as f32;
        let mean = Vector3::new(
            c[0] + self.s1[0] as f32 / n * step,
            c[1] + self.s1[1] as f32 / n * step,
            c[2] + self.s1[2] as f32 / n * step,
        );
        let mut cov = Matrix3::zeros();
        if self.n >= 2 {
            // n S2 - S1 S1^T is exact in i64; one rounding to f32 afterwards.
            let s1 = self.s1.map(|x| x as i64);
            let s2 = self.s2.map(|x| x as i64);
            let m = scatter(self.n as i64, &s1, &s2);
            let scale = step * step / (self.n as f32 * (self.n - 1) as f32);
            for (&(i, j), &v) in S2_INDEX.iter().zip(m.iter()) {
                // Decay's rounding can leave a flat direction a hair below zero.
                let v = if i == j { v.max(0) } else { v };
                let f = v as f32 * scale;
                cov[(i, j)] = f;
                cov[(j, i)] = f;
            }
        }
        Gaussian {
            mean,
            covariance: cov,
            count: self.n,
        }
    }

    /// The Gaussian ready for ray tests, with the eigenvalue floors of `cfg`.
    pub(crate) fn prepared(&self, cfg: &Config) -> Prepared {
        self.gaussian(cfg.cell_size, cfg.quant_step())
            .prepare(cfg.eigen_ratio, floor_abs(cfg.cell_size))
    }
}

/// Matrix positions of the six stored `S2` entries: xx, xy, xz, yy, yz, zz.
pub(crate) const S2_INDEX: [(usize, usize); 6] = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];

/// The scatter matrix `M = n S2 - S1 S1^T` (entries in `S2` order), exact in `i64`: `n` times
/// the sum of squared deviations from the mean, positive semi-definite for real points.
pub(crate) fn scatter(n: i64, s1: &[i64; 3], s2: &[i64; 6]) -> [i64; 6] {
    let mut m = [0i64; 6];
    for (e, (&(i, j), &s)) in m.iter_mut().zip(S2_INDEX.iter().zip(s2.iter())) {
        *e = n * s - s1[i] * s1[j];
    }
    m
}

/// Most voted class (1-based) of a histogram and its share of the votes; ties go to the
/// lower class, and an empty histogram has none.
pub(crate) fn argmax(hist: &[u8]) -> Option<(u8, f32)> {
    let mut best = 0usize;
    let mut total = 0u32;
    for (i, &b) in hist.iter().enumerate() {
        total += b as u32;
        if b > hist[best] {
            best = i;
        }
    }
    if total == 0 {
        None
    } else {
        Some((best as u8 + 1, hist[best] as f32 / total as f32))
    }
}
