//! The baselines S-NDT is compared with: S-BKI (Gan et al., RA-L 2020) and the paper's
//! optimised OS-BKI (the paper's section III-B); `docs/EVALUATION.md` (evaluation
//! protocol, baselines) sums them up.
//!
//! Both run Bayesian kernel inference on a voxel grid: every training point (a labelled
//! hit, or a free sample along a ray) adds the sparse kernel `k(|x - x_i|)` to one
//! Dirichlet count of every voxel centre `x` within the kernel length. They differ in what
//! the counts mean when read:
//! - **S-BKI** has 1 + n classes, free among them: a voxel is free when the free count is
//!   the largest, otherwise its class is the largest count. Where a noisy segmentation
//!   splits the hits of a surface over several classes, free outvotes each of them and the
//!   surface gets holes — the failure the paper describes.
//! - **OS-BKI** first decides free vs occupied with binary BGK inference over all samples
//!   (`alpha` = kernel weight of hits, `beta` = of free samples), then takes the class from
//!   the semantic counts of labelled hits only, and only where the voxel is occupied.
//!
//! Step 1 of OS-BKI sums exactly the kernel weights step 2 splits by class (plus hits
//! without a class), so one set of per-voxel counts `[free, class 1..=40, unclassified]`
//! serves both read-outs: [`BkiMap`] is updated once and read as either [`Readout`].
//!
//! Training data per frame follows S-BKI's code: hits within `max_range` are down-sampled on
//! a world-aligned grid of `ds_resolution` (centroid, majority label); each down-sampled hit
//! casts a beam from the camera with free samples every `free_resolution` up to one at
//! `free_resolution` before the hit (none closer), plus the camera position itself; the
//! free samples are down-sampled the same way. Only voxels within the kernel length of some sample receive
//! evidence; a voxel without evidence is unknown (neither free nor occupied).
//!
//! The kernel is evaluated exactly over its whole support (S-BKI's code truncates it at a
//! block's face neighbours; results here must not depend on the spatial index).
//! Voxels live in hashed blocks of 8^3.

pub use crate::baselines::label_grid::LabelGrid;
use crate::dataset::frame::{Frame, LabelSource};
use crate::mapping::{LabelView, SemanticMap};
use anyhow::{bail, Result};
use nalgebra::{Point3, Vector3};
use rustc_hash::FxHashMap;
use sndt_core::{validate_pose, INVALID_LABEL};

/// Dirichlet counts per voxel: free, classes 1..=40, hits without a class (void).
pub const COUNT_BINS: usize = 42;
/// Count index of the free class.
pub const FREE: usize = 0;
/// Count index of occupied evidence without a class (hits labelled void).
pub const UNCLASSIFIED: usize = COUNT_BINS - 1;

const BLOCK_BITS: i32 = 3;
const BLOCK_SIDE: i32 = 1 << BLOCK_BITS;
const BLOCK_VOXELS: usize = 1 << (3 * BLOCK_BITS);
const KERNEL_TABLE: usize = 4096;

/// How the counts are read: the original or the paper's optimised inference.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub enum Readout {
    /// S-BKI: free is one of 1 + n classes.
    Sbki,
    /// OS-BKI: binary occupancy first, class from labelled hits only.
    Osbki,
}

/// Parameters of S-BKI / OS-BKI.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BkiConfig {
    /// Voxel side, metres.
    pub cell_size: f32,
    /// Kernel length `l`, metres (the paper: 0.1-0.4).
    pub kernel_length: f32,
    /// Kernel scale `sigma0` (S-BKI's config: 10).
    pub sigma0: f32,
    /// Dirichlet / Beta prior pseudo-count per class (S-BKI: 0.001).
    pub prior: f32,
    /// Spacing of free samples along each beam, metres (default 0.3, whatever the cell
    /// size).
    pub free_resolution: f32,
    /// Down-sampling grid for hits and free samples, metres; `<= 0` keeps every sample
    /// (default: the cell size).
    pub ds_resolution: f32,
    /// Hits farther than this from the camera are dropped, metres (default 20, as S-NDT).
    pub max_range: f32,
    /// OS-BKI: a voxel is occupied when `(alpha + prior) / (alpha + beta + 2 prior)` exceeds
    /// this (default 0.5: occupied evidence outweighs free evidence, the binary
    /// counterpart of S-BKI's argmax).
    pub occupied_threshold: f32,
}

