//! Eviction: when a table is full, the entries farthest from the sensor go.
//!
//! Distances (Chebyshev, in blocks or voxels) from the sensor's voxel are binned in a
//! histogram, and whole bins are evicted from the far end until at least 1/16 of the
//! capacity is free. Blocks touched in the current frame and voxels that received points in
//! it stay, so a frame never evicts what it is updating. The result depends only on the
//! map's content and the sensor position, not on table order, and the scan is two passes
//! over the table with a fixed-size histogram (no sorting, no allocation).

use crate::block::{bits, Block};
use crate::key::VoxelKey;
use crate::map::Map;
use crate::table::Entry;

impl<const V: usize, const B: usize, const C: usize> Map<V, B, C> {
    /// Evicts occupancy blocks (with their NDT voxels) farthest from `center`, not touched
    /// in frame `stamp`. Returns how many blocks went.
    pub(crate) fn evict_blocks(&mut self, center: &VoxelKey, stamp: u16) -> u32 {
        let c = center.block();
        let dist = |b: &Block| block_distance(b.packed_key(), c);
        let mut hist = [0u32; DISTANCE_BINS];
        for s in self.blocks.live() {
            let b = &self.blocks.slots[s];
            if b.stamp != stamp {
                hist[bin(dist(b))] += 1;
            }
        }
        let Some(threshold) = threshold(&hist, B) else {
            return 0;
        };
        let mut evicted = 0;
        for s in 0..B {
            let b = self.blocks.slots[s];
            if b.packed_key() == 0 || b.stamp == stamp || bin(dist(&b)) < threshold {
                continue;
            }
            for cell in bits(b.surface) {
                let key = VoxelKey::from_block_cell(b.packed_key(), cell);
                if let Some(v) = self.voxels.find(key.packed()) {
                    self.voxels.remove(v);
                    self.stats.voxels_evicted += 1;
                }
            }
            self.blocks.remove(s);
            evicted += 1;
        }
        self.stats.blocks_evicted += evicted as u64;
        evicted
    }

    /// Evicts NDT voxels farthest from `center` that got no points in frame `stamp`; their
    /// occupancy stays in the block layer. Returns how many went.
    pub(crate) fn evict_voxels(&mut self, center: &VoxelKey, stamp: u16) -> u32 {
        let mut hist = [0u32; DISTANCE_BINS];
        for s in self.voxels.live() {
            let key = self.voxels.slots[s].voxel_key();
            if !self.hit_this_frame(&key, stamp) {
                hist[bin(key.chebyshev(center))] += 1;
            }
        }
        let Some(threshold) = threshold(&hist, V) else {
            return 0;
        };
        let mut evicted = 0;
        for s in 0..V {
            let v = &self.voxels.slots[s];
            if v.packed_key() == 0 {
                continue;
            }
            let key = v.voxel_key();
            if bin(key.chebyshev(center)) < threshold || self.hit_this_frame(&key, stamp) {
                continue;
            }
            self.voxels.remove(s);
            if let Some(b) = self.blocks.find(key.block()) {
                self.blocks.slots[b].surface &= !(1u64 << key.cell());
            }
            evicted += 1;
        }
        self.stats.voxels_evicted += evicted as u64;
        evicted
    }

    fn hit_this_frame(&self, key: &VoxelKey, stamp: u16) -> bool {
        match self.blocks.find(key.block()) {
            Some(b) => {
                let b = &self.blocks.slots[b];
                b.stamp == stamp && b.hit & (1u64 << key.cell()) != 0
            }
            None => false,
        }
    }
}

/// Distance histogram resolution for eviction.
const DISTANCE_BINS: usize = 512;

/// Distance bins: exact up to 255, then 64 wide, last bin open-ended.
fn bin(d: u32) -> usize {
    if d < 256 {
        d as usize
    } else {
        (256 + (d - 256) / 64).min(DISTANCE_BINS as u32 - 1) as usize
    }
}

/// Chebyshev distance of two packed block keys, in blocks.
fn block_distance(a: u64, b: u64) -> u32 {
    let d = |s: u32| (((a >> s) & 0xffff) as i32 - ((b >> s) & 0xffff) as i32).unsigned_abs();
    d(32).max(d(16)).max(d(0))
}

/// Eviction policy: evict every evictable entry in the farthest distance bins, taking whole
/// bins from the far end until at least 1/16 of the capacity (at least one entry) goes.
/// Returns the first bin to evict, or `None` when nothing is evictable.
fn threshold(hist: &[u32; DISTANCE_BINS], capacity: usize) -> Option<usize> {
    let target = (capacity / 16).max(1) as u32;
    let mut sum = 0u32;
    let mut last = None;
    for b in (0..DISTANCE_BINS).rev() {
        if hist[b] > 0 {
            sum += hist[b];
            last = Some(b);
            if sum >= target {
                break;
            }
        }
    }
    last
}
