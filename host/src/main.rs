//! `sndt`: the host command line.

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use sndt_core::{Config, MissModel};
use sndt_host::colors::{render_color, NYU40};
use sndt_host::eval::Confusion;
use sndt_host::room::{orbit, Scene, HYPERSIM_CAMERA};
use sndt_host::{picture, progress};
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
    /// Map the built-in box room (no download), print metrics, write pictures.
    Demo(DemoArgs),
    /// Exact memory of a Map<N, B, K>; with a dataset, peak voxels and evictions per trajectory.
    Budget(BudgetArgs),
    /// Write (--out) or check (--check) the cross-architecture test vector of the firmware.
    Testvector(TestvectorArgs),
    /// Write one frame's world points, coloured by label, as a PLY point cloud.
    Cloud(CloudArgs),
    /// Generate a synthetic labelled split in the prepared layout (no download).
    Synth(SynthArgs),
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
    #[arg(long, default_value_t = sndt_host::synth::DEFAULT_SEED)]
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
    /// Output directory for pictures.
    #[arg(long, default_value = "out/demo")]
    out: PathBuf,
    /// Voxel edge in metres.
    #[arg(long, default_value_t = 0.10)]
    cell: f32,
    /// Frames of the walk around the room.
    #[arg(long, default_value_t = 12)]
    frames: usize,
    /// Use constant misses instead of NDT-OM misses.
    #[arg(long)]
    constant_miss: bool,
}

/// Map capacity of the demo: 2^19 NDT voxels, 2^17 blocks, 40 classes (~71 MiB).
type DemoMap = sndt_core::Map<{ 1 << 19 }, { 1 << 17 }, 40>;

fn main() -> Result<()> {
    match Cli::parse().command {
        Command::Demo(a) => demo(&a),
        Command::Synth(a) => synth(&a),
        Command::Budget(a) => {
            let dataset = a.dataset.as_deref();
            let (cell, classes, blocks) = (a.cell, a.classes, a.blocks);
            let report = sndt_host::budget::command(
                cell, classes, a.capacity, blocks, dataset, a.split, a.stride,
            )?;
            println!("{report}");
            Ok(())
        }
        Command::Testvector(a) => {
            let summary = sndt_host::testvector::command(a.out.as_deref(), a.check.as_deref())?;
            println!("{summary}");
            Ok(())
        }
        Command::Cloud(a) => {
            let options = sndt_host::dataset::OpenOptions {
                split: Some(a.split),
                paper_fy: a.paper_fy,
                predictions: None,
            };
            let summary = sndt_host::ply::cloud_command(&a.dataset, &a.frame, &a.out, &options)?;
            println!("{summary}");
            Ok(())
        }
    }
}

