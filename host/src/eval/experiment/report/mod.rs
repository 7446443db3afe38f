//! The experiment's reports, one file per format: Markdown tables (`markdown.rs`, also
//! what `sndt experiment` prints), CSV tables (`csv.rs`), every number as JSON
//! (`json.rs`) and the SVG charts (`charts.rs`). Each is a method of [`Experiment`], so
//! that the results can be reported without running anything again.

mod charts;
mod csv;
mod json;
mod markdown;

use crate::eval::experiment::results::Experiment;
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

impl Experiment {
    /// Writes table1.md/.csv, table2.md/.csv, holes.md, results.json, `iou_<labels>.svg`
    /// (Fig. 5: per-class IoU of S-BKI and OS-BKI at 10 cm with a 30 cm kernel against
    /// S-NDT at 10 and 15 cm, or the nearest configurations run) and
    /// `rate_vs_miou_<labels>.svg`, each atomically; returns the files written, in that
    /// order.
    ///
    /// ```
    /// let dir = std::env::temp_dir().join(format!("sndt-report-{}", std::process::id()));
    /// let written = sndt_host::eval::experiment::Experiment::default().write(&dir).unwrap();
    /// assert_eq!(written.len(), 6); // no label source run: no charts
    /// std::fs::remove_dir_all(&dir).unwrap();
    /// ```
    pub fn write(&self, out: &Path) -> Result<Vec<PathBuf>> {
        std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
        let mut written = Vec::new();
        let mut put = |name: &str, text: &str| -> Result<()> {
            let p = out.join(name);
            crate::atomic::write_bytes(&p, text)?;
            written.push(p);
            Ok(())
        };
        put("table1.md", &self.table1_markdown())?;
        put("table1.csv", &self.table1_csv())?;
        put("table2.md", &self.table2_markdown())?;
        put("table2.csv", &self.table2_csv())?;
        put("holes.md", &self.holes_markdown())?;
        put(
            "results.json",
            &serde_json::to_string_pretty(&self.to_json())?,
        )?;
        for labels in self.inputs.keys() {
            written.extend(self.write_charts(*labels, out)?);
        }
        Ok(written)
    }
}
