//! `sndt compare`: the core's fixed-point map against the f64 reference.
//!
//! The same frames go into a [`sndt_core::Map`] and a [`RefMap`] per cell size; then the
//! maps are compared voxel by voxel (surface voxel sets, voxel means, covariances,
//! occupancy states, class argmax) and both are back-projected into every frame and
//! scored with the paper's metrics ([`crate::eval::metrics`]). The tolerances at 10 cm,
//! [`TOLERANCES`], are checked by the `reference` test on a fixed synthetic trajectory;
//! `docs/EVALUATION.md` (the f64 reference and tolerances) explains each.
//!
//! ```
//! use sndt_core::{Config, Pinhole};
//! use sndt_host::eval::compare::{compare, Options};
//! use sndt_host::dataset::Dataset;
//! use sndt_host::dataset::synthetic::{SynthOptions, Synthetic};
//! let camera = Pinhole { fx: 55.4, fy: 55.4, cx: 32.0, cy: 24.0, width: 64, height: 48 };
//! let split = Synthetic::new(SynthOptions { scenes: 1, frames: 2, camera, predictions: false,
//!                                           ..Default::default() }).unwrap();
//! let frames: Vec<_> = split.frames().iter().map(|id| split.load(id).unwrap()).collect();
//! let r = compare(&frames, &Config::DEFAULT, &Options::default()).unwrap();
//! assert_eq!((r.only_core, r.only_ref), (0, 0));
//! assert!(r.mean_error_mm.max < 1.4); // at most half a quantum (h/128) per axis
//! ```

use crate::dataset::frame::{Frame, LabelSource, Rays};

use crate::eval::metrics::{Confusion, Metrics, MAX_GT_DEPTH};
use crate::mapping::{boxed_map, integrate_frame, HostMap, SemanticMap};
use crate::reference::key::Key;
use crate::reference::map::RefMap;
use anyhow::{anyhow, Result};
use rayon::prelude::*;
use sndt_core::{Config, MapStats, MissModel, Occupancy, VoxelKey, INVALID_LABEL};
use std::borrow::Cow;
use std::collections::HashSet;
use std::time::Instant;

/// Classes of the compared maps (NYU40).
pub const CLASSES: usize = 40;

/// What feeds the maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Options {
    /// Labels attached to the points.
    pub labels: LabelSource,
    /// Every `stride`-th pixel in both directions is integrated (rendering uses all).
    pub stride: u32,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            labels: LabelSource::Gt,
            stride: 1,
        }
    }
}

/// Tolerances for the core against the reference (asserted at 10 cm on a synthetic
/// trajectory): how far the core's integer arithmetic may drift from exact `f64` maths.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerances {
    /// Largest mean voxel-mean error, mm.
    pub mean_error_mm: f64,
    /// Largest 99th percentile of the voxel-mean error, mm.
    pub p99_error_mm: f64,
    /// Largest median relative covariance error (fraction).
    pub covariance_median: f64,
    /// Smallest occupancy-state agreement (fraction).
    pub occupancy: f64,
    /// Smallest class-argmax agreement (fraction).
    pub class: f64,
    /// Largest |mIoU(core) - mIoU(reference)| in percentage points.
    pub miou_points: f64,
    /// Largest |invR(core) - invR(reference)| in percentage points.
    pub invr_points: f64,
}

/// The tolerances the core must meet against the reference at 10 cm: voxel means within
/// 1 mm on average (2 mm at the 99th percentile), covariances within 2 % (median), 99.5 %
/// of occupancy states and class argmaxes equal, back-projection mIoU within 0.2 and invR
/// within 0.1 percentage points.
pub const TOLERANCES: Tolerances = Tolerances {
    mean_error_mm: 1.0,
    p99_error_mm: 2.0,
    covariance_median: 0.02,
    occupancy: 0.995,
    class: 0.995,
    miou_points: 0.2,
    invr_points: 0.1,
};

/// How many of `total` compared items agree.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Agreement {
    /// Items that agree.
    pub same: u64,
    /// Items compared.
    pub total: u64,
}

