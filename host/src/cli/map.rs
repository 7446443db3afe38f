//! `sndt map`: map every trajectory of a dataset and evaluate the back-projections with the
//! paper's evaluation protocol (docs/EVALUATION.md).

use crate::cli::labels::{check_labels, LabelArg};
use crate::cli::open_args::{EveryArgs, OpenArgs, PredictionsArgs, StrideArgs};
use crate::cli::parse::check_config;
use crate::dataset::frame::LabelSource;
use crate::dataset::open::open_spec;
use crate::eval::evaluate::{evaluate, EvalOptions, Evaluation, SpillSummary};
use crate::mapping::{DeviceCapacity, Spill};
use crate::output::progress::progress;
use anyhow::{Context, Result};
use sndt_core::{Config, ConfigField};
use std::path::{Path, PathBuf};

/// Arguments of `sndt map`.
#[derive(clap::Args, Clone, Debug)]
#[command(after_help = "Examples:
  sndt map synthetic:2:20 --cell 0.05 --save-maps --out out/map
  sndt map robot.mcap --every 2 --world-frame odom --mcap out/robot/map.mcap --mcap-interval 10
  sndt map synthetic:floor --device 4096,512 --out out/floor")]
pub struct MapArgs {
    /// Dataset: a directory (prepared layout or raw Hypersim), a ROS 2 bag (`.mcap` file or rosbag2 folder),
    /// `synthetic[:SCENES:FRAMES]` or `synthetic:floor[:WALK[:FRAMES]]` (rendered on the
    /// fly).
    pub dataset: String,
    /// Voxel edge in metres.
    #[arg(long, default_value_t = 0.10, value_parser = super::parse::positive)]
    pub cell: f32,
    /// Labels fed to the map.
    #[arg(long, value_enum, default_value = "gt")]
    pub labels: LabelArg,
    /// Output directory: back-projection PNGs `<out>/<scene>/<cam>/<NNNN>.png`,
    /// metrics.json and metrics.md.
    #[arg(long, default_value = "out/map")]
    pub out: PathBuf,
    /// How to open the dataset.
    #[command(flatten)]
    pub open: OpenArgs,
    /// Where the predicted labels are.
    #[command(flatten)]
    pub predictions: PredictionsArgs,
    /// Which frames to map.
    #[command(flatten)]
    pub every: EveryArgs,
    /// Which pixels to integrate.
    #[command(flatten)]
    pub stride: StrideArgs,
    /// About how many votes a voxel takes from one frame (1..=64; `Config::votes_per_frame`).
    #[arg(long, default_value_t = Config::DEFAULT.votes_per_frame)]
    pub votes_per_frame: u8,
    /// Log-odds of the see-through miss that clears what moved (`Config::see_through_miss`:
    /// in [-30, 0], a multiple of 1/1024; 0 is S-NDT as published; docs/DYNAMICS.md).
    #[arg(long, default_value_t = Config::DEFAULT.see_through_miss, allow_negative_numbers = true)]
    pub see_through_miss: f32,
    /// Also write each trajectory's map snapshot to `<out>/maps/<scene>_<cam>.sndt`.
    #[arg(long)]
    pub save_maps: bool,
    /// Also write each trajectory's map as a ROS 2 bag (rosbag2, MCAP: PointCloud2,
    /// MarkerArray, /tf_static): this file for one trajectory, `<stem>_<scene>_<cam>.mcap` for
    /// several. A path ending in `/` (or an existing directory) is a bag folder
    /// (`DIR/<DIR's name>_0.mcap` and `DIR/metadata.yaml`; `DIR_<scene>_<cam>/` for several).
    #[arg(long)]
    pub mcap: Option<PathBuf>,
    /// With --mcap: also write the map every N frames (of those --every keeps), so the bag
    /// plays back as a growing map (default: only after the last frame).
    #[arg(long, value_name = "N", value_parser = super::parse::at_least_one)]
    pub mcap_interval: Option<usize>,
    /// Map as a co-processor would: a device map of VOXELS,BLOCKS capacity (1024,128,
    /// 4096,512 or 16384,2048) hands everything it evicts to a global map that grows,
    /// and the merged global map is evaluated. Prints what the spill costs per frame.
    #[arg(long, value_name = "V,B", value_parser = DeviceCapacity::parse)]
    pub device: Option<DeviceCapacity>,
    /// With --device: evaluate the device map alone (what the co-processor keeps).
    #[arg(long, requires = "device")]
    pub device_only: bool,
}

