//! Placeholder: being written (issue 3).

use crate::dataset::{Dataset, Frame, FrameId, OpenOptions};
use anyhow::{bail, Result};
use std::path::Path;

/// Placeholder reader.
pub struct Hypersim {
    frames: Vec<FrameId>,
}

impl Hypersim {
    /// Opens the dataset at `root`.
    pub fn open(root: &Path, _options: &OpenOptions) -> Result<Hypersim> {
        bail!("{}: reader not implemented yet", root.display())
    }
}

impl Dataset for Hypersim {
    fn describe(&self) -> String {
        String::new()
    }
    fn frames(&self) -> &[FrameId] {
        &self.frames
    }
    fn load(&self, id: &FrameId) -> Result<Frame> {
        bail!("{id}: reader not implemented yet")
    }
}
