//! The reference map: [`RefMap`] and its voxels, integrated in the core's steps.

use crate::dataset::frame::{Frame, LabelSource};
use crate::mapping::{LabelView, SemanticMap};
use crate::reference::key::{Key, KeyMap, KeySet};
use crate::reference::render::{RefHit, RenderIndex, Renderable};
use anyhow::anyhow;
use nalgebra::{Matrix3, Vector3};
use sndt_core::{
    Config, DepthImage, DepthKind, Error, Isometry3, LabeledPoint, MissModel, Occupancy, KEY_LIMIT,
    MAX_TOP_K,
};

/// One surface voxel of the reference: exact `f64` point statistics and class votes.
#[derive(Clone, Debug, PartialEq)]
pub struct RefVoxel {
    /// Number of points (after the point cap).
    pub n: f64,
    /// `S1`: sum of the points' offsets from the voxel centre, metres.
    pub s1: Vector3<f64>,
    /// `S2`: sum of the outer products of those offsets, square metres.
    pub s2: Matrix3<f64>,
    /// Class votes; bin `i` is class `i + 1`. Real-valued: halving is exact.
    pub hist: Vec<f64>,
    /// This frame's vote sample keeps one voting point in `2^vote_exponent`
    /// (`sndt_core::next_vote_exponent`).
    pub vote_exponent: u8,
}

impl RefVoxel {
    fn new(classes: usize) -> RefVoxel {
        RefVoxel {
            n: 0.0,
            s1: Vector3::zeros(),
            s2: Matrix3::zeros(),
            hist: vec![0.0; classes],
            vote_exponent: 0,
        }
    }

    /// The most voted class (1-based) and its share of the votes; ties go to the lowest
    /// class, as in the core. `None` without votes.
    ///
    /// ```
    /// # use sndt_host::reference::RefVoxel;
    /// # use nalgebra::{Matrix3, Vector3};
    /// let v = RefVoxel { n: 1.0, s1: Vector3::zeros(), s2: Matrix3::zeros(), hist: vec![1.0, 3.0, 3.0, 1.0], vote_exponent: 0 };
    /// assert_eq!(v.class(), Some((2, 0.375)));
    /// ```
    pub fn class(&self) -> Option<(u8, f64)> {
        let mut best = 0;
        let mut total = 0.0;
        for (i, &b) in self.hist.iter().enumerate() {
            total += b;
            if b > self.hist[best] {
                best = i;
            }
        }
        (total > 0.0).then(|| (best as u8 + 1, self.hist[best] / total))
    }

    /// Sample covariance `(S2 - S1 S1^T / n) / (n - 1)` in square metres (zero for `n < 2`).
    pub fn covariance(&self) -> Matrix3<f64> {
        if self.n < 2.0 {
            return Matrix3::zeros();
        }
        (self.s2 - self.s1 * self.s1.transpose() / self.n) / (self.n - 1.0)
    }

    /// Scales the count down to the point cap: `n` is halved (rounding up) until
    /// `n <= n_max` and the sums are multiplied by the same factor, which keeps the mean.
    fn decay(&mut self, n_max: u32) {
        let n = self.n as u64;
        if n <= n_max as u64 {
            return;
        }
        let mut m = n;
        while m > n_max as u64 {
            m = m.div_ceil(2);
        }
        let f = m as f64 / n as f64;
        self.s1 *= f;
        self.s2 *= f;
        self.n = m as f64;
    }
}

/// A voxel's normal distribution in world coordinates (metres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefGaussian {
    /// Mean, metres.
    pub mean: Vector3<f64>,
    /// Sample covariance, square metres (zero for fewer than 2 points).
    pub covariance: Matrix3<f64>,
    /// Number of points (after the point cap).
    pub count: f64,
}

