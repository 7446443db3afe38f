//! ESANet-style top-3 predictions as NumPy `.npy` files.
//!
//! One file per frame: float32, shape `(3, H, W)`, C or Fortran order. Channel `k` holds the
//! `k`-th best class of every pixel, each value encoding class and score together as
//! `class + min(score, 0.9999)` with `class` the NYU40 id `1..=40` (the network's 0-based
//! output index plus one; the network never predicts void). Decoding is therefore
//! `class = floor(v)`, `score = v - class`.
//!
//! The channels are kept in file order (the network's ranking): the decoded scores can be
//! off by one f32 ulp of `class + score`, which may swap near-ties, so they are not
//! re-sorted.

use crate::dataset::frame::TopK;
use anyhow::{bail, Context, Result};
use npyz::WriterBuilder;
use std::fmt::Display;
use std::fs::File;
use std::io::{BufReader, BufWriter, Read};
use std::path::Path;

/// Largest score that can be encoded: `class + score` must stay below `class + 1`.
pub const MAX_SCORE: f32 = 0.9999;

/// Encodes one `(class, score)` pair as ESANet does: `class + min(score, 0.9999)`, with the
/// score clamped to `0..=0.9999`. `None` when `class` is not `1..=40` or the score is NaN.
///
/// ```
/// use sndt_host::dataset::npy::encode;
/// assert_eq!(encode(3, 0.5), Some(3.5));
/// assert_eq!(encode(40, 1.0), Some(40.0 + 0.9999));
/// assert_eq!(encode(0, 0.5), None);
/// assert_eq!(encode(41, 0.5), None);
/// ```
pub fn encode(class: u8, score: f32) -> Option<f32> {
    if !(1..=40).contains(&class) || score.is_nan() {
        return None;
    }
    Some(class as f32 + score.clamp(0.0, MAX_SCORE))
}

/// Decodes one value: `class = floor(v)` (must be `1..=40`), `score = v - class`. `None`
/// for values outside `1.0..41.0` (including NaN and infinities).
///
/// ```
/// use sndt_host::dataset::npy::decode;
/// assert_eq!(decode(3.5), Some((3, 0.5)));
/// assert_eq!(decode(1.0), Some((1, 0.0)));
/// assert_eq!(decode(0.5), None); // class 0 (void) is never predicted
/// assert_eq!(decode(41.0), None);
/// ```
pub fn decode(v: f32) -> Option<(u8, f32)> {
    if !(1.0..41.0).contains(&v) {
        return None;
    }
    let class = v.floor();
    Some((class as u8, v - class))
}

/// Reads a `(3, height, width)` float32 prediction file into top-3 classes and scores per
/// pixel (row-major, best first as stored).
///
/// Errors name the file: unreadable or truncated file, a dtype other than float32, a shape
/// other than `(3, height, width)`, or a value outside `1.0..41.0`.
///
/// ```
/// # let dir = std::env::temp_dir().join(format!("sndt-npy-doc-{}", std::process::id()));
/// # std::fs::create_dir_all(&dir).unwrap();
/// use sndt_host::dataset::{npy, TopK};
/// let path = dir.join("frame.npy");
/// let topk = TopK { classes: vec![[2, 1, 5]], scores: vec![[0.75, 0.125, 0.0625]] };
/// npy::write_topk(&path, &topk, 1, 1).unwrap();
/// assert_eq!(npy::read_topk(&path, 1, 1).unwrap(), topk);
/// assert!(npy::read_topk(&path, 2, 1).is_err()); // wrong shape
/// # std::fs::remove_dir_all(&dir).unwrap();
/// ```
pub fn read_topk(path: &Path, width: u32, height: u32) -> Result<TopK> {
    let shown = path.display();
    let file = File::open(path).with_context(|| format!("{shown}: opening predictions"))?;
    read_topk_from(BufReader::new(file), &shown, width, height)
}

/// [`read_topk`] of a `.npy` image from any reader (bytes in memory, for example), its
/// errors naming the source `shown`.
///
/// ```
/// use sndt_host::dataset::npy::read_topk_from;
/// assert!(read_topk_from(&b"not npy"[..], &"memory", 1, 1).is_err());
/// ```
pub fn read_topk_from(
    src: impl Read,
    shown: &dyn Display,
    width: u32,
    height: u32,
) -> Result<TopK> {
    let src = check_header_nesting(src, shown)?;
    let npy =
        npyz::NpyFile::new(src).with_context(|| format!("{shown}: not a readable .npy file"))?;
    let dtype = npy.dtype();
    match &dtype {
        npyz::DType::Plain(t) if t.type_char() == npyz::TypeChar::Float && t.size_field() == 4 => {}
        npyz::DType::Plain(t) => bail!("{shown}: dtype {t}, expected float32 (<f4)"),
        other => bail!("{shown}: dtype {other:?}, expected float32 (<f4)"),
    }
    let (w, h) = (width as u64, height as u64);
    if npy.shape() != [3, h, w] {
        bail!(
            "{shown}: shape {:?}, expected (3, {height}, {width})",
            npy.shape()
        );
    }
    let fortran = npy.order() == npyz::Order::Fortran;
    let values: Vec<f32> = npy
        .into_vec()
        .with_context(|| format!("{shown}: reading {} float32 values (truncated?)", 3 * w * h))?;
    let n = (w * h) as usize;
    if values.len() != 3 * n {
        bail!("{shown}: {} values, expected {}", values.len(), 3 * n);
    }
    let mut out = TopK {
        classes: vec![[0; 3]; n],
        scores: vec![[0.0; 3]; n],
    };
    for k in 0..3 {
        for i in 0..n {
            let idx = if fortran {
                // element (k, row, col) lives at k + 3 * (row + h * col)
                let (row, col) = (i / width as usize, i % width as usize);
                k + 3 * (row + height as usize * col)
            } else {
                k * n + i
            };
            let v = values[idx];
            let Some((class, score)) = decode(v) else {
                bail!(
                    "{shown}: value {v} at channel {k}, pixel ({}, {}) is outside 1..41 \
                     (class = floor(v) must be an NYU40 id 1..=40)",
                    i % width as usize,
                    i / width as usize
                );
            };
            out.classes[i][k] = class;
            out.scores[i][k] = score;
        }
    }
    Ok(out)
}