impl BkiConfig {
    /// The configuration used for the paper's comparison at `cell_size` with kernel length
    /// `kernel_length`: sigma0 10 and prior 0.001 from S-BKI's published configuration,
    /// down-sampling at the cell size as S-BKI's configuration for depth images (KITTI 15),
    /// free samples every 0.3 m along each beam (BGKOctoMap's published configurations use
    /// 0.2-0.5 m; one sample per cell crossed made every kernel of more than two cells read
    /// 30-90 % of the surface voxels free in both read-outs on the synthetic split), max
    /// range 20 m, occupancy threshold 0.5.
    ///
    /// ```
    /// let c = sndt_host::baselines::bki::BkiConfig::new(0.1, 0.3);
    /// assert_eq!((c.sigma0, c.prior, c.ds_resolution), (10.0, 0.001, 0.1));
    /// assert!(c.validate().is_ok());
    /// ```
    pub fn new(cell_size: f32, kernel_length: f32) -> BkiConfig {
        BkiConfig {
            cell_size,
            kernel_length,
            sigma0: 10.0,
            prior: 0.001,
            free_resolution: 0.3,
            ds_resolution: cell_size,
            max_range: 20.0,
            occupied_threshold: 0.5,
        }
    }

    /// Checks every parameter is finite and in range.
    ///
    /// ```
    /// let mut c = sndt_host::baselines::bki::BkiConfig::new(0.1, 0.3);
    /// c.kernel_length = f32::NAN;
    /// assert!(c.validate().is_err());
    /// ```
    pub fn validate(&self) -> Result<()> {
        let ok = |x: f32, lo: f32, hi: f32| x.is_finite() && x >= lo && x <= hi;
        let valid = ok(self.cell_size, 1e-3, 10.0)
            && ok(self.kernel_length, 1e-3, 10.0)
            && ok(self.sigma0, 1e-6, 1e6)
            && ok(self.prior, 1e-9, 1e3)
            && ok(self.free_resolution, 1e-3, 1e3)
            && self.ds_resolution.is_finite()
            && self.ds_resolution <= 10.0
            && ok(self.max_range, 1e-3, 1e4)
            && ok(self.occupied_threshold, 0.0, 1.0);
        if !valid {
            bail!("invalid BKI configuration {self:?}");
        }
        Ok(())
    }
}

/// The sparse kernel of S-BKI at distance `d` for length `l`:
/// `sigma0 [ (2 + cos 2 pi r)(1 - r) / 3 + sin(2 pi r) / (2 pi) ]`, `r = d / l`, for
/// `r < 1`, else 0.
///
/// ```
/// use sndt_host::baselines::bki::kernel;
/// assert_eq!(kernel(0.0, 0.3, 10.0), 10.0);
/// assert!((kernel(0.15, 0.3, 10.0) - 10.0 / 6.0).abs() < 1e-5);
/// assert_eq!(kernel(0.3, 0.3, 10.0), 0.0);
/// ```
pub fn kernel(d: f32, l: f32, sigma0: f32) -> f32 {
    let r = (d / l) as f64;
    if !(0.0..1.0).contains(&r) {
        return 0.0;
    }
    let a = 2.0 * core::f64::consts::PI * r;
    let k = (2.0 + a.cos()) * (1.0 - r) / 3.0 + a.sin() / (2.0 * core::f64::consts::PI);
    (sigma0 as f64 * k).max(0.0) as f32
}

/// The kernel tabulated over `s = d^2 / l^2` (smooth in `s`: its odd terms in `r` cancel
/// near 0), interpolated linearly; within 1e-5 sigma0 of [`kernel`].
#[derive(Clone, Debug)]
struct KernelTable {
    l2: f32,
    scale: f32,
    values: Vec<f32>,
}

impl KernelTable {
    fn new(l: f32, sigma0: f32) -> KernelTable {
        let values = (0..=KERNEL_TABLE + 1)
            .map(|i| {
                let s = (i as f64 / KERNEL_TABLE as f64).min(1.0);
                kernel((s.sqrt() * l as f64) as f32, l, sigma0)
            })
            .collect();
        KernelTable {
            l2: l * l,
            scale: KERNEL_TABLE as f32 / (l * l),
            values,
        }
    }

