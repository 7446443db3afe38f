//! Requirements 6 and 7: a wall seen head-on (occupied surface, free space in front,
//! unknown behind, the wall's class), and a thin surface under grazing rays (NDT-OM keeps
//! it, constant misses erase it).

use sndt_core::{
    Config, Isometry3, LabeledPoint, Labels, Map, MissModel, Occupancy, Point3, Translation3,
    Vector3, VoxelKey,
};
use sndt_host::dataset::synthetic::room::{look_at, nyu, Scene};
use sndt_tests::*;
use std::collections::BTreeSet;

/// A synthetic wall: a planar depth image of constant depth 2.03 m (the wall plane z = 2.03
/// lies inside voxel layer 20 at h = 0.1), label 5, camera at the origin looking along +z.
#[test]
fn wall_depth_image_front_free_behind_unknown() {
    let cam = camera(64, 48);
    let depth = vec![2.03f32; 64 * 48];
    let labels = vec![5u8; 64 * 48];
    let mut map = sndt_host::mapping::boxed_map::<4096, 2048, 40>(Config::DEFAULT).unwrap();
    let r = map
        .integrate_depth(&Isometry3::identity(), &depth_image(cam, &depth, &labels))
        .unwrap();
    assert_eq!(r.points_used, 64 * 48);
    assert_accounted(&r, 64 * 48);
    assert_eq!(r.dropped_misses, 0);

    let h = 0.1f32;
    for (x, y) in [(0.05f32, 0.05f32), (-0.05, -0.05), (0.25, -0.15)] {
        let key = |z: f32| VoxelKey::from_point(&[x, y, z], h).unwrap();
        let wall = key(2.03);
        assert_eq!(wall.z, 20);
        assert_eq!(
            map.occupancy(&wall),
            Occupancy::Occupied,
            "wall at ({x}, {y})"
        );
        assert_eq!(map.class(&wall), Some((5, 1.0)));
        for kz in 0..20 {
            // Only voxels whose near face lies inside the frustum (half-width 0.577 z), and
            // the voxels around the sensor (every ray starts there).
            let half_width = 0.5 * kz as f32 * h;
            let at_sensor = kz == 0 && x.abs().max(y.abs()) < h;
            if x.abs().max(y.abs()) + h > half_width && !at_sensor {
                continue;
            }
            let k = key(kz as f32 * h + 0.05);
            assert_eq!(
                map.occupancy(&k),
                Occupancy::Free,
                "in front of the wall: {k:?}"
            );
        }
        for kz in 21..60 {
            let k = key(kz as f32 * h + 0.05);
            assert_eq!(map.log_odds(&k), 0.0, "behind the wall: {k:?}");
            assert_eq!(map.occupancy(&k), Occupancy::Unknown);
        }
    }
    // Globally: nothing behind the wall was observed, every surface voxel is the wall.
    assert!(map.cells().all(|(k, _)| k.z <= 20));
    assert_eq!(map.len() as u32, r.end_voxels);
    for v in map.voxels() {
        assert_eq!(v.key.z, 20);
        assert_eq!(v.occupancy(), Occupancy::Occupied);
        assert_eq!(v.class(), Some((5, 1.0)));
        // All points of a voxel have z = 2.03 exactly: the mean is within half a quantum
        // (h / 64) of it and the z variance is exactly zero.
        assert!((v.gaussian.mean.z - 2.03).abs() <= h / 128.0 + 1e-6);
        assert_eq!(v.gaussian.covariance[(2, 2)], 0.0);
    }
    // Free cells are exactly in front: the traversed voxels of the frustum.
    let free = map.cells().filter(|&(_, l)| l < 0.0).count();
    assert!(free > 2000, "{free}");
}

