//! Merging: records ([`Map::merge_record`]) or a whole map ([`Map::merge`]) into a map, and
//! a map written out as records ([`Map::write_records`]).
//!
//! A merge adds what two maps observed, field by field, under the rules of the update:
//!
//! - **Surface voxels** (same key): the point sums `n, S1, S2` add exactly, then decay to
//!   `n_max` as at the end of a frame (halve `n` until it fits, scale the sums). Rounding
//!   can leave the scatter `n S2 - S1 S1^T` a hair outside the positive semi-definite
//!   cone; the merge then moves `S2` to its edge (variances at least 0, each covariance
//!   within the geometric mean of its variances), so a merged map always loads from its
//!   snapshot. The class histograms add bin by bin; if a bin would pass 255, every bin of
//!   the sum is halved (once suffices: two bins sum to at most 510). The vote sampling
//!   exponent is the larger of the two.
//! - **Occupancy** (same block): the fixed-point log-odds of each cell add and are clamped
//!   to `[clamp_min, clamp_max]`, as every hit and miss is. Surface bits follow the
//!   voxels: a block's bit is set where the merged map holds a voxel.
//! - **Keys only one side has** are copied unchanged, so merging maps with disjoint keys
//!   gives exactly their union, and merging an empty map changes nothing.
//! - **Frames**: [`Map::merge`] adds the other map's frame count.
//!
//! Merging is deterministic: the same records in the same order give the same bits on
//! every target. It differs from integrating both maps' frames into one map where the
//! update is not additive: a clamped log-odds value forgets the updates beyond the clamp
//! (one map at `clamp_max` plus another's misses ends lower than a joint run in which the
//! misses came first), a decay that happens once per frame in a joint run happens once
//! per merge here, and histogram halving happens at other moments.
//!
//! Before it changes anything a merge checks its input (a typed [`Error`], map untouched):
//! a record against the map's config ([`Error::RecordCorrupt`]), the other map's config
//! ([`Error::ConfigMismatch`]), and the room it needs ([`Error::MapFull`]).

use crate::config::to_fixed;
use crate::error::Error;
use crate::key::VoxelKey;
use crate::storage::block::{bits, Block};
use crate::storage::map::Map;
use crate::storage::record::{
    block_record, decode_block, decode_voxel, voxel_record, Record, RecordKind, RecordSink,
    VOXEL_RECORD_MAX,
};
use crate::storage::table::Entry;
use crate::storage::voxel::{scatter, Voxel};

/// What [`Map::write_records`] handed out.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RecordCount {
    /// Records the sink took.
    pub taken: u32,
    /// Records the sink refused.
    pub refused: u32,
}

impl<const V: usize, const B: usize, const C: usize> Map<V, B, C> {
    /// Hands the whole map to `sink` as records: every voxel, then every block, each in
    /// canonical order (by key hash, then key; the order of the snapshot). Merging them,
    /// in this order, into a map is what [`Map::merge`] does. The map is unchanged.
    ///
    /// ```
    /// use sndt_core::*;
    /// let mut map: Map<64, 16, 4> = Map::new(Config::DEFAULT);
    /// let p = [LabeledPoint::new(Point3::new(0.0, 0.0, 1.0), Labels::top1(2)); 3];
    /// map.integrate(&Isometry3::identity(), &p).unwrap();
    /// let mut copy: Map<64, 16, 4> = Map::new(Config::DEFAULT);
    /// let sent = map.write_records(&mut |r: Record<'_>| copy.merge_record(r).is_ok());
    /// assert_eq!(sent.taken as usize, map.len() + map.block_count());
    /// copy.add_frames(map.stats().frames);
    /// assert_eq!(copy.checksum(), map.checksum());
    /// ```
    pub fn write_records(&self, sink: &mut dyn RecordSink) -> RecordCount {
        let mut count = RecordCount::default();
        let mut buf = [0u8; 160];
        let mut voxel = [0u8; VOXEL_RECORD_MAX];
        for v in self.voxels.canonical().filter_map(|s| self.voxels.get(s)) {
            let taken = sink.take(Record {
                kind: RecordKind::Voxel,
                bytes: voxel_record(v, &mut voxel),
            });
            count.add(taken);
        }
        for b in self.blocks.canonical().filter_map(|s| self.blocks.get(s)) {
            let taken = sink.take(Record {
                kind: RecordKind::Block,
                bytes: block_record(b, &mut buf),
            });
            count.add(taken);
        }
        count
    }

