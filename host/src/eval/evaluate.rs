//! The paper's evaluation loop (DESIGN.md section 4): one map per trajectory, built from
//! every frame in order (single-threaded, timed), then back-projected into every frame of
//! that trajectory at its ground-truth pose with the core's `raycast`; one confusion matrix
//! over all frames of the split; each back-projection written as a plain 8-bit PNG at
//! `<out>/<scene>/<cam>/<NNNN>.png` (0 void, 1..40 class, 255 invalid) for the authors'
//! evaluate.py.
//!
//! Trajectories are processed in parallel (rayon), each map by one thread, so update
//! times stay comparable to single-threaded figures; back-projection of a frame is split
//! into row bands rendered in parallel.

use crate::dataset::frame::{Frame, LabelSource, Rays};

use crate::dataset::source::Dataset;
use crate::eval::metrics::{Confusion, Metrics};
use anyhow::{anyhow, Context, Result};
use rayon::prelude::*;
use sndt_core::{
    Config, DepthImage, DepthKind, LabelImage, Labels, Map, Pinhole, Point3, Vector3, INVALID_LABEL,
};
use std::path::PathBuf;
use std::time::Instant;

/// Map capacity used for evaluation: 2^19 NDT voxels, 2^17 blocks, 40 classes (~74 MiB).
pub type EvalMap = Map<{ 1 << 19 }, { 1 << 17 }, 40>;

/// What to evaluate.
#[derive(Clone, Debug)]
pub struct EvalOptions {
    /// Map parameters (cell size etc.).
    pub config: Config,
    /// Which labels feed the map.
    pub labels: LabelSource,
    /// Where to write back-projection PNGs (none when `None`).
    pub out: Option<PathBuf>,
    /// Use every `stride`-th pixel when mapping (1 = all, as the paper).
    pub stride: u32,
    /// Frames whose back-projections to return in [`Evaluation::kept`] (for pictures).
    pub keep_frames: Vec<crate::dataset::frame::FrameId>,
    /// Whether to return the final maps in [`Evaluation::maps`].
    pub keep_maps: bool,
    /// Directory to write each trajectory's final map snapshot into
    /// (`<dir>/<scene>_<cam>.sndt`, readable by `sndt export`).
    pub save_maps: Option<PathBuf>,
}

impl EvalOptions {
    /// Options for `config` and `labels`: no PNGs, every pixel, nothing kept.
    pub fn new(config: Config, labels: LabelSource) -> EvalOptions {
        EvalOptions {
            config,
            labels,
            out: None,
            stride: 1,
            keep_frames: Vec::new(),
            keep_maps: false,
            save_maps: None,
        }
    }
}

/// Per-trajectory figures.
#[derive(Clone, Debug, serde::Serialize)]
pub struct TrajectoryResult {
    /// `scene/cam`.
    pub name: String,
    /// Frames mapped.
    pub frames: usize,
    /// Update time per frame, milliseconds.
    pub update_ms: Vec<f64>,
    /// NDT voxels in the final map.
    pub voxels: usize,
    /// Occupancy blocks in the final map.
    pub blocks: usize,
    /// Voxels evicted for lack of room.
    pub evicted: u64,
}

impl TrajectoryResult {
    /// Mean update time, milliseconds.
    pub fn mean_ms(&self) -> f64 {
        self.update_ms.iter().sum::<f64>() / self.update_ms.len().max(1) as f64
    }
}

/// Result of an evaluation.
pub struct Evaluation {
    /// Confusion over all frames of all trajectories.
    pub confusion: Confusion,
    /// Per trajectory.
    pub trajectories: Vec<TrajectoryResult>,
    /// The labels fed to the map, scored against the ground truth on the frames
    /// themselves (e.g. the network alone, without mapping).
    pub input: Confusion,
    /// Back-projections of the frames asked for in [`EvalOptions::keep_frames`].
    pub kept: Vec<(crate::dataset::frame::FrameId, Vec<u8>)>,
    /// Final maps, per trajectory, when [`EvalOptions::keep_maps`].
    pub maps: Vec<Box<EvalMap>>,
}

