//! The `sndt` command line: the only module that uses clap.

pub mod demo;

use crate::dataset::classes::{render_color, NYU40};
use crate::output::picture;
use crate::output::progress::progress;
use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use sndt_core::Config;
use std::path::PathBuf;
use std::time::Instant;

/// sndt: semantic occupancy-NDT mapping tools.
#[derive(Parser)]
#[command(version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Map a small synthetic split (no download) with GT and predicted labels; metrics and pictures.
    Demo(DemoArgs),
    /// Exact memory of a Map<N, B, K>; with a dataset, peak voxels and evictions per trajectory.
    Budget(BudgetArgs),
    /// Write (--out) or check (--check) the cross-architecture test vector of the firmware.
    Testvector(TestvectorArgs),
    /// Write one frame's world points, coloured by label, as a PLY point cloud.
    Cloud(CloudArgs),
    /// Generate a synthetic labelled split in the prepared layout (no download).
    Synth(SynthArgs),
    /// Map every trajectory of a dataset and evaluate the back-projections (DESIGN §4).
    Map(MapArgs),
    /// Write a map's Gaussians as a PLY (points or ellipsoids) for MeshLab/CloudCompare.
    Export(ExportArgs),
    /// Integrate frames into the core and the f64 reference and compare them per cell size.
    Compare(crate::eval::compare::CompareArgs),
    /// The paper's comparison: S-NDT, S-BKI and OS-BKI per cell size and kernel length;
    /// Tables I and II (Markdown, CSV), per-class IoU and rate-vs-mIoU charts.
    Experiment(ExperimentArgs),
}

/// Which labels an experiment maps with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum ExperimentLabels {
    Gt,
    Pred,
    Both,
}

#[derive(clap::Args)]
struct ExperimentArgs {
    /// Dataset directory (prepared layout or raw Hypersim), or `synthetic[:SCENES:FRAMES]`.
    dataset: String,
    /// Labels fed to the maps.
    #[arg(long, value_enum, default_value = "both")]
    labels: ExperimentLabels,
    /// Cell sizes, metres.
    #[arg(long, value_delimiter = ',', default_value = "0.05,0.1,0.15,0.2")]
    cells: Vec<f32>,
    /// Kernel lengths of S-BKI and OS-BKI, metres.
    #[arg(long, value_delimiter = ',', default_value = "0.1,0.2,0.3,0.4")]
    kernels: Vec<f32>,
    /// Methods.
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "sndt,sbki,osbki"
    )]
    methods: Vec<crate::eval::experiment::Method>,
    /// Spacing of BKI free samples along each ray, metres (default 0.3).
    #[arg(long)]
    free_resolution: Option<f32>,
    /// S-NDT: about how many votes a voxel takes from one frame (1..=64;
    /// `Config::votes_per_frame`).
    #[arg(long, default_value_t = Config::DEFAULT.votes_per_frame)]
    votes_per_frame: u8,
    /// Use every k-th frame of each trajectory (1 = all, as the paper).
    #[arg(long, default_value_t = 1)]
    every: u32,
    /// Output directory for tables and charts.
    #[arg(long, default_value = "out/experiment")]
    out: PathBuf,
    #[command(flatten)]
    open: OpenArgs,
}

/// How to open a dataset directory (shared by `map` and `experiment`).
#[derive(clap::Args)]
struct OpenArgs {
    /// Split of the prepared layout.
    #[arg(long, default_value = "test")]
    split: String,
    /// Use the authors' v0.3.1 fy = 927.06 (prepared layout without intrinsics).
    #[arg(long)]
    paper_fy: bool,
    /// Directory of ESANet `.npy` predictions.
    #[arg(long)]
    predictions: Option<PathBuf>,
}

impl OpenArgs {
    fn options(&self) -> crate::dataset::source::OpenOptions {
        crate::dataset::source::OpenOptions {
            split: Some(self.split.clone()),
            paper_fy: self.paper_fy,
            predictions: self.predictions.clone(),
        }
    }
}

#[derive(clap::Args)]
struct MapArgs {
    /// Dataset directory (prepared layout or raw Hypersim), or `synthetic[:SCENES:FRAMES]`.
    dataset: String,
    /// Voxel edge in metres.
    #[arg(long, default_value_t = 0.10)]
    cell: f32,
    /// Labels fed to the map.
    #[arg(long, value_enum, default_value = "gt")]
    labels: crate::dataset::frame::LabelSource,
    /// Output directory: back-projection PNGs `<out>/<scene>/<cam>/<NNNN>.png`,
    /// metrics.json and metrics.md.
    #[arg(long, default_value = "out/map")]
    out: PathBuf,
    #[command(flatten)]
    open: OpenArgs,
    /// Use every stride-th pixel when mapping.
    #[arg(long, default_value_t = 1)]
    stride: u32,
    /// About how many votes a voxel takes from one frame (1..=64; `Config::votes_per_frame`).
    #[arg(long, default_value_t = Config::DEFAULT.votes_per_frame)]
    votes_per_frame: u8,
    /// Also write each trajectory's map snapshot to `<out>/maps/<scene>_<cam>.sndt`.
    #[arg(long)]
    save_maps: bool,
}

