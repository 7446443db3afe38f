//! The map: its two fixed tables (occupancy blocks, NDT voxels), construction and the
//! read-only queries. What changes the map lives with its concern: integration
//! (`integrate/`, one file per phase), eviction (`integrate/evict.rs`), snapshots
//! (`snapshot.rs`).

use crate::config::{Config, MissModel, LOGODDS_ONE};
use crate::error::Error;
use crate::geometry::gaussian::Gaussian;
use crate::key::VoxelKey;
use crate::storage::block::Block;
use crate::storage::table::{Entry, Table};
use crate::storage::voxel::{argmax, Voxel};

/// Bytes of one occupancy block (64 voxels) in the block table, hash index (a 4-byte
/// bucket head per slot) included.
pub const BLOCK_BYTES: usize = core::mem::size_of::<Block>() + BUCKET_HEAD_BYTES;

/// Bytes of a table's bucket head, one per slot (`table.rs`).
const BUCKET_HEAD_BYTES: usize = core::mem::size_of::<u32>();

/// Bytes of the map besides its two tables' slots and heads: config, counters and the
/// voxel table's bookkeeping (the block table's is [`BLOCK_TABLE_BYTES`]).
pub const MAP_HEADER_BYTES: usize = 116;

/// Bytes of the block table's bookkeeping; the table is 8-byte aligned, so it takes
/// `round_up(BLOCK_TABLE_BYTES + B * BLOCK_BYTES, 8)` bytes.
pub const BLOCK_TABLE_BYTES: usize = 12;

/// Occupancy state of a voxel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Occupancy {
    /// Never observed (or log-odds exactly 0).
    Unknown,
    /// Log-odds below 0.
    Free,
    /// Log-odds above 0.
    Occupied,
}

/// Totals since the map was created or cleared.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MapStats {
    /// Frames integrated.
    pub frames: u32,
    /// NDT voxels evicted to make room.
    pub voxels_evicted: u64,
    /// Occupancy blocks evicted to make room.
    pub blocks_evicted: u64,
    /// Point updates dropped because nothing could be evicted.
    pub dropped_points: u64,
    /// Free-space updates dropped because nothing could be evicted.
    pub dropped_misses: u64,
}

/// Everything the map knows about one surface voxel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoxelView<'a, const C: usize> {
    /// The voxel's key.
    pub key: VoxelKey,
    /// Occupancy log-odds (natural units).
    pub log_odds: f32,
    /// Mean, covariance, count.
    pub gaussian: Gaussian,
    /// Class votes; bin `i` is class `i + 1`.
    pub histogram: &'a [u8; C],
}

impl<const C: usize> VoxelView<'_, C> {
    /// Most voted class (1-based) and its share of votes.
    ///
    /// ```
    /// # use sndt_core::*;
    /// let mut map: Map<16, 4, 3> = Map::new(Config::DEFAULT);
    /// let p = [LabeledPoint::new(Point3::new(0.0, 0.0, 1.0), Labels::top1(2)); 3];
    /// map.integrate(&Isometry3::identity(), &p).unwrap();
    /// let v = map.voxels().next().unwrap();
    /// assert_eq!(v.class(), Some((2, 1.0)));
    /// ```
    pub fn class(&self) -> Option<(u8, f32)> {
        argmax(self.histogram)
    }

    /// Occupancy state.
    pub fn occupancy(&self) -> Occupancy {
        state(self.log_odds)
    }
}

fn state(l: f32) -> Occupancy {
    if l > 0.0 {
        Occupancy::Occupied
    } else if l < 0.0 {
        Occupancy::Free
    } else {
        Occupancy::Unknown
    }
}

/// A semantic occupancy-NDT map with room for `VOXELS` surface voxels, `BLOCKS` occupancy
/// blocks of 4x4x4 voxels and `CLASSES` semantic classes (ids `1..=CLASSES`).
///
/// Its size is its whole memory: [`Map::BYTES`] `== size_of::<Map<V, B, C>>()`.
///
/// ```
/// use sndt_core::{Config, Map};
/// type RobotMap = Map<4096, 1024, 40>;
/// let map = RobotMap::new(Config::DEFAULT);
/// assert_eq!(core::mem::size_of::<RobotMap>(), RobotMap::BYTES);
/// assert_eq!(RobotMap::VOXEL_BYTES, 96); // per NDT voxel with 40 classes, index included
/// assert!(map.is_empty());
/// ```
pub struct Map<const VOXELS: usize, const BLOCKS: usize, const CLASSES: usize> {
    pub(crate) config: Config,
    pub(crate) voxels: Table<Voxel<CLASSES>, VOXELS>,
    pub(crate) blocks: Table<Block, BLOCKS>,
    pub(crate) stats: MapStats,
}