impl Evaluation {
    /// mIoU / mPAcc / invR and per-class IoU.
    pub fn metrics(&self) -> Metrics {
        self.confusion.metrics()
    }

    /// Mean update time per frame over all frames, milliseconds.
    pub fn mean_update_ms(&self) -> f64 {
        let (sum, n) = self.trajectories.iter().fold((0.0, 0usize), |(s, n), t| {
            (s + t.update_ms.iter().sum::<f64>(), n + t.update_ms.len())
        });
        sum / n.max(1) as f64
    }

    /// The result as JSON (metrics, per-class IoU by name, trajectories).
    pub fn to_json(&self) -> serde_json::Value {
        let m = self.metrics();
        let per_class = m.iou_by_name();
        serde_json::json!({
            "miou": m.miou,
            "mpacc": m.mpacc,
            "invr": m.invr,
            "per_class_iou": per_class,
            "mean_update_ms": self.mean_update_ms(),
            "trajectories": self.trajectories,
        })
    }

    /// A readable table: summary metrics, then per-class IoU.
    pub fn table(&self) -> String {
        let m = self.metrics();
        let mut s = String::new();
        s += "| metric | value |\n|---|---|\n";
        s += &format!("| mIoU | {:.2} % |\n", m.miou * 100.0);
        s += &format!("| mPAcc | {:.2} % |\n", m.mpacc * 100.0);
        s += &format!("| invR | {:.2} % |\n", m.invr * 100.0);
        let ms = self.mean_update_ms();
        s += &format!("| update | {ms:.1} ms/frame ({:.1} Hz) |\n", 1e3 / ms);
        s += "\n| class | IoU |\n|---|---|\n";
        for (c, v) in m.iou.iter().enumerate() {
            if let Some(v) = v {
                s += &format!(
                    "| {} | {:.2} % |\n",
                    crate::dataset::classes::NYU40[c],
                    v * 100.0
                );
            }
        }
        s
    }
}

/// Integrates one frame into `map` with labels from `source`.
pub fn integrate_frame<const V: usize, const B: usize, const C: usize>(
    map: &mut Map<V, B, C>,
    frame: &Frame,
    source: LabelSource,
    stride: u32,
) -> Result<sndt_core::FrameReport> {
    let err = |e: sndt_core::Error| anyhow!("{}: integrate: {e:?}", frame.id);
    match frame.rays.as_ref() {
        Rays::Pinhole(cam) => {
            let top1: Vec<u8>;
            let topk: Vec<Labels>;
            let labels = match source {
                LabelSource::None => LabelImage::None,
                LabelSource::Gt => match &frame.labels {
                    Some(l) => LabelImage::Top1(l),
                    None => LabelImage::None,
                },
                LabelSource::Pred => match &frame.predictions {
                    Some(p) => {
                        top1 = p.top1();
                        LabelImage::Top1(&top1)
                    }
                    None => LabelImage::None,
                },
                LabelSource::PredTopk => match &frame.predictions {
                    Some(p) => {
                        topk = (0..frame.pixels()).map(|i| p.labels(i)).collect();
                        LabelImage::TopK(&topk)
                    }
                    None => LabelImage::None,
                },
            };
            let image = DepthImage {
                camera: *cam,
                depth: &frame.depth,
                kind: frame.depth_kind,
                labels,
                stride,
            };
            map.integrate_depth(&frame.pose, &image).map_err(err)
        }
        Rays::PerPixel { .. } => {
            let points = frame.camera_points(source, stride);
            map.integrate(&frame.pose, &points).map_err(err)
        }
    }
}

