//! S-BKI / OS-BKI baselines: the kernel against hand-computed values, one labelled point's
//! update against a hand calculation, the paper's failure case (a wall with alternating
//! labels: S-BKI opens holes, OS-BKI keeps it), ray casting against an exact reference,
//! bad input, and `sndt experiment`'s S-NDT rows against the evaluation loop.

use sndt_core::{
    Config, DepthKind, Isometry3, Pinhole, Translation3, UnitQuaternion, INVALID_LABEL,
};
use sndt_host::baselines::bki::{
    kernel, BkiConfig, BkiMap, Readout, Sample, VoxelState, FREE, UNCLASSIFIED,
};
use sndt_host::dataset::open_spec;
use sndt_host::dataset::{Frame, FrameId, LabelSource, Rays};
use sndt_host::eval::experiment::{run, ExperimentOptions, Method, RunKey, Segmentation};
use std::sync::Arc;

/// Reference values: sigma0 [ (2 + cos 2 pi r)(1 - r) / 3 + sin(2 pi r) / (2 pi) ],
/// sigma0 = 10, evaluated by hand (Python, double precision).
const K_QUARTER: f32 = 6.591_549_4; // r = 1/4: 10 (2 (3/4) / 3 + 1 / (2 pi))
const K_HALF: f32 = 1.666_666_7; // r = 1/2: 10 (1 (1/2) / 3)
const K_TWO_THIRDS: f32 = 0.288_344_43; // r = 2/3: 10 (1.5 / 9 - sin(pi/3) / (2 pi))

#[test]
fn kernel_values_at_zero_half_one_and_beyond() {
    let l = 0.4;
    assert_eq!(kernel(0.0, l, 10.0), 10.0);
    assert!((kernel(0.1, l, 10.0) - K_QUARTER).abs() < 1e-5);
    assert!((kernel(0.2, l, 10.0) - K_HALF).abs() < 1e-5);
    assert_eq!(kernel(0.4, l, 10.0), 0.0);
    assert_eq!(kernel(0.6, l, 10.0), 0.0);
    assert_eq!(kernel(100.0, l, 10.0), 0.0);
    // Just inside the support it is tiny but not negative; it falls monotonically.
    assert!(kernel(0.399, l, 10.0) >= 0.0 && kernel(0.399, l, 10.0) < 1e-6);
    let mut prev = f32::INFINITY;
    for i in 0..=400 {
        let k = kernel(i as f32 * 0.001, l, 10.0);
        assert!(k <= prev + 1e-6, "kernel rises at {i} mm");
        prev = k;
    }
    // Scale with sigma0.
    assert!((kernel(0.2, l, 1.0) - K_HALF / 10.0).abs() < 1e-6);
}

#[test]
fn one_sample_spreads_the_kernel_over_voxels_within_its_length() {
    // Cell 10 cm, kernel 15 cm, a class-3 sample at voxel (0,0,0)'s centre: its own voxel
    // gets sigma0, the 6 face neighbours (10 cm) k(2/3), the 12 edge neighbours (14.1 cm,
    // r = 0.943) 10 [(2 + cos 2 pi r)(1 - r)/3 + sin(2 pi r)/(2 pi)] = 5.2652e-5, corners
    // (17.3 cm) nothing.
    let mut map = BkiMap::new(BkiConfig::new(0.1, 0.15)).unwrap();
    map.add_sample(&Sample {
        position: [0.05, 0.05, 0.05],
        bin: 3,
    });
    let at = |k: [i32; 3]| map.counts(k).map(|c| c[3]);
    assert_eq!(at([0, 0, 0]), Some(10.0));
    for k in [
        [1, 0, 0],
        [-1, 0, 0],
        [0, 1, 0],
        [0, -1, 0],
        [0, 0, 1],
        [0, 0, -1],
    ] {
        assert!((at(k).unwrap() - K_TWO_THIRDS).abs() < 1e-5, "{k:?}");
    }
    for k in [[1, 1, 0], [-1, 0, 1], [0, -1, -1]] {
        assert!((at(k).unwrap() - 5.265_17e-5).abs() < 2e-6, "{k:?}");
    }
    for k in [[1, 1, 1], [-1, -1, -1], [2, 0, 0]] {
        assert!(at(k).unwrap_or(0.0) == 0.0, "{k:?}");
    }
    // Only bin 3 moved.
    let c = map.counts([0, 0, 0]).unwrap();
    assert_eq!(c.iter().sum::<f32>(), 10.0);
}

