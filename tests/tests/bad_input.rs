//! Bad input: every class of bad input is rejected or counted, never panics, and never
//! loses what is already in the map.

use sndt_core::{
    pose_from_matrix, Config, ConfigField, DepthImage, DepthKind, Error, Isometry3, LabelImage,
    LabeledPoint, Labels, Map, Matrix3, Occupancy, Pinhole, Point3, Translation3, UnitQuaternion,
    Vector3, MAX_FRAME_POINTS,
};
use sndt_tests::*;

type M = Map<4096, 2048, 40>;

/// A map with one room frame in it.
fn populated() -> Box<M> {
    let mut map = sndt_host::mapping::boxed_map::<4096, 2048, 40>(Config::DEFAULT).unwrap();
    let pose = sndt_host::dataset::synthetic::room::orbit(6)[2];
    let pts = room_frame(&pose, &camera(32, 24));
    let r = map.integrate(&pose, &pts).unwrap();
    assert_eq!(r.points_used as usize, pts.len());
    assert!(map.len() > 100);
    map
}

fn pose_at(x: f32, y: f32, z: f32) -> Isometry3<f32> {
    Isometry3::from_parts(Translation3::new(x, y, z), UnitQuaternion::identity())
}

/// A frame that must leave the content untouched (it still counts as a frame).
fn assert_frame_changes_nothing(map: &mut M, pose: &Isometry3<f32>, pts: &[LabeledPoint]) {
    let before = content(map);
    let frames = map.stats().frames;
    let r = map.integrate(pose, pts).unwrap();
    assert_accounted(&r, pts.len());
    assert_eq!(r.points_used, 0, "{r:?}");
    assert_eq!(
        (r.rays, r.end_voxels, r.voxels_created, r.blocks_created),
        (0, 0, 0, 0)
    );
    assert_eq!(content(map), before, "a rejected frame changed the map");
    assert_eq!(map.stats().frames, frames + 1);
}

/// An error must leave the map bit-identical (frame counter included).
fn assert_untouched<T: std::fmt::Debug>(
    map: &mut M,
    expected: Error,
    f: impl FnOnce(&mut M) -> Result<T, Error>,
) {
    let before = map.checksum();
    let snap = snapshot(map);
    let r = f(map);
    assert_eq!(r.unwrap_err(), expected);
    assert_eq!(map.checksum(), before);
    assert_eq!(snapshot(map), snap);
}

#[test]
fn invalid_depths_are_counted_and_change_nothing() {
    let mut map = populated();
    let cam = camera(8, 6);
    let bad = [
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        0.0,
        -0.0,
        -1.0,
        -f32::MIN_POSITIVE,
    ];
    let depth: Vec<f32> = (0..48).map(|i| bad[i % bad.len()]).collect();
    let labels = vec![1u8; 48];
    let pose = sndt_host::dataset::synthetic::room::orbit(6)[2];
    let before = content(&map);
    let r = map
        .integrate_depth(&pose, &depth_image(cam, &depth, &labels))
        .unwrap();
    assert_eq!(r.rejected_depth, 48);
    assert_accounted(&r, 48);
    assert_eq!(content(&map), before);

    // Mixed with valid depths: exactly the invalid ones are rejected.
    let depth: Vec<f32> = (0..48)
        .map(|i| if i % 3 == 0 { bad[i % bad.len()] } else { 2.0 })
        .collect();
    let r = map
        .integrate_depth(&pose, &depth_image(cam, &depth, &labels))
        .unwrap();
    assert_eq!((r.rejected_depth, r.points_used), (16, 32));
    // Range depth images reject the same way.
    let img = DepthImage {
        kind: DepthKind::Range,
        ..depth_image(cam, &depth, &labels)
    };
    assert_eq!(map.integrate_depth(&pose, &img).unwrap().rejected_depth, 16);
}

#[test]
fn non_finite_and_zero_points_are_counted_and_change_nothing() {
    let mut map = populated();
    let pose = sndt_host::dataset::synthetic::room::orbit(6)[2];
    let bad = [
        lp(f32::NAN, 0.0, 1.0, 1),
        lp(0.0, f32::INFINITY, 1.0, 1),
        lp(0.0, 0.0, f32::NEG_INFINITY, 1),
        lp(0.0, 0.0, 0.0, 1),
        lp(f32::MAX, f32::MAX, 0.0, 1), // |p|^2 overflows to inf
    ];
    assert_frame_changes_nothing(&mut map, &pose, &bad);
    let r = map.integrate(&pose, &bad).unwrap();
    assert_eq!(r.rejected_depth, 5);
}

