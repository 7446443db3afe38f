//! Datasets from Python: `sndt.open_dataset` reads whatever the command line reads and
//! yields trajectories of frames as numpy values.

use crate::errors::dataset_error;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyList, PyTuple};
use sndt_core::DepthKind;
use sndt_host::dataset::source::BadFrame;
use sndt_host::dataset::{Dataset, Frame, FrameId, Rays};
use std::sync::Arc;

/// A dataset opened by ``sndt.open_dataset``: iterate it for its trajectories.
#[pyclass(module = "sndt", name = "Dataset", frozen)]
pub struct PyDataset {
    dataset: Arc<dyn Dataset>,
}

/// One trajectory (``scene/cam``) of a dataset: iterate it for its frames, read one at a
/// time. A frame whose own files are unreadable is skipped with a warning, as ``sndt map``
/// skips it.
#[pyclass(module = "sndt", name = "Trajectory", frozen)]
pub struct PyTrajectory {
    dataset: Arc<dyn Dataset>,
    /// ``scene/cam``.
    #[pyo3(get)]
    name: String,
    ids: Vec<FrameId>,
}

/// The iterator of a trajectory's frames.
#[pyclass(module = "sndt", name = "FrameIterator")]
pub struct PyFrameIter {
    dataset: Arc<dyn Dataset>,
    ids: Vec<FrameId>,
    next: usize,
}

/// One frame: ``id`` (``scene/cam/NNNN``), ``depth`` ``float32`` metres (H, W) of
/// ``depth_kind`` ``"planar"`` or ``"range"``, ``labels`` ``uint8`` (H, W) or ``None``,
/// ``intrinsics`` ``(fx, fy, cx, cy)`` in OpenCV's convention (``None`` for a camera with a
/// ray per pixel),
/// ``pose`` 4x4 ``float64`` camera-to-world (OpenCV axes), ``topk`` the predicted top-3
/// ``(ids uint8 (3, H, W), scores float32 (3, H, W))`` or ``None``, ``stamp`` the
/// recording time in integer nanoseconds (ROS 2 bags) or ``None``.
#[pyclass(module = "sndt", name = "Frame", frozen)]
pub struct PyFrame {
    pub frame: Arc<Frame>,
    stamp: Option<u64>,
}

/// Opens ``path``: a prepared-layout or raw Hypersim directory, a ROS 2 bag (``.mcap``
/// file or rosbag2 folder), or ``synthetic``, ``synthetic:SCENES:FRAMES``,
/// ``synthetic:floor[:WALK[:FRAMES]]``, ``synthetic:dynamic[:FRAMES[:CHANGE]]``,
/// ``synthetic:floor-people[:WALK[:FRAMES]]`` (rendered on the fly) — what ``sndt map``
/// takes.
/// Keywords as its options: ``split`` (prepared layout, default ``"test"``),
/// ``predictions`` (directory of ESANet ``.npy`` files), ``world_frame`` (bags, default
/// ``"world"``), ``every`` (every n-th frame of each trajectory).
#[pyfunction]
#[pyo3(signature = (path, *, split=None, predictions=None, world_frame=None, every=1))]
pub fn open_dataset(
    py: Python<'_>,
    path: std::path::PathBuf,
    split: Option<String>,
    predictions: Option<std::path::PathBuf>,
    world_frame: Option<String>,
    every: u32,
) -> PyResult<PyDataset> {
    if every == 0 {
        return Err(PyValueError::new_err("every must be at least 1"));
    }
    let mut options = sndt_host::dataset::OpenOptions {
        split,
        predictions,
        ..Default::default()
    };
    options.bag.world_frame = world_frame;
    let spec = path.to_string_lossy().into_owned();
    let dataset = py
        .detach(|| sndt_host::dataset::open_spec(&spec, &options))
        .map_err(dataset_error)?;
    let dataset: Box<dyn Dataset> = if every > 1 {
        Box::new(sndt_host::dataset::Every::new(dataset, every))
    } else {
        dataset
    };
    Ok(PyDataset {
        dataset: Arc::from(dataset),
    })
}

#[pymethods]
impl PyDataset {
    /// The trajectories, in order.
    #[getter]
    fn trajectories(&self) -> Vec<PyTrajectory> {
        self.dataset
            .trajectories()
            .into_iter()
            .map(|(name, ids)| PyTrajectory {
                dataset: self.dataset.clone(),
                name,
                ids,
            })
            .collect()
    }

    /// Frames over all trajectories.
    #[getter]
    fn frames(&self) -> usize {
        self.dataset.frames().len()
    }

    fn __iter__(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        let list = PyList::new(py, self.trajectories())?;
        Ok(list.try_iter()?.into_any().unbind())
    }

    fn __len__(&self) -> usize {
        self.dataset.trajectories().len()
    }

    fn __repr__(&self) -> String {
        format!("sndt.Dataset({})", self.dataset.describe())
    }
}

#[pymethods]
impl PyTrajectory {
    /// The frame ids, ``scene/cam/NNNN``.
    #[getter]
    fn ids(&self) -> Vec<String> {
        self.ids.iter().map(ToString::to_string).collect()
    }

