//! The f64 reference S-NDT (`sndt_host::reference`) against hand calculations, and the
//! core against the reference within `sndt_host::eval::compare::TOLERANCES` on a fixed
//! synthetic trajectory at 10 cm (`docs/EVALUATION.md`, the f64 reference and
//! tolerances).

use sndt_core::{
    Config, Isometry3, LabeledPoint, Labels, Map, MissModel, Pinhole, Point3, VoxelKey,
};
use sndt_host::dataset::Dataset;
use sndt_host::eval::compare::{compare, Options};
use sndt_host::reference::RefMap;

type SmallMap = Map<1024, 256, 40>;

fn pts(points: &[[f32; 3]], class: u8) -> Vec<LabeledPoint> {
    points
        .iter()
        .map(|p| LabeledPoint::new(Point3::new(p[0], p[1], p[2]), Labels::top1(class)))
        .collect()
}

fn close(a: f64, b: f64, tol: f64, what: &str) {
    assert!((a - b).abs() <= tol, "{what}: {a} != {b} (tolerance {tol})");
}

/// Six points symmetric about the centre of voxel (0, 0, 10) at 10 cm:
/// `c +- (0.02, 0, 0)`, `c +- (0, 0.01, 0)`, `c +- (0, 0, 0.03)`, so the mean is `c` and the
/// covariance `diag(2 * 0.02^2, 2 * 0.01^2, 2 * 0.03^2) / 5`.
fn six_points() -> Vec<[f32; 3]> {
    vec![
        [0.07, 0.05, 1.05],
        [0.03, 0.05, 1.05],
        [0.05, 0.06, 1.05],
        [0.05, 0.04, 1.05],
        [0.05, 0.05, 1.08],
        [0.05, 0.05, 1.02],
    ]
}

#[test]
fn one_voxel_mean_and_covariance_are_the_textbook_values() {
    // Offsets from the mean m = (0.05, 0.05, 1.05): (+-0.02, 0, 0), +-(0, 0.01, 0.01).
    let p = [
        [0.07, 0.05, 1.05],
        [0.03, 0.05, 1.05],
        [0.05, 0.06, 1.06],
        [0.05, 0.04, 1.04],
    ];
    let mut r = RefMap::new(Config::DEFAULT, 40);
    r.integrate(&Isometry3::identity(), &pts(&p, 1)).unwrap();
    let g = r.gaussian(&[0, 0, 10]).unwrap();
    assert_eq!(g.count, 4.0);
    // Inputs are f32: a few 1e-8 m of representation error.
    for (i, m) in [0.05, 0.05, 1.05].into_iter().enumerate() {
        close(g.mean[i], m, 1e-7, "mean");
    }
    // Sigma = sum d d^T / (n - 1): xx = 2 * 0.02^2 / 3, yy = zz = yz = 2 * 0.01^2 / 3.
    let want = [
        [0.0008 / 3.0, 0.0, 0.0],
        [0.0, 0.0002 / 3.0, 0.0002 / 3.0],
        [0.0, 0.0002 / 3.0, 0.0002 / 3.0],
    ];
    for (i, row) in want.iter().enumerate() {
        for (j, &w) in row.iter().enumerate() {
            close(g.covariance[(i, j)], w, 1e-9, "covariance");
        }
    }
    // The core quantises offsets to h / 64 (round half up): 0.02 m = 12.8 quanta -> +-13,
    // 0.01 m = 6.4 quanta -> +-6. By hand: mean at the centre, Sigma = (2 * 13^2, 2 * 6^2
    // ...) / 3 quanta^2.
    let mut core: Box<SmallMap> = sndt_host::mapping::boxed_map(Config::DEFAULT).unwrap();
    core.integrate(&Isometry3::identity(), &pts(&p, 1)).unwrap();
    let c = core.gaussian(&VoxelKey { x: 0, y: 0, z: 10 }).unwrap();
    assert_eq!(c.count, 4);
    let q2 = (0.1f64 / 64.0).powi(2);
    let (qx, qy) = (2.0 * 169.0 / 3.0 * q2, 2.0 * 36.0 / 3.0 * q2);
    let want = [[qx, 0.0, 0.0], [0.0, qy, qy], [0.0, qy, qy]];
    for (i, row) in want.iter().enumerate() {
        close(
            c.mean[i] as f64,
            0.05 + (i == 2) as u8 as f64,
            1e-6,
            "core mean",
        );
        for (j, &w) in row.iter().enumerate() {
            close(c.covariance[(i, j)] as f64, w, 1e-6 * qx, "core covariance");
        }
    }
}

