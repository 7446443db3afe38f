//! `sndt.Map`: the core's map behind a lock, fed from numpy arrays with the GIL released.

use crate::args::{self, DepthArray, LabelArray};
use crate::capacity::{self, AnyMap, CLASSES};
use crate::data::PyFrame;
use crate::each_map;
use crate::errors::{core_error, CapacityError, SnapshotError};
use numpy::{PyArray1, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyByteArray, PyBytes, PyDict, PyTuple};
use rayon::prelude::*;
use sndt_core::{
    Depth, DepthImage, DepthKind, FrameReport, LabelImage, Labels, MapStats, Occupancy, Pinhole,
    INVALID_LABEL,
};
use sndt_host::dataset::LabelSource;
use std::path::PathBuf;
use std::sync::{Mutex, MutexGuard};

/// A semantic occupancy-NDT map of fixed capacity (it never grows; when full it evicts
/// the voxels farthest from the sensor, and the frame report counts them).
///
/// ``Map(cell=0.1, classes=40, voxels=None, blocks=None, **config)``: ``cell`` is the
/// voxel edge in metres; ``classes`` the number of classes (40, NYU40: ids 1..=40, 0
/// void); ``voxels`` and ``blocks`` the capacity, one of ``sndt.CAPACITIES`` (default
/// ``sndt.DEFAULT_CAPACITY``, the command line's map: 2^19 voxels, 2^17 blocks, 74 MiB);
/// ``config`` any field of the core's config (``sndt.CONFIG_FIELDS``), with its defaults.
/// The same frames give the same snapshot bytes as ``sndt map``.
///
/// Methods release the GIL while the map works, so maps on several threads run in
/// parallel; calls on one map from several threads take turns.
#[pyclass(module = "sndt", name = "Map", frozen)]
pub struct PyMap {
    map: Mutex<AnyMap>,
}

/// What one integrated frame did: every pixel is counted once in ``points_used``,
/// ``truncated``, ``rejected_*`` or ``dropped_points``.
#[pyclass(module = "sndt", name = "FrameReport", frozen, get_all)]
#[derive(Clone)]
pub struct PyFrameReport {
    /// Points folded into voxel statistics.
    pub points_used: u32,
    /// Points beyond ``max_range``: they only cleared free space up to it.
    pub truncated: u32,
    /// Pixels without a measurement: zero, negative, NaN or inf depth.
    pub rejected_depth: u32,
    /// Points whose labels the map cannot take.
    pub rejected_label: u32,
    /// Points outside the map's key range.
    pub rejected_out_of_range: u32,
    /// Points lost because the map was full and nothing could be evicted.
    pub dropped_points: u32,
    /// Free-space updates lost for the same reason.
    pub dropped_misses: u32,
    /// Unique voxels points ended in (one hit update each).
    pub end_voxels: u32,
    /// Rays cast for free space.
    pub rays: u32,
    /// Surface voxels created.
    pub voxels_created: u32,
    /// Occupancy blocks created.
    pub blocks_created: u32,
    /// Surface voxels evicted to make room.
    pub voxels_evicted: u32,
    /// Occupancy blocks evicted to make room.
    pub blocks_evicted: u32,
    /// Records of evicted voxels and blocks a spill sink took: always 0 here, as a
    /// ``Map`` has no sink (its evictions are counted in ``voxels_evicted`` and
    /// ``blocks_evicted``).
    pub records_spilled: u32,
    /// Records of evicted voxels and blocks a spill sink refused: always 0 here, as a
    /// ``Map`` has no sink.
    pub records_dropped: u32,
}

#[pymethods]
impl PyFrameReport {
    fn __repr__(&self) -> String {
        format!(
            "FrameReport(points_used={}, truncated={}, rejected_depth={}, rejected_label={}, \
             rejected_out_of_range={}, dropped_points={}, voxels_created={}, \
             voxels_evicted={}, blocks_evicted={})",
            self.points_used,
            self.truncated,
            self.rejected_depth,
            self.rejected_label,
            self.rejected_out_of_range,
            self.dropped_points,
            self.voxels_created,
            self.voxels_evicted,
            self.blocks_evicted
        )
    }
}

