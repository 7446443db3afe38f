//! The paper's experiments in one call: S-NDT, S-BKI and OS-BKI on every trajectory of a
//! dataset, per label source, cell size and kernel length, each evaluated by the same loop
//! ([`map_and_score`], the paper's evaluation protocol in `docs/ARCHITECTURE.md`), written
//! as the paper's Table I (mIoU / invR / mPAcc) and Table II (map update rate) in Markdown
//! and CSV, with a per-class IoU chart like the paper's Fig. 5 and an update-rate-vs-mIoU
//! plot.
//!
//! Each trajectory's frames are loaded once and every configuration is run on them in
//! turn; trajectories run in parallel (rayon), each map is built by one thread, so update
//! times are single-threaded figures. S-BKI and OS-BKI share one map per kernel length
//! (their counts are the same, see [`crate::baselines::bki`]); the update time is that map's.
//!
//! [`run_resumable`] keeps every finished run (one map on one trajectory) in a
//! [`RunStore`] as soon as it is finished, with everything the tables take from it
//! (confusion matrices, surface read-outs, update time), and takes the runs the store
//! already holds instead of computing them again: an interrupted experiment continues
//! where it stopped and writes the tables an uninterrupted one would (update times of
//! resumed runs are those measured when they ran).

use crate::baselines::bki::{BkiConfig, BkiMap, Readout, SurfaceStates};
use crate::dataset::frame::{Frame, FrameId, LabelSource};
use crate::dataset::source::{usable_frames, Dataset};
use crate::eval::evaluate::{gt_depth, map_and_score, MapScore};
use crate::eval::metrics::{Confusion, Metrics};
use crate::eval::run_store::{file_name_part, Manifest, RunStore};
use crate::semantic_map::{boxed_map, HostMap, SemanticMap};
use anyhow::{anyhow, bail, Context, Result};
use rayon::prelude::*;
use sndt_core::Config;
use std::borrow::Cow;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A mapping method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Method {
    /// Semantic occupancy NDT (sndt-core).
    Sndt,
    /// Semantic Bayesian kernel inference (Gan et al. 2020).
    Sbki,
    /// The paper's optimised S-BKI.
    Osbki,
}

impl Method {
    fn name(self) -> &'static str {
        match self {
            Method::Sndt => "S-NDT",
            Method::Sbki => "S-BKI",
            Method::Osbki => "OS-BKI",
        }
    }
}

/// What to run.
#[derive(Clone, Debug)]
pub struct ExperimentOptions {
    /// Label sources (ground truth, predicted top 1).
    pub labels: Vec<LabelSource>,
    /// Cell sizes, metres.
    pub cells: Vec<f32>,
    /// Kernel lengths of S-BKI / OS-BKI, metres.
    pub kernels: Vec<f32>,
    /// Methods.
    pub methods: Vec<Method>,
    /// BKI free-sample spacing, metres; `None`: [`BkiConfig::new`]'s 0.3 m (see
    /// [`BkiConfig::free_resolution`]).
    pub free_resolution: Option<f32>,
    /// S-NDT votes a voxel takes per frame ([`Config::votes_per_frame`]; default
    /// [`Config::DEFAULT`]'s).
    pub votes_per_frame: u8,
}

impl Default for ExperimentOptions {
    /// The paper's grid: GT and predicted labels, cells 5/10/15/20 cm, kernels
    /// 10/20/30/40 cm, all three methods.
    fn default() -> Self {
        ExperimentOptions {
            labels: vec![LabelSource::Gt, LabelSource::Pred],
            cells: vec![0.05, 0.10, 0.15, 0.20],
            kernels: vec![0.1, 0.2, 0.3, 0.4],
            methods: vec![Method::Sndt, Method::Sbki, Method::Osbki],
            free_resolution: None,
            votes_per_frame: Config::DEFAULT.votes_per_frame,
        }
    }
}

/// One configuration: label source, method, cell size and kernel length (millimetres, so
/// that keys compare exactly; kernel 0 for S-NDT).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct RunKey {
    /// Ground truth or predicted labels.
    pub labels: Segmentation,
    /// The method.
    pub method: Method,
    /// Kernel length in mm (0 for S-NDT).
    pub kernel_mm: u32,
    /// Cell size in mm.
    pub cell_mm: u32,
}

impl RunKey {
    /// `S-NDT` or `S-BKI (30cm)`, as the paper's row names.
    pub fn row_name(&self) -> String {
        match self.method {
            Method::Sndt => self.method.name().to_string(),
            m => format!("{} ({}cm)", m.name(), mm_to_cm(self.kernel_mm)),
        }
    }
}

/// The segmentation a map is fed, as an ordered key: the experiment's two label sources.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Segmentation {
    /// Ground-truth segmentation.
    Gt,
    /// Predicted segmentation (top 1).
    Pred,
}

impl Segmentation {
    fn from_source(s: LabelSource) -> Result<Segmentation> {
        match s {
            LabelSource::Gt => Ok(Segmentation::Gt),
            LabelSource::Pred => Ok(Segmentation::Pred),
            other => bail!("experiment labels must be gt or pred, not {other:?}"),
        }
    }

    /// The label source that feeds the maps.
    fn source(self) -> LabelSource {
        match self {
            Segmentation::Gt => LabelSource::Gt,
            Segmentation::Pred => LabelSource::Pred,
        }
    }

