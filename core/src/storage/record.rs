//! Records: one occupancy block or one surface voxel in the snapshot's record layout. A
//! record is what eviction hands out ([`RecordSink`]), what a record stream carries
//! (`stream.rs`) and what [`Map::merge_record`](crate::Map::merge_record) takes in, so
//! one codec serves snapshots, spilling and merging.
//!
//! | record | bytes |
//! |---|---|
//! | block | 142: key (3 x u16, biased by 32768), 64 x i16 log-odds, u64 surface mask |
//! | voxel | 47 + C: key (3 x u16), n (u32), S1 (3 x i32), S2 (6 x i32), vote sampling exponent (u8, <= 15), C x u8 histogram |
//!
//! All little-endian, as in the snapshot (`snapshot.rs`).

use crate::config::{to_fixed, Config};
use crate::error::Error;
use crate::key::{join_key, split_key, KEY_LIMIT};
use crate::storage::block::Block;
use crate::storage::table::Entry;
use crate::storage::votes::MAX_VOTE_EXPONENT;
use crate::storage::voxel::{scatter, Voxel};

/// Bytes of one block record (in a snapshot, a record stream, a spill).
pub const BLOCK_RECORD_BYTES: usize = 142;

/// Bytes of a voxel record before its `C` histogram bytes.
pub const VOXEL_RECORD_HEAD_BYTES: usize = 47;

/// Bytes of the largest voxel record (254 classes), a buffer for any voxel record.
pub(crate) const VOXEL_RECORD_MAX: usize = VOXEL_RECORD_HEAD_BYTES + 255;

/// Which kind of record a [`Record`] holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RecordKind {
    /// An occupancy block: [`BLOCK_RECORD_BYTES`] bytes.
    Block,
    /// A surface voxel: `47 + C` bytes ([`crate::Map::SNAPSHOT_VOXEL_BYTES`]).
    Voxel,
}

/// One block or voxel, as the bytes of its snapshot record. Records borrow a buffer of
/// the map (or of a stream reader) and are only valid during the call that hands them out.
///
/// ```
/// use sndt_core::*;
/// let mut map: Map<64, 16, 4> = Map::new(Config::DEFAULT);
/// let p = [LabeledPoint::new(Point3::new(0.0, 0.0, 1.0), Labels::top1(2)); 3];
/// map.integrate(&Isometry3::identity(), &p).unwrap();
/// let mut kinds = Vec::new();
/// map.write_records(&mut |r: Record<'_>| {
///     kinds.push((r.kind, r.bytes.len()));
///     true
/// });
/// // The voxel first (47 + 4 bytes), then every block (the ray's blocks are free space).
/// assert_eq!(kinds[0], (RecordKind::Voxel, 51));
/// assert!(kinds[1..].iter().all(|&k| k == (RecordKind::Block, BLOCK_RECORD_BYTES)));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Record<'a> {
    /// Block or voxel.
    pub kind: RecordKind,
    /// The record's bytes, in the snapshot's record layout.
    pub bytes: &'a [u8],
}

/// Where evicted records go: the caller's code, given to [`crate::Map::integrate_spilling`]
/// and [`crate::Map::write_records`]. The core calls [`RecordSink::take`] once per record and
/// allocates nothing; a closure `FnMut(Record) -> bool` is a sink.
pub trait RecordSink {
    /// Takes one record (copy the bytes: they are only valid during the call). Returns
    /// `false` when the record cannot be taken (a full queue, a busy link): it is then
    /// lost, and counted in [`crate::FrameReport::records_dropped`].
    fn take(&mut self, record: Record<'_>) -> bool;
}

impl<F: FnMut(Record<'_>) -> bool> RecordSink for F {
    fn take(&mut self, record: Record<'_>) -> bool {
        self(record)
    }
}

pub(crate) struct Writer<'a> {
    pub(crate) buf: &'a mut [u8],
    pub(crate) pos: usize,
}

impl<'a> Writer<'a> {
    /// Appends `bytes`. Callers size the buffer first (`snapshot_len`, fixed records), so
    /// they always fit; were they not to, they are left out instead of halting.
    pub(crate) fn put(&mut self, bytes: &[u8]) {
        let rest = self.buf.get_mut(self.pos..);
        if let Some(dst) = rest.and_then(|r| r.get_mut(..bytes.len())) {
            dst.copy_from_slice(bytes);
            self.pos += bytes.len();
        }
    }