#[derive(clap::Args)]
struct ExportArgs {
    /// A map snapshot (`.sndt`, from `sndt map --save-maps`), or a dataset
    /// (directory or `synthetic[:SCENES:FRAMES]`) whose first trajectory is mapped.
    input: String,
    /// Output PLY file.
    #[arg(long)]
    ply: PathBuf,
    /// Ellipsoid meshes at this many standard deviations instead of points at the means.
    #[arg(long)]
    ellipsoids: Option<f32>,
    /// Voxel edge in metres (when mapping a dataset).
    #[arg(long, default_value_t = 0.10)]
    cell: f32,
    /// Labels fed to the map (when mapping a dataset).
    #[arg(long, value_enum, default_value = "gt")]
    labels: crate::dataset::frame::LabelSource,
    /// Only voxels with at least this many points.
    #[arg(long, default_value_t = 3)]
    min_points: u32,
}

#[derive(clap::Args)]
struct SynthArgs {
    /// Output directory (the dataset root).
    #[arg(long)]
    out: PathBuf,
    /// Number of scenes (kinds cycle: living, bedroom, kitchen, office, bathroom, open plan).
    #[arg(long, default_value_t = 6)]
    scenes: usize,
    /// Seed of everything.
    #[arg(long, default_value_t = crate::dataset::synthetic::DEFAULT_SEED)]
    seed: u64,
    /// Frames per trajectory.
    #[arg(long, default_value_t = 100)]
    frames: usize,
    /// Add range-dependent depth noise (Kinect v1 model).
    #[arg(long)]
    noise: bool,
    /// Skip the ESANet-style predictions (9.4 MB per frame).
    #[arg(long)]
    no_predictions: bool,
}

#[derive(clap::Args)]
struct CloudArgs {
    /// Dataset directory (prepared layout or raw Hypersim).
    dataset: PathBuf,
    /// The frame, as `<scene>/<cam>/<NNNN>`.
    #[arg(long)]
    frame: String,
    /// Output PLY file.
    #[arg(long)]
    out: PathBuf,
    /// Split of the prepared layout.
    #[arg(long, default_value = "test")]
    split: String,
    /// Use the authors' v0.3.1 fy = 927.06 (prepared layout without intrinsics).
    #[arg(long)]
    paper_fy: bool,
}

#[derive(clap::Args)]
struct BudgetArgs {
    /// Voxel edge in metres.
    #[arg(long, default_value_t = 0.10)]
    cell: f32,
    /// Classes K.
    #[arg(long, default_value_t = 40)]
    classes: usize,
    /// Surface voxel capacity N.
    #[arg(long)]
    capacity: usize,
    /// Occupancy block capacity B (default N / 8).
    #[arg(long)]
    blocks: Option<usize>,
    /// Dataset directory: simulate each trajectory at this capacity.
    #[arg(long)]
    dataset: Option<PathBuf>,
    /// Split of the prepared layout.
    #[arg(long)]
    split: Option<String>,
    /// Use every stride-th pixel of the dataset frames.
    #[arg(long, default_value_t = 1)]
    stride: u32,
}

#[derive(clap::Args)]
struct TestvectorArgs {
    /// Directory to write frames.bin and expected_crc.txt into.
    #[arg(long)]
    out: Option<PathBuf>,
    /// A vector to integrate and check (against expected_crc.txt beside it).
    #[arg(long)]
    check: Option<PathBuf>,
}

#[derive(clap::Args)]
struct DemoArgs {
    /// Output directory for pictures, back-projections and metrics.
    #[arg(long, default_value = "out/demo")]
    out: PathBuf,
    /// Voxel edge in metres.
    #[arg(long, default_value_t = 0.10)]
    cell: f32,
    /// Synthetic scenes (kinds cycle: living, bedroom, kitchen, office, bathroom, open plan).
    #[arg(long, default_value_t = 2)]
    scenes: usize,
    /// Frames per trajectory.
    #[arg(long, default_value_t = 20)]
    frames: usize,
    /// Use constant misses instead of NDT-OM misses.
    #[arg(long)]
    constant_miss: bool,
}