    fn title(self) -> &'static str {
        match self {
            Segmentation::Gt => "GT segmentation",
            Segmentation::Pred => "Predicted segmentation",
        }
    }

    fn tag(self) -> &'static str {
        match self {
            Segmentation::Gt => "gt",
            Segmentation::Pred => "pred",
        }
    }
}

fn mm(x: f32) -> u32 {
    (x * 1000.0).round() as u32
}

fn mm_to_cm(x: u32) -> String {
    let cm = x as f64 / 10.0;
    if cm.fract() == 0.0 {
        format!("{cm:.0}")
    } else {
        format!("{cm}")
    }
}

/// One configuration's result.
#[derive(Clone, Debug, Default)]
pub struct Run {
    /// Confusion over all frames of all trajectories.
    pub confusion: Confusion,
    /// Per trajectory: name, frames, total update time in seconds.
    pub trajectories: Vec<(String, usize, f64)>,
    /// S-BKI / OS-BKI: how the final maps read their surface voxels (summed over
    /// trajectories); zero for S-NDT.
    pub surface: SurfaceStates,
}

impl Run {
    /// mIoU, invR, mPAcc and per-class IoU.
    pub fn metrics(&self) -> Metrics {
        self.confusion.metrics()
    }

    /// Mean over trajectories of each trajectory's update rate (frames / update time), Hz.
    pub fn mean_hz(&self) -> f64 {
        let r = self.rates();
        r.iter().sum::<f64>() / r.len().max(1) as f64
    }

    /// Update rates of the slowest and the fastest trajectory, Hz.
    pub fn slowest_fastest_hz(&self) -> (f64, f64) {
        let r = self.rates();
        (
            r.iter().cloned().fold(f64::INFINITY, f64::min),
            r.iter().cloned().fold(0.0, f64::max),
        )
    }

    /// Mean update time per frame over all frames, milliseconds.
    pub fn mean_ms(&self) -> f64 {
        let (s, n) = self
            .trajectories
            .iter()
            .fold((0.0, 0), |(s, n), t| (s + t.2, n + t.1));
        s * 1e3 / n.max(1) as f64
    }

    fn rates(&self) -> Vec<f64> {
        self.trajectories
            .iter()
            .map(|(_, n, s)| *n as f64 / s.max(1e-12))
            .collect()
    }
}

/// All results of an experiment.
#[derive(Clone, Debug, Default)]
pub struct Experiment {
    /// Per configuration.
    pub runs: BTreeMap<RunKey, Run>,
    /// The labels fed to the maps, scored on the frames themselves (per label source).
    pub inputs: BTreeMap<Segmentation, Confusion>,
    /// Frames mapped, over all trajectories.
    pub frames: usize,
    /// Frames skipped for bad input (each named in a `warning:` on stderr when read).
    pub skipped: usize,
}

/// How many progress steps [`run`] reports for `frames` frames: one per frame mapped and
/// one per frame back-projected, per configuration.
pub fn progress_steps(options: &ExperimentOptions, frames: usize) -> u64 {
    let has = |m| options.methods.contains(&m);
    let sndt = if has(Method::Sndt) { 2 } else { 0 };
    let readouts = has(Method::Sbki) as usize + has(Method::Osbki) as usize;
    let bki = if readouts > 0 {
        options.kernels.len() * (1 + readouts)
    } else {
        0
    };
    (options.labels.len() * options.cells.len() * (sndt + bki) * frames) as u64
}

/// Runs every configuration of `options` on every trajectory of `dataset`.
/// `progress` is called once per frame mapped or back-projected.
pub fn run(
    dataset: &dyn Dataset,
    options: &ExperimentOptions,
    progress: &(dyn Fn() + Sync),
) -> Result<Experiment> {
    run_with(dataset, options, None, progress)
}

/// [`run`], keeping each finished run in `store` as soon as it is finished and taking the
/// runs `store` already holds instead of computing them again (`sndt experiment
/// --resume`). Runs taken from the store keep the update times measured when they were
/// computed, so an interrupted and resumed experiment writes the same tables as the
/// stored runs and the new ones together; progress steps of stored runs are reported at
/// once. The store counts runs resumed and computed ([`RunStore::resumed`],
/// [`RunStore::computed`]).
pub fn run_resumable(
    dataset: &dyn Dataset,
    options: &ExperimentOptions,
    store: &RunStore,
    progress: &(dyn Fn() + Sync),
) -> Result<Experiment> {
    run_with(dataset, options, Some(store), progress)
}

/// What every trajectory runs, and where its runs are kept.
struct Plan<'a> {
    options: &'a ExperimentOptions,
    sources: Vec<Segmentation>,
    bki_methods: Vec<Method>,
    store: Option<&'a RunStore>,
    progress: &'a (dyn Fn() + Sync),
}

