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
//! A walk ([`Floor::walk`]) enters every room in turn: along the corridor, through the
//! doorway, to a standpoint inside, looks to either side there, then out through the
//! doorway and on to the next room. Paths are planned on a 5 cm grid of the clearance to
//! everything standing on the floor, at least 34 cm from it (doorways are 90 cm wide),
//! and smoothed; the camera is carried at about 1.3-1.5 m, walks at up to 1.3 m/s and
//! turns at up to 60 degrees per second. Walks are timed in seconds (about 110) and
//! sampled at any number of frames: the default 1,000 frames are about 9 per second,
//! fewer frames are the same walk at a lower frame rate. Odd walks go from the west end of
//! the corridor to the east, even walks back, and each walk picks its own standpoints and
//! views.

use super::geometry::{Cast, Group, Hit, Primitive, Shape};
use super::room::look_at;
use super::scenes::class::{CEILING, FLOOR, PICTURE, VOID, WALL, WINDOW};
use super::scenes::{OpenRoom, SceneKind, SynthScene, DOOR_H, DOOR_W, WALL_T};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sndt_core::Isometry3;
use std::cmp::Reverse;
use std::collections::BinaryHeap;
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
/// Cell of the clearance grid.
const RES: f32 = 0.05;
/// Clearances above this are stored as this.
const CAP: f32 = 1.0;
/// The least clearance of a planned path (cell centres).
const R_MIN: f32 = 0.34;
/// Paths prefer to keep this much clearance.
const R_PREF: f32 = 0.8;
/// Walking speed and acceleration.
const SPEED: f32 = 1.3;
const ACCEL: f32 = 1.0;
/// Most turning speed of the view, radians per second (yaw, pitch).
const TURN: [f32; 2] = [60.0 * PI / 180.0, 40.0 * PI / 180.0];
/// How long the view takes to settle on a new direction (first-order lag), seconds.
const LAG: f32 = 0.3;
/// Simulation step, seconds.
const DT: f32 = 0.02;
/// Seconds of holding the view on something from a standpoint.
const HOLD: f32 = 0.4;
/// The last metres of a leg, in which the view turns to the first thing to look at from
/// the standpoint it ends at.
const APPROACH: f32 = 1.5;

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

    /// Walk `walk` (1, 2, ...) sampled at `frames` frames: camera-to-world poses (OpenCV
    /// axes). The walk takes the same seconds whatever `frames` is; frame `i` is at
    /// `i / (frames - 1)` of it.
    ///
    /// # Panics
    /// If `walk` is 0.
    pub fn walk(&self, walk: u32, frames: usize) -> Vec<Isometry3<f32>> {
        assert!(walk >= 1, "walks are numbered from 1");
        let ticks = self.simulate(&self.plan(walk), walk);
        let last = (ticks.len() - 1) as f32;
        (0..frames)
            .map(|i| {
                let at = if frames > 1 {
                    last * i as f32 / (frames - 1) as f32
                } else {
                    0.0
                };
                let k = (at.floor() as usize).min(ticks.len() - 1);
                let (a, b) = (ticks[k], ticks[(k + 1).min(ticks.len() - 1)]);
                let f = at - k as f32;
                let lerp = |u: f32, v: f32| u + f * (v - u);
                let eye = [
                    lerp(a.eye[0], b.eye[0]),
                    lerp(a.eye[1], b.eye[1]),
                    lerp(a.eye[2], b.eye[2]),
                ];
                let (yaw, pitch) = (lerp(a.yaw, b.yaw), lerp(a.pitch, b.pitch));
                let dir = [
                    pitch.cos() * yaw.cos(),
                    pitch.cos() * yaw.sin(),
                    pitch.sin(),
                ];
                look_at(eye, [eye[0] + dir[0], eye[1] + dir[1], eye[2] + dir[2]])
            })
            .collect()
    }

    /// How long walk `walk` takes, seconds.
    pub fn walk_seconds(&self, walk: u32) -> f32 {
        (self.simulate(&self.plan(walk), walk).len() - 1) as f32 * DT
    }

    /// The legs of a walk: from one end of the corridor into every room in turn (by the
    /// position of its doorway along the corridor), and out to the other end.
    fn plan(&self, walk: u32) -> Vec<Step> {
        let mut rng = ChaCha8Rng::seed_from_u64(
            self.seed ^ u64::from(walk).wrapping_mul(0xA24B_AED4_963E_E407),
        );
        let eastward = walk % 2 == 1;
        let mut order: Vec<usize> = (0..self.rooms.len()).collect();
        order.sort_by(|&a, &b| self.rooms[a].door[0].total_cmp(&self.rooms[b].door[0]));
        if !eastward {
            order.reverse();
        }
        let c = self.corridor;
        let (start, end) = ([c[0] + 0.8, 0.0], [c[2] - 0.8, 0.0]);
        let (start, end) = if eastward { (start, end) } else { (end, start) };
        let mut steps = Vec::new();
        let mut at = start;
        for &r in &order {
            let room = &self.rooms[r];
            let stand = self.standpoint(room, &mut rng);
            let path = self.path(at, stand);
            let arrive = heading(&path);
            // Look to one side while arriving, then sweep to the other (which first: the
            // walk's parity).
            let sides = if eastward { [-1.0, 1.0] } else { [1.0, -1.0] };
            let views = sides.map(|s| view_towards(room, stand, arrive + s * 1.1, &mut rng));
            steps.push(Step::Move(path, Some(views[0])));
            steps.push(Step::Dwell(views.to_vec()));
            at = stand;
        }
        steps.push(Step::Move(self.path(at, end), None));
        steps
    }

    /// A point of `room` to look around from: reachable from its doorway, clear of
    /// everything by 0.6 m (less where the room has no such place), a third of the way
    /// into the room (1.4-3 m) and not far to the side of its doorway; the walk's
    /// generator picks among the places within half a metre of the best.
    fn standpoint(&self, room: &FloorRoom, rng: &mut ChaCha8Rng) -> [f32; 2] {
        let entry = [
            room.door[0] + 0.6 * room.inward[0],
            room.door[1] + 0.6 * room.inward[1],
        ];
        let reach = self.grid.reachable(entry, R_MIN);
        let inside: Vec<usize> = reach
            .into_iter()
            .filter(|&i| room.contains(&self.grid.centre(i)))
            .collect();
        let best = inside
            .iter()
            .map(|&i| self.grid.clear[i])
            .fold(0.0f32, f32::max);
        let r = room.interior;
        let deep = if room.inward[0] == 0.0 {
            r[3] - r[1]
        } else {
            r[2] - r[0]
        };
        let aim = (deep / 3.0).clamp(1.4, 3.0);
        let cost = |i: usize| {
            let p = self.grid.centre(i);
            let d = [p[0] - room.door[0], p[1] - room.door[1]];
            let depth = d[0] * room.inward[0] + d[1] * room.inward[1];
            let side = d[0] * room.inward[1] - d[1] * room.inward[0];
            (depth - aim).abs() + side.abs()
        };
        let good: Vec<(usize, f32)> = inside
            .into_iter()
            .filter(|&i| self.grid.clear[i] >= (0.8 * best).min(0.6))
            .map(|i| (i, cost(i)))
            .collect();
        let least = good.iter().map(|c| c.1).fold(f32::INFINITY, f32::min);
        let near: Vec<usize> = good
            .iter()
            .filter(|c| c.1 <= least + 0.5)
            .map(|c| c.0)
            .collect();
        self.grid.centre(near[rng.random_range(0..near.len())])
    }

    /// A smooth path from `a` to `b` keeping clear of everything.
    ///
    /// # Panics
    /// If there is none (every room is checked to be enterable when generated).
    fn path(&self, a: [f32; 2], b: [f32; 2]) -> Vec<[f32; 2]> {
        let cells = self
            .grid
            .astar(a, b)
            .expect("every room of the floor is reachable from the corridor");
        let short = self.grid.shortcut(&cells);
        let fine = resample(&short, 0.05);
        for half in [8, 4, 2] {
            let smooth = smoothed(&fine, half);
            if smooth.iter().all(|p| self.grid.at(p) >= R_MIN) {
                return smooth;
            }
        }
        fine
    }

    /// Runs a plan at [`DT`]: where the camera is and where it looks, tick by tick.
    fn simulate(&self, steps: &[Step], walk: u32) -> Vec<Tick> {
        let height = if walk % 2 == 1 { 1.45 } else { 1.35 };
        let sway = if walk % 2 == 1 { 0.0 } else { 0.5 };
        let first = steps.iter().find_map(|s| match s {
            Step::Move(p, _) => Some(heading(p)),
            Step::Dwell(_) => None,
        });
        let mut view = View {
            yaw: first.unwrap_or(0.0),
            pitch: -0.15,
        };
        let mut ticks = Vec::new();
        let mut time = 0.0f32;
        let mut pos = match steps.first() {
            Some(Step::Move(p, _)) => p[0],
            _ => [0.0, 0.0],
        };
        let mut push = |pos: [f32; 2], view: &View, time: f32, speed: f32| {
            // A slight bob while walking, and a slow drift of the carried height.
            let z = height
                + 0.02 * (speed / SPEED) * (TAU * 1.8 * time).sin()
                + 0.04 * (TAU * time / 23.0).sin();
            ticks.push(Tick {
                eye: [pos[0], pos[1], z],
                yaw: view.yaw,
                pitch: view.pitch,
            });
        };
        for step in steps {
            match step {
                Step::Move(path, gaze) => {
                    let lens = cumulative(path);
                    let total = *lens.last().unwrap_or(&0.0);
                    let mut s = 0.0f32;
                    let mut v = 0.0f32;
                    while s < total {
                        // Trapezoidal speed: accelerate, cruise, brake to a stop at the end.
                        let brake = (2.0 * ACCEL * (total - s)).sqrt();
                        v = (v + ACCEL * DT).min(SPEED).min(brake.max(0.05));
                        s = (s + v * DT).min(total);
                        pos = point_at(path, &lens, s);
                        let ahead = point_at(path, &lens, s + 2.0);
                        let beyond = (s + 2.0 - total).max(0.0);
                        let dir = heading(path);
                        let ahead = [ahead[0] + beyond * dir.cos(), ahead[1] + beyond * dir.sin()];
                        let mut yaw = (ahead[1] - pos[1]).atan2(ahead[0] - pos[0]);
                        let mut pitch = -0.2;
                        if inside(&self.corridor, &pos) {
                            yaw += sway * (TAU * time / 5.0).sin();
                        }
                        if let Some(target) = gaze.filter(|_| total - s < APPROACH) {
                            (yaw, pitch) = aim(pos, height, target);
                        }
                        view.turn_to(yaw, pitch);
                        time += DT;
                        push(pos, &view, time, v);
                    }
                }
                Step::Dwell(targets) => {
                    for target in targets {
                        let (yaw, pitch) = aim(pos, height, *target);
                        let mut held = 0.0;
                        while held < HOLD || view.off(yaw, pitch) > 0.05 {
                            view.turn_to(yaw, pitch);
                            time += DT;
                            held += DT;
                            push(pos, &view, time, 0.0);
                        }
                    }
                }
            }
        }
        ticks
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

/// One leg of a walk.
#[derive(Clone, Debug)]
enum Step {
    /// Walk along a path (floor plan), starting and ending at rest, looking ahead, or in
    /// the last [`APPROACH`] metres at the target given.
    Move(Vec<[f32; 2]>, Option<[f32; 3]>),
    /// Stand and look at each target in turn.
    Dwell(Vec<[f32; 3]>),
}

/// Where the camera is and looks at one simulation step.
#[derive(Clone, Copy, Debug)]
struct Tick {
    eye: [f32; 3],
    yaw: f32,
    pitch: f32,
}

/// The view direction, turned towards targets at a bounded rate with a short lag.
struct View {
    yaw: f32,
    pitch: f32,
}

impl View {
    fn turn_to(&mut self, yaw: f32, pitch: f32) {
        let dy = wrap(yaw - self.yaw);
        let dp = pitch - self.pitch;
        let gain = DT / LAG;
        self.yaw += (dy * gain).clamp(-TURN[0] * DT, TURN[0] * DT);
        self.pitch += (dp * gain).clamp(-TURN[1] * DT, TURN[1] * DT);
    }

    fn off(&self, yaw: f32, pitch: f32) -> f32 {
        wrap(yaw - self.yaw).abs().max((pitch - self.pitch).abs())
    }
}

/// The view direction (yaw, pitch) from `pos` at `height` to `target`, pitch within
/// -34..14 degrees.
fn aim(pos: [f32; 2], height: f32, target: [f32; 3]) -> (f32, f32) {
    let d = [target[0] - pos[0], target[1] - pos[1]];
    let flat = (d[0] * d[0] + d[1] * d[1]).sqrt().max(0.3);
    (
        d[1].atan2(d[0]),
        ((target[2] - height) / flat).atan().clamp(-0.6, 0.25),
    )
}

/// An angle in `(-pi, pi]`.
fn wrap(a: f32) -> f32 {
    a - TAU * ((a + PI) / TAU).floor()
}

/// Something of `room` to look at from `from`, near the direction `yaw`, 1-5.5 m away:
/// the object of interest closest in direction (with a little chance), else a point on
/// the floor 2 m away in that direction.
fn view_towards(room: &FloorRoom, from: [f32; 2], yaw: f32, rng: &mut ChaCha8Rng) -> [f32; 3] {
    let mut best: Option<([f32; 3], f32)> = None;
    for p in &room.interest {
        let d = [p[0] - from[0], p[1] - from[1]];
        let dist = (d[0] * d[0] + d[1] * d[1]).sqrt();
        if !(1.0..=5.5).contains(&dist) {
            continue;
        }
        let off = wrap(d[1].atan2(d[0]) - yaw).abs() + rng.random_range(0.0..0.3);
        if off < 0.9 && best.is_none_or(|b| off < b.1) {
            best = Some((*p, off));
        }
    }
    best.map_or(
        [from[0] + 2.0 * yaw.cos(), from[1] + 2.0 * yaw.sin(), 0.8],
        |b| b.0,
    )
}

/// Direction of a path's last stretch (of its first, for a path of one point: 0).
fn heading(path: &[[f32; 2]]) -> f32 {
    let n = path.len();
    if n < 2 {
        return 0.0;
    }
    let (a, b) = (path[n.saturating_sub(6).min(n - 2)], path[n - 1]);
    (b[1] - a[1]).atan2(b[0] - a[0])
}

fn cumulative(path: &[[f32; 2]]) -> Vec<f32> {
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
fn point_at(path: &[[f32; 2]], lens: &[f32], s: f32) -> [f32; 2] {
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
struct Grid {
    origin: [f32; 2],
    nx: usize,
    ny: usize,
    clear: Vec<f32>,
}

impl Grid {
    fn new<'a>(
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

    fn centre(&self, k: usize) -> [f32; 2] {
        let (i, j) = (k % self.nx, k / self.nx);
        [
            self.origin[0] + (i as f32 + 0.5) * RES,
            self.origin[1] + (j as f32 + 0.5) * RES,
        ]
    }

    /// The clearance of the cell of `p`.
    fn at(&self, p: &[f32; 2]) -> f32 {
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
    fn reachable(&self, from: [f32; 2], r: f32) -> Vec<usize> {
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

#[cfg(test)]
mod tests {
    use super::super::geometry::Bvh;
    use super::super::{render, SynthOptions, Synthetic, DEFAULT_SEED};
    use super::*;
    use crate::dataset::Dataset;
    use sndt_core::{Pinhole, Point3, Vector3};
    use std::collections::HashSet;
    use std::sync::OnceLock;

    fn floor() -> &'static Floor {
        static FLOOR: OnceLock<Floor> = OnceLock::new();
        FLOOR.get_or_init(|| Floor::generate(DEFAULT_SEED))
    }

    /// Walks 1 and 2 at the default frame count.
    fn walks() -> &'static [Vec<Isometry3<f32>>; 2] {
        static WALKS: OnceLock<[Vec<Isometry3<f32>>; 2]> = OnceLock::new();
        WALKS.get_or_init(|| [1, 2].map(|w| floor().walk(w, DEFAULT_FRAMES)))
    }

    fn eye(p: &Isometry3<f32>) -> [f32; 3] {
        let t = p.translation.vector;
        [t.x, t.y, t.z]
    }

    /// The default camera's field of view at `w` x `h` pixels.
    fn small(w: u32, h: u32) -> Pinhole {
        let f = super::super::CAMERA.fx * w as f32 / 1024.0;
        Pinhole {
            fx: f,
            fy: f,
            cx: 0.5 * w as f32,
            cy: 0.5 * h as f32,
            width: w,
            height: h,
        }
    }

    #[test]
    fn floor_has_eleven_rooms_of_every_kind_along_a_corridor_within_60_m() {
        let f = floor();
        assert_eq!(f.rooms.len(), ROOMS);
        const { assert!(ROOMS >= 10) };
        for kind in SceneKind::ALL {
            assert!(f.rooms.iter().any(|r| r.kind == kind), "no {kind:?}");
        }
        let e = f.extent();
        assert!(e.iter().all(|v| v.abs() <= 60.0), "{e:?}");
        let overlap =
            |a: &[f32; 4], b: &[f32; 4]| a[0] < b[2] && b[0] < a[2] && a[1] < b[3] && b[1] < a[3];
        for (i, r) in f.rooms.iter().enumerate() {
            assert!(!overlap(&r.interior, &f.corridor), "{}", r.name);
            for s in &f.rooms[i + 1..] {
                assert!(!overlap(&r.interior, &s.interior), "{} {}", r.name, s.name);
            }
            // The doorway opens onto the corridor, in the middle of the corridor's wall.
            let side = 0.5 * CORRIDOR_W + 0.5 * WALL_T;
            assert!((r.door[1].abs() - side).abs() < 1e-4, "{}", r.name);
            assert!(r.door[0] > f.corridor[0] && r.door[0] < f.corridor[2]);
            assert!(r.contains(&[r.door[0] + 0.2 * r.inward[0], r.door[1] + 0.2 * r.inward[1]]));
        }
        // Pictures hang on both walls of the corridor.
        let corridor = &f.group().parts()[ROOMS];
        for south in [true, false] {
            let on_side =
                |p: &&Primitive| p.label == PICTURE && (p.shape.aabb().min[1] < 0.0) == south;
            assert!(corridor.primitives().iter().filter(on_side).count() >= 2);
        }
        // Rooms and corridor keep their object instances apart.
        let mut seen = HashSet::new();
        for part in f.group().parts() {
            let mine: HashSet<u16> = part.primitives().iter().map(|p| p.instance).collect();
            assert!(mine.is_disjoint(&seen));
            seen.extend(mine);
        }
        // The labels the rooms have, and the corridor's.
        let classes = f.classes();
        for c in [
            WALL,
            FLOOR,
            CEILING,
            PICTURE,
            WINDOW,
            super::super::scenes::class::DOOR,
        ] {
            assert!(classes[c as usize], "class {c}");
        }
        let again = Floor::generate(DEFAULT_SEED);
        assert!(again.primitives().eq(f.primitives()));
    }

    #[test]
    fn floor_rooms_are_the_generators_rooms_with_an_open_doorway() {
        // Same kinds, sizes and objects as SynthScene::generate makes them: only the door
        // wall (cut in three), the door leaf (swung open) and the placement differ.
        let f = floor();
        for (i, room) in f.rooms.iter().enumerate() {
            assert_eq!(room.generator % 6, i % 6);
            let scene = SynthScene::generate(room.generator, f.seed);
            assert_eq!(scene.kind, room.kind);
            let n = f.group().parts()[i].primitives().len();
            assert_eq!(n, scene.bvh.primitives().len() + 2, "{}", room.name);
            let r = room.interior;
            let mut size = [r[2] - r[0], r[3] - r[1]];
            size.sort_by(f32::total_cmp);
            let mut want = [scene.size[0], scene.size[1]];
            want.sort_by(f32::total_cmp);
            assert!((size[0] - want[0]).abs() < 1e-3 && (size[1] - want[1]).abs() < 1e-3);
        }
    }

    #[test]
    fn walks_stay_in_free_space_at_person_height() {
        let f = floor();
        for (w, poses) in walks().iter().enumerate() {
            for (i, p) in poses.iter().enumerate() {
                let e = eye(p);
                assert!(f.free(&e, 0.3), "walk {} frame {i} at {e:?}", w + 1);
                assert!(
                    (1.2..=1.6).contains(&e[2]),
                    "walk {} frame {i}: z {}",
                    w + 1,
                    e[2]
                );
                let fwd = p.rotation * Vector3::z();
                assert!(
                    fwd.z.abs() < 0.6,
                    "walk {} frame {i} looks at {fwd:?}",
                    w + 1
                );
            }
        }
        // A point inside a wall, outside the building and under a table are not free.
        let r = &f.rooms[0];
        assert!(!f.free(&[r.door[0] + 0.5, r.door[1], 1.4], 0.0));
        assert!(!f.free(&[0.0, 59.0, 1.4], 0.0));
        assert!(!f.free(&[0.0, 0.0, 2.45], 0.0));
    }

    #[test]
    fn walks_move_and_turn_by_small_steps() {
        // At the default 1,000 frames: about 10 frames a second at walking speed.
        for (w, poses) in walks().iter().enumerate() {
            let walk = w as u32 + 1;
            let seconds = floor().walk_seconds(walk);
            assert!(
                (90.0..=125.0).contains(&seconds),
                "walk {walk}: {seconds} s"
            );
            for (i, pair) in poses.windows(2).enumerate() {
                let step = (pair[1].translation.vector - pair[0].translation.vector).norm();
                let turn = pair[1].rotation.angle_to(&pair[0].rotation).to_degrees();
                assert!(step <= 0.16, "walk {walk} frame {i}: {step} m");
                assert!(turn <= 9.0, "walk {walk} frame {i}: {turn} degrees");
            }
        }
    }

    #[test]
    fn walks_enter_every_room_and_end_in_the_corridor() {
        let f = floor();
        for (w, poses) in walks().iter().enumerate() {
            for room in &f.rooms {
                let frames = poses
                    .iter()
                    .filter(|p| room.contains(&[eye(p)[0], eye(p)[1]]))
                    .count();
                assert!(
                    frames >= 20,
                    "walk {}: {} frames in {}",
                    w + 1,
                    frames,
                    room.name
                );
            }
            for p in [&poses[0], &poses[poses.len() - 1]] {
                assert!(inside(&f.corridor, &[eye(p)[0], eye(p)[1]]));
            }
        }
    }

    #[test]
    fn walks_one_and_two_differ_on_the_same_floor() {
        let [one, two] = walks();
        let apart = one
            .iter()
            .zip(two)
            .filter(|(a, b)| (a.translation.vector - b.translation.vector).norm() > 1.0)
            .count();
        assert!(apart > one.len() / 2, "{apart}");
        // Walk 1 goes east, walk 2 west.
        assert!(eye(&one[0])[0] < eye(&one[one.len() - 1])[0]);
        assert!(eye(&two[0])[0] > eye(&two[two.len() - 1])[0]);
        // The walk does not change the floor.
        let camera = small(16, 12);
        let split = |walk| {
            Synthetic::new(SynthOptions {
                floor: Some(walk),
                frames: 2,
                camera,
                predictions: false,
                ..SynthOptions::default()
            })
            .unwrap()
        };
        let (a, b) = (split(1), split(2));
        let (fa, fb) = (a.floor_scene().unwrap(), b.floor_scene().unwrap());
        assert!(fa.primitives().eq(fb.primitives()));
        assert_ne!(a.poses(), b.poses());
        assert_eq!(a.frames()[0].to_string(), "synth_floor/cam_00/0000");
        assert_eq!(b.frames()[1].to_string(), "synth_floor/cam_01/0001");
    }

    #[test]
    fn fewer_frames_sample_the_same_walk() {
        let f = floor();
        let full = &walks()[0];
        let short = f.walk(1, 20);
        assert_eq!(short.len(), 20);
        assert_eq!(short[0], full[0]);
        for p in &short {
            let near = full
                .iter()
                .map(|q| (p.translation.vector - q.translation.vector).norm())
                .fold(f32::INFINITY, f32::min);
            assert!(near < 0.1, "{near}");
        }
    }

    #[test]
    fn floor_renders_as_one_hierarchy_does_casting_into_few_parts() {
        let f = floor();
        let flat = Bvh::new(f.primitives().copied().collect());
        let cam = small(64, 48);
        let (mut rays, mut parts) = (0usize, 0usize);
        for p in walks()[0].iter().step_by(25) {
            // Compared pixel by pixel (a failure shows the first, not the whole frame).
            let (a, b) = (render(f, p, &cam), render(&flat, p, &cam));
            let first = (0..a.planar.len()).find(|&i| {
                (a.planar[i], a.labels[i], a.instances[i])
                    != (b.planar[i], b.labels[i], b.instances[i])
            });
            assert_eq!(
                first,
                None,
                "{:?}",
                first.map(|i| (a.planar[i], a.labels[i], b.labels[i]))
            );
            let rot = p.rotation.to_rotation_matrix();
            let o = eye(p);
            for row in 0..cam.height {
                for col in 0..cam.width {
                    let r = cam.ray(col, row);
                    let d = rot * Vector3::new(r[0], r[1], r[2]);
                    parts += f.group().cast_counted(&o, &[d.x, d.y, d.z], 100.0).1;
                    rays += 1;
                }
            }
        }
        let mean = parts as f32 / rays as f32;
        // Of 12 parts, a ray enters the camera's own and now and then one through a
        // doorway (measured: 1.4).
        assert!(mean < 2.0, "{mean} parts per ray");
    }

    #[test]
    fn default_walk_sees_far_more_surface_than_a_4096_voxel_map_holds() {
        // Distinct 10 cm voxels hit by every frame of walk 1 at 40x30 pixels (the full
        // 1024x768 frames hit more): 112,591, 27 times what a Map<4096, ..> holds.
        let cam = small(40, 30);
        let mut voxels = HashSet::new();
        for p in &walks()[0] {
            let r = render(floor(), p, &cam);
            for (i, &z) in r.planar.iter().enumerate().filter(|&(_, &z)| z > 0.0) {
                let ray = cam.ray(i as u32 % cam.width, i as u32 / cam.width);
                let v = p * Point3::new(ray[0] * z, ray[1] * z, z);
                voxels.insert([v.x, v.y, v.z].map(|c| (c / 0.1).floor() as i32));
            }
        }
        println!("walk 1: {} surface voxels of 10 cm at 40x30", voxels.len());
        assert!(voxels.len() > 10 * 4096, "{}", voxels.len());
    }

    #[test]
    fn floor_frames_have_depth_labels_and_predictions() {
        let split = Synthetic::new(SynthOptions {
            floor: Some(1),
            frames: 20,
            camera: small(64, 48),
            ..SynthOptions::default()
        })
        .unwrap();
        assert_eq!(split.frames().len(), 20);
        assert!(split.describe().contains("walk 1 of 20 frames"));
        let mut classes = HashSet::new();
        for id in split.frames() {
            let f = split.load(id).unwrap();
            let labels = f.labels.as_ref().unwrap();
            let pred = f.predictions.as_ref().unwrap();
            assert_eq!(pred.top1().len(), labels.len());
            assert!(
                f.depth.iter().all(|&d| d > 0.0),
                "{id}: a ray left the building"
            );
            assert!(labels.iter().filter(|&&l| l > 0).count() > labels.len() / 2);
            classes.extend(labels.iter().copied());
        }
        assert!(classes.len() >= 15, "{} classes", classes.len());
        // Frames are deterministic, and other ids are refused.
        let id = &split.frames()[7];
        assert_eq!(split.load(id).unwrap().depth, split.load(id).unwrap().depth);
        let mut other = id.clone();
        other.cam = "cam_01".into();
        assert!(split.load(&other).is_err());
        other.cam = "cam_00".into();
        other.index = 20;
        assert!(split.load(&other).is_err());
    }
}
