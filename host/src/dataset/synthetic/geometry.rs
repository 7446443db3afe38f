//! Labelled primitives (boxes turned about z, upright cylinders), a bounding-volume
//! hierarchy over them and exact ray casting.
//!
//! A ray returns the nearest surface it enters from outside (`t > 0`); a camera is never
//! placed inside a primitive, so there is no inside case to handle.

/// A shape in world coordinates (metres, z up).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// A box with half extents `half`, centred at `center`, turned by `yaw` about z.
    Box {
        /// Centre.
        center: [f32; 3],
        /// Half extents along its own axes.
        half: [f32; 3],
        /// Rotation about z, radians.
        yaw: f32,
    },
    /// An upright cylinder: axis along z through `(x, y)`, from `z0` to `z1`.
    Cylinder {
        /// Axis position.
        xy: [f32; 2],
        /// Radius.
        radius: f32,
        /// Bottom height.
        z0: f32,
        /// Top height.
        z1: f32,
    },
}

/// A shape with its NYU40 class (0 = void: geometry without a label) and object instance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Primitive {
    /// Geometry.
    pub shape: Shape,
    /// NYU40 class, 0 = void.
    pub label: u8,
    /// Object instance (all parts of one object share it).
    pub instance: u16,
}

impl Primitive {
    /// An axis-aligned box from its corners.
    ///
    /// ```
    /// use sndt_host::dataset::synthetic::geometry::{Primitive, Shape};
    /// let p = Primitive::axis_box([0.0, 0.0, 0.0], [2.0, 1.0, 1.0], 7, 3);
    /// assert_eq!(p.shape, Shape::Box { center: [1.0, 0.5, 0.5], half: [1.0, 0.5, 0.5], yaw: 0.0 });
    /// ```
    pub fn axis_box(min: [f32; 3], max: [f32; 3], label: u8, instance: u16) -> Primitive {
        let center = std::array::from_fn(|a| 0.5 * (min[a] + max[a]));
        let half = std::array::from_fn(|a| 0.5 * (max[a] - min[a]));
        Primitive {
            shape: Shape::Box {
                center,
                half,
                yaw: 0.0,
            },
            label,
            instance,
        }
    }
}

/// An axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: [f32; 3],
    /// Upper corner.
    pub max: [f32; 3],
}

impl Aabb {
    const EMPTY: Aabb = Aabb {
        min: [f32::INFINITY; 3],
        max: [f32::NEG_INFINITY; 3],
    };

    fn grow(&mut self, o: &Aabb) {
        for a in 0..3 {
            self.min[a] = self.min[a].min(o.min[a]);
            self.max[a] = self.max[a].max(o.max[a]);
        }
    }

    /// The smallest box holding both.
    ///
    /// ```
    /// use sndt_host::dataset::synthetic::geometry::Aabb;
    /// let a = Aabb { min: [0.0; 3], max: [1.0; 3] };
    /// let b = Aabb { min: [2.0, -1.0, 0.5], max: [3.0, 0.0, 0.6] };
    /// assert_eq!(a.union(&b), Aabb { min: [0.0, -1.0, 0.0], max: [3.0, 1.0, 1.0] });
    /// ```
    pub fn union(&self, o: &Aabb) -> Aabb {
        let mut u = *self;
        u.grow(o);
        u
    }

    /// Whether `p` lies inside, faces included, after growing every side by `margin`.
    ///
    /// ```
    /// use sndt_host::dataset::synthetic::geometry::Aabb;
    /// let a = Aabb { min: [0.0; 3], max: [1.0; 3] };
    /// assert!(a.contains(&[1.1, 0.5, 0.5], 0.2) && !a.contains(&[1.1, 0.5, 0.5], 0.0));
    /// ```
    pub fn contains(&self, p: &[f32; 3], margin: f32) -> bool {
        (0..3).all(|a| p[a] >= self.min[a] - margin && p[a] <= self.max[a] + margin)
    }

    fn centre(&self, a: usize) -> f32 {
        0.5 * (self.min[a] + self.max[a])
    }

