//! A room where things move: the scene of the dynamics report (`sndt dynamics`).
//!
//! A 6 x 5 x 2.7 m room seen by a camera near its front wall that sways slowly sideways.
//! For the first [`DEFAULT_CHANGE`] frames nothing moves, long enough for every surface to
//! reach its occupancy clamp; then, at the change frame `c`:
//!
//! - a **chair** beside the table is moved to the other side of the room;
//! - a **night stand** is replaced, in the same place, by a slightly smaller **box**;
//! - the **door** in the back wall swings open over five frames, showing the corridor
//!   behind it;
//! - a **person** (NYU40 class 31) walks in from the left, stands in front of the table
//!   for 20 frames and walks out to the right, gone at `c + 40`;
//! - a **cart** rolls in from the left between the camera and the table's thin top and
//!   legs (from `c + 45`), stops in front of the table for 15 frames and rolls out to the
//!   right, gone at `c + 80`.
//!
//! A passing object's place is *vacated* when it leaves the place where it stopped: the
//! person at `c + 30`, the cart at `c + 70`.
//!
//! Every frame is rendered from the scene as it is at that frame, so its ground-truth
//! labels (and the predictions made from them) show the objects where they are. The
//! *frozen* variant renders every frame with every object as at frame 0: the reference a
//! dynamic run's static surface is compared with.
//!
//! [`Event`] describes each change for the report: the shapes the object had before it
//! left (its former surface), the frame from which its old place is empty, and the object
//! that appears in its place, if any.

use super::floor::Floor;
use super::geometry::{Aabb, Bvh, Cast, Hit, Primitive, Shape};
use super::scenes::class::*;
use crate::dataset::synthetic::room::look_at;
use anyhow::{bail, Result};
use sndt_core::Isometry3;

/// The frame of the first change by default.
pub const DEFAULT_CHANGE: u32 = 30;
/// Frames of the default walk: 50 frames after the last object has left.
pub const DEFAULT_FRAMES: usize = 160;
/// Frames after the change frame until the last object (the cart) has left.
pub const LAST_MOVE: u32 = 80;
/// Frames after the change frame when the cart comes in.
const CART_COMES: u32 = 45;
/// The scene's name in frame ids.
pub const NAME: &str = "synth_dynamic";

/// Interior extents of the room, metres.
const SIZE: [f32; 3] = [6.0, 5.0, 2.7];
/// Wall, floor and ceiling thickness.
const THICK: f32 = 0.1;
/// The door opening in the back wall: x range, height.
const DOOR_X: [f32; 2] = [2.55, 3.45];
const DOOR_TOP: f32 = 2.05;

/// What kind of change an [`Event`] is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EventKind {
    /// An object leaves one place and stands in another.
    Moved,
    /// An object is replaced by one of another class in the same place.
    Replaced,
    /// A door swings open.
    Door,
    /// Something passes through the view and leaves it (a person, a cart).
    Passes,
}

/// One change of the scene, as the dynamics report measures it.
#[derive(Clone, Debug)]
pub struct Event {
    /// Short name, e.g. `chair moved`.
    pub name: &'static str,
    /// What kind of change.
    pub kind: EventKind,
    /// The first frame at which the scene differs from the frame before.
    pub first: u32,
    /// From this frame on the object's old place is empty (for a passing object: it has
    /// left the view).
    pub vacated: u32,
    /// Every shape the object had before `vacated`: its former surface.
    pub old: Vec<Primitive>,
    /// The object that stands in the end where it did not stand before, with its instance
    /// and class: what frames-to-relabel measures.
    pub new: Option<(u16, u8)>,
    /// Where the event happens (old and new shapes, and the thin structure it passes):
    /// static loss is counted in here.
    pub region: Aabb,
}

/// An object's shapes over time: state `i` holds from frame `states[i].0` until the next.
#[derive(Clone, Debug)]
pub(super) struct Timeline {
    pub(super) states: Vec<(u32, Vec<Primitive>)>,
}

impl Timeline {
    /// The shapes at frame `frame`.
    fn at(&self, frame: u32) -> &[Primitive] {
        let i = self.states.partition_point(|(from, _)| *from <= frame);
        self.states
            .get(i.saturating_sub(1))
            .map_or(&[], |s| &s.1[..])
    }
}

