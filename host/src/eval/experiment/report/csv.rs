//! The CSV tables: Table I and Table II with more digits than the Markdown ones, for
//! scripts and spreadsheets.

use crate::eval::experiment::results::Experiment;
use std::fmt::Write as _;

impl Experiment {
    /// Table I as CSV: labels, method, kernel_m, cell_m, miou, invr, mpacc (%).
    ///
    /// ```
    /// use sndt_host::eval::experiment::Experiment;
    /// let csv = Experiment::default().table1_csv();
    /// assert_eq!(csv, "labels,method,kernel_m,cell_m,miou,invr,mpacc\n");
    /// ```
    pub fn table1_csv(&self) -> String {
        let mut s = String::from("labels,method,kernel_m,cell_m,miou,invr,mpacc\n");
        for (k, run) in &self.runs {
            let m = run.metrics();
            let _ = writeln!(
                s,
                "{},{},{},{},{:.4},{:.4},{:.4}",
                k.labels.tag(),
                k.method.name(),
                k.kernel_mm as f64 / 1000.0,
                k.cell_mm as f64 / 1000.0,
                m.miou * 100.0,
                m.invr * 100.0,
                m.mpacc * 100.0
            );
        }
        s
    }

    /// Table II as CSV: method, kernel_m, cell_m, mean_hz, slowest_hz, fastest_hz, mean_ms.
    pub fn table2_csv(&self) -> String {
        let mut s = String::from("method,kernel_m,cell_m,mean_hz,slowest_hz,fastest_hz,mean_ms\n");
        for ((m, k, c), r) in self.timing() {
            let (lo, hi) = r.slowest_fastest_hz();
            let _ = writeln!(
                s,
                "{},{},{},{:.4},{:.4},{:.4},{:.3}",
                m.name(),
                k as f64 / 1000.0,
                c as f64 / 1000.0,
                r.mean_hz(),
                lo,
                hi,
                r.mean_ms()
            );
        }
        s
    }
}
