//! Voxel keys of the reference and the hash maps keyed by them.

use std::collections::{HashMap, HashSet};
use std::hash::{BuildHasherDefault, Hasher};

/// A voxel index `[x, y, z]`: the voxel covers `[k h, (k + 1) h)` on each axis (the same
/// convention as [`sndt_core::VoxelKey`]).
pub type Key = [i32; 3];

/// Hasher for [`Key`]s: a multiply-rotate fold with a 64-bit finaliser (std's SipHash is
/// needlessly slow for the millions of lookups of a render).
#[derive(Clone, Copy, Default)]
pub(crate) struct KeyHasher(u64);

impl Hasher for KeyHasher {
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(4) {
            let mut w = [0u8; 4];
            w[..chunk.len()].copy_from_slice(chunk);
            self.0 = (self.0.rotate_left(21) ^ u32::from_le_bytes(w) as u64)
                .wrapping_mul(0x9E37_79B9_7F4A_7C15);
        }
    }

    fn write_usize(&mut self, _: usize) {
        // Only the (constant) length prefix of a key array arrives here.
    }

    fn finish(&self) -> u64 {
        let mut x = self.0;
        x ^= x >> 30;
        x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
        x ^= x >> 27;
        x = x.wrapping_mul(0x94D0_49BB_1331_11EB);
        x ^ (x >> 31)
    }
}

pub(crate) type KeyMap<V> = HashMap<Key, V, BuildHasherDefault<KeyHasher>>;
pub(crate) type KeySet = HashSet<Key, BuildHasherDefault<KeyHasher>>;
