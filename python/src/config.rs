//! The core's `Config` as keyword arguments (`sndt.Map(cell=0.05, n_max=1024)`) and as a
//! dict (`Map.config`).

use crate::errors::ConfigError;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sndt_core::{Config, MissModel};

/// The keyword names, in the order of the struct (`cell` is `cell_size`).
pub const FIELDS: [&str; 19] = [
    "cell_size",
    "quant_bits",
    "n_min",
    "eigen_ratio",
    "n_max",
    "hit",
    "miss",
    "clamp_min",
    "clamp_max",
    "lambda_",
    "see_through_miss",
    "noise_base",
    "noise_quadratic",
    "max_range",
    "top_k",
    "min_score",
    "votes_per_frame",
    "miss_model",
    "render_radius",
];

/// `Config::with_cell_size(cell)` with the fields of `kwargs` set; a `TypeError` for an
/// unknown name or a value of the wrong type, a `ValueError` for an integer out of its
/// type's range, a `sndt.ConfigError` naming the field and its range for a value the
/// core refuses.
pub fn from_kwargs(cell: f32, kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<Config> {
    let mut c = Config::with_cell_size(cell);
    if let Some(kwargs) = kwargs {
        for (key, value) in kwargs.iter() {
            let name: String = key.extract()?;
            set(&mut c, &name, &value)?;
        }
    }
    c.validate()
        .map_err(|e| ConfigError::new_err(format!("Map: {e}")))?;
    Ok(c)
}

/// Sets field `name` of `c` from `value`.
fn set(c: &mut Config, name: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
    let float = |what: &str| -> PyResult<f32> {
        value
            .extract::<f64>()
            .map(|x| x as f32)
            .map_err(|_| PyTypeError::new_err(format!("{name} must be {what}, got {value}")))
    };
    fn int<T: TryFrom<i64>>(name: &str, value: &Bound<'_, PyAny>, what: &str) -> PyResult<T> {
        let i: i64 = value
            .extract()
            .map_err(|_| PyTypeError::new_err(format!("{name} must be {what}, got {value}")))?;
        T::try_from(i).map_err(|_| PyValueError::new_err(format!("{name} must be {what}, got {i}")))
    }
    match name {
        "cell_size" | "cell" => c.cell_size = float("a number of metres")?,
        "quant_bits" => c.quant_bits = int(name, value, "an integer in 0..=6")?,
        "n_min" => c.n_min = int(name, value, "an integer of at least 2")?,
        "eigen_ratio" => c.eigen_ratio = float("a number")?,
        "n_max" => c.n_max = int(name, value, "an integer in [n_min, 65535]")?,
        "hit" => c.hit = float("a log-odds number")?,
        "miss" => c.miss = float("a log-odds number")?,
        "clamp_min" => c.clamp_min = float("a log-odds number")?,
        "clamp_max" => c.clamp_max = float("a log-odds number")?,
        "lambda_" | "lambda" => c.lambda = float("a number in [0, 0.49]")?,
        "noise_base" => c.noise_base = float("a number of metres")?,
        "noise_quadratic" => c.noise_quadratic = float("a number")?,
        "max_range" => c.max_range = float("a number of metres")?,
        "top_k" => c.top_k = int(name, value, "an integer in 1..=3")?,
        "min_score" => c.min_score = int(name, value, "an integer in 0..=255")?,
        "votes_per_frame" => c.votes_per_frame = int(name, value, "an integer in 1..=64")?,
        "miss_model" => {
            let s: String = value.extract().map_err(|_| {
                PyTypeError::new_err(format!(
                    "miss_model must be 'ndt_om' or 'constant', got {value}"
                ))
            })?;
            c.miss_model = match s.as_str() {
                "ndt_om" => MissModel::NdtOm,
                "constant" => MissModel::Constant,
                _ => {
                    return Err(PyValueError::new_err(format!(
                        "miss_model must be 'ndt_om' or 'constant', got {s:?}"
                    )))
                }
            };
        }
        "render_radius" => c.render_radius = float("a number")?,
        "see_through_miss" => c.see_through_miss = float("a number")?,
        _ => {
            return Err(PyTypeError::new_err(format!(
            "Map() got an unexpected keyword argument '{name}'; the config fields are: cell, {}",
            FIELDS[1..].join(", ")
        )))
        }
    }
    Ok(())
}

/// The config as a dict of its fields (`lambda` as `lambda_`, the miss model by name).
pub fn to_dict<'py>(py: Python<'py>, c: &Config) -> PyResult<Bound<'py, PyDict>> {
    // Field by field (no `..`): a field the core adds fails to compile here until the dict,
    // and so `FIELDS` and `set` (python/tests/test_mirrors.py), hold it.
    let Config {
        cell_size,
        quant_bits,
        n_min,
        eigen_ratio,
        n_max,
        hit,
        miss,
        clamp_min,
        clamp_max,
        lambda,
        see_through_miss,
        noise_base,
        noise_quadratic,
        max_range,
        top_k,
        min_score,
        votes_per_frame,
        miss_model,
        render_radius,
    } = *c;
    let d = PyDict::new(py);
    d.set_item("cell_size", cell_size)?;
    d.set_item("quant_bits", quant_bits)?;
    d.set_item("n_min", n_min)?;
    d.set_item("eigen_ratio", eigen_ratio)?;
    d.set_item("n_max", n_max)?;
    d.set_item("hit", hit)?;
    d.set_item("miss", miss)?;
    d.set_item("clamp_min", clamp_min)?;
    d.set_item("clamp_max", clamp_max)?;
    d.set_item("lambda_", lambda)?;
    d.set_item("see_through_miss", see_through_miss)?;
    d.set_item("noise_base", noise_base)?;
    d.set_item("noise_quadratic", noise_quadratic)?;
    d.set_item("max_range", max_range)?;
    d.set_item("top_k", top_k)?;
    d.set_item("min_score", min_score)?;
    d.set_item("votes_per_frame", votes_per_frame)?;
    let model = match miss_model {
        MissModel::NdtOm => "ndt_om",
        MissModel::Constant => "constant",
    };
    d.set_item("miss_model", model)?;
    d.set_item("render_radius", render_radius)?;
    Ok(d)
}
