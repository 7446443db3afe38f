//! ROS 2 bags (MCAP): a synthetic trajectory written as a bag gives exactly the frames and
//! the map of the same trajectory written in the prepared layout; bad bags give errors that
//! name the topic and stamp, and the usable frames are still read.

use sndt_core::Config;
use sndt_host::dataset::frame::LabelSource;
use sndt_host::dataset::synthetic::{write_split, SynthOptions, Synthetic};
use sndt_host::dataset::{open, Dataset, OpenOptions};
use sndt_host::ros::bag::{Bag, BagOptions};
use sndt_host::ros::msgs::{self, Header, Image, TfMessage, TransformStamped};
use sndt_host::ros::write::{
    camera_info, camera_transform, frame_time, names, write_trajectory, BagWriter,
};
use sndt_host::semantic_map::{boxed_map, integrate_frame, HostMap};
use std::path::PathBuf;

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("sndt-ros-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn split(frames: usize) -> Synthetic {
    Synthetic::new(SynthOptions {
        scenes: 1,
        frames,
        predictions: false,
        ..SynthOptions::default()
    })
    .unwrap()
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
    let _ = std::fs::remove_dir_all(&dir);
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
            let tf = TransformStamped {
                header: Header {
                    stamp,
                    frame_id: names::WORLD.into(),
                },
                child_frame_id: names::CAMERA.into(),
                transform: camera_transform(&f.pose),
            };
            bag.write(
                "/tf",
                stamp,
                &TfMessage {
                    transforms: vec![tf],
                },
            )
            .unwrap();
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
        let img = Image {
            header,
            height: cam.height,
            width: cam.width,
            encoding: encoding.into(),
            is_bigendian: 0,
            step: cam.width * 2,
            data: mm,
        };
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
