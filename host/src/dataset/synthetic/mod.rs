//! Synthetic labelled indoor scenes ("mini-Hypersim"), deterministic from a seed, so that
//! every tool runs without a download.
//!
//! - [`scenes`]: procedural rooms of six kinds built from labelled primitives (the
//!   scene type here, the generator's parts in a file each: placement rules, the room
//!   shell, furniture, the kinds of room);
//! - [`dynamic`]: a room where a chair is moved, an object replaced, a door opens and a
//!   person and a cart pass (the scene of the dynamics report), and its frozen twin;
//! - [`floor`]: a building floor of eleven such rooms along a corridor (its layout), and
//!   walks through all of them (timing in `floor/walk.rs`, paths planned on a clearance
//!   grid in `floor/planner.rs`);
//! - [`geometry`]: the primitives, a BVH and exact ray casting;
//! - [`render`]: 1024x768 Euclidean range, planar depth, NYU40 labels and instances with
//!   exact pinhole intrinsics;
//! - [`trajectory`]: random walks of camera poses at person height looking into the scene;
//! - [`DepthNoise`]: an optional range-dependent depth-noise model;
//! - [`predict`]: a segmentation-network model producing ESANet-style top-3 predictions;
//! - [`Synthetic`]: the split (separate rooms, or a walk of the floor) as a [`Dataset`]
//!   rendered on demand, and [`write_split`] writing it in the prepared layout that
//!   [`crate::dataset::prepared`] reads.
//!
//! The renderer sits in the host's reader layer (see the crate doc): it makes the same
//! [`Frame`]s a reader returns, and uses nothing above that layer.

pub mod dynamic;
pub mod floor;
pub mod geometry;
pub mod people;
pub mod predict;
pub mod room;
pub mod scenes;

use crate::dataset::frame::{Frame, FrameId, Rays};
use crate::dataset::source::Dataset;
use anyhow::{bail, Result};
use geometry::Cast;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use scenes::SynthScene;
use sndt_core::{DepthKind, Isometry3, Pinhole, Vector3};
use std::path::Path;
use std::sync::Arc;

/// The default seed of `sndt synth` and the demo.
pub const DEFAULT_SEED: u64 = 20_240_710;

/// The camera of the synthetic split: Hypersim's nominal 1024x768 pinhole, exact here.
pub const CAMERA: Pinhole = crate::dataset::synthetic::room::HYPERSIM_CAMERA;

/// Rays longer than this hit nothing (metres).
const MAX_RAY: f32 = 100.0;

/// Added to the walk number to key the floor's noise and predictions (rooms use their
/// scene number).
const FLOOR_KEY: u64 = 0xF100;

/// The same for the dynamic room.
const DYNAMIC_KEY: u64 = 0xD100;

/// One rendered view.
#[derive(Clone, Debug, PartialEq)]
pub struct Render {
    /// Euclidean distance from the optical centre, metres (0 = nothing hit).
    pub range: Vec<f32>,
    /// Depth along the optical axis, metres (0 = nothing hit).
    pub planar: Vec<f32>,
    /// NYU40 class per pixel (0 = void or nothing hit).
    pub labels: Vec<u8>,
    /// Object instance per pixel (0 = nothing hit).
    pub instances: Vec<u16>,
}

