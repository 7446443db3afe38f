//! The one plain configuration struct of the map, with documented defaults.

use crate::error::{ConfigField, Error};
use crate::key::KEY_LIMIT;
use crate::labels::MAX_TOP_K;
use core::fmt;

/// How a voxel traversed by a free-space ray loses occupancy.
///
/// `repr(u8)` with `NdtOm = 0`: an all-zero map (as firmware and the C API place it in
/// zeroed memory) holds a valid `MissModel`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum MissModel {
    /// Occupancy-NDT (Saarinen et al.): a voxel with a valid Gaussian gets a miss weighted by
    /// how close the ray passes to its Gaussian, so grazing rays do not erase thin surfaces.
    /// Voxels without a valid Gaussian get [`Config::miss`].
    NdtOm = 0,
    /// Every traversed voxel gets the constant [`Config::miss`] (classic OctoMap behaviour,
    /// kept to show why NDT-OM misses matter).
    Constant = 1,
}

/// Map configuration. Every field is public; [`Config::DEFAULT`] documents the defaults,
/// each field its range, and [`Config::validate`] refuses a config with a field out of its
/// range, naming the field ([`ConfigField`]).
///
/// ```
/// let mut config = sndt_core::Config::DEFAULT;
/// config.cell_size = 0.05;
/// assert!(config.validate().is_ok());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config {
    /// Voxel edge `h` in metres, in `[0.001, 100]`. Default 0.10. Bounds
    /// [`Config::max_range`] from below: at most [`Config::MAX_RAY_CELLS`] cells per ray.
    pub cell_size: f32,
    /// Point offsets inside a voxel are quantised to `h / 2^quant_bits`. Default 6
    /// (1.56 mm at 10 cm). At most [`Config::MAX_QUANT_BITS`] so the integer sums provably
    /// cannot overflow (see [`crate::MAX_FRAME_POINTS`]).
    pub quant_bits: u8,
    /// Points needed before a voxel's Gaussian is valid. Default 3 (at least 2).
    pub n_min: u32,
    /// Eigenvalues below `eigen_ratio * lambda_max` (and below `(h / 1000)^2`, for voxels
    /// whose points coincide) are raised to it before inversion. Default 1e-3.
    pub eigen_ratio: f32,
    /// Point cap: when a voxel holds more than `n_max` points at the end of a frame, its
    /// count and sums are halved until they fit (old data decays). Default 2048,
    /// range `[n_min, 65535]`.
    pub n_max: u32,
    /// Log-odds added once per frame to a voxel that received points, in `[0, 30]`.
    /// Default 0.85 (p = 0.7).
    pub hit: f32,
    /// Log-odds of a constant miss, in `[-30, 0]`. Default -0.4 (p = 0.4).
    pub miss: f32,
    /// Lower log-odds clamp. Default -2.0.
    pub clamp_min: f32,
    /// Upper log-odds clamp. Default 3.5.
    pub clamp_max: f32,
    /// NDT-OM miss weight `lambda` in `p = 0.5 - lambda pN (1 - pz)`, in `[0, 0.49]` so
    /// that `p > 0`. Default 0.1.
    pub lambda: f32,
    /// Log-odds of the *see-through miss*, which clears what moved away; in `[-30, 0]` and
    /// a multiple of `1/1024` (the map's log-odds step, so that a snapshot keeps it
    /// exactly). Default -3; 0 is S-NDT as published, where every surface voxel gets the
    /// NDT-OM miss.
    ///
    /// A surface voxel that received no points in a frame and is crossed by one of its
    /// rays gets `see_through_miss` when the frame is a depth image
    /// ([`crate::Map::integrate_depth`]) whose pixel at the projection of the voxel's mean
    /// measured more than a cell plus twice the range noise beyond the mean: the camera
    /// looked through the middle of the old surface. Otherwise (and for point frames) it
    /// gets `see_through_miss * (1 - p_z)` from a ray that passes through the middle of
    /// its Gaussian (Mahalanobis radius 2) and ends well beyond it (the measured end more
    /// than about 1.2 range-noise sigmas past the ray's closest approach, `p_z < 1/2`);
    /// once its log-odds lie more than 1 below `clamp_max` (doubted), a ray through its
    /// Gaussian's 4-sigma ellipsoid is enough. Other rays give it no miss and leave it to
    /// the frame's next ray; voxels that received points keep the NDT-OM miss, which
    /// protects thin surfaces from grazing rays. At -3 a voxel at the clamp (3.5) needs
    /// two frames of such evidence to turn free. In a depth frame a see-through miss
    /// also spreads, as a quarter of it, to each face neighbour of the same class that
    /// got neither points nor a miss and that the image shows hidden behind something:
    /// the hidden side of an object that is gone where the camera sees it goes too.
    ///
    /// NDT-OM's miss is at most `logit(0.5 - lambda)` (-0.41 at the default `lambda`) and
    /// reaches a thin structure's former voxel only from the rare ray that crosses its
    /// footprint: as published, a moved chair stays occupied for the whole 160-frame walk
    /// of the dynamic synthetic room. At -3 it clears in 2 frames at 10 cm, as do an
    /// opened door (2), a passing person (3) and a cart (4), and a night stand replaced by
    /// a box in 10, for 0.20 points of mIoU on the default synthetic split at 10 cm with
    /// ground-truth labels (0.08 with predicted ones): `sndt dynamics`, docs/DYNAMICS.md.
    pub see_through_miss: f32,
    /// Sensor range noise `sigma = noise_base + noise_quadratic * range^2` in metres, used
    /// by NDT-OM misses. Defaults 0.02 and 0.0025 (0.06 m at 4 m).
    pub noise_base: f32,
    /// See [`Config::noise_base`].
    pub noise_quadratic: f32,
    /// Points farther than this (metres) only clear free space up to it, and rendering
    /// rays end here. Default 20, in `[0.001, 1e4]` and at most
    /// [`Config::MAX_RAY_CELLS`] (4096) cells: `max_range <= 4096 * cell_size`, because
    /// the work of every free-space and rendering ray grows with its length in voxels (see
    /// [`Config::MAX_RAY_CELLS`]).
    pub max_range: f32,
    /// How many of a point's labels vote in the class histogram (1..=3). Default 1.
    pub top_k: u8,
    /// Labels whose score (0..=255) is below this do not vote. Default 0.
    pub min_score: u8,
    /// About how many votes one voxel takes from one frame, in `1..=64`. Default 64.
    ///
    /// A 1024x768 frame puts hundreds of points into a near voxel; counting every one
    /// would let a single frame overwrite the histogram and saturate its `u8` bins (where
    /// a tie goes to the lower class). So a voxel takes the votes of only one voting point
    /// in `2^k`: those whose coordinates' hash ([`crate::vote_hash`]) has its top `k` bits
    /// zero ([`crate::takes_vote`]), a sample with the frame's class proportions that does
    /// not depend on point order (points at identical coordinates are sampled together).
    /// `k` is set at the end of each frame from the votes the voxel took
    /// ([`crate::next_vote_exponent`]) so that a voxel seen as densely in the next frame
    /// takes between half and all of `votes_per_frame` votes; a new voxel starts with
    /// `k = 0` (its first frame counts every point). Before a frame's first vote the
    /// histogram is halved if a bin exceeds `255 - votes_per_frame`, so the sample fits.
    ///
    /// Smaller values weigh frames more equally and remember more of them; larger ones
    /// keep more of each frame and still let a close view (more points) outweigh a
    /// distant one, whose segmentation is usually worse. On the synthetic split with
    /// predicted labels at 10 cm (`sndt map synthetic:6:20 --labels pred
    /// --votes-per-frame N`), larger was better.
    pub votes_per_frame: u8,
    /// Free-space model. Default [`MissModel::NdtOm`].
    pub miss_model: MissModel,
    /// Mahalanobis radius of the ellipsoid a rendering ray must enter. Default 2.5.
    pub render_radius: f32,
}

