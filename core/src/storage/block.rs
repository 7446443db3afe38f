//! The occupancy layer: 4x4x4 blocks of fixed-point log-odds for every observed voxel,
//! free or occupied.
//!
//! Free space is most of an indoor map, so it is stored compactly: 64 `i16` log-odds in a
//! block (180 bytes = 2.8 bytes per voxel incl. per-frame bookkeeping and the hash
//! index). A voxel's occupancy lives only here; the surface layer (NDT voxels) holds the
//! Gaussian and the histogram, and a block's `surface` mask says which cells have one.

use crate::key::{join_key, split_key};
use crate::storage::table::Entry;

/// Log-odds value 0 = probability 0.5 = unknown.
pub(crate) const UNKNOWN: i16 = 0;

#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Block {
    /// Fixed-point log-odds per cell (see [`crate::LOGODDS_ONE`]); 0 = unknown.
    pub(crate) cells: [i16; 64],
    /// Cells that have an NDT voxel in the surface layer.
    pub(crate) surface: u64,
    /// Cells that received points in the current frame (valid when `stamp` is current).
    pub(crate) hit: u64,
    /// Cells that already got their one miss in the current frame.
    pub(crate) missed: u64,
    /// Cells where a ray truncated at max range ended in the current frame.
    pub(crate) far: u64,
    pub(crate) chain: u32,
    /// Next block touched by points in this frame (`slot + 1`).
    pub(crate) frame_next: u32,
    pub(crate) key: [u16; 3],
    /// Frame stamp of the per-frame masks (0 = never).
    pub(crate) stamp: u16,
}

impl Entry for Block {
    const EMPTY: Self = Block {
        cells: [UNKNOWN; 64],
        surface: 0,
        hit: 0,
        missed: 0,
        far: 0,
        chain: 0,
        frame_next: 0,
        key: [0; 3],
        stamp: 0,
    };
    #[inline]
    fn packed_key(&self) -> u64 {
        join_key(self.key)
    }
    fn chain(&self) -> u32 {
        self.chain
    }
    fn set_chain(&mut self, next: u32) {
        self.chain = next;
    }
}

impl Block {
    pub(crate) fn new(packed: u64) -> Block {
        let mut b = Block::EMPTY;
        b.key = split_key(packed);
        b
    }

    /// Starts the per-frame masks for frame `stamp` if they belong to an older frame.
    /// Returns true when this is the block's first touch in the frame.
    #[inline]
    pub(crate) fn touch(&mut self, stamp: u16) -> bool {
        if self.stamp == stamp {
            return false;
        }
        self.stamp = stamp;
        self.hit = 0;
        self.missed = 0;
        self.far = 0;
        self.frame_next = 0;
        true
    }

    /// Adds `delta` to a cell's log-odds, clamped to `[lo, hi]`.
    #[inline]
    pub(crate) fn add_logodds(&mut self, cell: u32, delta: i32, lo: i32, hi: i32) {
        let c = &mut self.cells[(cell & 63) as usize];
        // max then min, not clamp: clamp panics when lo > hi, and a halt is worse than a
        // clamp to hi (the config validation keeps lo < hi anyway).
        *c = (*c as i32 + delta).max(lo).min(hi) as i16;
    }
}

/// Indices of the set bits of a cell mask, lowest first.
#[inline]
pub(crate) fn bits(mut mask: u64) -> impl Iterator<Item = u32> {
    core::iter::from_fn(move || {
        if mask == 0 {
            return None;
        }
        let cell = mask.trailing_zeros();
        mask &= mask - 1;
        Some(cell)
    })
}
