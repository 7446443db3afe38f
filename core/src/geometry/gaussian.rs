//! A voxel's Gaussian: mean and covariance in metres, and its inverse prepared for ray
//! tests with an eigenvalue floor (so flat and degenerate voxels stay invertible).

use crate::geometry::sqrt::sqrt;
use nalgebra::{Matrix3, Vector3};

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

    /// The prepared Gaussian of the voxel in slot `slot`, from `prepare` on a miss.
    #[inline]
    pub(crate) fn get(&mut self, slot: usize, prepare: impl FnOnce() -> Prepared) -> Prepared {
        let i = slot % N;
        let tag = slot as u32 + 1;
        if let Some(g) = self.entries[i]
            && self.tags[i] == tag
        {
            return g;
        }
        let g = prepare();
        self.tags[i] = tag;
        self.entries[i] = Some(g);
        g
    }
}

impl Gaussian {
    /// Inverse covariance with eigenvalues raised to `ratio * lambda_max` (and to `floor_abs`
    /// for a degenerate voxel whose points coincide).
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    pub(crate) fn prepare(&self, ratio: f32, floor_abs: f32) -> Prepared {
        let (vals, vecs) = symmetric_eigen(&self.covariance);
        let lmax = max_f32(max_f32(vals[0], vals[1]), vals[2]);
        let floor = max_f32(lmax * ratio, floor_abs);
        let mut inv = Matrix3::zeros();
        for (i, val) in vals.iter().enumerate() {
            let l = max_f32(*val, floor);
            let v = vecs.column(i);
            inv += v * v.transpose() * (1.0 / l);
        }
        Prepared {
            mean: self.mean,
            inv,
        }
    }
}

/// `x.max(y)` as `libm::fmaxf` computes it: `y` when `x` is NaN or smaller, else `x`.
/// `f32::max` is a library call on a Cortex-M4 (its FPU has no max instruction); this is
/// two comparisons inline.
#[inline(always)]
fn max_f32(x: f32, y: f32) -> f32 {
    if x.is_nan() || x < y {
        y
    } else {
        x
    }
}

/// Absolute eigenvalue floor for degenerate voxels: `(h / 1000)^2`, so a voxel whose
/// points coincide still has an invertible covariance.
pub(crate) fn floor_abs(h: f32) -> f32 {
    (h * 1e-3) * (h * 1e-3)
}

/// Eigenvalues and eigenvectors (columns) of a symmetric 3x3 matrix by cyclic Jacobi
/// rotations. Pure arithmetic plus a correctly rounded square root, so results are
/// bit-identical on every target.
#[cfg_attr(target_pointer_width = "64", inline(always))]
pub(crate) fn symmetric_eigen(m: &Matrix3<f32>) -> ([f32; 3], Matrix3<f32>) {
    let mut a = *m;
    let mut v = Matrix3::<f32>::identity();
    for _sweep in 0..12 {
        let off = a[(0, 1)] * a[(0, 1)] + a[(0, 2)] * a[(0, 2)] + a[(1, 2)] * a[(1, 2)];
        let diag = a[(0, 0)] * a[(0, 0)] + a[(1, 1)] * a[(1, 1)] + a[(2, 2)] * a[(2, 2)];
        if off <= diag * 1e-14 || off == 0.0 {
            break;
        }
        jacobi_rotate::<0, 1>(&mut a, &mut v);
        jacobi_rotate::<0, 2>(&mut a, &mut v);
        jacobi_rotate::<1, 2>(&mut a, &mut v);
    }
    ([a[(0, 0)], a[(1, 1)], a[(2, 2)]], v)
}

/// One Jacobi rotation of [`symmetric_eigen`], zeroing `a[(P, Q)]`. The plane is a const
/// parameter so every index is a constant: no bounds check (and no panic path) remains.
#[inline]
fn jacobi_rotate<const P: usize, const Q: usize>(a: &mut Matrix3<f32>, v: &mut Matrix3<f32>) {
    let (p, q) = (P, Q);
    let apq = a[(p, q)];
    if apq == 0.0 {
        return;
    }
    let theta = (a[(q, q)] - a[(p, p)]) / (2.0 * apq);
    let sign = if theta >= 0.0 { 1.0 } else { -1.0 };
    let t = sign / (theta.abs() + sqrt(theta * theta + 1.0));
    let c = 1.0 / sqrt(t * t + 1.0);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::*;

    /// `max_f32` is `libm::fmaxf` (what `f32::max` called in firmware builds) bit for
    /// bit on every pair of special and ordinary values with at most one NaN, signed
    /// zeros included.
    #[test]
    fn max_f32_is_fmaxf() {
        let values = [
            0.0f32,
            -0.0,
            1e-45,
            -1e-45,
            1.0,
            -1.0,
            2.5e-7,
            3.4e38,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        for &x in &values {
            for &y in &values {
                if x.is_nan() && y.is_nan() {
                    continue;
                }
                assert_eq!(
                    max_f32(x, y).to_bits(),
                    libm::fmaxf(x, y).to_bits(),
                    "max({x}, {y})"
                );
            }
        }
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
}
