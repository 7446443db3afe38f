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
    DepthImage, Error, FrameReport, Isometry3, LabeledPoint, Map, Pinhole, RecordSink, Vectors,
};

/// What a render needs besides its buffers: the pose, the camera and the first row.
type View<'a> = (&'a Isometry3<f32>, &'a Pinhole, u32);

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

/// [`Map::render_rows`] at `level`, which must not exceed [`level`].
pub(crate) fn render_rows<const V: usize, const B: usize, const C: usize>(
    level: Level,
    map: &Map<V, B, C>,
    view: View<'_>,
    labels: &mut [u8],
    distance: &mut [f32],
) -> Result<(), Error> {
    match level {
        // SAFETY: `level` is at most `level()`, so the CPU has these features.
        Level::Avx512 => unsafe { render_avx512(map, view, labels, distance) },
        // SAFETY: as above.
        Level::Avx2 => unsafe { render_avx2(map, view, labels, distance) },
        Level::Baseline => map.render_rows(view.0, view.1, view.2, labels, distance),
    }
}

#[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,popcnt")]
fn render_avx2<const V: usize, const B: usize, const C: usize>(
    map: &Map<V, B, C>,
    (pose, camera, first_row): View<'_>,
    labels: &mut [u8],
    distance: &mut [f32],
) -> Result<(), Error> {
    map.render_rows(pose, camera, first_row, labels, distance)
}

#[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,popcnt")]
#[target_feature(enable = "avx512f,avx512bw,avx512cd,avx512dq,avx512vl")]
fn render_avx512<const V: usize, const B: usize, const C: usize>(
    map: &Map<V, B, C>,
    (pose, camera, first_row): View<'_>,
    labels: &mut [u8],
    distance: &mut [f32],
) -> Result<(), Error> {
    map.render_rows(pose, camera, first_row, labels, distance)
}

#[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,popcnt")]
fn depth_avx2<const V: usize, const B: usize, const C: usize>(
    map: &mut Map<V, B, C>,
    pose: &Isometry3<f32>,
    image: &DepthImage<'_>,
    sink: Option<&mut dyn RecordSink>,
) -> Result<FrameReport, Error> {
    map.integrate_depth_with(pose, image, sink, Vectors::Wide)
}

#[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,popcnt")]
#[target_feature(enable = "avx512f,avx512bw,avx512cd,avx512dq,avx512vl")]
fn depth_avx512<const V: usize, const B: usize, const C: usize>(
    map: &mut Map<V, B, C>,
    pose: &Isometry3<f32>,
    image: &DepthImage<'_>,
    sink: Option<&mut dyn RecordSink>,
) -> Result<FrameReport, Error> {
    map.integrate_depth_with(pose, image, sink, Vectors::Wide)
}

#[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,popcnt")]
fn points_avx2<const V: usize, const B: usize, const C: usize>(
    map: &mut Map<V, B, C>,
    pose: &Isometry3<f32>,
    points: &[LabeledPoint],
    sink: Option<&mut dyn RecordSink>,
) -> Result<FrameReport, Error> {
    map.integrate_with(pose, points, sink, Vectors::Wide)
}

#[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,popcnt")]
#[target_feature(enable = "avx512f,avx512bw,avx512cd,avx512dq,avx512vl")]
fn points_avx512<const V: usize, const B: usize, const C: usize>(
    map: &mut Map<V, B, C>,
    pose: &Isometry3<f32>,
    points: &[LabeledPoint],
    sink: Option<&mut dyn RecordSink>,
) -> Result<FrameReport, Error> {
    map.integrate_with(pose, points, sink, Vectors::Wide)
}
