//! Minimum stick-out: the smallest tip-to-holder-face length at which a whole toolpath is
//! free of shank and holder collisions.
//!
//! # Method
//! For a move `p → q` and a triangle, let `M` be the swept body of [`crate::collide`] and
//! `[lo, hi]` the heights (above the tip) of `M ∩ {dist_xy(axis) < ρ}` for a part of radius
//! ρ: a convex set, so its heights form an interval. At stick-out `s` holder cylinder *i*
//! spans `[s + a_i, s + b_i]` and collides iff that meets `[lo, hi]`, i.e. iff
//! `s ∈ [lo − b_i, hi − a_i]` (`b_i = ∞` for the topmost cylinder). The shank spans
//! `[flute, s]` and collides iff `hi ≥ flute` and `s ≥ max(lo, flute)`. So every
//! (move, triangle, part) forbids one closed interval of `s`; the answer is the infimum of
//! the complement above the flute length, found by one sweep over the sorted intervals.
//!
//! `hi` and `lo` are computed in closed form per triangle (see `height_range`: the
//! extremes of a height over a convex polytope cut by a vertical cylinder lie at a vertex
//! inside, an edge crossing, or a face's extreme point on the circle) and cross-checked in
//! the unit tests against bisection on the exact slab predicate of [`crate::collide`].

use cam_core::{Aabb, MoveKind, Toolpath};
use glam::{DVec2, DVec3};
use rayon::prelude::*;
use serde::Serialize;

use crate::collide::{CheckConfig, HolderChecker, move_start, swept_box, vertical};
use crate::geom::{PRISM_EDGES, swept_points};
use crate::library::{AssemblyPart, ToolAssembly};

/// The result of [`min_stick_out`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StickOut {
    /// The smallest stick-out (mm) from which on the path is collision-free: every stick-out
    /// slightly above it is free; it is itself free when `limiting` is `None` (then it is the
    /// lower bound asked for). `None` when no stick-out is free (the shank itself collides).
    pub min_mm: Option<f64>,
    /// The move and tip position (mm) of the contact that sets the minimum, if any.
    pub limiting: Option<(usize, DVec3)>,
    /// The part that sets it, if any.
    pub limiting_part: Option<AssemblyPart>,
}

/// One forbidden interval of stick-out values.
#[derive(Debug, Clone, Copy)]
struct Forbidden {
    lo: f64,
    hi: f64,
    move_index: usize,
    part: AssemblyPart,
}

/// Faces of the prism of [`swept_points`]: the triangle at both ends and three
/// parallelograms (vertex lists in order around the face).
const PRISM_FACES: [&[usize]; 5] = [
    &[0, 1, 2],
    &[3, 4, 5],
    &[0, 1, 4, 3],
    &[1, 2, 5, 4],
    &[2, 0, 3, 5],
];

/// Exact height range `[lo, hi]` of `M ∩ {dist_xy ≤ rho}` for the prism `M` of six
/// [`swept_points`], or `None` if empty.
///
/// The extremes of a linear function over the convex set `M ∩ cylinder` lie on the boundary
/// of `M` (the cylinder is vertical), so at one of: a vertex of `M` inside the cylinder; a
/// crossing of an edge of `M` with the cylinder; on a face, the point of the circle where
/// the face's height is extreme (`±rho·ĝ`, `g` the face's XY gradient) or, for a face whose
/// height is constant over the disc, the face point above the axis. Every candidate is
/// checked to lie in `M ∩ cylinder`, so the max and min over the candidates are exact.
pub(crate) fn height_range(pts: &[DVec3; 6], rho: f64) -> Option<(f64, f64)> {
    let r2 = rho * rho;
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    let mut take = |z: f64| {
        lo = lo.min(z);
        hi = hi.max(z);
    };
    for p in pts {
        if p.truncate().length_squared() <= r2 {
            take(p.z);
        }
    }
    for &(i, j) in &PRISM_EDGES {
        let (a, b) = (pts[i], pts[j]);
        let e = b - a;
        let qa = e.truncate().length_squared();
        if qa == 0.0 {
            continue;
        }
        let qb = 2.0 * a.truncate().dot(e.truncate());
        let qc = a.truncate().length_squared() - r2;
        let disc = qb * qb - 4.0 * qa * qc;
        if disc < 0.0 {
            continue;
        }
        let sq = disc.sqrt();
        for s in [(-qb - sq) / (2.0 * qa), (-qb + sq) / (2.0 * qa)] {
            if (0.0..=1.0).contains(&s) {
                take(a.z + s * e.z);
            }
        }
    }
    for f in PRISM_FACES {
        let m = f.len();
        let mut v = [DVec3::ZERO; 4];
        for (k, &i) in f.iter().enumerate() {
            v[k] = pts[i];
        }
        let n = (v[1] - v[0]).cross(v[m - 1] - v[0]);
        let scale = (v[1] - v[0])
            .length_squared()
            .max((v[m - 1] - v[0]).length_squared());
        if n.z.abs() <= 1e-14 * scale {
            continue; // vertical or degenerate: its extremes are on its edges
        }
        let g = DVec2::new(-n.x / n.z, -n.y / n.z);
        let gl = g.length();
        let xs = if gl > 0.0 {
            [DVec2::ZERO, g * (rho / gl), -g * (rho / gl)]
        } else {
            [DVec2::ZERO; 3]
        };
        let count = if gl > 0.0 { 3 } else { 1 };
        for &x in &xs[..count] {
            // Inside the projected convex face (either orientation)?
            let (mut pos, mut neg) = (false, false);
            for k in 0..m {
                let (a, b) = (v[k].truncate(), v[(k + 1) % m].truncate());
                let c = (b - a).perp_dot(x - a);
                pos |= c > 0.0;
                neg |= c < 0.0;
            }
            if pos && neg {
                continue;
            }
            take(v[0].z + g.dot(x - v[0].truncate()));
        }
    }
    (hi >= lo).then_some((lo, hi))
}

