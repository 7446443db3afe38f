//! `sndt experiment`: the paper's comparison of S-NDT, S-BKI and OS-BKI per cell size and
//! kernel length (Tables I and II, per-class IoU, rate-vs-mIoU charts); `--resume`
//! continues an interrupted one from the runs it kept on disk.
//!
//! This file parses the options, opens the dataset, hands both to
//! [`run_experiment`] once and prints what it returns: planning, running, the
//! stored runs and the reports are all the experiment's own
//! ([`crate::eval::experiment`]).

use crate::cli::open_args::OpenArgs;
use crate::cli::parse::renamed;
use crate::dataset::frame::LabelSource;
use crate::dataset::open::open_spec;
use crate::dataset::source::{Dataset, Every};
use crate::eval::experiment::store::Manifest;
use crate::eval::experiment::{run_experiment, Experiment, ExperimentOptions, ExperimentRequest};
use crate::eval::experiment::{Finished, Method};
use anyhow::{bail, Result};
use sndt_core::Config;
use std::path::PathBuf;

/// Which labels an experiment maps with: ground truth, predicted top-1, or both (ground
/// truth first).
// The variants have no doc comments: clap would print them in `--help`, whose text stays
// a plain list of the possible values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ExperimentLabels {
    Gt,
    Pred,
    Both,
}

impl ExperimentLabels {
    /// The label sources to run, in order.
    pub fn sources(self) -> Vec<LabelSource> {
        match self {
            ExperimentLabels::Gt => vec![LabelSource::Gt],
            ExperimentLabels::Pred => vec![LabelSource::Pred],
            ExperimentLabels::Both => vec![LabelSource::Gt, LabelSource::Pred],
        }
    }
}

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
#[command(
    after_help = "Example:\n  sndt experiment synthetic --every 2 --cell 0.05,0.1 --out out/experiment"
)]
pub struct ExperimentArgs {
    /// Dataset directory (prepared layout or raw Hypersim), `synthetic[:SCENES:FRAMES]` or
    /// `synthetic:floor[:WALK[:FRAMES]]`.
    pub dataset: String,
    /// Labels fed to the maps.
    #[arg(long, value_enum, default_value = "both")]
    pub labels: ExperimentLabels,
    /// Cell sizes, metres (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "0.05,0.1,0.15,0.2", value_parser = super::parse::positive)]
    pub cell: Vec<f32>,
    /// `--cell`'s old spelling, hidden: taken with a deprecation warning, so that scripts
    /// written before the rename still run (one spelling of cell sizes across commands).
    #[arg(long, hide = true, conflicts_with = "cell", value_delimiter = ',', value_parser = super::parse::positive)]
    pub cells: Option<Vec<f32>>,
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
    /// Use every k-th frame of each trajectory (frames 0, k, 2k, ...; 1 = all, as the
    /// paper). The same option as `map`'s, refusing 0 as it does.
    #[arg(long, value_name = "K", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub every: u32,
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
}

impl ExperimentArgs {
    /// The experiment's grid these arguments ask for; `--cells` (the old spelling of
    /// `--cell`) is taken with a warning on stderr.
    pub fn options(&self) -> ExperimentOptions {
        ExperimentOptions {
            labels: self.labels.sources(),
            cells: renamed(self.cell.clone(), self.cells.clone(), "--cells", "--cell"),
            kernels: self.kernels.clone(),
            methods: self.methods.iter().map(|&m| m.into()).collect(),
            free_resolution: self.free_resolution,
            votes_per_frame: self.votes_per_frame,
        }
    }

    /// Everything [`run_experiment`] needs besides the dataset: the grid, the output, and
    /// what the stored runs depend on that the opened dataset does not tell (the dataset
    /// as given, `--every`, how it was opened).
    pub fn request(&self) -> ExperimentRequest {
        let provenance: Manifest = [
            ("dataset", self.dataset.clone()),
            ("--every", self.every.max(1).to_string()),
            ("dataset options", format!("{:?}", self.open)),
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

    /// Opens the dataset (every k-th frame with `--every`) and says which it is; predicted
    /// labels asked of a dataset without predictions are refused, since maps without
    /// labels would score 0 % and look like a result.
    fn open_dataset(&self) -> Result<Box<dyn Dataset>> {
        let mut dataset = open_spec(&self.dataset, &self.open.options()?)?;
        if self.every > 1 {
            dataset = Box::new(Every::new(dataset, self.every));
        }
        println!("sndt experiment: {}", dataset.describe());
        if self.labels != ExperimentLabels::Gt
            && let Some(place) = dataset.missing_predictions()
        {
            let option = format!("{:?}", self.labels).to_lowercase();
            bail!(
                "--labels {option}: {} has no predictions: {place}",
                self.dataset
            );
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
