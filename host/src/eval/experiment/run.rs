//! Running a [`Plan`]: every job on every trajectory, each map built with the plan's
//! configuration and scored by the evaluation loop ([`map_and_score`], the paper's
//! evaluation protocol in `docs/EVALUATION.md`), with its update time.
//!
//! Each trajectory's frames are loaded once and every job is run on them; trajectories
//! run in parallel (rayon), and so do a trajectory's jobs, but each map is built by one
//! thread, so update times are single-threaded figures. S-BKI and OS-BKI share one map per
//! kernel length (their counts are the same, see [`crate::baselines::bki`]); the update
//! time is that map's. With a store, each finished job is kept as soon as it is finished
//! and the jobs it already holds are taken instead of run.

use super::key::{Method, Segmentation};
use super::plan::{Job, MapConfig, Plan};
use super::results::{Experiment, RunResult, TrajectoryResults};
use super::store::records::{load_inputs, load_job, save_inputs, save_job};
use super::store::RunStore;
use crate::baselines::bki::{BkiMap, Readout};
use crate::dataset::frame::{Frame, FrameId, LabelSource};
use crate::dataset::source::{usable_frames, Dataset};
use crate::eval::evaluate::{gt_depth, map_and_score, Frames, MapScore};
use crate::eval::metrics::Confusion;
use crate::mapping::{boxed_map, HostMap, SemanticMap};
use crate::output::progress::progress;
use anyhow::{anyhow, bail, Context, Result};
use rayon::prelude::*;
use std::borrow::Cow;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// What every trajectory's run shares: the dataset, the plan, the store (if runs are
/// kept) and the progress callback.
struct Runner<'a> {
    dataset: &'a dyn Dataset,
    plan: &'a Plan,
    store: Option<&'a RunStore>,
    progress: &'a (dyn Fn() + Sync),
}

/// Runs `plan` on `dataset`, keeping each finished job in `store` (if any) and taking
/// the jobs it holds instead of running them again; `progress` is called once per frame
/// mapped or back-projected (at once for the frames of a job taken from the store).
pub(super) fn run(
    dataset: &dyn Dataset,
    plan: &Plan,
    store: Option<&RunStore>,
    progress: &(dyn Fn() + Sync),
) -> Result<Experiment> {
    let runner = Runner {
        dataset,
        plan,
        store,
        progress,
    };
    let parts: Vec<Result<TrajectoryResults>> = plan
        .trajectories
        .par_iter()
        .map(|(name, ids)| {
            runner
                .trajectory(name, ids)
                .with_context(|| format!("trajectory {name}"))
        })
        .collect();
    let mut exp = Experiment::default();
    for ((name, _), part) in plan.trajectories.iter().zip(parts) {
        exp.add(name, part?);
    }
    Ok(exp)
}

/// [`run`] behind a progress bar; long runs in logs (no terminal, bar hidden) get a line
/// on stderr every 5 % instead, timed from `t`.
pub(super) fn run_with_progress(
    dataset: &dyn Dataset,
    plan: &Plan,
    store: &RunStore,
    t: Instant,
) -> Result<Experiment> {
    let steps = plan.progress_steps();
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
    let exp = run(dataset, plan, Some(store), &tick)?;
    bar.finish_and_clear();
    Ok(exp)
}

