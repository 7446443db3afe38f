//! Frame integration: one frame of labelled points, or a depth image with labels, into the
//! map. [`Map::integrate`] and [`Map::integrate_depth`] run the same steps, each phase
//! ([`Phase`]) in the file of its name:
//!
//! 1. **validate the frame** (size, image, pose; an error leaves the map untouched) and
//!    start its state (`frame.rs`);
//! 2. phase 1, **turn pixels into points** ([`Phase::Points`], `points.rs`): in batches of
//!    64, world coordinates, voxel keys and offsets; pixels with the arithmetic of
//!    [`crate::depth_point`] (`geometry/camera.rs`);
//! 3. phase 1, **accumulate points per end voxel** ([`Phase::Accumulate`],
//!    `accumulate.rs`, and `accumulate_point.rs` for one point at a time): integer sums,
//!    histogram votes of a hashed sample (`storage/votes.rs`), the frame's list of touched
//!    blocks; a full table evicts far entries (`evict.rs`);
//! 4. phase 2, **apply one update per touched voxel** ([`Phase::EndVoxels`],
//!    `end_voxels.rs`): the list is sorted by key; each voxel that received points decays
//!    to `n_max`, gets one hit and sets its vote sampling for the next frame;
//! 5. phase 3, **free space along the rays** ([`Phase::FreeSpace`], `free_space.rs`): one
//!    ray per unique end voxel and per unique truncated end, in sorted order, at most one
//!    miss per traversed voxel.
//!
//! Phase 1 only adds to integer sums and sets per-frame masks, and phases 2 and 3 go in
//! key order, so the result does not depend on point order.

pub(crate) mod evict;

pub(crate) mod frame;

pub(crate) mod points;

pub(crate) mod accumulate_point;

pub(crate) mod accumulate;

pub(crate) mod end_voxels;

pub(crate) mod free_space;

use crate::error::Error;
use crate::geometry::camera::{DepthImage, LabelImage, PixelRays};
use crate::integrate::frame::{FrameReport, FrameState, Phase, Vectors, MAX_FRAME_POINTS};
use crate::integrate::points::{Batch, BATCH, TILE_COLS};
use crate::labels::{LabeledPoint, Labels};
use crate::storage::map::Map;
use crate::storage::record::RecordSink;
use nalgebra::Isometry3;

impl<const V: usize, const B: usize, const C: usize> Map<V, B, C> {
    /// Integrates one frame of labelled points given in the sensor frame at `pose`
    /// (sensor to world). Per-point problems are counted in the report; a bad pose or an
    /// oversized frame is an error and leaves the map untouched.
    ///
    /// Unless the map had to evict or drop updates during the frame, the result does not
    /// depend on the order of `points`.
    ///
    /// ```
    /// use sndt_core::*;
    /// let mut map: Map<64, 16, 4> = Map::new(Config::DEFAULT);
    /// let pts = [
    ///     LabeledPoint::new(Point3::new(0.0, 0.0, 1.0), Labels::top1(1)),
    ///     LabeledPoint::new(Point3::new(0.0, 0.0, f32::NAN), Labels::top1(1)),
    ///     LabeledPoint::new(Point3::new(0.0, 0.0, 1.0), Labels::top1(9)),
    /// ];
    /// let r = map.integrate(&Isometry3::identity(), &pts).unwrap();
    /// assert_eq!((r.points_used, r.rejected_depth, r.rejected_label), (1, 1, 1));
    /// ```
    pub fn integrate(
        &mut self,
        pose: &Isometry3<f32>,
        points: &[LabeledPoint],
    ) -> Result<FrameReport, Error> {
        self.integrate_points(pose, points, |_| {}, (None, Vectors::AsBuilt))
    }

    /// Integrates a depth image with labels (see [`DepthImage`]); invalid depths are
    /// counted in `rejected_depth`.
    pub fn integrate_depth(
        &mut self,
        pose: &Isometry3<f32>,
        image: &DepthImage<'_>,
    ) -> Result<FrameReport, Error> {
        self.integrate_depth_image(pose, image, |_| {}, (None, Vectors::AsBuilt))
    }

