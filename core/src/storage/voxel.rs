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
use crate::geometry::gaussian::{floor_abs, Gaussian, Prepared};
use crate::key::{join_key, split_key, VoxelKey};
use crate::storage::table::Entry;
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
}

/// Sums `n, S1, S2` of quantised offsets not yet added to a voxel (integer sums: adding
/// points in groups gives the same result as adding them one by one).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PointSums {
    pub(crate) n: u32,
    pub(crate) s1: [i32; 3],
    pub(crate) s2: [i32; 6],
}

#[cfg(test)]
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

/// Sums of up to [`PackedSums::MAX_POINTS`] points' offsets in three words: each point adds
/// its biased offsets `u = q + 32` (0..=64, as `|q| <= 2^(Q-1) <= 32`) and their six
/// products (0..=4096) in 21-bit fields ([`packed_offsets`]). Four additions per point
/// instead of ten additions and six multiplications; [`PackedSums::unbias`] recovers the
/// exact `n, S1, S2`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PackedSums {
    pub(crate) n: u32,
    /// `sum u_x | sum u_y << 21 | sum u_z << 42`, then the products `xx, xy, xz` and
    /// `yy, yz, zz` packed the same way.
    pub(crate) w: [u64; 3],
}

/// Width of a field of [`PackedSums`].
const FIELD_BITS: u32 = 21;
const FIELD_MASK: u64 = (1 << FIELD_BITS) - 1;
/// The offset bias: `q = u - OFFSET_BIAS`.
const OFFSET_BIAS: i64 = 32;

/// A point's contribution to [`PackedSums`]: its biased offsets `u = q + 32` and their
/// products, three fields `a | b << 21 | c << 42` per word. A field value is below
/// `2^13`, so the products fit 32 bits: 64-bit targets multiply zero-extended values (one
/// `pmuludq` per product in x86 vector code), 32-bit ones work in 32-bit halves.
#[inline]
pub(crate) fn packed_offsets(q: [i32; 3]) -> [u64; 3] {
    if cfg!(target_pointer_width = "64") {
        packed_in_words(q)
    } else {
        packed_in_halves(q)
    }
}

/// [`packed_offsets`] in 64-bit arithmetic.
#[inline]
fn packed_in_words(q: [i32; 3]) -> [u64; 3] {
    let u = q.map(|q| (q + OFFSET_BIAS as i32) as u32 as u64);
    let pack = |a: u64, b: u64, c: u64| a | (b << FIELD_BITS) | (c << (2 * FIELD_BITS));
    [
        pack(u[0], u[1], u[2]),
        pack(u[0] * u[0], u[0] * u[1], u[0] * u[2]),
        pack(u[1] * u[1], u[1] * u[2], u[2] * u[2]),
    ]
}

/// [`packed_offsets`] in 32-bit halves: `a | b << 21 | c << 42` is `lo | hi << 32` with
/// `lo = a | b << 21` (mod `2^32`) and `hi = b >> 11 | c << 10`.
#[inline]
fn packed_in_halves(q: [i32; 3]) -> [u64; 3] {
    let u = q.map(|q| (q + OFFSET_BIAS as i32) as u32);
    let pack = |a: u32, b: u32, c: u32| {
        let lo = a | (b << FIELD_BITS);
        let hi = (b >> (32 - FIELD_BITS)) | (c << (2 * FIELD_BITS - 32));
        ((hi as u64) << 32) | lo as u64
    };
    [
        pack(u[0], u[1], u[2]),
        pack(u[0] * u[0], u[0] * u[1], u[0] * u[2]),
        pack(u[1] * u[1], u[1] * u[2], u[2] * u[2]),
    ]
}

impl PackedSums {
    /// Most points before a field could overflow: `511 * 4096 < 2^21`.
    pub(crate) const MAX_POINTS: u32 = 511;

    pub(crate) const EMPTY: PackedSums = PackedSums { n: 0, w: [0; 3] };

    /// Adds the sum `w` of the [`packed_offsets`] of `n` points.
    #[inline]
    pub(crate) fn add(&mut self, w: &[u64; 3], n: u32) {
        self.n += n;
        self.w[0] += w[0];
        self.w[1] += w[1];
        self.w[2] += w[2];
    }

