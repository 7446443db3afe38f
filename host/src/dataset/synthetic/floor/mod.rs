//! A building floor: eleven rooms of the six kinds in two rows on either side of a
//! corridor, each entered through a doorway, and walks through all of them.
//!
//! Every room is the room [`SynthScene::generate`] makes (same furniture, labels and
//! instances; the floor's rooms have their own seed, [`Floor::room_seed`]), with its door
//! standing open in a doorway cut through its wall, turned so that the doorway opens onto
//! the corridor. The corridor has the floor, ceiling and wall labels of the rooms,
//! pictures between the doorways, a window at each end and unlabelled ceiling lights.
//! Object instances are numbered apart per room. Rooms and corridor are the parts of a
//! [`Group`], so a ray descends only into the part the camera stands in and into what it
//! sees through an opening (1.4 of the 12 parts per ray on walk 1): a 1024x768 frame
//! costs about 1.3 times a frame of one room (280 against 220 ms on 2 cores).
//!
//! The floor is made here (layout: rooms placed along the corridor, the corridor's
//! primitives); `walk.rs` times the walks through it and `planner.rs` plans their paths on
//! the clearance grid.

mod planner;
mod walk;

use super::geometry::{Cast, Group, Hit, Primitive, Shape};
use super::scenes::class::{CEILING, FLOOR, PICTURE, VOID, WALL, WINDOW};
use super::scenes::{OpenRoom, SceneKind, SynthScene, DOOR_H, DOOR_W, WALL_T};
use planner::{Grid, RES, R_MIN};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f32::consts::{FRAC_PI_2, PI, TAU};

/// Rooms on the floor: the six kinds in [`SceneKind::ALL`]'s order, then again without
/// the open plan.
pub const ROOMS: usize = 11;

/// Frames of a walk when none are asked for: about 10 per second.
pub const DEFAULT_FRAMES: usize = 1000;

/// The scene name of the floor (its walks are trajectories `cam_00`, `cam_01`, ...).
pub const NAME: &str = "synth_floor";

/// Width of the corridor, metres.
const CORRIDOR_W: f32 = 2.0;
/// Height of the corridor: the lowest room's, so no room's ceiling shows above a lintel.
const CORRIDOR_H: f32 = 2.5;
/// Space between the walls of neighbouring rooms.
const GAP: f32 = 0.1;

/// A room of the floor.
#[derive(Clone, Debug)]
pub struct FloorRoom {
    /// Name, e.g. `r03_office`.
    pub name: String,
    /// Kind of room.
    pub kind: SceneKind,
    /// The room of the generator it is: [`SynthScene::generate`]`(generator, seed)`
    /// with the floor's seed for its rooms ([`Floor::room_seed`]).
    pub generator: usize,
    /// Interior on the floor plan: `[xmin, ymin, xmax, ymax]`.
    pub interior: [f32; 4],
    /// Ceiling height.
    pub height: f32,
    /// Centre of the doorway, in the middle of the wall.
    pub door: [f32; 2],
    /// Unit vector across the doorway, from the corridor into the room.
    pub inward: [f32; 2],
    /// Centres of objects worth looking at.
    pub interest: Vec<[f32; 3]>,
}

impl FloorRoom {
    /// Whether `p` (floor plan) lies inside the room.
    pub fn contains(&self, p: &[f32; 2]) -> bool {
        inside(&self.interior, p)
    }

    /// The doorway on the floor plan: the opening through the wall.
    fn doorway(&self) -> [f32; 4] {
        let along = [self.inward[1].abs(), self.inward[0].abs()];
        let (a, c) = (0.5 * DOOR_W, 0.5 * WALL_T);
        let h = [
            along[0] * a + self.inward[0].abs() * c,
            along[1] * a + self.inward[1].abs() * c,
        ];
        [
            self.door[0] - h[0],
            self.door[1] - h[1],
            self.door[0] + h[0],
            self.door[1] + h[1],
        ]
    }
}

fn inside(r: &[f32; 4], p: &[f32; 2]) -> bool {
    p[0] >= r[0] && p[0] <= r[2] && p[1] >= r[1] && p[1] <= r[3]
}

