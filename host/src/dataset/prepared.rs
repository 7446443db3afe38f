//! The prepared layout: the authors' Hypersim preparation (v0.3.1) and our synthetic
//! scenes, read and written.
//!
//! ```text
//! <root>/<split>.txt                                   lines `scene/cam/NNNN` (optional)
//! <root>/<split>/depth/<scene>/<cam>/<NNNN>.png        uint16 planar depth, mm, 0 = invalid
//! <root>/<split>/semantic_40/<scene>/<cam>/<NNNN>.png  uint8, 0 void / 1..=40 (optional dir)
//! <root>/<split>/extrinsics/<scene>/<cam>/<NNNN>.json  {x,y,z,quat_x,quat_y,quat_z,quat_w}
//! <root>/<split>/intrinsics/<scene>/<cam>.json         {fx,fy,cx,cy,width,height} (ours only)
//! <root>/<split>/esanet/<scene>/<cam>/<NNNN>.npy       top-3 predictions (optional dir)
//! ```
//!
//! The extrinsics hold the camera position in metres and the *raw* Hypersim
//! `R_world_from_cam`, whose camera axes are OpenGL's (x right, y up, z backward); the
//! reader turns it into our OpenCV-axes pose with `R_cv = R diag(1, -1, -1)` and the writer
//! undoes that. Without an intrinsics file (the authors' data) the camera is the nominal
//! Hypersim pinhole, or with [`OpenOptions::paper_fy`] the authors' wrong fy.

use crate::atomic::write_atomic;
use crate::dataset::frame::{show_number, Frame, FrameId, Rays};

use crate::dataset::npy;
use crate::dataset::source::Dataset;
use crate::dataset::source::{BadFrame, OpenOptions};
use anyhow::{bail, Context, Result};
use sndt_core::{DepthKind, Isometry3, Pinhole, Translation3, UnitQuaternion};
use std::collections::HashMap;
use std::fmt::Display;
use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Cursor, Seek, Write};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// Nominal Hypersim focal length in pixels (fx = fy), for 1024x768 images.
pub const HYPERSIM_F: f32 = 886.81;
/// The fy the authors' v0.3.1 preparation used for every scene (a bug; see
/// [`OpenOptions::paper_fy`]).
pub const PAPER_FY: f32 = 927.06;

/// The nominal Hypersim pinhole (fx = fy = 886.81, cx = 512, cy = 384, 1024x768), or with
/// `paper_fy` the authors' fy = 927.06.
///
/// ```
/// let cam = sndt_host::dataset::prepared::nominal_camera(true);
/// assert_eq!((cam.fx, cam.fy, cam.width, cam.height), (886.81, 927.06, 1024, 768));
/// assert_eq!(sndt_host::dataset::prepared::nominal_camera(false).fy, 886.81);
/// ```
pub fn nominal_camera(paper_fy: bool) -> Pinhole {
    Pinhole {
        fx: HYPERSIM_F,
        fy: if paper_fy { PAPER_FY } else { HYPERSIM_F },
        cx: 512.0,
        cy: 384.0,
        width: 1024,
        height: 768,
    }
}

/// The `extrinsics/*.json` record: position in metres and the raw Hypersim
/// `R_world_from_cam` (OpenGL camera axes) as a quaternion.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Extrinsics {
    /// Camera position x, metres.
    pub x: f64,
    /// Camera position y, metres.
    pub y: f64,
    /// Camera position z, metres.
    pub z: f64,
    /// Quaternion x of the raw (OpenGL-axes) rotation.
    pub quat_x: f64,
    /// Quaternion y.
    pub quat_y: f64,
    /// Quaternion z.
    pub quat_z: f64,
    /// Quaternion w.
    pub quat_w: f64,
}

/// Largest accepted deviation of the extrinsics quaternion's norm from 1.
pub const QUAT_NORM_TOLERANCE: f64 = 1e-3;

