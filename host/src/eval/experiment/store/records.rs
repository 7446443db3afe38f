//! What the experiment keeps in its [`RunStore`]: one file per finished job (one map on
//! one trajectory, with every read-out of it) holding everything the tables take from it,
//! one file per trajectory with the input labels' scores, and the manifest of the options
//! the runs depend on. A stored file is only taken if it holds exactly the run asked for;
//! otherwise [`RunStore::load`] reports it and the run is computed again.

use super::{file_name_part, Manifest, RunStore};
use crate::baselines::bki::SurfaceStates;
use crate::dataset::source::Dataset;
use crate::eval::experiment::key::{mm, Segmentation};
use crate::eval::experiment::plan::{Job, MapConfig, Plan};
use crate::eval::experiment::results::RunResult;
use crate::eval::metrics::Confusion;
use anyhow::Result;
use std::collections::BTreeMap;

/// The options an experiment's stored runs depend on, named as `sndt experiment` spells
/// them so that a refused resume names them ([`RunStore::open`]): the grid, the methods'
/// parameters, the frames run (their ids hashed), this sndt's version, and `provenance`,
/// what the caller knows and the plan does not (the dataset as given, how it was opened).
pub fn manifest(plan: &Plan, dataset: &dyn Dataset, provenance: &Manifest) -> Manifest {
    let options = &plan.options;
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
    let free = options
        .free_resolution
        .map_or_else(|| "default".to_string(), |f| f.to_string());
    let mut m: Manifest = [
        ("--labels", labels.join(",")),
        ("--cell", list(&options.cells)),
        ("--kernels", list(&options.kernels)),
        ("--methods", methods.join(",")),
        ("--free-resolution", free),
        ("--votes-per-frame", options.votes_per_frame.to_string()),
        ("--see-through-miss", options.see_through_miss.to_string()),
        ("frames", frames_run(dataset)),
        ("sndt version", env!("CARGO_PKG_VERSION").to_string()),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect();
    m.extend(provenance.iter().map(|(k, v)| (k.clone(), v.clone())));
    m
}

/// The frames a dataset runs, with their ids hashed (FNV-1a): a dataset whose frames
/// changed is not resumed, however it is named.
fn frames_run(dataset: &dyn Dataset) -> String {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    for id in dataset.frames() {
        for b in format!("{}/{}/{}\n", id.scene, id.cam, id.index).bytes() {
            hash = (hash ^ b as u64).wrapping_mul(0x0100_0000_01b3);
        }
    }
    format!(
        "{} trajectories, {} frames, ids {hash:016x}",
        dataset.trajectories().len(),
        dataset.frames().len()
    )
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
fn job_file(name: &str, job: &Job) -> String {
    let method = match job.map {
        MapConfig::Sndt(_) => "sndt".to_string(),
        MapConfig::Bki { .. } => format!("bki-kernel{}mm", job.kernel_mm()),
    };
    format!(
        "{}__{}__{method}__cell{}mm.json",
        file_name_part(name),
        job.segmentation.tag(),
        mm(job.cell)
    )
}

/// The store's file of trajectory `name`'s input labels scored.
fn inputs_file(name: &str) -> String {
    format!("{}__inputs.json", file_name_part(name))
}

/// Stores the finished `job` on trajectory `name` of `frames` frames, as soon as it is
/// finished, counted as a computed result.
pub fn save_job(
    store: &RunStore,
    name: &str,
    frames: usize,
    job: &Job,
    runs: &[RunResult],
) -> Result<()> {
    let record = StoredJob {
        trajectory: name.to_string(),
        frames,
        labels: job.segmentation.tag().to_string(),
        cell_mm: mm(job.cell),
        kernel_mm: job.kernel_mm(),
        update_s: runs.first().map_or(0.0, |r| r.seconds).to_string(),
        results: runs
            .iter()
            .map(|r| StoredResult {
                method: r.key.method.name().to_string(),
                confusion: sparse(&r.confusion),
                surface_voxels: r.surface.voxels,
                surface_free: r.surface.free,
                surface_unknown: r.surface.unknown,
                surface_occupied: r.surface.occupied,
            })
            .collect(),
    };
    store.save_result(&job_file(name, job), &record)
}

/// The stored `job` on trajectory `name` of `frames` frames, if the store holds it whole
/// and for that job (trajectory, frames, labels, cell, kernel and read-outs).
pub fn load_job(
    store: &RunStore,
    plan: &Plan,
    name: &str,
    frames: usize,
    job: &Job,
) -> Option<Vec<RunResult>> {
    store.load(&job_file(name, job), |s: StoredJob| {
        let (tag, cell_mm, kernel_mm) = (job.segmentation.tag(), mm(job.cell), job.kernel_mm());
        let holds = (&*s.trajectory, s.frames, &*s.labels, s.cell_mm, s.kernel_mm);
        if holds != (name, frames, tag, cell_mm, kernel_mm) {
            return Err(format!(
                "holds {holds:?}, not (trajectory, frames, labels, cell mm, kernel mm) {:?}",
                (name, frames, tag, cell_mm, kernel_mm)
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
                Ok(RunResult {
                    key: job.key(method),
                    confusion: dense(&r.confusion)?,
                    seconds,
                    surface,
                })
            })
            .collect()
    })
}

/// Stores trajectory `name`'s input labels scored, with its frames and how many of them
/// were skipped (not counted as a result: every job of the trajectory shares it).
pub fn save_inputs(
    store: &RunStore,
    name: &str,
    (frames, skipped): (usize, usize),
    inputs: &[(Segmentation, Confusion)],
) -> Result<()> {
    let record = StoredInputs {
        trajectory: name.to_string(),
        frames,
        skipped,
        inputs: inputs
            .iter()
            .map(|(s, c)| (s.tag().to_string(), sparse(c)))
            .collect(),
    };
    store.save(&inputs_file(name), &record)
}

/// Trajectory `name`'s stored input scores, if the store holds them for every source, and
/// how many of its frames were skipped.
pub fn load_inputs(
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

/// The non-zero cells of a confusion matrix, `[gt, prediction, count]`: a 42x42 matrix
/// is mostly zeros, and stored runs are read back by sndt, not by people.
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
