//! Frames as raw world points for other mappers: the sensor origin and the world-frame
//! points of every frame, the points the core integrates, in a small binary file
//! (`SNDTPTS1`) that `scripts/peers/octomap_bench.cpp` reads to build OctoMap from the
//! same input as sndt.
//!
//! Format, all little-endian:
//!
//! | bytes | content |
//! |---|---|
//! | 8 | magic `SNDTPTS1` |
//! | 4 | `u32` number of frames |
//!
//! then per frame:
//!
//! | bytes | content |
//! |---|---|
//! | 12 | `3 x f32` sensor origin (the pose's translation), world, metres |
//! | 4 | `u32` number of points `n` |
//! | 12 n | `n x 3 x f32` world points `x, y, z`, metres |
//!
//! The points of a frame are those of every measured pixel, row-major
//! ([`Frame::for_each_camera_point`], the core's `depth_point`), moved to the world by
//! `frame.pose * point` in `f32`: the points the core integrates, the same pixels and
//! depths (the core's depth-image path computes pixel rays with reciprocals, which can
//! differ from `Pinhole::ray` in the last bit). Points beyond the map's `max_range` are
//! kept: the consumer applies its own maximum range, as the core does.

use crate::dataset::frame::{Frame, FrameId};
use crate::dataset::source::Dataset;
use anyhow::{bail, Context, Result};
use sndt_core::Point3;
use std::fmt;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// The first 8 bytes of a points file.
pub const MAGIC: &[u8; 8] = b"SNDTPTS1";

/// One frame's sensor origin and measured world points.
///
/// ```
/// use sndt_host::dataset::{Frame, FrameId, Rays};
/// use sndt_core::{Isometry3, Translation3, UnitQuaternion};
/// let cam = sndt_core::Pinhole { fx: 1.0, fy: 1.0, cx: 1.0, cy: 1.0, width: 2, height: 2 };
/// let frame = Frame {
///     id: FrameId::parse("s/c/0").unwrap(),
///     pose: Isometry3::from_parts(Translation3::new(1.0, 2.0, 3.0), UnitQuaternion::identity()),
///     rays: std::sync::Arc::new(Rays::Pinhole(cam)),
///     depth: vec![2.0, 0.0, f32::NAN, 2.0],
///     depth_kind: sndt_core::DepthKind::Planar,
///     labels: None,
///     predictions: None,
/// };
/// let (origin, points) = sndt_host::output::points::frame_points(&frame);
/// assert_eq!(origin, [1.0, 2.0, 3.0]);
/// assert_eq!(points, [[0.0, 1.0, 5.0], [2.0, 3.0, 5.0]]);
/// ```
pub fn frame_points(frame: &Frame) -> ([f32; 3], Vec<[f32; 3]>) {
    let t = frame.pose.translation.vector;
    let mut points = Vec::with_capacity(frame.pixels());
    frame.for_each_camera_point(1, |_, p| {
        let w = frame.pose * Point3::from(p);
        points.push([w.x, w.y, w.z]);
    });
    ([t.x, t.y, t.z], points)
}

/// What [`write_points`] wrote.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PointsSummary {
    /// The file.
    pub path: PathBuf,
    /// Number of frames.
    pub frames: usize,
    /// Number of points over all frames.
    pub points: usize,
}

impl fmt::Display for PointsSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "wrote {}: {} frames, {} points",
            self.path.display(),
            self.frames,
            self.points
        )
    }
}

/// Writes frames `ids` of `data`, in that order, to `out` in the format above (one frame
/// in memory at a time), creating `out`'s directory.
///
/// ```
/// use sndt_host::dataset::{open_spec, Dataset};
/// let data = open_spec("synthetic:1:2", &Default::default()).unwrap();
/// # let out = std::env::temp_dir().join(format!("sndt-points-doc-{}.bin", std::process::id()));
/// let s = sndt_host::output::points::write_points(data.as_ref(), &data.frames()[..1], &out).unwrap();
/// assert_eq!(s.frames, 1);
/// let bytes = std::fs::read(&out).unwrap();
/// assert_eq!(&bytes[..8], b"SNDTPTS1");
/// assert_eq!(bytes.len(), 12 + 16 + 12 * s.points);
/// # std::fs::remove_file(&out).unwrap();
/// ```
pub fn write_points(data: &dyn Dataset, ids: &[FrameId], out: &Path) -> Result<PointsSummary> {
    let mut summary = None;
    crate::atomic::write_atomic(out, |tmp| {
        summary = Some(write_points_to(data, ids, tmp)?);
        Ok(())
    })?;
    summary.ok_or_else(|| anyhow::anyhow!("{}: nothing written", out.display()))
}

