//! What every mapper offers the evaluation: the [`SemanticMap`] trait, implemented by
//! S-NDT (the core's [`Map`], here), the f64 reference (`crate::reference::RefMap`) and
//! the baselines S-BKI / OS-BKI (`crate::baselines::bki::BkiMap`), so that the evaluation
//! runs every method through one loop: integrate each frame of a trajectory, then render
//! the final map into each frame's camera and score it.
//!
//! Rendering goes through a [`LabelView`], prepared once per map and read-out by
//! [`SemanticMap::prepare`]: some read-outs need work before the first ray (BKI builds a
//! dense label grid, the reference an index of its inverted covariances), and that work
//! must not be repeated for every frame. A map with a single read-out (S-NDT, the
//! reference) has `Readout = ()`.
//!
//! This module also holds the S-NDT side of the trait: [`integrate_frame`] (a dataset
//! frame into the core, as a depth image or as points) and [`backproject`] (the core's
//! render or ray casting into a frame's camera), and the evaluation's map capacity
//! [`HostMap`].

use crate::dataset::frame::{key_range_error, Frame, LabelSource, Rays};
use anyhow::{anyhow, Result};
use rayon::prelude::*;
use sndt_core::{
    Config, Depth, DepthImage, LabelImage, Labels, Map, Point3, RecordSink, Vector3, INVALID_LABEL,
};

/// The core map the host evaluates, compares and exports with: 2^19 surface voxels, 2^17
/// occupancy blocks, the 40 NYU40 classes (~74 MiB), large enough that a trajectory of a
/// room does not evict (evictions are reported).
pub type HostMap = Map<{ 1 << 19 }, { 1 << 17 }, 40>;

/// A semantic map the evaluation can build and score: S-NDT, the f64 reference, S-BKI /
/// OS-BKI.
///
/// ```
/// use sndt_host::dataset::{open_spec, Dataset, LabelSource};
/// use sndt_host::mapping::{boxed_map, HostMap, SemanticMap};
/// let data = open_spec("synthetic:1:2", &Default::default()).unwrap();
/// let frame = data.load(&data.frames()[0]).unwrap();
/// let mut map: Box<HostMap> = boxed_map(sndt_core::Config::with_cell_size(0.2)).unwrap();
/// map.integrate_frame(&frame, LabelSource::Gt, 1).unwrap();
/// assert!(map.voxel_count() > 100);
/// let view = map.prepare(());
/// let labels = view.render_frame(&frame).unwrap();
/// assert_eq!(labels.len(), frame.pixels());
/// assert!(labels.iter().all(|&l| l <= 40 || l == sndt_core::INVALID_LABEL));
/// ```
pub trait SemanticMap {
    /// The ways the map can be read out: `()` when there is only one.
    type Readout: Copy;

    /// Integrates one dataset frame at its pose, with labels from `labels` and every
    /// `stride`-th pixel in both directions (`stride` 1: every pixel, as the paper).
    fn integrate_frame(&mut self, frame: &Frame, labels: LabelSource, stride: u32) -> Result<()>;

    /// The map read out as `readout`, prepared for rendering any number of frames.
    fn prepare(&self, readout: Self::Readout) -> Box<dyn LabelView + '_>;

    /// Bytes of memory the map holds.
    fn memory_bytes(&self) -> usize;

    /// Voxels the map holds (what each implementation counts is documented on its impl).
    fn voxel_count(&self) -> usize;
}

/// A prepared read-out of a map, rendered into dataset frames (from any thread: the
/// comparison renders several maps at once).
pub trait LabelView: Sync {
    /// What the frame's camera sees of the map at the frame's pose: one label per pixel,
    /// row-major, 0 void, 1..=40 class, [`INVALID_LABEL`] where the ray hits nothing.
    fn render_frame(&self, frame: &Frame) -> Result<Vec<u8>>;
}

impl<T: LabelView + ?Sized> LabelView for &T {
    fn render_frame(&self, frame: &Frame) -> Result<Vec<u8>> {
        (**self).render_frame(frame)
    }
}

/// S-NDT: the core's map, read out by its own renderer.
impl<const V: usize, const B: usize, const C: usize> SemanticMap for Map<V, B, C> {
    type Readout = ();

    fn integrate_frame(&mut self, frame: &Frame, labels: LabelSource, stride: u32) -> Result<()> {
        integrate_frame(self, frame, labels, stride).map(|_| ())
    }

    /// The map itself: the core renders without preparation.
    fn prepare(&self, _: ()) -> Box<dyn LabelView + '_> {
        Box::new(self)
    }

    /// The map's fixed footprint: it never allocates.
    fn memory_bytes(&self) -> usize {
        core::mem::size_of::<Self>()
    }

    /// Surface voxels (those holding a Gaussian and class votes).
    fn voxel_count(&self) -> usize {
        self.len()
    }
}

/// The core's back-projection, [`backproject`].
impl<const V: usize, const B: usize, const C: usize> LabelView for Map<V, B, C> {
    fn render_frame(&self, frame: &Frame) -> Result<Vec<u8>> {
        backproject(self, frame)
    }
}

