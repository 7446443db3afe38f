//! Cross-architecture check: the committed test vector (`targets/cortex-m4f/vector/`) must
//! give the committed snapshot CRC on this architecture. `bash scripts/test.sh` runs it on
//! x86-64 (`cargo test`); on aarch64 (`scripts/aarch64.sh`, qemu-aarch64) the C API's
//! `vector_crc` program checks the same CRCs, and the Cortex-M4F firmware checks them in
//! QEMU (`scripts/firmware.sh`). The same holds
//! for the CRC of the 64 x 48 view every target renders from that map
//! (`expected_render_crc.txt`).

use sndt_core::INVALID_LABEL;
use sndt_host::embedded::testvector::{
    expected_crc, generate, parse_crc, render_scene, run, TestVector,
};
use std::path::PathBuf;

fn vector_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../targets/cortex-m4f/vector")
}

fn committed() -> (Vec<u8>, u32) {
    let dir = vector_dir();
    let bytes = std::fs::read(dir.join("frames.bin")).expect("reading frames.bin");
    (bytes, committed_crc("expected_crc.txt"))
}

fn committed_crc(name: &str) -> u32 {
    let txt = std::fs::read_to_string(vector_dir().join(name)).expect(name);
    parse_crc(&txt).unwrap_or_else(|e| panic!("{name} holds 0x........: {e}"))
}

#[test]
fn committed_vector_gives_the_committed_crc() {
    let (bytes, want) = committed();
    let got = expected_crc(&bytes).expect("integrating the test vector");
    // Shown with --nocapture.
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

/// The view the firmware renders: its CRC is the committed one on this architecture, and
/// it shows what the scene's exact ray-box render shows from the same camera, labels and
/// distances, independently of how the map renders.
#[test]
fn committed_vector_renders_the_committed_view() {
    let (bytes, _) = committed();
    let v = TestVector::parse(&bytes).expect("parsing frames.bin");
    let view = run(&v).expect("integrating the test vector").view;
    let want = committed_crc("expected_render_crc.txt");
    // Shown with --nocapture.
    println!(
        "crosscheck: {} render crc {:#010x} (expected {want:#010x})",
        std::env::consts::ARCH,
        view.crc
    );
    assert_eq!(
        view.crc, want,
        "render CRC differs from expected_render_crc.txt"
    );

    let last = v.frames.last().unwrap();
    let cam = view.camera;
    let (depth, labels) = render_scene(&last.rotation, &last.translation, &cam);
    let n = labels.len();
    let (mut hits, mut same_label, mut close) = (0, 0, 0);
    for (i, (&truth, &z)) in labels.iter().zip(&depth).enumerate() {
        assert!(z > 0.0, "the scene fills the view");
        let (col, row) = ((i % 64) as u32, (i / 64) as u32);
        let r = cam.ray(col, row);
        let t = z * (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
        if view.labels[i] == INVALID_LABEL {
            assert_eq!(view.distance[i], 0.0);
            continue;
        }
        hits += 1;
        same_label += usize::from(view.labels[i] == truth);
        // 1.5 cells of 10 cm, as the probes.
        close += usize::from((view.distance[i] - t).abs() < 0.15);
    }
    println!("view: {hits} of {n} hit, {same_label} with the true label, {close} within 15 cm");
    assert!(hits * 100 >= n * 99, "{hits} of {n} pixels hit");
    assert!(
        same_label * 100 >= hits * 95,
        "{same_label} of {hits} labels agree"
    );
    assert!(
        close * 100 >= hits * 95,
        "{close} of {hits} distances within 15 cm"
    );
    // The dominant classes of the ground truth are the view's too.
    let count = |ls: &[u8], c: u8| ls.iter().filter(|&&l| l == c).count();
    for class in [1u8, 2] {
        let (a, b) = (count(&view.labels, class), count(&labels, class));
        assert!(
            a.abs_diff(b) * 10 <= b,
            "class {class}: {a} pixels, truth {b}"
        );
    }
}
