//! Integer voxel keys, their packing into table keys (and the block and cell of a packed
//! key, read without unpacking), and the hash that orders them.

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

    #[inline]
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
    #[inline]
    pub(crate) fn packed(&self) -> u64 {
        pack(self.x as i32, self.y as i32, self.z as i32)
    }

    #[inline]
    pub(crate) fn unpack(p: u64) -> VoxelKey {
        let (x, y, z) = unpack(p);
        VoxelKey {
            x: x as i16,
            y: y as i16,
            z: z as i16,
        }
    }

    /// Key of the 4x4x4 block holding this voxel, packed.
    #[inline]
    pub(crate) fn block(&self) -> u64 {
        pack(
            (self.x as i32) >> 2,
            (self.y as i32) >> 2,
            (self.z as i32) >> 2,
        )
    }

    /// Index of this voxel inside its block (0..64).
    #[inline]
    pub(crate) fn cell(&self) -> u32 {
        ((self.x as u32) & 3) | (((self.y as u32) & 3) << 2) | (((self.z as u32) & 3) << 4)
    }

    /// The voxel key of cell `cell` in packed block `block`.
    #[inline]
    pub(crate) fn from_block_cell(block: u64, cell: u32) -> VoxelKey {
        let (bx, by, bz) = unpack(block);
        VoxelKey {
            x: ((bx << 2) | (cell & 3) as i32) as i16,
            y: ((by << 2) | ((cell >> 2) & 3) as i32) as i16,
            z: ((bz << 2) | ((cell >> 4) & 3) as i32) as i16,
        }
    }

    /// Chebyshev distance in voxels.
    #[inline]
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

/// The 2-bit field of the x coordinate in a block's cell index ([`VoxelKey::cell`]).
pub(crate) const X_FIELD: u32 = 0b00_00_11;
/// The 2-bit field of the y coordinate in a block's cell index.
pub(crate) const Y_FIELD: u32 = 0b00_11_00;
/// The 2-bit field of the z coordinate in a block's cell index.
pub(crate) const Z_FIELD: u32 = 0b11_00_00;

/// The packed block key of the voxel with packed key `key`: each 16-bit field `x + 2^15`
/// becomes `(x >> 2) + 2^15`, which is `((x + 2^15) >> 2) + 3 * 2^13`.
#[inline(always)]
pub(crate) fn block_of_packed(key: u64) -> u64 {
    ((key >> 2) & 0x3fff_3fff_3fff) + 0x6000_6000_6000
}

/// [`VoxelKey::cell`] of the voxel with packed key `key` (the offset 2^15 of a field
/// leaves its low bits alone).
#[inline(always)]
pub(crate) fn cell_of_packed(key: u64) -> u32 {
    (((key >> 32) & 0x3) | ((key >> 14) & 0xc) | ((key << 4) & 0x30)) as u32
}

/// The key of voxel coordinates known to be in the key range, without the check of
/// [`VoxelKey::from_ints`] (a free-space walk's ends are valid keys).
#[inline]
pub(crate) fn key_of(k: [i32; 3]) -> VoxelKey {
    VoxelKey {
        x: k[0] as i16,
        y: k[1] as i16,
        z: k[2] as i16,
    }
}