impl From<FrameReport> for PyFrameReport {
    fn from(report: FrameReport) -> Self {
        // Taken apart field by field (no `..`): a field the core adds fails to compile here
        // until `FrameReport` shows it (python/tests/test_mirrors.py checks the names).
        let FrameReport {
            points_used,
            truncated,
            rejected_depth,
            rejected_label,
            rejected_out_of_range,
            dropped_points,
            dropped_misses,
            end_voxels,
            rays,
            voxels_created,
            blocks_created,
            voxels_evicted,
            blocks_evicted,
            records_spilled,
            records_dropped,
        } = report;
        PyFrameReport {
            points_used,
            truncated,
            rejected_depth,
            rejected_label,
            rejected_out_of_range,
            dropped_points,
            dropped_misses,
            end_voxels,
            rays,
            voxels_created,
            blocks_created,
            voxels_evicted,
            blocks_evicted,
            records_spilled,
            records_dropped,
        }
    }
}

/// The surface voxels of a map as arrays, one row per voxel (``Map.voxels()``).
#[pyclass(module = "sndt", name = "Voxels", frozen, get_all)]
pub struct PyVoxels {
    /// Gaussian means, metres, ``float32`` (N, 3).
    pub means: Py<PyAny>,
    /// Gaussian covariances, square metres, ``float32`` (N, 3, 3).
    pub covariances: Py<PyAny>,
    /// Points behind each Gaussian (after decay), ``uint32`` (N,).
    pub counts: Py<PyAny>,
    /// Most voted class, ``uint8`` (N,): 1..=classes, 0 for a voxel without votes.
    pub classes: Py<PyAny>,
    /// Share of the votes the class got, ``float32`` (N,), 0 without votes.
    pub confidence: Py<PyAny>,
    /// Occupancy probability ``1 / (1 + exp(-log_odds))``, ``float32`` (N,).
    pub occupancy: Py<PyAny>,
    /// Occupancy log-odds, ``float32`` (N,).
    pub log_odds: Py<PyAny>,
}

#[pymethods]
impl PyVoxels {
    fn __len__(&self, py: Python<'_>) -> PyResult<usize> {
        self.counts.bind(py).len()
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        Ok(format!("Voxels({} voxels)", self.__len__(py)?))
    }
}

/// Occupancy codes of ``Map.occupancy``.
pub const UNKNOWN: u8 = 0;
/// Log-odds below 0.
pub const FREE: u8 = 1;
/// Log-odds above 0.
pub const OCCUPIED: u8 = 2;

impl PyMap {
    /// The map, waiting for another thread's call on it to end.
    fn lock(&self) -> MutexGuard<'_, AnyMap> {
        // A poisoned lock means a call panicked half way; the core does not panic, and its
        // calls change nothing before they succeed, so the map is still whole.
        self.map
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// A map holding `map`.
    pub fn wrap(map: AnyMap) -> PyMap {
        PyMap {
            map: Mutex::new(map),
        }
    }

    /// Runs `f` on the core map with the GIL released.
    pub fn with<T: Send>(&self, py: Python<'_>, f: impl FnOnce(&mut AnyMap) -> T + Send) -> T {
        py.detach(|| f(&mut self.lock()))
    }
}

/// ``"planar"`` or ``"range"``.
fn depth_kind(kind: &str) -> PyResult<DepthKind> {
    match kind {
        "planar" => Ok(DepthKind::Planar),
        "range" => Ok(DepthKind::Range),
        _ => Err(PyValueError::new_err(format!(
            "depth_kind must be 'planar' (along the optical axis) or 'range' (from the \
             optical centre), got {kind:?}"
        ))),
    }
}

/// A `ValueError` when a label is above the class count (0 is void).
fn check_classes(name: &str, labels: &[u8], (height, width): (usize, usize)) -> PyResult<()> {
    // The maximum first: a loop without an early exit vectorises (30 us for 1024x768).
    if labels.iter().copied().max().unwrap_or(0) as usize <= CLASSES {
        return Ok(());
    }
    match labels.iter().position(|&l| l as usize > CLASSES) {
        None => Ok(()),
        Some(i) => {
            let (row, col) = ((i / width.max(1)) % height.max(1), i % width.max(1));
            Err(PyValueError::new_err(format!(
                "{name} hold class {} at row {row}, column {col}; this map has classes \
                 1..={CLASSES} and 0 for void",
                labels[i]
            )))
        }
    }
}

