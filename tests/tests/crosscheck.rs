//! Cross-architecture check: the committed test vector (`targets/cortex-m4f/vector/`) must
//! give the committed snapshot CRC on this architecture. `bash scripts/test.sh` runs it on
//! x86-64 (`cargo test`) and on aarch64 under qemu-aarch64 (`scripts/aarch64.sh`); the
//! Cortex-M4F firmware checks the same CRC in QEMU (`scripts/firmware.sh`).

use sndt_host::embedded::testvector::{expected_crc, generate, parse_crc, TestVector};
use std::path::PathBuf;

fn vector_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../targets/cortex-m4f/vector")
}

fn committed() -> (Vec<u8>, u32) {
    let dir = vector_dir();
    let bytes = std::fs::read(dir.join("frames.bin")).expect("reading frames.bin");
    let txt = std::fs::read_to_string(dir.join("expected_crc.txt")).expect("expected_crc.txt");
    (
        bytes,
        parse_crc(&txt).expect("expected_crc.txt holds 0x........"),
    )
}

#[test]
fn committed_vector_gives_the_committed_crc() {
    let (bytes, want) = committed();
    let got = expected_crc(&bytes).expect("integrating the test vector");
    // Parsed by scripts/aarch64.sh (run with --nocapture).
    println!(
        "crosscheck: {} snapshot crc {got:#010x} (expected {want:#010x})",
        std::env::consts::ARCH
    );
    assert_eq!(
        got,
        want,
        "snapshot CRC {got:#010x} differs from expected_crc.txt ({want:#010x}) on {}",
        std::env::consts::ARCH
    );
}

#[test]
fn regenerating_the_vector_reproduces_the_committed_bytes() {
    let (bytes, _) = committed();
    let fresh = generate();
    assert_eq!(
        TestVector::parse(&bytes).expect("parsing frames.bin"),
        fresh
    );
    assert!(
        fresh.to_bytes() == bytes,
        "frames.bin differs from `sndt testvector` output: regenerate with \
         `cargo run --release -p sndt-host --bin sndt -- testvector --out targets/cortex-m4f/vector`"
    );
}
