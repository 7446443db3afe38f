//! What the update benches share: a frame as the core's depth image, and one timed pass.

use sndt_core::{Depth, DepthImage, LabelImage};
use sndt_dispatch::Level;
use sndt_host::dataset::frame::{Frame, Rays};
use sndt_host::mapping::HostMap;
use std::time::Instant;

/// The frame as the core's depth image: every pixel, ground-truth labels.
pub fn image(frame: &Frame) -> DepthImage<'_> {
    let Rays::Pinhole(camera) = frame.rays.as_ref() else {
        panic!("{}: the benchmark needs a pinhole camera", frame.id);
    };
    DepthImage {
        camera: *camera,
        depth: Depth::Metres(&frame.depth),
        kind: frame.depth_kind,
        labels: LabelImage::Top1(frame.labels.as_deref().expect("ground-truth labels")),
        stride: 1,
    }
}

/// The level the update runs at (`sndt-dispatch`): the CPU's fastest, or lower if the
/// environment's `SNDT_LEVEL` says so (`baseline`, `avx2`, `avx512`), to time what a CPU
/// without AVX-512 or AVX2 would run.
pub fn level() -> Level {
    let cap = match std::env::var("SNDT_LEVEL").as_deref() {
        Ok("baseline") => Level::Baseline,
        Ok("avx2") => Level::Avx2,
        Ok("avx512") | Err(_) => Level::Avx512,
        Ok(other) => panic!("SNDT_LEVEL={other}: baseline, avx2 or avx512"),
    };
    cap.min(sndt_dispatch::level())
}

/// Integrates every frame; the time of each in ms. Panics if the map dropped or evicted
/// anything (the benchmark would then time a smaller map).
pub fn integrate_all(map: &mut HostMap, frames: &[Frame]) -> Vec<f64> {
    let level = level();
    frames
        .iter()
        .map(|f| {
            let img = image(f);
            let t = Instant::now();
            let report = sndt_dispatch::integrate_depth_at(level, map, &f.pose, &img, None)
                .expect("frame integrates");
            let ms = t.elapsed().as_secs_f64() * 1e3;
            assert_eq!(
                report.dropped_points + report.voxels_evicted,
                0,
                "bench map too small"
            );
            ms
        })
        .collect()
}

/// A fresh map for `config`, warmed by one pass over `frames` (its memory touched) and
/// reset, then timed over them: the map and the sorted ms per frame.
pub fn warm_timed_pass(config: sndt_core::Config, frames: &[Frame]) -> (Box<HostMap>, Vec<f64>) {
    let mut map: Box<HostMap> = sndt_host::mapping::boxed_map(config).expect("valid config");
    integrate_all(&mut map, frames);
    map.reset(config).expect("valid config");
    let mut ms = integrate_all(&mut map, frames);
    ms.sort_by(f64::total_cmp);
    (map, ms)
}

/// The median of sorted values (the mean of the middle two for an even count).
pub fn median(sorted: &[f64]) -> f64 {
    let n = sorted.len();
    (sorted[(n - 1) / 2] + sorted[n / 2]) / 2.0
}