impl Extrinsics {
    /// Our camera-to-world pose (OpenCV axes): `R_cv = R_gl diag(1, -1, -1)`, i.e. the
    /// quaternion times a 180 degree turn about x. Fails on non-finite values or a
    /// quaternion whose norm is not 1 (within [`QUAT_NORM_TOLERANCE`]).
    ///
    /// ```
    /// use sndt_host::dataset::prepared::Extrinsics;
    /// let e = Extrinsics { x: 1.0, y: 2.0, z: 3.0, quat_x: 0.0, quat_y: 0.0, quat_z: 0.0, quat_w: 1.0 };
    /// let pose = e.to_pose().unwrap();
    /// // identity OpenGL rotation: the camera looks along world -z
    /// let forward = pose.rotation * sndt_core::Vector3::z();
    /// assert!((forward - sndt_core::Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-6);
    /// assert_eq!(Extrinsics::from_pose(&pose).to_pose().unwrap(), pose);
    /// ```
    pub fn to_pose(&self) -> Result<Isometry3<f32>> {
        let v = [
            ("position x", self.x),
            ("position y", self.y),
            ("position z", self.z),
            ("quat_x", self.quat_x),
            ("quat_y", self.quat_y),
            ("quat_z", self.quat_z),
            ("quat_w", self.quat_w),
        ];
        // The pose is f32: a value finite in the file's f64 may not be (1e39).
        if let Some((name, x)) = v.iter().find(|(_, x)| !(*x as f32).is_finite()) {
            bail!("{name} = {} is not finite as f32", show_number(*x));
        }
        let (x, y, z, w) = (self.quat_x, self.quat_y, self.quat_z, self.quat_w);
        let norm = (x * x + y * y + z * z + w * w).sqrt();
        if (norm - 1.0).abs() > QUAT_NORM_TOLERANCE {
            bail!("extrinsics quaternion has norm {norm}, not 1");
        }
        // q_cv = q_gl * q_x(180°), q_x(180°) = (w 0, x 1, y 0, z 0): exact component shuffle.
        let q = nalgebra::Quaternion::new(-x, w, z, -y) / norm;
        let rotation = UnitQuaternion::from_quaternion(q.cast::<f32>());
        Ok(Isometry3::from_parts(
            Translation3::new(self.x as f32, self.y as f32, self.z as f32),
            rotation,
        ))
    }

    /// The record of our pose (OpenCV axes): the inverse of [`Extrinsics::to_pose`].
    pub fn from_pose(pose: &Isometry3<f32>) -> Extrinsics {
        let q = pose.rotation.into_inner().cast::<f64>();
        // q_gl = q_cv * q_x(180°)^-1 = q_cv * (w 0, x -1, y 0, z 0)
        let gl = q * nalgebra::Quaternion::new(0.0, -1.0, 0.0, 0.0);
        let t = pose.translation.vector.cast::<f64>();
        Extrinsics {
            x: t.x,
            y: t.y,
            z: t.z,
            quat_x: gl.i,
            quat_y: gl.j,
            quat_z: gl.k,
            quat_w: gl.w,
        }
    }
}

/// The `intrinsics/<scene>/<cam>.json` record our writer adds (pinhole, pixels).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Intrinsics {
    /// Focal length along x.
    pub fx: f64,
    /// Focal length along y.
    pub fy: f64,
    /// Principal point x (pixel centres at `col + 0.5`).
    pub cx: f64,
    /// Principal point y.
    pub cy: f64,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
}

impl Intrinsics {
    /// The pinhole, checking focal lengths are positive and, like the principal point,
    /// finite as f32, and the size non-zero; the error names the field and its value.
    ///
    /// ```
    /// use sndt_host::dataset::prepared::Intrinsics;
    /// let mut i = Intrinsics { fx: 500.0, fy: 500.0, cx: 320.0, cy: 240.0, width: 640, height: 480 };
    /// assert!(i.to_pinhole().is_ok());
    /// i.fx = 0.0;
    /// assert_eq!(i.to_pinhole().unwrap_err().to_string(), "fx = 0, must be > 0");
    /// ```
    pub fn to_pinhole(&self) -> Result<Pinhole> {
        for (name, f) in [("fx", self.fx), ("fy", self.fy)] {
            if f.is_nan() || f <= 0.0 {
                bail!("{name} = {}, must be > 0", show_number(f));
            }
        }
        for (name, x) in [
            ("fx", self.fx),
            ("fy", self.fy),
            ("cx", self.cx),
            ("cy", self.cy),
        ] {
            if !(x as f32).is_finite() {
                bail!("{name} = {} is not finite as f32", show_number(x));
            }
        }
        for (name, n) in [("width", self.width), ("height", self.height)] {
            if n == 0 {
                bail!("{name} = 0, must be > 0");
            }
        }
        Ok(Pinhole {
            fx: self.fx as f32,
            fy: self.fy as f32,
            cx: self.cx as f32,
            cy: self.cy as f32,
            width: self.width,
            height: self.height,
        })
    }

