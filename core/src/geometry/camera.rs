//! The sensor side: pinhole cameras, depth images with labels, the one pixel-to-point
//! routine ([`depth_point`]) and sensor pose checks.

use crate::error::Error;
use crate::geometry::sqrt::sqrt;
use crate::labels::Labels;
use nalgebra::{Isometry3, Matrix3, Vector3};

/// Pinhole intrinsics in pixels, OpenCV camera axes (x right, y down, z forward). Pixel
/// `(col, row)` has its centre at `(col + 0.5, row + 0.5)`, so a centred principal point is
/// `cx = width / 2`.
///
/// ```
/// let cam = sndt_core::Pinhole { fx: 100.0, fy: 100.0, cx: 2.0, cy: 2.0, width: 4, height: 4 };
/// assert_eq!(cam.ray(2, 1), [0.005, -0.005, 1.0]);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Pinhole {
    /// Focal length along x, pixels.
    pub fx: f32,
    /// Focal length along y, pixels.
    pub fy: f32,
    /// Principal point x, pixels.
    pub cx: f32,
    /// Principal point y, pixels.
    pub cy: f32,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
}

impl Pinhole {
    /// Direction of the pixel's centre ray with unit z: `(col + 0.5 - cx) / fx` across,
    /// `(row + 0.5 - cy) / fy` down. Rendering and callers use this one; integration
    /// computes the same rays through reciprocals (see `PixelRays`).
    pub fn ray(&self, col: u32, row: u32) -> [f32; 3] {
        [
            (col as f32 + 0.5 - self.cx) / self.fx,
            (row as f32 + 0.5 - self.cy) / self.fy,
            1.0,
        ]
    }

    /// Finite, positive focal lengths and a finite principal point.
    pub(crate) fn valid(&self) -> bool {
        let ok = |f: f32| f.is_finite() && f > 0.0;
        ok(self.fx) && ok(self.fy) && self.cx.is_finite() && self.cy.is_finite()
    }

    /// `width * height`, or `None` when it overflows `usize` (16-bit/32-bit targets).
    pub(crate) fn pixels(&self) -> Option<usize> {
        (self.width as usize).checked_mul(self.height as usize)
    }
}

/// What a depth value means.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DepthKind {
    /// Distance along the optical axis (z), as in most depth cameras.
    Planar,
    /// Euclidean distance from the optical centre (Hypersim `depth_meters`).
    Range,
}

/// Per-pixel labels of a depth image.
#[derive(Clone, Copy, Debug)]
pub enum LabelImage<'a> {
    /// No labels: geometry only.
    None,
    /// One class id per pixel (0 = void).
    Top1(&'a [u8]),
    /// Top-k labels per pixel.
    TopK(&'a [Labels]),
}

/// The depth values of an image, row-major.
///
/// ```
/// use sndt_core::Depth;
/// let (m, mm) = ([1.5f32, 0.0], [1500u16, 0]);
/// assert_eq!(Depth::Metres(&m).len(), 2);
/// assert_eq!(Depth::Millimetres(&mm).metres(0), Some(1.5));
/// assert_eq!(Depth::Millimetres(&mm).metres(2), None); // past the end
/// ```
#[derive(Clone, Copy, Debug)]
pub enum Depth<'a> {
    /// Metres; 0, negative, NaN or inf = no return.
    Metres(&'a [f32]),
    /// Millimetres as most depth cameras give them (`16UC1`); 0 = no return. A value `v`
    /// is `v as f32 / 1000.0` metres.
    Millimetres(&'a [u16]),
}

impl Depth<'_> {
    /// Number of depth values.
    ///
    /// ```
    /// assert_eq!(sndt_core::Depth::Millimetres(&[1, 2, 3]).len(), 3);
    /// ```
    pub fn len(&self) -> usize {
        match self {
            Depth::Metres(d) => d.len(),
            Depth::Millimetres(d) => d.len(),
        }
    }

    /// No depth values at all.
    ///
    /// ```
    /// assert!(sndt_core::Depth::Metres(&[]).is_empty());
    /// ```
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Value `i` in metres, `None` past the end.
    ///
    /// ```
    /// assert_eq!(sndt_core::Depth::Millimetres(&[2500]).metres(0), Some(2.5));
    /// ```
    #[inline]
    pub fn metres(&self, i: usize) -> Option<f32> {
        match self {
            Depth::Metres(d) => d.get(i).copied(),
            Depth::Millimetres(d) => d.get(i).map(|&v| mm_to_metres(v)),
        }
    }
}

/// Millimetres to metres, the conversion of [`Depth::Millimetres`].
#[inline]
pub(crate) fn mm_to_metres(v: u16) -> f32 {
    v as f32 / 1000.0
}

/// A depth image with labels, row-major, `width * height` entries each.
///
/// ```
/// use sndt_core::*;
/// let cam = Pinhole { fx: 4.0, fy: 4.0, cx: 4.0, cy: 3.0, width: 8, height: 6 };
/// let depth = [2.0f32; 48];
/// let labels = [1u8; 48];
/// let img = DepthImage { camera: cam, depth: Depth::Metres(&depth), kind: DepthKind::Planar,
///                        labels: LabelImage::Top1(&labels), stride: 1 };
/// let mut map: Map<256, 64, 40> = Map::new(Config::DEFAULT);
/// let r = map.integrate_depth(&Isometry3::identity(), &img).unwrap();
/// assert_eq!(r.points_used, 48);
/// ```
#[derive(Clone, Copy, Debug)]
pub struct DepthImage<'a> {
    /// Intrinsics and size.
    pub camera: Pinhole,
    /// Depth in metres or millimetres.
    pub depth: Depth<'a>,
    /// Planar depth or Euclidean range.
    pub kind: DepthKind,
    /// Labels.
    pub labels: LabelImage<'a>,
    /// Use every `stride`-th pixel in both directions (1 = all).
    pub stride: u32,
}

