//! Voxel statistics: integer-quantised point sums, the Gaussian they define, and the `u8`
//! class histogram.
//!
//! A point `p` in voxel `k` contributes `q = round_half_up((p / h - k - 1/2) 2^Q)` (so
//! `|q_i| <= 2^(Q-1)`) to `S1 = sum q` and `S2 = sum q q^T`. A voxel holds at most `n_max`
//! points between frames and one frame adds at most [`crate::MAX_FRAME_POINTS`], so with
//! `n_max <= 65535` and `Q <= 6`: `n <= 65535 + 2^20`, `|S1_i| <= 2^5 n < 2^26` and
//! `|S2_ij| <= 2^10 n = 1,140,849,664 < 2^31`: the sums fit `i32` exactly (see
//! `sums_cannot_overflow` in the tests) and do not depend on point order.

use crate::key::VoxelKey;
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
    /// [`VOTES_TAKEN_MAX`]; 0 between frames).
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
        ((self.key[0] as u64) << 32) | ((self.key[1] as u64) << 16) | self.key[2] as u64
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

/// Largest count of votes taken in one frame that a tally holds.
pub(crate) const VOTES_TAKEN_MAX: u16 = 0xfff;
/// Position of the sampling exponent in a tally.
pub(crate) const EXPONENT_SHIFT: u32 = 12;

