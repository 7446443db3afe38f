//! Where an ellipsoid lands in a pinhole image: the pixels whose rays may enter it, as at
//! most two column spans per row (`render.rs` tests only those pixels).
//!
//! The ray from the camera centre `s` along `p` enters the ellipsoid
//! `(x - mu)^T A (x - mu) = r^2` at a positive distance iff
//! `(p^T A d)^2 >= (p^T A p) c` and `p^T A d < 0`, with `d = s - mu` and
//! `c = d^T A d - r^2 > 0` (the centre outside; the two roots of the ray's quadratic then
//! have the sign of `-p^T A d`). A pixel-centre coordinate `(X, Y) = (col + 0.5, row + 0.5)`
//! has `p = T (X, Y, 1)` with `T = R K^-1`, so the first condition is a conic
//! `q^T P q >= 0` with `P = g g^T - c T^T A T`, `g = T^T A d`, and the second the half-plane
//! `g . q < 0`. On one row both are a quadratic and a linear inequality in `X`.
//!
//! Everything here is `f64` with `r^2` inflated by 2% and one pixel of margin on every
//! side, so the spans hold every pixel the exact `f32` test (`Prep::enter`) can accept.

use nalgebra::{Matrix3, Vector3};

/// How much `r^2` is inflated for the footprint.
const INFLATE: f64 = 1.02;

/// Pixels of one row to test: `start..end` (empty when `start >= end`).
pub(crate) type Span = (u32, u32);

/// The pixels an ellipsoid may cover in the rows `rows` of an image `width` pixels wide.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Footprint {
    /// Conic `P` in pixel coordinates: `P00, P01, P02, P11, P12, P22`.
    p: [f64; 6],
    /// Half-plane `g . (X, Y, 1) < 0` of rays that meet the ellipsoid ahead.
    g: [f64; 3],
    /// Whether the camera centre is inside the inflated ellipsoid (every pixel is a
    /// candidate).
    inside: bool,
    /// First and one past the last row that may be covered.
    pub(crate) rows: (u32, u32),
    width: u32,
}

/// `T = R K^-1` of a camera with rotation `rot` (camera to world) and pinhole `fx, fy,
/// cx, cy`, by columns: the world ray of pixel coordinate `(X, Y)` is `T (X, Y, 1)`.
pub(crate) fn pixel_to_ray(rot: &Matrix3<f32>, k: [f32; 4]) -> [Vector3<f64>; 3] {
    let r = rot.map(|v| v as f64);
    let [fx, fy, cx, cy] = k.map(|v| v as f64);
    let (c0, c1, c2) = (r.column(0), r.column(1), r.column(2));
    [c0 / fx, c1 / fy, c2 - c0 * (cx / fx) - c1 * (cy / fy)]
}

