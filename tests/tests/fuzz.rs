//! Fuzzing the core: random garbage (NaN/inf/huge/tiny coordinates, any labels, any poses,
//! any image shapes, random valid configs) never panics a small map, keeps it within
//! capacity, accounts for every point, and leaves it in a state whose snapshot loads back.

use proptest::prelude::*;
use sndt_core::{
    Config, DepthImage, DepthKind, Error, Isometry3, LabelImage, LabeledPoint, Labels, Map,
    MissModel, Pinhole, Point3, Translation3, UnitQuaternion, Vector3, KEY_LIMIT,
};
use sndt_tests::*;

type Small = Map<32, 8, 8>;

fn weird() -> impl Strategy<Value = f32> {
    prop_oneof![
        6 => -4.0f32..4.0,
        1 => any::<f32>(),
        1 => -1e6f32..1e6,
        1 => prop::sample::select(vec![
            f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 0.0, -0.0, f32::MAX, f32::MIN,
            f32::MIN_POSITIVE, 1e-40, -1e-40, 1e30, -1e30, 3276.7, -3276.8, 3276.8, 1e-7,
        ]),
    ]
}

fn labels() -> impl Strategy<Value = Labels> {
    (
        any::<[u8; 3]>(),
        any::<[u8; 3]>(),
        prop_oneof![4 => 0u8..=3, 1 => any::<u8>()],
        prop_oneof![3 => 0u8..=8, 1 => any::<u8>()],
    )
        .prop_map(|(mut classes, scores, len, first)| {
            classes[0] = first;
            Labels {
                classes,
                scores,
                len,
            }
        })
}

fn points() -> impl Strategy<Value = Vec<LabeledPoint>> {
    prop::collection::vec(
        ([weird(), weird(), weird()], labels())
            .prop_map(|(p, l)| LabeledPoint::new(Point3::new(p[0], p[1], p[2]), l)),
        0..48,
    )
}

/// A "unit" quaternion from four raw values `w + xi + yj + zk`, not normalised.
fn raw_rotation(q: [f32; 4]) -> UnitQuaternion<f32> {
    let mut raw = UnitQuaternion::<f32>::identity().into_inner();
    raw.w = q[0];
    raw.i = q[1];
    raw.j = q[2];
    raw.k = q[3];
    UnitQuaternion::new_unchecked(raw)
}

fn pose() -> impl Strategy<Value = Isometry3<f32>> {
    prop_oneof![
        3 => ([-3.0f32..3.0, -3.0f32..3.0, -3.0f32..3.0], [-3.2f32..3.2, -3.2f32..3.2, -3.2f32..3.2])
            .prop_map(|(t, r)| Isometry3::from_parts(
                Translation3::new(t[0], t[1], t[2]),
                UnitQuaternion::from_scaled_axis(Vector3::new(r[0], r[1], r[2])),
            )),
        1 => ([weird(), weird(), weird()], [weird(), weird(), weird(), weird()])
            .prop_map(|(t, q)| Isometry3::from_parts(
                Translation3::new(t[0], t[1], t[2]),
                raw_rotation(q),
            )),
        1 => ([weird(), weird(), weird()], [weird(), weird(), weird()])
            .prop_map(|(t, r)| Isometry3::from_parts(
                Translation3::new(t[0], t[1], t[2]),
                UnitQuaternion::from_scaled_axis(Vector3::new(r[0], r[1], r[2])),
            )),
    ]
}

/// Random configs over the documented ranges, kept only if `Config::validate` accepts them.
fn config() -> impl Strategy<Value = Config> {
    (
        prop_oneof![0.01f32..0.5, 0.5f32..100.0],
        1u8..=6,
        (2u32..6, 0u32..40),
        (0.0f32..30.0, -30.0f32..0.0, -30.0f32..0.0, 0.0f32..30.0),
        (
            0.0f32..0.5,
            1u8..=3,
            any::<u8>(),
            0.1f32..50.0,
            any::<bool>(),
        ),
    )
        .prop_map(
            |(h, qb, (n_min, extra), (hit, miss, lo, hi), (lambda, k, score, range, constant))| {
                let mut c = Config::with_cell_size(h);
                c.quant_bits = qb;
                c.n_min = n_min;
                c.n_max = n_min + extra;
                c.hit = hit;
                c.miss = miss;
                c.clamp_min = lo;
                c.clamp_max = hi;
                c.lambda = lambda;
                c.top_k = k;
                c.min_score = score;
                c.max_range = range;
                c.miss_model = if constant {
                    MissModel::Constant
                } else {
                    MissModel::NdtOm
                };
                c
            },
        )
        .prop_filter("validate accepts it", |c| c.validate().is_ok())
}

