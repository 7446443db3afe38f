//! Phase 1's second stage ([`Phase::Accumulate`](crate::Phase::Accumulate)): the points
//! of a converted [`Batch`] into the frame's voxel accumulators, with their votes. Every
//! point ends in exactly one counter of the frame's report.
//!
//! Three ways, with the same result (integer sums and saturating vote counts do not
//! depend on grouping; voxels are looked up in the order of their first point each way):
//!
//! - **by points** (32-bit targets, such as a Cortex-M): every point goes straight into
//!   its voxel's accumulator, votes included (`Accumulator::votes`). The runs below are
//!   short on a small sensor (two points on average on the firmware's 160x120 frames at
//!   10 cm), and there ending a run costs more than the additions it saves;
//! - **by runs** (64-bit targets without 256-bit vectors): consecutive points of one
//!   voxel are summed in registers and added to the voxel's accumulator once;
//! - **by voxel** (64-bit code with 256-bit vectors, see [`crate::Vectors`]): once per
//!   voxel of the batch, a branch-free pass over all 64 points sums those in the voxel. A
//!   tile of pixels covers two to four voxels but switches between them every four points
//!   or so (surfaces straddle voxel faces), and every switch of a run is a mispredicted
//!   branch.
//!
//! A point that is not the common case (beyond max range, outside the key range,
//! non-finite, several voting classes) goes through the scalar `Map::add_point`, which
//! handles and counts every case, at its place in the batch.

#[cfg(doc)]
use crate::integrate::frame::Accumulator;
use crate::integrate::frame::{accumulator_index, FrameState};
use crate::integrate::points::{Batch, BAD_LABEL, BATCH, FAST, NO_DEPTH, PACK_PER_POINT};
use crate::key::VoxelKey;
use crate::labels::Labels;
use crate::storage::map::Map;
#[cfg(doc)]
use crate::storage::voxel::packed_offsets;

/// The accumulator index of points whose voxel could not be created (the map is full).
const DROPPED: usize = usize::MAX;

/// A pending point for the scalar path (never a packed key, which has 48 bits).
const OTHER: u64 = u64::MAX;

/// The first point from `j` on with something left to do (`BATCH - 1` if none).
#[cfg_attr(target_pointer_width = "64", inline(always))]
fn next_pending(pending: &[u64; BATCH], j: usize) -> usize {
    let rest = pending.get(j..).unwrap_or(&[]);
    (j + rest.iter().position(|&p| p != 0).unwrap_or(rest.len())).min(BATCH - 1)
}

/// Whether this target sums by points (see the module documentation); where it does not,
/// the frame chooses between voxels and runs (`FrameState::by_voxel`).
const BY_POINTS: bool = PACK_PER_POINT;

