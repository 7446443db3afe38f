//! The dynamics report: how fast a map forgets an object that left and relabels one that
//! took its place, and what the static scene loses meanwhile (`sndt dynamics`,
//! docs/DYNAMICS.md).
//!
//! The scene is the [`dynamic`](crate::dataset::synthetic::dynamic) room. Each map runs
//! twice over the same camera walk: on the dynamic scene, and on its frozen twin where
//! every object stays where it stood at frame 0. After every frame the report reads the
//! map's occupancy at a fixed list of voxels (per cell size): each event's *former
//! surface* (voxels the object's old shapes pass through, less those that a shape standing
//! at the end passes through) and the *static surface* (voxels the room's static shapes
//! pass through, less any voxel a moving object ever touches). OctoMap, run by
//! `scripts/octomap/octomap_dynamics.cpp` on the same world points, gives the same reading,
//! so both are measured by one definition:
//!
//! - **ghost** at frame `t`: of the former-surface voxels the map held occupied at some
//!   frame from just before the first change until just before the object left (frame
//!   `vacated - 1`), the share still occupied after frame `t`;
//! - **frames to clear**: from the first frame at or after `vacated` whose camera sees
//!   through the vacated space (a former-surface voxel projects in front of the measured
//!   depth), the frames until the ghost is at most 5 % (1: cleared by that frame itself);
//! - **frames to relabel** (S-NDT only, OctoMap has no classes): from the first frame that
//!   shows the new object (at least [`MIN_VISIBLE`] of the pixels), the frames until at
//!   least 95 % of its pixels render with its class. Beside it, the same figure for a
//!   twin of the map started afresh at that frame (*fresh*): it never saw the old object,
//!   so it relabels as fast as the view and the cell size allow, and the difference is
//!   what the map's memory of the old object costs;
//! - **static loss**: static-surface voxels occupied at the end of the frozen run but not
//!   at the end of the dynamic one, as a share of those occupied in the frozen run; per
//!   event, counted within 0.3 m of the event's region;
//! - **the paper's metrics** of the final map rendered into every frame, on the dynamic
//!   walk (against each frame's own ground truth) and on the frozen walk.

pub mod octomap;
pub mod surface;

use crate::dataset::frame::{Frame, LabelSource};
use crate::dataset::synthetic::dynamic::{DynamicScene, Event};
use crate::dataset::synthetic::{DynamicOptions, SynthOptions, Synthetic};
use crate::dataset::Dataset;
use crate::eval::evaluate::gt_depth;
use crate::eval::metrics::{Confusion, Metrics};
use crate::mapping::{backproject, boxed_map, integrate_frame, HostMap};
use crate::output::points::PointsWriter;
use anyhow::{anyhow, bail, Context, Result};
use sndt_core::{Config, Point3, VoxelKey};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// Ghost share at or below which an object counts as cleared.
pub const CLEARED: f64 = 0.05;
/// Share of the new object's pixels that must render with its class.
pub const RELABELLED: f64 = 0.95;
/// Share of the image a new object must cover to count as shown.
pub const MIN_VISIBLE: f64 = 1e-3;
/// Static voxels this far (metres) around an event's region count for its static loss.
pub const REGION_MARGIN: f32 = 0.3;

/// One S-NDT map of the report: a name and its configuration (cell size included).
#[derive(Clone, Debug)]
pub struct Mapper {
    /// Shown in the tables, e.g. `sndt`.
    pub name: String,
    /// Its configuration.
    pub config: Config,
}

/// What to run.
#[derive(Clone, Debug)]
pub struct DynamicsOptions {
    /// The S-NDT maps.
    pub mappers: Vec<Mapper>,
    /// Labels fed to them.
    pub labels: LabelSource,
    /// The `octomap_dynamics` program: OctoMap runs at every cell size of `mappers` too.
    pub octomap: Option<PathBuf>,
    /// Where OctoMap's input and output files go.
    pub work: PathBuf,
}