/// Runs `sndt map`: maps and evaluates every trajectory, prints the per-trajectory lines
/// (with the frames skipped for bad input) and the metrics table, and writes metrics.md
/// and metrics.json beside the pictures. Fails on a config the options make invalid, on
/// predicted labels asked of a dataset without them, and when no frame could be mapped.
pub fn run(a: &MapArgs) -> Result<()> {
    let labels = LabelSource::from(a.labels);
    let config = Config {
        votes_per_frame: a.votes_per_frame,
        see_through_miss: a.see_through_miss,
        ..Config::with_cell_size(a.cell)
    };
    let (cell, votes, see) = (
        format!("--cell {}", a.cell),
        format!("--votes-per-frame {}", a.votes_per_frame),
        format!("--see-through-miss {}", a.see_through_miss),
    );
    check_config(
        &config,
        &[
            (ConfigField::CellSize, &cell),
            (ConfigField::RayCells, &cell),
            (ConfigField::VotesPerFrame, &votes),
            (ConfigField::SeeThroughMiss, &see),
        ],
    )?;
    let options = a.open.options_with(&a.predictions)?;
    let dataset = a.every.apply(open_spec(&a.dataset, &options)?);
    check_labels(a.labels, dataset.as_ref(), &a.dataset)?;
    println!("sndt map: {}", dataset.describe());
    let frames = dataset.frames().len();
    let bar = progress(2 * frames as u64, "map+eval");
    let eval = evaluate(
        dataset.as_ref(),
        &EvalOptions {
            out: Some(a.out.clone()),
            stride: a.stride.stride,
            save_maps: a.save_maps.then(|| a.out.join("maps")),
            mcap: a.mcap.clone(),
            mcap_interval: a.mcap_interval,
            mcap_world: a.open.bag.world_frame.clone(),
            device: a.device.map(|d| {
                let readout = if a.device_only {
                    Spill::DeviceOnly
                } else {
                    Spill::Merged
                };
                (d, readout)
            }),
            ..EvalOptions::new(config, labels)
        },
        &|| bar.inc(1),
    )?;
    bar.finish_and_clear();
    for t in &eval.trajectories {
        println!(
            "  {}: {} frames, {} skipped, {:.1} ms/frame, {} voxels, {} blocks, {} evicted",
            t.name,
            t.frames,
            t.skipped,
            t.mean_ms(),
            t.voxels,
            t.blocks,
            t.evicted
        );
        if let Some(s) = &t.spill {
            print_spill(s, a.device_only);
        }
    }
    println!(
        "{} frames mapped, {} skipped (bad input, named in the warnings)",
        eval.frames(),
        eval.skipped()
    );
    let table = eval.table();
    println!(
        "\ncell {:.0} cm, {:?} labels\n{table}",
        a.cell * 100.0,
        labels
    );
    write_metrics(&eval, &table, &a.out)
}

/// The spill figures of one trajectory.
fn print_spill(s: &SpillSummary, device_only: bool) {
    let st = &s.stats;
    println!(
        "    device {},{}: {} voxels, {} blocks at the end, {} points and {} misses dropped \
         (full); spilled {} records ({} dropped), stream {:.0} bytes/frame mean, {} max, \
         {} for the final map",
        s.device.0,
        s.device.1,
        s.device_voxels,
        s.device_blocks,
        st.dropped_points,
        st.dropped_misses,
        st.records,
        st.dropped,
        st.mean_bytes(),
        st.max_bytes(),
        st.final_bytes
    );
    println!(
        "    global map: tier {} ({:.0} MiB); scored below: the {} map; the {} map: \
         mIoU {:.2} %, invR {:.2} %, mPAcc {:.2} %",
        s.global_tier,
        s.global_bytes as f64 / (1 << 20) as f64,
        if device_only {
            "device"
        } else {
            "merged global"
        },
        if device_only {
            "merged global"
        } else {
            "device"
        },
        100.0 * s.other.0,
        100.0 * s.other.1,
        100.0 * s.other.2
    );
}

/// Writes the metrics table (`metrics.md`) and all numbers (`metrics.json`) into `out`.
fn write_metrics(eval: &Evaluation, table: &str, out: &Path) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    crate::atomic::write_bytes(&out.join("metrics.md"), table)?;
    crate::atomic::write_bytes(
        &out.join("metrics.json"),
        serde_json::to_string_pretty(&eval.to_json())?,
    )?;
    println!(
        "wrote {}/<scene>/<cam>/<NNNN>.png, metrics.json, metrics.md",
        out.display()
    );
    Ok(())
}