fn run_with(
    dataset: &dyn Dataset,
    options: &ExperimentOptions,
    store: Option<&RunStore>,
    progress: &(dyn Fn() + Sync),
) -> Result<Experiment> {
    let (sources, bki_methods) = check(options)?;
    let plan = Plan {
        options,
        sources,
        bki_methods,
        store,
        progress,
    };
    let trajectories = dataset.trajectories();
    let parts: Vec<Result<(String, TrajectoryRuns)>> = trajectories
        .par_iter()
        .map(|(name, ids)| {
            let part = run_trajectory(dataset, name, ids, &plan)
                .with_context(|| format!("trajectory {name}"))?;
            Ok((name.clone(), part))
        })
        .collect();
    let mut exp = Experiment::default();
    for p in parts {
        let (name, (runs, inputs, (n, skipped))) = p?;
        exp.frames += n;
        exp.skipped += skipped;
        for (key, confusion, seconds, surface) in runs {
            let run = exp.runs.entry(key).or_default();
            run.confusion.merge(&confusion);
            run.surface.voxels += surface.voxels;
            run.surface.free += surface.free;
            run.surface.unknown += surface.unknown;
            run.surface.occupied += surface.occupied;
            run.trajectories.push((name.clone(), n, seconds));
        }
        for (labels, c) in inputs {
            exp.inputs.entry(labels).or_default().merge(&c);
        }
    }
    Ok(exp)
}

/// Checks `options` before anything runs: the label sources as segmentations and the BKI
/// methods asked for.
fn check(options: &ExperimentOptions) -> Result<(Vec<Segmentation>, Vec<Method>)> {
    let sources: Vec<Segmentation> = options
        .labels
        .iter()
        .map(|&s| Segmentation::from_source(s))
        .collect::<Result<_>>()?;
    if options.cells.is_empty() || options.methods.is_empty() || sources.is_empty() {
        bail!("nothing to run: give at least one cell size, method and label source");
    }
    let bki_methods: Vec<Method> = [Method::Sbki, Method::Osbki]
        .into_iter()
        .filter(|m| options.methods.contains(m))
        .collect();
    if !bki_methods.is_empty() && options.kernels.is_empty() {
        bail!("S-BKI / OS-BKI need at least one kernel length");
    }
    for &cell in &options.cells {
        sndt_config(options, cell)
            .validate()
            .map_err(|e| anyhow!("cell size {cell}: {e:?}"))?;
        for &l in &options.kernels {
            bki_config(options, cell, l).validate()?;
        }
    }
    Ok((sources, bki_methods))
}

fn sndt_config(options: &ExperimentOptions, cell: f32) -> Config {
    Config {
        votes_per_frame: options.votes_per_frame,
        ..Config::with_cell_size(cell)
    }
}

fn bki_config(options: &ExperimentOptions, cell: f32, kernel: f32) -> BkiConfig {
    let mut c = BkiConfig::new(cell, kernel);
    if let Some(f) = options.free_resolution {
        c.free_resolution = f;
    }
    c
}

/// One trajectory's results: per configuration (key, confusion, update seconds, surface
/// read-out), the input labels' confusion per source, and the frames mapped and skipped
/// (bad input).
type TrajectoryRuns = (
    Vec<(RunKey, Confusion, f64, SurfaceStates)>,
    Vec<(Segmentation, Confusion)>,
    (usize, usize),
);

/// One map to build on a trajectory: a label source, a cell size and S-NDT (`None`) or a
/// BKI kernel length (`Some`).
type Job = (Segmentation, f32, Option<f32>);

/// What one [`Job`] yields: one result for S-NDT, one per BKI read-out.
type JobRuns = Vec<(RunKey, Confusion, f64, SurfaceStates)>;

impl Plan<'_> {
    /// Every map to build on a trajectory: per segmentation and cell size, S-NDT and, per
    /// kernel length, one BKI map read out as S-BKI and / or OS-BKI.
    fn jobs(&self) -> Vec<Job> {
        let mut jobs: Vec<Job> = Vec::new();
        for &segmentation in &self.sources {
            for &cell in &self.options.cells {
                if self.options.methods.contains(&Method::Sndt) {
                    jobs.push((segmentation, cell, None));
                }
                if !self.bki_methods.is_empty() {
                    jobs.extend(
                        self.options
                            .kernels
                            .iter()
                            .map(|&l| (segmentation, cell, Some(l))),
                    );
                }
            }
        }
        jobs
    }

    /// The methods a job's map is read out as, in the order of its results.
    fn methods(&self, (_, _, kernel): Job) -> &[Method] {
        match kernel {
            None => &[Method::Sndt],
            Some(_) => &self.bki_methods,
        }
    }

    /// Reports the progress steps of a job taken from the store: one per frame mapped and
    /// one per frame back-projected per read-out, as if it had run.
    fn skip(&self, job: Job, frames: usize) {
        if let Some(store) = self.store {
            store.count_resumed();
        }
        for _ in 0..frames * (1 + self.methods(job).len()) {
            (self.progress)();
        }
    }
}

