//! Shared helpers for the integration tests: snapshot helpers, report accounting, an
//! exact (f64) reference for voxel traversal, and small scenes.

use sndt_host::dataset::synthetic::{SynthOptions, Synthetic};

use sndt_core::{
    Config, DepthImage, DepthKind, FrameReport, Isometry3, LabelImage, LabeledPoint, Labels, Map,
    Pinhole, Point3, SnapshotHeader, VoxelKey,
};

/// The proptest config of every property test here, with `cases` cases. Failing cases
/// are saved next to the test's source, in `tests/tests/<file>.proptest-regressions`
/// (commit them; they are replayed first on every run). Proptest's default looks for a
/// `lib.rs` or `main.rs` above the test file to put them beside `src/`, finds none for
/// integration tests, and warns before falling back to this same place.
pub fn proptest_config(cases: u32) -> proptest::test_runner::Config {
    proptest::test_runner::Config {
        cases,
        failure_persistence: Some(Box::new(
            proptest::test_runner::FileFailurePersistence::WithSource("proptest-regressions"),
        )),
        ..proptest::test_runner::Config::default()
    }
}

/// The map's snapshot in a `Vec` of exactly `snapshot_len()` bytes.
pub fn snapshot<const V: usize, const B: usize, const C: usize>(map: &Map<V, B, C>) -> Vec<u8> {
    let mut buf = vec![0u8; map.snapshot_len()];
    let n = map
        .write_snapshot(&mut buf)
        .expect("a buffer of snapshot_len() bytes must be enough");
    assert_eq!(
        n,
        buf.len(),
        "write_snapshot must fill exactly snapshot_len() bytes"
    );
    buf
}

/// The map's content: its snapshot without the frame counter and the CRC, so a frame whose
/// points were all rejected (which still counts as a frame) compares equal.
pub fn content<const V: usize, const B: usize, const C: usize>(map: &Map<V, B, C>) -> Vec<u8> {
    let mut s = snapshot(map);
    let mut header = SnapshotHeader::read(&s).expect("the map's own snapshot header");
    header.frames = 0;
    header
        .rewrite(&mut s)
        .expect("a whole snapshot holds its header");
    s
}

/// A snapshot with its header changed by `edit` and its CRC recomputed, so a reader gets
/// past the checksum to the changed field (what a buggy writer could produce).
pub fn edit_header(snap: &[u8], edit: impl FnOnce(&mut SnapshotHeader)) -> Vec<u8> {
    let mut bytes = snap.to_vec();
    let mut header = SnapshotHeader::read(&bytes).expect("a snapshot header to edit");
    edit(&mut header);
    header
        .rewrite(&mut bytes)
        .expect("a whole snapshot holds its header");
    bytes
}

/// Every point of a frame must land in exactly one of these counters.
pub fn accounted(r: &FrameReport) -> u64 {
    r.points_used as u64
        + r.truncated as u64
        + r.rejected_depth as u64
        + r.rejected_label as u64
        + r.rejected_out_of_range as u64
        + r.dropped_points as u64
}

/// Asserts the point accounting identity of one frame.
pub fn assert_accounted(r: &FrameReport, points: usize) {
    assert_eq!(
        accounted(r),
        points as u64,
        "every point must be counted exactly once: {r:?}"
    );
}

/// Asserts that a map respects its capacities.
pub fn assert_capacity<const V: usize, const B: usize, const C: usize>(map: &Map<V, B, C>) {
    assert!(map.len() <= V, "len {} > capacity {V}", map.len());
    assert!(
        map.block_count() <= B,
        "block_count {} > capacity {B}",
        map.block_count()
    );
}

/// A config with another miss model.
pub fn config_with(model: sndt_core::MissModel) -> Config {
    let mut c = Config::DEFAULT;
    c.miss_model = model;
    c
}

/// The exact (f64) voxel traversal of a segment given in voxel units.
#[derive(Clone, Debug)]
pub struct Reference {
    /// Voxels the segment passes through, in order, both ends included.
    pub voxels: Vec<VoxelKey>,
    /// Smallest distance (in voxel units, along the segment) between two consecutive
    /// breakpoints: segment start/end and crossings of grid planes. When it is tiny the
    /// segment passes (nearly) through a voxel edge or corner, or an end (nearly) lies on a
    /// grid plane, and the order of the crossings is decided by rounding.
    pub min_gap: f64,
    /// Segment length in voxel units.
    pub length: f64,
}

