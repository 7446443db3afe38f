//! The paper's evaluation protocol, as the authors' evaluate.py computes it: one 42x42
//! confusion matrix over all frames, void ignored, invalid predictions counted against
//! recall, mIoU / mPAcc / invR (`docs/EVALUATION.md`).

/// Side of the confusion matrix: rows and columns 0 void, 1..=40 classes, 41 invalid.
pub const CONFUSION_SIDE: usize = 42;
/// Column of invalid predictions: every rendered label above 40, i.e.
/// [`sndt_core::INVALID_LABEL`] (nothing hit), is counted here.
pub const INVALID_COLUMN: usize = 41;
/// Pixels whose ground-truth depth is this far or farther are not counted (metres).
pub const MAX_GT_DEPTH: f32 = 20.0;

/// `cm[gt][pred]` pixel counts.
#[derive(Clone, Debug, PartialEq)]
pub struct Confusion {
    /// Row = ground truth (0 void, 1..=40), column = prediction (0..=40, 41 invalid).
    pub cm: Box<[[u64; CONFUSION_SIDE]; CONFUSION_SIDE]>,
}

impl Default for Confusion {
    fn default() -> Self {
        Confusion {
            cm: Box::new([[0; CONFUSION_SIDE]; CONFUSION_SIDE]),
        }
    }
}

/// Summary metrics, as fractions (multiply by 100 for the paper's percentages).
#[derive(Clone, Debug, PartialEq)]
pub struct Metrics {
    /// Mean IoU over classes present in the ground truth.
    pub miou: f64,
    /// Mean pixel accuracy (recall) over classes present in the ground truth.
    pub mpacc: f64,
    /// Invalid predictions over all non-void ground-truth pixels.
    pub invr: f64,
    /// IoU per class 1..=40 (`None` when the class is absent from the ground truth).
    pub iou: [Option<f64>; 41],
}

impl Metrics {
    /// Per-class IoU keyed by NYU40 class name (classes present in the ground truth).
    ///
    /// ```
    /// let mut c = sndt_host::eval::metrics::Confusion::default();
    /// c.add_frame(&[1, 1], &[1, 2], &[1.0, 1.0]);
    /// let j = c.metrics().iou_by_name();
    /// assert_eq!(j["wall"], serde_json::json!(0.5));
    /// assert!(!j.contains_key("floor"));
    /// ```
    pub fn iou_by_name(&self) -> serde_json::Map<String, serde_json::Value> {
        self.iou
            .iter()
            .enumerate()
            .filter_map(|(c, v)| {
                v.map(|v| {
                    (
                        crate::dataset::classes::NYU40[c].to_string(),
                        serde_json::json!(v),
                    )
                })
            })
            .collect()
    }
}

impl Confusion {
    /// Adds one frame: ground-truth labels (0 void, 1..=40; anything else is treated as
    /// void), predictions (0..=40, anything above 40 counts as invalid) and ground-truth
    /// depth in metres (pixels at or beyond 20 m are skipped; 0 is kept).
    ///
    /// ```
    /// let mut c = sndt_host::eval::metrics::Confusion::default();
    /// c.add_frame(&[1, 1, 2, 0], &[1, 255, 2, 5], &[1.0, 1.0, 25.0, 1.0]);
    /// assert_eq!(c.cm[1][1], 1);
    /// assert_eq!(c.cm[1][41], 1);
    /// assert_eq!(c.cm[2][2], 0); // beyond 20 m
    /// assert_eq!(c.cm[0][5], 1);
    /// ```
    pub fn add_frame(&mut self, gt: &[u8], pred: &[u8], gt_depth: &[f32]) {
        for ((&g, &p), &d) in gt.iter().zip(pred).zip(gt_depth) {
            if d >= MAX_GT_DEPTH || d.is_nan() {
                continue;
            }
            let g = if g as usize > 40 { 0 } else { g as usize };
            let p = (p as usize).min(INVALID_COLUMN);
            self.cm[g][p] += 1;
        }
    }

