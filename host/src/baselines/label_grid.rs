//! A read-out's dense label grid (class 0..=40 where occupied, [`INVALID_LABEL`]
//! elsewhere) and its back-projection: a pixel's ray returns the class of the first
//! occupied voxel it enters.
//!
//! [`LabelGrid::cast`] walks one ray through the grid voxel by voxel. [`LabelGrid::render`]
//! renders a pinhole image by drawing faces instead: a ray from outside enters its first
//! occupied voxel through a face whose neighbour across is empty (or outside the grid),
//! on a side that looks at the camera. Every such face is drawn over the pixels its
//! corners project around, each pixel testing its own ray against the face and keeping the
//! nearest; the cost follows the pixels the faces cover, not the length of the rays. Only
//! where a ray meets two faces at the same distance to rounding (along a voxel edge) can
//! the two ways pick different voxels.

use crate::dataset::frame::{Frame, Rays};
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use sndt_core::{Pinhole, INVALID_LABEL};

/// A read-out's labels on a dense voxel grid.
#[derive(Clone, Debug)]
pub struct LabelGrid {
    cell_size: f32,
    /// Voxel key of the grid's corner cell.
    origin: [i32; 3],
    dims: [usize; 3],
    /// Labels, x fastest.
    cells: Vec<u8>,
    /// Indices of the occupied cells.
    occupied: Vec<usize>,
}

/// Per-pixel unit rays of a frame, by axis (`d[axis][pixel]`).
type PixelRays = [Vec<f32>; 3];

impl LabelGrid {
    /// A grid of `dims` voxels of edge `cell_size` whose corner cell has key `origin`.
    pub(crate) fn new(cell_size: f32, origin: [i32; 3], dims: [usize; 3], cells: Vec<u8>) -> Self {
        let occupied = (0..cells.len())
            .filter(|&i| cells[i] != INVALID_LABEL)
            .collect();
        LabelGrid {
            cell_size,
            origin,
            dims,
            cells,
            occupied,
        }
    }

    /// Number of occupied voxels.
    pub fn occupied(&self) -> usize {
        self.occupied.len()
    }

    /// The class of the first occupied voxel along the ray from `origin` in unit direction
    /// `dir`, within `max_range` metres.
    ///
    /// ```
    /// use sndt_host::baselines::bki::{BkiConfig, BkiMap, Readout, Sample};
    /// let mut map = BkiMap::new(BkiConfig::new(0.1, 0.15)).unwrap();
    /// map.add_sample(&Sample { position: [1.05, 0.05, 0.05], bin: 5 });
    /// let grid = map.label_grid(Readout::Osbki);
    /// assert_eq!(grid.cast([0.05, 0.05, 0.05], [1.0, 0.0, 0.0], 20.0), Some(5));
    /// assert_eq!(grid.cast([0.05, 0.05, 0.05], [-1.0, 0.0, 0.0], 20.0), None);
    /// ```
    pub fn cast(&self, origin: [f32; 3], dir: [f32; 3], max_range: f32) -> Option<u8> {
        if self.cells.is_empty() {
            return None;
        }
        let res = self.cell_size;
        // Ray in grid units, relative to the grid's corner.
        let o: [f32; 3] = core::array::from_fn(|a| origin[a] / res - self.origin[a] as f32);
        let dims = self.dims.map(|d| d as f32);
        // Clip to the grid box.
        let (mut t0, mut t1) = (0f32, max_range / res);
        for a in 0..3 {
            if dir[a] == 0.0 {
                if o[a] < 0.0 || o[a] >= dims[a] {
                    return None;
                }
            } else {
                let (ta, tb) = ((0.0 - o[a]) / dir[a], (dims[a] - o[a]) / dir[a]);
                t0 = t0.max(ta.min(tb));
                t1 = t1.min(ta.max(tb));
            }
        }
        if t0 >= t1 || t0.is_nan() || t1.is_nan() {
            return None;
        }
        let start: [f32; 3] = core::array::from_fn(|a| o[a] + dir[a] * t0);
        let mut v: [i64; 3] =
            core::array::from_fn(|a| (start[a].floor() as i64).clamp(0, self.dims[a] as i64 - 1));
        let step: [i64; 3] = dir.map(|d| if d > 0.0 { 1 } else { -1 });
        let delta: [f32; 3] = dir.map(|d| {
            if d != 0.0 {
                1.0 / d.abs()
            } else {
                f32::INFINITY
            }
        });
        let mut next: [f32; 3] = core::array::from_fn(|a| {
            if dir[a] == 0.0 {
                f32::INFINITY
            } else {
                let edge = if dir[a] > 0.0 { v[a] + 1 } else { v[a] } as f32;
                t0 + (edge - start[a]) / dir[a]
            }
        });
        let (sx, sxy) = (self.dims[0] as i64, (self.dims[0] * self.dims[1]) as i64);
        let stride = [step[0], step[1] * sx, step[2] * sxy];
        let mut idx = v[0] + v[1] * sx + v[2] * sxy;
        loop {
            let c = self.cells[idx as usize];
            if c != INVALID_LABEL {
                return Some(c);
            }
            let a = if next[0] < next[1] {
                if next[0] < next[2] {
                    0
                } else {
                    2
                }
            } else if next[1] < next[2] {
                1
            } else {
                2
            };
            if next[a] >= t1 {
                return None;
            }
            v[a] += step[a];
            if v[a] < 0 || v[a] >= self.dims[a] as i64 {
                return None;
            }
            idx += stride[a];
            next[a] += delta[a];
        }
    }

