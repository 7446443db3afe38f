//! `sndt export`: a map's Gaussians as a PLY (points or ellipsoids) for
//! MeshLab/CloudCompare, its occupancy layer as an OctoMap (`.bt` / `.ot`) for MoveIt,
//! octomap_server and octovis, and / or both as a ROS 2 bag (MCAP: point cloud, ellipsoid
//! markers, OctoMap message) for Foxglove and RViz, from a saved snapshot or from mapping a
//! dataset's first trajectory (then, with `--mcap-interval N`, the bag holds the map as it
//! grows).

use crate::cli::labels::{check_labels, LabelArg};
use crate::cli::open_args::{EveryArgs, OpenArgs, PredictionsArgs};
use crate::cli::parse::check_cell_config;
use crate::dataset::open::open_spec;
use crate::dataset::ros::msgs::Time;
use crate::dataset::source::usable_frames;
use crate::eval::evaluate::load_snapshot;
use crate::mapping::{integrate_frame, HostMap};
use crate::output::export::{ellipsoids, write_ellipsoids, write_points};
use crate::output::octomap::{write_octomap, OctoFormat, OctoMap};
use crate::output::progress::progress;
use crate::output::ros::export::MapBag;
use crate::output::ros::write::frame_time;
use anyhow::Result;
use sndt_core::Config;
use std::path::{Path, PathBuf};

/// Arguments of `sndt export`.
#[derive(clap::Args, Clone, Debug)]
#[command(after_help = "Examples:
  sndt export out/map/maps/synth_00_living_cam_00.sndt --ply out/map.ply --ellipsoids 1
  sndt export out/map/maps/synth_00_living_cam_00.sndt --octomap out/map.bt
  sndt export synthetic:1:20 --cell 0.05 --mcap out/map.mcap --mcap-interval 5")]
pub struct ExportArgs {
    /// A map snapshot (`.sndt`, from `sndt map --save-maps`), or a dataset whose first
    /// trajectory is mapped: a directory (prepared layout or raw Hypersim), a ROS 2 bag (`.mcap` file or rosbag2 folder),
    /// `synthetic[:SCENES:FRAMES]` or `synthetic:floor[:WALK[:FRAMES]]` (rendered on the
    /// fly).
    pub input: String,
    /// Output PLY file.
    #[arg(long, required_unless_present_any = ["mcap", "octomap"])]
    pub ply: Option<PathBuf>,
    /// Output OctoMap of the occupancy layer at the map's cell size, one leaf per known
    /// voxel: `.bt` a binary OcTree (free / occupied), `.ot` a ColorOcTree (log-odds and
    /// class colours).
    #[arg(long, value_name = "FILE")]
    pub octomap: Option<PathBuf>,
    /// Output ROS 2 bag (rosbag2, MCAP): /sndt/map/points (PointCloud2), /sndt/map/gaussians
    /// (MarkerArray), /octomap_binary (octomap_msgs/Octomap), /tf_static (latched). A path
    /// ending in `/` (or an existing directory) is written as a bag folder:
    /// `DIR/<DIR's name>_0.mcap` and `DIR/metadata.yaml`.
    #[arg(long)]
    pub mcap: Option<PathBuf>,
    /// With a dataset and --mcap: also write the map every N frames (of those --every
    /// keeps), so the bag plays back as a growing map (default: only after the last frame).
    #[arg(long, value_name = "N", value_parser = super::parse::at_least_one)]
    pub mcap_interval: Option<usize>,
    /// Ellipsoid meshes at this many standard deviations instead of points at the means.
    #[arg(long, value_parser = super::parse::positive)]
    pub ellipsoids: Option<f32>,
    /// Voxel edge in metres (when mapping a dataset).
    #[arg(long, default_value_t = 0.10, value_parser = super::parse::positive)]
    pub cell: f32,
    /// Labels fed to the map (when mapping a dataset).
    #[arg(long, value_enum, default_value = "gt")]
    pub labels: LabelArg,
    /// Only voxels with at least this many points.
    #[arg(long, default_value_t = 3)]
    pub min_points: u32,
    /// How to open the dataset (when mapping one; `--world-frame` also names the frame a
    /// map bag is attached to).
    #[command(flatten)]
    pub open: OpenArgs,
    /// Where the predicted labels are (when mapping a dataset).
    #[command(flatten)]
    pub predictions: PredictionsArgs,
    /// Which frames to map (when mapping a dataset).
    #[command(flatten)]
    pub every: EveryArgs,
}

