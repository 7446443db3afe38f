//! Raw Hypersim reader.
//!
//! Layout, as in the raw Hypersim download:
//! - `<root>/<scene>/_detail/<cam>/camera_keyframe_{orientations,positions}.hdf5`:
//!   `(N, 3, 3)` R_world_from_cam with OpenGL camera axes and `(N, 3)` positions in asset
//!   units;
//! - `<root>/<scene>/images/scene_<cam>_geometry_hdf5/frame.NNNN.depth_meters.hdf5`:
//!   float16 Euclidean range in metres, NaN where nothing was hit;
//! - optional `frame.NNNN.semantic.hdf5` beside it: int16, `-1` void, `1..=40` NYU40;
//! - `metadata_camera_parameters.csv` in `<root>` or its parent: per-scene image size,
//!   `settings_units_info_meters_scale` and the ray matrix `M_cam_from_uv`;
//! - optional `<root>/<scene>/_detail/metadata_scene.csv` with `meters_per_asset_unit`,
//!   which takes precedence over the camera CSV's scale.
//!
//! Every HDF5 file holds one dataset named `dataset`. Frames are the depth files that
//! exist, ordered by scene, camera and index. Rays come from the per-scene
//! `M_cam_from_uv` (many scenes use tilt-shift cameras, for which the nominal pinhole is
//! wrong), converted to OpenCV axes with unit z and shared by all frames of the scene.
//! Rotations are re-orthonormalised (polar decomposition) and counted when they are
//! slightly off; NaN, infinite or badly non-orthonormal poses are errors naming the file
//! and the keyframe.

use crate::dataset::frame::{Frame, FrameId, Rays};
use crate::dataset::source::Dataset;
use crate::dataset::source::{BadFrame, OpenOptions};
use anyhow::{anyhow, bail, ensure, Context, Result};
use sndt_core::{DepthKind, Isometry3, Matrix3, Translation3, UnitQuaternion, Vector3};
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, Weak};

/// Name of the per-scene camera parameter table.
pub const CAMERA_CSV: &str = "metadata_camera_parameters.csv";

/// Largest `max |RᵀR - I|` taken as orthonormal as stored (the rotation is still
/// re-projected onto SO(3), but not counted as re-orthonormalised).
pub const ORTHONORMAL_TOLERANCE: f64 = 1e-6;

/// Largest `max |RᵀR - I|` that is repaired; anything worse is rejected as corrupt.
pub const REPAIRABLE_TOLERANCE: f64 = 0.05;

/// The per-scene camera parameters Hypersim publishes in `metadata_camera_parameters.csv`.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraParams {
    /// Image width in pixels (`settings_output_img_width`).
    pub width: u32,
    /// Image height in pixels (`settings_output_img_height`).
    pub height: u32,
    /// Metres per asset unit (`settings_units_info_meters_scale`).
    pub meters_scale: f64,
    /// `M_cam_from_uv`, row-major (`m[i][j]` = column `M_cam_from_uv_ij`): the OpenGL
    /// camera-space ray of the image point `(u, v)` is `M [u, v, 1]ᵀ`.
    pub m_cam_from_uv: [[f64; 3]; 3],
}

impl CameraParams {
    /// True when the camera is tilt-shift, i.e. its rays are not centred
    /// (`M_cam_from_uv_02` or `M_cam_from_uv_12` is non-zero).
    pub fn is_tilt_shift(&self) -> bool {
        self.m_cam_from_uv[0][2] != 0.0 || self.m_cam_from_uv[1][2] != 0.0
    }
}

/// A keyframe pose as read and checked by [`cv_pose`].
#[derive(Clone, Copy, Debug)]
pub struct CheckedPose {
    /// Camera-to-world, metres, OpenCV camera axes.
    pub pose: Isometry3<f32>,
    /// `max |RᵀR - I|` of the rotation as stored.
    pub orthonormality_error: f64,
    /// True when the stored rotation was off by more than [`ORTHONORMAL_TOLERANCE`]
    /// and was replaced by its nearest rotation.
    pub reorthonormalised: bool,
}

/// The keyframe poses of one trajectory.
#[derive(Clone, Debug)]
pub struct KeyframePoses {
    /// Camera-to-world, metres, OpenCV camera axes, one per keyframe.
    pub poses: Vec<Isometry3<f32>>,
    /// Indices of the keyframes whose rotation was re-orthonormalised.
    pub reorthonormalised: Vec<usize>,
}

/// A raw Hypersim dataset (see the module documentation).
pub struct Hypersim {
    root: PathBuf,
    frames: Vec<FrameId>,
    /// Per scene: camera parameters and metres per asset unit.
    scenes: BTreeMap<String, Scene>,
    /// Per scene: the rays, built on first use and shared by the frames alive at a time
    /// (one table is 9.4 MB at 1024 x 768; a whole test split would hold 46 of them).
    rays: Mutex<HashMap<String, Weak<Rays>>>,
    /// Per `(scene, cam)`: keyframe poses.
    trajectories: BTreeMap<(String, String), KeyframePoses>,
    camera_csv: PathBuf,
    /// ESANet predictions: `<dir>/<scene>/<cam>/<NNNN>.npy`.
    predictions: Option<PathBuf>,
}