    /// [`Map::integrate`] with an optional sink ([`Map::integrate_spilling`]), for code
    /// running with the vector instructions `vectors` (see [`Vectors`]; the map is the
    /// same whatever they are).
    ///
    /// ```
    /// use sndt_core::*;
    /// let mut map: Map<64, 16, 4> = Map::new(Config::DEFAULT);
    /// let pts = [LabeledPoint::new(Point3::new(0.0, 0.0, 1.0), Labels::top1(1))];
    /// let r = map.integrate_with(&Isometry3::identity(), &pts, None, Vectors::Wide).unwrap();
    /// assert_eq!(r.points_used, 1);
    /// ```
    #[inline(always)]
    pub fn integrate_with(
        &mut self,
        pose: &Isometry3<f32>,
        points: &[LabeledPoint],
        sink: Option<&mut dyn RecordSink>,
        vectors: Vectors,
    ) -> Result<FrameReport, Error> {
        self.integrate_points(pose, points, |_| {}, (sink, vectors))
    }

    /// [`Map::integrate_depth`] with an optional sink ([`Map::integrate_depth_spilling`]),
    /// for code running with the vector instructions `vectors` (see [`Vectors`], which has
    /// an example).
    #[inline(always)]
    pub fn integrate_depth_with(
        &mut self,
        pose: &Isometry3<f32>,
        image: &DepthImage<'_>,
        sink: Option<&mut dyn RecordSink>,
        vectors: Vectors,
    ) -> Result<FrameReport, Error> {
        self.integrate_depth_image(pose, image, |_| {}, (sink, vectors))
    }

    /// [`Map::integrate`] that hands every voxel and block it evicts to `sink` as a
    /// record (an evicted block's voxels first, then the block), so that nothing leaves
    /// the map unseen: a host can merge them ([`Map::merge_record`]) into a larger map.
    /// The report counts the records the sink took (`records_spilled`) and refused
    /// (`records_dropped`). The map is the same as without a sink.
    ///
    /// ```
    /// use sndt_core::*;
    /// // Room for 4 voxels; 8 frames of one voxel each evict the far ones.
    /// let mut map: Map<4, 64, 2> = Map::new(Config::with_cell_size(1.0));
    /// let mut global: Map<64, 64, 2> = Map::new(Config::with_cell_size(1.0));
    /// let mut spilled = 0;
    /// for i in 0..8 {
    ///     let p = [LabeledPoint::new(Point3::new(i as f32 + 0.5, 0.5, 2.5), Labels::top1(1))];
    ///     let mut sink = |r: Record<'_>| global.merge_record(r).is_ok();
    ///     let report = map.integrate_spilling(&Isometry3::identity(), &p, &mut sink).unwrap();
    ///     assert_eq!(report.records_dropped, 0);
    ///     spilled += report.records_spilled;
    /// }
    /// assert!(spilled > 0 && map.len() <= 4);
    /// global.merge(&map).unwrap(); // the device's last map completes the global one
    /// assert_eq!(global.len(), 8);
    /// ```
    pub fn integrate_spilling(
        &mut self,
        pose: &Isometry3<f32>,
        points: &[LabeledPoint],
        sink: &mut dyn RecordSink,
    ) -> Result<FrameReport, Error> {
        self.integrate_points(pose, points, |_| {}, (Some(sink), Vectors::AsBuilt))
    }

    /// [`Map::integrate_depth`] that hands every voxel and block it evicts to `sink`, as
    /// [`Map::integrate_spilling`] does.
    pub fn integrate_depth_spilling(
        &mut self,
        pose: &Isometry3<f32>,
        image: &DepthImage<'_>,
        sink: &mut dyn RecordSink,
    ) -> Result<FrameReport, Error> {
        self.integrate_depth_image(pose, image, |_| {}, (Some(sink), Vectors::AsBuilt))
    }