/// A one-pixel camera at `t` looking along +z with planar depth `depth` and label `label`.
fn one_pixel(t: [f32; 3], depth: f32, label: u8) -> Frame {
    Frame {
        id: FrameId::parse("test/cam_00/0000").unwrap(),
        pose: Isometry3::from_parts(
            Translation3::new(t[0], t[1], t[2]),
            UnitQuaternion::identity(),
        ),
        rays: Arc::new(Rays::Pinhole(Pinhole {
            fx: 1.0,
            fy: 1.0,
            cx: 0.5,
            cy: 0.5,
            width: 1,
            height: 1,
        })),
        depth: vec![depth],
        depth_kind: DepthKind::Planar,
        labels: Some(vec![label]),
        predictions: None,
    }
}

const K_04: f32 = 3.317_455_3; // r = 0.4
const K_08: f32 = 0.025_691_205; // r = 0.8

#[test]
fn a_single_labelled_point_updates_as_calculated_by_hand() {
    // Camera at voxel (0,0,0)'s centre, hit 1 m ahead at voxel (0,0,10)'s centre, class 7.
    // Cell 10 cm, kernel 25 cm, free samples every 20 cm up to 20 cm before the hit: at
    // 0.2, 0.4, 0.6 and 0.8 m along the beam, plus the camera itself; each lands on a
    // voxel centre (z = 0.05, 0.25, 0.45, 0.65, 0.85).
    let config = BkiConfig {
        free_resolution: 0.2,
        ..BkiConfig::new(0.1, 0.25)
    };
    let mut map = BkiMap::new(config).unwrap();
    let report = map
        .integrate(&one_pixel([0.05, 0.05, 0.05], 1.0, 7), Some(&[7]))
        .unwrap();
    assert_eq!(
        (report.hits, report.hit_samples, report.free_samples),
        (1, 1, 5)
    );
    let c = |z: i32| map.counts([0, 0, z]).unwrap();
    let near = |a: f32, b: f32| (a - b).abs() < 1e-5;
    // The hit voxel: sigma0 for class 7, k(0.8) of free from the sample at 0.85.
    assert!(
        near(c(10)[7], 10.0) && near(c(10)[FREE], K_08),
        "{:?}",
        c(10)
    );
    // 0.95: k(0.4) from the hit and from the sample at 0.85.
    assert!(near(c(9)[7], K_04) && near(c(9)[FREE], K_04));
    // 0.85: its own sample, k(0.8) from 0.65; the hit k(0.8).
    assert!(near(c(8)[FREE], 10.0 + K_08) && near(c(8)[7], K_08));
    // 0.75: k(0.4) from 0.65 and 0.85; the hit is 0.3 away.
    assert!(near(c(7)[FREE], 2.0 * K_04) && c(7)[7] == 0.0);
    // Behind the hit: class evidence only.
    assert!(near(c(11)[7], K_04) && c(11)[FREE] == 0.0);
    assert!(near(c(12)[7], K_08) && c(12)[FREE] == 0.0);
    // Off the beam, one voxel sideways of the hit: k(0.4) of class 7, and free from the
    // sample at 0.85, 22.4 cm away (r = 0.894): 10 [(2 + cos 2 pi r)(1 - r)/3 +
    // sin(2 pi r)/(2 pi)] = 0.0011120.
    let side = map.counts([1, 0, 10]).unwrap();
    assert!(
        near(side[7], K_04) && (side[FREE] - 0.001_112_0).abs() < 2e-6,
        "{side:?}"
    );
    // The camera's sample (one neighbour 20 cm away) and the ones at 0.25 / 0.45 / 0.65 m
    // (two each).
    assert!(near(c(0)[FREE], 10.0 + K_08));
    for z in [2, 4, 6] {
        assert!(near(c(z)[FREE], 10.0 + 2.0 * K_08), "z {z}: {:?}", c(z));
    }
    // Read-outs: the hit voxel is occupied with class 7 in both, its front free.
    for r in [Readout::Sbki, Readout::Osbki] {
        assert_eq!(map.voxel([0, 0, 10], r), VoxelState::Occupied(7));
        assert_eq!(map.voxel([0, 0, 11], r), VoxelState::Occupied(7));
        assert_eq!(map.voxel([0, 0, 8], r), VoxelState::Free);
        assert_eq!(map.voxel([0, 0, 14], r), VoxelState::Unknown);
        assert_eq!(map.voxel([3, 0, 10], r), VoxelState::Unknown);
    }
    // A void hit is occupied evidence without a class.
    let mut void = BkiMap::new(config).unwrap();
    void.integrate(&one_pixel([0.05, 0.05, 0.05], 1.0, 0), Some(&[0]))
        .unwrap();
    assert!((void.counts([0, 0, 10]).unwrap()[UNCLASSIFIED] - 10.0).abs() < 1e-5);
    assert_eq!(
        void.voxel([0, 0, 10], Readout::Sbki),
        VoxelState::Occupied(0)
    );
    assert_eq!(
        void.voxel([0, 0, 10], Readout::Osbki),
        VoxelState::Occupied(0)
    );
}

