//! The raw Hypersim reader on the real sample (scene ai_037_002, cam_00) in
//! `tests/fixtures/hypersim` (unmodified Hypersim files, CC BY-SA 3.0, see the README
//! there), and on broken copies of it.
//!
//! Reference numbers marked "h5py" were printed by h5py 3.16 / numpy reading the same
//! files independently of this crate's HDF5 reader.

use sndt_core::{DepthKind, Matrix3, Vector3};
use sndt_host::dataset;
use sndt_host::dataset::hypersim::{self, Hypersim};
use sndt_host::dataset::OpenOptions;
use sndt_host::dataset::{Dataset, Frame, FrameId, Rays};
use std::path::{Path, PathBuf};
use std::sync::Arc;

const SCENE: &str = "ai_037_002";
const CAM: &str = "cam_00";
const DEPTH: &str = "frame.0000.depth_meters.hdf5";
const ORIENTATIONS: &str = "camera_keyframe_orientations.hdf5";
const POSITIONS: &str = "camera_keyframe_positions.hdf5";
/// `settings_units_info_meters_scale` of ai_037_002 in the camera CSV.
const METERS_SCALE: f64 = 0.009999999776482582;

/// The Hypersim sample checked into this crate.
fn fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/hypersim")
}

fn frame0() -> FrameId {
    FrameId {
        scene: SCENE.into(),
        cam: CAM.into(),
        index: 0,
    }
}

fn open_fixture() -> Hypersim {
    Hypersim::open(&fixture(), &OpenOptions::default()).expect("opening the fixture")
}

/// h5py: orientations[0] and orientations[99] (row-major R_world_from_cam, OpenGL axes).
const R0: [f64; 9] = [
    1.0,
    0.0,
    0.0,
    0.0,
    0.0093262055888772,
    -0.999956488609314,
    0.0,
    0.999956488609314,
    0.0093262055888772,
];
const R99: [f64; 9] = [
    -0.1505086069155383,
    0.01805605565088796,
    0.9884437961253417,
    0.9849654585692186,
    -0.08301904864467374,
    0.1514954883409483,
    0.08479507456139833,
    0.9963843718246815,
    -0.005289509775165043,
];
/// h5py: positions[0] and positions[99], asset units.
const P0: [f64; 3] = [2.91323471069336, -443.65399169921886, 97.61222076416016];
const P99: [f64; 3] = [-238.10917760995147, 280.0901420737906, 99.44278926155422];

#[test]
fn fixture_frame_zero_loads_with_h5py_values() {
    let ds = open_fixture();
    assert_eq!(ds.frames(), &[frame0()]);
    assert!(ds.describe().contains("1 frames"), "{}", ds.describe());
    let f = ds.load(&frame0()).unwrap();
    assert_eq!((f.rays.width(), f.rays.height()), (1024, 768));
    assert_eq!(f.depth.len(), 768 * 1024);
    assert_eq!(f.depth_kind, DepthKind::Range);
    assert!(
        f.labels.is_none(),
        "the public fixture has no semantic.hdf5"
    );
    assert!(f.predictions.is_none());
    assert!(matches!(f.rays.as_ref(), Rays::PerPixel { .. }));
    // Frames of a scene share one ray table while any of them is alive.
    let again = ds.load(&frame0()).unwrap();
    assert!(Arc::ptr_eq(&f.rays, &again.rays));

    // h5py: 0 NaN, 0 inf, min 2.9609375 (35 pixels), max 13.234375, float64 sum
    // 4685919.486328125 (mean 5.958454750478268).
    assert_eq!(f.depth.iter().filter(|d| d.is_nan()).count(), 0);
    assert!(f.depth.iter().all(|d| d.is_finite()));
    let min = f.depth.iter().cloned().fold(f32::INFINITY, f32::min);
    let max = f.depth.iter().cloned().fold(f32::NEG_INFINITY, f32::max);
    assert_eq!((min, max), (2.9609375, 13.234375));
    assert_eq!(f.depth.iter().filter(|&&d| d == min).count(), 35);
    let sum = f.depth.iter().map(|&d| d as f64).sum::<f64>();
    assert_eq!(sum, 4685919.486328125);
    // h5py: depth[row, col] (exact float16 values, exactly representable in f32).
    for (row, col, want) in [
        (0, 0, 6.29296875f64),
        (0, 1023, 4.34765625),
        (383, 511, 7.8828125),
        (384, 512, 7.8828125),
        (767, 0, 3.46875),
        (767, 1023, 3.283203125),
        (100, 200, 7.328125),
        (500, 700, 7.71484375),
    ] {
        assert_eq!(
            f64::from(f.depth[row * 1024 + col]),
            want,
            "pixel ({row}, {col})"
        );
    }
    // Every pixel valid: planar depth is range / |ray|, smaller than the range.
    assert!(f.planar_depth(0).unwrap() < f.depth[0]);
}

