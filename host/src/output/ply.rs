//! Coloured point clouds as binary little-endian PLY (for MeshLab, CloudCompare, Blender).

use crate::dataset::frame::Frame;
use anyhow::{Context, Result};
use std::fmt;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Colour of points of a frame without labels.
pub const GREY: [u8; 3] = [128, 128, 128];

/// Writes `points` (position, RGB) as a binary little-endian PLY with one `vertex`
/// element of `float x, y, z` and `uchar red, green, blue` (15 bytes per point).
///
/// ```
/// # let path = std::env::temp_dir().join(format!("sndt-ply-doc-{}.ply", std::process::id()));
/// sndt_host::output::ply::write_points(&path, &[([1.0, 2.0, 3.0], [255, 0, 0])]).unwrap();
/// let bytes = std::fs::read(&path).unwrap();
/// assert!(bytes.starts_with(b"ply\nformat binary_little_endian 1.0\nelement vertex 1\n"));
/// assert_eq!(&bytes[bytes.len() - 3..], &[255, 0, 0]);
/// # std::fs::remove_file(&path).unwrap();
/// ```
pub fn write_points(path: &Path, points: &[([f32; 3], [u8; 3])]) -> Result<()> {
    crate::atomic::write_atomic(path, |tmp| write_points_to(tmp, points))
}

/// What [`write_points`] writes, into `path` directly.
fn write_points_to(path: &Path, points: &[([f32; 3], [u8; 3])]) -> Result<()> {
    let shown = path.display();
    let file = File::create(path).with_context(|| format!("{shown}: creating"))?;
    let mut w = BufWriter::new(file);
    let header = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n",
        points.len()
    );
    let mut body = Vec::with_capacity(header.len() + points.len() * 15);
    body.extend_from_slice(header.as_bytes());
    for (p, c) in points {
        for v in p {
            body.extend_from_slice(&v.to_le_bytes());
        }
        body.extend_from_slice(c);
    }
    w.write_all(&body)
        .and_then(|()| w.flush())
        .with_context(|| format!("{shown}: writing"))
}

/// The world points of a frame ([`Frame::world_points`]) coloured by their ground-truth
/// label ([`crate::dataset::classes::color`], void black), or [`GREY`] when the frame has no labels.
pub fn frame_points(frame: &Frame) -> Vec<([f32; 3], [u8; 3])> {
    let labelled = frame.labels.is_some();
    frame
        .world_points()
        .into_iter()
        .map(|(p, l)| {
            (
                p,
                if labelled {
                    crate::dataset::classes::color(l)
                } else {
                    GREY
                },
            )
        })
        .collect()
}

/// What [`write_frame_cloud`] wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct CloudSummary {
    /// The PLY file.
    pub path: PathBuf,
    /// Number of points.
    pub points: usize,
    /// Axis-aligned bounding box `(min, max)` in world coordinates; `None` without points.
    pub bounds: Option<([f32; 3], [f32; 3])>,
}

impl fmt::Display for CloudSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "wrote {}: {} points", self.path.display(), self.points)?;
        if let Some((lo, hi)) = self.bounds {
            write!(
                f,
                ", bounding box [{:.3}, {:.3}, {:.3}] .. [{:.3}, {:.3}, {:.3}] m",
                lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
            )?;
        }
        Ok(())
    }
}

/// Writes the coloured world points of `frame` ([`frame_points`]) to `out`.
///
/// ```
/// use sndt_host::dataset::{Frame, FrameId, Rays};
/// let cam = sndt_core::Pinhole { fx: 1.0, fy: 1.0, cx: 1.0, cy: 1.0, width: 2, height: 2 };
/// let frame = Frame {
///     id: FrameId::parse("s/c/0").unwrap(),
///     pose: sndt_core::Isometry3::identity(),
///     rays: std::sync::Arc::new(Rays::Pinhole(cam)),
///     depth: vec![2.0, 2.0, 0.0, 2.0],
///     depth_kind: sndt_core::DepthKind::Planar,
///     labels: None,
///     predictions: None,
/// };
/// # let out = std::env::temp_dir().join(format!("sndt-cloud-doc-{}.ply", std::process::id()));
/// let s = sndt_host::output::ply::write_frame_cloud(&frame, &out).unwrap();
/// assert_eq!(s.points, 3);
/// assert_eq!(s.bounds, Some(([-1.0, -1.0, 2.0], [1.0, 1.0, 2.0])));
/// # std::fs::remove_file(&out).unwrap();
/// ```
pub fn write_frame_cloud(frame: &Frame, out: &Path) -> Result<CloudSummary> {
    let points = frame_points(frame);
    write_points(out, &points)?;
    let bounds = points
        .iter()
        .fold(None, |acc: Option<([f32; 3], [f32; 3])>, (p, _)| {
            let (mut lo, mut hi) = acc.unwrap_or((*p, *p));
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
            Some((lo, hi))
        });
    Ok(CloudSummary {
        path: out.to_path_buf(),
        points: points.len(),
        bounds,
    })
}
