//! The paper's evaluation protocol (`docs/EVALUATION.md`): one map
//! per trajectory, built from every frame in order (single-threaded, timed), then
//! back-projected into every frame of that trajectory at its ground-truth pose; one
//! confusion matrix over all frames of the split.
//!
//! [`map_and_score`] is that loop for any [`SemanticMap`] and read-out: the experiment
//! runs S-NDT, S-BKI and OS-BKI through it. [`evaluate`] runs S-NDT through it on a whole
//! dataset (`sndt map`), writing each back-projection as a plain 8-bit PNG at
//! `<out>/<scene>/<cam>/<NNNN>.png` (0 void, 1..40 class, 255 invalid) for the authors'
//! evaluate.py.
//!
//! Trajectories are processed in parallel (rayon), each map by one thread, so update
//! times stay comparable to single-threaded figures; back-projection of a frame is split
//! into row bands rendered in parallel.

use crate::dataset::frame::{Frame, FrameId, LabelSource};
use crate::dataset::ros::msgs::Time;
use crate::dataset::source::{usable_frames, Dataset};
use crate::eval::metrics::{Confusion, Metrics};
use crate::mapping::{boxed_map, HostMap, SemanticMap};
use crate::mapping::{DeviceCapacity, GlobalMap, Spill, SpillStats, SpillingMap};
use crate::output::ros::export::MapBag;
use crate::output::ros::write::frame_time;
use anyhow::{anyhow, bail, Context, Result};
use rayon::prelude::*;
use sndt_core::{Config, DepthKind, Map, SnapshotHeader};
use std::borrow::Cow;
use std::path::{Path, PathBuf};
use std::time::Instant;

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
    pub keep_frames: Vec<FrameId>,
    /// Whether to return the final maps in [`Evaluation::maps`].
    pub keep_maps: bool,
    /// Directory to write each trajectory's final map snapshot into
    /// (`<dir>/<scene>_<cam>.sndt`, readable by `sndt export`).
    pub save_maps: Option<PathBuf>,
    /// ROS 2 bag of each trajectory's map ([`crate::output::ros::export`]): this file for one
    /// trajectory, `<stem>_<scene>_<cam>.mcap` beside it for several; a folder path gives
    /// bag folders ([`crate::output::ros::write::BagWriter`]).
    pub mcap: Option<PathBuf>,
    /// With `mcap`: write the map after every this many frames of the trajectory as well
    /// as at the end (`sndt map --mcap-interval`).
    pub mcap_interval: Option<usize>,
    /// With `mcap`: the frame `/tf_static` attaches the map frame to.
    pub mcap_world: String,
    /// Map with a device-capacity map spilling into a global map (`sndt map --device`)
    /// instead of one host map, and which of its maps to score.
    pub device: Option<(DeviceCapacity, Spill)>,
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
            mcap: None,
            mcap_interval: None,
            mcap_world: "world".into(),
            device: None,
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
    /// Frames skipped for bad input (named in a `warning:` on stderr).
    pub skipped: usize,
    /// Update time per frame, milliseconds.
    pub update_ms: Vec<f64>,
    /// NDT voxels in the final map.
    pub voxels: usize,
    /// Occupancy blocks in the final map.
    pub blocks: usize,
    /// Voxels evicted for lack of room.
    pub evicted: u64,
    /// With a device map (`--device`): what spilling into the global map cost.
    pub spill: Option<SpillSummary>,
}

/// A trajectory's spill from a device map into the global map.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SpillSummary {
    /// Device capacity (voxels, blocks).
    pub device: (usize, usize),
    /// Records, dropped records and stream bytes per frame.
    pub stats: SpillStats,
    /// The global map's tier (0..=2) and bytes.
    pub global_tier: usize,
    /// Bytes of the global map (its tier's fixed size).
    pub global_bytes: usize,
    /// mIoU, invR and mPAcc of the other read-out: the device map alone when the merged
    /// map is scored, the merged map when the device map is (both from one run).
    pub other: (f64, f64, f64),
    /// Voxels and blocks of the device map at the end.
    pub device_voxels: usize,
    /// Blocks of the device map at the end.
    pub device_blocks: usize,
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
    pub kept: Vec<(FrameId, Vec<u8>)>,
    /// Final maps, per trajectory, when [`EvalOptions::keep_maps`].
    pub maps: Vec<Box<HostMap>>,
}