struct Scene {
    params: CameraParams,
    meters_per_asset_unit: f64,
}

impl Hypersim {
    /// Opens the raw Hypersim tree at `root`: finds the depth files, reads the camera
    /// parameters of the scenes that have any, and reads and checks the keyframe poses
    /// of their trajectories. Errors name the offending file (and keyframe).
    pub fn open(root: &Path, options: &OpenOptions) -> Result<Hypersim> {
        if let Some(p) = options.predictions.as_ref().filter(|p| !p.is_dir()) {
            bail!("{}: predictions directory not found", p.display());
        }
        let camera_csv = find_camera_csv(root)?;
        let frames = find_frames(root)?;
        let scenes = read_scenes(root, &camera_csv, &frames)?;
        let trajectories = read_trajectories(root, &frames, &scenes)?;
        Ok(Hypersim {
            root: root.to_path_buf(),
            frames,
            scenes,
            trajectories,
            camera_csv,
            rays: Mutex::new(HashMap::new()),
            predictions: options.predictions.clone(),
        })
    }

    /// Number of keyframe rotations (over all trajectories that have frames) that were
    /// slightly non-orthonormal and were replaced by their nearest rotation.
    pub fn reorthonormalised(&self) -> usize {
        self.trajectories
            .values()
            .map(|t| t.reorthonormalised.len())
            .sum()
    }

    /// All keyframe poses of a trajectory (also those without a depth file), or `None`
    /// when the trajectory has no frames.
    pub fn keyframe_poses(&self, scene: &str, cam: &str) -> Option<&KeyframePoses> {
        self.trajectories.get(&(scene.to_string(), cam.to_string()))
    }

    /// The camera parameters of a scene that has frames.
    pub fn camera(&self, scene: &str) -> Option<&CameraParams> {
        self.scenes.get(scene).map(|s| &s.params)
    }

    /// Metres per asset unit used for a scene's positions.
    pub fn meters_per_asset_unit(&self, scene: &str) -> Option<f64> {
        self.scenes.get(scene).map(|s| s.meters_per_asset_unit)
    }

    /// The per-pixel rays of a scene, shared with every frame of it that is still alive
    /// (built again once none is).
    pub fn rays(&self, scene: &str) -> Result<Arc<Rays>> {
        let params = self
            .camera(scene)
            .ok_or_else(|| anyhow!("scene {scene} not in {}", self.root.display()))?;
        let mut cache = self
            .rays
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if let Some(rays) = cache.get(scene).and_then(Weak::upgrade) {
            return Ok(rays);
        }
        let rays = Arc::new(
            per_pixel_rays(params)
                .with_context(|| format!("{}: scene {scene}", self.camera_csv.display()))?,
        );
        cache.insert(scene.to_string(), Arc::downgrade(&rays));
        Ok(rays)
    }

    /// The camera parameter table that was used.
    pub fn camera_csv(&self) -> &Path {
        &self.camera_csv
    }

    /// Path of a frame's depth file.
    pub fn depth_path(&self, id: &FrameId) -> PathBuf {
        geometry_dir(&self.root, &id.scene, &id.cam)
            .join(format!("frame.{:04}.depth_meters.hdf5", id.index))
    }

    /// Path of a frame's (optional) semantic label file.
    pub fn semantic_path(&self, id: &FrameId) -> PathBuf {
        geometry_dir(&self.root, &id.scene, &id.cam)
            .join(format!("frame.{:04}.semantic.hdf5", id.index))
    }
}

impl Dataset for Hypersim {
    fn describe(&self) -> String {
        let tilt = self
            .scenes
            .values()
            .filter(|s| s.params.is_tilt_shift())
            .count();
        format!(
            "raw Hypersim at {}: {} scenes ({tilt} tilt-shift), {} trajectories, {} frames; {} keyframe rotations re-orthonormalised",
            self.root.display(),
            self.scenes.len(),
            self.trajectories.len(),
            self.frames.len(),
            self.reorthonormalised()
        )
    }

    fn frames(&self) -> &[FrameId] {
        &self.frames
    }

    /// Errors in the frame's own files (depth, labels, predictions) and a frame without
    /// a keyframe pose are [`BadFrame`]s; the scene's and camera's are not.
    fn load(&self, id: &FrameId) -> Result<Frame> {
        let scene = self
            .scenes
            .get(&id.scene)
            .ok_or_else(|| anyhow!("{id}: scene not in {}", self.root.display()))?;
        let poses = self
            .trajectories
            .get(&(id.scene.clone(), id.cam.clone()))
            .ok_or_else(|| anyhow!("{id}: trajectory not in {}", self.root.display()))?;
        let rays = self.rays(&id.scene)?;
        self.read_frame(id, scene, poses, rays)
            .map_err(|e| BadFrame::wrap(id, e))
    }