    /// Back-projects the grid into `frame` at its pose: one label per pixel, [`INVALID_LABEL`]
    /// where the ray meets nothing occupied within `max_range`. A pinhole frame is drawn
    /// face by face; a frame with per-pixel rays is cast ray by ray (row bands in
    /// parallel).
    ///
    /// ```
    /// use sndt_host::baselines::bki::{BkiConfig, BkiMap, Readout, Sample};
    /// use sndt_host::dataset::{Frame, FrameId, Rays};
    /// use sndt_core::{DepthKind, Isometry3, Pinhole};
    /// let mut map = BkiMap::new(BkiConfig::new(0.1, 0.15)).unwrap();
    /// // A 1 m patch of class 5 two metres ahead of a camera at the origin.
    /// for i in 0..100 {
    ///     let (x, y) = ((i % 10) as f32 * 0.1 - 0.45, (i / 10) as f32 * 0.1 - 0.45);
    ///     map.add_sample(&Sample { position: [x, y, 2.05], bin: 5 });
    /// }
    /// let grid = map.label_grid(Readout::Osbki);
    /// let cam = Pinhole { fx: 50.0, fy: 50.0, cx: 32.0, cy: 24.0, width: 64, height: 48 };
    /// let frame = Frame {
    ///     id: FrameId::parse("s/c/0000").unwrap(),
    ///     pose: Isometry3::identity(),
    ///     rays: std::sync::Arc::new(Rays::Pinhole(cam)),
    ///     depth: vec![0.0; 64 * 48],
    ///     depth_kind: DepthKind::Planar,
    ///     labels: None,
    ///     predictions: None,
    /// };
    /// let labels = grid.render(&frame, 20.0);
    /// assert_eq!((labels[24 * 64 + 32], labels[0]), (5, sndt_core::INVALID_LABEL));
    /// ```
    pub fn render(&self, frame: &Frame, max_range: f32) -> Vec<u8> {
        match frame.rays.as_ref() {
            Rays::Pinhole(cam) => self.draw(frame, cam, max_range),
            Rays::PerPixel { .. } => self.cast_all(frame, max_range),
        }
    }

