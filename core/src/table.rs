//! A fixed-capacity chained hash table with stable slot indices.
//!
//! Slots live in one array; the `head` field of slot `b` holds `slot + 1` of the first entry
//! of bucket `b` (0 = empty; it belongs to the bucket, not to the entry in the slot, so the
//! index costs exactly 4 bytes per slot) and entries chain through their own `chain` field,
//! kept sorted in the canonical order `(hash, key)` so that iteration by bucket is
//! independent of insertion order. Removed slots go on a free list, so indices of live
//! entries never move. An all-zero table is a valid empty table (statics land in `.bss`).
//!
//! Why not `heapless::IndexMap`: it removes by moving the last entry into the hole, so slot
//! indices (held by blocks, caches and the frame list) would move, and it iterates in
//! insertion order, where snapshots need an order that depends on the keys alone. Its
//! capacity must also be a power of two of at most 2^16 (indices are `u16`; maps on a
//! host hold 2^19 voxels), and an all-zero `IndexMap` is not a valid empty one, so a map
//! `static` would need a copy in flash instead of landing in `.bss`.

use crate::key::{hash, order};

/// What a table entry must provide. `packed_key() == 0` marks an empty slot.
pub(crate) trait Entry: Copy {
    const EMPTY: Self;
    fn packed_key(&self) -> u64;
    fn chain(&self) -> u32;
    fn set_chain(&mut self, next: u32);
    fn head(&self) -> u32;
    fn set_head(&mut self, head: u32);
}

/// Index value meaning "none" in chains and lists (indices are stored as `slot + 1`).
pub(crate) const NIL: u32 = 0;

pub(crate) struct Table<T: Entry, const N: usize> {
    pub(crate) slots: [T; N],
    /// Head of the list of removed slots (`slot + 1`).
    free_head: u32,
    /// Slots `[0, high)` have been handed out at least once.
    high: u32,
    len: u32,
}

impl<T: Entry, const N: usize> Table<T, N> {
    pub(crate) const fn new() -> Self {
        const {
            assert!(
                N >= 1 && N < u32::MAX as usize,
                "capacity must be in 1..u32::MAX"
            )
        };
        Table {
            slots: [T::EMPTY; N],
            free_head: NIL,
            high: 0,
            len: 0,
        }
    }

    pub(crate) fn clear(&mut self) {
        for s in self.slots.iter_mut() {
            *s = T::EMPTY;
        }
        self.free_head = NIL;
        self.high = 0;
        self.len = 0;
    }

    pub(crate) fn len(&self) -> usize {
        self.len as usize
    }

    pub(crate) fn is_full(&self) -> bool {
        self.len as usize >= N
    }

    fn bucket(packed: u64) -> usize {
        ((hash(packed) as u64 * N as u64) >> 32) as usize
    }

    /// Slot index of `packed`, if present.
    pub(crate) fn find(&self, packed: u64) -> Option<usize> {
        let mut i = self.slots[Self::bucket(packed)].head();
        let want = order(packed);
        while i != NIL {
            let s = &self.slots[(i - 1) as usize];
            let k = s.packed_key();
            if k == packed {
                return Some((i - 1) as usize);
            }
            if order(k) > want {
                return None;
            }
            i = s.chain();
        }
        None
    }

    /// Inserts `entry` (whose key must not be present); `Err(entry)` when full.
    pub(crate) fn insert(&mut self, mut entry: T) -> Result<usize, T> {
        let slot = if self.free_head != NIL {
            let s = (self.free_head - 1) as usize;
            self.free_head = self.slots[s].chain();
            s
        } else if (self.high as usize) < N {
            self.high += 1;
            (self.high - 1) as usize
        } else {
            return Err(entry);
        };
        let packed = entry.packed_key();
        let want = order(packed);
        let b = Self::bucket(packed);
        // Find the link to patch: the bucket head or the last chain entry ordered before us.
        let mut prev = NIL;
        let mut next = self.slots[b].head();
        while next != NIL {
            let s = &self.slots[(next - 1) as usize];
            if order(s.packed_key()) > want {
                break;
            }
            prev = next;
            next = s.chain();
        }
        entry.set_chain(next);
        entry.set_head(self.slots[slot].head());
        self.slots[slot] = entry;
        if prev == NIL {
            self.slots[b].set_head(slot as u32 + 1);
        } else {
            self.slots[(prev - 1) as usize].set_chain(slot as u32 + 1);
        }
        self.len += 1;
        Ok(slot)
    }

    /// Removes the live entry in `slot` and returns it.
    pub(crate) fn remove(&mut self, slot: usize) -> T {
        let entry = self.slots[slot];
        let b = Self::bucket(entry.packed_key());
        let target = slot as u32 + 1;
        if self.slots[b].head() == target {
            self.slots[b].set_head(entry.chain());
        } else {
            let mut i = self.slots[b].head();
            while i != NIL {
                let s = &mut self.slots[(i - 1) as usize];
                if s.chain() == target {
                    s.set_chain(entry.chain());
                    break;
                }
                i = s.chain();
            }
        }
        let mut empty = T::EMPTY;
        empty.set_chain(self.free_head);
        empty.set_head(self.slots[slot].head());
        self.slots[slot] = empty;
        self.free_head = target;
        self.len -= 1;
        entry
    }

    /// Live slot indices in storage order (not canonical).
    pub(crate) fn live(&self) -> impl Iterator<Item = usize> + '_ {
        self.slots[..self.high as usize]
            .iter()
            .enumerate()
            .filter(|(_, s)| s.packed_key() != 0)
            .map(|(i, _)| i)
    }

    /// Live slot indices in canonical order `(hash, key)`, independent of insertion order.
    pub(crate) fn canonical(&self) -> impl Iterator<Item = usize> + '_ {
        let mut bucket = 0usize;
        let mut i = NIL;
        core::iter::from_fn(move || {
            while i == NIL {
                if bucket >= N {
                    return None;
                }
                i = self.slots[bucket].head();
                bucket += 1;
            }
            let slot = (i - 1) as usize;
            i = self.slots[slot].chain();
            Some(slot)
        })
    }
}
