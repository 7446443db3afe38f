//! The synthetic split: renders against analytic ray-box intersections, trajectories,
//! the depth-noise model, the calibration of the predicted segmentation, and the round
//! trip through the prepared layout.

use sndt_core::{Isometry3, Pinhole, Point3, Vector3};
use sndt_host::dataset;
use sndt_host::dataset::synthetic::geometry::{Bvh, Primitive};
use sndt_host::dataset::synthetic::room::look_at;
use sndt_host::dataset::synthetic::scenes::{SceneKind, SynthScene};
use sndt_host::dataset::synthetic::{
    self, render, trajectory, DepthNoise, SynthOptions, Synthetic,
};
use sndt_host::dataset::OpenOptions;
use sndt_host::dataset::{Dataset, FrameId};
use sndt_host::eval::label_stats::LabelStats;
use std::sync::Mutex;

const SMALL: Pinhole = Pinhole {
    fx: 60.0,
    fy: 55.0,
    cx: 41.3,
    cy: 29.8,
    width: 80,
    height: 60,
};

fn aabb(min: [f32; 3], max: [f32; 3], label: u8) -> Primitive {
    Primitive::axis_box(min, max, label, label as u16)
}

/// A 4 x 3 x 2.5 m room with one table-sized box in it.
fn hand_room() -> SynthScene {
    let (x, y, z, t) = (4.0, 3.0, 2.5, 0.1);
    let prims = vec![
        aabb([-t, -t, -t], [x + t, y + t, 0.0], 2),
        aabb([-t, -t, z], [x + t, y + t, z + t], 22),
        aabb([-t, -t, 0.0], [0.0, y + t, z], 1),
        aabb([x, -t, 0.0], [x + t, y + t, z], 8),
        aabb([0.0, -t, 0.0], [x, 0.0, z], 9),
        aabb([0.0, y, 0.0], [x, y + t, z], 11),
        aabb([2.5, 1.0, 0.0], [3.2, 2.0, 0.8], 7),
    ];
    SynthScene {
        name: "hand".into(),
        kind: SceneKind::LivingRoom,
        size: [x, y, z],
        bvh: Bvh::new(prims),
        interest: vec![[2.85, 1.5, 0.8]],
    }
}

/// Nearest intersection of a world ray with the hand room, computed plane by plane:
/// (distance, label, gap to the second-nearest candidate surface).
fn analytic(o: &Vector3<f32>, d: &Vector3<f32>) -> (f32, u8) {
    let mut best = (f32::INFINITY, 0u8);
    let mut consider =
        |t: f32, label: u8, p: Vector3<f32>, inside: &dyn Fn(&Vector3<f32>) -> bool| {
            if t > 0.0 && t < best.0 && inside(&p) {
                best = (t, label);
            }
        };
    // Room faces: the inner planes of the six slabs.
    let room = |p: &Vector3<f32>| {
        (-1e-4..=4.0001).contains(&p.x)
            && (-1e-4..=3.0001).contains(&p.y)
            && (-1e-4..=2.5001).contains(&p.z)
    };
    for (axis, value, label) in [
        (2, 0.0, 2u8),
        (2, 2.5, 22),
        (0, 0.0, 1),
        (0, 4.0, 8),
        (1, 0.0, 9),
        (1, 3.0, 11),
    ] {
        let t = (value - o[axis]) / d[axis];
        consider(t, label, o + d * t, &room);
    }
    // The box: its five visible faces from inside the room (top, four sides).
    let in_box = |p: &Vector3<f32>| {
        (2.4999..=3.2001).contains(&p.x)
            && (0.9999..=2.0001).contains(&p.y)
            && (-1e-4..=0.8001).contains(&p.z)
    };
    for (axis, value) in [(2, 0.8), (0, 2.5), (0, 3.2), (1, 1.0), (1, 2.0)] {
        let t = (value - o[axis]) / d[axis];
        consider(t, 7, o + d * t, &in_box);
    }
    best
}

