//! The exact height of the CL surface above a straight move's chord: the largest vertical
//! depth by which a cutter moving in a straight line between two tool-tip positions sinks
//! below the CL surface, found without dropping the cutter along the move.
//!
//! The CL surface is the maximum over triangles of the drop onto each triangle alone
//! ([`DropCutter::triangle_drop`]), and each of those is concave along a straight line (the
//! triangle's Minkowski sum with the reflected cutter is convex). So the CL minus the chord,
//! per triangle, is a concave function of the position along the move: its maximum is found
//! by golden-section search on the interval where the triangle is within reach (stopped as
//! soon as secants extended past their points, which lie above a concave function, bound it
//! below the best height found so far), and the move's value is the largest over the
//! triangles within reach, those whose top cannot beat the best skipped.

use crate::certify::seg_rect_dist2;
use crate::index::DropCutter;

/// What [`DropCutter::chord_rise`] found along a move.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChordRise {
    /// Largest height (mm, vertical) of the CL surface above the chord over the move, or
    /// the floor asked for if none is above it (`-inf` when the cutter touches nothing
    /// along the move and no floor was given). When the search stopped early at its limit,
    /// a height above the limit that the CL surface reaches (not always the largest).
    pub rise_mm: f64,
    /// Where that height is reached: the fraction of the way from the start to the end.
    pub at: f64,
}

/// Golden-section iterations per side of a triangle's interval: the bracket shrinks to
/// 0.618^60 ≈ 3e-13 of the move.
const GOLDEN_ITERS: usize = 60;

impl DropCutter {
    /// The largest height (mm) of the exact CL surface above the chord of the move from
    /// `(a, za)` to `(b, zb)` (XY in mm, tool-tip z in mm): how far the cutter moving along
    /// the chord sinks below the surface it may touch, measured vertically. Heights at or
    /// below `floor_mm` are not searched for: if there is none above it, the result is
    /// `floor_mm` (at 0). Stops as soon as a height above `limit_mm` is found. Pass
    /// `-inf` and `inf` for the exact maximum.
    ///
    /// Exact up to the golden-section bracket (3e-13 of the move's length along it), and
    /// the height reported is one the CL surface reaches there: a planner may trust a value
    /// at or below its tolerance as a proof that the move keeps within it.
    pub fn chord_rise(
        &self,
        a: (f64, f64),
        b: (f64, f64),
        za: f64,
        zb: f64,
        floor_mm: f64,
        limit_mm: f64,
    ) -> ChordRise {
        let big_r = self.pf.big_r;
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let len2 = dx * dx + dy * dy;
        let chord = |t: f64| za + t * (zb - za);
        let at = |t: f64| (a.0 + t * dx, a.1 + t * dy);
        let mut best = ChordRise {
            rise_mm: floor_mm,
            at: 0.0,
        };
        if !(a.0.is_finite() && a.1.is_finite() && b.0.is_finite() && b.1.is_finite()) {
            return best;
        }
        // Triangles within reach: the cells the segment crosses list every triangle within
        // R of them.
        // A triangle whose top is not above the floor over the chord's lower end cannot rise
        // above it anywhere (the bound below is never larger): left out before the
        // duplicates are sorted away. A cell lists its triangles by descending top, so the
        // rest of the cell goes with the first such one.
        let z_low = za.min(zb);
        let mut slots: Vec<u32> = Vec::new();
        for (c, _) in self.cells_on_segment(a, b) {
            slots.extend(
                self.items[self.start[c] as usize..self.start[c + 1] as usize]
                    .iter()
                    .take_while(|&&s| self.tris[s as usize].top - z_low > floor_mm),
            );
        }
        slots.sort_unstable();
        slots.dedup();
        // Each triangle's interval of reach along the move (from its XY box) and the bound
        // its top gives there; the most promising first.
        let len = len2.sqrt();
        let mut cands: Vec<(f64, u32, f64, f64)> = slots
            .into_iter()
            .filter_map(|s| {
                let t = &self.tris[s as usize];
                if seg_rect_dist2(a, b, (t.lo[0], t.lo[1], t.hi[0], t.hi[1])) > big_r * big_r {
                    return None;
                }
                let (lo, hi) = if len2 > 0.0 {
                    let mut pmin = f64::INFINITY;
                    let mut pmax = f64::NEG_INFINITY;
                    for x in [t.lo[0], t.hi[0]] {
                        for y in [t.lo[1], t.hi[1]] {
                            let p = ((x - a.0) * dx + (y - a.1) * dy) / len;
                            pmin = pmin.min(p);
                            pmax = pmax.max(p);
                        }
                    }
                    (
                        ((pmin - big_r) / len).clamp(0.0, 1.0),
                        ((pmax + big_r) / len).clamp(0.0, 1.0),
                    )
                } else {
                    (0.0, 0.0)
                };
                let bound = t.top - chord(lo).min(chord(hi));
                // Cannot rise above the floor: not a candidate.
                (bound > floor_mm).then_some((bound, s, lo, hi))
            })
            .collect();
        cands.sort_by(|p, q| q.0.total_cmp(&p.0).then(p.1.cmp(&q.1)));
        for (bound, s, lo, hi) in cands {
            if bound <= best.rise_mm {
                break;
            }
            let orig = self.tris[s as usize].orig;
            let h = |t: f64| {
                let (x, y) = at(t);
                self.triangle_drop(orig, x, y)
                    .map_or(f64::NEG_INFINITY, |z| z - chord(t))
            };
            // A point of the interval where the triangle is within reach.
            let Some((tc, hc)) = self.reach_point(orig, a, (dx, dy), lo, hi, &h) else {
                continue;
            };
            let consider = |best: &mut ChordRise, t: f64, v: f64| {
                if v > best.rise_mm {
                    *best = ChordRise { rise_mm: v, at: t };
                }
            };
            consider(&mut best, tc, hc);
            // Concave on its domain (an interval containing tc): search each side, ties
            // moving towards tc (the domain's side).
            for (l0, r0, toward_right) in [(lo, tc, true), (tc, hi, false)] {
                if r0 - l0 <= 0.0
                    || self.tris[s as usize].top - chord(l0).min(chord(r0)) <= best.rise_mm
                {
                    continue;
                }
                let ends = if toward_right {
                    ((l0, h(l0)), (r0, hc))
                } else {
                    ((l0, hc), (r0, h(r0)))
                };
                let (t, v) = golden_max(ends.0, ends.1, toward_right, best.rise_mm, &h);
                consider(&mut best, t, v);
            }
            if best.rise_mm > limit_mm {
                return best;
            }
        }
        best
    }