#[test]
fn point_cap_halves_the_count_and_keeps_the_mean() {
    let mut config = Config::DEFAULT;
    config.n_max = 4;
    let mut r = RefMap::new(config, 40);
    let p = six_points();
    let mut ten = p.clone();
    ten.extend_from_slice(&p[..4]);
    r.integrate(&Isometry3::identity(), &pts(&ten, 1)).unwrap();
    // 10 > 4: 10 -> 5 -> 3 points; sums scaled by 3/10, so the mean stays.
    let v = r.voxel(&[0, 0, 10]).unwrap();
    assert_eq!(v.n, 3.0);
    let mean: [f64; 3] = [0, 1, 2].map(|i| ten.iter().map(|q| q[i] as f64).sum::<f64>() / 10.0);
    let g = r.gaussian(&[0, 0, 10]).unwrap();
    for (&got, &want) in g.mean.iter().zip(&mean) {
        close(got, want, 1e-12, "mean after decay");
    }
}

/// Frame 1: the six points (voxel A = (0, 0, 10) gets a hit and a Gaussian). Frame 2: one
/// point at `p2` whose ray passes through A.
fn two_frames(config: Config, first: &[[f32; 3]], p2: [f32; 3]) -> (RefMap, Box<SmallMap>) {
    let mut r = RefMap::new(config, 40);
    let mut core: Box<SmallMap> = sndt_host::mapping::boxed_map(config).unwrap();
    for frame in [pts(first, 1), pts(&[p2], 2)] {
        r.integrate(&Isometry3::identity(), &frame).unwrap();
        core.integrate(&Isometry3::identity(), &frame).unwrap();
    }
    (r, core)
}

fn core_log_odds(core: &SmallMap, k: [i16; 3]) -> f64 {
    core.log_odds(&VoxelKey {
        x: k[0],
        y: k[1],
        z: k[2],
    }) as f64
}

/// A's log-odds after `two_frames` is `want` in the reference (to 1e-5) and the core (its
/// 1/1024 fixed point), and the voxel behind A, which has no Gaussian, got the constant
/// `miss`.
fn check_a_and_behind(r: &RefMap, core: &SmallMap, want: f64, miss: f32) {
    close(r.log_odds(&[0, 0, 10]), want, 1e-5, "reference A");
    close(core_log_odds(core, [0, 0, 10]), want, 2e-3, "core A");
    close(r.log_odds(&[0, 0, 15]), miss as f64, 1e-12, "behind A");
}

#[test]
fn constant_miss_by_hand() {
    let mut config = Config::DEFAULT;
    config.miss_model = MissModel::Constant;
    let (r, core) = two_frames(config, &six_points(), [0.09, 0.09, 2.15]);
    let (hit, miss) = (config.hit as f64, config.miss as f64);
    // A: a hit in frame 1, a miss in frame 2.
    close(r.log_odds(&[0, 0, 10]), hit + miss, 1e-12, "A");
    // In front of A: a miss in each frame; behind A: one miss; the end voxel: one hit.
    close(r.log_odds(&[0, 0, 5]), 2.0 * miss, 1e-12, "before A");
    close(r.log_odds(&[0, 0, 15]), miss, 1e-12, "behind A");
    close(r.log_odds(&[0, 0, 21]), hit, 1e-12, "end voxel");
    // The core's fixed point (1/1024 per update) agrees.
    for (k, want) in [
        ([0, 0, 10], hit + miss),
        ([0, 0, 5], 2.0 * miss),
        ([0, 0, 15], miss),
        ([0, 0, 21], hit),
    ] {
        close(core_log_odds(&core, k), want, 2e-3, "core");
    }
}