    /// The exact `n, S1, S2` of the points added: `sum q = sum u - 32 n` and
    /// `sum q_i q_j = sum u_i u_j - 32 (sum u_i + sum u_j) + 1024 n`.
    ///
    /// Without `array::map`: with its closures the host build kept an out-of-line
    /// `try_map` call in every accumulator flush (the 5 cm update was 8 % slower).
    #[inline]
    pub(crate) fn unbias(&self) -> PointSums {
        let field = |w: u64, i: u32| ((w >> (i * FIELD_BITS)) & FIELD_MASK) as i64;
        let n = self.n as i64;
        let [w0, w1, w2] = self.w;
        let u = [field(w0, 0), field(w0, 1), field(w0, 2)];
        let uu = [
            field(w1, 0),
            field(w1, 1),
            field(w1, 2),
            field(w2, 0),
            field(w2, 1),
            field(w2, 2),
        ];
        let mut s2 = [0i32; 6];
        for (k, &(i, j)) in S2_INDEX.iter().enumerate() {
            s2[k] = (uu[k] - OFFSET_BIAS * (u[i] + u[j]) + OFFSET_BIAS * OFFSET_BIAS * n) as i32;
        }
        PointSums {
            n: self.n,
            s1: [
                (u[0] - OFFSET_BIAS * n) as i32,
                (u[1] - OFFSET_BIAS * n) as i32,
                (u[2] - OFFSET_BIAS * n) as i32,
            ],
            s2,
        }
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
                let f = to_f32(v) * scale;
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

/// `v as f32`: through `i32` on 32-bit targets, where converting an `i64` is a software
/// call (`__aeabi_l2f`, about 30 instructions on a Cortex-M4).
#[inline(always)]
fn to_f32(v: i64) -> f32 {
    if cfg!(target_pointer_width = "32") {
        to_f32_via_i32(v)
    } else {
        v as f32
    }
}

/// `v as f32`, by one hardware `i32` conversion when `v` fits in `i32` (the same value, so
/// the same rounding; the scatter of a voxel with few points is small). `black_box`
/// keeps the compiler from folding that conversion back into the `i64` one.
#[inline(always)]
fn to_f32_via_i32(v: i64) -> f32 {
    match i32::try_from(v) {
        Ok(small) => core::hint::black_box(small) as f32,
        Err(_) => v as f32,
    }
}

/// Matrix positions of the six stored `S2` entries: xx, xy, xz, yy, yz, zz.
pub(crate) const S2_INDEX: [(usize, usize); 6] = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];

/// The scatter matrix `M = n S2 - S1 S1^T` (entries in `S2` order), exact in `i64`: `n` times
/// the sum of squared deviations from the mean, positive semi-definite for real points.
#[inline]
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
    // (index, votes) of the best so far; a class needs a vote to lead.
    let mut best = (0usize, 0u8);
    let mut total = 0u32;
    for (i, &b) in hist.iter().enumerate() {
        total += b as u32;
        if b > best.1 {
            best = (i, b);
        }
    }
    if total == 0 {
        None
    } else {
        Some((best.0 as u8 + 1, best.1 as f32 / total as f32))
    }
}

#[cfg(test)]
mod tests {
    // Reference formulas read best with explicit indices.
    #![allow(clippy::needless_range_loop)]
    extern crate std;

    use super::*;
    use crate::testutil::*;
    use crate::*;

