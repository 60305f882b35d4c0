//! Runs of consecutive moves bounded together, for a ball's direct search.
//!
//! A finishing program's feed moves are short next to the ball (on the dome's ball
//! program half a millimetre against a 3 mm radius), so some forty moves' capsules reach
//! near each group of vectors, and every vector tests each (see `measure_vectors`). A run
//! of consecutive moves whose centres stay within a small `slack` of the run's chord lies
//! in the capsule of radius `r + slack` about that chord: one test turns the whole run
//! away for the vectors that pass clear of it, and the runs, several times fewer than the
//! moves, are what the tiles and groups gather.

use glam::DVec3;

use crate::envelope::segment_distance;

/// The most moves in a run: a vector near a run tests every member of it. On the dome's
/// ball program runs of 8, 16 and 32 moves are the same runs (the passes' curvature ends
/// them first); the limit bounds straight passes.
pub(crate) const RUN_MOVES: usize = 8;

/// The largest slack (mm) a run may have: the farthest its moves' centres may lie from its
/// chord. A run's capsule is then at most this much fatter than its moves'. Longer runs
/// are fewer to test and their members more often tested in vain: on the dome's ball
/// program (callgrind, 1 thread) 2.404 G instructions at 0.02 mm, 2.386 G at 0.05 mm,
/// 2.512 G at 0.1 mm; mount_rush's 21.83 G at 0.02 mm and 20.68 G at 0.05 mm (21.93 G
/// without runs).
pub(crate) const MAX_SLACK_MM: f64 = 0.05;

/// The runs: each a range of `members` (item indices, in program order) with its chord
/// and slack.
pub(crate) struct Runs {
    /// Per run: the first of its members in `members` and how many.
    pub ranges: Vec<(u32, u32)>,
    /// The runs' members: indices of the moves' items.
    pub members: Vec<u32>,
    /// Per run: the chord's ends (the first member's first centre, the last member's last)
    /// and the slack (mm), rounded up: every member's centres' segment lies within it of
    /// the chord.
    pub chords: Vec<(DVec3, DVec3, f64)>,
}

/// The farthest of the centres `ends` from the chord `a`–`b`.
fn slack_of(ends: &[(DVec3, DVec3)], a: DVec3, b: DVec3) -> f64 {
    ends.iter()
        .map(|&(c0, c1)| segment_distance(c0, a, b).max(segment_distance(c1, a, b)))
        .fold(0.0, f64::max)
}

/// Groups the moves `(move number, item index, first centre, last centre)`, taken in the
/// order of their move numbers, into runs of at most [`RUN_MOVES`] consecutive moves whose
/// slack stays within [`MAX_SLACK_MM`]. The distance from a segment is convex along
/// another, so a member segment's farthest point from the chord is one of its ends: the
/// slack bounds the whole member. It is rounded up by a relative and an absolute margin
/// (against the rounding of the distances computed here and of the tests that use it).
pub(crate) fn runs(mut moves: Vec<(u32, u32, DVec3, DVec3)>) -> Runs {
    moves.sort_unstable_by_key(|m| m.0);
    let scale = moves.iter().fold(0.0f64, |m, x| {
        m.max(x.2.abs().max_element()).max(x.3.abs().max_element())
    });
    let pad = 1e-9 * (1.0 + scale);
    let mut out = Runs {
        ranges: Vec::new(),
        members: Vec::new(),
        chords: Vec::new(),
    };
    let mut ends: Vec<(DVec3, DVec3)> = Vec::with_capacity(RUN_MOVES);
    let mut i = 0;
    while i < moves.len() {
        let first = out.members.len() as u32;
        ends.clear();
        ends.push((moves[i].2, moves[i].3));
        out.members.push(moves[i].1);
        let a = moves[i].2;
        let (mut b, mut slack) = (moves[i].3, 0.0);
        let mut j = i + 1;
        while j < moves.len() && ends.len() < RUN_MOVES && moves[j].0 == moves[j - 1].0 + 1 {
            ends.push((moves[j].2, moves[j].3));
            let s = slack_of(&ends, a, moves[j].3);
            if s > MAX_SLACK_MM {
                ends.pop();
                break;
            }
            out.members.push(moves[j].1);
            (b, slack) = (moves[j].3, s);
            j += 1;
        }
        let slack = slack * (1.0 + 1e-9) + pad;
        out.ranges.push((first, (j - i) as u32));
        out.chords.push((a, b, slack));
        i = j;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Every point of every member's centres' segment lies within the run's slack of
        /// its chord (sampled at 101 points), runs hold consecutive moves and every move
        /// once, and the slack never exceeds the limit.
        #[test]
        fn runs_bound_their_members(
            steps in prop::collection::vec(
                ((-1.0..1.0f64, -1.0..1.0f64, -0.3..0.3f64), 0..4u32), 1..60),
            start in (-50.0..50.0f64, -50.0..50.0f64, -5.0..5.0f64),
        ) {
            let mut p = DVec3::new(start.0, start.1, start.2);
            let mut moves = Vec::new();
            let mut mv = 1u32;
            for (k, (d, gap)) in steps.iter().enumerate() {
                // Mostly small turns; some moves skipped in the numbering.
                let q = p + DVec3::new(0.5 + 0.1 * d.0, 0.05 * d.1, 0.02 * d.2);
                moves.push((mv, k as u32, p, q));
                mv += 1 + u32::from(*gap == 0);
                p = q;
            }
            let n = moves.len();
            let runs = runs(moves.clone());
            let mut seen = vec![false; n];
            for (r, &(first, count)) in runs.ranges.iter().enumerate() {
                let (a, b, slack) = runs.chords[r];
                prop_assert!(slack <= MAX_SLACK_MM * (1.0 + 1e-6) + 1e-6);
                let ms = &runs.members[first as usize..(first + count) as usize];
                prop_assert!(!ms.is_empty() && ms.len() <= RUN_MOVES);
                for (k, &ci) in ms.iter().enumerate() {
                    prop_assert!(!seen[ci as usize]);
                    seen[ci as usize] = true;
                    let m = moves[ci as usize];
                    if k > 0 {
                        prop_assert_eq!(m.0, moves[ms[k - 1] as usize].0 + 1);
                    }
                    for t in 0..=100 {
                        let x = m.2.lerp(m.3, t as f64 / 100.0);
                        prop_assert!(segment_distance(x, a, b) <= slack, "{} > {}", segment_distance(x, a, b), slack);
                    }
                }
                prop_assert_eq!(a, moves[ms[0] as usize].2);
                prop_assert_eq!(b, moves[*ms.last().unwrap() as usize].3);
            }
            prop_assert!(seen.iter().all(|&s| s));
        }
    }
}
