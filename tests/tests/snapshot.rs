//! Snapshots: round trip, corruption, truncation, buffer and class checks.

use proptest::prelude::*;
use sndt_core::{Config, Error, Isometry3, Map, MissModel, SnapshotHeader, SNAPSHOT_HEADER_BYTES};
use sndt_tests::*;
use std::sync::OnceLock;

const C: usize = 8;
type Small = Map<512, 128, C>;

/// CRC-32 (IEEE, reflected, init and final xor 0xFFFFFFFF), written independently.
fn crc32(data: &[u8]) -> u32 {
    let mut crc = 0xFFFF_FFFFu32;
    for &b in data {
        crc ^= b as u32;
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

fn fix_crc(buf: &mut [u8]) {
    let n = buf.len() - 4;
    let crc = crc32(&buf[..n]);
    buf[n..].copy_from_slice(&crc.to_le_bytes());
}

/// A snapshot as a map of the given capacities writes it back: the reader ignores the
/// writer's capacities, everything else must come back byte for byte.
fn with_capacities(snap: &[u8], voxels: u32, blocks: u32) -> Vec<u8> {
    edit_header(snap, |h| {
        (h.voxel_capacity, h.block_capacity) = (voxels, blocks);
    })
}

/// A small map with a bit of everything: two room frames (surface voxels, free space,
/// several classes), classes folded into 1..=8.
fn build(frames: &[usize], model: MissModel) -> Box<Small> {
    let mut map = sndt_host::mapping::boxed_map::<512, 128, C>(config_with(model)).unwrap();
    let cam = camera(16, 12);
    let poses = sndt_host::dataset::synthetic::room::orbit(8);
    for &i in frames {
        let mut pts = room_frame(&poses[i], &cam);
        for p in pts.iter_mut() {
            p.labels.classes[0] = p.labels.classes[0] % C as u8 + 1;
        }
        let r = map.integrate(&poses[i], &pts).unwrap();
        assert_accounted(&r, pts.len());
    }
    assert!(map.len() > 20 && map.block_count() > 20);
    map
}

/// The snapshot under test and a different map to read into.
fn fixtures() -> &'static (Vec<u8>, Vec<u8>) {
    static F: OnceLock<(Vec<u8>, Vec<u8>)> = OnceLock::new();
    F.get_or_init(|| {
        (
            snapshot(&*build(&[0, 1], MissModel::NdtOm)),
            snapshot(&*build(&[5], MissModel::Constant)),
        )
    })
}

/// A map holding the second fixture.
fn target() -> Box<Small> {
    let mut t = sndt_host::mapping::boxed_map::<512, 128, C>(Config::DEFAULT).unwrap();
    t.read_snapshot(&fixtures().1).unwrap();
    t
}

#[test]
fn crc_matches_independent_implementation() {
    let (snap, _) = fixtures();
    let n = snap.len() - 4;
    assert_eq!(crc32(&snap[..n]).to_le_bytes(), snap[n..]);
    assert_eq!(crc32(b"123456789"), 0xCBF4_3926); // the standard check value
}

#[test]
fn round_trip_is_byte_identical() {
    let map = build(&[0, 1, 2], MissModel::NdtOm);
    let snap = snapshot(&*map);
    assert_eq!(snap.len(), map.snapshot_len());
    assert_eq!(&snap[..4], b"SNDT");
    assert_eq!(
        snap.len(),
        SNAPSHOT_HEADER_BYTES
            + map.block_count() * sndt_core::SNAPSHOT_BLOCK_BYTES
            + map.len() * Small::SNAPSHOT_VOXEL_BYTES
            + 4
    );
    let mut copy =
        sndt_host::mapping::boxed_map::<512, 128, C>(Config::with_cell_size(0.3)).unwrap();
    copy.read_snapshot(&snap).unwrap();
    assert_eq!(snapshot(&*copy), snap);
    assert_eq!(copy.checksum(), map.checksum());
    assert_eq!(copy.config(), map.config());
    assert_eq!(copy.stats().frames, 3);
    // Its header says what the map was built with, without loading it.
    let header = SnapshotHeader::read(&snap).unwrap();
    assert_eq!(header.config, config_with(MissModel::NdtOm));
    assert_eq!((header.frames, header.classes), (3, C as u16));
    assert_eq!((header.voxel_capacity, header.block_capacity), (512, 128));
    assert_eq!(header.voxels as usize, map.len());
    assert_eq!(header.blocks as usize, map.block_count());
    // Queries agree too.
    let cells: Vec<_> = map.cells().collect();
    assert_eq!(cells, copy.cells().collect::<Vec<_>>());
    for v in map.voxels() {
        assert_eq!(copy.voxel(&v.key), Some(v));
    }
    // The copy keeps integrating exactly like the original.
    let mut original = map;
    let pose = sndt_host::dataset::synthetic::room::orbit(8)[4];
    let pts = room_frame(&pose, &camera(16, 12));
    let pts: Vec<_> = pts
        .into_iter()
        .map(|mut p| {
            p.labels.classes[0] = p.labels.classes[0] % C as u8 + 1;
            p
        })
        .collect();
    assert_eq!(
        original.integrate(&pose, &pts).unwrap(),
        copy.integrate(&pose, &pts).unwrap()
    );
    assert_eq!(snapshot(&*original), snapshot(&*copy));

    // Into a map with more capacity: same content (only the capacity fields differ).
    let mut big = sndt_host::mapping::boxed_map::<1024, 512, C>(Config::DEFAULT).unwrap();
    big.read_snapshot(&snap).unwrap();
    assert_eq!(snapshot(&*big), with_capacities(&snap, 1024, 512));
}

#[test]
fn empty_map_round_trips() {
    let map: Small = Map::new(Config::DEFAULT);
    let snap = snapshot(&map);
    assert_eq!(snap.len(), SNAPSHOT_HEADER_BYTES + 4);
    let mut t = target();
    t.read_snapshot(&snap).unwrap();
    assert!(t.is_empty() && t.block_count() == 0 && t.voxels().next().is_none());
    assert_eq!(snapshot(&*t), snap);
}

#[test]
fn write_into_short_or_long_buffers() {
    let map = target();
    let len = map.snapshot_len();
    for short in [0, 1, SNAPSHOT_HEADER_BYTES, len - 4, len - 1] {
        let mut buf = vec![0xA5u8; short];
        assert_eq!(map.write_snapshot(&mut buf), Err(Error::BufferTooSmall));
        assert!(buf.iter().all(|&b| b == 0xA5), "nothing may be written");
    }
    let mut buf = vec![0xA5u8; len + 100];
    assert_eq!(map.write_snapshot(&mut buf), Ok(len));
    assert_eq!(buf[..len], fixtures().1[..]);
    assert!(buf[len..].iter().all(|&b| b == 0xA5));
}

#[test]
fn truncated_or_extended_buffers_are_rejected() {
    let (snap, _) = fixtures();
    let mut t = target();
    let before = t.checksum();
    for n in 0..snap.len() {
        assert!(
            t.read_snapshot(&snap[..n]).is_err(),
            "prefix of {n} bytes accepted"
        );
    }
    let mut long = snap.clone();
    long.push(0);
    assert_eq!(t.read_snapshot(&long), Err(Error::SnapshotTruncated));
    // Even with a recomputed CRC, a length that disagrees with the header fails.
    let mut short = snap[..snap.len() - 5].to_vec();
    short.extend_from_slice(&[0; 4]);
    fix_crc(&mut short);
    assert_eq!(t.read_snapshot(&short), Err(Error::SnapshotTruncated));
    assert_eq!(t.checksum(), before);
    assert_eq!(snapshot(&*t), fixtures().1);
}

#[test]
fn wrong_class_count_or_capacity_is_rejected() {
    let (snap, _) = fixtures();
    let mut four: Map<512, 128, 4> = Map::new(Config::DEFAULT);
    let before = four.checksum();
    assert_eq!(four.read_snapshot(snap), Err(Error::SnapshotClasses));
    assert_eq!(four.checksum(), before);
    let mut many: Map<512, 128, 40> = Map::new(Config::DEFAULT);
    assert_eq!(many.read_snapshot(snap), Err(Error::SnapshotClasses));
    let mut tiny: Map<8, 4, C> = Map::new(Config::DEFAULT);
    let before = tiny.checksum();
    assert_eq!(tiny.read_snapshot(snap), Err(Error::SnapshotCapacity));
    assert_eq!(tiny.checksum(), before);
}

#[test]
fn header_fields_are_checked() {
    let (snap, _) = fixtures();
    let mut t = target();
    let before = snapshot(&*t);
    let mut bad = snap.clone();
    bad[0] = b'X';
    assert_eq!(t.read_snapshot(&bad), Err(Error::SnapshotMagic));
    let mut bad = snap.clone();
    bad[4] = bad[4].wrapping_add(1);
    assert_eq!(t.read_snapshot(&bad), Err(Error::SnapshotVersion));
    // Semantic corruption behind a valid CRC.
    let corrupt = |edit: &dyn Fn(&mut Vec<u8>)| {
        let mut b = snap.clone();
        edit(&mut b);
        fix_crc(&mut b);
        b
    };
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("miss model 7", corrupt(&|b| b[71] = 7)),
        (
            "quant_bits 0",
            edit_header(snap, |h| h.config.quant_bits = 0),
        ),
        (
            "cell size NaN",
            edit_header(snap, |h| h.config.cell_size = f32::NAN),
        ),
        ("n_min 1", edit_header(snap, |h| h.config.n_min = 1)),
        (
            "first log-odds beyond the clamp",
            corrupt(&|b| {
                let p = SNAPSHOT_HEADER_BYTES + 6;
                b[p..p + 2].copy_from_slice(&i16::MAX.to_le_bytes());
            }),
        ),
        (
            "blocks swapped (order)",
            corrupt(&|b| {
                let (p, n) = (SNAPSHOT_HEADER_BYTES, sndt_core::SNAPSHOT_BLOCK_BYTES);
                let first: Vec<u8> = b[p..p + n].to_vec();
                b.copy_within(p + n..p + 2 * n, p);
                b[p + n..p + 2 * n].copy_from_slice(&first);
            }),
        ),
        (
            "voxel with n = 0",
            corrupt(&|b| {
                let p = voxel_offset(b, 0) + 6;
                b[p..p + 4].copy_from_slice(&0u32.to_le_bytes());
            }),
        ),
        (
            "voxel with |S1| > n 2^(Q-1)",
            corrupt(&|b| {
                let p = voxel_offset(b, 0) + 10;
                b[p..p + 4].copy_from_slice(&i32::MAX.to_le_bytes());
            }),
        ),
        (
            "voxel with negative S2 diagonal",
            corrupt(&|b| {
                let p = voxel_offset(b, 0) + 22;
                b[p..p + 4].copy_from_slice(&(-1i32).to_le_bytes());
            }),
        ),
        (
            "voxel count without records",
            edit_header(snap, |h| h.voxels += 1),
        ),
    ];
    for (what, bytes) in cases {
        assert!(t.read_snapshot(&bytes).is_err(), "{what}: accepted");
        assert_eq!(snapshot(&*t), before, "{what}: map changed");
    }
}

