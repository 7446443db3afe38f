//! # sndt-host
//!
//! The std side of sndt: feeds [`sndt_core`] from datasets, checks it, evaluates it and
//! draws it. This crate grows module by module (datasets, reference, evaluation,
//! baselines, experiments); the core stays `no_std`.

pub mod bki;
pub mod budget;
pub mod chart;
pub mod colors;
pub mod compare;
pub mod dataset;
pub mod demo;
pub mod eval;
pub mod evaluate;
pub mod experiment;
pub mod export;
pub mod hypersim;
pub mod npy;
pub mod picture;
pub mod ply;
pub mod prepared;
pub mod reference;
pub mod room;
pub mod synth;
pub mod testvector;

use sndt_core::{Config, Map};

/// A map on the heap, built on a helper thread whose stack is large enough to hold it
/// (a `Map` of a million voxels is ~100 MB and would overflow the caller's stack when
/// constructed by value). No `unsafe` involved.
///
/// ```
/// let map = sndt_host::boxed_map::<1024, 256, 40>(sndt_core::Config::DEFAULT).unwrap();
/// assert!(map.is_empty());
/// ```
pub fn boxed_map<const V: usize, const B: usize, const C: usize>(
    config: Config,
) -> Result<Box<Map<V, B, C>>, sndt_core::Error> {
    config.validate()?;
    let stack = 4 * core::mem::size_of::<Map<V, B, C>>() + (16 << 20);
    std::thread::Builder::new()
        .name("sndt-map-alloc".into())
        .stack_size(stack)
        .spawn(move || Box::new(Map::new(config)))
        .expect("spawning the map allocation thread")
        .join()
        .map_err(|_| sndt_core::Error::InvalidConfig)
}

/// A progress bar on stderr (hidden when stderr is not a terminal, e.g. in CI logs).
pub fn progress(len: u64, what: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(len);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg:>14} [{bar:40}] {pos}/{len} {elapsed}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_message(what.to_string());
    bar
}
