//! A model of a segmentation network's output (ESANet-like top-3 labels with scores),
//! made from the ground truth so that its errors look like a real network's:
//!
//! - **object-level confusion** between similar classes (a dresser read as a cabinet, a
//!   picture as a whiteboard), for a whole object or a part of it, more often for the
//!   classes the paper names as hard, and stable over a stretch of frames as a network's
//!   mistakes are for similar views;
//! - **small objects absorbed** by what surrounds them (books on a shelf read as shelf);
//! - **boundary errors**: the label image is warped by a smooth random displacement
//!   field, so edges wobble by a few pixels;
//! - **spurious blobs** of a plausible wrong class;
//! - no void: the network always answers with one of the 40 classes;
//! - top-3 with scores: confident where right, less so where wrong, with the true class
//!   often second when the first is wrong.
//!
//! Calibrated (see [`ModelParams::DEFAULT`]) so that the raw top-1 prediction scores
//! 38-45 % mIoU against the ground truth on the default synthetic split with the paper's
//! evaluation (the paper's ESANet: 41.17 %).

use super::scenes::class::*;
use crate::dataset::frame::TopK;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::HashMap;

/// Knobs of the error model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelParams {
    /// Probability that an object of an easy / medium / hard class is confused.
    pub confuse: [f32; 3],
    /// Of confused objects, the fraction confused as a whole (the rest: a part of it).
    pub whole: f32,
    /// Probability that a small object of a hard class is absorbed by its surroundings.
    pub absorb: f32,
    /// Objects smaller than this many pixels count as small.
    pub small_pixels: u32,
    /// Amplitude of the boundary displacement field, pixels.
    pub warp: f32,
    /// Spacing of the displacement field's control grid, pixels.
    pub warp_grid: u32,
    /// Mean number of spurious blobs per 1024x768 frame.
    pub blobs: f32,
    /// Frames over which an object's confusion stays the same.
    pub period: u32,
}

impl ModelParams {
    /// The calibrated default.
    pub const DEFAULT: ModelParams = ModelParams {
        confuse: [0.15, 0.4, 0.65],
        whole: 0.6,
        absorb: 0.6,
        small_pixels: 6000,
        warp: 10.0,
        warp_grid: 40,
        blobs: 8.0,
        period: 12,
    };
}

/// How hard a class is for the network: 0 easy, 1 medium, 2 hard.
fn difficulty(c: u8) -> usize {
    match c {
        WALL | FLOOR | CEILING | BED | REFRIGERATOR | TOILET | BATHTUB => 0,
        CABINET | CHAIR | SOFA | TABLE | DOOR | WINDOW | BOOKSHELF | COUNTER | DESK | SINK
        | TELEVISION | CURTAIN | WHITEBOARD | MIRROR | LAMP | PERSON | BLINDS | SHOWER_CURTAIN => 1,
        _ => 2,
    }
}