/// The shapes of the moving objects over time, and the table they pass.
struct Objects {
    chair_old: Vec<Primitive>,
    chair_new: Vec<Primitive>,
    stand: Vec<Primitive>,
    box_new: Vec<Primitive>,
    swing: Vec<(u32, Vec<Primitive>)>,
    person: Vec<(u32, Vec<Primitive>)>,
    cart: Vec<(u32, Vec<Primitive>)>,
    table: Vec<Primitive>,
}

impl Objects {
    /// The objects with the first change at frame `c`.
    fn new(c: u32) -> Objects {
        let b = Primitive::axis_box;
        Objects {
            chair_old: chair([1.75, 3.0], CHAIR_OLD),
            chair_new: chair([4.9, 4.3], CHAIR_NEW),
            stand: vec![b([3.9, 3.5, 0.0], [4.4, 3.95, 0.55], NIGHT_STAND, STAND)],
            box_new: vec![b([3.97, 3.58, 0.0], [4.33, 3.9, 0.38], BOX, BOX_NEW)],
            swing: (0..=5)
                .map(|i| {
                    (
                        if i == 0 { 0 } else { c + i - 1 },
                        vec![door_leaf(i as f32 / 5.0)],
                    )
                })
                .collect(),
            person: person_walk(c),
            cart: cart_roll(c + CART_COMES),
            table: table_shapes(),
        }
    }

    /// One timeline per moving object.
    fn timelines(&self, c: u32) -> Vec<Timeline> {
        let states = |s: &[(u32, Vec<Primitive>)]| Timeline { states: s.to_vec() };
        vec![
            states(&[(0, self.chair_old.clone()), (c, self.chair_new.clone())]),
            states(&[(0, self.stand.clone()), (c, self.box_new.clone())]),
            states(&self.swing),
            states(&self.person),
            states(&self.cart),
        ]
    }

    /// The events, in the order of the module doc.
    fn events(&self, c: u32) -> Vec<Event> {
        let cart_leaves = c + CART_COMES + 25;
        vec![
            Event {
                name: "chair moved",
                kind: EventKind::Moved,
                first: c,
                vacated: c,
                old: self.chair_old.clone(),
                new: Some((CHAIR_NEW, CHAIR)),
                region: bounds(&[&self.chair_old[..], &self.chair_new].concat()),
            },
            Event {
                name: "night stand replaced by a box",
                kind: EventKind::Replaced,
                first: c,
                vacated: c,
                old: self.stand.clone(),
                new: Some((BOX_NEW, BOX)),
                region: bounds(&[&self.stand[..], &self.box_new].concat()),
            },
            Event {
                name: "door opens",
                kind: EventKind::Door,
                first: c,
                vacated: c + 4,
                old: flatten(&self.swing, c + 4),
                new: Some((DOOR_LEAF, DOOR)),
                region: bounds(&flatten(&self.swing, u32::MAX)),
            },
            Event {
                name: "person walks by",
                kind: EventKind::Passes,
                first: c,
                vacated: c + 30,
                old: flatten(&self.person, c + 30),
                new: None,
                region: bounds(&flatten(&self.person, u32::MAX)),
            },
            Event {
                name: "cart passes the table",
                kind: EventKind::Passes,
                first: c + CART_COMES,
                vacated: cart_leaves,
                old: flatten(&self.cart, cart_leaves),
                new: None,
                region: bounds(&[flatten(&self.cart, u32::MAX), self.table.clone()].concat()),
            },
        ]
    }
}

/// Every shape of the states that begin before frame `before`.
pub(super) fn flatten(states: &[(u32, Vec<Primitive>)], before: u32) -> Vec<Primitive> {
    let kept = states.iter().filter(|(from, _)| *from < before);
    kept.flat_map(|(_, p)| p.iter().copied()).collect()
}