/// Parses the command line and runs the command.
pub fn main() -> Result<()> {
    match Cli::parse().command {
        Command::Demo(a) => demo(&a),
        Command::Experiment(a) => experiment(&a),
        Command::Synth(a) => synth(&a),
        Command::Compare(a) => {
            println!("{}", crate::eval::compare::command(&a)?);
            Ok(())
        }
        Command::Map(a) => map_command(&a),
        Command::Export(a) => export(&a),
        Command::Budget(a) => {
            let dataset = a.dataset.as_deref();
            let (cell, classes, blocks) = (a.cell, a.classes, a.blocks);
            let report = crate::embedded::budget::command(
                cell, classes, a.capacity, blocks, dataset, a.split, a.stride,
            )?;
            println!("{report}");
            Ok(())
        }
        Command::Testvector(a) => {
            let summary =
                crate::embedded::testvector::command(a.out.as_deref(), a.check.as_deref())?;
            println!("{summary}");
            Ok(())
        }
        Command::Cloud(a) => {
            let options = crate::dataset::source::OpenOptions {
                split: Some(a.split),
                paper_fy: a.paper_fy,
                predictions: None,
            };
            let summary =
                crate::output::ply::cloud_command(&a.dataset, &a.frame, &a.out, &options)?;
            println!("{summary}");
            Ok(())
        }
    }
}

fn demo(a: &DemoArgs) -> Result<()> {
    crate::cli::demo::run(&crate::cli::demo::DemoOptions {
        out: a.out.clone(),
        cell: a.cell,
        scenes: a.scenes,
        frames: a.frames,
        constant_miss: a.constant_miss,
    })
}