#[test]
fn invalid_poses_are_errors_and_change_nothing() {
    let mut map = populated();
    let pts = [lp(0.0, 0.0, 1.0, 1)];
    let cam = camera(8, 6);
    let (depth, labels) = (vec![1.0f32; 48], vec![1u8; 48]);
    let q = *UnitQuaternion::<f32>::identity().quaternion();
    let bad_poses = [
        pose_at(f32::NAN, 0.0, 0.0),
        pose_at(0.0, f32::INFINITY, 0.0),
        Isometry3::from_parts(
            Translation3::new(1.0, 1.0, 1.0),
            UnitQuaternion::new_unchecked(q * 1.1),
        ),
        Isometry3::from_parts(
            Translation3::new(1.0, 1.0, 1.0),
            UnitQuaternion::new_unchecked(q * 0.5),
        ),
        Isometry3::from_parts(
            Translation3::new(1.0, 1.0, 1.0),
            UnitQuaternion::new_unchecked(q * 0.0),
        ),
        Isometry3::from_parts(
            Translation3::new(1.0, 1.0, 1.0),
            UnitQuaternion::new_unchecked(q * f32::NAN),
        ),
    ];
    for pose in bad_poses {
        assert_untouched(&mut map, Error::InvalidPose, |m| m.integrate(&pose, &pts));
        assert_untouched(&mut map, Error::InvalidPose, |m| {
            m.integrate_depth(&pose, &depth_image(cam, &depth, &labels))
        });
        let (mut l, mut d) = (vec![0u8; 48], vec![0f32; 48]);
        assert_eq!(
            map.render(&pose, &cam, &mut l, &mut d),
            Err(Error::InvalidPose)
        );
    }
}

#[test]
fn pose_from_matrix_rejects_non_rotations() {
    let t = Vector3::new(1.0, 2.0, 3.0);
    let bad = [
        Matrix3::new(1.0, 0.2, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0), // shear
        Matrix3::identity() * 1.1,                                 // scale
        Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0)),     // reflection
        Matrix3::from_diagonal(&Vector3::new(-1.0, -1.0, -1.0)),   // point reflection
        Matrix3::zeros(),
        Matrix3::identity() * f32::NAN,
    ];
    for r in bad {
        assert_eq!(pose_from_matrix(&r, &t), Err(Error::InvalidPose), "{r}");
    }
    assert_eq!(
        pose_from_matrix(&Matrix3::identity(), &Vector3::new(f32::NAN, 0.0, 0.0)),
        Err(Error::InvalidPose)
    );
    // A proper rotation is accepted and reproduced.
    let rot = UnitQuaternion::from_euler_angles(0.3f32, -1.2, 2.5);
    let m = *rot.to_rotation_matrix().matrix();
    let pose = pose_from_matrix(&m, &t).unwrap();
    assert!(
        (pose.rotation.to_rotation_matrix().matrix() - m)
            .abs()
            .max()
            < 1e-5
    );
    assert_eq!(pose.translation.vector, t);
}

#[test]
fn bad_labels_are_counted_and_change_nothing() {
    let mut map = populated();
    let pose = sndt_host::dataset::synthetic::room::orbit(6)[2];
    let p = Point3::new(0.1, 0.2, 1.5);
    let mut four = Labels::top_k(&[(1, 200), (2, 100), (3, 50)]);
    four.len = 4;
    let mut huge_len = Labels::top1(1);
    huge_len.len = 255;
    let bad = [
        LabeledPoint::new(p, Labels::top1(41)),
        LabeledPoint::new(p, Labels::top1(255)),
        LabeledPoint::new(p, Labels::top_k(&[(1, 255), (41, 10)])),
        LabeledPoint::new(p, Labels::top_k(&[(1, 255), (2, 10), (200, 1)])),
        LabeledPoint::new(p, four),
        LabeledPoint::new(p, huge_len),
    ];
    assert_frame_changes_nothing(&mut map, &pose, &bad);
    let r = map.integrate(&pose, &bad).unwrap();
    assert_eq!(r.rejected_label, bad.len() as u32);
    // Label 40 (= CLASSES) and 0 (void) are valid.
    let ok = [
        LabeledPoint::new(p, Labels::top1(40)),
        LabeledPoint::new(p, Labels::top1(0)),
        LabeledPoint::new(p, Labels::NONE),
    ];
    let r = map.integrate(&pose, &ok).unwrap();
    assert_eq!((r.points_used, r.rejected_label), (3, 0));
    // Bad labels in a depth image are counted the same way.
    let cam = camera(4, 3);
    let depth = vec![2.0f32; 12];
    let labels = vec![41u8; 12];
    let r = map
        .integrate_depth(&pose, &depth_image(cam, &depth, &labels))
        .unwrap();
    assert_eq!(r.rejected_label, 12);
}

