//! Bad command lines: each exits non-zero with a message that names the option or the file
//! and says what is wrong.

use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs `sndt args`; returns the exit code and stderr.
fn sndt(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_sndt"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn bad_option_values_are_refused_naming_the_option() {
    let ply = std::env::temp_dir().join(format!("sndt-cli-{}.ply", std::process::id()));
    let ply = ply.to_str().unwrap();
    for bad in ["NaN", "inf", "0", "-3"] {
        let option = format!("--ellipsoids={bad}");
        let (code, err) = sndt(&["export", "synthetic:1:2", "--ply", ply, &option]);
        assert_eq!(code, 2, "--ellipsoids {bad}: {err}");
        assert!(
            err.contains("--ellipsoids") && err.contains("must be a finite number > 0"),
            "{err}"
        );
    }
    assert!(!std::path::Path::new(ply).exists(), "nothing written");
    let cases: [(&[&str], &str, &str); 9] = [
        (&["map", "synthetic:1:2", "--cell", "0"], "--cell", "> 0"),
        (&["map", "synthetic:1:2", "--cell", "NaN"], "--cell", "> 0"),
        (&["map", "synthetic:1:2", "--stride", "0"], "--stride", "0"),
        (&["map", "synthetic:1:2", "--every", "0"], "--every", "0"),
        (
            &["experiment", "synthetic:1:2", "--every", "0"],
            "--every",
            "0",
        ),
        (
            &[
                "map",
                "synthetic:1:2",
                "--mcap",
                "m.mcap",
                "--mcap-interval",
                "0",
            ],
            "--mcap-interval",
            "0",
        ),
        (
            &["compare", "synthetic", "--cell", "0.1,0"],
            "--cell",
            "> 0",
        ),
        (
            &["experiment", "synthetic:1:2", "--cell", "0.1,-1"],
            "--cell",
            "> 0",
        ),
        (
            &["map", "synthetic:1:2", "--sync-tolerance=-1"],
            "--sync-tolerance",
            ">= 0",
        ),
    ];
    for (args, option, why) in cases {
        let (code, err) = sndt(args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(option) && err.contains(why), "{args:?}: {err}");
    }
}

#[test]
fn missing_inputs_are_named() {
    let (code, err) = sndt(&["export", "nope.sndt", "--ply", "x.ply"]);
    assert_ne!(code, 0);
    assert!(
        err.contains("nope.sndt: no such map snapshot file"),
        "{err}"
    );
    let (code, err) = sndt(&["map", "no-such-dataset"]);
    assert_ne!(code, 0);
    assert!(
        err.contains("no-such-dataset: no such file or directory"),
        "{err}"
    );
    let (code, err) = sndt(&["info", "no-such.mcap"]);
    assert_ne!(code, 0);
    assert!(err.contains("no-such.mcap"), "{err}");
}

