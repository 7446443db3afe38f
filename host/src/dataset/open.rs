//! Opening a dataset: the layout is detected from the directory, or `synthetic[:S:F]`
//! renders the synthetic split on the fly (`synthetic:floor[:WALK[:FRAMES]]`: a walk of
//! the synthetic building floor).

use super::source::{Dataset, OpenOptions};
use anyhow::{bail, Context, Result};
use std::path::Path;

/// Opens `spec`, else a dataset directory (see [`open`]). Rendered on the fly, no files:
///
/// - `synthetic`: the default synthetic split (six rooms, 100 frames each);
/// - `synthetic:SCENES:FRAMES`: `SCENES` rooms of `FRAMES` frames each;
/// - `synthetic:floor`: walk 1 of the building floor
///   ([`floor`](super::synthetic::floor)), 1,000 frames, scene `synth_floor`,
///   trajectory `cam_00`;
/// - `synthetic:floor:WALK`: walk `WALK` (1, 2, ...; trajectory `cam_NN`, `NN = WALK - 1`);
/// - `synthetic:floor:WALK:FRAMES`: the same walk sampled at `FRAMES` frames (fewer frames
///   are the whole walk at a lower frame rate);
/// - `synthetic:dynamic`: the room where things move
///   ([`dynamic`](super::synthetic::dynamic)), 160 frames, the first change at frame 30,
///   scene `synth_dynamic`; `synthetic:dynamic:FRAMES` and
///   `synthetic:dynamic:FRAMES:CHANGE` set both (every event must fit in the walk);
///   `synthetic:dynamic-frozen[...]` is the same walk with every object left where it
///   stands at frame 0;
/// - `synthetic:floor-people[:WALK[:FRAMES]]`: walk `WALK` (default 1) of the building
///   floor, 1,000 frames unless `FRAMES`, with people walking its corridor
///   ([`people`](super::synthetic::people)), scene `synth_floor_people`;
///   `synthetic:floor-people-frozen[...]` is the same walk without them.
///
/// ```
/// let d = sndt_host::dataset::open_spec("synthetic:1:2", &Default::default()).unwrap();
/// assert_eq!(d.frames().len(), 2);
/// let f = sndt_host::dataset::open_spec("synthetic:floor:2:3", &Default::default()).unwrap();
/// assert_eq!(f.frames()[2].to_string(), "synth_floor/cam_01/0002");
/// ```
pub fn open_spec(spec: &str, options: &OpenOptions) -> Result<Box<dyn Dataset>> {
    match synthetic_options(spec) {
        Some(o) => Ok(Box::new(super::synthetic::Synthetic::new(o?)?)),
        None => open(Path::new(spec), options),
    }
}

/// The options of a `synthetic...` spec (see [`open_spec`]); `None` for any other spec.
///
/// ```
/// let o = sndt_host::dataset::open::synthetic_options("synthetic:dynamic:120").unwrap().unwrap();
/// assert_eq!((o.frames, o.dynamic.unwrap().change), (120, 30));
/// assert!(sndt_host::dataset::open::synthetic_options("data/hypersim").is_none());
/// ```
pub fn synthetic_options(spec: &str) -> Option<Result<super::synthetic::SynthOptions>> {
    let rest = spec.strip_prefix("synthetic")?;
    Some(parse_synthetic(spec, rest))
}

/// [`synthetic_options`] of `spec`, `rest` being what follows `synthetic`.
fn parse_synthetic(spec: &str, rest: &str) -> Result<super::synthetic::SynthOptions> {
    let mut o = super::synthetic::SynthOptions::default();
    let parts: Vec<&str> = rest.split(':').skip(1).collect();
    match parts.as_slice() {
        [] if rest.is_empty() => {}
        ["floor", more @ ..] if more.len() <= 2 => {
            let walk = more.first().map_or(Ok(1), |w| w.parse());
            let walk: u32 = walk.with_context(|| format!("{spec}: walk"))?;
            if walk == 0 {
                bail!("{spec}: walks are numbered from 1");
            }
            o.floor = Some(walk);
            o.frames = match more.get(1) {
                Some(f) => f.parse().with_context(|| format!("{spec}: frames"))?,
                None => super::synthetic::floor::DEFAULT_FRAMES,
            };
        }
        ["floor-people" | "floor-people-frozen", more @ ..] if more.len() <= 2 => {
            let walk = more.first().map_or(Ok(1), |w| w.parse());
            let walk: u32 = walk.with_context(|| format!("{spec}: walk"))?;
            if walk == 0 {
                bail!("{spec}: walks are numbered from 1");
            }
            o.frames = match more.get(1) {
                Some(f) => f.parse().with_context(|| format!("{spec}: frames"))?,
                None => super::synthetic::floor::DEFAULT_FRAMES,
            };
            o.dynamic = Some(super::synthetic::DynamicOptions {
                frozen: parts[0] == "floor-people-frozen",
                floor_walk: Some(walk),
                ..Default::default()
            });
        }
        ["dynamic" | "dynamic-frozen", more @ ..] if more.len() <= 2 => {
            let frozen = parts[0] == "dynamic-frozen";
            let mut d = super::synthetic::DynamicOptions {
                frozen,
                ..Default::default()
            };
            o.frames = match more.first() {
                Some(f) => f.parse().with_context(|| format!("{spec}: frames"))?,
                None => super::synthetic::dynamic::DEFAULT_FRAMES,
            };
            if let Some(c) = more.get(1) {
                d.change = c.parse().with_context(|| format!("{spec}: change frame"))?;
            }
            o.dynamic = Some(d);
        }
        [scenes, frames] => {
            o.scenes = scenes.parse().with_context(|| format!("{spec}: scenes"))?;
            o.frames = frames.parse().with_context(|| format!("{spec}: frames"))?;
        }
        _ => bail!(
            "{spec}: expected synthetic, synthetic:SCENES:FRAMES, synthetic:floor, \
                 synthetic:floor:WALK, synthetic:floor:WALK:FRAMES, synthetic:dynamic, \
                 synthetic:dynamic:FRAMES[:CHANGE] or synthetic:floor-people[:WALK[:FRAMES]]"
        ),
    }
    Ok(o)
}