    /// The record of a pinhole.
    pub fn from_pinhole(p: &Pinhole) -> Intrinsics {
        Intrinsics {
            fx: p.fx as f64,
            fy: p.fy as f64,
            cx: p.cx as f64,
            cy: p.cy as f64,
            width: p.width,
            height: p.height,
        }
    }
}

/// A prepared-layout dataset opened for reading (see the module docs).
pub struct Prepared {
    root: PathBuf,
    split: String,
    dir: PathBuf,
    frames: Vec<FrameId>,
    labels: bool,
    predictions: Option<PathBuf>,
    paper_fy: bool,
    rays: Mutex<HashMap<(String, String), Arc<Rays>>>,
    /// With an `intrinsics/` directory: the intrinsics files missing for cameras with frames.
    fallback: Vec<PathBuf>,
}

impl Prepared {
    /// Opens split `options.split` (default `test`) of the layout at `root`. The frame
    /// list comes from `<root>/<split>.txt` when present, else from listing
    /// `<split>/depth/`; a split without frames is an error. The intrinsics of every
    /// camera are read and checked here (an error names the file); with an
    /// `intrinsics/` directory, a camera without its file uses the nominal camera
    /// ([`Prepared::fallback_cameras`]). Files of individual frames are only read by
    /// [`Dataset::load`].
    pub fn open(root: &Path, options: &OpenOptions) -> Result<Prepared> {
        let split = options.split.clone().unwrap_or_else(|| "test".to_string());
        let dir = root.join(&split);
        let depth = dir.join("depth");
        if !depth.is_dir() {
            bail!(
                "{}: missing (prepared layout needs depth/)",
                depth.display()
            );
        }
        let list = root.join(format!("{split}.txt"));
        let mut frames = if list.is_file() {
            read_split_list(&list)?
        } else {
            list_depth(&depth)?
        };
        frames.sort();
        frames.dedup();
        if frames.is_empty() {
            if list.is_file() {
                bail!("{}: lists no frames (0 frames to map)", list.display());
            }
            bail!(
                "{}: no <scene>/<cam>/<NNNN>.png depth images (0 frames to map)",
                depth.display()
            );
        }
        let predictions = match &options.predictions {
            Some(p) if !p.is_dir() => bail!("{}: predictions directory not found", p.display()),
            Some(p) => Some(p.clone()),
            None => Some(dir.join("esanet")).filter(|p| p.is_dir()),
        };
        let mut prepared = Prepared {
            root: root.to_path_buf(),
            labels: dir.join("semantic_40").is_dir(),
            split,
            dir,
            frames,
            predictions,
            paper_fy: options.paper_fy,
            rays: Mutex::new(HashMap::new()),
            fallback: Vec::new(),
        };
        prepared.fallback = prepared.read_cameras()?;
        Ok(prepared)
    }

    /// The intrinsics files missing from the layout's `intrinsics/` directory for cameras
    /// with frames: those cameras use the nominal Hypersim camera. Empty without an
    /// `intrinsics/` directory (the authors' layout, where every camera is nominal) and
    /// when every camera has its file.
    ///
    /// A layout may mix both legitimately: [`write_frame`] into the authors' layout adds
    /// intrinsics for the cameras it writes only.
    pub fn fallback_cameras(&self) -> &[PathBuf] {
        &self.fallback
    }

    /// Reads every camera's intrinsics into the rays cache (an error names the file);
    /// returns the missing files when the layout has an `intrinsics/` directory.
    fn read_cameras(&self) -> Result<Vec<PathBuf>> {
        let per_camera = self.dir.join("intrinsics").is_dir();
        let mut missing = Vec::new();
        let mut seen = None;
        for id in &self.frames {
            if seen == Some((&id.scene, &id.cam)) {
                continue;
            }
            seen = Some((&id.scene, &id.cam));
            let path = intrinsics_path(&self.dir, id);
            if per_camera && !path.is_file() {
                missing.push(path);
            }
            self.rays(id)?;
        }
        Ok(missing)
    }

