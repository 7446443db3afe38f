//! One frame type and one dataset interface for every source: our synthetic scenes, the
//! prepared layout (ours and the authors' v0.3.1), raw Hypersim HDF5, plus ESANet top-k
//! predictions beside any of them.
//!
//! Conventions, the same for every reader:
//! - poses are camera-to-world, metres, world as the dataset defines it (z up for
//!   Hypersim and ours), **OpenCV camera axes** (x right, y down, z forward);
//! - pixel rays have unit z in that camera frame, so a planar depth `d` gives the point
//!   `d * ray` and a Euclidean range `r` gives `r * ray / |ray|`;
//! - depth `0`, NaN, inf or negative means "no measurement";
//! - labels: `0` void, `1..=40` NYU40.

use anyhow::{bail, Context, Result};
use sndt_core::{
    depth_point, validate_pose, Depth, DepthImage, DepthKind, Isometry3, LabelImage, LabeledPoint,
    Labels, Pinhole, Point3,
};
use std::fmt;
use std::sync::Arc;

/// Identifies a frame as `<scene>/<cam>/<NNNN>` (the split-list line format).
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct FrameId {
    /// Scene name, e.g. `ai_001_010` or `synth_00_bedroom`.
    pub scene: String,
    /// Camera/trajectory name, e.g. `cam_00`.
    pub cam: String,
    /// Frame index within the trajectory.
    pub index: u32,
}

impl FrameId {
    /// Parses `scene/cam/NNNN` (surrounding whitespace ignored).
    ///
    /// ```
    /// let id = sndt_host::dataset::FrameId::parse("ai_001_010/cam_00/0007").unwrap();
    /// assert_eq!((id.scene.as_str(), id.cam.as_str(), id.index), ("ai_001_010", "cam_00", 7));
    /// assert_eq!(id.to_string(), "ai_001_010/cam_00/0007");
    /// assert!(sndt_host::dataset::FrameId::parse("ai_001_010/0007").is_err());
    /// ```
    pub fn parse(s: &str) -> Result<FrameId> {
        let parts: Vec<&str> = s.trim().split('/').collect();
        if parts.len() != 3 || parts[0].is_empty() || parts[1].is_empty() {
            bail!("frame id {s:?} is not <scene>/<cam>/<NNNN>");
        }
        let index = parts[2]
            .parse()
            .with_context(|| format!("frame id {s:?}: frame number {:?}", parts[2]))?;
        Ok(FrameId {
            scene: parts[0].to_string(),
            cam: parts[1].to_string(),
            index,
        })
    }

    /// `scene/cam`: the trajectory this frame belongs to.
    pub fn trajectory(&self) -> String {
        format!("{}/{}", self.scene, self.cam)
    }

    /// The file stem used by the prepared layout: `NNNN`.
    pub fn stem(&self) -> String {
        format!("{:04}", self.index)
    }
}

impl fmt::Display for FrameId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}/{:04}", self.scene, self.cam, self.index)
    }
}

/// How pixels map to rays in the OpenCV camera frame.
#[derive(Clone, Debug, PartialEq)]
pub enum Rays {
    /// An ideal pinhole.
    Pinhole(Pinhole),
    /// One ray per pixel (row-major, unit z), e.g. Hypersim's tilt-shift cameras.
    PerPixel {
        /// Image width.
        width: u32,
        /// Image height.
        height: u32,
        /// `width * height` directions with z = 1.
        dirs: Vec<[f32; 3]>,
    },
}

impl Rays {
    /// Image width.
    pub fn width(&self) -> u32 {
        match self {
            Rays::Pinhole(p) => p.width,
            Rays::PerPixel { width, .. } => *width,
        }
    }

    /// Image height.
    pub fn height(&self) -> u32 {
        match self {
            Rays::Pinhole(p) => p.height,
            Rays::PerPixel { height, .. } => *height,
        }
    }

    /// The ray (unit z) of pixel `(col, row)`.
    ///
    /// ```
    /// use sndt_host::dataset::Rays;
    /// let cam = sndt_core::Pinhole { fx: 2.0, fy: 2.0, cx: 1.0, cy: 1.0, width: 2, height: 2 };
    /// assert_eq!(Rays::Pinhole(cam).ray(1, 1), [0.25, 0.25, 1.0]);
    /// ```
    pub fn ray(&self, col: u32, row: u32) -> [f32; 3] {
        match self {
            Rays::Pinhole(p) => p.ray(col, row),
            Rays::PerPixel { width, dirs, .. } => dirs[(row * width + col) as usize],
        }
    }
}

/// Top-k predicted labels per pixel (ESANet style: best first, scores in 0..1).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TopK {
    /// Classes per pixel, best first (1..=40; 0 = unused entry).
    pub classes: Vec<[u8; 3]>,
    /// Scores per pixel, matching `classes`.
    pub scores: Vec<[f32; 3]>,
}

impl TopK {
    /// The best class of every pixel.
    pub fn top1(&self) -> Vec<u8> {
        self.classes.iter().map(|c| c[0]).collect()
    }