/// Top-k ids (k, H, W) and scores in 0..1 as the core's per-pixel labels (scores scaled
/// to 0..=255 as the ESANet reader scales them; entries with class 0 are left out).
fn topk_labels(ids: &[u8], scores: &[f32], k: usize) -> Vec<Labels> {
    let n = ids.len() / k;
    (0..n)
        .map(|i| {
            let mut pairs = [(0u8, 0u8); sndt_core::MAX_TOP_K];
            let mut len = 0;
            for j in 0..k {
                let c = ids[j * n + i];
                if c != 0 {
                    let s = (scores[j * n + i].clamp(0.0, 1.0) * 255.0).round() as u8;
                    pairs[len] = (c, s);
                    len += 1;
                }
            }
            Labels::top_k(&pairs[..len])
        })
        .collect()
}

#[pymethods]
impl PyMap {
    #[new]
    #[pyo3(signature = (cell=0.1, classes=40, voxels=None, blocks=None, **config))]
    fn new(
        py: Python<'_>,
        cell: f32,
        classes: usize,
        voxels: Option<usize>,
        blocks: Option<usize>,
        config: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<PyMap> {
        if classes != CLASSES {
            return Err(PyValueError::new_err(format!(
                "classes must be {CLASSES} (the NYU40 classes; ids 1..=40, 0 void): other class \
                 counts are not built into this package, got {classes}"
            )));
        }
        let config = crate::config::from_kwargs(cell, config)?;
        let capacity =
            capacity::choose(voxels, blocks, capacity::DEFAULT).map_err(PyValueError::new_err)?;
        let map = py.detach(|| AnyMap::new(capacity, config));
        match map {
            Some(Ok(map)) => Ok(PyMap::wrap(map)),
            Some(Err(e)) => Err(crate::errors::ConfigError::new_err(format!("Map: {e}"))),
            None => Err(PyValueError::new_err("capacity not offered")),
        }
    }

    /// Integrates one depth image with its labels, seen from ``pose``, and returns what it
    /// did as a ``FrameReport``.
    ///
    /// ``depth``: ``uint16`` millimetres or ``float32`` metres, shape (H, W); zero,
    /// negative, NaN or inf is no measurement. ``labels``: ``uint8`` class ids (H, W), or
    /// the top-k ids (k, H, W) with ``topk_scores`` ``float32`` in [0, 1] of the same shape;
    /// ``None`` for geometry only. ``intrinsics``: ``(fx, fy, cx, cy)`` in pixels, OpenCV's
    /// convention (the centre of pixel ``(u, v)`` is at ``(u, v)``, as ROS ``CameraInfo.k``).
    /// ``pose``: 4x4 camera-to-world (OpenCV axes: x right, y down, z forward).
    /// ``depth_kind``: ``"planar"`` (along the optical axis) or ``"range"`` (from the optical
    /// centre). ``stride``: use every stride-th pixel in both directions.
    ///
    /// C-contiguous arrays are read in place; the GIL is released while the map works.
    /// Raises ``TypeError``/``ValueError`` for a bad argument, ``sndt.PoseError`` for a pose
    /// the map refuses; the map is unchanged then.
    #[pyo3(signature = (depth, labels=None, *, intrinsics, pose, topk_scores=None, depth_kind="planar", stride=1))]
    #[allow(clippy::too_many_arguments)]
    fn integrate(
        &self,
        py: Python<'_>,
        depth: &Bound<'_, PyAny>,
        labels: Option<&Bound<'_, PyAny>>,
        intrinsics: &Bound<'_, PyAny>,
        pose: &Bound<'_, PyAny>,
        topk_scores: Option<&Bound<'_, PyAny>>,
        depth_kind: &str,
        stride: u32,
    ) -> PyResult<PyFrameReport> {
        let depth = args::depth(depth)?;
        let size = depth.size();
        let labels = args::labels(labels, topk_scores, size)?;
        let camera = args::intrinsics(intrinsics, size)?;
        let pose = args::pose(pose)?;
        let kind = self::depth_kind(depth_kind)?;
        if stride == 0 {
            return Err(PyValueError::new_err("stride must be at least 1"));
        }
        let depth_values = match &depth {
            DepthArray::Millimetres(a) => Depth::Millimetres(a.as_slice()?),
            DepthArray::Metres(a) => Depth::Metres(a.as_slice()?),
        };
        enum Given<'a> {
            None,
            Top1(&'a [u8]),
            TopK(&'a [u8], &'a [f32], usize),
        }
        let given = match &labels {
            LabelArray::None => Given::None,
            LabelArray::Top1(a) => {
                let l = a.as_slice()?;
                check_classes("labels", l, size)?;
                Given::Top1(l)
            }
            LabelArray::TopK(ids, scores) => {
                let (i, s) = (ids.as_slice()?, scores.as_slice()?);
                check_classes("labels", i, size)?;
                if let Some(bad) = s.iter().find(|x| !(0.0..=1.0).contains(*x)) {
                    return Err(PyValueError::new_err(format!(
                        "topk_scores must be in [0, 1], got {bad}"
                    )));
                }
                Given::TopK(i, s, ids.shape()[0])
            }
        };
        let report = self.with(py, |map| {
            let topk;
            let labels = match given {
                Given::None => LabelImage::None,
                Given::Top1(l) => LabelImage::Top1(l),
                Given::TopK(ids, scores, k) => {
                    topk = topk_labels(ids, scores, k);
                    LabelImage::TopK(&topk)
                }
            };
            let image = DepthImage {
                camera,
                depth: depth_values,
                kind,
                labels,
                stride,
            };
            each_map!(map, m => sndt_dispatch::integrate_depth(m, &pose, &image, None))
        });
        report
            .map(PyFrameReport::from)
            .map_err(|e| core_error("integrate", e))
    }

    /// Integrates a frame of ``sndt.open_dataset`` exactly as ``sndt map`` does (any camera,
    /// per-pixel rays included), with labels ``"gt"``, ``"pred"``, ``"pred_topk"`` or
    /// ``"none"``.
    #[pyo3(signature = (frame, labels="gt", stride=1))]
    fn integrate_frame(
        &self,
        py: Python<'_>,
        frame: &PyFrame,
        labels: &str,
        stride: u32,
    ) -> PyResult<PyFrameReport> {
        let source = match labels {
            "gt" => LabelSource::Gt,
            "pred" => LabelSource::Pred,
            "pred_topk" => LabelSource::PredTopk,
            "none" => LabelSource::None,
            _ => {
                return Err(PyValueError::new_err(format!(
                    "labels must be 'gt', 'pred', 'pred_topk' or 'none', got {labels:?}"
                )))
            }
        };
        if stride == 0 {
            return Err(PyValueError::new_err("stride must be at least 1"));
        }
        let frame = frame.frame.clone();
        let t = frame.pose.translation.vector;
        self.with(py, |map| {
            each_map!(map, m => {
                // The pose's errors first, typed; what the core refuses after that is the
                // image (its size, or more points than a frame may have).
                sndt_core::validate_pose(&frame.pose)
                    .and_then(|()| m.voxel_key(&[t.x, t.y, t.z]).map(|_| ()).ok_or(sndt_core::Error::PoseOutOfRange))
                    .map_err(|e| core_error(&format!("integrate_frame {}", frame.id), e))?;
                sndt_host::mapping::integrate_frame(m, &frame, source, stride)
                    .map_err(|e| crate::errors::ImageError::new_err(format!("{e:#}")))
            })
        })
        .map(PyFrameReport::from)
    }

    /// Renders what a pinhole camera at ``pose`` sees of the map: ``(labels, depth)``, both
    /// (height, width). ``labels`` ``uint8``: the class of the first Gaussian each pixel's
    /// ray enters, 0 void, 255 nothing (as ``sndt map``'s back-projection PNGs).
    /// ``depth`` ``float32`` metres to that hit, along the optical axis (``depth_kind``
    /// ``"planar"``) or from the optical centre (``"range"``); 0 where nothing is hit.
    #[pyo3(signature = (pose, intrinsics, width, height, *, depth_kind="planar"))]
    fn render<'py>(
        &self,
        py: Python<'py>,
        pose: &Bound<'py, PyAny>,
        intrinsics: &Bound<'py, PyAny>,
        width: usize,
        height: usize,
        depth_kind: &str,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let camera = args::intrinsics(intrinsics, (height, width))?;
        let pose = args::pose(pose)?;
        let kind = self::depth_kind(depth_kind)?;
        if width.checked_mul(height).is_none_or(|n| n > 1 << 28) {
            return Err(PyValueError::new_err(format!(
                "width x height must be at most 2^28 pixels, got {width} x {height}"
            )));
        }
        let (labels, depth) = self
            .with(py, |map| render(map, &pose, &camera, kind))
            .map_err(|e| core_error("render", e))?;
        let labels = PyArray1::from_vec(py, labels).reshape([height, width])?;
        let depth = PyArray1::from_vec(py, depth).reshape([height, width])?;
        PyTuple::new(py, [labels.into_any(), depth.into_any()])
    }

