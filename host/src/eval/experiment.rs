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

use crate::baselines::bki::{BkiConfig, BkiMap, Readout, SurfaceStates};
use crate::dataset::frame::{Frame, LabelSource};
use crate::dataset::source::Dataset;
use crate::eval::evaluate::{gt_depth, map_and_score, MapScore};
use crate::eval::metrics::{Confusion, Metrics};
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
    /// Frames per trajectory and trajectory count.
    pub frames: usize,
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
    let trajectories = dataset.trajectories();
    let parts: Vec<Result<(String, TrajectoryRuns)>> = trajectories
        .par_iter()
        .map(|(name, ids)| {
            let frames = ids
                .iter()
                .map(|id| dataset.load(id))
                .collect::<Result<Vec<Frame>>>()?;
            let part = run_trajectory(&frames, options, &sources, &bki_methods, progress)
                .with_context(|| format!("trajectory {name}"))?;
            Ok((name.clone(), part))
        })
        .collect();
    let mut exp = Experiment::default();
    for p in parts {
        let (name, (runs, inputs, n)) = p?;
        exp.frames += n;
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
/// read-out), the input labels' confusion per source, and the frame count.
type TrajectoryRuns = (
    Vec<(RunKey, Confusion, f64, SurfaceStates)>,
    Vec<(Segmentation, Confusion)>,
    usize,
);

/// One map to build on a trajectory: a label source, a cell size and S-NDT (`None`) or a
/// BKI kernel length (`Some`).
type Job = (Segmentation, f32, Option<f32>);

/// One trajectory through every configuration: per segmentation, its input labels scored,
/// then per cell size S-NDT and, per kernel length, one BKI map read out as S-BKI and / or
/// OS-BKI. The maps are independent, so they are built in parallel (rayon): with more
/// maps than trajectories, no core idles while the last trajectory finishes. Update times
/// are unaffected: an update makes no rayon call, so no other work is stolen into it.
fn run_trajectory(
    frames: &[Frame],
    options: &ExperimentOptions,
    sources: &[Segmentation],
    bki_methods: &[Method],
    progress: &(dyn Fn() + Sync),
) -> Result<TrajectoryRuns> {
    let inputs = sources
        .iter()
        .map(|&s| Ok((s, input_confusion(frames, s)?)))
        .collect::<Result<Vec<_>>>()?;
    let mut jobs: Vec<Job> = Vec::new();
    for &segmentation in sources {
        for &cell in &options.cells {
            if options.methods.contains(&Method::Sndt) {
                jobs.push((segmentation, cell, None));
            }
            if !bki_methods.is_empty() {
                jobs.extend(
                    options
                        .kernels
                        .iter()
                        .map(|&l| (segmentation, cell, Some(l))),
                );
            }
        }
    }
    let runs = jobs
        .par_iter()
        .map(|&job| run_job(frames, options, job, bki_methods, progress))
        .collect::<Result<Vec<_>>>()?;
    Ok((runs.into_iter().flatten().collect(), inputs, frames.len()))
}

/// Builds and scores one map of [`run_trajectory`]: one result for S-NDT, one per BKI
/// read-out.
fn run_job(
    frames: &[Frame],
    options: &ExperimentOptions,
    (segmentation, cell, kernel): Job,
    bki_methods: &[Method],
    progress: &(dyn Fn() + Sync),
) -> Result<Vec<(RunKey, Confusion, f64, SurfaceStates)>> {
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
            crate::output::atomic::write_bytes(&p, text)?;
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
