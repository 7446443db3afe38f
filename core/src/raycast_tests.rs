//! The optimised ray caster against the straightforward one it replaced (kept here as the
//! reference): every pixel's label and distance must be bit-identical.

extern crate std;

use super::RayHit;
use crate::block::Block;
use crate::dda::Dda;
use crate::gaussian::PrepCache;
use crate::key::VoxelKey;
use crate::map::Map;
use crate::render::INVALID_LABEL;
use crate::table::Table;
use crate::voxel::argmax;
use crate::*;
use std::boxed::Box;
use std::vec::Vec;

// ---------------------------------------------------------------------------------------
// Reference: the original algorithm (every cell of every new face looked up one by one).
// ---------------------------------------------------------------------------------------

struct Probe<'a, const B: usize, const N: usize> {
    blocks: &'a Table<Block, B>,
    cache: &'a mut PrepCache<N>,
    block_cache: [(u64, u32); 8],
    best: Option<RayHit>,
    origin: Vector3<f32>,
    u: Vector3<f32>,
    max_t: f32,
}

fn reference_raycast<const V: usize, const B: usize, const C: usize, const N: usize>(
    map: &Map<V, B, C>,
    cache: &mut PrepCache<N>,
    origin: &Point3<f32>,
    dir: &Vector3<f32>,
    max_t: f32,
) -> Option<RayHit> {
    let n = dir.norm();
    let finite = origin.coords.iter().all(|x| x.is_finite());
    if !(finite && n.is_finite() && n > 0.0 && max_t > 0.0) {
        return None;
    }
    let u = dir / n;
    let cfg = &map.config;
    let h = cfg.cell_size;
    let start = map.voxel_key(&[origin.x, origin.y, origin.z])?;
    let inv = 1.0 / h;
    let o = [origin.x * inv, origin.y * inv, origin.z * inv];
    let k = [start.x as i32, start.y as i32, start.z as i32];
    let mut dda = Dda::new(o, [u.x, u.y, u.z], k);
    let mut probe = Probe {
        blocks: &map.blocks,
        cache,
        block_cache: [(0, 0); 8],
        best: None,
        origin: Vector3::new(origin.x, origin.y, origin.z),
        u,
        max_t,
    };
    for dx in -1..=1 {
        for dy in -1..=1 {
            for dz in -1..=1 {
                reference_examine(map, &mut probe, [k[0] + dx, k[1] + dy, k[2] + dz]);
            }
        }
    }
    let max_t = max_t.min(h * 4.0 * (crate::KEY_LIMIT + 1) as f32);
    let max_steps = ((max_t / h) as u32).saturating_mul(3).saturating_add(12);
    for _ in 0..max_steps {
        let (a, t) = dda.next_axis();
        let t_enter = t * h;
        if t_enter > max_t + 2.5 * h {
            break;
        }
        if let Some(best) = probe.best {
            if t_enter > best.t + 2.5 * h {
                break;
            }
        }
        dda.advance(a);
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        for db in -1..=1 {
            for dc in -1..=1 {
                let mut cell = dda.k;
                cell[a] += dda.step(a);
                cell[b] += db;
                cell[c] += dc;
                reference_examine(map, &mut probe, cell);
            }
        }
    }
    probe.best
}

