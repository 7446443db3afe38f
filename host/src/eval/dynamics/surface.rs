//! Which voxels a shape's surface passes through: the former surface of an object that
//! left, and the static surface a dynamic run must not lose.

use crate::dataset::synthetic::geometry::{Primitive, Shape};
use sndt_core::VoxelKey;
use std::collections::BTreeSet;

/// Samples per voxel edge on a surface: dense enough that no voxel the surface crosses is
/// missed (a sample every third of a cell).
const SAMPLES_PER_CELL: f32 = 3.0;
/// A sample on a voxel face counts for the voxels on both sides (metres).
const FACE_SLACK: f32 = 1e-3;

/// Every voxel of edge `h` that the surface of any shape in `prims` passes through.
///
/// ```
/// use sndt_host::dataset::synthetic::geometry::Primitive;
/// use sndt_host::eval::dynamics::surface::surface_voxels;
/// // A 0.2 m cube from 0.05 to 0.25: its surface crosses 3 x 3 x 3 voxels of 0.1 m,
/// // all but the middle one.
/// let cube = Primitive::axis_box([0.05; 3], [0.25; 3], 1, 1);
/// assert_eq!(surface_voxels(&[cube], 0.1).len(), 26);
/// ```
pub fn surface_voxels(prims: &[Primitive], h: f32) -> BTreeSet<VoxelKey> {
    let mut out = BTreeSet::new();
    for_each_sample(prims, h, |sides| out.extend(sides.into_iter().flatten()));
    out
}

/// The pairs of voxels of edge `h` on the two sides of a voxel face that the surface of
/// a shape in `prims` lies on: either voxel holds that part of the surface (its points
/// fall on both sides, each with half of the range noise). Each pair once, smaller key
/// first.
///
/// ```
/// use sndt_host::dataset::synthetic::geometry::Primitive;
/// use sndt_host::eval::dynamics::surface::face_pairs;
/// use sndt_core::VoxelKey;
/// // A 0.2 m square in the plane z = 0.3 (on a boundary at 0.1 m): 2 x 2 pairs of
/// // voxels one above the other (its edges, on boundaries too, add the pairs beside).
/// let square = Primitive::axis_box([0.05, 0.05, 0.3], [0.15, 0.15, 0.3], 1, 1);
/// let pairs = face_pairs(&[square], 0.1);
/// let (below, above) = (VoxelKey { x: 1, y: 1, z: 2 }, VoxelKey { x: 1, y: 1, z: 3 });
/// assert!(pairs.contains(&(below, above)));
/// assert!(pairs.iter().all(|(a, b)| a < b));
/// ```
pub fn face_pairs(prims: &[Primitive], h: f32) -> BTreeSet<(VoxelKey, VoxelKey)> {
    let mut out = BTreeSet::new();
    for_each_sample(prims, h, |sides| {
        if let [Some(a), Some(b)] = sides
            && a != b
        {
            out.insert((a.min(b), a.max(b)));
        }
    });
    out
}

/// Calls `visit` with the voxels just behind and just in front of every surface sample
/// of every shape in `prims` (a sample every third of a cell of edge `h`): the same voxel
/// twice unless the sample lies on a voxel face.
fn for_each_sample(prims: &[Primitive], h: f32, mut visit: impl FnMut([Option<VoxelKey>; 2])) {
    let step = h / SAMPLES_PER_CELL;
    let mut add = |p: [f32; 3], n: [f32; 3]| {
        visit([-FACE_SLACK, FACE_SLACK].map(|s| {
            let q = [p[0] + s * n[0], p[1] + s * n[1], p[2] + s * n[2]];
            VoxelKey::from_point(&q, h)
        }));
    };
    for prim in prims {
        match prim.shape {
            Shape::Box { center, half, yaw } => {
                let (sin, cos) = yaw.sin_cos();
                let turn = |v: [f32; 3]| [cos * v[0] - sin * v[1], sin * v[0] + cos * v[1], v[2]];
                for axis in 0..3 {
                    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                    for side in [-1.0f32, 1.0] {
                        for a in steps(half[u], step) {
                            for b in steps(half[v], step) {
                                let mut local = [0.0; 3];
                                local[axis] = side * half[axis];
                                local[u] = a;
                                local[v] = b;
                                let mut normal = [0.0; 3];
                                normal[axis] = side;
                                let w = turn(local);
                                let p = [center[0] + w[0], center[1] + w[1], center[2] + w[2]];
                                add(p, turn(normal));
                            }
                        }
                    }
                }
            }
            Shape::Cylinder { xy, radius, z0, z1 } => {
                let around = ((std::f32::consts::TAU * radius / step).ceil() as usize).max(8);
                for i in 0..around {
                    let (s, c) = (std::f32::consts::TAU * i as f32 / around as f32).sin_cos();
                    for z in steps(0.5 * (z1 - z0), step) {
                        let p = [xy[0] + radius * c, xy[1] + radius * s, 0.5 * (z0 + z1) + z];
                        add(p, [c, s, 0.0]);
                    }
                }
                for a in steps(radius, step) {
                    for b in steps(radius, step) {
                        if a * a + b * b <= radius * radius {
                            add([xy[0] + a, xy[1] + b, z0], [0.0, 0.0, -1.0]);
                            add([xy[0] + a, xy[1] + b, z1], [0.0, 0.0, 1.0]);
                        }
                    }
                }
            }
        }
    }
}

