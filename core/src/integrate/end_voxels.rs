//! Phase 2 of a frame ([`Phase::EndVoxels`](crate::Phase::EndVoxels)): one update per
//! voxel that received points, along the frame list sorted by key.

use crate::config::to_fixed;
use crate::integrate::frame::FrameState;
use crate::key::VoxelKey;
use crate::storage::block::bits;
use crate::storage::map::Map;
use crate::storage::table::Entry;

impl<const V: usize, const B: usize, const C: usize> Map<V, B, C> {
    /// Phase 2 along the sorted frame list from `head`: every voxel that received points
    /// decays to `n_max`, ends its vote sample, and gets one hit.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    pub(crate) fn update_end_voxels(&mut self, f: &mut FrameState, head: u32) {
        let cfg = self.config;
        let (lo, hi) = (to_fixed(cfg.clamp_min), to_fixed(cfg.clamp_max));
        let hit = to_fixed(cfg.hit);
        self.for_each_frame_block(head, |map, bs, b| {
            for cell in bits(b.hit) {
                let key = VoxelKey::from_block_cell(b.packed_key(), cell);
                let found = map.voxels.find(key.packed());
                if let Some(v) = found.and_then(|vs| map.voxels.get_mut(vs)) {
                    v.decay(cfg.n_max);
                    v.end_vote_sample(cfg.votes_per_frame);
                }
                if let Some(b) = map.blocks.get_mut(bs) {
                    b.add_logodds(cell, hit, lo, hi);
                }
                f.report.end_voxels += 1;
            }
        });
    }
}
