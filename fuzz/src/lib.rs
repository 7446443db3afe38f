//! Checks shared by the fuzz targets in `fuzz_targets/` (see docs/FUZZING.md): snapshot
//! helpers, the map invariants every target asserts, and one validated frame through a
//! small map.

use sndt_core::{
    Config, DepthImage, Error, FrameReport, LabelImage, Map, Pinhole, SnapshotHeader, KEY_LIMIT,
};
use sndt_host::dataset::{Frame, Rays};

/// Overwrites the last four bytes with the CRC-32 of everything before them, as
/// `Map::write_snapshot` stores it, so mutated inputs reach the record checks instead of
/// all failing the checksum.
pub fn fix_crc(bytes: &mut [u8]) {
    if let Some(body) = bytes.len().checked_sub(4) {
        let mut crc = sndt_core::Crc32::new();
        crc.update(&bytes[..body]);
        bytes[body..].copy_from_slice(&crc.finish().to_le_bytes());
    }
}

/// The class count a snapshot header claims, 0 when the header is unreadable.
pub fn snapshot_classes(bytes: &[u8]) -> u16 {
    SnapshotHeader::read(bytes).map_or(0, |h| h.classes)
}

/// `bytes` as a map of `voxels` x `blocks` capacity writes it back (with its CRC): the
/// reader ignores the writer's capacities, so an accepted snapshot must come back as this.
/// Unchanged when the header is unreadable.
pub fn with_capacities(bytes: &[u8], voxels: usize, blocks: usize) -> Vec<u8> {
    let mut out = bytes.to_vec();
    if let Ok(mut h) = SnapshotHeader::read(bytes) {
        (h.voxel_capacity, h.block_capacity) = (voxels as u32, blocks as u32);
        if h.write(&mut out).is_ok() {
            fix_crc(&mut out);
        }
    }
    out
}

/// The map's snapshot, checking that `write_snapshot` fills exactly `snapshot_len()`
/// bytes and that `checksum()` equals the CRC it stores.
pub fn snapshot<const V: usize, const B: usize, const C: usize>(map: &Map<V, B, C>) -> Vec<u8> {
    let mut buf = vec![0u8; map.snapshot_len()];
    assert_eq!(map.write_snapshot(&mut buf), Ok(buf.len()));
    let crc = &buf[buf.len() - 4..];
    assert_eq!(
        map.checksum().to_le_bytes(),
        crc,
        "checksum() != stored CRC"
    );
    buf
}

/// A snapshot read into a fresh map writes back the same bytes.
pub fn assert_round_trip<const V: usize, const B: usize, const C: usize>(map: &Map<V, B, C>) {
    let s = snapshot(map);
    let mut copy: Box<Map<V, B, C>> = Box::new(Map::new(Config::DEFAULT));
    if let Err(e) = copy.read_snapshot(&s) {
        panic!("the map's own snapshot is refused: {e:?}");
    }
    assert_eq!(
        snapshot(&*copy),
        s,
        "snapshot changed by a write/read round trip"
    );
}

/// What every map must satisfy whatever it was fed: within capacity, every voxel a
/// finite Gaussian with non-negative variances, a class in `1..=C` when it has votes, and
/// every cell inside the key range with log-odds within the config's clamps.
pub fn assert_map_invariants<const V: usize, const B: usize, const C: usize>(map: &Map<V, B, C>) {
    assert!(map.len() <= V && map.block_count() <= B, "over capacity");
    let c = map.config();
    assert_eq!(c.validate(), Ok(()), "map holds an invalid config");
    let mut voxels = 0;
    for v in map.voxels() {
        voxels += 1;
        let g = &v.gaussian;
        let finite = g
            .mean
            .iter()
            .chain(g.covariance.iter())
            .all(|x| x.is_finite());
        assert!(finite, "voxel {:?}: non-finite Gaussian {g:?}", v.key);
        assert!(
            (0..3).all(|i| g.covariance[(i, i)] >= 0.0),
            "voxel {:?}: negative variance {g:?}",
            v.key
        );
        if let Some((class, share)) = v.class() {
            assert!((1..=C).contains(&(class as usize)) && (0.0..=1.0).contains(&share));
        }
        assert_eq!(map.class(&v.key), v.class());
        assert_eq!(map.gaussian(&v.key), Some(*g));
    }
    assert_eq!(voxels, map.len(), "voxels() misses entries");
    let slack = 1.0 / sndt_core::LOGODDS_ONE;
    for (k, l) in map.cells() {
        let in_range = [k.x, k.y, k.z]
            .iter()
            .all(|&x| (x as i32).abs() <= KEY_LIMIT);
        assert!(in_range, "cell {k:?} outside the key range");
        assert!(
            l >= c.clamp_min - slack && l <= c.clamp_max + slack,
            "cell {k:?}: log-odds {l} outside the clamps"
        );
        assert_eq!(map.log_odds(&k), l);
    }
}

/// Every point of a depth image is counted exactly once in the report.
pub fn assert_accounted(r: &FrameReport, samples: u64) {
    let counted = r.points_used as u64
        + r.truncated as u64
        + r.rejected_depth as u64
        + r.rejected_label as u64
        + r.rejected_out_of_range as u64
        + r.dropped_points as u64;
    assert_eq!(counted, samples, "points not accounted for: {r:?}");
}

/// A small image (8x6 pixels, planar depth 1.5 to 2.2 m, labels `1..=classes`): what the
/// snapshot target integrates before and after reading a snapshot.
pub fn small_frame(classes: u8) -> (Pinhole, Vec<f32>, Vec<u8>) {
    let cam = Pinhole {
        fx: 6.0,
        fy: 6.0,
        cx: 4.0,
        cy: 3.0,
        width: 8,
        height: 6,
    };
    let depth = (0..48).map(|i| 1.5 + 0.015 * i as f32).collect();
    let labels = (0..48)
        .map(|i| 1 + (i % classes.max(1) as usize) as u8)
        .collect();
    (cam, depth, labels)
}

/// Integrates a frame a reader accepted (the caller checked it with [`Frame::validate`])
/// into a small map: the core must take it (a sensor outside the key range or an
/// oversized frame are the errors it may give), stay within its invariants, and write a
/// snapshot that reads back.
pub fn map_frame(frame: &Frame) {
    let Rays::Pinhole(cam) = *frame.rays else {
        return;
    };
    let labels = frame
        .labels
        .as_deref()
        .map_or(LabelImage::None, LabelImage::Top1);
    let image = DepthImage {
        camera: cam,
        depth: sndt_core::Depth::Metres(&frame.depth),
        kind: frame.depth_kind,
        labels,
        stride: 1,
    };
    let mut map: Box<Map<64, 16, 40>> = Box::new(Map::new(Config::DEFAULT));
    match map.integrate_depth(&frame.pose, &image) {
        Ok(r) => assert_accounted(&r, frame.depth.len() as u64),
        Err(Error::PoseOutOfRange | Error::FrameTooLarge) => {}
        // A camera the reader accepted but the core does not (zero-size image, bad
        // intrinsics) would fail later in `sndt map`: flag it here.
        Err(e) => panic!("a validated frame is refused by the core: {e:?} ({image:?})"),
    }
    assert_map_invariants(&*map);
    assert_round_trip(&*map);
}
