//! Exact first entry of a line into the cutter's *column*: the solid cylinder of radius
//! `R = a + r` above the torus centre plane, unbounded along the axis (the flutes, the shank
//! and what holds them). Together with the puck ([`crate::exact`]) it is the whole cutter,
//! so a line that starts inside the cutter, or comes at it from the side above its corner,
//! enters where the cutter is — not only where its lower part is.
//!
//! For one pose the column is a half-infinite cylinder: a quadratic and a half-line. For a
//! translation (centre `c0 + u·d`, `u ∈ [0, 1]`, fixed axis `k`) the union over the move is
//! convex (a Minkowski sum of the column and a segment): with `q(s, u) = o + s·n − c0 − u·d`
//! the set of `(s, u)` with `|q_⊥| ≤ R`, `q·k ≥ 0` and `0 ≤ u ≤ 1` is convex, and the smallest
//! `s` in it lies where one or two of these constraints are active. Each such place gives a
//! candidate `s` in closed form (a linear equation or a quadratic); the answer is the smallest
//! candidate at which some `u` satisfies all three (itself a pair of intervals in `u`).

use cam_core::DVec3;

use crate::exact::{Entry, Line, quadratic_roots as roots};

/// Relative slack (of the problem's size) allowed to the feasibility of a candidate: the
/// candidates are computed boundary points, which rounding may put just outside.
const FEAS_REL: f64 = 1e-9;

/// First entry of `line` into the half-infinite cylinder of radius `radius` about the axis
/// `k` (unit) from base centre `c` upward (`(x − c)·k ≥ 0`): side, base disk, or `lo` (with
/// normal `−n`) when the line starts inside. With `base` false an entry through the base
/// disk (which the cutter's puck covers) is not reported: `None` then.
pub fn column_entry(
    line: &Line,
    c: DVec3,
    k: DVec3,
    radius: f64,
    base_counts: bool,
) -> Option<Entry> {
    let (m, n) = (line.o - c, line.n);
    let (mk, nk) = (m.dot(k), n.dot(k));
    // Axial half-line: mk + s·nk ≥ 0.
    let (mut lo, mut hi) = (line.lo, line.hi);
    let mut base = None;
    if nk > 0.0 {
        let s = -mk / nk;
        if s > lo {
            lo = s;
            base = Some(s);
        }
    } else if nk < 0.0 {
        hi = hi.min(-mk / nk);
    } else if mk < 0.0 {
        return None;
    }
    let (mp, np) = (m - mk * k, n - nk * k);
    let qa = np.length_squared();
    let qc = mp.length_squared() - radius * radius;
    let mut side = None;
    if qa > 1e-300 {
        let (r1, r2) = roots(qa, mp.dot(np), qc)?;
        if r1 > lo {
            lo = r1;
            side = Some(r1);
        }
        hi = hi.min(r2);
    } else if qc > 0.0 {
        return None;
    }
    if lo > hi {
        return None;
    }
    let normal = if side == Some(lo) {
        ((mp + lo * np) / radius).normalize_or(-n)
    } else if base == Some(lo) {
        if !base_counts {
            return None;
        }
        -k
    } else {
        -n
    };
    Some(Entry { s: lo, normal })
}

/// First entry of `line` into the union of the columns of radius `radius` about the axis `k`
/// (unit) with base centres on the segment `c0 → c1` (a translation), in closed form (see
/// the module docs). The normal is the outward normal of the union at the entry where one
/// constraint is active there, else a normal of an active piece (`−n` when the line starts
/// inside); it always faces against the line.
///
/// With `base` false the entries through the union's bottom (the swept base disk and its
/// rim, which the cutter's puck covers) are not candidates: the answer is then the least
/// of the start (if inside) and the entries through the side, a point of the union at or
/// after the first entry, and the first entry itself whenever that is not on the bottom.
pub fn column_translation_entry(
    line: &Line,
    c0: DVec3,
    c1: DVec3,
    k: DVec3,
    radius: f64,
    base: bool,
) -> Option<Entry> {
    translation_entry_with(line, (c0, c1), k, radius, base, true)
}

