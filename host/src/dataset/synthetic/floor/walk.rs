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

use super::planner::{cumulative, point_at, R_MIN};
use super::{inside, Floor, FloorRoom};
use crate::dataset::synthetic::room::look_at;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sndt_core::Isometry3;
use std::f32::consts::{PI, TAU};

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

impl Floor {
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
            let path = self.grid.path(at, stand);
            let arrive = heading(&path);
            // Look to one side while arriving, then sweep to the other (which first: the
            // walk's parity).
            let sides = if eastward { [-1.0, 1.0] } else { [1.0, -1.0] };
            let views = sides.map(|s| view_towards(room, stand, arrive + s * 1.1, &mut rng));
            steps.push(Step::Move(path, Some(views[0])));
            steps.push(Step::Dwell(views.to_vec()));
            at = stand;
        }
        steps.push(Step::Move(self.grid.path(at, end), None));
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
