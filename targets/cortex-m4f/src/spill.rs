//! The spill run: the vector's frames integrated again into the same static map at a cell
//! size small enough to overflow it ([`SPILL_CELL`]), every evicted voxel and block sent
//! as a record over UART0 in the core's record stream (`StreamWriter`: COBS frames with a
//! CRC-32, a sequence number and the config's tag), then the map's last content
//! (`Map::write_records`) and the end frame. The host merges the stream into a larger map
//! (`sndt testvector --merge-stream`) and checks that map's CRC against its own run and
//! `vector/expected_spill_crc.txt` (scripts/firmware.sh); the firmware reports the figures
//! of the link and the device map's checksum, which the stream's end frame carries too.

use sndt_core::{Config, FrameReport, Record, RecordSink, StreamWriter, STREAM_FRAME_BYTES};

use crate::uart::Uart;
use crate::vector::Vector;
use crate::{frame_input, Abort, FwMap};

/// Cell size of the spill run, metres: the host's `embedded::spill::SPILL_CELL`, whose doc
/// says why 9 cm (every frame fits the map on its own, the 4 frames together overflow it:
/// frames 1 to 3 evict 2,900 voxels and 364 blocks).
pub const SPILL_CELL: f32 = 0.09;

/// Frames per second the link budget is checked for.
const FRAME_RATE: u32 = 10;
/// The link's nominal rate (UART0 runs at `uart::BAUDDIV_921600`, 0.5 % faster), and its
/// bytes per second: 10 bits on the line per byte (8N1), 92,160.
const LINK_BAUD: u32 = 921_600;
const LINK_BYTES_PER_SECOND: u32 = LINK_BAUD / 10;

/// The record stream on UART0: the stream's writer, one frame's buffer, and the bytes sent
/// since `bytes` was last zeroed.
struct Link<'u> {
    uart: &'u mut Uart,
    writer: StreamWriter,
    buf: [u8; STREAM_FRAME_BYTES],
    bytes: u32,
}

impl Link<'_> {
    /// Sends the first `n` bytes of the buffer (a frame the writer just wrote).
    fn send(&mut self, n: usize) {
        if let Some(frame) = self.buf.get(..n) {
            self.uart.write(frame);
            self.bytes += frame.len() as u32;
        }
    }
}

/// Each record becomes one stream frame on the UART; a record the writer cannot frame
/// (none of this map's records) is refused, and counted as dropped.
impl RecordSink for Link<'_> {
    fn take(&mut self, record: Record<'_>) -> bool {
        match self.writer.record(record, &mut self.buf) {
            Ok(n) => {
                self.send(n);
                true
            }
            Err(_) => false,
        }
    }
}

/// What the frames sent, for the totals.
#[derive(Default)]
struct Totals {
    voxels_evicted: u32,
    blocks_evicted: u32,
    spilled: u32,
    dropped: u32,
    bytes: u32,
    max_bytes: u32,
}

/// Runs the spill: `Ok(true)` when every evicted entry went out as a record, none was
/// dropped, and the map overflowed (voxels and blocks were evicted).
pub fn run(map: &mut FwMap, v: &Vector<'_>, uart: &mut Uart) -> Result<bool, Abort> {
    if map.reset(Config::with_cell_size(SPILL_CELL)).is_err() {
        defmt::error!("spill: invalid cell size {=f32}", SPILL_CELL);
        return Err(Abort);
    }
    let mut buf = [0u8; STREAM_FRAME_BYTES];
    let Ok((writer, n)) = StreamWriter::start(map, &mut buf) else {
        defmt::error!("spill: no start frame");
        return Err(Abort);
    };
    let mut link = Link {
        uart,
        writer,
        buf,
        bytes: 0,
    };
    link.send(n);
    let start_bytes = link.bytes;
    let (totals, frames_ok) = spill_frames(map, v, &mut link)?;
    link.bytes = 0;
    let last = map.write_records(&mut link);
    let last_bytes = link.bytes;
    let dropped = totals.dropped + last.refused;
    let Ok(n) = link.writer.end(map, dropped, &mut link.buf) else {
        defmt::error!("spill: no end frame");
        return Err(Abort);
    };
    link.bytes = 0;
    link.send(n);
    link.uart.flush();
    let all = start_bytes + totals.bytes + last_bytes + link.bytes;
    report_totals(map, v, &totals, (last.taken, last_bytes), all);
    let overflowed = totals.voxels_evicted > 0 && totals.blocks_evicted > 0;
    if !overflowed {
        defmt::error!("spill: the map did not overflow");
    }
    Ok(frames_ok && overflowed && dropped == 0)
}