/// Classes a network confuses `c` with.
fn similar(c: u8) -> &'static [u8] {
    match c {
        WALL => &[OTHER_STRUCTURE, DOOR, CEILING],
        FLOOR => &[FLOOR_MAT],
        CABINET => &[DRESSER, NIGHT_STAND, COUNTER, OTHER_FURNITURE, SHELVES],
        BED => &[SOFA, PILLOW],
        CHAIR => &[SOFA, OTHER_FURNITURE],
        SOFA => &[CHAIR, BED, PILLOW],
        TABLE => &[DESK, COUNTER, OTHER_FURNITURE],
        DOOR => &[WALL, CABINET],
        WINDOW => &[BLINDS, CURTAIN, PICTURE],
        BOOKSHELF => &[SHELVES, CABINET, BOOKS],
        PICTURE => &[WHITEBOARD, MIRROR, TELEVISION, WINDOW],
        COUNTER => &[TABLE, CABINET, DESK],
        BLINDS => &[WINDOW, CURTAIN],
        DESK => &[TABLE, COUNTER],
        SHELVES => &[BOOKSHELF, CABINET, OTHER_FURNITURE],
        CURTAIN => &[BLINDS, SHOWER_CURTAIN, WINDOW],
        DRESSER => &[CABINET, NIGHT_STAND],
        PILLOW => &[BED, SOFA, CLOTHES],
        MIRROR => &[PICTURE, WINDOW],
        FLOOR_MAT => &[FLOOR],
        CLOTHES => &[PILLOW, BAG, TOWEL],
        CEILING => &[WALL],
        BOOKS => &[OTHER_PROP, BOX, SHELVES],
        REFRIGERATOR => &[CABINET],
        TELEVISION => &[PICTURE, OTHER_PROP],
        PAPER => &[BOOKS, OTHER_PROP],
        TOWEL => &[CLOTHES, CURTAIN],
        SHOWER_CURTAIN => &[CURTAIN],
        BOX => &[OTHER_PROP, BOOKS, CABINET],
        WHITEBOARD => &[PICTURE, WALL],
        PERSON => &[CLOTHES, OTHER_PROP],
        NIGHT_STAND => &[CABINET, DRESSER, TABLE],
        TOILET => &[SINK, BATHTUB],
        SINK => &[COUNTER, TOILET],
        LAMP => &[OTHER_PROP],
        BATHTUB => &[SINK, TOILET],
        BAG => &[BOX, OTHER_PROP, CLOTHES],
        OTHER_STRUCTURE => &[WALL, OTHER_FURNITURE],
        OTHER_FURNITURE => &[CABINET, TABLE, CHAIR],
        OTHER_PROP => &[BOX, BOOKS, LAMP],
        _ => &[OTHER_PROP, WALL, CEILING, LAMP],
    }
}

fn pick(rng: &mut ChaCha8Rng, xs: &[u8]) -> u8 {
    xs[rng.random_range(0..xs.len())]
}

/// Where one object (an instance with one label) lies in the frame.
#[derive(Clone, Copy)]
struct Stats {
    count: u32,
    bbox: [u32; 4],
    sum: [f64; 2],
}

/// What the network makes of one object.
#[derive(Clone, Copy)]
enum Fate {
    Keep,
    /// Every pixel of the object becomes this class.
    Whole(u8),
    /// Pixels on one side of a line through the centroid become this class.
    Part(u8, [f32; 2], [f32; 2]),
}

/// The model's answer for one frame, from its ground-truth labels and object instances.
///
/// `key` makes the per-object decisions (with `frame / params.period`); `frame_seed`
/// drives everything that changes every frame. Deterministic in its inputs.
///
/// ```
/// use sndt_host::dataset::synthetic::predict::{predict, ModelParams};
/// let (w, h) = (64u32, 48u32);
/// let labels = vec![1u8; (w * h) as usize];
/// let instances = vec![3u16; (w * h) as usize];
/// let p = predict(&labels, &instances, w, h, 7, 0, 1, &ModelParams::DEFAULT);
/// assert_eq!(p.classes.len(), (w * h) as usize);
/// assert!(p.classes.iter().all(|c| (1..=40).contains(&c[0])));
/// assert!(p.scores.iter().all(|s| s[0] >= s[1] && s[1] >= s[2] && s[0] + s[1] + s[2] <= 1.0));
/// ```
#[allow(clippy::too_many_arguments)]
pub fn predict(
    labels: &[u8],
    instances: &[u16],
    width: u32,
    height: u32,
    key: u64,
    frame: u32,
    frame_seed: u64,
    params: &ModelParams,
) -> TopK {
    let (w, h) = (width as usize, height as usize);
    // Pixel counts and blob sizes are tuned for 1024x768 and scale with the image.
    let scale = ((w * h) as f32 / (1024.0 * 768.0)).max(1e-3);
    let objects = objects_in_view(labels, instances, w);
    let epoch = frame / params.period.max(1);
    let fates: HashMap<(u16, u8), Fate> = objects
        .iter()
        .map(|(&(inst, l), s)| {
            let mut rng = object_rng(key, inst, epoch, l);
            let fate = object_fate(&mut rng, l, s, labels, w, h, scale, params);
            ((inst, l), fate)
        })
        .collect();
    let mut relabelled = apply_fates(labels, instances, w, &fates);
    // One generator for everything that changes every frame, drawn in this order:
    // blobs, then the displacement field, then the scores.
    let mut frame_rng = ChaCha8Rng::seed_from_u64(frame_seed);
    add_spurious_blobs(&mut relabelled, w, h, scale, params, &mut frame_rng);
    let pred = warp_boundaries(&relabelled, w, h, params, &mut frame_rng);
    top3(&pred, labels, &mut frame_rng)
}