fn synth(a: &SynthArgs) -> Result<()> {
    use crate::dataset::synthetic::{write_split, DepthNoise, SynthOptions, Synthetic};
    let t = Instant::now();
    let options = SynthOptions {
        scenes: a.scenes,
        frames: a.frames,
        seed: a.seed,
        noise: a.noise.then_some(DepthNoise::KINECT),
        predictions: !a.no_predictions,
        ..SynthOptions::default()
    };
    let split = Synthetic::new(options)?;
    println!(
        "sndt synth: {} -> {}",
        crate::dataset::source::Dataset::describe(&split),
        a.out.display()
    );
    let bar = progress((a.scenes * a.frames) as u64, "synth");
    let summary = write_split(&a.out, &split, &|| bar.inc(1))?;
    bar.finish_and_clear();
    let total: u64 = summary.class_pixels.iter().sum();
    println!(
        "{} frames in {:.1} s",
        summary.frames,
        t.elapsed().as_secs_f64()
    );
    println!("ground-truth class histogram (share of all pixels):");
    for (c, &n) in summary.class_pixels.iter().enumerate() {
        if n > 0 {
            println!(
                "  {:>2} {:<14} {:7.3} %",
                c,
                NYU40[c],
                100.0 * n as f64 / total as f64
            );
        }
    }
    let present = summary.class_pixels[1..].iter().filter(|&&n| n > 0).count();
    println!("{present} of 40 classes occur");
    // Previews: ground truth | prediction for the first and the middle frame of each scene.
    let dir = a.out.join("preview");
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    for (_, ids) in crate::dataset::source::Dataset::trajectories(&split) {
        for id in [&ids[0], &ids[ids.len() / 2]] {
            let f = crate::dataset::source::Dataset::load(&split, id)?;
            let gt = f.labels.clone().unwrap_or_default();
            let pred = f
                .predictions
                .as_ref()
                .map(|p| p.top1())
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

fn experiment(a: &ExperimentArgs) -> Result<()> {
    use crate::dataset::frame::LabelSource;
    use crate::dataset::open::open_spec;
    use crate::dataset::source::Every;
    use crate::eval::experiment::{progress_steps, run, ExperimentOptions};
    let options = a.open.options();
    let mut dataset = open_spec(&a.dataset, &options)?;
    if a.every > 1 {
        dataset = Box::new(Every::new(dataset, a.every));
    }
    println!("sndt experiment: {}", dataset.describe());
    let labels = match a.labels {
        ExperimentLabels::Gt => vec![LabelSource::Gt],
        ExperimentLabels::Pred => vec![LabelSource::Pred],
        ExperimentLabels::Both => vec![LabelSource::Gt, LabelSource::Pred],
    };
    let opts = ExperimentOptions {
        labels,
        cells: a.cells.clone(),
        kernels: a.kernels.clone(),
        methods: a.methods.clone(),
        free_resolution: a.free_resolution,
        votes_per_frame: a.votes_per_frame,
    };
    let frames = dataset.frames().len();
    let steps = progress_steps(&opts, frames);
    let bar = progress(steps, "experiment");
    let t = Instant::now();
    // Long runs in logs (no terminal, bar hidden): a line every 5 %.
    let done = std::sync::atomic::AtomicU64::new(0);
    let tick = || {
        bar.inc(1);
        let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        if bar.is_hidden() && n * 20 / steps != (n - 1) * 20 / steps {
            eprintln!(
                "experiment: {} % after {:.0} s",
                n * 100 / steps,
                t.elapsed().as_secs_f64()
            );
        }
    };
    let exp = run(dataset.as_ref(), &opts, &tick)?;
    bar.finish_and_clear();
    println!(
        "{} trajectories, {} frames, {:.0} s\n",
        dataset.trajectories().len(),
        exp.frames,
        t.elapsed().as_secs_f64()
    );
    for (l, c) in &exp.inputs {
        let m = c.metrics();
        println!(
            "input labels {l:?} on the frames themselves: mIoU {:.2} %, mPAcc {:.2} %",
            m.miou * 100.0,
            m.mpacc * 100.0
        );
    }
    println!(
        "\nTable I (mIoU / invR / mPAcc, %)\n{}",
        exp.table1_markdown()
    );
    println!(
        "Table II (map update rate, Hz, single thread; S-BKI and OS-BKI share one map)\n{}",
        exp.table2_markdown()
    );
    println!(
        "Surface voxels read as free (holes, %)\n{}",
        exp.holes_markdown()
    );
    for p in exp.write(&a.out)? {
        println!("wrote {}", p.display());
    }
    Ok(())
}

fn map_command(a: &MapArgs) -> Result<()> {
    use crate::dataset::open::open_spec;
    use crate::eval::evaluate::{evaluate, EvalOptions};
    let options = a.open.options();
    let dataset = open_spec(&a.dataset, &options)?;
    println!("sndt map: {}", dataset.describe());
    let frames = dataset.frames().len();
    let bar = progress(2 * frames as u64, "map+eval");
    let eval = evaluate(
        dataset.as_ref(),
        &EvalOptions {
            out: Some(a.out.clone()),
            stride: a.stride,
            save_maps: a.save_maps.then(|| a.out.join("maps")),
            ..EvalOptions::new(
                Config {
                    votes_per_frame: a.votes_per_frame,
                    ..Config::with_cell_size(a.cell)
                },
                a.labels,
            )
        },
        &|| bar.inc(1),
    )?;
    bar.finish_and_clear();
    for t in &eval.trajectories {
        println!(
            "  {}: {} frames, {:.1} ms/frame, {} voxels, {} blocks, {} evicted",
            t.name,
            t.frames,
            t.mean_ms(),
            t.voxels,
            t.blocks,
            t.evicted
        );
    }
    let table = eval.table();
    println!(
        "\ncell {:.0} cm, {:?} labels\n{table}",
        a.cell * 100.0,
        a.labels
    );
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    std::fs::write(a.out.join("metrics.md"), &table)?;
    std::fs::write(
        a.out.join("metrics.json"),
        serde_json::to_string_pretty(&eval.to_json())?,
    )?;
    println!(
        "wrote {}/<scene>/<cam>/<NNNN>.png, metrics.json, metrics.md",
        a.out.display()
    );
    Ok(())
}

fn export(a: &ExportArgs) -> Result<()> {
    use crate::dataset::open::open_spec;
    use crate::eval::evaluate::load_snapshot;
    use crate::semantic_map::{integrate_frame, HostMap};
    let path = std::path::Path::new(&a.input);
    let map: Box<HostMap> = if path.is_file() {
        load_snapshot(path)?
    } else {
        let dataset = open_spec(&a.input, &crate::dataset::source::OpenOptions::default())?;
        let trajectories = dataset.trajectories();
        let (name, ids) = trajectories
            .first()
            .ok_or_else(|| anyhow::anyhow!("{}: no frames", a.input))?;
        let mut map: Box<HostMap> = crate::semantic_map::boxed_map(Config::with_cell_size(a.cell))
            .map_err(|e| anyhow::anyhow!("config: {e:?}"))?;
        let bar = progress(ids.len() as u64, "map");
        for id in ids {
            integrate_frame(map.as_mut(), &dataset.load(id)?, a.labels, 1)?;
            bar.inc(1);
        }
        bar.finish_and_clear();
        println!("mapped {name}: {} frames", ids.len());
        map
    };
    let es = crate::output::export::ellipsoids(map.as_ref(), a.min_points);
    match a.ellipsoids {
        Some(s) => crate::output::export::write_ellipsoids(&a.ply, &es, s)?,
        None => crate::output::export::write_points(&a.ply, &es)?,
    }
    println!(
        "wrote {}: {} occupied Gaussians of {} voxels ({})",
        a.ply.display(),
        es.len(),
        map.len(),
        a.ellipsoids
            .map_or("points at the means".to_string(), |s| format!(
                "ellipsoids at {s} sigma"
            ))
    );
    Ok(())
}