#[test]
fn points_outside_the_key_range_are_counted_and_change_nothing() {
    let mut map = populated();
    // Sensor near the upper key limit (32767 * 0.1 m); points 5-10 m beyond it.
    let pose = pose_at(3276.0, 0.0, 0.0);
    let pts = [
        lp(5.0, 0.0, 0.0, 1),
        lp(10.0, 1.0, 0.0, 2),
        lp(19.0, 0.0, 0.0, 3),
    ];
    assert_frame_changes_nothing(&mut map, &pose, &pts);
    let r = map.integrate(&pose, &pts).unwrap();
    assert_eq!(r.rejected_out_of_range, 3);
    // Beyond max range the truncated end is outside the key range too.
    let far = [lp(30.0, 0.0, 0.0, 1)];
    let r = map.integrate(&pose, &far).unwrap();
    assert_eq!(r.rejected_out_of_range + r.truncated, 1);
    assert_accounted(&r, 1);
}

#[test]
fn sensor_outside_the_key_range_is_an_error() {
    let mut map = populated();
    let pts = [lp(0.0, 0.0, 1.0, 1)];
    for pose in [
        pose_at(1e4, 0.0, 0.0),
        pose_at(0.0, -3276.9, 0.0),
        pose_at(0.0, 0.0, 1e30),
    ] {
        assert_untouched(&mut map, Error::PoseOutOfRange, |m| {
            m.integrate(&pose, &pts)
        });
    }
}

#[test]
fn wrong_image_sizes_are_errors() {
    let mut map = populated();
    let pose = sndt_host::dataset::synthetic::room::orbit(6)[2];
    let cam = camera(8, 6);
    let depth = vec![1.0f32; 48];
    let labels = vec![1u8; 48];
    let topk = vec![Labels::top1(1); 48];
    let short_d = vec![1.0f32; 47];
    let short_l = vec![1u8; 49];
    let short_k = vec![Labels::top1(1); 10];
    let images = [
        depth_image(cam, &short_d, &labels),
        depth_image(cam, &depth, &short_l),
        DepthImage {
            labels: LabelImage::TopK(&short_k),
            ..depth_image(cam, &depth, &labels)
        },
        DepthImage {
            stride: 0,
            ..depth_image(cam, &depth, &labels)
        },
        depth_image(Pinhole { fx: 0.0, ..cam }, &depth, &labels),
        depth_image(
            Pinhole {
                fy: f32::NAN,
                ..cam
            },
            &depth,
            &labels,
        ),
        depth_image(Pinhole { fx: -5.0, ..cam }, &depth, &labels),
        depth_image(
            Pinhole {
                cx: f32::INFINITY,
                ..cam
            },
            &depth,
            &labels,
        ),
        depth_image(Pinhole { width: 9, ..cam }, &depth, &labels),
    ];
    for img in images {
        assert_untouched(&mut map, Error::InvalidImage, |m| {
            m.integrate_depth(&pose, &img)
        });
    }
    // Correct sizes with every label kind work.
    for labels in [
        LabelImage::None,
        LabelImage::Top1(&labels),
        LabelImage::TopK(&topk),
    ] {
        let img = DepthImage {
            labels,
            ..depth_image(cam, &depth, &[])
        };
        assert_eq!(map.integrate_depth(&pose, &img).unwrap().points_used, 48);
    }
    // Render checks its buffers too.
    let (mut l, mut d) = (vec![0u8; 47], vec![0f32; 48]);
    assert_eq!(
        map.render(&pose, &cam, &mut l, &mut d),
        Err(Error::InvalidImage)
    );
    let (mut l, mut d) = (vec![0u8; 48], vec![0f32; 49]);
    assert_eq!(
        map.render(&pose, &cam, &mut l, &mut d),
        Err(Error::InvalidImage)
    );
}