/// The box room, camera looking head-on at the wall y = 5 (cell 0.07 m so the wall plane is
/// not on a voxel boundary: 5 / 0.07 = 71.4).
#[test]
fn room_wall_front_free_behind_unknown() {
    let h = 0.07f32;
    let cfg = Config::with_cell_size(h);
    let scene = Scene::simple_room();
    let cam = camera(128, 96);
    let pose = look_at([4.5, 2.0, 1.5], [4.5, 5.0, 1.5]);
    let (depth, labels) = scene.render(&pose, &cam);
    let mut map = sndt_host::mapping::boxed_map::<16384, 8192, 40>(cfg).unwrap();
    let r = map
        .integrate_depth(&pose, &depth_image(cam, &depth, &labels))
        .unwrap();
    assert_accounted(&r, depth.len());
    assert_eq!(
        (r.dropped_points, r.voxels_evicted, r.blocks_evicted),
        (0, 0, 0)
    );

    let key = |y: f32| VoxelKey::from_point(&[4.5, y, 1.5], h).unwrap();
    let wall = key(4.999);
    assert_eq!(wall.y, 71);
    assert_eq!(map.occupancy(&wall), Occupancy::Occupied);
    assert_eq!(map.class(&wall).map(|c| c.0), Some(nyu::WALL));
    // In front: from 0.3 m after the camera to 0.3 m before the wall.
    let mut y = 2.3;
    while y < 4.7 {
        assert_eq!(map.occupancy(&key(y)), Occupancy::Free, "y = {y}");
        y += h / 2.0;
    }
    // Behind: inside the 10 cm wall and outside the room.
    let mut y = 5.04;
    while y < 7.0 {
        assert_eq!(map.occupancy(&key(y)), Occupancy::Unknown, "y = {y}");
        y += h / 2.0;
    }
    // No ray ever went beyond the wall plane (voxel 71 ends at 5.04).
    assert!(map.cells().all(|(k, _)| k.y <= 71));

    // Classes: a voxel whose mean lies inside exactly one box carries that box's label
    // for nearly every voxel (boundary voxels mix classes).
    let mut agree = 0;
    let mut total = 0;
    for v in map.voxels() {
        let m = v.gaussian.mean;
        let inside: Vec<u8> = scene
            .boxes
            .iter()
            .filter(|b| (0..3).all(|a| m[a] >= b.min[a] - 0.01 && m[a] <= b.max[a] + 0.01))
            .map(|b| b.label)
            .collect();
        if inside.len() == 1 {
            total += 1;
            if v.class().map(|c| c.0) == Some(inside[0]) {
                agree += 1;
            }
        }
    }
    assert!(total > 500, "{total}");
    assert!(
        agree * 100 >= total * 97,
        "{agree} of {total} voxels have their box's class"
    );
}

/// Surface: a horizontal 2 m x 2 m grid of points at z = 0.03 (voxel layer 0, h = 0.1),
/// 2 cm apart, seen three times from above.
fn surface_frames() -> Vec<(Isometry3<f32>, Vec<LabeledPoint>)> {
    let world: Vec<[f32; 3]> = (0..100 * 100)
        .map(|i| {
            let (a, b) = (i % 100, i / 100);
            [-0.99 + 0.02 * a as f32, -0.99 + 0.02 * b as f32, 0.03]
        })
        .collect();
    [[0.0, 0.0, 1.5], [0.3, -0.2, 1.4], [-0.3, 0.2, 1.6]]
        .iter()
        .map(|t| {
            let pose = look_at(*t, [t[0], t[1] + 0.001, 0.0]);
            let pts = world
                .iter()
                .map(|w| LabeledPoint::new(to_sensor(&pose, w), Labels::top1(2)))
                .collect();
            (pose, pts)
        })
        .collect()
}

/// The sensor just above the surface layer at x = -2.05; one point per end voxel on a far
/// "wall" at x = 2.55, z = 0.015. Every ray stays inside voxel layer 0 (z from 0.09 down to
/// 0.015), passing 1-4 cm above the surface points through the surface voxels' cells.
const GRAZING_SENSOR: [f32; 3] = [-2.05, 0.05, 0.09];

fn grazing_targets() -> Vec<[f32; 3]> {
    (0..9)
        .map(|j| [2.55, -0.75 + 0.2 * j as f32, 0.015])
        .collect()
}

