//! The renderer on the demo's scene: `Map::render` (every Gaussian drawn over the pixels it
//! covers) against one `Map::raycast` per pixel (the walk the renderer replaced, which
//! examines the neighbourhood of every voxel on the ray), and the host's banded, parallel
//! back-projection against one single-threaded render.

use sndt_core::{Config, Map, Pinhole, Point3, Vector3, INVALID_LABEL};
use sndt_host::dataset::source::Every;
use sndt_host::dataset::synthetic::{SynthOptions, Synthetic};
use sndt_host::dataset::{Dataset, Frame, LabelSource, Rays};
use sndt_host::semantic_map::{backproject, boxed_map, integrate_frame, HostMap};

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

/// One `raycast` per pixel along the render's ray (camera ray rotated, not normalised),
/// rows split over two threads.
fn raycast_image<const V: usize, const B: usize, const C: usize>(
    map: &Map<V, B, C>,
    frame: &Frame,
) -> (Vec<u8>, Vec<f32>) {
    let cam = pinhole(frame);
    let w = cam.width as usize;
    let n = w * cam.height as usize;
    let (mut labels, mut dist) = (vec![0u8; n], vec![0f32; n]);
    let origin = Point3::from(frame.pose.translation.vector);
    let rot = frame.pose.rotation.to_rotation_matrix();
    let half = (cam.height as usize).div_ceil(2) * w;
    std::thread::scope(|s| {
        for (k, (ls, ds)) in labels
            .chunks_mut(half)
            .zip(dist.chunks_mut(half))
            .enumerate()
        {
            s.spawn(move || {
                for (i, (l, d)) in ls.iter_mut().zip(ds.iter_mut()).enumerate() {
                    let p = k * half + i;
                    let r = cam.ray((p % w) as u32, (p / w) as u32);
                    let dir = rot * Vector3::new(r[0], r[1], r[2]);
                    let hit = map.raycast(&origin, &dir, map.config().max_range);
                    *l = hit.map_or(INVALID_LABEL, |h| h.class);
                    *d = hit.map_or(0.0, |h| h.t);
                }
            });
        }
    });
    (labels, dist)
}

/// At 10 cm (the demo's cell) on frames a quarter and three quarters into the walk, and
/// at 5 cm half way: at least 99.9% of the pixels get the per-pixel ray's label, and where both
/// hit the distances differ by at most 1 mm. (The two agree bit for bit on these frames
/// today; the bound is what a change of arithmetic may use.)
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
            let (want_l, want_d) = raycast_image(map.as_ref(), frame);
            let same = labels.iter().zip(&want_l).filter(|(a, b)| a == b).count();
            let identical = (0..n)
                .filter(|&i| labels[i] == want_l[i] && dist[i].to_bits() == want_d[i].to_bits())
                .count();
            let hits = want_l.iter().filter(|&&l| l != INVALID_LABEL).count();
            println!(
                "{cell} m, {}: {same} of {n} labels, {identical} identical",
                frame.id
            );
            assert!(hits > n * 9 / 10, "{}: only {hits} hits", frame.id);
            assert!(same * 1000 >= n * 999, "{}: {same} of {n} labels", frame.id);
            for i in 0..n {
                if labels[i] != INVALID_LABEL && want_l[i] != INVALID_LABEL {
                    let e = (dist[i] - want_d[i]).abs();
                    assert!(
                        e <= 1e-3,
                        "{} pixel {i}: {} vs {}",
                        frame.id,
                        dist[i],
                        want_d[i]
                    );
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