#[test]
fn fixture_poses_match_raw_keyframes() {
    let ds = open_fixture();
    assert_eq!(ds.meters_per_asset_unit(SCENE), Some(METERS_SCALE));
    let cam = ds.camera(SCENE).unwrap();
    assert!(cam.is_tilt_shift());
    assert_eq!((cam.width, cam.height), (1024, 768));
    let kf = ds.keyframe_poses(SCENE, CAM).unwrap();
    assert_eq!(kf.poses.len(), 100);
    // The fixture's rotations are orthonormal to 4.3e-8 (h5py/numpy): nothing repaired.
    assert!(kf.reorthonormalised.is_empty());
    assert_eq!(ds.reorthonormalised(), 0);

    let detail = fixture().join(SCENE).join("_detail").join(CAM);
    let (oshape, o) = hypersim::read_hdf5_f64(&detail.join(ORIENTATIONS)).unwrap();
    let (pshape, p) = hypersim::read_hdf5_f64(&detail.join(POSITIONS)).unwrap();
    assert_eq!((oshape, pshape), (vec![100, 3, 3], vec![100, 3]));
    // The reader's raw values are h5py's.
    assert_eq!(&o[..9], &R0);
    assert_eq!(&o[99 * 9..], &R99);
    assert_eq!(&p[..3], &P0);
    assert_eq!(&p[99 * 3..], &P99);

    let flip = Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0));
    for (k, pose) in kf.poses.iter().enumerate() {
        let t = pose.translation.vector;
        for i in 0..3 {
            let want = p[3 * k + i] * METERS_SCALE;
            assert!((t[i] as f64 - want).abs() < 1e-5, "keyframe {k} t[{i}]");
        }
        let r = pose
            .rotation
            .to_rotation_matrix()
            .into_inner()
            .cast::<f64>();
        assert!((r.transpose() * r - Matrix3::identity()).abs().max() < 1e-6);
        assert!((r.determinant() - 1.0).abs() < 1e-6);
        let want = Matrix3::from_row_slice(&o[9 * k..9 * k + 9]) * flip;
        assert!((r - want).abs().max() < 1e-6, "keyframe {k}: {r} vs {want}");
    }
    // Frame 0 looks horizontally along world +y (R0's GL -z column is (0, 0.99996, -0.0093)),
    // from 0.976 m above the floor.
    let f = ds.load(&frame0()).unwrap();
    let forward = f.pose.rotation * Vector3::z();
    assert!((forward.y - 0.999956).abs() < 1e-5 && forward.z < 0.0);
    assert!((f.pose.translation.vector.z - 0.976_122).abs() < 1e-5);
}

/// Least-squares plane `z = a x + b y + c` through `pts`: (a, b, c, tilt in degrees,
/// RMS orthogonal residual in metres).
fn fit_plane(pts: &[[f32; 3]]) -> (f64, f64, f64, f64, f64) {
    let n = pts.len() as f64;
    let mean = |k: usize| pts.iter().map(|p| p[k] as f64).sum::<f64>() / n;
    let (mx, my, mz) = (mean(0), mean(1), mean(2));
    let (mut sxx, mut sxy, mut syy, mut sxz, mut syz) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for p in pts {
        let (x, y, z) = (p[0] as f64 - mx, p[1] as f64 - my, p[2] as f64 - mz);
        sxx += x * x;
        sxy += x * y;
        syy += y * y;
        sxz += x * z;
        syz += y * z;
    }
    let det = sxx * syy - sxy * sxy;
    let a = (sxz * syy - syz * sxy) / det;
    let b = (syz * sxx - sxz * sxy) / det;
    let c = mz - a * mx - b * my;
    let norm = (a * a + b * b + 1.0).sqrt();
    let tilt = (1.0 / norm).acos().to_degrees();
    let ss: f64 = pts
        .iter()
        .map(|p| {
            let r = (p[2] as f64 - (a * p[0] as f64 + b * p[1] as f64 + c)) / norm;
            r * r
        })
        .sum();
    (a, b, c, tilt, (ss / n).sqrt())
}

