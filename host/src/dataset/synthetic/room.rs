//! A small labelled box room and an exact ray-cast renderer: the embedded default scene
//! for benchmarks, tests and the quick demo (no download).
//!
//! World axes: z up, metres. Camera poses are camera-to-world with OpenCV camera axes
//! (x right, y down, z forward), as everywhere in sndt.

use sndt_core::{Isometry3, Matrix3, Pinhole, Point3, Translation3, UnitQuaternion, Vector3};

/// An axis-aligned labelled box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LabelledBox {
    /// Lower corner, metres.
    pub min: [f32; 3],
    /// Upper corner, metres.
    pub max: [f32; 3],
    /// NYU40 class id (1..=40).
    pub label: u8,
}

/// A scene made of labelled boxes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scene {
    /// The boxes; rays return the nearest one.
    pub boxes: Vec<LabelledBox>,
}

/// NYU40 ids used by the room.
pub mod nyu {
    /// wall
    pub const WALL: u8 = 1;
    /// floor
    pub const FLOOR: u8 = 2;
    /// bed
    pub const BED: u8 = 4;
    /// table
    pub const TABLE: u8 = 7;
    /// picture
    pub const PICTURE: u8 = 11;
    /// shelves
    pub const SHELVES: u8 = 15;
    /// ceiling
    pub const CEILING: u8 = 22;
    /// books
    pub const BOOKS: u8 = 23;
    /// lamp
    pub const LAMP: u8 = 35;
}

fn b(min: [f32; 3], max: [f32; 3], label: u8) -> LabelledBox {
    LabelledBox { min, max, label }
}

impl Scene {
    /// A 6 m x 5 m x 2.8 m bedroom: walls, floor, ceiling, a bed, a table, shelves with
    /// books, a thin picture on a wall and a lamp.
    ///
    /// ```
    /// let room = sndt_host::dataset::synthetic::room::Scene::simple_room();
    /// assert!(room.boxes.len() > 8);
    /// ```
    pub fn simple_room() -> Scene {
        use nyu::*;
        let t = 0.1; // wall thickness
        Scene {
            boxes: vec![
                b([-t, -t, -t], [6.0 + t, 5.0 + t, 0.0], FLOOR),
                b([-t, -t, 2.8], [6.0 + t, 5.0 + t, 2.8 + t], CEILING),
                b([-t, -t, 0.0], [0.0, 5.0 + t, 2.8], WALL),
                b([6.0, -t, 0.0], [6.0 + t, 5.0 + t, 2.8], WALL),
                b([0.0, -t, 0.0], [6.0, 0.0, 2.8], WALL),
                b([0.0, 5.0, 0.0], [6.0, 5.0 + t, 2.8], WALL),
                b([0.3, 0.3, 0.0], [2.3, 1.9, 0.55], BED),
                b([3.5, 2.0, 0.72], [4.7, 2.8, 0.76], TABLE),
                b([3.55, 2.05, 0.0], [3.6, 2.1, 0.72], TABLE),
                b([4.6, 2.7, 0.0], [4.65, 2.75, 0.72], TABLE),
                b([5.6, 1.0, 0.0], [6.0, 2.2, 1.8], SHELVES),
                b([5.5, 1.1, 1.0], [5.6, 1.6, 1.25], BOOKS),
                b([2.0, 4.98, 1.2], [3.2, 5.0, 1.9], PICTURE),
                b([0.5, 4.4, 0.0], [0.8, 4.7, 1.5], LAMP),
            ],
        }
    }

    /// Distance along the unit ray `dir` from `origin` to the nearest box, and its label.
    pub fn cast(&self, origin: &[f32; 3], dir: &[f32; 3]) -> Option<(f32, u8)> {
        let mut best: Option<(f32, u8)> = None;
        for bx in &self.boxes {
            let (mut t0, mut t1) = (0.0f32, f32::INFINITY);
            let mut hit = true;
            for a in 0..3 {
                if dir[a].abs() < 1e-12 {
                    if origin[a] < bx.min[a] || origin[a] > bx.max[a] {
                        hit = false;
                        break;
                    }
                    continue;
                }
                let inv = 1.0 / dir[a];
                let (mut ta, mut tb) =
                    ((bx.min[a] - origin[a]) * inv, (bx.max[a] - origin[a]) * inv);
                if ta > tb {
                    std::mem::swap(&mut ta, &mut tb);
                }
                t0 = t0.max(ta);
                t1 = t1.min(tb);
                if t0 > t1 {
                    hit = false;
                    break;
                }
            }
            if hit && best.is_none_or(|(t, _)| t0 < t) {
                best = Some((t0, bx.label));
            }
        }
        best
    }