/// A 2 m x 2 m wall 2.05 m in front of a camera at the origin (OpenCV axes: +z ahead),
/// labels from `label(x, y)` in world metres.
fn wall_frame(label: impl Fn(f32, f32) -> u8) -> Frame {
    let (w, h) = (200u32, 200u32);
    let cam = Pinhole {
        fx: 90.0,
        fy: 90.0,
        cx: 100.0,
        cy: 100.0,
        width: w,
        height: h,
    };
    let z = 2.05;
    let mut labels = Vec::new();
    for row in 0..h {
        for col in 0..w {
            let r = cam.ray(col, row);
            labels.push(label(r[0] * z, r[1] * z));
        }
    }
    Frame {
        id: FrameId::parse("wall/cam_00/0000").unwrap(),
        pose: Isometry3::identity(),
        rays: Arc::new(Rays::Pinhole(cam)),
        depth: vec![z; (w * h) as usize],
        depth_kind: DepthKind::Planar,
        labels: Some(labels),
        predictions: None,
    }
}

/// States of the wall's voxels (z index 20) in the central 1.2 m x 1.2 m.
fn wall_states(map: &BkiMap, readout: Readout) -> (usize, usize, usize) {
    let (mut free, mut occupied, mut unknown) = (0, 0, 0);
    for y in -6..6 {
        for x in -6..6 {
            match map.voxel([x, y, 20], readout) {
                VoxelState::Free => free += 1,
                VoxelState::Occupied(_) => occupied += 1,
                VoxelState::Unknown => unknown += 1,
            }
        }
    }
    (free, occupied, unknown)
}

