//! Unit tests of the core against independently known answers: hand-computed values and
//! direct `f64` formulas.
//!
//! The submodule `findings` holds tests that demonstrate defects found in review; they fail
//! (or panic in debug builds) until the defect is fixed. Run the rest with
//! `cargo test -p sndt-core -- --skip findings`.

#![allow(clippy::needless_range_loop)]

extern crate std;

use crate::block::Block;
use crate::config::to_fixed;
use crate::crc::crc32;
use crate::gaussian::{floor_abs, symmetric_eigen};
use crate::key::{hash, order};
use crate::table::{Entry, Table};
use crate::voxel::argmax;
use crate::voxel::Voxel;
use crate::*;
use std::vec::Vec;

// ---------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------

fn lp(x: f32, y: f32, z: f32, class: u8) -> LabeledPoint {
    LabeledPoint::new(Point3::new(x, y, z), Labels::top1(class))
}

fn at(x: f32, y: f32, z: f32) -> Isometry3<f32> {
    Isometry3::translation(x, y, z)
}

fn key(x: i16, y: i16, z: i16) -> VoxelKey {
    VoxelKey { x, y, z }
}

/// Fixed-point log-odds of a cell (exact: the map stores `i16 / LOGODDS_ONE`).
fn fixed<const V: usize, const B: usize, const C: usize>(m: &Map<V, B, C>, k: &VoxelKey) -> i32 {
    let l = m.log_odds(k) * LOGODDS_ONE;
    assert_eq!(l, libm::roundf(l), "log-odds must be a multiple of 1/1024");
    l as i32
}

/// The stored voxel record of `k`.
fn voxel<const V: usize, const B: usize, const C: usize>(
    m: &Map<V, B, C>,
    k: &VoxelKey,
) -> Voxel<C> {
    let s = m.voxels.find(k.packed()).expect("voxel present");
    m.voxels.slots[s]
}

fn snapshot<const V: usize, const B: usize, const C: usize>(m: &Map<V, B, C>) -> Vec<u8> {
    let mut buf = std::vec![0u8; m.snapshot_len()];
    assert_eq!(m.write_snapshot(&mut buf), Ok(buf.len()));
    buf
}

/// Recomputes the trailing CRC after patching a snapshot.
fn fix_crc(buf: &mut [u8]) {
    let body = buf.len() - 4;
    let crc = crc32(&buf[..body]);
    buf[body..].copy_from_slice(&crc.to_le_bytes());
}

/// Deterministic pseudo-random numbers in [0, 1).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn rel_close(got: f64, want: f64, rel: f64, abs: f64) -> bool {
    (got - want).abs() <= rel * want.abs() + abs
}

/// Rotation matrix (f64) about a unit axis by `angle`.
fn rotation(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
    let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    let (x, y, z) = (axis[0] / n, axis[1] / n, axis[2] / n);
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]
}

/// `R diag(d) R^T` in f64.
fn rdrt(r: &[[f64; 3]; 3], d: [f64; 3]) -> [[f64; 3]; 3] {
    let mut m = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            for k in 0..3 {
                m[i][j] += r[i][k] * d[k] * r[j][k];
            }
        }
    }
    m
}

fn to_m32(m: &[[f64; 3]; 3]) -> Matrix3<f32> {
    Matrix3::from_fn(|i, j| m[i][j] as f32)
}

fn sorted3(mut v: [f32; 3]) -> [f32; 3] {
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    v
}

// ---------------------------------------------------------------------------------------
// Memory contract
// ---------------------------------------------------------------------------------------

fn check_size<const V: usize, const B: usize, const C: usize>() {
    let voxel = (56 + C).div_ceil(4) * 4;
    let bytes = (128 + V * voxel + B * 184).div_ceil(8) * 8;
    assert_eq!(Map::<V, B, C>::VOXEL_BYTES, voxel, "VOXEL_BYTES C={C}");
    assert_eq!(
        Map::<V, B, C>::BYTES,
        bytes,
        "BYTES formula V={V} B={B} C={C}"
    );
    assert_eq!(
        core::mem::size_of::<Map<V, B, C>>(),
        Map::<V, B, C>::BYTES,
        "size_of V={V} B={B} C={C}"
    );
}

macro_rules! sizes_c {
    ($v:literal, $b:literal) => {
        check_size::<$v, $b, 1>();
        check_size::<$v, $b, 2>();
        check_size::<$v, $b, 3>();
        check_size::<$v, $b, 13>();
        check_size::<$v, $b, 40>();
        check_size::<$v, $b, 41>();
    };
}

macro_rules! sizes_b {
    ($($v:literal),*) => {
        $(
            sizes_c!($v, 1);
            sizes_c!($v, 2);
            sizes_c!($v, 3);
            sizes_c!($v, 7);
            sizes_c!($v, 10);
            sizes_c!($v, 64);
            sizes_c!($v, 1000);
        )*
    };
}

#[test]
fn memory_contract_exact_size() {
    sizes_b!(1, 2, 3, 7, 10, 64, 1000);
    assert_eq!(Map::<4096, 1024, 40>::VOXEL_BYTES, 96);
    assert_eq!(Map::<1, 1, 40>::VOXEL_BYTES, 96);
    assert_eq!(BLOCK_BYTES, 184);
    assert_eq!(MAP_HEADER_BYTES, 128);
    assert_eq!(core::mem::size_of::<Block>(), 184);
    assert_eq!(Map::<1, 1, 1>::BYTES, 376); // 128 + 60 + 184 = 372 -> 376
}

// ---------------------------------------------------------------------------------------
// Voxel statistics
// ---------------------------------------------------------------------------------------

/// f64 mean (metres) and covariance (m^2) of quantised offsets in voxel `k`.
fn gaussian_f64(qs: &[[i32; 3]], k: &VoxelKey, h: f64, step: f64) -> ([f64; 3], [[f64; 3]; 3]) {
    let n = qs.len() as f64;
    let kk = [k.x as f64, k.y as f64, k.z as f64];
    let mut mq = [0.0; 3];
    for q in qs {
        for i in 0..3 {
            mq[i] += q[i] as f64 / n;
        }
    }
    let mean = [
        (kk[0] + 0.5) * h + mq[0] * step,
        (kk[1] + 0.5) * h + mq[1] * step,
        (kk[2] + 0.5) * h + mq[2] * step,
    ];
    let mut cov = [[0.0; 3]; 3];
    if qs.len() >= 2 {
        for q in qs {
            for i in 0..3 {
                for j in 0..3 {
                    cov[i][j] +=
                        (q[i] as f64 - mq[i]) * (q[j] as f64 - mq[j]) * step * step / (n - 1.0);
                }
            }
        }
    }
    (mean, cov)
}