impl<const V: usize, const B: usize, const C: usize> Map<V, B, C> {
    /// Bytes per NDT voxel, hash index (a 4-byte bucket head per slot) included:
    /// `round_up(52 + C, 4) + 4` (96 for 40 classes).
    pub const VOXEL_BYTES: usize = core::mem::size_of::<Voxel<C>>() + BUCKET_HEAD_BYTES;

    /// Exact size of the map: `round_up(MAP_HEADER_BYTES + V * VOXEL_BYTES +
    /// round_up(BLOCK_TABLE_BYTES + B * BLOCK_BYTES, 8), 8)`.
    pub const BYTES: usize = (MAP_HEADER_BYTES
        + V * Self::VOXEL_BYTES
        + (BLOCK_TABLE_BYTES + B * BLOCK_BYTES).div_ceil(8) * 8)
        .div_ceil(8)
        * 8;

    /// An empty map with `config` as given (callers check it).
    const fn empty(config: Config) -> Self {
        Map {
            config,
            voxels: Table::new(),
            blocks: Table::new(),
            stats: MapStats {
                frames: 0,
                voxels_evicted: 0,
                blocks_evicted: 0,
                dropped_points: 0,
                dropped_misses: 0,
            },
        }
    }

    /// An empty map. Invalid configs are replaced by [`Config::DEFAULT`]; use
    /// [`Map::try_new`] to get an error instead.
    pub const fn new(config: Config) -> Self {
        const {
            assert!(C >= 1 && C <= 254, "CLASSES must be in 1..=254");
            assert!(V >= 1 && B >= 1, "capacities must be at least 1");
        };
        Self::empty(config).checked()
    }

    /// An empty map whose memory is all zero bytes, for a `static` on a microcontroller: it
    /// is placed in `.bss` (zeroed at start-up, no copy in flash) instead of `.data`, where a
    /// `static` built with [`Map::new`] goes because [`Config::DEFAULT`] is not all zero.
    ///
    /// It holds no valid configuration yet (all fields zero, cell size 0): call
    /// [`Map::reset`] once at start-up. Until then the map stays empty and inert: every
    /// update fails with [`crate::Error::PoseOutOfRange`] and every query finds nothing.
    ///
    /// ```
    /// use sndt_core::*;
    /// let mut map: Map<64, 16, 4> = Map::zeroed();
    /// let p = [LabeledPoint::new(Point3::new(0.0, 0.0, 1.0), Labels::top1(2)); 3];
    /// assert_eq!(map.integrate(&Isometry3::identity(), &p).err(), Some(Error::PoseOutOfRange));
    /// assert!(map.raycast(&Point3::origin(), &Vector3::z(), 5.0).is_none());
    /// map.reset(Config::DEFAULT).unwrap(); // at start-up, e.g. for `static MAP: Mutex<RefCell<Map<..>>>`
    /// assert_eq!(map.integrate(&Isometry3::identity(), &p).unwrap().points_used, 3);
    /// ```
    pub const fn zeroed() -> Self {
        const {
            assert!(C >= 1 && C <= 254, "CLASSES must be in 1..=254");
            assert!(V >= 1 && B >= 1, "capacities must be at least 1");
        };
        Self::empty(Config {
            cell_size: 0.0,
            quant_bits: 0,
            n_min: 0,
            eigen_ratio: 0.0,
            n_max: 0,
            hit: 0.0,
            miss: 0.0,
            clamp_min: 0.0,
            clamp_max: 0.0,
            lambda: 0.0,
            see_through_miss: 0.0,
            noise_base: 0.0,
            noise_quadratic: 0.0,
            max_range: 0.0,
            top_k: 0,
            min_score: 0,
            votes_per_frame: 0,
            miss_model: MissModel::NdtOm,
            render_radius: 0.0,
        })
    }

    const fn checked(mut self) -> Self {
        if self.config.validate().is_err() {
            self.config = Config::DEFAULT;
        }
        self
    }

    /// An empty map, or [`crate::Error::InvalidConfig`].
    ///
    /// ```
    /// let mut c = sndt_core::Config::DEFAULT;
    /// c.n_max = 1;
    /// assert!(sndt_core::Map::<8, 8, 2>::try_new(c).is_err());
    /// ```
    pub fn try_new(config: Config) -> Result<Self, Error> {
        config.validate()?;
        Ok(Self::new(config))
    }

