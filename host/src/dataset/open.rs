//! Opening a dataset: the layout is detected from the directory, or `synthetic[:S:F]`
//! renders the synthetic split on the fly.

use super::source::{Dataset, OpenOptions};
use anyhow::{bail, Context, Result};
use std::path::Path;

/// Opens `spec`: the word `synthetic` for the default synthetic split rendered on the
/// fly (no files; `synthetic:SCENES:FRAMES` for a smaller one), else a dataset
/// directory (see [`open`]).
///
/// ```
/// let d = sndt_host::dataset::open_spec("synthetic:1:2", &Default::default()).unwrap();
/// assert_eq!(d.frames().len(), 2);
/// ```
pub fn open_spec(spec: &str, options: &OpenOptions) -> Result<Box<dyn Dataset>> {
    if let Some(rest) = spec.strip_prefix("synthetic") {
        let mut o = super::synthetic::SynthOptions::default();
        let nums: Vec<&str> = rest.split(':').skip(1).collect();
        if let [scenes, frames] = nums.as_slice() {
            o.scenes = scenes.parse().with_context(|| format!("{spec}: scenes"))?;
            o.frames = frames.parse().with_context(|| format!("{spec}: frames"))?;
        } else if !rest.is_empty() {
            bail!("{spec}: expected synthetic or synthetic:SCENES:FRAMES");
        }
        return Ok(Box::new(super::synthetic::Synthetic::new(o)?));
    }
    open(Path::new(spec), options)
}

/// Opens a dataset directory, detecting its layout, or a ROS 2 bag (`*.mcap`):
/// - a prepared layout has `<root>/<split>.txt` or `<root>/<split>/depth/` (a `warning:`
///   on stderr names each camera's missing intrinsics file, when it has an
///   `intrinsics/` directory);
/// - raw Hypersim has `<root>/<scene>/_detail/`.
pub fn open(root: &Path, options: &OpenOptions) -> Result<Box<dyn Dataset>> {
    if root.extension().is_some_and(|e| e == "mcap") {
        let bag = crate::dataset::ros::bag::Bag::open(root, &options.bag)?;
        for (stamp, why) in &bag.skipped {
            eprintln!(
                "warning: {}: skipped depth image at {:.9} s: {why}",
                root.display(),
                *stamp as f64 * 1e-9
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