/// Integrates the frames with the link as the sink, one line per frame; false when a
/// frame failed, dropped a record or spilled other than what it evicted.
fn spill_frames(
    map: &mut FwMap,
    v: &Vector<'_>,
    link: &mut Link<'_>,
) -> Result<(Totals, bool), Abort> {
    let mut t = Totals::default();
    let mut ok = true;
    for k in 0..v.frames {
        let (pose, image) = frame_input(v, k)?;
        link.bytes = 0;
        let rep = match map.integrate_depth_spilling(&pose, &image, link) {
            Ok(rep) => rep,
            Err(e) => {
                defmt::error!("spill frame {=usize}: {}", k, e);
                ok = false;
                continue;
            }
        };
        report_frame(k, &rep, link.bytes);
        t.voxels_evicted += rep.voxels_evicted;
        t.blocks_evicted += rep.blocks_evicted;
        t.spilled += rep.records_spilled;
        t.dropped += rep.records_dropped;
        t.bytes += link.bytes;
        t.max_bytes = t.max_bytes.max(link.bytes);
        let evicted = rep.voxels_evicted + rep.blocks_evicted;
        if rep.records_dropped != 0 || rep.records_spilled != evicted {
            defmt::error!(
                "spill frame {=usize}: {=u32} evicted, {=u32} spilled",
                k,
                evicted,
                rep.records_spilled
            );
            ok = false;
        }
    }
    Ok((t, ok))
}

/// One line per spilled frame.
fn report_frame(k: usize, rep: &FrameReport, bytes: u32) {
    defmt::println!(
        "spill frame {=usize}: points {=u32}, voxels +{=u32} -{=u32}, blocks +{=u32} -{=u32}, dropped {=u32}/{=u32}, records spilled {=u32} dropped {=u32}, stream {=u32} bytes",
        k,
        rep.points_used,
        rep.voxels_created,
        rep.voxels_evicted,
        rep.blocks_created,
        rep.blocks_evicted,
        rep.dropped_points,
        rep.dropped_misses,
        rep.records_spilled,
        rep.records_dropped,
        bytes
    );
}

/// The totals, the link budget and the device map's checksum.
fn report_totals(map: &FwMap, v: &Vector<'_>, t: &Totals, last: (u32, u32), all: u32) {
    let frames = v.frames.max(1) as u32;
    defmt::println!(
        "spill totals: evicted {=u32} voxels and {=u32} blocks, records spilled {=u32} dropped {=u32}, {=u32} stream bytes; last map {=u32} records {=u32} bytes",
        t.voxels_evicted,
        t.blocks_evicted,
        t.spilled,
        t.dropped,
        t.bytes,
        last.0,
        last.1
    );
    let budget = LINK_BYTES_PER_SECOND / FRAME_RATE;
    defmt::println!(
        "spill stream per frame: mean {=u32} bytes, max {=u32}; the UART ({=u32} baud, {=u32} bytes/s) carries {=u32} bytes per frame at {=u32} frames/s: {=str}",
        t.bytes / frames,
        t.max_bytes,
        LINK_BAUD,
        LINK_BYTES_PER_SECOND,
        budget,
        FRAME_RATE,
        if t.max_bytes <= budget {
            "fits"
        } else {
            "does not fit"
        }
    );
    defmt::println!("spill stream bytes {=u32}", all);
    let stats = map.stats();
    defmt::println!(
        "spill device map: voxels {=usize}, blocks {=usize}, frames {=u32}; device crc {=u32:#010x}",
        map.len(),
        map.block_count(),
        stats.frames,
        map.checksum()
    );
}