/// Stick-out analysis of one assembly on one toolpath: all forbidden intervals above `from`.
fn forbidden(
    checker: &HolderChecker<'_>,
    assembly: &ToolAssembly,
    toolpath: &Toolpath,
    cfg: &CheckConfig,
    from: f64,
) -> Vec<Forbidden> {
    let flute = assembly.cutter.flute_length();
    // (part, radius, a, b) with heights relative to the stick-out for the holder.
    let mut specs: Vec<(AssemblyPart, f64, f64, f64)> = vec![(
        AssemblyPart::Shank,
        assembly.shank_diameter_mm / 2.0,
        0.0,
        0.0,
    )];
    let mut a = 0.0;
    let n = assembly.holder.len();
    for (i, c) in assembly.holder.iter().enumerate() {
        let b = if i + 1 == n {
            f64::INFINITY
        } else {
            a + c.length
        };
        specs.push((AssemblyPart::Holder(i), c.diameter / 2.0, a, b));
        a += c.length;
    }
    let per_move: Vec<Vec<Forbidden>> = (0..toolpath.moves.len())
        .into_par_iter()
        .map(|i| {
            let m = &toolpath.moves[i];
            let start_axis = if i == 0 {
                m.pose.axis
            } else {
                toolpath.moves[i - 1].pose.axis
            };
            if !vertical(m.pose.axis)
                || !vertical(start_axis)
                || (m.kind == MoveKind::Rapid && !cfg.check_rapids)
            {
                return Vec::new();
            }
            let (p, q) = (move_start(toolpath, i), m.pose.tip);
            let mut out = Vec::new();
            let boxes: Vec<Aabb> = specs
                .iter()
                .map(|&(part, r, a, _)| {
                    let zlo = if part == AssemblyPart::Shank {
                        flute
                    } else {
                        from + a
                    };
                    swept_box(p, q, r + cfg.clearance_mm, zlo, f64::INFINITY)
                })
                .collect();
            let mut lists = vec![Vec::new(); specs.len()];
            checker.candidates_multi(&boxes, &mut lists);
            for (&(part, r, a, b), buf) in specs.iter().zip(&lists) {
                let rho = r + cfg.clearance_mm;
                let thresh = rho - cfg.min_depth_mm;
                if thresh <= 0.0 {
                    continue;
                }
                for &ti in buf {
                    let pts = swept_points(checker.tri(ti), p, q);
                    let Some((lo, hi)) = height_range(&pts, thresh) else {
                        continue;
                    };
                    let iv = if part == AssemblyPart::Shank {
                        if hi < flute {
                            continue;
                        }
                        (lo.max(flute), f64::INFINITY)
                    } else {
                        (lo - b, hi - a)
                    };
                    if iv.1 >= from {
                        out.push(Forbidden {
                            lo: iv.0,
                            hi: iv.1,
                            move_index: i,
                            part,
                        });
                    }
                }
            }
            out
        })
        .collect();
    let mut all: Vec<Forbidden> = per_move.into_iter().flatten().collect();
    all.sort_by(|x, y| {
        x.lo.total_cmp(&y.lo)
            .then(x.move_index.cmp(&y.move_index))
            .then(x.part.cmp(&y.part))
    });
    all
}

