//! Phase 1's second stage ([`Phase::Accumulate`](crate::Phase::Accumulate)): the points
//! of a converted [`Batch`] into the frame's voxel accumulators, with their votes. Every
//! point ends in exactly one counter of the frame's report.
//!
//! Two ways, with the same result (integer sums and saturating vote counts do not depend
//! on grouping; voxels are looked up in the order of their first point either way):
//!
//! - **by runs** (targets without wide vectors, such as a Cortex-M): consecutive points
//!   of one voxel are summed in registers and added to the voxel's accumulator once;
//! - **by voxel** (targets with 256-bit vectors): once per voxel of the batch, a
//!   branch-free pass over all 64 points sums those in the voxel. A tile of pixels covers
//!   two to four voxels but switches between them every four points or so (surfaces
//!   straddle voxel faces), and every switch of a run is a mispredicted branch.
//!
//! A point that is not the common case (beyond max range, outside the key range,
//! non-finite, several voting classes) goes through the scalar `Map::add_point`, which
//! handles and counts every case, at its place in the batch.

use crate::batch::{Batch, BAD_LABEL, BATCH, FAST, NO_DEPTH};
#[cfg(doc)]
use crate::frame::Accumulator;
use crate::frame::{accumulator_index, FrameState};
use crate::key::VoxelKey;
use crate::labels::Labels;
use crate::map::Map;
#[cfg(doc)]
use crate::voxel::packed_offsets;

/// The accumulator index of points whose voxel could not be created (the map is full).
const DROPPED: usize = usize::MAX;

/// A pending point for the scalar path (never a packed key, which has 48 bits).
const OTHER: u64 = u64::MAX;

/// The first point from `j` on with something left to do.
fn next_pending(pending: &[u64; BATCH], j: usize) -> usize {
    let rest = pending.get(j..).unwrap_or(&[]);
    j + rest.iter().position(|&p| p != 0).unwrap_or(rest.len())
}

/// Whether this target sums by voxel (see the module documentation).
const BY_VOXEL: bool = cfg!(target_feature = "avx2");

impl<const V: usize, const B: usize, const C: usize> Map<V, B, C> {
    /// The accumulation stage for a converted batch with its labels set; `labels(index)`
    /// gives the labels of a point (see [`crate::batch::Source::index`]) for the scalar
    /// path.
    #[inline]
    pub(crate) fn accumulate(
        &mut self,
        f: &mut FrameState,
        batch: &Batch,
        labels: impl Fn(usize) -> Labels,
    ) {
        if BY_VOXEL {
            self.accumulate_by_voxel(f, batch, labels);
        } else {
            self.accumulate_by_runs(f, batch, labels);
        }
    }

    /// A point that is not `FAST`: counted, or through the scalar path.
    #[inline]
    fn other_point(
        &mut self,
        f: &mut FrameState,
        batch: &Batch,
        j: usize,
        labels: impl Fn(usize) -> Labels,
    ) {
        match batch.status[j] {
            NO_DEPTH => f.report.rejected_depth += 1,
            BAD_LABEL => f.report.rejected_label += 1,
            _ => {
                let labels = labels(batch.source.index(j));
                self.add_point(f, batch.point(j), &labels);
            }
        }
    }

    /// The accumulator of voxel `key` for this frame's points: index `a` if it holds the
    /// voxel, else [`Map::open_point_accumulator`]. Returns the accumulator (`DROPPED`
    /// when the map is full), the voxel's slot and the largest vote key that votes (see
    /// `Batch::vote_key`).
    #[inline(always)]
    fn point_accumulator(&mut self, f: &mut FrameState, key: u64) -> (usize, usize, u32) {
        let a = accumulator_index(key);
        match f.acc.get(a) {
            Some(acc) if acc.key == key => (a, acc.slot, acc.vote_max >> 1),
            _ => self.open_point_accumulator(f, key, a),
        }
    }