    /// The surface voxels as arrays (``sndt.Voxels``): means, covariances, counts, class,
    /// confidence, occupancy probability and log-odds, one row per voxel.
    fn voxels(&self, py: Python<'_>) -> PyResult<PyVoxels> {
        struct Columns {
            means: Vec<[f32; 3]>,
            cov: Vec<f32>,
            counts: Vec<u32>,
            classes: Vec<u8>,
            confidence: Vec<f32>,
            occupancy: Vec<f32>,
            log_odds: Vec<f32>,
        }
        let c = self.with(py, |map| {
            each_map!(map, m => {
                let n = m.len();
                let mut c = Columns {
                    means: Vec::with_capacity(n),
                    cov: Vec::with_capacity(9 * n),
                    counts: Vec::with_capacity(n),
                    classes: Vec::with_capacity(n),
                    confidence: Vec::with_capacity(n),
                    occupancy: Vec::with_capacity(n),
                    log_odds: Vec::with_capacity(n),
                };
                for v in m.voxels() {
                    let g = v.gaussian;
                    c.means.push([g.mean.x, g.mean.y, g.mean.z]);
                    for i in 0..3 {
                        for j in 0..3 {
                            c.cov.push(g.covariance[(i, j)]);
                        }
                    }
                    c.counts.push(g.count);
                    let (class, share) = v.class().unwrap_or((0, 0.0));
                    c.classes.push(class);
                    c.confidence.push(share);
                    c.occupancy.push(1.0 / (1.0 + (-v.log_odds).exp()));
                    c.log_odds.push(v.log_odds);
                }
                c
            })
        });
        let n = c.counts.len();
        let means: Vec<f32> = c.means.into_iter().flatten().collect();
        Ok(PyVoxels {
            means: PyArray1::from_vec(py, means)
                .reshape([n, 3])?
                .into_any()
                .unbind(),
            covariances: PyArray1::from_vec(py, c.cov)
                .reshape([n, 3, 3])?
                .into_any()
                .unbind(),
            counts: PyArray1::from_vec(py, c.counts).into_any().unbind(),
            classes: PyArray1::from_vec(py, c.classes).into_any().unbind(),
            confidence: PyArray1::from_vec(py, c.confidence).into_any().unbind(),
            occupancy: PyArray1::from_vec(py, c.occupancy).into_any().unbind(),
            log_odds: PyArray1::from_vec(py, c.log_odds).into_any().unbind(),
        })
    }

