//! The floor walk with people in the corridor: a walk of the building floor ([`floor`])
//! while [`PEOPLE`] people walk the corridor's length, one after the other, each at
//! 1.3 m/s along a lane 0.5 m off its middle, alternately east- and westwards. A person
//! comes in at one end, walks to the other and is gone there.
//!
//! Each person's start is chosen, within its third of the walk, as the one that puts the
//! person in view of the walking camera for the most frames (in the image, not hidden by
//! a wall) while never coming within 0.8 m of it. Each person is an
//! [`EventKind::Passes`] event of the dynamics report: its former surface is every place
//! it walked through, vacated when it is gone. The camera looks through the corridor only
//! between rooms, so part of a trail is never seen again: what the report measures there
//! is how much of it each map still holds at the end.
//!
//! [`floor`]: super::floor

use super::dynamic::{bounds, flatten, person, Base, DynamicScene, Event, EventKind, Timeline};
use super::floor::Floor;
use super::geometry::Cast;
use anyhow::{bail, Result};
use sndt_core::{Isometry3, Point3};

/// The scene's name in frame ids.
pub const NAME: &str = "synth_floor_people";

/// People walking the corridor.
pub const PEOPLE: usize = 3;

/// Walking speed, metres per second.
const SPEED: f32 = 1.3;

/// The closest a person's axis comes to the camera, metres (a person is 0.4 m wide).
const CLEARANCE: f32 = 0.8;

/// The lanes' offset from the corridor's middle, metres.
const LANE: f32 = 0.5;

/// Candidate starts are this many frames apart.
const START_STEP: usize = 5;

/// The people's instances: above any object of the floor's rooms.
const FIRST_INSTANCE: u16 = 60_000;

/// Event names, one per person.
const NAMES: [&str; PEOPLE] = [
    "person 1 walks the corridor",
    "person 2 walks the corridor",
    "person 3 walks the corridor",
];

impl DynamicScene {
    /// Walk `walk` of the floor of seed `seed` in `frames` frames, with [`PEOPLE`] people
    /// in the corridor (none when `frozen`). Fails when the walk is too short for a
    /// person to cross the corridor in each third of it, or when no start keeps a person
    /// clear of the camera and in its view.
    ///
    /// ```
    /// use sndt_host::dataset::synthetic::dynamic::DynamicScene;
    /// use sndt_host::dataset::synthetic::{floor, people, DEFAULT_SEED};
    /// let s = DynamicScene::floor_people(DEFAULT_SEED, 1, floor::DEFAULT_FRAMES, false).unwrap();
    /// assert_eq!(s.events.len(), people::PEOPLE);
    /// assert!(DynamicScene::floor_people(DEFAULT_SEED, 1, 6, false).is_err()); // too few frames
    /// ```
    pub fn floor_people(seed: u64, walk: u32, frames: usize, frozen: bool) -> Result<DynamicScene> {
        if frames < 2 || walk == 0 {
            bail!("floor walk with people: need a walk 1, 2, ... and at least 2 frames");
        }
        let floor = Floor::generate(seed);
        let poses = floor.walk(walk, frames);
        let seconds_per_frame = floor.walk_seconds(walk) / (frames - 1) as f32;
        let step = SPEED * seconds_per_frame;
        let [x0, y0, x1, y1] = floor.corridor;
        let (from, to) = (x0 + 0.4, x1 - 0.4);
        let crossing = ((to - from) / step).ceil() as usize + 1;
        let third = frames / PEOPLE;
        if crossing + 1 >= third {
            bail!(
                "floor walk with people: a person needs {} frames to cross the corridor, \
                 in each third of the walk and inside it; give at least {} frames",
                crossing + 2,
                PEOPLE * (crossing + 2)
            );
        }
        let mut timelines = Vec::new();
        let mut events = Vec::new();
        for (i, &name) in NAMES.iter().enumerate() {
            let east = i % 2 == 0;
            let lane = 0.5 * (y0 + y1) + if east { -LANE } else { LANE };
            let at = |k: usize| {
                let d = (k as f32 * step).min(to - from);
                [if east { from + d } else { to - d }, lane]
            };
            let track = |start: usize| (0..crossing).map(move |k| (start + k, at(k)));
            // From frame 1: a person there at frame 0 would stand in the frozen twin.
            let starts = ((i * third).max(1)..(i + 1) * third - crossing).step_by(START_STEP);
            let best = starts
                .filter(|&s| track(s).all(|(f, p)| clear_of(&poses[f], p)))
                .map(|s| {
                    (
                        track(s)
                            .filter(|&(f, p)| in_view(&floor, &poses[f], p))
                            .count(),
                        s,
                    )
                })
                .filter(|&(seen, _)| seen > 0)
                .max_by_key(|&(seen, s)| (seen, std::cmp::Reverse(s)));
            let Some((_, start)) = best else {
                bail!(
                    "floor walk with people: no start in frames {}..{} keeps person {} clear \
                     of the camera and in its view",
                    i * third,
                    (i + 1) * third,
                    i + 1
                );
            };
            let instance = FIRST_INSTANCE + i as u16;
            let mut states = vec![(0, Vec::new())];
            states.extend(track(start).map(|(f, p)| (f as u32, person(p, instance))));
            let gone = (start + crossing) as u32;
            states.push((gone, Vec::new()));
            let old = flatten(&states, gone);
            events.push(Event {
                name,
                kind: EventKind::Passes,
                first: start as u32,
                vacated: gone,
                region: bounds(&old),
                old,
                new: None,
            });
            timelines.push(Timeline { states });
        }
        Ok(DynamicScene {
            name: NAME,
            base: Base::Floor(Box::new(floor)),
            timelines,
            events,
            frames,
            frozen,
            poses: Some(poses),
        })
    }
}

/// Whether a person at `xy` stays [`CLEARANCE`] away from the camera at `pose`.
fn clear_of(pose: &Isometry3<f32>, xy: [f32; 2]) -> bool {
    let t = pose.translation.vector;
    (t.x - xy[0]).hypot(t.y - xy[1]) >= CLEARANCE
}

/// Whether the chest of a person at `xy` is in the view of the camera at `pose` (within
/// 10 m and Hypersim's field of view) and not hidden by the floor's walls or furniture.
fn in_view(floor: &Floor, pose: &Isometry3<f32>, xy: [f32; 2]) -> bool {
    let chest = Point3::new(xy[0], xy[1], 1.2);
    let c = pose.inverse() * chest;
    let fov = c.z > 0.3 && c.z < 10.0 && (c.x / c.z).abs() < 0.55 && (c.y / c.z).abs() < 0.42;
    if !fov {
        return false;
    }
    let eye = pose.translation.vector;
    let d = chest.coords - eye;
    let dist = d.norm();
    let dir = [d.x / dist, d.y / dist, d.z / dist];
    // A hit within the person's radius of the chest is the person's own place.
    floor
        .cast(&[eye.x, eye.y, eye.z], &dir, dist)
        .is_none_or(|hit| hit.t > dist - 0.3)
}
