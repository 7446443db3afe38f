//! Paths through the floor: a clearance grid of the floor plan (the distance from each
//! cell to the nearest thing standing on the floor), A* on it with a preference for
//! clearance, shortcuts along clear lines, and the resampled, smoothed path a walk follows.
//! It knows nothing of the floor it is made from (the floor and its walks use it).

use crate::dataset::synthetic::geometry::Primitive;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Cell of the clearance grid.
pub(super) const RES: f32 = 0.05;
/// Clearances above this are stored as this.
const CAP: f32 = 1.0;
/// The least clearance of a planned path (cell centres).
pub(super) const R_MIN: f32 = 0.34;
/// Paths prefer to keep this much clearance.
const R_PREF: f32 = 0.8;

impl Grid {
    /// A smooth path from `a` to `b` keeping clear of everything.
    ///
    /// # Panics
    /// If there is none (every room of a floor is checked to be enterable when generated).
    pub(super) fn path(&self, a: [f32; 2], b: [f32; 2]) -> Vec<[f32; 2]> {
        let cells = self
            .astar(a, b)
            .expect("every room of the floor is reachable from the corridor");
        let short = self.shortcut(&cells);
        let fine = resample(&short, 0.05);
        for half in [8, 4, 2] {
            let smooth = smoothed(&fine, half);
            if smooth.iter().all(|p| self.at(p) >= R_MIN) {
                return smooth;
            }
        }
        fine
    }
}

pub(super) fn cumulative(path: &[[f32; 2]]) -> Vec<f32> {
    let mut out = Vec::with_capacity(path.len());
    let mut s = 0.0;
    for (i, p) in path.iter().enumerate() {
        if i > 0 {
            let q = path[i - 1];
            s += ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
        }
        out.push(s);
    }
    out
}

/// The point at arc length `s` (clamped to the ends).
pub(super) fn point_at(path: &[[f32; 2]], lens: &[f32], s: f32) -> [f32; 2] {
    let i = lens.partition_point(|&l| l <= s);
    if i == 0 {
        return path[0];
    }
    if i >= path.len() {
        return path[path.len() - 1];
    }
    let (a, b) = (path[i - 1], path[i]);
    let span = lens[i] - lens[i - 1];
    let f = if span > 0.0 {
        (s - lens[i - 1]) / span
    } else {
        0.0
    };
    [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])]
}

/// Points every `step` metres along a polyline (ends kept).
fn resample(path: &[[f32; 2]], step: f32) -> Vec<[f32; 2]> {
    let lens = cumulative(path);
    let total = *lens.last().unwrap_or(&0.0);
    let n = (total / step).ceil().max(1.0) as usize;
    (0..=n)
        .map(|i| point_at(path, &lens, total * i as f32 / n as f32))
        .collect()
}

/// A moving average over `2 half + 1` points, twice; the window shrinks at the ends so
/// they stay put.
fn smoothed(path: &[[f32; 2]], half: usize) -> Vec<[f32; 2]> {
    let mut cur = path.to_vec();
    for _ in 0..2 {
        let n = cur.len();
        cur = (0..n)
            .map(|i| {
                let h = half.min(i).min(n - 1 - i);
                let mut acc = [0.0f32; 2];
                for p in &cur[i - h..=i + h] {
                    acc[0] += p[0];
                    acc[1] += p[1];
                }
                let k = (2 * h + 1) as f32;
                [acc[0] / k, acc[1] / k]
            })
            .collect();
    }
    cur
}

/// Clearance on the floor plan: per cell of [`RES`], the distance from its centre to the
/// nearest thing standing on the floor (up to [`CAP`]; 0 outside where one may walk).
#[derive(Clone, Debug)]
pub(super) struct Grid {
    origin: [f32; 2],
    nx: usize,
    ny: usize,
    pub(super) clear: Vec<f32>,
}