/// The point a depth value measures along a pixel ray (sensor frame, metres), or `None`
/// for a depth that is 0, negative, NaN or infinite (no return).
///
/// `ray` must have unit z, as [`Pinhole::ray`] gives (or a per-pixel ray table scaled to
/// z = 1). [`DepthKind::Planar`] depth scales the ray to that z; [`DepthKind::Range`] is the
/// Euclidean distance from the optical centre, `ray * depth / sqrt(rx^2 + ry^2 + 1)`.
/// [`crate::Map::integrate_depth`] turns pixels into points with exactly this function.
///
/// ```
/// use sndt_core::{depth_point, DepthKind, Pinhole};
/// let cam = Pinhole { fx: 100.0, fy: 100.0, cx: 2.0, cy: 2.0, width: 4, height: 4 };
/// let ray = cam.ray(2, 1); // [0.005, -0.005, 1.0]
/// assert_eq!(depth_point(ray, 2.0, DepthKind::Planar), Some([0.01, -0.01, 2.0]));
/// // Range 2.5 along [0.75, 0, 1], whose length is 1.25.
/// assert_eq!(depth_point([0.75, 0.0, 1.0], 2.5, DepthKind::Range), Some([1.5, 0.0, 2.0]));
/// assert_eq!(depth_point(ray, 0.0, DepthKind::Planar), None);
/// assert_eq!(depth_point(ray, f32::NAN, DepthKind::Range), None);
/// ```
#[inline]
pub fn depth_point(ray: [f32; 3], depth: f32, kind: DepthKind) -> Option<[f32; 3]> {
    if !(depth.is_finite() && depth > 0.0) {
        return None;
    }
    let scale = match kind {
        DepthKind::Planar => depth,
        DepthKind::Range => depth / sqrt(ray[0] * ray[0] + ray[1] * ray[1] + 1.0),
    };
    Some([ray[0] * scale, ray[1] * scale, ray[2] * scale])
}

/// Pixel rays as integration computes them: `(col + 0.5 - cx) * (1 / fx)`, the reciprocals
/// computed once per image. [`Pinhole::ray`] divides instead, which differs in the last bit
/// for some pixels; each path keeps its own arithmetic because maps (snapshot CRCs) and
/// renders are compared bit for bit across versions and targets.
pub(crate) struct PixelRays {
    ifx: f32,
    ify: f32,
    cx: f32,
    cy: f32,
}

impl PixelRays {
    pub(crate) fn new(cam: &Pinhole) -> Self {
        PixelRays {
            ifx: 1.0 / cam.fx,
            ify: 1.0 / cam.fy,
            cx: cam.cx,
            cy: cam.cy,
        }
    }

    /// The y component of every ray in image row `row`.
    #[inline]
    pub(crate) fn y(&self, row: usize) -> f32 {
        (row as f32 + 0.5 - self.cy) * self.ify
    }

    /// The x component of every ray in image column `col` (a `u32`, as image sizes are).
    #[inline]
    pub(crate) fn x(&self, col: usize) -> f32 {
        (col as u32 as f32 + 0.5 - self.cx) * self.ifx
    }
}