impl Evaluation {
    /// mIoU / mPAcc / invR and per-class IoU.
    pub fn metrics(&self) -> Metrics {
        self.confusion.metrics()
    }

    /// Frames mapped, over all trajectories.
    pub fn frames(&self) -> usize {
        self.trajectories.iter().map(|t| t.frames).sum()
    }

    /// Frames skipped for bad input, over all trajectories.
    pub fn skipped(&self) -> usize {
        self.trajectories.iter().map(|t| t.skipped).sum()
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

/// One map's pass over one trajectory, from [`map_and_score`].
#[derive(Clone, Debug, Default)]
pub struct MapScore {
    /// Update time per frame, milliseconds.
    pub update_ms: Vec<f64>,
    /// Per read-out asked for, in that order: its renders scored over all frames.
    pub confusions: Vec<Confusion>,
}

impl MapScore {
    /// Total update time, seconds.
    pub fn update_seconds(&self) -> f64 {
        self.update_ms.iter().sum::<f64>() / 1e3
    }
}

/// Bytes of owned frames [`map_and_score`] keeps in memory for its render pass; frames
/// past this are read again from the dataset instead, so a long recording is evaluated in
/// bounded memory (a 1024x768 frame is about 4 MB).
pub const KEEP_FRAME_BYTES: usize = 512 << 20;

/// How [`map_and_score`] reads a frame again for its render pass (the dataset's `load`).
pub type Reload<'a> = &'a (dyn Fn(&FrameId) -> Result<Frame> + Sync);

/// Frames loaded one at a time, kept for the render pass up to [`KEEP_FRAME_BYTES`] and
/// read again with `reload` past that.
fn lazy_frames<'a, 'f>(
    frames: impl Iterator<Item = Result<Frame>>,
    reload: Reload<'a>,
) -> Frames<'a, impl Iterator<Item = Result<Cow<'f, Frame>>>> {
    Frames {
        frames: frames.map(|frame| frame.map(Cow::Owned)),
        reload: Some(reload),
        keep_bytes: KEEP_FRAME_BYTES,
    }
}

/// The frames [`map_and_score`] maps and renders into.
pub struct Frames<'a, I> {
    /// The trajectory's frames in order (loaded lazily if the iterator does).
    pub frames: I,
    /// Reads a frame again for the render pass; `None` keeps every frame in memory.
    pub reload: Option<Reload<'a>>,
    /// Bytes of owned frames kept for the render pass before the others are read again
    /// ([`KEEP_FRAME_BYTES`] for the tools).
    pub keep_bytes: usize,
}

impl<'a, 'f, I: IntoIterator<Item = Result<Cow<'f, Frame>>>> Frames<'a, I> {
    /// All frames kept in memory (borrowed ones cost nothing).
    pub fn kept(frames: I) -> Self {
        Frames {
            frames,
            reload: None,
            keep_bytes: usize::MAX,
        }
    }
}

/// A frame as the render pass gets it: kept, or to be read again.
enum Kept<'f> {
    Frame(Cow<'f, Frame>),
    Reload(FrameId),
}

/// The paper's evaluation of one map on one trajectory, the same for every method: each
/// frame is integrated in order with labels from `labels` (every `stride`-th pixel), each
/// update timed on its own; then each read-out in `readouts` is prepared once and
/// rendered into every frame at the frame's pose, and the renders are scored against the
/// frames' ground truth (a frame without it is rendered but not scored).
///
/// Frames arrive one at a time from `frames.frames`, so a caller can load them lazily:
/// borrowed frames are rendered as they are; owned ones are kept without their predictions
/// (which rendering does not need) up to `frames.keep_bytes`, and past that read again
/// with `frames.reload` when there is one (without one, all are kept). The scores are the
/// same either way. `after_update` sees each frame
/// and the map after its (timed) update, `after_render` each frame's render.
pub fn map_and_score<'f, M: SemanticMap + ?Sized>(
    map: &mut M,
    frames: Frames<impl IntoIterator<Item = Result<Cow<'f, Frame>>>>,
    labels: LabelSource,
    stride: u32,
    readouts: &[M::Readout],
    mut after_update: impl FnMut(&Frame, &M) -> Result<()>,
    mut after_render: impl FnMut(&Frame, &[u8]) -> Result<()>,
) -> Result<MapScore> {
    let Frames {
        frames,
        reload,
        keep_bytes,
    } = frames;
    let mut update_ms = Vec::new();
    let mut kept = Vec::new();
    let mut kept_bytes = 0;
    for frame in frames {
        let frame = frame?;
        let t = Instant::now();
        map.integrate_frame(&frame, labels, stride)?;
        update_ms.push(t.elapsed().as_secs_f64() * 1e3);
        after_update(&frame, map)?;
        let bytes = frame.depth.len() * 4 + frame.labels.as_ref().map_or(0, Vec::len);
        kept.push(match frame {
            Cow::Borrowed(f) => Kept::Frame(Cow::Borrowed(f)),
            Cow::Owned(f) if reload.is_some() && kept_bytes + bytes > keep_bytes => {
                Kept::Reload(f.id)
            }
            Cow::Owned(f) => {
                kept_bytes += bytes;
                Kept::Frame(Cow::Owned(Frame {
                    predictions: None,
                    ..f
                }))
            }
        });
    }
    let mut confusions = Vec::with_capacity(readouts.len());
    for &readout in readouts {
        let view = map.prepare(readout);
        let mut confusion = Confusion::default();
        for k in &kept {
            let frame = match (k, reload) {
                (Kept::Frame(f), _) => Cow::Borrowed(f.as_ref()),
                (Kept::Reload(id), Some(load)) => Cow::Owned(load(id)?),
                (Kept::Reload(id), None) => bail!("{id}: not kept and no way to read it again"),
            };
            let rendered = view.render_frame(&frame)?;
            if let Some(gt) = &frame.labels {
                confusion.add_frame(gt, &rendered, &gt_depth(&frame));
            }
            after_render(&frame, &rendered)?;
        }
        confusions.push(confusion);
    }
    Ok(MapScore {
        update_ms,
        confusions,
    })
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
        .map_err(|e| anyhow!("config: {e}"))?;
    let trajectories = dataset.trajectories();
    let single = trajectories.len() == 1;
    let parts: Vec<Result<TrajectoryEvaluation>> = trajectories
        .par_iter()
        .map(|(name, ids)| {
            let bag = match &options.mcap {
                Some(path) => Some(MapBag::create(
                    &bag_path(path, name, single),
                    &options.mcap_world,
                    Time::default(),
                )?),
                None => None,
            };
            evaluate_trajectory(dataset, (name, ids), options, bag, progress)
        })
        .collect();
    let mut eval = Evaluation {
        confusion: Confusion::default(),
        trajectories: Vec::new(),
        input: Confusion::default(),
        kept: Vec::new(),
        maps: Vec::new(),
    };
    let mut last_skipped = None;
    for part in parts {
        let part = part?;
        eval.confusion.merge(&part.confusion);
        eval.input.merge(&part.input);
        eval.trajectories.push(part.result);
        eval.kept.extend(part.kept);
        eval.maps.extend(part.map);
        last_skipped = part.skipped.or(last_skipped);
    }
    if eval.frames() == 0 {
        match last_skipped {
            Some(why) => bail!(
                "nothing mapped: all {} frames were skipped (the last: {why})",
                eval.skipped()
            ),
            None => bail!("nothing mapped: {} has no frames", dataset.describe()),
        }
    }
    Ok(eval)
}

