//! Update time of S-NDT against S-BKI / OS-BKI on the same 1024x768 synthetic frames.
//!
//! `cargo bench -p sndt-host --bench baselines` prints, per cell size (5/10/15/20 cm),
//! the mean update time per frame of S-NDT (sndt-core) and of the BKI map for kernel
//! lengths 10-40 cm (S-BKI and OS-BKI share that update: the same counts, read two ways),
//! each read-out's cost (building the label grid once per map), and the ratio BKI / S-NDT.
//! Single thread, release build. Frames: every 10th of the first synthetic trajectory
//! (living room, default seed), predicted top-1 labels.

use sndt_core::Config;
use sndt_host::baselines::bki::{BkiConfig, BkiMap, Readout};
use sndt_host::dataset::open_spec;
use sndt_host::dataset::{Frame, LabelSource};
use sndt_host::mapping::{integrate_frame, HostMap};
use std::time::Instant;

fn main() {
    let data = open_spec("synthetic:1:100", &Default::default()).expect("synthetic split");
    let frames: Vec<Frame> = data.frames()[..]
        .iter()
        .step_by(10)
        .map(|id| {
            let f = data.load(id).expect("frame renders");
            // Feed predicted top-1 labels to both mappers.
            Frame {
                labels: f.predictions.as_ref().map(sndt_host::dataset::TopK::top1),
                predictions: None,
                ..f
            }
        })
        .collect();
    println!(
        "baselines update benchmark: {} synthetic frames of {}x{} (living room, every 10th), predicted labels, single thread",
        frames.len(),
        frames[0].rays.width(),
        frames[0].rays.height()
    );
    println!(
        "{:>5} {:>14} {:>10} {:>12} {:>11} {:>11} {:>9} {:>10}",
        "cell", "method", "ms/frame", "samples/fr", "S-BKI r/o", "OS-BKI r/o", "BKI/NDT", "MiB"
    );
    for cell in [0.05f32, 0.10, 0.15, 0.20] {
        let mut map: Box<HostMap> =
            sndt_host::mapping::boxed_map(Config::with_cell_size(cell)).expect("valid config");
        let t = Instant::now();
        for f in &frames {
            integrate_frame(map.as_mut(), f, LabelSource::Gt, 1).expect("frame integrates");
        }
        let ndt = t.elapsed().as_secs_f64() * 1e3 / frames.len() as f64;
        println!(
            "{:>3.0}cm {:>14} {:>10.1} {:>12} {:>11} {:>11} {:>9} {:>10.1}",
            cell * 100.0,
            "S-NDT",
            ndt,
            "",
            "",
            "",
            "1.0",
            core::mem::size_of::<HostMap>() as f64 / (1 << 20) as f64
        );
        for l in [0.1f32, 0.2, 0.3, 0.4] {
            let mut bki = BkiMap::new(BkiConfig::new(cell, l)).expect("valid config");
            let mut samples = 0;
            let t = Instant::now();
            for f in &frames {
                let r = bki
                    .integrate(f, f.labels.as_deref())
                    .expect("frame integrates");
                samples += r.hit_samples + r.free_samples;
            }
            let ms = t.elapsed().as_secs_f64() * 1e3 / frames.len() as f64;
            let readout = |r| {
                let t = Instant::now();
                let g = bki.label_grid(r);
                std::hint::black_box(g.occupied());
                t.elapsed().as_secs_f64() * 1e3
            };
            println!(
                "{:>5} {:>14} {:>10.1} {:>12} {:>11.1} {:>11.1} {:>9.1} {:>10.1}",
                "",
                format!("(O)S-BKI {:.0}cm", l * 100.0),
                ms,
                samples / frames.len(),
                readout(Readout::Sbki),
                readout(Readout::Osbki),
                ms / ndt,
                bki.bytes() as f64 / (1 << 20) as f64
            );
        }
    }
}
