//! The dataset-opening options `map` and `experiment` share (`--split`, `--paper-fy`,
//! `--predictions`).

use crate::dataset::source::OpenOptions;
use std::path::PathBuf;

/// How to open a dataset directory (shared by `map` and `experiment`).
#[derive(clap::Args, Clone, Debug)]
pub struct OpenArgs {
    /// Split of the prepared layout.
    #[arg(long, default_value = "test")]
    pub split: String,
    /// Use the authors' v0.3.1 fy = 927.06 (prepared layout without intrinsics).
    #[arg(long)]
    pub paper_fy: bool,
    /// Directory of ESANet `.npy` predictions.
    #[arg(long)]
    pub predictions: Option<PathBuf>,
}

impl OpenArgs {
    /// The options the dataset readers take.
    pub fn options(&self) -> OpenOptions {
        OpenOptions {
            split: Some(self.split.clone()),
            paper_fy: self.paper_fy,
            predictions: self.predictions.clone(),
        }
    }
}