/// The box around `prims` (a point at the origin for none).
pub(super) fn bounds(prims: &[Primitive]) -> Aabb {
    let first = prims.first().map(|p| p.shape.aabb());
    let origin = Aabb {
        min: [0.0; 3],
        max: [0.0; 3],
    };
    prims
        .iter()
        .fold(first.unwrap_or(origin), |b, p| b.union(&p.shape.aabb()))
}

/// What never moves: the room, or the building floor of the floor walk with people
/// ([`super::people`]).
#[derive(Clone, Debug)]
pub enum Base {
    /// The dynamic room's shell, table and furniture.
    Room(Bvh),
    /// The building floor.
    Floor(Box<Floor>),
}

impl Base {
    /// Every static shape.
    pub fn primitives(&self) -> Vec<Primitive> {
        match self {
            Base::Room(bvh) => bvh.primitives().to_vec(),
            Base::Floor(floor) => floor.primitives().copied().collect(),
        }
    }
}

impl Cast for Base {
    fn cast(&self, o: &[f32; 3], d: &[f32; 3], t_max: f32) -> Option<Hit> {
        match self {
            Base::Room(bvh) => bvh.cast(o, d, t_max),
            Base::Floor(floor) => floor.cast(o, d, t_max),
        }
    }
}

/// A scene where things move: its static part, its moving objects and its events.
#[derive(Clone, Debug)]
pub struct DynamicScene {
    /// Scene name in frame ids: [`NAME`] or [`super::people::NAME`].
    pub name: &'static str,
    /// What never moves.
    pub base: Base,
    pub(super) timelines: Vec<Timeline>,
    /// The changes, in the order of the module doc.
    pub events: Vec<Event>,
    /// Frames of the walk.
    pub frames: usize,
    /// Every frame shows frame 0's scene.
    pub frozen: bool,
    /// The camera per frame, for a walk of the floor (the room's camera is a formula).
    pub(super) poses: Option<Vec<Isometry3<f32>>>,
}

/// The scene at one frame: the static part and the moving objects where they are then.
pub struct SceneAt<'a> {
    base: &'a Base,
    moving: Option<Bvh>,
}

impl Cast for SceneAt<'_> {
    fn cast(&self, o: &[f32; 3], d: &[f32; 3], t_max: f32) -> Option<Hit> {
        let near = self.base.cast(o, d, t_max);
        let limit = near.map_or(t_max, |h| h.t);
        match self.moving.as_ref().and_then(|m| m.cast(o, d, limit)) {
            Some(hit) => Some(hit),
            None => near,
        }
    }
}

// Instances: the room's static objects take 1..=20, moving ones 21 and up.
const CHAIR_OLD: u16 = 21;
const CHAIR_NEW: u16 = 22;
const STAND: u16 = 23;
const BOX_NEW: u16 = 24;
const DOOR_LEAF: u16 = 25;
const PERSON_ID: u16 = 26;
const CART: u16 = 27;

impl DynamicScene {
    /// The room with its first change at frame `change`, walked for `frames` frames.
    /// Every event must happen inside the walk: `change + LAST_MOVE < frames`.
    ///
    /// ```
    /// use sndt_host::dataset::synthetic::dynamic::DynamicScene;
    /// let s = DynamicScene::new(160, 30, false).unwrap();
    /// assert_eq!(s.events.len(), 5);
    /// assert!(DynamicScene::new(100, 30, false).is_err()); // the cart leaves at frame 110
    /// ```
    pub fn new(frames: usize, change: u32, frozen: bool) -> Result<DynamicScene> {
        if frames == 0 {
            bail!("dynamic scene: a walk needs at least one frame");
        }
        let last = change as usize + LAST_MOVE as usize;
        if change == 0 || last >= frames {
            bail!(
                "dynamic scene: its events run from frame {change} to frame {last} (the cart \
                 leaves {LAST_MOVE} frames after the first change), outside a walk of {frames} \
                 frames; give at least {} frames, and a first change after frame 0",
                last + 1
            );
        }
        let objects = Objects::new(change);
        let mut base = room_shell();
        base.extend(objects.table.iter().copied());
        base.extend(furniture());
        Ok(DynamicScene {
            name: NAME,
            base: Base::Room(Bvh::new(base)),
            timelines: objects.timelines(change),
            events: objects.events(change),
            frames,
            frozen,
            poses: None,
        })
    }