    /// [`Map::integrate`], reporting the start of every [`Phase`] to `on_phase` (for
    /// example to time them; the map is the same).
    pub fn integrate_observed(
        &mut self,
        pose: &Isometry3<f32>,
        points: &[LabeledPoint],
        on_phase: impl FnMut(Phase),
    ) -> Result<FrameReport, Error> {
        self.integrate_points(pose, points, on_phase, (None, Vectors::AsBuilt))
    }

    /// The steps of [`Map::integrate`], with an observer, a sink and the vectors.
    #[inline(always)]
    fn integrate_points(
        &mut self,
        pose: &Isometry3<f32>,
        points: &[LabeledPoint],
        mut on_phase: impl FnMut(Phase),
        (sink, vectors): (Option<&mut dyn RecordSink>, Vectors),
    ) -> Result<FrameReport, Error> {
        if points.len() > MAX_FRAME_POINTS {
            return Err(Error::FrameTooLarge);
        }
        let mut f = self.begin_frame(pose)?;
        f.sink = sink;
        f.by_voxel = vectors.by_voxel();
        let mut batch = Batch::new();
        for chunk in points.chunks(BATCH) {
            on_phase(Phase::Points);
            batch.load_points(chunk);
            batch.convert(&f, C);
            batch.set_labels(|j| chunk[j].labels, &self.config, C);
            on_phase(Phase::Accumulate);
            self.accumulate(&mut f, &batch, |j| chunk[j].labels);
        }
        Ok(self.finish(&mut f, on_phase))
    }

    /// [`Map::integrate_depth`], reporting the start of every [`Phase`] to `on_phase`.
    ///
    /// ```
    /// use sndt_core::*;
    /// let cam = Pinhole { fx: 4.0, fy: 4.0, cx: 4.0, cy: 3.0, width: 8, height: 6 };
    /// let depth = [2.0f32; 48];
    /// let img = DepthImage { camera: cam, depth: Depth::Metres(&depth), kind: DepthKind::Planar,
    ///                        labels: LabelImage::None, stride: 1 };
    /// let mut map: Map<256, 64, 40> = Map::new(Config::DEFAULT);
    /// let mut batches = 0;
    /// let on_phase = |p| batches += (p == Phase::Points) as u32;
    /// map.integrate_depth_observed(&Isometry3::identity(), &img, on_phase).unwrap();
    /// assert_eq!(batches, 1); // one tile of 8x8 pixels holds the image
    /// ```
    pub fn integrate_depth_observed(
        &mut self,
        pose: &Isometry3<f32>,
        image: &DepthImage<'_>,
        on_phase: impl FnMut(Phase),
    ) -> Result<FrameReport, Error> {
        self.integrate_depth_image(pose, image, on_phase, (None, Vectors::AsBuilt))
    }

    /// [`Map::integrate_depth_observed`] for code running with the vector instructions
    /// `vectors` (see [`Vectors`]).
    ///
    /// ```
    /// use sndt_core::*;
    /// let cam = Pinhole { fx: 4.0, fy: 4.0, cx: 4.0, cy: 3.0, width: 8, height: 6 };
    /// let img = DepthImage { camera: cam, depth: Depth::Metres(&[2.0f32; 48]),
    ///                        kind: DepthKind::Planar, labels: LabelImage::None, stride: 1 };
    /// let mut map: Map<256, 64, 4> = Map::new(Config::DEFAULT);
    /// let mut phases = 0;
    /// let pose = Isometry3::identity();
    /// map.integrate_depth_observed_with(&pose, &img, |_| phases += 1, Vectors::Wide).unwrap();
    /// assert_eq!(phases, 5);
    /// ```
    #[inline(always)]
    pub fn integrate_depth_observed_with(
        &mut self,
        pose: &Isometry3<f32>,
        image: &DepthImage<'_>,
        on_phase: impl FnMut(Phase),
        vectors: Vectors,
    ) -> Result<FrameReport, Error> {
        self.integrate_depth_image(pose, image, on_phase, (None, vectors))
    }