impl Footprint {
    /// The footprint of the ellipsoid with inverse covariance `inv`, seen from a centre at
    /// `d` from its mean, radius `r2` (squared), in rows `rows` (first, one past the last)
    /// of an image `width` wide whose pixel rays are `t` ([`pixel_to_ray`]).
    pub(crate) fn new(
        inv: &Matrix3<f32>,
        d: &Vector3<f32>,
        r2: f32,
        t: &[Vector3<f64>; 3],
        rows: (u32, u32),
        width: u32,
    ) -> Footprint {
        let a = inv.map(|v| v as f64);
        let d = d.map(|v| v as f64);
        let ad = a * d;
        let c = d.dot(&ad) - r2 as f64 * INFLATE;
        let g = t.map(|col| col.dot(&ad));
        let ta = t.map(|col| a * col);
        let tat = |i: usize, j: usize| t[i].dot(&ta[j]);
        let p = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)]
            .map(|(i, j)| g[i] * g[j] - c * tat(i, j));
        let mut fp = Footprint {
            p,
            g,
            inside: c.is_nan() || c <= 0.0,
            rows,
            width,
        };
        if let Some((y0, y1)) = fp.ellipse_rows() {
            // Rows whose centre `row + 0.5` lies in `[y0, y1]`, one more on each side.
            let first = to_pixel(libm::ceil(y0 - 0.5) - 1.0);
            let last = to_pixel(libm::floor(y1 - 0.5) + 2.0);
            // max then min: clamp would panic on an empty band (rows.0 > rows.1).
            let band = |r: u32| r.max(rows.0).min(rows.1);
            fp.rows = (band(first), band(last));
        }
        fp
    }

    /// The rows `(Y min, Y max)` of the conic when it is a bounded ellipse (the ellipsoid
    /// entirely ahead of the camera), from its horizontal tangents: the lines
    /// `l = (0, 1, -Y)` with `l^T adj(P) l = 0`.
    fn ellipse_rows(&self) -> Option<(f64, f64)> {
        let [a, b, c, d, e, f] = self.p;
        if self.inside || !(a < 0.0 && a * d - b * b > 0.0) {
            return None;
        }
        let (adj11, adj12, adj22) = (a * f - c * c, b * c - a * e, a * d - b * b);
        let disc = adj12 * adj12 - adj11 * adj22;
        if disc.is_nan() || disc < 0.0 {
            return None;
        }
        let s = libm::sqrt(disc);
        let (y0, y1) = ((adj12 - s) / adj22, (adj12 + s) / adj22);
        (y0.is_finite() && y1.is_finite()).then_some((y0.min(y1), y0.max(y1)))
    }

    /// The column spans of row `row` that may be covered (at most two).
    pub(crate) fn spans(&self, row: u32) -> [Span; 2] {
        let full = (0, self.width);
        if self.inside {
            return [full, (0, 0)];
        }
        let y = row as f64 + 0.5;
        let [p00, p01, p02, p11, p12, p22] = self.p;
        // Quadratic a X^2 + b X + c >= 0 on this row.
        let (a, b, c) = (p00, 2.0 * (p01 * y + p02), (p11 * y + 2.0 * p12) * y + p22);
        let (lo, hi) = (f64::NEG_INFINITY, f64::INFINITY);
        let disc = b * b - 4.0 * a * c;
        let (first, second) = if !(a.is_finite() && b.is_finite() && c.is_finite()) {
            ((lo, hi), (1.0, 0.0))
        } else if a == 0.0 {
            match b.partial_cmp(&0.0) {
                Some(core::cmp::Ordering::Greater) => ((-c / b, hi), (1.0, 0.0)),
                Some(core::cmp::Ordering::Less) => ((lo, -c / b), (1.0, 0.0)),
                _ if c >= 0.0 => ((lo, hi), (1.0, 0.0)),
                _ => return [(0, 0); 2],
            }
        } else if disc.is_nan() || disc < 0.0 {
            if a < 0.0 {
                return [(0, 0); 2];
            }
            ((lo, hi), (1.0, 0.0))
        } else {
            // Roots without cancellation: q = -(b + sign(b) sqrt(disc)) / 2.
            let q = -0.5 * (b + libm::copysign(libm::sqrt(disc), b));
            let (r0, r1) = if q == 0.0 { (0.0, 0.0) } else { (q / a, c / q) };
            let (r0, r1) = (r0.min(r1), r0.max(r1));
            if a < 0.0 {
                ((r0, r1), (1.0, 0.0))
            } else {
                ((lo, r0), (r1, hi))
            }
        };
        // Half-plane g0 X + k < 0.
        let k = self.g[1] * y + self.g[2];
        let g0 = self.g[0];
        let (h0, h1) = if g0 > 0.0 {
            (lo, -k / g0)
        } else if g0 < 0.0 {
            (-k / g0, hi)
        } else if k <= 0.0 || k.is_nan() {
            (lo, hi)
        } else {
            return [(0, 0); 2];
        };
        let clip = |(x0, x1): (f64, f64)| -> Span {
            let (x0, x1) = (x0.max(h0), x1.min(h1));
            if x0.is_nan() || x1.is_nan() || x0 > x1 {
                return (0, 0);
            }
            // Columns whose centre `col + 0.5` lies in `[x0, x1]`, one more on each side.
            let start = to_pixel(libm::ceil(x0 - 0.5) - 1.0).min(self.width);
            let end = to_pixel(libm::floor(x1 - 0.5) + 2.0).min(self.width);
            (start, end)
        };
        [clip(first), clip(second)]
    }
}

