//! Integer voxel keys, their packing into table keys, and the hash that orders them.

/// Integer index of a voxel: the voxel covers `[k h, (k + 1) h)` on each axis.
///
/// Valid components are `-KEY_LIMIT..=KEY_LIMIT` (±32767: ±3.2 km at 10 cm); points outside
/// are rejected and counted.
///
/// ```
/// use sndt_core::VoxelKey;
/// let k = VoxelKey::from_point(&[0.25, -0.05, 1.0], 0.1).unwrap();
/// assert_eq!(k, VoxelKey { x: 2, y: -1, z: 10 });
/// let c = k.center(0.1);
/// assert!((c[0] - 0.25).abs() < 1e-6 && (c[1] + 0.05).abs() < 1e-6 && (c[2] - 1.05).abs() < 1e-6);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct VoxelKey {
    /// Index along x.
    pub x: i16,
    /// Index along y.
    pub y: i16,
    /// Index along z.
    pub z: i16,
}

/// Largest absolute key component.
pub const KEY_LIMIT: i32 = 32767;

impl VoxelKey {
    /// The key of the voxel containing `p` (metres) for cell size `h`, or `None` outside the
    /// key range or for non-finite input.
    ///
    /// ```
    /// assert!(sndt_core::VoxelKey::from_point(&[1e9, 0.0, 0.0], 0.1).is_none());
    /// ```
    pub fn from_point(p: &[f32; 3], h: f32) -> Option<VoxelKey> {
        let inv = 1.0 / h;
        Some(VoxelKey {
            x: axis_key(p[0] * inv)?,
            y: axis_key(p[1] * inv)?,
            z: axis_key(p[2] * inv)?,
        })
    }

    /// Centre of the voxel in metres.
    ///
    /// ```
    /// let k = sndt_core::VoxelKey { x: -1, y: 0, z: 3 };
    /// assert_eq!(k.center(0.5), [-0.25, 0.25, 1.75]);
    /// ```
    pub fn center(&self, h: f32) -> [f32; 3] {
        [
            (self.x as f32 + 0.5) * h,
            (self.y as f32 + 0.5) * h,
            (self.z as f32 + 0.5) * h,
        ]
    }

    pub(crate) fn from_ints(x: i32, y: i32, z: i32) -> Option<VoxelKey> {
        if x.abs() > KEY_LIMIT || y.abs() > KEY_LIMIT || z.abs() > KEY_LIMIT {
            return None;
        }
        Some(VoxelKey {
            x: x as i16,
            y: y as i16,
            z: z as i16,
        })
    }

    /// Table key: biased components, never 0 for a valid key (0 marks an empty slot).
    pub(crate) fn packed(&self) -> u64 {
        pack(self.x as i32, self.y as i32, self.z as i32)
    }

    pub(crate) fn unpack(p: u64) -> VoxelKey {
        let (x, y, z) = unpack(p);
        VoxelKey {
            x: x as i16,
            y: y as i16,
            z: z as i16,
        }
    }

    /// Key of the 4x4x4 block holding this voxel, packed.
    pub(crate) fn block(&self) -> u64 {
        pack(
            (self.x as i32) >> 2,
            (self.y as i32) >> 2,
            (self.z as i32) >> 2,
        )
    }

    /// Index of this voxel inside its block (0..64).
    pub(crate) fn cell(&self) -> u32 {
        ((self.x as u32) & 3) | (((self.y as u32) & 3) << 2) | (((self.z as u32) & 3) << 4)
    }

    /// The voxel key of cell `cell` in packed block `block`.
    pub(crate) fn from_block_cell(block: u64, cell: u32) -> VoxelKey {
        let (bx, by, bz) = unpack(block);
        VoxelKey {
            x: ((bx << 2) | (cell & 3) as i32) as i16,
            y: ((by << 2) | ((cell >> 2) & 3) as i32) as i16,
            z: ((bz << 2) | ((cell >> 4) & 3) as i32) as i16,
        }
    }

    /// Chebyshev distance in voxels.
    pub(crate) fn chebyshev(&self, o: &VoxelKey) -> u32 {
        let d = |a: i16, b: i16| (a as i32 - b as i32).unsigned_abs();
        d(self.x, o.x).max(d(self.y, o.y)).max(d(self.z, o.z))
    }
}

/// Floor of a scaled coordinate (`p / h`, computed as `p * (1 / h)` everywhere) as a key
/// component, if in range; `None` for NaN.
#[inline]
pub(crate) fn axis_key(s: f32) -> Option<i16> {
    // Written so that NaN fails the comparison.
    if !(s >= -(KEY_LIMIT as f32) && s < (KEY_LIMIT + 1) as f32) {
        return None;
    }
    Some(floor_i32(s) as i16)
}

/// `floor` for finite values well inside the `i32` range, without a libm call (exact:
/// truncation toward zero, corrected for negative non-integers).
#[inline]
pub(crate) fn floor_i32(s: f32) -> i32 {
    let i = s as i32;
    i - ((i as f32 > s) as i32)
}

/// A packed key as three `u16` (how tables store it: 4-byte alignment, no padding).
pub(crate) fn split_key(packed: u64) -> [u16; 3] {
    [(packed >> 32) as u16, (packed >> 16) as u16, packed as u16]
}

/// The packed key stored as three `u16` by [`split_key`].
#[inline]
pub(crate) fn join_key(k: [u16; 3]) -> u64 {
    ((k[0] as u64) << 32) | ((k[1] as u64) << 16) | k[2] as u64
}

fn pack(x: i32, y: i32, z: i32) -> u64 {
    let b = |v: i32| ((v + 32768) as u64) & 0xffff;
    (b(x) << 32) | (b(y) << 16) | b(z)
}

fn unpack(p: u64) -> (i32, i32, i32) {
    let u = |s: u32| ((p >> s) & 0xffff) as i32 - 32768;
    (u(32), u(16), u(0))
}

/// Hash of a packed key; also the first part of the canonical (snapshot) order.
pub(crate) fn hash(packed: u64) -> u32 {
    let h = packed.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    (h >> 32) as u32 ^ (h as u32).rotate_left(7)
}

/// Canonical order of packed keys: by hash, then by key.
pub(crate) fn order(packed: u64) -> (u32, u64) {
    (hash(packed), packed)
}