/// One event as one map saw it.
#[derive(Clone, Debug, PartialEq)]
pub struct EventResult {
    /// The event's name.
    pub name: String,
    /// Former-surface voxels occupied at some frame from just before the change until
    /// just before the object left (the ghost's 100 %).
    pub former: usize,
    /// The ghost share after each frame (relative to `former`; 0 when `former` is 0).
    pub ghost: Vec<f64>,
    /// The first frame that sees through the vacated space.
    pub seen_through: Option<u32>,
    /// Frames to clear, counted from `seen_through`; `None`: not within the walk.
    pub frames_to_clear: Option<u32>,
    /// The share of the new object's pixels rendered with its class after each frame
    /// (`None` before it is shown, and for maps without classes).
    pub relabelled: Vec<Option<f64>>,
    /// Frames to relabel, counted from the first frame that shows the new object;
    /// `None`: no new object, a map without classes, or not within the walk.
    pub frames_to_relabel: Option<u32>,
    /// The same for a twin of the map started afresh at the event's first frame, which
    /// never saw the old object; `None` as above, and for events whose first frame is not
    /// the twin's (the twin starts at the earliest first frame of the events with a new
    /// object).
    pub fresh_frames_to_relabel: Option<u32>,
    /// Static voxels near the event occupied at the end of the frozen run.
    pub static_voxels: usize,
    /// Of those, free or unknown at the end of the dynamic run.
    pub static_lost: usize,
}

/// One map's results.
#[derive(Clone, Debug, PartialEq)]
pub struct MapperResult {
    /// `sndt`, `octomap`, ...
    pub name: String,
    /// Cell size, metres.
    pub cell: f32,
    /// Per event, in the scene's order.
    pub events: Vec<EventResult>,
    /// Static voxels occupied at the end of the frozen run.
    pub static_voxels: usize,
    /// Of those, free or unknown at the end of the dynamic run.
    pub static_lost: usize,
    /// Of the lost ones, those where the surface lies on a voxel face and the voxel on
    /// its other side, also static surface, is occupied at the end of the dynamic run:
    /// the map still holds that part of the surface, one voxel over.
    pub static_held_across: usize,
    /// The paper's metrics (S-NDT only).
    pub metrics: Option<PaperMetrics>,
}

/// The paper's metrics of a map's final state rendered into the frames of a walk.
#[derive(Clone, Debug, PartialEq)]
pub struct PaperMetrics {
    /// Every frame of the dynamic walk, each against its own ground truth.
    pub dynamic: Metrics,
    /// The frames of the dynamic walk from the last object's leaving on, when the scene
    /// no longer changes: a map that forgets and relabels at once scores here what the
    /// frozen map scores on its walk.
    pub settled: Metrics,
    /// Every frame of the frozen walk, rendered from the frozen run's map.
    pub frozen: Metrics,
}

/// The whole report.
#[derive(Clone, Debug)]
pub struct DynamicsReport {
    /// Frames of the walk.
    pub frames: usize,
    /// The events, as the scene defines them.
    pub events: Vec<Event>,
    /// Every map, S-NDT maps first, then OctoMap per cell size.
    pub mappers: Vec<MapperResult>,
}

/// The voxels watched at one cell size.
struct Watch {
    cell: f32,
    keys: Vec<VoxelKey>,
    /// Per event, indices into `keys` of its former surface.
    former: Vec<Vec<usize>>,
    /// Indices into `keys` of the static surface.
    statics: Vec<usize>,
    /// Per event, the static indices near it.
    near: Vec<Vec<usize>>,
    /// Per index into `keys`: the static voxels across a voxel face the static surface
    /// lies on (see [`surface::face_pairs`]).
    across: Vec<Vec<usize>>,
}

impl Watch {
    fn new(scene: &DynamicScene, cell: f32) -> Watch {
        let last = scene.frames.saturating_sub(1) as u32;
        let standing = surface::surface_voxels(&scene.primitives_at(last), cell);
        let moving = surface::surface_voxels(&scene.moving_primitives(), cell);
        let base = scene.base.primitives();
        let statics: BTreeSet<VoxelKey> = surface::surface_voxels(&base, cell)
            .difference(&moving)
            .copied()
            .collect();
        let formers: Vec<BTreeSet<VoxelKey>> = scene
            .events
            .iter()
            .map(|e| {
                let old = surface::surface_voxels(&e.old, cell);
                old.difference(&standing).copied().collect()
            })
            .collect();
        let mut keys: BTreeSet<VoxelKey> = statics.clone();
        formers.iter().for_each(|f| keys.extend(f));
        let keys: Vec<VoxelKey> = keys.into_iter().collect();
        let index = |k: &VoxelKey| keys.binary_search(k).unwrap_or(0);
        let statics: Vec<usize> = statics.iter().map(index).collect();
        let near = scene
            .events
            .iter()
            .map(|e| {
                let inside = |&&i: &&usize| e.region.contains(&keys[i].center(cell), REGION_MARGIN);
                statics.iter().filter(inside).copied().collect()
            })
            .collect();
        let former = formers
            .iter()
            .map(|f| f.iter().map(index).collect())
            .collect();
        let mut across = vec![Vec::new(); keys.len()];
        for (a, b) in surface::face_pairs(&base, cell) {
            if let (Ok(i), Ok(j)) = (keys.binary_search(&a), keys.binary_search(&b)) {
                across[i].push(j);
                across[j].push(i);
            }
        }
        Watch {
            cell,
            keys,
            former,
            statics,
            near,
            across,
        }
    }

