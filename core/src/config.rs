//! The one plain configuration struct of the map, with documented defaults.

use crate::Error;

/// How a voxel traversed by a free-space ray loses occupancy.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MissModel {
    /// Occupancy-NDT (Saarinen et al.): a voxel with a valid Gaussian gets a miss weighted by
    /// how close the ray passes to its Gaussian, so grazing rays do not erase thin surfaces.
    /// Voxels without a valid Gaussian get [`Config::miss`].
    NdtOm,
    /// Every traversed voxel gets the constant [`Config::miss`] (classic OctoMap behaviour,
    /// kept to show why NDT-OM misses matter).
    Constant,
}

/// Map configuration. Every field is public; [`Config::DEFAULT`] documents the defaults.
///
/// ```
/// let mut config = sndt_core::Config::DEFAULT;
/// config.cell_size = 0.05;
/// assert!(config.validate().is_ok());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config {
    /// Voxel edge `h` in metres. Default 0.10.
    pub cell_size: f32,
    /// Point offsets inside a voxel are quantised to `h / 2^quant_bits`. Default 6
    /// (1.56 mm at 10 cm). At most [`Config::MAX_QUANT_BITS`] so the integer sums provably
    /// cannot overflow (see [`crate::MAX_FRAME_POINTS`]).
    pub quant_bits: u8,
    /// Points needed before a voxel's Gaussian is valid. Default 3 (at least 2).
    pub n_min: u32,
    /// Eigenvalues below `eigen_ratio * lambda_max` are raised to it before inversion.
    /// Default 1e-3.
    pub eigen_ratio: f32,
    /// Point cap: when a voxel holds more than `n_max` points at the end of a frame, its
    /// count and sums are halved until they fit (old data decays). Default 2048,
    /// range `[n_min, 65535]`.
    pub n_max: u32,
    /// Log-odds added once per frame to a voxel that received points. Default 0.85 (p = 0.7).
    pub hit: f32,
    /// Log-odds of a constant miss. Default -0.4 (p = 0.4).
    pub miss: f32,
    /// Lower log-odds clamp. Default -2.0.
    pub clamp_min: f32,
    /// Upper log-odds clamp. Default 3.5.
    pub clamp_max: f32,
    /// NDT-OM miss weight `lambda` in `p = 0.5 - lambda pN (1 - pz)`. Default 0.1.
    pub lambda: f32,
    /// Sensor range noise `sigma = noise_base + noise_quadratic * range^2` in metres, used
    /// by NDT-OM misses. Defaults 0.02 and 0.0025 (0.06 m at 4 m).
    pub noise_base: f32,
    /// See [`Config::noise_base`].
    pub noise_quadratic: f32,
    /// Points farther than this (metres) only clear free space up to it. Default 20.
    pub max_range: f32,
    /// How many of a point's labels vote in the class histogram (1..=3). Default 1.
    pub top_k: u8,
    /// Labels whose score (0..=255) is below this do not vote. Default 0.
    pub min_score: u8,
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
        noise_base: 0.02,
        noise_quadratic: 0.0025,
        max_range: 20.0,
        top_k: 1,
        min_score: 0,
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

    /// Checks every field; a map only ever holds a valid config.
    ///
    /// ```
    /// let mut c = sndt_core::Config::DEFAULT;
    /// c.cell_size = f32::NAN;
    /// assert_eq!(c.validate(), Err(sndt_core::Error::InvalidConfig));
    /// ```
    pub fn validate(&self) -> Result<(), Error> {
        let finite_pos = |x: f32| x.is_finite() && x > 0.0;
        let ok = finite_pos(self.cell_size)
            && self.cell_size <= 100.0
            && self.quant_bits >= 1
            && self.quant_bits <= Self::MAX_QUANT_BITS
            && self.n_min >= 2
            && self.n_max >= self.n_min
            && self.n_max <= 65535
            && finite_pos(self.eigen_ratio)
            && self.eigen_ratio < 1.0
            && self.hit.is_finite()
            && self.hit >= 0.0
            && self.miss.is_finite()
            && self.miss <= 0.0
            && self.clamp_min.is_finite()
            && self.clamp_max.is_finite()
            && self.clamp_min <= 0.0
            && self.clamp_max >= 0.0
            && self.clamp_min >= -30.0
            && self.clamp_max <= 30.0
            && self.lambda.is_finite()
            && (0.0..=0.5).contains(&self.lambda)
            && finite_pos(self.noise_base)
            && self.noise_quadratic.is_finite()
            && self.noise_quadratic >= 0.0
            && finite_pos(self.max_range)
            && self.top_k >= 1
            && self.top_k as usize <= crate::MAX_TOP_K
            && finite_pos(self.render_radius);
        if ok {
            Ok(())
        } else {
            Err(Error::InvalidConfig)
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

/// Converts natural log-odds to the map's fixed point (round to nearest).
pub(crate) fn to_fixed(l: f32) -> i32 {
    libm::roundf(l * LOGODDS_ONE) as i32
}