fn reference_examine<const V: usize, const B: usize, const C: usize, const N: usize>(
    map: &Map<V, B, C>,
    p: &mut Probe<'_, B, N>,
    k: [i32; 3],
) {
    let Some(key) = VoxelKey::from_ints(k[0], k[1], k[2]) else {
        return;
    };
    let packed = key.block();
    let i = (((k[0] >> 2) & 1) | (((k[1] >> 2) & 1) << 1) | (((k[2] >> 2) & 1) << 2)) as usize;
    let (tag, found) = p.block_cache[i];
    let found = if tag == packed {
        found
    } else {
        let f = p.blocks.find(packed).map_or(0, |s| s as u32 + 1);
        p.block_cache[i] = (packed, f);
        f
    };
    if found == 0 {
        return;
    }
    let b = &p.blocks.slots[(found - 1) as usize];
    let cell = key.cell();
    if b.surface & (1u64 << cell) == 0 || b.cells[cell as usize] <= 0 {
        return;
    }
    let Some(vs) = map.voxels.find(key.packed()) else {
        return;
    };
    let v = &map.voxels.slots[vs];
    let cfg = &map.config;
    if v.n < cfg.n_min {
        return;
    }
    let g = p.cache.get(vs, || v.prepared(cfg));
    let d = p.origin - g.mean;
    let w = g.inv * p.u;
    let a = p.u.dot(&w);
    let bq = 2.0 * w.dot(&d);
    let c = d.dot(&(g.inv * d));
    if a.is_nan() || a <= 0.0 {
        return;
    }
    let r2 = cfg.render_radius * cfg.render_radius;
    let t_star = -bq / (2.0 * a);
    let e = d + p.u * t_star;
    let d2 = e.dot(&(g.inv * e));
    if d2 > r2 || c <= r2 {
        return;
    }
    let t = t_star - libm::sqrtf((r2 - d2) / a);
    if !(t >= 0.0 && t <= p.max_t) {
        return;
    }
    if p.best
        .is_none_or(|best| t < best.t || (t == best.t && key < best.key))
    {
        let class = argmax(&v.hist).map_or(0, |(c, _)| c);
        p.best = Some(RayHit { t, class, key });
    }
}

/// The original `render`: row-major, one ray per pixel.
fn reference_render<const V: usize, const B: usize, const C: usize>(
    map: &Map<V, B, C>,
    pose: &Isometry3<f32>,
    camera: &Pinhole,
) -> (Vec<u8>, Vec<f32>) {
    let n = (camera.width * camera.height) as usize;
    let (mut labels, mut distance) = (std::vec![0u8; n], std::vec![0f32; n]);
    let rot = pose.rotation.to_rotation_matrix();
    let origin = Point3::from(pose.translation.vector);
    let w = camera.width as usize;
    let mut cache = PrepCache::<128>::new();
    for (i, (l, d)) in labels.iter_mut().zip(distance.iter_mut()).enumerate() {
        let r = camera.ray((i % w) as u32, (i / w) as u32);
        let dir = rot * Vector3::new(r[0], r[1], r[2]);
        match reference_raycast(map, &mut cache, &origin, &dir, map.config.max_range) {
            Some(hit) => {
                *l = hit.class;
                *d = hit.t;
            }
            None => {
                *l = INVALID_LABEL;
                *d = 0.0;
            }
        }
    }
    (labels, distance)
}

// ---------------------------------------------------------------------------------------
// A box room (the host's `Scene::simple_room`, rebuilt here: the core cannot use the host).
// ---------------------------------------------------------------------------------------

const ROOM: [([f32; 3], [f32; 3], u8); 14] = [
    ([-0.1, -0.1, -0.1], [6.1, 5.1, 0.0], 2),
    ([-0.1, -0.1, 2.8], [6.1, 5.1, 2.9], 22),
    ([-0.1, -0.1, 0.0], [0.0, 5.1, 2.8], 1),
    ([6.0, -0.1, 0.0], [6.1, 5.1, 2.8], 1),
    ([0.0, -0.1, 0.0], [6.0, 0.0, 2.8], 1),
    ([0.0, 5.0, 0.0], [6.0, 5.1, 2.8], 1),
    ([0.3, 0.3, 0.0], [2.3, 1.9, 0.55], 4),
    ([3.5, 2.0, 0.72], [4.7, 2.8, 0.76], 7),
    ([3.55, 2.05, 0.0], [3.6, 2.1, 0.72], 7),
    ([4.6, 2.7, 0.0], [4.65, 2.75, 0.72], 7),
    ([5.6, 1.0, 0.0], [6.0, 2.2, 1.8], 15),
    ([5.5, 1.1, 1.0], [5.6, 1.6, 1.25], 23),
    ([2.0, 4.98, 1.2], [3.2, 5.0, 1.9], 11),
    ([0.5, 4.4, 0.0], [0.8, 4.7, 1.5], 35),
];