impl Config {
    /// Largest allowed [`Config::quant_bits`].
    pub const MAX_QUANT_BITS: u8 = 6;

    /// The documented defaults.
    pub const DEFAULT: Config = Config {
        cell_size: 0.10,
        quant_bits: 6,
        n_min: 3,
        eigen_ratio: 1e-3,
        n_max: 2048,
        hit: 0.85,
        miss: -0.4,
        clamp_min: -2.0,
        clamp_max: 3.5,
        lambda: 0.1,
        see_through_miss: -3.0,
        noise_base: 0.02,
        noise_quadratic: 0.0025,
        max_range: 20.0,
        top_k: 1,
        min_score: 0,
        votes_per_frame: 64,
        miss_model: MissModel::NdtOm,
        render_radius: 2.5,
    };

    /// The defaults with another cell size.
    ///
    /// ```
    /// assert_eq!(sndt_core::Config::with_cell_size(0.2).cell_size, 0.2);
    /// ```
    pub const fn with_cell_size(cell_size: f32) -> Config {
        let mut c = Config::DEFAULT;
        c.cell_size = cell_size;
        c
    }

    /// Quantisation step in metres (`cell_size / 2^quant_bits`).
    ///
    /// ```
    /// assert_eq!(sndt_core::Config::DEFAULT.quant_step(), 0.1 / 64.0);
    /// ```
    pub fn quant_step(&self) -> f32 {
        self.cell_size / (1u32 << self.quant_bits.min(Self::MAX_QUANT_BITS)) as f32
    }