fn grazing_frame() -> (Isometry3<f32>, Vec<LabeledPoint>) {
    let s = GRAZING_SENSOR;
    let pose = Isometry3::from_parts(Translation3::new(s[0], s[1], s[2]), Default::default());
    let pts = grazing_targets()
        .iter()
        .map(|w| LabeledPoint::new(to_sensor(&pose, w), Labels::top1(1)))
        .collect();
    (pose, pts)
}

type SurfaceMap = Map<4096, 2048, 4>;

fn surface_keys() -> BTreeSet<VoxelKey> {
    let mut s = BTreeSet::new();
    for x in -10..10 {
        for y in -10..10 {
            s.insert(VoxelKey { x, y, z: 0 });
        }
    }
    s
}

/// Runs the surface frames, returns the map and the surface log-odds before grazing.
fn build_surface(model: MissModel) -> Box<SurfaceMap> {
    let mut map = sndt_host::mapping::boxed_map::<4096, 2048, 4>(config_with(model)).unwrap();
    for (pose, pts) in surface_frames() {
        let r = map.integrate(&pose, &pts).unwrap();
        assert_eq!(r.points_used as usize, pts.len());
    }
    for k in surface_keys() {
        let g = map.gaussian(&k).expect("surface voxel");
        assert!(g.count >= map.config().n_min, "valid Gaussian");
        // Thin: all points at z = 0.03, so no z spread.
        assert_eq!(g.covariance[(2, 2)], 0.0);
        assert!((g.mean.z - 0.03).abs() < 1e-3);
        assert_eq!(map.occupancy(&k), Occupancy::Occupied);
    }
    map
}

#[test]
fn grazing_rays_keep_thin_surface_with_ndt_om_but_erase_it_with_constant_misses() {
    // The geometry really traverses the surface: each ray passes through at least 15
    // surface voxels' cells (checked with the core's own traversal), ending beyond them.
    let surface = surface_keys();
    let mut traversed = BTreeSet::new();
    for t in grazing_targets() {
        let on_ray: Vec<VoxelKey> = segment_voxels(&GRAZING_SENSOR, &t, 0.1).unwrap();
        let hits: Vec<_> = on_ray.iter().filter(|k| surface.contains(k)).collect();
        assert!(
            hits.len() >= 15,
            "ray to {t:?} crosses {} surface voxels",
            hits.len()
        );
        assert!(
            !surface.contains(on_ray.last().unwrap()),
            "rays end beyond the surface"
        );
        assert!(
            on_ray.iter().all(|k| k.z == 0),
            "grazing: the ray stays in layer 0"
        );
        traversed.extend(hits.into_iter().copied());
    }
    assert!(traversed.len() >= 100, "{}", traversed.len());

    let frames = 8;
    let mut results = Vec::new();
    for model in [MissModel::NdtOm, MissModel::Constant] {
        let mut map = build_surface(model);
        let before: Vec<f32> = traversed.iter().map(|k| map.log_odds(k)).collect();
        let (pose, pts) = grazing_frame();
        for _ in 0..frames {
            let r = map.integrate(&pose, &pts).unwrap();
            assert_eq!(r.points_used, 9);
            assert_eq!(r.rays, 9);
        }
        let after: Vec<f32> = traversed.iter().map(|k| map.log_odds(k)).collect();
        results.push((map, before, after));
    }

    // NDT-OM: the rays pass many standard deviations (sigma_z ~ 1 mm) from the flat
    // Gaussians, so the misses are negligible and the surface stays occupied.
    let (ndt, before, after) = &results[0];
    for ((k, b), a) in traversed.iter().zip(before).zip(after) {
        assert_eq!(ndt.occupancy(k), Occupancy::Occupied, "{k:?}");
        assert!(a >= &(b - 0.05), "{k:?}: {b} -> {a}");
    }
    // Constant misses: 8 x -0.4 = -3.2 beats the surface's at most 3 x 0.85 = 2.55.
    let (constant, before, after) = &results[1];
    for ((k, b), a) in traversed.iter().zip(before).zip(after) {
        assert!(*b > 1.0, "{k:?} was built occupied ({b})");
        assert_eq!(constant.occupancy(k), Occupancy::Free, "{k:?}: {b} -> {a}");
    }
    // What it means downstream: looking down at the surface, NDT-OM still sees it; with
    // constant misses the erased voxels are gone.
    let down = -Vector3::z();
    let k = *traversed.iter().next().unwrap();
    let c = k.center(0.1);
    let origin = Point3::new(c[0], c[1], 1.0);
    let hit = ndt
        .raycast(&origin, &down, 2.0)
        .expect("surface visible with NDT-OM");
    assert!((hit.t - 0.97).abs() < 0.02 && hit.class == 2, "{hit:?}");
    let miss = constant.raycast(&origin, &down, 2.0);
    assert!(miss.is_none_or(|h| h.key != k), "{miss:?}");
}

