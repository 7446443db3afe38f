//! Procedural indoor scenes built from labelled primitives: living room, bedroom,
//! kitchen, office, bathroom and an open-plan space up to 15 m long.
//!
//! Every scene is a closed room (floor, ceiling, four walls) with a door, windows and
//! furniture placed against the walls or free-standing without overlaps, and the small,
//! thin objects the paper names as the hard ones (books, pictures, lamps, towels, paper,
//! boxes, shelves). A few unlabelled fixtures (ceiling lights, vents, sockets) give void
//! pixels, as Hypersim has. Everything is deterministic in the seed.

use super::geometry::{Bvh, Cast, Hit, Primitive, Shape};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f32::consts::{FRAC_PI_2, PI};

/// NYU40 ids used here beyond those in [`crate::dataset::synthetic::room::nyu`].
#[allow(missing_docs)]
pub mod class {
    pub use crate::dataset::synthetic::room::nyu::*;
    pub const CABINET: u8 = 3;
    pub const CHAIR: u8 = 5;
    pub const SOFA: u8 = 6;
    pub const DOOR: u8 = 8;
    pub const WINDOW: u8 = 9;
    pub const BOOKSHELF: u8 = 10;
    pub const COUNTER: u8 = 12;
    pub const BLINDS: u8 = 13;
    pub const DESK: u8 = 14;
    pub const CURTAIN: u8 = 16;
    pub const DRESSER: u8 = 17;
    pub const PILLOW: u8 = 18;
    pub const MIRROR: u8 = 19;
    pub const FLOOR_MAT: u8 = 20;
    pub const CLOTHES: u8 = 21;
    pub const REFRIGERATOR: u8 = 24;
    pub const TELEVISION: u8 = 25;
    pub const PAPER: u8 = 26;
    pub const TOWEL: u8 = 27;
    pub const SHOWER_CURTAIN: u8 = 28;
    pub const BOX: u8 = 29;
    pub const WHITEBOARD: u8 = 30;
    pub const PERSON: u8 = 31;
    pub const NIGHT_STAND: u8 = 32;
    pub const TOILET: u8 = 33;
    pub const SINK: u8 = 34;
    pub const BATHTUB: u8 = 36;
    pub const BAG: u8 = 37;
    pub const OTHER_STRUCTURE: u8 = 38;
    pub const OTHER_FURNITURE: u8 = 39;
    pub const OTHER_PROP: u8 = 40;
    /// Unlabelled geometry.
    pub const VOID: u8 = 0;
}
use class::*;

/// The kinds of room the generator knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SceneKind {
    /// Sofa, TV, coffee table, bookshelf, lamps.
    LivingRoom,
    /// Bed, night stands, dresser, wardrobe.
    Bedroom,
    /// Counters, cabinets, sink, refrigerator, dining table.
    Kitchen,
    /// Desks, chairs, monitors, whiteboard, shelves.
    Office,
    /// Bathtub, toilet, sink, mirror, towels.
    Bathroom,
    /// A large space (up to 15 m) with living, dining, kitchen and work zones.
    OpenPlan,
}

impl SceneKind {
    /// All kinds, in the order the generator cycles through them.
    pub const ALL: [SceneKind; 6] = [
        SceneKind::LivingRoom,
        SceneKind::Bedroom,
        SceneKind::Kitchen,
        SceneKind::Office,
        SceneKind::Bathroom,
        SceneKind::OpenPlan,
    ];

    /// Short name used in scene names.
    pub fn name(self) -> &'static str {
        match self {
            SceneKind::LivingRoom => "living",
            SceneKind::Bedroom => "bedroom",
            SceneKind::Kitchen => "kitchen",
            SceneKind::Office => "office",
            SceneKind::Bathroom => "bathroom",
            SceneKind::OpenPlan => "openplan",
        }
    }
}

/// A generated scene.
#[derive(Clone, Debug)]
pub struct SynthScene {
    /// Scene name, e.g. `synth_03_office`.
    pub name: String,
    /// Kind of room.
    pub kind: SceneKind,
    /// Interior extents: x in `[0, size[0]]`, y in `[0, size[1]]`, z in `[0, size[2]]`.
    pub size: [f32; 3],
    /// The primitives, ready for ray casting.
    pub bvh: Bvh,
    /// Centres of objects worth looking at (camera targets).
    pub interest: Vec<[f32; 3]>,
}

impl Cast for SynthScene {
    fn cast(&self, o: &[f32; 3], d: &[f32; 3], t_max: f32) -> Option<Hit> {
        self.bvh.cast(o, d, t_max)
    }
}

impl SynthScene {
    /// Generates scene number `index` of the split with seed `seed`; the kind cycles
    /// through [`SceneKind::ALL`].
    ///
    /// ```
    /// let s = sndt_host::dataset::synthetic::scenes::SynthScene::generate(0, 42);
    /// assert_eq!(s.name, "synth_00_living");
    /// assert!(s.bvh.primitives().len() > 30);
    /// ```
    pub fn generate(index: usize, seed: u64) -> SynthScene {
        let b = Self::build(index, seed);
        SynthScene {
            name: format!("synth_{index:02}_{}", b.kind.name()),
            kind: b.kind,
            size: b.size,
            bvh: Bvh::new(b.prims),
            interest: b.interest,
        }
    }

    /// The room [`generate`](Self::generate) makes, with its door standing open in a
    /// doorway cut through its wall: a room of a building floor
    /// ([`floor`](crate::dataset::synthetic::floor)). Everything else is the same
    /// primitives in the same (room) frame; `None` when the room has no door.
    pub(crate) fn generate_open(index: usize, seed: u64) -> Option<OpenRoom> {
        let mut b = Self::build(index, seed);
        let (wall, along, leaf) = b.door?;
        // The opening along the wall's axis (x for south and north, y for east and west).
        let [x, y, _] = b.size;
        let span = match wall {
            0 | 1 => (along, along + DOOR_W),
            2 => (x - along - DOOR_W, x - along),
            _ => (y - along - DOOR_W, y - along),
        };
        let axis = if wall % 2 == 0 { 0 } else { 1 };
        let w = b.prims[b.walls[wall]];
        let Shape::Box { center, half, .. } = w.shape else {
            return None;
        };
        let lo: [f32; 3] = std::array::from_fn(|a| center[a] - half[a]);
        let hi: [f32; 3] = std::array::from_fn(|a| center[a] + half[a]);
        let (mut left_hi, mut right_lo, mut lintel_lo, mut lintel_hi) = (hi, lo, lo, hi);
        left_hi[axis] = span.0;
        right_lo[axis] = span.1;
        lintel_lo[axis] = span.0;
        lintel_hi[axis] = span.1;
        lintel_lo[2] = DOOR_H;
        b.prims[b.walls[wall]] = Primitive::axis_box(lo, left_hi, WALL, w.instance);
        b.prims
            .push(Primitive::axis_box(right_lo, hi, WALL, w.instance));
        b.prims
            .push(Primitive::axis_box(lintel_lo, lintel_hi, WALL, w.instance));
        // The leaf swung open into the room, inside the swing kept clear.
        let pl = b.wall_place(wall, along);
        let id = b.prims[leaf].instance;
        b.lbox(&pl, [0.0, 0.04, 0.0], [0.04, 0.94, 2.05], DOOR, id);
        b.prims.swap_remove(leaf);
        Some(OpenRoom {
            kind: b.kind,
            size: b.size,
            door_wall: wall,
            door_span: span,
            instances: b.next_instance,
            prims: b.prims,
            interest: b.interest,
        })
    }