    /// Static voxels occupied in `frozen` and not in `dynamic` (readings of `keys`) whose
    /// partner across a voxel face the static surface lies on is occupied in `dynamic`.
    fn held_across(&self, frozen: &[bool], dynamic: &[bool]) -> usize {
        let lost = |&i: &usize| frozen[i] && !dynamic[i];
        let statics = self.statics.iter().copied().filter(lost);
        statics
            .filter(|&i| self.across[i].iter().any(|&j| dynamic[j]))
            .count()
    }

    /// Which watched voxels `map` holds occupied.
    fn read(&self, map: &HostMap) -> Vec<bool> {
        self.keys.iter().map(|k| map.log_odds(k) > 0.0).collect()
    }

    /// Whether `frame`'s camera sees through a voxel of event `e`'s former surface: one
    /// projects into the image in front of the measured depth (by more than a cell).
    fn sees_through(&self, e: usize, frame: &Frame) -> bool {
        let crate::dataset::frame::Rays::Pinhole(cam) = frame.rays.as_ref() else {
            return false;
        };
        let to_camera = frame.pose.inverse();
        self.former[e].iter().any(|&i| {
            let c = self.keys[i].center(self.cell);
            let p = to_camera * Point3::new(c[0], c[1], c[2]);
            if p.z <= 0.0 {
                return false;
            }
            let (u, v) = (cam.fx * p.x / p.z + cam.cx, cam.fy * p.y / p.z + cam.cy);
            if u < 0.0 || v < 0.0 || u >= cam.width as f32 || v >= cam.height as f32 {
                return false;
            }
            let depth = frame.depth[v as usize * cam.width as usize + u as usize];
            depth.is_finite() && depth > p.z + self.cell
        })
    }
}

/// One map's reading over a walk.
#[derive(Default)]
struct Run {
    /// Occupancy of the watched voxels after each frame.
    trace: Vec<Vec<bool>>,
    /// Per event, the new object's relabelled share after each frame.
    relabelled: Vec<Vec<Option<f64>>>,
    /// The final map scored on every frame.
    confusion: Confusion,
    /// ... and on the frames from the last object's leaving on.
    settled: Confusion,
}

