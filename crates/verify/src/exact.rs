//! Exact first entry of a line into the volume the cutter sweeps along one toolpath move:
//! the refinement of a crossing found on the piecewise-linear imprint surface.
//!
//! # Tool model
//! The cutter's lower part as a solid, the *puck*: every point within `r` (corner radius) of
//! the disk of radius `a` (major radius) centred on the torus centre `c = tip + r·k`,
//! perpendicular to the axis `k`. Below the centre plane this is exactly the cutter's lower
//! surface (flat bottom and corner torus); above it the puck lies inside the real cutter
//! (whose cylinder continues upward), so an entry into the puck is an entry into the cutter.
//! A ball is the sphere of radius `r` about `c`; a flat end mill (`r = 0`) is the disk itself.
//! Above the puck the cutter continues as its *column* ([`crate::column`]: the cylinder of
//! radius `a + r` from the centre plane up, unbounded), entered by
//! [`MoveGeometry::column_entry`]; the imprint surface holds the corner only, so the
//! measurement searches every move's column directly.
//!
//! # Motion model
//! As in [`crate::sweep`]: along move `A → B` the tip moves linearly and the axis is
//! interpolated linearly and renormalised, parameter `u ∈ [0, 1]`.
//!
//! # What is computed
//! For the line `x(s) = o + s·n` (unit `n`), `s ∈ [lo, hi]`, the smallest `s` with `x(s)` in
//! the union of the puck instances — or `lo` when `x(lo)` is already inside. Every answer is
//! a point where the line enters some instance, so it is never below the true first entry
//! into the volume swept by the whole path; for the instance set searched it is exact:
//! - **translation** (equal axes at both ends): the union over the move is convex (the
//!   Minkowski sum of the puck and a segment). Ball: the capsule, in closed form. Otherwise
//!   `F(s) = min_u dist(x(s) − c(u), disk) − r` is convex in `s` and in `u`; Newton on `F`
//!   from the left of its first root (monotone, never overshooting) with the inner minimum
//!   found as the root of its monotone derivative (Illinois regula falsi).
//! - **one pose** (a cap): the same with the segment reduced to a point.
//! - **rotation**: Newton on the continuous imprint surface `m(u, ψ)`: the Eq. 2 point of the
//!   insert at body angle `ψ` on the pose at `u`, with the insert's exact velocity
//!   `dT/du = tip' + r·k' − a·(k'·û)·k` (the body turning by `ω = k × k'`, the rotation-
//!   minimising motion; any spin about the axis leaves the solid of revolution unchanged).
//!   Where that does not converge to an entry point on the cutting quarter, the minimum over
//!   `u` of the one-pose entries is taken by golden-section search: exact where that function
//!   is unimodal on the searched interval (one step either side of the crossing).

use cam_core::{DVec3, Pose};

use crate::imprint::minimal_rotation;

/// A line `o + s·n` searched for `s ∈ [lo, hi]` (mm); `n` is a unit vector.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Line {
    /// Origin (mm).
    pub o: DVec3,
    /// Unit direction.
    pub n: DVec3,
    /// Smallest `s` searched (mm).
    pub lo: f64,
    /// Largest `s` searched (mm).
    pub hi: f64,
}

impl Line {
    fn at(&self, s: f64) -> DVec3 {
        self.o + s * self.n
    }
}

/// Where a line enters the swept volume.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Entry {
    /// Line parameter of the entry (mm).
    pub s: f64,
    /// Outward unit normal of the cutter surface there (`−n` when the line starts inside).
    pub normal: DVec3,
}

/// The cutter's lower part: disk radius `a` and corner radius `r` (mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Puck {
    /// Major radius `a` (mm).
    pub a: f64,
    /// Corner radius `r` (mm).
    pub r: f64,
}

impl Puck {
    /// Distance (mm) from `y` (relative to the torus centre) to the disk of radius `a`
    /// perpendicular to `k`, and the unit direction from the disk's nearest point to `y`
    /// (zero when `y` lies on the disk).
    #[inline]
    fn disk_distance(&self, y: DVec3, k: DVec3) -> (f64, DVec3) {
        let z = y.dot(k);
        let h = y - z * k;
        let rho = h.length();
        if rho <= self.a {
            let d = z.abs();
            let g = if z > 0.0 {
                k
            } else if z < 0.0 {
                -k
            } else {
                DVec3::ZERO
            };
            (d, g)
        } else {
            let e = rho - self.a;
            // Not `hypot`: lengths here are mm-sized (no overflow), and libm's hypot costs
            // several times a square root in this innermost loop.
            let d = (e * e + z * z).sqrt();
            if d > 0.0 {
                (d, (e / rho * h + z * k) / d)
            } else {
                (0.0, DVec3::ZERO)
            }
        }
    }
}

const NEWTON_ITERS: usize = 80;
/// A line point this close to a convex set (mm) is on it.
const ROOT_TOL_MM: f64 = 1e-12;

/// The first root of the convex function `f` on `[lo, hi]` by Newton's method from `lo`
/// (`f` returns value and gradient; the derivative is `gradient · n`). For convex `f` the
/// iterates increase monotonically and stay left of the first root; a non-negative slope with
/// `f > 0` proves there is none. Returns the root and the gradient at the last iterate still
/// outside (`f > 0`): the outward normal there, well defined even for a set without
/// thickness (a flat end mill's disk), where the gradient at the root itself is not.
fn first_root_convex(
    lo: f64,
    hi: f64,
    f: impl FnMut(f64) -> (f64, DVec3),
    n: DVec3,
) -> Option<(f64, DVec3)> {
    first_root_from(lo, lo, hi, f, n)
}

/// [`first_root_convex`] from `start ∈ [lo, hi]`, a point known to lie at or before the
/// first root (`f(start) ≥ 0` and `f` falling there, or `start = lo`). Inside at `start`,
/// the root is `start`: with the normal `−n` at `lo` (the line starts inside), else the
/// gradient there (`start` lies on the surface).
fn first_root_from(
    lo: f64,
    start: f64,
    hi: f64,
    mut f: impl FnMut(f64) -> (f64, DVec3),
    n: DVec3,
) -> Option<(f64, DVec3)> {
    let mut s = start;
    let (mut v, mut g) = f(s);
    // Within the tolerance counts as inside, as for the iterates below (a set without
    // thickness is never at distance exactly 0 from a computed point).
    if v <= ROOT_TOL_MM {
        return Some((start, if start > lo { g } else { -n }));
    }
    for _ in 0..NEWTON_ITERS {
        let slope = g.dot(n);
        if slope.is_nan() || slope >= 0.0 {
            return None;
        }
        let next = s - v / slope;
        if next.is_nan() || next <= s {
            return Some((s, g));
        }
        if next > hi {
            // Check the end: the root may lie just before it.
            let (vh, _) = f(hi);
            return (vh <= 0.0).then_some((hi, g));
        }
        let (nv, ng) = f(next);
        // On the surface to 1e-12 mm: the gradient there is not reliable any more (for a
        // set without thickness it points anywhere), so stop with the last good one.
        if nv <= ROOT_TOL_MM || next - s <= 1e-15 * (1.0 + s.abs()) {
            return Some((next, g));
        }
        (s, v, g) = (next, nv, ng);
    }
    Some((s, g))
}

/// The first `s ∈ [line.lo, line.hi]` where `line` is inside the cylinder of radius `radius`
/// and half-height `half` about centre `c` and axis `k` (a bound of the puck at `c`: radius
/// `a + r`, half-height `r`), or `None`. Closed form: a slab and a quadratic.
pub fn cylinder_entry(line: &Line, c: DVec3, k: DVec3, radius: f64, half: f64) -> Option<f64> {
    let (m, n) = (line.o - c, line.n);
    let (mk, nk) = (m.dot(k), n.dot(k));
    let (mut lo, mut hi) = (line.lo, line.hi);
    if nk != 0.0 {
        let (a, b) = ((-half - mk) / nk, (half - mk) / nk);
        lo = lo.max(a.min(b));
        hi = hi.min(a.max(b));
    } else if mk.abs() > half {
        return None;
    }
    let (mp, np) = (m - mk * k, n - nk * k);
    let (qa, qb, qc) = (
        np.length_squared(),
        mp.dot(np),
        mp.length_squared() - radius * radius,
    );
    if qa > 1e-300 {
        let disc = qb * qb - qa * qc;
        if disc.is_nan() || disc < 0.0 {
            return None;
        }
        let sq = disc.sqrt();
        lo = lo.max((-qb - sq) / qa);
        hi = hi.min((-qb + sq) / qa);
    } else if qc > 0.0 {
        return None;
    }
    (lo <= hi).then_some(lo)
}

/// First entry of `line` into the puck at torus centre `c`, axis `k`.
pub fn puck_entry(line: &Line, puck: &Puck, c: DVec3, k: DVec3) -> Option<Entry> {
    let f = |s: f64| {
        let (d, g) = puck.disk_distance(line.at(s) - c, k);
        (d - puck.r, g)
    };
    first_root_convex(line.lo, line.hi, f, line.n).map(|(s, normal)| Entry { s, normal })
}

/// The two roots of `qa·t² + 2·qb·t + qc = 0`, ordered, if real (`qa > 0`), computed
/// without cancellation.
pub(crate) fn quadratic_roots(qa: f64, qb: f64, qc: f64) -> Option<(f64, f64)> {
    let disc = qb * qb - qa * qc;
    if disc.is_nan() || disc < 0.0 || qa <= 0.0 {
        return None;
    }
    let q = -qb - qb.signum() * disc.sqrt();
    let (r1, r2) = if q != 0.0 {
        (q / qa, qc / q)
    } else {
        (0.0, 0.0)
    };
    Some((r1.min(r2), r1.max(r2)))
}

/// The interval of `s` where `|o + s·n − c|² ≤ r²`, if any.
fn sphere_interval(o: DVec3, n: DVec3, c: DVec3, r: f64) -> Option<(f64, f64)> {
    let m = o - c;
    quadratic_roots(1.0, m.dot(n), m.length_squared() - r * r)
}

/// Relative widening of [`misses_capsule_hull`]'s cylinder and slab: far beyond the
/// rounding of the capsule's own quadratics, so no segment it turns away could have been
/// found entering the capsule by them.
const HULL_WIDEN: f64 = 1e-9;

