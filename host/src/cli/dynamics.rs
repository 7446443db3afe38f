//! `sndt dynamics`: how fast the map clears what moved and relabels what replaced it, and
//! what the static scene loses, against OctoMap on the same points (docs/DYNAMICS.md).

use crate::cli::labels::LabelArg;
use crate::cli::parse::check_config;
use crate::dataset::frame::LabelSource;
use crate::dataset::open::synthetic_options;
use crate::dataset::synthetic::Synthetic;
use crate::dataset::Dataset;
use crate::eval::dynamics::{run as run_dynamics, DynamicsOptions, DynamicsReport, Mapper};
use crate::output::chart::{ghost_over_time, GhostPanel};
use crate::output::progress::progress;
use anyhow::{bail, Context, Result};
use sndt_core::{Config, ConfigField};
use std::path::PathBuf;

/// Arguments of `sndt dynamics`.
#[derive(clap::Args, Clone, Debug)]
#[command(after_help = "Examples:
  sndt dynamics synthetic:dynamic --camera-scale 0.5
  sndt dynamics synthetic:dynamic --cell 0.1,0.05 --octomap target/octomap/octomap_dynamics
  sndt dynamics synthetic:dynamic:200:60 --labels pred --see-through-miss 0,-1.5,-3
  sndt dynamics synthetic:floor-people --camera-scale 0.25")]
pub struct DynamicsArgs {
    /// The dynamic room, `synthetic:dynamic[:FRAMES[:CHANGE]]` (160 frames, the first change
    /// at frame 30; every event must fit in the walk), or the floor walk with people in the
    /// corridor, `synthetic:floor-people[:WALK[:FRAMES]]` (1,000 frames).
    #[arg(default_value = "synthetic:dynamic")]
    pub dataset: String,
    /// Voxel edges in metres, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "0.1", value_parser = super::parse::positive)]
    pub cell: Vec<f32>,
    /// Labels fed to the map.
    #[arg(long, value_enum, default_value = "gt")]
    pub labels: LabelArg,
    /// The `octomap_dynamics` program (scripts/octomap/octomap_dynamics.cpp, built by
    /// scripts/dynamics.sh): OctoMap runs on the same points at every cell size.
    #[arg(long, value_name = "PROGRAM")]
    pub octomap: Option<PathBuf>,
    /// Scale of the camera (1: Hypersim's 1024x768; 0.5: 512x384, four times faster).
    #[arg(long, default_value_t = 1.0, value_parser = super::parse::positive)]
    pub camera_scale: f32,
    /// NDT-OM miss weight `lambda` (`Config::lambda`), in [0, 0.49].
    #[arg(long, default_value_t = Config::DEFAULT.lambda)]
    pub lambda: f32,
    /// Log-odds of the see-through miss (`Config::see_through_miss`), comma-separated: one
    /// S-NDT map per value (each in [-30, 0], a multiple of 1/1024; 0 is S-NDT as
    /// published).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "0,-3",
        allow_negative_numbers = true
    )]
    pub see_through_miss: Vec<f32>,
    /// Upper log-odds clamp (`Config::clamp_max`), in [0, 30].
    #[arg(long, default_value_t = Config::DEFAULT.clamp_max)]
    pub clamp_max: f32,
    /// Output directory: dynamics.md, dynamics.json, ghost.svg and OctoMap's files.
    #[arg(long, default_value = "out/dynamics")]
    pub out: PathBuf,
}