impl Agreement {
    /// `same / total` (1 when nothing was compared).
    ///
    /// ```
    /// let a = sndt_host::eval::compare::Agreement { same: 199, total: 200 };
    /// assert_eq!(a.fraction(), 0.995);
    /// ```
    pub fn fraction(&self) -> f64 {
        if self.total == 0 {
            1.0
        } else {
            self.same as f64 / self.total as f64
        }
    }

    fn add(&mut self, same: bool) {
        self.same += same as u64;
        self.total += 1;
    }
}

/// Summary of a set of non-negative values.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Spread {
    /// Number of values.
    pub count: usize,
    /// Arithmetic mean.
    pub mean: f64,
    /// Median (nearest rank).
    pub median: f64,
    /// 99th percentile (nearest rank).
    pub p99: f64,
    /// Largest value.
    pub max: f64,
}

impl Spread {
    /// Summarises `values` (any order; NaNs sort last).
    ///
    /// ```
    /// let s = sndt_host::eval::compare::Spread::of((1..=200).map(f64::from).collect());
    /// assert_eq!((s.count, s.median, s.p99, s.max), (200, 100.0, 198.0, 200.0));
    /// assert_eq!(s.mean, 100.5);
    /// ```
    pub fn of(mut values: Vec<f64>) -> Spread {
        if values.is_empty() {
            return Spread::default();
        }
        values.sort_by(f64::total_cmp);
        let n = values.len();
        let rank = |q: f64| values[((q * n as f64).ceil() as usize).clamp(1, n) - 1];
        Spread {
            count: n,
            mean: values.iter().sum::<f64>() / n as f64,
            median: rank(0.5),
            p99: rank(0.99),
            max: values[n - 1],
        }
    }
}

/// Back-projection scores of both maps over all frames (the paper's evaluation protocol).
#[derive(Clone, Debug, PartialEq)]
pub struct BackProjection {
    /// The core's map.
    pub core: Metrics,
    /// The reference map.
    pub reference: Metrics,
    /// Pixels (with ground-truth depth < 20 m) where both renders give the same label.
    pub pixels: Agreement,
}

/// The comparison at one cell size.
#[derive(Clone, Debug, PartialEq)]
pub struct CellReport {
    /// Voxel edge, metres.
    pub cell_size: f32,
    /// Surface voxels only the core has.
    pub only_core: usize,
    /// Surface voxels only the reference has.
    pub only_ref: usize,
    /// Surface voxels both have.
    pub both: usize,
    /// Voxels in both whose point counts differ (should be 0 without evictions).
    pub count_mismatch: usize,
    /// `|mean(core) - mean(ref)|` over the voxels in both, millimetres.
    pub mean_error_mm: Spread,
    /// `||Sigma(core) - Sigma(ref)||_F / ||Sigma(ref)||_F` over the voxels in both with a
    /// valid Gaussian (`n >= n_min`) and a non-zero reference covariance (fraction).
    pub covariance_error: Spread,
    /// Occupancy states (free / occupied / unknown) over every voxel either map observed.
    pub occupancy: Agreement,
    /// Occupancy states over the surface voxels both have.
    pub surface_occupancy: Agreement,
    /// Class argmax over the surface voxels both have that have votes in either.
    pub class: Agreement,
    /// Core voxels whose largest histogram bin is shared by several classes (typically
    /// bins saturated at 255 within one frame): their argmax is the lowest class id.
    pub core_class_ties: usize,
    /// Back-projection scores, when the frames have ground-truth labels.
    pub back_projection: Option<BackProjection>,
    /// The core map's totals (evictions and dropped updates make the maps differ).
    pub core_stats: MapStats,
    /// Seconds the core spent integrating.
    pub core_seconds: f64,
    /// Seconds the reference spent integrating.
    pub reference_seconds: f64,
}

