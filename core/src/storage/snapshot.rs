//! Snapshot: a versioned little-endian image of the map with a CRC-32, written into and
//! read from a caller's buffer.
//!
//! Layout (all little-endian):
//!
//! | bytes | field |
//! |---|---|
//! | 4 | magic `SNDT` |
//! | 2 | version ([`SNAPSHOT_VERSION`]) |
//! | 2 | classes `C` |
//! | 4 + 4 | voxel and block capacity of the writer |
//! | 60 | config: cell_size, eigen_ratio, hit, miss, clamp_min, clamp_max, lambda, noise_base, noise_quadratic, max_range, render_radius (f32 bits), n_min, n_max (u32), quant_bits, top_k, min_score, miss_model, votes_per_frame (u8), see_through_miss (i16, in 1/1024 log-odds), 1 zero byte |
//! | 4 | frames integrated |
//! | 4 + 4 | block count, voxel count |
//! | 142 each | blocks: key (3 x u16, biased by 32768), 64 x i16 log-odds, u64 surface mask |
//! | 47 + C each | voxels: key (3 x u16), n (u32), S1 (3 x i32), S2 (6 x i32), vote sampling exponent (u8, <= 15), C x u8 histogram |
//! | 4 | CRC-32 (IEEE) of everything before |
//!
//! `see_through_miss` sits in what were zero bytes before it existed: a snapshot written
//! then reads as a map with the see-through miss off, the S-NDT it was built with.
//!
//! Blocks and voxels appear in canonical order (by key hash, then key), so equal maps give
//! equal bytes whatever order they were built in, and duplicates are detectable.
//!
//! The header is read and written in one place, [`SnapshotHeader`], which
//! [`Map::read_snapshot`] and [`Map::write_snapshot`] use too: code outside the core reads
//! a snapshot's config or frame count through it, never by byte offset.

use crate::config::{to_fixed, Config, MissModel, LOGODDS_ONE};
use crate::crc::{crc32, Crc32};
use crate::error::Error;
use crate::key::{order, split_key, VoxelKey};
use crate::storage::block::Block;
use crate::storage::map::{Map, MapStats};
use crate::storage::record::{
    block_key_ok, block_record, cells_outside_key_range, sums_possible, voxel_record_head, Reader,
    Writer, BLOCK_RECORD_BYTES, VOXEL_RECORD_HEAD_BYTES,
};
use crate::storage::table::Entry;
use crate::storage::votes::MAX_VOTE_EXPONENT;
use crate::storage::voxel::Voxel;

/// Snapshot format version written by this build.
pub const SNAPSHOT_VERSION: u16 = 2;
/// Bytes before the first block record.
pub const SNAPSHOT_HEADER_BYTES: usize = 88;
/// Bytes of one block record.
pub const SNAPSHOT_BLOCK_BYTES: usize = BLOCK_RECORD_BYTES;
const MAGIC: &[u8; 4] = b"SNDT";

impl<const V: usize, const B: usize, const C: usize> Map<V, B, C> {
    /// Bytes of one voxel record in a snapshot.
    pub const SNAPSHOT_VOXEL_BYTES: usize = VOXEL_RECORD_HEAD_BYTES + C;

    /// Exact length of this map's snapshot.
    pub fn snapshot_len(&self) -> usize {
        SNAPSHOT_HEADER_BYTES
            + self.blocks.len() * SNAPSHOT_BLOCK_BYTES
            + self.voxels.len() * Self::SNAPSHOT_VOXEL_BYTES
            + 4
    }

    /// Writes the snapshot into `buf` and returns its length, or
    /// [`Error::BufferTooSmall`] (nothing written).
    ///
    /// ```
    /// use sndt_core::*;
    /// let mut map: Map<64, 16, 4> = Map::new(Config::DEFAULT);
    /// let p = [LabeledPoint::new(Point3::new(0.0, 0.0, 1.0), Labels::top1(2)); 5];
    /// map.integrate(&Isometry3::identity(), &p).unwrap();
    /// let mut buf = [0u8; 4096];
    /// let n = map.write_snapshot(&mut buf).unwrap();
    /// let mut copy: Map<64, 16, 4> = Map::new(Config::DEFAULT);
    /// copy.read_snapshot(&buf[..n]).unwrap();
    /// let mut buf2 = [0u8; 4096];
    /// assert_eq!(copy.write_snapshot(&mut buf2), Ok(n));
    /// assert_eq!(buf[..n], buf2[..n]);
    /// buf[40] ^= 1;
    /// assert_eq!(copy.read_snapshot(&buf[..n]), Err(Error::SnapshotChecksum));
    /// ```
    pub fn write_snapshot(&self, buf: &mut [u8]) -> Result<usize, Error> {
        let len = self.snapshot_len();
        if buf.len() < len {
            return Err(Error::BufferTooSmall);
        }
        let mut w = Writer { buf, pos: 0 };
        let mut hdr = [0u8; SNAPSHOT_HEADER_BYTES];
        self.snapshot_header().encode(&mut hdr);
        w.put(&hdr);
        let mut chunk = [0u8; 160];
        for b in self.blocks.canonical().filter_map(|s| self.blocks.get(s)) {
            w.put(block_record(b, &mut chunk));
        }
        for v in self.voxels.canonical().filter_map(|s| self.voxels.get(s)) {
            w.put(voxel_record_head(v, &mut chunk));
            w.put(&v.hist);
        }
        let crc = crc32(w.buf.get(..w.pos).unwrap_or(&[]));
        w.put(&crc.to_le_bytes());
        Ok(w.pos)
    }

