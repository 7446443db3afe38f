//! Update time of the S-NDT map, in total and per phase, on 12 consecutive 1024x768 frames
//! of the synthetic living room (the frames `sndt synth --scenes 1 --frames-per-scene 12
//! --no-predictions` writes, here with exact depth and ground-truth labels).
//!
//! `cargo bench -p sndt-host --bench update [-- CELL...]` prints, per cell size (default
//! 0.05 0.10 0.15 0.20 m), single thread:
//! - ms/frame: median, min and max over the 12 frames of a warm pass (the map's memory
//!   touched by an earlier pass, then reset);
//! - ns/point per phase ([`sndt_core::Phase`]) from a third pass that reports its phases:
//!   `points` (pixel -> point -> key and offset), `accumulate` (lookup, sums, votes),
//!   `end voxels` (one update per touched voxel) and `free space` (rays, misses), divided by
//!   the frame's pixels; reporting the phases costs two clock reads per batch of 64 points.

mod common;

use common::{image, median, warm_timed_pass};
use sndt_core::{Config, Phase};
use sndt_host::dataset::frame::Frame;
use sndt_host::dataset::source::Dataset;
use sndt_host::dataset::synthetic::{SynthOptions, Synthetic};
use std::time::{Duration, Instant};

const CELLS: [f32; 4] = [0.05, 0.10, 0.15, 0.20];

fn main() {
    let frames = living_room();
    let pixels = frames[0].pixels();
    println!(
        "sndt-core update benchmark: synthetic living room, {} frames of {} pixels, one thread, level {:?}",
        frames.len(),
        pixels,
        common::level()
    );
    println!(
        "{:>5} | {:>7} {:>7} {:>7} | {:>6} {:>10} {:>9} {:>9} {:>7} | {:>6} {:>7} {:>6}",
        "cell",
        "med ms",
        "min ms",
        "max ms",
        "points",
        "accumulate",
        "end vox",
        "free sp",
        "total",
        "rays",
        "voxels",
        "blocks"
    );
    // `cargo bench` passes `--bench`; other arguments are cell sizes.
    let cells: Vec<f32> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    for cell in if cells.is_empty() { &CELLS[..] } else { &cells } {
        bench_cell(&frames, *cell);
    }
    println!("(ms: whole integrate_depth per frame; the other columns: ns per pixel, by phase)");
}

/// The 12 frames, rendered once.
fn living_room() -> Vec<Frame> {
    // SNDT_BENCH_FRAMES=N: fewer frames (for profilers that run the bench slowly).
    let frames = std::env::var("SNDT_BENCH_FRAMES")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(12);
    let split = Synthetic::new(SynthOptions {
        scenes: 1,
        frames,
        predictions: false,
        ..SynthOptions::default()
    })
    .expect("synthetic split");
    split
        .frames()
        .iter()
        .map(|id| split.load(id).expect("frame renders"))
        .collect()
}

/// One row of the table: a warm-up pass, a timed pass and a pass timed by phase.
fn bench_cell(frames: &[Frame], cell: f32) {
    let config = Config::with_cell_size(cell);
    let (mut map, ms) = warm_timed_pass(config, frames);
    map.reset(config).expect("valid config");
    let mut phases = [Duration::ZERO; 5];
    let mut rays = 0u64;
    for f in frames {
        let mut last = Instant::now();
        let mut current: Option<Phase> = None;
        let on_phase = |p| {
            let now = Instant::now();
            if let Some(c) = current {
                phases[c as usize] += now - last;
            }
            (last, current) = (now, Some(p));
        };
        let level = common::level();
        let r = sndt_dispatch::integrate_depth_observed_at(
            level,
            &mut map,
            &f.pose,
            &image(f),
            on_phase,
        )
        .expect("frame integrates");
        assert_eq!(
            r.dropped_points + r.voxels_evicted,
            0,
            "bench map too small"
        );
        rays += r.rays as u64;
    }
    let points = (frames.len() * frames[0].pixels()) as f64;
    let ns = |d: Duration| d.as_secs_f64() * 1e9 / points;
    let total: Duration = phases.iter().sum();
    println!(
        "{:>3.0}cm | {:>7.2} {:>7.2} {:>7.2} | {:>6.2} {:>10.2} {:>9.2} {:>9.2} {:>7.2} | {:>6} {:>7} {:>6}",
        cell * 100.0,
        median(&ms),
        ms[0],
        ms[ms.len() - 1],
        ns(phases[Phase::Points as usize]),
        ns(phases[Phase::Accumulate as usize]),
        ns(phases[Phase::EndVoxels as usize]),
        ns(phases[Phase::FreeSpace as usize]),
        ns(total),
        rays / frames.len() as u64,
        map.len(),
        map.block_count()
    );
}