/// Runs `sndt args`; returns the exit code, stdout and stderr.
fn sndt_out(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_sndt"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A fresh temporary directory for test `name`.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("sndt-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A small synthetic split: `scenes` scenes of `frames` 64x48 frames each, with labels and
/// without predictions.
fn small_split(scenes: usize, frames: usize) -> sndt_host::dataset::synthetic::Synthetic {
    use sndt_host::dataset::synthetic::{SynthOptions, Synthetic};
    let camera = sndt_core::Pinhole {
        fx: 40.0,
        fy: 40.0,
        cx: 32.0,
        cy: 24.0,
        width: 64,
        height: 48,
    };
    Synthetic::new(SynthOptions {
        scenes,
        frames,
        camera,
        predictions: false,
        ..SynthOptions::default()
    })
    .unwrap()
}

/// A small prepared layout ([`small_split`]) in split `test`.
fn prepared(name: &str, scenes: usize, frames: usize) -> PathBuf {
    use sndt_host::dataset::Dataset;
    let root = temp_dir(name).join("data");
    let split = small_split(scenes, frames);
    for id in split.frames() {
        let frame = split.load(id).unwrap();
        sndt_host::dataset::prepared::write_frame(&root, "test", &frame).unwrap();
    }
    sndt_host::dataset::prepared::write_split_list(&root, "test", split.frames()).unwrap();
    root
}

/// `sndt map DIR --out OUT extra...` on a prepared layout.
fn map(root: &Path, extra: &[&str]) -> (i32, String, String) {
    let out = root.with_file_name("out");
    let mut args = vec![
        "map",
        root.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    sndt_out(&args)
}

/// Asserts that `err` warns that frame `synth_00_living/cam_00/<frame>` was skipped because
/// of `file`, for `why`.
fn assert_skipped(err: &str, frame: &str, file: &Path, why: &str) {
    let want = format!(
        "warning: skipping frame synth_00_living/cam_00/{frame}: {}: {why}",
        file.display()
    );
    assert!(err.contains(&want), "{err}");
}

/// Replaces `"key": <number>` in a JSON record by `"key": value`.
fn set_json(path: &Path, key: &str, value: &str) {
    let text = std::fs::read_to_string(path).unwrap();
    let at = text.find(&format!("\"{key}\"")).unwrap();
    let colon = at + text[at..].find(':').unwrap();
    let end = colon + text[colon..].find([',', '\n', '}']).unwrap();
    let patched = format!("{}: {value}{}", &text[..colon], &text[end..]);
    std::fs::write(path, patched).unwrap();
}

#[test]
fn predicted_labels_without_predictions_are_an_error() {
    let root = prepared("nopred", 1, 2);
    let (code, out, err) = map(&root, &["--labels", "pred"]);
    assert_eq!(code, 1, "{out}{err}");
    let esanet = root.join("test").join("esanet");
    assert!(
        err.contains("--labels pred: ")
            && err.contains("has no predictions: no ")
            && err.contains(&format!("{} directory", esanet.display())),
        "{err}"
    );
    assert!(!out.contains("mIoU"), "{out}");
}

#[test]
fn a_split_without_frames_is_an_error() {
    let root = prepared("empty", 1, 1);
    std::fs::write(root.join("test.txt"), "# nothing\n").unwrap();
    let (code, out, err) = map(&root, &[]);
    assert_eq!(code, 1, "{out}{err}");
    let list = root.join("test.txt");
    assert!(
        err.contains(&format!(
            "{}: lists no frames (0 frames to map)",
            list.display()
        )),
        "{err}"
    );
    assert!(!out.contains("Hz"), "{out}");
}

#[test]
fn a_missing_intrinsics_file_is_a_warning_and_counted() {
    let root = prepared("intrinsics", 2, 1);
    let missing = root
        .join("test/intrinsics/synth_01_bedroom")
        .join("cam_00.json");
    std::fs::remove_file(&missing).unwrap();
    let (code, out, err) = map(&root, &[]);
    // The nominal camera is 1024x768: the 64x48 frame of that camera is skipped.
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        err.contains(&format!(
            "warning: {}: no such file; this camera uses the nominal Hypersim camera",
            missing.display()
        )),
        "{err}"
    );
    assert!(
        out.contains("1 of 2 cameras have no intrinsics file and use the nominal Hypersim camera"),
        "{out}"
    );
    assert!(out.contains("1 frames mapped, 1 skipped"), "{out}");
    assert!(err.contains("depth is 64x48, camera (the nominal Hypersim camera) is 1024x768"));
}

#[test]
fn bad_intrinsics_are_an_error_naming_the_file_and_field() {
    let root = prepared("fx", 1, 1);
    let file = root.join("test/intrinsics/synth_00_living/cam_00.json");
    for (value, why) in [
        ("0", "fx = 0, must be > 0"),
        ("-3.5", "fx = -3.5, must be > 0"),
        ("1e39", "fx = 1e39 is not finite as f32"),
    ] {
        set_json(&file, "fx", value);
        let (code, out, err) = map(&root, &[]);
        assert_eq!(code, 1, "{out}{err}");
        assert!(err.contains(&format!("{}: {why}", file.display())), "{err}");
    }
}

#[test]
fn bad_extrinsics_are_skipped_naming_the_file_value_and_range() {
    let root = prepared("extrinsics", 1, 3);
    let file = root.join("test/extrinsics/synth_00_living/cam_00/0002.json");
    set_json(&file, "x", "1e39");
    let (code, out, err) = map(&root, &[]);
    assert_eq!(code, 0, "{out}{err}");
    assert_skipped(
        &err,
        "0002",
        &file,
        "position x = 1e39 is not finite as f32",
    );
    assert!(out.contains("cam_00: 2 frames, 1 skipped"), "{out}");
    assert!(out.contains("2 frames mapped, 1 skipped"), "{out}");

    set_json(&file, "x", "1e7");
    let (code, out, err) = map(&root, &[]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        err.contains(&format!(
            "{}: position x = 1e7 m is outside the map's key range (±32767 cells of 0.1 m, about ±3276.7 m)",
            file.display()
        )),
        "{err}"
    );
    assert!(out.contains("2 frames mapped, 1 skipped"), "{out}");
}

#[test]
fn bad_frames_are_skipped_and_a_run_without_any_fails() {
    let root = prepared("corrupt", 1, 3);
    let png = root.join("test/depth/synth_00_living/cam_00/0001.png");
    std::fs::write(&png, b"not a PNG").unwrap();
    let (code, out, err) = map(&root, &[]);
    assert_eq!(code, 0, "{out}{err}");
    assert_skipped(&err, "0001", &png, "not a readable PNG");
    assert!(out.contains("2 frames mapped, 1 skipped"), "{out}");
    // Nothing usable left: an error, with the last reason.
    for k in [0, 2] {
        let p = png.with_file_name(format!("{k:04}.png"));
        std::fs::write(p, b"").unwrap();
    }
    let (code, out, err) = map(&root, &[]);
    assert_eq!(code, 1, "{out}{err}");
    assert!(
        err.contains("nothing mapped: all 3 frames were skipped (the last: ")
            && err.contains("0002.png: not a readable PNG"),
        "{err}"
    );
    assert!(!out.contains("mIoU"), "{out}");
}

#[test]
fn config_errors_name_the_option_and_the_field() {
    let cases: [(&[&str], &str); 3] = [
        (
            &["map", "synthetic:1:2", "--cell", "1000"],
            "--cell 1000: invalid config: cell_size must be a number of metres in [0.001, 100]",
        ),
        (
            &["map", "synthetic:1:2", "--cell", "0.001"],
            "--cell 0.001: invalid config: max_range / cell_size must be at most 4096 cells \
             (one ray's length in voxels); max_range 20 m is 20000 cells of 0.001 m",
        ),
        (
            &["map", "synthetic:1:2", "--votes-per-frame", "0"],
            "--votes-per-frame 0: invalid config: votes_per_frame must be in 1..=64",
        ),
    ];
    for (args, message) in cases {
        let (code, _, err) = sndt_out(args);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(err.contains(message), "{args:?}: {err}");
    }
}

/// A snapshot whose config has a 10 km `max_range` at 10 cm (100,000 cells per ray) is
/// refused on load, naming the file and the bound.
#[test]
fn a_snapshot_with_an_absurd_max_range_is_refused() {
    let dir = temp_dir("snapshot");
    let map = sndt_host::mapping::boxed_map::<64, 16, 40>(sndt_core::Config::DEFAULT).unwrap();
    let mut bytes = vec![0; map.snapshot_len()];
    map.write_snapshot(&mut bytes).unwrap();
    let mut header = sndt_core::SnapshotHeader::read(&bytes).unwrap();
    header.config.max_range = 1e4;
    header.rewrite(&mut bytes).unwrap();
    let file = dir.join("far.sndt");
    std::fs::write(&file, &bytes).unwrap();
    let ply = dir.join("far.ply");
    let (code, _, err) = sndt_out(&[
        "export",
        file.to_str().unwrap(),
        "--ply",
        ply.to_str().unwrap(),
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains(&format!(
            "{}: not a readable sndt snapshot: its stored config is refused: invalid config: \
             max_range / cell_size must be at most 4096 cells",
            file.display()
        )),
        "{err}"
    );
    assert!(!ply.exists());
}

/// The map snapshots (`/sndt/map/points` messages) in the map bag `path`.
fn map_bag_snapshots(path: &Path) -> usize {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    mcap::MessageStream::new(&bytes)
        .unwrap()
        .filter(|m| m.as_ref().unwrap().channel.topic == sndt_host::output::ros::export::POINTS)
        .count()
}

#[test]
fn map_every_takes_every_kth_frame_and_mcap_interval_writes_the_growing_map() {
    let root = prepared("every", 1, 4);
    let (code, out, err) = map(&root, &[]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("4 frames mapped, 0 skipped"), "{out}");
    // `--every` was the map bag's interval before it was `--mcap-interval`; now it
    // subsamples the frames, as in `sndt experiment`.
    let bag = root.with_file_name("every.mcap");
    let bag_arg = bag.to_str().unwrap();
    let (code, out, err) = map(&root, &["--every", "2", "--mcap", bag_arg]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("2 frames mapped, 0 skipped"), "{out}");
    assert_eq!(map_bag_snapshots(&bag), 1, "the map after the last frame");
    let (code, out, err) = map(&root, &["--mcap", bag_arg, "--mcap-interval", "2"]);
    assert_eq!(code, 0, "{out}{err}");
    assert_eq!(map_bag_snapshots(&bag), 2, "after frames 2 and 4");
    let (code, out, err) = map(
        &root,
        &["--every", "2", "--mcap", bag_arg, "--mcap-interval", "1"],
    );
    assert_eq!(code, 0, "{out}{err}");
    assert_eq!(
        map_bag_snapshots(&bag),
        2,
        "after each of the 2 frames mapped"
    );
}

#[test]
fn export_takes_every_and_mcap_interval_as_map_does() {
    let root = prepared("export-every", 1, 4);
    let bag = root.with_file_name("export.mcap");
    let mut args = vec![
        "export",
        root.to_str().unwrap(),
        "--mcap",
        bag.to_str().unwrap(),
    ];
    args.extend(["--every", "2", "--mcap-interval", "1"]);
    let (code, out, err) = sndt_out(&args);
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.contains("mapped synth_00_living/cam_00: 2 frames, 0 skipped")
            && out.contains(": 2 map snapshots"),
        "{out}"
    );
}

#[test]
fn removed_and_renamed_options_are_refused() {
    let cases: [&[&str]; 9] = [
        &["budget", "--dataset", "synthetic:1:2", "--capacity", "4096"],
        &["demo", "--frames", "1"],
        &["experiment", "synthetic:1:2", "--cells", "0.1"],
        &["synth", "--out", "x", "--frames", "2"],
        &["experiment", "synthetic:1:2", "--labels", "both"],
        &[
            "cloud",
            "synthetic:1:2",
            "--frame",
            "s/c/0000",
            "--out",
            "f.ply",
        ],
        &["points", "synthetic:1:2", "--out", "p.bin"],
        &["merge", "a.sndt", "--out", "b.sndt"],
        &["info", "robot.mcap", "--split", "test"],
    ];
    for args in cases {
        let (code, out, err) = sndt_out(args);
        assert_eq!(code, 2, "{args:?}: {out}{err}");
        assert!(
            err.contains("unexpected argument '--") || err.contains("invalid value 'both'"),
            "{args:?}: {err}"
        );
    }
}

/// A ROS 2 bag of one small synthetic trajectory ([`small_split`]) of `frames` frames,
/// posed in frame `world`.
fn bag(name: &str, frames: usize) -> PathBuf {
    use sndt_host::dataset::Dataset;
    use sndt_host::output::ros::write::{write_trajectory_compressed, ChunkCompression};
    let file = temp_dir(name).join("robot.mcap");
    let split = small_split(1, frames);
    let loaded = split.frames().iter().map(|id| split.load(id));
    write_trajectory_compressed(&file, loaded, ChunkCompression::None).unwrap();
    file
}

/// `budget`, `compare` and `cloud` take a bag's options as `map` does: a world frame the
/// bag's transform tree lacks skips every frame with a warning naming the frame (`budget`
/// then reports no trajectory, the others fail); the bag's own world frame works.
#[test]
fn budget_compare_and_cloud_take_the_bag_options() {
    let file = bag("bag-options", 2);
    let bag = file.to_str().unwrap();
    let ply = file.with_file_name("frame.ply");
    let commands: [Vec<&str>; 3] = [
        vec!["budget", bag, "--capacity", "4096"],
        vec!["compare", bag, "--cell", "0.2"],
        vec![
            "cloud",
            bag,
            "--frame",
            "robot/cam_00/0001",
            "--ply",
            ply.to_str().unwrap(),
        ],
    ];
    for command in commands {
        let mut args = command.clone();
        args.extend(["--world-frame", "nowhere", "--sync-tolerance", "0.01"]);
        let (_, out, err) = sndt_out(&args);
        assert!(
            err.contains("frame nowhere is not in the transform tree"),
            "{args:?}: {out}{err}"
        );
        let mut args = command.clone();
        args.extend([
            "--world-frame",
            "world",
            "--depth-topic",
            "/camera/depth/image_rect_raw",
        ]);
        let (code, out, err) = sndt_out(&args);
        assert_eq!(code, 0, "{args:?}: {out}{err}");
        assert!(!err.contains("skipped"), "{args:?}: {err}");
    }
    assert!(ply.is_file());
}

#[test]
fn merge_writes_the_sndt_file_it_is_given() {
    let dir = temp_dir("merge-sndt");
    let map = sndt_core::Map::<64, 16, 40>::new(sndt_core::Config::DEFAULT);
    let mut bytes = vec![0; map.snapshot_len()];
    map.write_snapshot(&mut bytes).unwrap();
    let (a, merged) = (dir.join("a.sndt"), dir.join("merged.sndt"));
    std::fs::write(&a, &bytes).unwrap();
    let args = [
        "merge",
        a.to_str().unwrap(),
        "--sndt",
        merged.to_str().unwrap(),
    ];
    let (code, out, err) = sndt_out(&args);
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.contains(&format!("wrote {}", merged.display())),
        "{out}"
    );
    assert!(merged.is_file());
}