/// One trajectory's share of an [`Evaluation`].
struct TrajectoryEvaluation {
    confusion: Confusion,
    input: Confusion,
    result: TrajectoryResult,
    kept: Vec<(FrameId, Vec<u8>)>,
    map: Option<Box<HostMap>>,
    /// Why the last skipped frame was skipped, if any was.
    skipped: Option<String>,
}

/// One trajectory through [`map_and_score`] with an S-NDT map: frames loaded one at a
/// time ([`usable_frames`]: bad ones skipped with a warning), the input labels scored as
/// they are mapped, back-projections written and kept as `options` asks, the final map
/// saved and kept as asked.
fn evaluate_trajectory(
    dataset: &dyn Dataset,
    (name, ids): (&str, &[FrameId]),
    options: &EvalOptions,
    mut bag: Option<MapBag>,
    progress: &(dyn Fn() + Sync),
) -> Result<TrajectoryEvaluation> {
    if let Some((capacity, readout)) = options.device {
        if bag.is_some() || options.keep_maps {
            bail!("--device maps cannot be written as bags or kept (use --save-maps)");
        }
        return crate::with_device!(capacity, M => {
            evaluate_spilling::<M>(dataset, (name, ids), options, readout, progress)
        });
    }
    let mut map: Box<HostMap> = boxed_map(options.config).map_err(|e| anyhow!("config: {e}"))?;
    let mut input = Confusion::default();
    let mut kept = Vec::new();
    let mut skipped = Vec::new();
    // The map after the last frame mapped, when the bag does not have it yet.
    let mut unwritten = None;
    let frames = usable_frames(dataset, ids, options.config.cell_size, &mut skipped);
    let reload = |id: &FrameId| dataset.load(id);
    let score = map_and_score(
        map.as_mut(),
        lazy_frames(frames, &reload),
        options.labels,
        options.stride,
        &[()],
        |frame, map| {
            score_input(&mut input, frame, options.labels);
            if let Some(b) = bag.as_mut() {
                unwritten = write_growing(b, dataset, ids, frame, map, options.mcap_interval)?;
            }
            progress();
            Ok(())
        },
        |frame, rendered| {
            if let Some(out) = &options.out {
                write_backprojection(out, frame, rendered)?;
            }
            if options.keep_frames.contains(&frame.id) {
                kept.push((frame.id.clone(), rendered.to_vec()));
            }
            progress();
            Ok(())
        },
    )?;
    if let Some(mut b) = bag {
        if let Some(stamp) = unwritten {
            b.write(map.as_ref(), stamp)?;
        }
        b.finish()?;
    }
    if let Some(dir) = &options.save_maps {
        save_snapshot(
            map.as_ref(),
            &dir.join(format!("{}.sndt", name.replace('/', "_"))),
        )?;
    }
    let stats = map.stats();
    Ok(TrajectoryEvaluation {
        confusion: score.confusions.into_iter().next().unwrap_or_default(),
        input,
        result: TrajectoryResult {
            name: name.to_string(),
            frames: score.update_ms.len(),
            skipped: skipped.len(),
            update_ms: score.update_ms,
            voxels: map.len(),
            blocks: map.block_count(),
            evicted: stats.voxels_evicted,
            spill: None,
        },
        kept,
        map: options.keep_maps.then_some(map),
        skipped: skipped.pop().map(|bad| bad.why),
    })
}

