//! `sndt info BAG`: what a ROS 2 recording holds (topics with types, counts and rates; the
//! transform tree's frames and roots) and then what `sndt map` would use of it, or what it
//! lacks.

use super::open_args::BagArgs;
use crate::dataset::ros::bag::Bag;
use crate::dataset::ros::index::BagIndex;
use crate::dataset::ros::stamp_text;
use crate::dataset::source::Dataset;
use anyhow::{anyhow, Result};
use std::fmt::Write;
use std::path::PathBuf;

/// Arguments of `sndt info`.
#[derive(clap::Args, Clone, Debug)]
#[command(after_help = "Examples:
  sndt info robot.mcap --world-frame odom
  sndt info rosbag2_2026_11_27-10_00_00/")]
pub struct InfoArgs {
    /// The recording: an `.mcap` file or a rosbag2 folder (`metadata.yaml` and its split
    /// `.mcap` files), ROS 2 messages in CDR.
    pub bag: PathBuf,
    /// Topics, world frame, label map and sync tolerance, as for `sndt map`.
    #[command(flatten)]
    pub bag_options: BagArgs,
}

/// Runs `sndt info`: the report on stdout; an error after it when the bag cannot be mapped.
pub fn run(a: &InfoArgs) -> Result<()> {
    let options = a.bag_options.options()?;
    let index = BagIndex::open(&a.bag)?;
    print!("{}", contents(&index));
    match Bag::new(index, &options) {
        Ok(bag) => {
            print!("{}", usage(&bag));
            Ok(())
        }
        Err(e) => {
            println!("\nsndt map cannot use this bag: {e:#}");
            Err(anyhow!(
                "{}: not mappable as it is (see above)",
                a.bag.display()
            ))
        }
    }
}

/// The topic table and the transform tree.
pub fn contents(index: &BagIndex) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| topic | type | messages | rate Hz | from s | to s | encoding |"
    );
    let _ = writeln!(s, "|---|---|---:|---:|---:|---:|---|");
    for (topic, t) in &index.topics {
        let rate = t.rate_hz().map_or(String::new(), |r| format!("{r:.2}"));
        let _ = writeln!(
            s,
            "| {topic} | {} | {} | {rate} | {} | {} | {} |",
            t.schema,
            t.count,
            stamp_text(t.time_range.0),
            stamp_text(t.time_range.1),
            t.encoding.as_deref().unwrap_or("")
        );
    }
    let tf = index.tf_tree();
    let _ = writeln!(
        s,
        "\ntransform tree (/tf, /tf_static): {} frames, roots: {}",
        tf.frames().len(),
        tf.roots().join(", ")
    );
    for (child, parent, samples) in tf.edges() {
        let kind = samples.map_or("static".into(), |n| format!("/tf, {n} samples"));
        let _ = writeln!(s, "  {parent} <- {child} ({kind})");
    }
    s
}

/// The topics and frame `sndt map` would use, and the frames it would skip, with the
/// reasons.
pub fn usage(bag: &Bag) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "\nsndt map would use: {}", bag.describe());
    for (stamp, why) in &bag.skipped {
        let _ = writeln!(s, "  skipped {} s: {why}", stamp_text(*stamp));
    }
    s
}
