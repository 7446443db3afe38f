//! Integration of arbitrary frames: depth images up to 64x64 with any f32 or u16 depth
//! (NaN, inf, negative), any intrinsics, stride and labels, any pose (non-unit
//! quaternions, huge translations) and any config, into a map small enough to evict, and
//! the same as labelled points.
//!
//! Nothing may panic; an error must leave the map's snapshot byte for byte as it was; a
//! frame that is taken must account for every point, keep the map's invariants and a
//! snapshot that round-trips.
#![no_main]

use libfuzzer_sys::arbitrary::{Result, Unstructured};
use libfuzzer_sys::fuzz_target;
use sndt_core::{
    Config, Depth, DepthImage, DepthKind, Isometry3, LabelImage, LabeledPoint, Labels, Map,
    MissModel, Pinhole, Point3, Quaternion, Translation3, UnitQuaternion,
};
use sndt_fuzz::{assert_accounted, assert_map_invariants, assert_round_trip, snapshot};

/// What an integration returns.
type Outcome = core::result::Result<sndt_core::FrameReport, sndt_core::Error>;

/// Small enough that a 64x64 frame evicts and drops updates.
type Small = Map<32, 8, 8>;

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let _ = run(&mut u);
});

fn run(u: &mut Unstructured) -> Result<()> {
    let config = config(u)?;
    let mut map: Box<Small> = Box::new(Map::new(Config::DEFAULT));
    let reset = map.reset(config);
    assert_eq!(
        reset.is_ok(),
        config.validate().is_ok(),
        "reset disagrees with validate"
    );
    // Up to three frames, so later ones meet voxels, decay and eviction of earlier ones.
    for _ in 0..3 {
        if u.is_empty() {
            break;
        }
        let pose = pose(u)?;
        if u.ratio(1, 4)? {
            points_frame(&mut map, &pose, u)?;
        } else {
            depth_frame(&mut map, &pose, u)?;
        }
    }
    Ok(())
}

/// An f32 that is usually in `lo..=hi` (so configs validate and images hit the map), and
/// otherwise any bit pattern.
fn float(u: &mut Unstructured, lo: f32, hi: f32) -> Result<f32> {
    if u.ratio(1, 8)? {
        return Ok(f32::from_bits(u.arbitrary()?));
    }
    let t = u.arbitrary::<u16>()? as f32 / u16::MAX as f32;
    Ok(lo + t * (hi - lo))
}

fn config(u: &mut Unstructured) -> Result<Config> {
    let mut c = Config::DEFAULT;
    if u.ratio(1, 4)? {
        return Ok(c);
    }
    c.cell_size = float(u, 0.001, 2.0)?;
    c.quant_bits = u.int_in_range(0..=7)?;
    c.n_min = u.int_in_range(0..=8)?;
    c.n_max = c.n_min + u.int_in_range(0..=70000)?;
    c.eigen_ratio = float(u, 1e-9, 0.5)?;
    c.hit = float(u, 0.0, 30.0)?;
    c.miss = float(u, -30.0, 0.0)?;
    c.clamp_min = float(u, -30.0, 0.0)?;
    c.clamp_max = float(u, 0.0, 30.0)?;
    c.lambda = float(u, 0.0, 0.49)?;
    // Multiples of 1/1024 in [-31, 0]: a little out of range too.
    c.see_through_miss = -(u.int_in_range(0..=31 * 1024)? as f32) / 1024.0;
    c.noise_base = float(u, 1e-6, 1.0)?;
    c.noise_quadratic = float(u, 0.0, 1.0)?;
    c.max_range = float(u, 0.001, 50.0)?;
    c.top_k = u.int_in_range(0..=4)?;
    c.min_score = u.arbitrary()?;
    c.votes_per_frame = u.int_in_range(0..=65)?;
    c.miss_model = if u.arbitrary()? {
        MissModel::Constant
    } else {
        MissModel::NdtOm
    };
    c.render_radius = float(u, 0.1, 10.0)?;
    Ok(c)
}