    /// Merges one record (a spilled voxel or block, a record of another map) into the map,
    /// by the rules of the module doc. A voxel whose block is missing brings an empty block
    /// (unknown occupancy) that its block's record fills in later.
    ///
    /// Errors, with the map unchanged: [`Error::RecordCorrupt`] for a record of the wrong
    /// length or one this map's config cannot hold (a key out of range, a count above
    /// `n_max`, impossible sums, log-odds outside the clamps); [`Error::MapFull`] when it
    /// needs a new voxel or block and the table is full.
    ///
    /// ```
    /// use sndt_core::*;
    /// let mut a: Map<64, 16, 4> = Map::new(Config::DEFAULT);
    /// let p = [LabeledPoint::new(Point3::new(0.0, 0.0, 1.0), Labels::top1(2)); 3];
    /// a.integrate(&Isometry3::identity(), &p).unwrap();
    /// let mut b: Map<64, 16, 4> = Map::new(Config::DEFAULT);
    /// a.write_records(&mut |r: Record<'_>| b.merge_record(r).is_ok());
    /// a.write_records(&mut |r: Record<'_>| b.merge_record(r).is_ok());
    /// let key = a.voxel_key(&[0.0, 0.0, 1.0]).unwrap();
    /// assert_eq!(b.gaussian(&key).unwrap().count, 6); // the points add
    /// let bad = Record { kind: RecordKind::Block, bytes: &[0u8; 7] };
    /// assert_eq!(b.merge_record(bad), Err(Error::RecordCorrupt));
    /// ```
    pub fn merge_record(&mut self, record: Record<'_>) -> Result<(), Error> {
        match record.kind {
            RecordKind::Voxel => {
                let v = decode_voxel::<C>(record.bytes, &self.config)?;
                let key = v.voxel_key();
                if self.voxels.find(key.packed()).is_none()
                    && (self.voxels.is_full()
                        || (self.blocks.find(key.block()).is_none() && self.blocks.is_full()))
                {
                    return Err(Error::MapFull);
                }
                self.merge_voxel(&v);
            }
            RecordKind::Block => {
                let b = decode_block(record.bytes, &self.config)?;
                if self.blocks.find(b.packed_key()).is_none() && self.blocks.is_full() {
                    return Err(Error::MapFull);
                }
                self.merge_block(&b);
            }
        }
        Ok(())
    }

    /// Checks a record as [`Map::merge_record`] would, without merging it: `Ok` when it is
    /// a valid record for this map's config (room is not checked).
    ///
    /// ```
    /// use sndt_core::*;
    /// let map: Map<64, 16, 4> = Map::new(Config::DEFAULT);
    /// let bad = Record { kind: RecordKind::Voxel, bytes: &[0u8; 51] }; // count 0
    /// assert_eq!(map.check_record(bad), Err(Error::RecordCorrupt));
    /// ```
    pub fn check_record(&self, record: Record<'_>) -> Result<(), Error> {
        match record.kind {
            RecordKind::Voxel => decode_voxel::<C>(record.bytes, &self.config).map(|_| ()),
            RecordKind::Block => decode_block(record.bytes, &self.config).map(|_| ()),
        }
    }