/// Maps the walk of `split` with every mapper at once (each frame rendered once), reading
/// the watched voxels after every frame; with `events`, also the new objects' relabelled
/// share and which frames see through each event's vacated space (per watch). Writes the
/// world points to `points` for OctoMap. A map with a restart frame is emptied before
/// that frame and gives no final metrics (a fresh twin, see [`EventResult`]).
fn run_walk(
    split: &Synthetic,
    maps: &mut [(Box<HostMap>, &Watch, Option<u32>)],
    labels: LabelSource,
    events: &[Event],
    mut points: Option<&mut PointsWriter>,
    seen: &mut [Vec<Vec<bool>>],
    progress: &(dyn Fn() + Sync),
) -> Result<Vec<Run>> {
    let mut runs: Vec<Run> = maps.iter().map(|_| Run::default()).collect();
    let mut kept = Vec::with_capacity(split.frames().len());
    for id in split.frames() {
        let (frame, instances) = split.render_frame(id)?;
        if let Some(w) = points.as_deref_mut() {
            w.add_frame(&frame)?;
        }
        for (watch_seen, (_, watch, _)) in seen.iter_mut().zip(maps.iter()) {
            let row = (0..events.len())
                .map(|e| id.index >= events[e].vacated && watch.sees_through(e, &frame))
                .collect();
            watch_seen.push(row);
        }
        for ((map, watch, restart), run) in maps.iter_mut().zip(&mut runs) {
            if *restart == Some(id.index) {
                let config = *map.config();
                map.reset(config).map_err(|e| anyhow!("fresh twin: {e}"))?;
            }
            integrate_frame(map, &frame, labels, 1)?;
            run.trace.push(watch.read(map));
            let shown = events
                .iter()
                .any(|e| e.new.is_some() && id.index >= e.first);
            let render = if shown && labels != LabelSource::None {
                Some(backproject(map, &frame)?)
            } else {
                None
            };
            run.relabelled.resize(events.len(), Vec::new());
            for (e, share) in events.iter().zip(&mut run.relabelled) {
                share.push(match (&render, e.new) {
                    (Some(r), Some((instance, class))) if id.index >= e.first => {
                        relabelled_share(r, &instances, instance, class)
                    }
                    _ => None,
                });
            }
        }
        kept.push(Frame {
            predictions: None,
            ..frame
        });
        progress();
    }
    let settle = events.iter().map(|e| e.vacated).max().unwrap_or(0);
    let scored = maps
        .iter()
        .zip(&mut runs)
        .filter(|((_, _, r), _)| r.is_none());
    for ((map, _, _), run) in scored {
        for frame in &kept {
            if let Some(gt) = &frame.labels {
                let mut one = Confusion::default();
                one.add_frame(gt, &backproject(map, frame)?, &gt_depth(frame));
                run.confusion.merge(&one);
                if frame.id.index >= settle {
                    run.settled.merge(&one);
                }
            }
        }
    }
    Ok(runs)
}

/// The share of `instance`'s pixels that `render` gives class `class`; `None` when it
/// covers less than [`MIN_VISIBLE`] of the image.
fn relabelled_share(render: &[u8], instances: &[u16], instance: u16, class: u8) -> Option<f64> {
    let (mut shown, mut right) = (0usize, 0usize);
    for (&r, &i) in render.iter().zip(instances) {
        if i == instance {
            shown += 1;
            right += usize::from(r == class);
        }
    }
    (shown as f64 >= MIN_VISIBLE * instances.len() as f64).then(|| right as f64 / shown as f64)
}

/// One walk mapped by every map: their readings, which frames see through each event's
/// vacated space (per map), and the world points written for OctoMap.
struct Walked {
    runs: Vec<Run>,
    seen: Vec<Vec<Vec<bool>>>,
    points: Option<PathBuf>,
}

/// Runs the report on the dynamic walk `split` (a [`Synthetic`] of the dynamic room or of
/// the floor walk with people).
pub fn run(
    split: &Synthetic,
    options: &DynamicsOptions,
    progress: &(dyn Fn() + Sync),
) -> Result<DynamicsReport> {
    let Some(scene) = split.dynamic_scene() else {
        bail!(
            "the dynamics report needs a dynamic walk (synthetic:dynamic[:FRAMES[:CHANGE]] or \
             synthetic:floor-people[:WALK[:FRAMES]])"
        );
    };
    if scene.frozen {
        bail!("the dynamics report needs the dynamic walk, not its frozen twin");
    }
    if options.mappers.is_empty() {
        bail!("the dynamics report needs at least one map to run");
    }
    for m in &options.mappers {
        m.config
            .validate()
            .map_err(|e| anyhow!("{}: config: {e}", m.name))?;
    }
    let frozen = Synthetic::new(SynthOptions {
        dynamic: split
            .options()
            .dynamic
            .map(|d| DynamicOptions { frozen: true, ..d }),
        ..split.options().clone()
    })?;
    let mut cells: Vec<f32> = options.mappers.iter().map(|m| m.config.cell_size).collect();
    cells.sort_by(f32::total_cmp);
    cells.dedup();
    let watches: Vec<Watch> = cells.iter().map(|&c| Watch::new(scene, c)).collect();
    let watch_of = |cell: f32| &watches[cells.iter().position(|&c| c == cell).unwrap_or(0)];
    let dynamic = walk_all(split, "dynamic", scene, options, &watch_of, progress)?;
    let still = walk_all(&frozen, "frozen", scene, options, &watch_of, progress)?;
    let mut mappers = Vec::new();
    for (i, m) in options.mappers.iter().enumerate() {
        let (d, f) = (&dynamic.runs[i], &still.runs[i]);
        let traces = (&d.trace[..], &f.trace[..]);
        let watch = watch_of(m.config.cell_size);
        let twin = dynamic.runs.get(i + options.mappers.len());
        let relabelled = Relabelled {
            map: &d.relabelled,
            fresh: twin.map(|t| &t.relabelled[..]),
            fresh_start: fresh_start(&scene.events),
        };
        let mut result = score(
            &m.name,
            watch,
            &scene.events,
            traces,
            &dynamic.seen[i],
            Some(relabelled),
        );
        result.metrics = Some(PaperMetrics {
            dynamic: d.confusion.metrics(),
            settled: d.settled.metrics(),
            frozen: f.confusion.metrics(),
        });
        mappers.push(result);
    }
    if let Some(tool) = &options.octomap {
        for watch in &watches {
            mappers.push(octomap_result(
                tool,
                watch,
                scene,
                options,
                (&dynamic, &still),
            )?);
        }
    }
    Ok(DynamicsReport {
        frames: split.frames().len(),
        events: scene.events.clone(),
        mappers,
    })
}