    #[inline]
    fn at(&self, d2: f32) -> f32 {
        let x = d2 * self.scale;
        let i = x as usize;
        let f = x - i as f32;
        let (a, b) = (self.values[i], self.values[i + 1]);
        a + (b - a) * f
    }
}

type Counts = [f32; COUNT_BINS];

/// What one frame's update did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BkiReport {
    /// Hits within range.
    pub hits: usize,
    /// Labelled training points after down-sampling.
    pub hit_samples: usize,
    /// Free training points after down-sampling.
    pub free_samples: usize,
}

/// A training point: position and count index.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// World position, metres.
    pub position: [f32; 3],
    /// Count index: [`FREE`], a class 1..=40 or [`UNCLASSIFIED`].
    pub bin: usize,
}

/// An S-BKI / OS-BKI map: Dirichlet counts per voxel in hashed 8^3 blocks.
#[derive(Clone, Debug)]
pub struct BkiMap {
    config: BkiConfig,
    table: KernelTable,
    /// Per block, counts bin-major (`[bin * 512 + voxel]`): one sample adds to one bin, so
    /// its kernel footprint is contiguous in memory.
    blocks: FxHashMap<[i32; 3], Box<[f32]>>,
    /// Voxels that held a down-sampled hit in some frame: one bit per voxel, per block.
    surface: FxHashMap<[i32; 3], [u64; BLOCK_VOXELS / 64]>,
}