    /// Entry and exit distances of the ray `o + t d` (with `inv = 1/d`), if it meets the
    /// box before `t_max`.
    pub(crate) fn slab(&self, o: &[f32; 3], inv: &[f32; 3], t_max: f32) -> Option<f32> {
        let (mut t0, mut t1) = (0.0f32, t_max);
        for a in 0..3 {
            let ta = (self.min[a] - o[a]) * inv[a];
            let tb = (self.max[a] - o[a]) * inv[a];
            let (lo, hi) = if ta < tb { (ta, tb) } else { (tb, ta) };
            // NaN (0 * inf on a face) compares false and leaves the interval unchanged.
            if lo > t0 {
                t0 = lo;
            }
            if hi < t1 {
                t1 = hi;
            }
        }
        (t0 <= t1).then_some(t0)
    }
}

impl Shape {
    /// The world-axis bounding box.
    pub fn aabb(&self) -> Aabb {
        match *self {
            Shape::Box { center, half, yaw } => {
                let (s, c) = yaw.sin_cos();
                let ex = (c * half[0]).abs() + (s * half[1]).abs();
                let ey = (s * half[0]).abs() + (c * half[1]).abs();
                Aabb {
                    min: [center[0] - ex, center[1] - ey, center[2] - half[2]],
                    max: [center[0] + ex, center[1] + ey, center[2] + half[2]],
                }
            }
            Shape::Cylinder { xy, radius, z0, z1 } => Aabb {
                min: [xy[0] - radius, xy[1] - radius, z0],
                max: [xy[0] + radius, xy[1] + radius, z1],
            },
        }
    }

    /// Distance along the ray `o + t d` (`d` of any length) at which it enters the shape
    /// from outside, when that is in `(0, t_max)`.
    ///
    /// ```
    /// use sndt_host::dataset::synthetic::geometry::Shape;
    /// let b = Shape::Box { center: [3.0, 0.0, 0.0], half: [1.0, 1.0, 1.0], yaw: 0.0 };
    /// assert_eq!(b.enter(&[0.0, 0.0, 0.0], &[1.0, 0.0, 0.0], 10.0), Some(2.0));
    /// let c = Shape::Cylinder { xy: [0.0, 5.0], radius: 0.5, z0: -1.0, z1: 1.0 };
    /// assert_eq!(c.enter(&[0.0, 0.0, 0.0], &[0.0, 1.0, 0.0], 10.0), Some(4.5));
    /// ```
    pub fn enter(&self, o: &[f32; 3], d: &[f32; 3], t_max: f32) -> Option<f32> {
        match *self {
            Shape::Box { center, half, yaw } => {
                // Into the box's own frame: translate, then turn by -yaw.
                let (s, c) = yaw.sin_cos();
                let (px, py) = (o[0] - center[0], o[1] - center[1]);
                let lo = [c * px + s * py, -s * px + c * py, o[2] - center[2]];
                let ld = [c * d[0] + s * d[1], -s * d[0] + c * d[1], d[2]];
                let (mut t0, mut t1) = (f32::NEG_INFINITY, t_max);
                for a in 0..3 {
                    if ld[a] == 0.0 {
                        if lo[a].abs() > half[a] {
                            return None;
                        }
                        continue;
                    }
                    let inv = 1.0 / ld[a];
                    let ta = (-half[a] - lo[a]) * inv;
                    let tb = (half[a] - lo[a]) * inv;
                    let (n, f) = if ta < tb { (ta, tb) } else { (tb, ta) };
                    t0 = t0.max(n);
                    t1 = t1.min(f);
                    if t0 > t1 {
                        return None;
                    }
                }
                (t0 > 0.0).then_some(t0)
            }
            Shape::Cylinder { xy, radius, z0, z1 } => {
                let mut best = None::<f32>;
                let mut consider = |t: f32| {
                    if t > 0.0 && t < t_max && best.is_none_or(|b| t < b) {
                        best = Some(t);
                    }
                };
                let (px, py) = (o[0] - xy[0], o[1] - xy[1]);
                let a = d[0] * d[0] + d[1] * d[1];
                if a > 0.0 {
                    let b = px * d[0] + py * d[1];
                    let c = px * px + py * py - radius * radius;
                    let disc = b * b - a * c;
                    if disc >= 0.0 {
                        let t = (-b - disc.sqrt()) / a;
                        let z = o[2] + t * d[2];
                        if z >= z0 && z <= z1 {
                            consider(t);
                        }
                    }
                }
                if d[2] != 0.0 {
                    for zc in [z0, z1] {
                        // A cap is entered from outside only from its own side.
                        let outside = if zc == z0 { o[2] < z0 } else { o[2] > z1 };
                        if !outside {
                            continue;
                        }
                        let t = (zc - o[2]) / d[2];
                        let (x, y) = (px + t * d[0], py + t * d[1]);
                        if x * x + y * y <= radius * radius {
                            consider(t);
                        }
                    }
                }
                best
            }
        }
    }