/// [`evaluate_trajectory`] with a device map spilling into a global map: the frames go into
/// the device map, what it evicts into the global map; `readout` says which map is scored.
/// `save_maps` writes the merged global map.
fn evaluate_spilling<M: SpillingDevice>(
    dataset: &dyn Dataset,
    (name, ids): (&str, &[FrameId]),
    options: &EvalOptions,
    readout: Spill,
    progress: &(dyn Fn() + Sync),
) -> Result<TrajectoryEvaluation> {
    let mut map = M::create(options.config)?;
    let other_readout = match readout {
        Spill::Merged => Spill::DeviceOnly,
        Spill::DeviceOnly => Spill::Merged,
    };
    let mut input = Confusion::default();
    let mut kept = Vec::new();
    let mut skipped = Vec::new();
    let mapped = std::cell::Cell::new(0usize);
    let mut renders = 0usize;
    let frames = usable_frames(dataset, ids, options.config.cell_size, &mut skipped);
    let reload = |id: &FrameId| dataset.load(id);
    let score = map_and_score(
        &mut map,
        lazy_frames(frames, &reload),
        options.labels,
        options.stride,
        &[readout, other_readout],
        |frame, _| {
            score_input(&mut input, frame, options.labels);
            mapped.set(mapped.get() + 1);
            progress();
            Ok(())
        },
        |frame, rendered| {
            // The first read-out is the one asked for; the second is only scored.
            if renders < mapped.get() {
                if let Some(out) = &options.out {
                    write_backprojection(out, frame, rendered)?;
                }
                if options.keep_frames.contains(&frame.id) {
                    kept.push((frame.id.clone(), rendered.to_vec()));
                }
                progress();
            }
            renders += 1;
            Ok(())
        },
    )?;
    let final_bytes = map.final_bytes();
    let merged = map.merged_map()?;
    if let Some(dir) = &options.save_maps {
        let path = dir.join(format!("{}.sndt", name.replace('/', "_")));
        crate::atomic::write_bytes(&path, merged.snapshot()?)?;
    }
    let (device_voxels, device_blocks, evicted) = map.device_counts();
    let (voxels, blocks) = match readout {
        Spill::Merged => (merged.len(), merged.block_count()),
        Spill::DeviceOnly => (device_voxels, device_blocks),
    };
    let mut confusions = score.confusions.into_iter();
    let confusion = confusions.next().unwrap_or_default();
    let other = confusions.next().unwrap_or_default().metrics();
    let spill = spill_summary(&map, merged, final_bytes, &other);
    Ok(TrajectoryEvaluation {
        confusion,
        input,
        result: TrajectoryResult {
            name: name.to_string(),
            frames: score.update_ms.len(),
            skipped: skipped.len(),
            update_ms: score.update_ms,
            voxels,
            blocks,
            evicted,
            spill: Some(spill),
        },
        kept,
        map: None,
        skipped: skipped.pop().map(|bad| bad.why),
    })
}

