//! A host map that grows, and a co-processor's map spilling into it.
//!
//! [`GlobalMap`] is the host's side of a bounded device map: it merges what the device
//! evicts (records) and, at the end, the device's own map, and never evicts. It is the
//! core's [`Map`] at one of three capacities ([`GlobalMap::TIERS`]); when a merge finds
//! the table full, the map moves into the next tier (one merge of the whole map into an
//! empty larger one, which copies it exactly) and the merge goes on. The smallest tier is
//! the tools' [`HostMap`], so a map that fits there is the same bytes as any other.
//!
//! [`SpillingMap`] runs a [`Map`] of device capacity (`--device V,B`) frame by frame, hands
//! every evicted voxel and block to the global map, and counts what that costs on a link:
//! records and bytes of the COBS-framed record stream ([`sndt_core::StreamWriter`]) per
//! frame. Its read-outs are the merged global map ([`Spill::Merged`]) or the device map
//! alone ([`Spill::DeviceOnly`]).

use crate::dataset::frame::{Frame, LabelSource};
use crate::semantic_map::{
    backproject, boxed_map, integrate_frame_spilling, HostMap, LabelView, SemanticMap,
};
use anyhow::{anyhow, bail, Result};
use sndt_core::{
    Config, Crc32, Error, Map, Record, SnapshotHeader, StreamEnd, StreamItem, StreamReader,
    StreamWriter, STREAM_FRAME_BYTES,
};
use std::fmt;
use std::sync::{Mutex, OnceLock};

/// The middle tier: 2^21 voxels, 2^19 blocks (~290 MiB).
pub type Tier1 = Map<{ 1 << 21 }, { 1 << 19 }, 40>;
/// The largest tier: 2^23 voxels, 2^21 blocks (~1.1 GiB).
pub type Tier2 = Map<{ 1 << 23 }, { 1 << 21 }, 40>;

/// A host map that grows by tiers instead of evicting (see the module doc).
///
/// ```
/// use sndt_core::{Config, Map, Record};
/// use sndt_host::global_map::GlobalMap;
/// let mut device: Map<64, 16, 40> = Map::new(Config::DEFAULT);
/// let p = [sndt_core::LabeledPoint::new(sndt_core::Point3::new(0.0, 0.0, 1.0), sndt_core::Labels::top1(2)); 3];
/// device.integrate(&sndt_core::Isometry3::identity(), &p).unwrap();
/// let mut global = GlobalMap::new(Config::DEFAULT).unwrap();
/// global.merge(&device).unwrap();
/// assert_eq!(global.checksum(), {
///     let mut same: Box<sndt_host::semantic_map::HostMap> = sndt_host::boxed_map(Config::DEFAULT).unwrap();
///     same.merge(&device).unwrap();
///     same.checksum()
/// });
/// ```
pub enum GlobalMap {
    /// [`HostMap`]: 2^19 voxels, 2^17 blocks.
    Tier0(Box<HostMap>),
    /// [`Tier1`].
    Tier1(Box<Tier1>),
    /// [`Tier2`].
    Tier2(Box<Tier2>),
}

/// `$body` with `$m` bound to the map of whichever tier `$g` is.
macro_rules! each_tier {
    ($g:expr, $m:ident => $body:expr) => {
        match $g {
            GlobalMap::Tier0($m) => $body,
            GlobalMap::Tier1($m) => $body,
            GlobalMap::Tier2($m) => $body,
        }
    };
}

impl GlobalMap {
    /// The tiers' (voxels, blocks) capacities, smallest first.
    pub const TIERS: [(usize, usize); 3] =
        [(1 << 19, 1 << 17), (1 << 21, 1 << 19), (1 << 23, 1 << 21)];

    /// An empty map of the smallest tier.
    pub fn new(config: Config) -> Result<GlobalMap> {
        Ok(GlobalMap::Tier0(
            boxed_map(config).map_err(|e| anyhow!("config: {e}"))?,
        ))
    }

    /// A snapshot (of any capacity) read into the smallest tier that holds it.
    pub fn from_snapshot(bytes: &[u8]) -> Result<GlobalMap> {
        let h = SnapshotHeader::read(bytes).map_err(|e| anyhow!("not a snapshot: {e}"))?;
        let (v, b) = (h.voxels as usize, h.blocks as usize);
        let tier = GlobalMap::TIERS
            .iter()
            .position(|&(tv, tb)| v <= tv && b <= tb)
            .ok_or_else(|| {
                anyhow!("snapshot of {v} voxels and {b} blocks: larger than every tier")
            })?;
        let mut g = GlobalMap::new(Config::DEFAULT)?;
        while g.tier() < tier {
            g.grow()?;
        }
        each_tier!(&mut g, m => m.read_snapshot(bytes)).map_err(|e| anyhow!("{e}"))?;
        Ok(g)
    }