    /// Longest ray in cells: [`Config::max_range`] is at most `MAX_RAY_CELLS` times
    /// [`Config::cell_size`] (409.6 m at 10 cm, 204.8 m at 5 cm, 4.096 m at the smallest
    /// cell of 1 mm).
    ///
    /// The work of a frame grows with the length of its rays in voxels: every free-space
    /// ray walks up to `max_range / cell_size` voxels (and may touch an occupancy block
    /// every few of them), and so does every rendering ray. Without this bound a config
    /// (or a snapshot's) with `max_range` = 10 km at 10 cm was valid, its rays as long as
    /// the key range allows (tens of thousands of cells): a frame of 1000 points 2.8 km
    /// away took 0.45 s to integrate (x86-64, release), against 0.06 s at this bound and
    /// 2 ms at the default 20 m. 4096 cells keep a ray within an eighth of the key range
    /// ([`crate::KEY_LIMIT`] cells from the origin on each axis), so a ray from a sensor
    /// near the origin stays inside it, and leave room for long-range sensors at useful
    /// cell sizes (a 200 m lidar at 5 cm).
    pub const MAX_RAY_CELLS: u32 = 4096;

    /// Checks every field; a map only ever holds a valid config. The error names the
    /// first field, in the order of [`ConfigField::ALL`], that is out of its range.
    ///
    /// ```
    /// use sndt_core::{Config, ConfigField, Error};
    /// let mut c = Config::DEFAULT;
    /// c.cell_size = f32::NAN;
    /// assert_eq!(c.validate(), Err(Error::InvalidConfig(ConfigField::CellSize)));
    /// // 10 km rays at 10 cm are 100,000 cells: more than `MAX_RAY_CELLS`.
    /// let mut c = Config::DEFAULT;
    /// c.max_range = 10_000.0;
    /// assert_eq!(c.validate(), Err(Error::InvalidConfig(ConfigField::RayCells)));
    /// c.cell_size = 2.5; // 4000 cells of 2.5 m
    /// assert!(c.validate().is_ok());
    /// ```
    pub const fn validate(&self) -> Result<(), Error> {
        const fn within(x: f32, lo: f32, hi: f32) -> bool {
            // False for NaN.
            x >= lo && x <= hi
        }
        use ConfigField as F;
        // In the order of `ConfigField::ALL`. `max_range <= MAX_RAY_CELLS * cell_size` is
        // exact in f32 (a power-of-two multiple), and false for NaN.
        let step = self.see_through_miss * LOGODDS_ONE;
        let checks: [(bool, ConfigField); 18] = [
            (within(self.cell_size, 1e-3, 100.0), F::CellSize),
            (
                self.quant_bits >= 1 && self.quant_bits <= Self::MAX_QUANT_BITS,
                F::QuantBits,
            ),
            (self.n_min >= 2, F::NMin),
            (within(self.eigen_ratio, 1e-9, 0.5), F::EigenRatio),
            (self.n_max >= self.n_min && self.n_max <= 65535, F::NMax),
            (within(self.hit, 0.0, 30.0), F::Hit),
            (within(self.miss, -30.0, 0.0), F::Miss),
            (within(self.clamp_min, -30.0, 0.0), F::ClampMin),
            (within(self.clamp_max, 0.0, 30.0), F::ClampMax),
            (within(self.lambda, 0.0, 0.49), F::Lambda),
            (
                within(self.see_through_miss, -30.0, 0.0) && step == step as i32 as f32,
                F::SeeThroughMiss,
            ),
            (within(self.noise_base, 1e-6, 1e3), F::NoiseBase),
            (within(self.noise_quadratic, 0.0, 1e3), F::NoiseQuadratic),
            (within(self.max_range, 1e-3, 1e4), F::MaxRange),
            (
                self.max_range <= Self::MAX_RAY_CELLS as f32 * self.cell_size,
                F::RayCells,
            ),
            (self.top_k >= 1 && self.top_k as usize <= MAX_TOP_K, F::TopK),
            (
                self.votes_per_frame >= 1 && self.votes_per_frame <= 64,
                F::VotesPerFrame,
            ),
            (within(self.render_radius, 0.1, 10.0), F::RenderRadius),
        ];
        let mut i = 0;
        while i < checks.len() {
            if !checks[i].0 {
                return Err(Error::InvalidConfig(checks[i].1));
            }
            i += 1;
        }
        Ok(())
    }
}

