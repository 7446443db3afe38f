//! The `sndt` command line: the only module that uses clap.
//!
//! [`main`] parses the command line into a command and hands its arguments to the
//! command's own file: each file below holds one command's clap `Args` struct and its `run`
//! function, which turns the options into calls of the job modules ([`crate::eval`],
//! [`crate::output`], [`crate::embedded`], ...) and prints what they return.
//!
//! An option has one meaning in every command that has it (`--every K`: every k-th frame;
//! `--frames`: which frames, `N` or `A..B`; `--cell`: voxel edges in metres; `--stride`:
//! every stride-th pixel; `--labels`: `gt`, `pred`, `pred-topk`, `none`; `--out`: an output
//! directory, while an output file is named by its format: `--ply`, `--octomap`, `--mcap`,
//! `--sndt`, `--points-file`). An option several commands have is declared once, in
//! [`open_args`] (the dataset's options, `--every`, `--frames`, `--stride`), and each
//! command's `--help` ends with an example command line (clap's `after_help`, on its `Args`
//! struct), which a test parses.

pub mod budget;
pub mod cloud;
pub mod compare;
pub mod demo;
pub mod dynamics;
pub mod experiment;
pub mod export;
pub mod info;
pub mod labels;
pub mod map;
pub mod merge;
pub mod open_args;
pub mod parse;
pub mod points;
pub mod synth;
pub mod testvector;

use anyhow::Result;
use clap::{Parser, Subcommand};

/// sndt: semantic occupancy-NDT mapping tools.
#[derive(Parser)]
#[command(version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The commands of `sndt`, in the order `sndt --help` lists them: the README's command
/// table's order, the main job first (a test checks that they agree).
#[derive(Subcommand)]
enum Command {
    /// Map a small synthetic split (no download) with GT and predicted labels; metrics and pictures.
    Demo(demo::DemoArgs),
    /// Generate a synthetic labelled split in the prepared layout and/or as ROS 2 bags.
    Synth(synth::SynthArgs),
    /// Map every trajectory of a dataset and evaluate the back-projections with the paper's
    /// evaluation protocol (docs/EVALUATION.md).
    Map(map::MapArgs),
    /// Merge saved maps and devices' record streams into one map (two robots, two
    /// sessions, a co-processor's spill).
    Merge(merge::MergeArgs),
    /// The paper's comparison: S-NDT, S-BKI and OS-BKI per cell size and kernel length;
    /// Tables I and II (Markdown, CSV), per-class IoU and rate-vs-mIoU charts.
    Experiment(experiment::ExperimentArgs),
    /// How fast the map clears what moved and relabels what replaced it, and what the static
    /// scene loses, against OctoMap on the same points (the dynamic synthetic room).
    Dynamics(dynamics::DynamicsArgs),
    /// Integrate frames into the core and the f64 reference and compare them per cell size.
    Compare(compare::CompareArgs),
    /// Exact memory of a Map<N, B, K>; with a dataset, peak voxels, evictions and the spill
    /// bandwidth per trajectory.
    Budget(budget::BudgetArgs),
    /// Write a map's Gaussians as a PLY (points or ellipsoids) for MeshLab/CloudCompare, its
    /// occupancy as an OctoMap (.bt, .ot) and / or both as a ROS 2 bag.
    Export(export::ExportArgs),
    /// List a ROS 2 bag's (MCAP) topics and what `sndt map` would use of it.
    Info(info::InfoArgs),
    /// Write one frame's world points, coloured by label, as a PLY point cloud.
    Cloud(cloud::CloudArgs),
    /// Write frames' sensor origins and world points as a raw binary file (SNDTPTS1), the
    /// input of the OctoMap peer benchmark.
    Points(points::PointsArgs),
    /// Write (--out) or check (--check) the cross-architecture test vector of the firmware.
    Testvector(testvector::TestvectorArgs),
}

/// Parses the command line and runs the command.
pub fn main() -> Result<()> {
    match Cli::parse().command {
        Command::Demo(a) => demo::run(&a),
        Command::Synth(a) => synth::run(&a),
        Command::Map(a) => map::run(&a),
        Command::Merge(a) => merge::run(&a),
        Command::Experiment(a) => experiment::run(&a),
        Command::Dynamics(a) => dynamics::run(&a),
        Command::Compare(a) => compare::run(&a),
        Command::Budget(a) => budget::run(&a),
        Command::Export(a) => export::run(&a),
        Command::Info(a) => info::run(&a),
        Command::Cloud(a) => cloud::run(&a),
        Command::Points(a) => points::run(&a),
        Command::Testvector(a) => testvector::run(&a),
    }
}

#[cfg(test)]
mod tests {
    use super::Cli;
    use clap::{CommandFactory, Parser};

    /// The commands of the README's command table, in its order: the first word of each
    /// `code` span in the first column of the rows after `| command | what |`.
    fn readme_commands(readme: &str) -> Vec<String> {
        let table = readme
            .split_once("| command | what |")
            .expect("README.md has the command table")
            .1;
        let rows = table.lines().skip(2).take_while(|l| l.starts_with('|'));
        let mut commands = Vec::new();
        for row in rows {
            let first_column = row
                .trim_start_matches('|')
                .split(" | ")
                .next()
                .unwrap_or("");
            let spans = first_column.split('`').skip(1).step_by(2);
            commands.extend(spans.filter_map(|s| s.split_whitespace().next().map(String::from)));
        }
        commands
    }

    /// `sndt --help` lists the commands in the README's order, so that the two cannot drift
    /// apart.
    #[test]
    fn help_lists_the_commands_in_the_readmes_order() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../README.md");
        let readme = std::fs::read_to_string(path).expect("README.md");
        let help: Vec<String> = Cli::command()
            .get_subcommands()
            .map(|c| c.get_name().to_string())
            .collect();
        assert_eq!(help, readme_commands(&readme));
        assert_eq!(help[0], "demo", "the main job first");
    }

    /// The example command lines of a help text: its lines `  sndt ...`.
    fn examples(help: &str) -> Vec<&str> {
        help.lines()
            .filter_map(|l| l.strip_prefix("  "))
            .filter(|l| l.starts_with("sndt "))
            .collect()
    }

    /// Every command's `--help` ends with at least one example of that command, and every
    /// example parses (so renaming an option without updating its examples fails here).
    #[test]
    fn every_command_ends_its_help_with_examples_that_parse() {
        let mut problems = Vec::new();
        for sub in Cli::command().get_subcommands() {
            let name = sub.get_name();
            let after = sub.get_after_help().map(ToString::to_string);
            let lines = examples(after.as_deref().unwrap_or(""));
            if lines.is_empty() {
                problems.push(format!("sndt {name} --help ends without an example"));
                continue;
            }
            let help = sub.clone().render_help().to_string();
            if !help.trim_end().ends_with(lines[lines.len() - 1]) {
                problems.push(format!("sndt {name} --help does not end with its example"));
            }
            for line in lines {
                if !line.starts_with(&format!("sndt {name} ")) {
                    problems.push(format!(
                        "the example of sndt {name} is another command: {line}"
                    ));
                } else {
                    if let Err(e) = Cli::try_parse_from(line.split_whitespace()) {
                        problems.push(format!("the example `{line}` does not parse: {e}"));
                    }
                }
            }
        }
        assert!(problems.is_empty(), "{}", problems.join("\n"));
    }
}