    /// The steps of [`Map::integrate_depth`], with an observer, a sink and the vectors.
    #[inline(always)]
    fn integrate_depth_image(
        &mut self,
        pose: &Isometry3<f32>,
        image: &DepthImage<'_>,
        mut on_phase: impl FnMut(Phase),
        (sink, vectors): (Option<&mut dyn RecordSink>, Vectors),
    ) -> Result<FrameReport, Error> {
        image.validate()?;
        if image.samples() > MAX_FRAME_POINTS {
            return Err(Error::FrameTooLarge);
        }
        let mut f = self.begin_frame(pose)?;
        // The cast shortens the sink's lifetime to the image's where that is shorter.
        f.sink = sink.map(|s| s as &mut dyn RecordSink);
        f.by_voxel = vectors.by_voxel();
        f.image = Some(*image);
        let rays = PixelRays::new(&image.camera);
        let mut batch = Batch::new();
        let stride = image.stride as usize;
        let (w, h) = (image.camera.width as usize, image.camera.height as usize);
        let per_row = w.div_ceil(stride);
        let tile_rows = BATCH / TILE_COLS;
        // `max(1)`: a validated image has stride >= 1; step_by(0) would panic.
        for strip in (0..h).step_by((stride * tile_rows).max(1)) {
            let mut done = 0;
            while done < per_row {
                let n = (per_row - done).min(TILE_COLS);
                on_phase(Phase::Points);
                let rows = (h - strip).div_ceil(stride).min(tile_rows);
                batch.load_tile(image, &rays, (strip, rows), (done * stride, n));
                batch.convert(&f, C);
                self.set_pixel_labels(&mut batch, image);
                on_phase(Phase::Accumulate);
                self.accumulate_pixels(&mut f, &batch, image);
                done += n;
            }
        }
        Ok(self.finish(&mut f, on_phase))
    }

    /// The labels and vote keys of a batch of pixels with top-k labels (one-class labels
    /// came with the tile, and their vote keys with the conversion).
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    fn set_pixel_labels(&self, batch: &mut Batch, image: &DepthImage<'_>) {
        match image.labels {
            LabelImage::None | LabelImage::Top1(_) => {}
            LabelImage::TopK(l) => {
                let at = |i: usize| l.get(i).copied().unwrap_or(Labels::NONE);
                batch.set_labels(at, &self.config, C);
            }
        }
    }

