//! The six kinds of room: which furniture each gets, and where.

use super::builder::Builder;
use super::class::*;

impl Builder {
    pub(super) fn living(&mut self) {
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

    pub(super) fn bedroom(&mut self) {
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

    pub(super) fn kitchen(&mut self) {
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

    pub(super) fn office(&mut self) {
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

    pub(super) fn bathroom(&mut self) {
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

    pub(super) fn open_plan(&mut self) {
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
