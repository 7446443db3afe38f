//! The native module of the `sndt` Python package (`sndt._sndt`): the core's map fed from
//! numpy arrays, and the host's datasets and evaluation. `python/sndt/__init__.py`
//! re-exports it; `docs/PYTHON.md` describes the API.
//!
//! The modules, in dependency order: each uses only modules above it (no two import each
//! other, which `tests/tests/layout.rs` checks).
//!
//! | module | what it holds |
//! |---|---|
//! | `errors` | `sndt.Error` and a subclass per kind of core error |
//! | `args` | checks of numpy arguments, the pose and the intrinsics |
//! | `config` | the core's `Config` as keyword arguments and as a dict |
//! | `capacity` | the capacities offered at run time (`AnyMap`) |
//! | `data` | `open_dataset`, `Dataset`, `Trajectory`, `Frame` |
//! | `map` | `sndt.Map` (which integrates a `Frame`), `FrameReport`, `Voxels` |
//! | `evaluate` | `evaluate` (a `Map` rendered into `Frame`s), `Metrics` |

mod args;
mod capacity;
mod config;
mod data;
mod errors;
mod evaluate;
mod map;

use pyo3::prelude::*;

/// Semantic occupancy-NDT maps (S-NDT) from numpy arrays.
#[pymodule]
fn _sndt(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<map::PyMap>()?;
    m.add_class::<map::PyFrameReport>()?;
    m.add_class::<map::PyVoxels>()?;
    m.add_class::<data::PyDataset>()?;
    m.add_class::<data::PyTrajectory>()?;
    m.add_class::<data::PyFrame>()?;
    m.add_class::<evaluate::PyMetrics>()?;
    m.add_function(wrap_pyfunction!(data::open_dataset, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate::evaluate, m)?)?;
    errors::register(m)?;
    m.add("UNKNOWN", map::UNKNOWN)?;
    m.add("FREE", map::FREE)?;
    m.add("OCCUPIED", map::OCCUPIED)?;
    m.add("CAPACITIES", capacity::CAPACITIES.to_vec())?;
    m.add("DEFAULT_CAPACITY", capacity::DEFAULT)?;
    let mut fields = vec!["cell"];
    fields.extend_from_slice(&config::FIELDS[1..]);
    m.add("CONFIG_FIELDS", fields)?;
    m.add("INVALID_LABEL", sndt_core::INVALID_LABEL)?;
    let classes = sndt_host::dataset::classes::NYU40;
    m.add("CLASS_NAMES", classes.to_vec())?;
    let colors: Vec<(u8, u8, u8)> = (0..=255u8)
        .map(sndt_host::dataset::classes::render_color)
        .map(|[r, g, b]| (r, g, b))
        .collect();
    m.add("CLASS_COLORS", colors)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
