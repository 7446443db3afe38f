//! Capacity: a tiny map never exceeds its capacity, every eviction and drop is counted
//! (per frame and in the totals), and every point is accounted for.

use sndt_core::{
    Config, FrameReport, Isometry3, LabeledPoint, Labels, Map, MapStats, Point3, Translation3,
};
use sndt_tests::*;

type Tiny = Map<64, 16, 4>;

#[derive(Default)]
struct Totals {
    voxels_created: u64,
    voxels_evicted: u64,
    blocks_created: u64,
    blocks_evicted: u64,
    dropped_points: u64,
    dropped_misses: u64,
    frames: u32,
}

impl Totals {
    fn add(&mut self, r: &FrameReport) {
        self.voxels_created += r.voxels_created as u64;
        self.voxels_evicted += r.voxels_evicted as u64;
        self.blocks_created += r.blocks_created as u64;
        self.blocks_evicted += r.blocks_evicted as u64;
        self.dropped_points += r.dropped_points as u64;
        self.dropped_misses += r.dropped_misses as u64;
        self.frames += 1;
    }

    fn check(&self, map: &Tiny) {
        assert_capacity(map);
        let s: MapStats = map.stats();
        assert_eq!(s.frames, self.frames);
        assert_eq!(s.voxels_evicted, self.voxels_evicted);
        assert_eq!(s.blocks_evicted, self.blocks_evicted);
        assert_eq!(s.dropped_points, self.dropped_points);
        assert_eq!(s.dropped_misses, self.dropped_misses);
        // Nothing appears or disappears without being counted.
        assert_eq!(
            map.len() as u64,
            self.voxels_created - self.voxels_evicted,
            "voxels created - evicted must equal len()"
        );
        assert_eq!(
            map.block_count() as u64,
            self.blocks_created - self.blocks_evicted,
            "blocks created - evicted must equal block_count()"
        );
    }
}

/// Integrates one frame and checks everything a frame must satisfy.
fn step(map: &mut Tiny, totals: &mut Totals, pose: &Isometry3<f32>, points: &[LabeledPoint]) {
    let r = map.integrate(pose, points).unwrap();
    assert_accounted(&r, points.len());
    totals.add(&r);
    totals.check(map);
    if r.dropped_points == 0 {
        // Voxels that received points this frame are never evicted in the same frame.
        let h = map.config().cell_size;
        for p in points {
            let w = pose * p.position;
            // Points within rounding distance of a voxel face may land on either side.
            let near_face = w.iter().any(|&x| ((x / h) - (x / h).round()).abs() < 1e-4);
            if p.position.coords.norm() <= map.config().max_range && !near_face {
                let key = map.voxel_key(&[w.x, w.y, w.z]).unwrap();
                let g = map.gaussian(&key);
                assert!(g.is_some_and(|g| g.count > 0), "voxel {key:?} lost");
            }
        }
    }
    // The map stays internally consistent: its snapshot passes every read check.
    let snap = snapshot(map);
    let mut copy: Box<Tiny> = sndt_host::mapping::boxed_map(*map.config()).unwrap();
    copy.read_snapshot(&snap).unwrap();
    assert_eq!(copy.checksum(), map.checksum());
}

#[test]
fn room_orbit_never_exceeds_capacity() {
    let mut map: Tiny = Map::new(Config::DEFAULT);
    let mut totals = Totals::default();
    let cam = camera(32, 24);
    let mut points_total = 0;
    for pose in sndt_host::dataset::synthetic::room::orbit(24) {
        let mut points = room_frame(&pose, &cam);
        // Room labels are NYU40 ids; keep a few above CLASSES (rejected and counted).
        for (i, p) in points.iter_mut().enumerate() {
            if i % 17 != 0 {
                p.labels = Labels::top1(p.labels.classes[0] % 5);
            }
        }
        points_total += points.len();
        step(&mut map, &mut totals, &pose, &points);
    }
    assert!(points_total > 10_000);
    assert!(totals.voxels_evicted > 0 && totals.blocks_evicted > 0);
    assert!(
        totals.dropped_points > 0,
        "room frames need more than 16 blocks"
    );
}

