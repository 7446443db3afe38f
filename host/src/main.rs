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