    /// Which tier (0..=2) the map is in.
    pub fn tier(&self) -> usize {
        match self {
            GlobalMap::Tier0(_) => 0,
            GlobalMap::Tier1(_) => 1,
            GlobalMap::Tier2(_) => 2,
        }
    }

    /// Merges one record, growing into the next tier when the table is full.
    pub fn merge_record(&mut self, record: Record<'_>) -> Result<()> {
        loop {
            match each_tier!(self, m => m.merge_record(record)) {
                Err(Error::MapFull) => self.grow()?,
                other => return other.map_err(|e| anyhow!("merge: {e}")),
            }
        }
    }

    /// Merges a whole map (its records and frames), growing as needed.
    pub fn merge<const V: usize, const B: usize>(&mut self, other: &Map<V, B, 40>) -> Result<()> {
        loop {
            match each_tier!(self, m => m.merge(other)) {
                Err(Error::MapFull) => self.grow()?,
                other => return other.map_err(|e| anyhow!("merge: {e}")),
            }
        }
    }

    /// Merges another global map.
    pub fn merge_global(&mut self, other: &GlobalMap) -> Result<()> {
        each_tier!(other, o => self.merge(o.as_ref()))
    }

    /// Counts frames merged as records (a stream's end).
    pub fn add_frames(&mut self, frames: u32) {
        each_tier!(self, m => m.add_frames(frames));
    }

    /// Moves the map into the next tier.
    fn grow(&mut self) -> Result<()> {
        let config = *self.config();
        let next = match self {
            GlobalMap::Tier0(m) => {
                let mut n: Box<Tier1> = boxed_map(config).map_err(|e| anyhow!("{e}"))?;
                n.merge(m.as_ref()).map_err(|e| anyhow!("growing: {e}"))?;
                GlobalMap::Tier1(n)
            }
            GlobalMap::Tier1(m) => {
                let mut n: Box<Tier2> = boxed_map(config).map_err(|e| anyhow!("{e}"))?;
                n.merge(m.as_ref()).map_err(|e| anyhow!("growing: {e}"))?;
                GlobalMap::Tier2(n)
            }
            GlobalMap::Tier2(_) => bail!(
                "the global map is full at its largest tier ({} voxels, {} blocks)",
                GlobalMap::TIERS[2].0,
                GlobalMap::TIERS[2].1
            ),
        };
        *self = next;
        Ok(())
    }

    /// The map's config.
    pub fn config(&self) -> &Config {
        each_tier!(self, m => m.config())
    }

    /// CRC-32 of its snapshot.
    pub fn checksum(&self) -> u32 {
        each_tier!(self, m => m.checksum())
    }

    /// Surface voxels.
    pub fn len(&self) -> usize {
        each_tier!(self, m => m.len())
    }

    /// True when nothing was observed.
    pub fn is_empty(&self) -> bool {
        each_tier!(self, m => m.is_empty())
    }

    /// Occupancy blocks.
    pub fn block_count(&self) -> usize {
        each_tier!(self, m => m.block_count())
    }

    /// Frames integrated into what was merged.
    pub fn frames(&self) -> u32 {
        each_tier!(self, m => m.stats().frames)
    }

    /// Bytes the map holds (its tier's fixed size).
    pub fn memory_bytes(&self) -> usize {
        each_tier!(self, m => core::mem::size_of_val(m.as_ref()))
    }

    /// The map's snapshot bytes.
    pub fn snapshot(&self) -> Result<Vec<u8>> {
        each_tier!(self, m => {
            let mut buf = vec![0u8; m.snapshot_len()];
            let n = m.write_snapshot(&mut buf).map_err(|e| anyhow!("snapshot: {e}"))?;
            buf.truncate(n);
            Ok(buf)
        })
    }
}

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

impl GlobalMap {
    /// Checks a whole record stream ([`check_stream`]), then merges its records in order
    /// and its end frame's frame count. Refused, with nothing merged, when the stream is
    /// bad or its config is not the map's.
    pub fn merge_stream(&mut self, bytes: &[u8]) -> Result<StreamSummary, StreamError> {
        let summary = check_stream(bytes)?;
        if summary.header.config != *self.config() {
            return Err(StreamError::Frame {
                index: 0,
                offset: 0,
                error: Error::ConfigMismatch,
            });
        }
        // Only a map full at its largest tier fails here, after the records before it.
        merge_checked(bytes, |r| self.merge_record(r).map_err(|_| Error::MapFull))?;
        self.add_frames(summary.end.frames);
        Ok(summary)
    }
}

impl LabelView for GlobalMap {
    fn render_frame(&self, frame: &Frame) -> Result<Vec<u8>> {
        each_tier!(self, m => backproject(m.as_ref(), frame))
    }
}

