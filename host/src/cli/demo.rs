//! `sndt demo`, the README's main job: a small synthetic split (no download) mapped at one
//! cell size with ground-truth and with predicted labels, evaluated as the paper does,
//! printed next to the paper's S-NDT numbers, and drawn.

use crate::dataset::classes::{render_color, NYU40};
use crate::dataset::frame::{FrameId, LabelSource};
use crate::dataset::source::{Dataset, Every};
use crate::dataset::synthetic::{SynthOptions, Synthetic};
use crate::eval::evaluate::{evaluate, EvalOptions, Evaluation, PAPER_ESANET_MIOU, PAPER_SNDT};
use crate::output::progress::progress;
use crate::output::{chart, picture};
use anyhow::{Context, Result};
use sndt_core::{Config, MissModel};
use std::path::PathBuf;
use std::time::Instant;

/// What the demo does.
#[derive(Clone, Debug)]
pub struct DemoOptions {
    /// Output directory for pictures, back-projections and metrics.
    pub out: PathBuf,
    /// Voxel edge in metres.
    pub cell: f32,
    /// Synthetic scenes (kinds cycle: living, bedroom, kitchen, ...).
    pub scenes: usize,
    /// Frames per trajectory (of a 100-frame walk, evenly spaced).
    pub frames: usize,
    /// Constant misses instead of NDT-OM misses.
    pub constant_miss: bool,
}

impl Default for DemoOptions {
    fn default() -> Self {
        DemoOptions {
            out: PathBuf::from("out/demo"),
            cell: 0.10,
            scenes: 2,
            frames: 20,
            constant_miss: false,
        }
    }
}