#[test]
fn alternating_labels_open_holes_in_sbki_but_not_in_osbki() {
    // Cell 10 cm, kernel 30 cm, free samples every 10 cm: the paper's failure case. A
    // noisy segmentation that splits a wall between two classes (a 10 cm checkerboard of
    // wall / picture) halves each class's count, and the free samples in front outvote
    // each half: S-BKI's wall turns free. OS-BKI weighs all hits against all free samples
    // first and keeps it occupied.
    let config = BkiConfig {
        free_resolution: 0.1,
        ..BkiConfig::new(0.1, 0.3)
    };
    let noisy = wall_frame(|x, y| {
        if ((x / 0.1).floor() as i32 + (y / 0.1).floor() as i32) % 2 == 0 {
            1
        } else {
            11
        }
    });
    let mut map = BkiMap::new(config).unwrap();
    map.integrate(&noisy, noisy.labels.as_deref()).unwrap();
    let (free, occupied, unknown) = wall_states(&map, Readout::Sbki);
    assert_eq!(unknown, 0);
    // Near the optical axis, where the free samples come straight at the wall, free
    // (~25) outvotes either class (~20 each): over a third of the patch is a hole.
    assert!(free >= 48, "S-BKI: {free} free, {occupied} occupied of 144");
    assert_eq!(map.voxel([0, 0, 20], Readout::Sbki), VoxelState::Free);
    let (free, occupied, _) = wall_states(&map, Readout::Osbki);
    assert_eq!((free, occupied), (0, 144), "OS-BKI keeps the whole wall");
    // The map's own surface statistics see the same: every wall voxel held a hit.
    let s = map.surface_states(Readout::Sbki);
    assert!(s.voxels >= 400 && s.free >= 48, "{s:?}");
    let o = map.surface_states(Readout::Osbki);
    assert_eq!((o.voxels, o.free, o.unknown), (s.voxels, 0, 0));
    // Labels still come out as one of the two classes where OS-BKI reads them.
    for x in -6..6 {
        match map.voxel([x, 0, 20], Readout::Osbki) {
            VoxelState::Occupied(c) => assert!(c == 1 || c == 11, "class {c}"),
            s => panic!("{s:?}"),
        }
    }
    // The same wall with one label: S-BKI keeps it too, so the holes come from the
    // split labels, not from the free samples alone.
    let clean = wall_frame(|_, _| 1);
    let mut map = BkiMap::new(config).unwrap();
    map.integrate(&clean, clean.labels.as_deref()).unwrap();
    assert_eq!(wall_states(&map, Readout::Sbki), (0, 144, 0));
    assert_eq!(wall_states(&map, Readout::Osbki), (0, 144, 0));
}

/// Entry distance of a ray into the axis-aligned box `[lo, hi]`, if it meets it.
fn slab(o: [f32; 3], d: [f32; 3], lo: [f32; 3], hi: [f32; 3]) -> Option<f32> {
    let (mut t0, mut t1) = (0f32, f32::INFINITY);
    for a in 0..3 {
        let (ta, tb) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
        t0 = t0.max(ta.min(tb));
        t1 = t1.min(ta.max(tb));
    }
    (t0 <= t1).then_some(t0)
}

