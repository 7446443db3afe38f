//! Order independence: the map after a frame does not depend on the order of the frame's points
//! (integer sums, one hit per end voxel, rays in sorted order). Checked on snapshot bytes.

use proptest::prelude::*;
use sndt_core::{
    Config, FrameReport, Isometry3, LabeledPoint, Labels, Map, Translation3, UnitQuaternion,
    Vector3,
};
use sndt_tests::*;

const CLASSES: usize = 8;
type BigMap = Map<4096, 4096, CLASSES>;

#[derive(Clone, Debug)]
struct Frame {
    pose: Isometry3<f32>,
    points: Vec<LabeledPoint>,
    /// A permutation of `0..points.len()`.
    order: Vec<usize>,
}

fn labels() -> impl Strategy<Value = Labels> {
    prop_oneof![
        (0u8..=CLASSES as u8).prop_map(Labels::top1),
        prop::collection::vec((0u8..=CLASSES as u8, any::<u8>()), 3)
            .prop_map(|pairs| Labels::top_k(&pairs)),
    ]
}

fn pose() -> impl Strategy<Value = Isometry3<f32>> {
    (
        [-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0],
        [-3.2f32..3.2, -3.2f32..3.2, -3.2f32..3.2],
    )
        .prop_map(|(t, r)| {
            Isometry3::from_parts(
                Translation3::new(t[0], t[1], t[2]),
                UnitQuaternion::from_scaled_axis(Vector3::new(r[0], r[1], r[2])),
            )
        })
}

/// World points in a 2 m cube, a quarter of them exact duplicates of others (several points
/// per voxel is what makes order matter for non-exact sums).
fn frame() -> impl Strategy<Value = Frame> {
    (
        pose(),
        prop::collection::vec(
            ([-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0], labels()),
            1..300,
        ),
        prop::collection::vec(any::<prop::sample::Index>(), 0..80),
    )
        .prop_flat_map(|(pose, world, dups)| {
            let mut points: Vec<LabeledPoint> = world
                .iter()
                .map(|(w, l)| LabeledPoint::new(to_sensor(&pose, w), *l))
                .collect();
            for d in dups {
                let p = points[d.index(points.len())];
                points.push(p);
            }
            let n = points.len();
            (
                Just(pose),
                Just(points),
                Just((0..n).collect::<Vec<_>>()).prop_shuffle(),
            )
        })
        .prop_map(|(pose, points, order)| Frame {
            pose,
            points,
            order,
        })
}

fn config() -> impl Strategy<Value = Config> {
    (
        0.08f32..0.25,
        1u8..=3,
        prop::sample::select(vec![0u8, 100]),
        prop::sample::select(vec![20.0f32, 1.5]),
        prop::bool::ANY,
    )
        .prop_map(|(h, top_k, min_score, max_range, constant)| {
            let mut c = Config::with_cell_size(h);
            c.top_k = top_k;
            c.min_score = min_score;
            c.max_range = max_range;
            if constant {
                c.miss_model = sndt_core::MissModel::Constant;
            }
            c
        })
}

fn run(map: &mut BigMap, frame: &Frame, permuted: bool) -> FrameReport {
    let points: Vec<LabeledPoint> = if permuted {
        frame.order.iter().map(|&i| frame.points[i]).collect()
    } else {
        frame.points.clone()
    };
    let r = map.integrate(&frame.pose, &points).unwrap();
    assert_eq!(r.voxels_evicted, 0, "map too small for the test: {r:?}");
    assert_eq!(r.blocks_evicted, 0, "map too small for the test: {r:?}");
    assert_eq!(r.dropped_points, 0);
    assert_eq!(r.dropped_misses, 0);
    assert_accounted(&r, points.len());
    r
}