/// A map on the heap, built on a helper thread whose stack is large enough to hold it
/// (a `Map` of a million voxels is ~100 MB and would overflow the caller's stack when
/// constructed by value). No `unsafe` involved.
///
/// ```
/// let map = sndt_host::mapping::boxed_map::<1024, 256, 40>(sndt_core::Config::DEFAULT).unwrap();
/// assert!(map.is_empty());
/// ```
pub fn boxed_map<const V: usize, const B: usize, const C: usize>(
    config: Config,
) -> Result<Box<Map<V, B, C>>, sndt_core::Error> {
    config.validate()?;
    let stack = 4 * core::mem::size_of::<Map<V, B, C>>() + (16 << 20);
    std::thread::Builder::new()
        .name("sndt-map-alloc".into())
        .stack_size(stack)
        .spawn(move || Box::new(Map::new(config)))
        .expect("spawning the map allocation thread")
        .join()
        // `Map::new` does not panic; should the thread fail anyway, its panic goes on here.
        .map_or_else(|panic| std::panic::resume_unwind(panic), Ok)
}

/// Integrates one frame into `map` with labels from `source`: a pinhole frame as the core's
/// depth image (every `stride`-th pixel), a per-pixel-ray frame as sensor-frame points.
pub fn integrate_frame<const V: usize, const B: usize, const C: usize>(
    map: &mut Map<V, B, C>,
    frame: &Frame,
    source: LabelSource,
    stride: u32,
) -> Result<sndt_core::FrameReport> {
    integrate_frame_spilling(map, frame, source, stride, None)
}

/// [`integrate_frame`], handing what the map evicts to `sink` when there is one
/// (`Map::integrate_depth_spilling`).
pub fn integrate_frame_spilling<const V: usize, const B: usize, const C: usize>(
    map: &mut Map<V, B, C>,
    frame: &Frame,
    source: LabelSource,
    stride: u32,
    sink: Option<&mut dyn RecordSink>,
) -> Result<sndt_core::FrameReport> {
    let cell = map.config().cell_size;
    let err = |e: sndt_core::Error| match e {
        sndt_core::Error::PoseOutOfRange => anyhow!(
            "{}: integrate: {}",
            frame.id,
            key_range_error(&frame.pose, cell).unwrap_or_else(|| e.to_string())
        ),
        e => anyhow!("{}: integrate: {e}", frame.id),
    };
    match frame.rays.as_ref() {
        Rays::Pinhole(cam) => {
            let top1: Vec<u8>;
            let topk: Vec<Labels>;
            let labels = match source {
                LabelSource::None => LabelImage::None,
                LabelSource::Gt => match &frame.labels {
                    Some(l) => LabelImage::Top1(l),
                    None => LabelImage::None,
                },
                LabelSource::Pred => match &frame.predictions {
                    Some(p) => {
                        top1 = p.top1();
                        LabelImage::Top1(&top1)
                    }
                    None => LabelImage::None,
                },
                LabelSource::PredTopk => match &frame.predictions {
                    Some(p) => {
                        topk = (0..frame.pixels()).map(|i| p.labels(i)).collect();
                        LabelImage::TopK(&topk)
                    }
                    None => LabelImage::None,
                },
            };
            let image = DepthImage {
                camera: *cam,
                depth: Depth::Metres(&frame.depth),
                kind: frame.depth_kind,
                labels,
                stride,
            };
            sndt_dispatch::integrate_depth(map, &frame.pose, &image, sink).map_err(err)
        }
        Rays::PerPixel { .. } => {
            let points = frame.camera_points(source, stride);
            sndt_dispatch::integrate(map, &frame.pose, &points, sink).map_err(err)
        }
    }
}

/// Back-projects `map` into a frame's camera: one label per pixel (0..=40,
/// [`INVALID_LABEL`] where nothing is hit). A pinhole frame is rendered by the core's
/// `render_rows` in bands of rows, two per rayon thread (the pixels do not depend on the
/// bands, and each band culls the map on its own, so fewer bands waste less); a
/// per-pixel-ray frame by one `raycast` per pixel along its normalised ray.
pub fn backproject<const V: usize, const B: usize, const C: usize>(
    map: &Map<V, B, C>,
    frame: &Frame,
) -> Result<Vec<u8>> {
    let (w, h) = (frame.rays.width() as usize, frame.rays.height() as usize);
    let mut labels = vec![INVALID_LABEL; w * h];
    let band = h.div_ceil(2 * rayon::current_num_threads()).max(1);
    labels
        .par_chunks_mut(band * w.max(1))
        .enumerate()
        .try_for_each(|(i, out)| -> Result<()> {
            let row0 = i * band;
            match frame.rays.as_ref() {
                Rays::Pinhole(cam) => {
                    let mut dist = vec![0f32; out.len()];
                    map.render_rows(&frame.pose, cam, row0 as u32, out, &mut dist)
                        .map_err(|e| anyhow!("{}: render: {e:?}", frame.id))
                }
                Rays::PerPixel { .. } => {
                    raycast_rows(map, frame, row0, out);
                    Ok(())
                }
            }
        })?;
    Ok(labels)
}

/// Rows `row0..` of a per-pixel-ray frame, one `raycast` per pixel.
fn raycast_rows<const V: usize, const B: usize, const C: usize>(
    map: &Map<V, B, C>,
    frame: &Frame,
    row0: usize,
    out: &mut [u8],
) {
    let w = frame.rays.width() as usize;
    let o = frame.pose.translation.vector;
    let origin = Point3::new(o.x, o.y, o.z);
    for (i, px) in out.iter_mut().enumerate() {
        let (c, r) = ((i % w) as u32, (row0 + i / w) as u32);
        let ray = frame.rays.ray(c, r);
        let d = frame.pose.rotation * Vector3::new(ray[0], ray[1], ray[2]).normalize();
        *px = map
            .raycast(&origin, &d, map.config().max_range)
            .map_or(INVALID_LABEL, |hit| hit.class);
    }
}