#[test]
fn label_grid_rays_return_the_first_occupied_voxel() {
    // Random labelled samples; compare every cast with the exact first entry over all
    // occupied voxels (slab test per voxel).
    let mut map = BkiMap::new(BkiConfig::new(0.1, 0.12)).unwrap();
    let mut seed = 12345u64;
    let mut rnd = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 33) as f32) / (1u64 << 31) as f32
    };
    for i in 0..60 {
        let p = [rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0];
        map.add_sample(&Sample {
            position: p,
            bin: 1 + i % 40,
        });
    }
    let grid = map.label_grid(Readout::Osbki);
    assert!(grid.occupied() > 60);
    let mut occupied = Vec::new();
    for x in -12..12 {
        for y in -12..12 {
            for z in -12..12 {
                if let VoxelState::Occupied(c) = map.voxel([x, y, z], Readout::Osbki) {
                    occupied.push(([x, y, z], c));
                }
            }
        }
    }
    assert_eq!(occupied.len(), grid.occupied());
    let mut hits = 0;
    for _ in 0..3000 {
        let o = [rnd() * 3.0 - 1.5, rnd() * 3.0 - 1.5, rnd() * 3.0 - 1.5];
        let mut d = [rnd() - 0.5, rnd() - 0.5, rnd() - 0.5];
        let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        d = d.map(|v| v / n);
        let expect = occupied
            .iter()
            .filter_map(|(k, c)| {
                let lo = k.map(|v| v as f32 * 0.1);
                slab(o, d, lo, lo.map(|v| v + 0.1)).map(|t| (t, *c))
            })
            .filter(|(t, _)| *t <= 5.0)
            .min_by(|a, b| a.0.total_cmp(&b.0));
        let got = grid.cast(o, d, 5.0);
        match expect {
            Some((t, c)) => {
                hits += 1;
                // Near-ties (two voxels entered within 1e-4 m) may go either way.
                let tied = occupied.iter().any(|(k, c2)| {
                    let lo = k.map(|v| v as f32 * 0.1);
                    *c2 != c
                        && slab(o, d, lo, lo.map(|v| v + 0.1))
                            .is_some_and(|t2| (t2 - t).abs() < 1e-4)
                });
                assert!(
                    got == Some(c) || tied,
                    "o {o:?} d {d:?}: {got:?} vs {c} at {t}"
                );
            }
            None => assert_eq!(got, None, "o {o:?} d {d:?}"),
        }
    }
    assert!(hits > 300, "{hits} rays hit");
    // Range limit: a voxel 1 m ahead is out of a 0.5 m range.
    let mut one = BkiMap::new(BkiConfig::new(0.1, 0.05)).unwrap();
    one.add_sample(&Sample {
        position: [1.05, 0.05, 0.05],
        bin: 9,
    });
    let g = one.label_grid(Readout::Sbki);
    assert_eq!(g.cast([0.05, 0.05, 0.05], [1.0, 0.0, 0.0], 2.0), Some(9));
    assert_eq!(g.cast([0.05, 0.05, 0.05], [1.0, 0.0, 0.0], 0.5), None);
    // Rendering a frame: the one-pixel camera looking at it.
    let mut f = one_pixel([1.05, 0.05, -1.0], 1.0, 0);
    f.depth = vec![f32::NAN];
    assert_eq!(g.render(&f, 20.0), vec![9]);
    f.pose.translation.vector.x = 3.0;
    assert_eq!(g.render(&f, 20.0), vec![INVALID_LABEL]);
}

#[test]
fn bad_input_is_refused_without_touching_the_map() {
    let config = BkiConfig::new(0.1, 0.2);
    assert!(BkiMap::new(BkiConfig {
        cell_size: -0.1,
        ..config
    })
    .is_err());
    assert!(BkiMap::new(BkiConfig {
        prior: f32::NAN,
        ..config
    })
    .is_err());
    let mut map = BkiMap::new(config).unwrap();
    let good = one_pixel([0.05, 0.05, 0.05], 1.0, 3);
    map.integrate(&good, Some(&[3])).unwrap();
    let before = map.counts([0, 0, 10]).unwrap();
    let blocks = map.block_count();
    // Label out of range, wrong label count, non-finite pose.
    assert!(map.integrate(&good, Some(&[41])).is_err());
    assert!(map.integrate(&good, Some(&[3, 3])).is_err());
    let mut nan_pose = good.clone();
    nan_pose.pose.translation.vector.y = f32::NAN;
    assert!(map.integrate(&nan_pose, Some(&[3])).is_err());
    assert_eq!(map.counts([0, 0, 10]).unwrap(), before);
    assert_eq!(map.block_count(), blocks);
    // NaN, infinite, negative and zero depth are skipped, as is a hit beyond max range.
    for d in [f32::NAN, f32::INFINITY, -1.0, 0.0, 25.0] {
        let r = map
            .integrate(&one_pixel([0.05, 0.05, 0.05], d, 3), Some(&[3]))
            .unwrap();
        assert_eq!(r.hits, 0, "depth {d}");
    }
    assert_eq!(map.counts([0, 0, 10]).unwrap(), before);
    // Samples far outside any sensible range are ignored rather than overflowing keys.
    map.add_sample(&Sample {
        position: [3e9, 0.0, 0.0],
        bin: 3,
    });
    map.add_sample(&Sample {
        position: [0.0, f32::NAN, 0.0],
        bin: 3,
    });
    assert_eq!(map.block_count(), blocks);
}

