//! A voxel's Gaussian: mean and covariance in metres, and its inverse prepared for ray
//! tests with an eigenvalue floor (so flat and degenerate voxels stay invertible).

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
        if let Some(g) = self.entries[i] {
            if self.tags[i] == tag {
                return g;
            }
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

/// Absolute eigenvalue floor for degenerate voxels: `(h / 1000)^2`, so a voxel whose
/// points coincide still has an invertible covariance.
pub(crate) fn floor_abs(h: f32) -> f32 {
    (h * 1e-3) * (h * 1e-3)
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
