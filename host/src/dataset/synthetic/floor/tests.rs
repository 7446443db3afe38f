use super::super::geometry::Bvh;
use super::super::{render, SynthOptions, Synthetic, DEFAULT_SEED};
use super::*;
use crate::dataset::Dataset;
use sndt_core::{Isometry3, Pinhole, Point3, Vector3};
use std::collections::HashSet;
use std::sync::OnceLock;

fn floor() -> &'static Floor {
    static FLOOR: OnceLock<Floor> = OnceLock::new();
    FLOOR.get_or_init(|| Floor::generate(DEFAULT_SEED))
}

/// Walks 1 and 2 at the default frame count.
fn walks() -> &'static [Vec<Isometry3<f32>>; 2] {
    static WALKS: OnceLock<[Vec<Isometry3<f32>>; 2]> = OnceLock::new();
    WALKS.get_or_init(|| [1, 2].map(|w| floor().walk(w, DEFAULT_FRAMES)))
}

fn eye(p: &Isometry3<f32>) -> [f32; 3] {
    let t = p.translation.vector;
    [t.x, t.y, t.z]
}

/// The default camera's field of view at `w` x `h` pixels.
fn small(w: u32, h: u32) -> Pinhole {
    let f = super::super::CAMERA.fx * w as f32 / 1024.0;
    Pinhole {
        fx: f,
        fy: f,
        cx: 0.5 * w as f32,
        cy: 0.5 * h as f32,
        width: w,
        height: h,
    }
}

#[test]
fn floor_has_eleven_rooms_of_every_kind_along_a_corridor_within_60_m() {
    let f = floor();
    assert_eq!(f.rooms.len(), ROOMS);
    const { assert!(ROOMS >= 10) };
    for kind in SceneKind::ALL {
        assert!(f.rooms.iter().any(|r| r.kind == kind), "no {kind:?}");
    }
    let e = f.extent();
    assert!(e.iter().all(|v| v.abs() <= 60.0), "{e:?}");
    let overlap =
        |a: &[f32; 4], b: &[f32; 4]| a[0] < b[2] && b[0] < a[2] && a[1] < b[3] && b[1] < a[3];
    for (i, r) in f.rooms.iter().enumerate() {
        assert!(!overlap(&r.interior, &f.corridor), "{}", r.name);
        for s in &f.rooms[i + 1..] {
            assert!(!overlap(&r.interior, &s.interior), "{} {}", r.name, s.name);
        }
        // The doorway opens onto the corridor, in the middle of the corridor's wall.
        let side = 0.5 * CORRIDOR_W + 0.5 * WALL_T;
        assert!((r.door[1].abs() - side).abs() < 1e-4, "{}", r.name);
        assert!(r.door[0] > f.corridor[0] && r.door[0] < f.corridor[2]);
        assert!(r.contains(&[r.door[0] + 0.2 * r.inward[0], r.door[1] + 0.2 * r.inward[1]]));
    }
    // Pictures hang on both walls of the corridor.
    let corridor = &f.group().parts()[ROOMS];
    for south in [true, false] {
        let on_side = |p: &&Primitive| p.label == PICTURE && (p.shape.aabb().min[1] < 0.0) == south;
        assert!(corridor.primitives().iter().filter(on_side).count() >= 2);
    }
    // Rooms and corridor keep their object instances apart.
    let mut seen = HashSet::new();
    for part in f.group().parts() {
        let mine: HashSet<u16> = part.primitives().iter().map(|p| p.instance).collect();
        assert!(mine.is_disjoint(&seen));
        seen.extend(mine);
    }
    // The labels the rooms have, and the corridor's.
    let classes = f.classes();
    for c in [
        WALL,
        FLOOR,
        CEILING,
        PICTURE,
        WINDOW,
        super::super::scenes::class::DOOR,
    ] {
        assert!(classes[c as usize], "class {c}");
    }
    let again = Floor::generate(DEFAULT_SEED);
    assert!(again.primitives().eq(f.primitives()));
}

