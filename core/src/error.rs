//! The crate's one error type.

use core::fmt;

/// Everything that can go wrong. Small and `Copy` (one byte: the field of
/// [`Error::InvalidConfig`] shares it with the other variants); bad input never panics and
/// never loses what is already in the map.
///
/// `Display` says what is wrong in a sentence, naming the config field and its range:
///
/// ```
/// use sndt_core::{ConfigField, Error};
/// assert_eq!(core::mem::size_of::<Error>(), 1);
/// let e = Error::InvalidConfig(ConfigField::CellSize);
/// assert_eq!(
///     format!("{e}"),
///     "invalid config: cell_size must be a number of metres in [0.001, 100]"
/// );
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// A [`crate::Config`] field is out of its documented range: which one.
    InvalidConfig(ConfigField),
    /// The sensor pose has a non-finite value or a rotation that is not orthonormal.
    InvalidPose,
    /// The sensor origin lies outside the key range.
    PoseOutOfRange,
    /// More than [`crate::MAX_FRAME_POINTS`] points in one frame.
    FrameTooLarge,
    /// Depth/label image sizes disagree with the camera, or the camera is invalid.
    InvalidImage,
    /// The caller's buffer is too small.
    BufferTooSmall,
    /// Snapshot: too short, or its length disagrees with its header.
    SnapshotTruncated,
    /// Snapshot: wrong magic bytes.
    SnapshotMagic,
    /// Snapshot: a version this build cannot read.
    SnapshotVersion,
    /// Snapshot: class count differs from the map's `CLASSES`.
    SnapshotClasses,
    /// Snapshot: more voxels or blocks than this map's capacity.
    SnapshotCapacity,
    /// Snapshot: CRC-32 mismatch.
    SnapshotChecksum,
    /// Snapshot: CRC matches but the content breaks an invariant (among them a stored
    /// config that [`crate::Config::validate`] refuses).
    SnapshotCorrupt,
    /// A merge needs more voxels or blocks than the map's capacity (nothing was merged).
    MapFull,
    /// A merge of maps, records or a record stream from a map of another config or class
    /// count.
    ConfigMismatch,
    /// A record's length or content breaks an invariant of the map's config (a key out of
    /// range, a count above `n_max`, impossible sums, log-odds outside the clamps).
    RecordCorrupt,
    /// Record stream: a frame that is not valid COBS, or whose CRC-32 does not match
    /// (corrupted on the link).
    StreamChecksum,
    /// Record stream: a frame out of sequence (missing, duplicated or reordered), a record
    /// before the stream's start or after its end, or a frame of an unknown kind.
    StreamOrder,
    /// Record stream: it ended before its end frame.
    StreamTruncated,
}

/// The [`crate::Config`] field that [`crate::Config::validate`] refused: the first one, in
/// the order of the struct, that is out of its range. [`ConfigField::RayCells`] is the one
/// bound on two fields together (`max_range / cell_size`).
///
/// [`ConfigField::name`] is the field's name in the struct (and in the C API's
/// `sndt_config`); `Display` says the field and its range, for example
/// `max_range / cell_size must be at most 4096 cells (one ray's length in voxels)`.
///
/// ```
/// use sndt_core::{Config, ConfigField, Error};
/// let mut c = Config::DEFAULT;
/// c.n_max = 1;
/// assert_eq!(c.validate(), Err(Error::InvalidConfig(ConfigField::NMax)));
/// assert_eq!(ConfigField::NMax.name(), "n_max");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigField {
    /// [`crate::Config::cell_size`].
    CellSize,
    /// [`crate::Config::quant_bits`].
    QuantBits,
    /// [`crate::Config::n_min`].
    NMin,
    /// [`crate::Config::eigen_ratio`].
    EigenRatio,
    /// [`crate::Config::n_max`].
    NMax,
    /// [`crate::Config::hit`].
    Hit,
    /// [`crate::Config::miss`].
    Miss,
    /// [`crate::Config::clamp_min`].
    ClampMin,
    /// [`crate::Config::clamp_max`].
    ClampMax,
    /// [`crate::Config::lambda`].
    Lambda,
    /// [`crate::Config::see_through_miss`].
    SeeThroughMiss,
    /// [`crate::Config::noise_base`].
    NoiseBase,
    /// [`crate::Config::noise_quadratic`].
    NoiseQuadratic,
    /// [`crate::Config::max_range`] on its own.
    MaxRange,
    /// [`crate::Config::max_range`] in cells of [`crate::Config::cell_size`]: the longest
    /// ray, [`crate::Config::MAX_RAY_CELLS`] at most.
    RayCells,
    /// [`crate::Config::top_k`].
    TopK,
    /// [`crate::Config::votes_per_frame`].
    VotesPerFrame,
    /// [`crate::Config::render_radius`].
    RenderRadius,
}

