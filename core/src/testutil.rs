//! Helpers shared by the unit tests of several modules.

// f64 reference formulas read best with explicit indices.
#![allow(clippy::needless_range_loop)]

extern crate std;

use crate::crc::crc32;
use crate::storage::map::Map;
use crate::storage::voxel::Voxel;
use crate::*;
use std::vec::Vec;

pub(crate) fn lp(x: f32, y: f32, z: f32, class: u8) -> LabeledPoint {
    LabeledPoint::new(Point3::new(x, y, z), Labels::top1(class))
}

pub(crate) fn at(x: f32, y: f32, z: f32) -> Isometry3<f32> {
    Isometry3::translation(x, y, z)
}

pub(crate) fn key(x: i16, y: i16, z: i16) -> VoxelKey {
    VoxelKey { x, y, z }
}

/// Fixed-point log-odds of a cell (exact: the map stores `i16 / LOGODDS_ONE`).
pub(crate) fn fixed<const V: usize, const B: usize, const C: usize>(
    m: &Map<V, B, C>,
    k: &VoxelKey,
) -> i32 {
    let l = m.log_odds(k) * LOGODDS_ONE;
    assert_eq!(l, libm::roundf(l), "log-odds must be a multiple of 1/1024");
    l as i32
}

/// The stored voxel record of `k`.
pub(crate) fn voxel<const V: usize, const B: usize, const C: usize>(
    m: &Map<V, B, C>,
    k: &VoxelKey,
) -> Voxel<C> {
    let s = m.voxels.find(k.packed()).expect("voxel present");
    m.voxels.slots[s]
}

pub(crate) fn snapshot<const V: usize, const B: usize, const C: usize>(
    m: &Map<V, B, C>,
) -> Vec<u8> {
    let mut buf = std::vec![0u8; m.snapshot_len()];
    assert_eq!(m.write_snapshot(&mut buf), Ok(buf.len()));
    buf
}

/// Recomputes the trailing CRC after patching a snapshot.
pub(crate) fn fix_crc(buf: &mut [u8]) {
    let body = buf.len() - 4;
    let crc = crc32(&buf[..body]);
    buf[body..].copy_from_slice(&crc.to_le_bytes());
}

/// Deterministic pseudo-random numbers in [0, 1).
pub(crate) struct Lcg(pub(crate) u64);

impl Lcg {
    pub(crate) fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

pub(crate) fn rel_close(got: f64, want: f64, rel: f64, abs: f64) -> bool {
    (got - want).abs() <= rel * want.abs() + abs
}

/// `n1` points of class 1 then `n2` of class 2 at distinct positions inside voxel
/// (0, 0, 10) of a 10 cm map, drawn from `rng`.
pub(crate) fn voxel_cloud(rng: &mut Lcg, n1: usize, n2: usize) -> Vec<LabeledPoint> {
    let mut c = || 0.002 + 0.096 * rng.next() as f32;
    (0..n1 + n2)
        .map(|i| lp(c(), c(), 1.0 + c(), if i < n1 { 1 } else { 2 }))
        .collect()
}

/// f64 mean (metres) and covariance (m^2) of quantised offsets in voxel `k`.
pub(crate) fn gaussian_f64(
    qs: &[[i32; 3]],
    k: &VoxelKey,
    h: f64,
    step: f64,
) -> ([f64; 3], [[f64; 3]; 3]) {
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

pub(crate) fn assert_gaussian_exact(g: &Gaussian, mean: [f64; 3], cov: [[f64; 3]; 3]) {
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