    /// The accumulation stage for a batch of pixels, with the image's labels.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    fn accumulate_pixels(&mut self, f: &mut FrameState, batch: &Batch, image: &DepthImage<'_>) {
        match image.labels {
            LabelImage::None => self.accumulate(f, batch, |_| Labels::NONE),
            LabelImage::Top1(l) => self.accumulate(f, batch, |i| {
                l.get(i).map_or(Labels::NONE, |&c| Labels::top1(c))
            }),
            LabelImage::TopK(l) => {
                self.accumulate(f, batch, |i| l.get(i).copied().unwrap_or(Labels::NONE));
            }
        }
    }

    /// Phases 2 and 3 after the frame's last point, then the frame's totals.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    pub(crate) fn finish(
        &mut self,
        f: &mut FrameState,
        mut on_phase: impl FnMut(Phase),
    ) -> FrameReport {
        on_phase(Phase::EndVoxels);
        self.flush_accumulators(f);
        let head = self.sort_frame_list(f.head);
        self.update_end_voxels(f, head);
        on_phase(Phase::FreeSpace);
        self.clear_free_space(f, head);
        let report = self.close_frame(f);
        on_phase(Phase::Done);
        report
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use crate::config::to_fixed;
    use crate::testutil::*;
    use crate::*;
    use std::vec::Vec;

    #[test]
    fn decay_through_integrate() {
        let mut cfg = Config::DEFAULT;
        cfg.n_max = 4;
        let mut map: Map<16, 16, 2> = Map::try_new(cfg).unwrap();
        let pts = [lp(0.05, 0.05, 1.05, 1); 10];
        map.integrate(&Isometry3::identity(), &pts).unwrap();
        // 10 -> 5 -> 3.
        assert_eq!(map.gaussian_at(&[0.05, 0.05, 1.05]).unwrap().count, 3);
    }

    #[test]
    fn hit_and_constant_miss_fixed_point() {
        let mut map: Map<64, 64, 2> = Map::new(Config::DEFAULT);
        let pts = [lp(0.05, 0.05, 1.05, 1); 3];
        let r = map.integrate(&Isometry3::identity(), &pts).unwrap();
        assert_eq!((r.end_voxels, r.rays), (1, 1));
        assert_eq!(to_fixed(0.85), 870);
        assert_eq!(to_fixed(-0.4), -410);
        assert_eq!(fixed(&map, &key(0, 0, 10)), 870);
        for z in 0..10 {
            // No Gaussian on the way: the constant miss, once per frame.
            assert_eq!(fixed(&map, &key(0, 0, z)), -410, "z={z}");
        }
        assert_eq!(fixed(&map, &key(0, 0, 11)), 0);
        // Clamping: many frames saturate at the configured bounds.
        for _ in 0..10 {
            map.integrate(&Isometry3::identity(), &pts).unwrap();
        }
        assert_eq!(fixed(&map, &key(0, 0, 10)), to_fixed(3.5));
        assert_eq!(fixed(&map, &key(0, 0, 3)), to_fixed(-2.0));
        assert_eq!(map.occupancy(&key(0, 0, 10)), Occupancy::Occupied);
        assert_eq!(map.occupancy(&key(0, 0, 3)), Occupancy::Free);
        assert_eq!(map.occupancy(&key(5, 5, 5)), Occupancy::Unknown);
    }

    #[test]
    fn snapshot_identical_under_point_permutation() {
        let mut rng = Lcg(99);
        let mut frames = Vec::new();
        for f in 0..3 {
            let mut pts = Vec::new();
            for i in 0..600 {
                // Clusters of points (decay with n_max = 16), top-3 labels, some rejects.
                let c = (i % 12) as f32;
                let mut p = [
                    0.3 * c - 1.52 + 0.06 * rng.next() as f32,
                    0.2 * (c % 3.0) - 0.22 + 0.06 * rng.next() as f32,
                    1.5 + 0.06 * rng.next() as f32,
                ];
                if i % 97 == 0 {
                    p[2] = 30.0; // truncated at max range
                }
                if i % 113 == 0 {
                    p[0] = f32::NAN;
                }
                let l = Labels::top_k(&[
                    (1 + (i % 4) as u8, 200),
                    (1 + (i % 3) as u8, (rng.next() * 255.0) as u8),
                    ((i % 5) as u8, 90),
                ]);
                pts.push(LabeledPoint::new(Point3::new(p[0], p[1], p[2]), l));
            }
            let pose = Isometry3::from_parts(
                Translation3::new(0.1 * f as f32, -0.05, 0.02),
                UnitQuaternion::from_euler_angles(0.0, 0.1 * f as f32, 0.05),
            );
            frames.push((pose, pts));
        }
        let mut cfg = Config::DEFAULT;
        cfg.n_max = 16;
        cfg.top_k = 3;
        cfg.min_score = 100;
        cfg.max_range = 3.0;
        let mut used = 0u32;
        let mut maps: Vec<std::boxed::Box<Map<1024, 1024, 6>>> = (0..3)
            .map(|_| std::boxed::Box::new(Map::new(cfg)))
            .collect();
        for (pose, pts) in &frames {
            let mut rev = pts.clone();
            rev.reverse();
            let mut shuffled = pts.clone();
            for i in (1..shuffled.len()).rev() {
                let j = (rng.next() * (i + 1) as f64) as usize;
                shuffled.swap(i, j);
            }
            let mut reports: Vec<FrameReport> = Vec::new();
            for (m, order) in maps.iter_mut().zip([pts, &rev, &shuffled]) {
                let r = m.integrate(pose, order).unwrap();
                assert_eq!(
                    (r.voxels_evicted, r.blocks_evicted, r.dropped_points),
                    (0, 0, 0)
                );
                assert_eq!(r.dropped_misses, 0);
                reports.push(r);
            }
            assert_eq!(reports[0], reports[1]);
            assert_eq!(reports[0], reports[2]);
            assert!(reports[0].truncated > 0 && reports[0].rejected_depth > 0);
            used += reports[0].points_used;
        }
        let s0 = snapshot(&*maps[0]);
        assert_eq!(s0, snapshot(&*maps[1]));
        assert_eq!(s0, snapshot(&*maps[2]));
        assert_eq!(maps[0].checksum(), maps[2].checksum());
        assert_eq!(
            maps[0].checksum(),
            u32::from_le_bytes(s0[s0.len() - 4..].try_into().unwrap())
        );
        // Decay happened (else this test would not cover it): fewer points kept than used.
        let kept: u32 = maps[0].voxels().map(|v| v.gaussian.count).sum();
        assert!(maps[0].voxels().all(|v| v.gaussian.count <= 16));
        assert!(kept < used, "kept {kept} of {used}");
    }
}