impl Runner<'_> {
    /// One trajectory through every job of the plan: the input labels scored per
    /// segmentation, then every map. The maps are independent, so they are built in
    /// parallel (rayon): with more maps than trajectories, no core idles while the last
    /// trajectory finishes. Update times are unaffected: an update makes no rayon call, so
    /// no other work is stolen into it. Results the store holds are taken from it; the
    /// frames are only loaded when something is left to compute.
    fn trajectory(&self, name: &str, ids: &[FrameId]) -> Result<TrajectoryResults> {
        let (plan, n) = (self.plan, ids.len());
        let stored: Vec<Option<Vec<RunResult>>> = plan
            .jobs
            .iter()
            .map(|job| self.store.and_then(|s| load_job(s, plan, name, n, job)))
            .collect();
        let stored_inputs = self.store.and_then(|s| load_inputs(s, plan, name, n));
        let mut skipped = Vec::new();
        let frames = if stored_inputs.is_none() || stored.iter().any(Option::is_none) {
            // Bad frames are skipped with a warning naming the file.
            usable_frames(self.dataset, ids, plan.smallest_cell, &mut skipped)
                .collect::<Result<Vec<Frame>>>()?
        } else {
            Vec::new()
        };
        if frames.is_empty() && !skipped.is_empty() {
            let last = skipped.last().map_or("", |b| b.why.as_str());
            bail!("nothing mapped: all {n} frames were skipped (the last: {last})");
        }
        let (inputs, skipped) = match stored_inputs {
            Some(inputs) => inputs,
            None => self.score_inputs(name, &frames, (n, skipped.len()))?,
        };
        let runs = plan
            .jobs
            .par_iter()
            .zip(stored.into_par_iter())
            .map(|(job, stored)| match stored {
                Some(runs) => {
                    self.skip(job, n);
                    Ok(runs)
                }
                None => {
                    let runs = self.job(&frames, job)?;
                    if let Some(store) = self.store {
                        save_job(store, name, n, job, &runs)?;
                    }
                    Ok(runs)
                }
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(TrajectoryResults {
            runs: runs.into_iter().flatten().collect(),
            inputs,
            frames: n - skipped,
            skipped,
        })
    }

    /// The input labels of every segmentation scored on `frames`, kept in the store with
    /// the trajectory's frame count `n` and its `skipped` frames.
    fn score_inputs(
        &self,
        name: &str,
        frames: &[Frame],
        (n, skipped): (usize, usize),
    ) -> Result<(Vec<(Segmentation, Confusion)>, usize)> {
        let inputs = self
            .plan
            .sources
            .iter()
            .map(|&s| Ok((s, input_confusion(frames, s)?)))
            .collect::<Result<Vec<_>>>()?;
        if let Some(store) = self.store {
            save_inputs(store, name, (n, skipped), &inputs)?;
        }
        Ok((inputs, skipped))
    }

    /// Reports the progress steps of a job taken from the store: one per frame mapped and
    /// one per frame back-projected per read-out, as if it had run.
    fn skip(&self, job: &Job, frames: usize) {
        if let Some(store) = self.store {
            store.count_resumed();
        }
        for _ in 0..frames * (1 + self.plan.methods(job).len()) {
            (self.progress)();
        }
    }

    /// Builds and scores one job's map with the plan's configuration: one result for
    /// S-NDT, one per BKI read-out.
    fn job(&self, frames: &[Frame], job: &Job) -> Result<Vec<RunResult>> {
        let labels = job.segmentation.source();
        let methods = self.plan.methods(job);
        let result = |method, confusion, seconds, surface| RunResult {
            key: job.key(method),
            confusion,
            seconds,
            surface,
        };
        match job.map {
            MapConfig::Sndt(config) => {
                let mut map: Box<HostMap> =
                    boxed_map(config).map_err(|e| anyhow!("config: {e:?}"))?;
                let score = run_map(map.as_mut(), frames, labels, &[()], self.progress)?;
                let seconds = score.update_seconds();
                Ok(score
                    .confusions
                    .into_iter()
                    .map(|c| result(Method::Sndt, c, seconds, Default::default()))
                    .collect())
            }
            MapConfig::Bki { config, .. } => {
                let readouts: Vec<Readout> = methods.iter().map(|&m| bki_readout(m)).collect();
                let mut map = BkiMap::new(config)?;
                let score = run_map(&mut map, frames, labels, &readouts, self.progress)?;
                let seconds = score.update_seconds();
                Ok(methods
                    .iter()
                    .zip(&readouts)
                    .zip(score.confusions)
                    .map(|((&m, &readout), c)| result(m, c, seconds, map.surface_states(readout)))
                    .collect())
            }
        }
    }
}

/// The BKI read-out of a BKI method.
fn bki_readout(method: Method) -> Readout {
    if method == Method::Sbki {
        Readout::Sbki
    } else {
        Readout::Osbki
    }
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
        Frames::kept(frames.iter().map(|f| Ok(Cow::Borrowed(f)))),
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
