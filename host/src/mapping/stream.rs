//! Checking a device's record stream before anything of it is merged: [`check_stream`]
//! reads a whole COBS-framed stream ([`sndt_core::StreamReader`]) and refuses it with a
//! [`StreamError`] (the frame and byte offset) if any frame is corrupt, out of order, of
//! another config, or holds a record the sender's config cannot hold; [`merge_checked`]
//! then merges an accepted stream's records in order.

use sndt_core::{
    Crc32, Error, Map, Record, SnapshotHeader, StreamEnd, StreamItem, StreamReader,
    STREAM_FRAME_BYTES,
};
use std::fmt;

/// Why a record stream was refused. Nothing is merged from a refused stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StreamError {
    /// No frame at all.
    Empty,
    /// Frame `index` (at byte `offset`) is corrupt ([`sndt_core::Error::StreamChecksum`]),
    /// out of order: missing, repeated or reordered ([`sndt_core::Error::StreamOrder`]), of
    /// another config ([`sndt_core::Error::ConfigMismatch`]), or holds a record the
    /// sender's config cannot hold ([`sndt_core::Error::RecordCorrupt`]).
    Frame {
        /// Frame number, from 0.
        index: usize,
        /// Byte offset of the frame in the stream.
        offset: usize,
        /// What is wrong with it.
        error: sndt_core::Error,
    },
    /// The stream ends inside a frame (bytes after the last zero delimiter).
    Unterminated {
        /// Byte offset of the cut frame.
        offset: usize,
    },
    /// The stream ends before its end frame.
    Truncated {
        /// Frames read.
        frames: usize,
    },
    /// The sender's map has another class count than the global map.
    Classes(u16),
    /// The sender's config is not a valid config.
    Config(sndt_core::Error),
    /// The map merged into has no room for the stream's records.
    MapFull {
        /// The record that did not fit, from 0.
        record: usize,
    },
}

impl fmt::Display for StreamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StreamError::Empty => write!(f, "record stream: empty"),
            StreamError::Frame {
                index,
                offset,
                error,
            } => write!(f, "record stream: frame {index} (byte {offset}): {error}"),
            StreamError::Unterminated { offset } => write!(
                f,
                "record stream: cut off inside the frame at byte {offset} (no zero delimiter)"
            ),
            StreamError::Truncated { frames } => {
                write!(f, "record stream: no end frame after {frames} frames")
            }
            StreamError::Classes(c) => write!(
                f,
                "record stream: the sender's map has {c} classes, the host's maps 40"
            ),
            StreamError::Config(e) => write!(f, "record stream: the sender's config: {e}"),
            StreamError::MapFull { record } => {
                write!(f, "record stream: record {record} does not fit the map")
            }
        }
    }
}

impl std::error::Error for StreamError {}

/// A stream [`check_stream`] accepted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StreamSummary {
    /// The sender's snapshot header (config, class count, capacities).
    pub header: SnapshotHeader,
    /// The end frame: the sender's frames, map checksum, records sent and dropped.
    pub end: StreamEnd,
    /// Bytes of the stream.
    pub bytes: usize,
    /// CRC-32 of the stream's bytes.
    pub crc: u32,
    /// Voxel records.
    pub voxels: u32,
    /// Block records.
    pub blocks: u32,
}

/// The frames of a stream, each with its byte offset: the bytes between zero delimiters
/// (empty ones skipped); `Err` if bytes follow the last delimiter.
fn frames(bytes: &[u8]) -> Result<Vec<(usize, &[u8])>, StreamError> {
    let mut out = Vec::new();
    let mut offset = 0;
    for piece in bytes.split_inclusive(|&b| b == 0) {
        if piece.last() != Some(&0) {
            return Err(StreamError::Unterminated { offset });
        }
        if piece.len() > 1 {
            out.push((offset, piece));
        }
        offset += piece.len();
    }
    Ok(out)
}

/// Reads the whole stream and checks it, merging nothing: every frame as
/// [`StreamReader`] does, every record against the sender's config as
/// [`Map::merge_record`] would, and that the stream ends with its end frame.
pub fn check_stream(bytes: &[u8]) -> Result<StreamSummary, StreamError> {
    let frames = frames(bytes)?;
    if frames.is_empty() {
        return Err(StreamError::Empty);
    }
    let mut reader = StreamReader::new();
    let mut scratch = [0u8; STREAM_FRAME_BYTES];
    // Records are checked against a map of the sender's config (room is not checked).
    let mut checker: Option<Map<1, 1, 40>> = None;
    let (mut voxels, mut blocks) = (0, 0);
    for (index, &(offset, frame)) in frames.iter().enumerate() {
        let at = |error| StreamError::Frame {
            index,
            offset,
            error,
        };
        match reader.read(frame, &mut scratch).map_err(at)? {
            StreamItem::Start(h) => {
                if h.classes != 40 {
                    return Err(StreamError::Classes(h.classes));
                }
                checker = Some(Map::try_new(h.config).map_err(StreamError::Config)?);
            }
            StreamItem::Record(r) => {
                let map = checker.as_ref().ok_or(at(sndt_core::Error::StreamOrder))?;
                map.check_record(r).map_err(at)?;
                match r.kind {
                    sndt_core::RecordKind::Voxel => voxels += 1,
                    sndt_core::RecordKind::Block => blocks += 1,
                }
            }
            StreamItem::End(_) => {}
        }
    }
    let end = reader.finish().map_err(|_| StreamError::Truncated {
        frames: frames.len(),
    })?;
    let header = reader
        .header()
        .ok_or(StreamError::Truncated { frames: 0 })?;
    let mut crc = Crc32::new();
    crc.update(bytes);
    Ok(StreamSummary {
        header,
        end,
        bytes: bytes.len(),
        crc: crc.finish(),
        voxels,
        blocks,
    })
}

/// Merges the records of a stream [`check_stream`] accepted, in order, through `merge`
/// (a map's `merge_record`); the caller adds the end frame's frame count.
pub fn merge_checked(
    bytes: &[u8],
    mut merge: impl FnMut(Record<'_>) -> Result<(), Error>,
) -> Result<(), StreamError> {
    let mut reader = StreamReader::new();
    let mut scratch = [0u8; STREAM_FRAME_BYTES];
    let mut record = 0;
    for (index, (offset, frame)) in frames(bytes)?.into_iter().enumerate() {
        let item = reader
            .read(frame, &mut scratch)
            .map_err(|error| StreamError::Frame {
                index,
                offset,
                error,
            })?;
        if let StreamItem::Record(r) = item {
            merge(r).map_err(|_| StreamError::MapFull { record })?;
            record += 1;
        }
    }
    Ok(())
}