#[test]
fn oversized_frames_are_errors() {
    let mut map = populated();
    let pose = sndt_host::dataset::synthetic::room::orbit(6)[2];
    let pts = vec![lp(0.0, 0.0, 1.0, 1); MAX_FRAME_POINTS + 1];
    assert_untouched(&mut map, Error::FrameTooLarge, |m| m.integrate(&pose, &pts));
    let cam = Pinhole {
        width: 1025,
        height: 1024,
        ..camera(1024, 1024)
    };
    let depth = vec![1.0f32; 1025 * 1024];
    let img = DepthImage {
        labels: LabelImage::None,
        ..depth_image(cam, &depth, &[])
    };
    assert_untouched(&mut map, Error::FrameTooLarge, |m| {
        m.integrate_depth(&pose, &img)
    });
}

#[test]
fn invalid_configs_are_errors_naming_the_field() {
    let mut map = populated();
    let mut bad = Vec::new();
    type Edit = (fn(&mut Config), ConfigField);
    let edits: [Edit; 12] = [
        (|c| c.cell_size = 0.0, ConfigField::CellSize),
        (|c| c.cell_size = f32::INFINITY, ConfigField::CellSize),
        (|c| c.quant_bits = 7, ConfigField::QuantBits),
        (|c| c.quant_bits = 0, ConfigField::QuantBits),
        (|c| c.n_min = 1, ConfigField::NMin),
        (|c| c.n_max = 70_000, ConfigField::NMax),
        (|c| c.hit = -1.0, ConfigField::Hit),
        (|c| c.miss = 0.5, ConfigField::Miss),
        (|c| c.lambda = 0.6, ConfigField::Lambda),
        (|c| c.top_k = 4, ConfigField::TopK),
        (|c| c.max_range = f32::NAN, ConfigField::MaxRange),
        // 10 km rays of 10 cm cells: valid once, now more than MAX_RAY_CELLS cells.
        (|c| c.max_range = 1e4, ConfigField::RayCells),
    ];
    for (edit, field) in edits {
        let mut c = Config::DEFAULT;
        edit(&mut c);
        bad.push((c, field));
    }
    for (c, field) in bad {
        let e = Error::InvalidConfig(field);
        assert_eq!(c.validate(), Err(e), "{c:?}");
        assert_eq!(Map::<8, 8, 2>::try_new(c).err(), Some(e));
        assert_untouched(&mut map, e, |m| m.reset(c));
        let text = e.to_string();
        assert!(
            text.contains(field.name()) && text.contains(" must be "),
            "{text}"
        );
    }
}

/// The error type's memory contract: one byte, `Copy`, with the field inside.
#[test]
fn error_is_one_copy_byte() {
    fn copy<T: Copy>(t: T) -> (T, T) {
        (t, t)
    }
    assert_eq!(std::mem::size_of::<Error>(), 1);
    assert_eq!(std::mem::size_of::<Option<Error>>(), 1);
    let (a, b) = copy(Error::InvalidConfig(ConfigField::RayCells));
    assert_eq!(a, b);
}

/// `Map::new` is documented to replace an invalid config by `Config::DEFAULT` (map.rs), and
/// "no input makes it panic" (lib.rs).
#[test]
fn map_new_replaces_every_invalid_config() {
    for edit in [
        |c: &mut Config| c.hit = -1.0,
        |c: &mut Config| c.miss = 0.5,
        |c: &mut Config| c.clamp_min = 1.0,
        |c: &mut Config| c.lambda = 0.6,
        |c: &mut Config| c.max_range = f32::NAN,
        |c: &mut Config| c.max_range = 1e4,
        |c: &mut Config| c.eigen_ratio = 2.0,
    ] {
        let mut c = Config::DEFAULT;
        edit(&mut c);
        assert!(matches!(c.validate(), Err(Error::InvalidConfig(_))));
        assert_eq!(
            Map::<8, 8, 2>::new(c).config(),
            &Config::DEFAULT,
            "{c:?} kept"
        );
    }
}

