//! Class votes: which labels of a point vote, and the order-independent sample of about
//! `votes_per_frame` votes a voxel takes per frame (see [`crate::Config::votes_per_frame`]).
//!
//! A voxel's `tally` holds this frame's sampling exponent `k` (the sample keeps a voting
//! point when the top `k` bits of its coordinates' hash are zero) and the votes taken so
//! far; at the end of the frame the votes taken set `k` for the next frame. Before its
//! first vote of a frame a voxel makes room in its `u8` histogram, so the sample cannot
//! saturate a bin.

use crate::config::Config;
use crate::labels::Labels;
use crate::voxel::Voxel;

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
pub fn takes_vote(hash: u32, exponent: u8) -> bool {
    (hash as u64) >> (32 - exponent.min(MAX_VOTE_EXPONENT) as u32) == 0
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
pub fn next_vote_exponent(exponent: u8, taken: u16, votes_per_frame: u8) -> u8 {
    let estimate = (taken as u64) << exponent.min(MAX_VOTE_EXPONENT);
    let budget = votes_per_frame.max(1) as u64;
    let mut k = 0;
    while k < MAX_VOTE_EXPONENT && estimate > budget << k {
        k += 1;
    }
    k
}

/// Whether any of a point's (valid) labels votes: one of its first `top_k` labels is a
/// class (not void) with a score of at least `min_score`.
#[inline]
pub(crate) fn has_vote(labels: &Labels, cfg: &Config) -> bool {
    let k = (cfg.top_k as usize).min(labels.len as usize);
    (0..k).any(|i| labels.classes[i] >= 1 && labels.scores[i] >= cfg.min_score)
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

    /// The votes of a point at `p` (sensor frame) whose labels vote ([`has_vote`]), if
    /// this frame's sample takes it: one per voting label, saturating.
    #[inline]
    pub(crate) fn vote(&mut self, p: &[f32; 3], labels: &Labels, cfg: &Config) {
        let exponent = self.vote_exponent();
        if exponent == 0 || takes_vote(vote_hash(p), exponent) {
            let taken = (self.tally & VOTES_TAKEN_MAX) + 1;
            self.tally = (self.tally & !VOTES_TAKEN_MAX) | taken.min(VOTES_TAKEN_MAX);
            let k = (cfg.top_k as usize).min(labels.len as usize);
            for i in 0..k {
                let c = labels.classes[i] as usize;
                if c >= 1 && labels.scores[i] >= cfg.min_score {
                    self.hist[c - 1] = self.hist[c - 1].saturating_add(1);
                }
            }
        }
    }

    /// Ends the frame's sample: the next frame samples so that a voxel seen as densely
    /// takes about `votes_per_frame` votes.
    pub(crate) fn end_vote_sample(&mut self, votes_per_frame: u8) {
        let taken = self.tally & VOTES_TAKEN_MAX;
        let next = next_vote_exponent(self.vote_exponent(), taken, votes_per_frame);
        self.start_vote_sample(next);
    }

    /// Halves every bin if any bin exceeds `255 - votes` so a frame's sample of about
    /// `votes` votes has room (done once per voxel per frame, before the votes, so the
    /// result does not depend on point order).
    pub(crate) fn make_vote_room(&mut self, votes: u8) {
        let limit = 255 - votes;
        if self.hist.iter().any(|&b| b > limit) {
            for b in self.hist.iter_mut() {
                *b /= 2;
            }
        }
    }
}