    fn missing_predictions(&self) -> Option<String> {
        match self.predictions {
            Some(_) => None,
            None => Some("raw Hypersim has predictions only from --predictions DIR".into()),
        }
    }

    fn pose_file(&self, id: &FrameId) -> Option<PathBuf> {
        Some(
            orientations_path(&self.root, &id.scene, &id.cam)
                .with_file_name("camera_keyframe_positions.hdf5"),
        )
    }
}

impl Hypersim {
    /// The files of frame `id` (depth, labels, predictions) with its keyframe pose; errors
    /// name the file.
    fn read_frame(
        &self,
        id: &FrameId,
        scene: &Scene,
        poses: &KeyframePoses,
        rays: Arc<Rays>,
    ) -> Result<Frame> {
        let pose = *poses.poses.get(id.index as usize).ok_or_else(|| {
            anyhow!(
                "{}: no keyframe {} for frame {id}",
                self.pose_file(id).unwrap_or_default().display(),
                id.index
            )
        })?;
        let shape = [scene.params.height as usize, scene.params.width as usize];
        let depth = read_depth(&self.depth_path(id), shape)?;
        let sem = self.semantic_path(id);
        let labels = if sem.is_file() {
            Some(read_semantic(&sem, shape)?)
        } else {
            None
        };
        let frame = Frame {
            id: id.clone(),
            pose,
            rays,
            depth,
            depth_kind: DepthKind::Range,
            labels,
            predictions: match &self.predictions {
                Some(dir) => Some(crate::dataset::npy::read_topk(
                    &dir.join(&id.scene)
                        .join(&id.cam)
                        .join(format!("{}.npy", id.stem())),
                    shape[1] as u32,
                    shape[0] as u32,
                )?),
                None => None,
            },
        };
        frame.validate()?;
        Ok(frame)
    }
}

fn geometry_dir(root: &Path, scene: &str, cam: &str) -> PathBuf {
    root.join(scene)
        .join("images")
        .join(format!("scene_{cam}_geometry_hdf5"))
}

fn orientations_path(root: &Path, scene: &str, cam: &str) -> PathBuf {
    root.join(scene)
        .join("_detail")
        .join(cam)
        .join("camera_keyframe_orientations.hdf5")
}

/// Sorted names of the sub-directories of `dir`.
fn sorted_dirs(dir: &Path) -> Result<Vec<String>> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).with_context(|| format!("listing {}", dir.display()))? {
        let e = e.with_context(|| format!("listing {}", dir.display()))?;
        if e.path().is_dir()
            && let Some(name) = e.file_name().to_str()
        {
            out.push(name.to_string());
        }
    }
    out.sort();
    Ok(out)
}

/// Sorted frame indices `NNNN` of the `frame.NNNN.depth_meters.hdf5` files in `dir`
/// (none when `dir` does not exist).
fn depth_indices(dir: &Path) -> Result<Vec<u32>> {
    if !dir.is_dir() {
        return Ok(Vec::new());
    }
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).with_context(|| format!("listing {}", dir.display()))? {
        let e = e.with_context(|| format!("listing {}", dir.display()))?;
        let name = e.file_name();
        let Some(name) = name.to_str() else { continue };
        if let Some(n) = name
            .strip_prefix("frame.")
            .and_then(|s| s.strip_suffix(".depth_meters.hdf5"))
            && let Ok(i) = n.parse()
        {
            out.push(i);
        }
    }
    out.sort_unstable();
    Ok(out)
}

/// The frames of a raw Hypersim tree: every depth file of every `cam_*` of every scene
/// with a `_detail` folder, ordered by scene, camera and index.
fn find_frames(root: &Path) -> Result<Vec<FrameId>> {
    let mut frames = Vec::new();
    for scene in sorted_dirs(root)? {
        if !root.join(&scene).join("_detail").is_dir() {
            continue;
        }
        for cam in sorted_dirs(&root.join(&scene).join("_detail"))? {
            if !cam.starts_with("cam_") {
                continue;
            }
            for index in depth_indices(&geometry_dir(root, &scene, &cam))? {
                frames.push(FrameId {
                    scene: scene.clone(),
                    cam: cam.clone(),
                    index,
                });
            }
        }
    }
    if frames.is_empty() {
        bail!(
            "{}: raw Hypersim layout without any <scene>/images/scene_<cam>_geometry_hdf5/frame.NNNN.depth_meters.hdf5",
            root.display()
        );
    }
    Ok(frames)
}