/// Offset of voxel record `i` in a snapshot.
fn voxel_offset(snap: &[u8], i: usize) -> usize {
    let nb = SnapshotHeader::read(snap).unwrap().blocks as usize;
    SNAPSHOT_HEADER_BYTES + nb * sndt_core::SNAPSHOT_BLOCK_BYTES + i * Small::SNAPSHOT_VOXEL_BYTES
}

proptest! {
    #![proptest_config(sndt_tests::proptest_config(384))]

    /// Any single corrupted byte is detected and leaves the target map untouched.
    #[test]
    fn any_flipped_byte_is_rejected(pos in any::<prop::sample::Index>(), xor in 1u8..=255) {
        let (snap, other) = fixtures();
        let mut bad = snap.clone();
        let i = pos.index(bad.len());
        bad[i] ^= xor;
        let mut t = target();
        let before = t.checksum();
        let r = t.read_snapshot(&bad);
        prop_assert!(r.is_err(), "flip of byte {} by {:#x} accepted", i, xor);
        prop_assert_eq!(t.checksum(), before);
        prop_assert_eq!(&snapshot(&*t), other);
        // The header alone never panics either, and a flip behind it leaves it as it was.
        let header = SnapshotHeader::read(&bad);
        if i >= SNAPSHOT_HEADER_BYTES {
            prop_assert_eq!(header, SnapshotHeader::read(snap));
        }
    }

    /// Any bytes, and any prefix of a snapshot: reading a header gives a header or a
    /// snapshot error, never a panic, and `SnapshotTruncated` when it is too short.
    #[test]
    fn header_of_any_bytes_is_read_or_refused(
        junk in prop::collection::vec(any::<u8>(), 0..200),
        cut in any::<prop::sample::Index>(),
    ) {
        let (snap, _) = fixtures();
        let prefix = &snap[..cut.index(snap.len())];
        for bytes in [&junk[..], prefix] {
            match SnapshotHeader::read(bytes) {
                Ok(_) => prop_assert!(bytes.len() >= SNAPSHOT_HEADER_BYTES),
                Err(e) if bytes.len() < SNAPSHOT_HEADER_BYTES => {
                    prop_assert_eq!(e, Error::SnapshotTruncated);
                }
                Err(e) => prop_assert!(matches!(
                    e,
                    Error::SnapshotMagic | Error::SnapshotVersion | Error::SnapshotCorrupt
                )),
            }
        }
    }

    /// Corruption behind a recomputed CRC (what a buggy writer could produce): never
    /// panics; a rejected snapshot leaves the map untouched, an accepted one loads a map
    /// whose own snapshot reproduces the input (except fields the reader ignores).
    #[test]
    fn corruption_with_valid_crc_is_rejected_or_reproduced(
        edits in prop::collection::vec((any::<prop::sample::Index>(), 1u8..=255), 1..4),
    ) {
        let (snap, other) = fixtures();
        let mut bad = snap.clone();
        let body = bad.len() - 4;
        for (pos, xor) in &edits {
            bad[pos.index(body)] ^= xor;
        }
        fix_crc(&mut bad);
        let mut t = target();
        match t.read_snapshot(&bad) {
            Err(_) => prop_assert_eq!(&snapshot(&*t), other),
            Ok(()) => {
                assert_capacity(&*t);
                let again = snapshot(&*t);
                prop_assert!(again == with_capacities(&bad, 512, 128), "not reproduced");
                // Its header gives the config and frame count the map now has.
                let header = SnapshotHeader::read(&bad).unwrap();
                prop_assert_eq!(header.config, *t.config());
                prop_assert_eq!(header.frames, t.stats().frames);
                // The loaded map is usable.
                let _ = t.integrate(&Isometry3::identity(), &[lp(0.1, 0.2, 1.0, 1)]);
                assert_capacity(&*t);
            }
        }
    }
}

