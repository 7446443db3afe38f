//! The crate's one error type.

/// Everything that can go wrong. Small and `Copy`; bad input never panics and never loses
/// what is already in the map.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// A [`crate::Config`] field is out of its documented range.
    InvalidConfig,
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
    /// Snapshot: CRC matches but the content breaks an invariant.
    SnapshotCorrupt,
}