/// A snapshot whose stored config breaks a bound (here `max_range` = 10 km at 10 cm, once
/// valid, now more than `Config::MAX_RAY_CELLS` cells per ray) is refused on load, with a
/// matching CRC, and the map keeps its content.
#[test]
fn snapshot_with_absurd_max_range_is_refused() {
    let mut map = populated();
    let far = edit_header(&snapshot(&*map), |h| h.config.max_range = 1e4);
    assert_untouched(&mut map, Error::SnapshotCorrupt, |m| m.read_snapshot(&far));
    // The same bytes with the old 20 m read back.
    let bytes = edit_header(&far, |h| h.config.max_range = 20.0);
    map.read_snapshot(&bytes).unwrap();
}

#[test]
fn map_new_with_inverted_clamp_does_not_panic() {
    let mut c = Config::DEFAULT;
    c.clamp_min = 1.0;
    c.clamp_max = 0.5;
    let mut map: Map<64, 16, 4> = Map::new(c);
    let r = map.integrate(&Isometry3::identity(), &[lp(0.05, 0.05, 1.05, 1)]);
    assert!(r.is_ok());
}

#[test]
fn corrupt_snapshots_are_errors() {
    let mut map = populated();
    let good = snapshot(&*map);
    let garbage: Vec<u8> = (0..5000u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
        .collect();
    let mut flipped = good.clone();
    flipped[good.len() / 2] ^= 0x10;
    for (bytes, e) in [
        (&[][..], Error::SnapshotTruncated),
        (&garbage[..], Error::SnapshotMagic),
        (&good[..good.len() - 1], Error::SnapshotTruncated),
        (&flipped[..], Error::SnapshotChecksum),
    ] {
        assert_untouched(&mut map, e, |m| m.read_snapshot(bytes));
    }
}

/// A map that is full: nothing can be evicted within a frame (all its blocks are in use
/// by the frame), so updates are dropped and counted; across frames the farthest entries
/// are evicted and counted. Never a panic, never over capacity.
#[test]
fn full_map_drops_and_evicts_with_counts() {
    let mut map: Map<8, 2, 40> = Map::new(Config::DEFAULT);
    let pose = Isometry3::identity();
    // 16 voxels in 4 blocks far apart: only 2 blocks fit.
    let pts: Vec<LabeledPoint> = (0..16)
        .map(|i| {
            lp(
                0.05 + 0.4 * (i % 4) as f32,
                0.05,
                1.05 + 0.1 * (i / 4) as f32,
                1,
            )
        })
        .collect();
    let r = map.integrate(&pose, &pts).unwrap();
    assert_accounted(&r, pts.len());
    assert!(r.dropped_points > 0, "{r:?}");
    assert!(r.dropped_misses > 0, "{r:?}");
    assert_eq!(map.stats().dropped_points, r.dropped_points as u64);
    assert_eq!(map.stats().dropped_misses, r.dropped_misses as u64);
    assert!(map.len() <= 8 && map.block_count() <= 2);

    // The surviving voxels are intact; a new frame elsewhere evicts them, counted.
    let old: Vec<_> = map.voxels().map(|v| (v.key, v.gaussian)).collect();
    assert!(!old.is_empty());
    let pose2 = pose_at(20.0, 0.0, 0.0);
    let pts2 = [lp(0.05, 0.05, 0.45, 2), lp(0.06, 0.05, 0.46, 2)];
    let r2 = map.integrate(&pose2, &pts2).unwrap();
    assert_accounted(&r2, 2);
    assert!(r2.blocks_evicted > 0, "{r2:?}");
    let gone = old
        .iter()
        .filter(|(k, _)| map.gaussian(k).is_none())
        .count();
    assert_eq!(
        gone as u32, r2.voxels_evicted,
        "every lost voxel is counted"
    );
    for (k, g) in &old {
        if let Some(now) = map.gaussian(k) {
            assert_eq!(&now, g, "a kept voxel changed");
        }
    }
    let new_key = map.voxel_key(&[20.05, 0.05, 0.45]).unwrap();
    assert_eq!(map.occupancy(&new_key), Occupancy::Occupied);
    assert!(map.len() <= 8 && map.block_count() <= 2);
}

/// Extreme hit and miss values: whatever `Config::validate` accepts must not overflow the
/// fixed-point update (a saturating `to_fixed` of 1e7 is `i32::MAX`; adding it to a cell
/// in `i32` overflows). Rejecting the config is an acceptable answer; the largest
/// documented values (+-30) must be accepted.
#[test]
fn extreme_valid_hit_and_miss_do_not_overflow() {
    let mut accepted = 0;
    for (hit, miss) in [(1e7f32, -1e7f32), (30.0, -30.0)] {
        let mut c = Config::DEFAULT;
        c.hit = hit;
        c.miss = miss;
        c.miss_model = sndt_core::MissModel::Constant;
        let Ok(mut map) = Map::<64, 16, 4>::try_new(c) else {
            continue;
        };
        accepted += 1;
        let pts = [lp(0.05, 0.05, 1.05, 1)];
        for _ in 0..3 {
            map.integrate(&Isometry3::identity(), &pts).unwrap();
        }
        let end = map.voxel_key(&[0.05, 0.05, 1.05]).unwrap();
        assert_eq!(map.log_odds(&end), c.clamp_max, "hit {hit}");
        let before = map.voxel_key(&[0.05, 0.05, 0.55]).unwrap();
        assert_eq!(map.log_odds(&before), c.clamp_min, "miss {miss}");
    }
    assert!(accepted >= 1);
}

/// A ray passing exactly through a Gaussian's mean far before its end gives the strongest
/// NDT-OM miss, `p = 0.5 - lambda`. With `lambda = 0.5` that is `logit(0) = -inf`
/// (`i32::MIN` after a saturating `to_fixed`), which must not overflow when added to a
/// negative cell; a config with lambda = 0.5 may instead be rejected. The largest accepted
/// lambda must give a clamped-free voxel.
///
/// Geometry (h = 0.1): voxel (0, 0, 10) holds the 8 corners of a 4 cm cube around its
/// centre (S1 = 0, so its mean is the centre exactly); the sensor sits at the centre of
/// voxel (0, 0, 0) and a second cube of points in voxel (0, 0, 30) is the ray's end: the
/// ray runs along the z axis through the first voxel's mean, 2 m before its end.
#[test]
fn strongest_ndt_om_miss_does_not_overflow() {
    let mut accepted = 0;
    for lambda in [0.5f32, 0.49] {
        let mut c = Config::DEFAULT;
        c.lambda = lambda;
        let Ok(mut map) = Map::<64, 32, 4>::try_new(c) else {
            continue;
        };
        accepted += 1;
        let cube = |z: f32| -> Vec<LabeledPoint> {
            (0..8)
                .map(|i| {
                    let s = |b: usize| if i >> b & 1 == 1 { 0.02 } else { -0.02 };
                    lp(s(0), s(1), z - 0.05 + s(2), 1)
                })
                .collect()
        };
        let mut pts = cube(1.05);
        pts.extend(cube(3.05));
        let pose = pose_at(0.05, 0.05, 0.05);
        let v = map.voxel_key(&[0.05, 0.05, 1.05]).unwrap();
        for frame in 0..3 {
            map.integrate(&pose, &pts).unwrap();
            let g = map.gaussian(&v).unwrap();
            assert_eq!((g.mean.x, g.mean.y), (0.05, 0.05), "frame {frame}");
            // Hit (+0.85) then a miss of logit(0.5 - lambda) <= -3.9: clamped free.
            assert!(
                map.log_odds(&v) <= c.clamp_min + c.hit + 1e-3,
                "lambda {lambda}, frame {frame}: {}",
                map.log_odds(&v)
            );
        }
    }
    assert!(accepted >= 1);
}

/// `raycast` with an unbounded range (`max_t = inf`, or just very large) must neither
/// overflow its step count nor lose the hit.
#[test]
fn raycast_with_unbounded_range() {
    let cam = camera(64, 48);
    let depth = vec![2.05f32; 64 * 48];
    let labels = vec![3u8; 64 * 48];
    let mut map = sndt_host::mapping::boxed_map::<1024, 512, 4>(Config::DEFAULT).unwrap();
    map.integrate_depth(&Isometry3::identity(), &depth_image(cam, &depth, &labels))
        .unwrap();
    let o = Point3::new(0.05, 0.05, 0.0);
    let bounded = map
        .raycast(&o, &Vector3::z(), 5.0)
        .expect("wall within 5 m");
    assert!((bounded.t - 2.05).abs() < 0.05 && bounded.class == 3);
    for max_t in [1e9f32, f32::MAX, f32::INFINITY] {
        assert_eq!(
            map.raycast(&o, &Vector3::z(), max_t),
            Some(bounded),
            "max_t {max_t}"
        );
    }
}
