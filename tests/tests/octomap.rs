//! The OctoMap of a map in the map bags that `sndt map --mcap` writes: one
//! `octomap_msgs/msg/Octomap` per map snapshot on `/octomap_binary`, carrying the binary tree
//! of the map as it was, byte for byte the tree of the `.bt` file of the final map. (That
//! liboctomap reads these trees as sndt's occupancy is checked by `scripts/octomap.sh`.)

use sndt_core::Config;
use sndt_host::dataset::frame::LabelSource;
use sndt_host::dataset::ros::msgs::{definitions, from_cdr, Octomap};
use sndt_host::dataset::synthetic::CAMERA;
use sndt_host::eval::evaluate::{evaluate, EvalOptions};
use sndt_host::output::octomap::{write_octomap, OctoFormat, OctoMap};
use sndt_host::output::ros::export::{MAP_FRAME, OCTOMAP};
use sndt_host::output::ros::write::frame_time;

#[test]
fn map_bags_carry_the_occupancy_as_an_octomap_message() {
    let dir = std::env::temp_dir().join(format!("sndt-octomap-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let s = sndt_tests::synthetic(1, 3, CAMERA, false);
    let options = EvalOptions {
        mcap: Some(dir.join("m.mcap")),
        mcap_interval: Some(2),
        keep_maps: true,
        ..EvalOptions::new(Config::with_cell_size(0.2), LabelSource::Gt)
    };
    let eval = evaluate(&s, &options, &|| {}).unwrap();
    assert_eq!(eval.maps.len(), 1);
    let map = &eval.maps[0];
    let bytes = std::fs::read(dir.join("m.mcap")).unwrap();
    let mut messages = Vec::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        if m.channel.topic != OCTOMAP {
            continue;
        }
        let schema = m.channel.schema.as_ref().unwrap();
        let (name, text) = definitions::octomap();
        assert_eq!(
            (schema.name.as_str(), schema.encoding.as_str()),
            (name, "ros2msg")
        );
        assert_eq!(std::str::from_utf8(&schema.data).unwrap(), text);
        messages.push((m.log_time, from_cdr::<Octomap>(&m.data).unwrap()));
    }
    // Like the other map topics: after frame 2 (every 2) and after the last, frame 3.
    let stamps: Vec<u64> = messages.iter().map(|m| m.0).collect();
    assert_eq!(stamps, [frame_time(1).nanos(), frame_time(2).nanos()]);
    let last = &messages[1].1;
    assert!(last.binary && last.id == "OcTree" && last.resolution == 0.2);
    assert_eq!(last.header.frame_id, MAP_FRAME);
    assert_eq!(last.header.stamp, frame_time(2));

    // The last message is the final map's tree, which has one leaf per known voxel.
    let tree = OctoMap::from_map(map.as_ref());
    assert_eq!(tree.leaves().len(), map.cells().count());
    assert_eq!(tree.occupied(), map.cells().filter(|c| c.1 > 0.0).count());
    assert_eq!(last.data, tree.binary_data().bytes);
    let bt = dir.join("m.bt");
    let (format, nodes) = write_octomap(&bt, &tree).unwrap();
    assert_eq!(format, OctoFormat::Binary);
    let file = std::fs::read(&bt).unwrap();
    let data_at = file.windows(6).position(|w| w == b"\ndata\n").unwrap() + 6;
    assert_eq!(file[data_at..], last.data[..]);
    let header = String::from_utf8_lossy(&file[..data_at]);
    assert!(
        header.contains(&format!("\nsize {nodes}\nres 0.2\n")),
        "{header}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
