//! `sndt synth`: a synthetic labelled split written in the prepared layout (no download),
//! with its class histogram, preview pictures and the raw prediction's score: separate
//! rooms, a walk through the building floor, or the room where things move.

use crate::dataset::classes::{render_color, NYU40};
use crate::dataset::source::Dataset;
use crate::dataset::synthetic::{
    dynamic, floor, people, write_split, DepthNoise, DynamicOptions, SynthOptions, Synthetic,
};
use crate::eval::label_stats::LabelStats;
use crate::output::picture;
use crate::output::progress::progress;
use crate::output::ros::write::ChunkCompression;
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

/// What `sndt synth` generates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SceneArg {
    /// Separate rooms, one trajectory each (`--scenes`).
    Rooms,
    /// One walk through a building floor: eleven rooms along a corridor (`--walk`).
    Floor,
    /// The room where things move: a chair is moved, an object replaced, a door opens,
    /// a person and a cart pass (`--change`, `--frozen`).
    Dynamic,
    /// A walk through the building floor while people walk its corridor (`--walk`,
    /// `--frozen`).
    FloorPeople,
}

/// Arguments of `sndt synth`.
#[derive(clap::Args, Clone, Debug)]
#[command(after_help = "Examples:
  sndt synth --out data/synth --scenes 2 --frames-per-scene 20 --no-predictions
  sndt synth --out data/floor --scene floor --walk 2 --frames-per-scene 200
  sndt synth --out data/dynamic --scene dynamic")]
pub struct SynthArgs {
    /// Output directory (the dataset root) of the prepared layout.
    #[arg(long, required_unless_present = "mcap")]
    pub out: Option<PathBuf>,
    /// Also (or only) write each trajectory as a ROS 2 bag (rosbag2, MCAP: 16UC1 depth, mono8
    /// labels, camera info, /tf and latched /tf_static): this file for one scene,
    /// `<stem>_<scene>.mcap` beside it for several. A path ending in `/` (or an existing
    /// directory) is a bag folder (`DIR/<DIR's name>_0.mcap` and `DIR/metadata.yaml`;
    /// `DIR_<scene>/` for several).
    #[arg(long)]
    pub mcap: Option<PathBuf>,
    /// Compression of the bags' chunks (`none` as `ros2 bag record` writes by default).
    #[arg(long, value_enum, default_value_t = ChunkCompression::Zstd, requires = "mcap")]
    pub mcap_compression: ChunkCompression,
    /// What to generate: separate rooms, a walk through the building floor (scene
    /// `synth_floor`, trajectory `cam_NN` of walk NN + 1), the room where things move
    /// (scene `synth_dynamic`), or a walk of the floor with people in its corridor (scene
    /// `synth_floor_people`).
    #[arg(long, value_enum, default_value = "rooms")]
    pub scene: SceneArg,
    /// Number of rooms with `--scene rooms` (kinds cycle: living, bedroom, kitchen, office,
    /// bathroom, open plan) [default: 6].
    #[arg(long)]
    pub scenes: Option<usize>,
    /// Which walk through the floor with `--scene floor` or `floor-people`: 1, 2, ... (odd walks go from the
    /// west end of the corridor to the east, even walks back; each picks its own
    /// standpoints and views) [default: 1].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub walk: Option<u32>,
    /// With `--scene dynamic`: the frame of the first change; every event must fit in the
    /// walk [default: 30].
    #[arg(long, value_name = "FRAME")]
    pub change: Option<u32>,
    /// With `--scene dynamic` or `floor-people`: leave every object where it stands at
    /// frame 0 (the frozen twin the dynamics report compares with; no people).
    #[arg(long)]
    pub frozen: bool,
    /// Seed of everything.
    #[arg(long, default_value_t = crate::dataset::synthetic::DEFAULT_SEED)]
    pub seed: u64,
    /// Frames of each scene's camera trajectory (one trajectory per scene); with `--scene
    /// floor`, frames the walk is sampled at (1000: about 9 per second; fewer: the same
    /// walk at a lower frame rate) [default: 100, with --scene floor 1000, with --scene
    /// dynamic 160].
    #[arg(long, value_name = "N")]
    pub frames_per_scene: Option<usize>,
    /// Add range-dependent depth noise (Kinect v1 model).
    #[arg(long)]
    pub noise: bool,
    /// Skip the ESANet-style predictions (9.4 MB per frame).
    #[arg(long)]
    pub no_predictions: bool,
}

