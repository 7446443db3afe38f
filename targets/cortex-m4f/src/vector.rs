//! Zero-copy reader of the cross-architecture test vector `vector/frames.bin` (no alloc).
//!
//! The vector and `vector/expected_crc.txt` are written on the host by
//!
//! ```sh
//! cargo run --release -p sndt-host --bin sndt -- testvector --out targets/cortex-m4f/vector
//! ```
//!
//! The format (version 1, little-endian) is specified in `host/src/embedded/testvector.rs`: a 56-byte
//! header (magic `SNDTVEC\0`, version, frame/probe counts, map capacities, camera, cell
//! size), 8-byte probe records `(frame, col, row, 0)` and frames of a 3x3 rotation and a
//! translation (f32), `W H` planar depths (f32) and `W H` labels (u8).

use sndt_core::Pinhole;

const MAGIC: &[u8; 8] = b"SNDTVEC\0";
const VERSION: u16 = 1;
const HEADER_BYTES: usize = 56;
const PROBE_BYTES: usize = 8;
const POSE_BYTES: usize = 48;

/// Why a vector was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum VectorError {
    /// Shorter than its header, or its length disagrees with the header.
    Size,
    /// Wrong magic bytes.
    Magic,
    /// A version this firmware cannot read.
    Version,
    /// Map capacities differ from the firmware's map.
    Capacity,
    /// A depth image is not 4-byte aligned (the vector must be embedded aligned).
    Align,
}

/// One frame, borrowed from the vector (in flash).
pub struct Frame<'a> {
    /// Camera-to-world rotation, row-major (OpenCV camera axes, world z up).
    pub rotation: [f32; 9],
    /// Camera position, metres.
    pub translation: [f32; 3],
    /// Planar depth, metres (0 = no return).
    pub depth: &'a [f32],
    /// Labels: 0 void, 1..=40 NYU40.
    pub labels: &'a [u8],
}

/// A parsed vector.
pub struct Vector<'a> {
    bytes: &'a [u8],
    /// The camera of every frame.
    pub camera: Pinhole,
    /// Map cell size, metres (the other config fields are `Config::DEFAULT`).
    pub cell_size: f32,
    /// Number of frames.
    pub frames: usize,
    /// Number of probes.
    pub probes: usize,
}

/// The little-endian `N` bytes at `o`; zeros past the end (lengths are checked when the
/// vector is parsed, so that never happens, and a read past the end must not halt).
fn bytes_at<const N: usize>(b: &[u8], o: usize) -> [u8; N] {
    b.get(o..o.saturating_add(N))
        .and_then(|s| s.try_into().ok())
        .unwrap_or([0; N])
}

fn u16_at(b: &[u8], o: usize) -> u16 {
    u16::from_le_bytes(bytes_at(b, o))
}

fn u32_at(b: &[u8], o: usize) -> u32 {
    u32::from_le_bytes(bytes_at(b, o))
}

fn f32_at(b: &[u8], o: usize) -> f32 {
    f32::from_bits(u32_at(b, o))
}

impl<'a> Vector<'a> {
    /// Checks the header against the firmware's map `Map<voxels, blocks, classes>` and the
    /// total length.
    pub fn parse(
        bytes: &'a [u8],
        voxels: usize,
        blocks: usize,
        classes: usize,
    ) -> Result<Self, VectorError> {
        if bytes.len() < HEADER_BYTES {
            return Err(VectorError::Size);
        }
        if bytes.get(..8) != Some(&MAGIC[..]) {
            return Err(VectorError::Magic);
        }
        if u16_at(bytes, 8) != VERSION {
            return Err(VectorError::Version);
        }
        let (frames, probes) = (u16_at(bytes, 10) as usize, u16_at(bytes, 12) as usize);
        if (
            u16_at(bytes, 14) as usize,
            u32_at(bytes, 16) as usize,
            u32_at(bytes, 20) as usize,
        ) != (classes, voxels, blocks)
        {
            return Err(VectorError::Capacity);
        }
        let camera = Pinhole {
            width: u32_at(bytes, 24),
            height: u32_at(bytes, 28),
            fx: f32_at(bytes, 32),
            fy: f32_at(bytes, 36),
            cx: f32_at(bytes, 40),
            cy: f32_at(bytes, 44),
        };
        let n = camera.width as usize * camera.height as usize;
        let len = HEADER_BYTES + PROBE_BYTES * probes + frames * (POSE_BYTES + 5 * n);
        if !n.is_multiple_of(4) || bytes.len() != len {
            return Err(VectorError::Size);
        }
        Ok(Vector {
            bytes,
            camera,
            cell_size: f32_at(bytes, 48),
            frames,
            probes,
        })
    }

    /// Probe `i`: `(frame, col, row)`.
    pub fn probe(&self, i: usize) -> Option<(usize, u32, u32)> {
        if i >= self.probes {
            return None;
        }
        let o = HEADER_BYTES + PROBE_BYTES * i;
        let b = self.bytes;
        Some((
            u16_at(b, o) as usize,
            u16_at(b, o + 2) as u32,
            u16_at(b, o + 4) as u32,
        ))
    }

    /// Frame `k`, with its depth image borrowed as `&[f32]` (no copy).
    pub fn frame(&self, k: usize) -> Result<Frame<'a>, VectorError> {
        if k >= self.frames {
            return Err(VectorError::Size);
        }
        let n = self.camera.width as usize * self.camera.height as usize;
        let b = self.bytes;
        let o = HEADER_BYTES + PROBE_BYTES * self.probes + k * (POSE_BYTES + 5 * n);
        let rotation = core::array::from_fn(|i| f32_at(b, o + 4 * i));
        let translation = core::array::from_fn(|i| f32_at(b, o + 36 + 4 * i));
        let d = o + POSE_BYTES;
        // Both targets are little-endian, so the bytes are the f32 values; bytemuck checks
        // the alignment (Err instead of undefined behaviour).
        let depth = b.get(d..d + 4 * n).ok_or(VectorError::Size)?;
        let depth: &[f32] = bytemuck::try_cast_slice(depth).map_err(|_| VectorError::Align)?;
        Ok(Frame {
            rotation,
            translation,
            depth,
            labels: b.get(d + 4 * n..d + 5 * n).ok_or(VectorError::Size)?,
        })
    }
}

/// Parses `0x1234abcd` (surrounding whitespace ignored), the format of `expected_crc.txt`.
pub fn parse_crc(s: &str) -> Option<u32> {
    let hex = s.trim().strip_prefix("0x")?;
    u32::from_str_radix(hex, 16).ok()
}