    fn file(&self, kind: &str, id: &FrameId, ext: &str) -> PathBuf {
        frame_path(&self.dir.join(kind), id, ext)
    }

    /// The rays of camera `scene/cam`: its intrinsics file, else the nominal camera.
    fn rays(&self, id: &FrameId) -> Result<Arc<Rays>> {
        let key = (id.scene.clone(), id.cam.clone());
        if let Some(r) = self.rays.lock().expect("rays cache").get(&key) {
            return Ok(r.clone());
        }
        let path = intrinsics_path(&self.dir, id);
        let cam = if path.is_file() {
            let intr: Intrinsics = read_json(&path)?;
            intr.to_pinhole()
                .map_err(|e| anyhow::anyhow!("{}: {e:#}", path.display()))?
        } else {
            nominal_camera(self.paper_fy)
        };
        let rays = Arc::new(Rays::Pinhole(cam));
        self.rays
            .lock()
            .expect("rays cache")
            .insert(key, rays.clone());
        Ok(rays)
    }
}

impl Dataset for Prepared {
    fn describe(&self) -> String {
        format!(
            "prepared layout {} split {}: {} frames, {} trajectories, labels {}, predictions {}, {}",
            self.root.display(),
            self.split,
            self.frames.len(),
            self.trajectories().len(),
            if self.labels { "yes" } else { "no" },
            self.predictions
                .as_ref()
                .map_or("none".to_string(), |p| p.display().to_string()),
            if self.dir.join("intrinsics").is_dir() {
                let c = nominal_camera(self.paper_fy);
                match self.fallback.len() {
                    0 => "intrinsics per camera".to_string(),
                    n => format!(
                        "intrinsics per camera, but {n} of {} cameras have no intrinsics file and use the nominal Hypersim camera fx {} fy {}",
                        self.trajectories().len(),
                        c.fx,
                        c.fy
                    ),
                }
            } else {
                let c = nominal_camera(self.paper_fy);
                format!(
                    "nominal Hypersim camera fx {} fy {}{}",
                    c.fx,
                    c.fy,
                    if self.paper_fy { " (paper)" } else { "" }
                )
            }
        )
    }

    fn frames(&self) -> &[FrameId] {
        &self.frames
    }

    /// Errors in the frame's own files are [`BadFrame`]s; the camera's are not.
    fn load(&self, id: &FrameId) -> Result<Frame> {
        let rays = self.rays(id)?;
        self.read_frame(id, rays).map_err(|e| BadFrame::wrap(id, e))
    }

    fn missing_predictions(&self) -> Option<String> {
        match self.predictions {
            Some(_) => None,
            None => Some(format!(
                "no {} directory (or give one with --predictions DIR)",
                self.dir.join("esanet").display()
            )),
        }
    }

    fn pose_file(&self, id: &FrameId) -> Option<PathBuf> {
        Some(self.file("extrinsics", id, "json"))
    }
}

impl Prepared {
    /// The files of frame `id` seen by a camera with `rays`: depth, labels, extrinsics,
    /// predictions; errors name the file.
    fn read_frame(&self, id: &FrameId, rays: Arc<Rays>) -> Result<Frame> {
        let (w, h) = (rays.width(), rays.height());
        let camera_source = || {
            let p = intrinsics_path(&self.dir, id);
            if p.is_file() {
                p.display().to_string()
            } else {
                "the nominal Hypersim camera".to_string()
            }
        };

        let depth_path = self.file("depth", id, "png");
        let (dw, dh, mm) = read_png16(&depth_path)?;
        if (dw, dh) != (w, h) {
            bail!(
                "{}: depth is {dw}x{dh}, camera ({}) is {w}x{h}",
                depth_path.display(),
                camera_source()
            );
        }
        let depth = mm.iter().map(|&v| v as f32 / 1000.0).collect();

        let labels = if self.labels {
            let path = self.file("semantic_40", id, "png");
            let (lw, lh, l) = read_png8(&path)?;
            if (lw, lh) != (w, h) {
                bail!("{}: labels are {lw}x{lh}, depth is {w}x{h}", path.display());
            }
            if let Some((i, bad)) = l.iter().enumerate().find(|&(_, &c)| c > 40) {
                bail!(
                    "{}: label {bad} at pixel ({}, {}) is outside 0..=40",
                    path.display(),
                    i as u32 % w,
                    i as u32 / w
                );
            }
            Some(l)
        } else {
            None
        };

        let ext_path = self.file("extrinsics", id, "json");
        let ext: Extrinsics = read_json(&ext_path)?;
        let pose = ext
            .to_pose()
            .with_context(|| format!("{}", ext_path.display()))?;

        let predictions = match &self.predictions {
            Some(dir) => Some(npy::read_topk(&frame_path(dir, id, "npy"), w, h)?),
            None => None,
        };

        let frame = Frame {
            id: id.clone(),
            pose,
            rays,
            depth,
            depth_kind: DepthKind::Planar,
            labels,
            predictions,
        };
        frame
            .validate()
            .with_context(|| format!("{}: frame {id}", self.dir.display()))?;
        Ok(frame)
    }
}