    /// One [`LabelGrid::cast`] per pixel, row bands in parallel.
    fn cast_all(&self, frame: &Frame, max_range: f32) -> Vec<u8> {
        let w = frame.rays.width() as usize;
        let t = frame.pose.translation.vector;
        let origin = [t.x, t.y, t.z];
        let mut out = vec![INVALID_LABEL; w * frame.rays.height() as usize];
        out.par_chunks_mut(w.max(1))
            .enumerate()
            .for_each(|(row, line)| {
                for (col, px) in line.iter_mut().enumerate() {
                    let d = unit_ray(frame, col as u32, row as u32);
                    *px = self.cast(origin, d, max_range).unwrap_or(INVALID_LABEL);
                }
            });
        out
    }

    /// The ray origin in grid units, relative to the grid's corner (as `cast` has it).
    fn grid_point(&self, p: [f32; 3]) -> [f32; 3] {
        core::array::from_fn(|a| p[a] / self.cell_size - self.origin[a] as f32)
    }

    /// The label of the voxel holding grid point `o`, if it is inside the grid.
    fn label_at(&self, o: [f32; 3]) -> Option<u8> {
        let mut idx = 0;
        for a in (0..3).rev() {
            if !(o[a] >= 0.0 && o[a] < self.dims[a] as f32) {
                return None;
            }
            idx = idx * self.dims[a] + o[a] as usize;
        }
        self.cells.get(idx).copied()
    }

    /// Renders a pinhole frame face by face (see the module documentation).
    fn draw(&self, frame: &Frame, cam: &Pinhole, max_range: f32) -> Vec<u8> {
        let n = (cam.width * cam.height) as usize;
        let t = frame.pose.translation.vector;
        let o = self.grid_point([t.x, t.y, t.z]);
        // From inside an occupied voxel every ray starts in it.
        if let Some(c) = self.label_at(o).filter(|&c| c != INVALID_LABEL) {
            return vec![c; n];
        }
        let rays = pixel_rays(frame, cam);
        let mut z = Zbuffer {
            t: vec![f32::INFINITY; n],
            labels: vec![INVALID_LABEL; n],
            t_max: max_range / self.cell_size,
        };
        let d = self.dims;
        for &i in &self.occupied {
            let v = [i % d[0], (i / d[0]) % d[1], i / (d[0] * d[1])];
            for axis in 0..3 {
                // The face on the camera's side of this axis, if the camera is outside the
                // voxel's slab, and if the neighbour across it is empty.
                let (plane, across) = if o[axis] < v[axis] as f32 {
                    (v[axis], v[axis].checked_sub(1))
                } else if o[axis] > (v[axis] + 1) as f32 {
                    (v[axis] + 1, Some(v[axis] + 1).filter(|&k| k < d[axis]))
                } else {
                    continue;
                };
                if let Some(k) = across {
                    let mut nb = v;
                    nb[axis] = k;
                    if self.cells[(nb[2] * d[1] + nb[1]) * d[0] + nb[0]] != INVALID_LABEL {
                        continue;
                    }
                }
                let face = Face {
                    axis,
                    plane: plane as f32,
                    v: v.map(|x| x as f32),
                    label: self.cells[i],
                };
                let rect = self.screen_rect(frame, cam, &face);
                z.draw(&face, rect, o, &rays, cam.width as usize);
            }
        }
        z.labels
    }

