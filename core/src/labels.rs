//! Semantic labels of a point: top-k class ids with scores.

use nalgebra::Point3;

/// Most labels a point can carry (top-k with k <= 3).
pub const MAX_TOP_K: usize = 3;

/// Top-k labels of one point: NYU40-style class ids `1..=CLASSES` (0 = void, which adds
/// geometry but no vote) with optional scores (0..=255, 255 when unknown).
///
/// A plain `Copy` struct of two arrays and a length rather than a `heapless::Vec`: points
/// are copied by value in bulk (slices of [`LabeledPoint`]) and the layout stays 7 fixed
/// bytes; the vote step, which builds a list, uses `heapless::Vec` for its voting classes.
///
/// ```
/// use sndt_core::Labels;
/// let l = Labels::top_k(&[(5, 200), (7, 40)]);
/// assert_eq!(l.len, 2);
/// assert_eq!(Labels::top1(3).classes[0], 3);
/// ```
///
/// `repr(C)`, 7 bytes of `u8`: any bytes are a `Labels` (the C API passes arrays of them).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(C)]
pub struct Labels {
    /// Class ids, best first.
    pub classes: [u8; MAX_TOP_K],
    /// Scores, best first.
    pub scores: [u8; MAX_TOP_K],
    /// How many entries are used (0..=3).
    pub len: u8,
}

impl Labels {
    /// No label: the point adds geometry only.
    pub const NONE: Labels = Labels {
        classes: [0; MAX_TOP_K],
        scores: [0; MAX_TOP_K],
        len: 0,
    };

    /// One label with full score.
    pub const fn top1(class: u8) -> Labels {
        Labels {
            classes: [class, 0, 0],
            scores: [255, 0, 0],
            len: 1,
        }
    }

    /// Up to three `(class, score)` pairs, best first; extra pairs are ignored.
    pub fn top_k(pairs: &[(u8, u8)]) -> Labels {
        let mut l = Labels::NONE;
        for (i, &(c, s)) in pairs.iter().take(MAX_TOP_K).enumerate() {
            l.classes[i] = c;
            l.scores[i] = s;
            l.len = i as u8 + 1;
        }
        l
    }

    /// Whether a map with `classes` classes can use these labels: at most [`MAX_TOP_K`]
    /// entries, none above the class count (0, void, is allowed).
    #[inline]
    pub(crate) fn fits(&self, classes: usize) -> bool {
        let n = self.len as usize;
        n <= MAX_TOP_K && !self.classes[..n].iter().any(|&c| c as usize > classes)
    }
}

/// A point in the sensor frame (metres) with its labels.
///
/// ```
/// use sndt_core::{LabeledPoint, Labels, Point3};
/// let p = LabeledPoint::new(Point3::new(0.0, 0.0, 1.5), Labels::top1(2));
/// assert_eq!(p.labels.classes[0], 2);
/// ```
///
/// `repr(C)`: the position's three `f32` then the 7 bytes of labels (the C API passes
/// arrays of them).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct LabeledPoint {
    /// Position in the sensor frame, metres.
    pub position: Point3<f32>,
    /// Segmentation labels.
    pub labels: Labels,
}

impl LabeledPoint {
    /// A labelled point.
    pub const fn new(position: Point3<f32>, labels: Labels) -> Self {
        LabeledPoint { position, labels }
    }
}
