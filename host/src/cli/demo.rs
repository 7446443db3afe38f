//! `sndt demo`, the README's main job: a small synthetic split (no download) mapped at one
//! cell size with ground-truth and with predicted labels, evaluated as the paper does,
//! printed next to the paper's S-NDT numbers, and drawn.

use crate::dataset::classes::{render_color, NYU40};
use crate::dataset::frame::{FrameId, LabelSource};
use crate::dataset::source::{Dataset, Every};
use crate::dataset::synthetic::{SynthOptions, Synthetic};
use crate::eval::evaluate::{evaluate, EvalOptions, Evaluation, PAPER_ESANET_MIOU, PAPER_SNDT};
use crate::eval::metrics::Metrics;
use crate::output::progress::progress;
use crate::output::{chart, picture};
use anyhow::{Context, Result};
use sndt_core::{Config, MissModel};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `sndt demo`.
#[derive(clap::Args, Clone, Debug, PartialEq)]
#[command(after_help = "Example:
  sndt demo --cell 0.05 --scenes 1 --frames-per-scene 10 --out out/demo")]
pub struct DemoArgs {
    /// Output directory for pictures, back-projections and metrics.
    #[arg(long, default_value = "out/demo")]
    pub out: PathBuf,
    /// Voxel edge in metres.
    #[arg(long, default_value_t = 0.10, value_parser = super::parse::positive)]
    pub cell: f32,
    /// Synthetic scenes (kinds cycle: living, bedroom, kitchen, office, bathroom, open plan).
    #[arg(long, default_value_t = 2)]
    pub scenes: usize,
    /// About this many frames mapped per scene: every k-th frame of its camera walk of 100
    /// frames (of this many, when more).
    #[arg(long, value_name = "N", default_value_t = 20)]
    pub frames_per_scene: usize,
    /// Use constant misses instead of NDT-OM misses.
    #[arg(long)]
    pub constant_miss: bool,
}

impl Default for DemoArgs {
    /// The command line's defaults (`sndt demo` without options).
    fn default() -> Self {
        DemoArgs {
            out: PathBuf::from("out/demo"),
            cell: 0.10,
            scenes: 2,
            frames_per_scene: 20,
            constant_miss: false,
        }
    }
}

/// The two evaluations of the demo: the map fed ground-truth labels, and fed predictions.
struct Runs {
    gt: Evaluation,
    pred: Evaluation,
}

/// Runs the demo and prints its report.
pub fn run(a: &DemoArgs) -> Result<()> {
    let start = Instant::now();
    let config = map_config(a);
    super::parse::check_cell_config(&config, a.cell)?;
    let split = walk_split(a)?;
    println!(
        "sndt demo: {}, cell {:.0} cm, {} miss",
        split.describe(),
        a.cell * 100.0,
        if a.constant_miss {
            "constant"
        } else {
            "NDT-OM"
        }
    );
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let keep = frames_to_draw(&split);
    let runs = Runs {
        gt: evaluate_with(&split, config, LabelSource::Gt, &keep, a)?,
        pred: evaluate_with(&split, config, LabelSource::Pred, &keep, a)?,
    };
    print_paper_comparison(a.cell, &runs);
    println!();
    write_frame_pictures(&split, &keep, &runs, a)?;
    write_birdseye_views(&runs.gt, a)?;
    write_iou_chart_and_metrics(&runs, a)?;
    println!();
    print_per_class_iou(&runs);
    println!("\ndone in {:.0} s", start.elapsed().as_secs_f64());
    Ok(())
}

/// Hypersim-like 100-frame walks, of which every k-th frame is used: the maps cover the
/// whole walk at a fraction of the cost.
fn walk_split(a: &DemoArgs) -> Result<Every> {
    let walk = a.frames_per_scene.max(100);
    let step = (walk / a.frames_per_scene.max(1)).max(1) as u32;
    let scenes = Synthetic::new(SynthOptions {
        scenes: a.scenes,
        frames: walk,
        ..SynthOptions::default()
    })?;
    Ok(Every::new(Box::new(scenes), step))
}

/// The core's configuration at `--cell`, with constant misses if asked.
fn map_config(a: &DemoArgs) -> Config {
    let mut config = Config::with_cell_size(a.cell);
    if a.constant_miss {
        config.miss_model = MissModel::Constant;
    }
    config
}

/// A few frames to draw: a third and two thirds of the way into each trajectory.
fn frames_to_draw(split: &Every) -> Vec<FrameId> {
    let mut keep: Vec<FrameId> = Vec::new();
    for (_, ids) in split.trajectories() {
        keep.push(ids[ids.len() / 3].clone());
        keep.push(ids[2 * ids.len() / 3].clone());
    }
    keep.dedup();
    keep
}