#[test]
fn points_selects_frames_as_compare_does_and_budget_and_cloud_take_any_dataset() {
    let root = prepared("points", 1, 4);
    let file = root.with_file_name("points.bin");
    let mut args = vec![
        "points",
        root.to_str().unwrap(),
        "--points-file",
        file.to_str().unwrap(),
    ];
    args.extend(["--frames", "1..3"]);
    let (code, out, err) = sndt_out(&args);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains(": 2 frames, "), "{out}");
    args[5] = "5";
    let (code, _, err) = sndt_out(&args);
    assert_eq!(code, 1);
    assert!(
        err.contains("--frames 5: need a non-empty range within the 4 frames"),
        "{err}"
    );
    let dir = root.to_str().unwrap();
    let (code, out, err) = sndt_out(&["budget", dir, "--capacity", "4096"]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("| synth_00_living/cam_00 | 4 |"), "{out}");
    // A DATASET is `synthetic[:SCENES:FRAMES]` too, for budget and cloud as for map.
    let (code, out, err) = sndt_out(&["budget", "synthetic:1:2", "--capacity", "4096"]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("| synth_00_living/cam_00 | 2 |"), "{out}");
    let ply = root.with_file_name("frame.ply");
    let frame = "synth_00_living/cam_00/0001";
    let mut args = vec!["cloud", "synthetic:1:2", "--frame", frame];
    args.extend(["--ply", ply.to_str().unwrap()]);
    let (code, out, err) = sndt_out(&args);
    assert_eq!(code, 0, "{out}{err}");
    assert!(ply.is_file(), "{out}");
}

