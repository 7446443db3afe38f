//! Spilling and merging: a full map hands every evicted voxel and block to its sink, and
//! nothing is lost on the way into a larger map; a sink does not change the map; merge
//! laws (an empty map changes nothing, disjoint maps give their union); the record stream
//! refuses corrupt, truncated, repeated, reordered and foreign input with the map unchanged.

use proptest::prelude::*;
use sndt_core::{
    Config, Error, Isometry3, LabeledPoint, Labels, Map, Point3, Record, RecordKind, StreamItem,
    StreamReader, StreamWriter, Translation3, UnitQuaternion, Vector3, STREAM_FRAME_BYTES,
};
use sndt_tests::*;

type Device = Map<64, 16, 4>;
type Global = Map<8192, 2048, 4>;

fn global(config: Config) -> Box<Global> {
    sndt_host::mapping::boxed_map(config).unwrap()
}

/// A sensor walking along x and back, 1 m from a cluster of points: the device map fills,
/// evicts, and re-observes voxels it evicted on the way back.
fn walk() -> Vec<(Isometry3<f32>, Vec<LabeledPoint>)> {
    (0..48)
        .map(|frame| {
            let x = 0.3 * (if frame < 24 { frame } else { 47 - frame }) as f32;
            let pose = Isometry3::from_parts(Translation3::new(x, 0.05, 0.05), Default::default());
            let points = (0..40)
                .map(|i| {
                    let p = Point3::new(
                        0.02 + 0.05 * (i % 4) as f32,
                        0.02 + 0.05 * (i / 4 % 4) as f32,
                        1.02 + 0.1 * (i / 16) as f32,
                    );
                    LabeledPoint::new(p, Labels::top1(1 + ((i + frame) % 4) as u8))
                })
                .collect();
            (pose, points)
        })
        .collect()
}

/// Every record of a map, as (kind, bytes), sorted.
fn records<const V: usize, const B: usize>(map: &Map<V, B, 4>) -> Vec<(bool, Vec<u8>)> {
    let mut out = Vec::new();
    map.write_records(&mut |r: Record<'_>| {
        out.push((r.kind == RecordKind::Block, r.bytes.to_vec()));
        true
    });
    out.sort();
    out
}

#[test]
fn a_sink_changes_nothing_in_the_map_and_takes_every_eviction() {
    let mut plain = Device::new(Config::DEFAULT);
    let mut spilling = Device::new(Config::DEFAULT);
    let mut refusing = Device::new(Config::DEFAULT);
    let (mut evicted, mut dropped) = (0u64, 0u64);
    for (pose, points) in walk() {
        let a = plain.integrate(&pose, &points).unwrap();
        let mut taken = 0u32;
        let mut sink = |_: Record<'_>| {
            taken += 1;
            true
        };
        let b = spilling
            .integrate_spilling(&pose, &points, &mut sink)
            .unwrap();
        let c = refusing
            .integrate_spilling(&pose, &points, &mut |_: Record<'_>| false)
            .unwrap();
        // One record per evicted voxel and per evicted block, taken or counted as dropped.
        let n = a.voxels_evicted + a.blocks_evicted;
        assert_eq!((b.records_spilled, b.records_dropped, taken), (n, 0, n));
        assert_eq!((c.records_spilled, c.records_dropped), (0, n));
        let strip = |mut r: sndt_core::FrameReport| {
            r.records_spilled = 0;
            r.records_dropped = 0;
            r
        };
        assert_eq!(strip(b), a);
        assert_eq!(strip(c), a);
        assert_eq!(spilling.checksum(), plain.checksum());
        assert_eq!(refusing.checksum(), plain.checksum());
        evicted += n as u64;
        dropped += c.records_dropped as u64;
    }
    assert!(evicted > 100, "the walk must overflow the device map");
    assert_eq!(dropped, evicted);
}

