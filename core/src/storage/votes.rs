//! Class votes: which labels of a point vote, and the order-independent sample of about
//! `votes_per_frame` votes a voxel takes per frame (see [`crate::Config::votes_per_frame`]).
//!
//! A voxel's `tally` holds this frame's sampling exponent `k` (the sample keeps a voting
//! point when the top `k` bits of its coordinates' hash are zero) and the votes taken so
//! far; at the end of the frame the votes taken set `k` for the next frame. Before its
//! first vote of a frame a voxel makes room in its `u8` histogram, so the sample cannot
//! saturate a bin.

use crate::config::Config;
use crate::labels::{Labels, MAX_TOP_K};
use crate::storage::voxel::Voxel;

/// Largest count of votes taken in one frame that a tally holds.
pub(crate) const VOTES_TAKEN_MAX: u16 = 0xfff;
/// Position of the sampling exponent in a tally.
pub(crate) const EXPONENT_SHIFT: u32 = 12;

/// The vote-sampling hash of a point (sensor frame): a mix of its coordinates' bits, so
/// the sample a voxel takes does not depend on point order (see
/// [`crate::Config::votes_per_frame`]).
///
/// ```
/// let h = sndt_core::vote_hash(&[0.1, -0.2, 1.5]);
/// assert_eq!(h, sndt_core::vote_hash(&[0.1, -0.2, 1.5]));
/// assert_ne!(h, sndt_core::vote_hash(&[0.1, -0.2, 1.5001]));
/// ```
#[inline]
pub fn vote_hash(p: &[f32; 3]) -> u32 {
    let mut h = p[0].to_bits().wrapping_mul(0x9e37_79b1);
    h = (h ^ p[1].to_bits()).wrapping_mul(0x85eb_ca77);
    h = (h ^ p[2].to_bits()).wrapping_mul(0xc2b2_ae3d);
    // murmur3's finaliser
    h ^= h >> 16;
    h = h.wrapping_mul(0x85eb_ca6b);
    h ^= h >> 13;
    h = h.wrapping_mul(0xc2b2_ae35);
    h ^ (h >> 16)
}

/// Whether a point with sampling hash `hash` votes in a voxel whose sample keeps one voting
/// point in `2^exponent` (`exponent <= 15`): the hash's top `exponent` bits are zero.
///
/// ```
/// assert!(sndt_core::takes_vote(u32::MAX, 0));
/// assert!(sndt_core::takes_vote(0x3fff_ffff, 2) && !sndt_core::takes_vote(0x4000_0000, 2));
/// ```
#[inline]
pub fn takes_vote(hash: u32, exponent: u8) -> bool {
    (hash as u64) >> (32 - exponent.min(MAX_VOTE_EXPONENT) as u32) == 0
}

/// The largest hash [`takes_vote`] takes at `exponent`: `takes_vote(h, e)` is
/// `h <= vote_max(e)`.
#[inline]
pub(crate) fn vote_max(exponent: u8) -> u32 {
    u32::MAX >> exponent.min(MAX_VOTE_EXPONENT)
}

/// Largest vote sampling exponent (one point in 32768).
pub const MAX_VOTE_EXPONENT: u8 = 15;

/// The sampling exponent of a voxel's next frame: the smallest `k` with
/// `taken * 2^exponent <= votes_per_frame * 2^k` (at most [`MAX_VOTE_EXPONENT`]), where
/// `taken` votes were sampled at one in `2^exponent` this frame. So a voxel seen about as
/// densely next frame takes between half and all of `votes_per_frame` votes.
///
/// ```
/// use sndt_core::next_vote_exponent;
/// assert_eq!(next_vote_exponent(0, 64, 64), 0);
/// assert_eq!(next_vote_exponent(0, 65, 64), 1);
/// assert_eq!(next_vote_exponent(2, 100, 64), 3); // about 400 voting points
/// assert_eq!(next_vote_exponent(5, 0, 64), 0); // no votes taken: count them all
/// ```
#[inline]
pub fn next_vote_exponent(exponent: u8, taken: u16, votes_per_frame: u8) -> u8 {
    let estimate = (taken as u64) << exponent.min(MAX_VOTE_EXPONENT);
    let budget = votes_per_frame.max(1) as u64;
    let mut k = 0;
    while k < MAX_VOTE_EXPONENT && estimate > budget << k {
        k += 1;
    }
    k
}