    /// Renders planar depth (metres, 0 where nothing is hit) and labels (0 void) for a
    /// camera at `pose`.
    pub fn render(&self, pose: &Isometry3<f32>, cam: &Pinhole) -> (Vec<f32>, Vec<u8>) {
        let n = (cam.width * cam.height) as usize;
        let (mut depth, mut labels) = (vec![0.0f32; n], vec![0u8; n]);
        let rot = pose.rotation.to_rotation_matrix();
        let o = pose.translation.vector;
        let origin = [o.x, o.y, o.z];
        for row in 0..cam.height {
            for col in 0..cam.width {
                let r = cam.ray(col, row);
                let d_cam = Vector3::new(r[0], r[1], r[2]);
                let norm = d_cam.norm();
                let d = rot * (d_cam / norm);
                if let Some((t, l)) = self.cast(&origin, &[d.x, d.y, d.z]) {
                    let i = (row * cam.width + col) as usize;
                    depth[i] = t / norm; // planar depth: z component in the camera
                    labels[i] = l;
                }
            }
        }
        (depth, labels)
    }
}

/// Camera-to-world pose of a camera at `eye` looking at `target`, z-up world, OpenCV axes.
///
/// ```
/// use sndt_host::dataset::synthetic::room::look_at;
/// let pose = look_at([0.0, 0.0, 1.0], [1.0, 0.0, 1.0]);
/// let fwd = pose.rotation * sndt_core::Vector3::z();
/// assert!((fwd.x - 1.0).abs() < 1e-6);
/// ```
pub fn look_at(eye: [f32; 3], target: [f32; 3]) -> Isometry3<f32> {
    let e = Vector3::new(eye[0], eye[1], eye[2]);
    let f = (Vector3::new(target[0], target[1], target[2]) - e).normalize();
    let right = f.cross(&Vector3::z()).normalize();
    let down = f.cross(&right);
    let m = Matrix3::from_columns(&[right, down, f]);
    let rot = UnitQuaternion::from_matrix(&m);
    Isometry3::from_parts(Translation3::from(e), rot)
}

/// The 1024x768 camera of Hypersim's nominal intrinsics (fx = fy = 886.81).
pub const HYPERSIM_CAMERA: Pinhole = Pinhole {
    fx: 886.81,
    fy: 886.81,
    cx: 512.0,
    cy: 384.0,
    width: 1024,
    height: 768,
};

/// `n` poses walking around the room at person height, looking across it.
///
/// ```
/// let poses = sndt_host::dataset::synthetic::room::orbit(10);
/// assert_eq!(poses.len(), 10);
/// ```
pub fn orbit(n: usize) -> Vec<Isometry3<f32>> {
    (0..n)
        .map(|i| {
            let a = i as f32 / n.max(1) as f32 * std::f32::consts::TAU;
            let eye = [3.0 + 1.2 * a.cos(), 2.5 + 1.0 * a.sin(), 1.5];
            let target = [
                3.0 - 2.5 * (a + 0.6).cos(),
                2.5 - 2.0 * (a + 0.6).sin(),
                0.9,
            ];
            look_at(eye, target)
        })
        .collect()
}

/// A rendered frame (planar depth, top-1 labels, every pixel) as the core's depth image.
pub fn depth_image<'a>(
    cam: &Pinhole,
    depth: &'a [f32],
    labels: &'a [u8],
) -> sndt_core::DepthImage<'a> {
    sndt_core::DepthImage {
        camera: *cam,
        depth: sndt_core::Depth::Metres(depth),
        kind: sndt_core::DepthKind::Planar,
        labels: sndt_core::LabelImage::Top1(labels),
        stride: 1,
    }
}

/// Points in the sensor frame for a rendered frame (pixels with depth), with labels.
pub fn points(depth: &[f32], labels: &[u8], cam: &Pinhole) -> Vec<sndt_core::LabeledPoint> {
    let mut out = Vec::with_capacity(depth.len());
    for (i, (&d, &l)) in depth.iter().zip(labels).enumerate() {
        if d > 0.0 {
            let r = cam.ray(i as u32 % cam.width, i as u32 / cam.width);
            out.push(sndt_core::LabeledPoint::new(
                Point3::new(r[0] * d, r[1] * d, d),
                sndt_core::Labels::top1(l),
            ));
        }
    }
    out
}