impl BkiMap {
    /// An empty map.
    ///
    /// ```
    /// let map = sndt_host::baselines::bki::BkiMap::new(sndt_host::baselines::bki::BkiConfig::new(0.1, 0.2)).unwrap();
    /// assert_eq!(map.block_count(), 0);
    /// ```
    pub fn new(config: BkiConfig) -> Result<BkiMap> {
        config.validate()?;
        Ok(BkiMap {
            config,
            table: KernelTable::new(config.kernel_length, config.sigma0),
            blocks: FxHashMap::default(),
            surface: FxHashMap::default(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &BkiConfig {
        &self.config
    }

    /// Number of allocated 8^3 blocks.
    pub fn block_count(&self) -> usize {
        self.blocks.len()
    }

    /// Bytes held by the counts.
    pub fn bytes(&self) -> usize {
        self.blocks.len() * BLOCK_VOXELS * core::mem::size_of::<Counts>()
    }

    /// Integrates one frame: `labels` (0 void, 1..=40; `None` = no classes) are the
    /// per-pixel labels to use, e.g. the frame's ground truth or a prediction's top 1.
    ///
    /// ```
    /// use sndt_host::baselines::bki::{BkiConfig, BkiMap, Readout};
    /// use sndt_host::dataset::{Dataset};
    /// use sndt_host::dataset::{open_spec};
    /// let data = open_spec("synthetic:1:1", &Default::default()).unwrap();
    /// let frame = data.load(&data.frames()[0]).unwrap();
    /// let mut map = BkiMap::new(BkiConfig::new(0.2, 0.3)).unwrap();
    /// let report = map.integrate(&frame, frame.labels.as_deref()).unwrap();
    /// assert!(report.hit_samples > 100 && report.free_samples > 100);
    /// ```
    pub fn integrate(&mut self, frame: &Frame, labels: Option<&[u8]>) -> Result<BkiReport> {
        if let Some(l) = labels {
            if l.len() != frame.pixels() {
                bail!(
                    "{}: {} labels for {} pixels",
                    frame.id,
                    l.len(),
                    frame.pixels()
                );
            }
            if let Some(&bad) = l.iter().find(|&&c| c as usize >= UNCLASSIFIED) {
                bail!("{}: label {bad} out of range 0..=40", frame.id);
            }
        }
        let pose = &frame.pose;
        if validate_pose(pose).is_err() {
            bail!(
                "{}: pose is not finite or its rotation is not unit",
                frame.id
            );
        }
        let t = pose.translation.vector;
        let origin = [t.x, t.y, t.z];
        let max2 = self.config.max_range * self.config.max_range;
        let mut hits = Downsampler::new(self.config.ds_resolution);
        let mut n_hits = 0;
        frame.for_each_camera_point(1, |i, p| {
            let p = pose * Point3::from(p);
            let d = Vector3::new(p.x - origin[0], p.y - origin[1], p.z - origin[2]);
            if d.norm_squared() > max2 || !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
                return;
            }
            let bin = match labels.map_or(0, |l| l[i]) {
                0 => UNCLASSIFIED,
                c => c as usize,
            };
            hits.add([p.x, p.y, p.z], bin);
            n_hits += 1;
        });
        let hit_samples = hits.samples();
        let free = free_samples(&origin, &hit_samples, self.config);
        for s in hit_samples.iter().chain(&free) {
            self.add_sample(s);
        }
        for s in &hit_samples {
            let key = s
                .position
                .map(|x| (x / self.config.cell_size).floor() as i32);
            let i = voxel_index(key);
            let bits = self
                .surface
                .entry(key.map(|v| v >> BLOCK_BITS))
                .or_default();
            bits[i / 64] |= 1 << (i % 64);
        }
        Ok(BkiReport {
            hits: n_hits,
            hit_samples: hit_samples.len(),
            free_samples: free.len(),
        })
    }

    /// Adds one training point's kernel weight to every voxel within the kernel length.
    ///
    /// ```
    /// use sndt_host::baselines::bki::{BkiConfig, BkiMap, Sample, kernel};
    /// let mut map = BkiMap::new(BkiConfig::new(0.1, 0.3)).unwrap();
    /// map.add_sample(&Sample { position: [0.05, 0.05, 0.05], bin: 7 });
    /// assert_eq!(map.counts([0, 0, 0]).unwrap()[7], 10.0);
    /// let k = map.counts([1, 0, 0]).unwrap()[7];
    /// assert!((k - kernel(0.1, 0.3, 10.0)).abs() < 1e-4);
    /// ```
    pub fn add_sample(&mut self, s: &Sample) {
        let res = self.config.cell_size;
        let l = self.config.kernel_length;
        let l2 = self.table.l2;
        let p = s.position;
        if s.bin >= COUNT_BINS || !p.iter().all(|x| x.is_finite() && x.abs() < 1e6) {
            return;
        }
        // Voxel i's centre is (i + 0.5) res; those within l of p on each axis.
        let lo = p.map(|x| ((x - l) / res - 0.5).ceil() as i32);
        let hi = p.map(|x| ((x + l) / res - 0.5).floor() as i32);
        let centre = |i: i32, axis: usize| (i as f32 + 0.5) * res - p[axis];
        for bz in lo[2] >> BLOCK_BITS..=hi[2] >> BLOCK_BITS {
            for by in lo[1] >> BLOCK_BITS..=hi[1] >> BLOCK_BITS {
                for bx in lo[0] >> BLOCK_BITS..=hi[0] >> BLOCK_BITS {
                    let b = [bx, by, bz];
                    let first = b.map(|v| v << BLOCK_BITS);
                    let from: [i32; 3] = core::array::from_fn(|a| lo[a].max(first[a]));
                    let to: [i32; 3] =
                        core::array::from_fn(|a| hi[a].min(first[a] + BLOCK_SIDE - 1));
                    // Skip blocks whose nearest voxel centre is out of reach.
                    let near2: f32 = (0..3)
                        .map(|a| {
                            let (a0, a1) = (centre(from[a], a), centre(to[a], a));
                            let d = if a0 > 0.0 {
                                a0
                            } else if a1 < 0.0 {
                                a1
                            } else {
                                0.0
                            };
                            d * d
                        })
                        .sum();
                    if near2 >= l2 {
                        continue;
                    }
                    let block = self
                        .blocks
                        .entry(b)
                        .or_insert_with(|| vec![0.0; COUNT_BINS * BLOCK_VOXELS].into_boxed_slice());
                    let counts = &mut block[s.bin * BLOCK_VOXELS..(s.bin + 1) * BLOCK_VOXELS];
                    for z in from[2]..=to[2] {
                        let dz = centre(z, 2);
                        let dz2 = dz * dz;
                        if dz2 >= l2 {
                            continue;
                        }
                        for y in from[1]..=to[1] {
                            let dy = centre(y, 1);
                            let dyz2 = dz2 + dy * dy;
                            if dyz2 >= l2 {
                                continue;
                            }
                            let row = (((z - first[2]) << BLOCK_BITS | (y - first[1]))
                                << BLOCK_BITS) as usize;
                            // The whole row, with the test inside: a fixed short range
                            // runs faster than one clipped to the sphere (measured).
                            for x in from[0]..=to[0] {
                                let dx = centre(x, 0);
                                let d2 = dyz2 + dx * dx;
                                if d2 < l2 {
                                    counts[row + (x - first[0]) as usize] += self.table.at(d2);
                                }
                            }
                        }
                    }
                }
            }
        }
    }

    /// The evidence counts of voxel `key` (integer voxel coordinates: voxel `i` spans
    /// `[i, i + 1) cell_size` on each axis), without the prior; `None` if never touched.
    pub fn counts(&self, key: [i32; 3]) -> Option<Counts> {
        let block = self.blocks.get(&key.map(|v| v >> BLOCK_BITS))?;
        Some(voxel_counts(block, voxel_index(key)))
    }

    /// How `readout` reads the surface: the voxels that held a down-sampled hit in some
    /// frame, counted as free (holes), unknown and occupied.
    ///
    /// ```
    /// use sndt_host::baselines::bki::{BkiConfig, BkiMap, Readout};
    /// use sndt_host::dataset::{Dataset};
    /// use sndt_host::dataset::{open_spec};
    /// let data = open_spec("synthetic:1:1", &Default::default()).unwrap();
    /// let frame = data.load(&data.frames()[0]).unwrap();
    /// let mut map = BkiMap::new(BkiConfig::new(0.2, 0.3)).unwrap();
    /// map.integrate(&frame, frame.labels.as_deref()).unwrap();
    /// let s = map.surface_states(Readout::Osbki);
    /// assert!(s.voxels > 100 && s.free + s.unknown + s.occupied == s.voxels);
    /// ```
    pub fn surface_states(&self, readout: Readout) -> SurfaceStates {
        let mut out = SurfaceStates::default();
        for (b, bits) in &self.surface {
            for i in 0..BLOCK_VOXELS {
                if bits[i / 64] >> (i % 64) & 1 == 0 {
                    continue;
                }
                let o = [i & 7, (i >> 3) & 7, i >> 6];
                let key: [i32; 3] = core::array::from_fn(|a| (b[a] << BLOCK_BITS) + o[a] as i32);
                out.voxels += 1;
                match self.voxel(key, readout) {
                    VoxelState::Free => out.free += 1,
                    VoxelState::Unknown => out.unknown += 1,
                    VoxelState::Occupied(_) => out.occupied += 1,
                }
            }
        }
        out
    }

    /// The state of voxel `key` as `readout` sees it.
    pub fn voxel(&self, key: [i32; 3], readout: Readout) -> VoxelState {
        self.counts(key)
            .map_or(VoxelState::Unknown, |c| self.state(&c, readout))
    }

    fn state(&self, c: &Counts, readout: Readout) -> VoxelState {
        let total: f32 = c.iter().sum();
        if total <= 0.0 {
            return VoxelState::Unknown;
        }
        // Ties go to the lower index (free first), as S-BKI's std::max_element.
        let argmax = |range: core::ops::Range<usize>| {
            range.fold((usize::MAX, f32::NEG_INFINITY), |(bi, bv), i| {
                if c[i] > bv {
                    (i, c[i])
                } else {
                    (bi, bv)
                }
            })
        };
        let class_of = |bin: usize| if bin == UNCLASSIFIED { 0 } else { bin as u8 };
        match readout {
            Readout::Sbki => {
                // The prior is the same for every class, so it does not move the argmax.
                let (bin, _) = argmax(0..COUNT_BINS);
                if bin == FREE {
                    VoxelState::Free
                } else {
                    VoxelState::Occupied(class_of(bin))
                }
            }
            Readout::Osbki => {
                let beta = c[FREE];
                let alpha = total - beta;
                let prior = self.config.prior;
                let p = (alpha + prior) / (alpha + beta + 2.0 * prior);
                if p <= self.config.occupied_threshold {
                    return VoxelState::Free;
                }
                let (bin, v) = argmax(1..UNCLASSIFIED);
                VoxelState::Occupied(if v > 0.0 { class_of(bin) } else { 0 })
            }
        }
    }

    /// Every voxel's state for `readout` as a dense grid for ray casting.
    pub fn label_grid(&self, readout: Readout) -> LabelGrid {
        let Some(first) = self.blocks.keys().next() else {
            return LabelGrid::new(self.config.cell_size, [0; 3], [0; 3], Vec::new());
        };
        let (mut lo, mut hi) = (*first, *first);
        for k in self.blocks.keys() {
            for a in 0..3 {
                lo[a] = lo[a].min(k[a]);
                hi[a] = hi[a].max(k[a]);
            }
        }
        let origin = lo.map(|v| v << BLOCK_BITS);
        let dims: [usize; 3] =
            core::array::from_fn(|a| ((hi[a] - lo[a] + 1) << BLOCK_BITS) as usize);
        let mut cells = vec![INVALID_LABEL; dims[0] * dims[1] * dims[2]];
        for (k, block) in &self.blocks {
            for i in 0..BLOCK_VOXELS {
                if let VoxelState::Occupied(class) = self.state(&voxel_counts(block, i), readout) {
                    let o = [i & 7, (i >> 3) & 7, i >> 6];
                    let v: [usize; 3] = core::array::from_fn(|a| {
                        ((k[a] << BLOCK_BITS) - origin[a]) as usize + o[a]
                    });
                    cells[(v[2] * dims[1] + v[1]) * dims[0] + v[0]] = class;
                }
            }
        }
        LabelGrid::new(self.config.cell_size, origin, dims, cells)
    }
}

/// S-BKI and OS-BKI as the evaluation runs them: one count map, read out either way.
impl SemanticMap for BkiMap {
    type Readout = Readout;

    /// [`BkiMap::integrate`] with one label per pixel: the ground truth (`gt`), the
    /// prediction's top 1 (`pred`) or none; a frame without the labels asked for adds
    /// geometry only, as in S-NDT. BKI takes no top-k labels and maps every pixel, so
    /// `pred-topk` and a stride other than 1 are errors.
    fn integrate_frame(&mut self, frame: &Frame, labels: LabelSource, stride: u32) -> Result<()> {
        if stride != 1 {
            bail!(
                "{}: S-BKI / OS-BKI map every pixel, not stride {stride}",
                frame.id
            );
        }
        let top1: Vec<u8>;
        let labels = match labels {
            LabelSource::None => None,
            LabelSource::Gt => frame.labels.as_deref(),
            LabelSource::Pred => match &frame.predictions {
                Some(p) => {
                    top1 = p.top1();
                    Some(&top1[..])
                }
                None => None,
            },
            LabelSource::PredTopk => {
                bail!(
                    "{}: S-BKI / OS-BKI take one label per pixel (gt or pred)",
                    frame.id
                )
            }
        };
        self.integrate(frame, labels).map(|_| ())
    }

    /// The read-out as a dense [`LabelGrid`], built once.
    fn prepare(&self, readout: Readout) -> Box<dyn LabelView + '_> {
        Box::new(GridView {
            grid: self.label_grid(readout),
            max_range: self.config.max_range,
        })
    }

    /// The counts and the surface bits.
    fn memory_bytes(&self) -> usize {
        self.bytes() + self.surface.len() * BLOCK_VOXELS / 8
    }

    /// Voxels of the allocated blocks (every voxel within a kernel length of a sample).
    fn voxel_count(&self) -> usize {
        self.blocks.len() * BLOCK_VOXELS
    }
}

/// A read-out's label grid, rendered up to the map's `max_range`.
struct GridView {
    grid: LabelGrid,
    max_range: f32,
}

impl LabelView for GridView {
    fn render_frame(&self, frame: &Frame) -> Result<Vec<u8>> {
        Ok(self.grid.render(frame, self.max_range))
    }
}

/// Surface voxels of a map and how a read-out sees them ([`BkiMap::surface_states`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SurfaceStates {
    /// Voxels that held a down-sampled hit.
    pub voxels: u64,
    /// Of those, read as free: holes in the surface.
    pub free: u64,
    /// Of those, without evidence (kernel shorter than the sample's distance to the
    /// voxel centre).
    pub unknown: u64,
    /// Of those, occupied.
    pub occupied: u64,
}

/// Index of voxel `key` within its block.
fn voxel_index(key: [i32; 3]) -> usize {
    let o = key.map(|v| v & (BLOCK_SIDE - 1));
    ((o[2] << BLOCK_BITS | o[1]) << BLOCK_BITS | o[0]) as usize
}

/// Voxel `i`'s counts out of a bin-major block.
fn voxel_counts(block: &[f32], i: usize) -> Counts {
    core::array::from_fn(|bin| block[bin * BLOCK_VOXELS + i])
}

/// A voxel as a read-out sees it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VoxelState {
    /// No kernel evidence.
    Unknown,
    /// Free space.
    Free,
    /// Occupied, with class 0 (void: no class evidence) or 1..=40.
    Occupied(u8),
}