    /// Merges `other` into the map: its records in the order of [`Map::write_records`], and
    /// its frame count. Both maps need the same config ([`Error::ConfigMismatch`]) and the
    /// map room for the union ([`Error::MapFull`]); on an error nothing is merged.
    ///
    /// ```
    /// use sndt_core::*;
    /// let pts = |x: f32| [LabeledPoint::new(Point3::new(x, 0.0, 1.0), Labels::top1(2)); 3];
    /// let mut a: Map<64, 16, 4> = Map::new(Config::DEFAULT);
    /// a.integrate(&Isometry3::identity(), &pts(0.0)).unwrap();
    /// let mut b: Map<64, 16, 4> = Map::new(Config::DEFAULT);
    /// b.integrate(&Isometry3::identity(), &pts(0.5)).unwrap();
    /// a.merge(&b).unwrap();
    /// assert_eq!((a.len(), a.stats().frames), (2, 2));
    /// let other: Map<64, 16, 4> = Map::new(Config::with_cell_size(0.2));
    /// assert_eq!(a.merge(&other), Err(Error::ConfigMismatch));
    /// ```
    pub fn merge<const V2: usize, const B2: usize>(
        &mut self,
        other: &Map<V2, B2, C>,
    ) -> Result<(), Error> {
        if other.config != self.config {
            return Err(Error::ConfigMismatch);
        }
        let new_voxels = other
            .voxels
            .live()
            .filter_map(|s| other.voxels.get(s))
            .filter(|v| self.voxels.find(v.packed_key()).is_none())
            .count();
        // Every voxel of a map has its block there, so the new blocks are `other`'s.
        let new_blocks = other
            .blocks
            .live()
            .filter_map(|s| other.blocks.get(s))
            .filter(|b| self.blocks.find(b.packed_key()).is_none())
            .count();
        if self.len() + new_voxels > V || self.block_count() + new_blocks > B {
            return Err(Error::MapFull);
        }
        for v in other.voxels.canonical().filter_map(|s| other.voxels.get(s)) {
            self.merge_voxel(v);
        }
        for b in other.blocks.canonical().filter_map(|s| other.blocks.get(s)) {
            self.merge_block(b);
        }
        self.add_frames(other.stats.frames);
        Ok(())
    }

    /// Counts `frames` more frames integrated, for frames merged as records (a record
    /// stream's end says how many its maps integrated); [`Map::merge`] does this itself.
    ///
    /// ```
    /// let mut map: sndt_core::Map<16, 4, 2> = sndt_core::Map::new(sndt_core::Config::DEFAULT);
    /// map.add_frames(7);
    /// assert_eq!(map.stats().frames, 7);
    /// ```
    pub fn add_frames(&mut self, frames: u32) {
        self.stats.frames = self.stats.frames.wrapping_add(frames);
        // A frame stamp is the frame count modulo 65535: after a jump, an old block's stamp
        // could look current. Forget them (only the per-frame masks depend on them).
        for b in self.blocks.slots.iter_mut() {
            b.stamp = 0;
        }
    }

    /// Merges a checked voxel; the caller made sure it fits.
    fn merge_voxel(&mut self, v: &Voxel<C>) {
        let key = v.voxel_key();
        let cfg = self.config;
        match self.voxels.find(key.packed()) {
            Some(s) => {
                if let Some(t) = self.voxels.get_mut(s) {
                    combine(t, v, cfg.n_max, 1i64 << (cfg.quant_bits.clamp(1, 6) - 1));
                }
            }
            None => {
                let mut copy = *v;
                copy.chain = 0;
                let _ = self.voxels.insert(copy);
            }
        }
        let bs = match self.blocks.find(key.block()) {
            Some(bs) => Some(bs),
            None => self.blocks.insert(Block::new(key.block())).ok(),
        };
        if let Some(b) = bs.and_then(|bs| self.blocks.get_mut(bs)) {
            b.surface |= 1u64 << key.cell();
        }
    }