#[cfg(test)]
mod tile_tests {
    extern crate std;

    use crate::geometry::camera::PixelRays;
    use crate::testutil::*;
    use crate::*;
    use std::vec::Vec;

    /// The points `integrate_depth` must see: every sampled pixel through `depth_point`
    /// in row-major order (a NaN point, rejected by depth, where it gives none).
    fn image_points(img: &DepthImage<'_>) -> Vec<LabeledPoint> {
        let cam = img.camera;
        let rays = PixelRays::new(&cam);
        let s = img.stride as usize;
        let mut pts = Vec::new();
        for row in (0..cam.height as usize).step_by(s) {
            for col in (0..cam.width as usize).step_by(s) {
                let i = row * cam.width as usize + col;
                let ray = [rays.x(col), rays.y(row), 1.0];
                let d = img.depth.metres(i).unwrap_or(f32::NAN);
                let p = depth_point(ray, d, img.kind).unwrap_or([f32::NAN; 3]);
                let labels = match img.labels {
                    LabelImage::None => Labels::NONE,
                    LabelImage::Top1(l) => Labels::top1(l[i]),
                    LabelImage::TopK(l) => l[i],
                };
                pts.push(LabeledPoint::new(Point3::new(p[0], p[1], p[2]), labels));
            }
        }
        pts
    }