    /// CRC-32 of the map's snapshot, computed without a buffer (the last four bytes
    /// [`Map::write_snapshot`] writes). Equal maps have equal checksums on every target.
    pub fn checksum(&self) -> u32 {
        let mut crc = Crc32::new();
        let mut chunk = [0u8; 160];
        // Header and records are streamed through a small stack buffer.
        let mut hdr = [0u8; SNAPSHOT_HEADER_BYTES];
        self.snapshot_header().encode(&mut hdr);
        crc.update(&hdr);
        for b in self.blocks.canonical().filter_map(|s| self.blocks.get(s)) {
            crc.update(block_record(b, &mut chunk));
        }
        for v in self.voxels.canonical().filter_map(|s| self.voxels.get(s)) {
            crc.update(voxel_record_head(v, &mut chunk));
            crc.update(&v.hist);
        }
        crc.finish()
    }

    /// The header of this map's snapshot.
    pub(crate) fn snapshot_header(&self) -> SnapshotHeader {
        SnapshotHeader {
            classes: C as u16,
            voxel_capacity: V as u32,
            block_capacity: B as u32,
            config: self.config,
            frames: self.stats.frames,
            blocks: self.blocks.len() as u32,
            voxels: self.voxels.len() as u32,
        }
    }

    /// Replaces the map's content with a snapshot. The whole snapshot is checked first
    /// (length, magic, version, class count, capacity, CRC, then every record's
    /// invariants); on any error the map is left exactly as it was.
    pub fn read_snapshot(&mut self, buf: &[u8]) -> Result<(), Error> {
        let (config, frames, nb, nv) = Self::validate_snapshot(buf)?;
        self.voxels.clear();
        self.blocks.clear();
        self.config = config;
        self.stats = MapStats {
            frames,
            ..Default::default()
        };
        let mut r = Reader {
            buf,
            pos: SNAPSHOT_HEADER_BYTES,
        };
        for _ in 0..nb {
            let mut b = Block::new(r.key());
            for l in b.cells.iter_mut() {
                *l = r.i16();
            }
            b.surface = r.u64();
            let _ = self.blocks.insert(b);
        }
        for _ in 0..nv {
            let mut v = Voxel::<C>::EMPTY;
            v.key = split_key(r.key());
            v.n = r.u32();
            for x in v.s1.iter_mut() {
                *x = r.i32();
            }
            for x in v.s2.iter_mut() {
                *x = r.i32();
            }
            v.start_vote_sample(r.u8());
            for x in v.hist.iter_mut() {
                *x = r.u8();
            }
            let _ = self.voxels.insert(v);
        }
        Ok(())
    }

    /// Checks a snapshot completely without touching the map, in this order: header
    /// (length, magic, version, class count, reserved bytes), total length, CRC, capacity,
    /// config, then every block and voxel record.
    fn validate_snapshot(buf: &[u8]) -> Result<(Config, u32, usize, usize), Error> {
        let h = Self::read_header(buf)?;
        let (nb, nv) = (h.fields.blocks as usize, h.fields.voxels as usize);
        Self::check_body(buf, nb, nv)?;
        let config = h.checked_config()?;
        let mut r = Reader {
            buf,
            pos: SNAPSHOT_HEADER_BYTES,
        };
        check_blocks(&mut r, nb, nv, &config)?;
        Self::check_voxels(&mut r, nb, nv, &config)?;
        Ok((config, h.fields.frames, nb, nv))
    }

