//! The paper's baselines: S-BKI (semantic Bayesian kernel inference) and its optimised
//! variant OS-BKI, one count map read out two ways.

pub mod bki;
pub mod label_grid;

pub use bki::{BkiConfig, BkiMap, LabelGrid, Readout};