/// Renders `scene` (a room, the building floor: any [`Cast`]) from camera-to-world `pose`
/// (OpenCV axes) with pinhole `cam`; rows in parallel.
///
/// ```
/// use sndt_host::dataset::synthetic::{render, scenes::SynthScene};
/// let scene = SynthScene::generate(1, 5);
/// let cam = sndt_core::Pinhole { fx: 40.0, fy: 40.0, cx: 32.0, cy: 24.0, width: 64, height: 48 };
/// let pose = sndt_host::dataset::synthetic::room::look_at([1.0, 1.0, 1.5], [2.0, 2.0, 1.0]);
/// let r = render(&scene, &pose, &cam);
/// assert!(r.planar.iter().all(|&d| d > 0.0)); // a closed room: every ray hits
/// ```
pub fn render<S: Cast + ?Sized>(scene: &S, pose: &Isometry3<f32>, cam: &Pinhole) -> Render {
    let (w, h) = (cam.width as usize, cam.height as usize);
    let rot = pose.rotation.to_rotation_matrix();
    let o = pose.translation.vector;
    let origin = [o.x, o.y, o.z];
    let rows: Vec<Vec<(f32, f32, u8, u16)>> = (0..h)
        .into_par_iter()
        .map(|row| {
            (0..w)
                .map(|col| {
                    let r = cam.ray(col as u32, row as u32);
                    let d = rot * Vector3::new(r[0], r[1], r[2]);
                    let norm = (r[0] * r[0] + r[1] * r[1] + 1.0).sqrt();
                    // With unit-z camera rays, t is the planar depth directly.
                    match scene.cast(&origin, &[d.x, d.y, d.z], MAX_RAY) {
                        Some(hit) => (hit.t * norm, hit.t, hit.label, hit.instance),
                        None => (0.0, 0.0, 0, 0),
                    }
                })
                .collect()
        })
        .collect();
    let mut out = Render {
        range: Vec::with_capacity(w * h),
        planar: Vec::with_capacity(w * h),
        labels: Vec::with_capacity(w * h),
        instances: Vec::with_capacity(w * h),
    };
    for (range, planar, label, inst) in rows.into_iter().flatten() {
        out.range.push(range);
        out.planar.push(planar);
        out.labels.push(label);
        out.instances.push(inst);
    }
    out
}

/// A Hypersim-like camera trajectory: `frames` poses of a random walk at person height
/// (1.35-1.75 m), turning smoothly towards objects of interest, never closer than 0.5 m
/// to anything. Deterministic in `seed`.
///
/// ```
/// use sndt_host::dataset::synthetic::{trajectory, scenes::SynthScene};
/// let scene = SynthScene::generate(0, 3);
/// let poses = trajectory(&scene, 100, 9);
/// assert_eq!(poses.len(), 100);
/// for p in &poses {
///     let t = p.translation.vector;
///     assert!(t.z > 1.3 && t.z < 1.8 && scene.free(&[t.x, t.y, t.z], 0.45));
/// }
/// ```
pub fn trajectory(scene: &SynthScene, frames: usize, seed: u64) -> Vec<Isometry3<f32>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let margin = 0.5;
    let [sx, sy, _] = scene.size;
    let mut eye = [0.5 * sx, 0.5 * sy, 1.55];
    for _ in 0..10_000 {
        let p = [
            rng.random_range(0.4..sx - 0.4),
            rng.random_range(0.4..sy - 0.4),
            rng.random_range(1.45..1.65),
        ];
        if scene.free(&p, margin + 0.1) {
            eye = p;
            break;
        }
    }
    let pick_target = |rng: &mut ChaCha8Rng, eye: &[f32; 3]| -> [f32; 3] {
        for _ in 0..50 {
            let t = scene.interest[rng.random_range(0..scene.interest.len().max(1))];
            let d = ((t[0] - eye[0]).powi(2) + (t[1] - eye[1]).powi(2)).sqrt();
            if d > 1.8 {
                return t;
            }
        }
        [sx - eye[0], sy - eye[1], 1.0]
    };
    let mut target = pick_target(&mut rng, &eye);
    let mut look =
        Vector3::new(target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]).normalize();
    let mut vel = [0.0f32; 2];
    let mut until_switch = rng.random_range(15..35);
    let mut poses = Vec::with_capacity(frames);
    for _ in 0..frames {
        // Walk: a smoothed random velocity, bounded to 8 cm per frame, reflecting off
        // obstacles.
        for attempt in 0..20 {
            let mut v = [
                0.85 * vel[0] + rng.random_range(-0.025..0.025),
                0.85 * vel[1] + rng.random_range(-0.025..0.025),
            ];
            let s = (v[0] * v[0] + v[1] * v[1]).sqrt();
            if s > 0.08 {
                v = [v[0] * 0.08 / s, v[1] * 0.08 / s];
            }
            if attempt > 0 {
                v = [
                    -vel[0] * 0.5 + rng.random_range(-0.04..0.04),
                    -vel[1] * 0.5 + rng.random_range(-0.04..0.04),
                ];
            }
            let z = (eye[2] + rng.random_range(-0.01..0.01)).clamp(1.35, 1.75);
            let next = [eye[0] + v[0], eye[1] + v[1], z];
            if scene.free(&next, margin) {
                eye = next;
                vel = v;
                break;
            }
            vel = [0.0, 0.0];
        }
        until_switch -= 1;
        if until_switch <= 0 {
            target = pick_target(&mut rng, &eye);
            until_switch = rng.random_range(15..35);
        }
        let want = Vector3::new(target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]);
        if want.norm() > 1e-3 {
            look = (0.88 * look + 0.12 * want.normalize()).normalize();
        }
        // Keep the view within 50 degrees of horizontal.
        let horiz = (look.x * look.x + look.y * look.y).sqrt();
        if look.z.abs() > 0.77 * look.norm() || horiz < 1e-3 {
            look = Vector3::new(look.x, look.y, look.z.clamp(-0.7, 0.7)).normalize();
        }
        let t = [eye[0] + look.x, eye[1] + look.y, eye[2] + look.z];
        poses.push(crate::dataset::synthetic::room::look_at(eye, t));
    }
    poses
}