#[derive(Clone, Debug)]
struct Image {
    camera: Pinhole,
    depth: Vec<f32>,
    labels: Vec<u8>,
    topk: Vec<Labels>,
    kind: u8,
    stride: u32,
}

fn image() -> impl Strategy<Value = Image> {
    (
        (
            0u32..6,
            0u32..6,
            prop_oneof![3 => 1.0f32..20.0, 1 => weird()],
            weird(),
            weird(),
        ),
        prop::collection::vec(prop_oneof![3 => 0.0f32..6.0, 1 => weird()], 0..40),
        prop::collection::vec(any::<u8>(), 0..40),
        prop::collection::vec(labels(), 0..40),
        0u8..6,
        prop_oneof![4 => 1u32..3, 1 => any::<u32>()],
        any::<bool>(),
    )
        .prop_map(
            |((w, h, f, cx, cy), mut depth, mut labels, mut topk, kind, stride, fit)| {
                let n = (w * h) as usize;
                if fit {
                    // Mostly the right sizes, so the pixels get integrated.
                    depth.resize(n, 2.0);
                    labels.resize(n, 1);
                    topk.resize(n, Labels::top1(1));
                }
                Image {
                    camera: Pinhole {
                        fx: f,
                        fy: f,
                        cx,
                        cy,
                        width: w,
                        height: h,
                    },
                    depth,
                    labels,
                    topk,
                    kind,
                    stride,
                }
            },
        )
}

fn check_frame(
    map: &Small,
    r: &Result<sndt_core::FrameReport, Error>,
    points: Option<usize>,
    before: u32,
) {
    match r {
        Ok(report) => {
            if let Some(n) = points {
                assert_accounted(report, n);
            }
        }
        Err(e) => {
            assert!(
                matches!(
                    e,
                    Error::InvalidPose | Error::PoseOutOfRange | Error::InvalidImage
                ),
                "{e:?}"
            );
            assert_eq!(map.checksum(), before, "an error changed the map");
        }
    }
    assert_capacity(map);
}

proptest! {
    #![proptest_config(sndt_tests::proptest_config(384))]

    #[test]
    fn garbage_never_panics(
        cfg in config(),
        frames in prop::collection::vec(
            (pose(), points(), prop::option::weighted(0.25, (0.0f32..4.0, any::<bool>()))),
            1..6,
        ),
        images in prop::collection::vec((pose(), image()), 0..3),
        rays in prop::collection::vec(([weird(), weird(), weird()], [weird(), weird(), weird()], prop_oneof![0.0f32..50.0, weird().prop_filter("finite", |t| t.abs() < 1e3)]), 0..4),
    ) {
        let mut map: Small = Map::try_new(cfg).unwrap();
        for (pose, pts, near_limit) in &frames {
            // Some sensors sit just inside the key range, so points beyond it are common.
            let mut pose = *pose;
            if let Some((offset, negative)) = near_limit {
                let edge = KEY_LIMIT as f32 * cfg.cell_size - offset;
                pose.translation.x = if *negative { -edge } else { edge };
            }
            let pose = &pose;
            let before = map.checksum();
            let r = map.integrate(pose, pts);
            check_frame(&map, &r, Some(pts.len()), before);
        }
        for (pose, img) in &images {
            let labels = match img.kind {
                0 | 1 => LabelImage::Top1(&img.labels),
                2 | 3 => LabelImage::TopK(&img.topk),
                _ => LabelImage::None,
            };
            let d = DepthImage {
                camera: img.camera,
                depth: sndt_core::Depth::Metres(&img.depth),
                kind: if img.kind % 2 == 0 { DepthKind::Planar } else { DepthKind::Range },
                labels,
                stride: img.stride,
            };
            let before = map.checksum();
            let r = map.integrate_depth(pose, &d);
            check_frame(&map, &r, None, before);
            if let Ok(rep) = r {
                let s = img.stride.max(1) as u64;
                let n = (img.camera.width as u64).div_ceil(s) * (img.camera.height as u64).div_ceil(s);
                prop_assert_eq!(accounted(&rep), n);
            }
            let (mut l, mut dist) = (vec![0u8; img.depth.len()], vec![0f32; img.depth.len()]);
            let _ = map.render(pose, &img.camera, &mut l, &mut dist);
        }
        for (o, d, t) in &rays {
            let _ = map.raycast(&Point3::new(o[0], o[1], o[2]), &Vector3::new(d[0], d[1], d[2]), *t);
        }
        for v in map.voxels() {
            let _ = (v.class(), v.occupancy());
            prop_assert!(v.gaussian.count >= 1);
        }
        // Whatever happened, the map is consistent: its snapshot loads and reproduces.
        let snap = snapshot(&map);
        let mut copy: Small = Map::new(Config::DEFAULT);
        copy.read_snapshot(&snap).unwrap();
        prop_assert_eq!(snapshot(&copy), snap);
    }
}