impl RefGaussian {
    /// The inverse covariance with every eigenvalue raised to
    /// `max(ratio * lambda_max, floor_abs)` (as the core: eigenvalues below
    /// `lambda_max / 1000` are raised before inversion; `floor_abs = (h / 1000)^2` covers
    /// voxels whose points coincide).
    ///
    /// ```
    /// # use sndt_host::reference::RefGaussian;
    /// # use nalgebra::{Matrix3, Vector3};
    /// let g = RefGaussian { mean: Vector3::zeros(), count: 9.0,
    ///     covariance: Matrix3::from_diagonal(&Vector3::new(4.0, 1e-9, 1.0)) };
    /// let inv = g.inverse(1e-3, 0.0);
    /// assert!((inv[(0, 0)] - 0.25).abs() < 1e-12 && (inv[(1, 1)] - 250.0).abs() < 1e-9);
    /// ```
    pub fn inverse(&self, ratio: f64, floor_abs: f64) -> Matrix3<f64> {
        let e = self.covariance.symmetric_eigen();
        let lmax = e.eigenvalues.max();
        let floor = (lmax * ratio).max(floor_abs);
        let mut inv = Matrix3::zeros();
        for i in 0..3 {
            let v = e.eigenvectors.column(i);
            inv += v * v.transpose() / e.eigenvalues[i].max(floor);
        }
        inv
    }
}

/// What one reference frame did (a subset of the core's `FrameReport`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RefFrameReport {
    /// Points folded into voxel statistics.
    pub points_used: u32,
    /// Points beyond max range (free space only).
    pub truncated: u32,
    /// Points rejected: bad coordinates, bad labels, or outside the key range.
    pub rejected: u32,
    /// Unique end voxels (= hits).
    pub end_voxels: u32,
    /// Rays cast (end voxels + unique truncated ends).
    pub rays: u32,
    /// Misses applied.
    pub misses: u32,
}

/// A free-space ray in world metres.
#[derive(Clone, Copy, Debug)]
struct Ray {
    origin: Vector3<f64>,
    /// Unit direction.
    dir: Vector3<f64>,
    /// Length to the ray's end `z`.
    len: f64,
    /// The end is a measurement (false for a ray truncated at max range: `pz = 0`).
    measured: bool,
}

/// The f64 reference map. See the [module documentation](self).
#[derive(Clone, Debug)]
pub struct RefMap {
    config: Config,
    classes: usize,
    h: f64,
    voxels: KeyMap<RefVoxel>,
    cells: KeyMap<f64>,
    frames: u64,
}

impl RefMap {
    /// An empty map with `config` (the core's parameters; `cell_size` etc. are used as
    /// their exact `f64` values) and `classes` semantic classes (ids `1..=classes`).
    pub fn new(config: Config, classes: usize) -> RefMap {
        RefMap {
            config,
            classes,
            h: config.cell_size as f64,
            voxels: KeyMap::default(),
            cells: KeyMap::default(),
            frames: 0,
        }
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// Frames integrated.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Number of surface voxels.
    pub fn len(&self) -> usize {
        self.voxels.len()
    }

    /// True before the first point.
    pub fn is_empty(&self) -> bool {
        self.voxels.is_empty() && self.cells.is_empty()
    }

    /// The key of the voxel holding world point `p` (`f32`, the shared convention:
    /// `floor(p * (1 / h))` in `f32`), or `None` outside the key range.
    ///
    /// ```
    /// let map = sndt_host::reference::RefMap::new(sndt_core::Config::DEFAULT, 40);
    /// assert_eq!(map.key(&[0.25, -0.05, 1.0]), Some([2, -1, 10]));
    /// assert_eq!(map.key(&[1e9, 0.0, 0.0]), None);
    /// ```
    pub fn key(&self, p: &[f32; 3]) -> Option<Key> {
        let inv = 1.0 / self.config.cell_size;
        let mut k = [0; 3];
        for (k, &x) in k.iter_mut().zip(p) {
            let s = x * inv;
            if !(s >= -(KEY_LIMIT as f32) && s < (KEY_LIMIT + 1) as f32) {
                return None;
            }
            *k = s.floor() as i32;
        }
        Some(k)
    }

    /// Centre of voxel `key` in metres.
    pub fn centre(&self, key: &Key) -> Vector3<f64> {
        Vector3::new(
            (key[0] as f64 + 0.5) * self.h,
            (key[1] as f64 + 0.5) * self.h,
            (key[2] as f64 + 0.5) * self.h,
        )
    }

    /// The surface voxel `key`, if it has points.
    pub fn voxel(&self, key: &Key) -> Option<&RefVoxel> {
        self.voxels.get(key)
    }

    /// All surface voxels (unordered).
    pub fn voxels(&self) -> impl Iterator<Item = (&Key, &RefVoxel)> + '_ {
        self.voxels.iter()
    }