/// Range-dependent depth noise of a structured-light camera (Nguyen et al. 2012):
/// `sigma(z) = a + b (z - 0.4)^2` metres, Gaussian, on planar depth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthNoise {
    /// Constant term, metres.
    pub a: f32,
    /// Quadratic term, 1/metres.
    pub b: f32,
}

impl DepthNoise {
    /// The Kinect v1 figures: 1.2 mm + 1.9 mm/m^2.
    pub const KINECT: DepthNoise = DepthNoise {
        a: 0.0012,
        b: 0.0019,
    };

    /// Standard deviation at planar depth `z`.
    ///
    /// ```
    /// let n = sndt_host::dataset::synthetic::DepthNoise::KINECT;
    /// assert!((n.sigma(3.4) - (0.0012 + 0.0019 * 9.0)).abs() < 1e-7);
    /// ```
    pub fn sigma(&self, z: f32) -> f32 {
        self.a + self.b * (z - 0.4) * (z - 0.4)
    }

    /// Adds noise to valid (positive) depths in place.
    pub fn apply(&self, depth: &mut [f32], seed: u64) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        for d in depth.iter_mut().filter(|d| **d > 0.0) {
            // Box-Muller from two uniforms.
            let (u1, u2): (f32, f32) = (rng.random_range(f32::EPSILON..1.0), rng.random());
            let g = (-2.0 * u1.ln()).sqrt() * (std::f32::consts::TAU * u2).cos();
            *d = (*d + g * self.sigma(*d)).max(0.01);
        }
    }
}

/// What to generate.
#[derive(Clone, Debug, PartialEq)]
pub struct SynthOptions {
    /// Number of scenes (the kinds cycle: living, bedroom, kitchen, office, bathroom,
    /// open plan).
    pub scenes: usize,
    /// Frames per trajectory (one trajectory `cam_00` per scene).
    pub frames: usize,
    /// Seed of everything.
    pub seed: u64,
    /// Depth noise, if any.
    pub noise: Option<DepthNoise>,
    /// Whether to generate predicted labels.
    pub predictions: bool,
    /// The camera.
    pub camera: Pinhole,
    /// The prediction model.
    pub model: predict::ModelParams,
    /// `Some(walk)`: instead of `scenes` rooms, one trajectory of `frames` frames: walk
    /// `walk` (1, 2, ...) of the building floor ([`floor`]), scene
    /// [`floor::NAME`], camera `cam_NN` with `NN = walk - 1`.
    pub floor: Option<u32>,
    /// `Some`: instead of rooms or the floor, the [`dynamic`] room for `frames` frames,
    /// scene [`dynamic::NAME`], camera `cam_00`.
    pub dynamic: Option<DynamicOptions>,
}

/// How the [`dynamic`] room changes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DynamicOptions {
    /// The frame of the first change ([`dynamic::DEFAULT_CHANGE`]; the room only).
    pub change: u32,
    /// Every frame shows the scene as at frame 0 (the reference of static loss).
    pub frozen: bool,
    /// `Some(walk)`: instead of the room, walk `walk` of the building floor with people in
    /// its corridor ([`people`]), scene [`people::NAME`].
    pub floor_walk: Option<u32>,
}

impl Default for DynamicOptions {
    fn default() -> Self {
        DynamicOptions {
            change: dynamic::DEFAULT_CHANGE,
            frozen: false,
            floor_walk: None,
        }
    }
}