// A ray of the longest length from a sensor at the origin stays inside the key range.
const _: () = assert!(Config::MAX_RAY_CELLS < KEY_LIMIT as u32);

/// The field and the range [`Config::validate`] wants it in, e.g. `cell_size must be a
/// number of metres in [0.001, 100]`.
impl fmt::Display for ConfigField {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let name = self.name();
        match self {
            ConfigField::CellSize => write!(f, "{name} must be a number of metres in [0.001, 100]"),
            ConfigField::QuantBits => {
                write!(f, "{name} must be in 1..={}", Config::MAX_QUANT_BITS)
            }
            ConfigField::NMin => write!(f, "{name} must be at least 2"),
            ConfigField::EigenRatio => write!(f, "{name} must be in [1e-9, 0.5]"),
            ConfigField::NMax => write!(f, "{name} must be in [n_min, 65535]"),
            ConfigField::Hit => write!(f, "{name} must be in [0, 30]"),
            ConfigField::Miss | ConfigField::ClampMin => write!(f, "{name} must be in [-30, 0]"),
            ConfigField::ClampMax => write!(f, "{name} must be in [0, 30]"),
            ConfigField::Lambda => write!(f, "{name} must be in [0, 0.49]"),
            ConfigField::SeeThroughMiss => {
                write!(f, "{name} must be in [-30, 0] and a multiple of 1/1024")
            }
            ConfigField::NoiseBase => {
                write!(f, "{name} must be a number of metres in [1e-6, 1000]")
            }
            ConfigField::NoiseQuadratic => write!(f, "{name} must be in [0, 1000]"),
            ConfigField::MaxRange => {
                write!(f, "{name} must be a number of metres in [0.001, 10000]")
            }
            ConfigField::RayCells => write!(
                f,
                "{name} must be at most {} cells (one ray's length in voxels)",
                Config::MAX_RAY_CELLS
            ),
            ConfigField::TopK => write!(f, "{name} must be in 1..={MAX_TOP_K}"),
            ConfigField::VotesPerFrame => write!(f, "{name} must be in 1..=64"),
            ConfigField::RenderRadius => write!(f, "{name} must be in [0.1, 10]"),
        }
    }
}

impl Default for Config {
    fn default() -> Self {
        Config::DEFAULT
    }
}

/// Fixed-point scale of log-odds: one natural log-odds unit is `LOGODDS_ONE` in an `i16`.
pub const LOGODDS_ONE: f32 = 1024.0;