    #[test]
    fn tiles_see_every_pixel_once_as_the_point_path_does() {
        // Image sizes that are not multiples of the 8x8 tile, strides, both depth kinds, all
        // label kinds; invalid depths, labels above the class count, points beyond max range.
        let mut rng = Lcg(5);
        for (w, h, stride) in [(13u32, 11u32, 1u32), (16, 9, 2), (21, 17, 3), (8, 8, 1)] {
            let n = (w * h) as usize;
            let depth: Vec<f32> = (0..n)
                .map(|i| match i % 29 {
                    3 => f32::NAN,
                    7 => -1.0,
                    11 => 0.0,
                    13 => f32::INFINITY,
                    17 => 40.0, // beyond max range
                    _ => 1.0 + 0.4 * rng.next() as f32,
                })
                .collect();
            let top1: Vec<u8> = (0..n).map(|i| (i % 7) as u8).collect(); // 6 > 5 classes
            let topk: Vec<Labels> = (0..n)
                .map(|i| Labels::top_k(&[(1 + (i % 6) as u8, 200), (1 + (i % 3) as u8, 150)]))
                .collect();
            let cam = Pinhole {
                fx: 9.0,
                fy: 8.0,
                cx: w as f32 / 2.0,
                cy: h as f32 / 2.0,
                width: w,
                height: h,
            };
            let labels = [
                LabelImage::None,
                LabelImage::Top1(&top1),
                LabelImage::TopK(&topk),
            ];
            for (kind, labels) in [DepthKind::Planar, DepthKind::Range]
                .into_iter()
                .flat_map(|k| labels.iter().map(move |l| (k, *l)))
            {
                let img = DepthImage {
                    camera: cam,
                    depth: Depth::Metres(&depth),
                    kind,
                    labels,
                    stride,
                };
                let mut cfg = Config::DEFAULT;
                cfg.top_k = 2;
                cfg.max_range = 3.0;
                let pose = at(0.3, -0.2, 0.1);
                let mut tiles: std::boxed::Box<Map<2048, 512, 5>> =
                    std::boxed::Box::new(Map::new(cfg));
                let mut points: std::boxed::Box<Map<2048, 512, 5>> =
                    std::boxed::Box::new(Map::new(cfg));
                let a = tiles.integrate_depth(&pose, &img).unwrap();
                let b = points.integrate(&pose, &image_points(&img)).unwrap();
                assert_eq!(a, b, "{w}x{h} stride {stride} {kind:?}");
                assert!(a.points_used > 0 && a.rejected_depth > 0 && a.truncated > 0);
                assert_eq!(
                    snapshot(&*tiles),
                    snapshot(&*points),
                    "{w}x{h} stride {stride}"
                );
            }
        }
    }

    #[test]
    fn millimetres_map_as_their_metres() {
        // u16 millimetres (0 = no return, 65535 beyond max range) give the map of the
        // same depths converted to f32 metres, whatever the tile, stride and kind.
        let mut rng = Lcg(9);
        for (w, h, stride) in [(13u32, 11u32, 1u32), (16, 9, 2), (21, 17, 3), (24, 16, 1)] {
            let n = (w * h) as usize;
            let mm: Vec<u16> = (0..n)
                .map(|i| match i % 23 {
                    5 => 0,
                    9 => u16::MAX,
                    _ => 800 + (rng.next() * 1500.0) as u16,
                })
                .collect();
            let metres: Vec<f32> = mm.iter().map(|&v| v as f32 / 1000.0).collect();
            let labels: Vec<u8> = (0..n).map(|i| 1 + (i % 5) as u8).collect();
            let camera = Pinhole {
                fx: 9.0,
                fy: 8.0,
                cx: w as f32 / 2.0,
                cy: h as f32 / 2.0,
                width: w,
                height: h,
            };
            for kind in [DepthKind::Planar, DepthKind::Range] {
                let image = |depth| DepthImage {
                    camera,
                    depth,
                    kind,
                    labels: LabelImage::Top1(&labels),
                    stride,
                };
                let mut cfg = Config::DEFAULT;
                cfg.max_range = 3.0;
                let pose = at(0.3, -0.2, 0.1);
                let mut a: std::boxed::Box<Map<2048, 512, 5>> = std::boxed::Box::new(Map::new(cfg));
                let mut b: std::boxed::Box<Map<2048, 512, 5>> = std::boxed::Box::new(Map::new(cfg));
                let ra = a
                    .integrate_depth(&pose, &image(Depth::Millimetres(&mm)))
                    .unwrap();
                let rb = b
                    .integrate_depth(&pose, &image(Depth::Metres(&metres)))
                    .unwrap();
                assert_eq!(ra, rb, "{w}x{h} stride {stride} {kind:?}");
                assert!(ra.points_used > 0 && ra.rejected_depth > 0 && ra.truncated > 0);
                assert_eq!(
                    snapshot(&*a),
                    snapshot(&*b),
                    "{w}x{h} stride {stride} {kind:?}"
                );
            }
        }
    }
}