    /// The header fields, after checking the length, magic, version, class count and
    /// reserved bytes.
    fn read_header(buf: &[u8]) -> Result<RawHeader, Error> {
        if buf.len() < SNAPSHOT_HEADER_BYTES + 4 {
            return Err(Error::SnapshotTruncated);
        }
        let h = RawHeader::decode(buf)?;
        if h.fields.classes as usize != C {
            return Err(Error::SnapshotClasses);
        }
        if h.reserved != [0] {
            return Err(Error::SnapshotCorrupt);
        }
        Ok(h)
    }

    /// The length the header implies, the CRC, and this map's capacity.
    fn check_body(buf: &[u8], nb: usize, nv: usize) -> Result<(), Error> {
        let expect = (nb as u64) * SNAPSHOT_BLOCK_BYTES as u64
            + (nv as u64) * Self::SNAPSHOT_VOXEL_BYTES as u64
            + SNAPSHOT_HEADER_BYTES as u64
            + 4;
        if buf.len() as u64 != expect {
            return Err(Error::SnapshotTruncated);
        }
        let body = buf.len() - 4;
        let stored = u32::from_le_bytes([buf[body], buf[body + 1], buf[body + 2], buf[body + 3]]);
        if crc32(&buf[..body]) != stored {
            return Err(Error::SnapshotChecksum);
        }
        if nb > B || nv > V {
            return Err(Error::SnapshotCapacity);
        }
        Ok(())
    }

    /// Voxel records: strictly increasing canonical order, valid keys, counts and sums,
    /// and each one's surface bit set in its block.
    fn check_voxels(r: &mut Reader, nb: usize, nv: usize, c: &Config) -> Result<(), Error> {
        let qhalf = 1i64 << (c.quant_bits - 1);
        let mut last = None;
        for _ in 0..nv {
            let k = r.key();
            if (0..3).any(|i| (k >> (32 - 16 * i)) & 0xffff == 0)
                || last.is_some_and(|l| l >= order(k))
            {
                return Err(Error::SnapshotCorrupt);
            }
            last = Some(order(k));
            let n = r.u32();
            if n == 0 || n > c.n_max {
                return Err(Error::SnapshotCorrupt);
            }
            let mut s1 = [0i64; 3];
            for x in s1.iter_mut() {
                *x = r.i32() as i64;
            }
            let mut s2 = [0i64; 6];
            for x in s2.iter_mut() {
                *x = r.i32() as i64;
            }
            if r.u8() > MAX_VOTE_EXPONENT {
                return Err(Error::SnapshotCorrupt);
            }
            r.pos += C; // any histogram is valid
            if !sums_possible(n as i64, &s1, &s2, qhalf) {
                return Err(Error::SnapshotCorrupt);
            }
            let key = VoxelKey::unpack(k);
            if !Self::surface_bit_set(r.buf, nb, key.block(), key.cell()) {
                return Err(Error::SnapshotCorrupt);
            }
        }
        Ok(())
    }

    /// Binary search of the (canonically sorted) block records for a surface bit.
    fn surface_bit_set(buf: &[u8], nb: usize, block: u64, cell: u32) -> bool {
        let want = order(block);
        let (mut lo, mut hi) = (0usize, nb);
        while lo < hi {
            let mid = (lo + hi) / 2;
            let mut r = Reader {
                buf,
                pos: SNAPSHOT_HEADER_BYTES + mid * SNAPSHOT_BLOCK_BYTES,
            };
            let k = r.key();
            match order(k).cmp(&want) {
                core::cmp::Ordering::Less => lo = mid + 1,
                core::cmp::Ordering::Greater => hi = mid,
                core::cmp::Ordering::Equal => {
                    r.pos += 128;
                    return r.u64() & (1u64 << cell) != 0;
                }
            }
        }
        false
    }
}