/// Translation within a few metres or anything; a rotation from a scaled axis, or four
/// raw quaternion components that need not have unit length.
fn pose(u: &mut Unstructured) -> Result<Isometry3<f32>> {
    let t = Translation3::new(
        float(u, -4.0, 4.0)?,
        float(u, -4.0, 4.0)?,
        float(u, -4.0, 4.0)?,
    );
    let q = [
        float(u, -1.0, 1.0)?,
        float(u, -1.0, 1.0)?,
        float(u, -1.0, 1.0)?,
        float(u, -1.0, 1.0)?,
    ];
    let rotation = if u.arbitrary()? {
        UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]))
    } else {
        UnitQuaternion::new_unchecked(Quaternion::new(q[0], q[1], q[2], q[3]))
    };
    Ok(Isometry3::from_parts(t, rotation))
}

fn labels(u: &mut Unstructured) -> Result<Labels> {
    Ok(Labels {
        classes: [u.int_in_range(0..=9)?, u.arbitrary()?, u.arbitrary()?],
        scores: u.arbitrary()?,
        len: u.int_in_range(0..=4)?,
    })
}

/// Runs one integration and checks its outcome: an error changes nothing, a report
/// accounts for `samples` points.
fn checked(map: &mut Small, samples: Option<u64>, f: impl FnOnce(&mut Small) -> Outcome) {
    let before = snapshot(map);
    match f(map) {
        Err(e) => assert_eq!(snapshot(map), before, "{e:?} changed the map"),
        Ok(r) => {
            if let Some(n) = samples {
                assert_accounted(&r, n);
            }
            assert_map_invariants(map);
            assert_round_trip(map);
        }
    }
}

fn depth_frame(map: &mut Small, pose: &Isometry3<f32>, u: &mut Unstructured) -> Result<()> {
    let (w, h) = (u.int_in_range(0..=64u32)?, u.int_in_range(0..=64u32)?);
    let camera = Pinhole {
        fx: float(u, 1.0, 80.0)?,
        fy: float(u, 1.0, 80.0)?,
        cx: float(u, 0.0, w as f32)?,
        cy: float(u, 0.0, h as f32)?,
        width: w,
        height: h,
    };
    // Mostly the right number of pixels; sometimes one more or less.
    let n = ((w * h) as usize)
        .saturating_add_signed(u.int_in_range(-1..=1)? * u.ratio(1, 16)? as isize);
    let metres = u.arbitrary()?;
    let depth_f: Vec<f32> = (0..n).map(|_| float(u, 0.0, 6.0)).collect::<Result<_>>()?;
    let depth_mm: Vec<u16> = (0..n).map(|_| u.arbitrary()).collect::<Result<_>>()?;
    let top1: Vec<u8> = (0..n)
        .map(|_| u.int_in_range(0..=9))
        .collect::<Result<_>>()?;
    let topk: Vec<Labels> = match u.ratio(1, 4)? {
        true => (0..n).map(|_| labels(u)).collect::<Result<_>>()?,
        false => Vec::new(),
    };
    let image = DepthImage {
        camera,
        depth: if metres {
            Depth::Metres(&depth_f)
        } else {
            Depth::Millimetres(&depth_mm)
        },
        kind: if u.arbitrary()? {
            DepthKind::Range
        } else {
            DepthKind::Planar
        },
        labels: match u.int_in_range(0..=2)? {
            0 => LabelImage::None,
            1 => LabelImage::Top1(&top1),
            _ => LabelImage::TopK(&topk),
        },
        stride: u.int_in_range(0..=5)?,
    };
    let s = image.stride.max(1) as u64;
    let samples = (w as u64).div_ceil(s) * (h as u64).div_ceil(s);
    checked(map, Some(samples), |m| m.integrate_depth(pose, &image));
    Ok(())
}

fn points_frame(map: &mut Small, pose: &Isometry3<f32>, u: &mut Unstructured) -> Result<()> {
    let n = u.int_in_range(0..=200usize)?;
    let mut points = Vec::with_capacity(n);
    for _ in 0..n {
        let p = Point3::new(
            float(u, -5.0, 5.0)?,
            float(u, -5.0, 5.0)?,
            float(u, -5.0, 5.0)?,
        );
        points.push(LabeledPoint::new(p, labels(u)?));
    }
    checked(map, Some(n as u64), |m| m.integrate(pose, &points));
    Ok(())
}
