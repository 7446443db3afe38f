//! The generator's state (the room so far: primitives, footprints and wall spans in use,
//! things worth looking at) and its placement rules: local frames of furniture, free floor
//! spots against a wall or inside a region, free wall spans.

use super::kind::SceneKind;
use crate::dataset::synthetic::geometry::{Primitive, Shape};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use std::f32::consts::{FRAC_PI_2, PI};

/// Wall, floor and ceiling thickness.
pub(crate) const WALL_T: f32 = 0.12;

/// Width of a door (and of the doorway of a room on a building floor).
pub(crate) const DOOR_W: f32 = 0.9;

/// Height of a doorway (the top of the door frame).
pub(crate) const DOOR_H: f32 = 2.1;

/// Where a piece of furniture stands: its local frame has x along its width, y along its
/// depth (away from the wall it stands against), z up; `yaw` turns local x into world.
#[derive(Clone, Copy, Debug)]
pub(super) struct Place {
    pub(super) x: f32,
    pub(super) y: f32,
    pub(super) yaw: f32,
}

impl Place {
    pub(super) fn world(&self, lx: f32, ly: f32) -> [f32; 2] {
        let (s, c) = self.yaw.sin_cos();
        [self.x + c * lx - s * ly, self.y + s * lx + c * ly]
    }
}

pub(super) struct Builder {
    pub(super) rng: ChaCha8Rng,
    pub(super) kind: SceneKind,
    pub(super) size: [f32; 3],
    pub(super) prims: Vec<Primitive>,
    pub(super) next_instance: u16,
    /// Floor footprints in use (xmin, ymin, xmax, ymax), furniture and door swings.
    pub(super) blocked: Vec<[f32; 4]>,
    /// Wall spans in use per wall (start, end along the wall) for wall-mounted items.
    pub(super) wall_used: [Vec<(f32, f32)>; 4],
    pub(super) interest: Vec<[f32; 3]>,
    /// The four walls' primitives (south, east, north, west).
    pub(super) walls: [usize; 4],
    /// The door: its wall, where it starts along it and its leaf's primitive.
    pub(super) door: Option<(usize, f32, usize)>,
}

impl Builder {
    pub(super) fn new(rng: ChaCha8Rng, kind: SceneKind, size: [f32; 3]) -> Builder {
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

    pub(super) fn r(&mut self, lo: f32, hi: f32) -> f32 {
        self.rng.random_range(lo..hi)
    }

    pub(super) fn chance(&mut self, p: f32) -> bool {
        self.rng.random::<f32>() < p
    }

    pub(super) fn instance(&mut self) -> u16 {
        self.next_instance = self.next_instance.wrapping_add(1);
        self.next_instance
    }

    pub(super) fn aabb(&mut self, min: [f32; 3], max: [f32; 3], label: u8, instance: u16) {
        self.prims
            .push(Primitive::axis_box(min, max, label, instance));
    }

    /// A box given in a place's local frame.
    pub(super) fn lbox(
        &mut self,
        pl: &Place,
        min: [f32; 3],
        max: [f32; 3],
        label: u8,
        instance: u16,
    ) {
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
    pub(super) fn lcyl(
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

    pub(super) fn look_at_local(&mut self, pl: &Place, lx: f32, ly: f32, z: f32) {
        let p = pl.world(lx, ly);
        self.interest.push([p[0], p[1], z]);
    }

    pub(super) fn footprint(pl: &Place, w: f32, d: f32) -> [f32; 4] {
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

    pub(super) fn overlaps(&self, f: &[f32; 4], gap: f32) -> bool {
        let s = self.size;
        if f[0] < -1e-3 || f[1] < -1e-3 || f[2] > s[0] + 1e-3 || f[3] > s[1] + 1e-3 {
            return true;
        }
        self.blocked.iter().any(|b| {
            f[0] < b[2] + gap && b[0] < f[2] + gap && f[1] < b[3] + gap && b[1] < f[3] + gap
        })
    }

    /// Length of wall `w`: 0 = south (y = 0), 1 = east (x = X), 2 = north (y = Y), 3 = west.
    pub(super) fn wall_len(&self, wall: usize) -> f32 {
        if wall.is_multiple_of(2) {
            self.size[0]
        } else {
            self.size[1]
        }
    }

    /// The frame of a span starting `along` metres along wall `wall`, facing into the room.
    pub(super) fn wall_place(&self, wall: usize, along: f32) -> Place {
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
    pub(super) fn against_wall(&mut self, w: f32, d: f32, wall: Option<usize>) -> Option<Place> {
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
    pub(super) fn free_spot(
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
    pub(super) fn wall_span(&mut self, w: f32, wall: Option<usize>) -> Option<(usize, f32)> {
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

    pub(super) fn interior(&self, margin: f32) -> [f32; 4] {
        [margin, margin, self.size[0] - margin, self.size[1] - margin]
    }
}