/// [`column_translation_entry`]; `quick` rejects the lines that cannot meet the union
/// before the candidates are formed (the answer is the same either way).
fn translation_entry_with(
    line: &Line,
    (c0, c1): (DVec3, DVec3),
    k: DVec3,
    radius: f64,
    base: bool,
    quick: bool,
) -> Option<Entry> {
    let d = c1 - c0;
    let (o, n) = (line.o - c0, line.n);
    // Axial and radial parts: a(s, u) = ak + s·nk − u·dk; P(s, u) = ap + s·np − u·dp.
    let (ak, nk, dk) = (o.dot(k), n.dot(k), d.dot(k));
    let (ap, np, dp) = (o - ak * k, n - nk * k, d - dk * k);
    let scale = 1.0 + radius + o.length() + d.length();
    let tol = FEAS_REL * scale;
    // Quick rejection: the line must come within R of the move's line across it (the slab
    // `|P·f| ≤ R`, `f` across the move in the plane ⟂ k) and above the lower end's base
    // plane, somewhere in `[lo, hi]`.
    let dpl2 = dp.length_squared();
    if quick {
        let (mut lo, mut hi) = (line.lo - tol, line.hi + tol);
        if dpl2 > 1e-300 {
            let f = k.cross(dp) / dpl2.sqrt();
            let (af, nf) = (ap.dot(f), np.dot(f));
            let r = radius + tol;
            if nf != 0.0 {
                let (x, y) = ((-r - af) / nf, (r - af) / nf);
                lo = lo.max(x.min(y));
                hi = hi.min(x.max(y));
            } else if af.abs() > r {
                return None;
            }
        }
        // a(s, u) ≥ 0 for some u: ak + s·nk ≥ min(0, dk).
        let need = dk.min(0.0) - tol;
        if nk > 0.0 {
            lo = lo.max((need - ak) / nk);
        } else if nk < 0.0 {
            hi = hi.min((need - ak) / nk);
        } else if ak < need {
            return None;
        }
        if lo > hi {
            return None;
        }
        // Above the base where the radius allows: the `u` whose columns the part of the line
        // in `[lo, hi]` can come within `R` of lie where the centre passes within `R` plus
        // half that part's radial length of its middle (an interval), and the line must rise
        // above the lowest base among them. Every candidate below is a point of some
        // column of such a `u` (to the tolerances `feasible` allows), so none is lost.
        let pm = ap + (0.5 * (lo + hi)) * np;
        let reach = radius + 2.0 * tol + 0.5 * (hi - lo) * np.length();
        let (u_lo, u_hi) = if dpl2 > 1e-300 {
            let (u1, u2) = roots(dpl2, -pm.dot(dp), pm.length_squared() - reach * reach)?;
            ((u1 - 1e-9).max(0.0), (u2 + 1e-9).min(1.0))
        } else {
            (0.0, 1.0)
        };
        if u_lo > u_hi {
            return None;
        }
        let a_max = ak + nk * if nk > 0.0 { hi } else { lo };
        let base_min = if dk > 0.0 { u_lo * dk } else { u_hi * dk };
        if a_max < base_min - 2.0 * tol {
            return None;
        }
    }
    // Whether some u ∈ [0, 1] puts x(s) in a column.
    let feasible = |s: f64| -> bool {
        let (mut ul, mut uh) = (0.0f64, 1.0f64);
        let a0 = ak + s * nk;
        // a0 − u·dk ≥ −tol.
        if dk > 0.0 {
            uh = uh.min((a0 + tol) / dk);
        } else if dk < 0.0 {
            ul = ul.max((a0 + tol) / dk);
        } else if a0 < -tol {
            return false;
        }
        let p0 = ap + s * np;
        let qa = dp.length_squared();
        let r = radius + tol;
        if qa > 1e-300 {
            let Some((r1, r2)) = roots(qa, -p0.dot(dp), p0.length_squared() - r * r) else {
                return false;
            };
            ul = ul.max(r1);
            uh = uh.min(r2);
        } else if p0.length_squared() > r * r {
            return false;
        }
        ul <= uh + 1e-12
    };
    // At most six candidates (unused slots stay NaN and are skipped); no allocation on
    // this hot path.
    let mut cands = [f64::NAN; 6];
    let mut nc = 0;
    let mut push = |s: f64| {
        cands[nc] = s;
        nc += 1;
    };
    push(line.lo);
    // The columns at the two ends (u fixed at a bound): their own entries.
    let mut best: Option<Entry> = None;
    for c in [c0, c1] {
        if let Some(e) = column_entry(line, c, k, radius, base)
            && best.is_none_or(|b| e.s < b.s)
        {
            best = Some(e);
        }
    }
    // The base plane of a column with u free (a level move's bottom).
    if base && nk != 0.0 {
        push(-ak / nk);
    }
    let dpl = dp.length();
    if dpl > 1e-12 * scale {
        // Radial active, u free: the slab |(ap + s·np)·f| ≤ R across the move's direction.
        let e = dp / dpl;
        let f = k.cross(e);
        let (af, nf) = (ap.dot(f), np.dot(f));
        if nf != 0.0 {
            push((-radius - af) / nf);
            push((radius - af) / nf);
        }
    } else {
        // Along the axis: the cylinder itself.
        if let Some((r1, _)) = roots(np.length_squared(), ap.dot(np), {
            ap.length_squared() - radius * radius
        }) {
            push(r1);
        }
    }
    if base && dk != 0.0 {
        // Axial and radial active: u = (ak + s·nk)/dk, |P|² = R².
        let (p0, p1) = (ap - (ak / dk) * dp, np - (nk / dk) * dp);
        if let Some((r1, r2)) = roots(
            p1.length_squared(),
            p0.dot(p1),
            p0.length_squared() - radius * radius,
        ) {
            push(r1);
            push(r2);
        }
    }
    for s in cands {
        if !(s >= line.lo && s <= line.hi) || best.is_some_and(|b| s >= b.s) {
            continue;
        }
        if feasible(s) {
            best = Some(Entry {
                s,
                normal: normal_at(line, s, (ap, np, dp), (ak, nk, dk), k, radius),
            });
        }
    }
    best
}

