//! # sndt-host
//!
//! The std side of sndt: feeds [`sndt_core`] from datasets, checks it against an f64
//! reference, evaluates it as the paper does, runs the baselines and draws the results.
//!
//! ## Layers
//!
//! The modules form layers, listed from the bottom up. A module uses only modules of its
//! own layer or of layers below it, never one above: a reader never depends on an
//! evaluation, an evaluation never on the command line. `tests/tests/layout.rs` reads this
//! table and fails on any import that points up it, and checks that `docs/ARCHITECTURE.md`
//! states the same order.
//!
//! | layer | modules | role |
//! |---|---|---|
//! | 1 | [`atomic`] | the shared leaf: every file is written atomically (temporary file, fsync, rename) |
//! | 2 | [`dataset`] | readers: one [`Frame`](dataset::Frame) type for the prepared layout, raw Hypersim, `.npy` predictions and ROS 2 bags ([`dataset::ros`]), and for the synthetic scenes ([`dataset::synthetic`]), which are rendered rather than read but give the same frames, so the renderer sits in this layer beside the readers it stands in for |
//! | 3 | [`mapping`] | maps as the host runs them, a file per job: the [`SemanticMap`](mapping::SemanticMap) trait every mapper implements and the core's side of it; the host map that grows; record-stream checks; a device map spilling into it; the device capacities |
//! | 4 | [`reference`](mod@reference), [`baselines`] | the other mappers: S-NDT in plain `f64` (the core's test oracle); S-BKI and OS-BKI |
//! | 5 | [`output`] | writers: PNG pictures, SVG charts, PLY, point files, OctoMap trees ([`output::octomap`]), ROS 2 bags of frames and maps ([`output::ros`]), progress bars |
//! | 6 | [`eval`], [`embedded`] | the jobs: the paper's metrics, the evaluation loop, the experiment, core-vs-reference; memory budget and the firmware's test vector |
//! | 7 | [`cli`] | the `sndt` command line (the only user of clap), one file per command |
//!
//! `docs/ARCHITECTURE.md` in the repository describes the data flow end to end.

pub mod atomic;
pub mod baselines;
pub mod cli;
pub mod dataset;
pub mod embedded;
pub mod eval;
pub mod mapping;
pub mod output;
pub mod reference;

pub use mapping::boxed_map;