    /// Merges a checked block; the caller made sure it fits.
    fn merge_block(&mut self, b: &Block) {
        let (lo, hi) = (
            to_fixed(self.config.clamp_min),
            to_fixed(self.config.clamp_max),
        );
        let packed = b.packed_key();
        if let Some(t) = self
            .blocks
            .find(packed)
            .and_then(|s| self.blocks.get_mut(s))
        {
            for (cell, &l) in b.cells.iter().enumerate() {
                t.add_logodds(cell as u32, l as i32, lo, hi);
            }
            return;
        }
        let mut copy = Block::new(packed);
        copy.cells = b.cells;
        // Surface bits say where this map holds a voxel (none of a new block's, unless
        // its voxels came first).
        for cell in bits(b.surface) {
            let key = VoxelKey::from_block_cell(packed, cell);
            if self.voxels.find(key.packed()).is_some() {
                copy.surface |= 1u64 << cell;
            }
        }
        let _ = self.blocks.insert(copy);
    }
}

impl RecordCount {
    fn add(&mut self, taken: bool) {
        if taken {
            self.taken += 1;
        } else {
            self.refused += 1;
        }
    }
}

/// Adds voxel `v` into `t`: sums, then decay to `n_max` and the scatter kept positive
/// semi-definite; histograms add (halved when a bin passes 255); the larger vote exponent.
fn combine<const C: usize>(t: &mut Voxel<C>, v: &Voxel<C>, n_max: u32, qhalf: i64) {
    t.n = t.n.wrapping_add(v.n);
    for (a, b) in t.s1.iter_mut().zip(v.s1.iter()) {
        *a = a.wrapping_add(*b);
    }
    for (a, b) in t.s2.iter_mut().zip(v.s2.iter()) {
        *a = a.wrapping_add(*b);
    }
    t.decay(n_max);
    settle_scatter(t, qhalf);
    let over = t
        .hist
        .iter()
        .zip(v.hist.iter())
        .any(|(&a, &b)| a as u32 + b as u32 > 255);
    for (a, &b) in t.hist.iter_mut().zip(v.hist.iter()) {
        let sum = *a as u32 + b as u32;
        *a = if over { sum / 2 } else { sum } as u8;
    }
    let exponent = t.vote_exponent().max(v.vote_exponent());
    t.start_vote_sample(exponent);
}

/// Moves `S2` (never `n` or `S1`) the least so that the scatter `M = n S2 - S1 S1^T` has
/// variances `M_ii >= 0` and covariances `|M_ij| <= sqrt(M_ii M_jj)`. Sums of real points
/// already satisfy this; decay's rounding in a merge may not, by a few quanta.
fn settle_scatter<const C: usize>(v: &mut Voxel<C>, qhalf: i64) {
    let n = v.n.max(1) as i64;
    let s1 = v.s1.map(|x| x as i64);
    let at = |a: &[i64; 6], k: usize| a.get(k).copied().unwrap_or(0);
    let bound = n * qhalf * qhalf;
    // Diagonal entries xx, yy, zz sit at 0, 3, 5 of S2.
    for (k, i) in [(0, 0), (3, 1), (5, 2)] {
        let s1i = s1.get(i).copied().unwrap_or(0);
        if let Some(s) = v.s2.get_mut(k)
            && n * (*s as i64) < s1i * s1i
        {
            *s = (s1i * s1i + n - 1).div_euclid(n).min(bound) as i32;
        }
    }
    let m = scatter(n, &s1, &v.s2.map(|x| x as i64));
    let var = |k: usize| at(&m, k).max(0) as u128;
    for (k, i, j, d) in [
        (1, 0, 1, var(0) * var(3)),
        (2, 0, 2, var(0) * var(5)),
        (4, 1, 2, var(3) * var(5)),
    ] {
        // sqrt of a product of two variances below 2^43 each: fits i64.
        let lim = d.isqrt() as i64;
        let p = s1.get(i).copied().unwrap_or(0) * s1.get(j).copied().unwrap_or(0);
        let cur = at(&m, k);
        if let Some(s) = v.s2.get_mut(k) {
            if cur > lim {
                *s = (p + lim).div_euclid(n) as i32;
            } else if cur < -lim {
                *s = -(lim - p).div_euclid(n) as i32;
            }
        }
    }
}