/// Accumulates samples per down-sampling cell (centroid and majority label), in order of
/// first appearance so the output is deterministic.
struct Downsampler {
    res: f32,
    index: FxHashMap<[i32; 3], u32>,
    cells: Vec<([f64; 3], u32, Counts)>,
    raw: Vec<Sample>,
    last: Option<([i32; 3], u32)>,
}

impl Downsampler {
    fn new(res: f32) -> Downsampler {
        Downsampler {
            res,
            index: FxHashMap::default(),
            cells: Vec::new(),
            raw: Vec::new(),
            last: None,
        }
    }

    fn add(&mut self, p: [f32; 3], bin: usize) {
        if self.res <= 0.0 {
            self.raw.push(Sample { position: p, bin });
            return;
        }
        let key = p.map(|x| (x / self.res).floor() as i32);
        let i = match self.last {
            Some((k, i)) if k == key => i,
            _ => {
                let n = self.cells.len() as u32;
                let i = *self.index.entry(key).or_insert(n);
                if i == n {
                    self.cells.push(([0.0; 3], 0, [0.0; COUNT_BINS]));
                }
                self.last = Some((key, i));
                i
            }
        };
        let cell = &mut self.cells[i as usize];
        for (sum, x) in cell.0.iter_mut().zip(p) {
            *sum += x as f64;
        }
        cell.1 += 1;
        cell.2[bin] += 1.0;
    }

