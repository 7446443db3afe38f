//! Every dispatch level gives the same map, on frames of a procedural room: a 6 x 5 x 3 m
//! box with a sphere and a pillar in it, seen from a camera walking a circle. Built for
//! baseline x86-64 (`RUSTFLAGS=""`, as `scripts/test.sh` runs it), this compares the SSE2
//! build summing phase 1 by runs with the AVX2 and AVX-512 copies summing by voxel.

use sndt_core::{
    Config, Depth, DepthImage, DepthKind, Isometry3, LabelImage, LabeledPoint, Labels, Map,
    Pinhole, Point3, Record, Translation3, UnitQuaternion, Vector3,
};
use sndt_dispatch::{integrate_at, integrate_depth_at, level, Level};

const CAMERA: Pinhole = Pinhole {
    fx: 200.0,
    fy: 200.0,
    cx: 160.0,
    cy: 120.0,
    width: 320,
    height: 240,
};

/// Every level up to the CPU's.
fn levels() -> Vec<Level> {
    [Level::Baseline, Level::Avx2, Level::Avx512]
        .into_iter()
        .filter(|&l| l <= level())
        .collect()
}

/// Frame `i` of the walk: camera 1.5 m from the room's centre, looking along the circle.
fn pose(i: usize) -> Isometry3<f32> {
    let a = i as f32 * 0.35;
    let eye = Vector3::new(3.0 + 1.5 * a.cos(), 2.5 + 1.5 * a.sin(), 1.4);
    // Camera z along the walk's tangent, y down.
    let forward = Vector3::new(-a.sin(), a.cos(), -0.1).normalize();
    let rotation = UnitQuaternion::face_towards(&forward, &Vector3::new(0.0, 0.0, -1.0));
    Isometry3::from_parts(Translation3::from(eye), rotation)
}

/// The nearest surface along a world ray from `o` in direction `d`: (distance, class).
fn cast(o: Vector3<f32>, d: Vector3<f32>) -> (f32, u8) {
    let mut best = (f32::INFINITY, 0u8);
    // Room walls, floor and ceiling (classes 1 to 3).
    let lo = [0.0, 0.0, 0.0];
    let hi = [6.0, 5.0, 3.0];
    for axis in 0..3 {
        for (bound, class) in [
            (lo[axis], if axis == 2 { 2 } else { 1 }),
            (hi[axis], if axis == 2 { 3 } else { 1 }),
        ] {
            if d[axis].abs() > 1e-6 {
                let t = (bound - o[axis]) / d[axis];
                if t > 0.0 && t < best.0 {
                    best = (t, class);
                }
            }
        }
    }
    // A sphere (class 5) and a vertical pillar (class 7).
    let c = Vector3::new(4.5, 2.0, 0.8);
    let oc = o - c;
    let (b, cc) = (oc.dot(&d), oc.norm_squared() - 0.6 * 0.6);
    let disc = b * b - cc;
    if disc > 0.0 {
        let t = -b - disc.sqrt();
        if t > 0.0 && t < best.0 {
            best = (t, 5);
        }
    }
    let (px, py, r) = (1.5, 3.5, 0.25);
    let (ox, oy) = (o.x - px, o.y - py);
    let (a2, b2, c2) = (
        d.x * d.x + d.y * d.y,
        ox * d.x + oy * d.y,
        ox * ox + oy * oy - r * r,
    );
    let disc = b2 * b2 - a2 * c2;
    if a2 > 1e-9 && disc > 0.0 {
        let t = (-b2 - disc.sqrt()) / a2;
        if t > 0.0 && t < best.0 && (o.z + t * d.z) < 2.2 {
            best = (t, 7);
        }
    }
    best
}

/// Planar depth and labels of frame `i` (a few pixels without depth).
fn frame(i: usize) -> (Vec<f32>, Vec<u8>) {
    let pose = pose(i);
    let (w, h) = (CAMERA.width as usize, CAMERA.height as usize);
    let (mut depth, mut labels) = (vec![0f32; w * h], vec![0u8; w * h]);
    for r in 0..h {
        for c in 0..w {
            let ray = Vector3::new(
                (c as f32 + 0.5 - CAMERA.cx) / CAMERA.fx,
                (r as f32 + 0.5 - CAMERA.cy) / CAMERA.fy,
                1.0,
            );
            let d = pose.rotation * ray.normalize();
            let (t, class) = cast(pose.translation.vector, d);
            let k = r * w + c;
            // Planar depth: the distance along the camera's z.
            depth[k] = if (c * 7 + r * 3) % 97 == 0 {
                f32::NAN
            } else {
                t / ray.norm()
            };
            labels[k] = class;
        }
    }
    (depth, labels)
}

#[test]
fn every_level_maps_and_spills_the_same() {
    // The maps are built on the stack before they are boxed: room for them.
    let big_stack = std::thread::Builder::new().stack_size(64 << 20);
    big_stack
        .spawn(same_at_every_level)
        .unwrap()
        .join()
        .unwrap();
}

fn same_at_every_level() {
    let frames: Vec<(Vec<f32>, Vec<u8>)> = (0..6).map(frame).collect();
    let run = |l: Level| {
        let mut map: Box<Map<16384, 2048, 8>> = Box::new(Map::new(Config::with_cell_size(0.05)));
        let mut device: Box<Map<2048, 256, 8>> = Box::new(Map::new(Config::with_cell_size(0.05)));
        let mut records = Vec::new();
        for (i, (depth, labels)) in frames.iter().enumerate() {
            let image = DepthImage {
                camera: CAMERA,
                depth: Depth::Metres(depth),
                kind: DepthKind::Planar,
                labels: LabelImage::Top1(labels),
                stride: 1,
            };
            integrate_depth_at(l, &mut *map, &pose(i), &image, None).unwrap();
            let mut sink = |r: Record<'_>| {
                records.push(r.bytes.to_vec());
                true
            };
            integrate_depth_at(l, &mut *device, &pose(i), &image, Some(&mut sink)).unwrap();
        }
        // A point list too: every 9th pixel of the last frame, with two classes each.
        let (depth, labels) = &frames[5];
        let points: Vec<LabeledPoint> = (0..depth.len())
            .step_by(9)
            .filter(|&k| depth[k].is_finite())
            .map(|k| {
                let (c, r) = ((k % 320) as f32 + 0.5, (k / 320) as f32 + 0.5);
                let z = depth[k];
                let p = Point3::new(
                    (c - CAMERA.cx) / CAMERA.fx * z,
                    (r - CAMERA.cy) / CAMERA.fy * z,
                    z,
                );
                LabeledPoint::new(
                    p,
                    Labels::top_k(&[(labels[k], 200), (labels[k] % 8 + 1, 55)]),
                )
            })
            .collect();
        integrate_at(l, &mut *map, &pose(5), &points, None).unwrap();
        (map.checksum(), map.len(), device.checksum(), records)
    };
    let runs: Vec<_> = levels().into_iter().map(run).collect();
    assert!(runs[0].1 > 5_000, "{} voxels", runs[0].1);
    assert!(runs[0].3.len() > 500, "{} records", runs[0].3.len());
    assert!(runs.iter().all(|r| *r == runs[0]), "the levels differ");
}