/// One trajectory through every configuration: the input labels scored per segmentation,
/// then every map of [`Plan::jobs`]. The maps are independent, so they are built in
/// parallel (rayon): with more maps than trajectories, no core idles while the last
/// trajectory finishes. Update times are unaffected: an update makes no rayon call, so no
/// other work is stolen into it. Results the store holds are taken from it; the frames
/// are only loaded when something is left to compute.
fn run_trajectory(
    dataset: &dyn Dataset,
    name: &str,
    ids: &[FrameId],
    plan: &Plan,
) -> Result<TrajectoryRuns> {
    let n = ids.len();
    let jobs = plan.jobs();
    let stored: Vec<Option<JobRuns>> = jobs
        .iter()
        .map(|&job| plan.store.and_then(|s| load_job(s, plan, name, n, job)))
        .collect();
    let stored_inputs = plan.store.and_then(|s| load_inputs(s, plan, name, n));
    let mut skipped = Vec::new();
    let frames = if stored_inputs.is_none() || stored.iter().any(Option::is_none) {
        // Bad frames are skipped with a warning naming the file; the smallest cell has
        // the smallest key range, so a pose it accepts every map accepts.
        let cell = plan
            .options
            .cells
            .iter()
            .copied()
            .fold(f32::INFINITY, f32::min);
        usable_frames(dataset, ids, cell, &mut skipped).collect::<Result<Vec<Frame>>>()?
    } else {
        Vec::new()
    };
    if frames.is_empty() && !skipped.is_empty() {
        let last = skipped.last().map_or("", |b| b.why.as_str());
        bail!("nothing mapped: all {n} frames were skipped (the last: {last})");
    }
    let (inputs, skipped) = match stored_inputs {
        Some(inputs) => inputs,
        None => {
            let inputs = plan
                .sources
                .iter()
                .map(|&s| Ok((s, input_confusion(&frames, s)?)))
                .collect::<Result<Vec<_>>>()?;
            let skipped = skipped.len();
            if let Some(store) = plan.store {
                let record = stored_inputs_of(name, (n, skipped), &inputs);
                store.save(&inputs_file(name), &record)?;
            }
            (inputs, skipped)
        }
    };
    let runs = jobs
        .par_iter()
        .zip(stored.into_par_iter())
        .map(|(&job, stored)| match stored {
            Some(runs) => {
                plan.skip(job, n);
                Ok(runs)
            }
            None => {
                let runs = run_job(&frames, plan, job)?;
                if let Some(store) = plan.store {
                    let record = stored_job_of(name, n, job, &runs);
                    store.save_result(&job_file(name, job), &record)?;
                }
                Ok(runs)
            }
        })
        .collect::<Result<Vec<_>>>()?;
    Ok((
        runs.into_iter().flatten().collect(),
        inputs,
        (n - skipped, skipped),
    ))
}

/// Builds and scores one map of [`run_trajectory`]: one result for S-NDT, one per BKI
/// read-out.
fn run_job(frames: &[Frame], plan: &Plan, (segmentation, cell, kernel): Job) -> Result<JobRuns> {
    let (options, progress) = (plan.options, plan.progress);
    let key = |method, kernel_mm| RunKey {
        labels: segmentation,
        method,
        kernel_mm,
        cell_mm: mm(cell),
    };
    let labels = segmentation.source();
    let Some(l) = kernel else {
        let mut map: Box<HostMap> =
            boxed_map(sndt_config(options, cell)).map_err(|e| anyhow!("config: {e:?}"))?;
        let score = run_map(map.as_mut(), frames, labels, &[()], progress)?;
        let seconds = score.update_seconds();
        return Ok(score
            .confusions
            .into_iter()
            .map(|c| (key(Method::Sndt, 0), c, seconds, Default::default()))
            .collect());
    };
    let bki_methods = &plan.bki_methods;
    let readouts: Vec<Readout> = bki_methods.iter().map(|&m| bki_readout(m)).collect();
    let mut map = BkiMap::new(bki_config(options, cell, l))?;
    let score = run_map(&mut map, frames, labels, &readouts, progress)?;
    let seconds = score.update_seconds();
    Ok(bki_methods
        .iter()
        .zip(&readouts)
        .zip(score.confusions)
        .map(|((&m, &readout), confusion)| {
            (
                key(m, mm(l)),
                confusion,
                seconds,
                map.surface_states(readout),
            )
        })
        .collect())
}