impl Default for SynthOptions {
    fn default() -> Self {
        SynthOptions {
            scenes: 6,
            frames: 100,
            seed: DEFAULT_SEED,
            noise: None,
            predictions: true,
            camera: CAMERA,
            model: predict::ModelParams::DEFAULT,
            floor: None,
            dynamic: None,
        }
    }
}

/// A synthetic split as a [`Dataset`]: scenes and trajectories are built on open, frames
/// are rendered when loaded.
pub struct Synthetic {
    options: SynthOptions,
    scenes: Vec<SynthScene>,
    /// The building floor, when the split is a walk of it (then `scenes` is empty).
    floor: Option<floor::Floor>,
    /// The dynamic room, when the split is its walk.
    dynamic: Option<dynamic::DynamicScene>,
    poses: Vec<Vec<Isometry3<f32>>>,
    frames: Vec<FrameId>,
    rays: Arc<Rays>,
}

impl Synthetic {
    /// Builds the scenes and trajectories.
    ///
    /// ```
    /// use sndt_host::dataset::Dataset;
    /// use sndt_host::dataset::synthetic::{Synthetic, SynthOptions};
    /// let camera = sndt_core::Pinhole { fx: 40.0, fy: 40.0, cx: 32.0, cy: 24.0, width: 64, height: 48 };
    /// let split = Synthetic::new(SynthOptions { scenes: 2, frames: 3, camera, ..Default::default() }).unwrap();
    /// assert_eq!(split.frames().len(), 6);
    /// let f = split.load(&split.frames()[4]).unwrap();
    /// assert_eq!(f.id.to_string(), "synth_01_bedroom/cam_00/0001");
    /// assert!(f.labels.is_some() && f.predictions.is_some());
    /// ```
    pub fn new(options: SynthOptions) -> Result<Synthetic> {
        if let Some(walk) = options.floor {
            return Self::floor(options, walk);
        }
        if let Some(d) = options.dynamic {
            return Self::dynamic(options, d);
        }
        if options.scenes == 0 || options.frames == 0 || options.frames > 10_000 {
            bail!("synthetic split: need 1.. scenes and 1..=10000 frames");
        }
        let scenes: Vec<SynthScene> = (0..options.scenes)
            .into_par_iter()
            .map(|i| SynthScene::generate(i, options.seed))
            .collect();
        let poses: Vec<Vec<Isometry3<f32>>> = scenes
            .par_iter()
            .enumerate()
            .map(|(i, s)| {
                trajectory(
                    s,
                    options.frames,
                    options.seed.wrapping_add(1000 + i as u64),
                )
            })
            .collect();
        let frames = scenes
            .iter()
            .flat_map(|s| {
                (0..options.frames as u32).map(|index| FrameId {
                    scene: s.name.clone(),
                    cam: "cam_00".into(),
                    index,
                })
            })
            .collect();
        let rays = Arc::new(Rays::Pinhole(options.camera));
        Ok(Synthetic {
            options,
            scenes,
            floor: None,
            dynamic: None,
            poses,
            frames,
            rays,
        })
    }

    /// Builds the dynamic room's walk.
    ///
    /// ```
    /// use sndt_host::dataset::Dataset;
    /// use sndt_host::dataset::synthetic::{dynamic, DynamicOptions, Synthetic, SynthOptions};
    /// let camera = sndt_core::Pinhole { fx: 40.0, fy: 40.0, cx: 32.0, cy: 24.0, width: 64, height: 48 };
    /// let dynamic = Some(DynamicOptions::default());
    /// let frames = dynamic::DEFAULT_FRAMES;
    /// let walk = Synthetic::new(SynthOptions { dynamic, frames, camera, ..Default::default() }).unwrap();
    /// let f = walk.load(&walk.frames()[4]).unwrap();
    /// assert_eq!(f.id.to_string(), "synth_dynamic/cam_00/0004");
    /// ```
    fn dynamic(options: SynthOptions, d: DynamicOptions) -> Result<Synthetic> {
        let scene = match d.floor_walk {
            Some(walk) => {
                dynamic::DynamicScene::floor_people(options.seed, walk, options.frames, d.frozen)?
            }
            None => dynamic::DynamicScene::new(options.frames, d.change, d.frozen)?,
        };
        let poses = vec![(0..options.frames as u32).map(|f| scene.pose(f)).collect()];
        let frames = (0..options.frames as u32)
            .map(|index| FrameId {
                scene: scene.name.into(),
                cam: "cam_00".into(),
                index,
            })
            .collect();
        let rays = Arc::new(Rays::Pinhole(options.camera));
        Ok(Synthetic {
            options,
            scenes: Vec::new(),
            floor: None,
            dynamic: Some(scene),
            poses,
            frames,
            rays,
        })
    }

