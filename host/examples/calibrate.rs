//! Calibration of the synthetic segmentation model: prints the raw top-1 mIoU on a subsample
//! of the default split for the parameters given on the command line.
//! `cargo run --release -p sndt-host --example calibrate -- [frames] [confuse_easy confuse_med confuse_hard absorb warp blobs]`
use sndt_host::dataset::synthetic::{predict::ModelParams, SynthOptions, Synthetic};
use sndt_host::dataset::Dataset;
use sndt_host::eval::label_stats::LabelStats;

fn main() {
    let a: Vec<f32> = std::env::args()
        .skip(1)
        .map(|s| s.parse().expect("number"))
        .collect();
    let frames = a.first().copied().unwrap_or(20.0) as usize;
    let mut model = ModelParams::DEFAULT;
    if a.len() >= 7 {
        model.confuse = [a[1], a[2], a[3]];
        model.absorb = a[4];
        model.warp = a[5];
        model.blobs = a[6];
    }
    let split = Synthetic::new(SynthOptions {
        frames,
        model,
        ..Default::default()
    })
    .unwrap();
    let mut stats = LabelStats::default();
    // Every 10th frame of each trajectory: a cheap proxy of the whole split.
    for id in split.frames().iter().filter(|id| id.index % 10 == 0) {
        stats.add(&split.load(id).unwrap());
    }
    let m = stats.prediction.metrics();
    println!(
        "{model:?}\nmIoU {:.2} % mPAcc {:.2} %",
        m.miou * 100.0,
        m.mpacc * 100.0
    );
}
