//! `sndt experiment`: the paper's comparison of S-NDT, S-BKI and OS-BKI per cell size and
//! kernel length (Tables I and II, per-class IoU, rate-vs-mIoU charts); `--resume`
//! continues an interrupted one from the runs it kept on disk.
//!
//! This file parses the options, opens the dataset, hands both to
//! [`run_experiment`] once and prints what it returns: planning, running, the
//! stored runs and the reports are all the experiment's own
//! ([`crate::eval::experiment`]).

use crate::cli::labels::{check_labels, LabelArg};
use crate::cli::open_args::{EveryArgs, OpenArgs, PredictionsArgs};
use crate::dataset::open::open_spec;
use crate::dataset::source::Dataset;
use crate::eval::experiment::store::Manifest;
use crate::eval::experiment::{run_experiment, Experiment, ExperimentOptions, ExperimentRequest};
use crate::eval::experiment::{Finished, Method};
use anyhow::{bail, Result};
use clap::ValueEnum;
use sndt_core::Config;
use std::path::PathBuf;

/// `--methods`: the command line's name for [`Method`], so that clap stays in `cli`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MethodArg {
    /// Semantic occupancy NDT (sndt-core).
    Sndt,
    /// Semantic Bayesian kernel inference (Gan et al. 2020).
    Sbki,
    /// The paper's optimised S-BKI.
    Osbki,
}

impl From<MethodArg> for Method {
    fn from(a: MethodArg) -> Method {
        match a {
            MethodArg::Sndt => Method::Sndt,
            MethodArg::Sbki => Method::Sbki,
            MethodArg::Osbki => Method::Osbki,
        }
    }
}

/// Arguments of `sndt experiment`.
#[derive(clap::Args, Clone, Debug)]
#[command(after_help = "Examples:
  sndt experiment synthetic --every 2 --cell 0.05,0.1 --out out/experiment
  sndt experiment data/synth --labels gt --methods sndt --out out/experiment-gt")]
pub struct ExperimentArgs {
    /// Dataset: a directory (prepared layout or raw Hypersim), a ROS 2 bag (`.mcap` file or
    /// rosbag2 folder), `synthetic[:SCENES:FRAMES]` or `synthetic:floor[:WALK[:FRAMES]]`
    /// (rendered on the fly).
    pub dataset: String,
    /// Labels fed to the maps, comma separated: each is run in turn (the values of `sndt
    /// map --labels`, of which the paper's comparison takes ground truth and predicted top
    /// 1).
    #[arg(long, value_delimiter = ',', default_value = "gt,pred", value_parser = super::labels::gt_or_pred())]
    pub labels: Vec<LabelArg>,
    /// Cell sizes, metres (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "0.05,0.1,0.15,0.2", value_parser = super::parse::positive)]
    pub cell: Vec<f32>,
    /// Kernel lengths of S-BKI and OS-BKI, metres.
    #[arg(long, value_delimiter = ',', default_value = "0.1,0.2,0.3,0.4", value_parser = super::parse::positive)]
    pub kernels: Vec<f32>,
    /// Methods.
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "sndt,sbki,osbki"
    )]
    pub methods: Vec<MethodArg>,
    /// Spacing of BKI free samples along each ray, metres (default 0.3).
    #[arg(long)]
    pub free_resolution: Option<f32>,
    /// S-NDT: about how many votes a voxel takes from one frame (1..=64;
    /// `Config::votes_per_frame`).
    #[arg(long, default_value_t = Config::DEFAULT.votes_per_frame)]
    pub votes_per_frame: u8,
    /// S-NDT: log-odds of the see-through miss that clears what moved
    /// (`Config::see_through_miss`: in [-30, 0], a multiple of 1/1024; 0 is S-NDT as
    /// published; docs/DYNAMICS.md).
    #[arg(long, default_value_t = Config::DEFAULT.see_through_miss, allow_negative_numbers = true)]
    pub see_through_miss: f32,
    /// Which frames to map.
    #[command(flatten)]
    pub every: EveryArgs,
    /// Output directory for tables and charts. Each finished run (one map on one
    /// trajectory) is also kept in `<out>/runs/` as soon as it is finished.
    #[arg(long, default_value = "out/experiment")]
    pub out: PathBuf,
    /// Continue an interrupted experiment in `--out`: the runs kept in `<out>/runs/` are
    /// taken instead of computed again, the rest is run, and the same tables are written
    /// (resumed runs keep the update times measured when they ran). Refused if they were
    /// made with other options. Without `--resume`, the runs kept in `<out>/runs/` are
    /// removed and everything is computed afresh.
    #[arg(long)]
    pub resume: bool,
    /// How to open the dataset.
    #[command(flatten)]
    pub open: OpenArgs,
    /// Where the predicted labels are.
    #[command(flatten)]
    pub predictions: PredictionsArgs,
}

