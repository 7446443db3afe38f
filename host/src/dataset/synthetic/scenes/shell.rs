//! The room shell: floor, ceiling, four walls with a door, windows, and unlabelled
//! fixtures (ceiling lights, vents, sockets).

use super::builder::{Builder, DOOR_W, WALL_T};
use super::class::*;
use crate::dataset::synthetic::geometry::{Primitive, Shape};

impl Builder {
    pub(super) fn shell(&mut self) {
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

    pub(super) fn window(&mut self) {
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
    pub(super) fn fixtures(&mut self) {
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
}
