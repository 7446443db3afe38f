//! Runtime CPU dispatch for `sndt-core`'s map update.
//!
//! `sndt-core` is plain Rust with no `unsafe`: built for baseline x86-64 (what a crate that
//! depends on it gets unless it sets `RUSTFLAGS`), its phase 1 runs on SSE2 and takes about
//! twice as long as a build for the CPU at hand. This crate checks the CPU once and runs
//! each frame's update in a copy of the core's code compiled for what the CPU has:
//!
//! - [`Level::Avx512`]: AVX-512 F, BW, CD, DQ and VL (x86-64-v4), with AVX2 and FMA;
//! - [`Level::Avx2`]: AVX, AVX2, FMA, BMI1, BMI2 and POPCNT (x86-64-v3 without LZCNT, MOVBE
//!   and F16C, which the update does not use);
//! - [`Level::Baseline`]: the code as the crate was built, on any other CPU and on other
//!   architectures.
//!
//! Every level gives the same map bits ([`sndt_core::Vectors`]): the core forms no fused
//! multiply-add, and IEEE operations give the same results in vector and scalar form. The
//! dispatch costs one branch per frame. The `unsafe` it needs, one call per frame into a
//! `#[target_feature]` function after the CPU check, lives in `src/x86.rs`.
//!
//! ```
//! use sndt_core::*;
//! let cam = Pinhole { fx: 4.0, fy: 4.0, cx: 4.0, cy: 3.0, width: 8, height: 6 };
//! let depth = [2.0f32; 48];
//! let img = DepthImage { camera: cam, depth: Depth::Metres(&depth), kind: DepthKind::Planar,
//!                        labels: LabelImage::None, stride: 1 };
//! let mut map: Map<256, 64, 4> = Map::new(Config::DEFAULT);
//! let report = sndt_dispatch::integrate_depth(&mut map, &Isometry3::identity(), &img, None).unwrap();
//! assert_eq!(report.points_used, 48);
//! println!("this CPU runs the update at {:?}", sndt_dispatch::level());
//! ```
#![no_std]

#[cfg(target_arch = "x86_64")]
mod x86;

use sndt_core::{DepthImage, Error, FrameReport, Isometry3, LabeledPoint, Map, Phase, RecordSink};

/// The code a frame's update runs as, from the slowest to the fastest.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Level {
    /// As built: whatever `RUSTFLAGS` (or `.cargo/config.toml`) chose for the crate.
    Baseline,
    /// Compiled with AVX2 and FMA (x86-64 only).
    Avx2,
    /// Compiled with AVX-512 F, BW, CD, DQ and VL as well (x86-64 only).
    Avx512,
}

/// The fastest level this CPU runs (checked once, then cached).
///
/// ```
/// use sndt_dispatch::{level, Level};
/// // Other architectures run the update as built.
/// if !cfg!(target_arch = "x86_64") {
///     assert_eq!(level(), Level::Baseline);
/// }
/// println!("this CPU runs the update at {:?}", level());
/// ```
pub fn level() -> Level {
    #[cfg(target_arch = "x86_64")]
    return x86::level();
    #[cfg(not(target_arch = "x86_64"))]
    Level::Baseline
}

/// [`Map::integrate_depth`] (with a sink, [`Map::integrate_depth_spilling`]) at the
/// fastest [`level`]: the same map and report.
///
/// ```
/// use sndt_core::*;
/// let cam = Pinhole { fx: 4.0, fy: 4.0, cx: 4.0, cy: 3.0, width: 8, height: 6 };
/// let depth = [2.0f32; 48];
/// let img = DepthImage { camera: cam, depth: Depth::Metres(&depth), kind: DepthKind::Planar,
///                        labels: LabelImage::None, stride: 1 };
/// let mut map: Map<256, 64, 4> = Map::new(Config::DEFAULT);
/// sndt_dispatch::integrate_depth(&mut map, &Isometry3::identity(), &img, None).unwrap();
/// assert_eq!(map.stats().frames, 1);
/// ```
pub fn integrate_depth<const V: usize, const B: usize, const C: usize>(
    map: &mut Map<V, B, C>,
    pose: &Isometry3<f32>,
    image: &DepthImage<'_>,
    sink: Option<&mut dyn RecordSink>,
) -> Result<FrameReport, Error> {
    integrate_depth_at(level(), map, pose, image, sink)
}