    /// The occupancy of the voxel holding each of ``points`` ((N, 3) metres, ``float32`` or
    /// ``float64``): ``uint8`` (N,) of ``sndt.UNKNOWN`` (never observed, or outside the key
    /// range), ``sndt.FREE`` or ``sndt.OCCUPIED``.
    fn occupancy<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<u8>>> {
        let points = args::points(points)?;
        let states = self.with(py, |map| {
            each_map!(map, m => points
                .iter()
                .map(|p| match m.voxel_key(p).map(|k| m.occupancy(&k)) {
                    Some(Occupancy::Free) => FREE,
                    Some(Occupancy::Occupied) => OCCUPIED,
                    _ => UNKNOWN,
                })
                .collect::<Vec<u8>>())
        });
        Ok(PyArray1::from_vec(py, states))
    }

    /// The map's snapshot: the bytes ``sndt map --save-maps`` writes to a ``.sndt`` file
    /// (versioned, little-endian, CRC-32).
    fn snapshot<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let bytes = self
            .with(py, |map| map.snapshot())
            .map_err(|e| core_error("snapshot", e))?;
        Ok(PyBytes::new(py, &bytes))
    }

    /// Writes the snapshot to ``path`` (atomically: a crash leaves any old file whole).
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let bytes = self
            .with(py, |map| map.snapshot())
            .map_err(|e| core_error("snapshot", e))?;
        py.detach(|| sndt_host::atomic::write_bytes(&path, &bytes))
            .map_err(|e| pyo3::exceptions::PyOSError::new_err(format!("{e:#}")))
    }

    /// A map read from a snapshot: a path (``str`` or ``os.PathLike``) or the bytes
    /// themselves. Its capacity is the one it was saved with when that is offered, else the
    /// smallest that holds it; ``voxels``/``blocks`` choose another. Raises
    /// ``sndt.SnapshotError`` for a file that is not a readable snapshot and
    /// ``sndt.CapacityError`` when it does not fit the capacity asked for.
    #[staticmethod]
    #[pyo3(signature = (source, *, voxels=None, blocks=None))]
    fn load(
        py: Python<'_>,
        source: &Bound<'_, PyAny>,
        voxels: Option<usize>,
        blocks: Option<usize>,
    ) -> PyResult<PyMap> {
        let bytes: Vec<u8> = if let Ok(b) = source.cast::<PyBytes>() {
            b.as_bytes().to_vec()
        } else if let Ok(b) = source.cast::<PyByteArray>() {
            b.to_vec()
        } else if let Ok(path) = source.extract::<PathBuf>() {
            py.detach(|| std::fs::read(&path)).map_err(|e| {
                pyo3::exceptions::PyOSError::new_err(format!("{}: {e}", path.display()))
            })?
        } else {
            return Err(PyTypeError::new_err(
                "Map.load takes a path (str or os.PathLike) or the snapshot's bytes",
            ));
        };
        let header = sndt_core::SnapshotHeader::read(&bytes)
            .map_err(|e| core_error("not a readable sndt snapshot", e))?;
        let saved = (
            header.voxel_capacity as usize,
            header.block_capacity as usize,
        );
        let fallback = if capacity::CAPACITIES.contains(&saved) {
            saved
        } else {
            capacity::CAPACITIES
                .iter()
                .copied()
                .find(|&(v, b)| v >= header.voxels as usize && b >= header.blocks as usize)
                .ok_or_else(|| {
                    CapacityError::new_err(format!(
                        "the snapshot holds {} voxels and {} blocks, more than the largest map",
                        header.voxels, header.blocks
                    ))
                })?
        };
        let capacity = capacity::choose(voxels, blocks, fallback).map_err(PyValueError::new_err)?;
        py.detach(|| -> PyResult<PyMap> {
            let Some(Ok(mut map)) = AnyMap::new(capacity, sndt_core::Config::DEFAULT) else {
                return Err(SnapshotError::new_err("no map of that capacity"));
            };
            each_map!(&mut map, m => m.read_snapshot(&bytes))
                .map_err(|e| core_error("not a readable sndt snapshot", e))?;
            Ok(PyMap::wrap(map))
        })
    }

    /// Adds ``other``'s observations to this map (``sndt merge``): the maps must have the
    /// same config (``sndt.ConfigError``) and this one room for the union
    /// (``sndt.CapacityError``; nothing is merged then). ``other`` is unchanged.
    fn merge(&self, py: Python<'_>, other: &Bound<'_, PyMap>) -> PyResult<()> {
        let other = other.get();
        if std::ptr::eq(self, other) {
            return Err(PyValueError::new_err(
                "a map cannot be merged into itself; merge a copy (Map.load(m.snapshot()))",
            ));
        }
        py.detach(|| {
            // Always lock the map at the lower address first, so that a.merge(b) and
            // b.merge(a) on two threads cannot wait for each other.
            let (mut mine, theirs);
            if (self as *const PyMap) < (other as *const PyMap) {
                mine = self.lock();
                theirs = other.lock();
            } else {
                theirs = other.lock();
                mine = self.lock();
            }
            mine.merge(&theirs)
        })
        .map_err(|e| core_error("merge", e))
    }

    /// CRC-32 of the snapshot (the ``crc`` ``sndt map`` prints for a saved map).
    fn checksum(&self, py: Python<'_>) -> u32 {
        self.with(py, |map| each_map!(map, m => m.checksum()))
    }

    /// The config, as a dict of the core's fields.
    #[getter]
    fn config<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let c = self.lock().config();
        crate::config::to_dict(py, &c)
    }

    /// ``(voxels, blocks)``: how many surface voxels and occupancy blocks fit.
    #[getter]
    fn capacity(&self) -> (usize, usize) {
        self.lock().capacity()
    }

    /// Number of classes (ids 1..=classes; 0 is void).
    #[getter]
    fn classes(&self) -> usize {
        CLASSES
    }

    /// Bytes the map holds (fixed by its capacity).
    #[getter]
    fn memory_bytes(&self) -> usize {
        self.lock().memory_bytes()
    }

    /// Occupancy blocks in use.
    #[getter]
    fn blocks(&self) -> usize {
        let map = self.lock();
        each_map!(&*map, m => m.block_count())
    }

    /// Totals since the map was made: frames, evicted voxels and blocks, dropped updates.
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let stats = {
            let map = self.lock();
            each_map!(&*map, m => m.stats())
        };
        // Field by field (no `..`): a field the core adds fails to compile here until the
        // dict holds it.
        let MapStats {
            frames,
            voxels_evicted,
            blocks_evicted,
            dropped_points,
            dropped_misses,
        } = stats;
        let d = PyDict::new(py);
        d.set_item("frames", frames)?;
        d.set_item("voxels_evicted", voxels_evicted)?;
        d.set_item("blocks_evicted", blocks_evicted)?;
        d.set_item("dropped_points", dropped_points)?;
        d.set_item("dropped_misses", dropped_misses)?;
        Ok(d)
    }

    /// Surface voxels in the map.
    fn __len__(&self) -> usize {
        let map = self.lock();
        each_map!(&*map, m => m.len())
    }

    fn __repr__(&self) -> String {
        let map = self.lock();
        let (v, b) = map.capacity();
        each_map!(&*map, m => format!(
            "sndt.Map(cell={}, voxels={v}, blocks={b}): {} voxels, {} blocks, {} frames",
            m.config().cell_size,
            m.len(),
            m.block_count(),
            m.stats().frames
        ))
    }
}