/// No rectangle on the floor plan (`[xmin, ymin, xmax, ymax]`, min above max).
const EMPTY: [f32; 4] = [
    f32::INFINITY,
    f32::INFINITY,
    f32::NEG_INFINITY,
    f32::NEG_INFINITY,
];

/// The smallest rectangle holding both.
fn union(a: &[f32; 4], b: &[f32; 4]) -> [f32; 4] {
    [
        a[0].min(b[0]),
        a[1].min(b[1]),
        a[2].max(b[2]),
        a[3].max(b[3]),
    ]
}

/// Room `open` turned by `k` quarter turns with its interior's minimum corner at `at`, its
/// instances after `base`: the room (name and generator still to set) and its primitives.
fn place_room(open: &OpenRoom, k: usize, at: [f32; 2], base: u16) -> (FloorRoom, Vec<Primitive>) {
    let [sx, sy, sz] = open.size;
    let t = WALL_T;
    // The turned interior's corners, to put its minimum corner at `at`.
    let (a, b) = (turn(k, [0.0, 0.0]), turn(k, [sx, sy]));
    let shift = [at[0] - a[0].min(b[0]), at[1] - a[1].min(b[1])];
    let place = |p: [f32; 2]| {
        let q = turn(k, p);
        [q[0] + shift[0], q[1] + shift[1]]
    };
    let (s0, s1) = open.door_span;
    let mid = 0.5 * (s0 + s1);
    let (door, normal) = match open.door_wall {
        0 => ([mid, -0.5 * t], [0.0, -1.0]),
        1 => ([sx + 0.5 * t, mid], [1.0, 0.0]),
        2 => ([mid, sy + 0.5 * t], [0.0, 1.0]),
        _ => ([-0.5 * t, mid], [-1.0, 0.0]),
    };
    let n = turn(k, normal);
    let (near, far) = (place([0.0, 0.0]), place([sx, sy]));
    let room = FloorRoom {
        name: String::new(),
        kind: open.kind,
        generator: 0,
        interior: union(
            &[near[0], near[1], near[0], near[1]],
            &[far[0], far[1], far[0], far[1]],
        ),
        height: sz,
        door: place(door),
        inward: [-n[0], -n[1]],
        interest: open
            .interest
            .iter()
            .map(|p| {
                let q = place([p[0], p[1]]);
                [q[0], q[1], p[2]]
            })
            .collect(),
    };
    let prims = open
        .prims
        .iter()
        .map(|p| turned(p, k, shift, base))
        .collect();
    (room, prims)
}

/// The floor: rooms, corridor, the primitives grouped by part for rendering, and the
/// clearance grid the walks are planned on.
#[derive(Clone, Debug)]
pub struct Floor {
    /// Scene name ([`NAME`]).
    pub name: String,
    /// The rooms, in the order they were generated.
    pub rooms: Vec<FloorRoom>,
    /// The corridor's interior: `[xmin, ymin, xmax, ymax]`.
    pub corridor: [f32; 4],
    /// The corridor's ceiling height.
    pub corridor_height: f32,
    /// One part per room (in order), then the corridor.
    group: Group,
    grid: Grid,
    seed: u64,
}

impl Cast for Floor {
    fn cast(&self, o: &[f32; 3], d: &[f32; 3], t_max: f32) -> Option<Hit> {
        self.group.cast(o, d, t_max)
    }
}