/// The camera parameters and scale of every scene that has frames, checked: a missing CSV
/// row, a scale that is not positive or unusable rays are errors naming the CSV.
fn read_scenes(
    root: &Path,
    camera_csv: &Path,
    frames: &[FrameId],
) -> Result<BTreeMap<String, Scene>> {
    // `frames` is ordered by scene, so this lists each scene once.
    let mut wanted: Vec<&str> = frames.iter().map(|f| f.scene.as_str()).collect();
    wanted.dedup();
    let mut table = read_camera_csv(camera_csv)?;
    let mut scenes = BTreeMap::new();
    for &name in &wanted {
        let params = table
            .remove(name)
            .ok_or_else(|| anyhow!("{}: no row for scene {name}", camera_csv.display()))?;
        let scene_csv = root.join(name).join("_detail").join("metadata_scene.csv");
        let meters_per_asset_unit = if scene_csv.is_file() {
            read_scene_meters_per_asset_unit(&scene_csv)?
        } else {
            params.meters_scale
        };
        ensure!(
            meters_per_asset_unit.is_finite() && meters_per_asset_unit > 0.0,
            "{}: scene {name}: meters per asset unit {meters_per_asset_unit} is not positive",
            camera_csv.display()
        );
        check_rays(&params).with_context(|| format!("{}: scene {name}", camera_csv.display()))?;
        scenes.insert(
            name.to_string(),
            Scene {
                params,
                meters_per_asset_unit,
            },
        );
    }
    Ok(scenes)
}

/// The checked keyframe poses of every trajectory that has frames; a depth file beyond
/// the last keyframe is an error naming the orientations file.
fn read_trajectories(
    root: &Path,
    frames: &[FrameId],
    scenes: &BTreeMap<String, Scene>,
) -> Result<BTreeMap<(String, String), KeyframePoses>> {
    let mut trajectories = BTreeMap::new();
    for id in frames {
        let key = (id.scene.clone(), id.cam.clone());
        if trajectories.contains_key(&key) {
            continue;
        }
        let dir = root.join(&id.scene).join("_detail").join(&id.cam);
        let poses = read_keyframe_poses(&dir, scenes[&id.scene].meters_per_asset_unit)?;
        trajectories.insert(key, poses);
    }
    for id in frames {
        let n = trajectories[&(id.scene.clone(), id.cam.clone())]
            .poses
            .len();
        if id.index as usize >= n {
            bail!(
                "{}: frame {} has a depth file but the trajectory has only {n} keyframes",
                orientations_path(root, &id.scene, &id.cam).display(),
                id.index
            );
        }
    }
    Ok(trajectories)
}

/// `<root>/metadata_camera_parameters.csv`, else the same in `root`'s parent.
fn find_camera_csv(root: &Path) -> Result<PathBuf> {
    let here = root.join(CAMERA_CSV);
    if here.is_file() {
        return Ok(here);
    }
    if let Some(parent) = root.parent() {
        let up = parent.join(CAMERA_CSV);
        if up.is_file() {
            return Ok(up);
        }
    }
    bail!(
        "{}: camera parameters not found (looked for {CAMERA_CSV} there and in its parent)",
        here.display()
    )
}

/// Splits one CSV line into fields, honouring double quotes (`""` inside quotes is a
/// literal quote).
pub fn split_csv_line(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut field = String::new();
    let mut quoted = false;
    let mut chars = line.trim_end_matches(['\r', '\n']).chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                field.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => out.push(std::mem::take(&mut field)),
            _ => field.push(c),
        }
    }
    out.push(field);
    out
}

/// Reads `metadata_camera_parameters.csv`: scene name → parameters.
pub fn read_camera_csv(path: &Path) -> Result<HashMap<String, CameraParams>> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let (_, header) = lines
        .next()
        .ok_or_else(|| anyhow!("{}: empty file", path.display()))?;
    let header = split_csv_line(header);
    let col = |name: &str| {
        header
            .iter()
            .position(|h| h == name)
            .ok_or_else(|| anyhow!("{}: no column {name}", path.display()))
    };
    let scene_col = col("scene_name")?;
    let w_col = col("settings_output_img_width")?;
    let h_col = col("settings_output_img_height")?;
    let s_col = col("settings_units_info_meters_scale")?;
    let mut m_cols = [[0usize; 3]; 3];
    for (i, row) in m_cols.iter_mut().enumerate() {
        for (j, c) in row.iter_mut().enumerate() {
            *c = col(&format!("M_cam_from_uv_{i}{j}"))?;
        }
    }
    let mut out = HashMap::new();
    for (n, line) in lines {
        let fields = split_csv_line(line);
        let num = |c: usize| -> Result<f64> {
            let s = fields.get(c).map(|s| s.trim()).unwrap_or("");
            s.parse::<f64>().with_context(|| {
                format!(
                    "{}:{}: column {} = {s:?} is not a number",
                    path.display(),
                    n + 1,
                    header[c]
                )
            })
        };
        let Some(scene) = fields.get(scene_col) else {
            continue;
        };
        let size = |c: usize| -> Result<u32> {
            let x = num(c)?;
            ensure!(
                (1.0..=65536.0).contains(&x) && x.fract() == 0.0,
                "{}:{}: {} = {x} is not an image size",
                path.display(),
                n + 1,
                header[c]
            );
            Ok(x as u32)
        };
        let mut m = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] = num(m_cols[i][j])?;
            }
        }
        out.insert(
            scene.clone(),
            CameraParams {
                width: size(w_col)?,
                height: size(h_col)?,
                meters_scale: num(s_col)?,
                m_cam_from_uv: m,
            },
        );
    }
    Ok(out)
}