/// Whether the segment `lo..hi` of `line` surely misses the capsule of radius `r` about
/// `c0 c1`: it misses the infinite cylinder of radius `r` about the centres' line, or the
/// slab of the capsule across that line, both widened by [`HULL_WIDEN`]. One quadratic, for
/// the many segments that pass near a move's box but not through its capsule. `false` means
/// nothing (the capsule itself is searched). The cylinder's parts are computed again by the
/// capsule's own search when this passes: handing them over in a struct cost more
/// instructions than recomputing them (callgrind, dome ball: 795 M against 874–908 M in
/// `capsule_entry`), as most segments leave by the slab first.
fn misses_capsule_hull(line: &Line, c0: DVec3, c1: DVec3, r: f64) -> bool {
    let d = c1 - c0;
    let dd = d.length_squared();
    if dd == 0.0 {
        return false;
    }
    let (o, n) = (line.o, line.n);
    let dl = dd.sqrt();
    let w = r * (1.0 + HULL_WIDEN) + HULL_WIDEN * dl;
    // Slab −w ≤ (x − c0)·d/|d| ≤ |d| + w: its interval in s.
    let (p0, pn) = ((o - c0).dot(d) / dl, n.dot(d) / dl);
    let (mut lo, mut hi) = (line.lo, line.hi);
    if pn != 0.0 {
        let (ta, tb) = ((-w - p0) / pn, (dl + w - p0) / pn);
        lo = lo.max(ta.min(tb));
        hi = hi.min(ta.max(tb));
    } else if p0 < -w || p0 > dl + w {
        return true;
    }
    if lo > hi {
        return true;
    }
    // Cylinder: |m⊥ + s·n⊥|² ≤ w².
    let (qa, qb, qc) = across_quadratic(o - c0, n, d / dl, w);
    if qa <= 1e-300 {
        return qc > 0.0;
    }
    let disc = qb * qb - qa * qc;
    if disc < 0.0 {
        return true;
    }
    let sq = disc.sqrt();
    let (c_in, c_out) = ((-qb - sq) / qa, (-qb + sq) / qa);
    c_out < lo || c_in > hi
}

/// First entry of `line` into the capsule of radius `r` about the segment `c0 c1` (a ball
/// swept along a straight move).
pub fn capsule_entry(line: &Line, c0: DVec3, c1: DVec3, r: f64) -> Option<Entry> {
    capsule_entry_with(line, c0, c1, r, true)
}

/// [`capsule_entry`], with (`quick`) or without the hull rejection first.
///
/// The capsule lies in its infinite cylinder: where the line enters the cylinder at or
/// after the segment's start at a point between the centres' planes, that point is the
/// entry, and the two spheres' intervals are not computed (most of a ball's entries);
/// otherwise the least entry of the three parts ([`capsule_parts_entry`]).
fn capsule_entry_with(line: &Line, c0: DVec3, c1: DVec3, r: f64, quick: bool) -> Option<Entry> {
    if quick && misses_capsule_hull(line, c0, c1, r) {
        return None;
    }
    let side = cylinder_side(line, c0, c1, r);
    if let Some(c) = &side
        && c.across
    {
        let Some((s, _)) = c.inside else {
            // The line misses the cylinder, and so the capsule.
            return None;
        };
        // Where along the centres' run the line enters (times |d|²).
        let (d, n) = (c1 - c0, line.n);
        let t = c.m.dot(d) + s * n.dot(d);
        if s >= line.lo && (0.0..=c.dd).contains(&t) {
            return (s <= line.hi).then(|| {
                let x = line.o + s * n - c0;
                let normal = (x - x.dot(c.dh) * c.dh).normalize_or(-n);
                Entry { s, normal }
            });
        }
    }
    capsule_parts_entry(line, c0, c1, r, side.as_ref())
}

/// The quadratic `qa·s² + 2·qb·s + qc` whose sign says where the line `m + s·n` (from a
/// point of the axis) lies within `r` of the axis along the unit `dh`: its parts across
/// the axis, squared.
#[inline]
fn across_quadratic(m: DVec3, n: DVec3, dh: DVec3, r: f64) -> (f64, f64, f64) {
    let mp = m - m.dot(dh) * dh;
    let np = n - n.dot(dh) * dh;
    (np.length_squared(), mp.dot(np), mp.length_squared() - r * r)
}

/// The infinite cylinder of radius `r` about the centres' line `c0`–`c1` (`None` for a
/// point-like capsule), seen by `line`.
struct CylinderSide {
    /// `|c1 − c0|²` and the unit axis.
    dd: f64,
    dh: DVec3,
    /// The line's origin from `c0`.
    m: DVec3,
    /// The line runs across the axis (not along it, to 1e-300 in the squared sine).
    across: bool,
    /// Where the line is inside the cylinder: `(in, out)` along it (all of it, unbounded,
    /// for a line along the axis inside).
    inside: Option<(f64, f64)>,
}

fn cylinder_side(line: &Line, c0: DVec3, c1: DVec3, r: f64) -> Option<CylinderSide> {
    let (o, n) = (line.o, line.n);
    let d = c1 - c0;
    let dd = d.length_squared();
    if dd <= 0.0 {
        return None;
    }
    let dh = d / dd.sqrt();
    let m = o - c0;
    let (qa, qb, qc) = across_quadratic(m, n, dh, r);
    let across = qa > 1e-300;
    let inside = if across {
        let disc = qb * qb - qa * qc;
        (disc >= 0.0).then(|| {
            let sq = disc.sqrt();
            ((-qb - sq) / qa, (-qb + sq) / qa)
        })
    } else {
        (qc <= 0.0).then_some((f64::NEG_INFINITY, f64::INFINITY))
    };
    Some(CylinderSide {
        dd,
        dh,
        m,
        across,
        inside,
    })
}

/// [`capsule_entry`] from the capsule's three parts (two spheres and the cylinder between
/// the centres' planes, `side` as [`cylinder_side`] gives it), the least entry of the three.
fn capsule_parts_entry(
    line: &Line,
    c0: DVec3,
    c1: DVec3,
    r: f64,
    side: Option<&CylinderSide>,
) -> Option<Entry> {
    let (o, n) = (line.o, line.n);
    let mut best: Option<(f64, DVec3)> = None;
    let mut take = |s_in: f64, s_out: f64, normal_at: &dyn Fn(f64) -> DVec3| {
        if s_out < line.lo || s_in > line.hi || s_in > s_out {
            return;
        }
        let s = s_in.max(line.lo);
        if best.is_none_or(|(b, _)| s < b) {
            let nm = if s_in < line.lo { -n } else { normal_at(s) };
            best = Some((s, nm));
        }
    };
    for c in [c0, c1] {
        if let Some((a, b)) = sphere_interval(o, n, c, r) {
            take(a, b, &|s| ((o + s * n - c) / r).normalize_or(-n));
        }
    }
    if let Some(CylinderSide {
        dd,
        dh,
        m,
        inside: Some((c_in, c_out)),
        ..
    }) = side
    {
        // Slab 0 ≤ (x − c0)·d ≤ |d|².
        let d = c1 - c0;
        let (p0, pn) = (m.dot(d), n.dot(d));
        let (t_in, t_out) = if pn.abs() > 1e-300 {
            let (ta, tb) = (-p0 / pn, (dd - p0) / pn);
            (ta.min(tb), ta.max(tb))
        } else if (0.0..=*dd).contains(&p0) {
            (f64::NEG_INFINITY, f64::INFINITY)
        } else {
            (1.0, -1.0)
        };
        let (s_in, s_out) = (c_in.max(t_in), c_out.min(t_out));
        take(s_in, s_out, &|s| {
            let x = o + s * n - c0;
            (x - x.dot(*dh) * *dh).normalize_or(-n)
        });
    }
    best.map(|(s, normal)| Entry { s, normal })
}

/// The inner minimisation along a move stops when a step moves the point by at most this
/// much (mm): the distance is then exact to rounding (it is quadratic about its minimum),
/// and the direction to within this over the distance (which matters for a flat end mill's
/// disk, where Newton's last iterate outside lies a hair from it).
const STEP_TOL_MM: f64 = 1e-13;

/// The minimum over `u ∈ [0, 1]` of `dist(y − u·d, disk)` (disk about the origin, axis `k`)
/// with the minimiser and the gradient direction there, searched from `guess` (a nearby
/// minimiser, e.g. the previous one along a line; any value in `[0, 1]` is correct).
///
/// The distance `D` is convex in `u`, so `φ = D²/2` is too, with `φ' = e·ρ' − z·z_d` and
/// `φ'' = ρ'² + e·ρ'' + z_d²` (`z = y·k − u·z_d` the axial offset, `ρ` the radial one,
/// `e = ρ − a` where positive, else 0). Newton's method on `φ'` kept inside a bracket of the
/// minimiser (bisection when a step leaves it) converges quadratically; it stops when a step
/// moves the point by at most [`STEP_TOL_MM`] along the move.
fn segment_disk_min(puck: &Puck, y: DVec3, d: DVec3, k: DVec3, guess: f64) -> (f64, DVec3, f64) {
    let at = |u: f64| puck.disk_distance(y - u * d, k);
    let dd = d.length_squared();
    if dd == 0.0 {
        let (dist, g) = at(0.0);
        return (dist, g, 0.0);
    }
    let dl = dd.sqrt();
    let (z0, dz) = (y.dot(k), d.dot(k));
    // A level move (d ⟂ k): the axial offset is the same for every u and the distance
    // grows with the radial one, so the minimiser is the nearest point of the segment in
    // the disk's plane.
    if dz == 0.0 {
        let u = ((y - z0 * k).dot(d) / dd).clamp(0.0, 1.0);
        let (dist, g) = at(u);
        return (dist, g, u);
    }
    let (h0, dh) = (y - z0 * k, d - dz * k);
    let dh2 = dh.length_squared();
    let a = puck.a;
    // φ'(u), φ''(u).
    let deriv = |u: f64| -> (f64, f64) {
        let z = z0 - u * dz;
        let h = h0 - u * dh;
        let rho = h.length();
        if rho <= a {
            (-z * dz, dz * dz)
        } else {
            let rp = -h.dot(dh) / rho;
            let rpp = (dh2 - rp * rp).max(0.0) / rho;
            let e = rho - a;
            (e * rp - z * dz, rp * rp + e * rpp + dz * dz)
        }
    };
    if a == 0.0 {
        // The distance to a point: the segment's nearest point.
        let u = (y.dot(d) / dd).clamp(0.0, 1.0);
        let (dist, g) = at(u);
        return (dist, g, u);
    }
    // φ is smooth except where the segment crosses the rim's cylinder (ρ = a); inside it
    // φ = z²/2, whose slope is known in closed form. Bracket the minimiser in one smooth
    // piece: Newton then converges quadratically (across the kink, where φ'' jumps, it
    // would crawl by bisection).
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    if let Some((t1, t2)) = disk_interval(h0, -dh, a) {
        let (u1, u2) = (t1.max(0.0), t2.min(1.0));
        if u1 <= u2 {
            let slope = |u: f64| -(z0 - u * dz) * dz;
            if slope(u1) >= 0.0 {
                hi = u1;
            } else if slope(u2) <= 0.0 {
                lo = u2;
            } else {
                // The axial offset vanishes within the rim: the segment meets the disk.
                let u = (z0 / dz).clamp(u1, u2);
                let (dist, g) = at(u);
                return (dist, g, u);
            }
        }
    }
    let (p_lo, p_hi) = (lo, hi);
    // φ' at the bracket's ends once known (< 0 at `lo`, > 0 at `hi`), NaN before: as
    // `Option`s these cost the dome's bull program 0.5 % more instructions.
    let (mut f_lo, mut f_hi) = (f64::NAN, f64::NAN);
    let mut u = if guess.is_finite() {
        guess.clamp(lo, hi)
    } else {
        0.5 * (lo + hi)
    };
    for _ in 0..100 {
        let (f1, f2) = deriv(u);
        if f1 == 0.0 || f1.is_nan() {
            break;
        }
        if f1 > 0.0 {
            (hi, f_hi) = (u, f1);
        } else {
            (lo, f_lo) = (u, f1);
        }
        if hi <= lo {
            // At an end of the piece with the slope pointing out of it.
            u = lo;
            break;
        }
        let mut next = u - f1 / f2;
        // Converged: a step below the tolerance ends the search, even where it lands on the
        // bracket's end just set to u (falling back to the bracket would start over).
        if next.is_finite() && (next - u).abs() * dl <= STEP_TOL_MM {
            u = next.clamp(lo, hi);
            break;
        }
        if !(next > lo && next < hi) {
            // Newton leaves the bracket: an end of the piece not yet tried, else the secant
            // through the bracket's ends (the root is often right at one of them), else
            // its middle.
            next = if f_lo.is_nan() && next <= lo {
                p_lo
            } else if f_hi.is_nan() && next >= hi {
                p_hi
            } else if !(f_lo.is_nan() || f_hi.is_nan()) {
                lo - f_lo * (hi - lo) / (f_hi - f_lo)
            } else {
                0.5 * (lo + hi)
            };
            if !(next >= lo && next <= hi) {
                next = 0.5 * (lo + hi);
            }
        }
        let step = (next - u).abs() * dl;
        u = next;
        if step <= STEP_TOL_MM || (hi - lo) * dl <= STEP_TOL_MM {
            break;
        }
    }
    let (dist, g) = at(u);
    (dist, g, u)
}