/// Back-projects `map` into a frame's camera: one label per pixel (0..=40, 255 invalid).
/// Row bands are rendered in parallel.
pub fn backproject<const V: usize, const B: usize, const C: usize>(
    map: &Map<V, B, C>,
    frame: &Frame,
) -> Result<Vec<u8>> {
    let (w, h) = (frame.rays.width() as usize, frame.rays.height() as usize);
    let mut labels = vec![INVALID_LABEL; w * h];
    const BAND: usize = 32;
    labels
        .par_chunks_mut(BAND * w)
        .enumerate()
        .try_for_each(|(band, out)| -> Result<()> {
            let row0 = band * BAND;
            let rows = out.len() / w;
            match frame.rays.as_ref() {
                Rays::Pinhole(cam) => {
                    // The band as a camera of its own: same rays, principal point shifted.
                    let sub = Pinhole {
                        cy: cam.cy - row0 as f32,
                        height: rows as u32,
                        ..*cam
                    };
                    let mut dist = vec![0f32; out.len()];
                    map.render(&frame.pose, &sub, out, &mut dist)
                        .map_err(|e| anyhow!("{}: render: {e:?}", frame.id))
                }
                Rays::PerPixel { .. } => {
                    let o = frame.pose.translation.vector;
                    let origin = Point3::new(o.x, o.y, o.z);
                    for r in 0..rows {
                        for c in 0..w {
                            let ray = frame.rays.ray(c as u32, (row0 + r) as u32);
                            let d = frame.pose.rotation
                                * Vector3::new(ray[0], ray[1], ray[2]).normalize();
                            out[r * w + c] = map
                                .raycast(&origin, &d, map.config().max_range)
                                .map_or(INVALID_LABEL, |hit| hit.class);
                        }
                    }
                    Ok(())
                }
            }
        })?;
    Ok(labels)
}

/// Maps every trajectory of `dataset` and evaluates it. `progress` is called once per
/// frame mapped and once per frame back-projected.
pub fn evaluate(
    dataset: &dyn Dataset,
    options: &EvalOptions,
    progress: &(dyn Fn() + Sync),
) -> Result<Evaluation> {
    options
        .config
        .validate()
        .map_err(|e| anyhow!("config: {e:?}"))?;
    let trajectories = dataset.trajectories();
    type Part = (
        Confusion,
        Confusion,
        TrajectoryResult,
        Vec<(crate::dataset::frame::FrameId, Vec<u8>)>,
        Option<Box<EvalMap>>,
    );
    let results: Vec<Result<Part>> = trajectories
        .par_iter()
        .map(|(name, ids)| -> Result<Part> {
            let mut map: Box<EvalMap> = crate::semantic_map::boxed_map(options.config)
                .map_err(|e| anyhow!("config: {e:?}"))?;
            let mut kept = Vec::with_capacity(ids.len());
            let mut input = Confusion::default();
            let mut update_ms = Vec::with_capacity(ids.len());
            for id in ids {
                let frame = dataset.load(id)?;
                let t = Instant::now();
                integrate_frame(map.as_mut(), &frame, options.labels, options.stride)?;
                update_ms.push(t.elapsed().as_secs_f64() * 1e3);
                if let Some(gt) = &frame.labels {
                    let given: Vec<u8> = (0..frame.pixels())
                        .map(|i| frame.point_labels(i, options.labels).classes[0])
                        .collect();
                    input.add_frame(gt, &given, &gt_depth(&frame));
                }
                // Predictions are not needed any more; keep depth, labels and pose.
                kept.push(Frame {
                    predictions: None,
                    ..frame
                });
                progress();
            }
            if let Some(dir) = &options.save_maps {
                save_snapshot(
                    map.as_ref(),
                    &dir.join(format!("{}.sndt", name.replace('/', "_"))),
                )?;
            }
            let mut confusion = Confusion::default();
            let mut images = Vec::new();
            for f in &kept {
                let pred = backproject(map.as_ref(), f)?;
                if let Some(gt) = &f.labels {
                    confusion.add_frame(gt, &pred, &gt_depth(f));
                }
                if let Some(out) = &options.out {
                    let path = out
                        .join(&f.id.scene)
                        .join(&f.id.cam)
                        .join(format!("{}.png", f.id.stem()));
                    if let Some(dir) = path.parent() {
                        std::fs::create_dir_all(dir)
                            .with_context(|| format!("creating {}", dir.display()))?;
                    }
                    crate::dataset::prepared::write_gray8(
                        &path,
                        f.rays.width(),
                        f.rays.height(),
                        &pred,
                    )?;
                }
                if options.keep_frames.contains(&f.id) {
                    images.push((f.id.clone(), pred));
                }
                progress();
            }
            let stats = map.stats();
            Ok((
                confusion,
                input,
                TrajectoryResult {
                    name: name.clone(),
                    frames: ids.len(),
                    update_ms,
                    voxels: map.len(),
                    blocks: map.block_count(),
                    evicted: stats.voxels_evicted,
                },
                images,
                options.keep_maps.then_some(map),
            ))
        })
        .collect();
    let mut eval = Evaluation {
        confusion: Confusion::default(),
        trajectories: Vec::new(),
        input: Confusion::default(),
        kept: Vec::new(),
        maps: Vec::new(),
    };
    for r in results {
        let (c, i, t, images, map) = r?;
        eval.confusion.merge(&c);
        eval.input.merge(&i);
        eval.trajectories.push(t);
        eval.kept.extend(images);
        eval.maps.extend(map);
    }
    Ok(eval)
}