/// Which map of a [`SpillingMap`] to read out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Spill {
    /// The global map with the device's final map merged in.
    Merged,
    /// The device map alone, as the co-processor holds it.
    DeviceOnly,
}

/// What spilling cost, over a run.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct SpillStats {
    /// Records the device evicted and the host merged.
    pub records: u64,
    /// Records lost (a sink refused them; 0 on the host, which takes everything).
    pub dropped: u64,
    /// Points the device map dropped: full, and nothing it could evict (a frame that needs
    /// more blocks or voxels than the device holds).
    pub dropped_points: u64,
    /// Free-space updates the device map dropped for the same reason.
    pub dropped_misses: u64,
    /// Bytes of the framed record stream each frame sent.
    pub bytes_per_frame: Vec<u64>,
    /// Bytes of the stream's start, the device's final map as records, and its end.
    pub final_bytes: u64,
}

impl SpillStats {
    /// Mean stream bytes per frame.
    pub fn mean_bytes(&self) -> f64 {
        self.bytes_per_frame.iter().sum::<u64>() as f64 / self.bytes_per_frame.len().max(1) as f64
    }

    /// Largest stream bytes of one frame.
    pub fn max_bytes(&self) -> u64 {
        self.bytes_per_frame.iter().copied().max().unwrap_or(0)
    }
}

/// A device-capacity map spilling into a [`GlobalMap`] (see the module doc).
pub struct SpillingMap<const V: usize, const B: usize> {
    device: Box<Map<V, B, 40>>,
    global: Mutex<Option<GlobalMap>>,
    merged: OnceLock<Result<GlobalMap, String>>,
    writer: StreamWriter,
    /// Records and bytes so far.
    pub stats: SpillStats,
}

impl<const V: usize, const B: usize> SpillingMap<V, B> {
    /// An empty device map and global map of `config`.
    pub fn new(config: Config) -> Result<Self> {
        let device: Box<Map<V, B, 40>> = boxed_map(config).map_err(|e| anyhow!("config: {e}"))?;
        let mut buf = [0u8; STREAM_FRAME_BYTES];
        let (writer, start) =
            StreamWriter::start(device.as_ref(), &mut buf).map_err(|e| anyhow!("stream: {e}"))?;
        Ok(SpillingMap {
            device,
            global: Mutex::new(Some(GlobalMap::new(config)?)),
            merged: OnceLock::new(),
            writer,
            stats: SpillStats {
                final_bytes: start as u64,
                ..SpillStats::default()
            },
        })
    }

    /// The device map.
    pub fn device(&self) -> &Map<V, B, 40> {
        &self.device
    }

    /// The global map with the device's final map merged in (done once, at the first
    /// call; no frame can be integrated afterwards).
    pub fn merged(&self) -> Result<&GlobalMap> {
        self.merged
            .get_or_init(|| {
                let taken = self.global.lock().map_err(|e| e.to_string())?.take();
                let mut g = taken.ok_or("the global map is gone")?;
                g.merge(self.device.as_ref()).map_err(|e| e.to_string())?;
                Ok(g)
            })
            .as_ref()
            .map_err(|e| anyhow!("{e}"))
    }

    /// The stream bytes of the device's final map as records and the end frame, as the
    /// firmware sends them after its last frame.
    pub fn final_stream_bytes(&mut self) -> u64 {
        let mut buf = [0u8; STREAM_FRAME_BYTES];
        let mut bytes = 0u64;
        let writer = &mut self.writer;
        self.device.write_records(&mut |r: Record<'_>| {
            bytes += writer.record(r, &mut buf).unwrap_or(0) as u64;
            true
        });
        bytes += writer
            .end(self.device.as_ref(), self.stats.dropped as u32, &mut buf)
            .unwrap_or(0) as u64;
        bytes
    }
}

impl<const V: usize, const B: usize> SemanticMap for SpillingMap<V, B> {
    type Readout = Spill;

