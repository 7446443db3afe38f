//! ROS 2 bags (MCAP): a synthetic trajectory written as a bag gives exactly the frames and
//! the map of the same trajectory written in the prepared layout; bad bags give errors that
//! name the topic and stamp, and the usable frames are still read.

use sndt_core::Config;
use sndt_host::dataset::frame::LabelSource;
use sndt_host::dataset::ros::bag::{Bag, BagOptions};
use sndt_host::dataset::ros::msgs::{self, Header, TfMessage, TransformStamped};
use sndt_host::dataset::synthetic::{write_split, Synthetic, CAMERA};
use sndt_host::dataset::{open, Dataset, OpenOptions};
use sndt_host::mapping::{boxed_map, integrate_frame, HostMap};
use sndt_host::output::ros::write::{
    camera_info, camera_transform, frame_time, image, names, write_trajectory, BagWriter,
};
use std::path::PathBuf;

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("sndt-ros-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn split(frames: usize) -> Synthetic {
    sndt_tests::synthetic(1, frames, CAMERA, false)
}

fn checksum(ds: &dyn Dataset) -> u32 {
    let mut map: Box<HostMap> = boxed_map(Config::DEFAULT).unwrap();
    for id in ds.frames() {
        let f = ds.load(id).unwrap();
        integrate_frame(map.as_mut(), &f, LabelSource::Gt, 1).unwrap();
    }
    map.checksum()
}