/// An outward normal of the union of columns where the line enters it at `s` (after
/// [`column_translation_entry`] found `s` feasible and least): `−n` at `lo`; else from the
/// constraints active at the `u` nearest the middle of the feasible range.
fn normal_at(
    line: &Line,
    s: f64,
    (ap, np, dp): (DVec3, DVec3, DVec3),
    (ak, nk, dk): (f64, f64, f64),
    k: DVec3,
    radius: f64,
) -> DVec3 {
    let n = line.n;
    if s <= line.lo {
        return -n;
    }
    let p0 = ap + s * np;
    let a0 = ak + s * nk;
    // The u where the radial distance is least (clamped), and where the axial one binds.
    let qa = dp.length_squared();
    let u_r = if qa > 1e-300 {
        (p0.dot(dp) / qa).clamp(0.0, 1.0)
    } else {
        0.5
    };
    let p = p0 - u_r * dp;
    let a = a0 - u_r * dk;
    let radial = p.length() >= radius * (1.0 - 1e-9);
    let axial = a <= 1e-9 * (1.0 + radius);
    let g = match (radial, axial) {
        (true, false) => p,
        (false, true) => -k,
        (true, true) => {
            // The sheared bottom rim: the radial gradient less its part along the move,
            // carried by the axial constraint.
            if dk != 0.0 {
                p - (p.dot(dp) / dk) * k
            } else {
                p - radius * k
            }
        }
        (false, false) => -n,
    };
    let g = g.normalize_or(-n);
    if g.dot(n) < 0.0 { g } else { -n }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn v3() -> impl Strategy<Value = DVec3> {
        crate::testkit::v3(4.0)
    }

    proptest! {
        // Cheap cases, and a rejection that is wrong only by a little shows in a few
        // thousand of them.
        #![proptest_config(ProptestConfig::with_cases(20_000))]

        /// The quick rejections never change the answer: over random lines (steep,
        /// shallow, from inside) and moves (level, climbing, along the axis), with and
        /// without the base, the entry is the same with them as without.
        #[test]
        fn quick_rejection_changes_no_entry(
            o in v3(),
            n in v3(),
            c0 in v3(),
            step in prop_oneof![v3(), v3().prop_map(|d| DVec3::new(d.x, d.y, 0.0)),
                                 (-3.0..3.0f64).prop_map(|z| DVec3::new(0.0, 0.0, z))],
            tilt in prop_oneof![Just(DVec3::Z), v3()],
            lo in -3.0..0.0f64,
            len in 0.0..6.0f64,
            radius in 0.5..4.0f64,
            base: bool,
        ) {
            prop_assume!(n.length() > 1e-3 && tilt.length() > 1e-3);
            let line = Line { o, n: n.normalize(), lo, hi: lo + len };
            let k = tilt.normalize();
            let c1 = c0 + step;
            let with = translation_entry_with(&line, (c0, c1), k, radius, base, true);
            let without = translation_entry_with(&line, (c0, c1), k, radius, base, false);
            prop_assert_eq!(with.map(|e| (e.s, e.normal)), without.map(|e| (e.s, e.normal)));
        }
    }

    #[test]
    fn one_pose_side_base_and_inside() {
        let k = DVec3::Z;
        let c = DVec3::ZERO;
        // From the side, above the base.
        let l = Line {
            o: DVec3::new(5.0, 0.0, 2.0),
            n: -DVec3::X,
            lo: 0.0,
            hi: 10.0,
        };
        let e = column_entry(&l, c, k, 3.0, true).unwrap();
        assert!((e.s - 2.0).abs() < 1e-12 && (e.normal - DVec3::X).length() < 1e-12);
        // From below, through the base.
        let l = Line {
            o: DVec3::new(1.0, 0.0, -2.0),
            n: DVec3::Z,
            lo: 0.0,
            hi: 10.0,
        };
        let e = column_entry(&l, c, k, 3.0, true).unwrap();
        assert!((e.s - 2.0).abs() < 1e-12 && (e.normal + k).length() < 1e-12);
        // Starting inside.
        let l = Line {
            o: DVec3::new(1.0, 0.0, 2.0),
            n: DVec3::X,
            lo: 0.0,
            hi: 10.0,
        };
        assert_eq!(column_entry(&l, c, k, 3.0, true).unwrap().s, 0.0);
        // Below the base, going down: never.
        let l = Line {
            o: DVec3::new(1.0, 0.0, -1.0),
            n: -DVec3::Z,
            lo: 0.0,
            hi: 10.0,
        };
        assert!(column_entry(&l, c, k, 3.0, true).is_none());
    }
}
