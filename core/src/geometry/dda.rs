//! Exact voxel traversal (Amanatides & Woo, 1987) in voxel units, shared by free space
//! (`integrate/free_space.rs`) and ray casting (`readout/raycast.rs`): the walk state
//! [`Dda`], [`lane_keys`] for eight walks at once, the voxel-by-voxel [`traverse`] of a
//! segment, and the public [`voxels_on_segment`] in metres.

use crate::key::VoxelKey;

/// Walk state: the current voxel and, per axis, the ray parameter of the next boundary.
pub(crate) struct Dda {
    /// Current voxel.
    pub(crate) k: [i32; 3],
    /// Per axis: the direction of travel (-1, 0 or 1), the ray parameter of the next
    /// boundary and the parameter between boundaries.
    pub(crate) step: [i32; 3],
    pub(crate) t_max: [f32; 3],
    pub(crate) t_delta: [f32; 3],
}

impl Dda {
    /// Starts in voxel `k` containing point `o`, walking along `d` (both in voxel units);
    /// the ray parameter `t` is in multiples of `d`.
    pub(crate) fn new(o: [f32; 3], d: [f32; 3], k: [i32; 3]) -> Dda {
        let mut dda = Dda {
            k,
            step: [0; 3],
            t_max: [f32::INFINITY; 3],
            t_delta: [f32::INFINITY; 3],
        };
        for a in 0..3 {
            if d[a] > 0.0 {
                dda.step[a] = 1;
                dda.t_delta[a] = 1.0 / d[a];
                dda.t_max[a] = (k[a] as f32 + 1.0 - o[a]) / d[a];
            } else if d[a] < 0.0 {
                dda.step[a] = -1;
                dda.t_delta[a] = -1.0 / d[a];
                dda.t_max[a] = (k[a] as f32 - o[a]) / d[a];
            }
        }
        dda
    }

    /// The axis of the next voxel boundary (ties go to the lowest axis) and the ray
    /// parameter at which it is crossed.
    #[inline]
    pub(crate) fn next_axis(&self) -> (usize, f32) {
        let mut a = 0;
        if self.t_max[1] < self.t_max[a] {
            a = 1;
        }
        if self.t_max[2] < self.t_max[a] {
            a = 2;
        }
        (a, self.t_max[a])
    }

    /// Steps into the next voxel across axis `a` (from [`Dda::next_axis`]).
    #[inline]
    pub(crate) fn advance(&mut self, a: usize) {
        self.k[a] += self.step[a];
        self.t_max[a] += self.t_delta[a];
    }

    /// Direction of travel along axis `a` (-1, 0 or 1).
    pub(crate) fn step(&self, a: usize) -> i32 {
        self.step[a]
    }
}

/// Walks traversed together by [`lane_keys`]: eight, as many as one AVX-512 register
/// holds `f32`s (AVX2 machines take two registers and still gain).
pub(crate) const LANES: usize = 8;

/// The most steps [`lane_keys`] records per walk; longer walks go step by step. None on
/// 32-bit targets, which walk step by step (see `integrate/free_space.rs`) and have little stack.
pub(crate) const LANE_STEPS: usize = if cfg!(target_pointer_width = "64") {
    256
} else {
    0
};