/// Indices of the points of the lowest dense z-level: the first 1 cm bin (from the
/// bottom) holding at least 2% of the points, and everything within 2 cm of its centre.
fn lowest_level(pts: &[[f32; 3]]) -> Vec<usize> {
    let zmin = pts.iter().map(|p| p[2]).fold(f32::INFINITY, f32::min);
    let mut bins = vec![0usize; 1000];
    for p in pts {
        let b = ((p[2] - zmin) / 0.01) as usize;
        if b < bins.len() {
            bins[b] += 1;
        }
    }
    let first = bins
        .iter()
        .position(|&c| c * 50 >= pts.len())
        .expect("a dense level");
    let z0 = zmin + (first as f32 + 0.5) * 0.01;
    (0..pts.len())
        .filter(|&i| (pts[i][2] - z0).abs() < 0.02)
        .collect()
}

#[test]
fn fixture_frame_zero_floor_is_a_horizontal_plane() {
    let ds = open_fixture();
    let f = ds.load(&frame0()).unwrap();
    let pts: Vec<[f32; 3]> = f.world_points().into_iter().map(|(p, _)| p).collect();
    assert_eq!(pts.len(), 768 * 1024, "no NaN: every pixel gives a point");
    let floor = lowest_level(&pts);
    let floor_pts: Vec<[f32; 3]> = floor.iter().map(|&i| pts[i]).collect();
    let (a, b, c, tilt, rms) = fit_plane(&floor_pts);
    eprintln!(
        "floor: {} points, z = {a:.5} x + {b:.5} y + {c:.4}, tilt {tilt:.3} deg, rms {:.2} mm",
        floor_pts.len(),
        rms * 1e3
    );
    // numpy on the same files: ~153k points, tilt 0.12 deg, rms 2.9 mm, c = 0.004 m.
    assert!(floor_pts.len() > 140_000, "{}", floor_pts.len());
    assert!(tilt < 0.5, "tilt {tilt} deg");
    assert!(rms < 0.005, "rms {rms} m");
    assert!(c.abs() < 0.02, "the asset's floor is at z = 0: {c}");

    // The same pixels through the nominal pinhole: the floor tilts by ~5 degrees and
    // sinks by ~0.4 m, because ai_037_002 is a tilt-shift camera.
    let nominal = sndt_host::dataset::synthetic::room::HYPERSIM_CAMERA;
    let pin = Frame {
        rays: Arc::new(Rays::Pinhole(nominal)),
        ..f.clone()
    };
    let pin_pts: Vec<[f32; 3]> = pin.world_points().into_iter().map(|(p, _)| p).collect();
    assert_eq!(pin_pts.len(), pts.len());
    let same: Vec<[f32; 3]> = floor.iter().map(|&i| pin_pts[i]).collect();
    let (_, _, pc, ptilt, prms) = fit_plane(&same);
    let shift = floor
        .iter()
        .map(|&i| {
            let d: f32 = (0..3).map(|k| (pts[i][k] - pin_pts[i][k]).powi(2)).sum();
            d.sqrt() as f64
        })
        .sum::<f64>()
        / floor.len() as f64;
    eprintln!(
        "pinhole: tilt {ptilt:.2} deg, offset {pc:.3} m, rms {:.2} mm, mean shift {shift:.3} m",
        prms * 1e3
    );
    assert!(ptilt > 3.0, "pinhole tilt {ptilt}");
    assert!(pc < -0.2, "pinhole floor offset {pc}");
    assert!(shift > 0.3, "mean shift {shift}");
}

