//! What an experiment runs, decided and checked before anything runs: the label sources,
//! the methods, the trajectories and every map to build on each of them, with the map's
//! configuration built and validated here once. The run and the stored runs take the
//! configurations from the [`Plan`]; nothing builds them again.

use super::key::{mm, Method, RunKey, Segmentation};
use crate::baselines::bki::BkiConfig;
use crate::dataset::frame::{FrameId, LabelSource};
use crate::dataset::source::Dataset;
use anyhow::{anyhow, bail, Result};
use sndt_core::Config;

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
    /// S-NDT see-through miss ([`Config::see_through_miss`]; default [`Config::DEFAULT`]'s).
    pub see_through_miss: f32,
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
            see_through_miss: Config::DEFAULT.see_through_miss,
        }
    }
}

/// The map a [`Job`] builds, with its configuration.
#[derive(Clone, Copy, Debug)]
pub enum MapConfig {
    /// An S-NDT map.
    Sndt(Config),
    /// One BKI map of kernel length `kernel` (metres, as given), read out as S-BKI and / or
    /// OS-BKI.
    Bki {
        /// The kernel length as the options give it: keys and file names are made of it.
        kernel: f32,
        /// The map's configuration.
        config: BkiConfig,
    },
}

/// One map to build on a trajectory: a segmentation, a cell size and the map.
#[derive(Clone, Copy, Debug)]
pub struct Job {
    /// The labels fed to the map.
    pub segmentation: Segmentation,
    /// Cell size, metres, as the options give it.
    pub cell: f32,
    /// The map and its configuration.
    pub map: MapConfig,
}

impl Job {
    /// The kernel length in mm, 0 for S-NDT (as [`RunKey::kernel_mm`]).
    pub fn kernel_mm(&self) -> u32 {
        match self.map {
            MapConfig::Sndt(_) => 0,
            MapConfig::Bki { kernel, .. } => mm(kernel),
        }
    }

    /// The key of this job's map read out as `method`.
    pub fn key(&self, method: Method) -> RunKey {
        RunKey {
            labels: self.segmentation,
            method,
            kernel_mm: self.kernel_mm(),
            cell_mm: mm(self.cell),
        }
    }
}

/// Everything an experiment runs.
#[derive(Clone, Debug)]
pub struct Plan {
    /// The options it was planned from (the stored runs' manifest records them).
    pub options: ExperimentOptions,
    /// The label sources, as segmentations, in the options' order.
    pub sources: Vec<Segmentation>,
    /// S-BKI and / or OS-BKI, in that order: how each BKI map is read out.
    pub bki_methods: Vec<Method>,
    /// Every map to build on each trajectory ([`Plan::new`] gives the order).
    pub jobs: Vec<Job>,
    /// The dataset's trajectories: name and frames.
    pub trajectories: Vec<(String, Vec<FrameId>)>,
    /// The smallest cell size: its key range is the smallest, so a pose it accepts every
    /// map accepts (frames are checked against it once).
    pub smallest_cell: f32,
}

impl Plan {
    /// Plans `options` on `dataset`, refusing what cannot run before anything runs: label
    /// sources other than ground truth and top-1 prediction, an empty grid, BKI without
    /// kernel lengths, and any configuration the options make invalid (each cell's S-NDT
    /// config and each cell and kernel's BKI config is built and validated here, whether
    /// or not its method is run, and kept in the jobs).
    ///
    /// The jobs are, per segmentation and cell size, S-NDT and then one BKI map per kernel
    /// length.
    ///
    /// ```
    /// use sndt_host::eval::experiment::{ExperimentOptions, Plan};
    /// let data = sndt_host::dataset::open_spec("synthetic:1:2", &Default::default()).unwrap();
    /// let plan = Plan::new(&ExperimentOptions::default(), data.as_ref()).unwrap();
    /// assert_eq!(plan.jobs.len(), 2 * 4 * (1 + 4)); // labels, cells, S-NDT + 4 kernels
    /// let bad = ExperimentOptions { cells: vec![], ..Default::default() };
    /// assert!(Plan::new(&bad, data.as_ref()).is_err());
    /// ```
    pub fn new(options: &ExperimentOptions, dataset: &dyn Dataset) -> Result<Plan> {
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
        let per_cell = options
            .cells
            .iter()
            .map(|&cell| cell_maps(options, cell, &bki_methods))
            .collect::<Result<Vec<_>>>()?;
        let mut jobs = Vec::new();
        for &segmentation in &sources {
            for (&cell, maps) in options.cells.iter().zip(&per_cell) {
                jobs.extend(maps.iter().map(|&map| Job {
                    segmentation,
                    cell,
                    map,
                }));
            }
        }
        let smallest_cell = options.cells.iter().copied().fold(f32::INFINITY, f32::min);
        Ok(Plan {
            options: options.clone(),
            sources,
            bki_methods,
            jobs,
            trajectories: dataset.trajectories(),
            smallest_cell,
        })
    }

    /// The methods a job's map is read out as, in the order of its results.
    pub fn methods(&self, job: &Job) -> &[Method] {
        match job.map {
            MapConfig::Sndt(_) => &[Method::Sndt],
            MapConfig::Bki { .. } => &self.bki_methods,
        }
    }

    /// How many progress steps the run reports: per trajectory and job, one per frame
    /// mapped and one per frame back-projected per read-out.
    pub fn progress_steps(&self) -> u64 {
        let frames: usize = self.trajectories.iter().map(|(_, ids)| ids.len()).sum();
        let per_frame: usize = self.jobs.iter().map(|j| 1 + self.methods(j).len()).sum();
        (frames * per_frame) as u64
    }
}

/// The maps of one cell size, configured and validated: S-NDT if asked for, then one BKI
/// map per kernel length if S-BKI or OS-BKI is. Every configuration is validated even if
/// its method is not run, so that the options are refused or accepted as a whole.
fn cell_maps(
    options: &ExperimentOptions,
    cell: f32,
    bki_methods: &[Method],
) -> Result<Vec<MapConfig>> {
    let sndt = Config {
        votes_per_frame: options.votes_per_frame,
        see_through_miss: options.see_through_miss,
        ..Config::with_cell_size(cell)
    };
    sndt.validate()
        .map_err(|e| anyhow!("cell size {cell}: {e:?}"))?;
    let mut maps = Vec::new();
    if options.methods.contains(&Method::Sndt) {
        maps.push(MapConfig::Sndt(sndt));
    }
    for &kernel in &options.kernels {
        let mut config = BkiConfig::new(cell, kernel);
        if let Some(f) = options.free_resolution {
            config.free_resolution = f;
        }
        config.validate()?;
        if !bki_methods.is_empty() {
            maps.push(MapConfig::Bki { kernel, config });
        }
    }
    Ok(maps)
}