/// With no decay (`n_max` above any count), the device plus its spill, merged, holds
/// exactly the points of one large map that integrated the same frames: the same voxels
/// with the same sums, and the same blocks. Only log-odds (clamped per update) and the
/// sampled histograms may differ.
#[test]
fn device_plus_spill_loses_no_point() {
    let mut config = Config::DEFAULT;
    config.n_max = 65535;
    let mut device = Device::new(config);
    let mut merged = global(config);
    let mut joint = global(config);
    let mut spilled = 0;
    for (pose, points) in walk() {
        let mut sink = |r: Record<'_>| merged.merge_record(r).is_ok();
        let r = device
            .integrate_spilling(&pose, &points, &mut sink)
            .unwrap();
        assert_eq!((r.dropped_points, r.records_dropped), (0, 0));
        spilled += r.records_spilled;
        let j = joint.integrate(&pose, &points).unwrap();
        assert_eq!(j.voxels_evicted + j.blocks_evicted, 0);
    }
    merged.merge(&device).unwrap();
    assert!(spilled > 100);
    assert_eq!(merged.stats().frames, joint.stats().frames);
    assert_eq!(merged.len(), joint.len());
    assert_eq!(merged.block_count(), joint.block_count());
    for v in joint.voxels() {
        let g = merged
            .gaussian(&v.key)
            .expect("every voxel of the joint map");
        assert_eq!(g.count, v.gaussian.count, "{:?}", v.key);
        assert_eq!(g.mean, v.gaussian.mean, "{:?}", v.key);
        assert_eq!(g.covariance, v.gaussian.covariance, "{:?}", v.key);
    }
    // The merged map is a valid map: its snapshot loads.
    let mut copy = global(config);
    copy.read_snapshot(&snapshot(&*merged)).unwrap();
    assert_eq!(copy.checksum(), merged.checksum());
}

#[test]
fn stream_round_trip_is_merge_and_refuses_bad_streams() {
    let mut device = Device::new(Config::DEFAULT);
    let mut direct = global(Config::DEFAULT);
    let mut frames: Vec<Vec<u8>> = Vec::new();
    let mut buf = [0u8; STREAM_FRAME_BYTES];
    let (mut out, n) = StreamWriter::start(&device, &mut buf).unwrap();
    frames.push(buf[..n].to_vec());
    let mut dropped = 0;
    for (pose, points) in walk() {
        let mut sink = |r: Record<'_>| {
            let n = out.record(r, &mut buf).unwrap();
            frames.push(buf[..n].to_vec());
            direct.merge_record(r).unwrap();
            true
        };
        dropped += device
            .integrate_spilling(&pose, &points, &mut sink)
            .unwrap()
            .records_dropped;
    }
    device.write_records(&mut |r: Record<'_>| {
        let n = out.record(r, &mut buf).unwrap();
        frames.push(buf[..n].to_vec());
        true
    });
    let n = out.end(&device, dropped, &mut buf).unwrap();
    frames.push(buf[..n].to_vec());
    direct.merge(&device).unwrap();

    // The stream merged frame by frame gives the same map as the direct merges.
    let good = merge_stream(&frames).unwrap();
    assert_eq!(good.checksum(), direct.checksum());

    let check = |bad: Vec<Vec<u8>>, want: Error| {
        assert_eq!(merge_stream(&bad).err(), Some(want));
    };
    // A flipped bit anywhere in a frame.
    let mut corrupt = frames.clone();
    corrupt[5][17] ^= 0x10;
    check(corrupt, Error::StreamChecksum);
    // Cut short: no end frame.
    check(frames[..frames.len() - 1].to_vec(), Error::StreamTruncated);
    // A frame twice, two frames swapped, one missing.
    let mut twice = frames.clone();
    twice.insert(7, frames[6].clone());
    check(twice, Error::StreamOrder);
    let mut swapped = frames.clone();
    swapped.swap(8, 9);
    check(swapped, Error::StreamOrder);
    let mut missing = frames.clone();
    missing.remove(10);
    check(missing, Error::StreamOrder);
    // Records of a stream of another cell size, spliced in at the right place in the
    // sequence (same sequence numbers), are from another config.
    let other = foreign_stream(Config::with_cell_size(0.2));
    let mut spliced = frames.clone();
    spliced[3] = other[3].clone();
    check(spliced, Error::ConfigMismatch);
}