    /// The bytes written so far.
    pub(crate) fn written(self) -> &'a [u8] {
        let Writer { buf, pos } = self;
        buf.get(..pos).unwrap_or(&[])
    }
}

pub(crate) struct Reader<'a> {
    pub(crate) buf: &'a [u8],
    pub(crate) pos: usize,
}

impl Reader<'_> {
    pub(crate) fn take<const N: usize>(&mut self) -> [u8; N] {
        let mut out = [0u8; N];
        if let Some(s) = self.buf.get(self.pos..self.pos + N) {
            out.copy_from_slice(s);
        }
        self.pos += N;
        out
    }
    pub(crate) fn u8(&mut self) -> u8 {
        self.take::<1>()[0]
    }
    pub(crate) fn u16(&mut self) -> u16 {
        u16::from_le_bytes(self.take())
    }
    pub(crate) fn i16(&mut self) -> i16 {
        i16::from_le_bytes(self.take())
    }
    pub(crate) fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take())
    }
    pub(crate) fn i32(&mut self) -> i32 {
        i32::from_le_bytes(self.take())
    }
    pub(crate) fn f32(&mut self) -> f32 {
        f32::from_bits(self.u32())
    }
    pub(crate) fn u64(&mut self) -> u64 {
        u64::from_le_bytes(self.take())
    }
    pub(crate) fn key(&mut self) -> u64 {
        join_key([self.u16(), self.u16(), self.u16()])
    }
}

pub(crate) fn block_record<'a>(b: &Block, out: &'a mut [u8; 160]) -> &'a [u8] {
    let mut w = Writer { buf: out, pos: 0 };
    for k in b.key {
        w.put(&k.to_le_bytes());
    }
    for l in b.cells {
        w.put(&l.to_le_bytes());
    }
    w.put(&b.surface.to_le_bytes());
    w.written()
}

/// A voxel's whole record (head and histogram) in `out`.
pub(crate) fn voxel_record<'a, const C: usize>(
    v: &Voxel<C>,
    out: &'a mut [u8; VOXEL_RECORD_MAX],
) -> &'a [u8] {
    let mut head = [0u8; 160];
    let mut w = Writer { buf: out, pos: 0 };
    w.put(voxel_record_head(v, &mut head));
    w.put(&v.hist);
    w.written()
}

pub(crate) fn voxel_record_head<'a, const C: usize>(
    v: &Voxel<C>,
    out: &'a mut [u8; 160],
) -> &'a [u8] {
    let mut w = Writer { buf: out, pos: 0 };
    for k in v.key {
        w.put(&k.to_le_bytes());
    }
    w.put(&v.n.to_le_bytes());
    for x in v.s1.iter().chain(v.s2.iter()) {
        w.put(&x.to_le_bytes());
    }
    w.put(&[v.vote_exponent()]);
    w.written()
}

/// Cells of packed block `k` outside the key range: blocks at coordinate -8192 hold one
/// layer of cells at key -32768 (one below `-KEY_LIMIT`), which must stay empty.
pub(crate) fn cells_outside_key_range(k: u64) -> u64 {
    let mut outside = 0u64;
    for axis in 0..3 {
        if ((k >> (32 - 16 * axis)) & 0xffff) as i32 - 32768 == -(KEY_LIMIT + 1) / 4 {
            for cell in 0..64u32 {
                if (cell >> (2 * axis)) & 3 == 0 {
                    outside |= 1 << cell;
                }
            }
        }
    }
    outside
}