#[test]
fn a_bag_gives_the_prepared_layouts_frames_and_map() {
    let dir = temp("same");
    let s = split(4);
    write_split(&dir, &s, &|_| {}).unwrap();
    let bag_path = dir.join("s.mcap");
    let ids = s.frames().to_vec();
    assert_eq!(
        write_trajectory(&bag_path, ids.iter().map(|id| s.load(id))).unwrap(),
        4
    );
    let prepared = open(&dir, &OpenOptions::default()).unwrap();
    let bag = open(&bag_path, &OpenOptions::default()).unwrap();
    assert_eq!(bag.frames().len(), 4);
    for (a, b) in prepared.frames().iter().zip(bag.frames()) {
        let (a, b) = (prepared.load(a).unwrap(), bag.load(b).unwrap());
        // Bit for bit: the pose (through the transform chain), depth, labels, camera.
        assert_eq!(a.pose, b.pose, "{}", a.id);
        assert_eq!(
            a.depth.iter().map(|d| d.to_bits()).collect::<Vec<_>>(),
            b.depth.iter().map(|d| d.to_bits()).collect::<Vec<_>>()
        );
        assert_eq!(a.labels, b.labels);
        assert_eq!(a.rays, b.rays);
    }
    let (ca, cb) = (checksum(prepared.as_ref()), checksum(bag.as_ref()));
    println!("snapshot crc: prepared {ca:#010x}, bag {cb:#010x}");
    assert_eq!(ca, cb);
    // Every k-th frame (`--every`) keeps the recording's stamps, which a map bag
    // (`--mcap`) is stamped with.
    let stamps: Vec<Option<u64>> = bag.frames().iter().map(|id| bag.stamp(id)).collect();
    let every = sndt_host::dataset::Every::new(bag, 2);
    let kept: Vec<Option<u64>> = every.frames().iter().map(|id| every.stamp(id)).collect();
    assert!(stamps.iter().all(Option::is_some), "{stamps:?}");
    assert_eq!(kept, [stamps[0], stamps[2]]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The camera's pose in the world on `/tf` at `stamp`.
fn write_camera_tf(bag: &mut BagWriter, stamp: msgs::Time, pose: &sndt_core::Isometry3<f32>) {
    let tf = TransformStamped {
        header: Header {
            stamp,
            frame_id: names::WORLD.into(),
        },
        child_frame_id: names::CAMERA.into(),
        transform: camera_transform(pose),
    };
    let msg = TfMessage {
        transforms: vec![tf],
    };
    bag.write("/tf", stamp, &msg).unwrap();
}

/// A bag of 3 synthetic frames written by hand: depth images of `encoding`, the last
/// frame's `/tf` left out when `gap` is set, camera info only `with_info`.
fn custom_bag(path: &std::path::Path, encoding: &str, gap: bool, with_info: bool) {
    let s = split(3);
    let mut bag = BagWriter::create(path).unwrap();
    bag.add_topic(names::DEPTH, msgs::definitions::image())
        .unwrap();
    bag.add_topic(names::CAMERA_INFO, msgs::definitions::camera_info())
        .unwrap();
    bag.add_topic("/tf", msgs::definitions::tf_message())
        .unwrap();
    for (k, id) in s.frames().iter().enumerate() {
        let f = s.load(id).unwrap();
        let sndt_host::dataset::frame::Rays::Pinhole(cam) = *f.rays else {
            unreachable!()
        };
        let stamp = frame_time(k);
        let header = Header {
            stamp,
            frame_id: names::CAMERA.into(),
        };
        if !(gap && k == 2) {
            write_camera_tf(&mut bag, stamp, &f.pose);
        }
        if with_info {
            bag.write(
                names::CAMERA_INFO,
                stamp,
                &camera_info(header.clone(), &cam),
            )
            .unwrap();
        }
        let mm: Vec<u8> = f
            .depth
            .iter()
            .flat_map(|&d| ((d * 1000.0) as u16).to_le_bytes())
            .collect();
        let img = image(header, &cam, encoding, 2, mm);
        bag.write(names::DEPTH, stamp, &img).unwrap();
    }
    bag.finish().unwrap();
}

#[test]
fn bad_bags_say_what_and_where_and_keep_the_usable_frames() {
    let dir = temp("bad");
    // No transform at the last frame's stamp (after the last /tf): frames 0 and 1 are read,
    // frame 2 is skipped, and the reason names the topic, the stamp and the frames.
    let p = dir.join("gap.mcap");
    custom_bag(&p, "16UC1", true, true);
    let bag = Bag::open(&p, &BagOptions::default()).unwrap();
    assert_eq!(bag.frames().len(), 2);
    assert_eq!(bag.skipped.len(), 1);
    assert_eq!(bag.skipped[0].0, frame_time(2).nanos());
    let why = &bag.skipped[0].1;
    assert!(
        why.contains(names::DEPTH) && why.contains("1.200000000") && why.contains("no transform"),
        "{why}"
    );
    let mut end = dir.join("end.mcap");
    custom_bag(&end, "16UC1", false, true);
    // Missing camera info: a clear error.
    let p = dir.join("noinfo.mcap");
    custom_bag(&p, "16UC1", false, false);
    let e = format!("{:#}", Bag::open(&p, &BagOptions::default()).err().unwrap());
    assert!(e.contains("CameraInfo"), "{e}");
    // An RGB image named as the depth topic: every frame skipped, saying the encoding.
    let p = dir.join("rgb.mcap");
    custom_bag(&p, "rgb8", false, true);
    let o = BagOptions {
        depth_topic: Some(names::DEPTH.into()),
        ..BagOptions::default()
    };
    let bag = Bag::open(&p, &o).unwrap();
    assert_eq!(bag.frames().len(), 0);
    assert_eq!(bag.skipped.len(), 3);
    assert!(
        bag.skipped[0].1.contains("rgb8") && bag.skipped[0].1.contains(names::DEPTH),
        "{:?}",
        bag.skipped
    );
    // Without naming it, no depth topic is found.
    let e = format!("{:#}", Bag::open(&p, &BagOptions::default()).err().unwrap());
    assert!(e.contains("no depth images"), "{e}");
    // A truncated file: an error, no panic.
    let bytes = std::fs::read(&end).unwrap();
    end.set_extension("cut.mcap");
    std::fs::write(&end, &bytes[..bytes.len() / 2]).unwrap();
    let e = format!(
        "{:#}",
        Bag::open(&end, &BagOptions::default()).err().unwrap()
    );
    assert!(e.contains("MCAP"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Writes the frames of `s` as a bag posed by a pose topic (`odometry`: an Odometry of
/// `base_link` plus /tf_static to the camera; else a PoseStamped of the camera), labels
/// shifted by 100 (to be mapped back), stamps in reverse order in the file, a declared but
/// empty topic, and returns the path.
fn posed_bag(dir: &std::path::Path, s: &Synthetic, odometry: bool) -> PathBuf {
    use sndt_host::dataset::ros::msgs::Pose;
    let path = dir.join(if odometry { "odom.mcap" } else { "pose.mcap" });
    let mut bag = BagWriter::create(&path).unwrap();
    bag.add_topic(names::DEPTH, msgs::definitions::image())
        .unwrap();
    bag.add_topic(names::LABELS, msgs::definitions::image())
        .unwrap();
    bag.add_topic("/empty", msgs::definitions::image()).unwrap();
    bag.add_topic(names::CAMERA_INFO, msgs::definitions::camera_info())
        .unwrap();
    let pose_def = if odometry {
        msgs::definitions::odometry()
    } else {
        msgs::definitions::pose_stamped()
    };
    bag.add_topic("/pose", pose_def).unwrap();
    bag.add_topic("/tf_static", msgs::definitions::tf_message())
        .unwrap();
    let fixed = TransformStamped {
        header: Header {
            stamp: frame_time(0),
            frame_id: names::BASE.into(),
        },
        child_frame_id: names::CAMERA.into(),
        transform: Default::default(),
    };
    bag.write(
        "/tf_static",
        frame_time(0),
        &TfMessage {
            transforms: vec![fixed],
        },
    )
    .unwrap();
    let ids = s.frames().to_vec();
    for (k, id) in ids.iter().enumerate().rev() {
        let f = s.load(id).unwrap();
        let sndt_host::dataset::frame::Rays::Pinhole(cam) = *f.rays else {
            unreachable!()
        };
        let stamp = frame_time(k);
        let header = Header {
            stamp,
            frame_id: names::CAMERA.into(),
        };
        let t = camera_transform(&f.pose);
        let pose = Pose {
            position: msgs::Point {
                x: t.translation.x,
                y: t.translation.y,
                z: t.translation.z,
            },
            orientation: t.rotation,
        };
        write_pose(&mut bag, stamp, pose, odometry);
        bag.write(
            names::CAMERA_INFO,
            stamp,
            &camera_info(header.clone(), &cam),
        )
        .unwrap();
        write_images(&mut bag, &header, &cam, &f);
    }
    bag.finish().unwrap();
    path
}

/// `pose` on `/pose`: an Odometry of `base_link` or a PoseStamped, both in the world.
fn write_pose(bag: &mut BagWriter, stamp: msgs::Time, pose: msgs::Pose, odometry: bool) {
    use sndt_host::dataset::ros::msgs::{
        Odometry, PoseStamped, PoseWithCovariance, Twist, TwistWithCovariance,
    };
    let world = Header {
        stamp,
        frame_id: names::WORLD.into(),
    };
    if odometry {
        let odom = Odometry {
            header: world,
            child_frame_id: names::BASE.into(),
            pose: PoseWithCovariance {
                pose,
                covariance: [[0.0; 6]; 6],
            },
            twist: TwistWithCovariance {
                twist: Twist::default(),
                covariance: [[0.0; 6]; 6],
            },
        };
        bag.write("/pose", stamp, &odom).unwrap();
    } else {
        bag.write(
            "/pose",
            stamp,
            &PoseStamped {
                header: world,
                pose,
            },
        )
        .unwrap();
    }
}

/// The frame's depth (16UC1, the prepared layout's millimetres) and its labels + 100.
fn write_images(
    bag: &mut BagWriter,
    header: &Header,
    cam: &sndt_core::Pinhole,
    f: &sndt_host::dataset::frame::Frame,
) {
    let mm: Vec<u8> = f
        .depth
        .iter()
        .flat_map(|&d| sndt_host::dataset::prepared::depth_to_mm(d).to_le_bytes())
        .collect();
    let stamp = header.stamp;
    bag.write(
        names::DEPTH,
        stamp,
        &image(header.clone(), cam, "16UC1", 2, mm),
    )
    .unwrap();
    let shifted: Vec<u8> = f
        .labels
        .as_ref()
        .unwrap()
        .iter()
        .map(|&l| l + 100)
        .collect();
    bag.write(
        names::LABELS,
        stamp,
        &image(header.clone(), cam, "mono8", 1, shifted),
    )
    .unwrap();
}

#[test]
fn pose_topics_label_maps_and_unordered_stamps_give_the_same_frames() {
    let dir = temp("posed");
    let s = split(3);
    write_split(&dir, &s, &|_| {}).unwrap();
    let prepared = open(&dir, &OpenOptions::default()).unwrap();
    let label_map: Vec<(u8, u8)> = (0..=40).map(|c| (c + 100, c)).collect();
    for odometry in [false, true] {
        let path = posed_bag(&dir, &s, odometry);
        let o = BagOptions {
            pose_topic: Some("/pose".into()),
            label_map: label_map.clone(),
            ..BagOptions::default()
        };
        let bag = Bag::open(&path, &o).unwrap();
        assert_eq!(bag.frames().len(), 3, "{:?}", bag.skipped);
        for (a, b) in prepared.frames().iter().zip(bag.frames()) {
            let (a, b) = (prepared.load(a).unwrap(), bag.load(b).unwrap());
            assert_eq!(a.pose, b.pose, "odometry {odometry}");
            assert_eq!(a.labels, b.labels);
            assert_eq!(a.depth, b.depth);
        }
        // Without the label map the ids are out of the NYU40 range: mapping counts them
        // as rejected labels rather than failing.
        let raw = Bag::open(
            &path,
            &BagOptions {
                pose_topic: Some("/pose".into()),
                ..BagOptions::default()
            },
        )
        .unwrap();
        assert!(raw
            .load(&raw.frames()[0])
            .unwrap()
            .labels
            .unwrap()
            .iter()
            .all(|&l| l >= 100));
    }
    // A declared topic without messages: named, it is an error that says so.
    let path = dir.join("pose.mcap");
    let o = BagOptions {
        labels_topic: Some("/empty".into()),
        ..BagOptions::default()
    };
    let e = format!("{:#}", Bag::open(&path, &o).err().unwrap());
    assert!(e.contains("/empty") && e.contains("no messages"), "{e}");
    // Without a pose topic and without /tf, every frame is skipped for lack of a transform.
    let bag = Bag::open(&path, &BagOptions::default()).unwrap();
    assert_eq!((bag.frames().len(), bag.skipped.len()), (0, 3));
    assert!(
        bag.skipped[0].1.contains("no transform"),
        "{:?}",
        bag.skipped[0]
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn sndt_map_writes_a_growing_map_bag_per_trajectory() {
    use sndt_host::dataset::ros::msgs::PointCloud2;
    use sndt_host::eval::evaluate::{evaluate, EvalOptions};
    use sndt_host::output::ros::export::{GAUSSIANS, POINTS};
    let dir = temp("growing");
    let s = sndt_tests::synthetic(2, 3, CAMERA, false);
    let options = EvalOptions {
        mcap: Some(dir.join("m.mcap")),
        mcap_interval: Some(2),
        keep_maps: true,
        ..EvalOptions::new(Config::DEFAULT, LabelSource::Gt)
    };
    let eval = evaluate(&s, &options, &|| {}).unwrap();
    for ((name, _), map) in s.trajectories().iter().zip(&eval.maps) {
        let path = dir.join(format!("m_{}.mcap", name.replace('/', "_")));
        let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let mut clouds = Vec::new();
        let mut markers = 0;
        for m in mcap::MessageStream::new(&bytes).unwrap() {
            let m = m.unwrap();
            if m.channel.topic == POINTS {
                clouds.push((m.log_time, msgs::from_cdr::<PointCloud2>(&m.data).unwrap()));
            }
            markers += usize::from(m.channel.topic == GAUSSIANS);
        }
        // After frame 2 (every 2) and after the last, frame 3, at their 10 Hz stamps.
        let stamps: Vec<u64> = clouds.iter().map(|c| c.0).collect();
        assert_eq!(
            stamps,
            vec![frame_time(1).nanos(), frame_time(2).nanos()],
            "{name}"
        );
        assert_eq!(markers, 2);
        // The last cloud: one point per occupied voxel with at least 3 points.
        let occupied = map
            .voxels()
            .filter(|v| v.occupancy() == sndt_core::Occupancy::Occupied && v.gaussian.count >= 3)
            .count();
        let last = &clouds[1].1;
        assert_eq!(last.width as usize, occupied);
        assert_eq!(last.data.len(), 28 * occupied);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// One synthetic frame on `depth_topic` with its labels `offset_ns` later and a camera info
/// of distortion `d`, posed by /tf.
fn one_frame_bag(path: &std::path::Path, depth_topic: &str, offset_ns: u64, d: f64) {
    let s = split(1);
    let f = s.load(&s.frames()[0]).unwrap();
    let sndt_host::dataset::frame::Rays::Pinhole(cam) = *f.rays else {
        unreachable!()
    };
    let mut bag = BagWriter::create(path).unwrap();
    for (topic, def) in [
        (depth_topic, msgs::definitions::image()),
        (names::LABELS, msgs::definitions::image()),
        (names::CAMERA_INFO, msgs::definitions::camera_info()),
        ("/tf", msgs::definitions::tf_message()),
    ] {
        bag.add_topic(topic, def).unwrap();
    }
    let stamp = frame_time(0);
    let header = |ns: u64| Header {
        stamp: msgs::Time::from_nanos(ns),
        frame_id: names::CAMERA.into(),
    };
    write_camera_tf(&mut bag, stamp, &f.pose);
    let mut info = camera_info(header(stamp.nanos()), &cam);
    info.d = vec![d, 0.0, 0.0, 0.0, 0.0];
    bag.write(names::CAMERA_INFO, stamp, &info).unwrap();
    let mm: Vec<u8> = f
        .depth
        .iter()
        .flat_map(|&d| ((d * 1000.0) as u16).to_le_bytes())
        .collect();
    bag.write(
        depth_topic,
        stamp,
        &image(header(stamp.nanos()), &cam, "16UC1", 2, mm),
    )
    .unwrap();
    let later = stamp.nanos() + offset_ns;
    let labels = f.labels.clone().unwrap();
    bag.write(
        names::LABELS,
        stamp,
        &image(header(later), &cam, "mono8", 1, labels),
    )
    .unwrap();
    bag.finish().unwrap();
}

#[test]
fn labels_pair_within_the_sync_tolerance_and_raw_distorted_images_are_refused() {
    let dir = temp("sync");
    let p = dir.join("late.mcap");
    one_frame_bag(&p, names::DEPTH, 5_000_000, 0.0);
    let bag = Bag::open(&p, &BagOptions::default()).unwrap();
    assert_eq!(bag.frames().len(), 0);
    let why = &bag.skipped[0].1;
    assert!(
        why.contains(names::LABELS)
            && why.contains("sync tolerance")
            && why.contains("1.000000000"),
        "{why}"
    );
    let o = BagOptions {
        sync_tolerance_ns: 10_000_000,
        ..BagOptions::default()
    };
    assert_eq!(Bag::open(&p, &o).unwrap().frames().len(), 1);
    // Distortion on an unrectified topic: refused, naming the camera info topic; the same
    // camera info for a rectified topic (image_rect...) is fine (its P describes it).
    let p = dir.join("raw.mcap");
    one_frame_bag(&p, "/camera/depth/image_raw", 0, 0.1);
    let bag = Bag::open(&p, &BagOptions::default()).unwrap();
    let why = &bag.skipped[0].1;
    assert!(
        why.contains("distortion") && why.contains(names::CAMERA_INFO),
        "{why}"
    );
    let p = dir.join("rect.mcap");
    one_frame_bag(&p, names::DEPTH, 0, 0.1);
    assert_eq!(
        Bag::open(&p, &BagOptions::default())
            .unwrap()
            .frames()
            .len(),
        1
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Regression (found by `fuzz/fuzz_targets/mcap.rs`; the input is in its corpus): a record
/// inside a zstd chunk whose length claims 36 PB made the mcap crate allocate that much and
/// abort the process; the reader now refuses the bag with an error.
#[test]
fn a_record_claiming_a_huge_length_is_an_error_not_an_abort() {
    let bytes = include_bytes!("../../fuzz/corpus/mcap/crash-huge-record-length");
    let path = temp("huge-record").join("bag.mcap");
    let e = Bag::from_bytes(&path, bytes.to_vec(), &BagOptions::default())
        .err()
        .expect("a corrupt record length must be refused");
    assert!(format!("{e:#}").contains("truncated or corrupt"), "{e:#}");
}

/// Regression (found by the fuzzing smoke of the test command; the input is in the mcap
/// corpus): a record inside an uncompressed chunk, longer than what is left of the chunk,
/// made the mcap crate's reader underflow its count of the chunk's bytes (a panic with
/// overflow checks); the reader now refuses the bag with an error.
#[test]
fn a_chunk_record_longer_than_its_chunk_is_an_error_not_a_panic() {
    let fuzzed = include_bytes!("../../fuzz/corpus/mcap/crash-chunk-record-overflow");
    // The same by hand: an uncompressed chunk of 20 record bytes whose first record
    // claims 100, with enough bytes after the chunk for the claim to be read.
    let mut built = b"\x89MCAP0\r\n".to_vec();
    let mut chunk = Vec::new();
    chunk.extend_from_slice(&[0u8; 8 + 8]); // message start and end times
    chunk.extend_from_slice(&20u64.to_le_bytes()); // uncompressed size
    chunk.extend_from_slice(&0u32.to_le_bytes()); // CRC (none)
    chunk.extend_from_slice(&0u32.to_le_bytes()); // compression "": uncompressed
    chunk.extend_from_slice(&20u64.to_le_bytes()); // records' length
    chunk.push(0x05); // a message record ...
    chunk.extend_from_slice(&100u64.to_le_bytes()); // ... of 100 bytes
    chunk.extend_from_slice(&[0u8; 11]);
    built.push(0x06);
    built.extend_from_slice(&(chunk.len() as u64).to_le_bytes());
    built.extend_from_slice(&chunk);
    built.extend_from_slice(&[0u8; 200]);
    for (name, bytes) in [("fuzzed", &fuzzed[..]), ("built", &built[..])] {
        let path = temp("chunk-overflow").join("bag.mcap");
        let e = Bag::from_bytes(&path, bytes.to_vec(), &BagOptions::default())
            .err()
            .unwrap_or_else(|| panic!("{name}: a chunk record past its chunk must be refused"));
        assert!(
            format!("{e:#}").contains("truncated or corrupt"),
            "{name}: {e:#}"
        );
    }
}

/// Regression (found by `fuzz/fuzz_targets/mcap.rs`; the input is in its corpus): a
/// transform chain whose pose is not finite as f32 (or not a rotation) gave a frame that
/// `Frame::validate` refuses and the core would refuse while mapping; the reader now
/// skips it when pairing, naming the reason, like other unusable depth images.
#[test]
fn a_pose_the_core_refuses_skips_the_frame_with_the_reason() {
    let bytes = include_bytes!("../../fuzz/corpus/mcap/crash-invalid-pose");
    let path = temp("invalid-pose").join("bag.mcap");
    let bag = Bag::from_bytes(&path, bytes.to_vec(), &BagOptions::default()).unwrap();
    for id in bag.frames() {
        let f = bag.load(id).unwrap();
        assert!(
            sndt_core::validate_pose(&f.pose).is_ok(),
            "{id}: {:?}",
            f.pose
        );
    }
    let reasons: Vec<&str> = bag.skipped.iter().map(|(_, r)| r.as_str()).collect();
    assert!(
        reasons.iter().any(|r| r.contains("not finite as f32")),
        "{reasons:?}"
    );
}

/// A tree rooted at another frame than `--world-frame`: every frame is skipped, and the
/// reason names the roots found and the flag to give. `sndt info`'s report lists the
/// topics with their rates and the tree before saying so.
#[test]
fn a_world_frame_outside_the_tree_names_the_roots_to_use() {
    use sndt_host::cli::info::{contents, usage};
    use sndt_host::dataset::ros::index::BagIndex;
    let dir = temp("world");
    let s = split(3);
    let path = dir.join("t.mcap");
    write_trajectory(&path, s.frames().iter().map(|id| s.load(id))).unwrap();
    let o = BagOptions {
        world_frame: Some("odom".into()),
        ..BagOptions::default()
    };
    let index = BagIndex::open(&path).unwrap();
    let report = contents(&index);
    // 3 frames at 10 Hz: the depth topic's rate is exactly 10 Hz; /tf_static is fixed.
    assert!(
        report.contains("| 3 | 10.00 | 1.000000000 | 1.200000000 | 16UC1 |"),
        "{report}"
    );
    assert!(report.contains("roots: world"), "{report}");
    assert!(
        report.contains("world <- base_link (/tf, 3 samples)"),
        "{report}"
    );
    assert!(
        report.contains("base_link <- camera_depth_optical_frame (static)"),
        "{report}"
    );
    let bag = Bag::new(index, &o).unwrap();
    assert_eq!(bag.frames().len(), 0);
    assert_eq!(bag.skipped.len(), 3);
    let why = usage(&bag);
    assert!(why.contains("try --world-frame world"), "{why}");
    // With the root named, every frame is used.
    let o = BagOptions {
        world_frame: Some("world".into()),
        ..BagOptions::default()
    };
    assert_eq!(Bag::open(&path, &o).unwrap().frames().len(), 3);
    let _ = std::fs::remove_dir_all(&dir);
}

/// An image message whose data claims 4 GiB in a message of a few hundred bytes: the bag
/// is refused with an error naming the topic, without allocating the claimed length (the
/// CDR reader checks a length against the bytes left before copying).
#[test]
fn a_cdr_length_past_the_message_is_an_error_not_an_allocation() {
    let mut cdr = vec![0u8, 1, 0, 0]; // plain CDR, little-endian
    cdr.extend_from_slice(&1i32.to_le_bytes()); // stamp.sec
    cdr.extend_from_slice(&0u32.to_le_bytes()); // stamp.nanosec
    cdr.extend_from_slice(&4u32.to_le_bytes()); // frame_id: "cam\0"
    cdr.extend_from_slice(b"cam\0");
    cdr.extend_from_slice(&2u32.to_le_bytes()); // height
    cdr.extend_from_slice(&2u32.to_le_bytes()); // width
    cdr.extend_from_slice(&6u32.to_le_bytes()); // encoding: "16UC1\0"
    cdr.extend_from_slice(b"16UC1\0");
    cdr.extend_from_slice(&[0, 0]); // is_bigendian, then padding to 4
    cdr.extend_from_slice(&4u32.to_le_bytes()); // step
    cdr.extend_from_slice(&0xffff_fff0u32.to_le_bytes()); // data: 4 GiB claimed
    cdr.extend_from_slice(&[0u8; 8]);
    let mut out = std::io::Cursor::new(Vec::new());
    let options = mcap::WriteOptions::new().compression(None);
    let mut w = mcap::Writer::with_options(&mut out, options).unwrap();
    let (name, def) = msgs::definitions::image();
    let schema = w.add_schema(name, "ros2msg", def.as_bytes()).unwrap();
    let channel = w
        .add_channel(schema, names::DEPTH, "cdr", &Default::default())
        .unwrap();
    let header = mcap::records::MessageHeader {
        channel_id: channel,
        sequence: 1,
        log_time: 1_000_000_000,
        publish_time: 1_000_000_000,
    };
    w.write_to_known_channel(&header, &cdr).unwrap();
    w.finish().unwrap();
    drop(w);
    let path = temp("cdr-length").join("bag.mcap");
    let e = Bag::from_bytes(&path, out.into_inner(), &BagOptions::default())
        .err()
        .expect("a CDR length past the message must be refused");
    let e = format!("{e:#}");
    assert!(
        e.contains(names::DEPTH) && e.contains("not a valid CDR message"),
        "{e}"
    );
}

/// The header (profile, library) and the metadata records (name, key-value pairs) of an
/// MCAP file, read with the `mcap` crate's record reader.
fn header_and_metadata(bytes: &[u8]) -> (mcap::records::Header, Vec<mcap::records::Metadata>) {
    let mut header = None;
    let mut metadata = Vec::new();
    for record in mcap::read::LinearReader::new(bytes).unwrap() {
        match record.unwrap() {
            mcap::records::Record::Header(h) => header = Some(h),
            mcap::records::Record::Metadata(m) => metadata.push(m),
            _ => {}
        }
    }
    (header.expect("an MCAP file starts with a header"), metadata)
}

#[test]
fn a_written_bag_is_a_rosbag2_mcap_file_with_the_recorded_qos() {
    let dir = temp("rosbag2");
    let s = split(3);
    let path = dir.join("t.mcap");
    write_trajectory(&path, s.frames().iter().map(|id| s.load(id))).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let (header, metadata) = header_and_metadata(&bytes);
    // rosbag2's MCAP storage plugin writes the `ros2` profile and, on Humble, the
    // distribution in a `rosbag2` metadata record.
    assert_eq!(header.profile, "ros2");
    assert!(header.library.starts_with("sndt "), "{}", header.library);
    assert_eq!(metadata.len(), 1);
    assert_eq!(metadata[0].name, "rosbag2");
    assert_eq!(metadata[0].metadata["ROS_DISTRO"], "humble");
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let mut topics: Vec<&str> = Vec::new();
    for channel in summary.channels.values() {
        let qos = &channel.metadata["offered_qos_profiles"];
        topics.push(&channel.topic);
        // rmw's enums: durability 1 transient local, 2 volatile; reliability 1 reliable;
        // history 1 keep last.
        let durability = if channel.topic == "/tf_static" { 1 } else { 2 };
        assert!(
            qos.starts_with("- history: 1\n"),
            "{}: {qos}",
            channel.topic
        );
        assert!(
            qos.contains("\n  reliability: 1\n"),
            "{}: {qos}",
            channel.topic
        );
        assert!(
            qos.contains(&format!("\n  durability: {durability}\n")),
            "{}: {qos}",
            channel.topic
        );
        assert_eq!(channel.message_encoding, "cdr");
        assert_eq!(channel.schema.as_ref().unwrap().encoding, "ros2msg");
    }
    topics.sort_unstable();
    assert_eq!(
        topics,
        [
            names::CAMERA_INFO,
            names::DEPTH,
            names::LABELS,
            "/tf",
            "/tf_static"
        ]
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_folder_path_writes_a_rosbag2_folder_of_the_same_bag() {
    use sndt_host::dataset::ros::metadata::{bag_files, MetadataFile};
    let dir = temp("folder");
    let s = split(3);
    let file = dir.join("t.mcap");
    write_trajectory(&file, s.frames().iter().map(|id| s.load(id))).unwrap();
    // A path ending in a separator names a folder: `rec/rec_0.mcap` and `rec/metadata.yaml`.
    let folder = dir.join("rec/");
    write_trajectory(&folder, s.frames().iter().map(|id| s.load(id))).unwrap();
    let mcap_file = dir.join("rec").join("rec_0.mcap");
    assert_eq!(
        bag_files(&dir.join("rec")).unwrap(),
        std::slice::from_ref(&mcap_file)
    );
    let bytes = std::fs::read(&mcap_file).unwrap();
    assert!(
        bytes == std::fs::read(&file).unwrap(),
        "the folder holds the same MCAP file"
    );
    // metadata.yaml agrees with the MCAP file's own statistics.
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let stats = summary.stats.clone().unwrap();
    let info = MetadataFile::read(&dir.join("rec"))
        .unwrap()
        .rosbag2_bagfile_information;
    assert_eq!(
        (info.version, info.storage_identifier.as_str()),
        (5, "mcap")
    );
    assert_eq!(info.message_count, stats.message_count);
    assert_eq!(
        info.message_count,
        1 + 4 * 3,
        "tf_static, and per frame tf, info, depth, labels"
    );
    assert_eq!(
        info.starting_time.nanoseconds_since_epoch,
        stats.message_start_time
    );
    assert_eq!(
        info.duration.nanoseconds,
        stats.message_end_time - stats.message_start_time
    );
    assert_eq!(info.relative_file_paths, ["rec_0.mcap"]);
    assert_eq!(info.files.len(), 1);
    assert_eq!(info.files[0].message_count, stats.message_count);
    for (id, channel) in &summary.channels {
        let topic = info
            .topics_with_message_count
            .iter()
            .find(|t| t.topic_metadata.name == channel.topic)
            .unwrap();
        assert_eq!(
            topic.message_count, stats.channel_message_counts[id],
            "{}",
            channel.topic
        );
        assert_eq!(
            topic.topic_metadata.kind,
            channel.schema.as_ref().unwrap().name
        );
    }
    // The existing directory, named without the separator, is written as a folder again.
    write_trajectory(&dir.join("rec"), s.frames().iter().map(|id| s.load(id))).unwrap();
    assert!(std::fs::read(&mcap_file).unwrap() == bytes);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_folder_holding_a_bag_sndt_did_not_write_is_refused_and_kept() {
    let dir = temp("foreign");
    let s = split(1);
    let frames = || s.frames().iter().map(|id| s.load(id));
    // A one-file recording by another writer (the mcap crate's own library string), as
    // `ros2 bag record` would leave it: rec/rec_0.mcap listed by rec/metadata.yaml.
    let rec = dir.join("rec");
    write_trajectory(&dir.join("mine/"), frames()).unwrap();
    std::fs::create_dir_all(&rec).unwrap();
    let yaml = std::fs::read_to_string(dir.join("mine/metadata.yaml")).unwrap();
    std::fs::write(rec.join("metadata.yaml"), yaml.replace("mine_0", "rec_0")).unwrap();
    let mut other = mcap::Writer::new(std::io::Cursor::new(Vec::new())).unwrap();
    other.finish().unwrap();
    let foreign = other.into_inner().into_inner();
    std::fs::write(rec.join("rec_0.mcap"), &foreign).unwrap();
    let err = format!("{:#}", write_trajectory(&rec, frames()).unwrap_err());
    assert!(err.contains("a bag that sndt did not write"), "{err}");
    assert_eq!(std::fs::read(rec.join("rec_0.mcap")).unwrap(), foreign);
    // A split recording: its metadata.yaml lists other files.
    let split_yaml = yaml.replace("- mine_0.mcap", "- rec_0.mcap\n  - rec_1.mcap");
    std::fs::write(rec.join("metadata.yaml"), &split_yaml).unwrap();
    let err = format!("{:#}", write_trajectory(&rec, frames()).unwrap_err());
    assert!(err.contains("holds another bag"), "{err}");
    assert_eq!(
        std::fs::read_to_string(rec.join("metadata.yaml")).unwrap(),
        split_yaml
    );
    let _ = std::fs::remove_dir_all(&dir);
}