/// First entry of `line` into the puck swept along the straight, non-rotating move of the
/// torus centre `c0 → c1` with axis `k`: in closed form for a ball ([`capsule_entry`]) and a
/// flat end mill ([`disk_translation_entry`]), otherwise by [`convex_translation_entry`].
pub fn translation_entry(
    line: &Line,
    puck: &Puck,
    c0: DVec3,
    c1: DVec3,
    k: DVec3,
) -> Option<Entry> {
    if puck.a == 0.0 {
        // Without the hull's rejection: the searches call this for moves whose capsule
        // their own closed-form tests did not turn away, and most of those are entered
        // (201 k of 284 k on the dome's ball program): dome ball 2.62 -> 2.57 G.
        return capsule_entry_with(line, c0, c1, puck.r, false);
    }
    if puck.r == 0.0 {
        return disk_translation_entry(line, puck.a, c0, c1, k);
    }
    convex_translation_entry(line, puck, c0, c1, k)
}

/// The parameter interval where `|w0 + t·w1| ≤ a` (unbounded when `w1 = 0` and `|w0| ≤ a`).
fn disk_interval(w0: DVec3, w1: DVec3, a: f64) -> Option<(f64, f64)> {
    let qa = w1.length_squared();
    let qc = w0.length_squared() - a * a;
    if qa == 0.0 {
        return (qc <= 0.0).then_some((f64::NEG_INFINITY, f64::INFINITY));
    }
    quadratic_roots(qa, w0.dot(w1), qc)
}

/// First entry of `line` into the disk of radius `a` (centre `c0`, axis `k`) swept along the
/// straight move `c0 → c1`: a flat end mill's translation, in closed form. The swept set is
/// the sheared cylinder `{c0 + u·d + h : u ∈ [0, 1], h ⟂ k, |h| ≤ a}` (flat when the move is
/// level); a line meets it where the axial coordinate puts it at some `u ∈ [0, 1]` and the
/// remaining radial offset `w` is at most `a` — a quadratic in one parameter. The line is
/// parametrised by `u` where the move climbs less than the line does over the move's length,
/// else by `s`, so that neither parametrisation amplifies rounding. Returns the entry with the
/// outward normal there (a cap's `±k`, the mantle's gradient, `−n` when `x(lo)` is inside;
/// for a level move, the side of the disk the line comes from).
pub fn disk_translation_entry(
    line: &Line,
    a: f64,
    c0: DVec3,
    c1: DVec3,
    k: DVec3,
) -> Option<Entry> {
    let (o, n) = (line.o, line.n);
    let d = c1 - c0;
    // A climb within the root tolerance is level: the set is then within that distance of
    // the flat one, and the mantle's orientation is not computable from rounding noise.
    let dz = Some(d.dot(k))
        .filter(|z| z.abs() > ROOT_TOL_MM)
        .unwrap_or(0.0);
    let dh = d - dz * k;
    let m = o - c0;
    let (q0, nk) = (m.dot(k), n.dot(k));
    let (mh, nh) = (m - q0 * k, n - nk * k);
    // Which bound is active at the entry.
    #[derive(Clone, Copy)]
    enum At {
        Cap0,
        Cap1,
        Mantle,
    }
    let (s_in, s_out, at) = if nk != 0.0 && dz.abs() <= nk.abs() * d.length() {
        // s(u) = (u·dz − q0)/nk; w(u) = mh + s(u)·nh − u·dh.
        let w0 = mh - (q0 / nk) * nh;
        let w1 = (dz / nk) * nh - dh;
        let (t1, t2) = disk_interval(w0, w1, a)?;
        let (u1, u2) = (t1.max(0.0), t2.min(1.0));
        if u1 > u2 {
            return None;
        }
        let s_of = |u: f64| (u * dz - q0) / nk;
        if dz / nk >= 0.0 {
            let at = if t1 <= 0.0 { At::Cap0 } else { At::Mantle };
            (s_of(u1), s_of(u2), at)
        } else {
            let at = if t2 >= 1.0 { At::Cap1 } else { At::Mantle };
            (s_of(u2), s_of(u1), at)
        }
    } else {
        if dz == 0.0 {
            // A level move and a line parallel to the disk: only lines in its plane meet it.
            return None;
        }
        // u(s) = (q0 + s·nk)/dz; w(s) = mh + s·nh − u(s)·dh.
        let w0 = mh - (q0 / dz) * dh;
        let w1 = nh - (nk / dz) * dh;
        let (t1, t2) = disk_interval(w0, w1, a)?;
        // The slab 0 ≤ u(s) ≤ 1.
        let (slab, cap_in) = if nk != 0.0 {
            let (sa, sb) = (-q0 / nk, (dz - q0) / nk);
            if sa <= sb {
                ((sa, sb), At::Cap0)
            } else {
                ((sb, sa), At::Cap1)
            }
        } else if (0.0..=1.0).contains(&(q0 / dz)) {
            ((f64::NEG_INFINITY, f64::INFINITY), At::Mantle)
        } else {
            return None;
        };
        let at = if slab.0 >= t1 { cap_in } else { At::Mantle };
        (t1.max(slab.0), t2.min(slab.1), at)
    };
    if s_in.is_nan() || s_out.is_nan() || s_in > s_out || s_out < line.lo || s_in > line.hi {
        return None;
    }
    if s_in < line.lo {
        return Some(Entry {
            s: line.lo,
            normal: -n,
        });
    }
    let sk = if dz != 0.0 { dz.signum() } else { -nk.signum() };
    let normal = match at {
        _ if dz == 0.0 => -nk.signum() * k,
        At::Cap0 => -sk * k,
        At::Cap1 => sk * k,
        At::Mantle => {
            let x = m + s_in * n;
            let u = x.dot(k) / dz;
            let w = x - x.dot(k) * k - u * dh;
            // ∇|w|² ∝ w − (w·dh/dz)·k, scaled by |dz| to stay finite.
            (dz.abs() * w - sk * w.dot(dh) * k).normalize_or(-n)
        }
    };
    Some(Entry { s: s_in, normal })
}

/// How far outside the swept disk (mm) a segment's top must lie for the tangent there to
/// start a bull's Newton search (see [`convex_entry`]).
const TANGENT_MIN_MM: f64 = 1e-6;

/// First entry of `line` into the puck swept along the straight move `c0 → c1` (axis `k`)
/// by Newton's method on the convex distance to the swept disk (see the module docs); any
/// puck, exact to 1e-12 mm.
pub fn convex_translation_entry(
    line: &Line,
    puck: &Puck,
    c0: DVec3,
    c1: DVec3,
    k: DVec3,
) -> Option<Entry> {
    convex_entry(line, puck, (c0, c1), k, true)
}

/// [`convex_translation_entry`] without the test at the segment's top (`top = false`):
/// for a line searched to its far end, where it seldom lies inside the puck or passes it
/// falling (a seed's move, tried on a vector's whole length), that test only adds work.
/// The entry is the same but where the top test would have started Newton's method nearer
/// the root (then within 1e-12 mm).
pub(crate) fn convex_entry(
    line: &Line,
    puck: &Puck,
    (c0, c1): (DVec3, DVec3),
    k: DVec3,
    top: bool,
) -> Option<Entry> {
    let d = c1 - c0;
    if let Some(e) = bottom_entry(line, puck, c0, c1, k) {
        return Some(e);
    }
    // The distance to the swept puck is convex along the line: outside at `hi` and not
    // rising there, the line is outside over the whole segment (it passes the puck beyond
    // `hi`, or enters it later). One evaluation in place of the walk up from `lo`, for the
    // many moves a search tries below a bound they cannot beat.
    //
    // Inside at `hi` with the distance falling there, the tangent there (which the convex
    // distance never passes below) reaches `r` at or before the first root: Newton's
    // method starts there, with the minimiser found at `hi`, instead of at `lo`. Only where
    // `hi` lies outside the swept disk itself, by more than [`TANGENT_MIN_MM`]: inside it
    // the distance is 0 all around and the direction to the nearest disk no gradient
    // (a line through the disk read its second root: the tests' bull case 16), and near it
    // that direction comes from a vector too short to trust. The start backs off by a
    // millionth of the tangent's run for rounding.
    let (mut start, mut guess) = (line.lo, 0.5);
    if top && line.hi.is_finite() && line.hi > line.lo {
        let (dist, g, u) = segment_disk_min(puck, line.at(line.hi) - c0, d, k, 0.5);
        let (v, slope) = (dist - puck.r, g.dot(line.n));
        if v > ROOT_TOL_MM && slope <= 0.0 {
            return None;
        }
        if v <= 0.0 && slope < 0.0 && dist > TANGENT_MIN_MM {
            let run = v / slope;
            let s = line.hi - run * (1.0 + 1e-6) - 1e-9;
            if s > line.lo {
                (start, guess) = (s, u);
            }
        }
    }
    // Along the line the minimiser moves little from one Newton iterate to the next.
    let f = |s: f64| {
        let (dist, g, u) = segment_disk_min(puck, line.at(s) - c0, d, k, guess);
        guess = u;
        (dist - puck.r, g)
    };
    first_root_from(line.lo, start, line.hi, f, line.n).map(|(s, normal)| Entry { s, normal })
}