proptest! {
    #![proptest_config(sndt_tests::proptest_config(64))]

    #[test]
    fn frame_is_independent_of_point_order(cfg in config(), a in frame(), b in frame()) {
        let mut m1 = sndt_host::mapping::boxed_map::<4096, 4096, CLASSES>(cfg).unwrap();
        let mut m2 = sndt_host::mapping::boxed_map::<4096, 4096, CLASSES>(cfg).unwrap();

        let r1 = run(&mut m1, &a, false);
        let r2 = run(&mut m2, &a, true);
        prop_assert_eq!(r1, r2);
        prop_assert!(r1.points_used + r1.truncated > 0);
        prop_assert_eq!(snapshot(&*m1), snapshot(&*m2));

        // A second frame on top of the first, again in two orders.
        let r1 = run(&mut m1, &b, true);
        let r2 = run(&mut m2, &b, false);
        prop_assert_eq!(r1, r2);
        let (s1, s2) = (snapshot(&*m1), snapshot(&*m2));
        prop_assert_eq!(&s1, &s2);
        prop_assert_eq!(m1.checksum(), m2.checksum());
        prop_assert_eq!(u32::from_le_bytes(s1[s1.len() - 4..].try_into().unwrap()), m1.checksum());
    }
}

/// A whole room frame (many points per voxel, realistic structure), reversed and
/// interleaved, gives the same bytes.
#[test]
fn room_frame_is_independent_of_point_order() {
    let cam = camera(96, 72);
    let pose = sndt_host::dataset::synthetic::room::orbit(8)[3];
    let points = room_frame(&pose, &cam);
    assert!(points.len() > 5000);
    let reversed: Vec<_> = points.iter().rev().copied().collect();
    let interleaved: Vec<_> = points
        .iter()
        .step_by(2)
        .chain(points.iter().skip(1).step_by(2))
        .copied()
        .collect();
    let mut snaps = Vec::new();
    for pts in [&points, &reversed, &interleaved] {
        let mut map = sndt_host::mapping::boxed_map::<8192, 8192, 40>(Config::DEFAULT).unwrap();
        let r = map.integrate(&pose, pts).unwrap();
        assert_eq!(
            (r.voxels_evicted, r.blocks_evicted, r.dropped_points),
            (0, 0, 0)
        );
        assert_accounted(&r, pts.len());
        snaps.push(snapshot(&*map));
    }
    assert_eq!(snaps[0], snaps[1]);
    assert_eq!(snaps[0], snaps[2]);
}

/// Crowded voxels sample their votes (`Config::votes_per_frame`): after a dense first frame
/// the next frames keep one voting point in `2^k`, chosen by coordinates, so three dense
/// room frames in any order still give the same bytes.
#[test]
fn sampled_votes_are_independent_of_point_order() {
    let cam = camera(256, 192);
    let poses = sndt_host::dataset::synthetic::room::orbit(12);
    let config = Config {
        votes_per_frame: 8,
        ..Config::DEFAULT
    };
    let mut forward = sndt_host::mapping::boxed_map::<16384, 8192, 40>(config).unwrap();
    let mut reversed = sndt_host::mapping::boxed_map::<16384, 8192, 40>(config).unwrap();
    for pose in &poses[..3] {
        let points = room_frame(pose, &cam);
        let back: Vec<_> = points.iter().rev().copied().collect();
        forward.integrate(pose, &points).unwrap();
        reversed.integrate(pose, &back).unwrap();
        assert_eq!(snapshot(&*forward), snapshot(&*reversed));
    }
    // Sampling did happen: voxels with at most 255 points (so counting them all would
    // neither saturate nor halve) hold fewer than half as many votes as points (every
    // point of the room carries a label).
    let sampled = forward
        .voxels()
        .filter(|v| {
            let votes: u32 = v.histogram.iter().map(|&b| b as u32).sum();
            votes > 0 && 2 * votes < v.gaussian.count && v.gaussian.count <= 255
        })
        .count();
    assert!(sampled > 10, "{sampled} voxels with sampled votes");
}