#[test]
fn floor_rooms_are_the_generators_rooms_with_an_open_doorway() {
    // Same kinds, sizes and objects as SynthScene::generate makes them: only the door
    // wall (cut in three), the door leaf (swung open) and the placement differ.
    let f = floor();
    for (i, room) in f.rooms.iter().enumerate() {
        assert_eq!(room.generator % 6, i % 6);
        let scene = SynthScene::generate(room.generator, f.seed);
        assert_eq!(scene.kind, room.kind);
        let n = f.group().parts()[i].primitives().len();
        assert_eq!(n, scene.bvh.primitives().len() + 2, "{}", room.name);
        let r = room.interior;
        let mut size = [r[2] - r[0], r[3] - r[1]];
        size.sort_by(f32::total_cmp);
        let mut want = [scene.size[0], scene.size[1]];
        want.sort_by(f32::total_cmp);
        assert!((size[0] - want[0]).abs() < 1e-3 && (size[1] - want[1]).abs() < 1e-3);
    }
}

#[test]
fn walks_stay_in_free_space_at_person_height() {
    let f = floor();
    for (w, poses) in walks().iter().enumerate() {
        for (i, p) in poses.iter().enumerate() {
            let e = eye(p);
            assert!(f.free(&e, 0.3), "walk {} frame {i} at {e:?}", w + 1);
            assert!(
                (1.2..=1.6).contains(&e[2]),
                "walk {} frame {i}: z {}",
                w + 1,
                e[2]
            );
            let fwd = p.rotation * Vector3::z();
            assert!(
                fwd.z.abs() < 0.6,
                "walk {} frame {i} looks at {fwd:?}",
                w + 1
            );
        }
    }
    // A point inside a wall, outside the building and under a table are not free.
    let r = &f.rooms[0];
    assert!(!f.free(&[r.door[0] + 0.5, r.door[1], 1.4], 0.0));
    assert!(!f.free(&[0.0, 59.0, 1.4], 0.0));
    assert!(!f.free(&[0.0, 0.0, 2.45], 0.0));
}

#[test]
fn walks_move_and_turn_by_small_steps() {
    // At the default 1,000 frames: about 10 frames a second at walking speed.
    for (w, poses) in walks().iter().enumerate() {
        let walk = w as u32 + 1;
        let seconds = floor().walk_seconds(walk);
        assert!(
            (90.0..=125.0).contains(&seconds),
            "walk {walk}: {seconds} s"
        );
        for (i, pair) in poses.windows(2).enumerate() {
            let step = (pair[1].translation.vector - pair[0].translation.vector).norm();
            let turn = pair[1].rotation.angle_to(&pair[0].rotation).to_degrees();
            assert!(step <= 0.16, "walk {walk} frame {i}: {step} m");
            assert!(turn <= 9.0, "walk {walk} frame {i}: {turn} degrees");
        }
    }
}

#[test]
fn walks_enter_every_room_and_end_in_the_corridor() {
    let f = floor();
    for (w, poses) in walks().iter().enumerate() {
        for room in &f.rooms {
            let frames = poses
                .iter()
                .filter(|p| room.contains(&[eye(p)[0], eye(p)[1]]))
                .count();
            assert!(
                frames >= 20,
                "walk {}: {} frames in {}",
                w + 1,
                frames,
                room.name
            );
        }
        for p in [&poses[0], &poses[poses.len() - 1]] {
            assert!(inside(&f.corridor, &[eye(p)[0], eye(p)[1]]));
        }
    }
}

#[test]
fn walks_one_and_two_differ_on_the_same_floor() {
    let [one, two] = walks();
    let apart = one
        .iter()
        .zip(two)
        .filter(|(a, b)| (a.translation.vector - b.translation.vector).norm() > 1.0)
        .count();
    assert!(apart > one.len() / 2, "{apart}");
    // Walk 1 goes east, walk 2 west.
    assert!(eye(&one[0])[0] < eye(&one[one.len() - 1])[0]);
    assert!(eye(&two[0])[0] > eye(&two[two.len() - 1])[0]);
    // The walk does not change the floor.
    let camera = small(16, 12);
    let split = |walk| {
        Synthetic::new(SynthOptions {
            floor: Some(walk),
            frames: 2,
            camera,
            predictions: false,
            ..SynthOptions::default()
        })
        .unwrap()
    };
    let (a, b) = (split(1), split(2));
    let (fa, fb) = (a.floor_scene().unwrap(), b.floor_scene().unwrap());
    assert!(fa.primitives().eq(fb.primitives()));
    assert_ne!(a.poses(), b.poses());
    assert_eq!(a.frames()[0].to_string(), "synth_floor/cam_00/0000");
    assert_eq!(b.frames()[1].to_string(), "synth_floor/cam_01/0001");
}