/// The voxels of up to [`LANES`] walks: `keys[n][l]` is the packed key (16-bit fields,
/// x highest, each offset by 2^15) of the voxel walk `l` is in after `n` steps, for `n`
/// up to the returned step count of the walk, each step's axis chosen as
/// [`Dda::next_axis`] chooses it (the lowest axis on ties). A walk stops after `limit[l]`
/// steps (at most [`LANE_STEPS`]), or before a step whose boundary lies beyond
/// `t = t_end`. `start[l]` is the packed key of walk `l`'s first voxel; of the walks only
/// `step`, `t_max` and `t_delta` are read. The keys of the steps a walk takes must stay
/// in range (no field wraps); past its step count a lane holds values nobody reads.
///
/// A scalar walk spends most of its time in mispredicted branches: the axis of the next
/// step is, to the branch predictor, random. Here every lane makes its choice with
/// comparisons and bit masks and no branch, and the compiler runs the lanes in vector
/// registers. The arithmetic is the scalar walk's (the same additions in the same order),
/// so the voxels are the same.
#[inline]
pub(crate) fn lane_keys(
    walks: &[Dda; LANES],
    start: [u64; LANES],
    limit: [u32; LANES],
    t_end: f32,
    keys: &mut [[u64; LANES]; LANE_STEPS + 1],
) -> [u32; LANES] {
    let limit = limit.map(|n| n.min(LANE_STEPS as u32));
    let (t_max, t_delta) = (
        walks.each_ref().map(|w| w.t_max),
        walks.each_ref().map(|w| w.t_delta),
    );
    let (mut t0, mut t1, mut t2) = (
        t_max.map(|t| t[0]),
        t_max.map(|t| t[1]),
        t_max.map(|t| t[2]),
    );
    let (d0, d1, d2) = (
        t_delta.map(|t| t[0]),
        t_delta.map(|t| t[1]),
        t_delta.map(|t| t[2]),
    );
    // The change of a packed key for a step along each axis: +-1 in its field.
    let steps_of = walks.each_ref().map(|w| w.step);
    let key_step = |a: usize, at: u32| -> [u64; LANES] {
        steps_of.map(|s| ((s.get(a).copied().unwrap_or(0) as i64) << at) as u64)
    };
    let (s0, s1, s2) = (key_step(0, 32), key_step(1, 16), key_step(2, 0));
    let mut key = start;
    let mut steps = [0u32; LANES];
    let mut live = [u32::MAX; LANES];
    let longest = limit.iter().copied().max().unwrap_or(0) as usize;
    let (first, rest) = keys.split_at_mut(1);
    first[0] = start;
    for (n, row) in rest.iter_mut().enumerate().take(longest) {
        for l in 0..LANES {
            // Masks (all ones for true) select without branches: `y` when axis 1's
            // boundary comes before axis 0's, `z` when axis 2's comes before both.
            let mask = |c: bool| (c as u32).wrapping_neg();
            let pick =
                |m: u32, a: f32, b: f32| f32::from_bits((a.to_bits() & m) | (b.to_bits() & !m));
            let y = mask(t1[l] < t0[l]);
            let t01 = pick(y, t1[l], t0[l]);
            let z = mask(t2[l] < t01);
            let t = pick(z, t2[l], t01);
            live[l] &= mask((n as u32) < limit[l]) & !mask(t > t_end);
            steps[l] += live[l] & 1;
            let (on2, on1) = (z, !z & y);
            let on0 = !z & !y;
            let wide = |m: u32| m as i32 as i64 as u64;
            key[l] = key[l]
                .wrapping_add((s0[l] & wide(on0)) | (s1[l] & wide(on1)) | (s2[l] & wide(on2)));
            row[l] = key[l];
            t0[l] = pick(on0, t0[l] + d0[l], t0[l]);
            t1[l] = pick(on1, t1[l] + d1[l], t1[l]);
            t2[l] = pick(on2, t2[l] + d2[l], t2[l]);
        }
    }
    steps
}

/// Exact voxel traversal (Amanatides & Woo) of the segment from `o` to `target` (voxel
/// units) starting in voxel `start` and ending in `end`, visiting `end` only if
/// `include_end`. Axis ties step the lowest axis first; at most the Manhattan distance
/// between the keys plus one voxels are visited. The walk stops early when `visit`
/// returns `false`.
pub(crate) fn traverse(
    o: [f32; 3],
    target: [f32; 3],
    start: [i32; 3],
    end: [i32; 3],
    include_end: bool,
    mut visit: impl FnMut([i32; 3]) -> bool,
) {
    let d = [target[0] - o[0], target[1] - o[1], target[2] - o[2]];
    let mut dda = Dda::new(o, d, start);
    let steps: u32 = (0..3).map(|a| (end[a] - start[a]).unsigned_abs()).sum();
    for _ in 0..=steps {
        if dda.k == end {
            if include_end {
                visit(end);
            }
            return;
        }
        if !visit(dda.k) {
            return;
        }
        let (a, t) = dda.next_axis();
        if t > 1.0 + 1e-4 {
            return;
        }
        dda.advance(a);
    }
}