/// `<dir>/<scene>/<cam>/<NNNN>.<ext>`.
fn frame_path(dir: &Path, id: &FrameId, ext: &str) -> PathBuf {
    dir.join(&id.scene)
        .join(&id.cam)
        .join(format!("{}.{ext}", id.stem()))
}

fn intrinsics_path(split_dir: &Path, id: &FrameId) -> PathBuf {
    split_dir
        .join("intrinsics")
        .join(&id.scene)
        .join(format!("{}.json", id.cam))
}

/// Reads a split list: one `scene/cam/NNNN` per line; blank lines and `#` comments skipped.
fn read_split_list(path: &Path) -> Result<Vec<FrameId>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: reading split list", path.display()))?;
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        out.push(
            FrameId::parse(line)
                .with_context(|| format!("{}:{}: malformed line", path.display(), n + 1))?,
        );
    }
    Ok(out)
}

/// Lists `<depth>/<scene>/<cam>/<NNNN>.png`.
fn list_depth(depth: &Path) -> Result<Vec<FrameId>> {
    let dirs = |p: &Path| -> Result<Vec<(String, PathBuf)>> {
        let mut v = Vec::new();
        for e in std::fs::read_dir(p).with_context(|| format!("listing {}", p.display()))? {
            let e = e.with_context(|| format!("listing {}", p.display()))?;
            v.push((e.file_name().to_string_lossy().into_owned(), e.path()));
        }
        Ok(v)
    };
    let mut out = Vec::new();
    for (scene, sp) in dirs(depth)?.into_iter().filter(|(_, p)| p.is_dir()) {
        for (cam, cp) in dirs(&sp)?.into_iter().filter(|(_, p)| p.is_dir()) {
            for (name, fp) in dirs(&cp)? {
                let Some(stem) = name.strip_suffix(".png") else {
                    continue;
                };
                let index = stem
                    .parse()
                    .with_context(|| format!("{}: file name is not <NNNN>.png", fp.display()))?;
                out.push(FrameId {
                    scene: scene.clone(),
                    cam: cam.clone(),
                    index,
                });
            }
        }
    }
    Ok(out)
}

fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T> {
    let file = File::open(path).with_context(|| format!("{}: opening", path.display()))?;
    serde_json::from_reader(BufReader::new(file))
        .with_context(|| format!("{}: invalid JSON record", path.display()))
}

/// Decodes a grayscale PNG of the given bit depth: `(width, height, raw bytes)`.
fn read_png(path: &Path, depth: png::BitDepth) -> Result<(u32, u32, Vec<u8>)> {
    let shown = path.display();
    let file = File::open(path).with_context(|| format!("{shown}: opening"))?;
    decode_png(BufReader::new(file), &shown, depth)
}

/// Largest decoded PNG accepted: 256 MiB, 64 times a 1024x768 uint16 frame.
const MAX_PNG_BYTES: usize = 1 << 28;

/// [`read_png`] from any reader, its errors naming the source `shown`.
fn decode_png(
    src: impl BufRead + Seek,
    shown: &dyn Display,
    depth: png::BitDepth,
) -> Result<(u32, u32, Vec<u8>)> {
    let mut decoder = png::Decoder::new(src);
    decoder.set_transformations(png::Transformations::IDENTITY);
    let mut reader = decoder
        .read_info()
        .with_context(|| format!("{shown}: not a readable PNG"))?;
    let info = reader.info();
    let (w, h, color, bits) = (info.width, info.height, info.color_type, info.bit_depth);
    if color != png::ColorType::Grayscale || bits != depth {
        bail!("{shown}: {color:?} {bits:?} PNG, expected Grayscale {depth:?}");
    }
    // The header alone sets the buffer size: a 100-byte file can claim terabytes, whose
    // allocation would abort the process instead of failing.
    let size = reader
        .output_buffer_size()
        .filter(|&n| n <= MAX_PNG_BYTES)
        .with_context(|| format!("{shown}: {w}x{h} image too large"))?;
    let mut buf = vec![0u8; size];
    reader
        .next_frame(&mut buf)
        .with_context(|| format!("{shown}: decoding image data (truncated?)"))?;
    Ok((w, h, buf))
}

