//! `sndt synth`: a synthetic labelled split written in the prepared layout (no download),
//! with its class histogram, preview pictures and the raw prediction's score.

use crate::cli::parse::renamed;
use crate::dataset::classes::{render_color, NYU40};
use crate::dataset::source::Dataset;
use crate::dataset::synthetic::{write_split, DepthNoise, SynthOptions, Synthetic};
use crate::eval::label_stats::LabelStats;
use crate::output::picture;
use crate::output::progress::progress;
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

/// Arguments of `sndt synth`.
#[derive(clap::Args, Clone, Debug)]
#[command(after_help = "Example:
  sndt synth --out data/synth --scenes 2 --frames-per-scene 20 --no-predictions")]
pub struct SynthArgs {
    /// Output directory (the dataset root) of the prepared layout.
    #[arg(long, required_unless_present = "mcap")]
    pub out: Option<PathBuf>,
    /// Also (or only) write each trajectory as a ROS 2 bag: this file for one scene,
    /// `<stem>_<scene>.mcap` beside it for several (16UC1 depth, mono8 labels, camera info,
    /// /tf and /tf_static).
    #[arg(long)]
    pub mcap: Option<PathBuf>,
    /// Number of scenes (kinds cycle: living, bedroom, kitchen, office, bathroom, open plan).
    #[arg(long, default_value_t = 6)]
    pub scenes: usize,
    /// Seed of everything.
    #[arg(long, default_value_t = crate::dataset::synthetic::DEFAULT_SEED)]
    pub seed: u64,
    /// Frames of each scene's camera trajectory (one trajectory per scene).
    #[arg(long, value_name = "N", default_value_t = 100)]
    pub frames_per_scene: usize,
    /// Deprecated spelling of --frames-per-scene.
    #[arg(long, hide = true, conflicts_with = "frames_per_scene")]
    pub frames: Option<usize>,
    /// Add range-dependent depth noise (Kinect v1 model).
    #[arg(long)]
    pub noise: bool,
    /// Skip the ESANet-style predictions (9.4 MB per frame).
    #[arg(long)]
    pub no_predictions: bool,
}

/// Runs `sndt synth`: writes the split, prints its ground-truth class histogram, writes
/// previews and scores the raw predictions.
pub fn run(a: &SynthArgs) -> Result<()> {
    let t = Instant::now();
    let per_scene = renamed(
        a.frames_per_scene,
        a.frames,
        "--frames",
        "--frames-per-scene",
    );
    let options = SynthOptions {
        scenes: a.scenes,
        frames: per_scene,
        seed: a.seed,
        noise: a.noise.then_some(DepthNoise::KINECT),
        predictions: !a.no_predictions,
        ..SynthOptions::default()
    };
    let split = Synthetic::new(options)?;
    if let Some(path) = &a.mcap {
        write_bags(&split, path)?;
    }
    let Some(out) = &a.out else {
        return Ok(());
    };
    println!("sndt synth: {} -> {}", split.describe(), out.display());
    let bar = progress((a.scenes * per_scene) as u64, "synth");
    // Per-frame statistics are summed outside the lock; only the merge is serialised.
    let stats = Mutex::new(LabelStats::default());
    let frames = write_split(out, &split, &|f| {
        let mut one = LabelStats::default();
        one.add(f);
        stats.lock().expect("no panic while merging").merge(&one);
        bar.inc(1);
    })?;
    let summary = stats.into_inner().expect("no panic while merging");
    bar.finish_and_clear();
    println!("{frames} frames in {:.1} s", t.elapsed().as_secs_f64());
    print_class_histogram(&summary.class_pixels);
    write_previews(&split, &out.join("preview"))?;
    if !a.no_predictions {
        let m = summary.prediction.metrics();
        println!(
            "raw top-1 prediction vs ground truth: mIoU {:.2} %, mPAcc {:.2} % (the paper's ESANet: 41.17 % mIoU)",
            m.miou * 100.0,
            m.mpacc * 100.0
        );
    }
    Ok(())
}

/// Writes each trajectory of `split` as a ROS 2 bag: `path` for one, `<stem>_<scene>.mcap`
/// for several.
pub fn write_bags(split: &Synthetic, path: &Path) -> Result<Vec<PathBuf>> {
    let trajectories = split.trajectories();
    let mut written = Vec::new();
    for (name, ids) in &trajectories {
        let file = if trajectories.len() == 1 {
            path.to_path_buf()
        } else {
            let stem = path
                .file_stem()
                .map_or("synthetic".into(), |s| s.to_string_lossy());
            path.with_file_name(format!("{stem}_{}.mcap", name.replace('/', "_")))
        };
        let n = crate::output::ros::write::write_trajectory(
            &file,
            ids.iter().map(|id| split.load(id)),
        )?;
        println!("wrote {} ({n} frames of {name})", file.display());
        written.push(file);
    }
    Ok(written)
}

/// Prints each occurring class's share of all pixels, so a split's class balance can be
/// checked before it is mapped.
fn print_class_histogram(class_pixels: &[u64]) {
    let total: u64 = class_pixels.iter().sum();
    println!("ground-truth class histogram (share of all pixels):");
    for (c, &n) in class_pixels.iter().enumerate() {
        if n > 0 {
            println!(
                "  {:>2} {:<14} {:7.3} %",
                c,
                NYU40[c],
                100.0 * n as f64 / total as f64
            );
        }
    }
    let present = class_pixels[1..].iter().filter(|&&n| n > 0).count();
    println!("{present} of 40 classes occur");
}

/// Writes ground truth | prediction for the first and the middle frame of each scene
/// into `dir` (the prediction falls back to the ground truth without predictions).
fn write_previews(split: &Synthetic, dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    for (_, ids) in split.trajectories() {
        for id in [&ids[0], &ids[ids.len() / 2]] {
            let f = split.load(id)?;
            let gt = f.labels.clone().unwrap_or_default();
            let pred = f
                .predictions
                .as_ref()
                .map(super::super::dataset::frame::TopK::top1)
                .unwrap_or_else(|| gt.clone());
            let path = dir.join(format!("{}_{}.png", id.scene, id.stem()));
            picture::side_by_side(
                &path,
                f.rays.width(),
                f.rays.height(),
                &[&gt, &pred],
                render_color,
            )?;
        }
    }
    println!(
        "wrote previews (ground truth | prediction) to {}",
        dir.display()
    );
    Ok(())
}