#[inline]
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

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use crate::storage::voxel::Voxel;
    use crate::testutil::*;

    use std::vec::Vec;

    #[test]
    fn key_from_point_floors() {
        let h = 0.25;
        let f = |x: f32| VoxelKey::from_point(&[x, 0.0, 0.0], h).map(|k| k.x);
        assert_eq!(f(0.0), Some(0));
        assert_eq!(f(-0.0), Some(0));
        assert_eq!(f(0.2499), Some(0));
        assert_eq!(f(0.25), Some(1));
        assert_eq!(f(-0.0001), Some(-1));
        assert_eq!(f(-0.25), Some(-1));
        assert_eq!(f(-0.2501), Some(-2));
        assert_eq!(f(-1.0), Some(-4));
        assert_eq!(f(-1.1), Some(-5));
        assert_eq!(
            VoxelKey::from_point(&[0.3, -0.3, -2.6], 0.5),
            Some(key(0, -1, -6))
        );
    }

    #[test]
    fn key_range_limits() {
        let f = |x: f32| VoxelKey::from_point(&[x, 0.0, 0.0], 1.0).map(|k| k.x);
        assert_eq!(f(32767.0), Some(32767));
        assert_eq!(f(32767.5), Some(32767));
        assert_eq!(f(32768.0), None);
        assert_eq!(f(-32767.0), Some(-32767));
        assert_eq!(f(-32766.5), Some(-32767));
        assert_eq!(f(-32767.5), None);
        assert_eq!(f(-32768.0), None);
        assert_eq!(f(f32::NAN), None);
        assert_eq!(f(f32::INFINITY), None);
        assert_eq!(f(f32::NEG_INFINITY), None);
        assert_eq!(f(1e30), None);
        assert_eq!(VoxelKey::from_point(&[0.0, 0.0, f32::NAN], 1.0), None);
        assert_eq!(KEY_LIMIT, 32767);
    }

    #[test]
    fn key_pack_block_cell_round_trips() {
        let mut rng = Lcg(5);
        let mut keys: Vec<VoxelKey> = Vec::new();
        for x in [
            -32767i16, -32766, -32765, -32764, -5, -4, -3, -1, 0, 1, 3, 4, 32764, 32767,
        ] {
            for y in [-32767i16, -2, 0, 2, 32767] {
                for z in [-32767i16, -1, 0, 5, 32766] {
                    keys.push(key(x, y, z));
                }
            }
        }
        for _ in 0..2000 {
            let r = |rng: &mut Lcg| (rng.next() * 65535.0) as i32 - 32767;
            keys.push(key(
                r(&mut rng) as i16,
                r(&mut rng) as i16,
                r(&mut rng) as i16,
            ));
        }
        for k in &keys {
            let p = k.packed();
            assert_ne!(p, 0, "{k:?}");
            assert!(p < 1 << 48);
            assert_eq!(VoxelKey::unpack(p), *k);
            let cell = k.cell();
            assert!(cell < 64);
            assert_eq!(VoxelKey::from_block_cell(k.block(), cell), *k);
            // The block is the floor division by 4 on every axis.
            let b = VoxelKey::unpack(k.block());
            assert_eq!(
                [b.x, b.y, b.z],
                [k.x.div_euclid(4), k.y.div_euclid(4), k.z.div_euclid(4)]
            );
            assert_eq!(
                cell,
                (k.x.rem_euclid(4) + 4 * k.y.rem_euclid(4) + 16 * k.z.rem_euclid(4)) as u32
            );
            assert_eq!(split_key(p), Voxel::<1>::new(k).key);
        }
        assert_eq!(key(-32767, 0, 5).chebyshev(&key(32767, 1, -5)), 65534);
        assert_eq!(key(1, 2, 3).chebyshev(&key(1, 2, 3)), 0);
    }

    /// The packed block key and cell of a packed voxel key are those of the voxel key.
    #[test]
    fn block_and_cell_of_packed_keys() {
        let mut rng = Lcg(7);
        let edges = [-32767i16, -32766, -5, -4, -3, -1, 0, 1, 3, 4, 32766, 32767];
        let edge_keys = edges.into_iter().flat_map(|x| {
            edges
                .into_iter()
                .flat_map(move |y| edges.into_iter().map(move |z| key(x, y, z)))
        });
        let random = (0..10_000).map(|_| {
            let mut c = || ((rng.next() * 65534.0) as i32 - 32767) as i16;
            key(c(), c(), c())
        });
        for k in edge_keys.chain(random) {
            assert_eq!(block_of_packed(k.packed()), k.block(), "{k:?}");
            assert_eq!(cell_of_packed(k.packed()), k.cell(), "{k:?}");
        }
    }
}