    fn __len__(&self) -> usize {
        self.ids.len()
    }

    fn __iter__(&self) -> PyFrameIter {
        PyFrameIter {
            dataset: self.dataset.clone(),
            ids: self.ids.clone(),
            next: 0,
        }
    }

    fn __repr__(&self) -> String {
        format!("sndt.Trajectory({}, {} frames)", self.name, self.ids.len())
    }
}

#[pymethods]
impl PyFrameIter {
    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    fn __next__(&mut self, py: Python<'_>) -> PyResult<Option<PyFrame>> {
        while let Some(id) = self.ids.get(self.next).cloned() {
            self.next += 1;
            let dataset = self.dataset.clone();
            match py.detach(|| dataset.load(&id)) {
                Ok(frame) => {
                    return Ok(Some(PyFrame {
                        stamp: self.dataset.stamp(&id),
                        frame: Arc::new(frame),
                    }))
                }
                Err(e) => match BadFrame::of(&e) {
                    Some(bad) => {
                        let warning = py.get_type::<pyo3::exceptions::PyUserWarning>();
                        let msg =
                            std::ffi::CString::new(format!("skipping frame {id}: {}", bad.why))
                                .unwrap_or_default();
                        PyErr::warn(py, &warning, &msg, 1)?;
                    }
                    None => return Err(dataset_error(e)),
                },
            }
        }
        Ok(None)
    }
}

/// `values` as a numpy array of `shape`.
fn array<'py, T: numpy::Element>(
    py: Python<'py>,
    values: Vec<T>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyAny>> {
    Ok(PyArray1::from_vec(py, values).reshape(shape)?.into_any())
}

#[pymethods]
impl PyFrame {
    /// ``scene/cam/NNNN``.
    #[getter]
    fn id(&self) -> String {
        self.frame.id.to_string()
    }

    /// (height, width).
    #[getter]
    fn shape(&self) -> (usize, usize) {
        (
            self.frame.rays.height() as usize,
            self.frame.rays.width() as usize,
        )
    }

    /// Depth in metres, ``float32`` (H, W); see ``depth_kind``.
    #[getter]
    fn depth<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let (h, w) = self.shape();
        array(py, self.frame.depth.clone(), &[h, w])
    }

    /// ``"planar"`` (along the optical axis) or ``"range"`` (from the optical centre).
    #[getter]
    fn depth_kind(&self) -> &'static str {
        match self.frame.depth_kind {
            DepthKind::Planar => "planar",
            DepthKind::Range => "range",
        }
    }

    /// Ground-truth class ids ``uint8`` (H, W), 0 void, or ``None``.
    #[getter]
    fn labels<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        let (h, w) = self.shape();
        self.frame
            .labels
            .as_ref()
            .map(|l| array(py, l.clone(), &[h, w]))
            .transpose()
    }

    /// Predicted top-3 ``(ids uint8 (3, H, W), scores float32 (3, H, W))`` or ``None``:
    /// ready for ``Map.integrate(depth, ids, topk_scores=scores, ...)``.
    #[getter]
    fn topk<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyTuple>>> {
        let Some(p) = &self.frame.predictions else {
            return Ok(None);
        };
        let (h, w) = self.shape();
        let n = h * w;
        let mut ids = vec![0u8; 3 * n];
        let mut scores = vec![0f32; 3 * n];
        for (i, (c, s)) in p.classes.iter().zip(&p.scores).enumerate() {
            for k in 0..3 {
                ids[k * n + i] = c[k];
                scores[k * n + i] = s[k];
            }
        }
        let ids = array(py, ids, &[3, h, w])?;
        let scores = array(py, scores, &[3, h, w])?;
        Ok(Some(PyTuple::new(py, [ids, scores])?))
    }

    /// ``(fx, fy, cx, cy)`` in OpenCV's convention (the centre of pixel ``(u, v)`` is at
    /// ``(u, v)``, as in ROS ``CameraInfo.k``), or ``None`` for a camera with a ray per pixel.
    #[getter]
    fn intrinsics(&self) -> Option<(f64, f64, f64, f64)> {
        match self.frame.rays.as_ref() {
            // The core counts the principal point from the pixels' corner: 0.5 more.
            Rays::Pinhole(p) => Some((
                p.fx as f64,
                p.fy as f64,
                p.cx as f64 - 0.5,
                p.cy as f64 - 0.5,
            )),
            Rays::PerPixel { .. } => None,
        }
    }

    /// Camera-to-world 4x4 ``float64`` (exactly the ``float32`` pose the map uses).
    #[getter]
    fn pose<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        // The rotation block is the quaternion's matrix, the one the map computes.
        let m = self.frame.pose.to_homogeneous();
        let rows: Vec<f64> = (0..16).map(|k| m[(k / 4, k % 4)] as f64).collect();
        array(py, rows, &[4, 4])
    }

    /// Recording time in integer nanoseconds (ROS 2 bags), else ``None``.
    #[getter]
    fn stamp(&self) -> Option<u64> {
        self.stamp
    }

    fn __repr__(&self) -> String {
        let (h, w) = self.shape();
        format!("sndt.Frame({}, {w}x{h})", self.frame.id)
    }
}
