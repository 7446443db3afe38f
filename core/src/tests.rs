//! Unit tests of the core against hand-computed answers.

use crate::*;
use std::println;
extern crate std;

#[test]
fn sizes() {
    println!(
        "voxel40 {}",
        core::mem::size_of::<crate::voxel::Voxel<40>>()
    );
    println!("block {}", BLOCK_BYTES);
    println!("map1 {}", core::mem::size_of::<Map<1, 1, 1>>());
    println!("map {}", core::mem::size_of::<Map<10, 10, 40>>());
    println!("cfg {}", core::mem::size_of::<Config>());
}