    /// The dynamic room, when the split is its walk.
    pub fn dynamic_scene(&self) -> Option<&dynamic::DynamicScene> {
        self.dynamic.as_ref()
    }

    /// Builds the floor and walk `walk` of it.
    ///
    /// ```
    /// use sndt_host::dataset::Dataset;
    /// use sndt_host::dataset::synthetic::{Synthetic, SynthOptions};
    /// let camera = sndt_core::Pinhole { fx: 40.0, fy: 40.0, cx: 32.0, cy: 24.0, width: 64, height: 48 };
    /// let walk = Synthetic::new(SynthOptions { floor: Some(2), frames: 5, camera, ..Default::default() }).unwrap();
    /// assert_eq!(walk.frames().len(), 5);
    /// let f = walk.load(&walk.frames()[4]).unwrap();
    /// assert_eq!(f.id.to_string(), "synth_floor/cam_01/0004");
    /// assert!(f.labels.is_some() && f.predictions.is_some());
    /// ```
    fn floor(options: SynthOptions, walk: u32) -> Result<Synthetic> {
        if walk == 0 || options.frames == 0 || options.frames > 10_000 {
            bail!("synthetic floor: need a walk 1, 2, ... and 1..=10000 frames");
        }
        let floor = floor::Floor::generate(options.seed);
        let poses = vec![floor.walk(walk, options.frames)];
        let frames = (0..options.frames as u32)
            .map(|index| FrameId {
                scene: floor.name.clone(),
                cam: Self::floor_cam(walk),
                index,
            })
            .collect();
        let rays = Arc::new(Rays::Pinhole(options.camera));
        Ok(Synthetic {
            options,
            scenes: Vec::new(),
            floor: Some(floor),
            dynamic: None,
            poses,
            frames,
            rays,
        })
    }

    /// The camera (trajectory) name of walk `walk` of the floor.
    fn floor_cam(walk: u32) -> String {
        format!("cam_{:02}", walk - 1)
    }

    /// The building floor, when the split is a walk of it.
    pub fn floor_scene(&self) -> Option<&floor::Floor> {
        self.floor.as_ref()
    }

    /// The camera poses of every trajectory (one per scene, or the floor's walk).
    pub fn poses(&self) -> &[Vec<Isometry3<f32>>] {
        &self.poses
    }

    /// The scenes.
    pub fn scenes(&self) -> &[SynthScene] {
        &self.scenes
    }

    /// The options it was built with.
    pub fn options(&self) -> &SynthOptions {
        &self.options
    }

    /// Renders a frame and also returns the instance image.
    pub fn render_frame(&self, id: &FrameId) -> Result<(Frame, Vec<u16>)> {
        if let Some(scene) = &self.dynamic {
            if id.scene != scene.name || id.cam != "cam_00" || id.index as usize >= scene.frames {
                bail!("{id}: no such frame in the synthetic dynamic walk");
            }
            let pose = self.poses[0][id.index as usize];
            return Ok(self.frame(id, &scene.at(id.index), pose, DYNAMIC_KEY));
        }
        if let (Some(floor), Some(walk)) = (&self.floor, self.options.floor) {
            if id.scene != floor.name
                || id.cam != Self::floor_cam(walk)
                || id.index as usize >= self.options.frames
            {
                bail!("{id}: no such frame in the synthetic floor's walk");
            }
            // Keys apart from the rooms' (scene numbers) and per walk.
            let key = FLOOR_KEY + u64::from(walk);
            return Ok(self.frame(id, floor, self.poses[0][id.index as usize], key));
        }
        let Some(s) = self.scenes.iter().position(|s| s.name == id.scene) else {
            bail!("{id}: no such scene in the synthetic split");
        };
        if id.cam != "cam_00" || id.index as usize >= self.options.frames {
            bail!("{id}: no such frame in the synthetic split");
        }
        Ok(self.frame(
            id,
            &self.scenes[s],
            self.poses[s][id.index as usize],
            s as u64,
        ))
    }

