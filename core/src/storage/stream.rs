//! The record stream: records framed for a byte link (a UART, a pipe, a file), so that a
//! co-processor can send what it evicts to a host that merges it. Each frame is
//! COBS-encoded (no zero byte inside) and ends with a zero byte, so a receiver finds frame
//! boundaries on its own and resynchronises after a lost byte; a CRC-32 per frame detects
//! corruption on the link.
//!
//! A frame before COBS encoding, all little-endian:
//!
//! | bytes | field |
//! |---|---|
//! | 1 | kind: 1 start, 2 block record, 3 voxel record, 4 end |
//! | 4 | sequence number: 0 for the start, then each frame's is the previous one's + 1 |
//! | 4 | config tag: CRC-32 of the sender's class count and config (as its snapshot header stores them) |
//! | n | payload: the start's snapshot header (88 bytes), a record (`record.rs`), or the end's frames, checksum, records and dropped records (4 x u32) |
//! | 4 | CRC-32 of everything before |
//!
//! A stream is one start, any number of records, one end. The start carries the sender's
//! snapshot header (its config, class count, capacities), from which a receiver builds a
//! map to merge into; the end, the frames the sender integrated, the CRC of its map at the
//! end, how many records it sent and how many its sink dropped. [`StreamReader`] refuses a
//! corrupt frame ([`Error::StreamChecksum`]), a missing, repeated or reordered one
//! ([`Error::StreamOrder`]), a record of another config ([`Error::ConfigMismatch`]) and a
//! stream without its end ([`Error::StreamTruncated`]).

use crate::crc::crc32;
use crate::error::Error;
use crate::storage::map::Map;
use crate::storage::record::{
    Record, RecordKind, Writer, BLOCK_RECORD_BYTES, VOXEL_RECORD_HEAD_BYTES,
};
use crate::storage::snapshot::{SnapshotHeader, SNAPSHOT_HEADER_BYTES};

/// Most bytes one framed frame takes on the link, delimiter included (a voxel record of
/// 254 classes: 13 + 47 + 254 bytes, plus COBS's 2 and the zero byte). A buffer this
/// large holds any frame for [`StreamWriter`] and [`StreamReader`].
pub const STREAM_FRAME_BYTES: usize = 320;

/// Bytes of a frame's kind, sequence number and config tag.
const FRAME_HEAD: usize = 9;
const START: u8 = 1;
const BLOCK: u8 = 2;
const VOXEL: u8 = 3;
const END: u8 = 4;

/// What a stream's end frame says about its sender.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StreamEnd {
    /// Frames the sender's map integrated.
    pub frames: u32,
    /// CRC-32 of the sender's map at the end ([`Map::checksum`]).
    pub checksum: u32,
    /// Record frames sent.
    pub records: u32,
    /// Records the sender evicted but could not send (refused by its sink).
    pub dropped: u32,
}

/// One frame read from a stream.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StreamItem<'a> {
    /// The sender's snapshot header: its config, class count and capacities.
    Start(SnapshotHeader),
    /// A block or voxel record, to merge in order.
    Record(Record<'a>),
    /// The last frame.
    End(StreamEnd),
}

/// The config tag of a class count and config: CRC-32 of a snapshot header that holds
/// only them.
fn config_tag(header: &SnapshotHeader) -> u32 {
    let only = SnapshotHeader {
        classes: header.classes,
        voxel_capacity: 0,
        block_capacity: 0,
        config: header.config,
        frames: 0,
        blocks: 0,
        voxels: 0,
    };
    let mut bytes = [0u8; SNAPSHOT_HEADER_BYTES];
    only.encode(&mut bytes);
    crc32(&bytes)
}

/// Writes a record stream, one frame at a time, into the caller's buffer.
///
/// ```
/// use sndt_core::*;
/// let mut map: Map<64, 16, 4> = Map::new(Config::DEFAULT);
/// let p = [LabeledPoint::new(Point3::new(0.0, 0.0, 1.0), Labels::top1(2)); 3];
/// map.integrate(&Isometry3::identity(), &p).unwrap();
///
/// // The sender: a start, every record of its map, an end.
/// let mut link = Vec::new();
/// let mut buf = [0u8; STREAM_FRAME_BYTES];
/// let (mut out, n) = StreamWriter::start(&map, &mut buf).unwrap();
/// link.extend_from_slice(&buf[..n]);
/// map.write_records(&mut |r: Record<'_>| match out.record(r, &mut buf) {
///     Ok(n) => { link.extend_from_slice(&buf[..n]); true }
///     Err(_) => false,
/// });
/// let n = out.end(&map, 0, &mut buf).unwrap();
/// link.extend_from_slice(&buf[..n]);
///
/// // The receiver: frames end at zero bytes.
/// let mut copy: Map<64, 16, 4> = Map::new(Config::DEFAULT);
/// let mut reader = StreamReader::new();
/// let mut scratch = [0u8; STREAM_FRAME_BYTES];
/// for frame in link.split(|&b| b == 0).filter(|f| !f.is_empty()) {
///     match reader.read(frame, &mut scratch).unwrap() {
///         StreamItem::Start(h) => assert_eq!(h.config, *copy.config()),
///         StreamItem::Record(r) => copy.merge_record(r).unwrap(),
///         StreamItem::End(end) => copy.add_frames(end.frames),
///     }
/// }
/// assert_eq!(reader.finish().unwrap().checksum, map.checksum());
/// assert_eq!(copy.checksum(), map.checksum());
/// ```
#[derive(Clone, Copy, Debug)]
pub struct StreamWriter {
    next: u32,
    tag: u32,
    records: u32,
    classes: u16,
}