#[test]
fn ndt_om_miss_by_hand() {
    // NDT-OM as published: no see-through miss.
    let config = Config {
        see_through_miss: 0.0,
        ..Config::DEFAULT
    };
    let p2 = [0.09f32, 0.09, 2.15];
    let (r, core) = two_frames(config, &six_points(), p2);
    // The ray: from s = 0 to the mean of the end voxel's single point, z = p2.
    let z = p2.map(|x| x as f64);
    let len = (z[0] * z[0] + z[1] * z[1] + z[2] * z[2]).sqrt();
    let u = z.map(|x| x / len);
    // A's Gaussian: mean (0.05, 0.05, 1.05), Sigma = diag(0.0008, 0.0002, 0.0018) / 5.
    let mu = [0.05, 0.05, 1.05];
    let inv = [5.0 / 0.0008, 5.0 / 0.0002, 5.0 / 0.0018];
    // t* = u^T Sinv (mu - s) / u^T Sinv u, x = s + t* u.
    let a: f64 = (0..3).map(|i| u[i] * inv[i] * u[i]).sum();
    let t = (0..3).map(|i| u[i] * inv[i] * mu[i]).sum::<f64>() / a;
    let x = u.map(|ui| t * ui);
    let m2: f64 = (0..3).map(|i| (x[i] - mu[i]).powi(2) * inv[i]).sum();
    let p_n = (-0.5 * m2).exp();
    let sigma = 0.02 + 0.0025 * len * len;
    let p_z = (-0.5 * (len - t).powi(2) / (sigma * sigma)).exp();
    let p = 0.5 - 0.1 * p_n * (1.0 - p_z);
    let miss = (p / (1.0 - p)).ln();
    // Mahalanobis^2 about 1.1 at 1.05 m, the point 1.1 m farther: a weaker miss than -0.4.
    assert!(
        p_n > 0.5 && p_z < 1e-6 && miss > -0.35 && miss < -0.2,
        "{p_n} {p_z} {miss}"
    );
    let want = config.hit as f64 + miss;
    // f32 inputs and config values: agreement to ~1e-6.
    check_a_and_behind(&r, &core, want, config.miss);
}

#[test]
fn ndt_om_miss_is_skipped_when_the_gaussian_lies_beyond_the_ray_end() {
    // A's points: mu +- 0.01 on each axis about mu = (0.085, 0.05, 1.085) (near A's far
    // corner). Frame 2's ray clips A's corner and ends just beyond it, at z = (0.1005, 0.05,
    // 1.05) in voxel (1, 0, 10): the ray's closest point to mu lies beyond z, so A gets no
    // miss and keeps exactly its hit.
    let mu = [0.085f32, 0.05, 1.085];
    let mut first = Vec::new();
    for axis in 0..3 {
        for s in [-0.01f32, 0.01] {
            let mut p = mu;
            p[axis] += s;
            first.push(p);
        }
    }
    let config = Config::DEFAULT;
    let (r, core) = two_frames(config, &first, [0.1005, 0.05, 1.05]);
    let (hit, miss) = (config.hit as f64, config.miss as f64);
    close(r.log_odds(&[0, 0, 10]), hit, 1e-12, "A");
    close(r.log_odds(&[0, 0, 9]), 2.0 * miss, 1e-12, "before A");
    close(r.log_odds(&[1, 0, 10]), hit, 1e-12, "end voxel");
    close(core_log_odds(&core, [0, 0, 10]), hit, 1e-3, "core A");
}

