//! The cross-architecture test vector: a few small labelled depth frames of a synthetic
//! scene, the map the firmware builds from them, and that map's snapshot CRC.
//!
//! The committed vector `targets/cortex-m4f/vector/frames.bin` and its expected CRC
//! `targets/cortex-m4f/vector/expected_crc.txt` are written by
//!
//! ```sh
//! cargo run --release -p sndt-host --bin sndt -- testvector --out targets/cortex-m4f/vector
//! ```
//!
//! and checked with `sndt testvector --check targets/cortex-m4f/vector/frames.bin`. The
//! firmware (`targets/cortex-m4f`, Cortex-M4F in QEMU), `cargo test` on x86-64 and the C
//! API's `vector_crc` program on aarch64 (qemu-aarch64, `scripts/aarch64.sh`) all integrate
//! these frames into a `Map<4096, 512, 40>` and must arrive at the same CRC: a bit-identical
//! map on every target.
//!
//! Rendering uses only `+ - * /` and `sqrt` (IEEE 754 exact), so regenerating the vector
//! reproduces the committed bytes (a test checks this).
//!
//! # Format (version 1, all numbers little-endian)
//!
//! | offset | bytes | field |
//! |---|---|---|
//! | 0 | 8 | magic `b"SNDTVEC\0"` |
//! | 8 | 2 | version (u16) = 1 |
//! | 10 | 2 | frame count `F` (u16) |
//! | 12 | 2 | probe count `P` (u16) |
//! | 14 | 2 | map classes (u16), 40 |
//! | 16 | 4 | map voxel capacity (u32), 4096 |
//! | 20 | 4 | map block capacity (u32), 512 |
//! | 24 | 8 | image width `W`, height `H` (u32 each) |
//! | 32 | 16 | pinhole `fx, fy, cx, cy` (f32 each) |
//! | 48 | 4 | map cell size in metres (f32); every other `Config` field is `Config::DEFAULT` |
//! | 52 | 4 | reserved, 0 |
//! | 56 | 8 P | probes: `frame, col, row, 0` (u16 each): pixels to ray cast in the map |
//! | ... | F x (48 + 5 W H) | frames (below) |
//!
//! A frame: camera-to-world rotation, 9 x f32 row-major (OpenCV camera axes: x right,
//! y down, z forward; world z up), translation 3 x f32 (metres), then `W H` planar depths
//! (f32 metres, 0 = no return), then `W H` labels (u8: 0 void, 1..=40 NYU40), row-major.
//! `W H` is a multiple of 4, so every depth image starts 4-byte aligned.

use crate::atomic::write_bytes;
use crate::embedded::view::{ViewRender, VIEW_HEIGHT, VIEW_WIDTH};
use anyhow::{bail, ensure, Context, Result};
use sndt_core::{
    pose_from_matrix, Config, Depth, DepthImage, DepthKind, FrameReport, Isometry3, LabelImage,
    Map, Matrix3, Pinhole, Point3, Vector3,
};

/// File magic.
pub const MAGIC: [u8; 8] = *b"SNDTVEC\0";
/// Format version.
pub const VERSION: u16 = 1;
/// Header bytes (before the probes).
pub const HEADER_BYTES: usize = 56;
/// Bytes of one probe record.
pub const PROBE_BYTES: usize = 8;
/// Bytes of a frame's pose (rotation 3x3 + translation, f32).
pub const POSE_BYTES: usize = 48;

/// Voxel capacity of the map every target builds from the vector.
pub const VOXELS: usize = 4096;
/// Block capacity of that map.
pub const BLOCKS: usize = 512;
/// Class count of that map.
pub const CLASSES: usize = 40;
/// The map every target builds: 4096 surface voxels, 512 blocks, 40 classes (476 KiB).
pub type VectorMap = Map<VOXELS, BLOCKS, CLASSES>;

/// The camera of the vector: 160 x 120, about 67 degrees horizontal field of view.
pub const CAMERA: Pinhole = Pinhole {
    fx: 120.0,
    fy: 120.0,
    cx: 80.0,
    cy: 60.0,
    width: 160,
    height: 120,
};

/// Cell size of the vector's map (metres).
pub const CELL: f32 = 0.10;