/// uint16 grayscale PNG (big-endian samples).
fn read_png16(path: &Path) -> Result<(u32, u32, Vec<u16>)> {
    let (w, h, raw) = read_png(path, png::BitDepth::Sixteen)?;
    Ok((w, h, big_endian_u16(&raw)))
}

fn big_endian_u16(raw: &[u8]) -> Vec<u16> {
    raw.chunks_exact(2)
        .map(|b| u16::from_be_bytes([b[0], b[1]]))
        .collect()
}

/// The depth PNG reader (uint16 grayscale, millimetres) on bytes in memory:
/// `(width, height, samples)`.
///
/// ```
/// use sndt_host::dataset::prepared::depth_png_from_bytes;
/// assert!(depth_png_from_bytes(b"not a PNG").is_err());
/// ```
pub fn depth_png_from_bytes(bytes: &[u8]) -> Result<(u32, u32, Vec<u16>)> {
    let (w, h, raw) = decode_png(Cursor::new(bytes), &"PNG bytes", png::BitDepth::Sixteen)?;
    Ok((w, h, big_endian_u16(&raw)))
}

/// The label PNG reader (uint8 grayscale) on bytes in memory: `(width, height, labels)`.
pub fn labels_png_from_bytes(bytes: &[u8]) -> Result<(u32, u32, Vec<u8>)> {
    decode_png(Cursor::new(bytes), &"PNG bytes", png::BitDepth::Eight)
}

fn read_png8(path: &Path) -> Result<(u32, u32, Vec<u8>)> {
    read_png(path, png::BitDepth::Eight)
}

/// Writes a plain 8-bit grayscale PNG (atomically: temporary file, then rename).
pub fn write_gray8(path: &Path, w: u32, h: u32, data: &[u8]) -> Result<()> {
    write_png(path, w, h, png::BitDepth::Eight, data)
}

fn write_png(path: &Path, w: u32, h: u32, depth: png::BitDepth, data: &[u8]) -> Result<()> {
    write_atomic(path, |tmp| {
        let file = File::create(tmp).with_context(|| format!("{}: creating", tmp.display()))?;
        let mut enc = png::Encoder::new(BufWriter::new(file), w, h);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(depth);
        let mut writer = enc
            .write_header()
            .with_context(|| format!("{}: writing PNG header", path.display()))?;
        writer
            .write_image_data(data)
            .with_context(|| format!("{}: writing PNG data", path.display()))?;
        writer
            .finish()
            .with_context(|| format!("{}: finishing PNG", path.display()))
    })
}

fn write_json<T: serde::Serialize>(path: &Path, value: &T) -> Result<()> {
    let mut text = serde_json::to_string_pretty(value)?;
    text.push('\n');
    write_atomic(path, |tmp| {
        let mut f = File::create(tmp).with_context(|| format!("{}: creating", tmp.display()))?;
        f.write_all(text.as_bytes())
            .with_context(|| format!("{}: writing", path.display()))
    })
}

/// Depth in metres to the layout's uint16 millimetres: rounded, 0 for no measurement or
/// beyond 65.535 m.
///
/// ```
/// use sndt_host::dataset::prepared::depth_to_mm;
/// assert_eq!(depth_to_mm(1.2345), 1235);
/// assert_eq!(depth_to_mm(0.0), 0);
/// assert_eq!(depth_to_mm(f32::NAN), 0);
/// assert_eq!(depth_to_mm(65.535), 65535);
/// assert_eq!(depth_to_mm(70.0), 0);
/// ```
pub fn depth_to_mm(d: f32) -> u16 {
    if !(d.is_finite() && d > 0.0) {
        return 0;
    }
    let mm = (d as f64 * 1000.0).round();
    if mm > u16::MAX as f64 {
        0
    } else {
        mm as u16
    }
}

