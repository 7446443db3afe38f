//! Eviction: when a table is full, the entries farthest from the sensor go.
//!
//! Distances (Chebyshev, in blocks or voxels) from the sensor's voxel are binned in a
//! histogram, and whole bins are evicted from the far end until at least 1/16 of the
//! capacity is free. Blocks touched in the current frame and voxels that received points in
//! it stay, so a frame never evicts what it is updating. The result depends only on the
//! map's content and the sensor position, not on table order, and the scan is two passes
//! over the table with a fixed-size histogram (no sorting, no allocation).
//!
//! With a sink ([`Map::integrate_spilling`]) every evicted entry first goes out as a
//! record: an evicted block's voxels, then the block; an evicted voxel on its own.

use crate::integrate::frame::{FrameReport, FrameState};
use crate::key::VoxelKey;
use crate::storage::block::{bits, Block};
use crate::storage::map::Map;
use crate::storage::record::{block_record, voxel_record, Record, RecordKind, VOXEL_RECORD_MAX};
use crate::storage::table::Entry;

impl<const V: usize, const B: usize, const C: usize> Map<V, B, C> {
    /// Evicts occupancy blocks (with their NDT voxels) farthest from the frame's sensor,
    /// not touched in the frame; spills them to the frame's sink. Returns how many blocks
    /// went.
    pub(crate) fn evict_blocks(&mut self, f: &mut FrameState) -> u32 {
        let stamp = f.stamp;
        let c = f.origin_key.block();
        let dist = |b: &Block| block_distance(b.packed_key(), c);
        let mut hist = [0u32; DISTANCE_BINS];
        for b in self.blocks.slots.iter().filter(|b| b.packed_key() != 0) {
            if b.stamp != stamp {
                add(&mut hist, dist(b));
            }
        }
        let Some(threshold) = threshold(&hist, B) else {
            return 0;
        };
        let mut evicted = 0;
        for s in 0..B {
            let Some(&b) = self.blocks.get(s) else {
                break;
            };
            if b.packed_key() == 0 || b.stamp == stamp || bin(dist(&b)) < threshold {
                continue;
            }
            for cell in bits(b.surface) {
                let key = VoxelKey::from_block_cell(b.packed_key(), cell);
                if let Some(v) = self.voxels.find(key.packed()) {
                    self.spill_voxel(f, v);
                    self.voxels.remove(v);
                    self.stats.voxels_evicted += 1;
                }
            }
            if let Some(sink) = f.sink.as_deref_mut() {
                let mut buf = [0u8; 160];
                let record = Record {
                    kind: RecordKind::Block,
                    bytes: block_record(&b, &mut buf),
                };
                count(&mut f.report, sink.take(record));
            }
            self.blocks.remove(s);
            evicted += 1;
        }
        self.stats.blocks_evicted += evicted as u64;
        evicted
    }

    /// Evicts NDT voxels farthest from the frame's sensor that got no points in the frame
    /// (their occupancy stays in the block layer); spills them to the frame's sink.
    /// Returns how many went.
    pub(crate) fn evict_voxels(&mut self, f: &mut FrameState) -> u32 {
        let (center, stamp) = (f.origin_key, f.stamp);
        let center = &center;
        let mut hist = [0u32; DISTANCE_BINS];
        for v in self.voxels.slots.iter().filter(|v| v.packed_key() != 0) {
            let key = v.voxel_key();
            if !self.hit_this_frame(&key, stamp) {
                add(&mut hist, key.chebyshev(center));
            }
        }
        let Some(threshold) = threshold(&hist, V) else {
            return 0;
        };
        let mut evicted = 0;
        for s in 0..V {
            let Some(v) = self.voxels.get(s) else {
                break;
            };
            if v.packed_key() == 0 {
                continue;
            }
            let key = v.voxel_key();
            if bin(key.chebyshev(center)) < threshold || self.hit_this_frame(&key, stamp) {
                continue;
            }
            self.spill_voxel(f, s);
            self.voxels.remove(s);
            let found = self.blocks.find(key.block());
            if let Some(b) = found.and_then(|b| self.blocks.get_mut(b)) {
                b.surface &= !(1u64 << key.cell());
            }
            evicted += 1;
        }
        self.stats.voxels_evicted += evicted as u64;
        evicted
    }