/// NYU40 ids of the scene.
const WALL: u8 = 1;
const FLOOR: u8 = 2;
const CABINET: u8 = 3;
const CHAIR: u8 = 5;
const TABLE: u8 = 7;
const DOOR: u8 = 8;
const PICTURE: u8 = 11;

/// An axis-aligned labelled box: min, max, NYU40 class.
type LBox = ([f32; 3], [f32; 3], u8);

/// The scene: a room corner seen from inside (z up, metres). A wall at x = 3 with a door
/// and a picture, side walls at y = -2 and y = 3, floor, a table, a chair and a cabinet.
const SCENE: [LBox; 10] = [
    ([-1.0, -2.1, -0.1], [3.1, 3.1, 0.0], FLOOR),
    ([3.0, -2.1, 0.0], [3.1, 3.1, 2.6], WALL),
    ([-1.0, -2.1, 0.0], [3.1, -2.0, 2.6], WALL),
    ([-1.0, 3.0, 0.0], [3.1, 3.1, 2.6], WALL),
    ([2.96, 0.6, 0.0], [3.0, 1.4, 2.0], DOOR),
    ([2.98, -1.2, 1.3], [3.0, -0.6, 1.8], PICTURE),
    ([1.8, -0.8, 0.7], [2.4, 0.0, 0.75], TABLE),
    ([2.0, -0.5, 0.0], [2.2, -0.3, 0.7], TABLE),
    ([1.5, 0.3, 0.0], [1.9, 0.7, 0.45], CHAIR),
    ([2.5, -1.9, 0.0], [2.95, -1.2, 0.9], CABINET),
];

/// Camera poses: eye (metres), yaw (cos, sin; 0 = looking along +x), pitch down (cos, sin).
/// Angles are given by their cosine and sine so that no transcendental function is needed.
#[allow(clippy::type_complexity)]
const POSES: [([f32; 3], (f64, f64), (f64, f64)); 4] = [
    // Towards the door wall: yaw 0, pitch 0.25 rad.
    (
        [0.0, 0.0, 1.2],
        (1.0, 0.0),
        (0.968_912_421_710_644_7, 0.247_403_959_254_522_94),
    ),
    // Left, to the door and the left wall: yaw +0.6, pitch 0.2.
    (
        [0.4, -0.3, 1.2],
        (0.825_335_614_909_678_3, 0.564_642_473_395_035_4),
        (0.980_066_577_841_241_6, 0.198_669_330_795_061_22),
    ),
    // Right, to the side wall and the cabinet: yaw -1.1, pitch 0.3.
    (
        [0.5, 0.5, 1.3],
        (0.453_596_121_425_577_3, -0.891_207_360_061_435_4),
        (0.955_336_489_125_606, 0.295_520_206_661_339_55),
    ),
    // Close to the table and the chair: yaw +0.15, pitch 0.35.
    (
        [0.8, 0.0, 1.0],
        (0.988_771_077_936_042_2, 0.149_438_132_473_599_22),
        (0.939_372_712_847_378_9, 0.342_897_807_455_451_34),
    ),
];

/// Pixels the targets ray cast after integrating: `(frame, col, row)`, one on each class
/// of the scene (door, picture, chair, floor, cabinet, wall, table), away from edges.
const PROBES: [(u16, u16, u16); 8] = [
    (0, 39, 36),
    (0, 117, 18),
    (0, 45, 96),
    (1, 30, 100),
    (2, 33, 50),
    (2, 100, 30),
    (3, 129, 45),
    (3, 90, 20),
];

/// One frame of the vector.
#[derive(Clone, Debug, PartialEq)]
pub struct VectorFrame {
    /// Camera-to-world rotation, row-major.
    pub rotation: [f32; 9],
    /// Camera position, metres.
    pub translation: [f32; 3],
    /// Planar depth, metres (0 = no return), row-major.
    pub depth: Vec<f32>,
    /// Labels (0 void, 1..=40), row-major.
    pub labels: Vec<u8>,
}

impl VectorFrame {
    /// The pose, checked by the core exactly as the firmware does it.
    pub fn pose(&self) -> Result<Isometry3<f32>> {
        let r = &self.rotation;
        let m = Matrix3::new(r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8]);
        let t = Vector3::new(
            self.translation[0],
            self.translation[1],
            self.translation[2],
        );
        pose_from_matrix(&m, &t).map_err(|e| anyhow::anyhow!("invalid pose: {e}"))
    }
}