    /// Empties the map in place and installs `config` (no large value on the stack).
    ///
    /// ```
    /// # use sndt_core::*;
    /// let mut map: Map<16, 4, 2> = Map::new(Config::DEFAULT);
    /// map.reset(Config::with_cell_size(0.2)).unwrap();
    /// assert_eq!(map.config().cell_size, 0.2);
    /// ```
    pub fn reset(&mut self, config: Config) -> Result<(), Error> {
        config.validate()?;
        self.config = config;
        self.voxels.clear();
        self.blocks.clear();
        self.stats = MapStats::default();
        Ok(())
    }

    /// The map's configuration.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// Totals since creation.
    pub fn stats(&self) -> MapStats {
        self.stats
    }

    /// Number of NDT (surface) voxels.
    pub fn len(&self) -> usize {
        self.voxels.len()
    }

    /// True when no voxel has been observed.
    pub fn is_empty(&self) -> bool {
        self.blocks.len() == 0
    }

    /// Number of occupancy blocks (each covers 4x4x4 voxels).
    pub fn block_count(&self) -> usize {
        self.blocks.len()
    }

    /// Key of the voxel containing a world point, if inside the key range.
    pub fn voxel_key(&self, p: &[f32; 3]) -> Option<VoxelKey> {
        VoxelKey::from_point(p, self.config.cell_size)
    }

    /// Occupancy log-odds of a voxel (natural units); 0 when unknown.
    pub fn log_odds(&self, key: &VoxelKey) -> f32 {
        let block = self
            .blocks
            .find(key.block())
            .and_then(|b| self.blocks.get(b));
        let cell = block.and_then(|b| b.cells.get(key.cell() as usize));
        cell.map_or(0.0, |&l| l as f32 / LOGODDS_ONE)
    }

    /// Occupancy state of a voxel.
    pub fn occupancy(&self, key: &VoxelKey) -> Occupancy {
        state(self.log_odds(key))
    }

    /// Most voted class (1-based) and its share of the votes, for a surface voxel.
    pub fn class(&self, key: &VoxelKey) -> Option<(u8, f32)> {
        let v = self.voxels.find(key.packed())?;
        argmax(&self.voxels.get(v)?.hist)
    }

    /// The Gaussian of a surface voxel (any count; check `count` against `n_min`).
    pub fn gaussian(&self, key: &VoxelKey) -> Option<Gaussian> {
        let v = self.voxels.get(self.voxels.find(key.packed())?)?;
        Some(v.gaussian(self.config.cell_size, self.config.quant_step()))
    }

    /// The Gaussian of the surface voxel containing a world point.
    pub fn gaussian_at(&self, p: &[f32; 3]) -> Option<Gaussian> {
        self.gaussian(&self.voxel_key(p)?)
    }

