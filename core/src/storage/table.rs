//! A fixed-capacity chained hash table with stable slot indices.
//!
//! Slots live in one array and bucket heads in another, one `u32` per slot: `heads[b]`
//! holds `slot + 1` of the first entry of bucket `b` (0 = empty), so the index costs
//! exactly 4 bytes per slot. Entries chain through their own `chain` field, kept sorted in
//! the canonical order `(hash, key)` so that iteration by bucket is independent of
//! insertion order. Removed slots go on a free list, so indices of live entries never
//! move. An all-zero table is a valid empty table (statics land in `.bss`).
//!
//! The heads have their own array because a lookup starts at a random bucket: in a
//! compact array of 4-byte heads (2 MiB for a host map of 2^19 voxels) that first read
//! hits the cache far more often than a head stored inside a 96-byte slot of a 50 MB
//! array. The update at 5 cm was 7-9 % faster that way (`cargo bench --bench update`).
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
}

/// Index value meaning "none" in chains and lists (indices are stored as `slot + 1`).
pub(crate) const NIL: u32 = 0;

pub(crate) struct Table<T: Entry, const N: usize> {
    pub(crate) slots: [T; N],
    /// Per bucket: the link (`slot + 1`) of its first entry, [`NIL`] when empty.
    heads: [u32; N],
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
            );
        };
        Table {
            slots: [T::EMPTY; N],
            heads: [NIL; N],
            free_head: NIL,
            high: 0,
            len: 0,
        }
    }

    pub(crate) fn clear(&mut self) {
        for s in self.slots.iter_mut() {
            *s = T::EMPTY;
        }
        self.heads.fill(NIL);
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

    #[cfg_attr(target_pointer_width = "64", inline(always))]
    fn bucket(packed: u64) -> usize {
        ((hash(packed) as u64 * N as u64) >> 32) as usize
    }

    /// The entry in `slot`; `None` past the capacity.
    #[inline]
    pub(crate) fn get(&self, slot: usize) -> Option<&T> {
        self.slots.get(slot)
    }

    /// The entry in `slot`, mutably; `None` past the capacity.
    #[inline]
    pub(crate) fn get_mut(&mut self, slot: usize) -> Option<&mut T> {
        self.slots.get_mut(slot)
    }

    /// The entry a link (`slot + 1`) points to; `None` for [`NIL`]. `NIL - 1` wraps to
    /// `usize::MAX`, so one range check covers both the end of a chain and a link out of
    /// range, and a damaged link ends a walk instead of halting the program.
    #[inline]
    pub(crate) fn linked(&self, link: u32) -> Option<&T> {
        self.slots.get((link as usize).wrapping_sub(1))
    }

    #[inline]
    pub(crate) fn linked_mut(&mut self, link: u32) -> Option<&mut T> {
        self.slots.get_mut((link as usize).wrapping_sub(1))
    }

    /// The first link of `packed`'s bucket.
    #[inline]
    fn bucket_head(&self, packed: u64) -> u32 {
        self.heads.get(Self::bucket(packed)).copied().unwrap_or(NIL)
    }

    /// Slot index of `packed`, if present.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    pub(crate) fn find(&self, packed: u64) -> Option<usize> {
        let mut i = self.bucket_head(packed);
        let want = order(packed);
        while let Some(s) = self.linked(i) {
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

    /// Takes a slot for a new entry: the last one removed, or a never-used one; `None` when
    /// every slot is live.
    fn take_slot(&mut self) -> Option<usize> {
        if let Some(s) = self.linked(self.free_head) {
            let slot = (self.free_head - 1) as usize;
            self.free_head = s.chain();
            Some(slot)
        } else if (self.high as usize) < N {
            self.high += 1;
            Some((self.high - 1) as usize)
        } else {
            None
        }
    }

    /// Inserts `entry` (whose key must not be present); `Err(entry)` when full.
    pub(crate) fn insert(&mut self, mut entry: T) -> Result<usize, T> {
        let Some(slot) = self.take_slot() else {
            return Err(entry);
        };
        let packed = entry.packed_key();
        let want = order(packed);
        let b = Self::bucket(packed);
        // Find the link to patch: the bucket head or the last chain entry ordered before us.
        let mut prev = NIL;
        let mut next = self.bucket_head(packed);
        while let Some(s) = self.linked(next) {
            if order(s.packed_key()) > want {
                break;
            }
            prev = next;
            next = s.chain();
        }
        let Some(place) = self.slots.get_mut(slot) else {
            return Err(entry);
        };
        entry.set_chain(next);
        *place = entry;
        let link = slot as u32 + 1;
        if prev == NIL {
            if let Some(head) = self.heads.get_mut(b) {
                *head = link;
            }
        } else if let Some(p) = self.linked_mut(prev) {
            p.set_chain(link);
        }
        self.len += 1;
        Ok(slot)
    }

    /// Removes the live entry in `slot` and returns it (an empty entry for a slot past the
    /// capacity, which removes nothing).
    pub(crate) fn remove(&mut self, slot: usize) -> T {
        let Some(&entry) = self.slots.get(slot) else {
            return T::EMPTY;
        };
        let b = Self::bucket(entry.packed_key());
        let target = slot as u32 + 1;
        match self.heads.get_mut(b) {
            Some(head) if *head == target => *head = entry.chain(),
            _ => {
                let mut i = self.bucket_head(entry.packed_key());
                while let Some(s) = self.linked_mut(i) {
                    if s.chain() == target {
                        s.set_chain(entry.chain());
                        break;
                    }
                    i = s.chain();
                }
            }
        }
        let mut empty = T::EMPTY;
        empty.set_chain(self.free_head);
        if let Some(place) = self.slots.get_mut(slot) {
            *place = empty;
        }
        self.free_head = target;
        self.len = self.len.saturating_sub(1);
        entry
    }

    /// Live slot indices in storage order (not canonical).
    pub(crate) fn live(&self) -> impl Iterator<Item = usize> + '_ {
        self.slots
            .iter()
            .take(self.high as usize)
            .enumerate()
            .filter(|(_, s)| s.packed_key() != 0)
            .map(|(i, _)| i)
    }

    /// Live slot indices in canonical order `(hash, key)`, independent of insertion order.
    pub(crate) fn canonical(&self) -> impl Iterator<Item = usize> + '_ {
        let mut heads = self.heads.iter();
        let mut i = NIL;
        core::iter::from_fn(move || {
            while i == NIL {
                i = *heads.next()?;
            }
            let s = self.linked(i)?;
            let slot = (i - 1) as usize;
            i = s.chain();
            Some(slot)
        })
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use crate::storage::voxel::Voxel;
    use crate::testutil::*;
    use crate::*;
    use std::vec::Vec;

    type T1 = Voxel<1>;

    fn entry(k: &VoxelKey) -> T1 {
        Voxel::<1>::new(k)
    }

    fn bucket_of(k: &VoxelKey, n: usize) -> usize {
        ((hash(k.packed()) as u64 * n as u64) >> 32) as usize
    }

    /// Keys whose hash lands in bucket `b` of an `n`-bucket table.
    fn colliding(n: usize, b: usize, count: usize) -> Vec<VoxelKey> {
        let mut out = Vec::new();
        let mut x = -500i16;
        while out.len() < count {
            let k = key(x, 3, -7);
            if bucket_of(&k, n) == b {
                out.push(k);
            }
            x += 1;
        }
        out
    }

    #[test]
    fn table_insert_find_remove_with_collisions() {
        let mut t: Table<T1, 4> = Table::new();
        let keys = colliding(4, 1, 4);
        let slots: Vec<usize> = keys.iter().map(|k| t.insert(entry(k)).unwrap()).collect();
        assert_eq!(slots, [0, 1, 2, 3]);
        assert_eq!(t.len(), 4);
        assert!(t.is_full());
        for (k, s) in keys.iter().zip(&slots) {
            assert_eq!(t.find(k.packed()), Some(*s));
            assert_eq!(t.slots[*s].voxel_key(), *k);
        }
        // Absent key in the same bucket, and in other buckets.
        let absent = colliding(4, 1, 5)[4];
        assert_eq!(t.find(absent.packed()), None);
        assert_eq!(t.find(key(1, 2, 3).packed()), None);
        // Full: the entry comes back.
        let e = entry(&absent);
        match t.insert(e) {
            Err(back) => assert_eq!(back, e),
            Ok(_) => panic!("insert into a full table"),
        }
        // Remove from the middle of the chain (by canonical position) and the ends.
        let canon: Vec<usize> = t.canonical().collect();
        assert_eq!(canon.len(), 4);
        let mid = canon[1];
        let removed = t.remove(mid);
        assert_eq!(removed.voxel_key(), t_key_of(&keys, &slots, mid));
        assert_eq!(t.len(), 3);
        assert_eq!(t.find(removed.packed_key()), None);
        for (k, s) in keys.iter().zip(&slots) {
            if *s != mid {
                assert_eq!(t.find(k.packed()), Some(*s));
            }
        }
        // The freed slot is reused.
        assert_eq!(t.insert(entry(&absent)), Ok(mid));
        assert_eq!(t.find(absent.packed()), Some(mid));
        // Free list is LIFO: remove two, the last removed is handed out first.
        let first = canon[0];
        let last = canon[3];
        t.remove(first);
        t.remove(last);
        let a = colliding(4, 1, 7)[5];
        let b = colliding(4, 1, 7)[6];
        assert_eq!(t.insert(entry(&a)), Ok(last));
        assert_eq!(t.insert(entry(&b)), Ok(first));
        for (k, s) in [(a, last), (b, first), (absent, mid)] {
            assert_eq!(t.find(k.packed()), Some(s));
        }
        assert_eq!(t.live().count(), 4);
        // Clearing gives an empty table that works again.
        t.clear();
        assert_eq!(t.len(), 0);
        assert_eq!(t.canonical().count(), 0);
        assert_eq!(t.find(a.packed()), None);
        assert_eq!(t.insert(entry(&a)), Ok(0));
    }

    fn t_key_of(keys: &[VoxelKey], slots: &[usize], slot: usize) -> VoxelKey {
        keys[slots.iter().position(|s| *s == slot).unwrap()]
    }

    #[test]
    fn table_single_bucket() {
        let mut t: Table<T1, 1> = Table::new();
        assert_eq!(t.insert(entry(&key(1, 1, 1))), Ok(0));
        assert!(t.insert(entry(&key(2, 1, 1))).is_err());
        assert_eq!(t.find(key(2, 1, 1).packed()), None);
        t.remove(0);
        assert_eq!(t.find(key(1, 1, 1).packed()), None);
        assert_eq!(t.insert(entry(&key(2, 1, 1))), Ok(0));
        assert_eq!(t.find(key(2, 1, 1).packed()), Some(0));
    }

    fn canonical_keys<const N: usize>(t: &Table<T1, N>) -> Vec<u64> {
        t.canonical().map(|s| t.slots[s].packed_key()).collect()
    }

    #[test]
    fn table_canonical_order_is_insertion_independent() {
        let mut rng = Lcg(3);
        let mut keys: Vec<VoxelKey> = Vec::new();
        while keys.len() < 40 {
            let k = key(
                (rng.next() * 200.0) as i16 - 100,
                (rng.next() * 20.0) as i16 - 10,
                (rng.next() * 6.0) as i16,
            );
            if !keys.contains(&k) {
                keys.push(k);
            }
        }
        let mut a: Table<T1, 48> = Table::new();
        let mut b: Table<T1, 48> = Table::new();
        let mut c: Table<T1, 48> = Table::new();
        for k in &keys {
            a.insert(entry(k)).unwrap();
        }
        for k in keys.iter().rev() {
            b.insert(entry(k)).unwrap();
        }
        // c: insert extra keys first, interleave, then remove the extras (free-list slots).
        let extra: Vec<VoxelKey> = (0..8).map(|i| key(500 + i, 0, 0)).collect();
        for k in &extra {
            c.insert(entry(k)).unwrap();
        }
        for k in keys.iter().skip(1).step_by(2) {
            c.insert(entry(k)).unwrap();
        }
        for k in &extra {
            let s = c.find(k.packed()).unwrap();
            c.remove(s);
        }
        for k in keys.iter().step_by(2) {
            c.insert(entry(k)).unwrap();
        }
        let ka = canonical_keys(&a);
        assert_eq!(ka.len(), keys.len());
        assert_eq!(ka, canonical_keys(&b));
        assert_eq!(ka, canonical_keys(&c));
        // Canonical order is (hash, key) ascending, whatever the capacity.
        assert!(ka.windows(2).all(|w| order(w[0]) < order(w[1])));
        let mut d: Table<T1, 40> = Table::new();
        for k in keys.iter().rev() {
            d.insert(entry(k)).unwrap();
        }
        assert_eq!(ka, canonical_keys(&d));
        // live() is the same set.
        let mut live: Vec<u64> = c.live().map(|s| c.slots[s].packed_key()).collect();
        live.sort_by_key(|k| order(*k));
        assert_eq!(live, ka);
    }
}
