//! A co-processor's map spilling into the host: [`SpillingMap`] runs a [`Map`] of device
//! capacity (`--device V,B`) frame by frame, hands every evicted voxel and block to a
//! [`GlobalMap`], and counts what that costs on a link: records and bytes of the
//! COBS-framed record stream ([`sndt_core::StreamWriter`]) per frame. Its read-outs are the
//! merged global map ([`Spill::Merged`]) or the device map alone ([`Spill::DeviceOnly`]).

use super::global::GlobalMap;
use super::semantic_map::{boxed_map, integrate_frame_spilling, LabelView, SemanticMap};
use crate::dataset::frame::{Frame, LabelSource};
use anyhow::{anyhow, bail, Result};
use sndt_core::{Config, Map, Record, StreamWriter, STREAM_FRAME_BYTES};
use std::sync::{Mutex, OnceLock};

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
