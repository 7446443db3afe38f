//! Hand-checked end-to-end voxel statistics: mean and covariance against an
//! f64 formula, decay, and the class histogram.

// Index loops over matrix entries (i, j) read like the formulas they check.
#![allow(clippy::needless_range_loop)]

use sndt_core::{Config, Isometry3, LabeledPoint, Labels, Map, Occupancy, Point3, VoxelKey};
use sndt_tests::*;

type M = Map<64, 64, 8>;

/// f64 mean and sample covariance (divisor n - 1).
fn mean_cov(pts: &[[f64; 3]]) -> ([f64; 3], [[f64; 3]; 3]) {
    let n = pts.len() as f64;
    let mut m = [0.0; 3];
    for p in pts {
        for a in 0..3 {
            m[a] += p[a] / n;
        }
    }
    let mut c = [[0.0; 3]; 3];
    for p in pts {
        for i in 0..3 {
            for j in 0..3 {
                c[i][j] += (p[i] - m[i]) * (p[j] - m[j]) / (n - 1.0);
            }
        }
    }
    (m, c)
}

fn integrate(map: &mut M, pts: &[[f32; 3]], labels: &[u8]) {
    let lps: Vec<LabeledPoint> = pts
        .iter()
        .zip(labels)
        .map(|(p, &l)| lp(p[0], p[1], p[2], l))
        .collect();
    let r = map.integrate(&Isometry3::identity(), &lps).unwrap();
    assert_eq!(r.points_used as usize, lps.len());
}

/// Six points in voxel (0, 0, 10) at h = 0.1, anywhere inside it (not on the quantisation
/// grid).
#[test]
fn gaussian_matches_f64_formula_within_quantisation() {
    let pts: [[f32; 3]; 6] = [
        [0.012, 0.034, 1.021],
        [0.047, 0.081, 1.055],
        [0.093, 0.016, 1.078],
        [0.031, 0.062, 1.097],
        [0.066, 0.049, 1.004],
        [0.058, 0.027, 1.043],
    ];
    let mut map: M = Map::new(Config::DEFAULT);
    integrate(&mut map, &pts, &[3, 3, 5, 3, 5, 3]);
    let key = VoxelKey { x: 0, y: 0, z: 10 };
    assert_eq!(map.voxel_key(&pts[0]), Some(key));
    let g = map.gaussian(&key).unwrap();
    assert_eq!(g.count, 6);
    assert_eq!(map.len(), 1);
    assert_eq!(map.class(&key), Some((3, 4.0 / 6.0)));
    assert_eq!(map.occupancy(&key), Occupancy::Occupied);

    let p64: Vec<[f64; 3]> = pts.iter().map(|p| p.map(f64::from)).collect();
    let (m, c) = mean_cov(&p64);
    let n = pts.len() as f64;
    let step = (0.1f32 / 64.0) as f64;
    // Quantisation error per coordinate: |e| <= step / 2, plus f32 rounding of p / h
    // (a few 1e-8 m at 1 m); 1e-6 m covers it generously.
    let e_max = step / 2.0 + 1e-6;
    for a in 0..3 {
        let d = (g.mean[a] as f64 - m[a]).abs();
        assert!(
            d <= e_max,
            "mean[{a}]: {} vs {} (diff {d:e})",
            g.mean[a],
            m[a]
        );
    }
    // Covariance of quantised points p + e:
    //   C' = C + Cov(p, e) + Cov(e, p) + Cov(e, e).
    // Cauchy-Schwarz on the centred sums gives |Cov(a, b)| <= sqrt(Var a * Var b), and
    //   Var(e_i) = sum (e_i - mean e_i)^2 / (n - 1) <= sum e_i^2 / (n - 1) <= n e_max^2 / (n - 1),
    // so with s_e = e_max sqrt(n / (n - 1)) and sigma_i = sqrt(C_ii):
    //   |C'_ij - C_ij| <= (sigma_i + sigma_j) s_e + s_e^2.
    // The core then forms (n S2 - S1 S1^T) exactly in integers and rounds once to f32
    // (relative 6e-8): 1e-6 relative plus 1e-10 m^2 absolute covers that.
    let s_e = e_max * (n / (n - 1.0)).sqrt();
    for i in 0..3 {
        for j in 0..3 {
            let tol = (c[i][i].sqrt() + c[j][j].sqrt()) * s_e + s_e * s_e;
            let tol = tol + 1e-6 * c[i][j].abs() + 1e-10;
            let got = g.covariance[(i, j)] as f64;
            assert!(
                (got - c[i][j]).abs() <= tol,
                "cov[{i}][{j}]: {got:e} vs {:e}, tolerance {tol:e}",
                c[i][j]
            );
        }
    }
    // The tolerance is meaningful: an order of magnitude below the variances.
    assert!(c[0][0] > 10.0 * ((c[0][0].sqrt() * 2.0) * s_e + s_e * s_e));
}

