//! Export of a map's Gaussians for MeshLab / CloudCompare: coloured points at the means,
//! or small coloured ellipsoid meshes at one standard deviation (binary PLY).

use crate::dataset::classes::color;
use anyhow::{Context, Result};
use sndt_core::{Map, Matrix3, Occupancy, Vector3};
use std::io::Write;
use std::path::Path;

/// One occupied voxel's Gaussian with its class colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ellipsoid {
    /// Mean, metres.
    pub mean: [f32; 3],
    /// Covariance, square metres.
    pub covariance: [[f32; 3]; 3],
    /// Class (0 = none).
    pub class: u8,
}

/// The occupied voxels of `map` with at least `min_points` points, as ellipsoids.
pub fn ellipsoids<const V: usize, const B: usize, const C: usize>(
    map: &Map<V, B, C>,
    min_points: u32,
) -> Vec<Ellipsoid> {
    map.voxels()
        .filter(|v| v.occupancy() == Occupancy::Occupied && v.gaussian.count >= min_points)
        .map(|v| {
            let m = v.gaussian.mean;
            let c = v.gaussian.covariance;
            Ellipsoid {
                mean: [m.x, m.y, m.z],
                covariance: std::array::from_fn(|i| std::array::from_fn(|j| c[(i, j)])),
                class: v.class().map_or(0, |c| c.0),
            }
        })
        .collect()
}

/// Unit directions of an octahedron subdivided once (18 vertices, 32 triangles).
fn unit_sphere() -> (Vec<Vector3<f32>>, Vec<[u32; 3]>) {
    let mut v: Vec<Vector3<f32>> = vec![
        Vector3::x(),
        -Vector3::x(),
        Vector3::y(),
        -Vector3::y(),
        Vector3::z(),
        -Vector3::z(),
    ];
    let octa: [[u32; 3]; 8] = [
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    let mut mid = std::collections::HashMap::new();
    let mut midpoint = |a: u32, b: u32, v: &mut Vec<Vector3<f32>>| -> u32 {
        *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
            v.push((v[a as usize] + v[b as usize]).normalize());
            (v.len() - 1) as u32
        })
    };
    let mut faces = Vec::new();
    for [a, b, c] in octa {
        let (ab, bc, ca) = (
            midpoint(a, b, &mut v),
            midpoint(b, c, &mut v),
            midpoint(c, a, &mut v),
        );
        faces.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    (v, faces)
}

/// Writes the means as coloured points (binary PLY).
pub fn write_points(path: &Path, es: &[Ellipsoid]) -> Result<()> {
    let pts: Vec<([f32; 3], [u8; 3])> = es.iter().map(|e| (e.mean, color(e.class))).collect();
    crate::output::ply::write_points(path, &pts)
}

/// Writes each Gaussian as a coloured ellipsoid mesh at `sigmas` standard deviations
/// (binary little-endian PLY with faces).
///
/// ```
/// use sndt_host::output::export::{write_ellipsoids, Ellipsoid};
/// let e = Ellipsoid { mean: [1.0, 2.0, 3.0], covariance: [[0.04, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 1e-6]], class: 1 };
/// let path = std::env::temp_dir().join(format!("sndt-ell-{}.ply", std::process::id()));
/// write_ellipsoids(&path, &[e], 1.0).unwrap();
/// let bytes = std::fs::read(&path).unwrap();
/// let header = String::from_utf8_lossy(&bytes[..300]);
/// assert!(header.contains("element vertex 18") && header.contains("element face 32"));
/// # std::fs::remove_file(&path).unwrap();
/// ```
pub fn write_ellipsoids(path: &Path, es: &[Ellipsoid], sigmas: f32) -> Result<()> {
    crate::atomic::write_atomic(path, |tmp| write_ellipsoids_to(tmp, es, sigmas))
}

/// What [`write_ellipsoids`] writes, into `path` directly.
fn write_ellipsoids_to(path: &Path, es: &[Ellipsoid], sigmas: f32) -> Result<()> {
    let (sphere, faces) = unit_sphere();
    let file =
        std::fs::File::create(path).with_context(|| format!("creating {}", path.display()))?;
    let mut w = std::io::BufWriter::new(file);
    let nv = es.len() * sphere.len();
    let nf = es.len() * faces.len();
    write!(
        w,
        "ply\nformat binary_little_endian 1.0\ncomment sndt map Gaussians at {sigmas} sigma\n\
         element vertex {nv}\nproperty float x\nproperty float y\nproperty float z\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\n\
         element face {nf}\nproperty list uchar int vertex_indices\nend_header\n"
    )?;
    for e in es {
        let c = Matrix3::from_fn(|i, j| e.covariance[i][j]);
        let eig = c.symmetric_eigen();
        // Axes scaled by the standard deviations (tiny or negative eigenvalues floored so
        // flat surfaces show as discs, not degenerate triangles).
        let floor = 1e-8f32;
        let axes = Matrix3::from_fn(|i, j| {
            eig.eigenvectors[(i, j)] * eig.eigenvalues[j].max(floor).sqrt() * sigmas
        });
        let rgb = color(e.class);
        for d in &sphere {
            let p = Vector3::new(e.mean[0], e.mean[1], e.mean[2]) + axes * d;
            for x in [p.x, p.y, p.z] {
                w.write_all(&x.to_le_bytes())?;
            }
            w.write_all(&rgb)?;
        }
    }
    for k in 0..es.len() {
        let base = (k * sphere.len()) as u32;
        for f in &faces {
            w.write_all(&[3u8])?;
            for i in f {
                w.write_all(&((base + i) as i32).to_le_bytes())?;
            }
        }
    }
    w.flush()
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_is_closed_and_unit() {
        let (v, f) = unit_sphere();
        assert_eq!((v.len(), f.len()), (18, 32));
        assert!(v.iter().all(|d| (d.norm() - 1.0).abs() < 1e-6));
        // Closed surface: every edge belongs to exactly two faces (Euler: V - E + F = 2).
        let mut edges = std::collections::HashMap::new();
        for t in &f {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
        assert!(edges.values().all(|&n| n == 2));
        assert_eq!(v.len() as i64 - edges.len() as i64 + f.len() as i64, 2);
    }
}
