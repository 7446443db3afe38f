//! A host map that grows: [`GlobalMap`] is the host's side of a bounded device map. It
//! merges what the device evicts (records) and, at the end, the device's own map, and never
//! evicts. It is the core's [`Map`] at one of three capacities ([`GlobalMap::TIERS`]); when a
//! merge finds the table full, the map moves into the next tier (one merge of the whole map
//! into an empty larger one, which copies it exactly) and the merge goes on. The smallest
//! tier is the tools' [`HostMap`], so a map that fits there is the same bytes as any other.

use super::semantic_map::{backproject, boxed_map, HostMap, LabelView};
use super::stream::{check_stream, merge_checked, StreamError, StreamSummary};
use crate::dataset::frame::Frame;
use anyhow::{anyhow, bail, Result};
use sndt_core::{Config, Error, Map, Record, SnapshotHeader};

/// The middle tier: 2^21 voxels, 2^19 blocks (~290 MiB).
pub type Tier1 = Map<{ 1 << 21 }, { 1 << 19 }, 40>;
/// The largest tier: 2^23 voxels, 2^21 blocks (~1.1 GiB).
pub type Tier2 = Map<{ 1 << 23 }, { 1 << 21 }, 40>;

/// A host map that grows by tiers instead of evicting (see the module doc).
///
/// ```
/// use sndt_core::{Config, Map, Record};
/// use sndt_host::mapping::GlobalMap;
/// let mut device: Map<64, 16, 40> = Map::new(Config::DEFAULT);
/// let p = [sndt_core::LabeledPoint::new(sndt_core::Point3::new(0.0, 0.0, 1.0), sndt_core::Labels::top1(2)); 3];
/// device.integrate(&sndt_core::Isometry3::identity(), &p).unwrap();
/// let mut global = GlobalMap::new(Config::DEFAULT).unwrap();
/// global.merge(&device).unwrap();
/// assert_eq!(global.checksum(), {
///     let mut same: Box<sndt_host::mapping::HostMap> = sndt_host::boxed_map(Config::DEFAULT).unwrap();
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