impl<const V: usize, const B: usize, const C: usize> Map<V, B, C> {
    /// The accumulation stage for a converted batch with its labels set; `labels(index)`
    /// gives the labels of a point (see [`crate::integrate::points::Source::index`]) for the scalar
    /// path.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    #[cfg_attr(not(target_pointer_width = "64"), inline)]
    pub(crate) fn accumulate(
        &mut self,
        f: &mut FrameState,
        batch: &Batch,
        labels: impl Fn(usize) -> Labels,
    ) {
        if BY_POINTS {
            self.accumulate_by_points(f, batch, labels);
        } else if f.by_voxel {
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
            Some(acc) if acc.key == key => (a, acc.slot, acc.vote_key_max),
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
                (a, vs, f.acc.get(a).map_or(0, |acc| acc.vote_key_max))
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
        if votes > 0
            && let Some(v) = self.voxels.slots.get_mut(slot)
        {
            v.take_votes(class, votes);
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

    /// Accumulation point by point.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    fn accumulate_by_points(
        &mut self,
        f: &mut FrameState,
        batch: &Batch,
        labels: impl Fn(usize) -> Labels,
    ) {
        let (mut used, mut dropped) = (0, 0);
        for j in 0..batch.len.min(BATCH) {
            if batch.status[j] != FAST {
                self.other_point(f, batch, j, &labels);
                continue;
            }
            let (key, w) = batch.packed(j);
            let (acc, _, vote_key_max) = self.point_accumulator(f, key);
            if acc == DROPPED {
                dropped += 1;
                continue;
            }
            let class = if batch.votes_in(j, vote_key_max) {
                batch.vote[j]
            } else {
                0
            };
            self.add_voting_point(f, acc, &w, class);
            used += 1;
        }
        f.report.points_used += used;
        f.report.dropped_points += dropped;
    }

    /// Accumulation by runs of consecutive points in one voxel.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
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
    #[cfg_attr(target_pointer_width = "64", inline(always))]
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
        // Points are done in order of their first pending point; the search for the
        // next one only moves forward and stops when every point is done.
        let mut left = pending.iter().filter(|&&p| p != 0).count();
        let mut j = 0;
        while left > 0 {
            j = next_pending(&pending, j);
            match pending[j] {
                0 => break, // cannot happen: `left` counts the pending points
                OTHER => {
                    pending[j] = 0;
                    left -= 1;
                    self.other_point(f, batch, j, &labels);
                }
                _ => {
                    let done = self.add_voxel(f, batch, (&mut pending, &votes), j);
                    left = left.saturating_sub(done);
                }
            }
        }
    }

    /// Adds the points of the voxel of point `j` (its first in the batch) with one pass
    /// over the batch, clearing them in `pending`; returns how many they were. Votes
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
        // In masks (all ones for true) that vectorise to one instruction each; a count
        // subtracts its masks.
        let mask = |b: bool| if b { u64::MAX } else { 0 };
        let mut w = [0u64; 3];
        let (mut n, mut voting, mut for_class) = (0u64, 0u64, 0u64);
        // Points before `j` are done (pending 0): the pass starts at `j`'s group of 8.
        for i in (j & !7)..BATCH {
            let same = mask(pending[i] == key);
            w[0] += batch.w[0][i] & same;
            w[1] += batch.w[1][i] & same;
            w[2] += batch.w[2][i] & same;
            n = n.wrapping_sub(same);
            let v = votes[i];
            let no_vote = mask((v & 0xffff_ffff) as i64 > vote_key_max);
            voting = voting.wrapping_sub(same & !no_vote);
            let no_class_vote = mask((v ^ base) as i64 > vote_key_max);
            for_class = for_class.wrapping_sub(same & !no_class_vote);
            pending[i] &= !same;
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
        n as usize
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
    /// Points vote if their `Batch::vote_key` is at most this (the voxel's
    /// [`Accumulator::vote_key_max`]).
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

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use crate::testutil::*;
    use crate::*;
    use std::vec::Vec;

    /// Frames of points in clusters that straddle voxel faces (runs switch often), with
    /// one-class and two-class labels, classes above the map's, non-finite and zero
    /// points, points beyond max range; then more frames on a map too small for them.
    fn frames(rng: &mut Lcg) -> Vec<Vec<LabeledPoint>> {
        (0..4)
            .map(|frame| {
                (0..700)
                    .map(|i| {
                        let c = (i % 9) as f32;
                        let mut p = [
                            0.1 * c - 0.4 + 0.02 * rng.next() as f32,
                            0.1 * (c % 3.0) + 0.02 * rng.next() as f32,
                            // The same voxels every frame: from the second on they sample
                            // their votes.
                            1.0 + 0.005 * frame as f32 + 0.02 * rng.next() as f32,
                        ];
                        match i % 53 {
                            5 => p[2] = f32::NAN,
                            9 => p = [0.0; 3],
                            14 => p[2] = 30.0,
                            _ => {}
                        }
                        let labels = match i % 11 {
                            3 => Labels::top_k(&[(2, 200), (5, 120)]),
                            7 => Labels::top1(9), // above the 6 classes
                            _ => Labels::top1(1 + (i % 5 == 0) as u8 + (i % 13 == 0) as u8),
                        };
                        LabeledPoint::new(Point3::new(p[0], p[1], p[2]), labels)
                    })
                    .collect()
            })
            .collect()
    }

    #[derive(Clone, Copy)]
    enum Way {
        Points,
        Runs,
        Voxel,
    }

    /// Runs `frames` through phase 1 one `way`, and the rest of each frame; returns the
    /// reports and the snapshot.
    fn integrate_with<const V: usize, const B: usize>(
        frames: &[Vec<LabeledPoint>],
        way: Way,
    ) -> (Vec<FrameReport>, Vec<u8>) {
        let mut cfg = Config::DEFAULT;
        cfg.top_k = 2;
        cfg.max_range = 4.0;
        cfg.votes_per_frame = 4; // sampled votes from the second frame on
        let mut map: std::boxed::Box<Map<V, B, 6>> = std::boxed::Box::new(Map::new(cfg));
        let mut reports = Vec::new();
        for (n, points) in frames.iter().enumerate() {
            let mut f = map.begin_frame(&at(0.01 * n as f32, 0.0, 0.0)).unwrap();
            let mut batch = Batch::new();
            for chunk in points.chunks(BATCH) {
                batch.load_points(chunk);
                batch.convert(&f, 6);
                batch.set_labels(|j| chunk[j].labels, &map.config, 6);
                let labels = |j: usize| chunk[j].labels;
                match way {
                    Way::Points => map.accumulate_by_points(&mut f, &batch, labels),
                    Way::Runs => map.accumulate_by_runs(&mut f, &batch, labels),
                    Way::Voxel => map.accumulate_by_voxel(&mut f, &batch, labels),
                }
            }
            reports.push(map.finish(&mut f, |_| {}));
        }
        (reports, snapshot(&*map))
    }

    /// The largest vote-sampling exponent of a voxel after `frames` (see `storage/votes.rs`).
    fn most_sampled(frames: &[Vec<LabeledPoint>]) -> u8 {
        let mut cfg = Config::DEFAULT;
        cfg.votes_per_frame = 4;
        let mut map: std::boxed::Box<Map<1024, 256, 6>> = std::boxed::Box::new(Map::new(cfg));
        for (n, points) in frames.iter().enumerate() {
            let _ = map.integrate(&at(0.01 * n as f32, 0.0, 0.0), points);
        }
        let voxels = map.voxels.slots.iter();
        voxels
            .map(crate::storage::voxel::Voxel::vote_exponent)
            .max()
            .unwrap_or(0)
    }

    #[test]
    fn points_runs_and_voxels_give_the_same_map() {
        let mut rng = Lcg(11);
        for _ in 0..5 {
            let frames = frames(&mut rng);
            let (runs, runs_map) = integrate_with::<1024, 256>(&frames, Way::Runs);
            for way in [Way::Points, Way::Voxel] {
                let (reports, map) = integrate_with::<1024, 256>(&frames, way);
                assert_eq!(reports, runs);
                assert_eq!(map, runs_map);
            }
            let r = &runs[1];
            assert!(r.points_used > 0 && r.rejected_depth > 0 && r.rejected_label > 0);
            assert!(most_sampled(&frames) > 0, "no voxel samples its votes");
            assert!(r.truncated > 0);
            // A map too small for the frames: evictions and dropped points.
            let (runs, runs_map) = integrate_with::<8, 4>(&frames, Way::Runs);
            assert!(runs.iter().any(|r| r.dropped_points > 0));
            for way in [Way::Points, Way::Voxel] {
                let (reports, map) = integrate_with::<8, 4>(&frames, way);
                assert_eq!(reports, runs);
                assert_eq!(map, runs_map);
            }
        }
    }
}
