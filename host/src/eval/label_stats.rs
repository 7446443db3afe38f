//! What the labels of a set of frames look like before any map is built: how many
//! ground-truth pixels each class covers, and how good the raw top-1 predictions are.
//! `sndt synth` prints both for the split it writes, the synthetic model's calibration
//! reads the second.

use crate::dataset::frame::Frame;
use crate::eval::metrics::Confusion;

/// Class histogram and raw-prediction confusion over frames.
///
/// ```
/// use sndt_host::dataset::Dataset;
/// use sndt_host::dataset::synthetic::{SynthOptions, Synthetic};
/// use sndt_host::eval::label_stats::LabelStats;
/// let camera = sndt_core::Pinhole { fx: 40.0, fy: 40.0, cx: 32.0, cy: 24.0, width: 64, height: 48 };
/// let split = Synthetic::new(SynthOptions { scenes: 1, frames: 2, camera, ..Default::default() }).unwrap();
/// let (mut a, mut b) = (LabelStats::default(), LabelStats::default());
/// a.add(&split.load(&split.frames()[0]).unwrap());
/// b.add(&split.load(&split.frames()[1]).unwrap());
/// a.merge(&b);
/// assert_eq!(a.class_pixels.iter().sum::<u64>(), 2 * 64 * 48);
/// assert!(a.prediction.metrics().miou > 0.0);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct LabelStats {
    /// Ground-truth pixels per class (index 0 = void).
    pub class_pixels: [u64; 41],
    /// Raw top-1 prediction against the ground truth, counted by [`Confusion::add_frame`]
    /// as in the evaluation (`docs/EVALUATION.md`).
    pub prediction: Confusion,
}

impl Default for LabelStats {
    fn default() -> Self {
        LabelStats {
            class_pixels: [0; 41],
            prediction: Confusion::default(),
        }
    }
}

impl LabelStats {
    /// Adds a frame's ground-truth classes and, if it has predictions, their top-1 against
    /// the ground truth. A frame without ground truth adds nothing.
    pub fn add(&mut self, frame: &Frame) {
        let Some(labels) = &frame.labels else {
            return;
        };
        for &c in labels {
            self.class_pixels[c as usize] += 1;
        }
        if let Some(p) = &frame.predictions {
            self.prediction
                .add_frame(labels, &p.top1(), &frame.planar_depth_image());
        }
    }

    /// Adds the counts of `other` (frames counted on another thread).
    pub fn merge(&mut self, other: &LabelStats) {
        for (total, n) in self.class_pixels.iter_mut().zip(other.class_pixels) {
            *total += n;
        }
        self.prediction.merge(&other.prediction);
    }
}
