//! Two robots: two walks of the same place mapped separately and merged (`Map::merge`, what
//! `sndt merge` does with their saved maps), against one map of both walks in sequence.
//! Prints both maps' sizes, how their voxels differ (class, mean, occupancy) and the
//! paper's metrics of each, back-projected into every frame of both walks.
//!
//! `cargo run --release -p sndt-host --example two_robots -- [A B [CELL [gt|pred [STRIDE]]]]`
//! (default: `synthetic:floor:1 synthetic:floor:2 0.1 gt 1`).

use sndt_core::{Config, Occupancy};
use sndt_host::dataset::{open_spec, Dataset, LabelSource};
use sndt_host::eval::evaluate::gt_depth;
use sndt_host::eval::metrics::Confusion;
use sndt_host::mapping::{backproject, boxed_map, integrate_frame, HostMap};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, default: &str| args.get(i).cloned().unwrap_or(default.into());
    let (a, b) = (arg(0, "synthetic:floor:1"), arg(1, "synthetic:floor:2"));
    let cell: f32 = arg(2, "0.1").parse()?;
    let labels = match arg(3, "gt").as_str() {
        "pred" => LabelSource::Pred,
        _ => LabelSource::Gt,
    };
    let stride: u32 = arg(4, "1").parse()?;
    let config = Config::with_cell_size(cell);
    let walks: Vec<Box<dyn Dataset>> = vec![
        open_spec(&a, &Default::default())?,
        open_spec(&b, &Default::default())?,
    ];
    let mut separate: Vec<Box<HostMap>> = Vec::new();
    let mut joint: Box<HostMap> = boxed_map(config).map_err(anyhow::Error::msg)?;
    for walk in &walks {
        let mut own: Box<HostMap> = boxed_map(config).map_err(anyhow::Error::msg)?;
        for id in walk.frames() {
            let frame = walk.load(id)?;
            integrate_frame(&mut *own, &frame, labels, stride)?;
            integrate_frame(&mut *joint, &frame, labels, stride)?;
        }
        println!(
            "{}: {} frames, {} voxels, {} blocks",
            walk.describe(),
            walk.frames().len(),
            own.len(),
            own.block_count()
        );
        separate.push(own);
    }
    let mut merged = separate.remove(0);
    merged.merge(&*separate[0]).map_err(anyhow::Error::msg)?;
    for (name, m) in [("merged", &merged), ("one map of both walks", &joint)] {
        let s = m.stats();
        println!(
            "{name}: {} voxels, {} blocks, {} frames, {} voxels evicted",
            m.len(),
            m.block_count(),
            s.frames,
            s.voxels_evicted
        );
    }
    compare_voxels(&merged, &joint);
    for (name, m) in [("merged", &merged), ("one map of both walks", &joint)] {
        score(name, m, &walks, labels, cell)?;
    }
    Ok(())
}

/// Voxel by voxel: the same keys? the same class, mean, occupancy?
fn compare_voxels(merged: &HostMap, joint: &HostMap) {
    let (mut shared, mut class_differs, mut occ_differs, mut shift) =
        (0usize, 0usize, 0usize, 0f64);
    for v in joint.voxels() {
        let Some(g) = merged.gaussian(&v.key) else {
            continue;
        };
        shared += 1;
        if merged.class(&v.key).map(|c| c.0) != v.class().map(|c| c.0) {
            class_differs += 1;
        }
        if merged.occupancy(&v.key) != v.occupancy() {
            occ_differs += 1;
        }
        shift += (g.mean - v.gaussian.mean).norm() as f64;
    }
    let occupied = |m: &HostMap| {
        m.voxels()
            .filter(|v| v.occupancy() == Occupancy::Occupied)
            .count()
    };
    println!(
        "voxels in both: {shared} (only merged: {}, only joint: {}); of those, class differs \
         {class_differs} ({:.2} %), occupancy state differs {occ_differs} ({:.2} %), mean shift \
         {:.2} mm on average; occupied surface voxels: merged {}, joint {}",
        merged.len() - shared,
        joint.len() - shared,
        100.0 * class_differs as f64 / shared.max(1) as f64,
        100.0 * occ_differs as f64 / shared.max(1) as f64,
        1000.0 * shift / shared.max(1) as f64,
        occupied(merged),
        occupied(joint)
    );
}

/// The paper's metrics of `m` back-projected into every frame of both walks.
fn score(
    name: &str,
    m: &HostMap,
    walks: &[Box<dyn Dataset>],
    labels: LabelSource,
    cell: f32,
) -> anyhow::Result<()> {
    let mut confusion = Confusion::default();
    for walk in walks {
        for id in walk.frames() {
            let frame = walk.load(id)?;
            if let Some(gt) = &frame.labels {
                confusion.add_frame(gt, &backproject(m, &frame)?, &gt_depth(&frame));
            }
        }
    }
    let x = confusion.metrics();
    println!(
        "{name}: mIoU {:.2} %, invR {:.2} %, mPAcc {:.2} % (both walks' frames, {labels:?} labels, cell {cell} m)",
        100.0 * x.miou,
        100.0 * x.invr,
        100.0 * x.mpacc
    );
    Ok(())
}
