//! The host side of spilling: a device-capacity map evaluated through its merged global map
//! (`sndt map --device`), the global map growing into its next tier, and `sndt merge` of
//! snapshots and record streams (refusing a corrupt stream without writing anything).

use sndt_core::{Config, Map, Pinhole, Record, RecordKind, StreamWriter, STREAM_FRAME_BYTES};
use sndt_host::cli::merge::{run as merge, MergeArgs};
use sndt_host::dataset::synthetic::Synthetic;
use sndt_host::dataset::{Dataset, LabelSource};
use sndt_host::eval::evaluate::{evaluate, EvalOptions};
use sndt_host::mapping::{boxed_map, integrate_frame, HostMap};
use sndt_host::mapping::{DeviceCapacity, GlobalMap, Spill, Tier1};

const CAM: Pinhole = sndt_tests::SMALL_CAMERA;

fn room(frames: usize) -> Synthetic {
    sndt_tests::synthetic(1, frames, CAM, true)
}

fn options(device: Option<(DeviceCapacity, Spill)>) -> EvalOptions {
    EvalOptions {
        device,
        ..EvalOptions::new(Config::with_cell_size(0.1), LabelSource::Gt)
    }
}

/// A device map that holds the whole room evicts nothing: its merged global map scores
/// exactly as one host map does. A device that cannot hold the room spills, and its merged
/// map scores better than the device map alone.
#[test]
fn device_maps_score_through_their_merged_global_map() {
    let data = room(12);
    let host = evaluate(&data, &options(None), &|| {}).unwrap();
    let fits = evaluate(
        &data,
        &options(Some((DeviceCapacity::Firmware, Spill::Merged))),
        &|| {},
    )
    .unwrap();
    let spill = fits.trajectories[0].spill.as_ref().unwrap();
    assert_eq!(spill.stats.records, 0, "the room fits 4096 voxels at 10 cm");
    assert_eq!(fits.confusion, host.confusion);
    assert_eq!(fits.trajectories[0].voxels, host.trajectories[0].voxels);

    let merged = evaluate(
        &data,
        &options(Some((DeviceCapacity::Small, Spill::Merged))),
        &|| {},
    )
    .unwrap();
    let device = evaluate(
        &data,
        &options(Some((DeviceCapacity::Small, Spill::DeviceOnly))),
        &|| {},
    )
    .unwrap();
    let s = merged.trajectories[0].spill.as_ref().unwrap();
    assert!(s.stats.records > 100, "{:?}", s.stats.records);
    assert_eq!(s.stats.dropped, 0);
    assert_eq!(s.stats.bytes_per_frame.len(), 12);
    assert!(s.stats.mean_bytes() > 0.0);
    // The merged map holds more than the device can.
    assert!(merged.trajectories[0].voxels > 1024);
    assert!(device.trajectories[0].voxels <= 1024);
    assert!(merged.metrics().miou > device.metrics().miou + 0.05);
}

/// One more voxel than the smallest tier holds moves the global map into the next tier,
/// with the same content as merging everything into that tier directly.
#[test]
fn global_map_grows_into_the_next_tier() {
    let n = GlobalMap::TIERS[0].0 + 10;
    let config = Config::with_cell_size(0.1);
    let mut global = GlobalMap::new(config).unwrap();
    let mut direct: Box<Tier1> = boxed_map(config).unwrap();
    let mut bytes = [0u8; 87];
    for i in 0..n {
        // A voxel record of one point at its voxel's centre (n = 1, zero sums).
        let (x, y, z) = ((i % 128) as u16, (i / 128 % 128) as u16, (i / 16384) as u16);
        bytes.fill(0);
        for (k, v) in [x, y, z].iter().enumerate() {
            bytes[2 * k..2 * k + 2].copy_from_slice(&(32768 + v).to_le_bytes());
        }
        bytes[6] = 1;
        bytes[47] = 3; // one vote for class 1
        let r = Record {
            kind: RecordKind::Voxel,
            bytes: &bytes,
        };
        global.merge_record(r).unwrap();
        direct.merge_record(r).unwrap();
    }
    assert_eq!(global.tier(), 1);
    assert_eq!(global.len(), n);
    assert_eq!(global.checksum(), direct.checksum());
    assert!(global.memory_bytes() > 250 << 20);
}