/// The spill figures of a finished [`evaluate_spilling`] run.
fn spill_summary<M: SpillingDevice>(
    map: &M,
    merged: &GlobalMap,
    final_bytes: u64,
    other: &crate::eval::metrics::Metrics,
) -> SpillSummary {
    let (device_voxels, device_blocks, _) = map.device_counts();
    let mut stats = map.spill_stats().clone();
    stats.final_bytes += final_bytes;
    SpillSummary {
        device: M::CAPACITY,
        other: (other.miou, other.invr, other.mpacc),
        stats,
        global_tier: merged.tier(),
        global_bytes: merged.memory_bytes(),
        device_voxels,
        device_blocks,
    }
}

/// What [`evaluate_spilling`] needs of a [`SpillingMap`] of any device capacity.
trait SpillingDevice: SemanticMap<Readout = Spill> + Sized {
    const CAPACITY: (usize, usize);
    fn create(config: Config) -> Result<Self>;
    fn final_bytes(&mut self) -> u64;
    fn merged_map(&self) -> Result<&GlobalMap>;
    fn device_counts(&self) -> (usize, usize, u64);
    fn spill_stats(&self) -> &SpillStats;
}

impl<const V: usize, const B: usize> SpillingDevice for SpillingMap<V, B> {
    const CAPACITY: (usize, usize) = (V, B);
    fn create(config: Config) -> Result<Self> {
        SpillingMap::new(config)
    }
    fn final_bytes(&mut self) -> u64 {
        self.final_stream_bytes()
    }
    fn merged_map(&self) -> Result<&GlobalMap> {
        self.merged()
    }
    fn device_counts(&self) -> (usize, usize, u64) {
        let d = self.device();
        (d.len(), d.block_count(), d.stats().voxels_evicted)
    }
    fn spill_stats(&self) -> &SpillStats {
        &self.stats
    }
}

