//! # sndt-core: a fixed-memory semantic occupancy-NDT map
//!
//! `#![no_std]`, no `alloc`, no `unsafe`. A [`Map`] is one value whose size is its whole
//! memory: capacities are const generics, nothing allocates, and no input makes it panic.
//! It implements the semantic occupancy NDT map (S-NDT) of Seichter et al. (ICRA 2022):
//! every surface voxel holds a Gaussian of its points and a class histogram, every observed
//! voxel an occupancy value, and free space comes from ray casting.
//!
//! ## Layers
//!
//! * **Map** ([`Map`], `map.rs`): two fixed-capacity hash tables with stable slots and
//!   deterministic eviction. The *occupancy layer* stores fixed-point log-odds of every
//!   observed voxel, free or occupied, in 4x4x4 blocks (`BLOCKS` capacity, 2.9 bytes per
//!   voxel); the *surface layer* stores NDT voxels (`VOXELS` capacity, 96 bytes each with 40
//!   classes). [`Map::BYTES`] is the exact `size_of` formula.
//! * **Voxel statistics** (`voxel.rs`): integer-quantised sums `n, S1, S2` (exact, so the map
//!   does not depend on point order), the [`Gaussian`] they define with an eigenvalue floor,
//!   the point cap `n_max` with decay, and the `u8` class histogram.
//! * **Integration** (`integrate.rs`): [`Map::integrate`] folds one frame of labelled points
//!   (or [`Map::integrate_depth`] a depth image with labels) into the map and returns a
//!   [`FrameReport`]; free space by exact 3-D DDA to the frame's unique end voxels, with
//!   NDT-OM likelihood-weighted misses ([`MissModel`]).
//! * **Ray casting and rendering** (`raycast.rs`): [`Map::raycast`] returns the first
//!   occupied Gaussian a ray enters; [`Map::render`] renders a label/depth image from a pose
//!   (back-projection for evaluation, or "what the robot should see").
//! * **Snapshot** (`snapshot.rs`): [`Map::write_snapshot`] / [`Map::read_snapshot`], a
//!   versioned little-endian image with CRC-32 in a caller's buffer.
//!
//! ## Example
//!
//! ```
//! use sndt_core::{Config, Isometry3, LabeledPoint, Labels, Map, Occupancy, Point3, Vector3};
//!
//! // 4096 surface voxels, 1024 occupancy blocks, 40 classes: a `static` on an MCU.
//! let mut map: Map<4096, 1024, 40> = Map::new(Config::DEFAULT);
//! // A 1 m x 1 m wall of class 1 ("wall"), 2 m in front of a sensor at the origin.
//! let mut points = [LabeledPoint::new(Point3::origin(), Labels::top1(1)); 400];
//! for (i, p) in points.iter_mut().enumerate() {
//!     let (u, v) = ((i % 20) as f32 / 20.0 - 0.5, (i / 20) as f32 / 20.0 - 0.5);
//!     p.position = Point3::new(u, v, 2.02);
//! }
//! let report = map.integrate(&Isometry3::identity(), &points).unwrap();
//! assert_eq!(report.points_used, 400);
//!
//! let wall = map.voxel_key(&[0.05, 0.05, 2.02]).unwrap();
//! assert_eq!(map.occupancy(&wall), Occupancy::Occupied);
//! assert_eq!(map.class(&wall).unwrap().0, 1);
//! let between = map.voxel_key(&[0.05, 0.05, 1.0]).unwrap();
//! assert_eq!(map.occupancy(&between), Occupancy::Free);
//!
//! let hit = map.raycast(&Point3::new(0.05, 0.05, 0.0), &Vector3::z(), 5.0).unwrap();
//! assert!((hit.t - 2.02).abs() < 0.05 && hit.class == 1);
//! ```
#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

mod block;
mod config;
mod crc;
mod dda;
mod integrate;
mod key;
mod map;
mod raycast;
mod snapshot;
mod table;
mod voxel;

#[cfg(test)]
mod tests;