    /// Euclidean distance from a point to the shape (0 inside).
    ///
    /// ```
    /// use sndt_host::dataset::synthetic::geometry::Shape;
    /// let b = Shape::Box { center: [0.0, 0.0, 0.0], half: [1.0, 1.0, 1.0], yaw: 0.0 };
    /// assert_eq!(b.distance(&[4.0, 5.0, 0.5]), 5.0);
    /// let c = Shape::Cylinder { xy: [0.0, 0.0], radius: 1.0, z0: 0.0, z1: 1.0 };
    /// assert_eq!(c.distance(&[3.0, 0.0, 0.5]), 2.0);
    /// ```
    pub fn distance(&self, p: &[f32; 3]) -> f32 {
        let (horizontal, dz) = self.excess(p);
        (horizontal * horizontal + dz * dz).sqrt()
    }

    /// Distance from a point to the shape's footprint on the floor plan (ignoring z).
    pub fn distance_2d(&self, p: &[f32; 2]) -> f32 {
        self.excess(&[p[0], p[1], 0.0]).0
    }

    /// How far a point lies outside the shape across z (horizontally) and along z.
    fn excess(&self, p: &[f32; 3]) -> (f32, f32) {
        let out = |v: f32, lo: f32, hi: f32| (lo - v).max(v - hi).max(0.0);
        match *self {
            Shape::Box { center, half, yaw } => {
                let (s, c) = yaw.sin_cos();
                let (px, py) = (p[0] - center[0], p[1] - center[1]);
                let l = [c * px + s * py, -s * px + c * py];
                let dx = (l[0].abs() - half[0]).max(0.0);
                let dy = (l[1].abs() - half[1]).max(0.0);
                let dz = out(p[2], center[2] - half[2], center[2] + half[2]);
                ((dx * dx + dy * dy).sqrt(), dz)
            }
            Shape::Cylinder { xy, radius, z0, z1 } => {
                let r = ((p[0] - xy[0]).powi(2) + (p[1] - xy[1]).powi(2)).sqrt();
                ((r - radius).max(0.0), out(p[2], z0, z1))
            }
        }
    }

    /// Whether a point is inside (or on) the shape.
    pub fn contains(&self, p: &[f32; 3]) -> bool {
        match *self {
            Shape::Box { center, half, yaw } => {
                let (s, c) = yaw.sin_cos();
                let (px, py) = (p[0] - center[0], p[1] - center[1]);
                let l = [c * px + s * py, -s * px + c * py, p[2] - center[2]];
                (0..3).all(|a| l[a].abs() <= half[a])
            }
            Shape::Cylinder { xy, radius, z0, z1 } => {
                let (dx, dy) = (p[0] - xy[0], p[1] - xy[1]);
                dx * dx + dy * dy <= radius * radius && p[2] >= z0 && p[2] <= z1
            }
        }
    }
}

/// What a ray hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray, in units of the ray direction's length.
    pub t: f32,
    /// NYU40 class (0 void).
    pub label: u8,
    /// Object instance.
    pub instance: u16,
}

#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: Aabb,
    /// Leaf: first primitive index; inner: index of the left child (right = left + 1).
    first: u32,
    /// Leaf: primitive count (> 0); inner: 0.
    count: u32,
}

