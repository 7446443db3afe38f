//! Render (back-projection) time of one 1024x768 frame of the box room at 5, 10 and 20 cm.
//!
//! `cargo bench -p sndt-host --bench render` prints ms/frame and ns/pixel (single thread,
//! release). Each cell size maps the 12 frames of a walk around the room into a fresh map,
//! then renders the map at those poses (`SNDT_RENDER_POSES=n` renders only the first `n`;
//! `SNDT_RENDER_CELLS=5,10` picks cell sizes in cm). The median over the poses is reported,
//! with the fraction of pixels that hit something and a checksum of the output.

use sndt_core::{Config, INVALID_LABEL};
use sndt_host::dataset::synthetic::room::{orbit, Scene, HYPERSIM_CAMERA};
use sndt_host::mapping::HostMap;
use std::time::Instant;

fn main() {
    let scene = Scene::simple_room();
    let cam = HYPERSIM_CAMERA;
    let poses = orbit(12);
    let frames: Vec<_> = poses.iter().map(|p| scene.render(p, &cam)).collect();
    let n_render = std::env::var("SNDT_RENDER_POSES")
        .ok()
        .and_then(|s| s.parse::<usize>().ok())
        .unwrap_or(poses.len())
        .clamp(1, poses.len());
    let cells: Vec<f32> = std::env::var("SNDT_RENDER_CELLS")
        .ok()
        .map(|s| {
            s.split(',')
                .filter_map(|c| c.trim().parse::<f32>().ok())
                .map(|c| c / 100.0)
                .collect()
        })
        .unwrap_or_else(|| vec![0.05, 0.10, 0.20]);
    let pixels = (cam.width * cam.height) as usize;
    println!(
        "sndt-core render benchmark: box room mapped from 12 poses, {}x{} renders at {} poses",
        cam.width, cam.height, n_render
    );
    println!(
        "{:>6} {:>10} {:>10} {:>10} {:>10} {:>8} {:>18}",
        "cell", "median ms", "min ms", "max ms", "ns/pixel", "hit %", "checksum"
    );
    for cell in cells {
        let mut map: Box<HostMap> =
            sndt_host::mapping::boxed_map(Config::with_cell_size(cell)).expect("valid config");
        for (pose, (depth, labels)) in poses.iter().zip(&frames) {
            let img = sndt_host::dataset::synthetic::room::depth_image(&cam, depth, labels);
            let r = map.integrate_depth(pose, &img).expect("frame integrates");
            assert_eq!(
                r.dropped_points + r.voxels_evicted,
                0,
                "bench map too small"
            );
        }
        let (mut labels, mut dist) = (vec![0u8; pixels], vec![0f32; pixels]);
        let mut times = Vec::new();
        let mut hits = 0usize;
        // FNV-1a over labels and distance bits: equal across versions iff the output is.
        let mut sum = 0xcbf2_9ce4_8422_2325u64;
        for pose in &poses[..n_render] {
            let t = Instant::now();
            map.render(pose, &cam, &mut labels, &mut dist)
                .expect("render");
            times.push(t.elapsed().as_secs_f64());
            hits += labels.iter().filter(|&&l| l != INVALID_LABEL).count();
            for (&l, &d) in labels.iter().zip(&dist) {
                for b in [l as u64, d.to_bits() as u64] {
                    sum = (sum ^ b).wrapping_mul(0x0000_0100_0000_01b3);
                }
            }
        }
        times.sort_by(f64::total_cmp);
        let median = times[times.len() / 2];
        println!(
            "{:>4.0}cm {:>10.1} {:>10.1} {:>10.1} {:>10.1} {:>8.1} {:>18x}",
            cell * 100.0,
            median * 1e3,
            times[0] * 1e3,
            times[times.len() - 1] * 1e3,
            median * 1e9 / pixels as f64,
            100.0 * hits as f64 / (pixels * n_render) as f64,
            sum
        );
    }
}