impl Floor {
    /// Generates the floor of seed `seed`; deterministic.
    pub fn generate(seed: u64) -> Floor {
        let seed = Self::room_seed(seed);
        let cy = 0.5 * CORRIDOR_W;
        let t = WALL_T;
        let mut parts: Vec<Vec<Primitive>> = Vec::new();
        let mut rooms = Vec::new();
        // Rows: 0 south of the corridor (doorway in the north wall), 1 north of it.
        let mut cursor = [0.0f32; 2];
        let mut instance_base = 0u16;
        for i in 0..ROOMS {
            let (generator, open) = enterable_room(i, seed);
            let row = usize::from(cursor[1] < cursor[0]);
            let target = if row == 0 { 2 } else { 0 };
            let k = (target + 4 - open.door_wall) % 4;
            let [sx, sy, _] = open.size;
            let (w, d) = if k % 2 == 0 { (sx, sy) } else { (sy, sx) };
            let x0 = cursor[row] + t;
            let y0 = if row == 0 { -cy - t - d } else { cy + t };
            cursor[row] += w + 2.0 * t + GAP;
            let (mut room, prims) = place_room(&open, k, [x0, y0], instance_base);
            instance_base = instance_base
                .checked_add(open.instances)
                .expect("fewer than 65,536 objects on the floor");
            room.name = format!("r{i:02}_{}", open.kind.name());
            room.generator = generator;
            rooms.push(room);
            parts.push(prims);
        }
        // Centre the corridor on the origin.
        let length = cursor[0].max(cursor[1]) - GAP;
        let dx = -0.5 * length;
        for (room, prims) in rooms.iter_mut().zip(&mut parts) {
            room.interior[0] += dx;
            room.interior[2] += dx;
            room.door[0] += dx;
            for p in &mut room.interest {
                p[0] += dx;
            }
            for p in prims.iter_mut() {
                p.shape = shifted(&p.shape, dx);
            }
        }
        let corridor = [dx, -cy, dx + length, cy];
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xC0_441D_0000);
        parts.push(corridor_prims(&rooms, corridor, instance_base, &mut rng));
        let group = Group::new(parts);
        let bounds = rooms.iter().fold(EMPTY, |b, r| union(&b, &r.interior));
        let walkable = |p: &[f32; 2]| {
            inside(&corridor, p)
                || rooms
                    .iter()
                    .any(|r| r.contains(p) || inside(&r.doorway(), p))
        };
        let grid = Grid::new(bounds, group.primitives(), &walkable);
        Floor {
            name: NAME.into(),
            rooms,
            corridor,
            corridor_height: CORRIDOR_H,
            group,
            grid,
            seed,
        }
    }

    /// The seed the rooms of the floor of seed `seed` are generated with (apart from the
    /// seed's separate rooms).
    pub fn room_seed(seed: u64) -> u64 {
        seed ^ 0x00F1_002D_5EED
    }

    /// The primitives, rooms' and corridor's.
    pub fn primitives(&self) -> impl Iterator<Item = &Primitive> {
        self.group.primitives()
    }

    /// The primitives grouped for rendering: one part per room (in order), then the
    /// corridor.
    pub fn group(&self) -> &Group {
        &self.group
    }

    /// Extent on the floor plan, walls included: `[xmin, ymin, xmax, ymax]`.
    pub fn extent(&self) -> [f32; 4] {
        self.group.parts().iter().fold(EMPTY, |e, bvh| {
            let b = bvh.bounds();
            union(&e, &[b.min[0], b.min[1], b.max[0], b.max[1]])
        })
    }

    /// The NYU40 classes that occur on the floor (index = class id).
    pub fn classes(&self) -> [bool; 41] {
        let mut out = [false; 41];
        for p in self.primitives() {
            out[p.label as usize] = true;
        }
        out
    }

    /// The room `p` (floor plan) is in.
    pub fn room_at(&self, p: &[f32; 2]) -> Option<usize> {
        self.rooms.iter().position(|r| r.contains(p))
    }

    /// Whether a camera may stand at `p`: inside a room, the corridor or a doorway, at
    /// least 0.2 m below its ceiling (lintel) and above the floor, and at least `margin`
    /// metres from every primitive.
    pub fn free(&self, p: &[f32; 3], margin: f32) -> bool {
        let xy = [p[0], p[1]];
        let top = if inside(&self.corridor, &xy) {
            Some(self.corridor_height)
        } else {
            self.rooms.iter().find_map(|r| {
                if r.contains(&xy) {
                    Some(r.height)
                } else {
                    inside(&r.doorway(), &xy).then_some(DOOR_H)
                }
            })
        };
        let Some(top) = top else {
            return false;
        };
        if p[2] < 0.2 || p[2] > top - 0.2 {
            return false;
        }
        self.group.parts().iter().all(|bvh| {
            let b = bvh.bounds();
            let near = (0..3).all(|a| p[a] >= b.min[a] - margin && p[a] <= b.max[a] + margin);
            !near
                || bvh
                    .primitives()
                    .iter()
                    .all(|q| q.shape.distance(p) >= margin)
        })
    }
}