/// Each object in view (instance and label) with its pixel count, bounding box and
/// centroid sums.
fn objects_in_view(labels: &[u8], instances: &[u16], w: usize) -> HashMap<(u16, u8), Stats> {
    let mut stats: HashMap<(u16, u8), Stats> = HashMap::new();
    for (i, (&l, &inst)) in labels.iter().zip(instances).enumerate() {
        let (x, y) = ((i % w) as u32, (i / w) as u32);
        let s = stats.entry((inst, l)).or_insert(Stats {
            count: 0,
            bbox: [x, y, x, y],
            sum: [0.0; 2],
        });
        s.count += 1;
        s.bbox = [
            s.bbox[0].min(x),
            s.bbox[1].min(y),
            s.bbox[2].max(x),
            s.bbox[3].max(y),
        ];
        s.sum[0] += x as f64;
        s.sum[1] += y as f64;
    }
    stats
}

/// The generator of one object's decisions: seeded by the object and the epoch only, so
/// the object keeps its fate for `period` frames whatever else is in view.
fn object_rng(key: u64, inst: u16, epoch: u32, label: u8) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(
        key ^ (inst as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ (epoch as u64).wrapping_mul(0xD1B5_4A32_D192_ED69)
            ^ label as u64,
    )
}

/// Decides what the network makes of an object with label `l`: a plausible class for void,
/// small hard objects absorbed by their surroundings, similar-class confusion of the whole
/// object or of one side of it, or nothing.
#[allow(clippy::too_many_arguments)]
fn object_fate(
    rng: &mut ChaCha8Rng,
    l: u8,
    s: &Stats,
    labels: &[u8],
    w: usize,
    h: usize,
    scale: f32,
    params: &ModelParams,
) -> Fate {
    if l == VOID {
        // The network never says void: unlabelled things get a plausible class.
        Fate::Whole(pick(rng, similar(VOID)))
    } else if difficulty(l) == 2
        && (s.count as f32) < params.small_pixels as f32 * scale
        && rng.random::<f32>() < params.absorb
    {
        Fate::Whole(surrounding(labels, w, h, &s.bbox, l).unwrap_or(l))
    } else if rng.random::<f32>() < params.confuse[difficulty(l)] {
        let to = pick(rng, similar(l));
        if rng.random::<f32>() < params.whole {
            Fate::Whole(to)
        } else {
            let c = [
                (s.sum[0] / s.count as f64) as f32,
                (s.sum[1] / s.count as f64) as f32,
            ];
            let a = rng.random_range(0.0..std::f32::consts::TAU);
            Fate::Part(to, c, [a.cos(), a.sin()])
        }
    } else {
        Fate::Keep
    }
}

/// The label image with every object's fate applied; whatever is still void becomes
/// "other prop".
fn apply_fates(
    labels: &[u8],
    instances: &[u16],
    w: usize,
    fates: &HashMap<(u16, u8), Fate>,
) -> Vec<u8> {
    let mut relabelled = vec![0u8; labels.len()];
    for i in 0..labels.len() {
        let l = labels[i];
        relabelled[i] = match fates.get(&(instances[i], l)).copied().unwrap_or(Fate::Keep) {
            Fate::Keep => l,
            Fate::Whole(c) => c,
            Fate::Part(c, o, d) => {
                let (x, y) = ((i % w) as f32 - o[0], (i / w) as f32 - o[1]);
                if x * d[0] + y * d[1] > 0.0 {
                    c
                } else {
                    l
                }
            }
        };
        if relabelled[i] == VOID {
            relabelled[i] = OTHER_PROP;
        }
    }
    relabelled
}