/// The smallest collision-free stick-out `≥ from_mm` (see [`StickOut`]), using a prepared
/// checker. Verified in the tests by a clear check at `min + 1e-6` and a collision at
/// `min − 1e-3`.
pub fn min_stick_out_from(
    checker: &HolderChecker<'_>,
    assembly: &ToolAssembly,
    toolpath: &Toolpath,
    cfg: &CheckConfig,
    from_mm: f64,
) -> StickOut {
    let ivs = forbidden(checker, assembly, toolpath, cfg, from_mm);
    let mut cur = from_mm;
    let mut limit: Option<Forbidden> = None;
    for iv in &ivs {
        if iv.lo > cur {
            break;
        }
        if iv.hi >= cur && (iv.hi > cur || limit.is_none()) {
            cur = iv.hi;
            limit = Some(*iv);
        }
    }
    // Of all intervals ending exactly at the answer, name the first in path order.
    if let Some(l) = limit {
        limit = ivs
            .iter()
            .filter(|iv| iv.hi == l.hi && iv.lo <= l.hi)
            .min_by_key(|iv| (iv.move_index, iv.part))
            .copied();
    }
    if cur == f64::INFINITY {
        return StickOut {
            min_mm: None,
            limiting: limit.map(|l| (l.move_index, toolpath.moves[l.move_index].pose.tip)),
            limiting_part: limit.map(|l| l.part),
        };
    }
    let limiting = limit.map(|l| {
        // Where it happens: the onset of that part on that move just below the minimum.
        let probe = assembly.with_stick_out(cur - 1e-7);
        let one = Toolpath {
            moves: vec![
                toolpath.moves[l.move_index.saturating_sub(1)],
                toolpath.moves[l.move_index],
            ],
        };
        let idx = if l.move_index == 0 { 0 } else { 1 };
        let rep = checker.check(&probe, &one, cfg);
        let pos = rep
            .collisions
            .iter()
            .find(|c| c.move_index == idx && c.part == l.part)
            .map_or(toolpath.moves[l.move_index].pose.tip, |c| c.position);
        (l.move_index, pos)
    });
    StickOut {
        min_mm: Some(cur),
        limiting,
        limiting_part: limit.map(|l| l.part),
    }
}

/// The smallest stick-out (≥ the flute length) at which `toolpath` is free of shank and
/// holder collisions with `mesh`; exact (see the module docs).
pub fn min_stick_out(
    mesh: &cam_core::Mesh,
    assembly: &ToolAssembly,
    toolpath: &Toolpath,
    cfg: &CheckConfig,
) -> StickOut {
    let checker = HolderChecker::new(mesh);
    min_stick_out_from(
        &checker,
        assembly,
        toolpath,
        cfg,
        assembly.cutter.flute_length(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::axis_distance;

    /// Reference by bisection on the exact monotone slab predicate.
    fn by_bisection(pts: &[DVec3; 6], rho: f64) -> Option<(f64, f64)> {
        let inside = |z0: f64, z1: f64| axis_distance(pts, z0, z1).is_some_and(|d| d <= rho);
        if !inside(f64::NEG_INFINITY, f64::INFINITY) {
            return None;
        }
        let zmin = pts.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
        let zmax = pts.iter().map(|p| p.z).fold(f64::NEG_INFINITY, f64::max);
        let bis = |up: bool| {
            let test = |z: f64| {
                if up {
                    inside(z, f64::INFINITY)
                } else {
                    inside(f64::NEG_INFINITY, z)
                }
            };
            let (mut good, mut bad) = if up { (zmin, zmax) } else { (zmax, zmin) };
            if test(bad) {
                return bad;
            }
            for _ in 0..200 {
                let mid = 0.5 * (good + bad);
                if mid == good || mid == bad {
                    break;
                }
                if test(mid) { good = mid } else { bad = mid }
            }
            good
        };
        Some((bis(false), bis(true)))
    }

    #[test]
    fn closed_form_matches_bisection() {
        let mut s = 0x2545F4914F6CDD1Du64;
        let mut r = |lo: f64, hi: f64| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            lo + (hi - lo) * ((s >> 11) as f64 / (1u64 << 53) as f64)
        };
        let mut both = 0;
        for case in 0..3000 {
            let tri = cam_core::Triangle::new(
                DVec3::new(r(-10.0, 10.0), r(-10.0, 10.0), r(-5.0, 5.0)),
                DVec3::new(r(-10.0, 10.0), r(-10.0, 10.0), r(-5.0, 5.0)),
                DVec3::new(r(-10.0, 10.0), r(-10.0, 10.0), r(-5.0, 5.0)),
            );
            let p = DVec3::new(r(-5.0, 5.0), r(-5.0, 5.0), r(-3.0, 3.0));
            // Some moves horizontal, some vertical, some static.
            let q = match case % 4 {
                0 => p,
                1 => DVec3::new(r(-5.0, 5.0), r(-5.0, 5.0), p.z),
                2 => DVec3::new(p.x, p.y, r(-3.0, 3.0)),
                _ => DVec3::new(r(-5.0, 5.0), r(-5.0, 5.0), r(-3.0, 3.0)),
            };
            let pts = swept_points(&tri, p, q);
            let rho = r(0.5, 6.0);
            let exact = height_range(&pts, rho);
            let reference = by_bisection(&pts, rho);
            match (exact, reference) {
                (Some(a), Some(b)) => {
                    both += 1;
                    assert!(
                        (a.0 - b.0).abs() < 1e-9 && (a.1 - b.1).abs() < 1e-9,
                        "case {case}: {a:?} vs {b:?}"
                    );
                }
                (None, None) => {}
                (a, b) => panic!("case {case}: {a:?} vs {b:?}"),
            }
        }
        assert!(both > 500, "{both}");
    }
}
