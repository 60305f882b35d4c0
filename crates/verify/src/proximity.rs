//! The least distance from a segment of a line to a box: the exact test that prunes a
//! search over many moves' volumes (a volume within `ρ` of its centres' segment reaches a
//! box only if that segment passes within `ρ` of the box).

use crate::exact::Line;
use glam::DVec3;

/// The least squared distance (mm²) from the segment `lo..=hi` of `line` to the box
/// `min..=max` (0 where they meet); `+∞` when `lo > hi`.
///
/// The squared distance to a box is convex along the line and piecewise quadratic, its
/// pieces joined where the line crosses the planes of the box's faces: the minimum is where
/// its derivative changes sign, found on the piece between the last crossing where it is
/// negative and the first where it is not, on which it is linear. Exact up to rounding.
pub fn segment_box_distance2(line: &Line, min: DVec3, max: DVec3) -> f64 {
    let (o, n) = (line.o, line.n);
    if line.lo > line.hi {
        return f64::INFINITY;
    }
    let outside = |t: f64| {
        let p = o + t * n;
        p - p.clamp(min, max)
    };
    // Half the derivative of the squared distance.
    let slope = |t: f64| outside(t).dot(n);
    let (mut u, mut w) = (line.lo, line.hi);
    let (mut su, mut sw) = (slope(u), slope(w));
    if su >= 0.0 {
        return outside(u).length_squared();
    }
    if sw <= 0.0 {
        return outside(w).length_squared();
    }
    for i in 0..3 {
        if n[i] == 0.0 {
            continue;
        }
        for face in [min[i], max[i]] {
            let t = (face - o[i]) / n[i];
            if t > u && t < w {
                let s = slope(t);
                if s < 0.0 {
                    (u, su) = (t, s);
                } else {
                    (w, sw) = (t, s);
                }
            }
        }
    }
    // No face's plane is crossed inside `u..w`: the slope is linear there, `su < 0 ≤ sw`.
    let t = (u - su * (w - u) / (sw - su)).clamp(u, w);
    outside(t).length_squared()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Brute force: the least of `f` over 2001 points of the segment, refined by
    /// golden-section search about the best of them.
    fn brute(line: &Line, f: impl Fn(DVec3) -> f64) -> f64 {
        let g = |t: f64| f(line.o + t * line.n);
        let k = 2000;
        let h = (line.hi - line.lo) / k as f64;
        let best = (0..=k)
            .map(|i| line.lo + i as f64 * h)
            .min_by(|&a, &b| g(a).total_cmp(&g(b)))
            .unwrap();
        let (mut a, mut b) = ((best - h).max(line.lo), (best + h).min(line.hi));
        for _ in 0..100 {
            let (m1, m2) = (a + 0.382 * (b - a), a + 0.618 * (b - a));
            if g(m1) < g(m2) {
                b = m2;
            } else {
                a = m1;
            }
        }
        g(0.5 * (a + b)).min(g(best))
    }

    fn v3() -> impl Strategy<Value = DVec3> {
        crate::testkit::v3(5.0)
    }

    /// A direction, sometimes along an axis or in a coordinate plane (zero components).
    fn dir() -> impl Strategy<Value = DVec3> {
        (v3(), 0..4usize).prop_filter_map("zero", |(d, zero)| {
            let mut d = d;
            if zero < 3 {
                d[zero] = 0.0;
            }
            (d.length() > 1e-3).then(|| d.normalize())
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(400))]

        #[test]
        fn box_distance_is_the_least_over_the_segment(
            o in v3(), n in dir(), lo in -4.0..0.0f64, len in 0.0..8.0f64,
            c in v3(), half in (0.0..2.0f64, 0.0..2.0f64, 0.0..2.0f64),
        ) {
            let line = Line { o, n, lo, hi: lo + len };
            let h = DVec3::new(half.0, half.1, half.2);
            let (min, max) = (c - h, c + h);
            let d2 = segment_box_distance2(&line, min, max);
            let b = brute(&line, |p| p.distance_squared(p.clamp(min, max)));
            // Never above the least (the pruning must not reject a box the segment reaches).
            prop_assert!(d2.sqrt() <= b.sqrt() + 1e-9, "{} > {}", d2.sqrt(), b.sqrt());
            prop_assert!(d2.sqrt() >= b.sqrt() - 1e-6, "{} < {}", d2.sqrt(), b.sqrt());
        }
    }

    #[test]
    fn a_vertical_segment_below_a_box_corner_is_as_far_as_pythagoras_says() {
        // The box x in [1, 2], z in [3, 4]; the segment x = 0, z in [-1, 0]: nearest points
        // (0, 0) and (1, 3), distance sqrt(10). The box grown by 3.2 holds the segment's
        // top; the points within 3.2 of the box do not.
        let line = Line {
            o: DVec3::ZERO,
            n: DVec3::Z,
            lo: -1.0,
            hi: 0.0,
        };
        let d2 =
            segment_box_distance2(&line, DVec3::new(1.0, -1.0, 3.0), DVec3::new(2.0, 1.0, 4.0));
        assert!((d2 - 10.0).abs() < 1e-12, "{d2}");
        let empty = Line { lo: 1.0, ..line };
        assert_eq!(
            segment_box_distance2(&empty, DVec3::ZERO, DVec3::ONE),
            f64::INFINITY
        );
    }
}