/// `-half ..= half` in steps of at most `step`, both ends included.
fn steps(half: f32, step: f32) -> impl Iterator<Item = f32> {
    let n = ((2.0 * half / step).ceil() as usize).max(1);
    (0..=n).map(move |i| -half + 2.0 * half * i as f32 / n as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A wall 2 m long and 1 m high in the plane y = 0.3 (a face on a voxel boundary):
    /// every voxel it crosses on both sides of the plane at 10 cm, and nothing farther.
    #[test]
    fn a_face_on_a_voxel_boundary_counts_both_sides() {
        let thin = Primitive::axis_box([0.0, 0.3, 0.0], [2.0, 0.3, 1.0], 1, 1);
        let v = surface_voxels(&[thin], 0.1);
        let ys: BTreeSet<i16> = v.iter().map(|k| k.y).collect();
        assert_eq!(ys, BTreeSet::from([2, 3]));
        for x in 0..20 {
            for z in 0..10 {
                for y in [2, 3] {
                    assert!(v.contains(&VoxelKey { x, y, z }), "{x} {y} {z}");
                }
            }
        }
        // The edges on voxel boundaries (x = 0 and 2, z = 0 and 1) add the voxels beside.
        assert!(v
            .iter()
            .all(|k| (-1..=20).contains(&k.x) && (-1..=10).contains(&k.z)));
    }

    /// The same wall: every pair across its plane, one voxel on each side, and no pair
    /// but across a face (its edges on boundaries add pairs across those).
    #[test]
    fn face_pairs_lie_across_the_plane() {
        let thin = Primitive::axis_box([0.0, 0.3, 0.0], [2.0, 0.3, 1.0], 1, 1);
        let pairs = face_pairs(&[thin], 0.1);
        for x in 0..20 {
            for z in 0..10 {
                let (a, b) = (VoxelKey { x, y: 2, z }, VoxelKey { x, y: 3, z });
                assert!(pairs.contains(&(a, b)), "{x} {z}");
            }
        }
        for (a, b) in &pairs {
            let d = [b.x - a.x, b.y - a.y, b.z - a.z];
            assert_eq!(d.iter().map(|v| v.abs()).sum::<i16>(), 1, "{a:?} {b:?}");
        }
        // A cube off the boundaries has no face on one.
        let cube = Primitive::axis_box([0.05; 3], [0.25; 3], 1, 1);
        assert!(face_pairs(&[cube], 0.1).is_empty());
    }

    /// An upright cylinder of radius 0.24 centred in a voxel column: its side passes
    /// through voxels two away from the centre's, not three, and not through the middle
    /// one (caps on voxel boundaries add the layers below and above).
    #[test]
    fn cylinder_side_and_caps() {
        let c = Primitive {
            shape: Shape::Cylinder {
                xy: [0.05, 0.05],
                radius: 0.24,
                z0: 0.0,
                z1: 0.3,
            },
            label: 1,
            instance: 1,
        };
        let v = surface_voxels(&[c], 0.1);
        let middle = |z| VoxelKey { x: 0, y: 0, z };
        assert!(!v.contains(&middle(1)) && v.contains(&middle(0)) && v.contains(&middle(-1)));
        assert!(v.contains(&VoxelKey { x: 2, y: 0, z: 1 }));
        assert!(v.contains(&VoxelKey { x: -2, y: 0, z: 1 }));
        assert!(!v.contains(&VoxelKey { x: 3, y: 0, z: 1 }));
    }
}