/// Paints elliptic blobs of a class similar to what lies under them. Done before the warp,
/// which makes their outlines irregular.
fn add_spurious_blobs(
    relabelled: &mut [u8],
    w: usize,
    h: usize,
    scale: f32,
    params: &ModelParams,
    rng: &mut ChaCha8Rng,
) {
    let blobs = poisson(rng, params.blobs);
    for _ in 0..blobs {
        let (cx, cy) = (rng.random_range(0..w) as f32, rng.random_range(0..h) as f32);
        let (rx, ry) = (
            rng.random_range(10.0..60.0) * scale.sqrt(),
            rng.random_range(10.0..60.0) * scale.sqrt(),
        );
        let under = relabelled[cy as usize * w + cx as usize];
        let class = pick(rng, similar(under));
        let (x0, x1) = ((cx - rx).max(0.0) as usize, ((cx + rx) as usize).min(w - 1));
        let (y0, y1) = ((cy - ry).max(0.0) as usize, ((cy + ry) as usize).min(h - 1));
        for y in y0..=y1 {
            for x in x0..=x1 {
                let (dx, dy) = ((x as f32 - cx) / rx, (y as f32 - cy) / ry);
                if dx * dx + dy * dy <= 1.0 {
                    relabelled[y * w + x] = class;
                }
            }
        }
    }
}

/// Boundary errors: every pixel takes the label a smooth random displacement away
/// (bilinear in a coarse grid of random offsets), so edges wobble by a few pixels.
fn warp_boundaries(
    relabelled: &[u8],
    w: usize,
    h: usize,
    params: &ModelParams,
    rng: &mut ChaCha8Rng,
) -> Vec<u8> {
    let g = params.warp_grid.max(2) as usize;
    let (gw, gh) = (w / g + 2, h / g + 2);
    let field: Vec<[f32; 2]> = (0..gw * gh)
        .map(|_| {
            [
                rng.random_range(-1.0f32..1.0) * params.warp,
                rng.random_range(-1.0f32..1.0) * params.warp,
            ]
        })
        .collect();
    let mut pred = vec![0u8; w * h];
    for y in 0..h {
        let fy = y as f32 / g as f32;
        let (y0, ty) = (fy as usize, fy.fract());
        for x in 0..w {
            let fx = x as f32 / g as f32;
            let (x0, tx) = (fx as usize, fx.fract());
            let at = |xx: usize, yy: usize| field[yy * gw + xx];
            let d: [f32; 2] = std::array::from_fn(|k| {
                let top = at(x0, y0)[k] * (1.0 - tx) + at(x0 + 1, y0)[k] * tx;
                let bot = at(x0, y0 + 1)[k] * (1.0 - tx) + at(x0 + 1, y0 + 1)[k] * tx;
                top * (1.0 - ty) + bot * ty
            });
            let sx = (x as f32 + d[0]).round().clamp(0.0, (w - 1) as f32) as usize;
            let sy = (y as f32 + d[1]).round().clamp(0.0, (h - 1) as f32) as usize;
            pred[y * w + x] = relabelled[sy * w + sx];
        }
    }
    pred
}

/// Top-3 classes and scores for every pixel whose top-1 is `pred`.
fn top3(pred: &[u8], labels: &[u8], rng: &mut ChaCha8Rng) -> TopK {
    let mut out = TopK {
        classes: Vec::with_capacity(pred.len()),
        scores: Vec::with_capacity(pred.len()),
    };
    for (&c1, &truth) in pred.iter().zip(labels) {
        let (classes, scores) = top3_at(c1, truth, rng);
        out.classes.push(classes);
        out.scores.push(scores);
    }
    out
}