    /// Everything about one surface voxel.
    pub fn voxel(&self, key: &VoxelKey) -> Option<VoxelView<'_, C>> {
        self.view(self.voxels.find(key.packed())?)
    }

    fn view(&self, slot: usize) -> Option<VoxelView<'_, C>> {
        let v = self.voxels.get(slot)?;
        let key = v.voxel_key();
        Some(VoxelView {
            key,
            log_odds: self.log_odds(&key),
            gaussian: v.gaussian(self.config.cell_size, self.config.quant_step()),
            histogram: &v.hist,
        })
    }

    /// All surface voxels in canonical order (independent of insertion order).
    pub fn voxels(&self) -> impl Iterator<Item = VoxelView<'_, C>> + '_ {
        self.voxels.canonical().filter_map(move |s| self.view(s))
    }

    /// Every observed voxel (free or occupied) with its log-odds, block by block.
    ///
    /// ```
    /// # use sndt_core::*;
    /// let mut map: Map<16, 64, 2> = Map::new(Config::DEFAULT);
    /// let p = [LabeledPoint::new(Point3::new(0.0, 0.0, 1.0), Labels::top1(1))];
    /// map.integrate(&Isometry3::identity(), &p).unwrap();
    /// let free = map.cells().filter(|(_, l)| *l < 0.0).count();
    /// assert_eq!(free, 10); // the voxels from the sensor to the hit
    /// ```
    pub fn cells(&self) -> impl Iterator<Item = (VoxelKey, f32)> + '_ {
        let blocks = self.blocks.canonical().filter_map(|b| self.blocks.get(b));
        blocks.flat_map(move |block| {
            let packed = block.packed_key();
            block
                .cells
                .iter()
                .enumerate()
                .filter(|&(_, &l)| l != 0)
                .map(move |(i, &l)| {
                    (
                        VoxelKey::from_block_cell(packed, i as u32),
                        l as f32 / LOGODDS_ONE,
                    )
                })
        })
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use crate::testutil::*;
    use crate::*;
    use std::vec::Vec;

    fn check_size<const V: usize, const B: usize, const C: usize>() {
        // A voxel slot (52 bytes + C, 4-aligned) and its bucket head; a block slot (176
        // bytes) and its bucket head.
        let voxel = (52 + C).div_ceil(4) * 4 + 4;
        let bytes = (116 + V * voxel + (12 + B * 180).div_ceil(8) * 8).div_ceil(8) * 8;
        assert_eq!(Map::<V, B, C>::VOXEL_BYTES, voxel, "VOXEL_BYTES C={C}");
        assert_eq!(
            Map::<V, B, C>::BYTES,
            bytes,
            "BYTES formula V={V} B={B} C={C}"
        );
        assert_eq!(
            core::mem::size_of::<Map<V, B, C>>(),
            Map::<V, B, C>::BYTES,
            "size_of V={V} B={B} C={C}"
        );
    }

    macro_rules! sizes_c {
        ($v:literal, $b:literal) => {
            check_size::<$v, $b, 1>();
            check_size::<$v, $b, 2>();
            check_size::<$v, $b, 3>();
            check_size::<$v, $b, 13>();
            check_size::<$v, $b, 40>();
            check_size::<$v, $b, 41>();
        };
    }

    macro_rules! sizes_b {
        ($($v:literal),*) => {
            $(
                sizes_c!($v, 1);
                sizes_c!($v, 2);
                sizes_c!($v, 3);
                sizes_c!($v, 7);
                sizes_c!($v, 10);
                sizes_c!($v, 64);
                sizes_c!($v, 1000);
            )*
        };
    }

    #[test]
    fn memory_contract_exact_size() {
        sizes_b!(1, 2, 3, 7, 10, 64, 1000);
        assert_eq!(Map::<4096, 1024, 40>::VOXEL_BYTES, 96);
        assert_eq!(Map::<1, 1, 40>::VOXEL_BYTES, 96);
        assert_eq!(BLOCK_BYTES, 180);
        assert_eq!(MAP_HEADER_BYTES, 116);
        assert_eq!(BLOCK_TABLE_BYTES, 12);
        assert_eq!(core::mem::size_of::<Block>(), 176);
        assert_eq!(core::mem::size_of::<Voxel<40>>(), 92);
        assert_eq!(Map::<1, 1, 1>::BYTES, 368); // 116 + (56 + 4) + (12 + 176 + 4) = 368
        assert_eq!(Map::<1, 2, 1>::BYTES, 552); // 116 + 60 + (12 + 2 * 180 = 372 -> 376) = 552
    }

    /// Regression: `Map::new` promises to replace invalid configs by the default, but `checked()` only
    /// looks at a few fields. With `clamp_min > clamp_max`, `i32::clamp(lo, hi)` in
    /// `Block::add_logodds` panics (in release too).
    #[test]
    fn map_new_keeps_invalid_config() {
        let mut bad = Config::DEFAULT;
        bad.clamp_min = 0.5;
        bad.clamp_max = 0.25;
        assert!(bad.validate().is_err());
        let mut map: Map<16, 16, 1> = Map::new(bad);
        let r = std::panic::catch_unwind(core::panic::AssertUnwindSafe(|| {
            map.integrate(&Isometry3::identity(), &[lp(0.05, 0.05, 1.05, 1)])
                .map(|_| ())
        }));
        assert!(r.is_ok(), "integrate panicked on a map built by Map::new");
        let mut others = Vec::new();
        for f in [
            (|c: &mut Config| c.hit = f32::INFINITY) as fn(&mut Config),
            |c| c.miss = 1.0,
            |c| c.lambda = 2.0,
            |c| c.eigen_ratio = 0.0,
            |c| c.noise_base = 0.0,
            |c| c.max_range = f32::NAN,
            |c| c.render_radius = -1.0,
        ] {
            let mut c = Config::DEFAULT;
            f(&mut c);
            assert!(c.validate().is_err());
            others.push(*Map::<1, 1, 1>::new(c).config() == Config::DEFAULT);
        }
        assert!(others.iter().all(|ok| *ok), "{others:?}");
    }
}