const LEAF_SIZE: usize = 4;

/// Primitives with a bounding-volume hierarchy for fast nearest-hit queries.
#[derive(Clone, Debug)]
pub struct Bvh {
    prims: Vec<Primitive>,
    nodes: Vec<Node>,
}

impl Bvh {
    /// Builds the hierarchy (median split on the longest axis of the centroids).
    ///
    /// ```
    /// use sndt_host::dataset::synthetic::geometry::{Bvh, Primitive, Shape};
    /// let wall = Primitive { shape: Shape::Box { center: [2.0, 0.0, 0.0], half: [0.1, 5.0, 5.0], yaw: 0.0 },
    ///                        label: 1, instance: 0 };
    /// let bvh = Bvh::new(vec![wall]);
    /// let hit = bvh.cast(&[0.0, 0.0, 0.0], &[1.0, 0.0, 0.0], 100.0).unwrap();
    /// assert!((hit.t - 1.9).abs() < 1e-6 && hit.label == 1);
    /// ```
    pub fn new(mut prims: Vec<Primitive>) -> Bvh {
        let mut nodes = Vec::with_capacity(2 * prims.len() / LEAF_SIZE + 1);
        let boxes: Vec<Aabb> = prims.iter().map(|p| p.shape.aabb()).collect();
        let mut order: Vec<usize> = (0..prims.len()).collect();
        nodes.push(Node {
            bounds: Aabb::EMPTY,
            first: 0,
            count: 0,
        });
        Self::build(&mut nodes, 0, &mut order, 0, &boxes);
        prims = order.iter().map(|&i| prims[i]).collect();
        Bvh { prims, nodes }
    }

    fn build(nodes: &mut Vec<Node>, at: usize, order: &mut [usize], first: usize, boxes: &[Aabb]) {
        let mut bounds = Aabb::EMPTY;
        for &i in order.iter() {
            bounds.grow(&boxes[i]);
        }
        nodes[at].bounds = bounds;
        if order.len() <= LEAF_SIZE {
            nodes[at].first = first as u32;
            nodes[at].count = order.len() as u32;
            return;
        }
        let mut cb = Aabb::EMPTY;
        for &i in order.iter() {
            let c = [boxes[i].centre(0), boxes[i].centre(1), boxes[i].centre(2)];
            cb.grow(&Aabb { min: c, max: c });
        }
        let axis = (0..3)
            .max_by(|&a, &b| (cb.max[a] - cb.min[a]).total_cmp(&(cb.max[b] - cb.min[b])))
            .unwrap_or(0);
        order.sort_by(|&a, &b| boxes[a].centre(axis).total_cmp(&boxes[b].centre(axis)));
        let mid = order.len() / 2;
        let left = nodes.len();
        let empty = Node {
            bounds: Aabb::EMPTY,
            first: 0,
            count: 0,
        };
        nodes.push(empty);
        nodes.push(empty);
        nodes[at].first = left as u32;
        nodes[at].count = 0;
        let (lo, hi) = order.split_at_mut(mid);
        Self::build(nodes, left, lo, first, boxes);
        Self::build(nodes, left + 1, hi, first + mid, boxes);
    }

    /// The primitives (in hierarchy order).
    pub fn primitives(&self) -> &[Primitive] {
        &self.prims
    }