    /// Every voxel a hit or miss reached, with its log-odds (unordered; exactly 0 means
    /// unknown).
    pub fn cells(&self) -> impl Iterator<Item = (&Key, f64)> + '_ {
        self.cells.iter().map(|(k, &l)| (k, l))
    }

    /// Occupancy log-odds (natural units); 0 when never observed.
    pub fn log_odds(&self, key: &Key) -> f64 {
        self.cells.get(key).copied().unwrap_or(0.0)
    }

    /// Occupancy state: occupied above 0, free below, unknown at exactly 0 (as the core).
    pub fn occupancy(&self, key: &Key) -> Occupancy {
        let l = self.log_odds(key);
        if l > 0.0 {
            Occupancy::Occupied
        } else if l < 0.0 {
            Occupancy::Free
        } else {
            Occupancy::Unknown
        }
    }

    /// Most voted class (1-based) and its share, for a surface voxel with votes.
    pub fn class(&self, key: &Key) -> Option<(u8, f64)> {
        self.voxels.get(key)?.class()
    }

    /// Mean, covariance and count of a surface voxel.
    pub fn gaussian(&self, key: &Key) -> Option<RefGaussian> {
        let v = self.voxels.get(key)?;
        Some(RefGaussian {
            mean: self.centre(key) + v.s1 / v.n,
            covariance: v.covariance(),
            count: v.n,
        })
    }

    /// Mean and inverse covariance (eigenvalue floor applied) of a voxel whose Gaussian
    /// is valid (`n >= n_min`).
    fn prepared(&self, key: &Key) -> Option<(Vector3<f64>, Matrix3<f64>)> {
        let v = self.voxels.get(key)?;
        if v.n < self.config.n_min as f64 {
            return None;
        }
        let g = self.gaussian(key)?;
        let floor_abs = (self.h * 1e-3) * (self.h * 1e-3);
        Some((g.mean, g.inverse(self.config.eigen_ratio as f64, floor_abs)))
    }

    /// Integrates one frame of labelled points in the sensor frame at `pose` (sensor to
    /// world), in the core's steps (see the [module documentation](super)): validate the
    /// pose, points to end voxels, one update per touched voxel, free space along rays. A
    /// non-finite or non-unit pose is [`Error::InvalidPose`], a sensor outside the key
    /// range [`Error::PoseOutOfRange`]; the map is then unchanged.
    pub fn integrate(
        &mut self,
        pose: &Isometry3<f32>,
        points: &[LabeledPoint],
    ) -> Result<RefFrameReport, Error> {
        self.integrate_seen(pose, points, None)
    }

    /// [`RefMap::integrate`] for the points of a depth image, which the see-through miss
    /// also consults: a surface voxel that got no points is seen through when the pixel
    /// its mean projects to measured well beyond the mean (the core's
    /// `Map::integrate_depth`). `points` are the image's points.
    pub fn integrate_seen(
        &mut self,
        pose: &Isometry3<f32>,
        points: &[LabeledPoint],
        image: Option<&DepthImage<'_>>,
    ) -> Result<RefFrameReport, Error> {
        let (origin, origin_key) = self.validate_pose(pose)?;
        let mut report = RefFrameReport::default();
        let (votes, far) = self.accumulate_points(pose, points, &mut report);
        self.update_end_voxels(&votes, &mut report);
        let mut ends: Vec<(Key, bool)> = votes.keys().map(|k| (*k, false)).collect();
        ends.extend(
            far.iter()
                .filter(|k| !votes.contains_key(*k))
                .map(|k| (*k, true)),
        );
        let view = image.map(|image| View::new(pose, image));
        self.free_space(origin, origin_key, ends, view.as_ref(), &mut report);
        self.frames += 1;
        Ok(report)
    }

    /// Step 0: the sensor origin and its voxel, or the error that leaves the map untouched.
    fn validate_pose(&self, pose: &Isometry3<f32>) -> Result<([f32; 3], Key), Error> {
        sndt_core::validate_pose(pose)?;
        let t = pose.translation.vector;
        let origin = [t.x, t.y, t.z];
        Ok((origin, self.key(&origin).ok_or(Error::PoseOutOfRange)?))
    }

    /// Step 1, per point: where it lands. The world point is computed in `f32` exactly as
    /// the core computes it (the shared key convention); a point beyond `max_range` lands
    /// where its ray is truncated.
    fn land(&self, p: &LabeledPoint, rotation: &Matrix3<f32>, origin: &[f32; 3]) -> Landing {
        let s = [p.position.x, p.position.y, p.position.z];
        let r2 = s[0] * s[0] + s[1] * s[1] + s[2] * s[2];
        let nl = p.labels.len as usize;
        if !(r2.is_finite() && r2 > 0.0)
            || nl > MAX_TOP_K
            || p.labels.classes[..nl]
                .iter()
                .any(|&c| c as usize > self.classes)
        {
            return Landing::Rejected;
        }
        let m = rotation;
        let mut w = [0.0f32; 3];
        for (i, wi) in w.iter_mut().enumerate() {
            *wi = m[(i, 0)] * s[0] + m[(i, 1)] * s[1] + m[(i, 2)] * s[2] + origin[i];
        }
        let max_range = self.config.max_range;
        if r2 > max_range * max_range {
            let scale = max_range / r2.sqrt();
            let e = [0, 1, 2].map(|i| origin[i] + (w[i] - origin[i]) * scale);
            return self.key(&e).map_or(Landing::Rejected, Landing::Truncated);
        }
        match self.key(&w) {
            Some(key) => Landing::End { key, world: w },
            None => Landing::Rejected,
        }
    }

    /// Step 1: every point into its end voxel's `f64` sums, its votes into the frame's
    /// sample; returns the frame's votes per end voxel and the truncated ends.
    fn accumulate_points(
        &mut self,
        pose: &Isometry3<f32>,
        points: &[LabeledPoint],
        report: &mut RefFrameReport,
    ) -> (KeyMap<FrameVotes>, KeySet) {
        let rotation = *pose.rotation.to_rotation_matrix().matrix();
        let t = pose.translation.vector;
        let origin = [t.x, t.y, t.z];
        let mut votes: KeyMap<FrameVotes> = KeyMap::default();
        let mut far = KeySet::default();
        for p in points {
            match self.land(p, &rotation, &origin) {
                Landing::Rejected => report.rejected += 1,
                Landing::Truncated(key) => {
                    far.insert(key);
                    report.truncated += 1;
                }
                Landing::End { key, world } => {
                    self.accumulate(key, &world, p, &mut votes);
                    report.points_used += 1;
                }
            }
        }
        (votes, far)
    }

    /// Step 1, per point in range: adds it to voxel `key`'s sums about the voxel centre,
    /// and its voting labels to the frame's votes if the voxel's sample takes it.
    fn accumulate(
        &mut self,
        key: Key,
        world: &[f32; 3],
        p: &LabeledPoint,
        votes: &mut KeyMap<FrameVotes>,
    ) {
        let (classes, cfg) = (self.classes, self.config);
        let d = Vector3::new(world[0] as f64, world[1] as f64, world[2] as f64) - self.centre(&key);
        let v = self
            .voxels
            .entry(key)
            .or_insert_with(|| RefVoxel::new(classes));
        v.n += 1.0;
        v.s1 += d;
        v.s2 += d * d.transpose();
        let nl = p.labels.len as usize;
        let voted: Vec<usize> = (0..(cfg.top_k as usize).min(nl))
            .filter(|&i| p.labels.classes[i] >= 1 && p.labels.scores[i] >= cfg.min_score)
            .map(|i| p.labels.classes[i] as usize)
            .collect();
        let exponent = v.vote_exponent;
        let frame = votes.entry(key).or_insert_with(|| FrameVotes {
            per_class: vec![0; classes],
            taken: 0,
        });
        let s = [p.position.x, p.position.y, p.position.z];
        if !voted.is_empty() && sndt_core::takes_vote(sndt_core::vote_hash(&s), exponent) {
            voted.iter().for_each(|&c| frame.per_class[c - 1] += 1);
            frame.taken += 1;
        }
    }

    /// Step 2, once per end voxel: histogram room and the frame's votes, the next vote
    /// exponent, the point cap, one hit.
    fn update_end_voxels(&mut self, votes: &KeyMap<FrameVotes>, report: &mut RefFrameReport) {
        let cfg = self.config;
        let (lo, hi) = (cfg.clamp_min as f64, cfg.clamp_max as f64);
        for (key, frame) in votes {
            let v = self
                .voxels
                .get_mut(key)
                .expect("end voxels have statistics");
            if v.hist
                .iter()
                .any(|&b| b > 255.0 - cfg.votes_per_frame as f64)
            {
                v.hist.iter_mut().for_each(|b| *b *= 0.5);
            }
            for (b, &n) in v.hist.iter_mut().zip(&frame.per_class) {
                *b = (*b + n as f64).min(255.0);
            }
            // The core counts taken votes in 12 bits.
            let taken = frame.taken.min(0xfff) as u16;
            v.vote_exponent =
                sndt_core::next_vote_exponent(v.vote_exponent, taken, cfg.votes_per_frame);
            v.decay(cfg.n_max);
            let l = self.cells.entry(*key).or_insert(0.0);
            *l = (*l + cfg.hit as f64).clamp(lo, hi);
            report.end_voxels += 1;
        }
    }

    /// Step 3: one ray per end (end voxels and truncated ends) in the core's order, at most
    /// one miss per traversed voxel.
    fn free_space(
        &mut self,
        origin32: [f32; 3],
        origin_key: Key,
        mut ends: Vec<(Key, bool)>,
        view: Option<&View<'_>>,
        report: &mut RefFrameReport,
    ) {
        ends.sort_unstable_by_key(|&(k, truncated)| ray_order(&k, truncated));
        let origin = Vector3::new(origin32[0] as f64, origin32[1] as f64, origin32[2] as f64);
        let o = [0, 1, 2].map(|i| origin[i] / self.h);
        let mut misses = FrameMisses {
            hit: ends.iter().filter(|e| !e.1).map(|e| e.0).collect(),
            ..FrameMisses::default()
        };
        let mut path = Vec::new();
        for (end, truncated) in ends {
            let (ray, target) = self.ray_to(origin, end, truncated);
            report.rays += 1;
            path.clear();
            walk_segment(o, target, origin_key, end, truncated, &mut path);
            for key in &path {
                if self.miss(key, &ray, view, &mut misses) {
                    report.misses += 1;
                }
            }
        }
    }

    /// Step 3, per end: the ray from `origin` and its target in voxel units, the mean of
    /// the end voxel's points kept 1 % inside the voxel, or the centre of a truncated end.
    fn ray_to(&self, origin: Vector3<f64>, end: Key, truncated: bool) -> (Ray, [f64; 3]) {
        let target = if truncated {
            [0, 1, 2].map(|i| end[i] as f64 + 0.5)
        } else {
            let v = &self.voxels[&end];
            [0, 1, 2].map(|i| {
                let off = 0.5 + v.s1[i] / v.n / self.h;
                end[i] as f64 + off.clamp(0.01, 0.99)
            })
        };
        let target_w = Vector3::new(target[0], target[1], target[2]) * self.h;
        let d = target_w - origin;
        let len = d.norm();
        let ray = Ray {
            origin,
            dir: if len > 0.0 { d / len } else { Vector3::z() },
            len,
            measured: !truncated,
        };
        (ray, target)
    }

    /// Step 3, per traversed voxel: its miss for `ray` unless it already had one this
    /// frame: with the voxel's current Gaussian where it has one, the see-through miss if
    /// it got no points this frame (and the miss is on), else the NDT-OM miss; the
    /// constant miss without one. A miss the ray does not give (closest point beyond the
    /// ray's end; for the see-through miss also outside the ellipsoid or near the end)
    /// leaves the voxel for a later ray. Returns whether a miss was applied.
    fn miss(
        &mut self,
        key: &Key,
        ray: &Ray,
        view: Option<&View<'_>>,
        misses: &mut FrameMisses,
    ) -> bool {
        if misses.missed.contains(key) {
            return false;
        }
        let cfg = self.config;
        let mut delta = cfg.miss as f64;
        let mut spread = false;
        if cfg.miss_model == MissModel::NdtOm {
            let g = *misses
                .gaussians
                .entry(*key)
                .or_insert_with(|| self.prepared(key));
            if let Some((mean, inv)) = g {
                let see = cfg.see_through_miss != 0.0 && !misses.hit.contains(key);
                // Doubted: more than 1 below the upper clamp (the core's
                // `SEE_THROUGH_DOUBT`, compared in its fixed point).
                let doubted = self.log_odds(key) < cfg.clamp_max as f64 - 1.0;
                let seen = see && view.is_some_and(|v| v.sees_beyond(&cfg, &mean));
                let miss = match (see, seen) {
                    (true, true) => Some(cfg.see_through_miss as f64),
                    (true, false) => see_through_miss(&cfg, ray, &mean, &inv, doubted),
                    (false, _) => ndt_om_miss(&cfg, ray, &mean, &inv),
                };
                match miss {
                    Some(l) => delta = l,
                    None => return false,
                }
                spread = see;
            }
        }
        self.apply_miss(key, delta, misses);
        if spread {
            self.spread_see_through(key, delta, view, misses);
        }
        true
    }

    /// Adds miss `delta` to voxel `key`, its one miss this frame.
    fn apply_miss(&mut self, key: &Key, delta: f64, misses: &mut FrameMisses) {
        let cfg = self.config;
        misses.missed.insert(*key);
        let l = self.cells.entry(*key).or_insert(0.0);
        *l = (*l + delta).clamp(cfg.clamp_min as f64, cfg.clamp_max as f64);
    }

    /// After a see-through miss `delta` of surface voxel `key`: each face neighbour (+x,
    /// -x, +y, -y, +z, -z) with a valid Gaussian and the same class, occupied, without
    /// points or a miss this frame, whose mean the depth image shows hidden (the pixel
    /// it projects to measured nearer by more than a cell plus twice the range noise),
    /// takes a quarter of it (the core's `SPREAD_SHARE`; the core rounds its fixed point
    /// towards 0).
    fn spread_see_through(
        &mut self,
        key: &Key,
        delta: f64,
        view: Option<&View<'_>>,
        misses: &mut FrameMisses,
    ) {
        let Some(view) = view else {
            return;
        };
        let class = self.class(key).map(|c| c.0);
        let cfg = self.config;
        for axis in 0..3 {
            for step in [1, -1] {
                let mut n = *key;
                n[axis] += step;
                if misses.hit.contains(&n) || misses.missed.contains(&n) {
                    continue;
                }
                if self.log_odds(&n) <= 0.0 || self.class(&n).map(|c| c.0) != class {
                    continue;
                }
                let Some((mean, _)) = self.prepared(&n) else {
                    continue;
                };
                if view.hides(&cfg, &mean) {
                    self.apply_miss(&n, delta / 4.0, misses);
                }
            }
        }
    }

    /// The occupied voxels with a valid Gaussian, prepared for ray casting.
    pub fn render_index(&self) -> RenderIndex {
        let entries = self
            .voxels
            .iter()
            .filter(|(k, _)| self.log_odds(k) > 0.0)
            .filter_map(|(k, v)| {
                let (mean, inv) = self.prepared(k)?;
                let class = v.class().map_or(0, |c| c.0);
                Some((*k, Renderable { mean, inv, class }))
            })
            .collect();
        RenderIndex::new(&self.config, entries)
    }

    /// The first occupied Gaussian the ray enters (see [`RenderIndex::raycast`]); builds
    /// a [`RenderIndex`] per call, so prefer [`RefMap::render_index`] for many rays.
    pub fn raycast(&self, origin: &[f64; 3], dir: &[f64; 3], max_t: f64) -> Option<RefHit> {
        self.render_index().raycast(origin, dir, max_t)
    }
}