    /// The scene as it is at frame `frame` (at frame 0 when frozen).
    pub fn at(&self, frame: u32) -> SceneAt<'_> {
        let frame = if self.frozen { 0 } else { frame };
        let prims: Vec<Primitive> = self
            .timelines
            .iter()
            .flat_map(|t| t.at(frame).iter().copied())
            .collect();
        SceneAt {
            base: &self.base,
            moving: (!prims.is_empty()).then(|| Bvh::new(prims)),
        }
    }

    /// Every shape that stands at frame `frame` (static and moving).
    pub fn primitives_at(&self, frame: u32) -> Vec<Primitive> {
        let frame = if self.frozen { 0 } else { frame };
        let moving = self.timelines.iter().flat_map(|t| t.at(frame).iter());
        let mut out = self.base.primitives();
        out.extend(moving.copied());
        out
    }

    /// Every shape any moving object ever has.
    pub fn moving_primitives(&self) -> Vec<Primitive> {
        let states = self.timelines.iter().flat_map(|t| t.states.iter());
        states.flat_map(|(_, p)| p.iter().copied()).collect()
    }

    /// The camera at frame `frame`: in the room 0.4 m from the front wall at eye height,
    /// swaying 0.5 m sideways with a period of 50 frames, looking at the table; on the
    /// floor, the walk's pose (the last one past its end).
    pub fn pose(&self, frame: u32) -> Isometry3<f32> {
        if let Some(poses) = &self.poses {
            let last = poses.len().saturating_sub(1);
            return poses
                .get((frame as usize).min(last))
                .copied()
                .unwrap_or_else(Isometry3::identity);
        }
        let phase = std::f32::consts::TAU * frame as f32 / 50.0;
        let eye = [3.0 + 0.5 * phase.sin(), 0.4, 1.5];
        look_at(eye, [3.0 + 0.25 * phase.sin(), 4.0, 0.75])
    }
}

/// Floor, ceiling, four walls with the doorway in the back one, and the corridor behind
/// it (its floor, ceiling and walls), so that the open door shows a surface.
fn room_shell() -> Vec<Primitive> {
    let [x, y, z] = SIZE;
    let t = THICK;
    let b = Primitive::axis_box;
    let mut p = vec![
        b([-t, -t, -t], [x + t, y + t, 0.0], FLOOR, 1),
        b([-t, -t, z], [x + t, y + t, z + t], CEILING, 2),
        b([-t, -t, 0.0], [0.0, y + t, z], WALL, 3),
        b([x, -t, 0.0], [x + t, y + t, z], WALL, 3),
        b([0.0, -t, 0.0], [x, 0.0, z], WALL, 3),
        // The back wall around the doorway.
        b([0.0, y, 0.0], [DOOR_X[0], y + t, z], WALL, 3),
        b([DOOR_X[1], y, 0.0], [x, y + t, z], WALL, 3),
        b([DOOR_X[0], y, DOOR_TOP], [DOOR_X[1], y + t, z], WALL, 3),
    ];
    // The corridor: 1.4 m deep behind the doorway.
    let (c0, c1) = (y + t, y + t + 1.4);
    p.push(b([1.5, c0, -t], [4.5, c1, 0.0], FLOOR, 4));
    p.push(b([1.5, c0, z], [4.5, c1, z + t], CEILING, 4));
    p.push(b([1.5, c1, 0.0], [4.5, c1 + t, z], WALL, 5));
    p.push(b([1.4, c0, 0.0], [1.5, c1, z], WALL, 5));
    p.push(b([4.5, c0, 0.0], [4.6, c1, z], WALL, 5));
    p
}

/// The table the cart passes: a 3 cm top on four 4 cm legs, the thin structure.
fn table_shapes() -> Vec<Primitive> {
    let (x0, x1, y0, y1) = (2.3, 3.7, 2.6, 3.4);
    let mut p = vec![Primitive::axis_box(
        [x0, y0, 0.72],
        [x1, y1, 0.75],
        TABLE,
        6,
    )];
    for (x, y) in [
        (x0, y0),
        (x1 - 0.04, y0),
        (x0, y1 - 0.04),
        (x1 - 0.04, y1 - 0.04),
    ] {
        p.push(Primitive::axis_box(
            [x, y, 0.0],
            [x + 0.04, y + 0.04, 0.72],
            TABLE,
            6,
        ));
    }
    p
}