/// Runs `sndt synth`: writes the split, prints its ground-truth class histogram, writes
/// previews and scores the raw predictions.
pub fn run(a: &SynthArgs) -> Result<()> {
    let t = Instant::now();
    let on_floor = matches!(a.scene, SceneArg::Floor | SceneArg::FloorPeople);
    if a.walk.is_some() && !on_floor {
        bail!("--walk: only with --scene floor or floor-people");
    }
    if a.scenes.is_some() && a.scene != SceneArg::Rooms {
        bail!("--scenes: only with --scene rooms");
    }
    if a.change.is_some() && a.scene != SceneArg::Dynamic {
        bail!("--change: only with --scene dynamic");
    }
    if a.frozen && !matches!(a.scene, SceneArg::Dynamic | SceneArg::FloorPeople) {
        bail!("--frozen: only with --scene dynamic or floor-people");
    }
    let floor_walk = (a.scene == SceneArg::Floor).then(|| a.walk.unwrap_or(1));
    let dynamic = match a.scene {
        SceneArg::Dynamic => Some(DynamicOptions {
            change: a.change.unwrap_or(dynamic::DEFAULT_CHANGE),
            frozen: a.frozen,
            floor_walk: None,
        }),
        SceneArg::FloorPeople => Some(DynamicOptions {
            frozen: a.frozen,
            floor_walk: Some(a.walk.unwrap_or(1)),
            ..DynamicOptions::default()
        }),
        SceneArg::Rooms | SceneArg::Floor => None,
    };
    let default_frames = match a.scene {
        SceneArg::Rooms => SynthOptions::default().frames,
        SceneArg::Floor | SceneArg::FloorPeople => floor::DEFAULT_FRAMES,
        SceneArg::Dynamic => dynamic::DEFAULT_FRAMES,
    };
    let options = SynthOptions {
        scenes: a.scenes.unwrap_or(SynthOptions::default().scenes),
        frames: a.frames_per_scene.unwrap_or(default_frames),
        seed: a.seed,
        noise: a.noise.then_some(DepthNoise::KINECT),
        predictions: !a.no_predictions,
        floor: floor_walk,
        dynamic,
        ..SynthOptions::default()
    };
    let split = Synthetic::new(options)?;
    if let Some(path) = &a.mcap {
        write_bags(&split, path, a.mcap_compression)?;
    }
    let Some(out) = &a.out else {
        return Ok(());
    };
    println!("sndt synth: {} -> {}", split.describe(), out.display());
    let bar = progress(split.frames().len() as u64, "synth");
    // Per-frame statistics are summed outside the lock; only the merge is serialised.
    let stats = Mutex::new(LabelStats::default());
    let frames = write_split(out, &split, &|f| {
        let mut one = LabelStats::default();
        one.add(f);
        stats.lock().expect("no panic while merging").merge(&one);
        bar.inc(1);
    })?;
    let summary = stats.into_inner().expect("no panic while merging");
    bar.finish_and_clear();
    println!("{frames} frames in {:.1} s", t.elapsed().as_secs_f64());
    print_class_histogram(&summary.class_pixels);
    write_previews(&split, &out.join("preview"))?;
    if !a.no_predictions {
        let m = summary.prediction.metrics();
        println!(
            "raw top-1 prediction vs ground truth: mIoU {:.2} %, mPAcc {:.2} % (the paper's ESANet: 41.17 % mIoU)",
            m.miou * 100.0,
            m.mpacc * 100.0
        );
    }
    Ok(())
}

/// Writes each trajectory of `split` as a ROS 2 bag: `path` for one, `<stem>_<scene>.mcap`
/// (or for a bag folder `path`, the folder `<dir>_<scene>/`) for several.
pub fn write_bags(
    split: &Synthetic,
    path: &Path,
    compression: ChunkCompression,
) -> Result<Vec<PathBuf>> {
    let trajectories = split.trajectories();
    let mut written = Vec::new();
    for (name, ids) in &trajectories {
        let file = if trajectories.len() == 1 {
            path.to_path_buf()
        } else {
            crate::output::ros::write::sibling_bag(path, name, "synthetic")
        };
        let n = crate::output::ros::write::write_trajectory_compressed(
            &file,
            ids.iter().map(|id| split.load(id)),
            compression,
        )?;
        println!("wrote {} ({n} frames of {name})", file.display());
        written.push(file);
    }
    Ok(written)
}