/// Visits every voxel the segment from `from` to `to` (metres) passes through, in order,
/// both end voxels included: the same traversal the map uses for free space. Returns
/// `false` (visiting nothing) when an end is outside the key range.
///
/// ```
/// use sndt_core::{voxels_on_segment, VoxelKey};
/// let mut seen = Vec::new();
/// assert!(voxels_on_segment(&[0.05, 0.05, 0.05], &[0.35, 0.15, 0.05], 0.1, |k| seen.push(k)));
/// assert_eq!(seen.first(), Some(&VoxelKey { x: 0, y: 0, z: 0 }));
/// assert_eq!(seen.last(), Some(&VoxelKey { x: 3, y: 1, z: 0 }));
/// assert_eq!(seen.len(), 5);
/// ```
pub fn voxels_on_segment(
    from: &[f32; 3],
    to: &[f32; 3],
    cell_size: f32,
    mut visit: impl FnMut(VoxelKey),
) -> bool {
    let (Some(a), Some(b)) = (
        VoxelKey::from_point(from, cell_size),
        VoxelKey::from_point(to, cell_size),
    ) else {
        return false;
    };
    let o = [
        from[0] / cell_size,
        from[1] / cell_size,
        from[2] / cell_size,
    ];
    let t = [to[0] / cell_size, to[1] / cell_size, to[2] / cell_size];
    let ka = [a.x as i32, a.y as i32, a.z as i32];
    let kb = [b.x as i32, b.y as i32, b.z as i32];
    traverse(o, t, ka, kb, true, |k| {
        if let Some(key) = VoxelKey::from_ints(k[0], k[1], k[2]) {
            visit(key);
        }
        true
    });
    true
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use crate::key::key_of;
    use crate::testutil::Lcg;
    use std::vec::Vec;

    /// The voxels of a walk from `o` along `d` in voxel `k`, step by step with
    /// [`Dda::next_axis`]: at most `limit` steps, none whose boundary lies beyond `t_end`.
    fn scalar(o: [f32; 3], d: [f32; 3], k: [i32; 3], limit: u32, t_end: f32) -> Vec<u64> {
        let mut dda = Dda::new(o, d, k);
        let packed = |k: [i32; 3]| key_of(k).packed();
        let mut keys = std::vec![packed(dda.k)];
        for _ in 0..limit {
            let (a, t) = dda.next_axis();
            if t > t_end {
                break;
            }
            dda.advance(a);
            keys.push(packed(dda.k));
        }
        keys
    }

    /// `lane_keys` takes the scalar walk's steps: on random rays, on rays whose boundaries
    /// tie (from voxel centres and corners along directions with equal components, where
    /// the lowest axis must go first), on axis-parallel rays, on walks cut short by
    /// `t_end`, and on limits beyond `LANE_STEPS`.
    #[test]
    fn lane_keys_take_the_scalar_walks_steps() {
        let mut rng = Lcg(11);
        let mut r = |s: f64| ((rng.next() * 2.0 - 1.0) * s) as f32;
        let mut rays = Vec::new();
        for i in 0..400 {
            let (o, d) = match i % 4 {
                0 => ([r(50.0), r(50.0), r(50.0)], [r(40.0), r(40.0), r(40.0)]),
                // Ties: a centre or a corner, equal (or opposite) integer components.
                1 => {
                    let c = [0.5f32, 0.0][(i / 4) % 2];
                    let m = (1 + (i / 8) % 9) as f32;
                    let s = |b: usize| if (i >> b) & 1 == 0 { m } else { -m };
                    (
                        [3.0 + c, -7.0 + c, 2.0 + c],
                        [s(3), s(4), if i % 3 == 0 { 0.0 } else { s(5) }],
                    )
                }
                // Axis-parallel, and along two axes.
                2 => {
                    let mut d = [0.0f32; 3];
                    d[(i / 4) % 3] = r(300.0);
                    if i % 8 == 6 {
                        d[(i / 4 + 1) % 3] = r(30.0);
                    }
                    ([r(9.0), r(9.0), r(9.0)], d)
                }
                _ => ([r(5.0), r(5.0), r(5.0)], [r(200.0), r(200.0), r(200.0)]),
            };
            let k = o.map(|x| libm::floorf(x) as i32);
            let end = [0, 1, 2].map(|a| libm::floorf(o[a] + d[a]) as i32);
            let steps: u32 = (0..3).map(|a| (end[a] - k[a]).unsigned_abs()).sum();
            // Some limits beyond the end (`t_end` stops those), some beyond LANE_STEPS.
            let limit = match i % 5 {
                0 => steps + 7,
                1 => 1000,
                _ => steps,
            };
            let t_end = if i % 7 == 0 { 0.5 } else { 1.0 + 1e-4 };
            rays.push((o, d, k, limit, t_end));
        }
        // Walks of one batch share `t_end`: group by it.
        for t_end in [0.5f32, 1.0 + 1e-4] {
            let group: Vec<_> = rays.iter().filter(|r| r.4 == t_end).collect();
            for batch in group.chunks(LANES) {
                let lane = |l: usize| batch.get(l).map(|r| (r.0, r.1, r.2, r.3));
                let idle = ([0.5f32; 3], [0.0f32; 3], [0i32; 3], 0u32);
                let walks: [Dda; LANES] = core::array::from_fn(|l| {
                    let (o, d, k, _) = lane(l).unwrap_or(idle);
                    Dda::new(o, d, k)
                });
                let start = core::array::from_fn(|l| {
                    let k = lane(l).unwrap_or(idle).2;
                    scalar([0.0; 3], [0.0; 3], k, 0, t_end)[0]
                });
                let limit = core::array::from_fn(|l| lane(l).unwrap_or(idle).3);
                let mut keys = [[0u64; LANES]; LANE_STEPS + 1];
                let steps = lane_keys(&walks, start, limit, t_end, &mut keys);
                for (l, ray) in batch.iter().enumerate() {
                    let (o, d, k, limit, _) = **ray;
                    let want = scalar(o, d, k, limit.min(LANE_STEPS as u32), t_end);
                    let got: Vec<u64> = keys[..=steps[l] as usize]
                        .iter()
                        .map(|row| row[l])
                        .collect();
                    assert_eq!(got, want, "o {o:?} d {d:?} limit {limit} t_end {t_end}");
                }
            }
        }
    }
}