#[test]
fn experiment_sndt_rows_equal_the_evaluation_loop() {
    // Two trajectories of 3 frames at 20 cm: the experiment's S-NDT confusion must equal
    // `evaluate`'s exactly, for GT and predicted labels; BKI rows exist for each kernel.
    let data = open_spec("synthetic:2:3", &Default::default()).unwrap();
    let options = ExperimentOptions {
        cells: vec![0.2],
        kernels: vec![0.2, 0.4],
        ..Default::default()
    };
    let exp = run(data.as_ref(), &options, &|| {}).unwrap();
    assert_eq!(exp.frames, 6);
    assert_eq!(exp.runs.len(), 2 * (1 + 2 * 2));
    for (labels, source) in [
        (Segmentation::Gt, LabelSource::Gt),
        (Segmentation::Pred, LabelSource::Pred),
    ] {
        let eval = sndt_host::eval::evaluate::evaluate(
            data.as_ref(),
            &sndt_host::eval::evaluate::EvalOptions::new(Config::with_cell_size(0.2), source),
            &|| {},
        )
        .unwrap();
        let key = RunKey {
            labels,
            method: Method::Sndt,
            kernel_mm: 0,
            cell_mm: 200,
        };
        let run = &exp.runs[&key];
        assert_eq!(run.confusion, eval.confusion, "{labels:?}");
        assert_eq!(run.trajectories.len(), 2);
        assert!(run.mean_hz() > 0.0);
        assert_eq!(exp.inputs[&labels], eval.input, "{labels:?}");
        for method in [Method::Sbki, Method::Osbki] {
            for kernel_mm in [200, 400] {
                let m = exp.runs[&RunKey {
                    labels,
                    method,
                    kernel_mm,
                    cell_mm: 200,
                }]
                    .metrics();
                assert!(
                    m.miou > 0.2 && m.miou < 1.0,
                    "{method:?} {kernel_mm}: {}",
                    m.miou
                );
            }
        }
    }
    // S-BKI and OS-BKI share their map: same update times.
    let time = |method| {
        exp.runs[&RunKey {
            labels: Segmentation::Gt,
            method,
            kernel_mm: 200,
            cell_mm: 200,
        }]
            .trajectories
            .clone()
    };
    assert_eq!(time(Method::Sbki), time(Method::Osbki));
    // Tables and charts.
    let dir = std::env::temp_dir().join(format!("sndt-experiment-{}", std::process::id()));
    let written = exp.write(&dir).unwrap();
    assert_eq!(written.len(), 6 + 2 * 2);
    let t1 = std::fs::read_to_string(dir.join("table1.md")).unwrap();
    assert!(t1.contains("| GT segmentation | S-BKI (20cm) |"));
    assert!(t1.contains("| Predicted segmentation | OS-BKI (40cm) |"));
    assert!(t1.contains("| GT segmentation | S-NDT |"));
    let csv = std::fs::read_to_string(dir.join("table1.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + exp.runs.len());
    let t2 = std::fs::read_to_string(dir.join("table2.csv")).unwrap();
    assert_eq!(t2.lines().count(), 1 + 5);
    let svg = std::fs::read_to_string(dir.join("iou_pred.svg")).unwrap();
    assert!(svg.contains("OS-BKI (20cm) @ 20cm") && svg.contains("S-NDT @ 20cm"));
    std::fs::remove_dir_all(&dir).unwrap();
    // Top-k or no labels are refused.
    let bad = ExperimentOptions {
        labels: vec![LabelSource::PredTopk],
        ..options
    };
    assert!(run(data.as_ref(), &bad, &|| {}).is_err());
}

#[test]
fn experiment_passes_votes_per_frame_to_the_sndt_maps() {
    // `--votes-per-frame` must reach S-NDT: the experiment's confusion equals `evaluate`'s
    // with the same votes, and differs from the default's (4 votes instead of 64 on near
    // 20 cm voxels that receive hundreds of points per frame).
    let data = open_spec("synthetic:2:4", &Default::default()).unwrap();
    let options = ExperimentOptions {
        labels: vec![LabelSource::Pred],
        cells: vec![0.2],
        methods: vec![Method::Sndt],
        votes_per_frame: 4,
        ..Default::default()
    };
    let exp = run(data.as_ref(), &options, &|| {}).unwrap();
    let evaluate = |votes_per_frame| {
        let config = Config {
            votes_per_frame,
            ..Config::with_cell_size(0.2)
        };
        sndt_host::eval::evaluate::evaluate(
            data.as_ref(),
            &sndt_host::eval::evaluate::EvalOptions::new(config, LabelSource::Pred),
            &|| {},
        )
        .unwrap()
        .confusion
    };
    let key = RunKey {
        labels: Segmentation::Pred,
        method: Method::Sndt,
        kernel_mm: 0,
        cell_mm: 200,
    };
    assert_eq!(exp.runs.len(), 1);
    assert_eq!(exp.runs[&key].confusion, evaluate(4));
    assert_ne!(
        exp.runs[&key].confusion,
        evaluate(Config::DEFAULT.votes_per_frame)
    );
    // Out of 1..=64: refused before any mapping.
    for votes in [0, 65] {
        let bad = ExperimentOptions {
            votes_per_frame: votes,
            ..options.clone()
        };
        assert!(run(data.as_ref(), &bad, &|| {}).is_err(), "{votes}");
    }
}

/// `LabelGrid::render` draws a pinhole frame face by face; a frame with the same rays given
/// per pixel is cast ray by ray. On a synthetic room at 5, 10 and 20 cm, both read-outs,
/// frames at and between the mapped poses: the same label at >= 99.9% of the pixels
/// (they may differ only where a ray runs along a voxel edge).
#[test]
fn label_grid_faces_render_what_the_rays_cast() {
    use sndt_host::dataset::synthetic::{SynthOptions, Synthetic};
    use sndt_host::dataset::Dataset;
    let cam = Pinhole {
        fx: 277.0,
        fy: 277.0,
        cx: 160.0,
        cy: 120.0,
        width: 320,
        height: 240,
    };
    let split = Synthetic::new(SynthOptions {
        scenes: 1,
        frames: 24,
        camera: cam,
        ..SynthOptions::default()
    })
    .unwrap();
    let ids = split.trajectories()[0].1.clone();
    let frames: Vec<Frame> = ids.iter().map(|id| split.load(id).unwrap()).collect();
    let dirs: Vec<[f32; 3]> = (0..cam.height)
        .flat_map(|r| (0..cam.width).map(move |c| cam.ray(c, r)))
        .collect();
    let per_pixel = Arc::new(Rays::PerPixel {
        width: cam.width,
        height: cam.height,
        dirs,
    });
    for cell in [0.05f32, 0.1, 0.2] {
        let mut map = BkiMap::new(BkiConfig::new(cell, 2.0 * cell)).unwrap();
        for f in frames.iter().step_by(3) {
            map.integrate(f, f.labels.as_deref()).unwrap();
        }
        for readout in [Readout::Sbki, Readout::Osbki] {
            let grid = map.label_grid(readout);
            for f in frames.iter().skip(1).step_by(5) {
                let drawn = grid.render(f, 20.0);
                let cast = grid.render(
                    &Frame {
                        rays: per_pixel.clone(),
                        ..f.clone()
                    },
                    20.0,
                );
                let same = drawn.iter().zip(&cast).filter(|(a, b)| a == b).count();
                let hits = cast.iter().filter(|&&l| l != INVALID_LABEL).count();
                assert!(
                    hits > drawn.len() * 3 / 4,
                    "{cell} {readout:?}: {hits} hits"
                );
                assert!(
                    same * 1000 >= drawn.len() * 999,
                    "{cell} {readout:?} {}: {same} of {} agree",
                    f.id,
                    drawn.len()
                );
            }
        }
    }
}
