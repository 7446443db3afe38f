//! The prepared layout and ESANet predictions: writer/reader round trip, the raw-R and fy
//! quirks of the authors' data, hand-written `.npy` files, bad inputs, and `sndt cloud`'s
//! PLY output.

use sndt_core::{DepthKind, Isometry3, Pinhole, Translation3, UnitQuaternion, Vector3};
use sndt_host::dataset;
use sndt_host::dataset::OpenOptions;
use sndt_host::dataset::{npy, prepared};
use sndt_host::dataset::{Dataset, Frame, FrameId, Rays, TopK};
use sndt_host::output::ply;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A fresh, empty temporary directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("sndt-prepared-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn open(root: &Path, paper_fy: bool) -> anyhow::Result<Box<dyn Dataset>> {
    dataset::open(
        root,
        &OpenOptions {
            paper_fy,
            ..OpenOptions::default()
        },
    )
}

/// The full error chain, e.g. "file: context: cause".
fn chain(e: anyhow::Error) -> String {
    format!("{e:#}")
}

fn assert_err_names<T>(result: anyhow::Result<T>, path: &Path, what: &str) {
    let Err(e) = result else {
        panic!("expected an error naming {}", path.display());
    };
    let msg = chain(e);
    assert!(
        msg.contains(&path.display().to_string()),
        "error does not name {}: {msg}",
        path.display()
    );
    assert!(msg.contains(what), "error does not mention {what:?}: {msg}");
}

fn write_png(path: &Path, w: u32, h: u32, depth: png::BitDepth, data: &[u8]) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    let file = std::fs::File::create(path).unwrap();
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(depth);
    let mut writer = enc.write_header().unwrap();
    writer.write_image_data(data).unwrap();
    writer.finish().unwrap();
}

fn write_text(path: &Path, text: &str) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(path, text).unwrap();
}

/// A 16x12 pinhole frame: depths exact in mm (every 7th pixel invalid), labels cycling
/// through 0..=40 (void included), a rotated and translated pose, top-3 predictions with
/// exactly representable scores.
fn hand_frame(cam: &str, index: u32, seed: u32) -> Frame {
    let pinhole = Pinhole {
        fx: 10.0,
        fy: 11.0,
        cx: 8.0,
        cy: 6.0,
        width: 16,
        height: 12,
    };
    let n = 16 * 12;
    let depth = (0..n as u32)
        .map(|i| {
            if (i + seed).is_multiple_of(7) {
                0.0
            } else {
                (500 + 37 * i + seed) as f32 / 1000.0
            }
        })
        .collect();
    let labels = (0..n as u32).map(|i| ((i + seed) % 41) as u8).collect();
    let classes: Vec<[u8; 3]> = (0..n as u32)
        .map(|i| {
            let c = (i + seed) % 40 + 1;
            [c as u8, (c % 40 + 1) as u8, ((c + 1) % 40 + 1) as u8]
        })
        .collect();
    let scores = (0..n)
        .map(|i| [0.5 + (i % 4) as f32 / 8.0, 0.25, 0.0625])
        .collect();
    let rotation = UnitQuaternion::from_euler_angles(0.3, -0.5, 1.2 + seed as f32 * 0.1);
    Frame {
        id: FrameId {
            scene: "synth_00_room".into(),
            cam: cam.into(),
            index,
        },
        pose: Isometry3::from_parts(Translation3::new(1.25, -2.5, 1.5 + seed as f32), rotation),
        rays: Arc::new(Rays::Pinhole(pinhole)),
        depth,
        depth_kind: DepthKind::Planar,
        labels: Some(labels),
        predictions: Some(TopK { classes, scores }),
    }
}