impl StreamWriter {
    /// Starts a stream for `map`'s config: writes the start frame into `out` and returns
    /// the writer and the frame's length ([`Error::BufferTooSmall`] below
    /// [`STREAM_FRAME_BYTES`] may not fit).
    pub fn start<const V: usize, const B: usize, const C: usize>(
        map: &Map<V, B, C>,
        out: &mut [u8],
    ) -> Result<(StreamWriter, usize), Error> {
        let header = map.snapshot_header();
        let mut w = StreamWriter {
            next: 0,
            tag: config_tag(&header),
            records: 0,
            classes: C as u16,
        };
        let mut payload = [0u8; SNAPSHOT_HEADER_BYTES];
        header.encode(&mut payload);
        let n = w.frame(START, &payload, out)?;
        Ok((w, n))
    }

    /// Writes one record's frame into `out` and returns its length. A record that is not
    /// one of this map's (wrong length) gives [`Error::RecordCorrupt`].
    pub fn record(&mut self, record: Record<'_>, out: &mut [u8]) -> Result<usize, Error> {
        let (kind, len) = match record.kind {
            RecordKind::Block => (BLOCK, BLOCK_RECORD_BYTES),
            RecordKind::Voxel => (VOXEL, VOXEL_RECORD_HEAD_BYTES + self.classes as usize),
        };
        if record.bytes.len() != len {
            return Err(Error::RecordCorrupt);
        }
        let n = self.frame(kind, record.bytes, out)?;
        self.records += 1;
        Ok(n)
    }

    /// Writes the end frame into `out`: `map`'s frame count and checksum, the records sent
    /// and `dropped`, the records its sink refused (from the frame reports).
    pub fn end<const V: usize, const B: usize, const C: usize>(
        &mut self,
        map: &Map<V, B, C>,
        dropped: u32,
        out: &mut [u8],
    ) -> Result<usize, Error> {
        let mut payload = [0u8; 16];
        let fields = [map.stats().frames, map.checksum(), self.records, dropped];
        for (dst, v) in payload.chunks_exact_mut(4).zip(fields) {
            dst.copy_from_slice(&v.to_le_bytes());
        }
        self.frame(END, &payload, out)
    }

    /// One frame: head, payload, CRC, COBS-encoded, then the zero delimiter.
    fn frame(&mut self, kind: u8, payload: &[u8], out: &mut [u8]) -> Result<usize, Error> {
        let mut body = [0u8; STREAM_FRAME_BYTES];
        let mut w = Writer {
            buf: &mut body,
            pos: 0,
        };
        w.put(&[kind]);
        w.put(&self.next.to_le_bytes());
        w.put(&self.tag.to_le_bytes());
        w.put(payload);
        let len = w.pos;
        if len != FRAME_HEAD + payload.len() {
            return Err(Error::BufferTooSmall);
        }
        let sum = crc32(w.written());
        let crc = body.get_mut(len..len + 4).ok_or(Error::BufferTooSmall)?;
        crc.copy_from_slice(&sum.to_le_bytes());
        let n = cobs::try_encode(body.get(..len + 4).unwrap_or(&[]), out)
            .map_err(|_| Error::BufferTooSmall)?;
        *out.get_mut(n).ok_or(Error::BufferTooSmall)? = 0;
        self.next = self.next.wrapping_add(1);
        Ok(n + 1)
    }
}

/// Reads a record stream one frame at a time, checking each frame's CRC, its place in the
/// sequence and its config. Frames are the bytes between zero delimiters (a trailing zero
/// is allowed). See [`StreamWriter`] for a round trip.
///
/// ```
/// use sndt_core::*;
/// let map: Map<64, 16, 4> = Map::new(Config::DEFAULT);
/// let mut buf = [0u8; STREAM_FRAME_BYTES];
/// let (_, n) = StreamWriter::start(&map, &mut buf).unwrap();
/// let mut scratch = [0u8; STREAM_FRAME_BYTES];
/// let mut flipped = buf;
/// flipped[20] ^= 0x40; // one bit flipped on the link
/// assert_eq!(StreamReader::new().read(&flipped[..n], &mut scratch), Err(Error::StreamChecksum));
/// let mut reader = StreamReader::new();
/// assert!(matches!(reader.read(&buf[..n], &mut scratch), Ok(StreamItem::Start(_))));
/// // The same frame again is a repeat.
/// assert_eq!(reader.read(&buf[..n], &mut scratch), Err(Error::StreamOrder));
/// assert_eq!(reader.finish(), Err(Error::StreamTruncated));
/// ```
#[derive(Clone, Copy, Debug, Default)]
pub struct StreamReader {
    next: u32,
    header: Option<SnapshotHeader>,
    tag: u32,
    end: Option<StreamEnd>,
    records: u32,
}