/// What [`write_points`] writes, into `out` directly.
fn write_points_to(data: &dyn Dataset, ids: &[FrameId], out: &Path) -> Result<PointsSummary> {
    let mut w = PointsWriter::create_at(out, ids.len())?;
    for id in ids {
        let frame = data
            .load(id)
            .with_context(|| format!("loading frame {id}"))?;
        w.add_frame(&frame)?;
    }
    w.finish_at()
}

/// Writes a points file frame by frame, for a caller that has the frames at hand (the
/// dynamics report renders each frame once for every map): the header with the frame
/// count first, then [`PointsWriter::add_frame`] once per frame, then
/// [`PointsWriter::finish`], which refuses a count that does not match. The file appears
/// under its name only when finished.
///
/// ```
/// use sndt_host::dataset::{open_spec, Dataset};
/// use sndt_host::output::points::PointsWriter;
/// let data = open_spec("synthetic:1:2", &Default::default()).unwrap();
/// let path = std::env::temp_dir().join(format!("sndt-pw-{}.bin", std::process::id()));
/// let mut w = PointsWriter::create(&path, 2).unwrap();
/// for id in data.frames() {
///     w.add_frame(&data.load(id).unwrap()).unwrap();
/// }
/// let summary = w.finish().unwrap();
/// assert_eq!((summary.frames, summary.points), (2, 2 * 1024 * 768));
/// # std::fs::remove_file(&path).unwrap();
/// ```
pub struct PointsWriter {
    w: BufWriter<File>,
    /// Where the file is written, and where it goes when finished.
    tmp: PathBuf,
    path: PathBuf,
    frames: usize,
    written: usize,
    points: usize,
}

impl PointsWriter {
    /// Starts a file of `frames` frames at `path` (written beside it until finished).
    pub fn create(path: &Path, frames: usize) -> Result<PointsWriter> {
        let tmp = crate::atomic::temporary(path)?;
        let mut w = Self::create_at(&tmp, frames)?;
        w.path = path.to_path_buf();
        Ok(w)
    }

    /// Starts the file at `path` itself.
    fn create_at(path: &Path, frames: usize) -> Result<PointsWriter> {
        let shown = path.display();
        let count = u32::try_from(frames).context("too many frames")?;
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        }
        let file = File::create(path).with_context(|| format!("{shown}: creating"))?;
        let mut w = BufWriter::new(file);
        let mut header = MAGIC.to_vec();
        header.extend_from_slice(&count.to_le_bytes());
        w.write_all(&header)
            .with_context(|| format!("{shown}: writing"))?;
        Ok(PointsWriter {
            w,
            tmp: path.to_path_buf(),
            path: path.to_path_buf(),
            frames,
            written: 0,
            points: 0,
        })
    }

    /// Appends one frame's sensor origin and world points ([`frame_points`]).
    pub fn add_frame(&mut self, frame: &Frame) -> Result<()> {
        let (origin, pts) = frame_points(frame);
        let Ok(n) = u32::try_from(pts.len()) else {
            bail!("{}: {} points do not fit a u32 count", frame.id, pts.len());
        };
        if self.written == self.frames {
            bail!(
                "{}: more frames than the {} announced",
                frame.id,
                self.frames
            );
        }
        let mut body = Vec::with_capacity(16 + 12 * pts.len());
        for v in origin {
            body.extend_from_slice(&v.to_le_bytes());
        }
        body.extend_from_slice(&n.to_le_bytes());
        for v in pts.iter().flatten() {
            body.extend_from_slice(&v.to_le_bytes());
        }
        self.w
            .write_all(&body)
            .with_context(|| format!("{}: writing", self.tmp.display()))?;
        self.written += 1;
        self.points += pts.len();
        Ok(())
    }

    /// Flushes the file and gives it its name.
    pub fn finish(self) -> Result<PointsSummary> {
        let (tmp, path) = (self.tmp.clone(), self.path.clone());
        let summary = self.finish_at();
        let summary = summary.and_then(|s| crate::atomic::commit(&tmp, &path).map(|()| s));
        if summary.is_err() {
            let _ = std::fs::remove_file(&tmp);
        }
        summary.map(|s| PointsSummary { path, ..s })
    }

    /// Flushes the file where it is.
    fn finish_at(mut self) -> Result<PointsSummary> {
        let shown = self.tmp.display().to_string();
        if self.written != self.frames {
            bail!(
                "{shown}: {} frames written of {}",
                self.written,
                self.frames
            );
        }
        self.w
            .flush()
            .with_context(|| format!("{shown}: writing"))?;
        Ok(PointsSummary {
            path: self.tmp.clone(),
            frames: self.frames,
            points: self.points,
        })
    }
}