#[test]
fn testvector_check_needs_its_crc_files_and_names_the_file() {
    let dir = temp_dir("testvector");
    let committed = Path::new(env!("CARGO_MANIFEST_DIR")).join("../targets/cortex-m4f/vector");
    let vector = dir.join("frames.bin");
    std::fs::copy(committed.join("frames.bin"), &vector).unwrap();
    let check = |file: &Path| sndt_out(&["testvector", "--check", file.to_str().unwrap()]);
    let (code, _, err) = check(&vector);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains(&format!(
            "{}: no such file: the expected snapshot CRC of {}",
            dir.join("expected_crc.txt").display(),
            vector.display()
        )),
        "{err}"
    );
    std::fs::copy(
        committed.join("expected_crc.txt"),
        dir.join("expected_crc.txt"),
    )
    .unwrap();
    let (code, _, err) = check(&vector);
    assert_eq!(code, 1, "{err}");
    let render = dir.join("expected_render_crc.txt");
    assert!(
        err.contains(&format!("{}: no such file", render.display())),
        "{err}"
    );
    std::fs::write(&render, "0x00000000\n").unwrap();
    let (code, _, err) = check(&vector);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains(&format!("{}: render CRC", vector.display()))
            && err.contains(&format!("differs from {}", render.display())),
        "{err}"
    );
    std::fs::copy(committed.join("expected_render_crc.txt"), &render).unwrap();
    let (code, out, err) = check(&vector);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("crc 0x"), "{out}");
    std::fs::write(&vector, b"SNDTVEC\0 but short").unwrap();
    let (code, _, err) = check(&vector);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains(&format!("{}: ", vector.display())), "{err}");
}