/// Reads `meters_per_asset_unit` from a scene's `_detail/metadata_scene.csv`
/// (`parameter_name,parameter_value` rows).
pub fn read_scene_meters_per_asset_unit(path: &Path) -> Result<f64> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    for line in text.lines() {
        let f = split_csv_line(line);
        if f.len() >= 2 && f[0].trim() == "meters_per_asset_unit" {
            return f[1].trim().parse().with_context(|| {
                format!(
                    "{}: meters_per_asset_unit {:?} is not a number",
                    path.display(),
                    f[1]
                )
            });
        }
    }
    bail!("{}: no meters_per_asset_unit row", path.display())
}

/// The image-plane coordinates `(u, v)` of the centre of pixel `(col, row)` in
/// Hypersim's convention: u runs from `-1 + 1/W` (left) to `1 - 1/W`, v from `1 - 1/H`
/// (top row) to `-1 + 1/H`.
pub fn pixel_uv(col: u32, row: u32, width: u32, height: u32) -> (f64, f64) {
    let u = -1.0 + (2.0 * col as f64 + 1.0) / width as f64;
    let v = 1.0 - (2.0 * row as f64 + 1.0) / height as f64;
    (u, v)
}

/// Converts an OpenGL camera-space ray (x right, y up, looking along -z) to OpenCV axes
/// (x right, y down, z forward) scaled to unit z; `None` if it does not point forward.
pub fn gl_ray_to_cv_unit_z(ray: [f64; 3]) -> Option<[f64; 3]> {
    let z = -ray[2];
    if !(z.is_finite() && z > 0.0) {
        return None;
    }
    Some([ray[0] / z, -ray[1] / z, 1.0])
}

/// Checks that `M_cam_from_uv` is finite and that every pixel's ray points forward
/// (the ray is affine in `(u, v)`, so checking the four image corners suffices).
fn check_rays(params: &CameraParams) -> Result<()> {
    let m = &params.m_cam_from_uv;
    ensure!(
        m.iter().flatten().all(|x| x.is_finite()),
        "M_cam_from_uv is not finite"
    );
    for (u, v) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
        let z = m[2][0] * u + m[2][1] * v + m[2][2];
        ensure!(
            z < 0.0,
            "M_cam_from_uv gives the image corner (u, v) = ({u}, {v}) a ray that does not point forward (z = {z})"
        );
    }
    Ok(())
}

/// Per-pixel rays (OpenCV axes, unit z, row-major) of a scene's camera from its
/// `M_cam_from_uv` and the pixel-centre uv grid of [`pixel_uv`].
pub fn per_pixel_rays(params: &CameraParams) -> Result<Rays> {
    let m = &params.m_cam_from_uv;
    ensure!(
        m.iter().flatten().all(|x| x.is_finite()),
        "M_cam_from_uv is not finite"
    );
    let (w, h) = (params.width, params.height);
    let mut dirs = Vec::with_capacity(w as usize * h as usize);
    for row in 0..h {
        for col in 0..w {
            let (u, v) = pixel_uv(col, row, w, h);
            let gl = [
                m[0][0] * u + m[0][1] * v + m[0][2],
                m[1][0] * u + m[1][1] * v + m[1][2],
                m[2][0] * u + m[2][1] * v + m[2][2],
            ];
            let cv = gl_ray_to_cv_unit_z(gl).ok_or_else(|| {
                anyhow!("M_cam_from_uv gives pixel ({col}, {row}) a ray {gl:?} that does not point forward")
            })?;
            dirs.push([cv[0] as f32, cv[1] as f32, 1.0]);
        }
    }
    Ok(Rays::PerPixel {
        width: w,
        height: h,
        dirs,
    })
}

/// `R · diag(1, -1, -1)`: a camera-to-world rotation with OpenGL camera axes turned into
/// one with OpenCV camera axes (a 180° turn about the camera's x axis).
pub fn gl_to_cv(r: &Matrix3<f64>) -> Matrix3<f64> {
    r * Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0))
}

/// `max |RᵀR - I|` over the entries.
pub fn orthonormality_error(r: &Matrix3<f64>) -> f64 {
    (r.transpose() * r - Matrix3::identity()).abs().max()
}

