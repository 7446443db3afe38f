//! Furniture and small objects, each built in the local frame of its [`Place`] (x along
//! its width, y out of the wall, z up).

use super::builder::{Builder, Place};
use super::class::*;
use rand::RngExt;
use std::f32::consts::PI;

impl Builder {
    pub(super) fn picture(&mut self, wall: Option<usize>) {
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

    pub(super) fn wall_board(&mut self, label: u8, w: f32, z0: f32, h: f32) {
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
    pub(super) fn clutter(
        &mut self,
        pl: &Place,
        x0: f32,
        x1: f32,
        y0: f32,
        y1: f32,
        z: f32,
        n: usize,
    ) {
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

    pub(super) fn table_lamp(&mut self, pl: &Place, x: f32, y: f32, z: f32) {
        let id = self.instance();
        self.lcyl(pl, x, y, 0.07, z, z + 0.03, LAMP, id);
        self.lcyl(pl, x, y, 0.015, z, z + 0.35, LAMP, id);
        self.lcyl(pl, x, y, 0.14, z + 0.3, z + 0.5, LAMP, id);
        self.look_at_local(pl, x, y, z + 0.3);
    }

    pub(super) fn floor_lamp(&mut self) {
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

    pub(super) fn table(&mut self, pl: &Place, w: f32, d: f32, h: f32, label: u8) -> u16 {
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

    pub(super) fn chair(&mut self, pl: &Place) {
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
    pub(super) fn dining(&mut self, region: [f32; 4]) {
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

    pub(super) fn bed(&mut self) {
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

    pub(super) fn cabinet(&mut self, label: u8, w: f32, d: f32, h: f32) -> Option<Place> {
        let pl = self.against_wall(w, d, None)?;
        let id = self.instance();
        self.lbox(&pl, [0.0, 0.0, 0.0], [w, d, h], label, id);
        self.look_at_local(&pl, 0.5 * w, d, 0.5 * h);
        Some(pl)
    }

    pub(super) fn bookshelf(&mut self) {
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
    pub(super) fn book_row(
        &mut self,
        pl: &Place,
        x0: f32,
        x1: f32,
        z: f32,
        depth: f32,
        max_h: f32,
    ) {
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

    pub(super) fn wall_shelves(&mut self) {
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

    pub(super) fn sofa(&mut self, wall: Option<usize>) -> Option<Place> {
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

    pub(super) fn tv_stand(&mut self) {
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

    pub(super) fn rug(&mut self, region: [f32; 4]) {
        let (w, d) = (self.r(1.2, 2.4), self.r(0.8, 1.8));
        // Rugs may lie under furniture: placed without reserving floor.
        let x = self.r(region[0], (region[2] - w).max(region[0] + 0.01));
        let y = self.r(region[1], (region[3] - d).max(region[1] + 0.01));
        let id = self.instance();
        self.aabb([x, y, 0.0], [x + w, y + d, 0.012], FLOOR_MAT, id);
    }

    pub(super) fn floor_things(&mut self, n: usize, region: [f32; 4]) {
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

    pub(super) fn person(&mut self, region: [f32; 4]) {
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

    pub(super) fn desk(&mut self) {
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

    pub(super) fn counter_run(&mut self, wall: Option<usize>, with_sink: bool) -> Option<Place> {
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
}