#[test]
fn render_agrees_with_analytic_plane_intersections() {
    let scene = hand_room();
    for (eye, target) in [
        ([0.7, 0.6, 1.5], [3.0, 1.6, 0.6]),
        ([3.6, 2.7, 1.2], [0.5, 0.4, 1.0]),
        ([2.0, 0.5, 2.0], [2.8, 1.5, 0.0]),
    ] {
        let pose = look_at(eye, target);
        let r = render(&scene, &pose, &SMALL);
        let rot = pose.rotation.to_rotation_matrix();
        let o = pose.translation.vector;
        let (mut checked, mut edges) = (0, 0);
        for row in 0..SMALL.height {
            for col in 0..SMALL.width {
                let i = (row * SMALL.width + col) as usize;
                // Independent camera model: pixel centre, pinhole, OpenCV axes.
                let dc = Vector3::new(
                    (col as f32 + 0.5 - SMALL.cx) / SMALL.fx,
                    (row as f32 + 0.5 - SMALL.cy) / SMALL.fy,
                    1.0,
                );
                let (t, label) = analytic(&o, &(rot * dc));
                let depth_ok = (r.planar[i] - t).abs() < 1e-4 * t.max(1.0);
                let range_ok = (r.range[i] - r.planar[i] * dc.norm()).abs() < 1e-5 * t.max(1.0);
                assert!(
                    range_ok,
                    "pixel {col},{row}: range {} planar {}",
                    r.range[i], r.planar[i]
                );
                // Rays grazing an edge (within 1 mm of two faces) may go either way.
                if !depth_ok || r.labels[i] != label {
                    let hit = pose * Point3::new(dc.x * t, dc.y * t, t);
                    let on_edge = [hit.x, hit.y, hit.z]
                        .iter()
                        .zip([
                            [0.0, 2.5, 3.2, 4.0],
                            [0.0, 1.0, 2.0, 3.0],
                            [0.0, 0.8, 2.5, 2.5],
                        ])
                        .filter(|(v, planes)| planes.iter().any(|p| (**v - p).abs() < 1e-3))
                        .count()
                        >= 2;
                    assert!(
                        on_edge,
                        "eye {eye:?} pixel {col},{row}: {} (class {}) vs analytic {t} (class {label})",
                        r.planar[i], r.labels[i]
                    );
                    edges += 1;
                }
                checked += 1;
            }
        }
        assert_eq!(checked, 80 * 60);
        assert!(edges < 20, "{edges} edge pixels");
        // The box is seen from these poses.
        assert!(r.labels.contains(&7));
    }
}

#[test]
fn trajectories_walk_at_person_height_in_free_space() {
    for i in [0, 2, 5] {
        let scene = SynthScene::generate(i, synthetic::DEFAULT_SEED);
        let poses = trajectory(&scene, 100, 77);
        assert_eq!(poses.len(), 100);
        let mut moved = 0.0;
        for w in poses.windows(2) {
            let step = (w[1].translation.vector - w[0].translation.vector).norm();
            assert!(step <= 0.085, "{}: step {step}", scene.name);
            moved += step;
        }
        assert!(
            moved > 1.0,
            "{}: the camera hardly moved ({moved} m)",
            scene.name
        );
        for p in &poses {
            let t = p.translation.vector;
            assert!((1.35..=1.75).contains(&t.z));
            assert!(
                scene.free(&[t.x, t.y, t.z], 0.45),
                "{}: camera in an obstacle",
                scene.name
            );
            // Looking within 50 degrees of horizontal.
            let fwd = p.rotation * Vector3::z();
            assert!(fwd.z.abs() < 0.78);
        }
        assert_eq!(trajectory(&scene, 100, 77), poses, "deterministic");
    }
}

#[test]
fn depth_noise_has_the_stated_spread() {
    let noise = DepthNoise::KINECT;
    let mut d = vec![3.0f32; 200_000];
    d[0] = 0.0; // invalid stays invalid
    noise.apply(&mut d, 5);
    assert_eq!(d[0], 0.0);
    let v = &d[1..];
    let mean = v.iter().map(|&x| x as f64).sum::<f64>() / v.len() as f64;
    let sd = (v.iter().map(|&x| (x as f64 - mean).powi(2)).sum::<f64>() / v.len() as f64).sqrt();
    let want = 0.0012 + 0.0019 * 2.6f64 * 2.6;
    assert!((mean - 3.0).abs() < 1e-3, "mean {mean}");
    assert!((sd / want - 1.0).abs() < 0.02, "sd {sd} vs {want}");
}