    /// Pixel `i` as the core's labels (scores scaled to 0..=255).
    pub fn labels(&self, i: usize) -> Labels {
        let (c, s) = (self.classes[i], self.scores[i]);
        let q = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
        let pairs: Vec<(u8, u8)> = (0..3)
            .filter(|&k| c[k] != 0)
            .map(|k| (c[k], q(s[k])))
            .collect();
        Labels::top_k(&pairs)
    }
}

/// Which labels to attach to points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LabelSource {
    /// Ground-truth labels (void pixels add geometry only).
    Gt,
    /// Predicted top-1 labels.
    Pred,
    /// Predicted top-k labels with scores.
    PredTopk,
    /// No labels: geometry only.
    None,
}

/// One frame of a dataset.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Which frame.
    pub id: FrameId,
    /// Camera-to-world, metres, OpenCV camera axes.
    pub pose: Isometry3<f32>,
    /// Pixel rays (shared by the frames of one camera).
    pub rays: Arc<Rays>,
    /// Depth in metres, row-major; see `depth_kind`.
    pub depth: Vec<f32>,
    /// Planar depth or Euclidean range.
    pub depth_kind: DepthKind,
    /// Ground-truth labels (0 void, 1..=40), when the dataset has them.
    pub labels: Option<Vec<u8>>,
    /// Predicted top-k labels, when available.
    pub predictions: Option<TopK>,
}

impl Frame {
    /// Number of pixels.
    pub fn pixels(&self) -> usize {
        self.depth.len()
    }

    /// The measured point of pixel `i` in the camera frame, or `None` without a
    /// measurement: the core's [`depth_point`] along the pixel's ray, so the host and the
    /// core turn a pixel into the same point bit for bit.
    pub fn camera_point(&self, i: usize) -> Option<[f32; 3]> {
        let w = self.rays.width();
        let ray = self.rays.ray(i as u32 % w, i as u32 / w);
        depth_point(ray, self.depth[i], self.depth_kind)
    }

    /// Planar depth (z in the camera frame) of pixel `i`, or `None` without a measurement.
    pub fn planar_depth(&self, i: usize) -> Option<f32> {
        self.camera_point(i).map(|p| p[2])
    }

    /// Calls `visit(i, point)` for every measured pixel `i` (row-major, every `stride`-th
    /// pixel in both directions, `stride` 0 taken as 1) with its camera-frame point.
    pub fn for_each_camera_point(&self, stride: u32, mut visit: impl FnMut(usize, [f32; 3])) {
        let (w, h) = (self.rays.width(), self.rays.height());
        let stride = stride.max(1) as usize;
        for row in (0..h).step_by(stride) {
            for col in (0..w).step_by(stride) {
                let i = (row * w + col) as usize;
                if let Some(p) =
                    depth_point(self.rays.ray(col, row), self.depth[i], self.depth_kind)
                {
                    visit(i, p);
                }
            }
        }
    }

