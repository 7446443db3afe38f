//! # sndt-host
//!
//! The std side of sndt: feeds [`sndt_core`] from datasets, checks it against an f64
//! reference, evaluates it as the paper does, runs the baselines and draws the results.
//!
//! Modules by role; dependencies point one way, from the top of this list down:
//!
//! | module | role |
//! |---|---|
//! | [`cli`] | the `sndt` command line (the only user of clap), one file per command |
//! | [`eval`] | the paper's metrics, the evaluation loop, the experiment, core-vs-reference |
//! | [`baselines`] | S-BKI and OS-BKI |
//! | [`reference`](mod@reference) | S-NDT in plain `f64` with std collections, the core's test oracle |
//! | [`output`] | PNG pictures, SVG charts, PLY export |
//! | [`embedded`] | memory budget and the firmware's test vector |
//! | [`semantic_map`] | the [`SemanticMap`](semantic_map::SemanticMap) trait every mapper implements |
//! | [`dataset`] | one frame type and one interface for synthetic, prepared and Hypersim data |
//!
//! `docs/ARCHITECTURE.md` in the repository describes the data flow end to end.

pub mod baselines;
pub mod cli;
pub mod dataset;
pub mod embedded;
pub mod eval;
pub mod output;
pub mod reference;
pub mod ros;
pub mod semantic_map;

pub use semantic_map::boxed_map;