/// A parsed test vector.
#[derive(Clone, Debug, PartialEq)]
pub struct TestVector {
    /// The camera of every frame.
    pub camera: Pinhole,
    /// Map configuration (`Config::DEFAULT` with the vector's cell size).
    pub config: Config,
    /// Pixels to ray cast: `(frame, col, row)`.
    pub probes: Vec<(u16, u16, u16)>,
    /// The frames, in integration order.
    pub frames: Vec<VectorFrame>,
}

/// Camera-to-world rotation (row-major) of a camera with yaw `(c, s)` about world z and
/// pitch `(cp, sp)` downwards; columns are the camera's right, down and forward axes.
fn rotation(yaw: (f64, f64), pitch: (f64, f64)) -> [f32; 9] {
    let ((c, s), (cp, sp)) = (yaw, pitch);
    let fwd = [c * cp, s * cp, -sp];
    let right = [s, -c, 0.0];
    let down = [-sp * c, -sp * s, -cp];
    let mut r = [0f32; 9];
    for i in 0..3 {
        r[3 * i] = right[i] as f32;
        r[3 * i + 1] = down[i] as f32;
        r[3 * i + 2] = fwd[i] as f32;
    }
    r
}

/// Distance along the unit ray to the nearest box of the scene, and its class.
fn cast(origin: &[f32; 3], dir: &[f32; 3]) -> Option<(f32, u8)> {
    let mut best: Option<(f32, u8)> = None;
    'boxes: for (min, max, label) in SCENE.iter() {
        let (mut t0, mut t1) = (0.0f32, f32::INFINITY);
        for a in 0..3 {
            if dir[a].abs() < 1e-12 {
                if origin[a] < min[a] || origin[a] > max[a] {
                    continue 'boxes;
                }
                continue;
            }
            let inv = 1.0 / dir[a];
            let (ta, tb) = ((min[a] - origin[a]) * inv, (max[a] - origin[a]) * inv);
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
            if t0 > t1 {
                continue 'boxes;
            }
        }
        if best.is_none_or(|(t, _)| t0 < t) {
            best = Some((t0, *label));
        }
    }
    best
}

/// Renders the scene exactly (ray against box): planar depth (0 = no hit) and label of
/// every pixel of `cam` from a camera-to-world `rotation` (row-major) at `eye`. This
/// ground truth is what the vector's frames are, and what a render of the map is checked
/// against.
pub fn render_scene(rotation: &[f32; 9], eye: &[f32; 3], cam: &Pinhole) -> (Vec<f32>, Vec<u8>) {
    let n = (cam.width * cam.height) as usize;
    let (mut depth, mut labels) = (vec![0f32; n], vec![0u8; n]);
    for row in 0..cam.height {
        for col in 0..cam.width {
            let r = cam.ray(col, row);
            let norm = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
            let u = [r[0] / norm, r[1] / norm, r[2] / norm];
            let m = rotation;
            let d = [
                m[0] * u[0] + m[1] * u[1] + m[2] * u[2],
                m[3] * u[0] + m[4] * u[1] + m[5] * u[2],
                m[6] * u[0] + m[7] * u[1] + m[8] * u[2],
            ];
            if let Some((t, l)) = cast(eye, &d) {
                let i = (row * cam.width + col) as usize;
                depth[i] = t / norm; // planar depth: the ray has unit z in the camera
                labels[i] = l;
            }
        }
    }
    (depth, labels)
}

/// The built-in vector: 4 frames of 160 x 120 of the room corner, 8 probes.
pub fn generate() -> TestVector {
    let frames = POSES
        .iter()
        .map(|(eye, yaw, pitch)| {
            let rotation = rotation(*yaw, *pitch);
            let (depth, labels) = render_scene(&rotation, eye, &CAMERA);
            VectorFrame {
                rotation,
                translation: *eye,
                depth,
                labels,
            }
        })
        .collect();
    TestVector {
        camera: CAMERA,
        config: Config::with_cell_size(CELL),
        probes: PROBES.to_vec(),
        frames,
    }
}

