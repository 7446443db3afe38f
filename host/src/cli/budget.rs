//! `sndt budget`: the exact memory of a `Map<N, B, K>` and, given a dataset, the peak
//! occupancy and evictions of each trajectory at that capacity.

use crate::dataset::open::open_spec;
use crate::dataset::source::OpenOptions;
use crate::embedded::budget::{
    pick_capacity, report, simulate_dataset, spill_table, table, CAPACITIES,
};
use anyhow::{bail, Result};
use sndt_core::Config;
use std::path::PathBuf;

/// Arguments of `sndt budget`.
#[derive(clap::Args, Clone, Debug)]
#[command(after_help = "Examples:
  sndt budget --capacity 4096 --blocks 512 --cell 0.1
  sndt budget data/synth --capacity 16384
  sndt budget synthetic:floor --capacity 4096 --blocks 512 --fps 10")]
pub struct BudgetArgs {
    /// Dataset whose trajectories to simulate at this capacity: a directory (prepared
    /// layout or raw Hypersim), a ROS 2 bag (`.mcap` file or rosbag2 folder), `synthetic[:SCENES:FRAMES]` or
    /// `synthetic:floor[:WALK[:FRAMES]]` (rendered on the fly).
    pub dataset: Option<PathBuf>,
    /// Voxel edge in metres.
    #[arg(long, default_value_t = 0.10, value_parser = super::parse::positive)]
    pub cell: f32,
    /// Classes K.
    #[arg(long, default_value_t = 40)]
    pub classes: usize,
    /// Surface voxel capacity N.
    #[arg(long)]
    pub capacity: usize,
    /// Occupancy block capacity B (default N / 8).
    #[arg(long)]
    pub blocks: Option<usize>,
    /// Deprecated spelling of the DATASET argument.
    #[arg(long = "dataset", hide = true, conflicts_with = "dataset")]
    pub dataset_option: Option<PathBuf>,
    /// Split of the prepared layout.
    #[arg(long, default_value = "test")]
    pub split: String,
    /// Use every stride-th pixel in both directions of the dataset's frames (1 = all).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub stride: u32,
    /// With a dataset: frames per second for the spill bandwidth (bytes/s of evicted
    /// records sent to a host).
    #[arg(long, default_value_t = 10.0, value_parser = super::parse::positive)]
    pub fps: f32,
    /// With a dataset: the UART baud rate the spill bandwidth is compared with.
    #[arg(long, default_value_t = 921_600)]
    pub baud: u32,
}

/// Runs `sndt budget` and prints its report.
pub fn run(a: &BudgetArgs) -> Result<()> {
    println!("{}", budget(a)?);
    Ok(())
}

/// The memory report for `Map<capacity, blocks, classes>` (blocks default to
/// `capacity / 8`, the firmware's ratio) and, given a dataset directory, the peak
/// occupancy and evictions of each of its trajectories at that capacity (rounded up to a
/// compiled one, 40 classes, ground-truth labels).
///
/// ```
/// use sndt_host::cli::budget::{budget, BudgetArgs};
/// let mut a = BudgetArgs { dataset: None, cell: 0.1, classes: 40, capacity: 4096,
///                          blocks: Some(512), dataset_option: None, split: "test".into(),
///                          stride: 1, fps: 10.0, baud: 921_600 };
/// assert!(budget(&a).unwrap().contains("= 485504 bytes"));
/// a.classes = 0;
/// assert!(budget(&a).is_err());
/// ```
pub fn budget(a: &BudgetArgs) -> Result<String> {
    let (cell, classes, capacity) = (a.cell, a.classes, a.capacity);
    if !(1..=254).contains(&classes) {
        bail!("--classes must be in 1..=254");
    }
    if capacity == 0 || capacity >= u32::MAX as usize {
        bail!("--capacity must be in 1..2^32-1");
    }
    let blocks = a.blocks.unwrap_or(capacity.div_ceil(8)).max(1);
    let mut s = report(cell, classes, capacity, blocks);
    let dataset = super::parse::renamed(
        a.dataset.clone(),
        a.dataset_option.clone().map(Some),
        "--dataset DIR",
        "the DATASET argument",
    );
    let Some(root) = dataset.as_deref() else {
        return Ok(s);
    };
    let config = Config::with_cell_size(cell);
    super::parse::check_cell_config(&config, cell)?;
    let Some(cap) = pick_capacity(capacity, blocks) else {
        bail!(
            "no compiled capacity holds {capacity} voxels and {blocks} blocks (largest: {:?})",
            CAPACITIES[CAPACITIES.len() - 1]
        );
    };
    let options = OpenOptions {
        split: Some(a.split.clone()),
        ..Default::default()
    };
    let ds = open_spec(&root.to_string_lossy(), &options)?;
    s += &format!("\n{}\n", ds.describe());
    if cap != (capacity, blocks) {
        s += &format!(
            "simulating Map<{}, {}, 40> (the smallest compiled capacity holding {capacity} voxels and {blocks} blocks)\n",
            cap.0, cap.1
        );
    }
    if classes != 40 {
        s += "the simulation uses 40 classes (NYU40 labels)\n";
    }
    let rows = simulate_dataset(ds.as_ref(), config, cap, a.stride)?;
    s += &table(&rows, cap, (capacity, blocks));
    s += &spill_table(&rows, a.fps as f64, a.baud);
    Ok(s)
}