    /// One frame into the device map; what it evicts goes to the global map.
    fn integrate_frame(&mut self, frame: &Frame, labels: LabelSource, stride: u32) -> Result<()> {
        if self.merged.get().is_some() {
            bail!("{}: the spilling map was already read out", frame.id);
        }
        let mut guard = self.global.lock().map_err(|_| anyhow!("global map lock"))?;
        let global = guard
            .as_mut()
            .ok_or_else(|| anyhow!("the global map is gone"))?;
        let mut buf = [0u8; STREAM_FRAME_BYTES];
        let mut bytes = 0u64;
        let mut failure = None;
        let writer = &mut self.writer;
        let mut sink = |r: Record<'_>| {
            bytes += writer.record(r, &mut buf).unwrap_or(0) as u64;
            match global.merge_record(r) {
                Ok(()) => true,
                Err(e) => {
                    failure.get_or_insert(e);
                    false
                }
            }
        };
        let report =
            integrate_frame_spilling(self.device.as_mut(), frame, labels, stride, Some(&mut sink))?;
        if let Some(e) = failure {
            return Err(e.context(format!("{}: spilling", frame.id)));
        }
        self.stats.records += report.records_spilled as u64;
        self.stats.dropped += report.records_dropped as u64;
        self.stats.dropped_points += report.dropped_points as u64;
        self.stats.dropped_misses += report.dropped_misses as u64;
        self.stats.bytes_per_frame.push(bytes);
        Ok(())
    }

    fn prepare(&self, readout: Spill) -> Box<dyn LabelView + '_> {
        match readout {
            Spill::DeviceOnly => Box::new(self.device.as_ref()),
            Spill::Merged => match self.merged() {
                Ok(g) => Box::new(g),
                Err(e) => Box::new(Failed(e.to_string())),
            },
        }
    }

    /// Device map plus the global map's tier.
    fn memory_bytes(&self) -> usize {
        let global = match self.merged.get() {
            Some(Ok(g)) => g.memory_bytes(),
            _ => self
                .global
                .lock()
                .ok()
                .and_then(|g| g.as_ref().map(GlobalMap::memory_bytes))
                .unwrap_or(0),
        };
        core::mem::size_of::<Map<V, B, 40>>() + global
    }

    /// Surface voxels of the merged map (of the device map before the read-out).
    fn voxel_count(&self) -> usize {
        match self.merged.get() {
            Some(Ok(g)) => g.len(),
            _ => self.device.len(),
        }
    }
}

/// A read-out that could not be prepared: every render fails with the reason.
struct Failed(String);

impl LabelView for Failed {
    fn render_frame(&self, frame: &Frame) -> Result<Vec<u8>> {
        bail!("{}: {}", frame.id, self.0)
    }
}

/// The device capacities `--device V,B` offers (each is its own compiled map type).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeviceCapacity {
    /// 1,024 voxels, 128 blocks (~120 KiB).
    Small,
    /// 4,096 voxels, 512 blocks: the Cortex-M4F example's map (~480 KiB).
    Firmware,
    /// 16,384 voxels, 2,048 blocks (~1.9 MiB).
    Large,
}

impl DeviceCapacity {
    /// Every capacity, as (capacity, voxels, blocks).
    pub const ALL: [(DeviceCapacity, usize, usize); 3] = [
        (DeviceCapacity::Small, 1024, 128),
        (DeviceCapacity::Firmware, 4096, 512),
        (DeviceCapacity::Large, 16384, 2048),
    ];

    /// `V,B`, one of [`DeviceCapacity::ALL`].
    ///
    /// ```
    /// use sndt_host::global_map::DeviceCapacity;
    /// assert_eq!(DeviceCapacity::parse("4096,512").unwrap(), DeviceCapacity::Firmware);
    /// assert!(DeviceCapacity::parse("4000,512").is_err());
    /// ```
    pub fn parse(s: &str) -> Result<DeviceCapacity, String> {
        let parsed = s.split_once(',').and_then(|(v, b)| {
            Some((
                v.trim().parse::<usize>().ok()?,
                b.trim().parse::<usize>().ok()?,
            ))
        });
        let offered = || {
            DeviceCapacity::ALL
                .iter()
                .map(|(_, v, b)| format!("{v},{b}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        match parsed {
            Some((v, b)) => DeviceCapacity::ALL
                .iter()
                .find(|&&(_, cv, cb)| (cv, cb) == (v, b))
                .map(|&(c, _, _)| c)
                .ok_or_else(|| {
                    format!(
                        "no device map of {v} voxels and {b} blocks; offered: {}",
                        offered()
                    )
                }),
            None => Err(format!("expected VOXELS,BLOCKS (one of {})", offered())),
        }
    }

    /// (voxels, blocks).
    pub fn capacity(self) -> (usize, usize) {
        DeviceCapacity::ALL
            .iter()
            .find(|(c, _, _)| *c == self)
            .map_or((0, 0), |&(_, v, b)| (v, b))
    }
}

/// `$body` with `$M` the [`SpillingMap`] type of capacity `$cap`.
#[macro_export]
macro_rules! with_device {
    ($cap:expr, $M:ident => $body:expr) => {
        match $cap {
            $crate::global_map::DeviceCapacity::Small => {
                type $M = $crate::global_map::SpillingMap<1024, 128>;
                $body
            }
            $crate::global_map::DeviceCapacity::Firmware => {
                type $M = $crate::global_map::SpillingMap<4096, 512>;
                $body
            }
            $crate::global_map::DeviceCapacity::Large => {
                type $M = $crate::global_map::SpillingMap<16384, 2048>;
                $body
            }
        }
    };
}