/// The reference as the evaluation runs it: frames as sensor-frame points with the depth
/// image of a pinhole frame (as [`crate::eval::compare`] feeds it), one read-out.
impl SemanticMap for RefMap {
    type Readout = ();

    fn integrate_frame(
        &mut self,
        frame: &Frame,
        labels: LabelSource,
        stride: u32,
    ) -> anyhow::Result<()> {
        let points = frame.integration_points(labels, stride);
        self.integrate_seen(&frame.pose, &points, frame.depth_view(stride).as_ref())
            .map(|_| ())
            .map_err(|e| anyhow!("{}: reference: {e:?}", frame.id))
    }

    /// The [`RenderIndex`], built once.
    fn prepare(&self, _: ()) -> Box<dyn LabelView + '_> {
        Box::new(self.render_index())
    }

    /// The entries of the voxel and log-odds tables with their histograms (not the hash
    /// tables' spare capacity): the reference has no fixed footprint.
    fn memory_bytes(&self) -> usize {
        let voxel = size_of::<Key>() + size_of::<RefVoxel>() + self.classes * size_of::<f64>();
        self.voxels.len() * voxel + self.cells.len() * (size_of::<Key>() + size_of::<f64>())
    }

    /// Surface voxels (those holding point statistics).
    fn voxel_count(&self) -> usize {
        self.len()
    }
}

