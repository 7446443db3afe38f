//! The Markdown tables: Table I (mIoU / invR / mPAcc), Table II (update rates) and the
//! holes table, written to files and printed by `sndt experiment`.

use crate::eval::experiment::key::{mm_to_cm, Method, RunKey, Segmentation};
use crate::eval::experiment::results::Experiment;
use crate::eval::metrics::Metrics;
use std::fmt::Write as _;

/// The header of a table: the leading `columns`, then `per_cell` columns per cell size
/// (`title(cell in cm)` gives them), and the separator, numbers right-aligned.
fn header(
    columns: &[&str],
    cells: &[u32],
    per_cell: usize,
    title: impl Fn(&str) -> String,
) -> String {
    let mut s = format!("| {} |", columns.join(" | "));
    for c in cells {
        s += &title(&mm_to_cm(*c));
    }
    s += "\n|";
    s += &"---|".repeat(columns.len());
    s += &"---:|".repeat(per_cell * cells.len());
    s += "\n";
    s
}

impl Experiment {
    /// Table I as Markdown: per label source, one row per method (and kernel), per cell
    /// size mIoU / invR / mPAcc in %, the best mIoU and mPAcc per cell size in bold.
    ///
    /// ```
    /// use sndt_host::eval::experiment::Experiment;
    /// assert_eq!(Experiment::default().table1_markdown(), "| labels | method |\n|---|---|\n");
    /// ```
    pub fn table1_markdown(&self) -> String {
        let cells = self.cells();
        let mut s = header(&["labels", "method"], &cells, 3, |c| {
            format!(" mIoU {c}cm | invR {c}cm | mPAcc {c}cm |")
        });
        for (labels, method, kernel) in self.rows() {
            let key = |cell_mm| RunKey {
                labels,
                method,
                kernel_mm: kernel,
                cell_mm,
            };
            let _ = write!(s, "| {} | {} |", labels.title(), key(0).row_name());
            for &cell in &cells {
                match self.runs.get(&key(cell)) {
                    Some(run) => s += &self.table1_cell(labels, cell, &run.metrics()),
                    None => s += " | | |",
                }
            }
            s += "\n";
        }
        s
    }

    /// One run's mIoU / invR / mPAcc cells of Table I, each of mIoU and mPAcc in bold
    /// if it is the best of its label source and cell size.
    fn table1_cell(&self, labels: Segmentation, cell: u32, m: &Metrics) -> String {
        let best = |f: fn(&Metrics) -> f64| {
            self.runs
                .iter()
                .filter(|(k, _)| k.labels == labels && k.cell_mm == cell)
                .map(|(_, r)| f(&r.metrics()))
                .fold(f64::NEG_INFINITY, f64::max)
        };
        let fmt = |v: f64, b: f64| {
            if (v - b).abs() < 1e-12 {
                format!("**{:.2}**", v * 100.0)
            } else {
                format!("{:.2}", v * 100.0)
            }
        };
        format!(
            " {} | {:.2} | {} |",
            fmt(m.miou, best(|m| m.miou)),
            m.invr * 100.0,
            fmt(m.mpacc, best(|m| m.mpacc))
        )
    }

    /// The share of surface voxels (those that held a hit) S-BKI and OS-BKI read as free,
    /// in %, per cell size: the holes of the paper's Fig. 2, which the back-projection
    /// only shows as invalid pixels where nothing occupied lies behind them.
    pub fn holes_markdown(&self) -> String {
        let cells = self.cells();
        let mut s = header(&["labels", "method"], &cells, 1, |c| format!(" {c}cm |"));
        for (labels, method, kernel) in self.rows() {
            if method == Method::Sndt {
                continue;
            }
            let key = |cell_mm| RunKey {
                labels,
                method,
                kernel_mm: kernel,
                cell_mm,
            };
            let _ = write!(s, "| {} | {} |", labels.title(), key(0).row_name());
            for &cell in &cells {
                match self.runs.get(&key(cell)) {
                    Some(r) => {
                        let v = r.surface.free as f64 / r.surface.voxels.max(1) as f64;
                        let _ = write!(s, " {:.2} |", v * 100.0);
                    }
                    None => s += " |",
                }
            }
            s += "\n";
        }
        s
    }

    /// Table II as Markdown: mean map update rate (Hz) per method and cell size, with the
    /// slowest / fastest trajectory's rate, single thread.
    pub fn table2_markdown(&self) -> String {
        let cells = self.cells();
        let timing = self.timing();
        let mut s = header(&["method"], &cells, 1, |c| {
            format!(" {c}cm: Hz (slowest / fastest) |")
        });
        let mut rows: Vec<(Method, u32)> = timing.keys().map(|k| (k.0, k.1)).collect();
        // The paper lists S-BKI, OS-BKI, then S-NDT.
        rows.sort_by_key(|&(m, k)| ((m as u8 + 2) % 3, k));
        rows.dedup();
        for (method, kernel) in rows {
            let key = RunKey {
                labels: Segmentation::Gt,
                method,
                kernel_mm: kernel,
                cell_mm: 0,
            };
            let _ = write!(s, "| {} |", key.row_name());
            for &cell in &cells {
                match timing.get(&(method, kernel, cell)) {
                    Some(r) => {
                        let (lo, hi) = r.slowest_fastest_hz();
                        let _ = write!(s, " {:.2} ({:.2} / {:.2}) |", r.mean_hz(), lo, hi);
                    }
                    None => s += " |",
                }
            }
            s += "\n";
        }
        s
    }
}
