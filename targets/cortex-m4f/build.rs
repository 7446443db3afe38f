use std::{env, fs, path::PathBuf};

fn main() {
    // Put memory.x where the linker finds it (cortex-m-rt's link.x INCLUDEs it).
    let out = PathBuf::from(env::var_os("OUT_DIR").unwrap());
    fs::copy("memory.x", out.join("memory.x")).unwrap();
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=memory.x");
    println!("cargo:rerun-if-changed=build.rs");
    // `-arg`, not `-arg-bins`: on-target test binaries need the vector table too.
    println!("cargo:rustc-link-arg=-Tlink.x");
    println!("cargo:rustc-link-arg=-Tdefmt.x");
}
