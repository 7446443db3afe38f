//! The spill run of the test vector: a co-processor's map that overflows, and the host
//! that keeps what it evicts.
//!
//! The firmware integrates the vector's 4 frames again, into its `Map<4096, 512, 40>` at
//! [`SPILL_CELL`] (9 cm: the 4 frames overflow the map, which evicts thousands of voxels
//! and hundreds of blocks), and sends every evicted voxel and block over its UART as the core's record
//! stream (`sndt_core::StreamWriter`: one COBS frame per record, each with a CRC-32, a
//! sequence number and the config's tag, ended by a zero byte), then its last map
//! (`Map::write_records`) and the end frame. On the host:
//!
//! - [`merge_stream`] checks the whole stream first ([`check_stream`]: every frame's CRC,
//!   order and config, every record against the config, the end frame present and last;
//!   a typed [`StreamError`] otherwise) and only then merges it into a [`GlobalMap`],
//!   adding the end frame's frame count;
//! - [`own_run`] does the same run itself: the same device map and config on the same
//!   frames, each evicted record merged straight into a [`GlobalMap`], then
//!   `global.merge(&device)`. It also writes the stream the firmware should have sent.
//!
//! Both give the same global map, so the same `spill crc`: the firmware's stream merged on
//! x86-64, the host's own run, the core's test on x86-64 and aarch64
//! (`core/tests/spill_vector.rs`) and the committed `vector/expected_spill_crc.txt` agree
//! (scripts/firmware.sh, scripts/aarch64.sh).

use crate::embedded::testvector::{TestVector, VectorMap, CLASSES};
use crate::mapping::boxed_map;
use crate::mapping::{check_stream, merge_checked, StreamError, StreamSummary};
use anyhow::{anyhow, Result};
use sndt_core::{Config, Crc32, FrameReport, Map, Record, StreamWriter, STREAM_FRAME_BYTES};

/// Cell size of the spill run, metres (the firmware's `spill::SPILL_CELL`). At 9 cm each
/// frame fits the device map on its own (no point and no free-space update is dropped),
/// while the 4 frames together overflow it: frames 1, 2 and 3 evict 367, 1,580 and 953
/// voxels and 92, 181 and 91 blocks, 3,264 records, so the global map holds everything the
/// device saw. Smaller cells overflow more but lose data before any eviction: at 8 cm
/// frame 1 drops free-space updates, and at 2 cm each frame fills the 512 blocks by itself
/// and drops about 78 % of its points.
pub const SPILL_CELL: f32 = 0.09;
/// Voxel capacity of the global map the spill merges into.
pub const GLOBAL_VOXELS: usize = 1 << 16;
/// Block capacity of the global map.
pub const GLOBAL_BLOCKS: usize = 1 << 14;
/// The host's global map: 65,536 voxels, 16,384 blocks, 40 classes (about 9 MiB).
pub type GlobalMap = Map<GLOBAL_VOXELS, GLOBAL_BLOCKS, CLASSES>;

/// The link the stream is budgeted for: a UART at 921,600 baud, 8N1 (10 bits a byte).
pub const LINK_BAUD: u32 = 921_600;
/// Its bytes per second.
pub const LINK_BYTES_PER_SECOND: u32 = LINK_BAUD / 10;
/// The frame rate the link must keep up with.
pub const FRAME_RATE: u32 = 10;
/// Bytes the link carries per frame at [`FRAME_RATE`]: 9,216.
pub const LINK_BYTES_PER_FRAME: u32 = LINK_BYTES_PER_SECOND / FRAME_RATE;

/// Checks the stream ([`check_stream`]), then merges its records in order into a new
/// [`GlobalMap`] of the sender's config and adds the end frame's frame count (what
/// `global.merge(&device)` adds in [`own_run`]).
pub fn merge_stream(bytes: &[u8]) -> Result<(Box<GlobalMap>, StreamSummary), StreamError> {
    let summary = check_stream(bytes)?;
    let mut global: Box<GlobalMap> =
        boxed_map(summary.header.config).map_err(StreamError::Config)?;
    merge_checked(bytes, |r| global.merge_record(r))?;
    global.add_frames(summary.end.frames);
    Ok((global, summary))
}

/// What [`own_run`] gives.
#[derive(Clone, Debug, PartialEq)]
pub struct SpillRun {
    /// The device map's report of each frame.
    pub reports: Vec<FrameReport>,
    /// Stream bytes each frame's evictions took.
    pub frame_bytes: Vec<usize>,
    /// The whole stream the device sends: start, the frames' records, its last map's
    /// records, end.
    pub stream: Vec<u8>,
    /// Records of the device's last map.
    pub last_records: u32,
    /// Stream bytes of the last map's records.
    pub last_bytes: usize,
    /// The device map at the end: voxels, blocks, checksum.
    pub device: (usize, usize, u32),
    /// The global map at the end: voxels, blocks, checksum (the `spill crc`).
    pub global: (usize, usize, u32),
}