#[test]
fn fewer_frames_sample_the_same_walk() {
    let f = floor();
    let full = &walks()[0];
    let short = f.walk(1, 20);
    assert_eq!(short.len(), 20);
    assert_eq!(short[0], full[0]);
    for p in &short {
        let near = full
            .iter()
            .map(|q| (p.translation.vector - q.translation.vector).norm())
            .fold(f32::INFINITY, f32::min);
        assert!(near < 0.1, "{near}");
    }
}

#[test]
fn floor_renders_as_one_hierarchy_does_casting_into_few_parts() {
    let f = floor();
    let flat = Bvh::new(f.primitives().copied().collect());
    let cam = small(64, 48);
    let (mut rays, mut parts) = (0usize, 0usize);
    for p in walks()[0].iter().step_by(25) {
        // Compared pixel by pixel (a failure shows the first, not the whole frame).
        let (a, b) = (render(f, p, &cam), render(&flat, p, &cam));
        let first = (0..a.planar.len()).find(|&i| {
            (a.planar[i], a.labels[i], a.instances[i]) != (b.planar[i], b.labels[i], b.instances[i])
        });
        assert_eq!(
            first,
            None,
            "{:?}",
            first.map(|i| (a.planar[i], a.labels[i], b.labels[i]))
        );
        let rot = p.rotation.to_rotation_matrix();
        let o = eye(p);
        for row in 0..cam.height {
            for col in 0..cam.width {
                let r = cam.ray(col, row);
                let d = rot * Vector3::new(r[0], r[1], r[2]);
                parts += f.group().cast_counted(&o, &[d.x, d.y, d.z], 100.0).1;
                rays += 1;
            }
        }
    }
    let mean = parts as f32 / rays as f32;
    // Of 12 parts, a ray enters the camera's own and now and then one through a
    // doorway (measured: 1.4).
    assert!(mean < 2.0, "{mean} parts per ray");
}

#[test]
fn default_walk_sees_far_more_surface_than_a_4096_voxel_map_holds() {
    // Distinct 10 cm voxels hit by every frame of walk 1 at 40x30 pixels (the full
    // 1024x768 frames hit more): 112,591, 27 times what a Map<4096, ..> holds.
    let cam = small(40, 30);
    let mut voxels = HashSet::new();
    for p in &walks()[0] {
        let r = render(floor(), p, &cam);
        for (i, &z) in r.planar.iter().enumerate().filter(|&(_, &z)| z > 0.0) {
            let ray = cam.ray(i as u32 % cam.width, i as u32 / cam.width);
            let v = p * Point3::new(ray[0] * z, ray[1] * z, z);
            voxels.insert([v.x, v.y, v.z].map(|c| (c / 0.1).floor() as i32));
        }
    }
    println!("walk 1: {} surface voxels of 10 cm at 40x30", voxels.len());
    assert!(voxels.len() > 10 * 4096, "{}", voxels.len());
}

#[test]
fn floor_frames_have_depth_labels_and_predictions() {
    let split = Synthetic::new(SynthOptions {
        floor: Some(1),
        frames: 20,
        camera: small(64, 48),
        ..SynthOptions::default()
    })
    .unwrap();
    assert_eq!(split.frames().len(), 20);
    assert!(split.describe().contains("walk 1 of 20 frames"));
    let mut classes = HashSet::new();
    for id in split.frames() {
        let f = split.load(id).unwrap();
        let labels = f.labels.as_ref().unwrap();
        let pred = f.predictions.as_ref().unwrap();
        assert_eq!(pred.top1().len(), labels.len());
        assert!(
            f.depth.iter().all(|&d| d > 0.0),
            "{id}: a ray left the building"
        );
        assert!(labels.iter().filter(|&&l| l > 0).count() > labels.len() / 2);
        classes.extend(labels.iter().copied());
    }
    assert!(classes.len() >= 15, "{} classes", classes.len());
    // Frames are deterministic, and other ids are refused.
    let id = &split.frames()[7];
    assert_eq!(split.load(id).unwrap().depth, split.load(id).unwrap().depth);
    let mut other = id.clone();
    other.cam = "cam_01".into();
    assert!(split.load(&other).is_err());
    other.cam = "cam_00".into();
    other.index = 20;
    assert!(split.load(&other).is_err());
}