/// Whether sums `n, S1, S2` can come from points of this map: each within `n` times its
/// largest offset, and a scatter matrix that is positive semi-definite up to the slack
/// decay's rounding allows.
pub(crate) fn sums_possible(n: i64, s1: &[i64; 3], s2: &[i64; 6], qhalf: i64) -> bool {
    let bound1 = n * qhalf;
    let bound2 = n * qhalf * qhalf;
    if s1.iter().any(|x| x.abs() > bound1) || s2.iter().any(|x| x.abs() > bound2) {
        return false;
    }
    // Sums of real points give a positive semi-definite scatter matrix
    // M = n S2 - S1 S1^T. Decay rounds each scaled sum on its own, which can move every
    // entry of M by about n (qhalf + 1/2) (and new points can at most double that before
    // the next decay), so each entry may be off by a slack of 2 n (qhalf + 1). The stored
    // M must then be within the slack of a PSD matrix: diagonals at least -slack, and each
    // off-diagonal, shrunk by the slack, within the geometric mean of the grown diagonals.
    // Anything beyond cannot come from this map.
    let m = scatter(n, s1, s2).map(|x| x as i128);
    let slack = 2 * n as i128 * (qhalf as i128 + 1);
    let (dx, dy, dz) = (m[0] + slack, m[3] + slack, m[5] + slack);
    let off = |x: i128| (x.abs() - slack).max(0);
    let (mxy, mxz, myz) = (off(m[1]), off(m[2]), off(m[4]));
    !(dx < 0
        || dy < 0
        || dz < 0
        || mxy * mxy > dx * dy
        || mxz * mxz > dx * dz
        || myz * myz > dy * dz)
}

/// Whether packed block key `k` is a block of the key range.
pub(crate) fn block_key_ok(k: u64) -> bool {
    (0..3).all(|i| {
        let v = ((k >> (32 - 16 * i)) & 0xffff) as i32 - 32768;
        (-(KEY_LIMIT + 1) / 4..=KEY_LIMIT / 4).contains(&v)
    })
}

/// Whether packed voxel key `k` is in the key range (no component is the unused -32768).
pub(crate) fn voxel_key_ok(k: u64) -> bool {
    (0..3).all(|i| (k >> (32 - 16 * i)) & 0xffff != 0)
}

/// A block record as a [`Block`], after checking it against `config`: a key in range,
/// log-odds within the clamps, nothing in cells outside the key range. The surface mask
/// is kept as stored (a merge sets surface bits from the voxels it holds).
pub(crate) fn decode_block(bytes: &[u8], config: &Config) -> Result<Block, Error> {
    if bytes.len() != BLOCK_RECORD_BYTES {
        return Err(Error::RecordCorrupt);
    }
    let (lo, hi) = (to_fixed(config.clamp_min), to_fixed(config.clamp_max));
    let mut r = Reader { buf: bytes, pos: 0 };
    let k = r.key();
    if !block_key_ok(k) {
        return Err(Error::RecordCorrupt);
    }
    let outside = cells_outside_key_range(k);
    let mut b = Block::new(k);
    for (cell, l) in b.cells.iter_mut().enumerate() {
        *l = r.i16();
        let v = *l as i32;
        if v < lo || v > hi || (v != 0 && outside & (1 << cell) != 0) {
            return Err(Error::RecordCorrupt);
        }
    }
    b.surface = r.u64();
    if b.surface & outside != 0 {
        return Err(Error::RecordCorrupt);
    }
    Ok(b)
}

/// A voxel record as a [`Voxel`], after checking it against `config`: a key in range, a
/// count in `1..=n_max`, sums that points of this config can give, a valid vote exponent.
pub(crate) fn decode_voxel<const C: usize>(
    bytes: &[u8],
    config: &Config,
) -> Result<Voxel<C>, Error> {
    if bytes.len() != VOXEL_RECORD_HEAD_BYTES + C {
        return Err(Error::RecordCorrupt);
    }
    let mut r = Reader { buf: bytes, pos: 0 };
    let k = r.key();
    let mut v = Voxel::<C>::EMPTY;
    v.key = split_key(k);
    v.n = r.u32();
    for x in v.s1.iter_mut().chain(v.s2.iter_mut()) {
        *x = r.i32();
    }
    let exponent = r.u8();
    for x in v.hist.iter_mut() {
        *x = r.u8();
    }
    let qhalf = 1i64 << (config.quant_bits.clamp(1, 6) - 1);
    let (s1, s2) = (v.s1.map(|x| x as i64), v.s2.map(|x| x as i64));
    if !voxel_key_ok(k)
        || v.n == 0
        || v.n > config.n_max
        || exponent > MAX_VOTE_EXPONENT
        || !sums_possible(v.n as i64, &s1, &s2, qhalf)
    {
        return Err(Error::RecordCorrupt);
    }
    v.start_vote_sample(exponent);
    Ok(v)
}
