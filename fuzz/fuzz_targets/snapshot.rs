//! Map snapshots: arbitrary bytes with their CRC recomputed, read by `Map::read_snapshot`.
//!
//! A refused snapshot must leave the map exactly as it was and name a snapshot error. An
//! accepted one must be canonical (written back byte for byte, but for the writer's
//! capacities), satisfy the map's invariants, answer queries, render, take another frame,
//! and round-trip through its own snapshot. A smaller map must accept it exactly when it
//! fits.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sndt_core::{
    Config, Depth, DepthImage, DepthKind, Error, Isometry3, LabelImage, Map, Point3, Translation3,
    UnitQuaternion, Vector3, INVALID_LABEL,
};
use sndt_fuzz::{
    assert_accounted, assert_map_invariants, assert_round_trip, fix_crc, small_frame, snapshot,
    snapshot_classes, with_capacities,
};

/// Capacities of the map snapshots are read into; the seeds fit.
const VOXELS: usize = 256;
const BLOCKS: usize = 128;

fuzz_target!(|data: &[u8]| {
    let mut bytes = data.to_vec();
    fix_crc(&mut bytes);
    // One map type per class count the seeds use, so every record size is reached; any
    // other count goes to the 4-class map, which refuses it.
    match snapshot_classes(&bytes) {
        1 => check::<1>(&bytes),
        40 => check::<40>(&bytes),
        _ => check::<4>(&bytes),
    }
});

fn check<const C: usize>(bytes: &[u8]) {
    let mut map: Box<Map<VOXELS, BLOCKS, C>> = Box::new(Map::new(Config::DEFAULT));
    integrate_small_frame(&mut map, &Isometry3::translation(0.3, -0.2, 0.1));
    let before = snapshot(&*map);
    match map.read_snapshot(bytes) {
        Err(e) => {
            assert!(is_snapshot_error(e), "not a snapshot error: {e:?}");
            assert_eq!(
                snapshot(&*map),
                before,
                "a refused snapshot changed the map"
            );
        }
        Ok(()) => accepted(&mut map, bytes),
    }
    check_small_map::<C>(bytes);
}

fn is_snapshot_error(e: Error) -> bool {
    matches!(
        e,
        Error::SnapshotTruncated
            | Error::SnapshotMagic
            | Error::SnapshotVersion
            | Error::SnapshotClasses
            | Error::SnapshotCapacity
            | Error::SnapshotChecksum
            | Error::SnapshotCorrupt
    )
}

fn accepted<const C: usize>(map: &mut Map<VOXELS, BLOCKS, C>, bytes: &[u8]) {
    // Canonical: the same bytes come back, but for the writer's capacities (which the
    // reader ignores) and so the CRC.
    let written = snapshot(map);
    assert_eq!(
        written.len(),
        bytes.len(),
        "rewritten snapshot has another length"
    );
    assert!(
        written == with_capacities(bytes, VOXELS, BLOCKS),
        "accepted snapshot is not canonical"
    );
    assert_map_invariants(map);
    assert_round_trip(map);
    query(map);
    render(map);
    let frames = map.stats().frames;
    integrate_small_frame(map, &Isometry3::translation(0.05, 0.1, -0.2));
    assert_eq!(map.stats().frames, frames.wrapping_add(1));
    assert_map_invariants(map);
    assert_round_trip(map);
}

/// Point queries and rays at every voxel's mean must agree with the voxel list.
fn query<const C: usize>(map: &Map<VOXELS, BLOCKS, C>) {
    let origin = Point3::new(0.0, 0.0, 0.0);
    let h = map.config().cell_size;
    for v in map.voxels().take(32) {
        let m = v.gaussian.mean;
        // Offsets are quantised to at most half a cell, so a mean may sit on the voxel's
        // face (and round into the neighbour), never beyond it.
        let c = v.key.center(h);
        let inside = (0..3).all(|i| (m[i] - c[i]).abs() <= 0.5 * h * (1.0 + 1e-4));
        assert!(
            inside,
            "mean {m:?} outside voxel {:?} (centre {c:?})",
            v.key
        );
        assert_eq!(map.voxel(&v.key).map(|w| w.key), Some(v.key));
        let _ = map.occupancy(&v.key);
        let dir = Vector3::new(m.x, m.y, m.z);
        if let Some(hit) = map.raycast(&origin, &dir, 5.0) {
            assert!(hit.t.is_finite() && (0.0..=5.0).contains(&hit.t), "{hit:?}");
            assert!((hit.class as usize) <= C, "{hit:?}");
            assert!(
                map.voxel(&hit.key).is_some(),
                "ray hit a voxel the map lacks"
            );
        }
    }
}

/// Renders 12x9 pixels from the origin and from 1.5 m in front of the first voxel.
fn render<const C: usize>(map: &Map<VOXELS, BLOCKS, C>) {
    let cam = sndt_core::Pinhole {
        fx: 8.0,
        fy: 8.0,
        cx: 6.0,
        cy: 4.5,
        width: 12,
        height: 9,
    };
    let mut poses = vec![Isometry3::identity()];
    if let Some(v) = map.voxels().next() {
        let m = v.gaussian.mean;
        let t = Translation3::new(m.x, m.y, m.z - 1.5);
        poses.push(Isometry3::from_parts(t, UnitQuaternion::identity()));
    }
    for pose in poses {
        let (mut labels, mut dist) = ([0u8; 108], [0f32; 108]);
        map.render(&pose, &cam, &mut labels, &mut dist).unwrap();
        for (&l, &d) in labels.iter().zip(&dist) {
            if l != INVALID_LABEL {
                assert!((l as usize) <= C, "rendered class {l}");
                assert!(
                    d.is_finite() && d >= 0.0,
                    "rendered distance {d} for class {l}"
                );
            }
        }
    }
}

fn integrate_small_frame<const C: usize>(map: &mut Map<VOXELS, BLOCKS, C>, pose: &Isometry3<f32>) {
    let (cam, depth, labels) = small_frame(C as u8);
    let image = DepthImage {
        camera: cam,
        depth: Depth::Metres(&depth),
        kind: DepthKind::Planar,
        labels: LabelImage::Top1(&labels),
        stride: 1,
    };
    let r = map
        .integrate_depth(pose, &image)
        .expect("a small frame near the origin");
    assert_accounted(&r, depth.len() as u64);
}

/// A map of 8 voxels and 4 blocks accepts the snapshot exactly when the big one does and
/// it fits; it may refuse for capacity before it reaches the big map's reason.
fn check_small_map<const C: usize>(bytes: &[u8]) {
    let mut big: Box<Map<VOXELS, BLOCKS, C>> = Box::new(Map::new(Config::DEFAULT));
    let mut small: Box<Map<8, 4, C>> = Box::new(Map::new(Config::DEFAULT));
    let (rb, rs) = (big.read_snapshot(bytes), small.read_snapshot(bytes));
    match rb {
        Ok(()) if big.len() <= 8 && big.block_count() <= 4 => {
            assert_eq!(
                rs,
                Ok(()),
                "a snapshot that fits is refused by the small map"
            );
            let (s, b) = (snapshot(&*small), snapshot(&*big));
            assert!(s == with_capacities(&b, 8, 4), "small and big maps differ");
        }
        Ok(()) => assert_eq!(rs, Err(Error::SnapshotCapacity)),
        Err(e) => assert!(
            rs == Err(e) || rs == Err(Error::SnapshotCapacity),
            "refused as {e:?} by the big map, {rs:?} by the small one"
        ),
    }
}
