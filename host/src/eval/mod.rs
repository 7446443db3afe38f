//! Evaluation: the paper's metrics, the evaluation loop, the paper's experiment, and the
//! comparison of the core with the f64 reference.
//!
//! - [`metrics`]: the 42x42 confusion matrix and mIoU / mPAcc / invR, as the authors'
//!   evaluator computes them;
//! - [`evaluate`]: one map per trajectory, back-projected into every frame;
//! - [`experiment`]: S-NDT, S-BKI and OS-BKI per cell size and kernel (Tables I and II),
//!   with its finished runs kept on disk to resume it ([`experiment::store`]);
//! - [`compare`]: the core against the f64 reference, with stated tolerances;
//! - [`dynamics`]: how fast a map clears and relabels what moved, against OctoMap.

pub mod compare;
pub mod dynamics;
pub mod evaluate;
pub mod experiment;
pub mod label_stats;
pub mod metrics;