/// Whether `path` is a ROS 2 recording: an `.mcap` file, or a rosbag2 folder (one with a
/// `metadata.yaml`, as `ros2 bag record` writes).
pub fn is_bag(path: &Path) -> bool {
    path.extension().is_some_and(|e| e == "mcap") || path.join("metadata.yaml").is_file()
}

/// Opens a dataset directory, detecting its layout, or a ROS 2 bag (an `.mcap` file or a
/// rosbag2 folder):
/// - a prepared layout has `<root>/<split>.txt` or `<root>/<split>/depth/` (a `warning:`
///   on stderr names each camera's missing intrinsics file, when it has an
///   `intrinsics/` directory);
/// - raw Hypersim has `<root>/<scene>/_detail/`.
pub fn open(root: &Path, options: &OpenOptions) -> Result<Box<dyn Dataset>> {
    if is_bag(root) {
        let bag = crate::dataset::ros::bag::Bag::open(root, &options.bag)?;
        for (stamp, why) in &bag.skipped {
            eprintln!(
                "warning: {}: skipped depth image at {} s: {why}",
                root.display(),
                crate::dataset::ros::stamp_text(*stamp)
            );
        }
        return Ok(Box::new(bag));
    }
    if !root.exists() {
        bail!("{}: no such file or directory", root.display());
    }
    if !root.is_dir() {
        bail!("{}: not a directory", root.display());
    }
    let split = options.split.as_deref().unwrap_or("test");
    if root.join(format!("{split}.txt")).is_file() || root.join(split).join("depth").is_dir() {
        let prepared = super::prepared::Prepared::open(root, options)?;
        let nominal = super::prepared::nominal_camera(options.paper_fy);
        for missing in prepared.fallback_cameras() {
            eprintln!(
                "warning: {}: no such file; this camera uses the nominal Hypersim camera (fx {} fy {}, {}x{})",
                missing.display(),
                nominal.fx,
                nominal.fy,
                nominal.width,
                nominal.height
            );
        }
        return Ok(Box::new(prepared));
    }
    let raw = std::fs::read_dir(root)
        .with_context(|| format!("listing {}", root.display()))?
        .filter_map(std::result::Result::ok)
        .any(|e| e.path().join("_detail").is_dir());
    if raw {
        return Ok(Box::new(super::hypersim::Hypersim::open(root, options)?));
    }
    bail!(
        "{}: neither a prepared layout ({split}.txt or {split}/depth/) nor raw Hypersim (<scene>/_detail/)",
        root.display()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames(spec: &str) -> Result<Vec<String>> {
        let d = open_spec(spec, &OpenOptions::default())?;
        Ok(d.frames().iter().map(ToString::to_string).collect())
    }

    #[test]
    fn synthetic_floor_specs() {
        let short = frames("synthetic:floor:1:20").unwrap();
        assert_eq!(short.len(), 20);
        assert_eq!(short[19], "synth_floor/cam_00/0019");
        let walk = frames("synthetic:floor").unwrap();
        assert_eq!(walk.len(), 1000);
        assert_eq!(walk[0], "synth_floor/cam_00/0000");
        let two = frames("synthetic:floor:2").unwrap();
        assert_eq!(
            (two.len(), two[999].as_str()),
            (1000, "synth_floor/cam_01/0999")
        );
        // The rooms' forms are as before.
        assert_eq!(
            frames("synthetic:2:3").unwrap()[3],
            "synth_01_bedroom/cam_00/0000"
        );
        assert_eq!(frames("synthetic").unwrap().len(), 600);
        for bad in [
            "synthetic:floor:0",
            "synthetic:floor:x",
            "synthetic:floor:1:0",
            "synthetic:floor:1:2:3",
            "synthetic:floor:",
            "synthetic:2",
            "synthetic:flor:1",
            "synthetics",
        ] {
            let err = format!("{:#}", frames(bad).unwrap_err());
            let named = err.starts_with(bad) || err.starts_with("synthetic floor: need");
            assert!(named, "{bad}: {err}");
        }
        let err = format!("{:#}", frames("synthetic:1:2:3").unwrap_err());
        assert!(err.contains("synthetic:floor:WALK:FRAMES"), "{err}");
    }
}
