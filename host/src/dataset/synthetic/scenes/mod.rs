//! Procedural indoor scenes built from labelled primitives: living room, bedroom,
//! kitchen, office, bathroom and an open-plan space up to 15 m long.
//!
//! Every scene is a closed room (floor, ceiling, four walls) with a door, windows and
//! furniture placed against the walls or free-standing without overlaps, and the small,
//! thin objects the paper names as the hard ones (books, pictures, lamps, towels, paper,
//! boxes, shelves). A few unlabelled fixtures (ceiling lights, vents, sockets) give void
//! pixels, as Hypersim has. Everything is deterministic in the seed.
//!
//! The [`SynthScene`] type and the generator's entry points are here, the kinds of room in
//! `kind.rs` and the extra NYU40 ids in [`class`]; the generator itself is a `Builder`
//! that places primitives: its state, measures and placement rules (`builder.rs`), the room
//! shell (`shell.rs`), furniture and small objects (`furniture.rs`) and what each kind of
//! room gets (`rooms.rs`). Those files use only each other and `kind.rs`, never this one.

mod builder;
pub mod class;
mod furniture;
mod kind;
mod rooms;
mod shell;

use super::geometry::{Bvh, Cast, Hit, Primitive, Shape};
use builder::Builder;
pub(crate) use builder::{DOOR_H, DOOR_W, WALL_T};
use class::*;
pub use kind::SceneKind;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

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