impl CellReport {
    /// The tolerances this report misses, one line each (empty when all hold).
    pub fn violations(&self, tol: &Tolerances) -> Vec<String> {
        let mut out = Vec::new();
        let mut check = |ok: bool, what: String| {
            if !ok {
                out.push(what);
            }
        };
        let e = &self.mean_error_mm;
        check(
            e.mean <= tol.mean_error_mm,
            format!("mean error {:.3} mm > {} mm", e.mean, tol.mean_error_mm),
        );
        check(
            e.p99 <= tol.p99_error_mm,
            format!("p99 error {:.3} mm > {} mm", e.p99, tol.p99_error_mm),
        );
        check(
            self.covariance_error.median <= tol.covariance_median,
            format!(
                "covariance median relative error {:.3} % > {} %",
                self.covariance_error.median * 100.0,
                tol.covariance_median * 100.0
            ),
        );
        check(
            self.occupancy.fraction() >= tol.occupancy,
            format!(
                "occupancy agreement {:.3} % < {} %",
                self.occupancy.fraction() * 100.0,
                tol.occupancy * 100.0
            ),
        );
        check(
            self.class.fraction() >= tol.class,
            format!(
                "class agreement {:.3} % < {} %",
                self.class.fraction() * 100.0,
                tol.class * 100.0
            ),
        );
        if let Some(b) = &self.back_projection {
            let dm = (b.core.miou - b.reference.miou) * 100.0;
            let di = (b.core.invr - b.reference.invr) * 100.0;
            check(
                dm.abs() <= tol.miou_points,
                format!("|dmIoU| {:.3} points > {}", dm.abs(), tol.miou_points),
            );
            check(
                di.abs() <= tol.invr_points,
                format!("|dinvR| {:.3} points > {}", di.abs(), tol.invr_points),
            );
        }
        out
    }
}

/// The comparison at every cell size.
#[derive(Clone, Debug, PartialEq)]
pub struct Report {
    /// What was compared (dataset, trajectory, frames).
    pub source: String,
    /// Frames integrated.
    pub frames: usize,
    /// Points integrated per map (after the stride).
    pub points: u64,
    /// The options used.
    pub options: Options,
    /// The miss model used.
    pub miss_model: MissModel,
    /// One report per cell size, in the order asked.
    pub cells: Vec<CellReport>,
}

/// Compares the core and the reference on `frames` at `config.cell_size`.
pub fn compare(frames: &[Frame], config: &Config, options: &Options) -> Result<CellReport> {
    let report = compare_cells("frames".into(), frames.len(), &[*config], options, |i| {
        Ok(Cow::Borrowed(&frames[i]))
    })?;
    Ok(report.cells.into_iter().next().expect("one cell size"))
}

/// Both maps at one cell size, with their evaluation state.
struct Pair {
    config: Config,
    core: Box<HostMap>,
    reference: RefMap,
    core_seconds: f64,
    reference_seconds: f64,
    core_confusion: Confusion,
    ref_confusion: Confusion,
    pixels: Agreement,
    evaluated: bool,
}

impl Pair {
    fn new(config: Config) -> Result<Pair> {
        Ok(Pair {
            config,
            core: boxed_map(config).map_err(|e| anyhow!("config {config:?}: {e:?}"))?,
            reference: RefMap::new(config, CLASSES),
            core_seconds: 0.0,
            reference_seconds: 0.0,
            core_confusion: Confusion::default(),
            ref_confusion: Confusion::default(),
            pixels: Agreement::default(),
            evaluated: false,
        })
    }
}

/// Compares the core and the reference at every configuration in `configs` (usually the
/// same parameters at several cell sizes) on `count` frames read by `load` (called twice
/// per frame: once to integrate, once to back-project, so frames need not all be in
/// memory). Cell sizes run in parallel.
pub fn compare_cells<'f>(
    source: String,
    count: usize,
    configs: &[Config],
    options: &Options,
    mut load: impl FnMut(usize) -> Result<Cow<'f, Frame>>,
) -> Result<Report> {
    let mut pairs = configs
        .iter()
        .map(|c| Pair::new(*c))
        .collect::<Result<Vec<_>>>()?;
    let points = integrate_all(&mut pairs, count, options, &mut load)?;
    backproject_all(&mut pairs, count, &mut load)?;
    let cells = pairs.par_iter().map(compare_maps).collect();
    Ok(Report {
        source,
        frames: count,
        points,
        options: *options,
        miss_model: configs.first().map_or(MissModel::NdtOm, |c| c.miss_model),
        cells,
    })
}