#[test]
fn default_split_covers_25_classes_and_prediction_is_calibrated() {
    // Every 10th frame of each trajectory of the default split (60 frames of 1024x768).
    let split = Synthetic::new(SynthOptions::default()).unwrap();
    let mut stats = LabelStats::default();
    for id in split.frames().iter().filter(|id| id.index % 10 == 0) {
        stats.add(&split.load(id).unwrap());
    }
    let (hist, conf) = (&stats.class_pixels, &stats.prediction);
    let present = hist[1..].iter().filter(|&&n| n > 0).count();
    assert!(present >= 25, "{present} classes in view");
    // The classes the paper names as hard are among them.
    for c in [23u8, 11, 35, 27, 26, 29, 15] {
        let in_scenes = split.scenes().iter().any(|s| s.classes()[c as usize]);
        assert!(in_scenes, "class {c} missing from the scenes");
    }
    let m = conf.metrics();
    assert!(
        (0.38..=0.45).contains(&m.miou),
        "raw prediction mIoU {:.2} %",
        m.miou * 100.0
    );
    // The network never predicts void.
    assert!((0..41).all(|g| conf.cm[g][0] == 0));
}

#[test]
fn frames_are_deterministic_and_consistent() {
    let opts = SynthOptions {
        scenes: 2,
        frames: 3,
        camera: SMALL,
        ..Default::default()
    };
    let a = Synthetic::new(opts.clone()).unwrap();
    let b = Synthetic::new(opts).unwrap();
    let id = FrameId::parse("synth_01_bedroom/cam_00/0002").unwrap();
    let (fa, fb) = (a.load(&id).unwrap(), b.load(&id).unwrap());
    assert_eq!(fa.depth, fb.depth);
    assert_eq!(fa.labels, fb.labels);
    assert_eq!(fa.predictions, fb.predictions);
    fa.validate().unwrap();
    // Top-3: distinct classes, sorted scores summing to at most 1.
    for (c, s) in fa
        .predictions
        .as_ref()
        .unwrap()
        .classes
        .iter()
        .zip(&fa.predictions.as_ref().unwrap().scores)
    {
        assert!(
            c[0] != c[1] && c[1] != c[2] && c[0] != c[2] && c.iter().all(|x| (1..=40).contains(x))
        );
        assert!(s[0] >= s[1] && s[1] >= s[2] && s[2] >= 0.0 && s.iter().sum::<f32>() <= 1.0 + 1e-6);
    }
    assert!(a
        .load(&FrameId::parse("synth_01_bedroom/cam_00/0003").unwrap())
        .is_err());
    assert!(a
        .load(&FrameId::parse("nowhere/cam_00/0000").unwrap())
        .is_err());
}

#[test]
fn written_split_reads_back_identically() {
    let dir = std::env::temp_dir().join(format!("sndt-synth-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let split = Synthetic::new(SynthOptions {
        scenes: 2,
        frames: 2,
        camera: SMALL,
        ..Default::default()
    })
    .unwrap();
    let seen = Mutex::new(Vec::new());
    let stats = Mutex::new(LabelStats::default());
    let frames = synthetic::write_split(&dir, &split, &|f| {
        seen.lock().unwrap().push(f.id.clone());
        stats.lock().unwrap().add(f);
    })
    .unwrap();
    assert_eq!(frames, 4);
    // Every frame is handed to the callback exactly once.
    let mut seen = seen.into_inner().unwrap();
    seen.sort_by_key(std::string::ToString::to_string);
    assert_eq!(seen, split.frames());
    assert_eq!(
        stats.into_inner().unwrap().class_pixels.iter().sum::<u64>(),
        4 * 80 * 60
    );
    let read = dataset::open(&dir, &OpenOptions::default()).unwrap();
    assert_eq!(read.frames(), split.frames());
    for id in split.frames() {
        let (a, b) = (split.load(id).unwrap(), read.load(id).unwrap());
        assert_eq!(a.labels, b.labels);
        assert_eq!(*b.rays, dataset::Rays::Pinhole(SMALL));
        for (x, y) in a.depth.iter().zip(&b.depth) {
            assert!((x - y).abs() <= 0.0005 + 1e-6, "{x} vs {y}"); // mm quantisation
        }
        let (pa, pb) = (a.predictions.unwrap(), b.predictions.unwrap());
        assert_eq!(pa.classes, pb.classes);
        for (x, y) in pa.scores.iter().flatten().zip(pb.scores.iter().flatten()) {
            assert!((x.min(0.9999) - y).abs() < 1e-5);
        }
        let (ta, tb): (&Isometry3<f32>, &Isometry3<f32>) = (&a.pose, &b.pose);
        assert!((ta.to_homogeneous() - tb.to_homogeneous()).abs().max() < 1e-5);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