#[test]
fn histogram_halving_by_hand() {
    // Distinct points on a 7 x 7 x 7 lattice in voxel (0, 0, 10); at most 64 voting
    // points per frame, so with `votes_per_frame = 64` every point votes.
    let lattice = |from: usize, n: usize| -> Vec<[f32; 3]> {
        let at = |d: usize| 0.005 + 0.012 * (d % 7) as f32;
        (from..from + n)
            .map(|c| [at(c), at(c / 7), 1.0 + at(c / 49)])
            .collect()
    };
    let frames = [
        (60, 1u8),
        (63, 1),
        (64, 1),
        (11, 2),
        (5, 1),
        (64, 3),
        (1, 3),
    ];
    let config = Config {
        votes_per_frame: 64,
        ..Config::DEFAULT
    };
    let mut r = RefMap::new(config, 40);
    let mut core: Box<SmallMap> = sndt_host::mapping::boxed_map(config).unwrap();
    let mut from = 0;
    for (n, class) in frames {
        let frame = pts(&lattice(from, n), class);
        from += n;
        r.integrate(&Isometry3::identity(), &frame).unwrap();
        core.integrate(&Isometry3::identity(), &frame).unwrap();
    }
    // [60] -> [123] -> [187] -> [187, 11] -> [192, 11] -> halve (192 > 255 - 64): [96, 5.5]
    // (the core floors: [96, 5]), + 64 x class 3 -> [96, 5.5, 64] -> + 1 -> [96, 5.5, 65].
    let v = r.voxel(&[0, 0, 10]).unwrap();
    assert_eq!(&v.hist[..4], &[96.0, 5.5, 65.0, 0.0]);
    assert_eq!(v.class(), Some((1, 96.0 / 166.5)));
    let c = core.voxel(&VoxelKey { x: 0, y: 0, z: 10 }).unwrap();
    assert_eq!(&c.histogram[..4], &[96, 5, 65, 0]);
    assert_eq!(c.class(), Some((1, 96.0 / 166.0)));
}

/// `TOLERANCES` on a fixed synthetic trajectory (living room, 20 frames of
/// 256x192, exact depth, ground-truth labels) at 10 cm. If this fails, fix the core, never
/// the thresholds.
#[test]
fn core_matches_reference_within_tolerances_at_10cm() {
    let camera = Pinhole {
        fx: 221.7,
        fy: 221.7,
        cx: 128.0,
        cy: 96.0,
        width: 256,
        height: 192,
    };
    let split = sndt_tests::synthetic(1, 20, camera, false);
    let frames: Vec<_> = split
        .frames()
        .iter()
        .map(|id| split.load(id).unwrap())
        .collect();
    let r = compare(&frames, &Config::with_cell_size(0.1), &Options::default()).unwrap();
    println!("{r:#?}");
    assert_eq!((r.only_core, r.only_ref, r.count_mismatch), (0, 0, 0));
    assert_eq!(r.core_stats.voxels_evicted + r.core_stats.blocks_evicted, 0);
    assert!(r.both > 1000, "{} voxels", r.both);
    let e = &r.mean_error_mm;
    assert!(e.mean <= 1.0, "voxel-mean error mean {} mm > 1 mm", e.mean);
    assert!(e.p99 <= 2.0, "voxel-mean error p99 {} mm > 2 mm", e.p99);
    let c = &r.covariance_error;
    assert!(c.count > 1000);
    assert!(
        c.median <= 0.02,
        "covariance median relative error {} > 2 %",
        c.median
    );
    let occ = r.occupancy.fraction();
    assert!(occ >= 0.995, "occupancy agreement {occ} < 99.5 %");
    let class = r.class.fraction();
    assert!(class >= 0.995, "class agreement {class} < 99.5 %");
    let b = r.back_projection.as_ref().expect("ground truth labels");
    let dmiou = (b.core.miou - b.reference.miou) * 100.0;
    let dinvr = (b.core.invr - b.reference.invr) * 100.0;
    assert!(dmiou.abs() <= 0.2, "|dmIoU| = {dmiou} points > 0.2");
    assert!(dinvr.abs() <= 0.1, "|dinvR| = {dinvr} points > 0.1");
}

