//! # sndt-core: a fixed-memory semantic occupancy-NDT map
//!
//! `#![no_std]`, no `alloc`, no `unsafe`. A [`Map`] is one value whose size is its whole
//! memory: capacities are const generics, nothing allocates, and no input makes it panic.
//! It implements the semantic occupancy NDT map (S-NDT) of Seichter et al. (ICRA 2022):
//! every surface voxel holds a Gaussian of its points and a class histogram, every observed
//! voxel an occupancy value, and free space comes from ray casting.
//!
//! ## The map
//!
//! Two fixed-capacity hash tables with stable slots and deterministic eviction. The
//! *occupancy layer* stores fixed-point log-odds of every observed voxel, free or occupied,
//! in 4x4x4 blocks (`BLOCKS` capacity, 2.8 bytes per voxel); the *surface layer* stores NDT
//! voxels (`VOXELS` capacity, 96 bytes each with 40 classes): integer-quantised point sums
//! `n, S1, S2` (exact, so the map does not depend on point order), which define a
//! [`Gaussian`], and a `u8` class histogram. [`Map::BYTES`] is the exact `size_of` formula.
//!
//! [`Map::integrate`] folds one frame of labelled points (or [`Map::integrate_depth`] a
//! depth image with labels) into the map and returns a [`FrameReport`]; free space comes
//! from exact 3-D DDA to the frame's unique end voxels, with NDT-OM likelihood-weighted
//! misses ([`MissModel`]). [`Map::raycast`] returns the first occupied Gaussian a ray
//! enters; [`Map::render`] renders a label/distance image from a pose (the same answer per
//! pixel, by drawing each visible Gaussian over the pixels it covers). [`Map::write_snapshot`]
//! and [`Map::read_snapshot`] keep a versioned little-endian image with a CRC-32 in a
//! caller's buffer.
//!
//! ## Modules, in dependency order
//!
//! Each module uses only modules above it (the unit tests at the end of a module may use
//! anything). Methods of [`Map`] are spread over the modules of their concern, and calls
//! between them point up this list too. The folders say what a module is for: `geometry/`
//! the numerics the others share, `storage/` what the map holds and its snapshot image,
//! `integrate/` the stages a frame passes through (one file per [`Phase`], then the entry
//! points in `integrate/mod.rs`), and `readout/` what is read back out along rays. A new
//! stage of a frame goes in `integrate/`, a new way to read the map in `readout/`, and a
//! change to what is stored or its format in `storage/`.
//!
//! | module | what it holds |
//! |---|---|
//! | `error`, `labels` | [`Error`] and the [`ConfigField`] it names; a point's top-k [`Labels`] and [`LabeledPoint`] |
//! | `key` | [`VoxelKey`], packed table keys, the block and cell of a packed key, and the hash that orders them |
//! | `config`, `crc` | [`Config`]; CRC-32 |
//! | `geometry::{sqrt, dda, gaussian, camera}` | the square root; the 3-D DDA voxel walk and [`voxels_on_segment`]; [`Gaussian`], its prepared inverse with the eigenvalue floor; [`Pinhole`], depth images, [`depth_point`], pose checks |
//! | `storage::table` | the fixed-capacity hash table with stable slots |
//! | `storage::{block, voxel, votes}` | occupancy blocks; surface voxels: sums, decay, histogram; vote sampling of the histogram |
//! | `storage::record` | one block or voxel as its snapshot record ([`Record`]), the [`RecordSink`] eviction hands them to |
//! | `storage::{map, snapshot}` | the [`Map`] struct and its queries; snapshots and their [`SnapshotHeader`] |
//! | `storage::{merge, stream}` | [`Map::merge`] and [`Map::merge_record`]; the COBS-framed record stream for a byte link ([`StreamWriter`], [`StreamReader`]) |
//! | `integrate::{evict, frame}` | eviction of far entries when a table is full; the state of one frame being integrated, [`FrameReport`], [`Phase`], [`Vectors`] |
//! | `integrate::{points, accumulate_point, accumulate}` | phase 1 in batches of 64 points: [`Phase::Points`] (pixels to world points, keys and offsets in vectorisable loops), then [`Phase::Accumulate`] (into voxel sums and votes; one point at a time in `accumulate_point`, which also holds the voxel lookup and accumulators) |
//! | `integrate::{end_voxels, free_space}` | [`Phase::EndVoxels`] (one update per touched voxel); [`Phase::FreeSpace`] (rays, NDT-OM misses) |
//! | `integrate` | [`Map::integrate`] and [`Map::integrate_depth`] as their steps |
//! | `readout::{raycast, splat, render}` | [`Map::raycast`] and the ray-ellipsoid test; an ellipsoid's pixel footprint; [`Map::render`] (each visible Gaussian drawn over its footprint) |
//!
//! Integer formats, the snapshot layout and eviction are described in more depth in
//! `docs/FORMATS.md`.
//!
//! ## Features
//!
//! Both off by default; neither changes a result.
//!
//! - `defmt`: `defmt::Format` for the public types (firmware logging).
//! - `std`: the square root of the hot loops from std, which the compiler vectorises
//!   (`libm`'s is scalar); rendering is several times faster on a host with it.
//!
//! ## Vector instructions
//!
//! The core has no CPU-specific code: the compiler vectorises its loops for whatever the
//! build targets. On 64-bit targets the frame update is `#[inline(always)]` down its hot
//! path, so that a caller's function compiled with
//! `#[target_feature(enable = "avx2")]` gets the whole update with AVX2; the `sndt-dispatch`
//! crate does this behind a run-time CPU check, and tells the update through [`Vectors`].
//! Every build and every [`Vectors`] give the same map bits. 32-bit targets keep the
//! compiler's own inlining (flash is scarce there).
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