/// `v` as a pixel index: negative to 0, beyond `u32` (or infinite) to `u32::MAX`, NaN to 0.
fn to_pixel(v: f64) -> u32 {
    if v >= u32::MAX as f64 {
        u32::MAX
    } else if v > 0.0 {
        v as u32
    } else {
        0
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::geometry::camera::Pinhole;
    use crate::geometry::gaussian::{floor_abs, Gaussian};
    use crate::readout::raycast::Prep;
    use crate::testutil::Lcg;
    use nalgebra::{Rotation3, Vector3};

    /// A random rotation from an axis and an angle.
    fn rotation(rng: &mut Lcg) -> Rotation3<f32> {
        let axis = Vector3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5);
        let angle = (rng.next() * 6.3) as f32;
        Rotation3::from_scaled_axis(axis.map(|v| v as f32).normalize() * angle)
    }

    /// Every pixel whose ray the exact test accepts lies in the footprint, for ellipsoids
    /// ahead of, around, behind and enclosing-nearly the camera, thin and round, at radii
    /// 1, 2.5 and 10; and the footprint is not much larger than what it holds.
    #[test]
    fn footprint_holds_every_hit() {
        let mut rng = Lcg(7);
        let cam = Pinhole {
            fx: 40.0,
            fy: 36.0,
            cx: 23.0,
            cy: 19.5,
            width: 48,
            height: 36,
        };
        let (mut hits, mut tested, mut straddling, mut cases) = (0usize, 0usize, 0, 0);
        for case in 0..3000 {
            let rot = rotation(&mut rng);
            let r = [1.0f32, 2.5, 10.0][case % 3];
            let r2 = r * r;
            // Means from 2 cm to 4 m away, in any direction (a third of them behind).
            let dir = Vector3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.2);
            let dist = 0.02 + 4.0 * rng.next() * rng.next();
            let mean = dir.map(|v| v as f32).normalize() * dist as f32;
            let sigma = [0, 1, 2].map(|_| (0.1 * rng.next().powi(3)) as f32);
            let shape = rotation(&mut rng).into_inner();
            let cov = shape
                * nalgebra::Matrix3::from_diagonal(&sigma.map(|s| s * s).into())
                * shape.transpose();
            let g = Gaussian {
                mean,
                covariance: cov,
                count: 10,
            };
            let prepared = g.prepare(1e-3, floor_abs(0.1));
            let Some(p) = Prep::new(&prepared, 1, &Vector3::zeros(), r2) else {
                continue;
            };
            cases += 1;
            let t = pixel_to_ray(rot.matrix(), [cam.fx, cam.fy, cam.cx, cam.cy]);
            let fp = Footprint::new(&p.inv, &p.d, r2, &t, (0, cam.height), cam.width);
            straddling += (fp.rows == (0, cam.height)) as usize;
            for row in 0..cam.height {
                let spans = fp.spans(row);
                let inside = |col: u32| {
                    (fp.rows.0..fp.rows.1).contains(&row)
                        && spans.iter().any(|&(s, e)| (s..e).contains(&col))
                };
                for col in 0..cam.width {
                    let ray = cam.ray(col, row);
                    let d = rot * Vector3::new(ray[0], ray[1], ray[2]);
                    let hit = p.enter(&(d / d.norm()), r2, 100.0).is_some();
                    assert!(
                        !hit || inside(col),
                        "case {case}: pixel ({col}, {row}) missed"
                    );
                    hits += hit as usize;
                    tested += inside(col) as usize;
                }
            }
        }
        assert!(
            cases > 2000 && straddling > 100,
            "{cases} cases, {straddling} unbounded"
        );
        assert!(hits > 100_000, "{hits} hits");
        // Margins of a pixel and 1% of the radius, and the rows of unbounded footprints.
        assert!(
            tested * 4 < hits * 5,
            "{tested} pixels tested for {hits} hits"
        );
    }
}