pub use config::{Config, MissModel, LOGODDS_ONE};
pub use integrate::{
    next_vote_exponent, pose_from_matrix, takes_vote, vote_hash, voxels_on_segment, DepthImage,
    DepthKind, FrameReport, LabelImage, Pinhole, MAX_VOTE_EXPONENT,
};
pub use key::{VoxelKey, KEY_LIMIT};
pub use map::{Map, MapStats, Occupancy, VoxelView, BLOCK_BYTES, MAP_HEADER_BYTES};
pub use nalgebra::{Isometry3, Matrix3, Point3, Translation3, UnitQuaternion, Vector3};
pub use raycast::{RayHit, INVALID_LABEL};
pub use snapshot::{SNAPSHOT_BLOCK_BYTES, SNAPSHOT_HEADER_BYTES, SNAPSHOT_VERSION};
pub use voxel::Gaussian;

/// Most labels a point can carry (top-k with k <= 3).
pub const MAX_TOP_K: usize = 3;

/// Most points one frame may hold. With `quant_bits <= 6` and `n_max <= 65535` this bounds a
/// voxel's count at `65535 + 2^20`, so `|S2| <= 2^10 (65535 + 2^20) < 2^31`: no overflow.
pub const MAX_FRAME_POINTS: usize = 1 << 20;

/// Everything that can go wrong. Small and `Copy`; bad input never panics and never loses
/// what is already in the map.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// A [`Config`] field is out of its documented range.
    InvalidConfig,
    /// The sensor pose has a non-finite value or a rotation that is not orthonormal.
    InvalidPose,
    /// The sensor origin lies outside the key range.
    PoseOutOfRange,
    /// More than [`MAX_FRAME_POINTS`] points in one frame.
    FrameTooLarge,
    /// Depth/label image sizes disagree with the camera, or the camera is invalid.
    InvalidImage,
    /// The caller's buffer is too small.
    BufferTooSmall,
    /// Snapshot: too short, or its length disagrees with its header.
    SnapshotTruncated,
    /// Snapshot: wrong magic bytes.
    SnapshotMagic,
    /// Snapshot: a version this build cannot read.
    SnapshotVersion,
    /// Snapshot: class count differs from the map's `CLASSES`.
    SnapshotClasses,
    /// Snapshot: more voxels or blocks than this map's capacity.
    SnapshotCapacity,
    /// Snapshot: CRC-32 mismatch.
    SnapshotChecksum,
    /// Snapshot: CRC matches but the content breaks an invariant.
    SnapshotCorrupt,
}

/// Top-k labels of one point: NYU40-style class ids `1..=CLASSES` (0 = void, which adds
/// geometry but no vote) with optional scores (0..=255, 255 when unknown).
///
/// ```
/// use sndt_core::Labels;
/// let l = Labels::top_k(&[(5, 200), (7, 40)]);
/// assert_eq!(l.len, 2);
/// assert_eq!(Labels::top1(3).classes[0], 3);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Labels {
    /// Class ids, best first.
    pub classes: [u8; MAX_TOP_K],
    /// Scores, best first.
    pub scores: [u8; MAX_TOP_K],
    /// How many entries are used (0..=3).
    pub len: u8,
}

impl Labels {
    /// No label: the point adds geometry only.
    pub const NONE: Labels = Labels {
        classes: [0; MAX_TOP_K],
        scores: [0; MAX_TOP_K],
        len: 0,
    };

    /// One label with full score.
    pub const fn top1(class: u8) -> Labels {
        Labels {
            classes: [class, 0, 0],
            scores: [255, 0, 0],
            len: 1,
        }
    }

    /// Up to three `(class, score)` pairs, best first; extra pairs are ignored.
    pub fn top_k(pairs: &[(u8, u8)]) -> Labels {
        let mut l = Labels::NONE;
        for (i, &(c, s)) in pairs.iter().take(MAX_TOP_K).enumerate() {
            l.classes[i] = c;
            l.scores[i] = s;
            l.len = i as u8 + 1;
        }
        l
    }
}

/// A point in the sensor frame (metres) with its labels.
///
/// ```
/// use sndt_core::{LabeledPoint, Labels, Point3};
/// let p = LabeledPoint::new(Point3::new(0.0, 0.0, 1.5), Labels::top1(2));
/// assert_eq!(p.labels.classes[0], 2);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LabeledPoint {
    /// Position in the sensor frame, metres.
    pub position: Point3<f32>,
    /// Segmentation labels.
    pub labels: Labels,
}

impl LabeledPoint {
    /// A labelled point.
    pub const fn new(position: Point3<f32>, labels: Labels) -> Self {
        LabeledPoint { position, labels }
    }
}
