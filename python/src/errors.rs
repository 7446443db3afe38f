//! `sndt.Error` and its subclasses, one per kind of core error, and the conversions into
//! them. Argument mistakes are `TypeError` / `ValueError` (`crate::args`); what the map
//! refuses is an `sndt.Error`. Either way the map is unchanged.

use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use sndt_core::Error as CoreError;

create_exception!(
    sndt,
    Error,
    PyException,
    "Base class of every error the map or a dataset reports (argument mistakes are \
     TypeError or ValueError)."
);
create_exception!(
    sndt,
    ConfigError,
    Error,
    "A config field out of its range, or a merge of maps with different configs."
);
create_exception!(
    sndt,
    PoseError,
    Error,
    "A pose whose rotation is not a rotation, or a sensor outside the map's key range."
);
create_exception!(
    sndt,
    ImageError,
    Error,
    "An image the map cannot take: sizes that disagree with the camera, or more than \
     2^20 points in one frame."
);
create_exception!(
    sndt,
    CapacityError,
    Error,
    "The map has no room: a merge or a snapshot needs more voxels or blocks than its \
     capacity."
);
create_exception!(
    sndt,
    SnapshotError,
    Error,
    "A snapshot that cannot be read: truncated, another format or version, a CRC \
     mismatch, or content that breaks the map's invariants."
);
create_exception!(
    sndt,
    DatasetError,
    Error,
    "A dataset that cannot be opened or a frame that cannot be read."
);

/// The exception of a core error, with its sentence as the message, prefixed by `what`.
pub fn core_error(what: &str, e: CoreError) -> PyErr {
    let msg = format!("{what}: {e}");
    match e {
        CoreError::InvalidConfig(_) | CoreError::ConfigMismatch => ConfigError::new_err(msg),
        CoreError::InvalidPose | CoreError::PoseOutOfRange => PoseError::new_err(msg),
        CoreError::FrameTooLarge | CoreError::InvalidImage | CoreError::BufferTooSmall => {
            ImageError::new_err(msg)
        }
        CoreError::MapFull | CoreError::SnapshotCapacity => CapacityError::new_err(msg),
        CoreError::SnapshotTruncated
        | CoreError::SnapshotMagic
        | CoreError::SnapshotVersion
        | CoreError::SnapshotClasses
        | CoreError::SnapshotChecksum
        | CoreError::SnapshotCorrupt
        | CoreError::RecordCorrupt
        | CoreError::StreamChecksum
        | CoreError::StreamOrder
        | CoreError::StreamTruncated => SnapshotError::new_err(msg),
    }
}

/// A dataset error with its whole chain of causes.
pub fn dataset_error(e: anyhow::Error) -> PyErr {
    DatasetError::new_err(format!("{e:#}"))
}

/// Adds the exception classes to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("Error", py.get_type::<Error>())?;
    m.add("ConfigError", py.get_type::<ConfigError>())?;
    m.add("PoseError", py.get_type::<PoseError>())?;
    m.add("ImageError", py.get_type::<ImageError>())?;
    m.add("CapacityError", py.get_type::<CapacityError>())?;
    m.add("SnapshotError", py.get_type::<SnapshotError>())?;
    m.add("DatasetError", py.get_type::<DatasetError>())?;
    Ok(())
}
