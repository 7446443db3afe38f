//! `sndt budget`: the exact memory of a `Map<N, B, K>` and, given a dataset, the peak
//! occupancy and evictions of each trajectory at that capacity.

use crate::cli::open_args::{OpenArgs, StrideArgs};
use crate::dataset::open::open_spec;
use crate::embedded::budget::{
    pick_capacity, report, simulate_dataset, spill_table, table, CAPACITIES,
};
use anyhow::{bail, Result};
use sndt_core::Config;

/// Arguments of `sndt budget`.
#[derive(clap::Args, Clone, Debug)]
#[command(after_help = "Examples:
  sndt budget --capacity 4096 --blocks 512 --cell 0.1
  sndt budget data/synth --capacity 16384
  sndt budget synthetic:floor --capacity 4096 --blocks 512 --fps 10
  sndt budget robot.mcap --world-frame odom --capacity 16384")]
pub struct BudgetArgs {
    /// Dataset whose trajectories to simulate at this capacity: a directory (prepared
    /// layout or raw Hypersim), a ROS 2 bag (`.mcap` file or rosbag2 folder), `synthetic[:SCENES:FRAMES]` or
    /// `synthetic:floor[:WALK[:FRAMES]]` (rendered on the fly).
    pub dataset: Option<String>,
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
    /// How to open the dataset.
    #[command(flatten)]
    pub open: OpenArgs,
    /// Which pixels of the dataset's frames to integrate.
    #[command(flatten)]
    pub stride: StrideArgs,
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
/// `capacity / 8`, the firmware's ratio) and, given a dataset, the peak
/// occupancy and evictions of each of its trajectories at that capacity (rounded up to a
/// compiled one, 40 classes, ground-truth labels).
///
/// ```
/// use sndt_host::cli::budget::{budget, BudgetArgs};
/// use sndt_host::cli::open_args::StrideArgs;
/// let mut a = BudgetArgs { dataset: None, cell: 0.1, classes: 40, capacity: 4096,
///                          blocks: Some(512), open: Default::default(),
///                          stride: StrideArgs { stride: 1 }, fps: 10.0, baud: 921_600 };
/// assert!(budget(&a).unwrap().contains("= 485512 bytes"));
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
    let Some(spec) = a.dataset.as_deref() else {
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
    let ds = open_spec(spec, &a.open.options()?)?;
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
    let rows = simulate_dataset(ds.as_ref(), config, cap, a.stride.stride)?;
    s += &table(&rows, cap, (capacity, blocks));
    s += &spill_table(&rows, a.fps as f64, a.baud);
    Ok(s)
}
