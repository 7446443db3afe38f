//! The paper's experiments in one call: S-NDT, S-BKI and OS-BKI on every trajectory of a
//! dataset, per label source, cell size and kernel length, each evaluated by the same loop
//! ([`map_and_score`](crate::eval::evaluate::map_and_score), the paper's evaluation
//! protocol in `docs/EVALUATION.md`), written as the paper's Table I (mIoU / invR /
//! mPAcc) and Table II (map update rate) in Markdown and CSV, with a per-class IoU chart
//! like the paper's Fig. 5 and an update-rate-vs-mIoU plot.
//!
//! [`run_experiment`] is `sndt experiment` after its options are parsed, step by step:
//! [`plan`] (what runs, each map's configuration built and checked once), `run.rs` (the
//! maps, their evaluation and update times), [`store`] (each finished run kept in
//! `<out>/runs/` as soon as it is finished, and taken from there on `--resume`) and
//! `report/` (Markdown, CSV, JSON and SVG). [`key`] names the runs and [`results`] holds
//! them. The files below this one import only each other, never this one, so that the
//! steps stay free of import cycles; what a caller needs is re-exported here.
//!
//! Resuming: every finished run (one map on one trajectory) is kept with everything the
//! tables take from it (confusion matrices, surface read-outs, update time), and the runs
//! the store already holds are taken instead of computed again: an interrupted experiment
//! continues where it stopped and writes the tables an uninterrupted one would (update
//! times of resumed runs are those measured when they ran).

pub mod key;
pub mod plan;
mod report;
pub mod results;
mod run;
pub mod store;

pub use key::{Method, RunKey, Segmentation};
pub use plan::{ExperimentOptions, Plan};
pub use results::{Experiment, Run};

use crate::dataset::source::Dataset;
use anyhow::Result;
use std::path::PathBuf;
use std::time::Instant;
use store::{records, Manifest, RunStore};

/// What `sndt experiment` asks for once its options are parsed.
#[derive(Clone, Debug)]
pub struct ExperimentRequest {
    /// The grid: label sources, cell sizes, kernel lengths, methods and their parameters.
    pub options: ExperimentOptions,
    /// What the stored runs also depend on that the dataset value does not tell: the
    /// dataset as given, how it was opened and thinned, named as the command line spells
    /// them (recorded in the manifest, so that a resume under others is refused).
    pub provenance: Manifest,
    /// Output directory: the reports, and the stored runs in `<out>/runs/`.
    pub out: PathBuf,
    /// Take the runs `<out>/runs/` holds instead of starting afresh.
    pub resume: bool,
}

/// A finished experiment: its results and what the run did, for the command to print.
#[derive(Debug)]
pub struct Finished {
    /// The results.
    pub experiment: Experiment,
    /// Trajectories run.
    pub trajectories: usize,
    /// Time the runs took (resumed and computed), seconds.
    pub seconds: f64,
    /// Runs taken from the store.
    pub resumed: usize,
    /// Runs computed (and stored).
    pub computed: usize,
    /// Where the runs are kept.
    pub runs_dir: PathBuf,
    /// The report files written, in order.
    pub written: Vec<PathBuf>,
}

/// Runs `sndt experiment` on `dataset`: plans the grid (refusing invalid options before
/// anything is touched), opens the store of runs (refusing a resume under other options),
/// runs what the store does not hold behind a progress bar, keeping each run as soon as
/// it is finished, and writes the reports into `request.out`.
///
/// ```
/// use sndt_host::eval::experiment::{run_experiment, ExperimentOptions, ExperimentRequest, Method};
/// use sndt_host::dataset::frame::LabelSource;
/// let data = sndt_host::dataset::open_spec("synthetic:1:2", &Default::default()).unwrap();
/// let out = std::env::temp_dir().join(format!("sndt-run-experiment-{}", std::process::id()));
/// let options = ExperimentOptions {
///     labels: vec![LabelSource::Gt],
///     cells: vec![0.2],
///     methods: vec![Method::Sndt],
///     ..Default::default()
/// };
/// let request = ExperimentRequest { options, provenance: Default::default(), out: out.clone(), resume: false };
/// let done = run_experiment(data.as_ref(), &request).unwrap();
/// assert_eq!((done.computed, done.resumed, done.experiment.frames), (1, 0, 2));
/// let again = run_experiment(data.as_ref(), &ExperimentRequest { resume: true, ..request }).unwrap();
/// assert_eq!((again.computed, again.resumed), (0, 1));
/// std::fs::remove_dir_all(&out).unwrap();
/// ```
pub fn run_experiment(dataset: &dyn Dataset, request: &ExperimentRequest) -> Result<Finished> {
    let plan = Plan::new(&request.options, dataset)?;
    let manifest = records::manifest(&plan, dataset, &request.provenance);
    let store = RunStore::open(&request.out.join("runs"), &manifest, request.resume)?;
    let t = Instant::now();
    let experiment = run::run_with_progress(dataset, &plan, &store, t)?;
    let seconds = t.elapsed().as_secs_f64();
    let written = experiment.write(&request.out)?;
    Ok(Finished {
        trajectories: plan.trajectories.len(),
        seconds,
        resumed: store.resumed(),
        computed: store.computed(),
        runs_dir: store.dir().to_path_buf(),
        written,
        experiment,
    })
}

/// Runs every configuration of `options` on every trajectory of `dataset`, in memory (no
/// store, no files); `progress` is called once per frame mapped or back-projected.
pub fn run(
    dataset: &dyn Dataset,
    options: &ExperimentOptions,
    progress: &(dyn Fn() + Sync),
) -> Result<Experiment> {
    let plan = Plan::new(options, dataset)?;
    run::run(dataset, &plan, None, progress)
}