/// Maps and evaluates the split with `labels`, writing back-projections under
/// `<out>/backprojection/{gt,pred}/` and keeping the `keep` frames' renders (and, with
/// ground-truth labels, the maps, for the bird's-eye views).
fn evaluate_with(
    split: &Every,
    config: Config,
    labels: LabelSource,
    keep: &[FrameId],
    a: &DemoArgs,
) -> Result<Evaluation> {
    let dir = if labels == LabelSource::Gt {
        "gt"
    } else {
        "pred"
    };
    let bar = progress(2 * split.frames().len() as u64, &format!("{dir} labels"));
    let eval = evaluate(
        split,
        &EvalOptions {
            out: Some(a.out.join("backprojection").join(dir)),
            keep_frames: keep.to_vec(),
            keep_maps: labels == LabelSource::Gt,
            ..EvalOptions::new(config, labels)
        },
        &|| bar.inc(1),
    )?;
    bar.finish_and_clear();
    Ok(eval)
}

/// The scores of both maps and of the network alone, as a Markdown table beside the
/// paper's S-NDT numbers on Hypersim at the same cell size (when the paper has it).
fn print_paper_comparison(cell: f32, runs: &Runs) {
    let paper = PAPER_SNDT
        .iter()
        .find(|p| (p.0 - cell).abs() < 1e-3)
        .copied();
    println!();
    println!(
        "| labels | mIoU | invR | mPAcc | update | paper S-NDT (Hypersim) mIoU / invR / mPAcc |"
    );
    println!("|---|---|---|---|---|---|");
    for (k, (name, e)) in [("ground truth", &runs.gt), ("predicted", &runs.pred)]
        .into_iter()
        .enumerate()
    {
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
    let net = network_alone(runs);
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
}

/// The network's own predictions scored on the frames (no map).
fn network_alone(runs: &Runs) -> Metrics {
    runs.pred.input.metrics()
}

/// Per kept frame: ground truth | network prediction | map from GT labels | map from
/// predicted labels, side by side.
fn write_frame_pictures(split: &Every, keep: &[FrameId], runs: &Runs, a: &DemoArgs) -> Result<()> {
    for id in keep {
        let f = split.load(id)?;
        let (w, h) = (f.rays.width(), f.rays.height());
        let gt = f.labels.clone().unwrap_or_default();
        let net = f
            .predictions
            .as_ref()
            .map(super::super::dataset::frame::TopK::top1)
            .unwrap_or_default();
        let find = |e: &Evaluation| e.kept.iter().find(|(k, _)| k == id).map(|(_, v)| v.clone());
        let (Some(bg), Some(bp)) = (find(&runs.gt), find(&runs.pred)) else {
            continue;
        };
        let path = a.out.join(format!("frame_{}_{}.png", id.scene, id.stem()));
        picture::side_by_side(&path, w, h, &[&gt, &net, &bg, &bp], render_color)?;
        println!(
            "wrote {} (ground truth | network prediction | map from GT labels | map from predicted labels)",
            path.display()
        );
    }
    Ok(())
}

/// Each trajectory's map (from ground-truth labels) seen from above, ceiling removed.
fn write_birdseye_views(gt: &Evaluation, a: &DemoArgs) -> Result<()> {
    for (map, t) in gt.maps.iter().zip(&gt.trajectories) {
        let scene = t.name.split('/').next().unwrap_or("map");
        let path = a.out.join(format!("birdseye_{scene}.png"));
        picture::birds_eye(&path, map.as_ref(), 2.2)?;
        println!(
            "wrote {} (semantic map from above, ceiling removed)",
            path.display()
        );
    }
    Ok(())
}

/// The per-class IoU chart (`iou.svg`) and all numbers (`metrics.json`).
fn write_iou_chart_and_metrics(runs: &Runs, a: &DemoArgs) -> Result<()> {
    let path = a.out.join("iou.svg");
    chart::iou_bars(
        &path,
        &format!("Per-class IoU, cell {:.0} cm", a.cell * 100.0),
        &[
            ("map, GT labels", &runs.gt.metrics().iou),
            ("map, predicted labels", &runs.pred.metrics().iou),
            ("network alone", &network_alone(runs).iou),
        ],
    )?;
    println!("wrote {} (per-class IoU)", path.display());
    let net = network_alone(runs);
    let json = serde_json::json!({
        "cell": a.cell,
        "gt": runs.gt.to_json(),
        "pred": runs.pred.to_json(),
        "network_alone": { "miou": net.miou, "mpacc": net.mpacc },
    });
    crate::atomic::write_bytes(
        &a.out.join("metrics.json"),
        serde_json::to_string_pretty(&json)?,
    )?;
    println!(
        "wrote {}/metrics.json and back-projections under {}/backprojection/{{gt,pred}}/",
        a.out.display(),
        a.out.display()
    );
    Ok(())
}

/// Per class present in the ground truth: IoU of the map from GT labels, from predicted
/// labels, and of the network alone.
fn print_per_class_iou(runs: &Runs) {
    println!("per-class IoU (map from GT labels / from predicted labels / network alone):");
    let (iou_gt, iou_pred, iou_net) = (
        runs.gt.metrics().iou,
        runs.pred.metrics().iou,
        network_alone(runs).iou,
    );
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    /// Parses `sndt demo` the way the command line does.
    #[derive(Parser)]
    struct Demo {
        #[command(flatten)]
        args: DemoArgs,
    }

    #[test]
    fn default_is_the_command_lines_default() {
        assert_eq!(Demo::parse_from(["demo"]).args, DemoArgs::default());
    }
}
