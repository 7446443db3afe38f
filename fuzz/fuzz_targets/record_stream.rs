//! The record stream: arbitrary link bytes, split on zero bytes as a receiver splits them,
//! read frame by frame by a `StreamReader`, every record it yields merged into a small map
//! (of the start frame's config when `Config::validate` takes it, else `Config::DEFAULT`).
//!
//! Input: one flags byte, then the link bytes. The flags repair each frame that decodes
//! as COBS before the reader sees it, so that mutations get past the link checks to the
//! records and the merge: bit 0 recomputes the frame's CRC-32, bit 1 sets a start frame's
//! config tag to its header's (and later frames' tags to that one), bit 2 numbers the
//! frame as the reader expects next, bit 3 passes the zero delimiter with the frame. With
//! flags 0 the bytes reach the reader as they are.
//!
//! Nothing may panic. The reader's errors are its documented ones (the header errors of
//! `SnapshotHeader::read` for a start frame) and leave it as it was; nothing but errors
//! follow the end frame, whose record count is the records read. A record's
//! `Map::merge_record` fails only with `RecordCorrupt` (exactly when `Map::check_record`
//! refuses it) or `MapFull`, and then leaves the map's checksum unchanged. At the end the
//! map keeps its invariants and its snapshot loads into a fresh map with the same checksum.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sndt_core::{
    Config, Crc32, Error, Map, SnapshotHeader, StreamItem, StreamReader, SNAPSHOT_HEADER_BYTES,
    STREAM_FRAME_BYTES,
};
use sndt_fuzz::{assert_map_invariants, assert_round_trip, snapshot};

/// Capacities of the receiving map: small, so that a seed stream (`wide-c1`, 56 voxels and
/// 24 blocks) fills it and merges meet `MapFull`, and the checksum taken before every
/// merge stays cheap.
const VOXELS: usize = 48;
const BLOCKS: usize = 16;

const RESEAL: u8 = 1;
const RETAG: u8 = 2;
const RENUMBER: u8 = 4;
const DELIMITER: u8 = 8;

/// Frame head: kind, sequence number, config tag.
const HEAD: usize = 9;
const START: u8 = 1;

fuzz_target!(|data: &[u8]| {
    let Some((&flags, link)) = data.split_first() else {
        return;
    };
    // One map type per class count the seeds use (so their voxel records merge); any
    // other count goes to the 40-class map, which refuses its voxel records.
    match start_classes(flags, link) {
        Some(1) => check::<1>(flags, link),
        Some(4) => check::<4>(flags, link),
        _ => check::<40>(flags, link),
    }
});

/// The class count of the start frame the reader would take: the first frame a fresh
/// reader reads as a start (no frame before it can be read, so its number is 0).
fn start_classes(flags: u8, link: &[u8]) -> Option<u16> {
    let mut scratch = [0u8; STREAM_FRAME_BYTES];
    link.split(|&b| b == 0).find_map(|raw| {
        let frame = Repair::new(flags).frame(raw, 0);
        match StreamReader::new().read(&frame, &mut scratch) {
            Ok(StreamItem::Start(h)) => Some(h.classes),
            _ => None,
        }
    })
}

fn check<const C: usize>(flags: u8, link: &[u8]) {
    let mut map: Box<Map<VOXELS, BLOCKS, C>> = Box::new(Map::new(Config::DEFAULT));
    let mut reader = StreamReader::new();
    let mut repair = Repair::new(flags);
    let mut scratch = [0u8; STREAM_FRAME_BYTES];
    let (mut read, mut records) = (0u32, 0u32);
    let mut end = None;
    for raw in link.split(|&b| b == 0) {
        let frame = repair.frame(raw, read);
        let before = format!("{reader:?}");
        let item = match reader.read(&frame, &mut scratch) {
            Ok(item) => item,
            Err(e) => {
                assert!(is_reader_error(e), "not a stream error: {e:?}");
                assert_eq!(format!("{reader:?}"), before, "{e:?} changed the reader");
                continue;
            }
        };
        assert!(end.is_none(), "a frame read after the end: {item:?}");
        read += 1;
        match item {
            StreamItem::Start(h) => {
                assert_eq!(read, 1, "a start that is not the first frame");
                // Debug, not ==: the header's config is as stored (NaN compares unequal).
                assert_eq!(format!("{:?}", reader.header()), format!("{:?}", Some(h)));
                let config = if h.config.validate().is_ok() {
                    h.config
                } else {
                    Config::DEFAULT
                };
                map.reset(config).expect("a validated config");
            }
            StreamItem::Record(r) => {
                assert!(reader.header().is_some(), "a record before the start");
                records += 1;
                let check = map.check_record(r);
                let sum = map.checksum();
                match map.merge_record(r) {
                    Ok(()) => assert_eq!(check, Ok(()), "check_record refused a merged record"),
                    Err(e) => {
                        assert_eq!(
                            map.checksum(),
                            sum,
                            "a failed merge ({e:?}) changed the map"
                        );
                        match e {
                            Error::RecordCorrupt => assert_eq!(check, Err(e)),
                            Error::MapFull => assert_eq!(check, Ok(()), "{e:?}"),
                            _ => panic!("not a merge error: {e:?}"),
                        }
                    }
                }
            }
            StreamItem::End(e) => {
                assert_eq!(e.records, records, "end's record count");
                map.add_frames(e.frames);
                end = Some(e);
            }
        }
    }
    match end {
        Some(e) => assert_eq!(reader.finish(), Ok(e)),
        None => assert_eq!(reader.finish(), Err(Error::StreamTruncated)),
    }
    assert_map_invariants(&*map);
    assert_round_trip(&*map);
    let mut copy: Box<Map<VOXELS, BLOCKS, C>> = Box::new(Map::new(Config::DEFAULT));
    copy.read_snapshot(&snapshot(&*map))
        .expect("the merged map's snapshot loads");
    assert_eq!(copy.checksum(), map.checksum());
}