/// The see-through miss by hand: frame 2's ray passes A's Gaussian (Mahalanobis^2 about
/// 1.1, see `ndt_om_miss_by_hand`) and ends 1.1 m beyond it (`pz` < 1e-6), and A gets no
/// point in frame 2: it takes `see_through_miss (1 - pz)` instead of NDT-OM's miss.
#[test]
fn see_through_miss_by_hand() {
    let config = Config {
        see_through_miss: -1.0,
        ..Config::DEFAULT
    };
    let (r, core) = two_frames(config, &six_points(), [0.09, 0.09, 2.15]);
    let want = config.hit as f64 - 1.0;
    check_a_and_behind(&r, &core, want, config.miss);
}

/// The see-through miss spares a confirmed surface's outline: A, at the upper clamp after
/// five frames of points, is passed by a ray through the outer shell of its Gaussian
/// (Mahalanobis^2 8.8 by the formula of `ndt_om_miss_by_hand`, between 2^2 and 4^2) and
/// keeps its clamp. A ray through its middle (Mahalanobis^2 about 1.1) takes it to
/// 3.5 - 3 = 0.5, more than 1 below the clamp: doubted, so the outer-shell ray now counts,
/// 0.5 - 3 clamped to -2.
#[test]
fn see_through_miss_needs_the_middle_of_a_confirmed_surface() {
    let config = Config {
        see_through_miss: -3.0,
        ..Config::DEFAULT
    };
    let (outline, middle) = ([0.18f32, 0.1024, 2.15], [0.09f32, 0.09, 2.15]);
    // The outer-shell ray, by hand: t* = u^T Sinv mu / u^T Sinv u, x = t* u.
    let z = outline.map(|x| x as f64);
    let len = (z[0] * z[0] + z[1] * z[1] + z[2] * z[2]).sqrt();
    let u = z.map(|x| x / len);
    let (mu, inv) = (
        [0.05, 0.05, 1.05],
        [5.0 / 0.0008, 5.0 / 0.0002, 5.0 / 0.0018],
    );
    let a: f64 = (0..3).map(|i| u[i] * inv[i] * u[i]).sum();
    let t = (0..3).map(|i| u[i] * inv[i] * mu[i]).sum::<f64>() / a;
    let m2: f64 = (0..3).map(|i| (t * u[i] - mu[i]).powi(2) * inv[i]).sum();
    assert!(m2 > 8.0 && m2 < 9.5, "Mahalanobis^2 {m2}");
    let mut r = RefMap::new(config, 40);
    let mut core: Box<SmallMap> = sndt_host::mapping::boxed_map(config).unwrap();
    for _ in 0..4 {
        r.integrate(&Isometry3::identity(), &pts(&six_points(), 1))
            .unwrap();
        core.integrate(&Isometry3::identity(), &pts(&six_points(), 1))
            .unwrap();
    }
    let mut run = |frame: Vec<LabeledPoint>, want: f64, what: &str| {
        r.integrate(&Isometry3::identity(), &frame).unwrap();
        core.integrate(&Isometry3::identity(), &frame).unwrap();
        close(r.log_odds(&[0, 0, 10]), want, 1e-5, what);
        close(core_log_odds(&core, [0, 0, 10]), want, 2e-3, what);
    };
    // 5 x 0.85 > 3.5.
    run(
        pts(&six_points(), 1),
        3.5,
        "five frames of points: the clamp",
    );
    run(pts(&[outline], 2), 3.5, "outline ray, confirmed: no miss");
    run(
        pts(&[middle], 2),
        0.5,
        "middle ray: 3.5 - 3 (1 - pz), pz < 1e-6",
    );
    run(
        pts(&[outline], 2),
        -2.0,
        "outline ray, doubted: 0.5 - 3, clamped",
    );
}