/// OctoMap's result at `watch`'s cell size, from the world points both walks wrote.
fn octomap_result(
    tool: &Path,
    watch: &Watch,
    scene: &DynamicScene,
    options: &DynamicsOptions,
    (dynamic, still): (&Walked, &Walked),
) -> Result<MapperResult> {
    let (Some(dyn_points), Some(frozen_points)) = (&dynamic.points, &still.points) else {
        bail!("OctoMap runs on the points both walks wrote");
    };
    let queries = options.work.join(format!("watch-{}.queries", watch.cell));
    octomap::write_queries(&queries, &watch.keys, watch.cell)?;
    let answer = |points: &PathBuf, name: &str| {
        let out = options
            .work
            .join(format!("octomap-{name}-{}.txt", watch.cell));
        octomap::run(tool, points, &queries, watch.cell, &out)
    };
    let (d, f) = (
        answer(dyn_points, "dynamic")?,
        answer(frozen_points, "frozen")?,
    );
    // Which frames see through depends on the camera and the cell, not the map: those of
    // the first S-NDT map at this cell size.
    let i = options
        .mappers
        .iter()
        .position(|m| m.config.cell_size == watch.cell)
        .context("a map at every watched cell size")?;
    Ok(score(
        "octomap",
        watch,
        &scene.events,
        (&d, &f),
        &dynamic.seen[i],
        None,
    ))
}

/// Maps walk `walk` (named `name`: `dynamic` or `frozen`) with a fresh map per mapper,
/// writing its world points for OctoMap when OctoMap runs.
fn walk_all<'w>(
    walk: &Synthetic,
    name: &str,
    scene: &DynamicScene,
    options: &DynamicsOptions,
    watch_of: &dyn Fn(f32) -> &'w Watch,
    progress: &(dyn Fn() + Sync),
) -> Result<Walked> {
    // On the dynamic walk, each map's fresh twin follows the maps (see `EventResult`).
    let fresh = fresh_start(&scene.events).filter(|_| name == "dynamic");
    let restarts = std::iter::repeat_n(None, options.mappers.len()).chain(
        fresh
            .map(|f| vec![Some(f); options.mappers.len()])
            .unwrap_or_default(),
    );
    let mut maps = options
        .mappers
        .iter()
        .cycle()
        .zip(restarts)
        .map(|(m, restart)| {
            let map = boxed_map(m.config).map_err(|e| anyhow!("{}: {e}", m.name))?;
            Ok((map, watch_of(m.config.cell_size), restart))
        })
        .collect::<Result<Vec<_>>>()?;
    let points = options
        .octomap
        .as_ref()
        .map(|_| options.work.join(format!("{name}.points")));
    let mut writer = match &points {
        Some(path) => Some(PointsWriter::create(path, walk.frames().len())?),
        None => None,
    };
    let mut seen = vec![Vec::new(); maps.len()];
    let runs = run_walk(
        walk,
        &mut maps,
        options.labels,
        &scene.events,
        writer.as_mut(),
        &mut seen,
        progress,
    )?;
    if let Some(w) = writer {
        w.finish()?;
    }
    Ok(Walked { runs, seen, points })
}

/// The first frame of the events with a new object: where the fresh twins start.
fn fresh_start(events: &[Event]) -> Option<u32> {
    events
        .iter()
        .filter(|e| e.new.is_some())
        .map(|e| e.first)
        .min()
}