fn cast_room(o: &Vector3<f32>, d: &Vector3<f32>) -> Option<(f32, u8)> {
    let mut best: Option<(f32, u8)> = None;
    for (lo, hi, label) in ROOM {
        let (mut t0, mut t1) = (0.0f32, f32::INFINITY);
        let mut hit = true;
        for a in 0..3 {
            if d[a].abs() < 1e-12 {
                if o[a] < lo[a] || o[a] > hi[a] {
                    hit = false;
                    break;
                }
                continue;
            }
            let (mut ta, mut tb) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
            if ta > tb {
                core::mem::swap(&mut ta, &mut tb);
            }
            t0 = t0.max(ta);
            t1 = t1.min(tb);
            if t0 > t1 {
                hit = false;
                break;
            }
        }
        if hit && best.is_none_or(|(t, _)| t0 < t) {
            best = Some((t0, label));
        }
    }
    best
}

fn look_at(eye: [f32; 3], target: [f32; 3]) -> Isometry3<f32> {
    let e = Vector3::from(eye);
    let f = (Vector3::from(target) - e).normalize();
    let right = f.cross(&Vector3::z()).normalize();
    let down = f.cross(&right);
    let m = Matrix3::from_columns(&[right, down, f]);
    Isometry3::from_parts(Translation3::from(e), UnitQuaternion::from_matrix(&m))
}

fn orbit(n: usize) -> Vec<Isometry3<f32>> {
    (0..n)
        .map(|i| {
            let a = i as f32 / n as f32 * core::f32::consts::TAU;
            let eye = [3.0 + 1.2 * libm::cosf(a), 2.5 + libm::sinf(a), 1.5];
            let target = [
                3.0 - 2.5 * libm::cosf(a + 0.6),
                2.5 - 2.0 * libm::sinf(a + 0.6),
                0.9,
            ];
            look_at(eye, target)
        })
        .collect()
}

/// Hypersim's field of view at 1/8 of its resolution.
const CAM: Pinhole = Pinhole {
    fx: 886.81 / 8.0,
    fy: 886.81 / 8.0,
    cx: 64.0,
    cy: 48.0,
    width: 128,
    height: 96,
};

fn room_frame(pose: &Isometry3<f32>, cam: &Pinhole) -> (Vec<f32>, Vec<u8>) {
    let n = (cam.width * cam.height) as usize;
    let (mut depth, mut labels) = (std::vec![0f32; n], std::vec![0u8; n]);
    for i in 0..n {
        let r = cam.ray(i as u32 % cam.width, i as u32 / cam.width);
        let d_cam = Vector3::new(r[0], r[1], r[2]);
        let norm = d_cam.norm();
        let d = pose.rotation * (d_cam / norm);
        if let Some((t, l)) = cast_room(&pose.translation.vector, &d) {
            depth[i] = t / norm;
            labels[i] = l;
        }
    }
    (depth, labels)
}

type RoomMap = Map<{ 1 << 16 }, { 1 << 15 }, 40>;

/// Runs `f` on a thread with room for building big maps in debug builds.
fn big_stack(f: impl FnOnce() + Send + 'static) {
    std::thread::Builder::new()
        .stack_size(256 << 20)
        .spawn(f)
        .unwrap()
        .join()
        .unwrap_or_else(|e| std::panic::resume_unwind(e));
}

fn room_map(cell: f32, frames: usize) -> Box<RoomMap> {
    let mut map = Box::new(RoomMap::new(Config::with_cell_size(cell)));
    for pose in orbit(frames) {
        let (depth, labels) = room_frame(&pose, &CAM);
        let img = DepthImage {
            camera: CAM,
            depth: &depth,
            kind: DepthKind::Planar,
            labels: LabelImage::Top1(&labels),
            stride: 1,
        };
        let r = map.integrate_depth(&pose, &img).unwrap();
        assert_eq!(r.dropped_points + r.voxels_evicted, 0, "test map too small");
    }
    map
}

fn assert_same_render(map: &RoomMap, pose: &Isometry3<f32>, cam: &Pinhole) -> usize {
    let n = (cam.width * cam.height) as usize;
    let (want_l, want_d) = reference_render(map, pose, cam);
    let (mut l, mut d) = (std::vec![0u8; n], std::vec![0f32; n]);
    map.render(pose, cam, &mut l, &mut d).unwrap();
    for i in 0..n {
        assert!(
            l[i] == want_l[i] && d[i].to_bits() == want_d[i].to_bits(),
            "pixel {i}: got ({}, {}) want ({}, {})",
            l[i],
            d[i],
            want_l[i],
            want_d[i]
        );
    }
    l.iter().filter(|&&c| c != INVALID_LABEL).count()
}