    /// Renders frame `id` of `scene` at `pose`, with noise and predictions keyed by `s`.
    fn frame<S: Cast>(
        &self,
        id: &FrameId,
        scene: &S,
        pose: Isometry3<f32>,
        s: u64,
    ) -> (Frame, Vec<u16>) {
        let cam = &self.options.camera;
        let r = render(scene, &pose, cam);
        let frame_seed = self.options.seed ^ (s << 32) ^ id.index as u64;
        let mut depth = r.planar;
        if let Some(noise) = self.options.noise {
            noise.apply(&mut depth, frame_seed.wrapping_mul(31));
        }
        let predictions = self.options.predictions.then(|| {
            predict::predict(
                &r.labels,
                &r.instances,
                cam.width,
                cam.height,
                self.options.seed.wrapping_add(s),
                id.index,
                frame_seed.wrapping_mul(17),
                &self.options.model,
            )
        });
        let frame = Frame {
            id: id.clone(),
            pose,
            rays: self.rays.clone(),
            depth,
            depth_kind: DepthKind::Planar,
            labels: Some(r.labels),
            predictions,
        };
        (frame, r.instances)
    }
}

impl Dataset for Synthetic {
    fn describe(&self) -> String {
        if let (Some(scene), Some(walk)) = (
            &self.dynamic,
            self.options.dynamic.and_then(|d| d.floor_walk),
        ) {
            return format!(
                "synthetic floor walk {walk} with {} people in the corridor{} (seed {}): {} \
                 frames of {}x{}",
                scene.events.len(),
                if scene.frozen {
                    ", frozen (no people)"
                } else {
                    ""
                },
                self.options.seed,
                scene.frames,
                self.options.camera.width,
                self.options.camera.height,
            );
        }
        if let Some(scene) = &self.dynamic {
            return format!(
                "synthetic dynamic room{} (seed {}): {} frames of {}x{}, first change at frame {}",
                if scene.frozen { ", frozen" } else { "" },
                self.options.seed,
                scene.frames,
                self.options.camera.width,
                self.options.camera.height,
                scene.events.first().map_or(0, |e| e.first)
            );
        }
        if let (Some(floor), Some(walk)) = (&self.floor, self.options.floor) {
            return format!(
                "synthetic building floor (seed {}): {} rooms, walk {walk} of {} frames of {}x{}",
                self.options.seed,
                floor.rooms.len(),
                self.options.frames,
                self.options.camera.width,
                self.options.camera.height
            );
        }
        format!(
            "synthetic split (seed {}): {} scenes x {} frames of {}x{}",
            self.options.seed,
            self.scenes.len(),
            self.options.frames,
            self.options.camera.width,
            self.options.camera.height
        )
    }

    fn frames(&self) -> &[FrameId] {
        &self.frames
    }

    fn load(&self, id: &FrameId) -> Result<Frame> {
        Ok(self.render_frame(id)?.0)
    }

    fn missing_predictions(&self) -> Option<String> {
        (!self.options.predictions)
            .then(|| "the synthetic split was rendered without predictions".into())
    }
}

/// Generates the split and writes it in the prepared layout under `root` (split `test`,
/// plus intrinsics and ESANet-style `.npy` predictions); frames in parallel. Returns the
/// number of frames written.
///
/// `on_frame` sees every frame once it is on disk, from the worker threads and in no
/// particular order: the caller counts classes or advances a progress bar there without
/// rendering the split a second time.
pub fn write_split(
    root: &Path,
    split: &Synthetic,
    on_frame: &(dyn Fn(&Frame) + Sync),
) -> Result<usize> {
    let ids = split.frames().to_vec();
    // Every chunk runs to its end even if another fails, then the first error is reported.
    let written: Vec<Result<()>> = ids
        .par_chunks(8)
        .map(|chunk| {
            for id in chunk {
                let f = split.load(id)?;
                crate::dataset::prepared::write_frame(root, "test", &f)?;
                on_frame(&f);
            }
            Ok(())
        })
        .collect();
    written.into_iter().collect::<Result<()>>()?;
    crate::dataset::prepared::write_split_list(root, "test", &ids)?;
    Ok(ids.len())
}