fn temp(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("sndt-spill-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// Maps of two halves of a walk (`a`, `b`), and the record stream of a 1,024-voxel device
/// on the whole walk (start, every evicted record, its final map, end) with the host map
/// it gives (`joint`: the records merged as they come, then the device map).
struct Robots {
    a: Box<HostMap>,
    b: Box<HostMap>,
    stream: Vec<u8>,
    joint: Box<HostMap>,
}

fn robots(data: &Synthetic, config: Config) -> Robots {
    let mut a: Box<HostMap> = boxed_map(config).unwrap();
    let mut b: Box<HostMap> = boxed_map(config).unwrap();
    let mut device: Box<Map<1024, 128, 40>> = boxed_map(config).unwrap();
    let mut stream = Vec::new();
    let mut buf = [0u8; STREAM_FRAME_BYTES];
    let (mut out, len) = StreamWriter::start(device.as_ref(), &mut buf).unwrap();
    stream.extend_from_slice(&buf[..len]);
    let mut joint: Box<HostMap> = boxed_map(config).unwrap();
    for (i, id) in data.frames().iter().enumerate() {
        let frame = data.load(id).unwrap();
        integrate_frame(
            if i < 3 { &mut *a } else { &mut *b },
            &frame,
            LabelSource::Gt,
            2,
        )
        .unwrap();
        let mut sink = |r: Record<'_>| {
            let n = out.record(r, &mut buf).unwrap();
            stream.extend_from_slice(&buf[..n]);
            joint.merge_record(r).unwrap();
            true
        };
        sndt_host::mapping::integrate_frame_spilling(
            &mut *device,
            &frame,
            LabelSource::Gt,
            2,
            Some(&mut sink),
        )
        .unwrap();
    }
    device.write_records(&mut |r: Record<'_>| {
        let n = out.record(r, &mut buf).unwrap();
        stream.extend_from_slice(&buf[..n]);
        true
    });
    let n = out.end(device.as_ref(), 0, &mut buf).unwrap();
    stream.extend_from_slice(&buf[..n]);
    joint.merge(device.as_ref()).unwrap();
    Robots {
        a,
        b,
        stream,
        joint,
    }
}

/// `sndt merge` of two saved maps equals `Map::merge`; of a device's record stream, the
/// device's map (all it evicted and its final map); a corrupt stream is refused and no
/// output is written.
#[test]
fn merge_command_merges_snapshots_and_streams() {
    let data = room(6);
    let config = Config::with_cell_size(0.1);
    let Robots {
        mut a,
        b,
        stream,
        joint,
    } = robots(&data, config);
    let (pa, pb, ps) = (temp("a.sndt"), temp("b.sndt"), temp("uart.bin"));
    sndt_host::eval::evaluate::save_snapshot(a.as_ref(), &pa).unwrap();
    sndt_host::eval::evaluate::save_snapshot(b.as_ref(), &pb).unwrap();
    std::fs::write(&ps, &stream).unwrap();
    let merged_path = temp("ab.sndt");
    let run = |inputs: Vec<std::path::PathBuf>, out: &std::path::Path| {
        merge(&MergeArgs {
            inputs,
            sndt: out.to_path_buf(),
        })
    };
    run(vec![pa.clone(), pb.clone()], &merged_path).unwrap();
    a.merge(b.as_ref()).unwrap();
    let written = GlobalMap::from_snapshot(&std::fs::read(&merged_path).unwrap()).unwrap();
    assert_eq!(written.checksum(), a.checksum());

    let from_stream = temp("stream.sndt");
    run(vec![ps.clone()], &from_stream).unwrap();
    let written = GlobalMap::from_snapshot(&std::fs::read(&from_stream).unwrap()).unwrap();
    assert!(written.len() > 1024, "the device spilled");
    assert_eq!(written.checksum(), joint.checksum());

    // One flipped byte in the middle of the stream: refused, nothing written.
    let mut corrupt = stream.clone();
    let mid = corrupt.len() / 2;
    corrupt[mid] = corrupt[mid].wrapping_add(1).max(1);
    let pc = temp("corrupt.bin");
    std::fs::write(&pc, &corrupt).unwrap();
    let never = temp("never.sndt");
    let err = run(vec![pc], &never).unwrap_err();
    assert!(format!("{err:#}").contains("record stream"), "{err:#}");
    assert!(!never.exists());
    // A stream cut before its end frame (at a frame boundary: cut inside a frame, the
    // partial frame fails its CRC).
    let cut = temp("cut.bin");
    let last = stream[..stream.len() - 1]
        .iter()
        .rposition(|&b| b == 0)
        .unwrap();
    std::fs::write(&cut, &stream[..=last]).unwrap();
    let err = run(vec![cut], &never).unwrap_err();
    assert!(format!("{err:#}").contains("no end frame"), "{err:#}");
    // Maps of different cell sizes do not merge.
    let mut other: Box<HostMap> = boxed_map(Config::with_cell_size(0.2)).unwrap();
    integrate_frame(
        &mut *other,
        &data.load(&data.frames()[0]).unwrap(),
        LabelSource::Gt,
        2,
    )
    .unwrap();
    let po = temp("other.sndt");
    sndt_host::eval::evaluate::save_snapshot(other.as_ref(), &po).unwrap();
    let err = run(vec![pa, po], &never).unwrap_err();
    assert!(format!("{err:#}").contains("another config"), "{err:#}");
    assert!(!never.exists());
}