/// A stream of a map of another config: start, then a few voxel records.
fn foreign_stream(config: Config) -> Vec<Vec<u8>> {
    let mut map = Device::new(config);
    let pts: Vec<LabeledPoint> = (0..8).map(|i| lp(0.3 * i as f32, 0.0, 1.0, 1)).collect();
    map.integrate(&Isometry3::identity(), &pts).unwrap();
    let mut buf = [0u8; STREAM_FRAME_BYTES];
    let (mut out, n) = StreamWriter::start(&map, &mut buf).unwrap();
    let mut frames = vec![buf[..n].to_vec()];
    map.write_records(&mut |r: Record<'_>| {
        let n = out.record(r, &mut buf).unwrap();
        frames.push(buf[..n].to_vec());
        true
    });
    frames
}

/// Reads a whole stream, checking everything before merging anything (the map is built
/// only when the whole stream is valid).
fn merge_stream(frames: &[Vec<u8>]) -> Result<Box<Global>, Error> {
    let mut reader = StreamReader::new();
    let mut scratch = [0u8; STREAM_FRAME_BYTES];
    let mut records = Vec::new();
    let check = Device::new(Config::DEFAULT);
    for f in frames {
        match reader.read(f, &mut scratch)? {
            StreamItem::Start(h) if h.config != Config::DEFAULT => {
                return Err(Error::ConfigMismatch)
            }
            StreamItem::Start(_) | StreamItem::End(_) => {}
            StreamItem::Record(r) => {
                check.check_record(r)?;
                records.push((r.kind, r.bytes.to_vec()));
            }
        }
    }
    let end = reader.finish()?;
    let mut map = global(Config::DEFAULT);
    for (kind, bytes) in &records {
        map.merge_record(Record { kind: *kind, bytes })?;
    }
    map.add_frames(end.frames);
    Ok(map)
}

#[test]
fn failed_merges_leave_the_map_unchanged() {
    let mut a = Device::new(Config::DEFAULT);
    for (pose, points) in walk().iter().take(6) {
        a.integrate(pose, points).unwrap();
    }
    // Another config: refused.
    let mut b = Device::new(Config::with_cell_size(0.2));
    b.integrate(&Isometry3::identity(), &[lp(0.0, 0.0, 1.0, 1)])
        .unwrap();
    let before = a.checksum();
    assert_eq!(a.merge(&b), Err(Error::ConfigMismatch));
    assert_eq!(a.checksum(), before);
    // No room: a tiny map cannot take a's content, and stays as it was.
    let mut tiny: Map<4, 2, 4> = Map::new(Config::DEFAULT);
    tiny.integrate(&Isometry3::identity(), &[lp(0.0, 0.0, 1.0, 1)])
        .unwrap();
    let tiny_before = tiny.checksum();
    assert_eq!(tiny.merge(&*Box::new(a)), Err(Error::MapFull));
    assert_eq!(tiny.checksum(), tiny_before);
    // Record by record, the first that does not fit fails and leaves the map as it was.
    let mut c = Device::new(Config::DEFAULT);
    for (pose, points) in walk().iter().skip(20).take(6) {
        c.integrate(pose, points).unwrap();
    }
    let mut refused = 0;
    c.write_records(&mut |r: Record<'_>| {
        let before = tiny.checksum();
        if let Err(e) = tiny.merge_record(r) {
            assert_eq!(e, Error::MapFull);
            assert_eq!(tiny.checksum(), before);
            refused += 1;
        }
        true
    });
    assert!(refused > 0);
    // A record of the wrong length, and a voxel with a count above n_max.
    let mut voxel = Vec::new();
    c.write_records(&mut |r: Record<'_>| {
        if r.kind == RecordKind::Voxel && voxel.is_empty() {
            voxel = r.bytes.to_vec();
        }
        true
    });
    let before = tiny.checksum();
    let short = Record {
        kind: RecordKind::Voxel,
        bytes: &voxel[..voxel.len() - 1],
    };
    assert_eq!(tiny.merge_record(short), Err(Error::RecordCorrupt));
    voxel[6..10].copy_from_slice(&(Config::DEFAULT.n_max + 1).to_le_bytes());
    let big = Record {
        kind: RecordKind::Voxel,
        bytes: &voxel,
    };
    assert_eq!(tiny.merge_record(big), Err(Error::RecordCorrupt));
    assert_eq!(tiny.checksum(), before);
}

