//! The `sndt` command line: the only module that uses clap.
//!
//! [`main`] parses the command line into a command and hands its arguments to the
//! command's own file: each file below holds one command's clap `Args` struct and its `run`
//! function, which turns the options into calls of the job modules ([`crate::eval`],
//! [`crate::output`], [`crate::embedded`], ...) and prints what they return.

pub mod budget;
pub mod cloud;
pub mod compare;
pub mod demo;
pub mod experiment;
pub mod export;
pub mod info;
pub mod labels;
pub mod map;
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

/// The commands of `sndt`, in the order `sndt --help` lists them.
#[derive(Subcommand)]
enum Command {
    /// Map a small synthetic split (no download) with GT and predicted labels; metrics and pictures.
    Demo(demo::DemoArgs),
    /// Exact memory of a Map<N, B, K>; with a dataset, peak voxels and evictions per trajectory.
    Budget(budget::BudgetArgs),
    /// Write (--out) or check (--check) the cross-architecture test vector of the firmware.
    Testvector(testvector::TestvectorArgs),
    /// Write one frame's world points, coloured by label, as a PLY point cloud.
    Cloud(cloud::CloudArgs),
    /// Write frames' sensor origins and world points as a raw binary file (SNDTPTS1), the
    /// input of the OctoMap peer benchmark.
    Points(points::PointsArgs),
    /// Generate a synthetic labelled split in the prepared layout and/or as ROS 2 bags.
    Synth(synth::SynthArgs),
    /// List a ROS 2 bag's (MCAP) topics and what `sndt map` would use of it.
    Info(info::InfoArgs),
    /// Map every trajectory of a dataset and evaluate the back-projections with the paper's
    /// evaluation protocol (docs/ARCHITECTURE.md).
    Map(map::MapArgs),
    /// Write a map's Gaussians as a PLY (points or ellipsoids) for MeshLab/CloudCompare.
    Export(export::ExportArgs),
    /// Integrate frames into the core and the f64 reference and compare them per cell size.
    Compare(compare::CompareArgs),
    /// The paper's comparison: S-NDT, S-BKI and OS-BKI per cell size and kernel length;
    /// Tables I and II (Markdown, CSV), per-class IoU and rate-vs-mIoU charts.
    Experiment(experiment::ExperimentArgs),
}

/// Parses the command line and runs the command.
pub fn main() -> Result<()> {
    match Cli::parse().command {
        Command::Demo(a) => demo::run(&a),
        Command::Budget(a) => budget::run(&a),
        Command::Testvector(a) => testvector::run(&a),
        Command::Cloud(a) => cloud::run(&a),
        Command::Points(a) => points::run(&a),
        Command::Synth(a) => synth::run(&a),
        Command::Info(a) => info::run(&a),
        Command::Map(a) => map::run(&a),
        Command::Export(a) => export::run(&a),
        Command::Compare(a) => compare::run(&a),
        Command::Experiment(a) => experiment::run(&a),
    }
}