/// `sndt experiment DIR --out OUT --cell 0.2 --kernels 0.4 extra...` on a prepared layout
/// (one small configuration per method).
fn experiment(root: &Path, extra: &[&str]) -> (i32, String, String) {
    let out = root.with_file_name("experiment");
    let mut args = vec![
        "experiment",
        root.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--cell",
        "0.2",
        "--kernels",
        "0.4",
    ];
    args.extend_from_slice(extra);
    sndt_out(&args)
}

#[test]
fn an_experiment_with_predicted_labels_needs_predictions() {
    let root = prepared("exp-nopred", 1, 1);
    for labels in ["pred", "gt,pred"] {
        let (code, out, err) = experiment(&root, &["--labels", labels]);
        assert_eq!(code, 1, "{out}{err}");
        let esanet = root.join("test").join("esanet");
        assert!(
            err.contains("--labels pred: ")
                && err.contains(&format!(
                    "has no predictions: no {} directory",
                    esanet.display()
                )),
            "{err}"
        );
        assert!(!out.contains("mIoU"), "{out}");
    }
}

#[test]
fn an_experiment_skips_bad_frames_and_counts_them() {
    let root = prepared("exp-corrupt", 1, 3);
    let png = root.join("test/depth/synth_00_living/cam_00/0001.png");
    std::fs::write(&png, b"not a PNG").unwrap();
    let (code, out, err) = experiment(&root, &["--labels", "gt"]);
    assert_eq!(code, 0, "{out}{err}");
    assert_skipped(&err, "0001", &png, "not a readable PNG");
    assert!(
        out.contains(
            "1 trajectories, 2 frames mapped, 1 skipped (bad input, named in the warnings)"
        ),
        "{out}"
    );
    // Every frame bad: an error naming the last reason, and no tables.
    for k in [0, 2] {
        std::fs::write(png.with_file_name(format!("{k:04}.png")), b"").unwrap();
    }
    let (code, out, err) = experiment(&root, &["--labels", "gt"]);
    assert_eq!(code, 1, "{out}{err}");
    assert!(
        err.contains("nothing mapped: all 3 frames were skipped (the last: ")
            && err.contains("0002.png: not a readable PNG"),
        "{err}"
    );
    assert!(!out.contains("Table"), "{out}");
}

#[test]
fn testvector_merge_stream_refuses_a_broken_stream_and_names_the_file() {
    let dir = temp_dir("merge-stream");
    let file = dir.join("uart.bin");
    let merge = |bytes: &[u8]| {
        std::fs::write(&file, bytes).unwrap();
        sndt_out(&["testvector", "--merge-stream", file.to_str().unwrap()])
    };
    let shown = file.display();
    // A frame without its zero delimiter: the stream was cut.
    let (code, _, err) = merge(b"\x05abcd");
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains(&format!(
            "{shown}: record stream: cut off inside the frame at byte 0"
        )),
        "{err}"
    );
    // A delimited frame whose CRC is wrong.
    let (code, _, err) = merge(b"\x05abcd\0");
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains(&format!("{shown}: record stream: frame 0 (byte 0): ")),
        "{err}"
    );
    let (code, _, err) = merge(b"");
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("record stream: empty"), "{err}");
}