    /// Hands the voxel in slot `s` to the frame's sink, if there is one.
    fn spill_voxel(&self, f: &mut FrameState, s: usize) {
        if let (Some(sink), Some(v)) = (f.sink.as_deref_mut(), self.voxels.get(s)) {
            let mut buf = [0u8; VOXEL_RECORD_MAX];
            let record = Record {
                kind: RecordKind::Voxel,
                bytes: voxel_record(v, &mut buf),
            };
            count(&mut f.report, sink.take(record));
        }
    }

    fn hit_this_frame(&self, key: &VoxelKey, stamp: u16) -> bool {
        match self
            .blocks
            .find(key.block())
            .and_then(|b| self.blocks.get(b))
        {
            Some(b) => b.stamp == stamp && b.hit & (1u64 << key.cell()) != 0,
            None => false,
        }
    }
}

/// Counts a record the sink took or refused.
fn count(report: &mut FrameReport, taken: bool) {
    if taken {
        report.records_spilled += 1;
    } else {
        report.records_dropped += 1;
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

/// Counts distance `d` in its bin of `hist`.
fn add(hist: &mut [u32; DISTANCE_BINS], d: u32) {
    if let Some(count) = hist.get_mut(bin(d)) {
        *count += 1;
    }
}

/// Eviction policy: evict every evictable entry in the farthest distance bins, taking whole
/// bins from the far end until at least 1/16 of the capacity (at least one entry) goes.
/// Returns the first bin to evict, or `None` when nothing is evictable.
fn threshold(hist: &[u32; DISTANCE_BINS], capacity: usize) -> Option<usize> {
    let target = (capacity / 16).max(1) as u32;
    let mut sum = 0u32;
    let mut last = None;
    for (b, &count) in hist.iter().enumerate().rev() {
        if count > 0 {
            sum += count;
            last = Some(b);
            if sum >= target {
                break;
            }
        }
    }
    last
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::*;
    use crate::*;

    /// One frame whose sensor and single point lie in block `b` (h = 1): touches only that
    /// block and creates one voxel at voxel (4 bx + 2, 4 by, 4 bz).
    fn frame_in_block<const V: usize, const B: usize, const C: usize>(
        map: &mut Map<V, B, C>,
        b: [i32; 3],
    ) -> FrameReport {
        let o = [4 * b[0], 4 * b[1], 4 * b[2]].map(|v| v as f32 + 0.5);
        map.integrate(&at(o[0], o[1], o[2]), &[lp(2.0, 0.0, 0.0, 1)])
            .unwrap()
    }

    fn voxel_in_block(b: [i32; 3]) -> VoxelKey {
        key(4 * b[0] as i16 + 2, 4 * b[1] as i16, 4 * b[2] as i16)
    }

    #[test]
    fn block_eviction_takes_whole_farthest_bin() {
        let cfg = Config::with_cell_size(1.0);
        let mut map: Map<16, 4, 1> = Map::try_new(cfg).unwrap();
        let far = [[1, 0, 0], [0, 2, 0], [0, 0, 3], [-3, 1, 0]];
        for b in far {
            let r = frame_in_block(&mut map, b);
            assert_eq!(
                (r.blocks_created, r.voxels_created, r.points_used),
                (1, 1, 1)
            );
        }
        assert_eq!(map.block_count(), 4);
        // Frame at block 0: table full, the two blocks at Chebyshev block distance 3 go
        // (whole bin), although one would be enough (target max(4/16, 1) = 1).
        let r = frame_in_block(&mut map, [0, 0, 0]);
        assert_eq!((r.blocks_evicted, r.voxels_evicted), (2, 2));
        assert_eq!(map.stats().blocks_evicted, 2);
        assert_eq!(map.stats().voxels_evicted, 2);
        assert_eq!(map.block_count(), 3);
        assert_eq!(map.len(), 3);
        for (b, kept) in far.iter().zip([true, true, false, false]) {
            let k = voxel_in_block(*b);
            assert_eq!(map.gaussian(&k).is_some(), kept, "{b:?}");
            assert_eq!(map.occupancy(&k) == Occupancy::Occupied, kept, "{b:?}");
        }
        assert!(map.gaussian(&voxel_in_block([0, 0, 0])).is_some());
    }

    #[test]
    fn block_eviction_bins_are_64_wide_beyond_255() {
        let cfg = Config::with_cell_size(1.0);
        let mut map: Map<16, 4, 1> = Map::try_new(cfg).unwrap();
        // Distances 1, 300, 310, 330 from block 0: bins 1, 256, 256, 257.
        let blocks = [[1, 0, 0], [300, 0, 0], [0, -310, 0], [0, 0, 330]];
        for b in blocks {
            frame_in_block(&mut map, b);
        }
        let r = frame_in_block(&mut map, [0, 0, 0]);
        assert_eq!(r.blocks_evicted, 1);
        assert!(map.gaussian(&voxel_in_block([0, 0, 330])).is_none());
        assert!(map.gaussian(&voxel_in_block([300, 0, 0])).is_some());
        // Next new block: 300 and 310 share bin 256 and go together.
        let r = frame_in_block(&mut map, [0, 1, 1]);
        assert_eq!(r.blocks_evicted, 2);
        assert!(map.gaussian(&voxel_in_block([300, 0, 0])).is_none());
        assert!(map.gaussian(&voxel_in_block([0, -310, 0])).is_none());
        assert!(map.gaussian(&voxel_in_block([1, 0, 0])).is_some());
        assert_eq!(map.stats().blocks_evicted, 3);
    }

    #[test]
    fn nothing_touched_this_frame_is_evicted() {
        let cfg = Config::with_cell_size(1.0);
        // One block: a frame whose points span two blocks drops the second.
        let mut map: Map<16, 1, 1> = Map::try_new(cfg).unwrap();
        let pts = [lp(1.0, 0.0, 0.0, 1), lp(5.0, 0.0, 0.0, 1)];
        let r = map.integrate(&at(0.5, 0.5, 0.5), &pts).unwrap();
        assert_eq!((r.points_used, r.dropped_points), (1, 1));
        assert_eq!((r.blocks_evicted, r.voxels_evicted), (0, 0));
        assert_eq!(map.stats().dropped_points, 1);
        // A ray needing a block that does not fit drops its misses, counted.
        let mut map: Map<16, 1, 1> = Map::try_new(cfg).unwrap();
        let r = map
            .integrate(&at(0.5, 0.5, 0.5), &[lp(6.0, 0.0, 0.0, 1)])
            .unwrap();
        assert_eq!(r.points_used, 1);
        assert_eq!(r.dropped_misses, 4); // voxels 0..=3 of the ray: block 0 does not fit
        assert_eq!(map.stats().dropped_misses, 4);
        // One voxel: a second voxel in the same frame is dropped (the first was hit).
        let mut map: Map<1, 16, 1> = Map::try_new(cfg).unwrap();
        let r = map.integrate(&at(0.5, 0.5, 0.5), &pts).unwrap();
        assert_eq!(
            (r.points_used, r.dropped_points, r.voxels_evicted),
            (1, 1, 0)
        );
    }

    #[test]
    fn voxel_eviction_farthest_bin_keeps_occupancy() {
        let cfg = Config::with_cell_size(1.0);
        let mut map: Map<4, 64, 1> = Map::try_new(cfg).unwrap();
        let sensor = at(0.5, 0.5, 0.5);
        // Voxels at Chebyshev distance 1, 2, 3, 3 from the sensor voxel.
        let pts = [
            [1.0, 0.0, 0.0],
            [0.0, 2.0, 0.0],
            [0.0, 0.0, 3.0],
            [-3.0, 0.0, 0.0],
        ];
        for p in pts {
            map.integrate(&sensor, &[lp(p[0], p[1], p[2], 1)]).unwrap();
        }
        assert_eq!(map.len(), 4);
        let r = map.integrate(&sensor, &[lp(1.0, 1.0, 0.0, 1)]).unwrap();
        assert_eq!(
            (r.voxels_evicted, r.blocks_evicted, r.points_used),
            (2, 0, 1)
        );
        assert_eq!(map.len(), 3);
        for (p, kept) in pts.iter().zip([true, true, false, false]) {
            let k = key(p[0] as i16, p[1] as i16, p[2] as i16);
            assert_eq!(map.gaussian(&k).is_some(), kept, "{p:?}");
            // Occupancy stays in the block layer.
            assert_eq!(map.occupancy(&k), Occupancy::Occupied, "{p:?}");
            // The block's surface mask agrees with the surface layer.
            let b = map.blocks.find(k.block()).unwrap();
            assert_eq!(map.blocks.slots[b].surface >> k.cell() & 1 == 1, kept);
        }
    }
}
