//! `sndt export`: a map's Gaussians as a PLY (points or ellipsoids) for
//! MeshLab/CloudCompare, from a saved snapshot or from mapping a dataset's first trajectory.

use crate::cli::labels::LabelArg;
use crate::dataset::frame::LabelSource;
use crate::dataset::open::open_spec;
use crate::dataset::source::OpenOptions;
use crate::eval::evaluate::load_snapshot;
use crate::output::export::{ellipsoids, write_ellipsoids, write_points};
use crate::output::progress::progress;
use crate::semantic_map::{integrate_frame, HostMap};
use anyhow::Result;
use sndt_core::Config;
use std::path::{Path, PathBuf};

/// Arguments of `sndt export`.
#[derive(clap::Args, Clone, Debug)]
pub struct ExportArgs {
    /// A map snapshot (`.sndt`, from `sndt map --save-maps`), or a dataset
    /// (directory or `synthetic[:SCENES:FRAMES]`) whose first trajectory is mapped.
    pub input: String,
    /// Output PLY file.
    #[arg(long)]
    pub ply: PathBuf,
    /// Ellipsoid meshes at this many standard deviations instead of points at the means.
    #[arg(long)]
    pub ellipsoids: Option<f32>,
    /// Voxel edge in metres (when mapping a dataset).
    #[arg(long, default_value_t = 0.10)]
    pub cell: f32,
    /// Labels fed to the map (when mapping a dataset).
    #[arg(long, value_enum, default_value = "gt")]
    pub labels: LabelArg,
    /// Only voxels with at least this many points.
    #[arg(long, default_value_t = 3)]
    pub min_points: u32,
}

/// Runs `sndt export`: loads or builds the map, writes its Gaussians and prints what it
/// wrote.
pub fn run(a: &ExportArgs) -> Result<()> {
    let path = Path::new(&a.input);
    let map = if path.is_file() {
        load_snapshot(path)?
    } else {
        map_first_trajectory(&a.input, a.cell, a.labels.into())?
    };
    let es = ellipsoids(map.as_ref(), a.min_points);
    match a.ellipsoids {
        Some(s) => write_ellipsoids(&a.ply, &es, s)?,
        None => write_points(&a.ply, &es)?,
    }
    println!(
        "wrote {}: {} occupied Gaussians of {} voxels ({})",
        a.ply.display(),
        es.len(),
        map.len(),
        a.ellipsoids
            .map_or("points at the means".to_string(), |s| format!(
                "ellipsoids at {s} sigma"
            ))
    );
    Ok(())
}

/// Maps the first trajectory of the dataset `spec` at `cell` with `labels`.
fn map_first_trajectory(spec: &str, cell: f32, labels: LabelSource) -> Result<Box<HostMap>> {
    let dataset = open_spec(spec, &OpenOptions::default())?;
    let trajectories = dataset.trajectories();
    let (name, ids) = trajectories
        .first()
        .ok_or_else(|| anyhow::anyhow!("{spec}: no frames"))?;
    let mut map: Box<HostMap> = crate::semantic_map::boxed_map(Config::with_cell_size(cell))
        .map_err(|e| anyhow::anyhow!("config: {e:?}"))?;
    let bar = progress(ids.len() as u64, "map");
    for id in ids {
        integrate_frame(map.as_mut(), &dataset.load(id)?, labels, 1)?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    println!("mapped {name}: {} frames", ids.len());
    Ok(map)
}