    /// Nearest hit along `o + t d` with `0 < t < t_max`.
    pub fn cast(&self, o: &[f32; 3], d: &[f32; 3], t_max: f32) -> Option<Hit> {
        let inv = [1.0 / d[0], 1.0 / d[1], 1.0 / d[2]];
        let mut best: Option<Hit> = None;
        let mut limit = t_max;
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if node.bounds.slab(o, &inv, limit).is_none() {
                continue;
            }
            if node.count > 0 {
                let first = node.first as usize;
                for p in &self.prims[first..first + node.count as usize] {
                    if let Some(t) = p.shape.enter(o, d, limit) {
                        limit = t;
                        best = Some(Hit {
                            t,
                            label: p.label,
                            instance: p.instance,
                        });
                    }
                }
                continue;
            }
            // Visit the nearer child first (pushed last).
            let (l, r) = (node.first, node.first + 1);
            let tl = self.nodes[l as usize].bounds.slab(o, &inv, limit);
            let tr = self.nodes[r as usize].bounds.slab(o, &inv, limit);
            let (near, far) = match (tl, tr) {
                (Some(a), Some(b)) if b < a => (Some(r), Some(l)),
                (Some(_), Some(_)) => (Some(l), Some(r)),
                (Some(_), None) => (Some(l), None),
                (None, Some(_)) => (Some(r), None),
                (None, None) => (None, None),
            };
            for c in [far, near].into_iter().flatten() {
                if top < stack.len() {
                    stack[top] = c;
                    top += 1;
                }
            }
        }
        best
    }

    /// Whether a point lies inside any primitive.
    pub fn occupied(&self, p: &[f32; 3]) -> bool {
        self.prims.iter().any(|q| q.shape.contains(p))
    }

    /// The bounds of all primitives (empty: min above max).
    pub fn bounds(&self) -> Aabb {
        self.nodes[0].bounds
    }
}

/// What the renderer casts rays against.
pub trait Cast: Sync {
    /// Nearest hit along `o + t d` with `0 < t < t_max`.
    fn cast(&self, o: &[f32; 3], d: &[f32; 3], t_max: f32) -> Option<Hit>;
}

impl Cast for Bvh {
    fn cast(&self, o: &[f32; 3], d: &[f32; 3], t_max: f32) -> Option<Hit> {
        Bvh::cast(self, o, d, t_max)
    }
}

/// Most parts a [`Group`] holds.
pub const MAX_PARTS: usize = 64;

/// Hierarchies side by side, each with its bounds (the rooms and the corridor of a
/// building floor). A ray descends only into the parts whose bounds it enters before its
/// nearest hit so far, nearest first: a camera in a closed room casts into that room, and
/// into another part only through an opening. Finds the same nearest hit as one
/// hierarchy over all primitives.
#[derive(Clone, Debug)]
pub struct Group {
    parts: Vec<Bvh>,
}

impl Group {
    /// One part per list of primitives (empty lists are dropped).
    ///
    /// # Panics
    /// With more than [`MAX_PARTS`] parts.
    ///
    /// ```
    /// use sndt_host::dataset::synthetic::geometry::{Cast, Group, Primitive};
    /// let near = Primitive::axis_box([2.0, -1.0, -1.0], [2.1, 1.0, 1.0], 1, 1);
    /// let far = Primitive::axis_box([5.0, -1.0, -1.0], [5.1, 1.0, 1.0], 2, 2);
    /// let g = Group::new(vec![vec![far], vec![near]]);
    /// let (hit, parts) = g.cast_counted(&[0.0, 0.0, 0.0], &[1.0, 0.0, 0.0], 100.0);
    /// assert_eq!((hit.unwrap().label, parts), (1, 1)); // the far part is never entered
    /// ```
    pub fn new(parts: Vec<Vec<Primitive>>) -> Group {
        let parts: Vec<Bvh> = parts
            .into_iter()
            .filter(|p| !p.is_empty())
            .map(Bvh::new)
            .collect();
        assert!(
            parts.len() <= MAX_PARTS,
            "a group holds at most {MAX_PARTS} parts"
        );
        Group { parts }
    }

    /// The parts' hierarchies.
    pub fn parts(&self) -> &[Bvh] {
        &self.parts
    }

    /// All primitives of all parts.
    pub fn primitives(&self) -> impl Iterator<Item = &Primitive> {
        self.parts.iter().flat_map(Bvh::primitives)
    }