#[test]
fn dataset_open_dispatches_to_hypersim() {
    let ds = dataset::open(&fixture(), &OpenOptions::default()).unwrap();
    assert!(
        ds.describe().starts_with("raw Hypersim"),
        "{}",
        ds.describe()
    );
    assert_eq!(ds.trajectories().len(), 1);
    assert_eq!(ds.load(&frame0()).unwrap().pixels(), 768 * 1024);
    let missing = FrameId {
        index: 1,
        ..frame0()
    };
    let e = ds.load(&missing).unwrap_err();
    assert!(
        format!("{e:#}").contains("frame.0001.depth_meters.hdf5"),
        "{e:#}"
    );
}

/// A writable copy of the fixture layout in a fresh temporary directory.
fn copy_fixture(tag: &str) -> PathBuf {
    let root = std::env::temp_dir().join(format!("sndt-hypersim-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let src = fixture();
    for rel in [
        "metadata_camera_parameters.csv".to_string(),
        format!("{SCENE}/_detail/{CAM}/{ORIENTATIONS}"),
        format!("{SCENE}/_detail/{CAM}/{POSITIONS}"),
        format!("{SCENE}/images/scene_{CAM}_geometry_hdf5/{DEPTH}"),
    ] {
        let to = root.join(&rel);
        std::fs::create_dir_all(to.parent().unwrap()).unwrap();
        std::fs::write(&to, std::fs::read(src.join(&rel)).unwrap()).unwrap();
    }
    root
}

fn depth_path(root: &Path) -> PathBuf {
    root.join(SCENE)
        .join("images")
        .join(format!("scene_{CAM}_geometry_hdf5"))
        .join(DEPTH)
}

#[test]
fn truncated_depth_names_the_file() {
    let root = copy_fixture("truncated");
    let path = depth_path(&root);
    let bytes = std::fs::read(&path).unwrap();
    let ds = Hypersim::open(&root, &OpenOptions::default()).unwrap();
    assert!(ds.load(&frame0()).is_ok());
    for keep in [0, 64, 1000, bytes.len() / 2, bytes.len() - 100] {
        std::fs::write(&path, &bytes[..keep]).unwrap();
        let e = ds.load(&frame0()).unwrap_err();
        assert!(
            format!("{e:#}").contains(DEPTH),
            "truncated to {keep}: {e:#}"
        );
    }
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn wrong_depth_shape_names_the_file() {
    let root = copy_fixture("shape");
    let path = depth_path(&root);
    std::fs::remove_file(&path).unwrap();
    let f = rust_hdf5::H5File::create(&path).unwrap();
    let d = f
        .new_dataset::<f32>()
        .shape([768usize, 1000])
        .create("dataset")
        .unwrap();
    d.write_raw(&vec![1.0f32; 768 * 1000]).unwrap();
    f.close().unwrap();
    let ds = Hypersim::open(&root, &OpenOptions::default()).unwrap();
    let e = format!("{:#}", ds.load(&frame0()).unwrap_err());
    assert!(e.contains(DEPTH) && e.contains("[768, 1000]"), "{e}");
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn missing_orientations_names_the_file() {
    let root = copy_fixture("missing");
    std::fs::remove_file(
        root.join(SCENE)
            .join("_detail")
            .join(CAM)
            .join(ORIENTATIONS),
    )
    .unwrap();
    let e = Hypersim::open(&root, &OpenOptions::default())
        .err()
        .unwrap();
    assert!(format!("{e:#}").contains(ORIENTATIONS), "{e:#}");
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn missing_camera_csv_is_an_error() {
    let root = copy_fixture("nocsv");
    std::fs::remove_file(root.join("metadata_camera_parameters.csv")).unwrap();
    let e = Hypersim::open(&root, &OpenOptions::default())
        .err()
        .unwrap();
    assert!(
        format!("{e:#}").contains("metadata_camera_parameters.csv"),
        "{e:#}"
    );
    std::fs::remove_dir_all(&root).unwrap();
}

/// Rewrites the fixture's orientations with keyframe `k`'s rotation replaced.
fn write_orientations(root: &Path, k: usize, r: [f64; 9]) {
    let path = root
        .join(SCENE)
        .join("_detail")
        .join(CAM)
        .join(ORIENTATIONS);
    let (_, mut o) = hypersim::read_hdf5_f64(&path).unwrap();
    o[9 * k..9 * k + 9].copy_from_slice(&r);
    std::fs::remove_file(&path).unwrap();
    let f = rust_hdf5::H5File::create(&path).unwrap();
    let d = f
        .new_dataset::<f64>()
        .shape([100usize, 3, 3])
        .create("dataset")
        .unwrap();
    d.write_raw(&o).unwrap();
    f.close().unwrap();
}

#[test]
fn nan_pose_names_file_and_keyframe() {
    let root = copy_fixture("nan");
    let mut r = R0;
    r[4] = f64::NAN;
    write_orientations(&root, 7, r);
    let e = format!(
        "{:#}",
        Hypersim::open(&root, &OpenOptions::default())
            .err()
            .unwrap()
    );
    assert!(e.contains(ORIENTATIONS) && e.contains("keyframe 7"), "{e}");
    assert!(e.contains("not finite"), "{e}");

    // A rotation scaled by 2 is not repairable either.
    write_orientations(&root, 7, R0.map(|x| 2.0 * x));
    let e = format!(
        "{:#}",
        Hypersim::open(&root, &OpenOptions::default())
            .err()
            .unwrap()
    );
    assert!(
        e.contains("keyframe 7") && e.contains("not orthonormal"),
        "{e}"
    );
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn slightly_skewed_rotation_is_repaired_and_counted() {
    let root = copy_fixture("skew");
    // R0 with one entry off by 1e-4: orthonormality error ~2e-4.
    let mut r = R0;
    r[1] = 1e-4;
    write_orientations(&root, 0, r);
    let ds = Hypersim::open(&root, &OpenOptions::default()).unwrap();
    assert_eq!(ds.reorthonormalised(), 1);
    assert_eq!(
        ds.keyframe_poses(SCENE, CAM).unwrap().reorthonormalised,
        vec![0]
    );
    assert!(
        ds.describe()
            .contains("1 keyframe rotations re-orthonormalised"),
        "{}",
        ds.describe()
    );
    let f = ds.load(&frame0()).unwrap();
    let m = f
        .pose
        .rotation
        .to_rotation_matrix()
        .into_inner()
        .cast::<f64>();
    assert!((m.transpose() * m - Matrix3::identity()).abs().max() < 1e-6);
    let want =
        Matrix3::from_row_slice(&R0) * Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0));
    assert!((m - want).abs().max() < 1e-4);
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn esanet_predictions_beside_the_raw_fixture() {
    let dir = std::env::temp_dir().join(format!("sndt-hs-pred-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (w, h) = (1024usize, 768usize);
    // Class (7 + row) % 40 + 1 with score 0.5 on top, then two fixed classes.
    let topk = sndt_host::dataset::TopK {
        classes: (0..w * h)
            .map(|i| [((7 + i / w) % 40 + 1) as u8, 1, 2])
            .collect(),
        scores: vec![[0.5, 0.25, 0.125]; w * h],
    };
    let path = dir.join(SCENE).join(CAM).join("0000.npy");
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    sndt_host::dataset::npy::write_topk(&path, &topk, w as u32, h as u32).unwrap();
    let options = OpenOptions {
        predictions: Some(dir.clone()),
        ..OpenOptions::default()
    };
    let data = Hypersim::open(&fixture(), &options).unwrap();
    let f = data.load(&frame0()).unwrap();
    let p = f.predictions.expect("predictions loaded");
    assert_eq!(p.classes[0], [8, 1, 2]);
    assert_eq!(p.classes[767 * w], [((7 + 767) % 40 + 1) as u8, 1, 2]);
    assert_eq!(p.scores[5], [0.5, 0.25, 0.125]);
    // A missing predictions directory is an error naming it.
    let missing = OpenOptions {
        predictions: Some(dir.join("nope")),
        ..OpenOptions::default()
    };
    let err = Hypersim::open(&fixture(), &missing).err().unwrap();
    assert!(format!("{err:#}").contains("nope"), "{err:#}");
    std::fs::remove_dir_all(&dir).unwrap();
}