/// A frame's depth image as step 3 consults it: the image and the world-to-camera pose.
struct View<'a> {
    image: &'a DepthImage<'a>,
    to_camera: Isometry3<f64>,
}

impl<'a> View<'a> {
    fn new(pose: &Isometry3<f32>, image: &'a DepthImage<'a>) -> View<'a> {
        View {
            image,
            to_camera: pose.cast::<f64>().inverse(),
        }
    }

    /// Whether the pixel that world point `p` projects to (the sampled pixel at or
    /// before it, with the image's stride) measured a depth beyond `p` by more than a
    /// cell plus twice the range noise there: the camera saw through `p`.
    fn sees_beyond(&self, cfg: &Config, p: &Vector3<f64>) -> bool {
        self.depths(cfg, p)
            .is_some_and(|(measured, along, margin)| measured > along + margin)
    }

    /// Whether the pixel that world point `p` projects to measured a depth nearer than
    /// `p` by more than a cell plus twice the range noise: something hides `p`.
    fn hides(&self, cfg: &Config, p: &Vector3<f64>) -> bool {
        self.depths(cfg, p)
            .is_some_and(|(measured, along, margin)| measured < along - margin)
    }

    /// The depth measured at the pixel `p` projects to, `p`'s own depth along it and the
    /// margin (a cell plus twice the range noise); `None` outside the image or without a
    /// positive finite depth.
    fn depths(&self, cfg: &Config, p: &Vector3<f64>) -> Option<(f64, f64, f64)> {
        let c = self.to_camera * nalgebra::Point3::from(*p);
        let cam = &self.image.camera;
        if c.z <= 0.0 {
            return None;
        }
        let u = cam.fx as f64 * c.x / c.z + cam.cx as f64;
        let v = cam.fy as f64 * c.y / c.z + cam.cy as f64;
        if !(u >= 0.0 && v >= 0.0 && u < cam.width as f64 && v < cam.height as f64) {
            return None;
        }
        let s = self.image.stride.max(1) as usize;
        let (col, row) = (u as usize / s * s, v as usize / s * s);
        let measured = self.image.depth.metres(row * cam.width as usize + col)?;
        let along = match self.image.kind {
            DepthKind::Planar => c.z,
            DepthKind::Range => c.coords.norm(),
        };
        let sigma = cfg.noise_base as f64 + cfg.noise_quadratic as f64 * along * along;
        (measured.is_finite() && measured > 0.0).then_some((
            measured as f64,
            along,
            cfg.cell_size as f64 + 2.0 * sigma,
        ))
    }
}