// ---------------------------------------------------------------------------------------
// Tests
// ---------------------------------------------------------------------------------------

/// Renders of the box room at 5, 10 and 20 cm from mapped poses, poses between them, a
/// pose outside the room and one looking straight down, at a resolution that is not a
/// multiple of the tile size: every pixel bit-identical to the reference.
#[test]
fn render_matches_reference() {
    big_stack(|| {
        let odd = Pinhole {
            fx: 70.0,
            fy: 70.0,
            cx: 50.0,
            cy: 37.5,
            width: 100,
            height: 75,
        };
        let mut poses = orbit(4);
        poses.extend(orbit(7).into_iter().skip(1).step_by(3));
        poses.push(look_at([-1.5, -1.0, 2.0], [3.0, 2.5, 1.0]));
        poses.push(look_at([2.0, 2.0, 2.5], [2.01, 2.0, 0.0]));
        for cell in [0.05f32, 0.10, 0.20] {
            let map = room_map(cell, 8);
            let mut hits = 0;
            for pose in &poses {
                hits += assert_same_render(&map, pose, &odd);
            }
            hits += assert_same_render(&map, &poses[0], &CAM);
            assert!(hits > poses.len() * 7000 / 2, "{cell}: only {hits} hits");
        }
    });
}

/// Single rays from inside and outside the room in many directions, with short `max_t`.
#[test]
fn raycast_matches_reference() {
    big_stack(|| {
        let map = room_map(0.1, 6);
        let mut cache = PrepCache::<8>::new();
        let mut state = 12345u32;
        let mut rnd = move || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state as f32 / u32::MAX as f32
        };
        let mut hits = 0;
        for i in 0..2000 {
            let o = Point3::new(rnd() * 8.0 - 1.0, rnd() * 7.0 - 1.0, rnd() * 4.0 - 0.6);
            let d = Vector3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5);
            let max_t = [20.0, 1.0, 0.3, f32::INFINITY][i % 4];
            let want = reference_raycast(&map, &mut cache, &o, &d, max_t);
            let got = map.raycast(&o, &d, max_t);
            assert_eq!(
                got.map(|h| (h.t.to_bits(), h.class, h.key)),
                want.map(|h| (h.t.to_bits(), h.class, h.key)),
                "ray {i}"
            );
            hits += got.is_some() as usize;
        }
        assert!(hits > 400, "{hits}");
    });
}

/// Surfaces at both ends of the key range: blocks whose cells are partly outside it.
#[test]
fn raycast_matches_reference_at_key_limit() {
    let mut map: Box<Map<4096, 1024, 4>> = Box::new(Map::new(Config::with_cell_size(1.0)));
    for x in [-32766.5f32, 32766.5] {
        let mut pts = Vec::new();
        for i in 0..400 {
            let (u, v) = ((i % 20) as f32 * 0.25 - 2.5, (i / 20) as f32 * 0.25 - 2.5);
            pts.push(LabeledPoint::new(
                Point3::new(x + (i % 3) as f32 * 0.3, u, v),
                Labels::top1(2),
            ));
        }
        let origin = Isometry3::translation(x.signum() * 32760.0, 0.3, 0.2);
        let pts: Vec<_> = pts
            .iter()
            .map(|p| LabeledPoint::new(origin.inverse() * p.position, p.labels))
            .collect();
        map.integrate(&origin, &pts).unwrap();
    }
    let mut cache = PrepCache::<8>::new();
    let mut hits = 0;
    for sx in [-1.0f32, 1.0] {
        for i in 0..200 {
            let a = i as f32 * 0.031;
            let o = Point3::new(sx * 32762.0, 0.3 * libm::cosf(a), 0.2 * libm::sinf(a));
            let d = Vector3::new(sx, 0.4 * libm::sinf(a * 3.0), 0.4 * libm::cosf(a * 2.0));
            let want = reference_raycast(&map, &mut cache, &o, &d, 50.0);
            assert_eq!(map.raycast(&o, &d, 50.0), want, "ray {sx} {i}");
            hits += want.is_some() as usize;
        }
    }
    assert!(hits > 100, "{hits}");
}