fn demo(a: &DemoArgs) -> Result<()> {
    let scene = Scene::simple_room();
    let cam = HYPERSIM_CAMERA;
    let poses = orbit(a.frames);
    let mut config = Config::with_cell_size(a.cell);
    if a.constant_miss {
        config.miss_model = MissModel::Constant;
    }
    let mut map: Box<DemoMap> =
        sndt_host::boxed_map(config).map_err(|e| anyhow::anyhow!("config: {e:?}"))?;
    println!(
        "sndt demo: box room, {} frames of {}x{}, cell {:.0} cm, map capacity {} voxels / {} blocks ({:.1} MiB)",
        poses.len(),
        cam.width,
        cam.height,
        a.cell * 100.0,
        1 << 19,
        1 << 17,
        DemoMap::BYTES as f64 / (1 << 20) as f64
    );

    let bar = progress(poses.len() as u64, "render");
    let frames: Vec<_> = poses
        .iter()
        .map(|p| {
            bar.inc(1);
            scene.render(p, &cam)
        })
        .collect();
    bar.finish_and_clear();

    let bar = progress(poses.len() as u64, "map");
    let mut update = Vec::new();
    let mut points = 0u64;
    for (pose, (depth, labels)) in poses.iter().zip(&frames) {
        let img = sndt_host::room::depth_image(&cam, depth, labels);
        let t = Instant::now();
        let r = map
            .integrate_depth(pose, &img)
            .map_err(|e| anyhow::anyhow!("integrate: {e:?}"))?;
        update.push(t.elapsed().as_secs_f64());
        points += r.points_used as u64;
        bar.inc(1);
    }
    bar.finish_and_clear();

    let bar = progress(poses.len() as u64, "back-project");
    let mut confusion = Confusion::default();
    let mut renders = Vec::new();
    let n = (cam.width * cam.height) as usize;
    for (pose, (depth, labels)) in poses.iter().zip(&frames) {
        let (mut pred, mut dist) = (vec![0u8; n], vec![0f32; n]);
        map.render(pose, &cam, &mut pred, &mut dist)
            .map_err(|e| anyhow::anyhow!("render: {e:?}"))?;
        confusion.add_frame(labels, &pred, depth);
        renders.push(pred);
        bar.inc(1);
    }
    bar.finish_and_clear();

    let m = confusion.metrics();
    let mean_ms = update.iter().sum::<f64>() / update.len() as f64 * 1e3;
    let free = map.cells().filter(|(_, l)| *l < 0.0).count();
    let occupied = map.cells().filter(|(_, l)| *l > 0.0).count();
    println!();
    println!("| metric | value |");
    println!("|---|---|");
    println!("| points integrated | {points} |");
    println!("| NDT voxels | {} |", map.len());
    println!("| occupancy blocks | {} |", map.block_count());
    println!("| occupied / free voxels | {occupied} / {free} |");
    println!(
        "| evicted voxels / blocks | {} / {} |",
        map.stats().voxels_evicted,
        map.stats().blocks_evicted
    );
    println!(
        "| memory in use | {:.1} MiB of {:.1} MiB |",
        (map.len() * DemoMap::VOXEL_BYTES + map.block_count() * sndt_core::BLOCK_BYTES) as f64
            / (1 << 20) as f64,
        DemoMap::BYTES as f64 / (1 << 20) as f64
    );
    println!(
        "| update time | {mean_ms:.1} ms/frame ({:.1} Hz) |",
        1e3 / mean_ms
    );
    println!("| mIoU | {:.2} % |", m.miou * 100.0);
    println!("| mPAcc | {:.2} % |", m.mpacc * 100.0);
    println!("| invR | {:.2} % |", m.invr * 100.0);
    println!();
    println!("per-class IoU (classes in the ground truth):");
    for (c, iou) in m.iou.iter().enumerate() {
        if let Some(v) = iou {
            println!("  {:>2} {:<14} {:6.2} %", c, NYU40[c], v * 100.0);
        }
    }

    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let step = (poses.len() / 3).max(1);
    for i in (0..poses.len()).step_by(step).take(3) {
        let path = a.out.join(format!("frame_{i:04}.png"));
        let gt = &frames[i].1;
        picture::side_by_side(
            &path,
            cam.width,
            cam.height,
            &[gt, &renders[i]],
            render_color,
        )?;
        println!("wrote {} (ground truth | back-projection)", path.display());
    }
    let path = a.out.join("birdseye.png");
    picture::birds_eye(&path, map.as_ref(), 2.2)?;
    println!(
        "wrote {} (semantic map from above, ceiling removed)",
        path.display()
    );
    Ok(())
}

fn synth(a: &SynthArgs) -> Result<()> {
    use sndt_host::synth::{write_split, DepthNoise, SynthOptions, Synthetic};
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
        sndt_host::dataset::Dataset::describe(&split),
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
    for (_, ids) in sndt_host::dataset::Dataset::trajectories(&split) {
        for id in [&ids[0], &ids[ids.len() / 2]] {
            let f = sndt_host::dataset::Dataset::load(&split, id)?;
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