/// A range image (Euclidean distance) of constant 2 m puts every point on the sphere of
/// radius 2 around the camera; a planar one on the plane z = 2.
#[test]
fn range_and_planar_depth_images() {
    let cam = camera(48, 36);
    let depth = vec![2.0f32; 48 * 36];
    let labels = vec![1u8; 48 * 36];
    for kind in [sndt_core::DepthKind::Range, sndt_core::DepthKind::Planar] {
        let mut map = sndt_host::mapping::boxed_map::<4096, 1024, 4>(Config::DEFAULT).unwrap();
        let img = sndt_core::DepthImage {
            kind,
            ..depth_image(cam, &depth, &labels)
        };
        let r = map.integrate_depth(&Isometry3::identity(), &img).unwrap();
        assert_eq!(r.points_used, 48 * 36);
        for v in map.voxels() {
            let m = v.gaussian.mean;
            // A voxel's patch of the sphere sags at most h^2 / (8 r) ~ 1 mm below its
            // chord, and quantisation adds half a quantum (0.8 mm) per axis.
            let (value, want) = match kind {
                sndt_core::DepthKind::Range => (m.norm(), 2.0),
                sndt_core::DepthKind::Planar => (m.z, 2.0),
            };
            assert!((value - want).abs() < 3e-3, "{kind:?}: {m:?}");
        }
        // The wide-angle corners differ: range images are shallower there.
        let corner = map
            .voxels()
            .map(|v| v.gaussian.mean.z)
            .fold(f32::INFINITY, f32::min);
        match kind {
            sndt_core::DepthKind::Range => assert!(corner < 1.8, "{corner}"),
            sndt_core::DepthKind::Planar => assert!(corner > 1.99, "{corner}"),
        }
    }
}

/// Points beyond `max_range` only clear free space up to max range (end voxel included):
/// no surface voxel, no occupied cell, nothing beyond.
#[test]
fn points_beyond_max_range_only_clear_free_space() {
    let mut cfg = Config::DEFAULT;
    cfg.max_range = 2.0;
    let mut map = sndt_host::mapping::boxed_map::<64, 256, 4>(cfg).unwrap();
    let pose = Isometry3::from_parts(Translation3::new(0.05, 0.05, 0.05), Default::default());
    let pts = [
        LabeledPoint::new(Point3::new(0.0, 0.0, 5.0), Labels::top1(1)),
        LabeledPoint::new(Point3::new(0.001, 0.0, 7.0), Labels::top1(1)),
    ];
    let r = map.integrate(&pose, &pts).unwrap();
    assert_eq!(
        (r.truncated, r.points_used, r.end_voxels, r.rays),
        (2, 0, 0, 1)
    );
    assert_eq!(map.len(), 0);
    // The ray runs up the z axis to max range: 2.05 m is voxel 20.
    let free: BTreeSet<VoxelKey> = map
        .cells()
        .map(|(k, l)| {
            assert!(l < 0.0, "{k:?} not free");
            k
        })
        .collect();
    let expected: BTreeSet<VoxelKey> = (0..=20).map(|z| VoxelKey { x: 0, y: 0, z }).collect();
    assert_eq!(free, expected);
}
