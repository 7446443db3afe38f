//! The sndt side of the OctoMap peer benchmark (`bash scripts/bench-peers.sh`): update
//! time of the S-NDT map on the first frames of a dataset directory, per cell size, for
//! the script to put beside OctoMap's on the same points.
//!
//! `cargo bench -p sndt-host --bench peers -- DATASET [FRAMES]` opens `DATASET` (a
//! prepared layout, e.g. what `sndt synth --scenes 1 --frames-per-scene 12
//! --no-predictions` writes, or `synthetic[:S:F]`), loads its first `FRAMES` frames (default 12) into
//! memory and, per cell size (5, 10, 20 cm), single thread:
//! - a warm-up pass into a fresh heap map ([`HostMap`]), then `reset`, so the timed pass
//!   finds the map's memory touched;
//! - a timed pass: one `integrate_depth` per frame through `sndt-dispatch` (at the CPU's
//!   fastest level, or at most `SNDT_LEVEL`: `baseline`, `avx2`, `avx512`; every pixel, ground-truth labels,
//!   `Config::with_cell_size(cell)`: statistics, classes and free space up to
//!   `max_range`), nothing else inside the clock.
//!
//! It prints one line per cell size,
//! `sndt cell=0.10 median_ms=... min_ms=... max_ms=... voxels=... blocks=...`, the median
//! of an even count being the mean of the two middle frames (as the OctoMap harness
//! computes it). Without a dataset argument (a plain `cargo bench`) it prints a note and
//! exits successfully.

mod common;

use common::{median, warm_timed_pass};
use sndt_core::Config;
use sndt_host::dataset::frame::Frame;
use sndt_host::dataset::open::open_spec;

const CELLS: [f32; 3] = [0.05, 0.10, 0.20];

fn main() {
    // `cargo bench` passes `--bench` (and other flags) before the user's arguments.
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let Some(spec) = args.first() else {
        println!("peers: no dataset given, skipped (run `bash scripts/bench-peers.sh`)");
        return;
    };
    let count: usize = args
        .get(1)
        .map_or(12, |n| n.parse().expect("FRAMES is a number"));
    let frames = load(spec, count);
    println!(
        "sndt frames={} pixels={} max_range={} threads=1 level={:?}",
        frames.len(),
        frames[0].pixels(),
        Config::DEFAULT.max_range,
        common::level()
    );
    for cell in CELLS {
        bench_cell(&frames, cell);
    }
}

/// The first `count` frames of the dataset at `spec`, in memory.
fn load(spec: &str, count: usize) -> Vec<Frame> {
    let data = open_spec(spec, &Default::default()).expect("dataset opens");
    let ids = data.frames();
    assert!(ids.len() >= count, "{spec}: fewer than {count} frames");
    ids[..count]
        .iter()
        .map(|id| data.load(id).expect("frame loads"))
        .collect()
}

/// One line: a warm-up pass, `reset`, then the timed pass.
fn bench_cell(frames: &[Frame], cell: f32) {
    let (map, ms) = warm_timed_pass(Config::with_cell_size(cell), frames);
    let n = ms.len();
    let median = median(&ms);
    println!(
        "sndt cell={cell:.2} median_ms={median:.3} min_ms={:.3} max_ms={:.3} voxels={} blocks={}",
        ms[0],
        ms[n - 1],
        map.len(),
        map.block_count()
    );
}