/// A wall observed for long enough that its voxels pass `n_max` and decay: the map's own
/// snapshot must still load (decayed sums must keep the invariants the reader checks).
#[test]
fn decayed_wall_snapshot_reads_back() {
    let mut cfg = Config::DEFAULT;
    cfg.n_max = 64;
    let cam = camera(64, 48);
    let depth = vec![2.03f32; 64 * 48];
    let labels = vec![1u8; 64 * 48];
    let mut map = sndt_host::mapping::boxed_map::<4096, 1024, C>(cfg).unwrap();
    for i in 0..12 {
        // Small sideways steps so the points differ from frame to frame.
        let pose = Isometry3::translation(0.0037 * i as f32, -0.0023 * i as f32, 0.0);
        map.integrate_depth(&pose, &depth_image(cam, &depth, &labels))
            .unwrap();
    }
    assert!(
        map.voxels().any(|v| v.gaussian.count < 12 * 4),
        "no voxel decayed"
    );
    let snap = snapshot(&*map);
    let mut copy = sndt_host::mapping::boxed_map::<4096, 1024, C>(Config::DEFAULT).unwrap();
    assert_eq!(copy.read_snapshot(&snap), Ok(()));
    assert_eq!(snapshot(&*copy), snap);
}

/// The smallest case the fuzz test found: three points in one voxel with `n_max = 2`.
#[test]
fn decayed_voxel_snapshot_reads_back() {
    let mut cfg = Config::DEFAULT;
    cfg.n_min = 2;
    cfg.n_max = 2;
    let mut map: Map<8, 8, 2> = Map::try_new(cfg).unwrap();
    let pts = [
        lp(0.076375276, 0.06201594, 1.0748917, 1),
        lp(0.07058345, 0.014663574, 1.077734, 1),
        lp(0.068669334, 0.017384721, 1.0872875, 1),
    ];
    map.integrate(&Isometry3::identity(), &pts).unwrap();
    assert_eq!(map.voxels().next().unwrap().gaussian.count, 2);
    let snap = snapshot(&map);
    let mut copy: Map<8, 8, 2> = Map::new(Config::DEFAULT);
    assert_eq!(copy.read_snapshot(&snap), Ok(()));
    assert_eq!(snapshot(&copy), snap);
}