/// Where one sensor point lands (step 1).
enum Landing {
    /// Bad coordinates, bad labels, or outside the key range.
    Rejected,
    /// Beyond `max_range`: only the voxel where its ray is truncated.
    Truncated(Key),
    /// In range: its end voxel and world position (`f32`, as the core computes it).
    End { key: Key, world: [f32; 3] },
}

/// One frame's votes for one end voxel: per class (bin `i` is class `i + 1`) and the
/// number of voting points the voxel's sample took.
struct FrameVotes {
    per_class: Vec<u32>,
    taken: u32,
}

/// What step 3 remembers within a frame: the voxels already missed, and the prepared
/// Gaussians looked up so far (unchanged during step 3: misses touch only log-odds).
#[derive(Default)]
struct FrameMisses {
    missed: KeySet,
    /// The voxels that received points this frame.
    hit: KeySet,
    gaussians: KeyMap<Option<(Vector3<f64>, Matrix3<f64>)>>,
}

/// The core's ray order inside a frame: by 4x4x4 block (lexicographic block key), then end
/// voxels before truncated ends, then by cell index in the block (x fastest).
fn ray_order(k: &Key, truncated: bool) -> (i32, i32, i32, bool, i32) {
    let cell = (k[0] & 3) | ((k[1] & 3) << 2) | ((k[2] & 3) << 4);
    (k[0] >> 2, k[1] >> 2, k[2] >> 2, truncated, cell)
}