    /// The frame's depth without labels as the core's [`DepthImage`], every `stride`-th
    /// pixel, for a pinhole frame (`None` for per-pixel rays): what the see-through test
    /// of the f64 reference consults beside the frame's points.
    pub fn depth_view(&self, stride: u32) -> Option<DepthImage<'_>> {
        match self.rays.as_ref() {
            Rays::Pinhole(camera) => Some(DepthImage {
                camera: *camera,
                depth: Depth::Metres(&self.depth),
                kind: self.depth_kind,
                labels: LabelImage::None,
                stride: stride.max(1),
            }),
            Rays::PerPixel { .. } => None,
        }
    }

    /// The points integration takes from the frame, with labels from `source`, every
    /// `stride`-th pixel: a pinhole frame's exactly as the core's depth path computes them
    /// ([`DepthImage::point`]), else [`Frame::camera_points`]. What the f64 reference gets
    /// beside [`Frame::depth_view`], so that it sees the core's input bit for bit.
    pub fn integration_points(&self, source: LabelSource, stride: u32) -> Vec<LabeledPoint> {
        let Some(view) = self.depth_view(stride) else {
            return self.camera_points(source, stride);
        };
        let s = stride.max(1) as usize;
        let (w, h) = (view.camera.width, view.camera.height);
        let mut out = Vec::with_capacity(self.pixels() / (s * s));
        for row in (0..h).step_by(s) {
            for col in (0..w).step_by(s) {
                if let Some(p) = view.point(col, row) {
                    let i = row as usize * w as usize + col as usize;
                    out.push(LabeledPoint::new(
                        Point3::from(p),
                        self.point_labels(i, source),
                    ));
                }
            }
        }
        out
    }

    /// Planar depth image (0 where there is no measurement), as the evaluation's GT mask
    /// and the prepared layout want it.
    pub fn planar_depth_image(&self) -> Vec<f32> {
        (0..self.pixels())
            .map(|i| self.planar_depth(i).unwrap_or(0.0))
            .collect()
    }

    /// The label of pixel `i` for `source`.
    pub fn point_labels(&self, i: usize, source: LabelSource) -> Labels {
        match source {
            LabelSource::None => Labels::NONE,
            LabelSource::Gt => match &self.labels {
                Some(l) if l[i] != 0 => Labels::top1(l[i]),
                _ => Labels::NONE,
            },
            LabelSource::Pred => match &self.predictions {
                Some(p) if p.classes[i][0] != 0 => Labels::top1(p.classes[i][0]),
                _ => Labels::NONE,
            },
            LabelSource::PredTopk => match &self.predictions {
                Some(p) => p.labels(i),
                None => Labels::NONE,
            },
        }
    }

    /// Measured points in the camera frame with labels from `source`, every `stride`-th
    /// pixel in both directions.
    pub fn camera_points(&self, source: LabelSource, stride: u32) -> Vec<LabeledPoint> {
        let stride = stride.max(1);
        let mut out = Vec::with_capacity(self.pixels() / (stride * stride) as usize);
        self.for_each_camera_point(stride, |i, p| {
            out.push(LabeledPoint::new(
                Point3::from(p),
                self.point_labels(i, source),
            ));
        });
        out
    }

    /// Measured points in world coordinates with their ground-truth label (0 when the
    /// frame has none), every pixel.
    pub fn world_points(&self) -> Vec<([f32; 3], u8)> {
        let mut out = Vec::with_capacity(self.pixels());
        self.for_each_camera_point(1, |i, p| {
            let p = self.pose * Point3::from(p);
            let l = self.labels.as_ref().map_or(0, |l| l[i]);
            out.push(([p.x, p.y, p.z], l));
        });
        out
    }

    /// Checks shapes and values: image sizes agree, the pose passes the core's
    /// [`validate_pose`] (finite, unit rotation), labels are
    /// 0..=40. Readers call this so that a bad file fails where it is read.
    pub fn validate(&self) -> Result<()> {
        let n = self.rays.width() as usize * self.rays.height() as usize;
        if self.depth.len() != n {
            bail!(
                "{}: depth has {} pixels, camera has {n}",
                self.id,
                self.depth.len()
            );
        }
        if let Rays::PerPixel { dirs, .. } = self.rays.as_ref()
            && dirs.len() != n
        {
            bail!("{}: {} rays for {n} pixels", self.id, dirs.len());
        }
        if let Some(l) = &self.labels {
            if l.len() != n {
                bail!("{}: labels have {} pixels, depth has {n}", self.id, l.len());
            }
            if let Some(bad) = l.iter().find(|&&c| c > 40) {
                bail!("{}: label {bad} is outside 0..=40", self.id);
            }
        }
        if let Some(p) = &self.predictions
            && (p.classes.len() != n || p.scores.len() != n)
        {
            bail!(
                "{}: predictions have {} pixels, depth has {n}",
                self.id,
                p.classes.len()
            );
        }
        if validate_pose(&self.pose).is_err() {
            bail!(
                "{}: pose is not finite or its rotation is not unit",
                self.id
            );
        }
        Ok(())
    }
}

/// A number as messages show it: plainly, or in exponent notation when very large or
/// small (`1e39`, not 40 digits).
///
/// ```
/// use sndt_host::dataset::frame::show_number;
/// assert_eq!(show_number(1e39f64), "1e39");
/// assert_eq!(show_number(1e7f32), "1e7");
/// assert_eq!(show_number(-0.25f64), "-0.25");
/// assert_eq!(show_number(0f64), "0");
/// ```
pub fn show_number<T>(v: T) -> String
where
    T: Copy + Into<f64> + fmt::Display + fmt::LowerExp,
{
    let x: f64 = v.into();
    if x != 0.0 && x.is_finite() && (x.abs() >= 1e6 || x.abs() < 1e-3) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// Why a camera at `pose` cannot be mapped with `cell_size` cells, or `None` when it can:
/// a position component outside the key range (the core's `Error::PoseOutOfRange`), with
/// the value and the range.
///
/// ```
/// use sndt_host::dataset::frame::key_range_error;
/// let far = sndt_core::Isometry3::translation(1e7, 0.0, 0.0);
/// assert_eq!(
///     key_range_error(&far, 0.1).unwrap(),
///     "position x = 1e7 m is outside the map's key range (±32767 cells of 0.1 m, about ±3276.7 m)"
/// );
/// assert!(key_range_error(&sndt_core::Isometry3::identity(), 0.1).is_none());
/// ```
pub fn key_range_error(pose: &Isometry3<f32>, cell_size: f32) -> Option<String> {
    let t = pose.translation.vector;
    let (axis, v) = [("x", t.x), ("y", t.y), ("z", t.z)]
        .into_iter()
        .find(|&(_, v)| sndt_core::VoxelKey::from_point(&[v, 0.0, 0.0], cell_size).is_none())?;
    let limit = sndt_core::KEY_LIMIT;
    let metres = limit as f64 * format!("{cell_size}").parse::<f64>().unwrap_or(0.0);
    Some(format!(
        "position {axis} = {} m is outside the map's key range (±{limit} cells of {cell_size} m, about ±{metres:.1} m)",
        show_number(v)
    ))
}
