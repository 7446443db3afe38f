//! Update time of one 1024x768 frame of the box room at 5, 10, 15 and 20 cm.
//!
//! `cargo bench -p sndt-host --bench update` prints ms/frame and points/s (single thread, release).
//! Each cell size maps the same 12 frames of a walk around the room into a fresh map; the
//! first frame (all voxels new) and the steady state are reported separately.

use sndt_core::{Config, Map};
use sndt_host::dataset::synthetic::room::{orbit, Scene, HYPERSIM_CAMERA};
use std::time::Instant;

type BenchMap = Map<{ 1 << 19 }, { 1 << 17 }, 40>;

fn main() {
    let scene = Scene::simple_room();
    let cam = HYPERSIM_CAMERA;
    let poses = orbit(12);
    let frames: Vec<_> = poses.iter().map(|p| scene.render(p, &cam)).collect();
    let valid: usize = frames[0].0.iter().filter(|&&d| d > 0.0).count();
    println!(
        "sndt-core update benchmark: box room, {}x{} frames ({} valid points in frame 0), 12 poses",
        cam.width, cam.height, valid
    );
    println!(
        "{:>6} {:>12} {:>14} {:>14} {:>10} {:>10} {:>8} {:>9}",
        "cell", "first ms", "steady ms", "points/s", "voxels", "blocks", "rays", "MiB map"
    );
    for cell in [0.05f32, 0.10, 0.15, 0.20] {
        let mut map = sndt_host::semantic_map::boxed_map::<{ 1 << 19 }, { 1 << 17 }, 40>(
            Config::with_cell_size(cell),
        )
        .expect("valid config");
        let mut times = Vec::new();
        let mut points = 0u64;
        let mut rays = 0u32;
        for (pose, (depth, labels)) in poses.iter().zip(&frames) {
            let img = sndt_host::dataset::synthetic::room::depth_image(&cam, depth, labels);
            let t = Instant::now();
            let r = map.integrate_depth(pose, &img).expect("frame integrates");
            times.push(t.elapsed().as_secs_f64());
            points += r.points_used as u64;
            rays += r.rays;
            assert_eq!(
                r.dropped_points + r.voxels_evicted,
                0,
                "bench map too small"
            );
        }
        let first = times[0] * 1e3;
        let steady: f64 = times[1..].iter().sum::<f64>() / (times.len() - 1) as f64;
        let total: f64 = times.iter().sum();
        println!(
            "{:>4.0}cm {:>12.2} {:>14.2} {:>14.3e} {:>10} {:>10} {:>8} {:>9.1}",
            cell * 100.0,
            first,
            steady * 1e3,
            points as f64 / total,
            map.len(),
            map.block_count(),
            rays / times.len() as u32,
            core::mem::size_of::<BenchMap>() as f64 / (1 << 20) as f64
        );
    }
}