/// A sensor walking along x, looking at a cluster of points 1 m ahead: every frame fits, so
/// old voxels and blocks must be evicted (and counted) to make room.
#[test]
fn walking_sensor_evicts_and_counts() {
    let mut map: Tiny = Map::new(Config::DEFAULT);
    let mut totals = Totals::default();
    for frame in 0..60 {
        let x = frame as f32 * 0.3;
        let pose = Isometry3::from_parts(Translation3::new(x, 0.05, 0.05), Default::default());
        let points: Vec<LabeledPoint> = (0..40)
            .map(|i| {
                let p = Point3::new(
                    0.02 + 0.05 * (i % 4) as f32,
                    0.02 + 0.05 * (i / 4 % 4) as f32,
                    1.02 + 0.1 * (i / 16) as f32,
                );
                LabeledPoint::new(p, Labels::top1(1 + (i % 4) as u8))
            })
            .collect();
        step(&mut map, &mut totals, &pose, &points);
    }
    assert!(totals.voxels_evicted > 0 && totals.blocks_evicted > 0);
    assert_eq!(map.stats().frames, 60);
}

/// Voxels fill before blocks: 64 voxels of a few blocks, then new voxels in the same blocks
/// force voxel (not block) eviction; block occupancy of evicted voxels stays.
#[test]
fn voxel_table_full_evicts_voxels_not_blocks() {
    let mut map: Tiny = Map::new(Config::DEFAULT);
    let mut totals = Totals::default();
    let pose = Isometry3::identity();
    // 4 x 4 x 4 voxels in one block (keys 0..4 on each axis) at z 1.0..1.4: 64 voxels.
    let grid = |z0: f32| -> Vec<LabeledPoint> {
        (0..64)
            .map(|i| {
                let (a, b, c) = (i % 4, i / 4 % 4, i / 16);
                lp(
                    0.05 + 0.1 * a as f32,
                    0.05 + 0.1 * b as f32,
                    z0 + 0.05 + 0.1 * c as f32,
                    1,
                )
            })
            .collect()
    };
    step(&mut map, &mut totals, &pose, &grid(1.2));
    assert_eq!(map.len(), 64);
    // A nearer layer of 16 new voxels: the voxel table is full, the farthest old voxels go.
    let near: Vec<_> = grid(0.4).into_iter().take(16).collect();
    step(&mut map, &mut totals, &pose, &near);
    assert!(totals.voxels_evicted >= 4, "{}", totals.voxels_evicted);
    assert_eq!(map.len(), 64 - totals.voxels_evicted as usize + 16);
    // Evicted voxels keep their occupancy in the block layer.
    let occupied = map.cells().filter(|&(_, l)| l > 0.0).count();
    assert!(
        occupied >= 64,
        "occupancy of evicted voxels was lost: {occupied}"
    );
}

/// Frame stamps are 16-bit: after 65535 frames they wrap, and stale per-frame masks of a
/// block last touched 65535 frames ago must not count as current (no extra hit).
#[test]
fn frame_stamp_wraparound_keeps_frames_separate() {
    let mut map: Tiny = Map::new(Config::DEFAULT);
    let pose = Isometry3::from_parts(Translation3::new(0.05, 0.05, 0.05), Default::default());
    let a = [
        lp(0.0, 0.0, 1.0, 1),
        lp(0.01, 0.0, 1.0, 1),
        lp(0.0, 0.01, 1.0, 1),
    ];
    let r = map.integrate(&pose, &a).unwrap();
    assert_eq!(r.end_voxels, 1);
    let key_a = map.voxel_key(&[0.05, 0.05, 1.05]).unwrap();
    let la = map.log_odds(&key_a);
    assert!(la > 0.8);
    for _ in 1..65535 {
        map.integrate(&pose, &[]).unwrap();
    }
    assert_eq!(map.stats().frames, 65535);
    // Same block as A (keys 0..4), different voxel; the ray does not pass through A.
    let b = [lp(0.1, 0.0, 1.0, 2)];
    let r = map.integrate(&pose, &b).unwrap();
    assert_eq!(
        r.end_voxels, 1,
        "a stale hit mask was taken for this frame's"
    );
    assert_eq!(map.log_odds(&key_a), la);
    assert_eq!(map.gaussian(&key_a).unwrap().count, 3);
}
