//! The Hypersim HDF5 readers (`read_hdf5_f64`, `read_depth`, `read_semantic`) on arbitrary
//! bytes. The HDF5 library opens files only by path, so each input is written to one
//! temporary file per process first.
//!
//! An accepted dataset has as many values as its shape says; a 2-D one is read again as
//! depth and as labels, which give one value per pixel and labels `0..=40`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sndt_host::dataset::hypersim::{read_depth, read_hdf5_f64, read_semantic};
use std::path::PathBuf;
use std::sync::OnceLock;

/// In memory where the machine has /dev/shm: the file is rewritten for every input.
fn scratch() -> &'static PathBuf {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    PATH.get_or_init(|| {
        let shm = std::path::Path::new("/dev/shm");
        let dir = if shm.is_dir() {
            shm.to_path_buf()
        } else {
            std::env::temp_dir()
        };
        dir.join(format!("sndt-fuzz-hdf5-{}.hdf5", std::process::id()))
    })
}

fuzz_target!(|data: &[u8]| {
    let path = scratch();
    std::fs::write(path, data).expect("writing the scratch file");
    let Ok((shape, values)) = read_hdf5_f64(path) else {
        return;
    };
    let n = shape.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
    assert_eq!(
        n,
        Some(values.len()),
        "shape {shape:?} but {} values",
        values.len()
    );
    if let [rows, cols] = shape[..] {
        if let Ok(d) = read_depth(path, [rows, cols]) {
            assert_eq!(d.len(), rows * cols);
        }
        if let Ok(l) = read_semantic(path, [rows, cols]) {
            assert_eq!(l.len(), rows * cols);
            assert!(l.iter().all(|&c| c <= 40), "labels above 40");
        }
    }
});