/// The classes one point votes for, best first: at most one per label.
pub(crate) type VotingClasses = heapless::Vec<u8, MAX_TOP_K, u8>;

/// The classes a point with (valid, see `Labels::fits`) labels votes for: those of its
/// first `top_k` labels that are a class (not void) with a score of at least `min_score`.
#[inline]
pub(crate) fn voting_classes(labels: &Labels, cfg: &Config) -> VotingClasses {
    let k = (cfg.top_k as usize).min(labels.len as usize);
    let mut classes = VotingClasses::new();
    for (&class, &score) in labels.classes.iter().zip(&labels.scores).take(k) {
        if class >= 1 && score >= cfg.min_score {
            // Cannot fail: at most MAX_TOP_K labels.
            let _ = classes.push(class);
        }
    }
    classes
}

impl<const C: usize> Voxel<C> {
    /// This frame's sampling exponent: the sample keeps one voting point in `2^k`.
    #[inline]
    pub(crate) fn vote_exponent(&self) -> u8 {
        (self.tally >> EXPONENT_SHIFT) as u8
    }

    /// Starts a sample of one voting point in `2^exponent`, no votes taken yet.
    pub(crate) fn start_vote_sample(&mut self, exponent: u8) {
        self.tally = (exponent as u16) << EXPONENT_SHIFT;
    }

    /// The votes of a point at `p` (sensor frame) for `classes` (1..=C, from
    /// [`voting_classes`], not empty), if this frame's sample takes the point: one vote per
    /// class, saturating.
    #[inline]
    pub(crate) fn vote(&mut self, p: &[f32; 3], classes: &[u8]) {
        let exponent = self.vote_exponent();
        if exponent == 0 || takes_vote(vote_hash(p), exponent) {
            self.take_vote(classes);
        }
    }

    /// One vote for each of `classes` (1..=C), saturating, counted as taken.
    #[inline]
    pub(crate) fn take_vote(&mut self, classes: &[u8]) {
        let taken = (self.tally & VOTES_TAKEN_MAX) + 1;
        self.tally = (self.tally & !VOTES_TAKEN_MAX) | taken.min(VOTES_TAKEN_MAX);
        for &c in classes {
            if let Some(bin) = self.hist.get_mut((c as usize).wrapping_sub(1)) {
                *bin = bin.saturating_add(1);
            }
        }
    }

    /// Ends the frame's sample: the next frame samples so that a voxel seen as densely
    /// takes about `votes_per_frame` votes.
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    pub(crate) fn end_vote_sample(&mut self, votes_per_frame: u8) {
        let taken = self.tally & VOTES_TAKEN_MAX;
        let next = next_vote_exponent(self.vote_exponent(), taken, votes_per_frame);
        self.start_vote_sample(next);
    }

    /// `count` votes for `class` (1..=C), each as [`Voxel::take_vote`] takes one: both
    /// the bin and the votes taken saturate, so the order of votes does not matter.
    #[inline]
    pub(crate) fn take_votes(&mut self, class: u8, count: u32) {
        let count = count.min(u16::MAX as u32) as u16;
        let taken = (self.tally & VOTES_TAKEN_MAX).saturating_add(count);
        self.tally = (self.tally & !VOTES_TAKEN_MAX) | taken.min(VOTES_TAKEN_MAX);
        if let Some(bin) = self.hist.get_mut((class as usize).wrapping_sub(1)) {
            *bin = (*bin as u32 + count as u32).min(u8::MAX as u32) as u8;
        }
    }