/// Points exactly on the quantisation grid (centre + m * step) lose nothing: mean and
/// covariance equal the f64 values up to f32 rounding.
#[test]
fn gaussian_on_the_quantisation_grid_is_exact() {
    let h = 0.1f32;
    let step = h / 64.0;
    let key = VoxelKey { x: -3, y: 2, z: 7 };
    let c = key.center(h);
    let offsets: [[i32; 3]; 5] = [
        [-31, 5, 12],
        [0, 0, 0],
        [17, -9, 3],
        [25, 31, -20],
        [-4, -30, 8],
    ];
    let pts: Vec<[f32; 3]> = offsets
        .iter()
        .map(|m| core::array::from_fn(|a| c[a] + m[a] as f32 * step))
        .collect();
    let mut map: M = Map::new(Config::DEFAULT);
    integrate(&mut map, &pts, &[1; 5]);
    let g = map.gaussian(&key).unwrap();
    assert_eq!(g.count, 5);
    // In quanta, the expected values are exact rationals.
    let q: Vec<[f64; 3]> = offsets.iter().map(|m| m.map(f64::from)).collect();
    let (mq, cq) = mean_cov(&q);
    let st = step as f64;
    for a in 0..3 {
        let want = c[a] as f64 + mq[a] * st;
        assert!((g.mean[a] as f64 - want).abs() < 1e-6, "mean[{a}]");
        for b in 0..3 {
            let want = cq[a][b] * st * st;
            let got = g.covariance[(a, b)] as f64;
            assert!(
                (got - want).abs() <= 1e-6 * want.abs() + 1e-12,
                "cov[{a}][{b}] {got} {want}"
            );
        }
    }
}

/// Decay (voxel.rs `decay`): with n_max = 4, ten points in one frame: the count halves,
/// rounding up, until n <= 4 (10 -> 5 -> 3), and the sums are scaled by the same factor
/// 3/10, rounded to nearest (halves away from zero), so mean and covariance are kept.
#[test]
fn decay_scales_counts_and_sums_as_documented() {
    let mut cfg = Config::DEFAULT;
    cfg.n_min = 3;
    cfg.n_max = 4;
    let h = 0.1f32;
    let step = h / 64.0;
    let key = VoxelKey { x: 1, y: 1, z: 12 };
    let c = key.center(h);
    let offsets: Vec<[i32; 3]> = (0..10)
        .map(|i| [i * 5 - 23, 31 - i * 7, (i * i) % 13 - 6])
        .collect();
    let pts: Vec<[f32; 3]> = offsets
        .iter()
        .map(|m| core::array::from_fn(|a| c[a] + m[a] as f32 * step))
        .collect();
    let mut map: M = Map::new(cfg);
    integrate(&mut map, &pts, &[2; 10]);

    let (n0, n) = (10i64, 3i64);
    let scale = |s: i64| {
        let v = s * n;
        if v >= 0 {
            (2 * v + n0) / (2 * n0)
        } else {
            -((-2 * v + n0) / (2 * n0))
        }
    };
    let mut s1 = [0i64; 3];
    let mut s2 = [[0i64; 3]; 3];
    for m in &offsets {
        for a in 0..3 {
            s1[a] += m[a] as i64;
            for b in 0..3 {
                s2[a][b] += m[a] as i64 * m[b] as i64;
            }
        }
    }
    let s1 = s1.map(scale);
    let s2 = s2.map(|r| r.map(scale));
    let g = map.gaussian(&key).unwrap();
    assert_eq!(g.count, 3);
    let st = step as f64;
    for a in 0..3 {
        let want = c[a] as f64 + s1[a] as f64 / n as f64 * st;
        assert!((g.mean[a] as f64 - want).abs() < 1e-6, "mean[{a}]");
        for b in 0..3 {
            let want = (n * s2[a][b] - s1[a] * s1[b]) as f64 / (n * (n - 1)) as f64 * st * st;
            let got = g.covariance[(a, b)] as f64;
            assert!(
                (got - want).abs() <= 1e-6 * want.abs() + 1e-12,
                "cov[{a}][{b}]"
            );
        }
    }
    // Decay keeps the mean within a quantum of the undecayed mean.
    for a in 0..3 {
        let undecayed: f64 = offsets.iter().map(|m| m[a] as f64).sum::<f64>() / 10.0;
        assert!((s1[a] as f64 / n as f64 - undecayed).abs() <= 0.5 / n as f64 + 1e-9);
    }
}