impl Grid {
    pub(super) fn new<'a>(
        bounds: [f32; 4],
        prims: impl Iterator<Item = &'a Primitive>,
        walkable: &dyn Fn(&[f32; 2]) -> bool,
    ) -> Grid {
        let origin = [bounds[0] - 0.5, bounds[1] - 0.5];
        let nx = ((bounds[2] - bounds[0] + 1.0) / RES).ceil() as usize;
        let ny = ((bounds[3] - bounds[1] + 1.0) / RES).ceil() as usize;
        let mut g = Grid {
            origin,
            nx,
            ny,
            clear: Vec::new(),
        };
        g.clear = (0..nx * ny)
            .map(|i| if walkable(&g.centre(i)) { CAP } else { 0.0 })
            .collect();
        for p in prims {
            // Only what stands between the floor and above a person's head blocks.
            let b = p.shape.aabb();
            if b.max[2] <= 0.05 || b.min[2] >= 2.0 {
                continue;
            }
            let lo = g.index_of([b.min[0] - CAP, b.min[1] - CAP]);
            let hi = g.index_of([b.max[0] + CAP, b.max[1] + CAP]);
            for j in lo[1]..=hi[1] {
                for i in lo[0]..=hi[0] {
                    let k = j * nx + i;
                    if g.clear[k] > 0.0 {
                        let d = p.shape.distance_2d(&g.centre(k));
                        if d < g.clear[k] {
                            g.clear[k] = d;
                        }
                    }
                }
            }
        }
        g
    }

    /// The cell of `p`, clamped to the grid.
    fn index_of(&self, p: [f32; 2]) -> [usize; 2] {
        let f = |v: f32, o: f32, n: usize| (((v - o) / RES).floor().max(0.0) as usize).min(n - 1);
        [
            f(p[0], self.origin[0], self.nx),
            f(p[1], self.origin[1], self.ny),
        ]
    }

    fn cell(&self, p: &[f32; 2]) -> usize {
        let [i, j] = self.index_of(*p);
        j * self.nx + i
    }

    pub(super) fn centre(&self, k: usize) -> [f32; 2] {
        let (i, j) = (k % self.nx, k / self.nx);
        [
            self.origin[0] + (i as f32 + 0.5) * RES,
            self.origin[1] + (j as f32 + 0.5) * RES,
        ]
    }

    /// The clearance of the cell of `p`.
    pub(super) fn at(&self, p: &[f32; 2]) -> f32 {
        self.clear[self.cell(p)]
    }

    fn neighbours(&self, k: usize) -> impl Iterator<Item = (usize, f32)> + '_ {
        let (i, j) = ((k % self.nx) as isize, (k / self.nx) as isize);
        const MOVES: [(isize, isize, f32); 8] = [
            (1, 0, 1.0),
            (-1, 0, 1.0),
            (0, 1, 1.0),
            (0, -1, 1.0),
            (1, 1, std::f32::consts::SQRT_2),
            (1, -1, std::f32::consts::SQRT_2),
            (-1, 1, std::f32::consts::SQRT_2),
            (-1, -1, std::f32::consts::SQRT_2),
        ];
        MOVES.iter().filter_map(move |&(di, dj, len)| {
            let (a, b) = (i + di, j + dj);
            (a >= 0 && b >= 0 && (a as usize) < self.nx && (b as usize) < self.ny)
                .then(|| (b as usize * self.nx + a as usize, len * RES))
        })
    }

    /// The cells reachable from `from` through cells of clearance `r` or more.
    pub(super) fn reachable(&self, from: [f32; 2], r: f32) -> Vec<usize> {
        let start = self.cell(&from);
        if self.clear[start] < r {
            return Vec::new();
        }
        let mut seen = vec![false; self.clear.len()];
        seen[start] = true;
        let mut out = vec![start];
        let mut next = 0;
        while next < out.len() {
            let k = out[next];
            next += 1;
            for (n, _) in self.neighbours(k) {
                if !seen[n] && self.clear[n] >= r {
                    seen[n] = true;
                    out.push(n);
                }
            }
        }
        out
    }

    /// The cheapest path of cell centres from `a` to `b` (both ends included as given)
    /// through cells of clearance [`R_MIN`] or more; a step costs its length, more where
    /// the clearance is under [`R_PREF`].
    fn astar(&self, a: [f32; 2], b: [f32; 2]) -> Option<Vec<[f32; 2]>> {
        let (start, goal) = (self.cell(&a), self.cell(&b));
        if self.clear[start] < R_MIN || self.clear[goal] < R_MIN {
            return None;
        }
        let gc = self.centre(goal);
        let h = |k: usize| {
            let c = self.centre(k);
            let (dx, dy) = ((c[0] - gc[0]).abs(), (c[1] - gc[1]).abs());
            dx.max(dy) + (std::f32::consts::SQRT_2 - 1.0) * dx.min(dy)
        };
        let mut cost = vec![f32::INFINITY; self.clear.len()];
        let mut from = vec![u32::MAX; self.clear.len()];
        let mut open = BinaryHeap::new();
        cost[start] = 0.0;
        open.push(Reverse((h(start).to_bits(), start)));
        while let Some(Reverse((f, k))) = open.pop() {
            if k == goal {
                break;
            }
            if f32::from_bits(f) > cost[k] + h(k) + 1e-4 {
                continue;
            }
            for (n, len) in self.neighbours(k) {
                let c = self.clear[n];
                if c < R_MIN {
                    continue;
                }
                let step = len * (1.0 + 3.0 * ((R_PREF - c) / R_PREF).max(0.0));
                let g = cost[k] + step;
                if g < cost[n] {
                    cost[n] = g;
                    from[n] = k as u32;
                    open.push(Reverse(((g + h(n)).to_bits(), n)));
                }
            }
        }
        if !cost[goal].is_finite() {
            return None;
        }
        let mut cells = vec![goal];
        while let Some(&k) = cells.last() {
            if k == start {
                break;
            }
            cells.push(from[k] as usize);
        }
        cells.reverse();
        let mut out = vec![a];
        out.extend(
            cells[1..cells.len().saturating_sub(1)]
                .iter()
                .map(|&k| self.centre(k)),
        );
        out.push(b);
        Some(out)
    }

    /// Drops the points of a path that a straight line can skip without coming closer to
    /// anything than the skipped stretch did (nor closer than [`R_PREF`] where it kept
    /// that).
    fn shortcut(&self, path: &[[f32; 2]]) -> Vec<[f32; 2]> {
        let mut out = vec![path[0]];
        let mut i = 0;
        while i + 1 < path.len() {
            let mut j = i + 1;
            let mut worst = self.at(&path[i]).min(self.at(&path[j]));
            while j + 1 < path.len() {
                let w = worst.min(self.at(&path[j + 1]));
                if !self.line_clear(path[i], path[j + 1], w.min(R_PREF)) {
                    break;
                }
                worst = w;
                j += 1;
            }
            out.push(path[j]);
            i = j;
        }
        out
    }

    /// Whether every cell along the segment has clearance `r` or more.
    fn line_clear(&self, a: [f32; 2], b: [f32; 2], r: f32) -> bool {
        let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        let n = (len / (0.5 * RES)).ceil().max(1.0) as usize;
        (0..=n).all(|i| {
            let f = i as f32 / n as f32;
            self.at(&[a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])]) >= r
        })
    }
}
