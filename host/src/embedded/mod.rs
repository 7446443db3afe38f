//! Host tools for firmware: the exact memory budget of a map, the test vector the
//! Cortex-M4F example maps in QEMU (its snapshot CRC is checked on three architectures),
//! and the spill run whose record stream the firmware sends over its UART.

pub mod budget;
pub mod spill;
pub mod testvector;
pub mod view;
