//! What every mapper offers the evaluation: S-NDT (the core), the f64 reference and the
//! baselines.

use sndt_core::{Config, Map};

/// A map on the heap, built on a helper thread whose stack is large enough to hold it
/// (a `Map` of a million voxels is ~100 MB and would overflow the caller's stack when
/// constructed by value). No `unsafe` involved.
///
/// ```
/// let map = sndt_host::semantic_map::boxed_map::<1024, 256, 40>(sndt_core::Config::DEFAULT).unwrap();
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