/// Labels and depth of a render, in bands of rows on rayon's threads (the pixels do not
/// depend on the bands: `Map::render_rows`).
fn render(
    map: &AnyMap,
    pose: &sndt_core::Isometry3<f32>,
    camera: &Pinhole,
    kind: DepthKind,
) -> Result<(Vec<u8>, Vec<f32>), sndt_core::Error> {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let mut labels = vec![INVALID_LABEL; w * h];
    let mut depth = vec![0f32; w * h];
    let band = h.div_ceil(2 * rayon::current_num_threads()).max(1);
    labels
        .par_chunks_mut(band * w)
        .zip(depth.par_chunks_mut(band * w))
        .enumerate()
        .try_for_each(|(i, (l, d))| {
            let row0 = (i * band) as u32;
            each_map!(map, m => m.render_rows(pose, camera, row0, l, d))?;
            for (k, (label, dist)) in l.iter().zip(d.iter_mut()).enumerate() {
                let (col, row) = ((k % w) as u32, row0 + (k / w) as u32);
                *dist = if *label == INVALID_LABEL || !dist.is_finite() {
                    0.0
                } else if kind == DepthKind::Planar {
                    let r = camera.ray(col, row);
                    *dist / (r[0] * r[0] + r[1] * r[1] + 1.0).sqrt()
                } else {
                    *dist
                };
            }
            Ok(())
        })?;
    Ok((labels, depth))
}