/// Runs the demo and prints its report.
pub fn run(o: &DemoOptions) -> Result<()> {
    let start = Instant::now();
    // Hypersim-like 100-frame walks, of which every k-th frame is used: the maps cover
    // the whole walk at a fraction of the cost.
    let walk = o.frames.max(100);
    let step = (walk / o.frames.max(1)).max(1) as u32;
    let split = Every::new(
        Box::new(Synthetic::new(SynthOptions {
            scenes: o.scenes,
            frames: walk,
            ..SynthOptions::default()
        })?),
        step,
    );
    let mut config = Config::with_cell_size(o.cell);
    if o.constant_miss {
        config.miss_model = MissModel::Constant;
    }
    println!(
        "sndt demo: {}, cell {:.0} cm, {} miss",
        split.describe(),
        o.cell * 100.0,
        if o.constant_miss {
            "constant"
        } else {
            "NDT-OM"
        }
    );
    std::fs::create_dir_all(&o.out).with_context(|| format!("creating {}", o.out.display()))?;

    // A few frames to draw: the middle of each trajectory, and a third of the way in.
    let mut keep: Vec<FrameId> = Vec::new();
    for (_, ids) in split.trajectories() {
        keep.push(ids[ids.len() / 3].clone());
        keep.push(ids[2 * ids.len() / 3].clone());
    }
    keep.dedup();

    let n = split.frames().len() as u64;
    let mut runs: Vec<(&str, Evaluation)> = Vec::new();
    for (name, labels, dir) in [
        ("ground truth", LabelSource::Gt, "gt"),
        ("predicted", LabelSource::Pred, "pred"),
    ] {
        let bar = progress(2 * n, &format!("{dir} labels"));
        let eval = evaluate(
            &split,
            &EvalOptions {
                out: Some(o.out.join("backprojection").join(dir)),
                keep_frames: keep.clone(),
                keep_maps: labels == LabelSource::Gt,
                ..EvalOptions::new(config, labels)
            },
            &|| bar.inc(1),
        )?;
        bar.finish_and_clear();
        runs.push((name, eval));
    }

    let paper = PAPER_SNDT
        .iter()
        .find(|p| (p.0 - o.cell).abs() < 1e-3)
        .copied();
    println!();
    println!(
        "| labels | mIoU | invR | mPAcc | update | paper S-NDT (Hypersim) mIoU / invR / mPAcc |"
    );
    println!("|---|---|---|---|---|---|");
    for (k, (name, e)) in runs.iter().enumerate() {
        let m = e.metrics();
        let ms = e.mean_update_ms();
        let reference = paper.map_or("-".to_string(), |p| {
            let r = if k == 0 { p.1 } else { p.2 };
            format!("{:.2} / {:.2} / {:.2} %", r[0], r[1], r[2])
        });
        println!(
            "| {name} | {:.2} % | {:.2} % | {:.2} % | {ms:.1} ms ({:.0} Hz) | {reference} |",
            m.miou * 100.0,
            m.invr * 100.0,
            m.mpacc * 100.0,
            1e3 / ms
        );
    }
    let net = runs[1].1.input.metrics();
    println!(
        "| network alone (no map) | {:.2} % | - | {:.2} % | - | ESANet {PAPER_ESANET_MIOU:.2} % mIoU |",
        net.miou * 100.0,
        net.mpacc * 100.0
    );
    if let Some(p) = paper {
        println!(
            "(paper: {:.1} Hz on an i7-6700HQ; frames here are 1024x768 like Hypersim's)",
            p.3
        );
    }

    // Pictures.
    println!();
    let (gt_run, pred_run) = (&runs[0].1, &runs[1].1);
    for id in &keep {
        let f = split.load(id)?;
        let (w, h) = (f.rays.width(), f.rays.height());
        let gt = f.labels.clone().unwrap_or_default();
        let net = f.predictions.as_ref().map(|p| p.top1()).unwrap_or_default();
        let find = |e: &Evaluation| e.kept.iter().find(|(k, _)| k == id).map(|(_, v)| v.clone());
        let (Some(bg), Some(bp)) = (find(gt_run), find(pred_run)) else {
            continue;
        };
        let path = o.out.join(format!("frame_{}_{}.png", id.scene, id.stem()));
        picture::side_by_side(&path, w, h, &[&gt, &net, &bg, &bp], render_color)?;
        println!(
            "wrote {} (ground truth | network prediction | map from GT labels | map from predicted labels)",
            path.display()
        );
    }
    for (map, t) in gt_run.maps.iter().zip(&gt_run.trajectories) {
        let scene = t.name.split('/').next().unwrap_or("map");
        let path = o.out.join(format!("birdseye_{scene}.png"));
        picture::birds_eye(&path, map.as_ref(), 2.2)?;
        println!(
            "wrote {} (semantic map from above, ceiling removed)",
            path.display()
        );
    }
    let path = o.out.join("iou.svg");
    let (iou_gt, iou_pred, iou_net) = (
        gt_run.metrics().iou,
        pred_run.metrics().iou,
        pred_run.input.metrics().iou,
    );
    chart::iou_bars(
        &path,
        &format!("Per-class IoU, cell {:.0} cm", o.cell * 100.0),
        &[
            ("map, GT labels", &iou_gt),
            ("map, predicted labels", &iou_pred),
            ("network alone", &iou_net),
        ],
    )?;
    println!("wrote {} (per-class IoU)", path.display());
    let json = serde_json::json!({
        "cell": o.cell,
        "gt": gt_run.to_json(),
        "pred": pred_run.to_json(),
        "network_alone": { "miou": net.miou, "mpacc": net.mpacc },
    });
    std::fs::write(
        o.out.join("metrics.json"),
        serde_json::to_string_pretty(&json)?,
    )?;
    println!(
        "wrote {}/metrics.json and back-projections under {}/backprojection/{{gt,pred}}/",
        o.out.display(),
        o.out.display()
    );
    println!();
    println!("per-class IoU (map from GT labels / from predicted labels / network alone):");
    let pct = |x: Option<f64>| x.map_or("-".to_string(), |x| format!("{:.1}", x * 100.0));
    for c in (1..=40).filter(|&c| iou_gt[c].is_some()) {
        println!(
            "  {:>2} {:<14} {:>5} / {:>5} / {:>5} %",
            c,
            NYU40[c],
            pct(iou_gt[c]),
            pct(iou_pred[c]),
            pct(iou_net[c])
        );
    }
    println!("\ndone in {:.0} s", start.elapsed().as_secs_f64());
    Ok(())
}