/// Exact voxel traversal (Amanatides & Woo) of the segment from `o` to `target` (voxel
/// units), from voxel `start` to voxel `end`, pushing every voxel visited; `end` only when
/// `include_end`. Where the segment crosses several boundaries at once, the lowest axis
/// steps first. Stops after the Manhattan distance of the keys (or if it would leave the
/// segment), so it always ends.
fn walk_segment(
    o: [f64; 3],
    target: [f64; 3],
    start: Key,
    end: Key,
    include_end: bool,
    out: &mut Vec<Key>,
) {
    let d = [0, 1, 2].map(|i| target[i] - o[i]);
    let mut k = start;
    let mut step = [0; 3];
    let mut t_next = [f64::INFINITY; 3];
    let mut t_delta = [f64::INFINITY; 3];
    for a in 0..3 {
        if d[a] > 0.0 {
            step[a] = 1;
            t_next[a] = (k[a] as f64 + 1.0 - o[a]) / d[a];
            t_delta[a] = 1.0 / d[a];
        } else if d[a] < 0.0 {
            step[a] = -1;
            t_next[a] = (k[a] as f64 - o[a]) / d[a];
            t_delta[a] = -1.0 / d[a];
        }
    }
    let steps: u32 = (0..3).map(|a| (end[a] - start[a]).unsigned_abs()).sum();
    for _ in 0..=steps {
        if k == end {
            if include_end {
                out.push(end);
            }
            return;
        }
        out.push(k);
        let mut a = 0;
        for b in 1..3 {
            if t_next[b] < t_next[a] {
                a = b;
            }
        }
        if t_next[a] > 1.0 + 1e-9 {
            return;
        }
        k[a] += step[a];
        t_next[a] += t_delta[a];
    }
}

