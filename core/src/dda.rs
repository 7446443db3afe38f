//! Exact voxel traversal (Amanatides & Woo, 1987) in voxel units, shared by free space
//! (`free_space.rs`) and ray casting (`raycast.rs`).

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