impl TestVector {
    /// Frame `f`'s depth image as the firmware integrates it: planar depth in metres, top-1
    /// labels, every pixel, the vector's camera.
    pub fn depth_image<'a>(&self, f: &'a VectorFrame) -> DepthImage<'a> {
        DepthImage {
            camera: self.camera,
            depth: Depth::Metres(&f.depth),
            kind: DepthKind::Planar,
            labels: LabelImage::Top1(&f.labels),
            stride: 1,
        }
    }

    /// The vector in the binary format of this module.
    pub fn to_bytes(&self) -> Vec<u8> {
        let c = &self.camera;
        let n = (c.width * c.height) as usize;
        let mut out = Vec::with_capacity(
            HEADER_BYTES
                + PROBE_BYTES * self.probes.len()
                + self.frames.len() * (POSE_BYTES + 5 * n),
        );
        out.extend_from_slice(&MAGIC);
        out.extend_from_slice(&VERSION.to_le_bytes());
        out.extend_from_slice(&(self.frames.len() as u16).to_le_bytes());
        out.extend_from_slice(&(self.probes.len() as u16).to_le_bytes());
        out.extend_from_slice(&(CLASSES as u16).to_le_bytes());
        out.extend_from_slice(&(VOXELS as u32).to_le_bytes());
        out.extend_from_slice(&(BLOCKS as u32).to_le_bytes());
        out.extend_from_slice(&c.width.to_le_bytes());
        out.extend_from_slice(&c.height.to_le_bytes());
        for x in [c.fx, c.fy, c.cx, c.cy, self.config.cell_size] {
            out.extend_from_slice(&x.to_le_bytes());
        }
        out.extend_from_slice(&0u32.to_le_bytes());
        for &(f, col, row) in &self.probes {
            for x in [f, col, row, 0] {
                out.extend_from_slice(&x.to_le_bytes());
            }
        }
        for f in &self.frames {
            for x in f.rotation.iter().chain(&f.translation).chain(&f.depth) {
                out.extend_from_slice(&x.to_le_bytes());
            }
            out.extend_from_slice(&f.labels);
        }
        out
    }

    /// Parses and checks a vector (sizes, capacities, pose validity, labels).
    pub fn parse(bytes: &[u8]) -> Result<TestVector> {
        let header = Header::parse(bytes)?;
        let n = header.camera.width as usize * header.camera.height as usize;
        let frame_bytes = POSE_BYTES + 5 * n;
        let want = HEADER_BYTES + PROBE_BYTES * header.probes + header.frames * frame_bytes;
        ensure!(
            bytes.len() == want,
            "test vector: {} bytes, its header says {want}",
            bytes.len()
        );
        let le = LittleEndian(bytes);
        let probes = (0..header.probes)
            .map(|p| header.parse_probe(le, HEADER_BYTES + PROBE_BYTES * p))
            .collect::<Result<Vec<_>>>()?;
        let first_frame = HEADER_BYTES + PROBE_BYTES * header.probes;
        let frames = (0..header.frames)
            .map(|k| parse_frame(le, first_frame + k * frame_bytes, n, k))
            .collect::<Result<Vec<_>>>()?;
        Ok(TestVector {
            camera: header.camera,
            config: header.config,
            probes,
            frames,
        })
    }
}

/// Little-endian numbers at byte offsets of a buffer whose length has been checked.
#[derive(Clone, Copy)]
struct LittleEndian<'a>(&'a [u8]);

impl LittleEndian<'_> {
    fn u16_at(self, o: usize) -> u16 {
        u16::from_le_bytes([self.0[o], self.0[o + 1]])
    }

    fn u32_at(self, o: usize) -> u32 {
        u32::from_le_bytes(self.0[o..o + 4].try_into().unwrap())
    }

    fn f32_at(self, o: usize) -> f32 {
        f32::from_bits(self.u32_at(o))
    }
}

/// The fixed-size header of a vector, checked against this build's map and for a usable
/// camera and cell size.
struct Header {
    frames: usize,
    probes: usize,
    camera: Pinhole,
    config: Config,
}