/// Converts natural log-odds to the map's fixed point (round to nearest), clamped to
/// +-64 so that adding it to an `i16` cell in `i32` can never overflow (NaN gives 0).
#[inline]
pub(crate) fn to_fixed(l: f32) -> i32 {
    let l = if l.is_nan() {
        0.0
    } else {
        l.clamp(-64.0, 64.0)
    };
    libm::roundf(l * LOGODDS_ONE) as i32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::*;
    use crate::*;

    /// Regression: `hit` was unbounded: `to_fixed(3e6)` saturated to `i32::MAX` and the second hit
    /// overflowed. Now `hit` is limited to 30 and `to_fixed` clamps; the largest valid hit
    /// saturates at the clamp.
    #[test]
    fn large_valid_hit_overflows_log_odds() {
        let mut cfg = Config::DEFAULT;
        cfg.hit = 3e6;
        assert_eq!(cfg.validate(), Err(Error::InvalidConfig(ConfigField::Hit)));
        cfg.hit = 30.0;
        assert!(cfg.validate().is_ok());
        let mut map: Map<16, 16, 1> = Map::try_new(cfg).unwrap();
        let pts = [lp(0.05, 0.05, 1.05, 1)];
        map.integrate(&Isometry3::identity(), &pts).unwrap();
        map.integrate(&Isometry3::identity(), &pts).unwrap();
        assert_eq!(map.log_odds(&key(0, 0, 10)), 3.5);
    }

    /// Regression: Same for `miss` (was `cell + i32::MIN` on the second miss).
    #[test]
    fn large_valid_miss_overflows_log_odds() {
        let mut cfg = Config::DEFAULT;
        cfg.miss = -3e6;
        assert_eq!(cfg.validate(), Err(Error::InvalidConfig(ConfigField::Miss)));
        cfg.miss = -30.0;
        assert!(cfg.validate().is_ok());
        let mut map: Map<16, 16, 1> = Map::try_new(cfg).unwrap();
        let pts = [lp(0.05, 0.05, 1.05, 1)];
        map.integrate(&Isometry3::identity(), &pts).unwrap();
        map.integrate(&Isometry3::identity(), &pts).unwrap();
        assert_eq!(map.log_odds(&key(0, 0, 5)), -2.0);
    }

    /// One config per field that breaks only that field (`ConfigField::ALL` order): the
    /// error names it, and its message names the field and its range.
    #[test]
    fn every_field_is_named() {
        let edits: [fn(&mut Config); 18] = [
            |c| c.cell_size = 0.0,
            |c| c.quant_bits = 7,
            |c| c.n_min = 1,
            |c| c.eigen_ratio = 0.0,
            |c| c.n_max = 70_000,
            |c| c.hit = -1.0,
            |c| c.miss = 0.5,
            |c| c.clamp_min = 0.5,
            |c| c.clamp_max = -0.5,
            |c| c.lambda = 0.5,
            |c| c.see_through_miss = -1.4,
            |c| c.noise_base = 0.0,
            |c| c.noise_quadratic = -1.0,
            |c| c.max_range = f32::INFINITY,
            |c| c.max_range = 409.7, // 4097 cells of 10 cm
            |c| c.top_k = 0,
            |c| c.votes_per_frame = 65,
            |c| c.render_radius = 11.0,
        ];
        for (edit, field) in edits.iter().zip(ConfigField::ALL) {
            let mut c = Config::DEFAULT;
            edit(&mut c);
            assert_eq!(c.validate(), Err(Error::InvalidConfig(field)), "{c:?}");
            let mut text = heapless::String::<128>::new();
            core::fmt::write(&mut text, format_args!("{}", Error::InvalidConfig(field))).unwrap();
            assert!(text.starts_with("invalid config: ") && text.contains(field.name()));
            assert!(text.contains(" must be "), "{text}");
        }
    }

    /// `max_range` may be exactly `MAX_RAY_CELLS` cells, not more, at any cell size; the
    /// default and the fixtures' configs stay valid.
    #[test]
    fn ray_length_is_bounded_in_cells() {
        for h in [0.001f32, 0.05, 0.1, 0.125, 2.5, 100.0] {
            let mut c = Config::with_cell_size(h);
            c.max_range = (Config::MAX_RAY_CELLS as f32 * h).min(1e4);
            assert!(c.validate().is_ok(), "{h}");
            if c.max_range < 1e4 {
                c.max_range = f32::from_bits(c.max_range.to_bits() + 1);
                let e = c.validate();
                assert_eq!(e, Err(Error::InvalidConfig(ConfigField::RayCells)), "{h}");
            }
        }
        assert!(Config::DEFAULT.validate().is_ok());
        // 1 mm cells with the default 20 m range: 20,000 cells per ray.
        let e = Config::with_cell_size(0.001).validate();
        assert_eq!(e, Err(Error::InvalidConfig(ConfigField::RayCells)));
    }

    /// The error stays one byte: the field shares the byte with the other variants.
    #[test]
    fn error_is_one_byte() {
        assert_eq!(core::mem::size_of::<Error>(), 1);
        assert_eq!(core::mem::size_of::<ConfigField>(), 1);
        assert_eq!(core::mem::size_of::<Result<(), Error>>(), 1);
    }
}