/// What `StreamReader::read` may refuse a frame with: the link and sequence checks, a
/// record of the wrong length, and for a start frame the errors of its header.
fn is_reader_error(e: Error) -> bool {
    matches!(
        e,
        Error::StreamChecksum
            | Error::StreamOrder
            | Error::ConfigMismatch
            | Error::RecordCorrupt
            | Error::SnapshotTruncated
            | Error::SnapshotMagic
            | Error::SnapshotVersion
            | Error::SnapshotCorrupt
    )
}

/// The repairs the flags byte asks for, applied to each frame that decodes as COBS.
struct Repair {
    flags: u8,
    /// The config tag of the last start frame repaired.
    tag: Option<u32>,
}

impl Repair {
    fn new(flags: u8) -> Repair {
        Repair { flags, tag: None }
    }

    /// The frame as the reader gets it; `seq` is the number the reader expects next.
    fn frame(&mut self, raw: &[u8], seq: u32) -> Vec<u8> {
        let mut out = self.repaired(raw, seq).unwrap_or_else(|| raw.to_vec());
        if self.flags & DELIMITER != 0 {
            out.push(0);
        }
        out
    }

    fn repaired(&mut self, raw: &[u8], seq: u32) -> Option<Vec<u8>> {
        if self.flags & (RESEAL | RETAG | RENUMBER) == 0 || raw.len() > STREAM_FRAME_BYTES {
            return None;
        }
        let mut body = [0u8; STREAM_FRAME_BYTES];
        let n = cobs::decode(raw, &mut body).ok()?.frame_size();
        let body = body.get_mut(..n).filter(|b| b.len() >= HEAD + 4)?;
        if self.flags & RENUMBER != 0 {
            body[1..5].copy_from_slice(&seq.to_le_bytes());
        }
        if self.flags & RETAG != 0 {
            let payload = &body[HEAD..n - 4];
            if body[0] == START && payload.len() == SNAPSHOT_HEADER_BYTES {
                if let Ok(h) = SnapshotHeader::read(payload) {
                    self.tag = Some(config_tag(&h));
                }
            }
            if let Some(tag) = self.tag {
                body[5..HEAD].copy_from_slice(&tag.to_le_bytes());
            }
        }
        if self.flags & RESEAL != 0 {
            let mut crc = Crc32::new();
            crc.update(&body[..n - 4]);
            body[n - 4..].copy_from_slice(&crc.finish().to_le_bytes());
        }
        let mut out = vec![0u8; cobs::max_encoding_length(n)];
        let len = cobs::try_encode(body, &mut out).ok()?;
        out.truncate(len);
        Some(out)
    }
}

/// A stream's config tag (`stream.rs`): the CRC-32 of a snapshot header holding only the
/// class count and the config.
fn config_tag(h: &SnapshotHeader) -> u32 {
    let only = SnapshotHeader {
        classes: h.classes,
        voxel_capacity: 0,
        block_capacity: 0,
        config: h.config,
        frames: 0,
        blocks: 0,
        voxels: 0,
    };
    let mut bytes = [0u8; SNAPSHOT_HEADER_BYTES];
    only.write(&mut bytes).expect("a header-sized buffer");
    let mut crc = Crc32::new();
    crc.update(&bytes);
    crc.finish()
}