impl DepthImage<'_> {
    /// The sensor-frame point [`crate::Map::integrate_depth`] takes from pixel `(col, row)`,
    /// bit for bit, or `None` for no return or a pixel outside the image. (Its rays use
    /// reciprocals of the focal lengths, which can differ from [`Pinhole::ray`] in the
    /// last bit.)
    ///
    /// ```
    /// use sndt_core::*;
    /// let cam = Pinhole { fx: 4.0, fy: 4.0, cx: 1.0, cy: 1.0, width: 2, height: 2 };
    /// let depth = [2.0f32, 0.0, 2.0, 2.0];
    /// let img = DepthImage { camera: cam, depth: Depth::Metres(&depth), kind: DepthKind::Planar,
    ///                        labels: LabelImage::None, stride: 1 };
    /// assert_eq!(img.point(0, 0), Some([-0.25, -0.25, 2.0]));
    /// assert_eq!((img.point(1, 0), img.point(2, 0)), (None, None));
    /// ```
    pub fn point(&self, col: u32, row: u32) -> Option<[f32; 3]> {
        let cam = &self.camera;
        if col >= cam.width || row >= cam.height {
            return None;
        }
        let rays = PixelRays::new(cam);
        let i = row as usize * cam.width as usize + col as usize;
        let ray = [rays.x(col as usize), rays.y(row as usize), 1.0];
        depth_point(ray, self.depth.metres(i)?, self.kind)
    }

    /// Checks the image against its camera: a valid camera, a pixel count that fits
    /// `usize`, depth and labels of that size, and a stride of at least 1.
    pub(crate) fn validate(&self) -> Result<(), Error> {
        let cam = &self.camera;
        let n = cam.pixels().ok_or(Error::InvalidImage)?;
        let labels_ok = match self.labels {
            LabelImage::None => true,
            LabelImage::Top1(l) => l.len() == n,
            LabelImage::TopK(l) => l.len() == n,
        };
        if !cam.valid() || self.depth.len() != n || !labels_ok || self.stride == 0 {
            return Err(Error::InvalidImage);
        }
        Ok(())
    }

    /// Pixels integration visits (of a validated image): every `stride`-th in both
    /// directions.
    pub(crate) fn samples(&self) -> usize {
        let stride = self.stride as usize;
        let (w, h) = (self.camera.width as usize, self.camera.height as usize);
        w.div_ceil(stride) * h.div_ceil(stride)
    }
}

/// Checks a sensor pose: translation and rotation quaternion finite, the quaternion of
/// unit length within 1e-3. Every map update and render checks its pose with this.
///
/// ```
/// use sndt_core::{validate_pose, Error, Isometry3};
/// assert!(validate_pose(&Isometry3::translation(1.0, 2.0, 3.0)).is_ok());
/// let mut pose = Isometry3::identity();
/// pose.translation.x = f32::NAN;
/// assert_eq!(validate_pose(&pose), Err(Error::InvalidPose));
/// ```
pub fn validate_pose(pose: &Isometry3<f32>) -> Result<(), Error> {
    let t = pose.translation.vector;
    let q = pose.rotation.quaternion();
    let finite = t.iter().chain(q.coords.iter()).all(|x| x.is_finite());
    if !finite || (q.norm_squared() - 1.0).abs() > 1e-3 {
        return Err(Error::InvalidPose);
    }
    Ok(())
}

/// Builds a pose from a rotation matrix and translation, checking that the rotation is
/// orthonormal with determinant +1 (within 1e-3) and everything is finite.
///
/// ```
/// use sndt_core::{pose_from_matrix, Matrix3, Vector3, Error};
/// assert!(pose_from_matrix(&Matrix3::identity(), &Vector3::zeros()).is_ok());
/// let sheared = Matrix3::new(1.0, 0.2, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);
/// assert_eq!(pose_from_matrix(&sheared, &Vector3::zeros()), Err(Error::InvalidPose));
/// ```
pub fn pose_from_matrix(r: &Matrix3<f32>, t: &Vector3<f32>) -> Result<Isometry3<f32>, Error> {
    if r.iter().chain(t.iter()).any(|x| !x.is_finite()) {
        return Err(Error::InvalidPose);
    }
    let rtr = r.transpose() * r;
    let off = (rtr - Matrix3::identity()).abs().max();
    if off > 1e-3 || r.determinant() < 0.0 {
        return Err(Error::InvalidPose);
    }
    let rot = nalgebra::Rotation3::from_matrix_unchecked(*r);
    let q = nalgebra::UnitQuaternion::from_rotation_matrix(&rot);
    Ok(Isometry3::from_parts(nalgebra::Translation3::from(*t), q))
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::*;

    #[test]
    fn depth_image_size_overflow_is_rejected() {
        // 65536 x 65536 pixels is 2^32: on a 32-bit target `width * height` must not wrap to
        // an empty image (it would then index the empty depth slice).
        let cam = Pinhole {
            fx: 100.0,
            fy: 100.0,
            cx: 0.0,
            cy: 0.0,
            width: 65536,
            height: 65536,
        };
        let img = DepthImage {
            camera: cam,
            depth: Depth::Metres(&[]),
            kind: DepthKind::Planar,
            labels: LabelImage::None,
            stride: 1,
        };
        let mut map: Map<16, 16, 1> = Map::new(Config::DEFAULT);
        assert_eq!(
            map.integrate_depth(&Isometry3::identity(), &img),
            Err(Error::InvalidImage)
        );
        assert_eq!(
            map.render(&Isometry3::identity(), &cam, &mut [], &mut []),
            Err(Error::InvalidImage)
        );
    }
}