impl Header {
    fn parse(bytes: &[u8]) -> Result<Header> {
        ensure!(
            bytes.len() >= HEADER_BYTES,
            "test vector: {} bytes, shorter than its header",
            bytes.len()
        );
        ensure!(bytes[..8] == MAGIC, "test vector: bad magic");
        let le = LittleEndian(bytes);
        ensure!(
            le.u16_at(8) == VERSION,
            "test vector: version {}, expected {VERSION}",
            le.u16_at(8)
        );
        let (frames, probes) = (le.u16_at(10) as usize, le.u16_at(12) as usize);
        let caps = (
            le.u16_at(14) as usize,
            le.u32_at(16) as usize,
            le.u32_at(20) as usize,
        );
        ensure!(
            caps == (CLASSES, VOXELS, BLOCKS),
            "test vector: map Map<{}, {}, {}>, this build has Map<{VOXELS}, {BLOCKS}, {CLASSES}>",
            caps.1,
            caps.2,
            caps.0
        );
        let camera = Pinhole {
            width: le.u32_at(24),
            height: le.u32_at(28),
            fx: le.f32_at(32),
            fy: le.f32_at(36),
            cx: le.f32_at(40),
            cy: le.f32_at(44),
        };
        let n = camera.width as usize * camera.height as usize;
        ensure!(
            n > 0
                && n <= sndt_core::MAX_FRAME_POINTS
                && n.is_multiple_of(4)
                && [camera.fx, camera.fy, camera.cx, camera.cy]
                    .iter()
                    .all(|x| x.is_finite())
                && camera.fx > 0.0
                && camera.fy > 0.0,
            "test vector: bad camera {camera:?}"
        );
        let config = Config::with_cell_size(le.f32_at(48));
        config.validate().map_err(|e| {
            anyhow::anyhow!(
                "test vector: bad cell size {} (byte 48): {e}",
                config.cell_size
            )
        })?;
        Ok(Header {
            frames,
            probes,
            camera,
            config,
        })
    }

    /// The probe record at byte `o`: `(frame, col, row)`, which must lie in the frames.
    fn parse_probe(&self, le: LittleEndian, o: usize) -> Result<(u16, u16, u16)> {
        let p = (le.u16_at(o), le.u16_at(o + 2), le.u16_at(o + 4));
        ensure!(
            (p.0 as usize) < self.frames
                && (p.1 as u32) < self.camera.width
                && (p.2 as u32) < self.camera.height,
            "test vector: probe {p:?} outside the frames"
        );
        Ok(p)
    }
}

/// Frame `k` of `n` pixels at byte `o`, with its labels and pose checked.
fn parse_frame(le: LittleEndian, o: usize, n: usize, k: usize) -> Result<VectorFrame> {
    let rotation: [f32; 9] = std::array::from_fn(|i| le.f32_at(o + 4 * i));
    let translation: [f32; 3] = std::array::from_fn(|i| le.f32_at(o + 36 + 4 * i));
    let depth_at = o + POSE_BYTES;
    let depth = (0..n).map(|i| le.f32_at(depth_at + 4 * i)).collect();
    let labels_at = depth_at + 4 * n;
    let labels = le.0[labels_at..labels_at + n].to_vec();
    if let Some(bad) = labels.iter().find(|&&l| l as usize > CLASSES) {
        bail!("test vector: frame {k}: label {bad} above {CLASSES}");
    }
    let f = VectorFrame {
        rotation,
        translation,
        depth,
        labels,
    };
    f.pose()
        .with_context(|| format!("test vector: frame {k}"))?;
    Ok(f)
}

/// A probe's outcome: the pixel's ground truth and what the map's ray cast found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeResult {
    /// `(frame, col, row)`.
    pub pixel: (u16, u16, u16),
    /// Ground-truth distance along the ray (metres) and class.
    pub expected: (f32, u8),
    /// The map's hit: distance and class.
    pub hit: Option<(f32, u8)>,
}

impl ProbeResult {
    /// Distance tolerance of a probe, metres (1.5 cells at 10 cm).
    pub const TOLERANCE: f32 = 0.15;

    /// The hit is within [`ProbeResult::TOLERANCE`] of the ground truth, with its class.
    pub fn ok(&self) -> bool {
        self.hit.is_some_and(|(t, c)| {
            (t - self.expected.0).abs() < Self::TOLERANCE && c == self.expected.1
        })
    }
}

/// What integrating a vector gives.
#[derive(Clone, Debug, PartialEq)]
pub struct VectorRun {
    /// One report per frame.
    pub reports: Vec<FrameReport>,
    /// Surface voxels and blocks at the end.
    pub voxels: usize,
    /// Occupancy blocks at the end.
    pub blocks: usize,
    /// Voxels and blocks evicted in total.
    pub evicted: (u64, u64),
    /// The probes.
    pub probes: Vec<ProbeResult>,
    /// The map's snapshot CRC-32 (`Map::checksum`).
    pub crc: u32,
    /// The 64 x 48 view from the last frame's pose ([`crate::embedded::view`]).
    pub view: ViewRender,
}

