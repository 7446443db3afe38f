//! Map capacities fixed when the library is built: `SNDT_VOXELS`, `SNDT_BLOCKS` and
//! `SNDT_CLASSES` from the environment (defaults 4096, 512, 40: the example firmware's map),
//! written to `$OUT_DIR/capacity.rs`. The C side must be compiled with the same values
//! (`-DSNDT_VOXELS=...`; CMake's `sndt` target does both).

use std::{env, fs, path::PathBuf};

fn capacity(name: &str, default: u64, max: u64) -> u64 {
    println!("cargo:rerun-if-env-changed={name}");
    let Ok(text) = env::var(name) else {
        return default;
    };
    match text.trim().parse::<u64>() {
        Ok(v) if (1..=max).contains(&v) => v,
        _ => panic!("{name}={text:?}: expected an integer in 1..={max}"),
    }
}

fn main() {
    let voxels = capacity("SNDT_VOXELS", 4096, u32::MAX as u64 - 1);
    let blocks = capacity("SNDT_BLOCKS", 512, u32::MAX as u64 - 1);
    let classes = capacity("SNDT_CLASSES", 40, 254);
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("OUT_DIR"));
    let code = format!(
        "/// Surface-voxel capacity (`SNDT_VOXELS`).\npub const VOXELS: usize = {voxels};\n\
         /// Occupancy-block capacity (`SNDT_BLOCKS`).\npub const BLOCKS: usize = {blocks};\n\
         /// Class count (`SNDT_CLASSES`).\npub const CLASSES: usize = {classes};\n"
    );
    fs::write(out.join("capacity.rs"), code).expect("writing capacity.rs");
    println!("cargo:rerun-if-changed=build.rs");
}