    /// A fraction `t` in `[lo, hi]` where the triangle `orig` is within reach of the cutter
    /// at `a + t·d`, with `h(t)`; `None` if there is none.
    fn reach_point(
        &self,
        orig: u32,
        a: (f64, f64),
        d: (f64, f64),
        lo: f64,
        hi: f64,
        h: &impl Fn(f64) -> f64,
    ) -> Option<(f64, f64)> {
        let slot = self.slot_of[orig as usize] as usize;
        let v = &self.tris[slot].v;
        // Nearest approach of the move to the triangle (XY distance, convex along the move).
        let dist2 = |t: f64| {
            let p = (a.0 + t * d.0, a.1 + t * d.1);
            point_triangle_dist2_xy(p, v)
        };
        let mid = 0.5 * (lo + hi);
        let hm = h(mid);
        if hm > f64::NEG_INFINITY {
            return Some((mid, hm));
        }
        let (mut l, mut r) = (lo, hi);
        let g = 0.5 * (5f64.sqrt() - 1.0);
        let (mut m1, mut m2) = (r - g * (r - l), l + g * (r - l));
        let (mut f1, mut f2) = (dist2(m1), dist2(m2));
        for _ in 0..GOLDEN_ITERS {
            if f1 <= f2 {
                r = m2;
                m2 = m1;
                f2 = f1;
                m1 = r - g * (r - l);
                f1 = dist2(m1);
            } else {
                l = m1;
                m1 = m2;
                f1 = f2;
                m2 = l + g * (r - l);
                f2 = dist2(m2);
            }
        }
        for t in [m1, m2, l, r, lo, hi] {
            let ht = h(t);
            if ht > f64::NEG_INFINITY {
                return Some((t, ht));
            }
        }
        None
    }
}

