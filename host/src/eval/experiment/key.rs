//! The names of an experiment's runs: the method, the segmentation fed to the map, and
//! the key that makes one configuration's results findable and sortable in the paper's
//! order. Every other file of the experiment speaks of runs in these terms, so they sit in
//! a leaf that imports nothing of the experiment.

use crate::dataset::frame::LabelSource;
use anyhow::{bail, Result};

/// A mapping method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Method {
    /// Semantic occupancy NDT (sndt-core).
    Sndt,
    /// Semantic Bayesian kernel inference (Gan et al. 2020).
    Sbki,
    /// The paper's optimised S-BKI.
    Osbki,
}

impl Method {
    /// The paper's name of the method, as tables, charts and stored runs spell it.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Method::Sndt => "S-NDT",
            Method::Sbki => "S-BKI",
            Method::Osbki => "OS-BKI",
        }
    }
}

/// One configuration: label source, method, cell size and kernel length (millimetres, so
/// that keys compare exactly; kernel 0 for S-NDT).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct RunKey {
    /// Ground truth or predicted labels.
    pub labels: Segmentation,
    /// The method.
    pub method: Method,
    /// Kernel length in mm (0 for S-NDT).
    pub kernel_mm: u32,
    /// Cell size in mm.
    pub cell_mm: u32,
}

impl RunKey {
    /// `S-NDT` or `S-BKI (30cm)`, as the paper's row names.
    ///
    /// ```
    /// use sndt_host::eval::experiment::{Method, RunKey, Segmentation};
    /// let key = |method, kernel_mm| RunKey { labels: Segmentation::Gt, method, kernel_mm, cell_mm: 100 };
    /// assert_eq!(key(Method::Sndt, 0).row_name(), "S-NDT");
    /// assert_eq!(key(Method::Osbki, 250).row_name(), "OS-BKI (25cm)");
    /// ```
    pub fn row_name(&self) -> String {
        match self.method {
            Method::Sndt => self.method.name().to_string(),
            m => format!("{} ({}cm)", m.name(), mm_to_cm(self.kernel_mm)),
        }
    }
}

/// The segmentation a map is fed, as an ordered key: the experiment's two label sources.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Segmentation {
    /// Ground-truth segmentation.
    Gt,
    /// Predicted segmentation (top 1).
    Pred,
}

impl Segmentation {
    /// The segmentation of a label source; only ground truth and the prediction's top 1
    /// are the paper's, so any other source is refused before anything runs.
    pub(crate) fn from_source(s: LabelSource) -> Result<Segmentation> {
        match s {
            LabelSource::Gt => Ok(Segmentation::Gt),
            LabelSource::Pred => Ok(Segmentation::Pred),
            other => bail!("experiment labels must be gt or pred, not {other:?}"),
        }
    }

    /// The label source that feeds the maps.
    pub(crate) fn source(self) -> LabelSource {
        match self {
            Segmentation::Gt => LabelSource::Gt,
            Segmentation::Pred => LabelSource::Pred,
        }
    }

    /// The paper's heading of the segmentation (tables and charts).
    pub(crate) fn title(self) -> &'static str {
        match self {
            Segmentation::Gt => "GT segmentation",
            Segmentation::Pred => "Predicted segmentation",
        }
    }

    /// The short tag of file names, CSV and JSON.
    pub(crate) fn tag(self) -> &'static str {
        match self {
            Segmentation::Gt => "gt",
            Segmentation::Pred => "pred",
        }
    }
}

/// Metres as whole millimetres: keys and file names compare exactly, which `f32` metres
/// (0.1 + 0.2) would not.
pub(crate) fn mm(x: f32) -> u32 {
    (x * 1000.0).round() as u32
}

/// Millimetres as centimetres without a trailing `.0` (`10`, `2.5`), as the paper writes them.
pub(crate) fn mm_to_cm(x: u32) -> String {
    let cm = x as f64 / 10.0;
    if cm.fract() == 0.0 {
        format!("{cm:.0}")
    } else {
        format!("{cm}")
    }
}
