//! The x86-64 side: the CPU check and the update compiled per level.
//!
//! Each `*_avx2` / `*_avx512` function is the core's update with those target features
//! enabled: the core's frame integration is `#[inline(always)]` down its hot path, so it
//! is compiled into these functions with the wider vectors. Calling a `#[target_feature]`
//! function is `unsafe` because it would fault on a CPU without the features; [`level`]
//! checks the CPU first, and callers pass no level above it.
#![allow(unsafe_code)]

use crate::Level;
use sndt_core::{
    DepthImage, Error, FrameReport, Isometry3, LabeledPoint, Map, Phase, RecordSink, Vectors,
};

/// A depth frame: its pose and its image.
type DepthFrame<'a, 'i> = (&'a Isometry3<f32>, &'a DepthImage<'i>);

cpufeatures::new!(avx2_cpu, "avx", "avx2", "fma", "bmi1", "bmi2", "popcnt");
cpufeatures::new!(avx512_cpu, "avx512f", "avx512bw", "avx512cd", "avx512dq", "avx512vl");

/// The fastest level this CPU runs (`cpufeatures` caches the check, OS support included).
pub(crate) fn level() -> Level {
    match (avx2_cpu::get(), avx512_cpu::get()) {
        (true, true) => Level::Avx512,
        (true, false) => Level::Avx2,
        _ => Level::Baseline,
    }
}

/// [`Map::integrate_depth_with`] at `level`, which must not exceed [`level`].
pub(crate) fn integrate_depth<const V: usize, const B: usize, const C: usize>(
    level: Level,
    map: &mut Map<V, B, C>,
    pose: &Isometry3<f32>,
    image: &DepthImage<'_>,
    sink: Option<&mut dyn RecordSink>,
) -> Result<FrameReport, Error> {
    match level {
        // SAFETY: `level` is at most `level()`, so the CPU has these features.
        Level::Avx512 => unsafe { depth_avx512(map, pose, image, sink) },
        // SAFETY: as above.
        Level::Avx2 => unsafe { depth_avx2(map, pose, image, sink) },
        Level::Baseline => map.integrate_depth_with(pose, image, sink, Vectors::AsBuilt),
    }
}

/// [`Map::integrate_with`] at `level`, which must not exceed [`level`].
pub(crate) fn integrate<const V: usize, const B: usize, const C: usize>(
    level: Level,
    map: &mut Map<V, B, C>,
    pose: &Isometry3<f32>,
    points: &[LabeledPoint],
    sink: Option<&mut dyn RecordSink>,
) -> Result<FrameReport, Error> {
    match level {
        // SAFETY: `level` is at most `level()`, so the CPU has these features.
        Level::Avx512 => unsafe { points_avx512(map, pose, points, sink) },
        // SAFETY: as above.
        Level::Avx2 => unsafe { points_avx2(map, pose, points, sink) },
        Level::Baseline => map.integrate_with(pose, points, sink, Vectors::AsBuilt),
    }
}

/// [`Map::integrate_depth_observed_with`] at `level`, which must not exceed [`level`].
pub(crate) fn integrate_depth_observed<const V: usize, const B: usize, const C: usize>(
    level: Level,
    map: &mut Map<V, B, C>,
    frame: DepthFrame<'_, '_>,
    on_phase: impl FnMut(Phase),
) -> Result<FrameReport, Error> {
    match level {
        // SAFETY: `level` is at most `level()`, so the CPU has these features.
        Level::Avx512 => unsafe { observed_avx512(map, frame, on_phase) },
        // SAFETY: as above.
        Level::Avx2 => unsafe { observed_avx2(map, frame, on_phase) },
        Level::Baseline => map.integrate_depth_observed(frame.0, frame.1, on_phase),
    }
}

/// Defines `$avx2` and `$avx512`, each `$body` compiled with its level's target features
/// (`V`, `B`, `C` are the map's capacities).
macro_rules! per_level {
    ($avx2:ident, $avx512:ident, ($($arg:ident: $ty:ty),*) $body:block) => {
        #[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,popcnt")]
        fn $avx2<const V: usize, const B: usize, const C: usize>(
            $($arg: $ty),*
        ) -> Result<FrameReport, Error> $body

        #[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,popcnt")]
        #[target_feature(enable = "avx512f,avx512bw,avx512cd,avx512dq,avx512vl")]
        fn $avx512<const V: usize, const B: usize, const C: usize>(
            $($arg: $ty),*
        ) -> Result<FrameReport, Error> $body
    };
}

per_level!(observed_avx2, observed_avx512, (
    map: &mut Map<V, B, C>,
    frame: DepthFrame<'_, '_>,
    on_phase: impl FnMut(Phase)
) {
    map.integrate_depth_observed_with(frame.0, frame.1, on_phase, Vectors::Wide)
});

per_level!(depth_avx2, depth_avx512, (
    map: &mut Map<V, B, C>,
    pose: &Isometry3<f32>,
    image: &DepthImage<'_>,
    sink: Option<&mut dyn RecordSink>
) {
    map.integrate_depth_with(pose, image, sink, Vectors::Wide)
});

per_level!(points_avx2, points_avx512, (
    map: &mut Map<V, B, C>,
    pose: &Isometry3<f32>,
    points: &[LabeledPoint],
    sink: Option<&mut dyn RecordSink>
) {
    map.integrate_with(pose, points, sink, Vectors::Wide)
});