/// A snapshot's header: the config and frame count of the map that wrote it, its class
/// count and capacities, and how many records follow. Read it to learn what a snapshot
/// holds without loading it (the [`Map`] type to read it into, the config a refused
/// snapshot was written with).
///
/// ```
/// use sndt_core::*;
/// let mut config = Config::with_cell_size(0.05);
/// config.max_range = 7.5;
/// let mut map: Map<64, 16, 4> = Map::new(config);
/// let p = [LabeledPoint::new(Point3::new(0.0, 0.0, 1.0), Labels::top1(2)); 5];
/// map.integrate(&Isometry3::identity(), &p).unwrap();
/// let mut buf = [0u8; 4096];
/// let n = map.write_snapshot(&mut buf).unwrap();
///
/// let h = SnapshotHeader::read(&buf[..n]).unwrap();
/// assert_eq!((h.config, h.frames, h.classes), (config, 1, 4));
/// assert_eq!((h.voxel_capacity, h.block_capacity), (64, 16));
/// assert_eq!((h.voxels as usize, h.blocks as usize), (map.len(), map.block_count()));
/// assert_eq!(SnapshotHeader::read(&buf[..40]), Err(Error::SnapshotTruncated));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SnapshotHeader {
    /// Classes `C` of the writer; only a `Map<_, _, C>` reads the snapshot.
    pub classes: u16,
    /// Voxel capacity `V` of the writer (a reader needs room for `voxels` only).
    pub voxel_capacity: u32,
    /// Block capacity `B` of the writer (a reader needs room for `blocks` only).
    pub block_capacity: u32,
    /// The writer's config as stored, not validated: a snapshot whose config
    /// [`Config::validate`] refuses does not load.
    pub config: Config,
    /// Frames integrated into the map ([`MapStats::frames`]).
    pub frames: u32,
    /// Block records after the header.
    pub blocks: u32,
    /// Voxel records after the blocks.
    pub voxels: u32,
}

impl SnapshotHeader {
    /// Reads the header at the start of `bytes` (a snapshot, or at least its first
    /// [`SNAPSHOT_HEADER_BYTES`]). It checks what decoding needs: the length
    /// ([`Error::SnapshotTruncated`]), magic ([`Error::SnapshotMagic`]), version
    /// ([`Error::SnapshotVersion`]), zero reserved bytes and a known miss model
    /// ([`Error::SnapshotCorrupt`]). The class count, config, records and CRC are checked
    /// by [`Map::read_snapshot`] only. Never panics.
    ///
    /// ```
    /// use sndt_core::*;
    /// let map: Map<64, 16, 4> = Map::new(Config::DEFAULT);
    /// let mut buf = [0u8; 256];
    /// let n = map.write_snapshot(&mut buf).unwrap();
    /// assert_eq!(SnapshotHeader::read(&buf[..n]).unwrap().config, Config::DEFAULT);
    /// buf[0] = b'X';
    /// assert_eq!(SnapshotHeader::read(&buf[..n]), Err(Error::SnapshotMagic));
    /// assert_eq!(SnapshotHeader::read(&[]), Err(Error::SnapshotTruncated));
    /// ```
    pub fn read(bytes: &[u8]) -> Result<SnapshotHeader, Error> {
        let raw = RawHeader::decode(bytes)?;
        if raw.reserved != [0] {
            return Err(Error::SnapshotCorrupt);
        }
        let mut h = raw.fields;
        h.config.miss_model = miss_model(raw.model).ok_or(Error::SnapshotCorrupt)?;
        Ok(h)
    }

    /// Writes the header into the first [`SNAPSHOT_HEADER_BYTES`] of `out`, as
    /// [`Map::write_snapshot`] does, and returns that length, or
    /// [`Error::BufferTooSmall`] (nothing written). The CRC at the end of a snapshot
    /// covers the header: a snapshot whose header was changed loads only with a new CRC.
    ///
    /// ```
    /// use sndt_core::*;
    /// let map: Map<64, 16, 4> = Map::new(Config::DEFAULT);
    /// let mut buf = [0u8; 256];
    /// let n = map.write_snapshot(&mut buf).unwrap();
    /// let mut h = SnapshotHeader::read(&buf[..n]).unwrap();
    /// h.frames = 7;
    /// assert_eq!(h.write(&mut buf), Ok(SNAPSHOT_HEADER_BYTES));
    /// assert_eq!(SnapshotHeader::read(&buf[..n]).unwrap().frames, 7);
    /// assert_eq!(h.write(&mut [0u8; 10]), Err(Error::BufferTooSmall));
    /// ```
    pub fn write(&self, out: &mut [u8]) -> Result<usize, Error> {
        let dst = out
            .get_mut(..SNAPSHOT_HEADER_BYTES)
            .ok_or(Error::BufferTooSmall)?;
        let mut hdr = [0u8; SNAPSHOT_HEADER_BYTES];
        self.encode(&mut hdr);
        dst.copy_from_slice(&hdr);
        Ok(SNAPSHOT_HEADER_BYTES)
    }