/// Per event, a map's relabelled share after each frame, and its fresh twin's.
#[derive(Clone, Copy)]
struct Relabelled<'a> {
    map: &'a [Vec<Option<f64>>],
    fresh: Option<&'a [Vec<Option<f64>>]>,
    /// The frame the twin started afresh at.
    fresh_start: Option<u32>,
}

/// Frames to relabel from per-frame shares: from the first frame with a share until one
/// is at least [`RELABELLED`] (1: that frame itself).
fn relabel_count(shares: &[Option<f64>]) -> Option<u32> {
    let shown = shares.iter().position(Option::is_some)?;
    let mut after = shares.iter().enumerate().skip(shown);
    let done = after.find(|(_, r)| r.is_some_and(|r| r >= RELABELLED));
    done.map(|(t, _)| (t - shown + 1) as u32)
}

/// One map's results from its traces on the dynamic and the frozen walk.
fn score(
    name: &str,
    watch: &Watch,
    events: &[Event],
    (dynamic, frozen): (&[Vec<bool>], &[Vec<bool>]),
    seen: &[Vec<bool>],
    relabelled: Option<Relabelled>,
) -> MapperResult {
    let end = |t: &[Vec<bool>]| t.last().cloned().unwrap_or_default();
    let (dyn_end, frozen_end) = (end(dynamic), end(frozen));
    let lost = |idx: &[usize]| {
        let kept: Vec<usize> = idx.iter().copied().filter(|&i| frozen_end[i]).collect();
        let lost = kept.iter().filter(|&&i| !dyn_end[i]).count();
        (kept.len(), lost)
    };
    let (static_voxels, static_lost) = lost(&watch.statics);
    let static_held_across = watch.held_across(&frozen_end, &dyn_end);
    let events = events
        .iter()
        .enumerate()
        .map(|(e, event)| {
            // Occupied at some frame from just before the first change until just before
            // the object left: what the map held of it.
            let held = (event.first as usize).saturating_sub(1)..event.vacated as usize;
            let rows = dynamic.get(held).unwrap_or(&[]);
            let former: Vec<usize> = watch.former[e]
                .iter()
                .copied()
                .filter(|&i| rows.iter().any(|row| row[i]))
                .collect();
            let ghost: Vec<f64> = dynamic
                .iter()
                .map(|row| match former.len() {
                    0 => 0.0,
                    n => former.iter().filter(|&&i| row[i]).count() as f64 / n as f64,
                })
                .collect();
            let seen_through = seen
                .iter()
                .position(|row| row.get(e).copied().unwrap_or(false))
                .map(|t| t as u32);
            let frames_to_clear = seen_through.and_then(|s| {
                let mut after = ghost.iter().enumerate().skip(s as usize);
                let cleared = after.find(|(_, g)| **g <= CLEARED);
                cleared.map(|(t, _)| t as u32 - s + 1)
            });
            let shares = relabelled
                .and_then(|r| r.map.get(e))
                .cloned()
                .unwrap_or_else(|| vec![None; dynamic.len()]);
            let frames_to_relabel = relabel_count(&shares);
            let fresh_frames_to_relabel = relabelled
                .filter(|r| r.fresh_start == Some(event.first))
                .and_then(|r| r.fresh?.get(e).map(|f| relabel_count(f)))
                .flatten();
            let (near, near_lost) = lost(&watch.near[e]);
            EventResult {
                name: event.name.to_string(),
                former: former.len(),
                ghost,
                seen_through,
                frames_to_clear,
                relabelled: shares,
                frames_to_relabel,
                fresh_frames_to_relabel,
                static_voxels: near,
                static_lost: near_lost,
            }
        })
        .collect();
    MapperResult {
        name: name.to_string(),
        cell: watch.cell,
        events,
        static_voxels,
        static_lost,
        static_held_across,
        metrics: None,
    }
}

