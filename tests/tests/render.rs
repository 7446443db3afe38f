//! The renderer on the demo's scene: `Map::render` (every Gaussian drawn over the pixels it
//! covers) against one `Map::raycast` per pixel (the walk the renderer replaced, which
//! examines the neighbourhood of every voxel on the ray), and the host's banded, parallel
//! back-projection against one single-threaded render.

use sndt_core::{Config, Map, Pinhole, Point3, Vector3, INVALID_LABEL};
use sndt_host::dataset::source::Every;
use sndt_host::dataset::synthetic::{SynthOptions, Synthetic};
use sndt_host::dataset::{Dataset, Frame, LabelSource, Rays};
use sndt_host::mapping::{backproject, boxed_map, integrate_frame, HostMap};

/// The demo's first trajectory (living room, every 5th frame of a 100-frame walk, full
/// 1024x768 frames) mapped with ground-truth labels at `cell`; returns the map and the
/// frames.
fn demo_map(cell: f32) -> (Box<HostMap>, Vec<Frame>) {
    let walk = Synthetic::new(SynthOptions {
        scenes: 1,
        frames: 100,
        ..SynthOptions::default()
    })
    .unwrap();
    let split = Every::new(Box::new(walk), 5);
    let ids = split.trajectories()[0].1.clone();
    let mut map = boxed_map(Config::with_cell_size(cell)).unwrap();
    let frames: Vec<Frame> = ids.iter().map(|id| split.load(id).unwrap()).collect();
    for f in &frames {
        let r = integrate_frame(map.as_mut(), f, LabelSource::Gt, 1).unwrap();
        assert_eq!(r.voxels_evicted, 0);
    }
    (map, frames)
}

fn pinhole(frame: &Frame) -> Pinhole {
    match frame.rays.as_ref() {
        Rays::Pinhole(cam) => *cam,
        Rays::PerPixel { .. } => panic!("the synthetic camera is a pinhole"),
    }
}

/// The pixels the per-pixel rays check: those with `(x + y) % 3 == 0`, a third of the
/// image. Every row and every column has them, at every offset within a render tile, so a
/// fault confined to some rows, columns or tile positions still shows; casting every pixel
/// made this the test suite's longest test.
fn sampled(cam: &Pinhole) -> Vec<usize> {
    let w = cam.width as usize;
    (0..w * cam.height as usize)
        .filter(|p| (p % w + p / w).is_multiple_of(3))
        .collect()
}

/// One `raycast` along the render's ray (camera ray rotated, not normalised) for each pixel
/// of `pixels`, split over two threads: (label, distance) per pixel, in their order.
fn raycast_pixels<const V: usize, const B: usize, const C: usize>(
    map: &Map<V, B, C>,
    frame: &Frame,
    pixels: &[usize],
) -> Vec<(u8, f32)> {
    let cam = pinhole(frame);
    let w = cam.width as usize;
    let origin = Point3::from(frame.pose.translation.vector);
    let rot = frame.pose.rotation.to_rotation_matrix();
    let mut out = vec![(0u8, 0f32); pixels.len()];
    let half = pixels.len().div_ceil(2);
    std::thread::scope(|s| {
        for (ps, os) in pixels.chunks(half).zip(out.chunks_mut(half)) {
            s.spawn(move || {
                for (&p, o) in ps.iter().zip(os.iter_mut()) {
                    let r = cam.ray((p % w) as u32, (p / w) as u32);
                    let dir = rot * Vector3::new(r[0], r[1], r[2]);
                    let hit = map.raycast(&origin, &dir, map.config().max_range);
                    *o = hit.map_or((INVALID_LABEL, 0.0), |h| (h.class, h.t));
                }
            });
        }
    });
    out
}

/// At 10 cm (the demo's cell) on frames a quarter and three quarters into the walk, and
/// at 5 cm half way, over the sampled pixels: at least 99.9% get the per-pixel ray's
/// label, and where both hit the distances differ by at most 1 mm. (The two agree bit for
/// bit on these frames today; the bound is what a change of arithmetic may use.)
#[test]
fn render_gives_what_a_raycast_per_pixel_gives() {
    for (cell, which) in [(0.10f32, &[5usize, 15][..]), (0.05, &[10][..])] {
        let (map, frames) = demo_map(cell);
        for frame in which.iter().map(|&i| &frames[i]) {
            let cam = pinhole(frame);
            let n = (cam.width * cam.height) as usize;
            let (mut labels, mut dist) = (vec![0u8; n], vec![0f32; n]);
            map.render(&frame.pose, &cam, &mut labels, &mut dist)
                .unwrap();
            let pixels = sampled(&cam);
            let want = raycast_pixels(map.as_ref(), frame, &pixels);
            let m = pixels.len();
            let same = pixels
                .iter()
                .zip(&want)
                .filter(|&(&p, w)| labels[p] == w.0)
                .count();
            let identical = pixels
                .iter()
                .zip(&want)
                .filter(|&(&p, w)| labels[p] == w.0 && dist[p].to_bits() == w.1.to_bits())
                .count();
            let hits = want.iter().filter(|w| w.0 != INVALID_LABEL).count();
            println!(
                "{cell} m, {}: {same} of {m} sampled labels, {identical} identical",
                frame.id
            );
            assert!(m * 3 >= n, "{m} of {n} pixels sampled");
            assert!(hits > m * 9 / 10, "{}: only {hits} hits", frame.id);
            assert!(same * 1000 >= m * 999, "{}: {same} of {m} labels", frame.id);
            for (&p, &(l, d)) in pixels.iter().zip(&want) {
                if labels[p] != INVALID_LABEL && l != INVALID_LABEL {
                    let e = (dist[p] - d).abs();
                    assert!(e <= 1e-3, "{} pixel {p}: {} vs {d}", frame.id, dist[p]);
                }
            }
        }
    }
}

/// The evaluation's back-projection (bands of rows on rayon's threads, `render_rows`) is
/// the single-threaded `render` pixel for pixel, whatever the number of threads.
#[test]
fn banded_parallel_backprojection_is_the_single_render() {
    let (map, frames) = demo_map(0.10);
    let frame = &frames[7];
    let cam = pinhole(frame);
    let n = (cam.width * cam.height) as usize;
    let (mut labels, mut dist) = (vec![0u8; n], vec![0f32; n]);
    map.render(&frame.pose, &cam, &mut labels, &mut dist)
        .unwrap();
    for threads in [1, 3, 7] {
        let pool = rayon_pool(threads);
        let banded = pool.install(|| backproject(map.as_ref(), frame).unwrap());
        assert!(banded == labels, "{threads} threads");
    }
    assert!(labels.iter().filter(|&&l| l != INVALID_LABEL).count() > n * 9 / 10);
}

fn rayon_pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}