/// A stream on the host: the writer, a frame buffer and the bytes written.
struct HostLink {
    writer: StreamWriter,
    buf: [u8; STREAM_FRAME_BYTES],
    stream: Vec<u8>,
}

impl HostLink {
    /// Appends `record`'s frame; false if the writer refused it.
    fn send(&mut self, record: Record<'_>) -> bool {
        match self.writer.record(record, &mut self.buf) {
            Ok(n) => {
                self.stream.extend_from_slice(&self.buf[..n]);
                true
            }
            Err(_) => false,
        }
    }
}

/// The host's own spill run on the vector's frames: a [`VectorMap`] at [`SPILL_CELL`]
/// integrating with `integrate_depth_spilling`, each record merged straight into a
/// [`GlobalMap`] (and written to the stream the firmware sends), then the device's last
/// map merged with `global.merge(&device)`. Fails if the global map refuses a record.
pub fn own_run(v: &TestVector) -> Result<SpillRun> {
    let config = Config::with_cell_size(SPILL_CELL);
    let mut device: Box<VectorMap> = boxed_map(config).map_err(|e| anyhow!("config: {e}"))?;
    let mut global: Box<GlobalMap> = boxed_map(config).map_err(|e| anyhow!("config: {e}"))?;
    let mut buf = [0u8; STREAM_FRAME_BYTES];
    let (writer, n) =
        StreamWriter::start(&*device, &mut buf).map_err(|e| anyhow!("stream start: {e}"))?;
    let mut link = HostLink {
        writer,
        buf,
        stream: buf[..n].to_vec(),
    };
    let (mut reports, mut frame_bytes) = (Vec::new(), Vec::new());
    for (k, f) in v.frames.iter().enumerate() {
        let image = v.depth_image(f);
        let before = link.stream.len();
        let mut sink = |r: Record<'_>| link.send(r) && global.merge_record(r).is_ok();
        let report = device
            .integrate_depth_spilling(&f.pose()?, &image, &mut sink)
            .map_err(|e| anyhow!("spill frame {k}: {e}"))?;
        anyhow::ensure!(
            report.records_dropped == 0,
            "spill frame {k}: {} records did not fit the global map",
            report.records_dropped
        );
        reports.push(report);
        frame_bytes.push(link.stream.len() - before);
    }
    let before = link.stream.len();
    let last = device.write_records(&mut |r: Record<'_>| link.send(r));
    let last_bytes = link.stream.len() - before;
    let n = link
        .writer
        .end(&*device, last.refused, &mut link.buf)
        .map_err(|e| anyhow!("stream end: {e}"))?;
    link.stream.extend_from_slice(&link.buf[..n]);
    global
        .merge(&device)
        .map_err(|e| anyhow!("merging the device's last map: {e}"))?;
    Ok(SpillRun {
        reports,
        frame_bytes,
        stream: link.stream,
        last_records: last.taken,
        last_bytes,
        device: (device.len(), device.block_count(), device.checksum()),
        global: (global.len(), global.block_count(), global.checksum()),
    })
}

/// The link budget of per-frame stream bytes: mean, max, and whether the max fits
/// [`LINK_BYTES_PER_FRAME`], as one line.
pub fn link_budget(frame_bytes: &[usize]) -> String {
    let max = frame_bytes.iter().copied().max().unwrap_or(0);
    let mean = frame_bytes.iter().sum::<usize>() / frame_bytes.len().max(1);
    let verdict = if max <= LINK_BYTES_PER_FRAME as usize {
        "fits".to_string()
    } else {
        format!(
            "does not fit (the largest frame needs {:.2} s, {:.1} frames/s at most)",
            max as f64 / f64::from(LINK_BYTES_PER_SECOND),
            f64::from(LINK_BYTES_PER_SECOND) / max as f64
        )
    };
    format!(
        "stream bytes per frame: mean {mean}, max {max}; a {LINK_BAUD}-baud UART (8N1: \
         {LINK_BYTES_PER_SECOND} bytes/s) carries {LINK_BYTES_PER_FRAME} bytes per frame at \
         {FRAME_RATE} frames/s: {verdict}"
    )
}

/// A summary of the host's own run; the last line is `spill crc 0x........`.
pub fn summary(run: &SpillRun) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "spill run: cell {SPILL_CELL} m, device Map<4096, 512, {CLASSES}>, global \
         Map<{GLOBAL_VOXELS}, {GLOBAL_BLOCKS}, {CLASSES}>"
    );
    for (k, (r, bytes)) in run.reports.iter().zip(&run.frame_bytes).enumerate() {
        let _ = writeln!(
            s,
            "spill frame {k}: points {}, voxels +{} -{}, blocks +{} -{}, dropped {}/{}, \
             records spilled {} dropped {}, stream {bytes} bytes",
            r.points_used,
            r.voxels_created,
            r.voxels_evicted,
            r.blocks_created,
            r.blocks_evicted,
            r.dropped_points,
            r.dropped_misses,
            r.records_spilled,
            r.records_dropped
        );
    }
    let spilled: u32 = run.reports.iter().map(|r| r.records_spilled).sum();
    let mut crc = Crc32::new();
    crc.update(&run.stream);
    let _ = writeln!(
        s,
        "spill stream: {} bytes (stream crc {:#010x}): {spilled} records spilled, last map \
         {} records in {} bytes",
        run.stream.len(),
        crc.finish(),
        run.last_records,
        run.last_bytes
    );
    let _ = writeln!(s, "{}", link_budget(&run.frame_bytes));
    let (v, b, device) = run.device;
    let _ = writeln!(
        s,
        "device map: voxels {v}, blocks {b}; device crc {device:#010x}"
    );
    let (v, b, global) = run.global;
    let _ = writeln!(s, "global map: voxels {v}, blocks {b}");
    let _ = writeln!(s, "spill crc {global:#010x}");
    s
}