/// First entry of `line` into the puck swept along the straight move of the torus centre
/// `c0 → c1` with axis `k`, for a line running along the axis (`line.n == k`, bit for bit,
/// as on a 3-axis program's floors): the swept puck's lower envelope over the line's foot,
/// in place of [`convex_entry`]'s Newton walk, whose every step is a minimisation itself.
///
/// At pose `u` the puck holds the line from `φ(ρ(u))` below the centre to as far above,
/// where `ρ(u)` is the foot's distance from the axis through `c(u)`, and `φ(ρ) = r` over
/// the disk (`ρ ≤ a`), `√(r² − (ρ − a)²)` under the corner (`ρ ≤ a + r`). The entry is the
/// least height `E = min_u c(u)·k − φ(ρ(u))`, a convex minimum: `ρ` is convex in `u`, and
/// `−φ` convex and rising in `ρ`. Its derivative is continuous (disk and corner meet level).
/// - Over the disk with a climbing move, the least is at or just beyond the disk's end the
///   move falls towards: within `c = r·dz²/(2ρ'²)` of that end's height (`ρ` lies above its
///   tangent there, so `r − φ ≥ ρ'²δ²/(2r)` a distance `δ` on, against the climb `δ·dz`),
///   and at most at its height at the pose where those balance. On a floor whose passes
///   climb a fraction of a micrometre over their length, `c` is far below 1e-13 mm, which
///   ends the search in closed form; else Newton's method finishes it.
/// - Elsewhere, safeguarded Newton on the derivative (its ends `∓∞` on the corner's rim),
///   after a bound from below: the lower centre less `φ` at the foot's least distance from
///   the centres' track.
///
/// `None` where this cannot decide, left to [`convex_entry`]: the line is not along `k`, the
/// puck is not a bull's, or the envelope lies at or below the segment's start plus 1e-9 mm
/// (the start may lie inside, which the general search answers by its own conventions).
/// `Some(None)`: no entry within `lo..=hi`.
pub(crate) fn axial_entry(
    line: &Line,
    puck: &Puck,
    c0: DVec3,
    c1: DVec3,
    k: DVec3,
) -> Option<Option<Entry>> {
    if line.n != k || !(line.lo.is_finite() && line.hi.is_finite()) {
        return None;
    }
    let (a, r) = (puck.a, puck.r);
    if !(a > 0.0 && r > 0.0) {
        return None;
    }
    let d = c1 - c0;
    let m = line.o - c0;
    let (h0, dh) = (across(m, k), across(d, k));
    let (mz, dz) = (m.dot(k), d.dot(k));
    let dh2 = dh.length_squared();
    let scale = 1.0 + mz.abs() + dz.abs() + a + r;
    // Whether an envelope height (relative to `c0`) no lower than `low` lies above the
    // segment, by more than rounding.
    let above = |low: f64| low - mz > line.hi + 1e-12 * scale;
    let rho_min = {
        let t = if dh2 > 0.0 {
            (h0.dot(dh) / dh2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (h0 - t * dh).length()
    };
    let e_min = rho_min - a;
    if e_min > r {
        return Some(None);
    }
    let phi_max = if e_min <= 0.0 {
        r
    } else {
        (r * r - e_min * e_min).sqrt()
    };
    if above(dz.min(0.0) - phi_max) {
        return Some(None);
    }
    let clip = |(t1, t2): (f64, f64)| {
        let (u1, u2) = (t1.max(0.0), t2.min(1.0));
        (u1 <= u2).then_some((t1, t2, u1, u2))
    };
    // The corner's height under the line at `u` (`φ`), and `f'`, `f''` of
    // `f(u) = u·dz − φ(ρ(u))` there.
    let phi_at = |u: f64| {
        let e = (h0 - u * dh).length() - a;
        if e <= 0.0 {
            Some(r)
        } else {
            let p2 = r * r - e * e;
            (p2 >= 0.0).then(|| p2.sqrt())
        }
    };
    let deriv = |u: f64| -> (f64, f64) {
        let h = h0 - u * dh;
        let rho = h.length();
        let e = rho - a;
        if e <= 0.0 {
            return (dz, 0.0);
        }
        let rp = -h.dot(dh) / rho;
        let phi2 = r * r - e * e;
        if phi2 <= 0.0 {
            // On the rim, where the corner stands vertical.
            let inf = if rp < 0.0 {
                f64::NEG_INFINITY
            } else {
                f64::INFINITY
            };
            return (inf, f64::INFINITY);
        }
        let phi = phi2.sqrt();
        let rpp = (dh2 - rp * rp).max(0.0) / rho;
        (
            dz + e / phi * rp,
            r * r / (phi2 * phi) * rp * rp + e / phi * rpp,
        )
    };
    // Where the least lies: a pose known, or a piece of the corner's poses to search (its
    // ends, whether each is the rim's, where its derivative is infinite).
    enum Least {
        At(f64),
        Within(f64, f64, bool, bool),
    }
    let flat = if e_min <= 0.0 {
        disk_interval(h0, -dh, a).and_then(clip)
    } else {
        None
    };
    let mut start = if dh2 > 0.0 {
        h0.dot(dh) / dh2
    } else {
        f64::NAN
    };
    let piece = match flat {
        Some((_, _, v1, _)) if dz == 0.0 => Least::At(v1),
        Some((t1, t2, v1, v2)) => {
            let up = dz > 0.0;
            let end = if up { v1 } else { v2 };
            if (up && t1 <= 0.0) || (!up && t2 >= 1.0) {
                // The disk reaches past the move's end: its lowest pose is the move's.
                Least::At(end)
            } else {
                let h = h0 - end * dh;
                let rp = h.dot(dh) / h.length();
                let e_flat = end * dz - r;
                let c = 0.5 * r * dz * dz / (rp * rp);
                if above(e_flat - c) {
                    return Some(None);
                }
                let du = r * dz.abs() / (rp * rp);
                start = if up { end - du } else { end + du };
                let at_start = (0.0..=1.0)
                    .contains(&start)
                    .then(|| phi_at(start))
                    .flatten()
                    .map(|phi| start * dz - phi);
                match at_start {
                    Some(v) if v <= e_flat && v - (e_flat - c) <= 1e-13 => Least::At(start),
                    _ if c <= 1e-13 => Least::At(end),
                    _ => {
                        let (t1, t2, u1, u2) = disk_interval(h0, -dh, a + r).and_then(clip)?;
                        if up {
                            Least::Within(u1, end, t1 >= 0.0, false)
                        } else {
                            Least::Within(end, u2, false, t2 <= 1.0)
                        }
                    }
                }
            }
        }
        None => {
            let Some((t1, t2, u1, u2)) = disk_interval(h0, -dh, a + r).and_then(clip) else {
                return Some(None);
            };
            if above((u1 * dz).min(u2 * dz) - phi_max) {
                return Some(None);
            }
            Least::Within(u1, u2, t1 >= 0.0, t2 <= 1.0)
        }
    };
    let u = match piece {
        Least::At(u) => u,
        Least::Within(lo, hi, _, _) if lo >= hi => lo,
        Least::Within(lo, hi, rim_lo, rim_hi) => {
            // f' rises across the piece: below 0 at a rim's start, above at its end, and
            // dz at the disk's end, which points the right way there.
            if !rim_lo && flat.is_none_or(|_| dz > 0.0) && deriv(lo).0 >= 0.0 {
                lo
            } else if !rim_hi && flat.is_none_or(|_| dz < 0.0) && deriv(hi).0 <= 0.0 {
                hi
            } else {
                let (mut blo, mut bhi) = (lo, hi);
                let dl = dh2.sqrt().max(dz.abs());
                let mut u = start;
                if !(u > lo && u < hi) {
                    u = 0.5 * (lo + hi);
                }
                for _ in 0..100 {
                    let (f1, f2) = deriv(u);
                    if f1 == 0.0 || f1.is_nan() {
                        break;
                    }
                    if f1 > 0.0 {
                        bhi = u;
                    } else {
                        blo = u;
                    }
                    let mut next = u - f1 / f2;
                    // Converged: a step below the tolerance, even onto the bracket's end.
                    if next.is_finite() && (next - u).abs() * dl <= STEP_TOL_MM {
                        u = next.clamp(blo, bhi);
                        break;
                    }
                    if !(next > blo && next < bhi) {
                        next = 0.5 * (blo + bhi);
                    }
                    let step = (next - u).abs() * dl;
                    u = next;
                    if step <= STEP_TOL_MM || (bhi - blo) * dl <= STEP_TOL_MM {
                        break;
                    }
                }
                u
            }
        }
    };
    let h = h0 - u * dh;
    let rho = h.length();
    let e = rho - a;
    let (phi, normal) = if e <= 0.0 {
        (r, -k)
    } else {
        let phi = (r * r - e * e).max(0.0).sqrt();
        // From the disk's nearest point to the envelope's: `e` outwards, `φ` down.
        let w = (e / rho) * h - phi * k;
        (phi, w.normalize_or(-k))
    };
    let s = u * dz - phi - mz;
    if s.is_nan() || s <= line.lo + 1e-9 {
        return None;
    }
    Some((s <= line.hi).then_some(Entry { s, normal }))
}

/// The entry of `line` through the flat bottom of the puck swept by a translation (centres
/// `c0 → c1`, axis `k`), in closed form, where it is one: no point of the swept puck lies
/// more than `r` below the lower centre along `k`, so nothing of it lies below the plane
/// `x·k = min(c0·k, c1·k) − r`, and the lower pose's bottom disk (radius `a` in that plane;
/// for a level move, the stadium the disk sweeps) belongs to it. A line rising along `k`
/// that crosses the plane within `lo..=hi` inside that face enters there, with the normal
/// `−k`. `None` when it does not (the line enters elsewhere, or not at all: left to the
/// search). On a level floor a bull's vectors meet many moves' bottoms at the same height;
/// each was a Newton walk.
fn bottom_entry(line: &Line, puck: &Puck, c0: DVec3, c1: DVec3, k: DVec3) -> Option<Entry> {
    let nk = line.n.dot(k);
    if nk <= 0.0 {
        return None;
    }
    let (z0, z1) = (c0.dot(k), c1.dot(k));
    let s = (z0.min(z1) - puck.r - line.o.dot(k)) / nk;
    if !(s >= line.lo && s <= line.hi) {
        return None;
    }
    let p = line.at(s);
    let w = if z0 == z1 {
        // The stadium: the offset from the nearest point of the centres' segment.
        let (h, d) = (across(p - c0, k), across(c1 - c0, k));
        h - from_segment(h, DVec3::ZERO, d, inv_or_zero(d.length_squared()))
    } else {
        across(p - if z0 < z1 { c0 } else { c1 }, k)
    };
    (w.length_squared() <= puck.a * puck.a).then_some(Entry { s, normal: -k })
}

/// The part of `x` across the unit axis `k`.
#[inline]
pub(crate) fn across(x: DVec3, k: DVec3) -> DVec3 {
    x - x.dot(k) * k
}

/// `1/x`, or 0 for `x = 0` (a segment of no length, for [`from_segment`]).
pub(crate) fn inv_or_zero(x: f64) -> f64 {
    if x > 0.0 { 1.0 / x } else { 0.0 }
}

/// The point of the segment `c0 + u·d` (`u ∈ [0, 1]`) nearest to `q`; `inv_dd` is `1/|d|²`
/// ([`inv_or_zero`]: `c0` for a point).
#[inline]
pub(crate) fn from_segment(q: DVec3, c0: DVec3, d: DVec3, inv_dd: f64) -> DVec3 {
    c0 + ((q - c0).dot(d) * inv_dd).clamp(0.0, 1.0) * d
}

/// Whether a plane separates the segment `lo..hi` of `line` from the puck swept by a
/// translation from centre `c0` to `c1` (axis `k`), by more than a margin for rounding
/// (1e-9 of the coordinates' size, and 1e-9 mm): a sufficient test in closed form, with no
/// Newton solve. The plane's normal `w` runs to the segment's top from the nearest point
/// of the disk about the centres' point nearest to it (near the swept disk's nearest
/// point); the swept puck reaches `max(c0·w, c1·w) + a·|w⊥k| + r` along `w` (its support
/// function: the two disks' hull grown by `r`), the segment no lower than the least of its
/// ends' `·w`.
pub(crate) fn separated_by_plane(line: &Line, puck: &Puck, c0: DVec3, c1: DVec3, k: DVec3) -> bool {
    if !(line.lo.is_finite() && line.hi.is_finite()) {
        return false;
    }
    let q = line.at(line.hi);
    let d = c1 - c0;
    let (_, w) = puck.disk_distance(
        q - from_segment(q, c0, d, inv_or_zero(d.length_squared())),
        k,
    );
    if w == DVec3::ZERO {
        return false;
    }
    let wk = w.dot(k);
    let reach = c0.dot(w).max(c1.dot(w)) + puck.a * (1.0 - wk * wk).max(0.0).sqrt() + puck.r;
    let nw = line.n.dot(w);
    let low = line.o.dot(w) + (line.lo * nw).min(line.hi * nw);
    let scale = q.abs().max(c0.abs()).max(c1.abs()).max_element() + puck.a + puck.r;
    low > reach + 1e-9 * (1.0 + scale)
}

/// Poses sampled evenly by [`MoveGeometry::entry_min_over`] before its golden-section
/// search.
pub const ENTRY_SAMPLES: usize = 16;

/// A toolpath move as the refinement sees it: tip and axis at both ends, cutter radii.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MoveGeometry {
    /// Pose at `u = 0`.
    pub a: Pose,
    /// Pose at `u = 1`.
    pub b: Pose,
    /// The cutter's lower part.
    pub puck: Puck,
}

/// What the closed-form hulls of a move's poses are built from (see
/// `MoveGeometry::hull_frame`).
struct HullFrame {
    /// Torus centres at the move's ends (mm).
    c0: DVec3,
    c1: DVec3,
    /// The mean axis: within `θ/2` of every pose's axis.
    km: DVec3,
    /// How far the centre strays from its chord (mm, [`MoveGeometry::centre_sag`]).
    sag: f64,
    /// `sin(θ/2)` of the axis turn `θ`.
    sh: f64,
}

impl HullFrame {
    /// Radius and half-height (mm) of the cylinder about the mean axis at a chord point
    /// that holds every pose's puck there: `a + r + δ + r·sin(θ/2)` and
    /// `r + δ + (a + r)·sin(θ/2)`, each with a relative pad for rounding.
    fn puck_cylinder(&self, puck: &Puck) -> (f64, f64) {
        let (a, r) = (puck.a, puck.r);
        let pad = 1e-9 * (1.0 + a + r + self.c0.abs().max(self.c1.abs()).max_element());
        (
            a + r + self.sag + r * self.sh + pad,
            r + self.sag + (a + r) * self.sh + pad,
        )
    }
}

impl MoveGeometry {
    /// True when the axis does not change along the move.
    pub fn is_translation(&self) -> bool {
        self.a.axis == self.b.axis
    }

    /// Torus centre and axis at `u`.
    pub fn centre_axis(&self, u: f64) -> (DVec3, DVec3) {
        let p = crate::model::interpolate(&self.a, &self.b, u);
        (p.tip + self.puck.r * p.axis, p.axis)
    }

    /// First entry of `line` into the puck at `u`.
    pub fn entry_at(&self, line: &Line, u: f64) -> Option<Entry> {
        let (c, k) = self.centre_axis(u);
        if self.puck.a == 0.0 {
            let (s_in, s_out) = sphere_interval(line.o, line.n, c, self.puck.r)?;
            if s_out < line.lo || s_in > line.hi {
                return None;
            }
            let s = s_in.max(line.lo);
            let normal = if s_in < line.lo {
                -line.n
            } else {
                ((line.at(s) - c) / self.puck.r).normalize_or(-line.n)
            };
            return Some(Entry { s, normal });
        }
        puck_entry(line, &self.puck, c, k)
    }

    /// First entry into the union of pucks for `u ∈ [u_lo, u_hi]` (`None` when it is not
    /// below `line.hi`): the least of [`MoveGeometry::entry_at`] over `u`, searched on the
    /// line extended by `a + r` beyond `line.hi` (so that poses entered just after `hi` still
    /// guide the search towards one entered before it): [`ENTRY_SAMPLES`] poses evenly over the
    /// range, then golden-section search in the two intervals about the least sample. Exact
    /// where the entry is unimodal in `u` on that bracket; misses count as `+∞`.
    pub fn entry_min_over(&self, line: &Line, u_lo: f64, u_hi: f64) -> Option<(Entry, f64)> {
        const G: f64 = 0.618_033_988_749_894_9;
        // A line that misses a superset of these pucks enters none of them.
        if !self.puck_hull_met(line, u_lo, u_hi) {
            return None;
        }
        let long = Line {
            hi: line.hi + self.puck.a + self.puck.r,
            ..*line
        };
        let val = |u: f64| self.entry_at(&long, u);
        let key = |e: &Option<Entry>| e.map_or(f64::INFINITY, |e| e.s);
        let mut best: Option<(Entry, f64)> = None;
        let consider = |e: Option<Entry>, u: f64, best: &mut Option<(Entry, f64)>| {
            if let Some(e) = e
                && best.is_none_or(|(b, _)| e.s < b.s)
            {
                *best = Some((e, u));
            }
        };
        let n = ENTRY_SAMPLES;
        let at = |i: usize| u_lo + (u_hi - u_lo) * i as f64 / n as f64;
        let mut least = 0;
        for i in 0..=n {
            let e = val(at(i));
            if key(&e) < best.map_or(f64::INFINITY, |(b, _)| b.s) {
                least = i;
            }
            consider(e, at(i), &mut best);
        }
        let (mut lo, mut hi) = (at(least.saturating_sub(1)), at((least + 1).min(n)));
        let (mut x1, mut x2) = (hi - G * (hi - lo), lo + G * (hi - lo));
        let (mut e1, mut e2) = (val(x1), val(x2));
        for _ in 0..90 {
            if hi - lo <= 1e-12 {
                break;
            }
            if key(&e1) <= key(&e2) {
                consider(e2, x2, &mut best);
                hi = x2;
                (x2, e2) = (x1, e1);
                x1 = hi - G * (hi - lo);
                e1 = val(x1);
            } else {
                consider(e1, x1, &mut best);
                lo = x1;
                (x1, e1) = (x2, e2);
                x2 = lo + G * (hi - lo);
                e2 = val(x2);
            }
        }
        consider(e1, x1, &mut best);
        consider(e2, x2, &mut best);
        best.filter(|(e, _)| e.s <= line.hi)
    }

    /// How deep `p` lies inside the puck swept along the move (mm, 0 outside): `r` minus its
    /// distance to the swept disk, the largest over the move. Exact for a translation (a
    /// convex minimisation); for a rotating move by golden-section search over `u`.
    pub fn depth_at(&self, p: DVec3) -> f64 {
        let r = self.puck.r;
        if self.is_translation() {
            let (c0, k) = self.centre_axis(0.0);
            let (c1, _) = self.centre_axis(1.0);
            let (d, _, _) = segment_disk_min(&self.puck, p - c0, c1 - c0, k, 0.5);
            return (r - d).max(0.0);
        }
        let dist = |u: f64| {
            let (c, k) = self.centre_axis(u);
            self.puck.disk_distance(p - c, k).0
        };
        (r - golden_min(0.0, 1.0, dist)).max(0.0)
    }

    /// First entry of `line` into the puck swept along the whole move, when it is a
    /// translation (exact, see the module docs).
    pub fn translation_entry(&self, line: &Line) -> Option<Entry> {
        let (c0, k) = self.centre_axis(0.0);
        let (c1, _) = self.centre_axis(1.0);
        translation_entry(line, &self.puck, c0, c1, k)
    }

    /// Whether `p` lies inside the puck swept along the move ([`MoveGeometry::depth_at`]
    /// above 0). A flat end mill's puck is its disk, which holds no volume.
    pub fn puck_holds(&self, p: DVec3) -> bool {
        if self.puck.r == 0.0 {
            return false;
        }
        let (c0, k) = self.centre_axis(0.0);
        let (c1, _) = self.centre_axis(1.0);
        let d = c1 - c0;
        let t = if d.length_squared() > 0.0 {
            ((p - c0).dot(d) / d.length_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let dist = p.distance(c0 + t * d);
        if !self.is_translation() {
            // Every pose's puck lies in the ball of radius a + r about its centre, which
            // strays from the chord by at most the centre's sag; and in the cylinder about
            // its axis, radius a + r and half-height r (see `puck_hull_holds`).
            let reach = self.puck.a + self.puck.r + self.centre_sag();
            if dist > reach * (1.0 + 1e-12) + 1e-12 || !self.puck_hull_holds(p) {
                return false;
            }
            return self.depth_at(p) > 0.0;
        }
        if self.puck.a == 0.0 {
            // A ball's swept puck is the capsule about the centre's segment.
            return dist < self.puck.r;
        }
        // Outside the capsule of radius a + r about the centre's segment, or below the lower
        // centre plane by more than r: not in the swept puck.
        let below = (p - c0).dot(k) - d.dot(k).min(0.0);
        if dist >= self.puck.a + self.puck.r || below <= -self.puck.r {
            return false;
        }
        self.depth_at(p) > 0.0
    }

    /// How far (mm) the torus centre strays from its chord `c(0) → c(1)` along the move:
    /// at most `r·(1 − cos(θ/2))` for an axis turn `θ`, since the tip runs on its chord and
    /// the interpolated axis (a normalised linear blend, [`crate::model::interpolate`]) differs
    /// from the linear blend by `1 − |blend| ≤ 1 − cos(θ/2)`. 0 for a translation.
    pub fn centre_sag(&self) -> f64 {
        if self.is_translation() {
            return 0.0;
        }
        self.puck.r * (1.0 - self.half_turn().1)
    }

    /// `(sin(θ/2), cos(θ/2))` of the axis turn `θ` over the move, from the chords of the
    /// unit axes (`|k1 − k0| = 2·sin(θ/2)`, `|k0 + k1| = 2·cos(θ/2)`).
    fn half_turn(&self) -> (f64, f64) {
        let (k0, k1) = (self.a.axis.normalize(), self.b.axis.normalize());
        (0.5 * (k1 - k0).length(), 0.5 * (k0 + k1).length())
    }

    /// A superset of the pucks of the poses `u ∈ [u_lo, u_hi]`: the cylinder of radius
    /// `a + r + δ + r·sin(θ/2)` and half-height `r + δ + (a + r)·sin(θ/2)` about the mean
    /// axis `k̄`, swept along the centre's chord from `c_lin(u_lo)` to `c_lin(u_hi)` (each
    /// pose's puck lies in the cylinder of radius `a + r`, half-height `r` about its own
    /// centre and axis; see [`MoveGeometry::column_hull_entry`] for the margins). Returns
    /// whether `line` may enter it: false only when it misses one of the two columns whose
    /// intersection holds it.
    pub fn puck_hull_met(&self, line: &Line, u_lo: f64, u_hi: f64) -> bool {
        let Some(h) = self.hull_frame() else {
            return true;
        };
        let (radius, half) = h.puck_cylinder(&self.puck);
        let (p0, p1) = (h.c0.lerp(h.c1, u_lo), h.c0.lerp(h.c1, u_hi));
        let km = h.km;
        let up = crate::column::column_translation_entry;
        up(line, p0 - half * km, p1 - half * km, km, radius, true).is_some()
            && up(line, p0 + half * km, p1 + half * km, -km, radius, true).is_some()
    }

    /// The centres at the move's ends, its mean axis, the centre's sag and `sin(θ/2)`: what
    /// the closed-form hulls of its poses are built from. `None` when the end axes are
    /// opposite (no mean axis).
    fn hull_frame(&self) -> Option<HullFrame> {
        let (c0, k0) = self.centre_axis(0.0);
        let (c1, k1) = self.centre_axis(1.0);
        let km = (k0 + k1).normalize_or_zero();
        (km != DVec3::ZERO).then(|| HullFrame {
            c0,
            c1,
            km,
            sag: self.centre_sag(),
            sh: self.half_turn().0,
        })
    }

    /// Whether `line` provably enters none of the move's pucks. The clearance
    /// `C(u) = min_s dist(line(s), disk(u)) − r` (`disk(u)`: the disk of radius `a` at pose
    /// `u`) is computed at `n + 1` evenly spaced poses, each from below (golden-section search
    /// of the convex distance along the segment, less its final bracket, the distance being
    /// 1-Lipschitz in `s`). Between poses a disk moves, in Hausdorff distance, by at most
    /// `L·Δu` with `L = |Δtip| + (r + a)·|k1 − k0| / cos(θ/2)` (the normalised blend of the
    /// axes turns at most that fast), so `C` is `L`-Lipschitz in `u`: a least sampled
    /// clearance above `L / (2n)` proves a miss. Tried with `n` = 64, then 1024.
    pub fn misses_pucks(&self, line: &Line) -> bool {
        let (a, r) = (self.puck.a, self.puck.r);
        let ch = self.half_turn().1;
        if !(ch > 0.0 && line.lo <= line.hi && line.hi.is_finite() && line.lo.is_finite()) {
            return false;
        }
        let lip =
            self.a.tip.distance(self.b.tip) + (r + a) * (self.b.axis - self.a.axis).length() / ch;
        let clearance = |u: f64| {
            let (c, k) = self.centre_axis(u);
            let d = |s: f64| self.puck.disk_distance(line.at(s) - c, k).0;
            let width = 1e-12 * (1.0 + line.hi.abs().max(line.lo.abs()));
            let (least, bracket) = golden_search(line.lo, line.hi, width, d);
            least - bracket - r
        };
        let pad = 1e-9 * (1.0 + a + r);
        for n in [64usize, 1024] {
            let least = (0..=n)
                .map(|i| clearance(i as f64 / n as f64))
                .fold(f64::INFINITY, f64::min);
            if least <= 0.0 {
                return false;
            }
            if least > lip / (2 * n) as f64 + pad {
                return true;
            }
        }
        false
    }

    /// Whether `p` lies in a superset of the puck swept along a rotating move: each pose's
    /// puck lies in the cylinder of radius `a + r` and half-height `r` about its centre and
    /// axis, so (as in [`MoveGeometry::column_hull_entry`]) in the cylinder about the mean
    /// axis `k̄` and the chord's point `c_lin(u)` grown in radius by `δ + r·sin(θ/2)` and in
    /// half-height by `δ + (a + r)·sin(θ/2)`; `p` must lie in it for some `u ∈ [0, 1]`.
    pub fn puck_hull_holds(&self, p: DVec3) -> bool {
        let Some(h) = self.hull_frame() else {
            return true;
        };
        let (radius, half) = h.puck_cylinder(&self.puck);
        let km = h.km;
        // q(u) = p − c0 − u·d: axial part linear in u, radial part a convex quadratic.
        let (q, d) = (p - h.c0, h.c1 - h.c0);
        let (qk, dk) = (q.dot(km), d.dot(km));
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        if dk.abs() > 0.0 {
            let (u1, u2) = ((qk - half) / dk, (qk + half) / dk);
            lo = lo.max(u1.min(u2));
            hi = hi.min(u1.max(u2));
        } else if qk.abs() > half {
            return false;
        }
        if lo > hi {
            return false;
        }
        let (qp, dp) = (q - qk * km, d - dk * km);
        let dd = dp.length_squared();
        let u = if dd > 0.0 {
            (qp.dot(dp) / dd).clamp(lo, hi)
        } else {
            lo
        };
        (qp - u * dp).length_squared() <= radius * radius
    }

    /// First entry of `line` into a superset of the column swept along the move (bases
    /// included), in closed form: a lower bound of every entry into one of the move's
    /// columns, `None` when the line meets none of them. A translation's swept column itself;
    /// for a rotating move the translation column along the centre's chord about the mean
    /// axis `k̄` (the normalised sum of the end axes, within `θ/2` of every pose's axis),
    /// grown in radius by `δ + H·sin(θ/2)` and lowered by `δ + (a + r)·sin(θ/2)`, where `δ`
    /// is the centre's sag ([`MoveGeometry::centre_sag`]) and `H` bounds the distance from
    /// the line's segment to the centres. (A point `c(u) + h·k(u) + w` of a pose's column,
    /// `h ≥ 0`, `|w| ≤ a + r`, `h ≤ H`, lies within `δ + h·sin(θ/2) + |w|` of the chord's
    /// axis line through `c_lin(u)` and at least `−δ − |w|·sin(θ/2)` along `k̄` from it.)
    pub fn column_hull_entry(&self, line: &Line) -> Option<Entry> {
        let rr = self.puck.a + self.puck.r;
        if self.is_translation() {
            let (c0, k) = self.centre_axis(0.0);
            let (c1, _) = self.centre_axis(1.0);
            return crate::column::column_translation_entry(line, c0, c1, k, rr, true);
        }
        let everywhere = Some(Entry {
            s: line.lo,
            normal: -line.n,
        });
        let Some(HullFrame {
            c0,
            c1,
            km,
            sag,
            sh,
        }) = self.hull_frame()
        else {
            return everywhere;
        };
        let ends = [line.at(line.lo), line.at(line.hi)];
        let far = ends
            .iter()
            .flat_map(|e| [e.distance(c0), e.distance(c1)])
            .fold(0.0, f64::max)
            + sag;
        if !far.is_finite() {
            return everywhere;
        }
        // A relative pad for rounding.
        let pad = 1e-9 * (1.0 + rr + far);
        let grow = sag + far * sh + pad;
        let lower = (sag + rr * sh + pad) * km;
        crate::column::column_translation_entry(line, c0 - lower, c1 - lower, km, rr + grow, true)
    }

    /// First entry of `line` into the cutter's column ([`crate::column`]: the cylinder of
    /// radius `a + r` above the torus centre plane, unbounded up) swept along the move, `lo`
    /// when the line starts inside; with `base` false, entries through its bottom (which
    /// the puck covers) are left out (see [`crate::column::column_translation_entry`]). A
    /// translation in closed form (exact). A rotating move by a search over the pose
    /// parameter `u` of the one-pose entry, scored where a pose is not entered by how far
    /// the line passes outside its column (so the search is led to the poses the line
    /// grazes): the least score over 33 poses, refined by golden-section search within a
    /// pose of it. Every answer is a pose's entry; it is the least where the score is
    /// unimodal there.
    pub fn column_entry(&self, line: &Line, base: bool) -> Option<Entry> {
        let rr = self.puck.a + self.puck.r;
        if self.is_translation() {
            let (c0, k) = self.centre_axis(0.0);
            let (c1, _) = self.centre_axis(1.0);
            return crate::column::column_translation_entry(line, c0, c1, k, rr, base);
        }
        let at = |u: f64| {
            let (c, k) = self.centre_axis(u);
            match crate::column::column_entry(line, c, k, rr, base) {
                Some(e) => (e.s, Some(e)),
                // Not entered: past the line's end, by the clearance to the column's axis.
                None => (
                    line.hi + 1.0 + (segment_ray_distance(line, c, k) - rr).max(0.0),
                    None,
                ),
            }
        };
        const POSES: usize = 32;
        let mut best: Option<Entry> = None;
        let consider = |e: Option<Entry>, best: &mut Option<Entry>| {
            if let Some(e) = e
                && best.is_none_or(|b| e.s < b.s)
            {
                *best = Some(e);
            }
        };
        let (mut u_best, mut score) = (0.0, f64::INFINITY);
        for i in 0..=POSES {
            let u = i as f64 / POSES as f64;
            let (sc, e) = at(u);
            consider(e, &mut best);
            if sc < score {
                (u_best, score) = (u, sc);
            }
        }
        let step = 1.0 / POSES as f64;
        golden_min((u_best - step).max(0.0), (u_best + step).min(1.0), |u| {
            let (sc, e) = at(u);
            consider(e, &mut best);
            sc
        });
        best
    }

    /// How deep `p` lies in the column swept along the move (mm, 0 outside): the largest
    /// over the move of its depth in one pose's column, the lesser of its distances to the
    /// cylinder's side and to its base plane. For a translation that is a concave function
    /// of `u` and the maximum is found to 1e-12 in `u`; for a rotating move by the same
    /// golden-section search. A lower bound of the depth in the union, equal to it away
    /// from the swept bottom rim.
    pub fn column_depth_at(&self, p: DVec3) -> f64 {
        let rr = self.puck.a + self.puck.r;
        let depth = |u: f64| {
            let (c, k) = self.centre_axis(u);
            let q = p - c;
            let axial = q.dot(k);
            (rr - (q - axial * k).length()).min(axial)
        };
        (-golden_min(0.0, 1.0, |u| -depth(u))).max(0.0)
    }

    /// How deep `p` lies in the whole cutter swept along the move, puck or column (mm, 0
    /// outside): the larger of [`MoveGeometry::depth_at`] and
    /// [`MoveGeometry::column_depth_at`].
    pub fn cutter_depth_at(&self, p: DVec3) -> f64 {
        self.depth_at(p).max(self.column_depth_at(p))
    }
}

/// The least value of `f` seen by a golden-section search for its minimum over
/// `[lo, hi]`, the ends included, until the bracket is 1e-12 wide: the minimum where `f`
/// is unimodal there.
fn golden_min(lo: f64, hi: f64, f: impl FnMut(f64) -> f64) -> f64 {
    golden_search(lo, hi, 1e-12, f).0
}

/// [`golden_min`] until the bracket is `width` wide: the least value seen and the final
/// bracket's width (for a convex `f` its minimum lies in that bracket).
fn golden_search(
    mut lo: f64,
    mut hi: f64,
    width: f64,
    mut f: impl FnMut(f64) -> f64,
) -> (f64, f64) {
    const G: f64 = 0.618_033_988_749_894_9;
    let mut best = f(lo).min(f(hi));
    let (mut x1, mut x2) = (hi - G * (hi - lo), lo + G * (hi - lo));
    let (mut f1, mut f2) = (f(x1), f(x2));
    while hi - lo > width {
        best = best.min(f1).min(f2);
        if f1 <= f2 {
            hi = x2;
            (x2, f2) = (x1, f1);
            x1 = hi - G * (hi - lo);
            f1 = f(x1);
        } else {
            lo = x1;
            (x1, f1) = (x2, f2);
            x2 = lo + G * (hi - lo);
            f2 = f(x2);
        }
    }
    (best.min(f1).min(f2), hi - lo)
}

/// The distance (mm) between the segment `lo..hi` of `line` and the ray from `c` along the
/// unit `k` (closest points by alternating exact minimisation, clamped to the segment and
/// the ray: two rounds, a guide for a search, not an answer).
fn segment_ray_distance(line: &Line, c: DVec3, k: DVec3) -> f64 {
    let w = line.o - c;
    let (b, wn, wk) = (line.n.dot(k), w.dot(line.n), w.dot(k));
    let den = 1.0 - b * b;
    let mut s = if den > 1e-12 {
        (b * wk - wn) / den
    } else {
        -wn
    };
    let mut t = 0.0;
    for _ in 0..2 {
        s = s.clamp(line.lo, line.hi);
        t = (s * b + wk).max(0.0);
        s = t * b - wn;
    }
    let s = s.clamp(line.lo, line.hi);
    (w + s * line.n - t * k).length()
}

/// The body frame used to name inserts along a rotating move: `e1` at a reference pose
/// carried by the minimal rotation between axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyFrame {
    /// Axis at the reference pose.
    pub k_ref: DVec3,
    /// `e1` at the reference pose (unit, ⟂ `k_ref`).
    pub e1_ref: DVec3,
}

/// One evaluation of the continuous imprint surface.
struct SurfacePoint {
    m: DVec3,
    w: DVec3,
    /// `w·û` and `−w·k`: where `w` sits on the insert circle.
    wu: f64,
    wk: f64,
}

/// Which formula gives the imprint point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Regime {
    /// Eq. 2 on the corner torus.
    Torus,
    /// Clamped to the bottom rim (`w = −k`).
    Rim,
    /// Clamped to the equator (`w = û`).
    Side,
}

impl MoveGeometry {
    fn surface(&self, frame: &BodyFrame, u: f64, psi: f64, regime: Regime) -> Option<SurfacePoint> {
        let (a, r) = (self.puck.a, self.puck.r);
        let kk = self.a.axis.lerp(self.b.axis, u);
        let len = kk.length();
        if len.is_nan() || len <= 1e-12 {
            return None;
        }
        let k = kk / len;
        let dk = self.b.axis - self.a.axis;
        let kp = (dk - k * k.dot(dk)) / len;
        let tip = self.a.tip.lerp(self.b.tip, u);
        let tipp = self.b.tip - self.a.tip;
        let e = minimal_rotation(frame.e1_ref, frame.k_ref, k);
        let e1 = (e - e.dot(k) * k).try_normalize()?;
        let e2 = k.cross(e1);
        let (sp, cp) = psi.sin_cos();
        let uh = cp * e1 + sp * e2;
        let t = tip + r * k + a * uh;
        let (w, wu, wk) = match regime {
            Regime::Rim => (-k, 0.0, 1.0),
            Regime::Side => (uh, 1.0, 0.0),
            Regime::Torus => {
                let v = tipp + r * kp - a * kp.dot(uh) * k;
                let nrm = k.cross(uh);
                let x = v.cross(nrm);
                let xx = x.length_squared();
                if xx.is_nan() || xx <= 1e-24 * v.length_squared() {
                    return None;
                }
                let mut w = x / xx.sqrt();
                let (mut wu, mut wk) = (w.dot(uh), -w.dot(k));
                if wu + wk < 0.0 {
                    w = -w;
                    wu = -wu;
                    wk = -wk;
                }
                (w, wu, wk)
            }
        };
        Some(SurfacePoint {
            m: t + r * w,
            w,
            wu,
            wk,
        })
    }

    /// Newton on `m(u, ψ) = o + s·n` in the given regime from `(u, ψ, s)`.
    fn newton(
        &self,
        line: &Line,
        frame: &BodyFrame,
        regime: Regime,
        mut x: [f64; 3],
    ) -> Option<([f64; 3], SurfacePoint)> {
        const H_U: f64 = 1e-7;
        const H_PSI: f64 = 1e-7;
        for _ in 0..30 {
            let [u, psi, s] = x;
            let p = self.surface(frame, u, psi, regime)?;
            let res = p.m - line.at(s);
            let err = res.length();
            let du = {
                let a = self.surface(frame, u + H_U, psi, regime)?;
                let b = self.surface(frame, u - H_U, psi, regime)?;
                (a.m - b.m) / (2.0 * H_U)
            };
            let dpsi = {
                let a = self.surface(frame, u, psi + H_PSI, regime)?;
                let b = self.surface(frame, u, psi - H_PSI, regime)?;
                (a.m - b.m) / (2.0 * H_PSI)
            };
            let ds = -line.n;
            let det = du.dot(dpsi.cross(ds));
            if det.is_nan() || det.abs() <= 1e-300 {
                return None;
            }
            // Cramer: J·δ = −res.
            let rhs = -res;
            let d0 = rhs.dot(dpsi.cross(ds)) / det;
            let d1 = du.dot(rhs.cross(ds)) / det;
            let d2 = du.dot(dpsi.cross(rhs)) / det;
            let scale = (d0.abs() / 0.25)
                .max(d1.abs() / 0.5)
                .max(d2.abs() / 2.0)
                .max(1.0);
            x = [u + d0 / scale, psi + d1 / scale, s + d2 / scale];
            if err <= 1e-12 && scale == 1.0 && d0.abs() < 1e-10 && d2.abs() < 1e-11 {
                let p = self.surface(frame, x[0], x[1], regime)?;
                return Some((x, p));
            }
            if !x.iter().all(|v| v.is_finite()) {
                return None;
            }
        }
        let p = self.surface(frame, x[0], x[1], regime)?;
        ((p.m - line.at(x[2])).length() <= 1e-10).then_some((x, p))
    }

    /// Refines a crossing of the imprint surface of a rotating move: Newton on the
    /// continuous imprint surface from the guess `(u, ψ, s)`, with the solution's `u`; `None`
    /// if it does not converge to an entry point on the cutting quarter with `u ∈ [0, 1]`,
    /// `s ∈ [lo, hi]`.
    pub fn imprint_entry(
        &self,
        line: &Line,
        frame: &BodyFrame,
        guess: [f64; 3],
    ) -> Option<(Entry, f64)> {
        let valid = |x: &[f64; 3], p: &SurfacePoint| {
            (0.0..=1.0).contains(&x[0])
                && x[2] >= line.lo
                && x[2] <= line.hi
                && p.w.dot(line.n) < 0.0
        };
        let (x, p) = self.newton(line, frame, Regime::Torus, guess)?;
        let torus_ok = p.wk >= -1e-12 && (p.wu >= -1e-12 || self.puck.a == 0.0);
        if torus_ok {
            return valid(&x, &p).then_some((
                Entry {
                    s: x[2],
                    normal: p.w,
                },
                x[0],
            ));
        }
        // Off the cutting quarter: the sweep clamps such points to the rim or the equator.
        let regime = if p.wk < 0.0 {
            Regime::Side
        } else {
            Regime::Rim
        };
        let (x, p) = self.newton(line, frame, regime, x)?;
        let eq2 = self.surface(frame, x[0], x[1], Regime::Torus)?;
        let consistent = match regime {
            Regime::Side => eq2.wk < 0.0,
            _ => eq2.wu < 0.0,
        };
        (consistent && valid(&x, &p)).then_some((
            Entry {
                s: x[2],
                normal: p.w,
            },
            x[0],
        ))
    }
}

impl Puck {
    /// The puck of a cutter.
    pub fn of(cutter: &cam_core::Cutter) -> Puck {
        Puck {
            a: cutter.major_radius(),
            r: cutter.corner_radius(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn v3() -> impl Strategy<Value = DVec3> {
        crate::testkit::v3(4.0)
    }

    proptest! {
        // Cheap cases; a hull a hair too narrow shows in a few thousand of them.
        #![proptest_config(ProptestConfig::with_cases(20_000))]

        /// The hull rejection never changes the answer: over random lines and lines grazing
        /// the capsule (within a millionth of its radius, past its ends included), the entry
        /// is the same with it as without.
        #[test]
        fn hull_rejection_changes_no_entry(
            o in v3(),
            n in v3(),
            c0 in v3(),
            step in prop_oneof![v3(), Just(DVec3::ZERO)],
            graze in prop_oneof![Just(None), (-0.3..1.3f64, v3(), -1.0..1.0f64, -1e-6..1e-6f64)
                .prop_map(Some)],
            lo in -3.0..0.0f64,
            len in 0.0..6.0f64,
            r in 0.5..4.0f64,
        ) {
            let c1 = c0 + step;
            let (o, n) = match graze {
                // Through a point at distance r(1 + eps) from the centres' line, across it.
                Some((u, e, t, eps)) if step.length() > 1e-3 && e.cross(step).length() > 1e-3 => {
                    let dh = step.normalize();
                    let e = (e - e.dot(dh) * dh).normalize();
                    let across = dh.cross(e);
                    let p = c0 + u * step + r * (1.0 + eps) * e;
                    let dir = t * dh + (1.0 - t.abs()) * across;
                    (p - 0.5 * len * dir.normalize(), dir)
                }
                _ => (o, n),
            };
            prop_assume!(n.length() > 1e-3);
            let line = Line { o, n: n.normalize(), lo, hi: lo + len };
            let with = capsule_entry_with(&line, c0, c1, r, true);
            let without = capsule_entry_with(&line, c0, c1, r, false);
            prop_assert_eq!(with.map(|e| (e.s, e.normal)), without.map(|e| (e.s, e.normal)));
        }

        /// The cylinder's shortcut gives the entry the three parts give: over random lines and
        /// lines through the cylinder near its ends' planes (within a millionth of its
        /// length), the same entry to 1e-12 mm and the same normal to 1e-6. Near the circle
        /// where a sphere meets the cylinder the two parts' entries agree to rounding, and the
        /// three parts' answer may be the sphere's, whose normal leans along the axis by the
        /// entry's distance from the end's plane over r (under 1e-7 where rounding decides;
        /// 4e-9 seen here), while the shortcut's is radial: both are the surface's normal to
        /// that accuracy.
        #[test]
        fn side_shortcut_gives_the_entry_of_the_three_parts(
            o in v3(),
            n in v3(),
            c0 in v3(),
            step in prop_oneof![v3(), Just(DVec3::ZERO)],
            at_end in prop_oneof![Just(None), (prop_oneof![Just(0.0), Just(1.0)], -1e-6..1e-6f64, v3()).prop_map(Some)],
            lo in -3.0..0.0f64,
            len in 0.0..6.0f64,
            r in 0.5..4.0f64,
        ) {
            let c1 = c0 + step;
            // Through a point on the cylinder near an end's plane.
            let o = match at_end {
                Some((u, eps, e)) if step.length() > 1e-3 && e.cross(step).length() > 1e-3 => {
                    let dh = step.normalize();
                    let e = (e - e.dot(dh) * dh).normalize();
                    c0 + (u + eps) * step + r * e - 0.5 * len * n.normalize_or(DVec3::X)
                }
                _ => o,
            };
            prop_assume!(n.length() > 1e-3);
            let line = Line { o, n: n.normalize(), lo, hi: lo + len };
            let got = capsule_entry_with(&line, c0, c1, r, false);
            let want = capsule_parts_entry(&line, c0, c1, r, cylinder_side(&line, c0, c1, r).as_ref());
            match (got, want) {
                (Some(g), Some(w)) => {
                    prop_assert!((g.s - w.s).abs() <= 1e-12 * (1.0 + w.s.abs()), "{} vs {}", g.s, w.s);
                    prop_assert!((g.normal - w.normal).length() <= 1e-6, "{} vs {}", g.normal, w.normal);
                }
                (None, None) => {}
                (g, w) => prop_assert!(false, "{:?} vs {:?}", g.map(|e| e.s), w.map(|e| e.s)),
            }
        }

        /// A segment the plane test separates from a bull's swept puck stays outside it:
        /// sampled at 101 points against the disks at 101 points of the move (closed form,
        /// no Newton), every point lies farther than `r` from each, and the Newton entry
        /// finds nothing. Tilted axes and moves along and across them included; a test that
        /// forgot the corner radius in the puck's reach fails here (checked).
        #[test]
        fn plane_test_separates_only_segments_clear_of_the_puck(
            o in v3(),
            n in v3(),
            c0 in v3(),
            step in prop_oneof![v3(), Just(DVec3::ZERO)],
            k in prop_oneof![Just(DVec3::Z), v3()],
            lo in -3.0..0.0f64,
            len in 0.0..4.0f64,
            a in 0.0..2.0f64,
            r in 0.1..1.5f64,
        ) {
            prop_assume!(n.length() > 1e-3 && k.length() > 1e-3);
            let (n, k) = (n.normalize(), k.normalize());
            let line = Line { o, n, lo, hi: lo + len };
            let puck = Puck { a, r };
            let c1 = c0 + step;
            if !separated_by_plane(&line, &puck, c0, c1, k) {
                return Ok(());
            }
            for i in 0..=100 {
                let p = line.at(line.lo + len * f64::from(i) / 100.0);
                for j in 0..=100 {
                    let c = c0 + (f64::from(j) / 100.0) * step;
                    let (dist, _) = puck.disk_distance(p - c, k);
                    prop_assert!(dist > r, "{dist} <= {r}");
                }
            }
            prop_assert!(convex_translation_entry(&line, &puck, c0, c1, k).is_none());
        }

        /// The axial entry is the swept puck's lowest point over the line's foot: no pose of
        /// the move (2,001 evenly spaced) holds the line lower, and Newton's general search
        /// finds the same entry (to 1e-9 mm where the envelope is not steep: at its rim the
        /// general search's tolerance in distance is a larger one along the line) or, where
        /// this finds none within the segment, none before its end. Moves of every kind:
        /// any, level to a micrometre over millimetres (a rounded floor's), level, along
        /// the axis, none; feet over the disk, the corner and beyond, axes tilted too.
        #[test]
        fn axial_entry_is_the_envelope_newton_finds(
            c0 in v3(),
            step in prop_oneof![
                v3(),
                (v3(), -1e-3..1e-3f64).prop_map(|(v, z)| DVec3::new(v.x * 8.0, v.y * 8.0, z)),
                v3().prop_map(|v| DVec3::new(v.x, v.y, 0.0)),
                (-2.0..2.0f64).prop_map(|z| DVec3::new(0.0, 0.0, z)),
                Just(DVec3::ZERO),
            ],
            k in prop_oneof![3 => Just(DVec3::Z), 1 => v3()],
            along in -0.2..1.2f64,
            aside in v3(),
            lo in -3.0..0.0f64,
            len in 0.0..8.0f64,
            a in 0.2..3.0f64,
            r in 0.1..2.0f64,
        ) {
            prop_assume!(k.length() > 1e-3);
            let k = k.normalize();
            // A level step is level along `k` only for the vertical axis.
            let c1 = c0 + step;
            let foot = c0 + along * step + aside;
            // The line's origin `r + 2` below the centre plane at `c0`, under the foot.
            let o = foot - (foot - c0).dot(k) * k - (r + 2.0) * k;
            let line = Line { o, n: k, lo, hi: lo + len };
            let puck = Puck { a, r };
            let Some(found) = axial_entry(&line, &puck, c0, c1, k) else {
                return Ok(());
            };
            let newton = convex_translation_entry(&line, &puck, c0, c1, k);
            // The envelope at pose u (the line's parameter there), where it reaches over.
            let (m, d) = (o - c0, c1 - c0);
            let low = |u: f64| {
                let e = across(m - u * d, k).length() - a;
                (e <= r).then(|| u * d.dot(k) - if e <= 0.0 { r } else { (r * r - e * e).sqrt() } - m.dot(k))
            };
            match found {
                None => {
                    prop_assert!(newton.is_none_or(|e| e.s >= line.hi - 1e-9), "{newton:?}");
                    for i in 0..=2000 {
                        if let Some(s) = low(f64::from(i) / 2000.0) {
                            prop_assert!(s > line.hi - 1e-9 || s < line.lo, "{s}");
                        }
                    }
                }
                Some(e) => {
                    prop_assert!(e.s > line.lo && e.s <= line.hi);
                    prop_assert!((e.normal.length() - 1.0).abs() < 1e-9);
                    for i in 0..=2000 {
                        if let Some(s) = low(f64::from(i) / 2000.0) {
                            prop_assert!(s >= e.s - 1e-12, "pose {i}: {s} below {}", e.s);
                        }
                    }
                    let Some(g) = newton else {
                        return Err(TestCaseError::fail(format!("Newton found nothing, axial {e:?}")));
                    };
                    if e.normal.dot(k) < -1e-3 {
                        prop_assert!((e.s - g.s).abs() <= 1e-9, "{e:?} {g:?}");
                        prop_assert!((e.normal - g.normal).length() <= 1e-5, "{e:?} {g:?}");
                    }
                }
            }
        }
    }

    /// The plane test decides what the capsule of radius `a + r` cannot: a vertical vector
    /// beside a level bull pass.
    #[test]
    fn plane_test_separates_a_vector_beside_a_pass() {
        let puck = Puck { a: 1.5, r: 1.5 };
        // Centres 1.5 mm up, the pass 2.8 mm aside along y: at that distance the capsule
        // (radius 3) spans z ∈ [0.42, 2.58], the puck only [0.752, 2.248].
        let line = Line {
            o: DVec3::ZERO,
            n: DVec3::Z,
            lo: -1.0,
            hi: 2.0,
        };
        let (c0, c1) = (DVec3::new(2.8, -1.0, 1.5), DVec3::new(2.8, 1.0, 1.5));
        assert!(!separated_by_plane(&line, &puck, c0, c1, DVec3::Z));
        let line = Line { hi: 0.6, ..line };
        assert!(capsule_entry(&line, c0, c1, 3.0).is_some());
        assert!(separated_by_plane(&line, &puck, c0, c1, DVec3::Z));
    }
}