/// Integrates every frame into both maps of every pair, timing each side: the core as the
/// evaluation feeds it ([`integrate_frame`]: a pinhole frame as its depth image), the
/// reference the same frame's points and, for a pinhole frame, its depth image for the
/// see-through test.
/// Returns the points integrated per map.
fn integrate_all<'f>(
    pairs: &mut [Pair],
    count: usize,
    options: &Options,
    load: &mut impl FnMut(usize) -> Result<Cow<'f, Frame>>,
) -> Result<u64> {
    let bar = crate::output::progress::progress(count as u64, "integrate");
    let mut points_total = 0u64;
    for i in 0..count {
        let frame = load(i)?;
        let points = frame.integration_points(options.labels, options.stride);
        let view = frame.depth_view(options.stride);
        points_total += points.len() as u64;
        pairs.par_iter_mut().try_for_each(|p| -> Result<()> {
            let (core, reference) = rayon::join(
                || {
                    let t = Instant::now();
                    let r = integrate_frame(&mut p.core, &frame, options.labels, options.stride);
                    (r, t.elapsed().as_secs_f64())
                },
                || {
                    let t = Instant::now();
                    let r = p
                        .reference
                        .integrate_seen(&frame.pose, &points, view.as_ref());
                    (r, t.elapsed().as_secs_f64())
                },
            );
            core.0.map_err(|e| anyhow!("{}: core: {e:#}", frame.id))?;
            reference
                .0
                .map_err(|e| anyhow!("{}: reference: {e:?}", frame.id))?;
            p.core_seconds += core.1;
            p.reference_seconds += reference.1;
            Ok(())
        })?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(points_total)
}

/// Back-projects both maps of every pair into every frame with ground truth and scores
/// them, counting the pixels where both renders agree. Each map's read-out is prepared
/// once ([`SemanticMap::prepare`]).
fn backproject_all<'f>(
    pairs: &mut [Pair],
    count: usize,
    load: &mut impl FnMut(usize) -> Result<Cow<'f, Frame>>,
) -> Result<()> {
    let bar = crate::output::progress::progress(count as u64, "back-project");
    let references: Vec<_> = pairs.iter().map(|p| p.reference.prepare(())).collect();
    let mut scores: Vec<(Confusion, Confusion, Agreement, bool)> =
        pairs.iter().map(|_| Default::default()).collect();
    for i in 0..count {
        let frame = load(i)?;
        let Some(gt) = frame.labels.as_ref() else {
            continue;
        };
        let depth = frame.planar_depth_image();
        pairs
            .par_iter()
            .zip(references.par_iter())
            .zip(scores.par_iter_mut())
            .try_for_each(|((p, reference), score)| -> Result<()> {
                let (core, reference) = rayon::join(
                    || render_core(&p.core, &frame),
                    || reference.render_frame(&frame),
                );
                let (core, reference) = (core?, reference?);
                score.0.add_frame(gt, &core, &depth);
                score.1.add_frame(gt, &reference, &depth);
                for ((&c, &r), &d) in core.iter().zip(&reference).zip(&depth) {
                    if d < MAX_GT_DEPTH {
                        score.2.add(c == r);
                    }
                }
                score.3 = true;
                Ok(())
            })?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    drop(references);
    for (p, (core, reference, pixels, evaluated)) in pairs.iter_mut().zip(scores) {
        p.core_confusion = core;
        p.ref_confusion = reference;
        p.pixels = pixels;
        p.evaluated = evaluated;
    }
    Ok(())
}

/// The core's back-projection of `frame`. A pinhole frame goes through the evaluation's
/// [`LabelView`] of the core (the same `Map::render` arithmetic the reference mirrors);
/// per-pixel rays are rotated by the pose's rotation matrix and cast unnormalised, as the
/// reference's render does, rather than normalised first as the evaluation does, so that
/// the two maps are cast along identical rays.
fn render_core(map: &HostMap, frame: &Frame) -> Result<Vec<u8>> {
    let Rays::PerPixel { width, .. } = frame.rays.as_ref() else {
        return map.prepare(()).render_frame(frame);
    };
    let rot = frame.pose.rotation.to_rotation_matrix();
    let origin = sndt_core::Point3::from(frame.pose.translation.vector);
    let w = *width as usize;
    let labels = (0..frame.pixels())
        .map(|i| {
            let r = frame.rays.ray((i % w) as u32, (i / w) as u32);
            let dir = rot * sndt_core::Vector3::new(r[0], r[1], r[2]);
            map.raycast(&origin, &dir, map.config().max_range)
                .map_or(INVALID_LABEL, |hit| hit.class)
        })
        .collect();
    Ok(labels)
}

fn to_key(k: &VoxelKey) -> Key {
    [k.x as i32, k.y as i32, k.z as i32]
}

fn from_key(k: &Key) -> Option<VoxelKey> {
    let c = |v: i32| i16::try_from(v).ok();
    Some(VoxelKey {
        x: c(k[0])?,
        y: c(k[1])?,
        z: c(k[2])?,
    })
}

/// The voxel-by-voxel comparison of one pair of maps.
fn compare_maps(p: &Pair) -> CellReport {
    let (core, reference) = (&p.core, &p.reference);
    let n_min = p.config.n_min;
    let core_keys: HashSet<Key> = core.voxels().map(|v| to_key(&v.key)).collect();
    let mut report = CellReport {
        cell_size: p.config.cell_size,
        only_core: core_keys
            .iter()
            .filter(|k| reference.voxel(k).is_none())
            .count(),
        only_ref: 0,
        both: 0,
        count_mismatch: 0,
        mean_error_mm: Spread::default(),
        covariance_error: Spread::default(),
        occupancy: Agreement::default(),
        surface_occupancy: Agreement::default(),
        class: Agreement::default(),
        core_class_ties: 0,
        back_projection: None,
        core_stats: core.stats(),
        core_seconds: p.core_seconds,
        reference_seconds: p.reference_seconds,
    };
    report.core_class_ties = core
        .voxels()
        .filter(|v| {
            let max = v.histogram.iter().copied().max().unwrap_or(0);
            max > 0 && v.histogram.iter().filter(|&&b| b == max).count() > 1
        })
        .count();
    let mut mean_err = Vec::new();
    let mut cov_err = Vec::new();
    for (key, rv) in reference.voxels() {
        let Some(cv) = from_key(key).and_then(|k| core.voxel(&k)) else {
            report.only_ref += 1;
            continue;
        };
        report.both += 1;
        let g = reference.gaussian(key).expect("voxel exists");
        if cv.gaussian.count as f64 != rv.n {
            report.count_mismatch += 1;
        }
        let cm = cv.gaussian.mean.cast::<f64>();
        mean_err.push((cm - g.mean).norm() * 1e3);
        if cv.gaussian.count >= n_min && rv.n >= n_min as f64 {
            let norm = g.covariance.norm();
            if norm > 0.0 {
                let cc = cv.gaussian.covariance.cast::<f64>();
                cov_err.push((cc - g.covariance).norm() / norm);
            }
        }
        report
            .surface_occupancy
            .add(cv.occupancy() == reference.occupancy(key));
        let (cc, rc) = (cv.class(), rv.class());
        if cc.is_some() || rc.is_some() {
            report.class.add(cc.map(|c| c.0) == rc.map(|c| c.0));
        }
    }
    report.mean_error_mm = Spread::of(mean_err);
    report.covariance_error = Spread::of(cov_err);

    let mut observed: HashSet<Key> = core.cells().map(|(k, _)| to_key(&k)).collect();
    observed.extend(reference.cells().map(|(k, _)| *k));
    for key in &observed {
        let c = from_key(key).map_or(Occupancy::Unknown, |k| core.occupancy(&k));
        report.occupancy.add(c == reference.occupancy(key));
    }
    if p.evaluated {
        report.back_projection = Some(BackProjection {
            core: p.core_confusion.metrics(),
            reference: p.ref_confusion.metrics(),
            pixels: p.pixels,
        });
    }
    report
}