/// Found by `garbage_never_panics`: a map with 75 m cells and `n_max` 3, decayed twice,
/// whose own snapshot was refused as `SnapshotCorrupt`: decay's rounding had moved an
/// off-diagonal of the scatter matrix beyond the reader's check, which allowed slack on
/// the diagonals only.
#[test]
fn a_huge_cell_map_snapshot_reads_back() {
    use sndt_core::{Quaternion, Translation3, UnitQuaternion};
    let cfg = Config {
        cell_size: 74.703865,
        quant_bits: 4,
        n_min: 3,
        eigen_ratio: 0.001,
        n_max: 3,
        hit: 0.0,
        miss: 0.0,
        clamp_min: 0.0,
        clamp_max: 0.0,
        lambda: 0.0,
        noise_base: 0.02,
        noise_quadratic: 0.0025,
        max_range: 32.972782,
        top_k: 1,
        min_score: 0,
        votes_per_frame: 64,
        miss_model: sndt_core::MissModel::NdtOm,
        render_radius: 2.5,
        see_through_miss: 0.0,
    };
    let pose = |q: [f32; 4], t: [f32; 3]| {
        let q = UnitQuaternion::new_unchecked(Quaternion::new(q[3], q[0], q[1], q[2]));
        Isometry3::from_parts(Translation3::new(t[0], t[1], t[2]), q)
    };
    let p = |x: f32, y: f32, z: f32| LabeledPoint::new(Point3::new(x, y, z), Labels::NONE);
    let frames = [
        (
            pose(
                [-0.094090104, 0.819113, 0.5656788, -0.014433165],
                [1.0446955, 2.383615, -1.9392056],
            ),
            vec![
                p(0.0, 0.0, 1.8180071),
                p(-1.7327003, 0.0, -1.0265286),
                p(-3.452669, 0.0, 0.0),
                p(-0.90857035, 0.0, 0.0),
                p(0.0, 0.0, 1e-7),
            ],
        ),
        (
            pose(
                [0.24558431, 0.25668985, -0.7341134, 0.57868487],
                [0.0, -1.1628203, 0.0],
            ),
            vec![
                p(0.0, 0.0, -2.6370633),
                p(0.0, 0.0, -2.3874147),
                p(-2.3801415, 0.0, -2.7705739),
            ],
        ),
    ];
    let mut map: Small = Map::try_new(cfg).unwrap();
    for (pose, pts) in &frames {
        assert_eq!(
            map.integrate(pose, pts).unwrap().points_used,
            pts.len() as u32
        );
    }
    let snap = snapshot(&map);
    let mut copy: Small = Map::new(Config::DEFAULT);
    copy.read_snapshot(&snap).unwrap();
    assert_eq!(snapshot(&copy), snap);
}