/// The core and the f64 reference agree with the see-through miss on, on the dynamic
/// room (everything moves once; small camera, 10 cm).
#[test]
fn core_matches_reference_with_the_see_through_miss_on_the_dynamic_room() {
    use sndt_host::dataset::synthetic::{dynamic, DynamicOptions, SynthOptions, Synthetic};
    let split = Synthetic::new(SynthOptions {
        dynamic: Some(DynamicOptions::default()),
        frames: dynamic::DEFAULT_FRAMES,
        camera: sndt_tests::SMALL_CAMERA,
        predictions: false,
        ..SynthOptions::default()
    })
    .unwrap();
    let frames: Vec<_> = split
        .frames()
        .iter()
        .step_by(2)
        .map(|id| split.load(id).unwrap())
        .collect();
    let config = Config {
        see_through_miss: -3.0,
        ..Config::with_cell_size(0.1)
    };
    let r = compare(&frames, &config, &Options::default()).unwrap();
    assert_eq!((r.only_core, r.only_ref, r.count_mismatch), (0, 0, 0));
    let occ = r.occupancy.fraction();
    assert!(occ >= 0.995, "occupancy agreement {occ} < 99.5 %");
}

/// The camera of the hand tests of depth images: 3x3 pixels, fx = fy = 10, principal
/// point at the centre.
const THREE_BY_THREE: Pinhole = Pinhole {
    fx: 10.0,
    fy: 10.0,
    cx: 1.5,
    cy: 1.5,
    width: 3,
    height: 3,
};

/// The defaults with the see-through miss at -3.
fn see_through_config() -> Config {
    Config {
        see_through_miss: -3.0,
        ..Config::DEFAULT
    }
}

/// A planar depth image of [`THREE_BY_THREE`] (row by row) with top-1 labels.
fn planar_image<'a>(depth: &'a [f32], labels: &'a [u8]) -> sndt_core::DepthImage<'a> {
    use sndt_core::{Depth, DepthImage, DepthKind, LabelImage};
    DepthImage {
        camera: THREE_BY_THREE,
        depth: Depth::Metres(depth),
        kind: DepthKind::Planar,
        labels: LabelImage::Top1(labels),
        stride: 1,
    }
}

/// The sensor-frame points of [`planar_image`]'s pixels, row by row.
fn image_points(depth: &[f32]) -> Vec<[f32; 3]> {
    let pixels = (0..9u32).zip(depth);
    let point = |(i, &d): (u32, &f32)| {
        let ray = THREE_BY_THREE.ray(i % 3, i / 3);
        sndt_core::depth_point(ray, d, sndt_core::DepthKind::Planar).unwrap()
    };
    pixels.map(point).collect()
}

/// The see-through test of a depth image, by hand. A, at the upper clamp after five
/// frames of `six_points`, gets no points in a 3x3 image of a wall (fx = fy = 10, principal
/// point at the centre, planar depth `d` everywhere). The only ray through A runs along
/// its corner edge x = y = 0 (Mahalanobis^2 78 by the formula of
/// `see_through_miss_needs_the_middle_of_a_confirmed_surface`): no miss by the ray rule.
/// A's mean (0.05, 0.05, 1.05) projects to u = v = 10 * 0.05 / 1.05 + 1.5 = 1.98, the
/// centre pixel. At d = 2.15 that pixel saw beyond the mean by more than a cell plus twice
/// the range noise there (1.05 + 0.1 + 2 (0.02 + 0.0025 * 1.05^2) = 1.196): A takes the
/// full see-through miss, 3.5 - 3. At d = 1.18 (beyond by more than a cell, less than
/// the noise margin) A keeps its clamp; so it does with the same points and no image.
#[test]
fn depth_image_sees_through_the_mean_by_hand() {
    let config = see_through_config();
    for (d, with_image, want) in [(2.15f32, true, 0.5), (1.18, true, 3.5), (2.15, false, 3.5)] {
        let mut r = RefMap::new(config, 40);
        let mut core: Box<SmallMap> = sndt_host::mapping::boxed_map(config).unwrap();
        for _ in 0..5 {
            r.integrate(&Isometry3::identity(), &pts(&six_points(), 1))
                .unwrap();
            core.integrate(&Isometry3::identity(), &pts(&six_points(), 1))
                .unwrap();
        }
        close(r.log_odds(&[0, 0, 10]), 3.5, 1e-9, "the clamp");
        let (depth, labels) = ([d; 9], [2u8; 9]);
        let image = planar_image(&depth, &labels);
        let points = image_points(&depth);
        let pose = Isometry3::identity();
        if with_image {
            r.integrate_seen(&pose, &pts(&points, 2), Some(&image))
                .unwrap();
            core.integrate_depth(&pose, &image).unwrap();
        } else {
            r.integrate(&pose, &pts(&points, 2)).unwrap();
            core.integrate(&pose, &pts(&points, 2)).unwrap();
        }
        let what = format!("depth {d}, image {with_image}");
        close(r.log_odds(&[0, 0, 10]), want, 1e-5, &what);
        close(core_log_odds(&core, [0, 0, 10]), want, 2e-3, &what);
    }
}