    /// Writes the header into a whole snapshot and seals it again with a fresh CRC, so
    /// that a tool can change what a stored map says about itself (its config, its frame
    /// count) without knowing the layout. `snapshot` must be exactly one snapshot; too short
    /// a slice gives [`Error::SnapshotTruncated`] and nothing is written. Whether the
    /// result loads is for [`Map::read_snapshot`] to say: a config it refuses is refused
    /// there.
    ///
    /// ```
    /// use sndt_core::*;
    /// let map: Map<64, 16, 4> = Map::new(Config::DEFAULT);
    /// let mut buf = [0u8; 256];
    /// let n = map.write_snapshot(&mut buf).unwrap();
    /// let mut h = SnapshotHeader::read(&buf[..n]).unwrap();
    /// h.frames = 7;
    /// h.rewrite(&mut buf[..n]).unwrap();
    /// let mut copy: Map<64, 16, 4> = Map::new(Config::DEFAULT);
    /// copy.read_snapshot(&buf[..n]).unwrap();
    /// assert_eq!(copy.stats().frames, 7);
    /// assert_eq!(h.rewrite(&mut [0u8; 20]), Err(Error::SnapshotTruncated));
    /// ```
    pub fn rewrite(&self, snapshot: &mut [u8]) -> Result<(), Error> {
        if snapshot.len() < SNAPSHOT_HEADER_BYTES + 4 {
            return Err(Error::SnapshotTruncated);
        }
        self.write(snapshot)?;
        let (body, crc) = snapshot
            .split_last_chunk_mut::<4>()
            .ok_or(Error::SnapshotTruncated)?;
        *crc = crc32(body).to_le_bytes();
        Ok(())
    }

    /// The header's bytes, in the layout of the module doc.
    pub(crate) fn encode(&self, hdr: &mut [u8; SNAPSHOT_HEADER_BYTES]) {
        let mut w = Writer { buf: hdr, pos: 0 };
        let c = &self.config;
        w.put(MAGIC);
        w.put(&SNAPSHOT_VERSION.to_le_bytes());
        w.put(&self.classes.to_le_bytes());
        w.put(&self.voxel_capacity.to_le_bytes());
        w.put(&self.block_capacity.to_le_bytes());
        for f in [
            c.cell_size,
            c.eigen_ratio,
            c.hit,
            c.miss,
            c.clamp_min,
            c.clamp_max,
            c.lambda,
            c.noise_base,
            c.noise_quadratic,
            c.max_range,
            c.render_radius,
        ] {
            w.put(&f.to_bits().to_le_bytes());
        }
        w.put(&c.n_min.to_le_bytes());
        w.put(&c.n_max.to_le_bytes());
        let model = match c.miss_model {
            MissModel::NdtOm => 0u8,
            MissModel::Constant => 1u8,
        };
        // Exact: `validate` wants a multiple of 1/1024 in [-30, 0].
        let see = (c.see_through_miss * LOGODDS_ONE) as i16;
        w.put(&[c.quant_bits, c.top_k, c.min_score, model, c.votes_per_frame]);
        w.put(&see.to_le_bytes());
        w.put(&[0]);
        w.put(&self.frames.to_le_bytes());
        w.put(&self.blocks.to_le_bytes());
        w.put(&self.voxels.to_le_bytes());
    }
}

/// A header as stored, before the checks that depend on who reads it: a map checks its
/// class count before the reserved bytes, and the miss model only after the CRC.
struct RawHeader {
    /// The fields; the config's miss model is not decoded yet (see `model`).
    fields: SnapshotHeader,
    /// The stored miss model byte.
    model: u8,
    /// The byte after the config, which must be zero.
    reserved: [u8; 1],
}

impl RawHeader {
    /// Every header field, after checking the length, magic and version.
    fn decode(buf: &[u8]) -> Result<RawHeader, Error> {
        if buf.len() < SNAPSHOT_HEADER_BYTES {
            return Err(Error::SnapshotTruncated);
        }
        let mut r = Reader { buf, pos: 0 };
        if &r.take::<4>() != MAGIC {
            return Err(Error::SnapshotMagic);
        }
        if r.u16() != SNAPSHOT_VERSION {
            return Err(Error::SnapshotVersion);
        }
        let classes = r.u16();
        let (voxel_capacity, block_capacity) = (r.u32(), r.u32());
        let (mut config, model) = read_config(&mut r);
        config.see_through_miss = f32::from(r.i16()) / LOGODDS_ONE;
        let reserved = r.take::<1>();
        let fields = SnapshotHeader {
            classes,
            voxel_capacity,
            block_capacity,
            config,
            frames: r.u32(),
            blocks: r.u32(),
            voxels: r.u32(),
        };
        Ok(RawHeader {
            fields,
            model,
            reserved,
        })
    }

    /// The stored config with its miss model, if it is a valid config.
    fn checked_config(&self) -> Result<Config, Error> {
        let mut c = self.fields.config;
        c.miss_model = miss_model(self.model).ok_or(Error::SnapshotCorrupt)?;
        c.validate().map_err(|_| Error::SnapshotCorrupt)?;
        Ok(c)
    }
}