/// The generator's room `i` of the floor, or the next of the same kind whose doorway
/// leads to a standpoint (a kind's rooms are `i + 6 k`), with its number.
fn enterable_room(i: usize, seed: u64) -> (usize, OpenRoom) {
    for k in 0.. {
        let index = i + SceneKind::ALL.len() * k;
        let Some(room) = SynthScene::generate_open(index, seed) else {
            continue;
        };
        let [x, y, _] = room.size;
        let (s0, s1) = room.door_span;
        let mid = 0.5 * (s0 + s1);
        let (door, inward) = match room.door_wall {
            0 => ([mid, 0.0], [0.0, 1.0]),
            1 => ([x, mid], [-1.0, 0.0]),
            2 => ([mid, y], [0.0, -1.0]),
            _ => ([0.0, mid], [1.0, 0.0]),
        };
        let interior = [0.0, 0.0, x, y];
        let grid = Grid::new(interior, room.prims.iter(), &|p| inside(&interior, p));
        let entry = [door[0] + 0.6 * inward[0], door[1] + 0.6 * inward[1]];
        let through = [door[0] + 0.1 * inward[0], door[1] + 0.1 * inward[1]];
        let reach = grid.reachable(entry, R_MIN);
        let best = reach.iter().map(|&c| grid.clear[c]).fold(0.0f32, f32::max);
        if grid.at(&through) >= R_MIN && reach.len() as f32 * RES * RES >= 1.0 && best >= 0.5 {
            return (index, room);
        }
    }
    unreachable!("the loop returns")
}

/// Turns a floor-plan point by `k` quarter turns anticlockwise about the origin (exact).
fn turn(k: usize, p: [f32; 2]) -> [f32; 2] {
    match k % 4 {
        0 => p,
        1 => [-p[1], p[0]],
        2 => [-p[0], -p[1]],
        _ => [p[1], -p[0]],
    }
}

/// A primitive turned by `k` quarter turns, moved by `shift`, its instance by `base`.
/// Boxes that end up axis-aligned are stored with yaw 0 (exact).
fn turned(p: &Primitive, k: usize, shift: [f32; 2], base: u16) -> Primitive {
    let shape = match p.shape {
        Shape::Box { center, half, yaw } => {
            let c = turn(k, [center[0], center[1]]);
            let y = yaw + k as f32 * FRAC_PI_2;
            let q = (y / FRAC_PI_2).round();
            let (yaw, half) = if (y - q * FRAC_PI_2).abs() < 1e-4 {
                let odd = (q as i64).rem_euclid(2) == 1;
                (
                    0.0,
                    if odd {
                        [half[1], half[0], half[2]]
                    } else {
                        half
                    },
                )
            } else {
                (y - TAU * ((y + PI) / TAU).floor(), half)
            };
            Shape::Box {
                center: [c[0] + shift[0], c[1] + shift[1], center[2]],
                half,
                yaw,
            }
        }
        Shape::Cylinder { xy, radius, z0, z1 } => {
            let c = turn(k, xy);
            Shape::Cylinder {
                xy: [c[0] + shift[0], c[1] + shift[1]],
                radius,
                z0,
                z1,
            }
        }
    };
    Primitive {
        shape,
        label: p.label,
        instance: p.instance + base,
    }
}

/// A shape moved by `dx` along x.
fn shifted(s: &Shape, dx: f32) -> Shape {
    match *s {
        Shape::Box { center, half, yaw } => Shape::Box {
            center: [center[0] + dx, center[1], center[2]],
            half,
            yaw,
        },
        Shape::Cylinder { xy, radius, z0, z1 } => Shape::Cylinder {
            xy: [xy[0] + dx, xy[1]],
            radius,
            z0,
            z1,
        },
    }
}