/// One pixel's top-3: confident where right, less so where wrong, with the true class
/// second half of the time when the first is wrong; three distinct classes, scores sorted
/// and summing to at most 1.
fn top3_at(c1: u8, truth: u8, rng: &mut ChaCha8Rng) -> ([u8; 3], [f32; 3]) {
    let right = c1 == truth;
    let s1 = if right {
        rng.random_range(0.55f32..0.98)
    } else {
        rng.random_range(0.3f32..0.75)
    };
    let alt = similar(c1);
    let c2 = if !right && truth != VOID && rng.random::<f32>() < 0.5 {
        truth
    } else {
        pick(rng, alt)
    };
    let mut c3 = pick(rng, similar(c2));
    if c3 == c1 || c3 == c2 {
        c3 = if c1 != OTHER_PROP && c2 != OTHER_PROP {
            OTHER_PROP
        } else {
            WALL
        };
    }
    let c2 = if c2 == c1 {
        if c1 != WALL {
            WALL
        } else {
            OTHER_PROP
        }
    } else {
        c2
    };
    if c3 == c2 || c3 == c1 {
        c3 = CEILING;
    }
    let rest = 1.0 - s1;
    let s2 = rng.random_range(0.4f32..0.8) * rest.min(s1);
    let s3 = rng.random_range(0.1f32..0.9) * (rest - s2).min(s2);
    ([c1, c2, c3], [s1, s2, s3])
}

/// The most common label just outside a bounding box (other than `own`).
fn surrounding(labels: &[u8], w: usize, h: usize, bbox: &[u32; 4], own: u8) -> Option<u8> {
    let pad = 3i64;
    let (x0, y0) = (bbox[0] as i64 - pad, bbox[1] as i64 - pad);
    let (x1, y1) = (bbox[2] as i64 + pad, bbox[3] as i64 + pad);
    let mut counts = [0u32; 41];
    let mut add = |x: i64, y: i64| {
        if x >= 0 && y >= 0 && (x as usize) < w && (y as usize) < h {
            let l = labels[y as usize * w + x as usize];
            if l != own && l != VOID {
                counts[l as usize] += 1;
            }
        }
    };
    for x in x0..=x1 {
        add(x, y0);
        add(x, y1);
    }
    for y in y0..=y1 {
        add(x0, y);
        add(x1, y);
    }
    let (best, &n) = counts.iter().enumerate().max_by_key(|&(_, n)| *n)?;
    (n > 0).then_some(best as u8)
}

/// A Poisson-distributed count (Knuth's method; `mean` is small).
fn poisson(rng: &mut ChaCha8Rng, mean: f32) -> u32 {
    let limit = (-mean).exp();
    let (mut k, mut p) = (0u32, 1.0f32);
    loop {
        p *= rng.random::<f32>();
        if p <= limit || k > 1000 {
            return k;
        }
        k += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_class_has_similar_classes_that_differ_from_it() {
        for c in 0..=40u8 {
            let s = similar(c);
            assert!(!s.is_empty());
            assert!(
                s.iter().all(|&x| x != c && (1..=40).contains(&x)),
                "class {c}"
            );
        }
    }

    #[test]
    fn surrounding_finds_the_enclosing_label() {
        // A 10x10 wall image with a 2x2 book in the middle.
        let (w, h) = (10, 10);
        let mut l = vec![WALL; w * h];
        for y in 4..6 {
            for x in 4..6 {
                l[y * w + x] = BOOKS;
            }
        }
        assert_eq!(surrounding(&l, w, h, &[4, 4, 5, 5], BOOKS), Some(WALL));
    }

    #[test]
    fn clean_model_reproduces_the_ground_truth() {
        let p = ModelParams {
            confuse: [0.0; 3],
            absorb: 0.0,
            warp: 0.0,
            blobs: 0.0,
            ..ModelParams::DEFAULT
        };
        let (w, h) = (32u32, 24u32);
        let labels: Vec<u8> = (0..w * h).map(|i| (i % 40 + 1) as u8).collect();
        let inst: Vec<u16> = (0..w * h).map(|i| (i % 40) as u16).collect();
        let out = predict(&labels, &inst, w, h, 1, 0, 2, &p);
        assert_eq!(out.top1(), labels);
    }
}