/// Writes a map snapshot file.
pub fn save_snapshot<const V: usize, const B: usize, const C: usize>(
    map: &Map<V, B, C>,
    path: &std::path::Path,
) -> Result<()> {
    let mut buf = vec![0u8; map.snapshot_len()];
    let n = map
        .write_snapshot(&mut buf)
        .map_err(|e| anyhow!("{}: snapshot: {e:?}", path.display()))?;
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    std::fs::write(path, &buf[..n]).with_context(|| format!("writing {}", path.display()))
}

/// Reads a map snapshot file into a heap map of the evaluation's capacity.
pub fn load_snapshot(path: &std::path::Path) -> Result<Box<EvalMap>> {
    let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    let mut map: Box<EvalMap> =
        crate::semantic_map::boxed_map(Config::DEFAULT).map_err(|e| anyhow!("{e:?}"))?;
    map.read_snapshot(&bytes)
        .map_err(|e| anyhow!("{}: not a readable sndt snapshot: {e:?}", path.display()))?;
    Ok(map)
}

/// The evaluation's ground-truth depth: planar depth, with no-measurement pixels as 0
/// (kept, as the authors' evaluator keeps depth 0) — only depth >= 20 m is masked.
pub fn gt_depth(f: &Frame) -> Vec<f32> {
    match f.depth_kind {
        DepthKind::Planar => f
            .depth
            .iter()
            .map(|&d| if d.is_finite() { d } else { 0.0 })
            .collect(),
        DepthKind::Range => f.planar_depth_image(),
    }
}

/// The paper's S-NDT results on Hypersim (Tables I and II): cell size (m), then mIoU,
/// invR, mPAcc (%) with ground-truth labels, the same with predicted labels, and the mean
/// map update rate (Hz, i7-6700HQ, single thread).
pub const PAPER_SNDT: [(f32, [f64; 3], [f64; 3], f64); 4] = [
    (0.05, [78.28, 2.93, 88.30], [41.12, 2.93, 56.18], 1.0),
    (0.10, [72.04, 0.83, 85.12], [39.62, 0.83, 54.73], 3.5),
    (0.15, [66.53, 0.73, 81.13], [37.68, 0.73, 52.82], 5.2),
    (0.20, [61.96, 0.78, 78.10], [35.56, 0.78, 50.37], 5.4),
];

/// The paper's ESANet-R34-NBt1D alone (no mapping) on the Hypersim test set: mIoU (%).
pub const PAPER_ESANET_MIOU: f64 = 41.17;