/// The corridor: floor, ceiling, end walls, the side walls between the rooms' walls,
/// pictures between the doorways, a window at each end and ceiling lights.
fn corridor_prims(
    rooms: &[FloorRoom],
    c: [f32; 4],
    base: u16,
    rng: &mut ChaCha8Rng,
) -> Vec<Primitive> {
    let (t, h) = (WALL_T, CORRIDOR_H);
    let (floor, ceiling, walls) = (base + 1, base + 2, base + 3);
    let mut next = walls;
    let mut out = vec![
        Primitive::axis_box([c[0] - t, c[1], -t], [c[2] + t, c[3], 0.0], FLOOR, floor),
        // Over half the side walls: its ends stay inside the rooms' walls, never flush
        // with their faces.
        Primitive::axis_box(
            [c[0] - t, c[1] - 0.5 * t, h],
            [c[2] + t, c[3] + 0.5 * t, h + t],
            CEILING,
            ceiling,
        ),
        Primitive::axis_box([c[0] - t, c[1] - t, 0.0], [c[0], c[3] + t, h], WALL, walls),
        Primitive::axis_box([c[2], c[1] - t, 0.0], [c[2] + t, c[3] + t, h], WALL, walls),
    ];
    for south in [true, false] {
        let side: Vec<&FloorRoom> = rooms
            .iter()
            .filter(|r| (r.interior[1] < 0.0) == south)
            .collect();
        let (y0, y1) = if south {
            (c[1] - t, c[1])
        } else {
            (c[3], c[3] + t)
        };
        // Side walls where no room's wall is.
        let mut covered: Vec<(f32, f32)> = side
            .iter()
            .map(|r| (r.interior[0] - t, r.interior[2] + t))
            .collect();
        covered.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut x = c[0];
        for &(a, b) in covered.iter().chain([(c[2], c[2])].iter()) {
            if a > x {
                out.push(Primitive::axis_box([x, y0, 0.0], [a, y1, h], WALL, walls));
            }
            x = x.max(b);
        }
        let mut doors: Vec<f32> = side.iter().map(|r| r.door[0]).collect();
        out.extend(pictures(&mut doors, south, c, &mut next, rng));
    }
    let mut id = || {
        next += 1;
        next
    };
    for (x0, x1) in [(c[0], c[0] + 0.03), (c[2] - 0.03, c[2])] {
        out.push(Primitive::axis_box(
            [x0, -0.6, 0.9],
            [x1, 0.6, 2.2],
            WINDOW,
            id(),
        ));
    }
    let lights = ((c[2] - c[0]) / 3.0).floor() as usize;
    for i in 0..lights {
        let x = c[0] + 1.5 + 3.0 * i as f32;
        out.push(Primitive {
            shape: Shape::Cylinder {
                xy: [x, 0.0],
                radius: 0.2,
                z0: h - 0.06,
                z1: h,
            },
            label: VOID,
            instance: id(),
        });
    }
    out
}

/// Pictures on most stretches between the doorways (at `doors` along x) of the
/// corridor's south or north wall.
fn pictures(
    doors: &mut Vec<f32>,
    south: bool,
    c: [f32; 4],
    next: &mut u16,
    rng: &mut ChaCha8Rng,
) -> Vec<Primitive> {
    doors.extend([c[0] - 0.5 * DOOR_W, c[2] + 0.5 * DOOR_W]);
    doors.sort_by(f32::total_cmp);
    let (y0, y1) = if south {
        (c[1], c[1] + 0.025)
    } else {
        (c[3] - 0.025, c[3])
    };
    let mut out = Vec::new();
    for pair in doors.windows(2) {
        let (a, b) = (pair[0] + 0.5 * DOOR_W + 0.4, pair[1] - 0.5 * DOOR_W - 0.4);
        if b - a < 1.5 || rng.random::<f32>() < 0.3 {
            continue;
        }
        let w = rng.random_range(0.5..1.0f32).min(b - a - 0.2);
        let x = rng.random_range(a..b - w);
        let z = rng.random_range(1.3..1.6f32);
        let h = rng.random_range(0.4..0.7f32);
        *next += 1;
        out.push(Primitive::axis_box(
            [x, y0, z],
            [x + w, y1, z + h],
            PICTURE,
            *next,
        ));
    }
    out
}

#[cfg(test)]
mod tests;
