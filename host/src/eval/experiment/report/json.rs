//! Every number of an experiment as JSON (`results.json`): what the tables round, the
//! per-class IoU and each trajectory's update time.

use crate::eval::experiment::results::Experiment;

impl Experiment {
    /// Every run's metrics, per-class IoU and timing as JSON.
    ///
    /// ```
    /// use sndt_host::eval::experiment::Experiment;
    /// let json = Experiment::default().to_json();
    /// assert_eq!(json["frames"], 0);
    /// assert!(json["runs"].as_array().unwrap().is_empty());
    /// ```
    pub fn to_json(&self) -> serde_json::Value {
        let runs: Vec<serde_json::Value> = self
            .runs
            .iter()
            .map(|(k, r)| {
                let m = r.metrics();
                let iou = m.iou_by_name();
                serde_json::json!({
                    "labels": k.labels.tag(),
                    "method": k.method.name(),
                    "kernel_m": k.kernel_mm as f64 / 1000.0,
                    "cell_m": k.cell_mm as f64 / 1000.0,
                    "miou": m.miou, "invr": m.invr, "mpacc": m.mpacc,
                    "per_class_iou": iou,
                    "mean_update_ms": r.mean_ms(),
                    "surface_voxels": r.surface.voxels,
                    "surface_free": r.surface.free,
                    "surface_unknown": r.surface.unknown,
                    "trajectories": r.trajectories.iter().map(|(n, f, s)| serde_json::json!({
                        "name": n, "frames": f, "update_s": s })).collect::<Vec<_>>(),
                })
            })
            .collect();
        let inputs: serde_json::Map<String, serde_json::Value> = self
            .inputs
            .iter()
            .map(|(l, c)| {
                let m = c.metrics();
                (
                    l.tag().to_string(),
                    serde_json::json!({"miou": m.miou, "mpacc": m.mpacc}),
                )
            })
            .collect();
        serde_json::json!({ "frames": self.frames, "inputs": inputs, "runs": runs })
    }
}