/// The rotation nearest to `r` (Frobenius norm): `U Vᵀ` from the SVD `r = U Σ Vᵀ`, the
/// orthogonal factor of the polar decomposition. `None` when `r` is not finite or the
/// nearest orthogonal matrix is a reflection (det < 0).
pub fn nearest_rotation(r: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    if !r.iter().all(|x| x.is_finite()) {
        return None;
    }
    let svd = r.svd(true, true);
    let q = svd.u? * svd.v_t?;
    (q.determinant() > 0.0).then_some(q)
}

/// Checks and converts one raw keyframe: `r_gl` is Hypersim's R_world_from_cam (OpenGL
/// camera axes), `position` in asset units. Returns the camera-to-world pose in metres
/// with OpenCV camera axes. Slightly non-orthonormal rotations (error up to
/// [`REPAIRABLE_TOLERANCE`]) are replaced by the nearest rotation; NaN/inf values,
/// worse rotations and reflections are errors (without a file name: callers add it).
pub fn cv_pose(
    r_gl: &Matrix3<f64>,
    position: &Vector3<f64>,
    meters_per_asset_unit: f64,
) -> Result<CheckedPose> {
    if !r_gl.iter().chain(position.iter()).all(|x| x.is_finite()) {
        bail!(
            "pose is not finite (R = {:?}, position = {:?})",
            r_gl.as_slice(),
            position.as_slice()
        );
    }
    let err = orthonormality_error(r_gl);
    if err > REPAIRABLE_TOLERANCE {
        bail!("rotation is not orthonormal: max |RᵀR - I| = {err:.3e} > {REPAIRABLE_TOLERANCE}");
    }
    let det = r_gl.determinant();
    if det <= 0.0 {
        bail!("rotation is a reflection (det = {det:.6})");
    }
    let r =
        nearest_rotation(r_gl).ok_or_else(|| anyhow!("rotation has no nearest proper rotation"))?;
    let r_cv = gl_to_cv(&r);
    let q = UnitQuaternion::from_matrix(&r_cv);
    let t = position * meters_per_asset_unit;
    let pose = Isometry3::from_parts(
        Translation3::new(t.x as f32, t.y as f32, t.z as f32),
        q.cast::<f32>(),
    );
    Ok(CheckedPose {
        pose,
        orthonormality_error: err,
        reorthonormalised: err > ORTHONORMAL_TOLERANCE,
    })
}

/// Opens `path` and reads its dataset `dataset` as `f64`, returning its shape too.
/// Integer or float storage of any width that widens exactly to `f64` is accepted.
pub fn read_hdf5_f64(path: &Path) -> Result<(Vec<usize>, Vec<f64>)> {
    let ds = open_dataset(path)?;
    let data = ds
        .read_numeric_as::<f64>()
        .map_err(|e| anyhow!("{}: reading dataset: {e}", path.display()))?;
    Ok((ds.shape(), data))
}

fn open_dataset(path: &Path) -> Result<rust_hdf5::H5Dataset> {
    if !path.is_file() {
        bail!("{}: file not found", path.display());
    }
    let file = rust_hdf5::H5File::open(path)
        .map_err(|e| anyhow!("{}: not a readable HDF5 file: {e}", path.display()))?;
    file.dataset("dataset")
        .map_err(|e| anyhow!("{}: no readable dataset `dataset`: {e}", path.display()))
}

fn check_shape(path: &Path, got: &[usize], want: &[usize]) -> Result<()> {
    ensure!(
        got == want,
        "{}: dataset has shape {got:?}, expected {want:?}",
        path.display()
    );
    Ok(())
}

/// Reads a `depth_meters` file (float16/32) of shape `[height, width]`.
pub fn read_depth(path: &Path, shape: [usize; 2]) -> Result<Vec<f32>> {
    let ds = open_dataset(path)?;
    check_shape(path, &ds.shape(), &shape)?;
    let data = ds
        .read_numeric_as::<f32>()
        .map_err(|e| anyhow!("{}: reading depth: {e}", path.display()))?;
    ensure!(
        data.len() == shape[0] * shape[1],
        "{}: {} depth values for shape {shape:?}",
        path.display(),
        data.len()
    );
    Ok(data)
}

/// Reads a `semantic` file (int16, `-1` void, `1..=40` NYU40) of shape
/// `[height, width]` as labels `0` void / `1..=40`.
pub fn read_semantic(path: &Path, shape: [usize; 2]) -> Result<Vec<u8>> {
    let ds = open_dataset(path)?;
    check_shape(path, &ds.shape(), &shape)?;
    let raw = ds
        .read_numeric_as::<i32>()
        .map_err(|e| anyhow!("{}: reading labels: {e}", path.display()))?;
    ensure!(
        raw.len() == shape[0] * shape[1],
        "{}: {} labels for shape {shape:?}",
        path.display(),
        raw.len()
    );
    raw.iter()
        .enumerate()
        .map(|(i, &c)| match c {
            -1 | 0 => Ok(0),
            1..=40 => Ok(c as u8),
            _ => Err(anyhow!(
                "{}: pixel {i} has label {c}, expected -1 or 1..=40",
                path.display()
            )),
        })
        .collect()
}