/// Prints each occurring class's share of all pixels, so a split's class balance can be
/// checked before it is mapped.
fn print_class_histogram(class_pixels: &[u64]) {
    let total: u64 = class_pixels.iter().sum();
    println!("ground-truth class histogram (share of all pixels):");
    for (c, &n) in class_pixels.iter().enumerate() {
        if n > 0 {
            println!(
                "  {:>2} {:<14} {:7.3} %",
                c,
                NYU40[c],
                100.0 * n as f64 / total as f64
            );
        }
    }
    let present = class_pixels[1..].iter().filter(|&&n| n > 0).count();
    println!("{present} of 40 classes occur");
}

/// Writes ground truth | prediction for the first and the middle frame of each scene
/// into `dir` (the prediction falls back to the ground truth without predictions).
fn write_previews(split: &Synthetic, dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    for (_, ids) in split.trajectories() {
        // The dynamic room: before the change, the person standing, the cart passing, the
        // end; the floor with people: the start and the middle of each person's crossing.
        let scene = split.dynamic_scene();
        let picks: Vec<usize> = match (scene, scene.and_then(|s| s.events.first())) {
            (Some(s), _) if s.name == people::NAME => std::iter::once(0)
                .chain(s.events.iter().map(|e| (e.first + e.vacated) as usize / 2))
                .collect(),
            (_, Some(e)) => vec![
                0,
                e.first as usize + 15,
                e.first as usize + 55,
                ids.len() - 1,
            ],
            _ => vec![0, ids.len() / 2],
        };
        for id in picks.iter().filter_map(|&i| ids.get(i)) {
            let f = split.load(id)?;
            let gt = f.labels.clone().unwrap_or_default();
            let pred = f
                .predictions
                .as_ref()
                .map(super::super::dataset::frame::TopK::top1)
                .unwrap_or_else(|| gt.clone());
            let path = dir.join(format!("{}_{}.png", id.scene, id.stem()));
            picture::side_by_side(
                &path,
                f.rays.width(),
                f.rays.height(),
                &[&gt, &pred],
                render_color,
            )?;
        }
    }
    println!(
        "wrote previews (ground truth | prediction) to {}",
        dir.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli::{Cli, Command};
    use clap::Parser;

    fn args(line: &str) -> SynthArgs {
        match Cli::try_parse_from(line.split_whitespace())
            .unwrap()
            .command
        {
            Command::Synth(a) => a,
            _ => unreachable!("a synth command line"),
        }
    }

    #[test]
    fn synth_writes_a_walk_of_the_floor() {
        let out = std::env::temp_dir().join(format!("sndt-synth-floor-{}", std::process::id()));
        let line = format!(
            "sndt synth --out {} --scene floor --walk 2 --frames-per-scene 2 --no-predictions",
            out.display()
        );
        run(&args(&line)).unwrap();
        let written = crate::dataset::open_spec(out.to_str().unwrap(), &Default::default());
        let ids: Vec<String> = written
            .unwrap()
            .frames()
            .iter()
            .map(ToString::to_string)
            .collect();
        std::fs::remove_dir_all(&out).unwrap();
        assert_eq!(ids, ["synth_floor/cam_01/0000", "synth_floor/cam_01/0001"]);
    }

    #[test]
    fn synth_walk_and_scenes_go_with_their_scene_only() {
        let a = args("sndt synth --out x --walk 2");
        assert_eq!(
            format!("{}", run(&a).unwrap_err()),
            "--walk: only with --scene floor or floor-people"
        );
        let a = args("sndt synth --out x --scene floor --frozen");
        assert_eq!(
            format!("{}", run(&a).unwrap_err()),
            "--frozen: only with --scene dynamic or floor-people"
        );
        let a = args("sndt synth --out x --scene floor-people --change 5");
        assert_eq!(
            format!("{}", run(&a).unwrap_err()),
            "--change: only with --scene dynamic"
        );
        let a = args("sndt synth --out x --scene floor --scenes 2");
        assert_eq!(
            format!("{}", run(&a).unwrap_err()),
            "--scenes: only with --scene rooms"
        );
        assert!(Cli::try_parse_from([
            "sndt", "synth", "--out", "x", "--scene", "floor", "--walk", "0"
        ])
        .is_err());
        let a = args("sndt synth --out x");
        assert_eq!(
            (a.scene, a.scenes, a.walk, a.frames_per_scene),
            (SceneArg::Rooms, None, None, None)
        );
    }
}