pub(crate) fn split_key(packed: u64) -> [u16; 3] {
    [(packed >> 32) as u16, (packed >> 16) as u16, packed as u16]
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

    /// Adds one quantised offset (integration sums runs of points instead, see `Run`).
    #[cfg(test)]
    pub(crate) fn add(&mut self, q: [i32; 3]) {
        let mut run = crate::integrate::Run::EMPTY;
        run.add(q);
        self.merge(&run);
    }

    /// Adds a run of points summed elsewhere.
    pub(crate) fn merge(&mut self, run: &crate::integrate::Run) {
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

    /// Halves every bin if any bin exceeds `255 - votes` so a frame's sample of about
    /// `votes` votes has room (done once per voxel per frame, before the votes, so the
    /// result does not depend on point order).
    pub(crate) fn make_vote_room(&mut self, votes: u8) {
        let limit = 255 - votes;
        if self.hist.iter().any(|&b| b > limit) {
            for b in self.hist.iter_mut() {
                *b /= 2;
            }
        }
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

/// A voxel's normal distribution in world coordinates (metres).
///
/// ```
/// use sndt_core::{Config, LabeledPoint, Labels, Map, Isometry3, Point3};
/// let mut map: Map<64, 16, 4> = Map::new(Config::DEFAULT);
/// let pts = [
///     LabeledPoint::new(Point3::new(0.01, 0.02, 1.01), Labels::top1(1)),
///     LabeledPoint::new(Point3::new(0.03, 0.02, 1.03), Labels::top1(1)),
///     LabeledPoint::new(Point3::new(0.05, 0.08, 1.01), Labels::top1(1)),
/// ];
/// map.integrate(&Isometry3::identity(), &pts).unwrap();
/// let g = map.gaussian_at(&[0.03, 0.04, 1.02]).unwrap();
/// assert_eq!(g.count, 3);
/// assert!((g.mean.x - 0.03).abs() < 1e-3);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gaussian {
    /// Mean in metres.
    pub mean: Vector3<f32>,
    /// Sample covariance in square metres (zero for fewer than 2 points).
    pub covariance: Matrix3<f32>,
    /// Number of points (after decay).
    pub count: u32,
}

/// A Gaussian ready for ray tests: mean and inverse covariance with the eigenvalue floor.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Prepared {
    pub(crate) mean: Vector3<f32>,
    pub(crate) inv: Matrix3<f32>,
}

/// Direct-mapped cache of prepared Gaussians keyed by voxel slot. Only valid while the
/// voxels it was filled from do not change (phase 3 of a frame, one render call).
pub(crate) struct PrepCache<const N: usize> {
    tags: [u32; N],
    entries: [Option<Prepared>; N],
}

impl<const N: usize> PrepCache<N> {
    pub(crate) const fn new() -> Self {
        PrepCache {
            tags: [0; N],
            entries: [None; N],
        }
    }

    /// The prepared Gaussian of voxel `v` in slot `slot`.
    pub(crate) fn get<const C: usize>(
        &mut self,
        slot: usize,
        v: &Voxel<C>,
        cfg: &crate::Config,
    ) -> Prepared {
        let i = slot % N;
        let tag = slot as u32 + 1;
        if let Some(g) = self.entries[i] {
            if self.tags[i] == tag {
                return g;
            }
        }
        let g = v
            .gaussian(cfg.cell_size, cfg.quant_step())
            .prepare(cfg.eigen_ratio, crate::integrate::floor_abs(cfg.cell_size));
        self.tags[i] = tag;
        self.entries[i] = Some(g);
        g
    }
}

impl Gaussian {
    /// Inverse covariance with eigenvalues raised to `ratio * lambda_max` (and to `floor_abs`
    /// for a degenerate voxel whose points coincide).
    pub(crate) fn prepare(&self, ratio: f32, floor_abs: f32) -> Prepared {
        let (vals, vecs) = symmetric_eigen(&self.covariance);
        let lmax = vals[0].max(vals[1]).max(vals[2]);
        let floor = (lmax * ratio).max(floor_abs);
        let mut inv = Matrix3::zeros();
        for (i, val) in vals.iter().enumerate() {
            let l = val.max(floor);
            let v = vecs.column(i);
            inv += v * v.transpose() * (1.0 / l);
        }
        Prepared {
            mean: self.mean,
            inv,
        }
    }
}

/// Eigenvalues and eigenvectors (columns) of a symmetric 3x3 matrix by cyclic Jacobi
/// rotations. Pure arithmetic plus `libm::sqrtf`, so results are bit-identical on every target.
pub(crate) fn symmetric_eigen(m: &Matrix3<f32>) -> ([f32; 3], Matrix3<f32>) {
    let mut a = *m;
    let mut v = Matrix3::<f32>::identity();
    for _sweep in 0..12 {
        let off = a[(0, 1)] * a[(0, 1)] + a[(0, 2)] * a[(0, 2)] + a[(1, 2)] * a[(1, 2)];
        let diag = a[(0, 0)] * a[(0, 0)] + a[(1, 1)] * a[(1, 1)] + a[(2, 2)] * a[(2, 2)];
        if off <= diag * 1e-14 || off == 0.0 {
            break;
        }
        for &(p, q) in &[(0usize, 1usize), (0, 2), (1, 2)] {
            let apq = a[(p, q)];
            if apq == 0.0 {
                continue;
            }
            let theta = (a[(q, q)] - a[(p, p)]) / (2.0 * apq);
            let sign = if theta >= 0.0 { 1.0 } else { -1.0 };
            let t = sign / (theta.abs() + libm::sqrtf(theta * theta + 1.0));
            let c = 1.0 / libm::sqrtf(t * t + 1.0);
            let s = t * c;
            // A <- J^T A J with J the rotation in the (p, q) plane.
            for k in 0..3 {
                let akp = a[(k, p)];
                let akq = a[(k, q)];
                a[(k, p)] = c * akp - s * akq;
                a[(k, q)] = s * akp + c * akq;
            }
            for k in 0..3 {
                let apk = a[(p, k)];
                let aqk = a[(q, k)];
                a[(p, k)] = c * apk - s * aqk;
                a[(q, k)] = s * apk + c * aqk;
            }
            for k in 0..3 {
                let vkp = v[(k, p)];
                let vkq = v[(k, q)];
                v[(k, p)] = c * vkp - s * vkq;
                v[(k, q)] = s * vkp + c * vkq;
            }
        }
    }
    ([a[(0, 0)], a[(1, 1)], a[(2, 2)]], v)
}