/// The see-through miss spreads to a hidden neighbour of the same class, by hand. A is
/// as in `depth_image_sees_through_the_mean_by_hand` (the centre pixel sees beyond its
/// mean: 3.5 to 0.5); its neighbour B = A + (0.1, 0, 0). Both are at the upper clamp
/// after five frames of `six_points` (B's shifted by 0.1 in x). B's mean (0.15, 0.05,
/// 1.05) projects to u = 10 * 0.15 / 1.05 + 1.5 = 2.93, v = 1.98: pixel (2, 1). No ray of
/// the frame passes through B's Gaussian and no point lands in B. With column 2 of the
/// image at 0.5 m, that pixel is nearer than B's mean by more than a cell plus twice the
/// noise (1.05 less 0.146): something hides B, and B, of A's class, takes a quarter of
/// A's miss, 3.5 to 2.75. B of another class, or B shown (column 2 at 1.12 m, within the
/// margin of its mean), keeps its clamp.
#[test]
fn see_through_spreads_to_a_hidden_neighbour_of_the_same_class_by_hand() {
    let config = see_through_config();
    let b_points: Vec<[f32; 3]> = six_points()
        .iter()
        .map(|p| [p[0] + 0.1, p[1], p[2]])
        .collect();
    for (column_2, b_class, want_b) in [(0.5f32, 2u8, 2.75), (0.5, 3, 3.5), (1.12, 2, 3.5)] {
        let mut r = RefMap::new(config, 40);
        let mut core: Box<SmallMap> = sndt_host::mapping::boxed_map(config).unwrap();
        let mut both = pts(&six_points(), 2);
        both.extend(pts(&b_points, b_class));
        for _ in 0..5 {
            r.integrate(&Isometry3::identity(), &both).unwrap();
            core.integrate(&Isometry3::identity(), &both).unwrap();
        }
        close(r.log_odds(&[1, 0, 10]), 3.5, 1e-9, "B at the clamp");
        let depth: Vec<f32> = (0..9)
            .map(|i| if i % 3 == 2 { column_2 } else { 2.15 })
            .collect();
        let labels = [2u8; 9];
        let image = planar_image(&depth, &labels);
        let points = image_points(&depth);
        let pose = Isometry3::identity();
        r.integrate_seen(&pose, &pts(&points, 2), Some(&image))
            .unwrap();
        core.integrate_depth(&pose, &image).unwrap();
        let what = format!("column 2 at {column_2}, B of class {b_class}");
        close(r.log_odds(&[0, 0, 10]), 0.5, 1e-5, &what);
        close(core_log_odds(&core, [0, 0, 10]), 0.5, 2e-3, &what);
        close(r.log_odds(&[1, 0, 10]), want_b, 1e-5, &what);
        close(core_log_odds(&core, [1, 0, 10]), want_b, 2e-3, &what);
    }
}