    /// The nearest hit and how many parts the ray descended into.
    pub fn cast_counted(&self, o: &[f32; 3], d: &[f32; 3], t_max: f32) -> (Option<Hit>, usize) {
        let inv = [1.0 / d[0], 1.0 / d[1], 1.0 / d[2]];
        // The parts the ray enters, by entry distance (insertion sort: a handful).
        let mut order = [(0.0f32, 0u8); MAX_PARTS];
        let mut n = 0;
        for (i, part) in self.parts.iter().enumerate() {
            if let Some(t) = part.bounds().slab(o, &inv, t_max) {
                let mut k = n;
                while k > 0 && order[k - 1].0 > t {
                    order[k] = order[k - 1];
                    k -= 1;
                }
                order[k] = (t, i as u8);
                n += 1;
            }
        }
        let (mut best, mut limit, mut entered) = (None::<Hit>, t_max, 0);
        for &(t, i) in &order[..n] {
            if t >= limit {
                break;
            }
            entered += 1;
            if let Some(hit) = self.parts[i as usize].cast(o, d, limit) {
                limit = hit.t;
                best = Some(hit);
            }
        }
        (best, entered)
    }
}

impl Cast for Group {
    fn cast(&self, o: &[f32; 3], d: &[f32; 3], t_max: f32) -> Option<Hit> {
        self.cast_counted(o, d, t_max).0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn turned_box_matches_hand_geometry() {
        // A unit cube turned 45 degrees: its corner points at the origin along -x; the ray
        // along +x from the origin enters at x = 5 - sqrt(2)/2.
        let b = Shape::Box {
            center: [5.0, 0.0, 0.0],
            half: [0.5, 0.5, 0.5],
            yaw: std::f32::consts::FRAC_PI_4,
        };
        let t = b.enter(&[0.0, 0.0, 0.0], &[1.0, 0.0, 0.0], 100.0).unwrap();
        assert!((t - (5.0 - 0.5f32 * 2f32.sqrt())).abs() < 1e-5, "{t}");
        let bb = b.aabb();
        assert!((bb.max[0] - (5.0 + 0.5 * 2f32.sqrt())).abs() < 1e-5);
    }

    #[test]
    fn cylinder_cap_and_side() {
        let c = Shape::Cylinder {
            xy: [0.0, 0.0],
            radius: 1.0,
            z0: 0.0,
            z1: 2.0,
        };
        // From above, straight down: the top cap at z = 2.
        assert_eq!(
            c.enter(&[0.2, 0.0, 5.0], &[0.0, 0.0, -1.0], 10.0),
            Some(3.0)
        );
        // Grazing past: no hit.
        assert_eq!(c.enter(&[-5.0, 1.01, 1.0], &[1.0, 0.0, 0.0], 10.0), None);
        // Too far for t_max.
        assert_eq!(c.enter(&[-5.0, 0.0, 1.0], &[1.0, 0.0, 0.0], 3.9), None);
    }

    #[test]
    fn bvh_agrees_with_brute_force() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut prims = Vec::new();
        for i in 0..200u16 {
            let c = [
                rng.random_range(-10.0..10.0),
                rng.random_range(-10.0..10.0),
                rng.random_range(-3.0..3.0),
            ];
            let shape = if i % 3 == 0 {
                Shape::Cylinder {
                    xy: [c[0], c[1]],
                    radius: rng.random_range(0.05..0.5),
                    z0: c[2],
                    z1: c[2] + rng.random_range(0.1..2.0),
                }
            } else {
                Shape::Box {
                    center: c,
                    half: [
                        rng.random_range(0.01..1.0),
                        rng.random_range(0.01..1.0),
                        rng.random_range(0.01..1.0),
                    ],
                    yaw: rng.random_range(0.0..6.3),
                }
            };
            prims.push(Primitive {
                shape,
                label: (i % 40 + 1) as u8,
                instance: i,
            });
        }
        let bvh = Bvh::new(prims.clone());
        let o = [0.0, 0.0, 0.0];
        for _ in 0..2000 {
            let d = [
                rng.random_range(-1.0f32..1.0),
                rng.random_range(-1.0f32..1.0),
                rng.random_range(-1.0f32..1.0),
            ];
            let brute = prims
                .iter()
                .filter(|p| !p.shape.contains(&o))
                .filter_map(|p| p.shape.enter(&o, &d, 100.0).map(|t| (t, p.instance)))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let fast = bvh.cast(&o, &d, 100.0).map(|h| (h.t, h.instance));
            assert_eq!(brute, fast, "ray {d:?}");
        }
    }
}