    /// Pixels (columns, rows; half-open) around the projection of `face`'s corners, a
    /// pixel of margin on every side; the whole image if a corner is not ahead of the
    /// camera, nothing if none is.
    fn screen_rect(&self, frame: &Frame, cam: &Pinhole, face: &Face) -> [(usize, usize); 2] {
        let (b, c) = ((face.axis + 1) % 3, (face.axis + 2) % 3);
        let whole = [(0, cam.width as usize), (0, cam.height as usize)];
        let (mut lo, mut hi) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
        let mut ahead = 0;
        for corner in 0..4 {
            let mut g = face.v;
            g[face.axis] = face.plane;
            g[b] += (corner & 1) as f32;
            g[c] += (corner >> 1) as f32;
            let world: [f32; 3] =
                core::array::from_fn(|a| (g[a] + self.origin[a] as f32) * self.cell_size);
            let p = frame.pose.inverse_transform_point(&Point3::from(world));
            if p.z <= 1e-6 {
                continue;
            }
            ahead += 1;
            let uv = [cam.fx * p.x / p.z + cam.cx, cam.fy * p.y / p.z + cam.cy];
            for k in 0..2 {
                lo[k] = lo[k].min(uv[k]);
                hi[k] = hi[k].max(uv[k]);
            }
        }
        match ahead {
            0 => [(0, 0), (0, 0)],
            4 => core::array::from_fn(|k| {
                // Pixel centres `i + 0.5` in `[lo, hi]`, one more on each side.
                let first = (lo[k] - 1.5).ceil().max(0.0) as usize;
                let end = (hi[k] + 1.5).floor().max(0.0) as usize;
                (first.min(whole[k].1), end.min(whole[k].1))
            }),
            _ => whole,
        }
    }
}

/// One voxel face: the plane `x[axis] = plane` (grid units) over the voxel `v`.
struct Face {
    axis: usize,
    plane: f32,
    v: [f32; 3],
    label: u8,
}

/// The nearest face hit per pixel so far (distance in grid units) and its label.
struct Zbuffer {
    t: Vec<f32>,
    labels: Vec<u8>,
    /// Rays end here (the range in grid units).
    t_max: f32,
}

impl Zbuffer {
    /// Tests the pixels of `rect` against `face` for rays from `o` (grid units).
    fn draw(
        &mut self,
        face: &Face,
        rect: [(usize, usize); 2],
        o: [f32; 3],
        rays: &PixelRays,
        w: usize,
    ) {
        let (a, b, c) = (face.axis, (face.axis + 1) % 3, (face.axis + 2) % 3);
        let (cols, rows) = (rect[0].0..rect[0].1, rect[1].0..rect[1].1);
        let (lo_b, lo_c) = (face.v[b], face.v[c]);
        let to_plane = face.plane - o[a];
        for row in rows {
            let px = row * w + cols.start..row * w + cols.end;
            let (da, db, dc) = (
                &rays[a][px.clone()],
                &rays[b][px.clone()],
                &rays[c][px.clone()],
            );
            let (ts, ls) = (&mut self.t[px.clone()], &mut self.labels[px]);
            for ((((t_px, l_px), &da), &db), &dc) in
                ts.iter_mut().zip(ls.iter_mut()).zip(da).zip(db).zip(dc)
            {
                let t = to_plane / da;
                let (pb, pc) = (o[b] + t * db - lo_b, o[c] + t * dc - lo_c);
                let hit = t >= 0.0
                    && t < self.t_max
                    && t < *t_px
                    && (0.0..=1.0).contains(&pb)
                    && (0.0..=1.0).contains(&pc);
                if hit {
                    *t_px = t;
                    *l_px = face.label;
                }
            }
        }
    }
}

/// The unit world ray of pixel `(col, row)`, as the evaluation has always cast it.
fn unit_ray(frame: &Frame, col: u32, row: u32) -> [f32; 3] {
    let r = frame.rays.ray(col, row);
    let d = (frame.pose.rotation * Vector3::new(r[0], r[1], r[2])).normalize();
    [d.x, d.y, d.z]
}

/// [`unit_ray`] of every pixel, by axis.
fn pixel_rays(frame: &Frame, cam: &Pinhole) -> PixelRays {
    let n = (cam.width * cam.height) as usize;
    let mut rays: PixelRays = core::array::from_fn(|_| Vec::with_capacity(n));
    for row in 0..cam.height {
        for col in 0..cam.width {
            let d = unit_ray(frame, col, row);
            for (axis, v) in rays.iter_mut().enumerate() {
                v.push(d[axis]);
            }
        }
    }
    rays
}