/// The miss model a stored byte names.
fn miss_model(byte: u8) -> Option<MissModel> {
    match byte {
        0 => Some(MissModel::NdtOm),
        1 => Some(MissModel::Constant),
        _ => None,
    }
}

/// The config fields in the order [`SnapshotHeader::encode`] writes them, and the miss
/// model byte (decoded by [`miss_model`]).
fn read_config(r: &mut Reader) -> (Config, u8) {
    let mut c = Config::DEFAULT;
    c.cell_size = r.f32();
    c.eigen_ratio = r.f32();
    c.hit = r.f32();
    c.miss = r.f32();
    c.clamp_min = r.f32();
    c.clamp_max = r.f32();
    c.lambda = r.f32();
    c.noise_base = r.f32();
    c.noise_quadratic = r.f32();
    c.max_range = r.f32();
    c.render_radius = r.f32();
    c.n_min = r.u32();
    c.n_max = r.u32();
    c.quant_bits = r.u8();
    c.top_k = r.u8();
    c.min_score = r.u8();
    let model = r.u8();
    c.votes_per_frame = r.u8();
    (c, model)
}

/// Block records: strictly increasing canonical order, valid keys, log-odds within the
/// clamps, nothing in cells outside the key range, and one surface bit per voxel record.
fn check_blocks(r: &mut Reader, nb: usize, nv: usize, c: &Config) -> Result<(), Error> {
    let (lo, hi) = (to_fixed(c.clamp_min), to_fixed(c.clamp_max));
    let mut last = None;
    let mut surface_bits = 0usize;
    for _ in 0..nb {
        let k = r.key();
        if !block_key_ok(k) || last.is_some_and(|l| l >= order(k)) {
            return Err(Error::SnapshotCorrupt);
        }
        last = Some(order(k));
        let outside = cells_outside_key_range(k);
        for cell in 0..64 {
            let l = r.i16() as i32;
            if l < lo || l > hi || (l != 0 && outside & (1 << cell) != 0) {
                return Err(Error::SnapshotCorrupt);
            }
        }
        let surface = r.u64();
        if surface & outside != 0 {
            return Err(Error::SnapshotCorrupt);
        }
        surface_bits += surface.count_ones() as usize;
    }
    if surface_bits != nv {
        return Err(Error::SnapshotCorrupt);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use crate::testutil::*;
    use crate::*;
    use std::vec::Vec;

    #[test]
    fn snapshot_round_trip_and_rejections() {
        let mut map: Map<64, 32, 3> = Map::new(Config::DEFAULT);
        let pts: Vec<_> = (0..50)
            .map(|i| {
                lp(
                    0.02 * (i % 7) as f32,
                    0.03 * (i % 5) as f32,
                    1.0 + 0.01 * i as f32,
                    1 + (i % 3) as u8,
                )
            })
            .collect();
        map.integrate(&Isometry3::identity(), &pts).unwrap();
        let s = snapshot(&map);
        let mut copy: Map<64, 32, 3> = Map::new(Config::with_cell_size(0.2));
        copy.read_snapshot(&s).unwrap();
        assert_eq!(snapshot(&copy), s);
        assert_eq!(copy.config(), map.config());
        // Every truncation and every flipped byte is rejected and leaves the map unchanged.
        for cut in [0, 10, 87, 88, s.len() - 1] {
            assert!(copy.read_snapshot(&s[..cut]).is_err());
        }
        for i in (0..s.len()).step_by(7) {
            let mut bad = s.clone();
            bad[i] ^= 0x10;
            assert!(copy.read_snapshot(&bad).is_err(), "byte {i}");
        }
        assert_eq!(snapshot(&copy), s);
        // A smaller map rejects it by capacity.
        let mut small: Map<4, 32, 3> = Map::new(Config::DEFAULT);
        assert_eq!(small.read_snapshot(&s), Err(Error::SnapshotCapacity));
        let mut other: Map<64, 32, 4> = Map::new(Config::DEFAULT);
        assert_eq!(other.read_snapshot(&s), Err(Error::SnapshotClasses));
        // A voxel count above n_max with a valid CRC is corrupt.
        let mut bad = s.clone();
        let first_voxel = SNAPSHOT_HEADER_BYTES + map.block_count() * SNAPSHOT_BLOCK_BYTES;
        bad[first_voxel + 6..first_voxel + 10].copy_from_slice(&4000u32.to_le_bytes());
        fix_crc(&mut bad);
        assert_eq!(copy.read_snapshot(&bad), Err(Error::SnapshotCorrupt));
        // So is a vote sampling exponent above 15 (byte 46 of a voxel record).
        let mut bad = s.clone();
        bad[first_voxel + 46] = 16;
        fix_crc(&mut bad);
        assert_eq!(copy.read_snapshot(&bad), Err(Error::SnapshotCorrupt));
    }

    #[test]
    fn snapshot_keeps_the_vote_sampling() {
        // A crowded voxel samples one point in 2^3 after its first frame (500 votes, 64 per
        // frame); a map read from its snapshot continues exactly like the original.
        let mut map: Map<16, 16, 2> = Map::new(Config::DEFAULT);
        let mut rng = Lcg(5);
        map.integrate(&Isometry3::identity(), &voxel_cloud(&mut rng, 200, 300))
            .unwrap();
        let k = key(0, 0, 10);
        assert_eq!(voxel(&map, &k).tally >> 12, 3);
        let mut copy: Map<16, 16, 2> = Map::new(Config::DEFAULT);
        copy.read_snapshot(&snapshot(&map)).unwrap();
        assert_eq!(voxel(&copy, &k).tally >> 12, 3);
        let next = voxel_cloud(&mut rng, 100, 400);
        map.integrate(&Isometry3::identity(), &next).unwrap();
        copy.integrate(&Isometry3::identity(), &next).unwrap();
        assert_eq!(snapshot(&copy), snapshot(&map));
    }

    /// Regression: A snapshot block at block coordinate -8192 covers voxels x = -32768..-32765; the
    /// reader accepts log-odds in its x = -32768 cells, and `cells()` then reports keys
    /// outside the documented range `-KEY_LIMIT..=KEY_LIMIT`.
    #[test]
    fn snapshot_accepts_cells_outside_key_range() {
        let mut src: Map<4, 4, 1> = Map::new(Config::DEFAULT);
        let edge = key(-32767, 0, 0);
        let mut b = Block::new(edge.block());
        b.cells[0] = -100; // cell 0 of block -8192 is voxel x = -32768
        src.blocks.insert(b).unwrap();
        let s = snapshot(&src);
        let mut map: Map<4, 4, 1> = Map::new(Config::DEFAULT);
        let read = map.read_snapshot(&s);
        let bad: Vec<VoxelKey> = map
            .cells()
            .map(|(k, _)| k)
            .filter(|k| (k.x as i32).abs() > KEY_LIMIT)
            .collect();
        assert!(
            read.is_err() || bad.is_empty(),
            "accepted cells with keys {bad:?}"
        );
    }

    /// Regression: The reader checks |S1| <= n 2^(Q-1) and |S2| <= n 4^(Q-1) but not that the sums can
    /// come from points (n S2_ii >= S1_i^2): a voxel with S1 = n * 32, S2 = 0 is accepted and
    /// its Gaussian has a negative variance.
    #[test]
    fn snapshot_accepts_impossible_sums() {
        let mut map: Map<16, 16, 1> = Map::new(Config::DEFAULT);
        map.integrate(&Isometry3::identity(), &[lp(0.05, 0.05, 1.05, 1); 4])
            .unwrap();
        let mut s = snapshot(&map);
        let v0 = SNAPSHOT_HEADER_BYTES + map.block_count() * SNAPSHOT_BLOCK_BYTES;
        // Record: key 6, n 4, S1 12, S2 24.
        s[v0 + 10..v0 + 14].copy_from_slice(&128i32.to_le_bytes()); // S1x = 4 * 32
        s[v0 + 22..v0 + 26].copy_from_slice(&0i32.to_le_bytes()); // S2xx = 0
        fix_crc(&mut s);
        let mut copy: Map<16, 16, 1> = Map::new(Config::DEFAULT);
        let read = copy.read_snapshot(&s);
        let var = copy
            .gaussian(&key(0, 0, 10))
            .map_or(0.0, |g| g.covariance[(0, 0)]);
        assert!(read.is_err() || var >= 0.0, "accepted; variance {var}");
    }

    /// Regression: The reserved byte of the header must be zero: junk there is rejected.
    #[test]
    fn snapshot_rejects_nonzero_reserved_bytes() {
        let mut map: Map<16, 16, 1> = Map::new(Config::DEFAULT);
        map.integrate(&Isometry3::identity(), &[lp(0.05, 0.05, 1.05, 1); 4])
            .unwrap();
        let mut s = snapshot(&map);
        s[75] = 0xAB; // reserved byte 75 (73..75: see_through_miss)
        fix_crc(&mut s);
        let mut copy: Map<16, 16, 1> = Map::new(Config::DEFAULT);
        assert_eq!(copy.read_snapshot(&s), Err(Error::SnapshotCorrupt));
    }

    /// `see_through_miss` is kept exactly in bytes 73..75 (i16, 1/1024 log-odds); zeros
    /// there, as every snapshot written before the field existed has, read as the miss
    /// turned off, and a value outside its range is refused.
    #[test]
    fn see_through_miss_in_the_header() {
        let mut config = Config::DEFAULT;
        config.see_through_miss = -2.75;
        let mut map: Map<16, 16, 1> = Map::new(config);
        map.integrate(&Isometry3::identity(), &[lp(0.05, 0.05, 1.05, 1); 4])
            .unwrap();
        let mut s = snapshot(&map);
        assert_eq!(i16::from_le_bytes([s[73], s[74]]), -2816);
        let mut copy: Map<16, 16, 1> = Map::new(Config::DEFAULT);
        copy.read_snapshot(&s).unwrap();
        assert_eq!(copy.config().see_through_miss, -2.75);
        (s[73], s[74]) = (0, 0);
        fix_crc(&mut s);
        copy.read_snapshot(&s).unwrap();
        assert_eq!(copy.config().see_through_miss, 0.0);
        s[73] = 1; // +1/1024: a miss must not add
        fix_crc(&mut s);
        assert_eq!(copy.read_snapshot(&s), Err(Error::SnapshotCorrupt));
    }

    /// The header of a real snapshot holds what the map was built with, and encoding it
    /// gives the snapshot's first bytes (one encoder for both).
    #[test]
    fn header_of_a_real_snapshot() {
        let mut config = Config::with_cell_size(0.07);
        config.miss_model = MissModel::Constant;
        config.votes_per_frame = 9;
        config.n_max = 500;
        let mut map: Map<64, 32, 3> = Map::new(config);
        for z in [1.05, 1.25] {
            map.integrate(&Isometry3::identity(), &[lp(0.05, 0.05, z, 2); 4])
                .unwrap();
        }
        let s = snapshot(&map);
        let h = SnapshotHeader::read(&s).unwrap();
        let want = SnapshotHeader {
            classes: 3,
            voxel_capacity: 64,
            block_capacity: 32,
            config,
            frames: 2,
            blocks: map.block_count() as u32,
            voxels: map.len() as u32,
        };
        assert_eq!(h, want);
        assert_eq!(SnapshotHeader::read(&s[..SNAPSHOT_HEADER_BYTES]), Ok(want));
        let mut out = [0u8; SNAPSHOT_HEADER_BYTES + 1];
        assert_eq!(h.write(&mut out), Ok(SNAPSHOT_HEADER_BYTES));
        assert_eq!(out[..SNAPSHOT_HEADER_BYTES], s[..SNAPSHOT_HEADER_BYTES]);
        assert_eq!(out[SNAPSHOT_HEADER_BYTES], 0);
    }

    /// Short or corrupt headers give a snapshot error, never a panic; a config the map
    /// would refuse is still read as stored.
    #[test]
    fn header_errors() {
        let s = snapshot(&Map::<16, 16, 1>::new(Config::DEFAULT));
        for n in 0..SNAPSHOT_HEADER_BYTES {
            assert_eq!(SnapshotHeader::read(&s[..n]), Err(Error::SnapshotTruncated));
        }
        let edited = |at: usize, v: u8| {
            let mut b = s.clone();
            b[at] = v;
            SnapshotHeader::read(&b)
        };
        assert_eq!(edited(0, b'X'), Err(Error::SnapshotMagic));
        assert_eq!(edited(4, 9), Err(Error::SnapshotVersion));
        assert_eq!(edited(71, 7), Err(Error::SnapshotCorrupt)); // miss model
        assert_eq!(edited(75, 1), Err(Error::SnapshotCorrupt)); // reserved
        let see = edited(74, 0xF4).map(|h| h.config.see_through_miss); // i16 0xF400 / 1024
        assert_eq!(see, Ok(-3.0));
        assert_eq!(edited(68, 0).map(|h| h.config.quant_bits), Ok(0));
        assert_eq!(edited(6, 40).map(|h| h.classes), Ok(40));
        let mut junk = [0u8; SNAPSHOT_HEADER_BYTES];
        for (i, b) in junk.iter_mut().enumerate() {
            *b = (i * 37 % 251) as u8;
        }
        assert!(SnapshotHeader::read(&junk).is_err());
        let h = SnapshotHeader::read(&s).unwrap();
        assert_eq!(h.write(&mut []), Err(Error::BufferTooSmall));
    }
}