    /// Adds another matrix.
    pub fn merge(&mut self, other: &Confusion) {
        for (a, b) in self.cm.iter_mut().zip(other.cm.iter()) {
            for (x, y) in a.iter_mut().zip(b) {
                *x += y;
            }
        }
    }

    /// mIoU, mPAcc, invR and per-class IoU.
    pub fn metrics(&self) -> Metrics {
        let cm = &self.cm;
        let mut iou = [None; 41];
        let (mut sum_iou, mut sum_acc, mut classes) = (0.0, 0.0, 0u32);
        let (mut inv, mut gt_all) = (0u64, 0u64);
        for c in 1..=40 {
            let tp = cm[c][c];
            let gt: u64 = cm[c].iter().sum();
            let pred: u64 = (1..=40).map(|g| cm[g][c]).sum();
            inv += cm[c][INVALID_COLUMN];
            gt_all += gt;
            if gt == 0 {
                continue;
            }
            let v = tp as f64 / (gt + pred - tp) as f64;
            iou[c] = Some(v);
            sum_iou += v;
            sum_acc += tp as f64 / gt as f64;
            classes += 1;
        }
        let n = classes.max(1) as f64;
        Metrics {
            miou: sum_iou / n,
            mpacc: sum_acc / n,
            invr: if gt_all == 0 {
                0.0
            } else {
                inv as f64 / gt_all as f64
            },
            iou,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) {
        assert!((a - b).abs() < 1e-12, "{a} != {b}");
    }

    #[test]
    fn perfect_prediction() {
        let mut c = Confusion::default();
        c.add_frame(&[1, 2, 2, 3], &[1, 2, 2, 3], &[1.0; 4]);
        let m = c.metrics();
        close(m.miou, 1.0);
        close(m.mpacc, 1.0);
        close(m.invr, 0.0);
        assert_eq!(m.iou[4], None);
    }

    #[test]
    fn hand_computed_two_classes_with_invalid_and_void() {
        // GT class 1: 4 pixels -> predicted 1, 1, 2, invalid.
        // GT class 2: 2 pixels -> predicted 2, void(0).
        // GT void: 3 pixels -> predicted 1, 2, invalid (must not count anywhere).
        let gt = [1, 1, 1, 1, 2, 2, 0, 0, 0];
        let pred = [1, 1, 2, 255, 2, 0, 1, 2, 255];
        let mut c = Confusion::default();
        c.add_frame(&gt, &pred, &[0.0; 9]); // depth 0 is kept
        let m = c.metrics();
        // class 1: TP 2, GT 4, P 2 -> IoU 2/4; acc 2/4
        // class 2: TP 1, GT 2, P 2 (one from GT 1) -> IoU 1/3; acc 1/2
        close(m.iou[1].unwrap(), 0.5);
        close(m.iou[2].unwrap(), 1.0 / 3.0);
        close(m.miou, (0.5 + 1.0 / 3.0) / 2.0);
        close(m.mpacc, (0.5 + 0.5) / 2.0);
        // invalid: 1 of 6 non-void GT pixels
        close(m.invr, 1.0 / 6.0);
    }

    #[test]
    fn absent_class_predictions_lower_others_but_are_not_averaged() {
        // Class 5 never occurs in GT but is predicted: it lowers class 1's IoU only.
        let mut c = Confusion::default();
        c.add_frame(&[1, 1], &[1, 5], &[1.0, 1.0]);
        let m = c.metrics();
        assert_eq!(m.iou[5], None);
        close(m.miou, 0.5);
        close(m.mpacc, 0.5);
    }

    #[test]
    fn far_pixels_and_out_of_range_labels() {
        let mut c = Confusion::default();
        c.add_frame(&[1, 1, 77], &[1, 2, 1], &[19.99, 20.0, 1.0]);
        assert_eq!(c.cm[1][1], 1);
        assert_eq!(c.cm[1][2], 0); // 20 m is excluded
        assert_eq!(c.cm[0][1], 1); // unknown GT label counted as void
        let mut d = Confusion::default();
        d.merge(&c);
        d.merge(&c);
        assert_eq!(d.cm[1][1], 2);
    }
}