/// Where `ray` passes a Gaussian (mean `mu`, inverse covariance `inv`): the squared
/// Mahalanobis distance of its closest point and `pz` there (see [`ndt_om_miss`]).
/// `Err(())` when `inv` gives no direction, `Ok(None)` when the closest point lies beyond
/// the ray's end.
#[allow(clippy::result_unit_err)]
fn closest_approach(
    cfg: &Config,
    ray: &Ray,
    mu: &Vector3<f64>,
    inv: &Matrix3<f64>,
) -> Result<Option<(f64, f64)>, ()> {
    let u = ray.dir;
    let w = inv * u;
    let a = u.dot(&w);
    if a.is_nan() || a <= 0.0 {
        return Err(());
    }
    let t = w.dot(&(mu - ray.origin)) / a;
    if t > ray.len {
        return Ok(None);
    }
    let dx = ray.origin + u * t - mu;
    let p_z = if ray.measured {
        let sigma = cfg.noise_base as f64 + cfg.noise_quadratic as f64 * ray.len * ray.len;
        let dz = ray.len - t;
        (-0.5 * dz * dz / (sigma * sigma)).exp()
    } else {
        0.0
    };
    Ok(Some((dx.dot(&(inv * dx)), p_z)))
}

/// The see-through miss (the core's `Config::see_through_miss`): for a ray whose closest
/// point lies within Mahalanobis radius 2 of the Gaussian (4 for a `doubted` voxel, more
/// than 1 below the upper clamp) and before the ray's end, with `pz < 1/2`,
/// `see_through_miss (1 - pz)`; else `None`.
fn see_through_miss(
    cfg: &Config,
    ray: &Ray,
    mu: &Vector3<f64>,
    inv: &Matrix3<f64>,
    doubted: bool,
) -> Option<f64> {
    let r2 = if doubted { 16.0 } else { 4.0 };
    match closest_approach(cfg, ray, mu, inv) {
        Err(()) => Some(cfg.miss as f64),
        Ok(Some((d2, p_z))) => {
            (d2 <= r2 && p_z < 0.5).then_some(cfg.see_through_miss as f64 * (1.0 - p_z))
        }
        Ok(None) => None,
    }
}

/// NDT-OM miss log-odds (the core's miss model) for `ray` through a Gaussian with mean `mu`
/// and inverse covariance `inv`, or `None` when the ray's closest point to the Gaussian
/// lies beyond its end:
/// `t* = u^T S^-1 (mu - s) / (u^T S^-1 u)`, `x = s + t* u`,
/// `pN = exp(-(x - mu)^T S^-1 (x - mu) / 2)`, `pz = exp(-|x - z|^2 / (2 sigma^2))` with
/// `sigma = noise_base + noise_quadratic r^2` at the ray's length `r` (0 for a truncated
/// ray), `p = 0.5 - lambda pN (1 - pz)`, miss = `logit(p)`.
fn ndt_om_miss(cfg: &Config, ray: &Ray, mu: &Vector3<f64>, inv: &Matrix3<f64>) -> Option<f64> {
    let (d2, p_z) = match closest_approach(cfg, ray, mu, inv) {
        Err(()) => return Some(cfg.miss as f64),
        Ok(None) => return None,
        Ok(Some(found)) => found,
    };
    let p_n = (-0.5 * d2).exp();
    let p = 0.5 - cfg.lambda as f64 * p_n * (1.0 - p_z);
    Some((p / (1.0 - p)).ln())
}
