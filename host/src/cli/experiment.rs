//! `sndt experiment`: the paper's comparison of S-NDT, S-BKI and OS-BKI per cell size and
//! kernel length (Tables I and II, per-class IoU, rate-vs-mIoU charts); `--resume`
//! continues an interrupted one from the runs it kept on disk.

use crate::cli::open_args::OpenArgs;
use crate::dataset::frame::LabelSource;
use crate::dataset::open::open_spec;
use crate::dataset::source::{Dataset, Every};
use crate::eval::experiment::{manifest, progress_steps, run_resumable, Experiment};
use crate::eval::experiment::{ExperimentOptions, Method};
use crate::eval::run_store::{Manifest, RunStore};
use crate::output::progress::progress;
use anyhow::{bail, Result};
use sndt_core::Config;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

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
pub struct ExperimentArgs {
    /// Dataset directory (prepared layout or raw Hypersim), or `synthetic[:SCENES:FRAMES]`.
    pub dataset: String,
    /// Labels fed to the maps.
    #[arg(long, value_enum, default_value = "both")]
    pub labels: ExperimentLabels,
    /// Cell sizes, metres.
    #[arg(long, value_delimiter = ',', default_value = "0.05,0.1,0.15,0.2", value_parser = super::parse::positive)]
    pub cells: Vec<f32>,
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
    /// Use every k-th frame of each trajectory (1 = all, as the paper).
    #[arg(long, default_value_t = 1)]
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
    /// The experiment these arguments ask for.
    pub fn options(&self) -> ExperimentOptions {
        ExperimentOptions {
            labels: self.labels.sources(),
            cells: self.cells.clone(),
            kernels: self.kernels.clone(),
            methods: self.methods.iter().map(|&m| m.into()).collect(),
            free_resolution: self.free_resolution,
            votes_per_frame: self.votes_per_frame,
        }
    }

    /// Everything the stored runs depend on: the experiment's own options, the dataset as
    /// given, `--every`, how it was opened, and this sndt's version.
    fn manifest(&self, opts: &ExperimentOptions, dataset: &dyn Dataset) -> Manifest {
        let mut m = manifest(opts, dataset);
        m.insert("dataset".into(), self.dataset.clone());
        m.insert("--every".into(), self.every.max(1).to_string());
        m.insert("dataset options".into(), format!("{:?}", self.open));
        m.insert("sndt version".into(), env!("CARGO_PKG_VERSION").into());
        m
    }
}

/// Runs `sndt experiment`: runs every method, label source, cell size and kernel length
/// (taking finished runs from `<out>/runs/` with `--resume`), prints the tables and writes
/// them with the charts into `--out`.
pub fn run(a: &ExperimentArgs) -> Result<()> {
    let mut dataset = open_spec(&a.dataset, &a.open.options()?)?;
    if a.every > 1 {
        dataset = Box::new(Every::new(dataset, a.every));
    }
    println!("sndt experiment: {}", dataset.describe());
    if a.labels != ExperimentLabels::Gt {
        // Maps without labels would score 0 % and look like a result.
        if let Some(place) = dataset.missing_predictions() {
            let option = format!("{:?}", a.labels).to_lowercase();
            bail!(
                "--labels {option}: {} has no predictions: {place}",
                a.dataset
            );
        }
    }
    let opts = a.options();
    let store = RunStore::open(
        &a.out.join("runs"),
        &a.manifest(&opts, dataset.as_ref()),
        a.resume,
    )?;
    let t = Instant::now();
    let exp = run_with_progress(dataset.as_ref(), &opts, &store, t)?;
    let skipped = match exp.skipped {
        0 => String::new(),
        k => format!(", {k} skipped (bad input, named in the warnings)"),
    };
    println!(
        "{} trajectories, {} frames mapped{skipped}, {:.0} s",
        dataset.trajectories().len(),
        exp.frames,
        t.elapsed().as_secs_f64()
    );
    println!(
        "resumed {} of {} runs, computed {} (a run: one map on one trajectory; kept in {})\n",
        store.resumed(),
        store.resumed() + store.computed(),
        store.computed(),
        store.dir().display()
    );
    print_tables(&exp);
    for p in exp.write(&a.out)? {
        println!("wrote {}", p.display());
    }
    Ok(())
}

/// Runs the experiment behind a progress bar; long runs in logs (no terminal, bar hidden)
/// get a line every 5 % instead, timed from `t`.
fn run_with_progress(
    dataset: &dyn Dataset,
    opts: &ExperimentOptions,
    store: &RunStore,
    t: Instant,
) -> Result<Experiment> {
    let steps = progress_steps(opts, dataset.frames().len());
    let bar = progress(steps, "experiment");
    let done = AtomicU64::new(0);
    let tick = || {
        bar.inc(1);
        let n = done.fetch_add(1, Ordering::Relaxed) + 1;
        if bar.is_hidden() && n * 20 / steps != (n - 1) * 20 / steps {
            eprintln!(
                "experiment: {} % after {:.0} s",
                n * 100 / steps,
                t.elapsed().as_secs_f64()
            );
        }
    };
    let exp = run_resumable(dataset, opts, store, &tick)?;
    bar.finish_and_clear();
    Ok(exp)
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