/// Runs `sndt export`: loads or builds the map, writes its Gaussians and occupancy and
/// prints what it wrote.
pub fn run(a: &ExportArgs) -> Result<()> {
    let path = Path::new(&a.input);
    let is_snapshot = path.is_file() && path.extension().is_none_or(|e| e != "mcap");
    if path.extension().is_some_and(|e| e == "sndt") && !path.is_file() {
        anyhow::bail!("{}: no such map snapshot file", path.display());
    }
    // Before any work: a wrong extension should not cost a mapping run.
    if let Some(o) = &a.octomap {
        OctoFormat::of(o)?;
    }
    let mut bag = match &a.mcap {
        Some(p) => Some(MapBag::create(p, &a.open.bag.world_frame, Time::default())?),
        None => None,
    };
    let map = if is_snapshot {
        let map = load_snapshot(path)?;
        // A snapshot has no recording time: its one map snapshot goes at 0, with /tf_static.
        if let Some(b) = bag.as_mut() {
            b.write(map.as_ref(), Time::default())?;
        }
        map
    } else {
        map_first_trajectory(a, bag.as_mut())?
    };
    if let (Some(b), Some(p)) = (bag, &a.mcap) {
        let snapshots = b.written;
        b.finish()?;
        println!("wrote {}: {snapshots} map snapshots", p.display());
    }
    if let Some(ply) = &a.ply {
        write_ply(ply, map.as_ref(), a)?;
    }
    if let Some(o) = &a.octomap {
        write_occupancy(o, map.as_ref())?;
    }
    Ok(())
}

/// Writes the OctoMap of `map`'s occupancy layer.
fn write_occupancy(path: &Path, map: &HostMap) -> Result<()> {
    let tree = OctoMap::from_map(map);
    let (format, nodes) = write_octomap(path, &tree)?;
    let kind = match format {
        OctoFormat::Binary => "binary OcTree",
        OctoFormat::Color => "ColorOcTree",
    };
    let leaves = tree.leaves().len();
    println!(
        "wrote {}: {kind} at {} m, {leaves} leaves = known voxels ({} occupied, {} free), \
         {nodes} nodes",
        path.display(),
        tree.resolution(),
        tree.occupied(),
        leaves - tree.occupied()
    );
    Ok(())
}

/// Writes the PLY of `map`.
fn write_ply(ply: &Path, map: &HostMap, a: &ExportArgs) -> Result<()> {
    let es = ellipsoids(map, a.min_points);
    match a.ellipsoids {
        Some(s) => write_ellipsoids(ply, &es, s)?,
        None => write_points(ply, &es)?,
    }
    println!(
        "wrote {}: {} occupied Gaussians of {} voxels ({})",
        ply.display(),
        es.len(),
        map.len(),
        a.ellipsoids
            .map_or("points at the means".to_string(), |s| format!(
                "ellipsoids at {s} sigma"
            ))
    );
    Ok(())
}

/// Maps the first trajectory of the dataset `a.input` (opened with `a.open` and `a.predictions`, every
/// `a.every`-th frame) at `a.cell` with `a.labels`, skipping bad frames with a warning
/// ([`usable_frames`]); with a bag, writes the map into it every `a.mcap_interval` frames
/// (if given) and after the last frame mapped, stamped with the frame's recording time (or
/// 10 Hz from 1 s when the dataset has none). Fails when no frame could be mapped.
fn map_first_trajectory(a: &ExportArgs, mut bag: Option<&mut MapBag>) -> Result<Box<HostMap>> {
    let (spec, cell, labels) = (a.input.as_str(), a.cell, a.labels);
    let config = Config::with_cell_size(cell);
    check_cell_config(&config, cell)?;
    let options = a.open.options_with(&a.predictions)?;
    let dataset = a.every.apply(open_spec(spec, &options)?);
    check_labels(labels, dataset.as_ref(), spec)?;
    let trajectories = dataset.trajectories();
    let (name, ids) = trajectories
        .first()
        .ok_or_else(|| anyhow::anyhow!("{spec}: no frames"))?;
    let mut map: Box<HostMap> =
        crate::mapping::boxed_map(config).map_err(|e| anyhow::anyhow!("config: {e}"))?;
    let bar = progress(ids.len() as u64, "map");
    let (mut skipped, mut mapped, mut unwritten) = (Vec::new(), 0, None);
    for frame in usable_frames(dataset.as_ref(), ids, cell, &mut skipped) {
        let frame = frame?;
        integrate_frame(map.as_mut(), &frame, labels.into(), 1)?;
        mapped += 1;
        let k = ids.iter().position(|id| *id == frame.id).unwrap_or(0);
        let stamp = dataset
            .stamp(&frame.id)
            .map_or(frame_time(k), Time::from_nanos);
        unwritten = Some(stamp);
        if let Some(b) = bag.as_deref_mut()
            && a.mcap_interval.is_some_and(|n| (k + 1) % n == 0)
        {
            b.write(map.as_ref(), stamp)?;
            unwritten = None;
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    if let (Some(b), Some(stamp)) = (bag, unwritten) {
        b.write(map.as_ref(), stamp)?;
    }
    if mapped == 0 {
        let why = skipped
            .last()
            .map_or(String::new(), |b| format!(" (the last: {})", b.why));
        anyhow::bail!(
            "nothing mapped: all {} frames of {name} were skipped{why}",
            ids.len()
        );
    }
    println!("mapped {name}: {mapped} frames, {} skipped", skipped.len());
    Ok(map)
}