#[test]
fn round_trip_through_writer_and_reader() {
    let root = scratch("roundtrip");
    let frames: Vec<Frame> = (0..4)
        .map(|k| hand_frame(if k < 3 { "cam_00" } else { "cam_01" }, k % 3, k))
        .collect();
    // several writers at once, frames of the same camera (shared intrinsics file)
    std::thread::scope(|s| {
        for f in &frames {
            let root = &root;
            s.spawn(move || prepared::write_frame(root, "test", f).unwrap());
        }
    });
    let ids: Vec<FrameId> = frames.iter().rev().map(|f| f.id.clone()).collect();
    prepared::write_split_list(&root, "test", &ids).unwrap();

    let data = open(&root, false).unwrap();
    let mut sorted: Vec<FrameId> = frames.iter().map(|f| f.id.clone()).collect();
    sorted.sort();
    assert_eq!(data.frames(), sorted.as_slice());
    assert_eq!(data.trajectories().len(), 2);
    assert!(data.describe().contains("4 frames"), "{}", data.describe());

    for f in &frames {
        let back = data.load(&f.id).unwrap();
        assert_eq!(back.id, f.id);
        assert_eq!(back.rays, f.rays, "intrinsics");
        assert_eq!(back.depth_kind, DepthKind::Planar);
        assert_eq!(back.depth, f.depth, "depth of {}", f.id);
        assert_eq!(back.labels, f.labels, "labels of {}", f.id);
        let (p, q) = (back.predictions.unwrap(), f.predictions.as_ref().unwrap());
        assert_eq!(p.classes, q.classes);
        for (got, (c, s)) in p.scores.iter().zip(q.classes.iter().zip(&q.scores)) {
            for k in 0..3 {
                // exactly v - floor(v) of the stored f32 v = class + score
                let v = c[k] as f32 + s[k];
                assert_eq!(got[k], v - v.floor());
                assert!((got[k] - s[k]).abs() <= 4e-6, "{} vs {}", got[k], s[k]);
            }
        }
        let (a, b) = (back.pose.to_homogeneous(), f.pose.to_homogeneous());
        assert!((a - b).abs().max() <= 1e-6, "pose of {}: {a} vs {b}", f.id);
    }

    // without the split list the frames come from listing depth/
    std::fs::remove_file(root.join("test.txt")).unwrap();
    assert_eq!(open(&root, false).unwrap().frames(), sorted.as_slice());
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn writer_stores_range_depth_as_planar_and_drops_far_points() {
    let root = scratch("range");
    let mut f = hand_frame("cam_00", 0, 0);
    f.predictions = None;
    f.labels = None;
    let planar = f.depth.clone();
    // Range depth r = z * |ray| must come back as the planar z (rounded to mm)
    f.depth = (0..f.pixels())
        .map(|i| {
            let r = f.rays.ray(i as u32 % 16, i as u32 / 16);
            planar[i] * (r[0] * r[0] + r[1] * r[1] + 1.0).sqrt()
        })
        .collect();
    f.depth_kind = DepthKind::Range;
    f.depth[1] = 100.0; // planar 77 m, beyond 65.535 m -> invalid
    prepared::write_frame(&root, "test", &f).unwrap();
    let data = open(&root, false).unwrap();
    let back = data.load(&f.id).unwrap();
    assert!(back.labels.is_none() && back.predictions.is_none());
    for (i, (&got, &want)) in back.depth.iter().zip(&planar).enumerate() {
        let want = if i == 1 { 0.0 } else { want };
        assert!((got - want).abs() < 1e-6, "pixel {i}: {got} vs {want}");
    }
    std::fs::remove_dir_all(&root).unwrap();
}

/// A layout as the authors ship it: no intrinsics, 1024x768 depth, raw-R extrinsics.
fn authors_layout(name: &str, quat: [f64; 4]) -> PathBuf {
    let root = scratch(name);
    let split = root.join("test");
    let (w, h) = (1024u32, 768u32);
    let mut depth = vec![0u8; (w * h * 2) as usize];
    depth[..2].copy_from_slice(&2000u16.to_be_bytes()); // pixel (0, 0) at 2 m
    write_png(
        &split.join("depth/ai_001_010/cam_00/0000.png"),
        w,
        h,
        png::BitDepth::Sixteen,
        &depth,
    );
    write_text(
        &split.join("extrinsics/ai_001_010/cam_00/0000.json"),
        &format!(
            r#"{{"x": 1.0, "y": 2.0, "z": 3.0, "quat_x": {}, "quat_y": {}, "quat_z": {}, "quat_w": {}}}"#,
            quat[0], quat[1], quat[2], quat[3]
        ),
    );
    write_text(&root.join("test.txt"), "ai_001_010/cam_00/0000\n");
    root
}

fn close(a: Vector3<f32>, b: [f32; 3]) -> bool {
    (a - Vector3::from(b)).norm() < 1e-6
}

#[test]
fn raw_opengl_rotation_is_flipped_to_opencv_axes() {
    // identity raw R: the OpenGL camera looks along its -z = world -z, y up = world +y
    let root = authors_layout("identity", [0.0, 0.0, 0.0, 1.0]);
    let data = open(&root, false).unwrap();
    let f = data.load(&data.frames()[0]).unwrap();
    let r = f.pose.rotation;
    assert!(close(r * Vector3::z(), [0.0, 0.0, -1.0]), "forward");
    assert!(close(r * Vector3::x(), [1.0, 0.0, 0.0]), "right");
    assert!(close(r * Vector3::y(), [0.0, -1.0, 0.0]), "down");
    assert_eq!(f.pose.translation.vector, Vector3::new(1.0, 2.0, 3.0));
    assert!(f.labels.is_none() && f.predictions.is_none());
    std::fs::remove_dir_all(&root).unwrap();

    // raw R = 90 degrees about x: OpenGL forward (0, 0, -1) maps to world (0, 1, 0)
    let s = std::f64::consts::FRAC_1_SQRT_2;
    let root = authors_layout("rotx", [s, 0.0, 0.0, s]);
    let data = open(&root, false).unwrap();
    let f = data.load(&data.frames()[0]).unwrap();
    assert!(close(f.pose.rotation * Vector3::z(), [0.0, 1.0, 0.0]));
    assert!(close(f.pose.rotation * Vector3::y(), [0.0, 0.0, -1.0]));
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn nominal_intrinsics_and_paper_fy() {
    let root = authors_layout("fy", [0.0, 0.0, 0.0, 1.0]);
    for (paper, fy) in [(false, 886.81f32), (true, 927.06f32)] {
        let data = open(&root, paper).unwrap();
        let f = data.load(&data.frames()[0]).unwrap();
        let Rays::Pinhole(cam) = f.rays.as_ref() else {
            panic!("expected a pinhole");
        };
        assert_eq!(
            (cam.fx, cam.fy, cam.cx, cam.cy, cam.width, cam.height),
            (886.81, fy, 512.0, 384.0, 1024, 768)
        );
        // the one valid pixel (0, 0) at planar depth 2 m: camera point (2 x, 2 y, 2)
        let pts = f.world_points();
        assert_eq!(pts.len(), 1);
        let (x, y) = (2.0 * (0.5 - 512.0) / 886.81, 2.0 * (0.5 - 384.0) / fy);
        // identity raw R: world = (1 + x, 2 - y, 3 - 2)
        let want = [1.0 + x, 2.0 - y, 1.0];
        for k in 0..3 {
            assert!(
                (pts[0].0[k] - want[k]).abs() < 1e-5,
                "{:?} vs {want:?}",
                pts[0].0
            );
        }
    }
    std::fs::remove_dir_all(&root).unwrap();
}

/// A version-1.0 `.npy` file of float32 values, written by hand.
fn npy_bytes(descr: &str, fortran: bool, shape: &[usize], values: &[f32]) -> Vec<u8> {
    let dims: Vec<String> = shape.iter().map(std::string::ToString::to_string).collect();
    let mut header = format!(
        "{{'descr': '{descr}', 'fortran_order': {}, 'shape': ({}), }}",
        if fortran { "True" } else { "False" },
        dims.join(", ")
    );
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    for v in values {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

/// A (3, 2, 2) top-3 array, channel-major with row-major pixels: integer part = class,
/// fraction = score.
#[rustfmt::skip]
const TOPK_VALUES: [f32; 12] = [
    1.5, 40.25, 7.75, 13.0,      // best: classes 1, 40, 7, 13
    2.25, 39.125, 8.5, 14.0,     // second
    3.125, 38.0625, 9.25, 15.0,  // third
];

/// Writes [`TOPK_VALUES`] as a C-order float32 `.npy` file in `dir`.
fn write_topk_npy(dir: &Path) -> PathBuf {
    let path = dir.join("c.npy");
    std::fs::write(&path, npy_bytes("<f4", false, &[3, 2, 2], &TOPK_VALUES)).unwrap();
    path
}

#[test]
fn hand_written_npy_decodes_to_known_classes_and_scores() {
    let dir = scratch("npy");
    let path = write_topk_npy(&dir);
    let t = npy::read_topk(&path, 2, 2).unwrap();
    assert_eq!(
        t.classes,
        vec![[1, 2, 3], [40, 39, 38], [7, 8, 9], [13, 14, 15]]
    );
    assert_eq!(
        t.scores,
        vec![
            [0.5, 0.25, 0.125],
            [0.25, 0.125, 0.0625],
            [0.75, 0.5, 0.25],
            [0.0, 0.0, 0.0]
        ]
    );

    // the same array stored in Fortran order: element (k, r, c) at k + 3 (r + 2 c)
    let mut f = vec![0.0; 12];
    for k in 0..3 {
        for r in 0..2 {
            for c in 0..2 {
                f[k + 3 * (r + 2 * c)] = TOPK_VALUES[k * 4 + r * 2 + c];
            }
        }
    }
    let path_f = dir.join("f.npy");
    std::fs::write(&path_f, npy_bytes("<f4", true, &[3, 2, 2], &f)).unwrap();
    assert_eq!(npy::read_topk(&path_f, 2, 2).unwrap(), t);

    // writing is the exact inverse
    let path_w = dir.join("w.npy");
    npy::write_topk(&path_w, &t, 2, 2).unwrap();
    assert_eq!(npy::read_topk(&path_w, 2, 2).unwrap(), t);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn malformed_npy_fails_with_the_file_named() {
    let dir = scratch("npy-bad");
    let path = write_topk_npy(&dir);
    // wrong shape for the requested image, and a wrong shape in the file
    assert_err_names(npy::read_topk(&path, 2, 3), &path, "shape");
    let p = dir.join("shape.npy");
    std::fs::write(&p, npy_bytes("<f4", false, &[2, 2, 3], &TOPK_VALUES)).unwrap();
    assert_err_names(npy::read_topk(&p, 2, 2), &p, "shape");
    // float64
    let p = dir.join("f8.npy");
    let mut b = npy_bytes("<f8", false, &[3, 2, 2], &[]);
    for v in TOPK_VALUES {
        b.extend_from_slice(&(v as f64).to_le_bytes());
    }
    std::fs::write(&p, b).unwrap();
    assert_err_names(npy::read_topk(&p, 2, 2), &p, "dtype");
    // truncated data and truncated header
    let bytes = std::fs::read(&path).unwrap();
    let p = dir.join("trunc.npy");
    std::fs::write(&p, &bytes[..bytes.len() - 4]).unwrap();
    assert_err_names(npy::read_topk(&p, 2, 2), &p, "");
    std::fs::write(&p, &bytes[..20]).unwrap();
    assert_err_names(npy::read_topk(&p, 2, 2), &p, "");
    // class 0 (value 0.5) and 41
    for (name, bad) in [
        ("zero.npy", 0.5f32),
        ("big.npy", 41.0),
        ("nan.npy", f32::NAN),
    ] {
        let mut v = TOPK_VALUES;
        v[6] = bad;
        let p = dir.join(name);
        std::fs::write(&p, npy_bytes("<f4", false, &[3, 2, 2], &v)).unwrap();
        assert_err_names(npy::read_topk(&p, 2, 2), &p, "outside 1..41");
    }
    // missing file
    let p = dir.join("missing.npy");
    assert_err_names(npy::read_topk(&p, 2, 2), &p, "");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A one-frame prepared split in a fresh directory, to be broken one file at a time.
struct OneFrame {
    root: PathBuf,
    frame: Frame,
}

impl OneFrame {
    fn new(name: &str) -> OneFrame {
        let root = scratch(name);
        let frame = hand_frame("cam_00", 0, 0);
        prepared::write_frame(&root, "test", &frame).unwrap();
        prepared::write_split_list(&root, "test", std::slice::from_ref(&frame.id)).unwrap();
        let one = OneFrame { root, frame };
        one.reload().unwrap();
        one
    }

    /// The frame's file of one kind (`depth`, `semantic_40`, `extrinsics`, `esanet`).
    fn file(&self, kind: &str, ext: &str) -> PathBuf {
        self.root
            .join(format!("test/{kind}/synth_00_room/cam_00/0000.{ext}"))
    }

    /// The camera's intrinsics file.
    fn intrinsics(&self) -> PathBuf {
        self.root.join("test/intrinsics/synth_00_room/cam_00.json")
    }

    /// Opens the split afresh and loads the frame.
    fn reload(&self) -> anyhow::Result<Frame> {
        open(&self.root, false)?.load(&self.frame.id)
    }
}

impl Drop for OneFrame {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.root);
    }
}

#[test]
fn bad_depth_png_fails_with_the_file_named() {
    let one = OneFrame::new("bad-depth");
    // missing and truncated depth PNG
    let depth = one.file("depth", "png");
    let good = std::fs::read(&depth).unwrap();
    std::fs::remove_file(&depth).unwrap();
    assert_err_names(one.reload(), &depth, "");
    std::fs::write(&depth, &good[..good.len() / 2]).unwrap();
    assert_err_names(one.reload(), &depth, "");
    std::fs::write(&depth, &good).unwrap();
    one.reload().unwrap();
    // 8-bit depth PNG
    write_png(&depth, 16, 12, png::BitDepth::Eight, &[1; 16 * 12]);
    assert_err_names(one.reload(), &depth, "Sixteen");
}

#[test]
fn bad_label_png_fails_with_the_file_named() {
    let one = OneFrame::new("bad-labels");
    // wrong image size
    let labels = one.file("semantic_40", "png");
    write_png(&labels, 8, 12, png::BitDepth::Eight, &[1; 8 * 12]);
    assert_err_names(one.reload(), &labels, "8x12");
    // label 41
    let mut l = vec![3u8; 16 * 12];
    l[17] = 41;
    write_png(&labels, 16, 12, png::BitDepth::Eight, &l);
    assert_err_names(one.reload(), &labels, "label 41");
}

#[test]
fn bad_extrinsics_fail_with_the_file_named() {
    let one = OneFrame::new("bad-extrinsics");
    // NaN, missing field, non-unit and zero quaternions, an infinite position
    let ext = one.file("extrinsics", "json");
    for text in [
        r#"{"x": NaN, "y": 0, "z": 0, "quat_x": 0, "quat_y": 0, "quat_z": 0, "quat_w": 1}"#,
        r#"{"x": 0, "y": 0, "z": 0, "quat_x": 0, "quat_y": 0, "quat_z": 0}"#,
        r#"{"x": 0, "y": 0, "z": 0, "quat_x": 0, "quat_y": 0, "quat_z": 0, "quat_w": 2}"#,
        r#"{"x": 0, "y": 0, "z": 0, "quat_x": 0, "quat_y": 0, "quat_z": 0, "quat_w": 0}"#,
        r#"{"x": 1e999, "y": 0, "z": 0, "quat_x": 0, "quat_y": 0, "quat_z": 0, "quat_w": 1}"#,
    ] {
        write_text(&ext, text);
        assert_err_names(one.reload(), &ext, "");
    }
}

#[test]
fn missing_prediction_fails_with_the_file_named() {
    let one = OneFrame::new("bad-prediction");
    // one frame's prediction missing while esanet/ exists
    let pred = one.file("esanet", "npy");
    std::fs::remove_file(&pred).unwrap();
    assert_err_names(one.reload(), &pred, "");
}

#[test]
fn bad_intrinsics_fail_with_the_file_named() {
    let one = OneFrame::new("bad-intrinsics");
    let intr = one.intrinsics();
    write_text(
        &intr,
        r#"{"fx": 0, "fy": 10, "cx": 8, "cy": 6, "width": 16, "height": 12}"#,
    );
    assert_err_names(one.reload(), &intr, "");

    // a frame whose intrinsics disagree with the camera's file is not written
    let mut other = hand_frame("cam_00", 1, 0);
    other.rays = Arc::new(Rays::Pinhole(Pinhole {
        fx: 20.0,
        fy: 20.0,
        cx: 8.0,
        cy: 6.0,
        width: 16,
        height: 12,
    }));
    assert_err_names(prepared::write_frame(&one.root, "test", &other), &intr, "");
}

#[test]
fn malformed_split_list_fails_with_the_file_named() {
    let one = OneFrame::new("bad-list");
    let list = one.root.join("test.txt");
    write_text(&list, "synth_00_room/cam_00/0000\nsynth_00_room/0001\n");
    assert_err_names(open(&one.root, false), &list, ":2");
    write_text(&list, "synth_00_room/cam_00/00x0\n");
    assert_err_names(open(&one.root, false), &list, "");
}

/// Parses a binary little-endian PLY of `x y z` floats and `red green blue` uchars.
fn read_ply(path: &Path) -> Vec<([f32; 3], [u8; 3])> {
    let bytes = std::fs::read(path).unwrap();
    let end = b"end_header\n";
    let at = bytes.windows(end.len()).position(|w| w == end).unwrap() + end.len();
    let header = std::str::from_utf8(&bytes[..at]).unwrap();
    let lines: Vec<&str> = header.lines().collect();
    assert_eq!(lines[0], "ply");
    assert_eq!(lines[1], "format binary_little_endian 1.0");
    let n: usize = lines[2]
        .strip_prefix("element vertex ")
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(
        &lines[3..9],
        &[
            "property float x",
            "property float y",
            "property float z",
            "property uchar red",
            "property uchar green",
            "property uchar blue"
        ]
    );
    let body = &bytes[at..];
    assert_eq!(body.len(), n * 15);
    body.chunks_exact(15)
        .map(|r| {
            let f = |k: usize| f32::from_le_bytes(r[4 * k..4 * k + 4].try_into().unwrap());
            ([f(0), f(1), f(2)], [r[12], r[13], r[14]])
        })
        .collect()
}

#[test]
fn cloud_writes_the_frames_world_points() {
    let root = scratch("cloud");
    // 2x2, f = 1, principal point at the centre: rays (+-0.5, +-0.5, 1)
    let cam = Pinhole {
        fx: 1.0,
        fy: 1.0,
        cx: 1.0,
        cy: 1.0,
        width: 2,
        height: 2,
    };
    let frame = Frame {
        id: FrameId::parse("s/c/0003").unwrap(),
        pose: Isometry3::identity(),
        rays: Arc::new(Rays::Pinhole(cam)),
        depth: vec![2.0, 4.0, 0.0, 1.0],
        depth_kind: DepthKind::Planar,
        labels: Some(vec![1, 2, 3, 0]),
        predictions: None,
    };
    prepared::write_frame(&root, "val", &frame).unwrap();
    let out = root.join("out/cloud.ply");
    let options = OpenOptions {
        split: Some("val".into()),
        ..OpenOptions::default()
    };
    let s = sndt_host::cli::cloud::cloud(&root, "s/c/0003", &out, &options).unwrap();
    assert_eq!(s.points, 3);
    assert_eq!(s.bounds, Some(([-1.0, -2.0, 1.0], [2.0, 0.5, 4.0])));
    assert!(s.to_string().contains("3 points"), "{s}");
    assert_eq!(
        read_ply(&out),
        vec![
            ([-1.0, -1.0, 2.0], [128, 0, 0]),
            ([2.0, -2.0, 4.0], [0, 128, 0]),
            ([0.5, 0.5, 1.0], [0, 0, 0]),
        ]
    );

    // no labels: grey; a translated pose moves the points
    let mut bare = frame.clone();
    bare.labels = None;
    bare.pose = Isometry3::translation(10.0, 0.0, 0.0);
    let out2 = root.join("bare.ply");
    ply::write_frame_cloud(&bare, &out2).unwrap();
    let pts = read_ply(&out2);
    assert_eq!(pts.len(), 3);
    assert_eq!(pts[0], ([9.0, -1.0, 2.0], [128, 128, 128]));

    // an unknown frame is an error naming it
    let e = chain(sndt_host::cli::cloud::cloud(&root, "s/c/0004", &out, &options).unwrap_err());
    assert!(e.contains("s/c/0004"), "{e}");
    std::fs::remove_dir_all(&root).unwrap();
}

/// Regression (found by `fuzz/fuzz_targets/png.rs`): a PNG header claiming 2048 x
/// 1929379840 pixels made the reader allocate its 7.9 TB output buffer and abort the
/// process; it is now an error naming the size, for depth and labels alike.
#[test]
fn png_claiming_a_huge_size_is_an_error_not_an_abort() {
    type Read = fn(&[u8]) -> anyhow::Result<()>;
    let readers: [(png::BitDepth, Read); 2] = [
        (png::BitDepth::Sixteen, |b| {
            prepared::depth_png_from_bytes(b).map(|_| ())
        }),
        (png::BitDepth::Eight, |b| {
            prepared::labels_png_from_bytes(b).map(|_| ())
        }),
    ];
    for (depth, read) in readers {
        let path = scratch("huge-png").join("one.png");
        write_png(&path, 1, 1, depth, &[0, 0][..depth as usize / 8]);
        let mut bytes = std::fs::read(&path).unwrap();
        // IHDR: length 8..12, type 12..16, width 16..20, height 20..24, CRC 29..33.
        bytes[16..20].copy_from_slice(&2048u32.to_be_bytes());
        bytes[20..24].copy_from_slice(&0x7300_0000u32.to_be_bytes());
        let mut crc = sndt_core::Crc32::new();
        crc.update(&bytes[12..29]);
        bytes[29..33].copy_from_slice(&crc.finish().to_be_bytes());
        let e = format!("{:#}", read(&bytes).unwrap_err());
        assert!(e.contains("2048x1929379840 image too large"), "{e}");
    }
}

/// Regression (found by `fuzz/fuzz_targets/npy.rs`): a 200-byte `.npy` whose header nests
/// 40 brackets kept the npy parser busy for minutes (its time grows exponentially with the
/// depth); the reader now refuses such a header at once.
#[test]
fn npy_header_nested_deeply_is_refused_at_once() {
    let header = format!(
        "{{'descr': '<f4', 'fortran_order': False, 'shape': (3,{}1, 1), }}\n",
        "[".repeat(40)
    );
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend((header.len() as u16).to_le_bytes());
    bytes.extend(header.as_bytes());
    bytes.extend([0u8; 12]);
    let start = std::time::Instant::now();
    let e = format!(
        "{:#}",
        npy::read_topk_from(&bytes[..], &"deep.npy", 1, 1).unwrap_err()
    );
    assert!(e.contains("nested 42 deep"), "{e}");
    assert!(start.elapsed().as_secs() < 5, "took {:?}", start.elapsed());
}
