//! Frame integration: one frame of labelled points, or a depth image with labels, into the
//! map. [`Map::integrate`] and [`Map::integrate_depth`] run the same steps:
//!
//! 1. **validate the frame** (size, image, pose; an error leaves the map untouched) and
//!    start its state (`frame.rs`);
//! 2. **turn pixels into points** ([`crate::depth_point`], `camera.rs`), for depth images;
//! 3. **accumulate points per end voxel** (`accumulate.rs`): integer sums, histogram votes
//!    of a hashed sample (`votes.rs`), the frame's list of touched blocks;
//! 4. **apply one update per touched voxel**: the list is sorted by key; each hit voxel
//!    decays to `n_max`, gets one hit and sets its vote sampling for the next frame;
//! 5. **free space along the rays** (`free_space.rs`): one ray per unique end voxel and per
//!    unique truncated end, in sorted order, at most one miss per traversed voxel.
//!
//! Points only meet integer sums and per-frame masks before step 4, and steps 4 and 5 go in
//! key order, so the result does not depend on point order.

use crate::block::bits;
use crate::camera::DepthImage;
use crate::config::to_fixed;
use crate::error::Error;
use crate::frame::{FrameReport, FrameState, MAX_FRAME_POINTS};
use crate::key::VoxelKey;
use crate::labels::LabeledPoint;
use crate::map::Map;
use crate::table::{Entry, NIL};
use nalgebra::Isometry3;

impl<const V: usize, const B: usize, const C: usize> Map<V, B, C> {
    /// Integrates one frame of labelled points given in the sensor frame at `pose`
    /// (sensor to world). Per-point problems are counted in the report; a bad pose or an
    /// oversized frame is an error and leaves the map untouched.
    ///
    /// Unless the map had to evict or drop updates during the frame, the result does not
    /// depend on the order of `points`.
    ///
    /// ```
    /// use sndt_core::*;
    /// let mut map: Map<64, 16, 4> = Map::new(Config::DEFAULT);
    /// let pts = [
    ///     LabeledPoint::new(Point3::new(0.0, 0.0, 1.0), Labels::top1(1)),
    ///     LabeledPoint::new(Point3::new(0.0, 0.0, f32::NAN), Labels::top1(1)),
    ///     LabeledPoint::new(Point3::new(0.0, 0.0, 1.0), Labels::top1(9)),
    /// ];
    /// let r = map.integrate(&Isometry3::identity(), &pts).unwrap();
    /// assert_eq!((r.points_used, r.rejected_depth, r.rejected_label), (1, 1, 1));
    /// ```
    pub fn integrate(
        &mut self,
        pose: &Isometry3<f32>,
        points: &[LabeledPoint],
    ) -> Result<FrameReport, Error> {
        if points.len() > MAX_FRAME_POINTS {
            return Err(Error::FrameTooLarge);
        }
        let mut f = self.begin_frame(pose)?;
        for p in points {
            let q = [p.position.x, p.position.y, p.position.z];
            self.add_point(&mut f, q, &p.labels);
        }
        Ok(self.finish(f))
    }

    /// Integrates a depth image with labels (see [`DepthImage`]); invalid depths are
    /// counted in `rejected_depth`.
    pub fn integrate_depth(
        &mut self,
        pose: &Isometry3<f32>,
        image: &DepthImage<'_>,
    ) -> Result<FrameReport, Error> {
        image.validate()?;
        if image.samples() > MAX_FRAME_POINTS {
            return Err(Error::FrameTooLarge);
        }
        let mut f = self.begin_frame(pose)?;
        f.report.rejected_depth += image.for_each_point(|p, l| self.add_point(&mut f, p, &l));
        Ok(self.finish(f))
    }

    /// Steps 4 and 5 after the frame's last point, then the frame's totals.
    fn finish(&mut self, mut f: FrameState) -> FrameReport {
        self.flush_run(&mut f);
        let head = self.sort_frame_list(f.head);
        self.update_end_voxels(&mut f, head);
        self.clear_free_space(&mut f, head);
        self.close_frame(f)
    }

    /// Step 4 along the sorted frame list from `head`: every voxel that received points
    /// decays to `n_max`, ends its vote sample, and gets one hit.
    fn update_end_voxels(&mut self, f: &mut FrameState, head: u32) {
        let cfg = self.config;
        let (lo, hi) = (to_fixed(cfg.clamp_min), to_fixed(cfg.clamp_max));
        let hit = to_fixed(cfg.hit);
        let mut i = head;
        while i != NIL {
            let bs = (i - 1) as usize;
            let b = self.blocks.slots[bs];
            for cell in bits(b.hit) {
                let key = VoxelKey::from_block_cell(b.packed_key(), cell);
                if let Some(vs) = self.voxels.find(key.packed()) {
                    let v = &mut self.voxels.slots[vs];
                    v.decay(cfg.n_max);
                    v.end_vote_sample(cfg.votes_per_frame);
                }
                self.blocks.slots[bs].add_logodds(cell, hit, lo, hi);
                f.report.end_voxels += 1;
            }
            i = b.frame_next;
        }
    }
}