/// Integrates the vector into a fresh [`VectorMap`] exactly as the firmware does
/// (`integrate_depth`, planar depth, top-1 labels, every pixel), ray casts its probes and
/// returns the map's snapshot CRC with the counts.
pub fn run(v: &TestVector) -> Result<VectorRun> {
    let mut map: Box<VectorMap> =
        crate::mapping::boxed_map(v.config).map_err(|e| anyhow::anyhow!("config: {e}"))?;
    let mut reports = Vec::with_capacity(v.frames.len());
    for (k, f) in v.frames.iter().enumerate() {
        let image = v.depth_image(f);
        let r = map
            .integrate_depth(&f.pose()?, &image)
            .map_err(|e| anyhow::anyhow!("frame {k}: integrate_depth: {e}"))?;
        reports.push(r);
    }
    let probes = v
        .probes
        .iter()
        .map(|&(k, col, row)| probe(&map, v, (k, col, row)))
        .collect::<Result<_>>()?;
    let last = v.frames.last().context("test vector: no frames")?;
    let view = ViewRender::new(&map, &v.camera, &last.pose()?)?;
    let stats = map.stats();
    Ok(VectorRun {
        reports,
        voxels: map.len(),
        blocks: map.block_count(),
        evicted: (stats.voxels_evicted, stats.blocks_evicted),
        probes,
        crc: map.checksum(),
        view,
    })
}

/// Ray casts pixel `(col, row)` of frame `k` in the map (the firmware's computation).
fn probe(map: &VectorMap, v: &TestVector, (k, col, row): (u16, u16, u16)) -> Result<ProbeResult> {
    let f = &v.frames[k as usize];
    let pose = f.pose()?;
    let r = v.camera.ray(col as u32, row as u32);
    let ray = Vector3::new(r[0], r[1], r[2]);
    let i = row as usize * v.camera.width as usize + col as usize;
    let expected = (f.depth[i] * ray.norm(), f.labels[i]);
    let origin = Point3::from(pose.translation.vector);
    let hit = map
        .raycast(&origin, &(pose.rotation * ray), 10.0)
        .map(|h| (h.t, h.class));
    Ok(ProbeResult {
        pixel: (k, col, row),
        expected,
        hit,
    })
}

/// The snapshot CRC the vector's map ends with (what every target must print).
pub fn expected_crc(bytes: &[u8]) -> Result<u32> {
    Ok(run(&TestVector::parse(bytes)?)?.crc)
}

/// Parses `0x1234abcd` (surrounding whitespace ignored), the format of `expected_crc.txt`.
///
/// ```
/// assert_eq!(sndt_host::embedded::testvector::parse_crc(" 0x9bdc524e\n").unwrap(), 0x9bdc524e);
/// ```
pub fn parse_crc(s: &str) -> Result<u32> {
    let s = s.trim();
    let hex = s
        .strip_prefix("0x")
        .with_context(|| format!("CRC {s:?} does not start with 0x"))?;
    u32::from_str_radix(hex, 16).with_context(|| format!("CRC {s:?}"))
}

/// Writes `frames.bin`, `expected_crc.txt` and `expected_render_crc.txt` into `dir`;
/// returns the run.
pub fn write(dir: &std::path::Path) -> Result<VectorRun> {
    let v = generate();
    let bytes = v.to_bytes();
    let run = run(&TestVector::parse(&bytes)?)?;
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let bin = dir.join("frames.bin");
    write_bytes(&bin, &bytes)?;
    let txt = dir.join("expected_crc.txt");
    write_bytes(&txt, format!("{:#010x}\n", run.crc))?;
    let txt = dir.join("expected_render_crc.txt");
    write_bytes(&txt, format!("{:#010x}\n", run.view.crc))?;
    Ok(run)
}