/// Reads and checks the keyframe poses of one trajectory from its `_detail/<cam>`
/// directory (see [`cv_pose`]); errors name the file and the keyframe.
pub fn read_keyframe_poses(cam_dir: &Path, meters_per_asset_unit: f64) -> Result<KeyframePoses> {
    let o_path = cam_dir.join("camera_keyframe_orientations.hdf5");
    let p_path = cam_dir.join("camera_keyframe_positions.hdf5");
    let (o_shape, o) = read_hdf5_f64(&o_path)?;
    let (p_shape, p) = read_hdf5_f64(&p_path)?;
    ensure!(
        o_shape.len() == 3 && o_shape[1..] == [3, 3],
        "{}: orientations have shape {o_shape:?}, expected (N, 3, 3)",
        o_path.display()
    );
    ensure!(
        p_shape.len() == 2 && p_shape[1] == 3,
        "{}: positions have shape {p_shape:?}, expected (N, 3)",
        p_path.display()
    );
    ensure!(
        o_shape[0] == p_shape[0],
        "{}: {} orientations but {} positions in {}",
        o_path.display(),
        o_shape[0],
        p_shape[0],
        p_path.display()
    );
    let mut out = KeyframePoses {
        poses: Vec::with_capacity(o_shape[0]),
        reorthonormalised: Vec::new(),
    };
    for k in 0..o_shape[0] {
        // HDF5 is row-major: element (k, i, j) is o[9k + 3i + j].
        let r = Matrix3::from_row_slice(&o[9 * k..9 * k + 9]);
        let t = Vector3::from_row_slice(&p[3 * k..3 * k + 3]);
        let checked = cv_pose(&r, &t, meters_per_asset_unit).with_context(|| {
            format!(
                "{} / {}: keyframe {k}",
                o_path.display(),
                p_path.file_name().unwrap_or_default().to_string_lossy()
            )
        })?;
        if checked.reorthonormalised {
            out.reorthonormalised.push(k);
        }
        out.poses.push(checked.pose);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uv_grid_is_pixel_centres() {
        // 4 x 2 image: u in {-3/4, -1/4, 1/4, 3/4}, v in {1/2, -1/2} (top row first).
        assert_eq!(pixel_uv(0, 0, 4, 2), (-0.75, 0.5));
        assert_eq!(pixel_uv(1, 0, 4, 2), (-0.25, 0.5));
        assert_eq!(pixel_uv(3, 1, 4, 2), (0.75, -0.5));
        // 1024 x 768: first and last centres.
        let (u0, v0) = pixel_uv(0, 0, 1024, 768);
        let (u1, v1) = pixel_uv(1023, 767, 1024, 768);
        assert!((u0 - (-1.0 + 1.0 / 1024.0)).abs() < 1e-15);
        assert!((v0 - (1.0 - 1.0 / 768.0)).abs() < 1e-15);
        assert!((u1 - (1.0 - 1.0 / 1024.0)).abs() < 1e-15);
        assert!((v1 - (-1.0 + 1.0 / 768.0)).abs() < 1e-15);
    }

    #[test]
    fn gl_rays_become_cv_unit_z() {
        // GL forward (0, 0, -1) is CV forward (0, 0, 1); GL up is CV up = -y.
        assert_eq!(gl_ray_to_cv_unit_z([0.0, 0.0, -1.0]), Some([0.0, 0.0, 1.0]));
        assert_eq!(
            gl_ray_to_cv_unit_z([1.0, 2.0, -2.0]),
            Some([0.5, -1.0, 1.0])
        );
        assert_eq!(gl_ray_to_cv_unit_z([0.0, 0.0, 1.0]), None);
        assert_eq!(gl_ray_to_cv_unit_z([0.0, 0.0, f64::NAN]), None);
    }

    #[test]
    fn pinhole_matrix_gives_pinhole_rays() {
        // M = diag(a, b, -1) is a centred pinhole: fx = W / (2a), cx = W / 2.
        let params = CameraParams {
            width: 4,
            height: 2,
            meters_scale: 1.0,
            m_cam_from_uv: [[0.5, 0.0, 0.0], [0.0, 0.25, 0.0], [0.0, 0.0, -1.0]],
        };
        assert!(!params.is_tilt_shift());
        let rays = per_pixel_rays(&params).unwrap();
        // pixel (0, 0): u = -0.75, v = 0.5 -> GL (-0.375, 0.125, -1) -> CV (-0.375, -0.125, 1)
        assert_eq!(rays.ray(0, 0), [-0.375, -0.125, 1.0]);
        assert_eq!(rays.ray(3, 1), [0.375, 0.125, 1.0]);
        let pin = sndt_core::Pinhole {
            fx: 4.0,
            fy: 4.0,
            cx: 2.0,
            cy: 1.0,
            width: 4,
            height: 2,
        };
        for (c, r) in [(0, 0), (1, 0), (2, 1), (3, 1)] {
            assert_eq!(rays.ray(c, r), pin.ray(c, r));
        }
    }

    #[test]
    fn tilt_shift_offsets_rays() {
        // A shift of 0.1 in GL y moves every CV ray up by 0.1 (y down in CV).
        let params = CameraParams {
            width: 2,
            height: 2,
            meters_scale: 1.0,
            m_cam_from_uv: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.1], [0.0, 0.0, -1.0]],
        };
        assert!(params.is_tilt_shift());
        let rays = per_pixel_rays(&params).unwrap();
        assert!((rays.ray(0, 0)[1] - (-0.5 - 0.1)).abs() < 1e-7);
        assert!((rays.ray(0, 1)[1] - (0.5 - 0.1)).abs() < 1e-7);
        let backwards = CameraParams {
            m_cam_from_uv: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            ..params
        };
        assert!(per_pixel_rays(&backwards).is_err());
        assert!(check_rays(&backwards).is_err());
        assert!(check_rays(&params).is_ok());
    }

    #[test]
    fn gl_to_cv_flips_y_and_z_columns() {
        let r = Matrix3::new(1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0);
        let want = Matrix3::new(1.0, -2.0, -3.0, 4.0, -5.0, -6.0, 7.0, -8.0, -9.0);
        assert_eq!(gl_to_cv(&r), want);
        // An identity GL camera (looking along world -z, y up) is an OpenCV camera
        // looking along world -z with y pointing down (world -y).
        let cv = gl_to_cv(&Matrix3::identity());
        assert_eq!(cv * Vector3::z(), -Vector3::z());
        assert_eq!(cv * Vector3::y(), -Vector3::y());
    }

    #[test]
    fn orthonormalisation_repairs_small_errors() {
        // Scaling one axis by 1 + e has orthonormality error 2e + e²; its nearest rotation
        // is the identity.
        let e = 1e-4;
        let r = Matrix3::from_diagonal(&Vector3::new(1.0 + e, 1.0, 1.0));
        assert!((orthonormality_error(&r) - (2.0 * e + e * e)).abs() < 1e-12);
        let q = nearest_rotation(&r).unwrap();
        assert!((q - Matrix3::identity()).abs().max() < 1e-12);
        // A rotation about z by 90° with a small shear: nearest rotation is close to it.
        let rz = Matrix3::new(0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0);
        let sheared = rz + Matrix3::new(0.0, 0.0, 0.0, 0.0, 0.0, 1e-3, 0.0, 0.0, 0.0);
        let fixed = nearest_rotation(&sheared).unwrap();
        assert!(orthonormality_error(&fixed) < 1e-12);
        assert!((fixed.determinant() - 1.0).abs() < 1e-12);
        assert!((fixed - rz).abs().max() < 1e-3);

        let p = cv_pose(&sheared, &Vector3::new(100.0, -200.0, 50.0), 0.01).unwrap();
        assert!(p.reorthonormalised);
        let t = p.pose.translation.vector;
        assert_eq!((t.x, t.y, t.z), (1.0, -2.0, 0.5));
        let exact = cv_pose(&rz, &Vector3::zeros(), 1.0).unwrap();
        assert!(!exact.reorthonormalised);
        let m = exact.pose.rotation.to_rotation_matrix().into_inner();
        let want = gl_to_cv(&rz).cast::<f32>();
        assert!((m - want).abs().max() < 1e-6);
    }

    #[test]
    fn bad_poses_are_rejected() {
        let mut nan = Matrix3::identity();
        nan[(1, 2)] = f64::NAN;
        assert!(cv_pose(&nan, &Vector3::zeros(), 1.0).is_err());
        assert!(cv_pose(
            &Matrix3::identity(),
            &Vector3::new(f64::INFINITY, 0.0, 0.0),
            1.0
        )
        .is_err());
        // Badly non-orthonormal (a factor 2) and a reflection.
        assert!(cv_pose(&(Matrix3::identity() * 2.0), &Vector3::zeros(), 1.0).is_err());
        let mirror = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0));
        let e = cv_pose(&mirror, &Vector3::zeros(), 1.0).unwrap_err();
        assert!(e.to_string().contains("reflection"), "{e}");
    }

    #[test]
    fn csv_lines_with_quotes() {
        assert_eq!(
            split_csv_line("a,\"AColor(0, 0, 0, 0)\",,1.5\r"),
            vec!["a", "AColor(0, 0, 0, 0)", "", "1.5"]
        );
        assert_eq!(split_csv_line("\"x\"\"y\",z"), vec!["x\"y", "z"]);
    }
}