/// Writes one frame into `<root>/<split>/...` (creating directories): depth PNG (planar,
/// mm), `semantic_40` PNG when the frame has labels, extrinsics JSON (raw OpenGL-axes
/// rotation), `intrinsics/<scene>/<cam>.json` (must agree with an existing one) and
/// `esanet` npy when it has predictions. Every file is written atomically, so several
/// threads may write different frames (of the same cameras) at once.
///
/// Only pinhole frames can be written: the layout has no place for per-pixel rays.
///
/// ```
/// use sndt_host::dataset::{Dataset, Frame, FrameId, Rays};
/// use sndt_host::dataset;
/// # let root = std::env::temp_dir().join(format!("sndt-prepared-doc-{}", std::process::id()));
/// let cam = sndt_core::Pinhole { fx: 2.0, fy: 2.0, cx: 1.0, cy: 1.0, width: 2, height: 2 };
/// let frame = Frame {
///     id: FrameId::parse("room/cam_00/0000").unwrap(),
///     pose: sndt_core::Isometry3::identity(),
///     rays: std::sync::Arc::new(Rays::Pinhole(cam)),
///     depth: vec![1.0, 2.0, 0.0, 1.5],
///     depth_kind: sndt_core::DepthKind::Planar,
///     labels: Some(vec![1, 2, 0, 40]),
///     predictions: None,
/// };
/// sndt_host::dataset::prepared::write_frame(&root, "test", &frame).unwrap();
/// sndt_host::dataset::prepared::write_split_list(&root, "test", &[frame.id.clone()]).unwrap();
/// let data = dataset::open(&root, &dataset::OpenOptions::default()).unwrap();
/// let back = data.load(&data.frames()[0]).unwrap();
/// assert_eq!((back.depth, back.labels), (frame.depth, frame.labels));
/// # std::fs::remove_dir_all(&root).unwrap();
/// ```
pub fn write_frame(root: &Path, split: &str, frame: &Frame) -> Result<()> {
    let id = &frame.id;
    frame
        .validate()
        .with_context(|| format!("writing frame {id}"))?;
    let Rays::Pinhole(cam) = frame.rays.as_ref() else {
        bail!("{id}: per-pixel rays cannot be stored in the prepared layout (pinhole only)");
    };
    let (w, h) = (cam.width, cam.height);
    let dir = root.join(split);

    let intr_path = intrinsics_path(&dir, id);
    let intr = Intrinsics::from_pinhole(cam);
    if intr_path.is_file() {
        let old: Intrinsics = read_json(&intr_path)?;
        if old != intr {
            bail!(
                "{}: holds {old:?}, frame {id} has {intr:?}",
                intr_path.display()
            );
        }
    } else {
        write_json(&intr_path, &intr)?;
    }

    let depth: Vec<u8> = frame
        .planar_depth_image()
        .iter()
        .flat_map(|&d| depth_to_mm(d).to_be_bytes())
        .collect();
    write_png(
        &frame_path(&dir.join("depth"), id, "png"),
        w,
        h,
        png::BitDepth::Sixteen,
        &depth,
    )?;

    if let Some(labels) = &frame.labels {
        write_png(
            &frame_path(&dir.join("semantic_40"), id, "png"),
            w,
            h,
            png::BitDepth::Eight,
            labels,
        )?;
    }

    write_json(
        &frame_path(&dir.join("extrinsics"), id, "json"),
        &Extrinsics::from_pose(&frame.pose),
    )?;

    if let Some(p) = &frame.predictions {
        let path = frame_path(&dir.join("esanet"), id, "npy");
        write_atomic(&path, |tmp| npy::write_topk(tmp, p, w, h))?;
    }
    Ok(())
}

/// Writes the split list `<root>/<split>.txt`, one `scene/cam/NNNN` line per frame in
/// the given order.
pub fn write_split_list(root: &Path, split: &str, ids: &[FrameId]) -> Result<()> {
    let mut text = String::with_capacity(ids.len() * 24);
    for id in ids {
        text.push_str(&id.to_string());
        text.push('\n');
    }
    let path = root.join(format!("{split}.txt"));
    write_atomic(&path, |tmp| {
        std::fs::write(tmp, &text).with_context(|| format!("{}: writing", path.display()))
    })
}