/// A human-readable summary of a run (one line per frame and probe, then the totals and
/// the rendered view, its `render crc 0x........` and a final `crc 0x........` line that
/// scripts parse).
pub fn summary(v: &TestVector, run: &VectorRun) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let c = &v.camera;
    let _ = writeln!(
        s,
        "test vector: {} frames of {}x{}, cell {} m, Map<{VOXELS}, {BLOCKS}, {CLASSES}> ({} bytes)",
        v.frames.len(),
        c.width,
        c.height,
        v.config.cell_size,
        VectorMap::BYTES
    );
    for (k, r) in run.reports.iter().enumerate() {
        let _ = writeln!(
            s,
            "frame {k}: points {}, end voxels {}, rays {}, voxels +{} -{}, blocks +{} -{}, dropped {}/{}",
            r.points_used,
            r.end_voxels,
            r.rays,
            r.voxels_created,
            r.voxels_evicted,
            r.blocks_created,
            r.blocks_evicted,
            r.dropped_points,
            r.dropped_misses
        );
    }
    for p in &run.probes {
        let hit = p
            .hit
            .map_or("no hit".to_string(), |(t, c)| format!("t {t:.3} class {c}"));
        let _ = writeln!(
            s,
            "probe {:?}: {hit} (expected t {:.3} class {}) {}",
            p.pixel,
            p.expected.0,
            p.expected.1,
            if p.ok() { "ok" } else { "WRONG" }
        );
    }
    let _ = writeln!(
        s,
        "voxels {}, blocks {}, evictions: voxels {} blocks {}",
        run.voxels, run.blocks, run.evicted.0, run.evicted.1
    );
    let view = &run.view;
    let shown: Vec<String> = view
        .histogram()
        .iter()
        .map(|(l, n)| format!("{l}:{n}"))
        .collect();
    let _ = writeln!(
        s,
        "view {VIEW_WIDTH}x{VIEW_HEIGHT} from frame {}: {} of {} pixels hit; pixels per label {}",
        run.reports.len().saturating_sub(1),
        view.hits(),
        view.labels.len(),
        shown.join(" ")
    );
    let _ = writeln!(s, "render crc {:#010x}", view.crc);
    let _ = writeln!(s, "crc {:#010x}", run.crc);
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_probes() {
        let v = generate();
        let bytes = v.to_bytes();
        assert_eq!(bytes.len(), HEADER_BYTES + 8 * PROBE_BYTES + 4 * 96_048);
        assert_eq!(TestVector::parse(&bytes).unwrap(), v);
        let run = run(&v).unwrap();
        for p in &run.probes {
            assert!(p.ok(), "{p:?}");
        }
        let mut bad = bytes.clone();
        bad.pop();
        assert!(TestVector::parse(&bad).is_err());
        bad = bytes.clone();
        bad[0] ^= 1;
        assert!(TestVector::parse(&bad).is_err());
    }

    #[test]
    fn parse_names_what_is_wrong() {
        let bytes = generate().to_bytes();
        let error = |edit: &dyn Fn(&mut Vec<u8>)| {
            let mut bad = bytes.clone();
            edit(&mut bad);
            format!("{:#}", TestVector::parse(&bad).unwrap_err())
        };
        assert!(error(&|b| b.truncate(10)).contains("shorter than its header"));
        assert!(error(&|b| b[8] = 2).contains("version 2"));
        assert!(error(&|b| b[14] = 41).contains("Map<4096, 512, 41>"));
        assert!(
            error(&|b| b[32..36].copy_from_slice(&(-1.0f32).to_le_bytes())).contains("bad camera")
        );
        assert!(
            error(&|b| b[48..52].copy_from_slice(&0.0f32.to_le_bytes())).contains(
                "bad cell size 0 (byte 48): invalid config: cell_size must be a number of metres"
            )
        );
        // The first probe's frame index, then the last frame's last label.
        assert!(error(&|b| b[HEADER_BYTES] = 9).contains("probe (9, "));
        assert!(error(&|b| *b.last_mut().unwrap() = 41).contains("frame 3: label 41"));
        // The last frame's first rotation entry.
        let rotation = bytes.len() - (POSE_BYTES + 5 * 160 * 120);
        assert!(
            error(&|b| b[rotation..rotation + 4].copy_from_slice(&f32::NAN.to_le_bytes()))
                .contains("frame 3")
        );
    }

    #[test]
    fn every_label_is_in_range_and_most_pixels_hit() {
        for f in generate().frames {
            let hits = f.depth.iter().filter(|&&d| d > 0.0).count();
            assert!(hits > f.depth.len() * 9 / 10);
            assert!(f.labels.iter().all(|&l| l as usize <= CLASSES));
        }
    }
}