// The `std` feature only switches the square root to std's (see `geometry/sqrt.rs`).
#[cfg(feature = "std")]
extern crate std;

// In dependency order (see the table above).
mod error;
mod labels;

mod key;

mod config;
mod crc;

mod geometry;

mod storage;

mod integrate;

mod readout;

#[cfg(test)]
mod testutil;

pub use config::{Config, MissModel, LOGODDS_ONE};
pub use crc::Crc32;
pub use error::{ConfigField, Error};
pub use geometry::camera::{
    depth_point, pose_from_matrix, validate_pose, Depth, DepthImage, DepthKind, LabelImage, Pinhole,
};
pub use geometry::dda::voxels_on_segment;
pub use geometry::gaussian::Gaussian;
pub use integrate::frame::{FrameReport, Phase, Vectors, MAX_FRAME_POINTS};
pub use key::{VoxelKey, KEY_LIMIT};
pub use labels::{LabeledPoint, Labels, MAX_TOP_K};
pub use nalgebra::{Isometry3, Matrix3, Point3, Quaternion, Translation3, UnitQuaternion, Vector3};
pub use readout::raycast::RayHit;
pub use readout::render::INVALID_LABEL;
pub use storage::map::{
    Map, MapStats, Occupancy, VoxelView, BLOCK_BYTES, BLOCK_TABLE_BYTES, MAP_HEADER_BYTES,
};
pub use storage::merge::RecordCount;
pub use storage::record::{Record, RecordKind, RecordSink, BLOCK_RECORD_BYTES};
pub use storage::snapshot::{
    SnapshotHeader, SNAPSHOT_BLOCK_BYTES, SNAPSHOT_HEADER_BYTES, SNAPSHOT_VERSION,
};
pub use storage::stream::{StreamEnd, StreamItem, StreamReader, StreamWriter, STREAM_FRAME_BYTES};
pub use storage::votes::{next_vote_exponent, takes_vote, vote_hash, MAX_VOTE_EXPONENT};