impl ConfigField {
    /// Every field, in the order [`crate::Config::validate`] checks them.
    pub const ALL: [ConfigField; 18] = [
        ConfigField::CellSize,
        ConfigField::QuantBits,
        ConfigField::NMin,
        ConfigField::EigenRatio,
        ConfigField::NMax,
        ConfigField::Hit,
        ConfigField::Miss,
        ConfigField::ClampMin,
        ConfigField::ClampMax,
        ConfigField::Lambda,
        ConfigField::SeeThroughMiss,
        ConfigField::NoiseBase,
        ConfigField::NoiseQuadratic,
        ConfigField::MaxRange,
        ConfigField::RayCells,
        ConfigField::TopK,
        ConfigField::VotesPerFrame,
        ConfigField::RenderRadius,
    ];

    /// The field's name in [`crate::Config`] (`max_range / cell_size` for
    /// [`ConfigField::RayCells`]).
    ///
    /// ```
    /// assert_eq!(sndt_core::ConfigField::CellSize.name(), "cell_size");
    /// ```
    pub const fn name(self) -> &'static str {
        match self {
            ConfigField::CellSize => "cell_size",
            ConfigField::QuantBits => "quant_bits",
            ConfigField::NMin => "n_min",
            ConfigField::EigenRatio => "eigen_ratio",
            ConfigField::NMax => "n_max",
            ConfigField::Hit => "hit",
            ConfigField::Miss => "miss",
            ConfigField::ClampMin => "clamp_min",
            ConfigField::ClampMax => "clamp_max",
            ConfigField::Lambda => "lambda",
            ConfigField::SeeThroughMiss => "see_through_miss",
            ConfigField::NoiseBase => "noise_base",
            ConfigField::NoiseQuadratic => "noise_quadratic",
            ConfigField::MaxRange => "max_range",
            ConfigField::RayCells => "max_range / cell_size",
            ConfigField::TopK => "top_k",
            ConfigField::VotesPerFrame => "votes_per_frame",
            ConfigField::RenderRadius => "render_radius",
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let what = match self {
            Error::InvalidConfig(field) => return write!(f, "invalid config: {field}"),
            Error::InvalidPose => "invalid pose: not finite, or its rotation is not orthonormal",
            Error::PoseOutOfRange => "the sensor position is outside the map's key range",
            Error::FrameTooLarge => "more points in one frame than MAX_FRAME_POINTS",
            Error::InvalidImage => "image sizes disagree with the camera, or the camera is invalid",
            Error::BufferTooSmall => "buffer too small",
            Error::SnapshotTruncated => "snapshot truncated (its length disagrees with its header)",
            Error::SnapshotMagic => "not a snapshot (wrong magic bytes)",
            Error::SnapshotVersion => "snapshot of a version this build cannot read",
            Error::SnapshotClasses => "snapshot of another class count",
            Error::SnapshotCapacity => "snapshot holds more than this map's capacity",
            Error::SnapshotChecksum => "snapshot CRC-32 mismatch",
            Error::SnapshotCorrupt => "snapshot content is corrupt (or its config is invalid)",
            Error::MapFull => "the merge needs more voxels or blocks than the map holds",
            Error::ConfigMismatch => "merge of maps or records with another config or class count",
            Error::RecordCorrupt => "record is corrupt or does not fit the map's config",
            Error::StreamChecksum => "record stream frame corrupt (COBS or CRC-32 mismatch)",
            Error::StreamOrder => {
                "record stream frame out of sequence (missing, repeated or reordered)"
            }
            Error::StreamTruncated => "record stream ended before its end frame",
        };
        f.write_str(what)
    }
}