/// Scores the labels `source` feeds the map against the frame's ground truth, on the
/// frame itself (the network alone, without mapping, for predictions).
fn score_input(input: &mut Confusion, frame: &Frame, source: LabelSource) {
    if let Some(gt) = &frame.labels {
        let given: Vec<u8> = (0..frame.pixels())
            .map(|i| frame.point_labels(i, source).classes[0])
            .collect();
        input.add_frame(gt, &given, &gt_depth(frame));
    }
}

/// Writes a back-projection as a plain 8-bit PNG at `<out>/<scene>/<cam>/<NNNN>.png`, the
/// layout of the authors' evaluate.py.
fn write_backprojection(out: &Path, frame: &Frame, labels: &[u8]) -> Result<()> {
    let path = out
        .join(&frame.id.scene)
        .join(&frame.id.cam)
        .join(format!("{}.png", frame.id.stem()));
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    crate::dataset::prepared::write_gray8(&path, frame.rays.width(), frame.rays.height(), labels)
}

/// Writes a map snapshot file.
pub fn save_snapshot<const V: usize, const B: usize, const C: usize>(
    map: &Map<V, B, C>,
    path: &std::path::Path,
) -> Result<()> {
    let mut buf = vec![0u8; map.snapshot_len()];
    let n = map
        .write_snapshot(&mut buf)
        .map_err(|e| anyhow!("{}: snapshot: {e}", path.display()))?;
    // Atomically: a crash or kill while saving leaves the previous map file intact.
    crate::atomic::write_bytes(path, &buf[..n])
}

/// Reads a map snapshot file into a heap map of the evaluation's capacity. The error says
/// what is wrong; for a stored config out of its range, which field.
pub fn load_snapshot(path: &std::path::Path) -> Result<Box<HostMap>> {
    let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    let mut map: Box<HostMap> = boxed_map(Config::DEFAULT).map_err(|e| anyhow!("{e}"))?;
    map.read_snapshot(&bytes).map_err(|e| {
        let stored = SnapshotHeader::read(&bytes).map(|h| h.config.validate());
        let why = match (e, stored) {
            (sndt_core::Error::SnapshotCorrupt, Ok(Err(bad))) => {
                format!("its stored config is refused: {bad}")
            }
            _ => e.to_string(),
        };
        anyhow!("{}: not a readable sndt snapshot: {why}", path.display())
    })?;
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

/// Writes `map` into `bag` after `frame` when it is every `every`-th frame of `ids`,
/// stamped with the frame's recording time (10 Hz from 1 s when unknown). Returns that
/// stamp when the map was not written: the caller writes the map after the last frame
/// mapped at its stamp (frames may be skipped, so the last of `ids` may never come).
fn write_growing(
    bag: &mut MapBag,
    dataset: &dyn Dataset,
    ids: &[FrameId],
    frame: &Frame,
    map: &HostMap,
    every: Option<usize>,
) -> Result<Option<Time>> {
    let k = ids.iter().position(|id| *id == frame.id).unwrap_or(0);
    let stamp = dataset
        .stamp(&frame.id)
        .map_or(frame_time(k), Time::from_nanos);
    if every.is_some_and(|n| n > 0 && (k + 1) % n == 0) {
        bag.write(map, stamp)?;
        return Ok(None);
    }
    Ok(Some(stamp))
}

/// The bag of trajectory `name`: `path` itself when it is the only one, else
/// `<stem>_<scene>_<cam>.mcap` beside it (for a bag folder `path`, the folder
/// `<dir>_<scene>_<cam>/`).
pub fn bag_path(path: &Path, name: &str, single: bool) -> PathBuf {
    if single {
        return path.to_path_buf();
    }
    crate::output::ros::write::sibling_bag(path, name, "map")
}