/// Random labelled points in a 2 m cube around `center`, seen from a random pose near it.
fn frames_near(center: f32) -> impl Strategy<Value = Vec<(Isometry3<f32>, Vec<LabeledPoint>)>> {
    let frame = (
        [-0.5f32..0.5, -0.5f32..0.5, -0.5f32..0.5],
        [-3.0f32..3.0, -3.0f32..3.0, -3.0f32..3.0],
        prop::collection::vec(
            ([-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0], 0u8..=4),
            1..120,
        ),
    )
        .prop_map(move |(t, r, world)| {
            let pose = Isometry3::from_parts(
                Translation3::new(center + t[0], t[1], t[2]),
                UnitQuaternion::from_scaled_axis(Vector3::new(r[0], r[1], r[2])),
            );
            let points = world
                .iter()
                .map(|(w, l)| {
                    let w = [center + w[0], w[1], w[2]];
                    LabeledPoint::new(to_sensor(&pose, &w), Labels::top1(*l))
                })
                .collect();
            (pose, points)
        });
    prop::collection::vec(frame, 1..5)
}

fn build(frames: &[(Isometry3<f32>, Vec<LabeledPoint>)], config: Config) -> Box<Global> {
    let mut map = global(config);
    for (pose, points) in frames {
        let r = map.integrate(pose, points).unwrap();
        assert_eq!(r.voxels_evicted + r.blocks_evicted + r.dropped_points, 0);
    }
    map
}

fn short_range() -> Config {
    let mut c = Config::with_cell_size(0.1);
    c.max_range = 3.0;
    c
}

proptest! {
    #![proptest_config(sndt_tests::proptest_config(24))]

    #[test]
    fn merging_an_empty_map_changes_nothing(frames in frames_near(0.0)) {
        let mut map = build(&frames, short_range());
        let before = snapshot(&*map);
        map.merge(&*global(short_range())).unwrap();
        prop_assert_eq!(snapshot(&*map), before);
    }

    /// Maps 50 m apart (rays end at 3 m) share no block: their merge is exactly their
    /// union, record for record, with their frames added.
    #[test]
    fn disjoint_maps_merge_to_their_union(a in frames_near(0.0), b in frames_near(50.0)) {
        let (ma, mb) = (build(&a, short_range()), build(&b, short_range()));
        let mut merged = global(short_range());
        merged.merge(&*ma).unwrap();
        merged.merge(&*mb).unwrap();
        let mut union = records(&*ma);
        union.extend(records(&*mb));
        union.sort();
        prop_assert_eq!(records(&*merged), union);
        prop_assert_eq!(merged.stats().frames, (a.len() + b.len()) as u32);
        // Merging into a copy of one side gives the same map.
        let mut other = build(&a, short_range());
        other.merge(&*mb).unwrap();
        prop_assert_eq!(other.checksum(), merged.checksum());
    }

    /// A map merged with itself (same keys everywhere) is a valid map: sums, histograms
    /// and log-odds stay within what its snapshot reader accepts.
    #[test]
    fn overlapping_merges_stay_valid(a in frames_near(0.0), b in frames_near(0.0)) {
        let mut merged = build(&a, short_range());
        let mb = build(&b, short_range());
        for _ in 0..3 {
            merged.merge(&*mb).unwrap();
        }
        let mut copy = global(short_range());
        copy.read_snapshot(&snapshot(&*merged)).unwrap();
        prop_assert_eq!(copy.checksum(), merged.checksum());
    }
}