    /// Runs the generator of room `index`.
    fn build(index: usize, seed: u64) -> Builder {
        let kind = SceneKind::ALL[index % SceneKind::ALL.len()];
        let mut rng =
            ChaCha8Rng::seed_from_u64(seed ^ (index as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
        let size = match kind {
            SceneKind::LivingRoom => [rng.random_range(5.0..7.0), rng.random_range(4.0..5.5), 2.7],
            SceneKind::Bedroom => [rng.random_range(3.8..5.0), rng.random_range(3.5..4.5), 2.6],
            SceneKind::Kitchen => [rng.random_range(4.0..5.5), rng.random_range(3.2..4.2), 2.6],
            SceneKind::Office => [rng.random_range(4.5..6.5), rng.random_range(4.0..5.5), 2.8],
            SceneKind::Bathroom => [rng.random_range(2.6..3.4), rng.random_range(2.2..2.8), 2.5],
            SceneKind::OpenPlan => [
                rng.random_range(12.0..15.0),
                rng.random_range(6.0..8.0),
                3.0,
            ],
        };
        let mut b = Builder::new(rng, kind, size);
        b.shell();
        match kind {
            SceneKind::LivingRoom => b.living(),
            SceneKind::Bedroom => b.bedroom(),
            SceneKind::Kitchen => b.kitchen(),
            SceneKind::Office => b.office(),
            SceneKind::Bathroom => b.bathroom(),
            SceneKind::OpenPlan => b.open_plan(),
        }
        b.fixtures();
        b
    }

    /// Whether a camera may stand at `p`: inside the room, at least `margin` metres from
    /// every wall and every object.
    pub fn free(&self, p: &[f32; 3], margin: f32) -> bool {
        let s = self.size;
        if p[0] < margin || p[1] < margin || p[0] > s[0] - margin || p[1] > s[1] - margin {
            return false;
        }
        if p[2] < 0.2 || p[2] > s[2] - 0.2 {
            return false;
        }
        let probes = [
            [0.0, 0.0, 0.0],
            [margin, 0.0, 0.0],
            [-margin, 0.0, 0.0],
            [0.0, margin, 0.0],
            [0.0, -margin, 0.0],
            [0.0, 0.0, margin],
            [0.0, 0.0, -margin],
        ];
        probes
            .iter()
            .all(|d| !self.bvh.occupied(&[p[0] + d[0], p[1] + d[1], p[2] + d[2]]))
    }

    /// The NYU40 classes that occur in the scene (index = class id).
    pub fn classes(&self) -> [bool; 41] {
        let mut out = [false; 41];
        for p in self.bvh.primitives() {
            out[p.label as usize] = true;
        }
        out
    }
}

/// Where a piece of furniture stands: its local frame has x along its width, y along its
/// depth (away from the wall it stands against), z up; `yaw` turns local x into world.
#[derive(Clone, Copy, Debug)]
struct Place {
    x: f32,
    y: f32,
    yaw: f32,
}

impl Place {
    fn world(&self, lx: f32, ly: f32) -> [f32; 2] {
        let (s, c) = self.yaw.sin_cos();
        [self.x + c * lx - s * ly, self.y + s * lx + c * ly]
    }
}

/// Wall, floor and ceiling thickness.
pub(crate) const WALL_T: f32 = 0.12;

/// Width of a door (and of the doorway of a room on a building floor).
pub(crate) const DOOR_W: f32 = 0.9;

/// Height of a doorway (the top of the door frame).
pub(crate) const DOOR_H: f32 = 2.1;

/// A room whose door stands open in a doorway through its wall
/// ([`SynthScene::generate_open`]), in its own frame: interior `[0, size]`.
#[derive(Clone, Debug)]
pub(crate) struct OpenRoom {
    pub kind: SceneKind,
    pub size: [f32; 3],
    pub prims: Vec<Primitive>,
    pub interest: Vec<[f32; 3]>,
    /// The wall of the doorway: 0 south (y = 0), 1 east (x = X), 2 north (y = Y), 3 west.
    pub door_wall: usize,
    /// The opening along the wall's axis (x for south and north, y for east and west).
    pub door_span: (f32, f32),
    /// The largest object instance (no primitive's is above it).
    pub instances: u16,
}

struct Builder {
    rng: ChaCha8Rng,
    kind: SceneKind,
    size: [f32; 3],
    prims: Vec<Primitive>,
    next_instance: u16,
    /// Floor footprints in use (xmin, ymin, xmax, ymax), furniture and door swings.
    blocked: Vec<[f32; 4]>,
    /// Wall spans in use per wall (start, end along the wall) for wall-mounted items.
    wall_used: [Vec<(f32, f32)>; 4],
    interest: Vec<[f32; 3]>,
    /// The four walls' primitives (south, east, north, west).
    walls: [usize; 4],
    /// The door: its wall, where it starts along it and its leaf's primitive.
    door: Option<(usize, f32, usize)>,
}

impl Builder {
    fn new(rng: ChaCha8Rng, kind: SceneKind, size: [f32; 3]) -> Builder {
        Builder {
            rng,
            kind,
            size,
            prims: Vec::new(),
            next_instance: 1,
            blocked: Vec::new(),
            wall_used: Default::default(),
            interest: Vec::new(),
            walls: [0; 4],
            door: None,
        }
    }

    fn r(&mut self, lo: f32, hi: f32) -> f32 {
        self.rng.random_range(lo..hi)
    }

    fn chance(&mut self, p: f32) -> bool {
        self.rng.random::<f32>() < p
    }

    fn instance(&mut self) -> u16 {
        self.next_instance = self.next_instance.wrapping_add(1);
        self.next_instance
    }

    fn aabb(&mut self, min: [f32; 3], max: [f32; 3], label: u8, instance: u16) {
        self.prims
            .push(Primitive::axis_box(min, max, label, instance));
    }

    /// A box given in a place's local frame.
    fn lbox(&mut self, pl: &Place, min: [f32; 3], max: [f32; 3], label: u8, instance: u16) {
        let c = pl.world(0.5 * (min[0] + max[0]), 0.5 * (min[1] + max[1]));
        self.prims.push(Primitive {
            shape: Shape::Box {
                center: [c[0], c[1], 0.5 * (min[2] + max[2])],
                half: [
                    0.5 * (max[0] - min[0]),
                    0.5 * (max[1] - min[1]),
                    0.5 * (max[2] - min[2]),
                ],
                yaw: pl.yaw,
            },
            label,
            instance,
        });
    }

    /// An upright cylinder given in a place's local frame.
    #[allow(clippy::too_many_arguments)]
    fn lcyl(
        &mut self,
        pl: &Place,
        lx: f32,
        ly: f32,
        radius: f32,
        z0: f32,
        z1: f32,
        label: u8,
        instance: u16,
    ) {
        let xy = pl.world(lx, ly);
        self.prims.push(Primitive {
            shape: Shape::Cylinder { xy, radius, z0, z1 },
            label,
            instance,
        });
    }

    fn look_at_local(&mut self, pl: &Place, lx: f32, ly: f32, z: f32) {
        let p = pl.world(lx, ly);
        self.interest.push([p[0], p[1], z]);
    }

    fn footprint(pl: &Place, w: f32, d: f32) -> [f32; 4] {
        let corners = [
            pl.world(0.0, 0.0),
            pl.world(w, 0.0),
            pl.world(0.0, d),
            pl.world(w, d),
        ];
        let mut f = [
            f32::INFINITY,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NEG_INFINITY,
        ];
        for c in corners {
            f[0] = f[0].min(c[0]);
            f[1] = f[1].min(c[1]);
            f[2] = f[2].max(c[0]);
            f[3] = f[3].max(c[1]);
        }
        f
    }

    fn overlaps(&self, f: &[f32; 4], gap: f32) -> bool {
        let s = self.size;
        if f[0] < -1e-3 || f[1] < -1e-3 || f[2] > s[0] + 1e-3 || f[3] > s[1] + 1e-3 {
            return true;
        }
        self.blocked.iter().any(|b| {
            f[0] < b[2] + gap && b[0] < f[2] + gap && f[1] < b[3] + gap && b[1] < f[3] + gap
        })
    }

    /// Length of wall `w`: 0 = south (y = 0), 1 = east (x = X), 2 = north (y = Y), 3 = west.
    fn wall_len(&self, wall: usize) -> f32 {
        if wall.is_multiple_of(2) {
            self.size[0]
        } else {
            self.size[1]
        }
    }

    /// The frame of a span starting `along` metres along wall `wall`, facing into the room.
    fn wall_place(&self, wall: usize, along: f32) -> Place {
        let [x, y, _] = self.size;
        match wall {
            0 => Place {
                x: along,
                y: 0.0,
                yaw: 0.0,
            },
            1 => Place {
                x,
                y: along,
                yaw: FRAC_PI_2,
            },
            2 => Place {
                x: x - along,
                y,
                yaw: PI,
            },
            _ => Place {
                x: 0.0,
                y: y - along,
                yaw: -FRAC_PI_2,
            },
        }
    }

    /// Finds a free floor spot of `w` x `d` against a wall (optionally a given one) and
    /// reserves it.
    fn against_wall(&mut self, w: f32, d: f32, wall: Option<usize>) -> Option<Place> {
        for _ in 0..60 {
            let wall = wall.unwrap_or_else(|| self.rng.random_range(0..4));
            let len = self.wall_len(wall);
            if len < w + 0.2 {
                continue;
            }
            let along = self.r(0.05, len - w - 0.05);
            let pl = self.wall_place(wall, along);
            let f = Self::footprint(&pl, w, d);
            if !self.overlaps(&f, 0.05) {
                self.blocked.push(f);
                self.wall_used[wall].push((along, along + w));
                return Some(pl);
            }
        }
        None
    }

    /// Finds a free spot of `w` x `d` inside `region` (xmin, ymin, xmax, ymax), turned by a
    /// random yaw when `any_yaw`, and reserves it with `gap` metres around it.
    fn free_spot(
        &mut self,
        w: f32,
        d: f32,
        region: [f32; 4],
        any_yaw: bool,
        gap: f32,
    ) -> Option<Place> {
        for _ in 0..80 {
            let yaw = if any_yaw {
                self.r(-PI, PI)
            } else {
                FRAC_PI_2 * self.rng.random_range(0..4) as f32
            };
            let pl = Place {
                x: self.r(region[0], region[2]),
                y: self.r(region[1], region[3]),
                yaw,
            };
            let f = Self::footprint(&pl, w, d);
            if !self.overlaps(&f, gap) {
                self.blocked.push(f);
                return Some(pl);
            }
        }
        None
    }

    /// A wall-mounted item: finds a span on a wall not used by furniture or other items.
    fn wall_span(&mut self, w: f32, wall: Option<usize>) -> Option<(usize, f32)> {
        for _ in 0..60 {
            let wall = wall.unwrap_or_else(|| self.rng.random_range(0..4));
            let len = self.wall_len(wall);
            if len < w + 0.3 {
                continue;
            }
            let along = self.r(0.15, len - w - 0.15);
            let clash = self.wall_used[wall]
                .iter()
                .any(|&(a, b)| along < b + 0.1 && a < along + w + 0.1);
            if !clash {
                self.wall_used[wall].push((along, along + w));
                return Some((wall, along));
            }
        }
        None
    }

    fn interior(&self, margin: f32) -> [f32; 4] {
        [margin, margin, self.size[0] - margin, self.size[1] - margin]
    }

    // ----- the room shell -----

    fn shell(&mut self) {
        let [x, y, z] = self.size;
        let t = WALL_T;
        let (floor, ceiling) = (self.instance(), self.instance());
        self.aabb([-t, -t, -t], [x + t, y + t, 0.0], FLOOR, floor);
        self.aabb([-t, -t, z], [x + t, y + t, z + t], CEILING, ceiling);
        let walls = self.instance();
        let first = self.prims.len();
        self.aabb([-t, -t, 0.0], [0.0, y + t, z], WALL, walls);
        self.aabb([x, -t, 0.0], [x + t, y + t, z], WALL, walls);
        self.aabb([0.0, -t, 0.0], [x, 0.0, z], WALL, walls);
        self.aabb([0.0, y, 0.0], [x, y + t, z], WALL, walls);
        self.walls = [first + 2, first + 1, first + 3, first];
        // A door (with its swing kept clear) and one or two windows.
        if let Some((wall, along)) = self.wall_span(DOOR_W, None) {
            let pl = self.wall_place(wall, along);
            let id = self.instance();
            self.door = Some((wall, along, self.prims.len()));
            self.lbox(&pl, [0.0, 0.0, 0.0], [DOOR_W, 0.04, 2.05], DOOR, id);
            let frame = self.instance();
            self.lbox(
                &pl,
                [-0.06, 0.0, 0.0],
                [0.0, 0.03, 2.1],
                OTHER_STRUCTURE,
                frame,
            );
            self.lbox(
                &pl,
                [0.9, 0.0, 0.0],
                [0.96, 0.03, 2.1],
                OTHER_STRUCTURE,
                frame,
            );
            let f = Self::footprint(&pl, 0.9, 1.0);
            self.blocked.push(f);
            self.look_at_local(&pl, 0.45, 0.0, 1.1);
        }
        let windows = if x * y > 20.0 { 2 } else { 1 };
        for _ in 0..windows {
            self.window();
        }
    }

    fn window(&mut self) {
        let w = self.r(0.9, 1.8);
        let Some((wall, along)) = self.wall_span(w + 0.6, None) else {
            return;
        };
        let pl = self.wall_place(wall, along + 0.3);
        let (z0, z1) = (self.r(0.8, 1.0), self.r(2.0, 2.3).min(self.size[2] - 0.1));
        let id = self.instance();
        self.lbox(&pl, [0.0, 0.0, z0], [w, 0.03, z1], WINDOW, id);
        self.look_at_local(&pl, 0.5 * w, 0.0, 0.5 * (z0 + z1));
        if self.chance(0.5) {
            // Blinds over the upper part.
            let b = self.instance();
            let drop = self.r(0.2, 0.6) * (z1 - z0);
            self.lbox(
                &pl,
                [-0.03, 0.03, z1 - drop],
                [w + 0.03, 0.06, z1 + 0.05],
                BLINDS,
                b,
            );
        } else {
            // Curtains on both sides, floor to above the window.
            let c = self.instance();
            let top = (z1 + 0.15).min(self.size[2] - 0.02);
            self.lbox(&pl, [-0.3, 0.05, 0.02], [0.05, 0.14, top], CURTAIN, c);
            self.lbox(
                &pl,
                [w - 0.05, 0.05, 0.02],
                [w + 0.3, 0.14, top],
                CURTAIN,
                c,
            );
        }
    }

    /// Unlabelled ceiling lights, vents and sockets (void in the ground truth).
    fn fixtures(&mut self) {
        let n = ((self.size[0] * self.size[1]) / 8.0).ceil() as usize;
        let z = self.size[2];
        for _ in 0..n {
            let (x, y) = (
                self.r(0.5, self.size[0] - 0.5),
                self.r(0.5, self.size[1] - 0.5),
            );
            let id = self.instance();
            let radius = self.r(0.12, 0.25);
            self.prims.push(Primitive {
                shape: Shape::Cylinder {
                    xy: [x, y],
                    radius,
                    z0: z - 0.06,
                    z1: z,
                },
                label: VOID,
                instance: id,
            });
        }
        for _ in 0..3 {
            if let Some((wall, along)) = self.wall_span(0.1, None) {
                let pl = self.wall_place(wall, along);
                let id = self.instance();
                let h = if self.chance(0.5) { 0.3 } else { 2.2 };
                self.lbox(&pl, [0.0, 0.0, h], [0.1, 0.015, h + 0.08], VOID, id);
            }
        }
    }

    // ----- furniture (local frames: x along the width, y out of the wall) -----

    fn picture(&mut self, wall: Option<usize>) {
        let w = self.r(0.3, 1.0);
        let Some((wall, along)) = self.wall_span(w, wall) else {
            return;
        };
        let pl = self.wall_place(wall, along);
        let h = self.r(0.3, 0.8);
        let z0 = self.r(1.2, 1.6);
        let id = self.instance();
        self.lbox(&pl, [0.0, 0.0, z0], [w, 0.025, z0 + h], PICTURE, id);
        self.look_at_local(&pl, 0.5 * w, 0.0, z0 + 0.5 * h);
    }

    fn wall_board(&mut self, label: u8, w: f32, z0: f32, h: f32) {
        let Some((wall, along)) = self.wall_span(w, None) else {
            return;
        };
        let pl = self.wall_place(wall, along);
        let id = self.instance();
        self.lbox(&pl, [0.0, 0.0, z0], [w, 0.02, z0 + h], label, id);
        self.look_at_local(&pl, 0.5 * w, 0.0, z0 + 0.5 * h);
    }

    /// Small things on a surface at height `z` within `[x0, x1] x [y0, y1]` (local).
    #[allow(clippy::too_many_arguments)]
    fn clutter(&mut self, pl: &Place, x0: f32, x1: f32, y0: f32, y1: f32, z: f32, n: usize) {
        for _ in 0..n {
            let kind = self.rng.random_range(0..6);
            let (w, d) = (self.r(0.12, 0.35), self.r(0.1, 0.3));
            if x1 - x0 < w + 0.02 || y1 - y0 < d + 0.02 {
                continue;
            }
            let x = self.r(x0, x1 - w);
            let y = self.r(y0, y1 - d);
            let id = self.instance();
            match kind {
                0 => self.lbox(pl, [x, y, z], [x + 0.21, y + 0.297, z + 0.004], PAPER, id),
                1 => {
                    let h = self.r(0.02, 0.12);
                    self.lbox(
                        pl,
                        [x, y, z],
                        [x + w.min(0.25), y + d.min(0.2), z + h],
                        BOOKS,
                        id,
                    );
                }
                2 => {
                    let h = self.r(0.1, 0.3);
                    self.lbox(pl, [x, y, z], [x + w, y + d, z + h], BOX, id);
                }
                3 => {
                    let h = self.r(0.1, 0.35);
                    let r = self.r(0.03, 0.08);
                    self.lcyl(pl, x + 0.06, y + 0.06, r, z, z + h, OTHER_PROP, id);
                }
                4 => self.table_lamp(pl, x + 0.1, y + 0.1, z),
                _ => self.lbox(pl, [x, y, z], [x + w, y + d, z + 0.03], OTHER_PROP, id),
            }
        }
    }

    fn table_lamp(&mut self, pl: &Place, x: f32, y: f32, z: f32) {
        let id = self.instance();
        self.lcyl(pl, x, y, 0.07, z, z + 0.03, LAMP, id);
        self.lcyl(pl, x, y, 0.015, z, z + 0.35, LAMP, id);
        self.lcyl(pl, x, y, 0.14, z + 0.3, z + 0.5, LAMP, id);
        self.look_at_local(pl, x, y, z + 0.3);
    }

    fn floor_lamp(&mut self) {
        let region = self.interior(0.25);
        let Some(pl) = self.free_spot(0.4, 0.4, region, false, 0.1) else {
            return;
        };
        let id = self.instance();
        self.lcyl(&pl, 0.2, 0.2, 0.15, 0.0, 0.03, LAMP, id);
        self.lcyl(&pl, 0.2, 0.2, 0.015, 0.0, 1.5, LAMP, id);
        self.lcyl(&pl, 0.2, 0.2, 0.2, 1.4, 1.7, LAMP, id);
        self.look_at_local(&pl, 0.2, 0.2, 1.2);
    }

    fn table(&mut self, pl: &Place, w: f32, d: f32, h: f32, label: u8) -> u16 {
        let id = self.instance();
        self.lbox(pl, [0.0, 0.0, h - 0.04], [w, d, h], label, id);
        for (x, y) in [
            (0.03, 0.03),
            (w - 0.08, 0.03),
            (0.03, d - 0.08),
            (w - 0.08, d - 0.08),
        ] {
            self.lbox(pl, [x, y, 0.0], [x + 0.05, y + 0.05, h - 0.04], label, id);
        }
        self.look_at_local(pl, 0.5 * w, 0.5 * d, h);
        id
    }

    fn chair(&mut self, pl: &Place) {
        // Local: 0.45 x 0.45, backrest at y = 0.
        let id = self.instance();
        self.lbox(pl, [0.0, 0.0, 0.42], [0.45, 0.45, 0.46], CHAIR, id);
        self.lbox(pl, [0.0, 0.0, 0.46], [0.45, 0.04, 0.9], CHAIR, id);
        for (x, y) in [(0.02, 0.02), (0.39, 0.02), (0.02, 0.39), (0.39, 0.39)] {
            self.lbox(pl, [x, y, 0.0], [x + 0.04, y + 0.04, 0.42], CHAIR, id);
        }
        if self.chance(0.15) {
            let c = self.instance();
            self.lbox(pl, [0.05, 0.1, 0.46], [0.4, 0.4, 0.56], CLOTHES, c);
        }
    }

    /// A table with chairs around it, free-standing in `region`.
    fn dining(&mut self, region: [f32; 4]) {
        let (w, d) = (self.r(1.2, 1.8), self.r(0.8, 1.0));
        // Reserve the table plus room for the chairs.
        let Some(outer) = self.free_spot(w + 1.0, d + 1.0, region, false, 0.1) else {
            return;
        };
        let pl = Place {
            x: outer.world(0.5, 0.5)[0],
            y: outer.world(0.5, 0.5)[1],
            yaw: outer.yaw,
        };
        self.table(&pl, w, d, 0.75, TABLE);
        self.clutter(&pl, 0.1, w - 0.1, 0.1, d - 0.1, 0.75, 2);
        let per_side = ((w / 0.6) as usize).max(1);
        for i in 0..per_side {
            let x = (i as f32 + 0.5) * w / per_side as f32;
            // Chair on the near side faces +y (back at local y = -0.45 - gap), far side -y.
            let near = Place {
                x: pl.world(x + 0.225, -0.5)[0],
                y: pl.world(x + 0.225, -0.5)[1],
                yaw: pl.yaw + PI,
            };
            self.chair(&near);
            let far = Place {
                x: pl.world(x - 0.225, d + 0.5)[0],
                y: pl.world(x - 0.225, d + 0.5)[1],
                yaw: pl.yaw,
            };
            self.chair(&far);
        }
    }

    fn bed(&mut self) {
        let (w, l) = if self.chance(0.7) {
            (self.r(1.4, 1.8), 2.05)
        } else {
            (0.95, 2.0)
        };
        let Some(pl) = self.against_wall(w + 1.2, l, None) else {
            return;
        };
        let bed = self.instance();
        let x0 = 0.6;
        self.lbox(&pl, [x0, 0.0, 0.0], [x0 + w, l, 0.35], BED, bed);
        self.lbox(
            &pl,
            [x0 + 0.02, 0.05, 0.35],
            [x0 + w - 0.02, l - 0.03, 0.55],
            BED,
            bed,
        );
        self.lbox(&pl, [x0, 0.0, 0.0], [x0 + w, 0.07, 1.05], BED, bed);
        self.look_at_local(&pl, x0 + 0.5 * w, 0.5 * l, 0.5);
        let pillows = if w > 1.2 { 2 } else { 1 };
        for i in 0..pillows {
            let id = self.instance();
            let px = x0 + 0.08 + i as f32 * (w - 0.16) / pillows as f32;
            self.lbox(
                &pl,
                [px, 0.1, 0.55],
                [px + w / pillows as f32 - 0.2, 0.5, 0.68],
                PILLOW,
                id,
            );
        }
        if self.chance(0.6) {
            let id = self.instance();
            let cx = x0 + self.r(0.1, w - 0.6);
            self.lbox(&pl, [cx, 1.2, 0.55], [cx + 0.5, 1.6, 0.62], CLOTHES, id);
        }
        // Night stands on both sides of the bed, with a lamp and books.
        for x in [0.05, x0 + w + 0.05] {
            let id = self.instance();
            self.lbox(&pl, [x, 0.02, 0.0], [x + 0.45, 0.42, 0.55], NIGHT_STAND, id);
            self.table_lamp(&pl, x + 0.22, 0.2, 0.55);
            if self.chance(0.6) {
                let b = self.instance();
                self.lbox(&pl, [x + 0.02, 0.28, 0.55], [x + 0.2, 0.4, 0.6], BOOKS, b);
            }
        }
    }

    fn cabinet(&mut self, label: u8, w: f32, d: f32, h: f32) -> Option<Place> {
        let pl = self.against_wall(w, d, None)?;
        let id = self.instance();
        self.lbox(&pl, [0.0, 0.0, 0.0], [w, d, h], label, id);
        self.look_at_local(&pl, 0.5 * w, d, 0.5 * h);
        Some(pl)
    }

    fn bookshelf(&mut self) {
        let (w, d, h) = (self.r(0.7, 1.2), 0.35, self.r(1.6, 2.1));
        let Some(pl) = self.against_wall(w, d, None) else {
            return;
        };
        let id = self.instance();
        let t = 0.025;
        self.lbox(&pl, [0.0, 0.0, 0.0], [t, d, h], BOOKSHELF, id);
        self.lbox(&pl, [w - t, 0.0, 0.0], [w, d, h], BOOKSHELF, id);
        self.lbox(&pl, [0.0, 0.0, 0.0], [w, 0.015, h], BOOKSHELF, id);
        let boards = ((h / 0.38) as usize).max(3);
        for i in 0..=boards {
            let z = i as f32 * (h - t) / boards as f32;
            self.lbox(&pl, [t, 0.0, z], [w - t, d, z + t], BOOKSHELF, id);
            if i < boards {
                self.book_row(&pl, t, w - t, z + t, d, 0.3);
            }
        }
        self.look_at_local(&pl, 0.5 * w, d, 0.5 * h);
    }

    /// Books standing in a row on a board at height `z` (local frame), with gaps, and
    /// sometimes a box.
    fn book_row(&mut self, pl: &Place, x0: f32, x1: f32, z: f32, depth: f32, max_h: f32) {
        let mut x = x0 + self.r(0.0, 0.1);
        while x < x1 - 0.05 {
            let w = self.r(0.12, 0.45).min(x1 - x);
            let roll = self.r(0.0, 1.0);
            let id = self.instance();
            if roll < 0.6 {
                let h = self.r(0.15, max_h.min(0.3));
                let back = depth - self.r(0.03, 0.1);
                self.lbox(pl, [x, 0.03, z], [x + w, back, z + h], BOOKS, id);
            } else if roll < 0.72 {
                let h = self.r(0.1, max_h.min(0.25));
                self.lbox(pl, [x, 0.03, z], [x + w, depth - 0.05, z + h], BOX, id);
            } else if roll < 0.8 {
                let top = z + self.r(0.08, 0.2);
                self.lcyl(pl, x + 0.05, 0.5 * depth, 0.04, z, top, OTHER_PROP, id);
            }
            x += w + self.r(0.02, 0.15);
        }
    }

    fn wall_shelves(&mut self) {
        let w = self.r(0.6, 1.2);
        let Some((wall, along)) = self.wall_span(w, None) else {
            return;
        };
        let pl = self.wall_place(wall, along);
        let id = self.instance();
        let n = self.rng.random_range(1..4);
        let z0 = self.r(1.1, 1.4);
        for i in 0..n {
            let z = z0 + i as f32 * 0.35;
            if z > self.size[2] - 0.4 {
                break;
            }
            self.lbox(&pl, [0.0, 0.0, z], [w, 0.25, z + 0.025], SHELVES, id);
            self.book_row(&pl, 0.0, w, z + 0.025, 0.25, 0.25);
        }
        self.look_at_local(&pl, 0.5 * w, 0.2, z0 + 0.2);
    }

    fn sofa(&mut self, wall: Option<usize>) -> Option<Place> {
        let (w, d) = (self.r(1.8, 2.4), 0.9);
        let pl = self.against_wall(w, d + 0.9, wall)?;
        let id = self.instance();
        self.lbox(&pl, [0.0, 0.15, 0.0], [w, d, 0.45], SOFA, id);
        self.lbox(&pl, [0.0, 0.0, 0.0], [w, 0.2, 0.85], SOFA, id);
        self.lbox(&pl, [0.0, 0.0, 0.0], [0.18, d, 0.62], SOFA, id);
        self.lbox(&pl, [w - 0.18, 0.0, 0.0], [w, d, 0.62], SOFA, id);
        for i in 0..self.rng.random_range(1..4) {
            let p = self.instance();
            let x = 0.25 + i as f32 * 0.5;
            if x + 0.45 < w - 0.2 {
                self.lbox(&pl, [x, 0.2, 0.45], [x + 0.42, 0.35, 0.8], PILLOW, p);
            }
        }
        self.look_at_local(&pl, 0.5 * w, 0.5 * d, 0.5);
        // A coffee table in front of it, with clutter.
        let t = Place {
            x: pl.world(0.3 * w, d + 0.3)[0],
            y: pl.world(0.3 * w, d + 0.3)[1],
            yaw: pl.yaw,
        };
        self.table(&t, 0.4 * w, 0.5, 0.42, TABLE);
        self.clutter(&t, 0.05, 0.4 * w - 0.05, 0.05, 0.45, 0.42, 3);
        Some(pl)
    }

    fn tv_stand(&mut self) {
        let w = self.r(1.2, 1.8);
        let Some(pl) = self.against_wall(w, 0.45, None) else {
            return;
        };
        let id = self.instance();
        self.lbox(&pl, [0.0, 0.0, 0.0], [w, 0.45, 0.5], CABINET, id);
        let tv = self.instance();
        let tw = (w - 0.2).min(1.3);
        let x = 0.5 * (w - tw);
        self.lbox(
            &pl,
            [x, 0.1, 0.55],
            [x + tw, 0.16, 0.55 + 0.56 * tw],
            TELEVISION,
            tv,
        );
        self.lbox(
            &pl,
            [0.5 * w - 0.15, 0.05, 0.5],
            [0.5 * w + 0.15, 0.25, 0.55],
            TELEVISION,
            tv,
        );
        self.look_at_local(&pl, 0.5 * w, 0.2, 0.9);
        self.clutter(&pl, 0.05, x - 0.02, 0.05, 0.4, 0.5, 1);
    }

    fn rug(&mut self, region: [f32; 4]) {
        let (w, d) = (self.r(1.2, 2.4), self.r(0.8, 1.8));
        // Rugs may lie under furniture: placed without reserving floor.
        let x = self.r(region[0], (region[2] - w).max(region[0] + 0.01));
        let y = self.r(region[1], (region[3] - d).max(region[1] + 0.01));
        let id = self.instance();
        self.aabb([x, y, 0.0], [x + w, y + d, 0.012], FLOOR_MAT, id);
    }

    fn floor_things(&mut self, n: usize, region: [f32; 4]) {
        for _ in 0..n {
            let (w, d) = (self.r(0.25, 0.5), self.r(0.2, 0.45));
            let Some(pl) = self.free_spot(w, d, region, true, 0.05) else {
                continue;
            };
            let id = self.instance();
            match self.rng.random_range(0..4) {
                0 => {
                    let h = self.r(0.2, 0.5);
                    self.lbox(&pl, [0.0, 0.0, 0.0], [w, d, h], BOX, id);
                }
                1 => self.lbox(&pl, [0.0, 0.0, 0.0], [w.min(0.4), 0.15, 0.4], BAG, id),
                2 => {
                    self.lcyl(&pl, 0.15, 0.15, 0.12, 0.0, 0.3, OTHER_PROP, id);
                    self.lcyl(&pl, 0.15, 0.15, 0.25, 0.3, 0.8, OTHER_PROP, id);
                }
                _ => self.lbox(
                    &pl,
                    [0.0, 0.0, 0.0],
                    [w + 0.2, d + 0.1, 0.42],
                    OTHER_FURNITURE,
                    id,
                ),
            }
            self.look_at_local(&pl, 0.5 * w, 0.5 * d, 0.3);
        }
    }

    fn person(&mut self, region: [f32; 4]) {
        let Some(pl) = self.free_spot(0.5, 0.3, region, true, 0.3) else {
            return;
        };
        let id = self.instance();
        self.lbox(&pl, [0.08, 0.08, 0.0], [0.22, 0.22, 0.85], PERSON, id);
        self.lbox(&pl, [0.28, 0.08, 0.0], [0.42, 0.22, 0.85], PERSON, id);
        self.lbox(&pl, [0.05, 0.03, 0.85], [0.45, 0.27, 1.45], PERSON, id);
        self.lcyl(&pl, 0.25, 0.15, 0.11, 1.47, 1.72, PERSON, id);
        self.look_at_local(&pl, 0.25, 0.15, 1.1);
    }

    fn desk(&mut self) {
        let (w, d) = (self.r(1.2, 1.6), 0.7);
        let Some(pl) = self.against_wall(w, d + 0.8, None) else {
            return;
        };
        let id = self.instance();
        self.lbox(&pl, [0.0, 0.0, 0.72], [w, d, 0.75], DESK, id);
        self.lbox(&pl, [0.0, 0.0, 0.0], [0.03, d, 0.72], DESK, id);
        self.lbox(&pl, [w - 0.03, 0.0, 0.0], [w, d, 0.72], DESK, id);
        if self.chance(0.5) {
            self.lbox(
                &pl,
                [w - 0.45, 0.02, 0.0],
                [w - 0.03, d - 0.02, 0.68],
                CABINET,
                id,
            );
        }
        let mon = self.instance();
        let mx = self.r(0.2, w - 0.8);
        self.lbox(
            &pl,
            [mx, 0.1, 0.78],
            [mx + 0.6, 0.14, 1.15],
            TELEVISION,
            mon,
        );
        self.lbox(
            &pl,
            [mx + 0.25, 0.08, 0.75],
            [mx + 0.35, 0.2, 0.78],
            TELEVISION,
            mon,
        );
        let kb = self.instance();
        self.lbox(
            &pl,
            [mx + 0.1, 0.3, 0.75],
            [mx + 0.55, 0.45, 0.77],
            OTHER_PROP,
            kb,
        );
        self.clutter(&pl, 0.05, w - 0.05, 0.35, d - 0.05, 0.75, 3);
        self.look_at_local(&pl, 0.5 * w, 0.4, 0.9);
        // An office chair in front.
        let c = self.instance();
        let (cx, cy) = (0.5 * w, d + 0.35);
        self.lcyl(&pl, cx, cy, 0.3, 0.05, 0.08, CHAIR, c);
        self.lcyl(&pl, cx, cy, 0.03, 0.08, 0.45, CHAIR, c);
        self.lbox(
            &pl,
            [cx - 0.25, cy - 0.25, 0.45],
            [cx + 0.25, cy + 0.25, 0.52],
            CHAIR,
            c,
        );
        self.lbox(
            &pl,
            [cx - 0.23, cy + 0.2, 0.52],
            [cx + 0.23, cy + 0.27, 1.05],
            CHAIR,
            c,
        );
    }

    fn counter_run(&mut self, wall: Option<usize>, with_sink: bool) -> Option<Place> {
        let w = self.r(1.6, 3.0);
        let pl = self.against_wall(w, 0.62, wall)?;
        let cab = self.instance();
        self.lbox(&pl, [0.0, 0.0, 0.0], [w, 0.58, 0.86], CABINET, cab);
        let top = self.instance();
        self.lbox(&pl, [0.0, 0.0, 0.86], [w, 0.62, 0.9], COUNTER, top);
        self.look_at_local(&pl, 0.5 * w, 0.3, 0.9);
        let mut free_from = 0.05;
        if with_sink {
            let sx = self.r(0.2, w - 0.8);
            let s = self.instance();
            self.lbox(&pl, [sx, 0.08, 0.9], [sx + 0.6, 0.5, 0.93], SINK, s);
            self.lcyl(&pl, sx + 0.3, 0.06, 0.02, 0.93, 1.2, SINK, s);
            free_from = (sx + 0.65).min(w - 0.3);
            if self.chance(0.7) {
                let t = self.instance();
                self.lbox(
                    &pl,
                    [sx - 0.25, 0.62, 0.5],
                    [sx - 0.05, 0.65, 0.85],
                    TOWEL,
                    t,
                );
            }
        }
        self.clutter(&pl, free_from, w - 0.05, 0.1, 0.55, 0.9, 3);
        // Upper cabinets.
        if self.chance(0.8) && self.size[2] > 2.3 {
            let up = self.instance();
            self.lbox(&pl, [0.0, 0.0, 1.45], [w, 0.35, 2.2], CABINET, up);
        }
        Some(pl)
    }

    // ----- room kinds -----

    fn living(&mut self) {
        self.sofa(None);
        self.tv_stand();
        self.bookshelf();
        if self.chance(0.6) {
            self.bookshelf();
        }
        self.floor_lamp();
        let region = self.interior(0.6);
        self.rug(region);
        for _ in 0..2 {
            let pl = self.free_spot(0.45, 0.45, region, true, 0.2);
            if let Some(pl) = pl {
                self.chair(&pl);
            }
        }
        for _ in 0..3 {
            self.picture(None);
        }
        self.wall_shelves();
        self.floor_things(3, region);
        if self.chance(0.5) {
            self.person(region);
        }
    }

    fn bedroom(&mut self) {
        self.bed();
        let w = self.r(0.9, 1.4);
        if self.cabinet(DRESSER, w, 0.5, 0.85).is_some() {
            self.picture(None);
        }
        if self.chance(0.3)
            && let Some(pl) = self.cabinet(DRESSER, 0.9, 0.45, 0.8)
        {
            self.clutter(&pl, 0.05, 0.85, 0.05, 0.4, 0.8, 2);
        }
        let w = self.r(0.9, 1.6);
        self.cabinet(CABINET, w, 0.6, 2.0);
        if self.chance(0.6) {
            self.wall_board(MIRROR, 0.5, 1.0, 0.9);
        }
        self.picture(None);
        self.wall_shelves();
        let region = self.interior(0.4);
        self.rug(region);
        self.floor_things(3, region);
        if self.chance(0.5) {
            self.desk();
        }
    }

    fn kitchen(&mut self) {
        self.counter_run(Some(0), true);
        self.counter_run(None, false);
        if let Some(pl) = self.against_wall(0.8, 0.7, None) {
            let id = self.instance();
            self.lbox(&pl, [0.0, 0.0, 0.0], [0.8, 0.7, 1.85], REFRIGERATOR, id);
            self.look_at_local(&pl, 0.4, 0.7, 1.0);
        }
        let region = self.interior(0.9);
        self.dining(region);
        self.wall_shelves();
        self.picture(None);
        self.floor_things(2, self.interior(0.3));
        if self.chance(0.5) {
            self.rug(region);
        }
    }

    fn office(&mut self) {
        self.desk();
        self.desk();
        if self.chance(0.6) {
            self.desk();
        }
        self.bookshelf();
        self.cabinet(CABINET, 0.5, 0.6, 1.3);
        let w = self.r(1.2, 2.0);
        self.wall_board(WHITEBOARD, w, 0.9, 1.0);
        self.wall_shelves();
        self.picture(None);
        let region = self.interior(0.5);
        self.floor_things(3, region);
        if self.chance(0.6) {
            self.person(region);
        }
        if self.chance(0.5) {
            self.floor_lamp();
        }
    }

    fn bathroom(&mut self) {
        // Bathtub along a short wall with a shower curtain.
        let wall = if self.size[0] < self.size[1] { 0 } else { 1 };
        if let Some(pl) = self.against_wall(1.7, 0.75, Some(wall)) {
            let id = self.instance();
            self.lbox(&pl, [0.0, 0.0, 0.0], [1.7, 0.75, 0.55], BATHTUB, id);
            let c = self.instance();
            self.lbox(&pl, [0.0, 0.73, 0.25], [1.7, 0.75, 2.0], SHOWER_CURTAIN, c);
            self.look_at_local(&pl, 0.85, 0.75, 0.8);
        }
        if let Some(pl) = self.against_wall(0.45, 0.7, None) {
            let id = self.instance();
            self.lcyl(&pl, 0.225, 0.45, 0.2, 0.0, 0.42, TOILET, id);
            self.lbox(&pl, [0.02, 0.0, 0.3], [0.43, 0.2, 0.8], TOILET, id);
            self.look_at_local(&pl, 0.22, 0.4, 0.5);
        }
        if let Some(pl) = self.against_wall(0.9, 0.5, None) {
            let cab = self.instance();
            self.lbox(&pl, [0.0, 0.0, 0.0], [0.9, 0.48, 0.8], CABINET, cab);
            let top = self.instance();
            self.lbox(&pl, [0.0, 0.0, 0.8], [0.9, 0.5, 0.84], COUNTER, top);
            let s = self.instance();
            self.lbox(&pl, [0.2, 0.08, 0.84], [0.7, 0.42, 0.88], SINK, s);
            self.clutter(&pl, 0.72, 0.88, 0.05, 0.45, 0.84, 1);
            let m = self.instance();
            self.lbox(&pl, [0.1, 0.0, 1.1], [0.8, 0.02, 1.9], MIRROR, m);
            self.look_at_local(&pl, 0.45, 0.3, 1.0);
        }
        for _ in 0..2 {
            if let Some((wall, along)) = self.wall_span(0.5, None) {
                let pl = self.wall_place(wall, along);
                let id = self.instance();
                self.lbox(&pl, [0.0, 0.0, 0.9], [0.5, 0.05, 1.5], TOWEL, id);
                self.look_at_local(&pl, 0.25, 0.0, 1.2);
            }
        }
        self.wall_shelves();
        let region = self.interior(0.3);
        self.rug(region);
        self.floor_things(1, region);
    }

    fn open_plan(&mut self) {
        let [x, y, _] = self.size;
        // Columns of the structure.
        for i in 1..3 {
            let id = self.instance();
            let cx = i as f32 * x / 3.0;
            let cy = 0.5 * y + self.r(-0.5, 0.5);
            self.aabb(
                [cx - 0.2, cy - 0.2, 0.0],
                [cx + 0.2, cy + 0.2, self.size[2]],
                OTHER_STRUCTURE,
                id,
            );
            self.blocked.push([cx - 0.2, cy - 0.2, cx + 0.2, cy + 0.2]);
        }
        self.sofa(Some(3));
        self.tv_stand();
        self.counter_run(Some(1), true);
        self.counter_run(None, false);
        if let Some(pl) = self.against_wall(0.8, 0.7, None) {
            let id = self.instance();
            self.lbox(&pl, [0.0, 0.0, 0.0], [0.8, 0.7, 1.85], REFRIGERATOR, id);
        }
        self.dining([2.0, 1.5, x - 3.0, y - 2.5]);
        self.desk();
        self.bookshelf();
        self.bookshelf();
        self.floor_lamp();
        self.window();
        for _ in 0..4 {
            self.picture(None);
        }
        self.wall_board(WHITEBOARD, 1.5, 0.9, 1.0);
        self.wall_shelves();
        self.wall_shelves();
        let region = self.interior(0.6);
        self.rug([0.6, 0.6, 0.4 * x, y - 0.6]);
        self.floor_things(5, region);
        self.person(region);
        if let Some(pl) = self.cabinet(OTHER_FURNITURE, 1.2, 0.45, 0.9) {
            self.clutter(&pl, 0.05, 1.15, 0.05, 0.4, 0.9, 2);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenes_are_deterministic_and_varied() {
        let a = SynthScene::generate(3, 11);
        let b = SynthScene::generate(3, 11);
        assert_eq!(a.bvh.primitives(), b.bvh.primitives());
        let c = SynthScene::generate(3, 12);
        assert_ne!(a.bvh.primitives(), c.bvh.primitives());
    }

    #[test]
    fn six_kinds_cover_at_least_25_classes() {
        let mut all = [false; 41];
        for i in 0..6 {
            let s = SynthScene::generate(i, 1);
            for (c, present) in s.classes().iter().enumerate() {
                all[c] |= present;
            }
        }
        let n = all[1..].iter().filter(|&&p| p).count();
        assert!(n >= 25, "only {n} classes");
    }

    #[test]
    fn open_plan_is_large() {
        let s = SynthScene::generate(5, 1);
        assert!(s.size[0] >= 12.0 && s.size[0] <= 15.0);
    }
}