/// Golden-section maximum of `h` on `[l, r]`, `h` concave where finite on an interval that
/// contains `r` (`toward_right`) or `l`; ties (both `-inf` included) move towards that end.
/// `fl`, `fr` are `h(l)`, `h(r)`. Stops once concavity bounds the maximum at or below
/// `stop_at` (the result is then the best value seen, below `stop_at`).
fn golden_max(
    (mut l, mut fl): (f64, f64),
    (mut r, mut fr): (f64, f64),
    toward_right: bool,
    stop_at: f64,
    h: &impl Fn(f64) -> f64,
) -> (f64, f64) {
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut m1, mut m2) = (r - g * (r - l), l + g * (r - l));
    let (mut f1, mut f2) = (h(m1), h(m2));
    let mut best = if f1 >= f2 { (m1, f1) } else { (m2, f2) };
    for _ in 0..GOLDEN_ITERS {
        if concave_bound((l, fl), (m1, f1), (m2, f2), (r, fr)) <= stop_at {
            break;
        }
        let go_left = if toward_right { f1 > f2 } else { f1 >= f2 };
        if go_left {
            (r, fr) = (m2, f2);
            (m2, f2) = (m1, f1);
            m1 = r - g * (r - l);
            f1 = h(m1);
            if f1 > best.1 {
                best = (m1, f1);
            }
        } else {
            (l, fl) = (m1, f1);
            (m1, f1) = (m2, f2);
            m2 = l + g * (r - l);
            f2 = h(m2);
            if f2 > best.1 {
                best = (m2, f2);
            }
        }
    }
    best
}

/// An upper bound of a function concave where finite (on an interval) over `[l, r]` from its
/// values at `l < m1 < m2 < r`: a secant extended beyond its interval lies above the
/// function. Infinite when the values do not allow one.
fn concave_bound(
    (l, fl): (f64, f64),
    (m1, f1): (f64, f64),
    (m2, f2): (f64, f64),
    (r, fr): (f64, f64),
) -> f64 {
    if !(f1.is_finite() && f2.is_finite()) || m2 <= m1 {
        return f64::INFINITY;
    }
    let s = (f2 - f1) / (m2 - m1);
    // [l, m1] and [m2, r]: the secant through m1 and m2.
    let outer = f1.max(f1 + s * (l - m1)).max(f2).max(f2 + s * (r - m2));
    // [m1, m2]: the secant through l and m1, or through m2 and r.
    let mut inner = f64::INFINITY;
    if fl.is_finite() && m1 > l {
        inner = inner.min(f1.max(f1 + (f1 - fl) / (m1 - l) * (m2 - m1)));
    }
    if fr.is_finite() && r > m2 {
        inner = inner.min(f2.max(f2 + (fr - f2) / (r - m2) * (m1 - m2)));
    }
    outer.max(inner)
}

/// Squared XY distance (mm²) from `p` to the XY projection of the triangle `v`.
fn point_triangle_dist2_xy(p: (f64, f64), v: &[cam_core::DVec3; 3]) -> f64 {
    let area = (v[1].x - v[0].x) * (v[2].y - v[0].y) - (v[1].y - v[0].y) * (v[2].x - v[0].x);
    let sgn = area.signum();
    let mut inside = area != 0.0;
    let mut best = f64::INFINITY;
    for k in 0..3 {
        let (q0, q1) = (v[k], v[(k + 1) % 3]);
        let (ex, ey) = (q1.x - q0.x, q1.y - q0.y);
        let (px, py) = (p.0 - q0.x, p.1 - q0.y);
        if sgn * (ex * py - ey * px) < 0.0 {
            inside = false;
        }
        let l2 = ex * ex + ey * ey;
        let t = if l2 > 0.0 {
            ((px * ex + py * ey) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        best = best.min((px - t * ex).powi(2) + (py - t * ey).powi(2));
    }
    if inside { 0.0 } else { best }
}