fn assert_gaussian_exact(g: &Gaussian, mean: [f64; 3], cov: [[f64; 3]; 3]) {
    let eps = f32::EPSILON as f64;
    for i in 0..3 {
        assert!(
            rel_close(g.mean[i] as f64, mean[i], 4.0 * eps, 0.0),
            "mean[{i}] {} vs {}",
            g.mean[i],
            mean[i]
        );
        for j in 0..3 {
            assert!(
                rel_close(g.covariance[(i, j)] as f64, cov[i][j], 8.0 * eps, 1e-30),
                "cov[{i}{j}] {} vs {}",
                g.covariance[(i, j)],
                cov[i][j]
            );
        }
    }
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

#[test]
fn decay_through_integrate() {
    let mut cfg = Config::DEFAULT;
    cfg.n_max = 4;
    let mut map: Map<16, 16, 2> = Map::try_new(cfg).unwrap();
    let pts = [lp(0.05, 0.05, 1.05, 1); 10];
    map.integrate(&Isometry3::identity(), &pts).unwrap();
    // 10 -> 5 -> 3.
    assert_eq!(map.gaussian_at(&[0.05, 0.05, 1.05]).unwrap().count, 3);
}

// ---------------------------------------------------------------------------------------
// Class histogram
// ---------------------------------------------------------------------------------------

#[test]
fn make_vote_room_halves_only_above_255_minus_votes() {
    let mut v = Voxel::<4>::new(&key(0, 0, 0));
    v.hist = [191, 3, 0, 1];
    v.make_vote_room(64);
    assert_eq!(v.hist, [191, 3, 0, 1]);
    v.hist = [192, 3, 0, 1];
    v.make_vote_room(64);
    assert_eq!(v.hist, [96, 1, 0, 0]);
    v.hist = [5, 255, 200, 7];
    v.make_vote_room(128);
    assert_eq!(v.hist, [2, 127, 100, 3]);
    v.hist = [5, 128, 200, 7];
    v.make_vote_room(1);
    assert_eq!(v.hist, [5, 128, 200, 7]);
}

#[test]
fn argmax_ties_go_to_lower_class() {
    assert_eq!(argmax(&[0, 5, 5, 1]), Some((2, 5.0 / 11.0)));
    assert_eq!(argmax(&[9, 9]), Some((1, 0.5)));
    assert_eq!(argmax(&[0, 0, 3]), Some((3, 1.0)));
    assert_eq!(argmax(&[0, 0, 0]), None);
}

/// `n1` points of class 1 then `n2` of class 2 at distinct positions inside voxel
/// (0, 0, 10) of a 10 cm map, drawn from `rng`.
fn voxel_cloud(rng: &mut Lcg, n1: usize, n2: usize) -> Vec<LabeledPoint> {
    let mut c = || 0.002 + 0.096 * rng.next() as f32;
    (0..n1 + n2)
        .map(|i| lp(c(), c(), 1.0 + c(), if i < n1 { 1 } else { 2 }))
        .collect()
}

#[test]
fn votes_within_the_frame_budget_all_count_and_halve_once_per_frame() {
    let mut cfg = Config::DEFAULT;
    cfg.votes_per_frame = 64;
    let mut map: Map<16, 16, 2> = Map::try_new(cfg).unwrap();
    let mut rng = Lcg(7);
    let k = key(0, 0, 10);
    let mut frame = |n1, n2| {
        let pts = voxel_cloud(&mut rng, n1, n2);
        map.integrate(&Isometry3::identity(), &pts).unwrap();
        *map.voxel(&k).unwrap().histogram
    };
    assert_eq!(frame(60, 0), [60, 0]);
    assert_eq!(frame(0, 10), [60, 10]);
    assert_eq!(frame(64, 0), [124, 10]);
    assert_eq!(frame(64, 0), [188, 10]);
    assert_eq!(frame(4, 0), [192, 10]); // 188 <= 255 - 64: no halving before these votes
                                        // 192 > 191: halve first (96, 5), then add (10, 10).
    assert_eq!(frame(10, 10), [106, 15]);
    assert_eq!(map.class(&k), Some((1, 106.0 / 121.0)));
}

#[test]
fn a_crowded_voxel_takes_a_hashed_sample_of_about_votes_per_frame() {
    let cfg = Config {
        votes_per_frame: 16,
        ..Config::DEFAULT
    };
    let mut map: Map<16, 16, 2> = Map::try_new(cfg).unwrap();
    let mut rng = Lcg(3);
    let k = key(0, 0, 10);
    // A new voxel counts every point of its first frame: 200 + 300 votes, saturating.
    map.integrate(&Isometry3::identity(), &voxel_cloud(&mut rng, 200, 300))
        .unwrap();
    assert_eq!(map.voxel(&k).unwrap().histogram, &[200, 255]);
    // 500 votes taken, 16 per frame: the next frame keeps one point in 2^5 = 32
    // (500 <= 16 * 32). Room first: 255 > 255 - 16, so halve to (100, 127).
    assert_eq!(voxel(&map, &k).tally >> 12, 5);
    let pts = voxel_cloud(&mut rng, 200, 300);
    map.integrate(&Isometry3::identity(), &pts).unwrap();
    let taken = |class: u8| {
        pts.iter()
            .filter(|p| p.labels.classes[0] == class)
            .filter(|p| vote_hash(&[p.position.x, p.position.y, p.position.z]) >> 27 == 0)
            .count()
    };
    let (t1, t2) = (taken(1), taken(2));
    let hist = *map.voxel(&k).unwrap().histogram;
    assert_eq!(hist, [100 + t1 as u8, 127 + t2 as u8]);
    assert!(
        (6..=30).contains(&(t1 + t2)),
        "about 500 / 32 = 15.6 votes, got {}",
        t1 + t2
    );
    // The next exponent follows the votes taken: about 500 points again.
    let want = next_vote_exponent(5, (t1 + t2) as u16, 16);
    assert_eq!(voxel(&map, &k).tally >> 12, want as u16);
    assert!((4..=6).contains(&want));
    assert_eq!(map.class(&k).unwrap().0, 2);
}

#[test]
fn the_histogram_averages_over_frames() {
    // Frames of 60 / 40 for class 2, then one frame entirely of class 1: once the voxel's
    // sampling has adapted, the last frame weighs about as much as any other (about 16
    // votes), so class 2 stays the argmax.
    let cfg = Config {
        votes_per_frame: 16,
        ..Config::DEFAULT
    };
    let mut map: Map<16, 16, 2> = Map::try_new(cfg).unwrap();
    let mut rng = Lcg(11);
    let k = key(0, 0, 10);
    for _ in 0..9 {
        let pts = voxel_cloud(&mut rng, 200, 300);
        map.integrate(&Isometry3::identity(), &pts).unwrap();
    }
    let before = *map.voxel(&k).unwrap().histogram;
    assert!(before[1] > before[0], "{before:?}");
    let pts = voxel_cloud(&mut rng, 500, 0);
    map.integrate(&Isometry3::identity(), &pts).unwrap();
    let hist = *map.voxel(&k).unwrap().histogram;
    // Without halving the gain is the sample; with it, the old votes halved first.
    let gain = if before.iter().any(|&b| b > 239) {
        hist[0] as i32 - before[0] as i32 / 2
    } else {
        hist[0] as i32 - before[0] as i32
    };
    assert!((4..=32).contains(&gain), "{before:?} -> {hist:?}");
    assert_eq!(map.class(&k).unwrap().0, 2, "{hist:?}");
}

#[test]
fn void_label_adds_geometry_but_no_vote() {
    let mut map: Map<16, 16, 3> = Map::new(Config::DEFAULT);
    let pts = [lp(0.05, 0.05, 1.05, 0); 4];
    let r = map.integrate(&Isometry3::identity(), &pts).unwrap();
    assert_eq!(r.points_used, 4);
    let k = key(0, 0, 10);
    assert_eq!(map.voxel(&k).unwrap().histogram, &[0, 0, 0]);
    assert_eq!(map.class(&k), None);
    assert_eq!(map.gaussian(&k).unwrap().count, 4);
    // Labels::NONE likewise.
    let none = [LabeledPoint::new(
        Point3::new(0.05, 0.05, 1.05),
        Labels::NONE,
    )];
    map.integrate(&Isometry3::identity(), &none).unwrap();
    assert_eq!(map.class(&k), None);
    assert_eq!(map.gaussian(&k).unwrap().count, 5);
}

#[test]
fn top_k_and_min_score() {
    let k = key(0, 0, 10);
    let labels = Labels::top_k(&[(1, 255), (2, 120), (3, 99)]);
    let pts = [LabeledPoint::new(Point3::new(0.05, 0.05, 1.05), labels)];
    let hist = |top_k: u8, min_score: u8| {
        let mut cfg = Config::DEFAULT;
        cfg.top_k = top_k;
        cfg.min_score = min_score;
        let mut map: Map<16, 16, 4> = Map::try_new(cfg).unwrap();
        map.integrate(&Isometry3::identity(), &pts).unwrap();
        *map.voxel(&k).unwrap().histogram
    };
    assert_eq!(hist(1, 0), [1, 0, 0, 0]);
    assert_eq!(hist(2, 0), [1, 1, 0, 0]);
    assert_eq!(hist(3, 0), [1, 1, 1, 0]);
    assert_eq!(hist(3, 100), [1, 1, 0, 0]); // 99 < 100 does not vote
    assert_eq!(hist(3, 120), [1, 1, 0, 0]); // 120 >= 120 votes
    assert_eq!(hist(3, 121), [1, 0, 0, 0]);
    // A label above the class count rejects the point.
    let mut map: Map<16, 16, 4> = Map::new(Config::DEFAULT);
    let bad = [LabeledPoint::new(
        Point3::new(0.05, 0.05, 1.05),
        Labels::top_k(&[(1, 255), (5, 255)]),
    )];
    let r = map.integrate(&Isometry3::identity(), &bad).unwrap();
    assert_eq!((r.points_used, r.rejected_label), (0, 1));
    assert!(map.voxel(&k).is_none());
}

// ---------------------------------------------------------------------------------------
// Table
// ---------------------------------------------------------------------------------------

type T1 = Voxel<1>;

fn entry(k: &VoxelKey) -> T1 {
    Voxel::<1>::new(k)
}

fn bucket_of(k: &VoxelKey, n: usize) -> usize {
    ((hash(k.packed()) as u64 * n as u64) >> 32) as usize
}

/// Keys whose hash lands in bucket `b` of an `n`-bucket table.
fn colliding(n: usize, b: usize, count: usize) -> Vec<VoxelKey> {
    let mut out = Vec::new();
    let mut x = -500i16;
    while out.len() < count {
        let k = key(x, 3, -7);
        if bucket_of(&k, n) == b {
            out.push(k);
        }
        x += 1;
    }
    out
}

#[test]
fn table_insert_find_remove_with_collisions() {
    let mut t: Table<T1, 4> = Table::new();
    let keys = colliding(4, 1, 4);
    let slots: Vec<usize> = keys.iter().map(|k| t.insert(entry(k)).unwrap()).collect();
    assert_eq!(slots, [0, 1, 2, 3]);
    assert_eq!(t.len(), 4);
    assert!(t.is_full());
    for (k, s) in keys.iter().zip(&slots) {
        assert_eq!(t.find(k.packed()), Some(*s));
        assert_eq!(t.slots[*s].voxel_key(), *k);
    }
    // Absent key in the same bucket, and in other buckets.
    let absent = colliding(4, 1, 5)[4];
    assert_eq!(t.find(absent.packed()), None);
    assert_eq!(t.find(key(1, 2, 3).packed()), None);
    // Full: the entry comes back.
    let e = entry(&absent);
    match t.insert(e) {
        Err(back) => assert_eq!(back, e),
        Ok(_) => panic!("insert into a full table"),
    }
    // Remove from the middle of the chain (by canonical position) and the ends.
    let canon: Vec<usize> = t.canonical().collect();
    assert_eq!(canon.len(), 4);
    let mid = canon[1];
    let removed = t.remove(mid);
    assert_eq!(removed.voxel_key(), t_key_of(&keys, &slots, mid));
    assert_eq!(t.len(), 3);
    assert_eq!(t.find(removed.packed_key()), None);
    for (k, s) in keys.iter().zip(&slots) {
        if *s != mid {
            assert_eq!(t.find(k.packed()), Some(*s));
        }
    }
    // The freed slot is reused.
    assert_eq!(t.insert(entry(&absent)), Ok(mid));
    assert_eq!(t.find(absent.packed()), Some(mid));
    // Free list is LIFO: remove two, the last removed is handed out first.
    let first = canon[0];
    let last = canon[3];
    t.remove(first);
    t.remove(last);
    let a = colliding(4, 1, 7)[5];
    let b = colliding(4, 1, 7)[6];
    assert_eq!(t.insert(entry(&a)), Ok(last));
    assert_eq!(t.insert(entry(&b)), Ok(first));
    for (k, s) in [(a, last), (b, first), (absent, mid)] {
        assert_eq!(t.find(k.packed()), Some(s));
    }
    assert_eq!(t.live().count(), 4);
    // Clearing gives an empty table that works again.
    t.clear();
    assert_eq!(t.len(), 0);
    assert_eq!(t.canonical().count(), 0);
    assert_eq!(t.find(a.packed()), None);
    assert_eq!(t.insert(entry(&a)), Ok(0));
}

fn t_key_of(keys: &[VoxelKey], slots: &[usize], slot: usize) -> VoxelKey {
    keys[slots.iter().position(|s| *s == slot).unwrap()]
}

#[test]
fn table_single_bucket() {
    let mut t: Table<T1, 1> = Table::new();
    assert_eq!(t.insert(entry(&key(1, 1, 1))), Ok(0));
    assert!(t.insert(entry(&key(2, 1, 1))).is_err());
    assert_eq!(t.find(key(2, 1, 1).packed()), None);
    t.remove(0);
    assert_eq!(t.find(key(1, 1, 1).packed()), None);
    assert_eq!(t.insert(entry(&key(2, 1, 1))), Ok(0));
    assert_eq!(t.find(key(2, 1, 1).packed()), Some(0));
}

fn canonical_keys<const N: usize>(t: &Table<T1, N>) -> Vec<u64> {
    t.canonical().map(|s| t.slots[s].packed_key()).collect()
}

#[test]
fn table_canonical_order_is_insertion_independent() {
    let mut rng = Lcg(3);
    let mut keys: Vec<VoxelKey> = Vec::new();
    while keys.len() < 40 {
        let k = key(
            (rng.next() * 200.0) as i16 - 100,
            (rng.next() * 20.0) as i16 - 10,
            (rng.next() * 6.0) as i16,
        );
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    let mut a: Table<T1, 48> = Table::new();
    let mut b: Table<T1, 48> = Table::new();
    let mut c: Table<T1, 48> = Table::new();
    for k in &keys {
        a.insert(entry(k)).unwrap();
    }
    for k in keys.iter().rev() {
        b.insert(entry(k)).unwrap();
    }
    // c: insert extra keys first, interleave, then remove the extras (free-list slots).
    let extra: Vec<VoxelKey> = (0..8).map(|i| key(500 + i, 0, 0)).collect();
    for k in &extra {
        c.insert(entry(k)).unwrap();
    }
    for k in keys.iter().skip(1).step_by(2) {
        c.insert(entry(k)).unwrap();
    }
    for k in &extra {
        let s = c.find(k.packed()).unwrap();
        c.remove(s);
    }
    for k in keys.iter().step_by(2) {
        c.insert(entry(k)).unwrap();
    }
    let ka = canonical_keys(&a);
    assert_eq!(ka.len(), keys.len());
    assert_eq!(ka, canonical_keys(&b));
    assert_eq!(ka, canonical_keys(&c));
    // Canonical order is (hash, key) ascending, whatever the capacity.
    assert!(ka.windows(2).all(|w| order(w[0]) < order(w[1])));
    let mut d: Table<T1, 40> = Table::new();
    for k in keys.iter().rev() {
        d.insert(entry(k)).unwrap();
    }
    assert_eq!(ka, canonical_keys(&d));
    // live() is the same set.
    let mut live: Vec<u64> = c.live().map(|s| c.slots[s].packed_key()).collect();
    live.sort_by_key(|k| order(*k));
    assert_eq!(live, ka);
}

// ---------------------------------------------------------------------------------------
// Keys
// ---------------------------------------------------------------------------------------

#[test]
fn key_from_point_floors() {
    let h = 0.25;
    let f = |x: f32| VoxelKey::from_point(&[x, 0.0, 0.0], h).map(|k| k.x);
    assert_eq!(f(0.0), Some(0));
    assert_eq!(f(-0.0), Some(0));
    assert_eq!(f(0.2499), Some(0));
    assert_eq!(f(0.25), Some(1));
    assert_eq!(f(-0.0001), Some(-1));
    assert_eq!(f(-0.25), Some(-1));
    assert_eq!(f(-0.2501), Some(-2));
    assert_eq!(f(-1.0), Some(-4));
    assert_eq!(f(-1.1), Some(-5));
    assert_eq!(
        VoxelKey::from_point(&[0.3, -0.3, -2.6], 0.5),
        Some(key(0, -1, -6))
    );
}

#[test]
fn key_range_limits() {
    let f = |x: f32| VoxelKey::from_point(&[x, 0.0, 0.0], 1.0).map(|k| k.x);
    assert_eq!(f(32767.0), Some(32767));
    assert_eq!(f(32767.5), Some(32767));
    assert_eq!(f(32768.0), None);
    assert_eq!(f(-32767.0), Some(-32767));
    assert_eq!(f(-32766.5), Some(-32767));
    assert_eq!(f(-32767.5), None);
    assert_eq!(f(-32768.0), None);
    assert_eq!(f(f32::NAN), None);
    assert_eq!(f(f32::INFINITY), None);
    assert_eq!(f(f32::NEG_INFINITY), None);
    assert_eq!(f(1e30), None);
    assert_eq!(VoxelKey::from_point(&[0.0, 0.0, f32::NAN], 1.0), None);
    assert_eq!(KEY_LIMIT, 32767);
}

#[test]
fn key_pack_block_cell_round_trips() {
    let mut rng = Lcg(5);
    let mut keys: Vec<VoxelKey> = Vec::new();
    for x in [
        -32767i16, -32766, -32765, -32764, -5, -4, -3, -1, 0, 1, 3, 4, 32764, 32767,
    ] {
        for y in [-32767i16, -2, 0, 2, 32767] {
            for z in [-32767i16, -1, 0, 5, 32766] {
                keys.push(key(x, y, z));
            }
        }
    }
    for _ in 0..2000 {
        let r = |rng: &mut Lcg| (rng.next() * 65535.0) as i32 - 32767;
        keys.push(key(
            r(&mut rng) as i16,
            r(&mut rng) as i16,
            r(&mut rng) as i16,
        ));
    }
    for k in &keys {
        let p = k.packed();
        assert_ne!(p, 0, "{k:?}");
        assert!(p < 1 << 48);
        assert_eq!(VoxelKey::unpack(p), *k);
        let cell = k.cell();
        assert!(cell < 64);
        assert_eq!(VoxelKey::from_block_cell(k.block(), cell), *k);
        // The block is the floor division by 4 on every axis.
        let b = VoxelKey::unpack(k.block());
        assert_eq!(
            [b.x, b.y, b.z],
            [k.x.div_euclid(4), k.y.div_euclid(4), k.z.div_euclid(4)]
        );
        assert_eq!(
            cell,
            (k.x.rem_euclid(4) + 4 * k.y.rem_euclid(4) + 16 * k.z.rem_euclid(4)) as u32
        );
        assert_eq!(crate::key::split_key(p), entry(k).key);
    }
    assert_eq!(key(-32767, 0, 5).chebyshev(&key(32767, 1, -5)), 65534);
    assert_eq!(key(1, 2, 3).chebyshev(&key(1, 2, 3)), 0);
}

// ---------------------------------------------------------------------------------------
// Eigen decomposition and prepared Gaussians
// ---------------------------------------------------------------------------------------

fn check_eigen(m: &Matrix3<f32>, want: [f64; 3], tol: f64) {
    let (vals, vecs) = symmetric_eigen(m);
    let got = sorted3(vals);
    let mut want = want;
    want.sort_by(|a, b| a.partial_cmp(b).unwrap());
    for i in 0..3 {
        assert!(
            (got[i] as f64 - want[i]).abs() <= tol,
            "eigenvalues {got:?} vs {want:?}"
        );
    }
    // Orthonormal vectors with A v = lambda v.
    let vtv = vecs.transpose() * vecs;
    for i in 0..3 {
        for j in 0..3 {
            let e = if i == j { 1.0 } else { 0.0 };
            assert!((vtv[(i, j)] - e).abs() < 1e-5, "V^T V = {vtv}");
        }
        let v = vecs.column(i);
        let r = m * v - v * vals[i];
        assert!(
            r.norm() as f64 <= tol,
            "residual {r} for lambda {}",
            vals[i]
        );
    }
}

#[test]
fn eigen_known_matrices() {
    // Diagonal: exact, identity vectors.
    let d = Matrix3::from_diagonal(&Vector3::new(3.0f32, 1.0, 2.0));
    let (vals, vecs) = symmetric_eigen(&d);
    assert_eq!(vals, [3.0, 1.0, 2.0]);
    assert_eq!(vecs, Matrix3::identity());
    // Zero matrix.
    let (vals, vecs) = symmetric_eigen(&Matrix3::zeros());
    assert_eq!(vals, [0.0; 3]);
    assert_eq!(vecs, Matrix3::identity());
    // Rotated diagonals, distinct and repeated eigenvalues, at covariance scales.
    let rots = [
        rotation([1.0, 2.0, 3.0], 0.7),
        rotation([0.0, 0.0, 1.0], core::f64::consts::FRAC_PI_4),
        rotation([-1.0, 0.5, 0.2], 2.5),
        rotation([1.0, 1.0, 1.0], 1e-3),
    ];
    for r in &rots {
        for (d, scale) in [
            ([4.0, 1.0, 0.25], 1.0),
            ([2.0, 2.0, 5.0], 1.0),
            ([3.0, 3.0, 3.0], 1.0),
            ([1.0, 1e-3, 0.0], 1.0),
            ([4.0, 1.0, 0.25], 1e-4),
        ] {
            let ds = [d[0] * scale, d[1] * scale, d[2] * scale];
            let m = to_m32(&rdrt(r, ds));
            check_eigen(&m, ds, 4e-6 * 5.0 * scale);
        }
    }
}

#[test]
fn prepare_applies_eigen_floor() {
    let g = |cov: Matrix3<f32>| Gaussian {
        mean: Vector3::new(1.0, 2.0, 3.0),
        covariance: cov,
        count: 10,
    };
    // Diagonal with a tiny and a zero eigenvalue: both raised to ratio * lambda_max.
    let p = g(Matrix3::from_diagonal(&Vector3::new(1e-2, 1e-8, 0.0))).prepare(1e-3, 1e-12);
    let want = Matrix3::from_diagonal(&Vector3::new(100.0f32, 1e5, 1e5));
    assert!((p.inv - want).abs().max() <= 1e-5 * 1e5, "{}", p.inv);
    assert_eq!(p.mean, Vector3::new(1.0, 2.0, 3.0));
    // Zero covariance: floor_abs = (h / 1000)^2.
    let fa = floor_abs(0.1);
    assert!(rel_close(fa as f64, 1e-8, 1e-5, 0.0));
    let p = g(Matrix3::zeros()).prepare(1e-3, fa);
    let want = Matrix3::identity() / fa;
    assert!(
        (p.inv - want).abs().max() <= 1e-6 * want[(0, 0)],
        "{}",
        p.inv
    );
    // Rotated, with one eigenvalue below the floor: R diag(1, 1e-3, 0.5)^-1 R^T after
    // raising 1e-5 to 1e-3.
    let r = rotation([0.3, -1.0, 0.4], 1.1);
    let cov = to_m32(&rdrt(&r, [1.0, 1e-5, 0.5]));
    let p = g(cov).prepare(1e-3, 1e-12);
    let want = rdrt(&r, [1.0, 1e3, 2.0]);
    for i in 0..3 {
        for j in 0..3 {
            assert!(
                (p.inv[(i, j)] as f64 - want[i][j]).abs() <= 1e-3 * 1e3,
                "inv {} vs {want:?}",
                p.inv
            );
        }
    }
}

#[test]
fn prepare_inverts_well_conditioned() {
    for (axis, angle, d) in [
        ([1.0, 0.0, 0.0], 0.0, [4e-4, 1e-4, 2.5e-4]),
        ([1.0, 2.0, -1.0], 0.9, [4e-4, 1e-4, 2.5e-4]),
        ([0.2, 0.1, 1.0], 2.0, [1.0, 0.5, 0.3]),
        ([1.0, 1.0, 0.0], 0.3, [2e-3, 2e-3, 1e-4]),
    ] {
        let cov = to_m32(&rdrt(&rotation(axis, angle), d));
        let g = Gaussian {
            mean: Vector3::zeros(),
            covariance: cov,
            count: 10,
        };
        let p = g.prepare(1e-3, floor_abs(0.1));
        let id = p.inv * cov;
        assert!(
            (id - Matrix3::identity()).abs().max() < 1e-4,
            "inv * cov = {id}"
        );
    }
}

// ---------------------------------------------------------------------------------------
// Occupancy: hits, misses, NDT-OM
// ---------------------------------------------------------------------------------------

#[test]
fn hit_and_constant_miss_fixed_point() {
    let mut map: Map<64, 64, 2> = Map::new(Config::DEFAULT);
    let pts = [lp(0.05, 0.05, 1.05, 1); 3];
    let r = map.integrate(&Isometry3::identity(), &pts).unwrap();
    assert_eq!((r.end_voxels, r.rays), (1, 1));
    assert_eq!(to_fixed(0.85), 870);
    assert_eq!(to_fixed(-0.4), -410);
    assert_eq!(fixed(&map, &key(0, 0, 10)), 870);
    for z in 0..10 {
        // No Gaussian on the way: the constant miss, once per frame.
        assert_eq!(fixed(&map, &key(0, 0, z)), -410, "z={z}");
    }
    assert_eq!(fixed(&map, &key(0, 0, 11)), 0);
    // Clamping: many frames saturate at the configured bounds.
    for _ in 0..10 {
        map.integrate(&Isometry3::identity(), &pts).unwrap();
    }
    assert_eq!(fixed(&map, &key(0, 0, 10)), to_fixed(3.5));
    assert_eq!(fixed(&map, &key(0, 0, 3)), to_fixed(-2.0));
    assert_eq!(map.occupancy(&key(0, 0, 10)), Occupancy::Occupied);
    assert_eq!(map.occupancy(&key(0, 0, 3)), Occupancy::Free);
    assert_eq!(map.occupancy(&key(5, 5, 5)), Occupancy::Unknown);
}

/// The NDT-OM miss for an isotropic Gaussian (variance `var`, m^2) in f64, exactly as the
/// design states it; `None` when the closest point lies beyond the ray's end.
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

#[test]
fn ndt_om_miss_hand_computed() {
    let h = 0.125f32;
    let cfg = Config::with_cell_size(h);
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

// ---------------------------------------------------------------------------------------
// Eviction
// ---------------------------------------------------------------------------------------

/// One frame whose sensor and single point lie in block `b` (h = 1): touches only that
/// block and creates one voxel at voxel (4 bx + 2, 4 by, 4 bz).
fn frame_in_block<const V: usize, const B: usize, const C: usize>(
    map: &mut Map<V, B, C>,
    b: [i32; 3],
) -> FrameReport {
    let o = [4 * b[0], 4 * b[1], 4 * b[2]].map(|v| v as f32 + 0.5);
    map.integrate(&at(o[0], o[1], o[2]), &[lp(2.0, 0.0, 0.0, 1)])
        .unwrap()
}

fn voxel_in_block(b: [i32; 3]) -> VoxelKey {
    key(4 * b[0] as i16 + 2, 4 * b[1] as i16, 4 * b[2] as i16)
}

#[test]
fn block_eviction_takes_whole_farthest_bin() {
    let cfg = Config::with_cell_size(1.0);
    let mut map: Map<16, 4, 1> = Map::try_new(cfg).unwrap();
    let far = [[1, 0, 0], [0, 2, 0], [0, 0, 3], [-3, 1, 0]];
    for b in far {
        let r = frame_in_block(&mut map, b);
        assert_eq!(
            (r.blocks_created, r.voxels_created, r.points_used),
            (1, 1, 1)
        );
    }
    assert_eq!(map.block_count(), 4);
    // Frame at block 0: table full, the two blocks at Chebyshev block distance 3 go
    // (whole bin), although one would be enough (target max(4/16, 1) = 1).
    let r = frame_in_block(&mut map, [0, 0, 0]);
    assert_eq!((r.blocks_evicted, r.voxels_evicted), (2, 2));
    assert_eq!(map.stats().blocks_evicted, 2);
    assert_eq!(map.stats().voxels_evicted, 2);
    assert_eq!(map.block_count(), 3);
    assert_eq!(map.len(), 3);
    for (b, kept) in far.iter().zip([true, true, false, false]) {
        let k = voxel_in_block(*b);
        assert_eq!(map.gaussian(&k).is_some(), kept, "{b:?}");
        assert_eq!(map.occupancy(&k) == Occupancy::Occupied, kept, "{b:?}");
    }
    assert!(map.gaussian(&voxel_in_block([0, 0, 0])).is_some());
}

#[test]
fn block_eviction_bins_are_64_wide_beyond_255() {
    let cfg = Config::with_cell_size(1.0);
    let mut map: Map<16, 4, 1> = Map::try_new(cfg).unwrap();
    // Distances 1, 300, 310, 330 from block 0: bins 1, 256, 256, 257.
    let blocks = [[1, 0, 0], [300, 0, 0], [0, -310, 0], [0, 0, 330]];
    for b in blocks {
        frame_in_block(&mut map, b);
    }
    let r = frame_in_block(&mut map, [0, 0, 0]);
    assert_eq!(r.blocks_evicted, 1);
    assert!(map.gaussian(&voxel_in_block([0, 0, 330])).is_none());
    assert!(map.gaussian(&voxel_in_block([300, 0, 0])).is_some());
    // Next new block: 300 and 310 share bin 256 and go together.
    let r = frame_in_block(&mut map, [0, 1, 1]);
    assert_eq!(r.blocks_evicted, 2);
    assert!(map.gaussian(&voxel_in_block([300, 0, 0])).is_none());
    assert!(map.gaussian(&voxel_in_block([0, -310, 0])).is_none());
    assert!(map.gaussian(&voxel_in_block([1, 0, 0])).is_some());
    assert_eq!(map.stats().blocks_evicted, 3);
}

#[test]
fn nothing_touched_this_frame_is_evicted() {
    let cfg = Config::with_cell_size(1.0);
    // One block: a frame whose points span two blocks drops the second.
    let mut map: Map<16, 1, 1> = Map::try_new(cfg).unwrap();
    let pts = [lp(1.0, 0.0, 0.0, 1), lp(5.0, 0.0, 0.0, 1)];
    let r = map.integrate(&at(0.5, 0.5, 0.5), &pts).unwrap();
    assert_eq!((r.points_used, r.dropped_points), (1, 1));
    assert_eq!((r.blocks_evicted, r.voxels_evicted), (0, 0));
    assert_eq!(map.stats().dropped_points, 1);
    // A ray needing a block that does not fit drops its misses, counted.
    let mut map: Map<16, 1, 1> = Map::try_new(cfg).unwrap();
    let r = map
        .integrate(&at(0.5, 0.5, 0.5), &[lp(6.0, 0.0, 0.0, 1)])
        .unwrap();
    assert_eq!(r.points_used, 1);
    assert_eq!(r.dropped_misses, 4); // voxels 0..=3 of the ray: block 0 does not fit
    assert_eq!(map.stats().dropped_misses, 4);
    // One voxel: a second voxel in the same frame is dropped (the first was hit).
    let mut map: Map<1, 16, 1> = Map::try_new(cfg).unwrap();
    let r = map.integrate(&at(0.5, 0.5, 0.5), &pts).unwrap();
    assert_eq!(
        (r.points_used, r.dropped_points, r.voxels_evicted),
        (1, 1, 0)
    );
}

#[test]
fn voxel_eviction_farthest_bin_keeps_occupancy() {
    let cfg = Config::with_cell_size(1.0);
    let mut map: Map<4, 64, 1> = Map::try_new(cfg).unwrap();
    let sensor = at(0.5, 0.5, 0.5);
    // Voxels at Chebyshev distance 1, 2, 3, 3 from the sensor voxel.
    let pts = [
        [1.0, 0.0, 0.0],
        [0.0, 2.0, 0.0],
        [0.0, 0.0, 3.0],
        [-3.0, 0.0, 0.0],
    ];
    for p in pts {
        map.integrate(&sensor, &[lp(p[0], p[1], p[2], 1)]).unwrap();
    }
    assert_eq!(map.len(), 4);
    let r = map.integrate(&sensor, &[lp(1.0, 1.0, 0.0, 1)]).unwrap();
    assert_eq!(
        (r.voxels_evicted, r.blocks_evicted, r.points_used),
        (2, 0, 1)
    );
    assert_eq!(map.len(), 3);
    for (p, kept) in pts.iter().zip([true, true, false, false]) {
        let k = key(p[0] as i16, p[1] as i16, p[2] as i16);
        assert_eq!(map.gaussian(&k).is_some(), kept, "{p:?}");
        // Occupancy stays in the block layer.
        assert_eq!(map.occupancy(&k), Occupancy::Occupied, "{p:?}");
        // The block's surface mask agrees with the surface layer.
        let b = map.blocks.find(k.block()).unwrap();
        assert_eq!(map.blocks.slots[b].surface >> k.cell() & 1 == 1, kept);
    }
}

// ---------------------------------------------------------------------------------------
// Order independence and snapshots
// ---------------------------------------------------------------------------------------

#[test]
fn snapshot_identical_under_point_permutation() {
    let mut rng = Lcg(99);
    let mut frames = Vec::new();
    for f in 0..3 {
        let mut pts = Vec::new();
        for i in 0..600 {
            // Clusters of points (decay with n_max = 16), top-3 labels, some rejects.
            let c = (i % 12) as f32;
            let mut p = [
                0.3 * c - 1.52 + 0.06 * rng.next() as f32,
                0.2 * (c % 3.0) - 0.22 + 0.06 * rng.next() as f32,
                1.5 + 0.06 * rng.next() as f32,
            ];
            if i % 97 == 0 {
                p[2] = 30.0; // truncated at max range
            }
            if i % 113 == 0 {
                p[0] = f32::NAN;
            }
            let l = Labels::top_k(&[
                (1 + (i % 4) as u8, 200),
                (1 + (i % 3) as u8, (rng.next() * 255.0) as u8),
                ((i % 5) as u8, 90),
            ]);
            pts.push(LabeledPoint::new(Point3::new(p[0], p[1], p[2]), l));
        }
        let pose = Isometry3::from_parts(
            Translation3::new(0.1 * f as f32, -0.05, 0.02),
            UnitQuaternion::from_euler_angles(0.0, 0.1 * f as f32, 0.05),
        );
        frames.push((pose, pts));
    }
    let mut cfg = Config::DEFAULT;
    cfg.n_max = 16;
    cfg.top_k = 3;
    cfg.min_score = 100;
    cfg.max_range = 3.0;
    let mut used = 0u32;
    let mut maps: Vec<std::boxed::Box<Map<1024, 1024, 6>>> = (0..3)
        .map(|_| std::boxed::Box::new(Map::new(cfg)))
        .collect();
    for (pose, pts) in &frames {
        let mut rev = pts.clone();
        rev.reverse();
        let mut shuffled = pts.clone();
        for i in (1..shuffled.len()).rev() {
            let j = (rng.next() * (i + 1) as f64) as usize;
            shuffled.swap(i, j);
        }
        let mut reports: Vec<FrameReport> = Vec::new();
        for (m, order) in maps.iter_mut().zip([pts, &rev, &shuffled]) {
            let r = m.integrate(pose, order).unwrap();
            assert_eq!(
                (r.voxels_evicted, r.blocks_evicted, r.dropped_points),
                (0, 0, 0)
            );
            assert_eq!(r.dropped_misses, 0);
            reports.push(r);
        }
        assert_eq!(reports[0], reports[1]);
        assert_eq!(reports[0], reports[2]);
        assert!(reports[0].truncated > 0 && reports[0].rejected_depth > 0);
        used += reports[0].points_used;
    }
    let s0 = snapshot(&*maps[0]);
    assert_eq!(s0, snapshot(&*maps[1]));
    assert_eq!(s0, snapshot(&*maps[2]));
    assert_eq!(maps[0].checksum(), maps[2].checksum());
    assert_eq!(
        maps[0].checksum(),
        u32::from_le_bytes(s0[s0.len() - 4..].try_into().unwrap())
    );
    // Decay happened (else this test would not cover it): fewer points kept than used.
    let kept: u32 = maps[0].voxels().map(|v| v.gaussian.count).sum();
    assert!(maps[0].voxels().all(|v| v.gaussian.count <= 16));
    assert!(kept < used, "kept {kept} of {used}");
}

#[test]
fn snapshot_round_trip_and_rejections() {
    let mut map: Map<64, 32, 3> = Map::new(Config::DEFAULT);
    let pts: Vec<_> = (0..50)
        .map(|i| {
            lp(
                0.02 * (i % 7) as f32,
                0.03 * (i % 5) as f32,
                1.0 + 0.01 * i as f32,
                1 + (i % 3) as u8,
            )
        })
        .collect();
    map.integrate(&Isometry3::identity(), &pts).unwrap();
    let s = snapshot(&map);
    let mut copy: Map<64, 32, 3> = Map::new(Config::with_cell_size(0.2));
    copy.read_snapshot(&s).unwrap();
    assert_eq!(snapshot(&copy), s);
    assert_eq!(copy.config(), map.config());
    // Every truncation and every flipped byte is rejected and leaves the map unchanged.
    for cut in [0, 10, 87, 88, s.len() - 1] {
        assert!(copy.read_snapshot(&s[..cut]).is_err());
    }
    for i in (0..s.len()).step_by(7) {
        let mut bad = s.clone();
        bad[i] ^= 0x10;
        assert!(copy.read_snapshot(&bad).is_err(), "byte {i}");
    }
    assert_eq!(snapshot(&copy), s);
    // A smaller map rejects it by capacity.
    let mut small: Map<4, 32, 3> = Map::new(Config::DEFAULT);
    assert_eq!(small.read_snapshot(&s), Err(Error::SnapshotCapacity));
    let mut other: Map<64, 32, 4> = Map::new(Config::DEFAULT);
    assert_eq!(other.read_snapshot(&s), Err(Error::SnapshotClasses));
    // A voxel count above n_max with a valid CRC is corrupt.
    let mut bad = s.clone();
    let first_voxel = SNAPSHOT_HEADER_BYTES + map.block_count() * SNAPSHOT_BLOCK_BYTES;
    bad[first_voxel + 6..first_voxel + 10].copy_from_slice(&4000u32.to_le_bytes());
    fix_crc(&mut bad);
    assert_eq!(copy.read_snapshot(&bad), Err(Error::SnapshotCorrupt));
    // So is a vote sampling exponent above 15 (byte 46 of a voxel record).
    let mut bad = s.clone();
    bad[first_voxel + 46] = 16;
    fix_crc(&mut bad);
    assert_eq!(copy.read_snapshot(&bad), Err(Error::SnapshotCorrupt));
}

#[test]
fn snapshot_keeps_the_vote_sampling() {
    // A crowded voxel samples one point in 2^3 after its first frame (500 votes, 64 per
    // frame); a map read from its snapshot continues exactly like the original.
    let mut map: Map<16, 16, 2> = Map::new(Config::DEFAULT);
    let mut rng = Lcg(5);
    map.integrate(&Isometry3::identity(), &voxel_cloud(&mut rng, 200, 300))
        .unwrap();
    let k = key(0, 0, 10);
    assert_eq!(voxel(&map, &k).tally >> 12, 3);
    let mut copy: Map<16, 16, 2> = Map::new(Config::DEFAULT);
    copy.read_snapshot(&snapshot(&map)).unwrap();
    assert_eq!(voxel(&copy, &k).tally >> 12, 3);
    let next = voxel_cloud(&mut rng, 100, 400);
    map.integrate(&Isometry3::identity(), &next).unwrap();
    copy.integrate(&Isometry3::identity(), &next).unwrap();
    assert_eq!(snapshot(&copy), snapshot(&map));
}

#[test]
fn nalgebra_norm_is_libm_sqrt() {
    // The core's only transcendental through nalgebra is sqrt (`norm`, quaternion from
    // matrix). In test builds num-traits' `std` feature (from proptest) routes it to
    // `f32::sqrt`, in firmware builds to `libm::sqrtf`; both are correctly rounded, so they
    // must agree bit for bit.
    let mut rng = Lcg(17);
    for i in 0..20000 {
        let e = i % 40 - 20;
        let s = libm::ldexpf(1.0, e);
        let v = Vector3::new(
            (rng.next() as f32 - 0.5) * s,
            (rng.next() as f32 - 0.5) * s,
            (rng.next() as f32 - 0.5) * s,
        );
        assert_eq!(
            v.norm().to_bits(),
            libm::sqrtf(v.norm_squared()).to_bits(),
            "{v}"
        );
    }
}

#[test]
fn depth_image_size_overflow_is_rejected() {
    // 65536 x 65536 pixels is 2^32: on a 32-bit target `width * height` must not wrap to
    // an empty image (it would then index the empty depth slice).
    let cam = Pinhole {
        fx: 100.0,
        fy: 100.0,
        cx: 0.0,
        cy: 0.0,
        width: 65536,
        height: 65536,
    };
    let img = DepthImage {
        camera: cam,
        depth: &[],
        kind: DepthKind::Planar,
        labels: LabelImage::None,
        stride: 1,
    };
    let mut map: Map<16, 16, 1> = Map::new(Config::DEFAULT);
    assert_eq!(
        map.integrate_depth(&Isometry3::identity(), &img),
        Err(Error::InvalidImage)
    );
    assert_eq!(
        map.render(&Isometry3::identity(), &cam, &mut [], &mut []),
        Err(Error::InvalidImage)
    );
}

// ---------------------------------------------------------------------------------------
// Regression tests for defects found in review (each failed or panicked before its fix).
// ---------------------------------------------------------------------------------------

mod findings {
    use super::*;

    /// `hit` was unbounded: `to_fixed(3e6)` saturated to `i32::MAX` and the second hit
    /// overflowed. Now `hit` is limited to 30 and `to_fixed` clamps; the largest valid hit
    /// saturates at the clamp.
    #[test]
    fn large_valid_hit_overflows_log_odds() {
        let mut cfg = Config::DEFAULT;
        cfg.hit = 3e6;
        assert_eq!(cfg.validate(), Err(Error::InvalidConfig));
        cfg.hit = 30.0;
        assert!(cfg.validate().is_ok());
        let mut map: Map<16, 16, 1> = Map::try_new(cfg).unwrap();
        let pts = [lp(0.05, 0.05, 1.05, 1)];
        map.integrate(&Isometry3::identity(), &pts).unwrap();
        map.integrate(&Isometry3::identity(), &pts).unwrap();
        assert_eq!(map.log_odds(&key(0, 0, 10)), 3.5);
    }

    /// Same for `miss` (was `cell + i32::MIN` on the second miss).
    #[test]
    fn large_valid_miss_overflows_log_odds() {
        let mut cfg = Config::DEFAULT;
        cfg.miss = -3e6;
        assert_eq!(cfg.validate(), Err(Error::InvalidConfig));
        cfg.miss = -30.0;
        assert!(cfg.validate().is_ok());
        let mut map: Map<16, 16, 1> = Map::try_new(cfg).unwrap();
        let pts = [lp(0.05, 0.05, 1.05, 1)];
        map.integrate(&Isometry3::identity(), &pts).unwrap();
        map.integrate(&Isometry3::identity(), &pts).unwrap();
        assert_eq!(map.log_odds(&key(0, 0, 5)), -2.0);
    }

    /// `lambda = 0.5` is valid. A truncated ray (p_z = 0) through a Gaussian's mean gives
    /// p_N = 1, p = 0.5 - 0.5 = 0, logit = -inf, `to_fixed` = i32::MIN, and the second such
    /// miss computes `-2048 + i32::MIN`: overflow (debug panic); in release the sum wraps
    /// and clamps to `clamp_max`, turning a cleared voxel into a fully occupied one.
    #[test]
    fn ndt_om_lambda_half_overflows_log_odds() {
        // lambda = 0.5 allowed p = 0 (logit -inf); now lambda <= 0.49, so p >= 0.01.
        let mut cfg = Config::with_cell_size(0.125);
        cfg.lambda = 0.5;
        assert_eq!(cfg.validate(), Err(Error::InvalidConfig));
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

    /// `raycast` computes `(max_t / h) as u32 * 3 + 12`: `max_t = inf` (accepted, only
    /// `max_t > 0` is checked) saturates the cast and overflows the product (debug panic);
    /// in release the step count wraps to 9 and a wall 2 m away is missed.
    #[test]
    fn raycast_with_infinite_max_t() {
        let mut map: Map<512, 256, 2> = Map::new(Config::DEFAULT);
        let mut pts = [lp(0.0, 0.0, 0.0, 1); 400];
        for (i, p) in pts.iter_mut().enumerate() {
            let (u, v) = ((i % 20) as f32 / 20.0 - 0.5, (i / 20) as f32 / 20.0 - 0.5);
            p.position = Point3::new(u, v, 2.02);
        }
        map.integrate(&Isometry3::identity(), &pts).unwrap();
        let hit = map.raycast(&Point3::new(0.05, 0.05, 0.0), &Vector3::z(), f32::INFINITY);
        assert!(hit.is_some_and(|h| (h.t - 2.02).abs() < 0.05));
    }

    /// `render` passes `config.max_range` as `max_t`; a valid `max_range = 1e9` hits the
    /// same overflow.
    #[test]
    fn render_with_large_valid_max_range() {
        let mut cfg = Config::DEFAULT;
        cfg.max_range = 1e9;
        assert_eq!(cfg.validate(), Err(Error::InvalidConfig));
        cfg.max_range = 1e4; // the largest valid max range still renders
        assert!(cfg.validate().is_ok());
        let mut map: Map<512, 256, 2> = Map::try_new(cfg).unwrap();
        let mut pts = [lp(0.0, 0.0, 0.0, 1); 400];
        for (i, p) in pts.iter_mut().enumerate() {
            let (u, v) = ((i % 20) as f32 / 20.0 - 0.5, (i / 20) as f32 / 20.0 - 0.5);
            p.position = Point3::new(u, v, 2.02);
        }
        map.integrate(&Isometry3::identity(), &pts).unwrap();
        let cam = Pinhole {
            fx: 10.0,
            fy: 10.0,
            cx: 0.5,
            cy: 0.5,
            width: 1,
            height: 1,
        };
        let (mut l, mut d) = ([0u8], [0f32]);
        map.render(&at(0.05, 0.05, 0.0), &cam, &mut l, &mut d)
            .unwrap();
        assert_eq!(l[0], 1);
    }

    /// `Map::new` promises to replace invalid configs by the default, but `checked()` only
    /// looks at a few fields. With `clamp_min > clamp_max`, `i32::clamp(lo, hi)` in
    /// `Block::add_logodds` panics (in release too).
    #[test]
    fn map_new_keeps_invalid_config() {
        let mut bad = Config::DEFAULT;
        bad.clamp_min = 0.5;
        bad.clamp_max = 0.25;
        assert!(bad.validate().is_err());
        let mut map: Map<16, 16, 1> = Map::new(bad);
        let r = std::panic::catch_unwind(core::panic::AssertUnwindSafe(|| {
            map.integrate(&Isometry3::identity(), &[lp(0.05, 0.05, 1.05, 1)])
                .map(|_| ())
        }));
        assert!(r.is_ok(), "integrate panicked on a map built by Map::new");
        let mut others = Vec::new();
        for f in [
            (|c: &mut Config| c.hit = f32::INFINITY) as fn(&mut Config),
            |c| c.miss = 1.0,
            |c| c.lambda = 2.0,
            |c| c.eigen_ratio = 0.0,
            |c| c.noise_base = 0.0,
            |c| c.max_range = f32::NAN,
            |c| c.render_radius = -1.0,
        ] {
            let mut c = Config::DEFAULT;
            f(&mut c);
            assert!(c.validate().is_err());
            others.push(*Map::<1, 1, 1>::new(c).config() == Config::DEFAULT);
        }
        assert!(others.iter().all(|ok| *ok), "{others:?}");
    }

    /// Frame stamps are `frames % 65535 + 1`, and old stamps are only forgotten when the
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

    /// The consequence of the stamp wrap-around at the documented bounds: with
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

    /// Decay rounds `n` up but halves the sums: for odd `n` the mean shrinks toward the
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

    /// A snapshot block at block coordinate -8192 covers voxels x = -32768..-32765; the
    /// reader accepts log-odds in its x = -32768 cells, and `cells()` then reports keys
    /// outside the documented range `-KEY_LIMIT..=KEY_LIMIT`.
    #[test]
    fn snapshot_accepts_cells_outside_key_range() {
        let mut src: Map<4, 4, 1> = Map::new(Config::DEFAULT);
        let edge = key(-32767, 0, 0);
        let mut b = Block::new(edge.block());
        b.cells[0] = -100; // cell 0 of block -8192 is voxel x = -32768
        src.blocks.insert(b).unwrap();
        let s = snapshot(&src);
        let mut map: Map<4, 4, 1> = Map::new(Config::DEFAULT);
        let read = map.read_snapshot(&s);
        let bad: Vec<VoxelKey> = map
            .cells()
            .map(|(k, _)| k)
            .filter(|k| (k.x as i32).abs() > KEY_LIMIT)
            .collect();
        assert!(
            read.is_err() || bad.is_empty(),
            "accepted cells with keys {bad:?}"
        );
    }

    /// The reader checks |S1| <= n 2^(Q-1) and |S2| <= n 4^(Q-1) but not that the sums can
    /// come from points (n S2_ii >= S1_i^2): a voxel with S1 = n * 32, S2 = 0 is accepted and
    /// its Gaussian has a negative variance.
    #[test]
    fn snapshot_accepts_impossible_sums() {
        let mut map: Map<16, 16, 1> = Map::new(Config::DEFAULT);
        map.integrate(&Isometry3::identity(), &[lp(0.05, 0.05, 1.05, 1); 4])
            .unwrap();
        let mut s = snapshot(&map);
        let v0 = SNAPSHOT_HEADER_BYTES + map.block_count() * SNAPSHOT_BLOCK_BYTES;
        // Record: key 6, n 4, S1 12, S2 24.
        s[v0 + 10..v0 + 14].copy_from_slice(&128i32.to_le_bytes()); // S1x = 4 * 32
        s[v0 + 22..v0 + 26].copy_from_slice(&0i32.to_le_bytes()); // S2xx = 0
        fix_crc(&mut s);
        let mut copy: Map<16, 16, 1> = Map::new(Config::DEFAULT);
        let read = copy.read_snapshot(&s);
        let var = copy
            .gaussian(&key(0, 0, 10))
            .map_or(0.0, |g| g.covariance[(0, 0)]);
        assert!(read.is_err() || var >= 0.0, "accepted; variance {var}");
    }

    /// The 3 reserved bytes of the header must be zero: junk there is rejected.
    #[test]
    fn snapshot_rejects_nonzero_reserved_bytes() {
        let mut map: Map<16, 16, 1> = Map::new(Config::DEFAULT);
        map.integrate(&Isometry3::identity(), &[lp(0.05, 0.05, 1.05, 1); 4])
            .unwrap();
        let mut s = snapshot(&map);
        s[73] = 0xAB; // reserved bytes 73..76
        fix_crc(&mut s);
        let mut copy: Map<16, 16, 1> = Map::new(Config::DEFAULT);
        assert_eq!(copy.read_snapshot(&s), Err(Error::SnapshotCorrupt));
    }
}