    fn samples(self) -> Vec<Sample> {
        if self.res <= 0.0 {
            return self.raw;
        }
        self.cells
            .into_iter()
            .map(|(sum, n, votes)| {
                // Majority label; ties to the lower index.
                let mut bin = 0;
                for b in 1..COUNT_BINS {
                    if votes[b] > votes[bin] {
                        bin = b;
                    }
                }
                Sample {
                    position: sum.map(|s| (s / n as f64) as f32),
                    bin,
                }
            })
            .collect()
    }
}

/// Free samples of S-BKI's beam sampling for `hits` seen from `origin`, down-sampled.
fn free_samples(origin: &[f32; 3], hits: &[Sample], config: BkiConfig) -> Vec<Sample> {
    let f = config.free_resolution;
    let mut frees = Downsampler::new(config.ds_resolution);
    if !hits.is_empty() {
        frees.add(*origin, FREE);
    }
    for h in hits {
        let v: [f32; 3] = core::array::from_fn(|a| h.position[a] - origin[a]);
        let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if len <= 0.0 {
            continue;
        }
        let at = |d: f32| -> [f32; 3] { core::array::from_fn(|a| origin[a] + v[a] * (d / len)) };
        // Every f up to f before the hit, and one at exactly f before it. (S-BKI's code
        // also keeps the multiples of f between there and the hit, which can put a free
        // sample inside the surface's own cell; at cell-size spacing that erases surfaces
        // in either read-out, so no sample comes closer to a hit than f.)
        let last = len - f;
        let mut d = f;
        while d < last {
            frees.add(at(d), FREE);
            d += f;
        }
        if last > 0.0 {
            frees.add(at(last), FREE);
        }
    }
    frees.samples()
}
