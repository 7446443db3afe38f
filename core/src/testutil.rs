//! Helpers shared by the unit tests of several modules.

// f64 reference formulas read best with explicit indices.
#![allow(clippy::needless_range_loop)]

extern crate std;

use crate::crc::crc32;
use crate::storage::map::Map;
use crate::storage::voxel::Voxel;
use crate::*;
use std::boxed::Box;
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

/// A furnished room 6 m x 5 m x 2.8 m as axis-aligned boxes `(min, max, class)`: floor,
/// ceiling, four walls, then the furniture.
const ROOM: [([f32; 3], [f32; 3], u8); 14] = [
    ([-0.1, -0.1, -0.1], [6.1, 5.1, 0.0], 2),
    ([-0.1, -0.1, 2.8], [6.1, 5.1, 2.9], 22),
    ([-0.1, -0.1, 0.0], [0.0, 5.1, 2.8], 1),
    ([6.0, -0.1, 0.0], [6.1, 5.1, 2.8], 1),
    ([0.0, -0.1, 0.0], [6.0, 0.0, 2.8], 1),
    ([0.0, 5.0, 0.0], [6.0, 5.1, 2.8], 1),
    ([0.3, 0.3, 0.0], [2.3, 1.9, 0.55], 4),
    ([3.5, 2.0, 0.72], [4.7, 2.8, 0.76], 7),
    ([3.55, 2.05, 0.0], [3.6, 2.1, 0.72], 7),
    ([4.6, 2.7, 0.0], [4.65, 2.75, 0.72], 7),
    ([5.6, 1.0, 0.0], [6.0, 2.2, 1.8], 15),
    ([5.5, 1.1, 1.0], [5.6, 1.6, 1.25], 23),
    ([2.0, 4.98, 1.2], [3.2, 5.0, 1.9], 11),
    ([0.5, 4.4, 0.0], [0.8, 4.7, 1.5], 35),
];

/// Where the ray from `o` along `d` first meets a box of [`ROOM`]: the ray parameter and
/// the box's class.
fn cast_room(o: &Vector3<f32>, d: &Vector3<f32>) -> Option<(f32, u8)> {
    let mut best: Option<(f32, u8)> = None;
    for (lo, hi, label) in ROOM {
        let (mut t0, mut t1) = (0.0f32, f32::INFINITY);
        let mut hit = true;
        for a in 0..3 {
            if d[a].abs() < 1e-12 {
                if o[a] < lo[a] || o[a] > hi[a] {
                    hit = false;
                    break;
                }
                continue;
            }
            let (mut ta, mut tb) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
            if ta > tb {
                core::mem::swap(&mut ta, &mut tb);
            }
            t0 = t0.max(ta);
            t1 = t1.min(tb);
            if t0 > t1 {
                hit = false;
                break;
            }
        }
        if hit && best.is_none_or(|(t, _)| t0 < t) {
            best = Some((t0, label));
        }
    }
    best
}

/// The camera pose at `eye` looking at `target`, image rows pointing down (towards -z).
pub(crate) fn look_at(eye: [f32; 3], target: [f32; 3]) -> Isometry3<f32> {
    let e = Vector3::from(eye);
    let f = (Vector3::from(target) - e).normalize();
    let right = f.cross(&Vector3::z()).normalize();
    let down = f.cross(&right);
    let m = Matrix3::from_columns(&[right, down, f]);
    Isometry3::from_parts(Translation3::from(e), UnitQuaternion::from_matrix(&m))
}

/// `n` camera poses on a loop inside [`ROOM`], each looking across the room.
pub(crate) fn orbit(n: usize) -> Vec<Isometry3<f32>> {
    (0..n)
        .map(|i| {
            let a = i as f32 / n as f32 * core::f32::consts::TAU;
            let eye = [3.0 + 1.2 * libm::cosf(a), 2.5 + libm::sinf(a), 1.5];
            let target = [
                3.0 - 2.5 * libm::cosf(a + 0.6),
                2.5 - 2.0 * libm::sinf(a + 0.6),
                0.9,
            ];
            look_at(eye, target)
        })
        .collect()
}

/// Hypersim's field of view at 1/8 of its resolution.
pub(crate) const CAM: Pinhole = Pinhole {
    fx: 886.81 / 8.0,
    fy: 886.81 / 8.0,
    cx: 64.0,
    cy: 48.0,
    width: 128,
    height: 96,
};

/// The exact planar depth (metres, 0 where no box is hit) and label image of [`ROOM`]
/// seen by `cam` from `pose`.
pub(crate) fn room_frame(pose: &Isometry3<f32>, cam: &Pinhole) -> (Vec<f32>, Vec<u8>) {
    let n = (cam.width * cam.height) as usize;
    let (mut depth, mut labels) = (std::vec![0f32; n], std::vec![0u8; n]);
    for i in 0..n {
        let r = cam.ray(i as u32 % cam.width, i as u32 / cam.width);
        let d_cam = Vector3::new(r[0], r[1], r[2]);
        let norm = d_cam.norm();
        let d = pose.rotation * (d_cam / norm);
        if let Some((t, l)) = cast_room(&pose.translation.vector, &d) {
            depth[i] = t / norm;
            labels[i] = l;
        }
    }
    (depth, labels)
}

/// A map with room for all of [`ROOM`] at the cell sizes the tests use.
pub(crate) type RoomMap = Map<{ 1 << 16 }, { 1 << 15 }, 40>;

/// Runs `f` on a thread with room for building big maps in debug builds.
pub(crate) fn big_stack(f: impl FnOnce() + Send + 'static) {
    std::thread::Builder::new()
        .stack_size(256 << 20)
        .spawn(f)
        .unwrap()
        .join()
        .unwrap_or_else(|e| std::panic::resume_unwind(e));
}

/// [`ROOM`] integrated from the first `frames` poses of [`orbit`] at cell size `cell`.
pub(crate) fn room_map(cell: f32, frames: usize) -> Box<RoomMap> {
    let mut map = Box::new(RoomMap::new(Config::with_cell_size(cell)));
    for pose in orbit(frames) {
        let (depth, labels) = room_frame(&pose, &CAM);
        let img = DepthImage {
            camera: CAM,
            depth: Depth::Metres(&depth),
            kind: DepthKind::Planar,
            labels: LabelImage::Top1(&labels),
            stride: 1,
        };
        let r = map.integrate_depth(&pose, &img).unwrap();
        assert_eq!(r.dropped_points + r.voxels_evicted, 0, "test map too small");
    }
    map
}
