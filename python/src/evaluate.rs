//! `sndt.evaluate`: maps scored on dataset frames with the command line's evaluation. It
//! uses both the map (`crate::map`) and the frames (`crate::data`), so it sits above them.

use crate::data::PyFrame;
use crate::errors::DatasetError;
use crate::map::PyMap;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sndt_host::eval::evaluate::gt_depth;
use sndt_host::eval::metrics::{Confusion, Metrics};

/// mIoU, invR and mPAcc of ``sndt.evaluate``, as fractions (the paper prints them x 100),
/// with the IoU of each class present in the ground truth, by NYU40 name.
#[pyclass(module = "sndt", name = "Metrics", frozen, get_all)]
pub struct PyMetrics {
    /// Mean IoU over the classes present in the ground truth.
    miou: f64,
    /// Invalid predictions (nothing rendered) over all non-void ground-truth pixels.
    invr: f64,
    /// Mean pixel accuracy over the classes present in the ground truth.
    mpacc: f64,
    /// IoU per class name.
    per_class_iou: Py<PyDict>,
    /// Frames scored.
    frames: usize,
}

#[pymethods]
impl PyMetrics {
    fn __repr__(&self) -> String {
        format!(
            "Metrics(mIoU {:.2} %, invR {:.2} %, mPAcc {:.2} %, {} frames)",
            100.0 * self.miou,
            100.0 * self.invr,
            100.0 * self.mpacc,
            self.frames
        )
    }
}

impl PyMetrics {
    /// The host's metrics of `frames` frames, taken apart field by field (no `..`), so that
    /// a field the host adds fails to compile here until `Metrics` shows it.
    fn new(py: Python<'_>, metrics: Metrics, frames: usize) -> PyResult<PyMetrics> {
        let per_class_iou = PyDict::new(py);
        for (name, v) in metrics.iou_by_name() {
            per_class_iou.set_item(name, v.as_f64())?;
        }
        // `iou` is `per_class_iou` above, by class name.
        let Metrics {
            miou,
            mpacc,
            invr,
            iou: _,
        } = metrics;
        Ok(PyMetrics {
            miou,
            invr,
            mpacc,
            per_class_iou: per_class_iou.unbind(),
            frames,
        })
    }
}

/// The `(map, frames)` pairs of `evaluate(map, frames)` or `evaluate([(map, frames), ...])`.
fn map_frame_pairs<'py>(
    maps: &Bound<'py, PyAny>,
    frames: Option<&Bound<'py, PyAny>>,
) -> PyResult<Vec<(Bound<'py, PyMap>, Bound<'py, PyAny>)>> {
    if let Some(frames) = frames {
        let map = maps
            .cast::<PyMap>()
            .map_err(|_| PyTypeError::new_err("evaluate(map, frames): map must be an sndt.Map"))?;
        return Ok(vec![(map.clone(), frames.clone())]);
    }
    maps.try_iter()
        .map_err(|_| {
            PyTypeError::new_err("evaluate takes (map, frames) or a list of (map, frames)")
        })?
        .map(|pair| {
            let pair = pair?;
            let (map, frames): (Bound<'py, PyAny>, Bound<'py, PyAny>) =
                pair.extract().map_err(|_| {
                    PyTypeError::new_err("evaluate([...]): each item must be (map, frames)")
                })?;
            let map = map.cast_into::<PyMap>().map_err(|_| {
                PyTypeError::new_err("evaluate([...]): each map must be an sndt.Map")
            })?;
            Ok((map, frames))
        })
        .collect()
}

/// Scores maps as ``sndt map`` does: each map is rendered into each of its frames at the
/// frame's pose, and the renders are scored against the frames' ground truth (pixels 20 m
/// or farther are not counted), all frames in one confusion matrix.
///
/// ``evaluate(map, frames)`` for one map, or ``evaluate([(map, frames), ...])`` for one
/// map per trajectory, as ``sndt map`` maps a dataset. ``frames`` is a ``Trajectory`` or
/// any iterable of ``Frame``.
#[pyfunction]
#[pyo3(signature = (maps, frames=None))]
pub fn evaluate(
    py: Python<'_>,
    maps: &Bound<'_, PyAny>,
    frames: Option<&Bound<'_, PyAny>>,
) -> PyResult<PyMetrics> {
    let mut total = Confusion::default();
    let mut count = 0;
    for (map, frames) in map_frame_pairs(maps, frames)? {
        for frame in frames.try_iter()? {
            let frame = frame?;
            let frame = frame.cast::<PyFrame>().map_err(|_| {
                PyTypeError::new_err("evaluate: frames must yield sndt.Frame objects")
            })?;
            let frame = frame.get().frame.clone();
            let Some(gt) = frame.labels.as_ref() else {
                continue;
            };
            let rendered = map
                .get()
                .with(py, |m| {
                    crate::each_map!(m, m => sndt_host::mapping::backproject(m.as_ref(), &frame))
                })
                .map_err(|e| DatasetError::new_err(format!("{e:#}")))?;
            total.add_frame(gt, &rendered, &gt_depth(&frame));
            count += 1;
        }
    }
    PyMetrics::new(py, total.metrics(), count)
}