/// What else stands still: a picture frame on the back wall, a bookshelf, a sofa.
fn furniture() -> Vec<Primitive> {
    let b = Primitive::axis_box;
    vec![
        b([0.8, 4.98, 1.2], [1.6, 5.0, 1.8], PICTURE, 7),
        b([0.0, 3.4, 0.0], [0.35, 4.8, 1.9], BOOKSHELF, 8),
        b([5.1, 0.8, 0.0], [6.0, 2.4, 0.45], SOFA, 9),
        b([5.7, 0.8, 0.45], [6.0, 2.4, 0.85], SOFA, 9),
    ]
}

/// A chair facing +x with its seat centred at `xy`: seat, four legs, backrest.
fn chair(xy: [f32; 2], instance: u16) -> Vec<Primitive> {
    let [x, y] = xy;
    let (h, leg) = (0.22, 0.03);
    let b = |min, max| Primitive::axis_box(min, max, CHAIR, instance);
    let mut p = vec![b([x - h, y - h, 0.42], [x + h, y + h, 0.46])];
    for (dx, dy) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
        let (lx, ly) = (x + dx * (h - leg), y + dy * (h - leg));
        p.push(b(
            [lx - leg / 2.0, ly - leg / 2.0, 0.0],
            [lx + leg / 2.0, ly + leg / 2.0, 0.42],
        ));
    }
    p.push(b([x - h, y - h, 0.46], [x - h + 0.04, y + h, 0.9]));
    p
}

/// The door leaf, opened by `open` (0 closed, 1 at 90 degrees into the room), hinged at
/// the doorway's left post.
fn door_leaf(open: f32) -> Primitive {
    let angle = open * std::f32::consts::FRAC_PI_2;
    let (half_w, half_t) = (0.5 * (DOOR_X[1] - DOOR_X[0]), 0.02);
    let hinge = [DOOR_X[0], SIZE[1] - half_t];
    // The leaf's centre turns about the hinge towards -y.
    let center = [
        hinge[0] + half_w * angle.cos(),
        hinge[1] - half_w * angle.sin(),
        0.5 * DOOR_TOP,
    ];
    Primitive {
        shape: Shape::Box {
            center,
            half: [half_w, half_t, 0.5 * DOOR_TOP - 0.01],
            yaw: -angle,
        },
        label: DOOR,
        instance: DOOR_LEAF,
    }
}

/// A person standing at `xy`: two legs, a torso, a head (upright cylinders), instance
/// `instance`.
pub(super) fn person(xy: [f32; 2], instance: u16) -> Vec<Primitive> {
    let [x, y] = xy;
    let c = |dx: f32, r: f32, z0: f32, z1: f32| Primitive {
        shape: Shape::Cylinder {
            xy: [x + dx, y],
            radius: r,
            z0,
            z1,
        },
        label: PERSON,
        instance,
    };
    vec![
        c(-0.1, 0.07, 0.0, 0.85),
        c(0.1, 0.07, 0.0, 0.85),
        c(0.0, 0.19, 0.85, 1.5),
        c(0.0, 0.1, 1.5, 1.75),
    ]
}

/// The person's timeline from frame `c`: 10 frames walking in from x = 0.6 to 3.0 along
/// y = 1.9, 20 frames standing there, 10 frames walking out to x = 5.4, then gone.
fn person_walk(c: u32) -> Vec<(u32, Vec<Primitive>)> {
    let mut states = Vec::new();
    for i in 0..10 {
        states.push((c + i, person([0.6 + 0.24 * i as f32, 1.9], PERSON_ID)));
    }
    states.push((c + 10, person([3.0, 1.9], PERSON_ID)));
    for i in 0..10 {
        states.push((c + 30 + i, person([3.24 + 0.24 * i as f32, 1.9], PERSON_ID)));
    }
    states.push((c + 40, Vec::new()));
    states
}

