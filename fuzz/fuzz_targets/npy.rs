//! The top-3 prediction reader (`.npy`, float32, shape `(3, H, W)`) on arbitrary bytes.
//! The first two input bytes give the expected width and height (1..=16) so that the
//! fuzzer can match a file's shape; the rest is the file.
//!
//! An accepted file gives one entry per pixel, classes `1..=40` and scores in `[0, 1)`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sndt_host::dataset::npy::read_topk_from;

fuzz_target!(|data: &[u8]| {
    let [w, h, file @ ..] = data else {
        return;
    };
    let (w, h) = (1 + (*w as u32 % 16), 1 + (*h as u32 % 16));
    let Ok(topk) = read_topk_from(file, &"fuzz.npy", w, h) else {
        return;
    };
    let n = (w * h) as usize;
    assert_eq!((topk.classes.len(), topk.scores.len()), (n, n));
    for (c, s) in topk.classes.iter().zip(&topk.scores) {
        assert!(c.iter().all(|c| (1..=40).contains(c)), "classes {c:?}");
        assert!(s.iter().all(|s| (0.0..1.0).contains(s)), "scores {s:?}");
    }
});