/// Exact traversal of the segment `o -> t` (voxel units, i.e. metres divided by the cell
/// size): every voxel containing a point of the segment strictly between two consecutive
/// plane crossings, found by sorting all crossing parameters in f64 and taking each
/// interval's midpoint. Independent of the core's incremental DDA.
pub fn reference_traversal(o: [f32; 3], t: [f32; 3]) -> Reference {
    let o = o.map(f64::from);
    let t = t.map(f64::from);
    let d = [t[0] - o[0], t[1] - o[1], t[2] - o[2]];
    let length = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let mut bps = vec![0.0f64, 1.0];
    for a in 0..3 {
        if d[a] == 0.0 {
            continue;
        }
        let (lo, hi) = (o[a].min(t[a]), o[a].max(t[a]));
        let mut m = lo.ceil();
        while m <= hi {
            bps.push((m - o[a]) / d[a]);
            m += 1.0;
        }
    }
    bps.sort_by(f64::total_cmp);
    let key = |p: [f64; 3]| VoxelKey {
        x: p[0].floor() as i16,
        y: p[1].floor() as i16,
        z: p[2].floor() as i16,
    };
    let at = |s: f64| [o[0] + s * d[0], o[1] + s * d[1], o[2] + s * d[2]];
    let mut voxels = vec![key(o)];
    let mut min_gap = f64::INFINITY;
    for w in bps.windows(2) {
        min_gap = min_gap.min((w[1] - w[0]) * length);
        if w[1] > w[0] {
            let k = key(at(0.5 * (w[0] + w[1])));
            if voxels.last() != Some(&k) {
                voxels.push(k);
            }
        }
    }
    let end = key(t);
    if voxels.last() != Some(&end) {
        voxels.push(end);
    }
    Reference {
        voxels,
        min_gap,
        length,
    }
}

/// Metres to voxel units the way the core's key functions do (`p / h` in f32).
pub fn to_voxel_units(p: &[f32; 3], h: f32) -> [f32; 3] {
    [p[0] / h, p[1] / h, p[2] / h]
}

/// Manhattan distance of two keys.
pub fn manhattan(a: &VoxelKey, b: &VoxelKey) -> i32 {
    (a.x as i32 - b.x as i32).abs()
        + (a.y as i32 - b.y as i32).abs()
        + (a.z as i32 - b.z as i32).abs()
}

/// All voxels `voxels_on_segment` visits, in order.
pub fn segment_voxels(from: &[f32; 3], to: &[f32; 3], h: f32) -> Option<Vec<VoxelKey>> {
    let mut out = Vec::new();
    sndt_core::voxels_on_segment(from, to, h, |k| out.push(k)).then_some(out)
}

/// A pinhole camera of `width x height` pixels with a horizontal field of view of about
/// 60 degrees (Hypersim's), principal point centred.
pub fn camera(width: u32, height: u32) -> Pinhole {
    let f = sndt_host::dataset::synthetic::room::HYPERSIM_CAMERA.fx * width as f32 / 1024.0;
    Pinhole {
        fx: f,
        fy: f,
        cx: width as f32 / 2.0,
        cy: height as f32 / 2.0,
        width,
        height,
    }
}

/// A planar depth image with top-1 labels.
pub fn depth_image<'a>(cam: Pinhole, depth: &'a [f32], labels: &'a [u8]) -> DepthImage<'a> {
    DepthImage {
        camera: cam,
        depth: sndt_core::Depth::Metres(depth),
        kind: DepthKind::Planar,
        labels: LabelImage::Top1(labels),
        stride: 1,
    }
}

/// One frame of the box room rendered from `pose`, as labelled points in the sensor frame.
pub fn room_frame(pose: &Isometry3<f32>, cam: &Pinhole) -> Vec<LabeledPoint> {
    let room = sndt_host::dataset::synthetic::room::Scene::simple_room();
    let (depth, labels) = room.render(pose, cam);
    sndt_host::dataset::synthetic::room::points(&depth, &labels, cam)
}

/// A labelled point.
pub fn lp(x: f32, y: f32, z: f32, class: u8) -> LabeledPoint {
    LabeledPoint::new(Point3::new(x, y, z), Labels::top1(class))
}

/// World to sensor frame.
pub fn to_sensor(pose: &Isometry3<f32>, world: &[f32; 3]) -> Point3<f32> {
    pose.inverse_transform_point(&Point3::new(world[0], world[1], world[2]))
}

/// A 160x120 camera with the synthetic split's field of view (a tenth of its pixels in
/// each direction, about): frames that map and render in milliseconds.
pub const SMALL_CAMERA: Pinhole = Pinhole {
    fx: 138.6,
    fy: 138.6,
    cx: 80.0,
    cy: 60.0,
    width: 160,
    height: 120,
};

/// The synthetic split of `scenes` scenes with `frames` frames each, seen by `camera`,
/// with or without the simulated network's predictions (which cost most of a frame's
/// rendering time); everything else is the split's default.
pub fn synthetic(scenes: usize, frames: usize, camera: Pinhole, predictions: bool) -> Synthetic {
    Synthetic::new(SynthOptions {
        scenes,
        frames,
        camera,
        predictions,
        ..SynthOptions::default()
    })
    .expect("a synthetic split of valid options")
}
