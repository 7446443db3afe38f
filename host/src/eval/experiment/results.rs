//! An experiment's results: per configuration the confusion over all trajectories, each
//! trajectory's update time and the BKI maps' surface read-outs, and the input labels'
//! own scores. The run fills them one trajectory at a time; the reports only read them,
//! through the groupings here that several reports share (cell sizes, rows, timing).

use super::key::{Method, RunKey, Segmentation};
use crate::baselines::bki::SurfaceStates;
use crate::eval::metrics::{Confusion, Metrics};
use std::collections::BTreeMap;

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
    ///
    /// ```
    /// use sndt_host::eval::experiment::Run;
    /// let run = Run {
    ///     trajectories: vec![("a".into(), 10, 1.0), ("b".into(), 10, 0.5)],
    ///     ..Default::default()
    /// };
    /// assert_eq!(run.mean_hz(), 15.0);
    /// assert_eq!(run.slowest_fastest_hz(), (10.0, 20.0));
    /// assert_eq!(run.mean_ms(), 75.0);
    /// ```
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

/// One configuration's result on one trajectory, computed or taken from the store.
#[derive(Clone, Debug)]
pub(crate) struct RunResult {
    pub key: RunKey,
    pub confusion: Confusion,
    /// The map's update time, seconds (one map, so S-BKI and OS-BKI give the same).
    pub seconds: f64,
    pub surface: SurfaceStates,
}

/// One trajectory's results: every configuration's, the input labels' confusion per
/// source, and the frames mapped and skipped (bad input).
pub(crate) struct TrajectoryResults {
    pub runs: Vec<RunResult>,
    pub inputs: Vec<(Segmentation, Confusion)>,
    /// Frames mapped (the trajectory's frames but the skipped ones).
    pub frames: usize,
    /// Frames skipped for bad input.
    pub skipped: usize,
}

impl Experiment {
    /// Adds trajectory `name`'s results. Trajectories are added in the dataset's order, so
    /// that every run lists them in that order whatever order they finished in.
    pub(crate) fn add(&mut self, name: &str, part: TrajectoryResults) {
        self.frames += part.frames;
        self.skipped += part.skipped;
        for r in part.runs {
            let run = self.runs.entry(r.key).or_default();
            run.confusion.merge(&r.confusion);
            run.surface.voxels += r.surface.voxels;
            run.surface.free += r.surface.free;
            run.surface.unknown += r.surface.unknown;
            run.surface.occupied += r.surface.occupied;
            run.trajectories
                .push((name.to_string(), part.frames, r.seconds));
        }
        for (labels, c) in part.inputs {
            self.inputs.entry(labels).or_default().merge(&c);
        }
    }

    /// The cell sizes run, mm, ascending: the tables' columns.
    pub(crate) fn cells(&self) -> Vec<u32> {
        let mut c: Vec<u32> = self.runs.keys().map(|k| k.cell_mm).collect();
        c.sort();
        c.dedup();
        c
    }

    /// Rows of a table: (label source, method, kernel) in the paper's order.
    pub(crate) fn rows(&self) -> Vec<(Segmentation, Method, u32)> {
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

    /// Update rates per (method, kernel, cell) over all label sources: per trajectory,
    /// frames over update time.
    pub(crate) fn timing(&self) -> BTreeMap<(Method, u32, u32), Run> {
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
}
