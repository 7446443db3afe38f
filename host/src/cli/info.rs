//! `sndt info BAG.mcap`: what a ROS 2 recording holds and what `sndt map` would use of it.

use super::open_args::OpenArgs;
use crate::dataset::ros::bag::Bag;
use crate::dataset::source::Dataset;
use anyhow::Result;
use std::fmt::Write;
use std::path::PathBuf;

/// Arguments of `sndt info`.
#[derive(clap::Args, Clone, Debug)]
#[command(after_help = "Example:
  sndt info robot.mcap --world-frame odom")]
pub struct InfoArgs {
    /// The bag (`.mcap`, ROS 2 messages in CDR).
    pub bag: PathBuf,
    /// Topics, world frame and sync tolerance, as for `sndt map`.
    #[command(flatten)]
    pub open: OpenArgs,
}

/// Runs `sndt info`.
pub fn run(a: &InfoArgs) -> Result<()> {
    let bag = Bag::open(&a.bag, &a.open.options()?.bag)?;
    print!("{}", info(&bag));
    Ok(())
}

/// The topic table, the topics and frame `sndt map` would use, and the frames it would
/// skip, with the reasons.
pub fn info(bag: &Bag) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "| topic | type | messages | from s | to s | encoding |");
    let _ = writeln!(s, "|---|---|---:|---:|---:|---|");
    for (topic, t) in &bag.topics {
        let _ = writeln!(
            s,
            "| {topic} | {} | {} | {:.3} | {:.3} | {} |",
            t.schema,
            t.count,
            t.time_range.0 as f64 * 1e-9,
            t.time_range.1 as f64 * 1e-9,
            t.encoding.as_deref().unwrap_or("")
        );
    }
    let _ = writeln!(s, "\nsndt map would use: {}", bag.describe());
    for (stamp, why) in &bag.skipped {
        let _ = writeln!(s, "  skipped {:.9} s: {why}", *stamp as f64 * 1e-9);
    }
    s
}