/// Runs `sndt dynamics`: maps the dynamic walk and its frozen twin, prints the tables and
/// writes them with the ghost chart.
pub fn run(a: &DynamicsArgs) -> Result<()> {
    let Some(options) = synthetic_options(&a.dataset) else {
        bail!(
            "{}: the dynamics report runs on the dynamic room, synthetic:dynamic[:FRAMES[:CHANGE]], \
             or the floor walk with people, synthetic:floor-people[:WALK[:FRAMES]]",
            a.dataset
        );
    };
    let mut options = options?;
    options.camera = scaled(&options.camera, a.camera_scale)?;
    if options.dynamic.is_none_or(|d| d.frozen) {
        bail!(
            "{}: the dynamics report runs on the dynamic room, synthetic:dynamic[:FRAMES[:CHANGE]], \
             or the floor walk with people, synthetic:floor-people[:WALK[:FRAMES]]",
            a.dataset
        );
    }
    let labels = LabelSource::from(a.labels);
    if !matches!(labels, LabelSource::Gt | LabelSource::Pred) {
        bail!("--labels: the dynamics report runs with gt or pred labels");
    }
    let mut mappers = Vec::new();
    for &cell in &a.cell {
        for &see in &a.see_through_miss {
            let config = Config {
                lambda: a.lambda,
                see_through_miss: see,
                clamp_max: a.clamp_max,
                ..Config::with_cell_size(cell)
            };
            let (cell_flag, see_flag) = (
                format!("--cell {cell}"),
                format!("--see-through-miss {see}"),
            );
            let flags = [
                (ConfigField::CellSize, &cell_flag[..]),
                (ConfigField::RayCells, &cell_flag),
                (ConfigField::SeeThroughMiss, &see_flag),
            ];
            check_config(&config, &flags)?;
            let name = match see {
                0.0 => "sndt published".to_string(),
                _ => format!("sndt see-through {see}"),
            };
            mappers.push(Mapper { name, config });
        }
    }
    let split = Synthetic::new(options)?;
    println!("sndt dynamics: {}", split.describe());
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let bar = progress(2 * split.frames().len() as u64, "dynamics");
    let report = run_dynamics(
        &split,
        &DynamicsOptions {
            mappers,
            labels,
            octomap: a.octomap.clone(),
            work: a.out.clone(),
        },
        &|| bar.inc(1),
    )?;
    bar.finish_and_clear();
    let table = report.table();
    println!("{table}");
    write_report(&report, &table, a)
}

/// Writes dynamics.md, dynamics.json and ghost.svg into `a.out`.
fn write_report(report: &DynamicsReport, table: &str, a: &DynamicsArgs) -> Result<()> {
    let md = a.out.join("dynamics.md");
    let heading = format!("# sndt dynamics {}\n", a.dataset);
    crate::atomic::write_atomic(&md, |tmp| {
        std::fs::write(tmp, format!("{heading}{table}")).context("writing dynamics.md")
    })?;
    let json = a.out.join("dynamics.json");
    crate::atomic::write_atomic(&json, |tmp| {
        let text = serde_json::to_string_pretty(&report.to_json())?;
        std::fs::write(tmp, text).context("writing dynamics.json")
    })?;
    let panels: Vec<GhostPanel> = report
        .events
        .iter()
        .enumerate()
        .map(|(e, event)| {
            let series = report.mappers.iter().map(|m| {
                let name = format!("{} {:.2}", m.name, m.cell);
                (name, &m.events[e].ghost[..])
            });
            (event.name.to_string(), event.vacated, series.collect())
        })
        .collect();
    let svg = a.out.join("ghost.svg");
    ghost_over_time(&svg, "Ghost surface after each frame", &panels)?;
    println!(
        "wrote {}, {} and {}",
        md.display(),
        json.display(),
        svg.display()
    );
    Ok(())
}

/// `camera` with its image `scale` times as large (intrinsics scaled alike).
fn scaled(camera: &sndt_core::Pinhole, scale: f32) -> Result<sndt_core::Pinhole> {
    let (w, h) = (camera.width as f32 * scale, camera.height as f32 * scale);
    if !(1.0..=8192.0).contains(&w.round()) || !(1.0..=8192.0).contains(&h.round()) {
        bail!("--camera-scale {scale}: a {w:.0}x{h:.0} image");
    }
    Ok(sndt_core::Pinhole {
        fx: camera.fx * scale,
        fy: camera.fy * scale,
        cx: camera.cx * scale,
        cy: camera.cy * scale,
        width: w.round() as u32,
        height: h.round() as u32,
    })
}
