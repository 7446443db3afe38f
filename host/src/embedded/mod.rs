//! Host tools for firmware: the exact memory budget of a map, and the test vector the
//! Cortex-M4F example maps in QEMU (its snapshot CRC is checked on three architectures).

pub mod budget;
pub mod testvector;
pub mod view;
