//! The SVG charts of one label source: per-class IoU like the paper's Fig. 5, and map
//! update rate against mIoU.

use crate::eval::experiment::key::{mm_to_cm, Method, RunKey, Segmentation};
use crate::eval::experiment::results::Experiment;
use crate::output::chart::{iou_bars, rate_vs_miou};
use anyhow::Result;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

impl Experiment {
    /// Writes `iou_<labels>.svg` and `rate_vs_miou_<labels>.svg` into `out`; returns them
    /// in that order.
    pub(super) fn write_charts(&self, labels: Segmentation, out: &Path) -> Result<[PathBuf; 2]> {
        let iou = out.join(format!("iou_{}.svg", labels.tag()));
        let series = self.fig5_series(labels);
        let refs: Vec<(&str, &[Option<f64>; 41])> =
            series.iter().map(|(n, v)| (n.as_str(), v)).collect();
        iou_bars(&iou, &format!("Per-class IoU, {}", labels.title()), &refs)?;
        let rate = out.join(format!("rate_vs_miou_{}.svg", labels.tag()));
        let timing = self.timing();
        let mut points: BTreeMap<String, Vec<(f64, f64, String)>> = BTreeMap::new();
        for (k, run) in self.runs.iter().filter(|(k, _)| k.labels == labels) {
            let hz = timing[&(k.method, k.kernel_mm, k.cell_mm)].mean_hz();
            let series = match k.method {
                Method::Sndt => k.row_name(),
                m => format!("{} ({}cm kernel)", m.name(), mm_to_cm(k.kernel_mm)),
            };
            points.entry(series).or_default().push((
                hz,
                run.metrics().miou * 100.0,
                format!("{}cm", mm_to_cm(k.cell_mm)),
            ));
        }
        let series: Vec<_> = points.into_iter().collect();
        let title = format!("Map update rate vs mIoU, {}", labels.title());
        rate_vs_miou(&rate, &title, &series)?;
        Ok([iou, rate])
    }

    /// The Fig. 5 series: S-BKI and OS-BKI at 10 cm with a 30 cm kernel, S-NDT at 10 and
    /// 15 cm (nearest available cell sizes and kernel otherwise).
    fn fig5_series(&self, labels: Segmentation) -> Vec<(String, [Option<f64>; 41])> {
        let cells = self.cells();
        let nearest = |v: &[u32], want: u32| v.iter().cloned().min_by_key(|&c| c.abs_diff(want));
        let mut kernels: Vec<u32> = self
            .runs
            .keys()
            .map(|k| k.kernel_mm)
            .filter(|&k| k > 0)
            .collect();
        kernels.sort();
        kernels.dedup();
        let mut out = Vec::new();
        let (Some(c10), Some(c15)) = (nearest(&cells, 100), nearest(&cells, 150)) else {
            return out;
        };
        let k30 = nearest(&kernels, 300).unwrap_or(0);
        let wanted = [
            (Method::Sbki, k30, c10),
            (Method::Osbki, k30, c10),
            (Method::Sndt, 0, c10),
            (Method::Sndt, 0, c15),
        ];
        for (method, kernel_mm, cell_mm) in wanted {
            let key = RunKey {
                labels,
                method,
                kernel_mm,
                cell_mm,
            };
            if let Some(run) = self.runs.get(&key) {
                let name = format!("{} @ {}cm", key.row_name(), mm_to_cm(cell_mm));
                if !out.iter().any(|(n, _)| n == &name) {
                    out.push((name, run.metrics().iou));
                }
            }
        }
        out
    }
}