/// Deepest bracket nesting accepted in a `.npy` header; a float32 `(3, H, W)` file's has 2
/// (`{'shape': (3, H, W)}`).
const MAX_HEADER_NESTING: usize = 8;

/// Refuses a header nested deeper than [`MAX_HEADER_NESTING`] before npyz parses it: its
/// parser takes time exponential in the depth (a 200-byte header with 40 `[` ran for
/// minutes). Returns the source with the bytes it read put back in front.
fn check_header_nesting(mut src: impl Read, shown: &dyn Display) -> Result<impl Read> {
    // Magic (6), version (2), length (2 or 4), then the header, of at most 65535 bytes in
    // version 1 and in practice in all versions.
    let mut head = Vec::new();
    src.by_ref()
        .take(12 + 65535)
        .read_to_end(&mut head)
        .with_context(|| format!("{shown}: reading the .npy header"))?;
    let (mut depth, mut deepest) = (0usize, 0usize);
    for &b in head.iter().skip(10).take_while(|&&b| b != b'\n') {
        match b {
            b'[' | b'(' | b'{' => depth += 1,
            b']' | b')' | b'}' => depth = depth.saturating_sub(1),
            _ => {}
        }
        deepest = deepest.max(depth);
    }
    if deepest > MAX_HEADER_NESTING {
        bail!("{shown}: .npy header nested {deepest} deep (at most {MAX_HEADER_NESTING})");
    }
    Ok(std::io::Cursor::new(head).chain(src))
}

/// Writes `topk` as a C-order float32 `(3, height, width)` file, the exact inverse of
/// [`read_topk`] up to f32 rounding of `class + score` (see [`encode`]).
///
/// Errors name the file when a class is not `1..=40` (unused entries cannot be encoded),
/// a score is NaN, the pixel count is not `width * height`, or writing fails.
///
/// ```
/// # let dir = std::env::temp_dir().join(format!("sndt-npy-doc-w-{}", std::process::id()));
/// # std::fs::create_dir_all(&dir).unwrap();
/// use sndt_host::dataset::{npy, TopK};
/// let topk = TopK { classes: vec![[0, 1, 2]], scores: vec![[0.5; 3]] };
/// assert!(npy::write_topk(&dir.join("bad.npy"), &topk, 1, 1).is_err()); // class 0
/// # std::fs::remove_dir_all(&dir).unwrap();
/// ```
pub fn write_topk(path: &Path, topk: &TopK, width: u32, height: u32) -> Result<()> {
    crate::atomic::write_atomic(path, |tmp| write_topk_to(tmp, topk, width, height))
}

/// What [`write_topk`] writes, into `path` directly.
fn write_topk_to(path: &Path, topk: &TopK, width: u32, height: u32) -> Result<()> {
    let shown = path.display();
    let n = width as usize * height as usize;
    if topk.classes.len() != n || topk.scores.len() != n {
        bail!(
            "{shown}: predictions have {} classes / {} scores, image has {n} pixels",
            topk.classes.len(),
            topk.scores.len()
        );
    }
    let mut values = Vec::with_capacity(3 * n);
    for k in 0..3 {
        for (i, (c, s)) in topk.classes.iter().zip(&topk.scores).enumerate() {
            let Some(v) = encode(c[k], s[k]) else {
                bail!(
                    "{shown}: pixel {i} entry {k}: class {} / score {} cannot be encoded \
                     (class must be 1..=40, score not NaN)",
                    c[k],
                    s[k]
                );
            };
            values.push(v);
        }
    }
    let file = File::create(path).with_context(|| format!("{shown}: creating"))?;
    let mut writer = npyz::WriteOptions::<f32>::new()
        .default_dtype()
        .shape(&[3, height as u64, width as u64])
        .writer(BufWriter::new(file))
        .begin_nd()
        .with_context(|| format!("{shown}: writing header"))?;
    writer
        .extend(values)
        .with_context(|| format!("{shown}: writing values"))?;
    writer
        .finish()
        .with_context(|| format!("{shown}: finishing"))?;
    Ok(())
}