/// Histogram: top-k voting with a score threshold, void labels, votes within the frame
/// budget, and halving.
#[test]
fn class_histogram_by_hand() {
    let mut cfg = Config::DEFAULT;
    cfg.top_k = 2;
    cfg.min_score = 100;
    let mut map: M = Map::new(cfg);
    let p = Point3::new(0.05, 0.05, 1.05);
    let key = VoxelKey { x: 0, y: 0, z: 10 };
    let pts = [
        Labels::top_k(&[(1, 200), (2, 150), (3, 255)]), // votes 1, 2 (third label ignored)
        Labels::top_k(&[(1, 90), (3, 250)]),            // votes 3 (score 90 < 100)
        Labels::top_k(&[(4, 255)]),                     // votes 4
        Labels::top_k(&[(2, 100), (1, 99)]),            // votes 2
        Labels::top_k(&[(0, 255), (2, 200)]),           // votes 2 (0 is void)
        Labels::NONE,                                   // geometry only
    ]
    .map(|l| LabeledPoint::new(p, l));
    let r = map.integrate(&Isometry3::identity(), &pts).unwrap();
    assert_eq!(r.points_used, 6);
    let v = map.voxel(&key).unwrap();
    assert_eq!(v.histogram, &[1, 3, 1, 1, 0, 0, 0, 0]);
    assert_eq!(v.class(), Some((2, 0.5)));
    assert_eq!(v.gaussian.count, 6);

    // Up to `votes_per_frame` voting points per voxel and frame all vote; a bin above
    // 255 - votes_per_frame halves the histogram once before the next frame's votes.
    let mut cfg = Config::DEFAULT;
    cfg.votes_per_frame = 64;
    let mut map: M = Map::new(cfg);
    let mut i = 0u32;
    let mut frame = |n1: u32, n2: u32| {
        // Distinct points on a 7 x 7 x 7 lattice inside the voxel.
        let pts: Vec<LabeledPoint> = (0..n1 + n2)
            .map(|j| {
                let c = i + j;
                let at = |d: u32| 0.005 + 0.012 * (d % 7) as f32;
                let q = Point3::new(at(c), at(c / 7), 1.0 + at(c / 49));
                LabeledPoint::new(q, Labels::top1(if j < n1 { 1 } else { 2 }))
            })
            .collect();
        i += n1 + n2;
        map.integrate(&Isometry3::identity(), &pts).unwrap();
        map.voxel(&key).unwrap().histogram[..2].to_vec()
    };
    assert_eq!(frame(60, 4), [60, 4]);
    assert_eq!(frame(64, 0), [124, 4]);
    assert_eq!(frame(64, 0), [188, 4]);
    assert_eq!(frame(0, 10), [188, 14]);
    assert_eq!(frame(4, 0), [192, 14]); // 188 <= 255 - 64: no halving
    assert_eq!(frame(0, 10), [96, 17]); // 192 > 191: halved to (96, 7), then + (0, 10)
}