/// The options an experiment's stored runs depend on (besides how the dataset was
/// opened, which the caller adds): the grid, the methods' parameters and the frames run,
/// named as `sndt experiment` spells them, for [`RunStore::open`].
pub fn manifest(options: &ExperimentOptions, dataset: &dyn Dataset) -> Manifest {
    let list = |v: &[f32]| -> String {
        let v: Vec<String> = v.iter().map(f32::to_string).collect();
        v.join(",")
    };
    let labels: Vec<String> = options
        .labels
        .iter()
        .map(|l| format!("{l:?}").to_lowercase())
        .collect();
    let methods: Vec<&str> = options.methods.iter().map(|m| m.name()).collect();
    // Frame ids hashed (FNV-1a): a dataset whose frames changed is not resumed, however
    // it is named.
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    for id in dataset.frames() {
        for b in format!("{}/{}/{}\n", id.scene, id.cam, id.index).bytes() {
            hash = (hash ^ b as u64).wrapping_mul(0x0100_0000_01b3);
        }
    }
    let frames = format!(
        "{} trajectories, {} frames, ids {hash:016x}",
        dataset.trajectories().len(),
        dataset.frames().len()
    );
    let free = options
        .free_resolution
        .map_or_else(|| "default".to_string(), |f| f.to_string());
    [
        ("--labels", labels.join(",")),
        ("--cells", list(&options.cells)),
        ("--kernels", list(&options.kernels)),
        ("--methods", methods.join(",")),
        ("--free-resolution", free),
        ("--votes-per-frame", options.votes_per_frame.to_string()),
        ("frames", frames),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect()
}

/// One finished [`Job`] on one trajectory as stored: everything the tables take from it.
#[derive(serde::Serialize, serde::Deserialize)]
struct StoredJob {
    trajectory: String,
    frames: usize,
    labels: String,
    cell_mm: u32,
    /// 0 for S-NDT.
    kernel_mm: u32,
    /// Update time, seconds, as Rust writes an `f64` (the shortest decimal that reads back
    /// to the same value): a JSON number need not read back exactly, and resumed tables
    /// must show the time measured.
    update_s: String,
    /// One per method the map was read out as, in [`Plan::methods`] order.
    results: Vec<StoredResult>,
}

/// One read-out of a stored job.
#[derive(serde::Serialize, serde::Deserialize)]
struct StoredResult {
    method: String,
    /// The non-zero cells of the confusion matrix: `[gt, prediction, count]`.
    confusion: Vec<[u64; 3]>,
    surface_voxels: u64,
    surface_free: u64,
    surface_unknown: u64,
    surface_occupied: u64,
}

/// One trajectory's input labels scored, as stored: per segmentation tag, the non-zero
/// confusion cells.
#[derive(serde::Serialize, serde::Deserialize)]
struct StoredInputs {
    trajectory: String,
    frames: usize,
    /// Of `frames`, how many were skipped for bad input.
    #[serde(default)]
    skipped: usize,
    inputs: BTreeMap<String, Vec<[u64; 3]>>,
}

/// The store's file of a job on trajectory `name`:
/// `<trajectory>__<labels>__sndt__cell<mm>mm.json` or
/// `<trajectory>__<labels>__bki-kernel<mm>mm__cell<mm>mm.json` (S-BKI and OS-BKI read
/// out of the same map share its file).
fn job_file(name: &str, (segmentation, cell, kernel): Job) -> String {
    let method = match kernel {
        None => "sndt".to_string(),
        Some(l) => format!("bki-kernel{}mm", mm(l)),
    };
    format!(
        "{}__{}__{method}__cell{}mm.json",
        file_name_part(name),
        segmentation.tag(),
        mm(cell)
    )
}

/// The store's file of trajectory `name`'s input labels scored.
fn inputs_file(name: &str) -> String {
    format!("{}__inputs.json", file_name_part(name))
}

fn stored_job_of(name: &str, frames: usize, job: Job, runs: &JobRuns) -> StoredJob {
    let (segmentation, cell, kernel) = job;
    StoredJob {
        trajectory: name.to_string(),
        frames,
        labels: segmentation.tag().to_string(),
        cell_mm: mm(cell),
        kernel_mm: kernel.map_or(0, mm),
        update_s: runs.first().map_or(0.0, |r| r.2).to_string(),
        results: runs
            .iter()
            .map(|(key, confusion, _, surface)| StoredResult {
                method: key.method.name().to_string(),
                confusion: sparse(confusion),
                surface_voxels: surface.voxels,
                surface_free: surface.free,
                surface_unknown: surface.unknown,
                surface_occupied: surface.occupied,
            })
            .collect(),
    }
}

/// The stored job `job` on trajectory `name` of `frames` frames, if the store holds it
/// whole and for that job.
fn load_job(store: &RunStore, plan: &Plan, name: &str, frames: usize, job: Job) -> Option<JobRuns> {
    store.load(&job_file(name, job), |s: StoredJob| {
        let (segmentation, cell, kernel) = job;
        let kernel_mm = kernel.map_or(0, mm);
        let holds = (&*s.trajectory, s.frames, &*s.labels, s.cell_mm, s.kernel_mm);
        if holds != (name, frames, segmentation.tag(), mm(cell), kernel_mm) {
            return Err(format!(
                "holds {holds:?}, not (trajectory, frames, labels, cell mm, kernel mm) {:?}",
                (name, frames, segmentation.tag(), mm(cell), kernel_mm)
            ));
        }
        let seconds = s
            .update_s
            .parse::<f64>()
            .ok()
            .filter(|t| t.is_finite() && *t >= 0.0)
            .ok_or_else(|| format!("update time {:?} is not a time", s.update_s))?;
        let want: Vec<&str> = plan.methods(job).iter().map(|m| m.name()).collect();
        let got: Vec<&str> = s.results.iter().map(|r| &*r.method).collect();
        if got != want {
            return Err(format!("holds read-outs {got:?}, not {want:?}"));
        }
        let key = |method| RunKey {
            labels: segmentation,
            method,
            kernel_mm,
            cell_mm: mm(cell),
        };
        s.results
            .iter()
            .zip(plan.methods(job))
            .map(|(r, &method)| {
                let surface = SurfaceStates {
                    voxels: r.surface_voxels,
                    free: r.surface_free,
                    unknown: r.surface_unknown,
                    occupied: r.surface_occupied,
                };
                Ok((key(method), dense(&r.confusion)?, seconds, surface))
            })
            .collect()
    })
}

fn stored_inputs_of(
    name: &str,
    (frames, skipped): (usize, usize),
    inputs: &[(Segmentation, Confusion)],
) -> StoredInputs {
    StoredInputs {
        trajectory: name.to_string(),
        frames,
        skipped,
        inputs: inputs
            .iter()
            .map(|(s, c)| (s.tag().to_string(), sparse(c)))
            .collect(),
    }
}

/// Trajectory `name`'s stored input scores, if the store holds them for every source, and
/// how many of its frames were skipped.
fn load_inputs(
    store: &RunStore,
    plan: &Plan,
    name: &str,
    frames: usize,
) -> Option<(Vec<(Segmentation, Confusion)>, usize)> {
    store.load(&inputs_file(name), |s: StoredInputs| {
        if (&*s.trajectory, s.frames) != (name, frames) {
            return Err(format!(
                "holds trajectory {} of {} frames, not {name} of {frames}",
                s.trajectory, s.frames
            ));
        }
        plan.sources
            .iter()
            .map(|&source| {
                let cells = s
                    .inputs
                    .get(source.tag())
                    .ok_or_else(|| format!("no {} labels", source.tag()))?;
                Ok((source, dense(cells)?))
            })
            .collect::<Result<Vec<_>, String>>()
            .map(|inputs| (inputs, s.skipped))
    })
}

/// The non-zero cells of a confusion matrix, `[gt, prediction, count]`.
fn sparse(c: &Confusion) -> Vec<[u64; 3]> {
    let mut out = Vec::new();
    for (g, row) in c.cm.iter().enumerate() {
        for (p, &n) in row.iter().enumerate() {
            if n > 0 {
                out.push([g as u64, p as u64, n]);
            }
        }
    }
    out
}

/// The confusion matrix of [`sparse`]'s cells; an index outside the matrix or a cell
/// given twice is an error.
fn dense(cells: &[[u64; 3]]) -> std::result::Result<Confusion, String> {
    let mut c = Confusion::default();
    for &[g, p, n] in cells {
        let cell = usize::try_from(g)
            .ok()
            .zip(usize::try_from(p).ok())
            .and_then(|(g, p)| c.cm.get_mut(g)?.get_mut(p))
            .ok_or_else(|| format!("confusion cell ({g}, {p}) is outside the matrix"))?;
        if *cell != 0 {
            return Err(format!("confusion cell ({g}, {p}) is given twice"));
        }
        *cell = n;
    }
    Ok(c)
}

/// One configuration's map through the trajectory ([`map_and_score`], every pixel), one
/// progress step per frame mapped and per frame rendered.
fn run_map<M: SemanticMap + ?Sized>(
    map: &mut M,
    frames: &[Frame],
    labels: LabelSource,
    readouts: &[M::Readout],
    progress: &(dyn Fn() + Sync),
) -> Result<MapScore> {
    map_and_score(
        map,
        frames.iter().map(|f| Ok(Cow::Borrowed(f))),
        labels,
        1,
        readouts,
        |_, _| {
            progress();
            Ok(())
        },
        |_, _| {
            progress();
            Ok(())
        },
    )
}

/// The BKI read-out of a BKI method.
fn bki_readout(method: Method) -> Readout {
    if method == Method::Sbki {
        Readout::Sbki
    } else {
        Readout::Osbki
    }
}

/// The labels `segmentation` feeds the maps (ground truth, or the prediction's top 1),
/// scored against the ground truth on the frames themselves. Predicted segmentation needs
/// predictions on every frame.
fn input_confusion(frames: &[Frame], segmentation: Segmentation) -> Result<Confusion> {
    let mut input = Confusion::default();
    for f in frames {
        let given = match segmentation {
            Segmentation::Gt => f.labels.clone(),
            Segmentation::Pred => Some(
                f.predictions
                    .as_ref()
                    .ok_or_else(|| anyhow!("{}: no predictions to map with", f.id))?
                    .top1(),
            ),
        };
        if let (Some(gt), Some(given)) = (&f.labels, &given) {
            input.add_frame(gt, given, &gt_depth(f));
        }
    }
    Ok(input)
}

impl Experiment {
    fn cells(&self) -> Vec<u32> {
        let mut c: Vec<u32> = self.runs.keys().map(|k| k.cell_mm).collect();
        c.sort();
        c.dedup();
        c
    }

    /// Rows of a table: (label source, method, kernel) in the paper's order.
    fn rows(&self) -> Vec<(Segmentation, Method, u32)> {
        let mut r: Vec<(Segmentation, Method, u32)> = self
            .runs
            .keys()
            .map(|k| (k.labels, k.method, k.kernel_mm))
            .collect();
        // The paper lists S-BKI, OS-BKI, then S-NDT.
        r.sort_by_key(|&(l, m, k)| (l, (m as u8 + 2) % 3, k));
        r.dedup();
        r
    }

    /// Table I as Markdown: per label source, one row per method (and kernel), per cell
    /// size mIoU / invR / mPAcc in %, the best mIoU and mPAcc per cell size in bold.
    pub fn table1_markdown(&self) -> String {
        let cells = self.cells();
        let mut s = String::from("| labels | method |");
        for c in &cells {
            let _ = write!(s, " mIoU {0}cm | invR {0}cm | mPAcc {0}cm |", mm_to_cm(*c));
        }
        s += "\n|---|---|";
        s += &"---:|".repeat(3 * cells.len());
        s += "\n";
        let rows = self.rows();
        for (labels, method, kernel) in &rows {
            let key = |cell| RunKey {
                labels: *labels,
                method: *method,
                kernel_mm: *kernel,
                cell_mm: cell,
            };
            let _ = write!(s, "| {} | {} |", labels.title(), key(0).row_name());
            for &cell in &cells {
                let Some(run) = self.runs.get(&key(cell)) else {
                    s += " | | |";
                    continue;
                };
                let m = run.metrics();
                let best = |f: fn(&Metrics) -> f64| {
                    self.runs
                        .iter()
                        .filter(|(k, _)| k.labels == *labels && k.cell_mm == cell)
                        .map(|(_, r)| f(&r.metrics()))
                        .fold(f64::NEG_INFINITY, f64::max)
                };
                let fmt = |v: f64, b: f64| {
                    if (v - b).abs() < 1e-12 {
                        format!("**{:.2}**", v * 100.0)
                    } else {
                        format!("{:.2}", v * 100.0)
                    }
                };
                let _ = write!(
                    s,
                    " {} | {:.2} | {} |",
                    fmt(m.miou, best(|m| m.miou)),
                    m.invr * 100.0,
                    fmt(m.mpacc, best(|m| m.mpacc))
                );
            }
            s += "\n";
        }
        s
    }

    /// The share of surface voxels (those that held a hit) S-BKI and OS-BKI read as free,
    /// in %, per cell size: the holes of the paper's Fig. 2, which the back-projection
    /// only shows as invalid pixels where nothing occupied lies behind them.
    pub fn holes_markdown(&self) -> String {
        let cells = self.cells();
        let mut s = String::from("| labels | method |");
        for c in &cells {
            let _ = write!(s, " {}cm |", mm_to_cm(*c));
        }
        s += "\n|---|---|";
        s += &"---:|".repeat(cells.len());
        s += "\n";
        for (labels, method, kernel) in self.rows() {
            if method == Method::Sndt {
                continue;
            }
            let key = |cell_mm| RunKey {
                labels,
                method,
                kernel_mm: kernel,
                cell_mm,
            };
            let _ = write!(s, "| {} | {} |", labels.title(), key(0).row_name());
            for &cell in &cells {
                match self.runs.get(&key(cell)) {
                    Some(r) => {
                        let v = r.surface.free as f64 / r.surface.voxels.max(1) as f64;
                        let _ = write!(s, " {:.2} |", v * 100.0);
                    }
                    None => s += " |",
                }
            }
            s += "\n";
        }
        s
    }

    /// Table I as CSV: labels, method, kernel_m, cell_m, miou, invr, mpacc (%).
    pub fn table1_csv(&self) -> String {
        let mut s = String::from("labels,method,kernel_m,cell_m,miou,invr,mpacc\n");
        for (k, run) in &self.runs {
            let m = run.metrics();
            let _ = writeln!(
                s,
                "{},{},{},{},{:.4},{:.4},{:.4}",
                k.labels.tag(),
                k.method.name(),
                k.kernel_mm as f64 / 1000.0,
                k.cell_mm as f64 / 1000.0,
                m.miou * 100.0,
                m.invr * 100.0,
                m.mpacc * 100.0
            );
        }
        s
    }

    /// Update rates per (method, kernel, cell) over all label sources: per trajectory,
    /// frames over update time.
    fn timing(&self) -> BTreeMap<(Method, u32, u32), Run> {
        let mut t: BTreeMap<(Method, u32, u32), Run> = BTreeMap::new();
        for (k, run) in &self.runs {
            let e = t.entry((k.method, k.kernel_mm, k.cell_mm)).or_default();
            for (name, n, s) in &run.trajectories {
                match e.trajectories.iter_mut().find(|x| &x.0 == name) {
                    Some(x) => {
                        x.1 += n;
                        x.2 += s;
                    }
                    None => e.trajectories.push((name.clone(), *n, *s)),
                }
            }
        }
        t
    }

    /// Table II as Markdown: mean map update rate (Hz) per method and cell size, with the
    /// slowest / fastest trajectory's rate, single thread.
    pub fn table2_markdown(&self) -> String {
        let cells = self.cells();
        let timing = self.timing();
        let mut s = String::from("| method |");
        for c in &cells {
            let _ = write!(s, " {}cm: Hz (slowest / fastest) |", mm_to_cm(*c));
        }
        s += "\n|---|";
        s += &"---:|".repeat(cells.len());
        s += "\n";
        let mut rows: Vec<(Method, u32)> = timing.keys().map(|k| (k.0, k.1)).collect();
        rows.sort_by_key(|&(m, k)| ((m as u8 + 2) % 3, k));
        rows.dedup();
        for (method, kernel) in rows {
            let key = RunKey {
                labels: Segmentation::Gt,
                method,
                kernel_mm: kernel,
                cell_mm: 0,
            };
            let _ = write!(s, "| {} |", key.row_name());
            for &cell in &cells {
                match timing.get(&(method, kernel, cell)) {
                    Some(r) => {
                        let (lo, hi) = r.slowest_fastest_hz();
                        let _ = write!(s, " {:.2} ({:.2} / {:.2}) |", r.mean_hz(), lo, hi);
                    }
                    None => s += " |",
                }
            }
            s += "\n";
        }
        s
    }

    /// Table II as CSV: method, kernel_m, cell_m, mean_hz, slowest_hz, fastest_hz, mean_ms.
    pub fn table2_csv(&self) -> String {
        let mut s = String::from("method,kernel_m,cell_m,mean_hz,slowest_hz,fastest_hz,mean_ms\n");
        for ((m, k, c), r) in self.timing() {
            let (lo, hi) = r.slowest_fastest_hz();
            let _ = writeln!(
                s,
                "{},{},{},{:.4},{:.4},{:.4},{:.3}",
                m.name(),
                k as f64 / 1000.0,
                c as f64 / 1000.0,
                r.mean_hz(),
                lo,
                hi,
                r.mean_ms()
            );
        }
        s
    }

    /// Writes table1.md/.csv, table2.md/.csv, holes.md, results.json, `iou_<labels>.svg` (Fig. 5:
    /// per-class IoU of S-BKI and OS-BKI at 10 cm with a 30 cm kernel against S-NDT at
    /// 10 and 15 cm, or the nearest configurations run) and `rate_vs_miou_<labels>.svg`.
    pub fn write(&self, out: &Path) -> Result<Vec<PathBuf>> {
        std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
        let mut written = Vec::new();
        let mut put = |name: &str, text: &str| -> Result<()> {
            let p = out.join(name);
            crate::atomic::write_bytes(&p, text)?;
            written.push(p);
            Ok(())
        };
        put("table1.md", &self.table1_markdown())?;
        put("table1.csv", &self.table1_csv())?;
        put("table2.md", &self.table2_markdown())?;
        put("table2.csv", &self.table2_csv())?;
        put("holes.md", &self.holes_markdown())?;
        put(
            "results.json",
            &serde_json::to_string_pretty(&self.to_json())?,
        )?;
        let sources: Vec<Segmentation> = self.inputs.keys().cloned().collect();
        for labels in sources {
            let p = out.join(format!("iou_{}.svg", labels.tag()));
            let series = self.fig5_series(labels);
            let refs: Vec<(&str, &[Option<f64>; 41])> =
                series.iter().map(|(n, v)| (n.as_str(), v)).collect();
            crate::output::chart::iou_bars(
                &p,
                &format!("Per-class IoU, {}", labels.title()),
                &refs,
            )?;
            written.push(p);
            let p = out.join(format!("rate_vs_miou_{}.svg", labels.tag()));
            let timing = self.timing();
            let mut points: BTreeMap<String, Vec<(f64, f64, String)>> = BTreeMap::new();
            for (k, run) in self.runs.iter().filter(|(k, _)| k.labels == labels) {
                let hz = timing[&(k.method, k.kernel_mm, k.cell_mm)].mean_hz();
                let series = match k.method {
                    Method::Sndt => k.row_name(),
                    m => format!("{} ({}cm kernel)", m.name(), mm_to_cm(k.kernel_mm)),
                };
                points.entry(series).or_default().push((
                    hz,
                    run.metrics().miou * 100.0,
                    format!("{}cm", mm_to_cm(k.cell_mm)),
                ));
            }
            let series: Vec<_> = points.into_iter().collect();
            crate::output::chart::rate_vs_miou(
                &p,
                &format!("Map update rate vs mIoU, {}", labels.title()),
                &series,
            )?;
            written.push(p);
        }
        Ok(written)
    }

    /// The Fig. 5 series: S-BKI and OS-BKI at 10 cm with a 30 cm kernel, S-NDT at 10 and
    /// 15 cm (nearest available cell sizes and kernel otherwise).
    fn fig5_series(&self, labels: Segmentation) -> Vec<(String, [Option<f64>; 41])> {
        let cells = self.cells();
        let nearest = |v: &[u32], want: u32| v.iter().cloned().min_by_key(|&c| c.abs_diff(want));
        let mut kernels: Vec<u32> = self
            .runs
            .keys()
            .map(|k| k.kernel_mm)
            .filter(|&k| k > 0)
            .collect();
        kernels.sort();
        kernels.dedup();
        let mut out = Vec::new();
        let (Some(c10), Some(c15)) = (nearest(&cells, 100), nearest(&cells, 150)) else {
            return out;
        };
        let k30 = nearest(&kernels, 300).unwrap_or(0);
        let wanted = [
            (Method::Sbki, k30, c10),
            (Method::Osbki, k30, c10),
            (Method::Sndt, 0, c10),
            (Method::Sndt, 0, c15),
        ];
        for (method, kernel_mm, cell_mm) in wanted {
            let key = RunKey {
                labels,
                method,
                kernel_mm,
                cell_mm,
            };
            if let Some(run) = self.runs.get(&key) {
                let name = format!("{} @ {}cm", key.row_name(), mm_to_cm(cell_mm));
                if !out.iter().any(|(n, _)| n == &name) {
                    out.push((name, run.metrics().iou));
                }
            }
        }
        out
    }

    /// Every run's metrics, per-class IoU and timing as JSON.
    pub fn to_json(&self) -> serde_json::Value {
        let runs: Vec<serde_json::Value> = self
            .runs
            .iter()
            .map(|(k, r)| {
                let m = r.metrics();
                let iou = m.iou_by_name();
                serde_json::json!({
                    "labels": k.labels.tag(),
                    "method": k.method.name(),
                    "kernel_m": k.kernel_mm as f64 / 1000.0,
                    "cell_m": k.cell_mm as f64 / 1000.0,
                    "miou": m.miou, "invr": m.invr, "mpacc": m.mpacc,
                    "per_class_iou": iou,
                    "mean_update_ms": r.mean_ms(),
                    "surface_voxels": r.surface.voxels,
                    "surface_free": r.surface.free,
                    "surface_unknown": r.surface.unknown,
                    "trajectories": r.trajectories.iter().map(|(n, f, s)| serde_json::json!({
                        "name": n, "frames": f, "update_s": s })).collect::<Vec<_>>(),
                })
            })
            .collect();
        let inputs: serde_json::Map<String, serde_json::Value> = self
            .inputs
            .iter()
            .map(|(l, c)| {
                let m = c.metrics();
                (
                    l.tag().to_string(),
                    serde_json::json!({"miou": m.miou, "mpacc": m.mpacc}),
                )
            })
            .collect();
        serde_json::json!({ "frames": self.frames, "inputs": inputs, "runs": runs })
    }
}