impl ExperimentArgs {
    /// The experiment's grid these arguments ask for.
    pub fn options(&self) -> ExperimentOptions {
        ExperimentOptions {
            labels: self.labels.iter().map(|&l| l.into()).collect(),
            cells: self.cell.clone(),
            kernels: self.kernels.clone(),
            methods: self.methods.iter().map(|&m| m.into()).collect(),
            free_resolution: self.free_resolution,
            votes_per_frame: self.votes_per_frame,
            see_through_miss: self.see_through_miss,
        }
    }

    /// Everything [`run_experiment`] needs besides the dataset: the grid, the output, and
    /// what the stored runs depend on that the opened dataset does not tell (the dataset
    /// as given, `--every`, how it was opened).
    pub fn request(&self) -> ExperimentRequest {
        let provenance: Manifest = [
            ("dataset", self.dataset.clone()),
            ("--every", self.every.every.max(1).to_string()),
            (
                "dataset options",
                format!("{:?} {:?}", self.open, self.predictions),
            ),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
        ExperimentRequest {
            options: self.options(),
            provenance,
            out: self.out.clone(),
            resume: self.resume,
        }
    }

    /// Opens the dataset (every k-th frame with `--every`) and says which it is. A label
    /// given twice is refused (its runs would be made twice), and so are predicted labels
    /// asked of a dataset without predictions, since maps without labels would score 0 %
    /// and look like a result.
    fn open_dataset(&self) -> Result<Box<dyn Dataset>> {
        for (k, label) in self.labels.iter().enumerate() {
            if self.labels[..k].contains(label) {
                let name = label.to_possible_value().map(|v| v.get_name().to_string());
                bail!("--labels: {} given twice", name.unwrap_or_default());
            }
        }
        let options = self.open.options_with(&self.predictions)?;
        let dataset = self.every.apply(open_spec(&self.dataset, &options)?);
        println!("sndt experiment: {}", dataset.describe());
        for &label in &self.labels {
            check_labels(label, dataset.as_ref(), &self.dataset)?;
        }
        Ok(dataset)
    }
}

/// Runs `sndt experiment`: runs every method, label source, cell size and kernel length
/// (taking finished runs from `<out>/runs/` with `--resume`), writes the tables and charts
/// into `--out` and prints them.
pub fn run(a: &ExperimentArgs) -> Result<()> {
    let request = a.request();
    let dataset = a.open_dataset()?;
    let finished = run_experiment(dataset.as_ref(), &request)?;
    print_finished(&finished);
    Ok(())
}

/// Prints what the experiment did, its tables and the files it wrote.
fn print_finished(f: &Finished) {
    let exp = &f.experiment;
    let skipped = match exp.skipped {
        0 => String::new(),
        k => format!(", {k} skipped (bad input, named in the warnings)"),
    };
    println!(
        "{} trajectories, {} frames mapped{skipped}, {:.0} s",
        f.trajectories, exp.frames, f.seconds
    );
    println!(
        "resumed {} of {} runs, computed {} (a run: one map on one trajectory; kept in {})\n",
        f.resumed,
        f.resumed + f.computed,
        f.computed,
        f.runs_dir.display()
    );
    print_tables(exp);
    for p in &f.written {
        println!("wrote {}", p.display());
    }
}

/// Prints the input labels' own scores, Tables I and II and the holes table.
fn print_tables(exp: &Experiment) {
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
}