impl DynamicsReport {
    /// The per-event table (Markdown): frames to clear, frames to relabel and static loss
    /// for every map.
    pub fn table(&self) -> String {
        let mut s = String::new();
        let frames = |f: Option<u32>, applies: bool| match (f, applies) {
            (_, false) => "-".to_string(),
            (Some(f), true) => f.to_string(),
            (None, true) => format!("> {}", self.frames),
        };
        // The fresh twin's figure in brackets, where it has one.
        let relabel_frames = |r: &EventResult, applies: bool| match r.fresh_frames_to_relabel {
            Some(fresh) if applies => format!("{} ({fresh})", frames(r.frames_to_relabel, true)),
            _ => frames(r.frames_to_relabel, applies),
        };
        for (e, event) in self.events.iter().enumerate() {
            s += &format!(
                "\n### {} (vacated at frame {})\n\n",
                event.name, event.vacated
            );
            s += "| map | cell | former voxels | seen through at | frames to clear | frames to relabel (fresh) | static loss |\n";
            s += "|---|---:|---:|---:|---:|---:|---:|\n";
            for m in &self.mappers {
                let r = &m.events[e];
                let relabel = event.new.is_some() && m.metrics.is_some();
                s += &format!(
                    "| {} | {:.2} | {} | {} | {} | {} | {} |\n",
                    m.name,
                    m.cell,
                    r.former,
                    r.seen_through.map_or("never".into(), |t| t.to_string()),
                    frames(r.frames_to_clear, r.former > 0),
                    relabel_frames(r, relabel),
                    share(r.static_lost, r.static_voxels),
                );
            }
        }
        s += "\n### Static surface and the paper's metrics\n\n";
        s += "mIoU / invR / mPAcc (%) of the final map rendered into every frame of the dynamic \
              walk, into its frames once nothing moves any more (settled), and of the frozen \
              run's map into the frozen walk.\n\n";
        s += "| map | cell | static loss | held across a face | dynamic | settled | frozen |\n";
        s += "|---|---:|---:|---:|---:|---:|---:|\n";
        for m in &self.mappers {
            let three = |x: &Metrics| {
                format!(
                    "{:.2} / {:.2} / {:.2}",
                    100.0 * x.miou,
                    100.0 * x.invr,
                    100.0 * x.mpacc
                )
            };
            let cols = match &m.metrics {
                Some(p) => [&p.dynamic, &p.settled, &p.frozen].map(three),
                None => std::array::from_fn(|_| "-".to_string()),
            };
            s += &format!(
                "| {} | {:.2} | {} | {} | {} |\n",
                m.name,
                m.cell,
                share(m.static_lost, m.static_voxels),
                m.static_held_across,
                cols.join(" | ")
            );
        }
        s
    }

    /// The report as JSON: per map and event the figures of the table and the ghost and
    /// relabelled share per frame.
    pub fn to_json(&self) -> serde_json::Value {
        let metrics =
            |m: &Metrics| serde_json::json!({"miou": m.miou, "invr": m.invr, "mpacc": m.mpacc});
        serde_json::json!({
            "frames": self.frames,
            "events": self.events.iter().map(|e| serde_json::json!({
                "name": e.name, "first": e.first, "vacated": e.vacated,
                "new_class": e.new.map(|n| n.1),
            })).collect::<Vec<_>>(),
            "maps": self.mappers.iter().map(|m| serde_json::json!({
                "name": m.name,
                "cell": m.cell,
                "static_voxels": m.static_voxels,
                "static_lost": m.static_lost,
                "static_held_across": m.static_held_across,
                "dynamic": m.metrics.as_ref().map(|p| metrics(&p.dynamic)),
                "settled": m.metrics.as_ref().map(|p| metrics(&p.settled)),
                "frozen": m.metrics.as_ref().map(|p| metrics(&p.frozen)),
                "events": m.events.iter().map(|r| serde_json::json!({
                    "name": r.name,
                    "former": r.former,
                    "seen_through": r.seen_through,
                    "frames_to_clear": r.frames_to_clear,
                    "frames_to_relabel": r.frames_to_relabel,
                    "fresh_frames_to_relabel": r.fresh_frames_to_relabel,
                    "static_voxels": r.static_voxels,
                    "static_lost": r.static_lost,
                    "ghost": r.ghost,
                    "relabelled": r.relabelled,
                })).collect::<Vec<_>>(),
            })).collect::<Vec<_>>(),
        })
    }
}

/// `lost` of `of` as a percentage with the counts.
fn share(lost: usize, of: usize) -> String {
    match of {
        0 => "- (0 voxels)".into(),
        _ => format!("{:.2} % ({lost}/{of})", 100.0 * lost as f64 / of as f64),
    }
}