/// The cart's timeline from frame `from`: rolls 0.2 m a frame along y = 2.2 from x = 1.0
/// to 3.0 (10 frames), stands there 15 frames, rolls on to x = 5.0 (10 frames), then is
/// gone. A 0.6 x 0.4 x 0.8 m body 0.1 m above the floor.
fn cart_roll(from: u32) -> Vec<(u32, Vec<Primitive>)> {
    let cart = |x: f32| {
        vec![Primitive::axis_box(
            [x - 0.3, 2.0, 0.1],
            [x + 0.3, 2.4, 0.9],
            OTHER_FURNITURE,
            CART,
        )]
    };
    let mut states = Vec::new();
    for i in 0..10 {
        states.push((from + i, cart(1.0 + 0.2 * i as f32)));
    }
    states.push((from + 10, cart(3.0)));
    for i in 0..10 {
        states.push((from + 25 + i, cart(3.2 + 0.2 * i as f32)));
    }
    states.push((from + 35, Vec::new()));
    // Before it comes, the cart is not in the room.
    states.insert(0, (0, Vec::new()));
    states
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The scene changes exactly at the event frames: the night stand's top (0.55 m) is
    /// hit before the change and the box's (0.38 m) after it; a frozen scene never
    /// changes.
    #[test]
    fn objects_are_where_their_timeline_says() {
        let s = DynamicScene::new(DEFAULT_FRAMES, DEFAULT_CHANGE, false).unwrap();
        let down = [0.0, 0.0, -1.0];
        let top = |scene: &DynamicScene, f: u32| {
            let hit = scene.at(f).cast(&[4.15, 3.75, 2.0], &down, 10.0).unwrap();
            (2.0 - hit.t, hit.label)
        };
        let (z, label) = top(&s, DEFAULT_CHANGE - 1);
        assert!(
            (z - 0.55).abs() < 1e-4 && label == NIGHT_STAND,
            "{z} {label}"
        );
        let (z, label) = top(&s, DEFAULT_CHANGE);
        assert!((z - 0.38).abs() < 1e-4 && label == BOX, "{z} {label}");
        let frozen = DynamicScene::new(DEFAULT_FRAMES, DEFAULT_CHANGE, true).unwrap();
        assert_eq!(top(&frozen, 140).1, NIGHT_STAND);
        // The person stands at (3.0, 1.9) from c + 10 to c + 29 and is gone at c + 40.
        let at = |f: u32| {
            let hit = s.at(f).cast(&[3.0, 1.9, 2.5], &down, 10.0).unwrap();
            hit.label
        };
        assert_eq!(at(DEFAULT_CHANGE + 15), PERSON);
        assert_eq!(at(DEFAULT_CHANGE + 40), FLOOR);
        assert_eq!(at(DEFAULT_CHANGE - 1), FLOOR);
    }

    /// The door turns about its hinge (at the left post, 2 cm in front of the wall):
    /// closed it fills the doorway, open it stands along y, 0.9 m into the room.
    #[test]
    fn door_leaf_turns_about_its_hinge() {
        let closed = door_leaf(0.0).shape.aabb();
        assert!(
            (closed.min[0] - DOOR_X[0]).abs() < 1e-4 && (closed.max[0] - DOOR_X[1]).abs() < 1e-4
        );
        let open = door_leaf(1.0).shape.aabb();
        assert!(
            (open.min[1] - (SIZE[1] - 0.02 - 0.9)).abs() < 1e-3,
            "{open:?}"
        );
        assert!(open.max[0] - open.min[0] < 0.05, "{open:?}");
    }

    #[test]
    fn events_outside_the_walk_are_refused() {
        let e = DynamicScene::new(110, 30, false).unwrap_err().to_string();
        assert!(
            e.contains("outside a walk of 110 frames") && e.contains("at least 111"),
            "{e}"
        );
        assert!(DynamicScene::new(111, 30, false).is_ok());
        assert!(DynamicScene::new(0, 30, false).is_err());
        assert!(DynamicScene::new(160, 0, false).is_err());
    }
}