/// [`integrate_depth`] at `level`, or at the fastest level this CPU runs if that is
/// lower (to compare levels: every one gives the same map).
///
/// ```
/// use sndt_core::*;
/// use sndt_dispatch::{integrate_depth_at, Level};
/// let cam = Pinhole { fx: 4.0, fy: 4.0, cx: 4.0, cy: 3.0, width: 8, height: 6 };
/// let depth = [2.0f32; 48];
/// let img = DepthImage { camera: cam, depth: Depth::Metres(&depth), kind: DepthKind::Planar,
///                        labels: LabelImage::None, stride: 1 };
/// let pose = Isometry3::identity();
/// let mut a: Map<256, 64, 4> = Map::new(Config::DEFAULT);
/// let mut b: Map<256, 64, 4> = Map::new(Config::DEFAULT);
/// integrate_depth_at(Level::Baseline, &mut a, &pose, &img, None).unwrap();
/// integrate_depth_at(Level::Avx512, &mut b, &pose, &img, None).unwrap();
/// assert_eq!(a.checksum(), b.checksum());
/// ```
pub fn integrate_depth_at<const V: usize, const B: usize, const C: usize>(
    level: Level,
    map: &mut Map<V, B, C>,
    pose: &Isometry3<f32>,
    image: &DepthImage<'_>,
    sink: Option<&mut dyn RecordSink>,
) -> Result<FrameReport, Error> {
    #[cfg(target_arch = "x86_64")]
    return x86::integrate_depth(level.min(self::level()), map, pose, image, sink);
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = level;
        map.integrate_depth_with(pose, image, sink, sndt_core::Vectors::AsBuilt)
    }
}

/// [`Map::integrate_depth_observed`] at `level`, or at the fastest level this CPU runs
/// if that is lower: the phases of a frame timed as the dispatched update runs them.
///
/// ```
/// use sndt_core::*;
/// let cam = Pinhole { fx: 4.0, fy: 4.0, cx: 4.0, cy: 3.0, width: 8, height: 6 };
/// let img = DepthImage { camera: cam, depth: Depth::Metres(&[2.0f32; 48]),
///                        kind: DepthKind::Planar, labels: LabelImage::None, stride: 1 };
/// let mut map: Map<256, 64, 4> = Map::new(Config::DEFAULT);
/// let mut seen = Vec::new();
/// let (level, pose) = (sndt_dispatch::level(), Isometry3::identity());
/// sndt_dispatch::integrate_depth_observed_at(level, &mut map, &pose, &img, |p| seen.push(p))
///     .unwrap();
/// assert_eq!(seen.last(), Some(&Phase::Done));
/// ```
pub fn integrate_depth_observed_at<const V: usize, const B: usize, const C: usize>(
    level: Level,
    map: &mut Map<V, B, C>,
    pose: &Isometry3<f32>,
    image: &DepthImage<'_>,
    on_phase: impl FnMut(Phase),
) -> Result<FrameReport, Error> {
    #[cfg(target_arch = "x86_64")]
    return x86::integrate_depth_observed(level.min(self::level()), map, (pose, image), on_phase);
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = level;
        map.integrate_depth_observed(pose, image, on_phase)
    }
}

/// [`Map::integrate`] (with a sink, [`Map::integrate_spilling`]) at the fastest
/// [`level`]: the same map and report.
///
/// ```
/// use sndt_core::*;
/// let mut map: Map<64, 16, 4> = Map::new(Config::DEFAULT);
/// let pts = [LabeledPoint::new(Point3::new(0.0, 0.0, 1.0), Labels::top1(1))];
/// let r = sndt_dispatch::integrate(&mut map, &Isometry3::identity(), &pts, None).unwrap();
/// assert_eq!(r.points_used, 1);
/// ```
pub fn integrate<const V: usize, const B: usize, const C: usize>(
    map: &mut Map<V, B, C>,
    pose: &Isometry3<f32>,
    points: &[LabeledPoint],
    sink: Option<&mut dyn RecordSink>,
) -> Result<FrameReport, Error> {
    integrate_at(level(), map, pose, points, sink)
}

/// [`integrate`] at `level`, or at the fastest level this CPU runs if that is lower.
///
/// ```
/// use sndt_core::*;
/// use sndt_dispatch::{integrate_at, Level};
/// let pts = [LabeledPoint::new(Point3::new(0.2, 0.1, 1.0), Labels::top1(2)); 3];
/// let mut a: Map<64, 16, 4> = Map::new(Config::DEFAULT);
/// let mut b: Map<64, 16, 4> = Map::new(Config::DEFAULT);
/// integrate_at(Level::Baseline, &mut a, &Isometry3::identity(), &pts, None).unwrap();
/// integrate_at(Level::Avx2, &mut b, &Isometry3::identity(), &pts, None).unwrap();
/// assert_eq!(a.checksum(), b.checksum());
/// ```
pub fn integrate_at<const V: usize, const B: usize, const C: usize>(
    level: Level,
    map: &mut Map<V, B, C>,
    pose: &Isometry3<f32>,
    points: &[LabeledPoint],
    sink: Option<&mut dyn RecordSink>,
) -> Result<FrameReport, Error> {
    #[cfg(target_arch = "x86_64")]
    return x86::integrate(level.min(self::level()), map, pose, points, sink);
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = level;
        map.integrate_with(pose, points, sink, sndt_core::Vectors::AsBuilt)
    }
}