    /// Halves every bin if any bin exceeds `255 - votes` so a frame's sample of about
    /// `votes` votes has room (done once per voxel per frame, before the votes, so the
    /// result does not depend on point order).
    #[cfg_attr(target_pointer_width = "64", inline(always))]
    pub(crate) fn make_vote_room(&mut self, votes: u8) {
        if any_bin_above(&self.hist, 255 - votes) {
            for b in self.hist.iter_mut() {
                *b /= 2;
            }
        }
    }
}

/// Whether a bin of `hist` is above `limit`, four bins at a time: `b > limit` exactly when
/// `b + (255 - limit)` carries out of its byte, and the carries out of the four byte
/// additions of two words come from their top bits and the carries into them (the sums
/// of their low 7 bits, which cannot reach the next byte).
#[cfg_attr(target_pointer_width = "64", inline(always))]
fn any_bin_above(hist: &[u8], limit: u8) -> bool {
    let v = u32::from_ne_bytes([255 - limit; 4]);
    let low7 = 0x7f7f_7f7f;
    let mut chunks = hist.chunks_exact(4);
    let mut carries = 0;
    for chunk in &mut chunks {
        let a = <[u8; 4]>::try_from(chunk).map_or(0, u32::from_ne_bytes);
        let into_top = (a & low7) + (v & low7);
        carries |= (a & v) | ((a | v) & into_top);
    }
    carries & !low7 != 0 || chunks.remainder().iter().any(|&b| b > limit)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::*;
    use crate::*;

    #[test]
    fn take_votes_is_take_vote_repeated() {
        // Counts around both saturation points (a bin at 255, the tally at 0xfff), classes
        // in and out of range.
        for (class, count, bin, taken) in [
            (1u8, 0u32, 0u8, 0u16),
            (2, 1, 7, 3),
            (4, 30, 250, 100),
            (3, 300, 0, 0xff0),
            (1, 70_000, 12, 5),
            (0, 5, 0, 0),
            (5, 5, 0, 0),
        ] {
            let mut one_by_one = Voxel::<4>::new(&key(0, 0, 0));
            one_by_one.hist = [bin, 9, bin, 1];
            one_by_one.tally = (3 << EXPONENT_SHIFT) | taken;
            let mut batched = one_by_one;
            for _ in 0..count {
                one_by_one.take_vote(&[class]);
            }
            batched.take_votes(class, count);
            assert_eq!(batched.hist, one_by_one.hist, "class {class} x {count}");
            assert_eq!(batched.tally, one_by_one.tally, "class {class} x {count}");
        }
    }

    #[test]
    fn vote_max_is_the_largest_hash_takes_vote_takes() {
        // Hand-computed: one in 2^e of the hash range, e capped at 15.
        assert_eq!(vote_max(0), u32::MAX);
        assert_eq!(vote_max(1), 0x7fff_ffff);
        assert_eq!(vote_max(15), 0x1_ffff);
        assert_eq!(vote_max(200), 0x1_ffff);
        for e in 0..=20u8 {
            let m = vote_max(e);
            for h in [0, 1, m.saturating_sub(1), m, m.wrapping_add(1), u32::MAX] {
                assert_eq!(h <= m, takes_vote(h, e), "hash {h:#x}, exponent {e}");
            }
        }
    }

    #[test]
    fn any_bin_above_is_any_greater_than() {
        // Every limit, histograms of 1 to 11 bins (whole words and a remainder) with each
        // bin in turn at the values around the limit, the others at 0 or limit - 1.
        for limit in 0..=255u8 {
            for len in 1..=11 {
                for at in 0..len {
                    for value in [limit.saturating_sub(1), limit, limit.saturating_add(1), 255] {
                        for rest in [0u8, limit.saturating_sub(1)] {
                            let mut hist = [rest; 11];
                            hist[at] = value;
                            let hist = &hist[..len];
                            let want = hist.iter().any(|&b| b > limit);
                            assert_eq!(any_bin_above(hist, limit), want, "{hist:?} > {limit}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn make_vote_room_halves_only_above_255_minus_votes() {
        let mut v = Voxel::<4>::new(&key(0, 0, 0));
        v.hist = [191, 3, 0, 1];
        v.make_vote_room(64);
        assert_eq!(v.hist, [191, 3, 0, 1]);
        v.hist = [192, 3, 0, 1];
        v.make_vote_room(64);
        assert_eq!(v.hist, [96, 1, 0, 0]);
        v.hist = [5, 255, 200, 7];
        v.make_vote_room(128);
        assert_eq!(v.hist, [2, 127, 100, 3]);
        v.hist = [5, 128, 200, 7];
        v.make_vote_room(1);
        assert_eq!(v.hist, [5, 128, 200, 7]);
    }

    #[test]
    fn votes_within_the_frame_budget_all_count_and_halve_once_per_frame() {
        let mut cfg = Config::DEFAULT;
        cfg.votes_per_frame = 64;
        let mut map: Map<16, 16, 2> = Map::try_new(cfg).unwrap();
        let mut rng = Lcg(7);
        let k = key(0, 0, 10);
        let mut frame = |n1, n2| {
            let pts = voxel_cloud(&mut rng, n1, n2);
            map.integrate(&Isometry3::identity(), &pts).unwrap();
            *map.voxel(&k).unwrap().histogram
        };
        assert_eq!(frame(60, 0), [60, 0]);
        assert_eq!(frame(0, 10), [60, 10]);
        assert_eq!(frame(64, 0), [124, 10]);
        assert_eq!(frame(64, 0), [188, 10]);
        assert_eq!(frame(4, 0), [192, 10]); // 188 <= 255 - 64: no halving before these votes
                                            // 192 > 191: halve first (96, 5), then add (10, 10).
        assert_eq!(frame(10, 10), [106, 15]);
        assert_eq!(map.class(&k), Some((1, 106.0 / 121.0)));
    }

    #[test]
    fn a_crowded_voxel_takes_a_hashed_sample_of_about_votes_per_frame() {
        let cfg = Config {
            votes_per_frame: 16,
            ..Config::DEFAULT
        };
        let mut map: Map<16, 16, 2> = Map::try_new(cfg).unwrap();
        let mut rng = Lcg(3);
        let k = key(0, 0, 10);
        // A new voxel counts every point of its first frame: 200 + 300 votes, saturating.
        map.integrate(&Isometry3::identity(), &voxel_cloud(&mut rng, 200, 300))
            .unwrap();
        assert_eq!(map.voxel(&k).unwrap().histogram, &[200, 255]);
        // 500 votes taken, 16 per frame: the next frame keeps one point in 2^5 = 32
        // (500 <= 16 * 32). Room first: 255 > 255 - 16, so halve to (100, 127).
        assert_eq!(voxel(&map, &k).tally >> 12, 5);
        let pts = voxel_cloud(&mut rng, 200, 300);
        map.integrate(&Isometry3::identity(), &pts).unwrap();
        let taken = |class: u8| {
            pts.iter()
                .filter(|p| p.labels.classes[0] == class)
                .filter(|p| vote_hash(&[p.position.x, p.position.y, p.position.z]) >> 27 == 0)
                .count()
        };
        let (t1, t2) = (taken(1), taken(2));
        let hist = *map.voxel(&k).unwrap().histogram;
        assert_eq!(hist, [100 + t1 as u8, 127 + t2 as u8]);
        assert!(
            (6..=30).contains(&(t1 + t2)),
            "about 500 / 32 = 15.6 votes, got {}",
            t1 + t2
        );
        // The next exponent follows the votes taken: about 500 points again.
        let want = next_vote_exponent(5, (t1 + t2) as u16, 16);
        assert_eq!(voxel(&map, &k).tally >> 12, want as u16);
        assert!((4..=6).contains(&want));
        assert_eq!(map.class(&k).unwrap().0, 2);
    }

    #[test]
    fn the_histogram_averages_over_frames() {
        // Frames of 60 / 40 for class 2, then one frame entirely of class 1: once the voxel's
        // sampling has adapted, the last frame weighs about as much as any other (about 16
        // votes), so class 2 stays the argmax.
        let cfg = Config {
            votes_per_frame: 16,
            ..Config::DEFAULT
        };
        let mut map: Map<16, 16, 2> = Map::try_new(cfg).unwrap();
        let mut rng = Lcg(11);
        let k = key(0, 0, 10);
        for _ in 0..9 {
            let pts = voxel_cloud(&mut rng, 200, 300);
            map.integrate(&Isometry3::identity(), &pts).unwrap();
        }
        let before = *map.voxel(&k).unwrap().histogram;
        assert!(before[1] > before[0], "{before:?}");
        let pts = voxel_cloud(&mut rng, 500, 0);
        map.integrate(&Isometry3::identity(), &pts).unwrap();
        let hist = *map.voxel(&k).unwrap().histogram;
        // Without halving the gain is the sample; with it, the old votes halved first.
        let gain = if before.iter().any(|&b| b > 239) {
            hist[0] as i32 - before[0] as i32 / 2
        } else {
            hist[0] as i32 - before[0] as i32
        };
        assert!((4..=32).contains(&gain), "{before:?} -> {hist:?}");
        assert_eq!(map.class(&k).unwrap().0, 2, "{hist:?}");
    }

    #[test]
    fn void_label_adds_geometry_but_no_vote() {
        let mut map: Map<16, 16, 3> = Map::new(Config::DEFAULT);
        let pts = [lp(0.05, 0.05, 1.05, 0); 4];
        let r = map.integrate(&Isometry3::identity(), &pts).unwrap();
        assert_eq!(r.points_used, 4);
        let k = key(0, 0, 10);
        assert_eq!(map.voxel(&k).unwrap().histogram, &[0, 0, 0]);
        assert_eq!(map.class(&k), None);
        assert_eq!(map.gaussian(&k).unwrap().count, 4);
        // Labels::NONE likewise.
        let none = [LabeledPoint::new(
            Point3::new(0.05, 0.05, 1.05),
            Labels::NONE,
        )];
        map.integrate(&Isometry3::identity(), &none).unwrap();
        assert_eq!(map.class(&k), None);
        assert_eq!(map.gaussian(&k).unwrap().count, 5);
    }

    #[test]
    fn top_k_and_min_score() {
        let k = key(0, 0, 10);
        let labels = Labels::top_k(&[(1, 255), (2, 120), (3, 99)]);
        let pts = [LabeledPoint::new(Point3::new(0.05, 0.05, 1.05), labels)];
        let hist = |top_k: u8, min_score: u8| {
            let mut cfg = Config::DEFAULT;
            cfg.top_k = top_k;
            cfg.min_score = min_score;
            let mut map: Map<16, 16, 4> = Map::try_new(cfg).unwrap();
            map.integrate(&Isometry3::identity(), &pts).unwrap();
            *map.voxel(&k).unwrap().histogram
        };
        assert_eq!(hist(1, 0), [1, 0, 0, 0]);
        assert_eq!(hist(2, 0), [1, 1, 0, 0]);
        assert_eq!(hist(3, 0), [1, 1, 1, 0]);
        assert_eq!(hist(3, 100), [1, 1, 0, 0]); // 99 < 100 does not vote
        assert_eq!(hist(3, 120), [1, 1, 0, 0]); // 120 >= 120 votes
        assert_eq!(hist(3, 121), [1, 0, 0, 0]);
        // A label above the class count rejects the point.
        let mut map: Map<16, 16, 4> = Map::new(Config::DEFAULT);
        let bad = [LabeledPoint::new(
            Point3::new(0.05, 0.05, 1.05),
            Labels::top_k(&[(1, 255), (5, 255)]),
        )];
        let r = map.integrate(&Isometry3::identity(), &bad).unwrap();
        assert_eq!((r.points_used, r.rejected_label), (0, 1));
        assert!(map.voxel(&k).is_none());
    }
}