/// A summary of a merged stream; the last line is `spill crc 0x........`.
pub fn stream_summary(global: &GlobalMap, s: &StreamSummary) -> String {
    let per_frame = s.bytes / (s.end.frames.max(1) as usize);
    format!(
        "spill stream: {} bytes (stream crc {:#010x}): {} voxel and {} block records; the \
         sender integrated {} frames at cell {} m and dropped {} records\n\
         whole stream per integrated frame: {per_frame} bytes (the stream does not mark \
         frames: --spill gives each frame's bytes)\n\
         device crc {:#010x}\n\
         global map: voxels {}, blocks {}\n\
         spill crc {:#010x}\n",
        s.bytes,
        s.crc,
        s.voxels,
        s.blocks,
        s.end.frames,
        s.header.config.cell_size,
        s.end.dropped,
        s.end.checksum,
        global.len(),
        global.block_count(),
        global.checksum()
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::embedded::testvector::generate;
    use sndt_core::Error;

    #[test]
    fn the_stream_merges_to_the_own_runs_map_and_broken_streams_are_refused() {
        let run = own_run(&generate()).unwrap();
        let evicted: u32 = run.reports.iter().map(|r| r.voxels_evicted).sum();
        assert!(evicted > 1000, "the device map did not overflow");
        let (global, s) = merge_stream(&run.stream).unwrap();
        assert_eq!(global.checksum(), run.global.2);
        assert_eq!(
            (s.end.frames, s.end.checksum, s.end.dropped),
            (4, run.device.2, 0)
        );

        let stream = &run.stream;
        let ends: Vec<usize> = (0..stream.len()).filter(|&i| stream[i] == 0).collect();
        let frame = |k: usize| {
            let start = if k == 0 { 0 } else { ends[k - 1] + 1 };
            start..ends[k] + 1
        };
        let err = |bytes: &[u8]| check_stream(bytes).unwrap_err();
        let frame_error = |bytes: &[u8]| match err(bytes) {
            StreamError::Frame { error, .. } => error,
            e => panic!("{e}"),
        };
        assert_eq!(err(&[]), StreamError::Empty);
        // One bit flipped inside the third frame.
        let mut bad = stream.clone();
        bad[frame(2).start + 5] ^= 0x10;
        assert_eq!(frame_error(&bad), Error::StreamChecksum);
        // The third frame twice, or the third and fourth swapped.
        let mut bad = stream[..frame(2).end].to_vec();
        bad.extend_from_slice(&stream[frame(2)]);
        assert_eq!(frame_error(&bad), Error::StreamOrder);
        let mut bad = stream[..frame(2).start].to_vec();
        bad.extend_from_slice(&stream[frame(3)]);
        bad.extend_from_slice(&stream[frame(2)]);
        assert_eq!(frame_error(&bad), Error::StreamOrder);
        // Cut after a frame, or inside one.
        let cut = frame(ends.len() - 2).end;
        assert!(matches!(err(&stream[..cut]), StreamError::Truncated { .. }));
        assert_eq!(
            err(&stream[..cut + 3]),
            StreamError::Unterminated { offset: cut }
        );
        // Without its start, the first record is out of order.
        assert_eq!(frame_error(&stream[frame(0).end..]), Error::StreamOrder);
    }
}
