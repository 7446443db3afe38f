//! The f64 reference S-NDT: the yardstick for the core's integer statistics.
//!
//! [`RefMap`] implements the S-NDT map in plain `f64` maths with std collections: no
//! quantisation, no fixed-point log-odds, no capacity limit. It is written from the
//! method's description, not by calling `sndt_core`'s update code; it shares only
//! [`Config`](sndt_core::Config) (so both sides use the same parameters), the
//! vote-sampling functions and the voxel-key convention (a world point `p`
//! in `f32`, computed from the sensor point as the core does, lies in voxel
//! `floor(p * (1 / h))`, see [`sndt_core::VoxelKey::from_point`]), so that both maps assign
//! every point to the same voxel and differences measure the core's arithmetic only.
//!
//! A frame runs in the same steps as the core ([`RefMap::integrate`]; step 0, not listed,
//! validates the pose and leaves the map untouched if it is bad):
//!
//! 1. **points**: each valid point is transformed to the world (in `f32`, the key
//!    convention) and added to its voxel's `f64` sums `n`, `S1 = sum (p - c)`,
//!    `S2 = sum (p - c)(p - c)^T` about the voxel centre `c`; its voting labels (top-k,
//!    score at least `min_score`, not void) count if the voxel's sample takes it. Points
//!    beyond `max_range` only mark the voxel of the point where their ray is truncated;
//! 2. **hits**: every voxel that received points gets one hit (`+hit`, clamped), its class
//!    histogram makes room once (all bins halved, exactly, when one exceeds
//!    `255 - votes_per_frame`) and takes the votes of the frame's sample of its voting
//!    points (those whose [`sndt_core::vote_hash`] passes [`sndt_core::takes_vote`] for
//!    the voxel's exponent) saturating at 255, then sets its exponent for the next frame
//!    ([`sndt_core::next_vote_exponent`]), and its count and
//!    sums are scaled down to the point cap (`n` halved, rounding up, until `n <= n_max`;
//!    sums scaled by the same factor);
//! 3. **free space**: one ray per unique end voxel, aimed at the mean of the voxel's points
//!    (kept 1 % of a cell inside the voxel), end voxel excluded, and one per unique
//!    truncated end (aimed at its centre, end included), in the core's order (by 4x4x4
//!    block, then end voxels before truncated ends, then by cell in the block). A traversed
//!    voxel gets at most one miss per frame: the NDT-OM miss with the voxel's
//!    *current* Gaussian (after phases 1 and 2) where it has one (`n >= n_min`), or the
//!    constant miss otherwise. A NDT-OM miss whose closest point lies beyond the ray's end
//!    is skipped and leaves the voxel free for a later ray of the frame.
//!
//! Rendering ([`RenderIndex`]) follows the core's ray casting: an exact DDA walk whose
//! every voxel's 3x3x3 neighbourhood is searched for occupied voxels with a valid Gaussian;
//! the hit is the smallest entry distance into an ellipsoid of Mahalanobis radius
//! `render_radius`.
//!
//! `docs/EVALUATION.md` (the f64 reference and tolerances) says what it shares with the
//! core and how the two are compared ([`crate::eval::compare`]).
//!
//! ```
//! use sndt_host::reference::RefMap;
//! use sndt_core::{Config, Isometry3, LabeledPoint, Labels, Occupancy, Point3};
//! let mut map = RefMap::new(Config::DEFAULT, 40);
//! let points = [
//!     LabeledPoint::new(Point3::new(0.02, 0.03, 1.02), Labels::top1(5)),
//!     LabeledPoint::new(Point3::new(0.07, 0.03, 1.05), Labels::top1(5)),
//!     LabeledPoint::new(Point3::new(0.03, 0.08, 1.04), Labels::top1(5)),
//! ];
//! map.integrate(&Isometry3::identity(), &points).unwrap();
//! let key = [0, 0, 10];
//! assert_eq!(map.occupancy(&key), Occupancy::Occupied);
//! assert_eq!(map.occupancy(&[0, 0, 5]), Occupancy::Free);
//! assert_eq!(map.class(&key), Some((5, 1.0)));
//! let g = map.gaussian(&key).unwrap();
//! assert!((g.mean.x - 0.04).abs() < 1e-7 && g.count == 3.0);
//! ```

pub mod key;
pub mod map;
pub mod render;

pub use key::Key;
pub use map::{RefFrameReport, RefGaussian, RefMap, RefVoxel};
pub use render::{RefHit, RenderIndex};