    /// The conversion through `i32` (used on 32-bit targets) rounds as `as f32` does, on
    /// both sides of the `i32` range, at the edges of f32's exact integers and on a sweep.
    #[test]
    fn to_f32_via_i32_is_as_f32() {
        let edges = [
            0,
            1,
            -1,
            16_777_217,
            -16_777_217,
            33_554_435,
            i32::MAX as i64,
        ];
        let edges = edges.into_iter().flat_map(|v| [v, -v, v + 1, v - 1]);
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        let sweep = core::iter::from_fn(|| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            // Magnitudes from 2^9 to 2^40: small scatters and ones past `i32`.
            Some((x as i64) >> (23 + (x >> 59)))
        });
        for v in edges
            .chain([i32::MIN as i64, i64::MIN, i64::MAX])
            .chain(sweep.take(100_000))
        {
            assert_eq!(to_f32_via_i32(v).to_bits(), (v as f32).to_bits(), "{v}");
        }
    }

    /// Both ways of packing a point's offsets agree on every offset a point can have
    /// (`|q| <= 32`), and the fields hold `u = q + 32` and its products.
    #[test]
    fn packed_in_words_is_packed_in_halves() {
        for x in -32..=32 {
            for y in -32..=32 {
                for z in -32..=32 {
                    let w = packed_in_halves([x, y, z]);
                    assert_eq!(packed_in_words([x, y, z]), w, "{x} {y} {z}");
                    let (ux, uz) = ((x + 32) as u64, (z + 32) as u64);
                    assert_eq!(w[0] & FIELD_MASK, ux);
                    assert_eq!(w[2] >> (2 * FIELD_BITS), uz * uz);
                }
            }
        }
    }

    #[test]
    fn packed_sums_unbias_to_the_exact_sums() {
        // Every extreme offset combination, then a pseudo-random stream, up to the
        // capacity of the packed fields.
        let mut x = 0x9e37_79b9u32;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x % 65) as i32 - 32
        };
        let corners = [-32, 0, 32];
        let mut qs: std::vec::Vec<[i32; 3]> = std::vec::Vec::new();
        for a in corners {
            for b in corners {
                for c in corners {
                    qs.push([a, b, c]);
                }
            }
        }
        while qs.len() < PackedSums::MAX_POINTS as usize {
            qs.push([next(), next(), next()]);
        }
        qs.push([32, 32, 32]);
        qs.truncate(PackedSums::MAX_POINTS as usize);
        let mut plain = PointSums::EMPTY;
        let mut packed = PackedSums::EMPTY;
        for (i, q) in qs.iter().enumerate() {
            plain.add(*q);
            packed.add(&packed_offsets(*q), 1);
            let u = packed.unbias();
            assert_eq!(
                (u.n, u.s1, u.s2),
                (plain.n, plain.s1, plain.s2),
                "after {} points",
                i + 1
            );
        }
        // All offsets at +32: every product field at its largest.
        let mut full = PackedSums::EMPTY;
        for _ in 0..PackedSums::MAX_POINTS {
            full.add(&packed_offsets([32, 32, 32]), 1);
        }
        let u = full.unbias();
        assert_eq!(u.s1, [32 * 511; 3]);
        assert_eq!(u.s2, [1024 * 511; 6]);
    }

    #[test]
    fn voxel_gaussian_matches_f64_formula() {
        let qs = [
            [3, -5, 7],
            [-2, 4, 1],
            [10, 0, -6],
            [-1, -1, -1],
            [5, 8, 2],
            [32, -32, 32],
            [-32, 31, 0],
        ];
        for (k, h) in [
            (key(-3, 2, 7), 0.1f32),
            (key(0, 0, 0), 0.05),
            (key(-1000, 999, -5), 0.2),
        ] {
            let mut v = Voxel::<4>::new(&k);
            for q in qs {
                v.add(q);
            }
            let step = h / 64.0;
            let g = v.gaussian(h, step);
            assert_eq!(g.count, qs.len() as u32);
            let (mean, cov) = gaussian_f64(&qs, &k, h as f64, step as f64);
            assert_gaussian_exact(&g, mean, cov);
        }
    }

    #[test]
    fn voxel_with_fewer_than_two_points_has_zero_covariance() {
        let k = key(4, -2, 1);
        let mut v = Voxel::<2>::new(&k);
        let g0 = v.gaussian(0.1, 0.1 / 64.0);
        assert_eq!(g0.count, 0);
        assert_eq!(g0.covariance, Matrix3::zeros());
        v.add([7, -3, 30]);
        let g = v.gaussian(0.1, 0.1 / 64.0);
        assert_eq!(g.count, 1);
        assert_eq!(g.covariance, Matrix3::zeros());
        let (mean, _) = gaussian_f64(&[[7, -3, 30]], &k, 0.1f32 as f64, (0.1f32 / 64.0) as f64);
        for i in 0..3 {
            assert!(rel_close(
                g.mean[i] as f64,
                mean[i],
                4.0 * f32::EPSILON as f64,
                0.0
            ));
        }
    }

    #[test]
    fn sums_cannot_overflow() {
        let half = 1i64 << (Config::MAX_QUANT_BITS - 1);
        let n_max = 65535i64; // largest n_max Config::validate accepts
        let n = n_max + MAX_FRAME_POINTS as i64;
        // The proof: a voxel starts a frame with n <= n_max and gains at most one frame.
        assert!(n * half <= i32::MAX as i64);
        assert!(n * half * half <= i32::MAX as i64);
        // i64 arithmetic of the covariance numerator n S2 - S1 S1^T cannot overflow either.
        let (n2, s1max) = (n as i128 * (n * half * half) as i128, (n * half) as i128);
        assert!(n2 + s1max * s1max < i64::MAX as i128);
        // The margin is less than one more frame: decay after every frame is essential.
        assert!((n_max + 2 * MAX_FRAME_POINTS as i64) * half * half > i32::MAX as i64);

        // And the real thing: every S2 entry at its worst-case magnitude, signs mixed.
        let mut cfg = Config::DEFAULT;
        cfg.n_max = n_max as u32;
        assert!(cfg.validate().is_ok());
        let q = half as i32;
        let mut v = Voxel::<1>::EMPTY;
        for _ in 0..n {
            v.add([q, -q, q]);
        }
        let s2 = (n * half * half) as i32;
        let s1 = (n * half) as i32;
        assert_eq!(v.n as i64, n);
        assert_eq!(v.s1, [s1, -s1, s1]);
        assert_eq!(v.s2, [s2, -s2, s2, s2, -s2, s2]);
        // The Gaussian of that voxel is finite (all points identical: zero covariance).
        let g = v.gaussian(0.1, 0.1 / 64.0);
        assert!(g.covariance.iter().all(|x| *x == 0.0));
        // Decay brings it back to n_max without overflow.
        v.decay(n_max as u32);
        assert!(v.n as i64 <= n_max);
    }

    #[test]
    fn decay_halves_until_below_cap() {
        let mut v = Voxel::<1>::new(&key(0, 0, 0));
        v.n = 11;
        v.s1 = [5, -5, 0];
        v.s2 = [7, -3, 0, 9, 1, 2];
        v.decay(5);
        // 11 -> 6 -> 3 (up); sums scale by 3/11, rounded half away from zero.
        assert_eq!(v.n, 3);
        assert_eq!(v.s1, [1, -1, 0]); // 5 * 3/11 = 1.36 -> 1
        assert_eq!(v.s2, [2, -1, 0, 2, 0, 1]); // 1.91, -0.82, 0, 2.45, 0.27, 0.55

        // No change at or below the cap.
        let mut w = Voxel::<1>::new(&key(0, 0, 0));
        w.n = 5;
        w.s1 = [1, 2, 3];
        w.decay(5);
        assert_eq!((w.n, w.s1), (5, [1, 2, 3]));

        // n = 1 never reaches 0 (the loop only runs while n > n_max >= 2).
        let mut u = Voxel::<1>::new(&key(0, 0, 0));
        u.n = 3;
        u.decay(2);
        assert_eq!(u.n, 2);
    }

    #[test]
    fn decay_preserves_mean_within_one_quantum() {
        let mut rng = Lcg(11);
        for n_max in [64u32, 100, 2048, 65535] {
            for _ in 0..20 {
                let mut v = Voxel::<1>::new(&key(0, 0, 0));
                let n = n_max + 1 + (rng.next() * 3.0 * n_max as f64) as u32;
                let centre: [f64; 3] = core::array::from_fn(|_| (rng.next() - 0.5) * 60.0);
                for _ in 0..n {
                    let q: [i32; 3] = core::array::from_fn(|i| {
                        (centre[i] + (rng.next() - 0.5) * 4.0)
                            .round()
                            .clamp(-32.0, 32.0) as i32
                    });
                    v.add(q);
                }
                let before: [f64; 3] = core::array::from_fn(|i| v.s1[i] as f64 / v.n as f64);
                v.decay(n_max);
                assert!(v.n <= n_max && v.n > n_max / 2, "n {} cap {n_max}", v.n);
                for i in 0..3 {
                    let after = v.s1[i] as f64 / v.n as f64;
                    assert!((after - before[i]).abs() <= 1.0, "{before:?} -> {after}");
                }
            }
        }
    }

    /// Regression: Decay rounds `n` up but halves the sums: for odd `n` the mean shrinks toward the
    /// voxel centre by a factor n / (n + 1) and variance appears from nothing. With a small
    /// (valid) `n_max`, three identical points 20 quanta off-centre end up as a Gaussian
    /// whose mean moved 5 quanta and whose standard deviation is 12 quanta.
    #[test]
    fn decay_with_small_n_max_distorts_gaussian() {
        let mut cfg = Config::with_cell_size(0.125);
        cfg.n_min = 2;
        cfg.n_max = 2;
        let mut map: Map<16, 16, 1> = Map::try_new(cfg).unwrap();
        // x = centre + 20 quanta + 1/4 quantum: q = 20 for all three points.
        let x = (32.0 + 20.0 + 0.25) / 512.0;
        map.integrate(&Isometry3::identity(), &[lp(x, 0.0625, 1.0625, 1); 3])
            .unwrap();
        let g = map.gaussian(&key(0, 0, 8)).unwrap();
        let step = 0.125 / 64.0;
        let mean_err = (g.mean.x as f64 - (0.0625 + 20.0 * step)).abs();
        assert!(
            mean_err <= step && g.covariance[(0, 0)] == 0.0,
            "mean off by {} quanta, var {} quanta^2",
            mean_err / step,
            g.covariance[(0, 0)] as f64 / (step * step)
        );
    }

    #[test]
    fn argmax_ties_go_to_lower_class() {
        assert_eq!(argmax(&[0, 5, 5, 1]), Some((2, 5.0 / 11.0)));
        assert_eq!(argmax(&[9, 9]), Some((1, 0.5)));
        assert_eq!(argmax(&[0, 0, 3]), Some((3, 1.0)));
        assert_eq!(argmax(&[0, 0, 0]), None);
    }
}