    /// [`Map::point_accumulator`] when accumulator `a` holds another voxel: finds or
    /// creates voxel `key` and opens the accumulator for it. (The caller's sums stay in
    /// registers: they are not passed.)
    #[inline(never)]
    fn open_point_accumulator(
        &mut self,
        f: &mut FrameState,
        key: u64,
        a: usize,
    ) -> (usize, usize, u32) {
        match self.point_voxel(f, &VoxelKey::unpack(key)) {
            Some(vs) => {
                self.open_accumulator(f, a, vs, key);
                (a, vs, f.acc.get(a).map_or(0, |acc| acc.vote_max >> 1))
            }
            None => (DROPPED, usize::MAX, 0),
        }
    }

    /// Adds `n` points with [`packed_offsets`] sums `w` to accumulator `acc` (or counts
    /// them as dropped), and gives voxel slot `slot` `votes` votes for `class`.
    #[inline(always)]
    fn add_points(
        &mut self,
        f: &mut FrameState,
        (acc, slot): (usize, usize),
        (n, w): (u32, &[u64; 3]),
        (class, votes): (u8, u32),
    ) {
        if votes > 0 {
            if let Some(v) = self.voxels.slots.get_mut(slot) {
                v.take_votes(class, votes);
            }
        }
        if n > 0 {
            if acc == DROPPED {
                f.report.dropped_points += n;
            } else {
                self.add_to_accumulator(f, acc, w, n);
                f.report.points_used += n;
            }
        }
    }

    /// Accumulation by runs of consecutive points in one voxel.
    fn accumulate_by_runs(
        &mut self,
        f: &mut FrameState,
        batch: &Batch,
        labels: impl Fn(usize) -> Labels,
    ) {
        let mut run = Run::NONE;
        for j in 0..batch.len.min(BATCH) {
            if batch.status[j] != FAST {
                // The scalar path uses the accumulators: the run goes in first.
                self.end_run(f, &mut run);
                self.other_point(f, batch, j, &labels);
                continue;
            }
            let key = batch.key[j];
            if key != run.key {
                self.end_run(f, &mut run);
                (run.acc, run.slot, run.vote_key_max) = self.point_accumulator(f, key);
                run.key = key;
            }
            run.n += 1;
            run.w[0] += batch.w[0][j];
            run.w[1] += batch.w[1][j];
            run.w[2] += batch.w[2][j];
            // The run's votes are counted per class and taken at once.
            let class = batch.vote[j];
            let votes = batch.vote_key[j] <= run.vote_key_max;
            if votes & (class != run.class) {
                self.add_points(f, (run.acc, run.slot), (0, &run.w), (run.class, run.votes));
                run.votes = 0;
                run.class = class;
            }
            run.votes += votes as u32;
        }
        self.end_run(f, &mut run);
    }

    /// Adds a run's points and votes and ends it.
    #[inline(always)]
    fn end_run(&mut self, f: &mut FrameState, run: &mut Run) {
        let (at, points, votes) = ((run.acc, run.slot), (run.n, &run.w), (run.class, run.votes));
        self.add_points(f, at, points, votes);
        *run = Run::NONE;
    }