impl StreamReader {
    /// A reader expecting a stream's start.
    pub const fn new() -> StreamReader {
        StreamReader {
            next: 0,
            header: None,
            tag: 0,
            end: None,
            records: 0,
        }
    }

    /// The sender's header, once the start was read.
    pub fn header(&self) -> Option<SnapshotHeader> {
        self.header
    }

    /// Decodes one frame (COBS bytes, with or without its zero delimiter) into `scratch`
    /// and checks it. Errors leave the reader where it was:
    ///
    /// - [`Error::StreamChecksum`]: not COBS, too long, or a CRC mismatch;
    /// - [`Error::StreamOrder`]: not the next sequence number, a record before the start,
    ///   anything after the end, an unknown kind, an end whose record count disagrees;
    /// - [`Error::ConfigMismatch`]: a record or end with another config tag;
    /// - [`Error::RecordCorrupt`]: a record of the wrong length for its kind and the
    ///   sender's class count;
    /// - a start whose header does not decode: the error of [`SnapshotHeader::read`].
    ///
    /// The start's config and class count are returned as sent: whether the receiver can
    /// use them ([`Config::validate`](crate::Config::validate), its own `C`) is its
    /// check, as the host's `check_stream` does.
    pub fn read<'s>(
        &mut self,
        frame: &[u8],
        scratch: &'s mut [u8; STREAM_FRAME_BYTES],
    ) -> Result<StreamItem<'s>, Error> {
        let frame = match frame.split_last() {
            Some((0, rest)) => rest,
            _ => frame,
        };
        if frame.is_empty() || frame.len() > STREAM_FRAME_BYTES {
            return Err(Error::StreamChecksum);
        }
        let len = cobs::decode(frame, scratch)
            .map_err(|_| Error::StreamChecksum)?
            .frame_size();
        let body: &'s [u8] = scratch.get(..len).ok_or(Error::StreamChecksum)?;
        let (data, crc) = body.split_last_chunk::<4>().ok_or(Error::StreamChecksum)?;
        if crc32(data) != u32::from_le_bytes(*crc) {
            return Err(Error::StreamChecksum);
        }
        let (head, payload) = data
            .split_at_checked(FRAME_HEAD)
            .ok_or(Error::StreamChecksum)?;
        let kind = head.first().copied().unwrap_or(0);
        let (seq, tag) = (le_u32(head, 1), le_u32(head, 5));
        if seq != self.next || self.end.is_some() {
            return Err(Error::StreamOrder);
        }
        let item = match (kind, self.header) {
            (START, None) => {
                let h = SnapshotHeader::read(payload)?;
                if payload.len() != SNAPSHOT_HEADER_BYTES || config_tag(&h) != tag {
                    return Err(Error::ConfigMismatch);
                }
                self.header = Some(h);
                self.tag = tag;
                StreamItem::Start(h)
            }
            (BLOCK | VOXEL | END, Some(_)) if tag != self.tag => {
                return Err(Error::ConfigMismatch);
            }
            (BLOCK, Some(_)) => StreamItem::Record(Record {
                kind: RecordKind::Block,
                bytes: payload,
            }),
            (VOXEL, Some(_)) => StreamItem::Record(Record {
                kind: RecordKind::Voxel,
                bytes: payload,
            }),
            (END, Some(_)) => {
                let end = StreamEnd {
                    frames: le_u32(payload, 0),
                    checksum: le_u32(payload, 4),
                    records: le_u32(payload, 8),
                    dropped: le_u32(payload, 12),
                };
                if payload.len() != 16 || end.records != self.records {
                    return Err(Error::StreamOrder);
                }
                self.end = Some(end);
                StreamItem::End(end)
            }
            _ => return Err(Error::StreamOrder),
        };
        if let StreamItem::Record(r) = item {
            let want = match r.kind {
                RecordKind::Block => BLOCK_RECORD_BYTES,
                RecordKind::Voxel => {
                    let classes = self.header.map_or(0, |h| h.classes as usize);
                    VOXEL_RECORD_HEAD_BYTES + classes
                }
            };
            if r.bytes.len() != want {
                return Err(Error::RecordCorrupt);
            }
            self.records += 1;
        }
        self.next = self.next.wrapping_add(1);
        Ok(item)
    }

    /// The end frame's fields, or [`Error::StreamTruncated`] if the end was not read.
    pub fn finish(&self) -> Result<StreamEnd, Error> {
        self.end.ok_or(Error::StreamTruncated)
    }
}

/// The little-endian `u32` at byte `at` of `bytes` (0 past the end).
fn le_u32(bytes: &[u8], at: usize) -> u32 {
    match bytes.get(at..at + 4) {
        Some(&[a, b, c, d]) => u32::from_le_bytes([a, b, c, d]),
        _ => 0,
    }
}