    /// Accumulation by voxel: at the first point of each voxel, one pass over the batch.
    fn accumulate_by_voxel(
        &mut self,
        f: &mut FrameState,
        batch: &Batch,
        labels: impl Fn(usize) -> Labels,
    ) {
        let n = batch.len.min(BATCH);
        // What is left to do for each point: the key of a `FAST` point not summed yet,
        // `OTHER` for a point for the scalar path, 0 for the rest. Points without depth
        // or with a bad label only count, in any order.
        let mut pending = [0u64; BATCH];
        // The vote key and class of each point in one word: `class << 32 | vote_key`.
        let mut votes = [0u64; BATCH];
        let (mut no_depth, mut bad_label) = (0u32, 0u32);
        for j in 0..n {
            let status = batch.status[j];
            pending[j] = match status {
                FAST => batch.key[j],
                NO_DEPTH | BAD_LABEL => 0,
                _ => OTHER,
            };
            no_depth += (status == NO_DEPTH) as u32;
            bad_label += (status == BAD_LABEL) as u32;
            votes[j] = ((batch.vote[j] as u64) << 32) | batch.vote_key[j] as u64;
        }
        f.report.rejected_depth += no_depth;
        f.report.rejected_label += bad_label;
        let mut j = next_pending(&pending, 0);
        while j < n {
            if pending[j] == OTHER {
                pending[j] = 0;
                self.other_point(f, batch, j, &labels);
                j = next_pending(&pending, j + 1);
            } else {
                j = self.add_voxel(f, batch, (&mut pending, &votes), j);
            }
        }
    }

    /// Adds the points of the voxel of point `j` (its first in the batch) with one pass
    /// over the batch, clearing them in `pending`; returns the next pending point. Votes
    /// for the class of point `j` are counted in the pass; others (rare: a voxel on the
    /// border of two objects) are taken one by one.
    #[inline(always)]
    fn add_voxel(
        &mut self,
        f: &mut FrameState,
        batch: &Batch,
        (pending, votes): (&mut [u64; BATCH], &[u64; BATCH]),
        j: usize,
    ) -> usize {
        let key = pending[j];
        let class = batch.vote[j];
        let (acc, slot, vote_key_max) = self.point_accumulator(f, key);
        // Signed 64-bit comparisons (every value here is below 2^40), which vectorise
        // directly. A point votes if its vote key is at most `vote_key_max`, and for
        // `class` if `votes ^ base` is: other classes leave high bits set.
        let vote_key_max = vote_key_max as i64;
        let base = (class as u64) << 32;
        let mut w = [0u64; 3];
        let (mut n, mut voting, mut for_class) = (0u64, 0u64, 0u64);
        let mut next = BATCH;
        for i in 0..BATCH {
            let same = if pending[i] == key { u64::MAX } else { 0 };
            w[0] += batch.w[0][i] & same;
            w[1] += batch.w[1][i] & same;
            w[2] += batch.w[2][i] & same;
            n += same & 1;
            let v = votes[i];
            voting += same & (((v & 0xffff_ffff) as i64 <= vote_key_max) as u64);
            for_class += same & (((v ^ base) as i64 <= vote_key_max) as u64);
            pending[i] &= !same;
            next = next.min(if pending[i] != 0 { i } else { BATCH });
        }
        self.add_points(f, (acc, slot), (n as u32, &w), (class, for_class as u32));
        if voting > for_class {
            for i in j..batch.len.min(BATCH) {
                let c = batch.vote[i];
                let same = batch.status[i] == FAST && batch.key[i] == key;
                if same && c != class && batch.vote_key[i] as i64 <= vote_key_max {
                    self.add_points(f, (acc, slot), (0, &w), (c, 1));
                }
            }
        }
        next
    }
}

/// The points of one voxel that phase 1 is summing in registers.
struct Run {
    /// The voxel's packed key (0, never a valid key, for no run).
    key: u64,
    /// Its accumulator (`DROPPED` if the voxel could not be created) and slot.
    acc: usize,
    slot: usize,
    /// The run's points and the sum of their [`packed_offsets`].
    n: u32,
    w: [u64; 3],
    /// Points vote if their `Batch::vote_key` is at most this: the voxel's
    /// [`Accumulator::vote_max`] halved.
    vote_key_max: u32,
    /// The run's voting points so far, all for `class`.
    votes: u32,
    class: u8,
}

impl Run {
    const NONE: Run = Run {
        key: 0,
        acc: DROPPED,
        slot: usize::MAX,
        n: 0,
        w: [0; 3],
        vote_key_max: 0,
        votes: 0,
        class: 0,
    };
}
