//! Closed-form contact heights of a cutter (axis +Z) with a vertex, an edge and a facet.
//!
//! Notation (all mm): `R` cutter radius, `r` corner radius, `a = R - r` major radius. The
//! cutter's lower surface at radial distance `ρ` from the axis lies `h(ρ)` above the tip,
//! `h = 0` for `ρ ≤ a` and `h = r - sqrt(r² - (ρ - a)²)` for `a < ρ ≤ R`. Filled, the cutter
//! is convex, so along any straight edge the drop height is a concave function of position
//! and has a single maximum: that is what makes the edge test closed-form (ball, flat) or a
//! one-dimensional monotone root (torus).

use glam::DVec3;

/// Which feature of a triangle the cutter rests on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum ContactKind {
    /// A triangle corner.
    Vertex,
    /// The interior of a triangle edge.
    Edge,
    /// The interior of a triangle face.
    Facet,
}

/// Where a dropped cutter comes to rest.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// Tool-tip z (mm).
    pub z_tip: f64,
    /// The cutter-contact (CC) point on the part (mm).
    pub cc: DVec3,
    /// Vertex, edge or facet contact.
    pub kind: ContactKind,
    /// Index of the triangle touched, in [`cam_core::Mesh::triangles`].
    pub triangle: u32,
}

/// Cutter dimensions as the contact tests use them (mm).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Profile {
    /// Cutter radius R.
    pub big_r: f64,
    /// R².
    pub big_r2: f64,
    /// Corner radius r.
    pub r: f64,
    /// Major radius a = R - r.
    pub a: f64,
}

impl Profile {
    pub fn new(c: &cam_core::Cutter) -> Profile {
        let big_r = c.radius();
        Profile {
            big_r,
            big_r2: big_r * big_r,
            r: c.corner_radius(),
            a: c.major_radius(),
        }
    }

    /// h(ρ) for ρ ≤ R (caller guarantees).
    #[inline]
    pub fn height(&self, rho: f64) -> f64 {
        let t = rho - self.a;
        if t <= 0.0 {
            0.0
        } else {
            self.r - (self.r * self.r - t * t).max(0.0).sqrt()
        }
    }
}

/// A candidate contact: tool-tip z and CC point.
pub(crate) type Hit = (f64, DVec3);

/// Cutter at `(x, y)` resting on the point `p`.
#[inline]
pub(crate) fn vertex(pf: &Profile, x: f64, y: f64, p: DVec3) -> Option<Hit> {
    let (dx, dy) = (p.x - x, p.y - y);
    let d2 = dx * dx + dy * dy;
    if d2 > pf.big_r2 {
        return None;
    }
    Some((p.z - pf.height(d2.sqrt()), p))
}

/// Cutter at `(x, y)` tangent to the plane of a triangle with upward unit normal `n`
/// (`n.z > 0`) through `v0`, if the tangency point lies inside the triangle `v`.
#[inline]
pub(crate) fn facet(pf: &Profile, x: f64, y: f64, v: &[DVec3; 3], n: DVec3) -> Option<Hit> {
    let (z_tip, cc) = plane_contact(pf, x, y, v[0], n);
    inside_xy(v, cc.x, cc.y).then_some((z_tip, cc))
}

/// Tool-tip z (mm) of the cutter at `(x, y)` tangent to the whole plane through `v0` with
/// upward unit normal `n` (`n.z > 0`): an upper bound of its contact with any part of that
/// plane (the tangency lies within the cutter's reach).
#[inline]
pub(crate) fn plane_tip(pf: &Profile, x: f64, y: f64, v0: DVec3, n: DVec3) -> f64 {
    plane_contact(pf, x, y, v0, n).0
}

/// The cutter at `(x, y)` tangent to the plane through `v0` with upward unit normal `n`:
/// tool-tip z and the tangency point (mm).
#[inline]
fn plane_contact(pf: &Profile, x: f64, y: f64, v0: DVec3, n: DVec3) -> Hit {
    let nxy = (n.x * n.x + n.y * n.y).sqrt();
    let (cx, cy) = if nxy <= 1e-15 {
        (x, y)
    } else {
        // The cutter's outward normal at the contact is -n: on the ring of corner centres
        // the point towards -n_xy, then r along -n.
        let k = pf.a / nxy + pf.r;
        (x - k * n.x, y - k * n.y)
    };
    let zc = v0.z - (n.x * (cx - v0.x) + n.y * (cy - v0.y)) / n.z;
    (zc - pf.r + pf.r * n.z, DVec3::new(cx, cy, zc))
}

/// Point-in-triangle test in the XY projection, edges included.
#[inline]
fn inside_xy(v: &[DVec3; 3], x: f64, y: f64) -> bool {
    let s = |a: DVec3, b: DVec3| (b.x - a.x) * (y - a.y) - (b.y - a.y) * (x - a.x);
    let d0 = s(v[0], v[1]);
    let d1 = s(v[1], v[2]);
    let d2 = s(v[2], v[0]);
    let neg = d0 < 0.0 || d1 < 0.0 || d2 < 0.0;
    let pos = d0 > 0.0 || d1 > 0.0 || d2 > 0.0;
    !(neg && pos)
}

/// Cutter at `(x, y)` resting on the interior of the edge `p1 → p2`. Contacts at or beyond
/// an end point are left to [`vertex`]; an edge that cannot rise above `best` is skipped.
#[inline]
pub(crate) fn edge(pf: &Profile, x: f64, y: f64, p1: DVec3, p2: DVec3, best: f64) -> Option<Hit> {
    let ex = p2.x - p1.x;
    let ey = p2.y - p1.y;
    let len2 = ex * ex + ey * ey;
    if len2 <= 1e-24 {
        return None; // vertical edge: its top end point is the contact
    }
    let len = len2.sqrt();
    let (tx, ty) = (ex / len, ey / len);
    let (wx, wy) = (x - p1.x, y - p1.y);
    let u0 = wx * tx + wy * ty; // foot of the axis on the edge line, along the edge (XY mm)
    let d = (wx * ty - wy * tx).abs(); // XY distance from the axis to the edge line
    if d > pf.big_r {
        return None;
    }
    let m = (p2.z - p1.z) / len; // dz per XY mm along the edge
    // Every point of the edge is at least d from the axis, so the cutter stands at least
    // h(d) above the tip there: the contact cannot beat max z - h(d).
    let hd = pf.height(d);
    if p1.z.max(p2.z) - hd <= best {
        return None;
    }
    let torus = pf.a > 0.0 && pf.r > 0.0;
    if torus {
        // Tighter, worth its square root before the torus's iterative contact: only the
        // stretch within R of the axis can touch, so its highest z less h(d).
        let w = (pf.big_r2 - d * d).max(0.0).sqrt();
        let (s0, s1) = ((u0 - w).max(0.0), (u0 + w).min(len));
        if s0 > s1 || p1.z + m * (if m > 0.0 { s1 } else { s0 }) - hd <= best {
            return None;
        }
        if tangent_bound(pf, d, m, hd, (s0 - u0, s1 - u0)) + p1.z + m * u0 + BOUND_MARGIN_MM <= best
        {
            return None;
        }
    }
    // Offset t from the foot to the contact (sign of m: the contact is uphill) and the
    // cutter height h there.
    let (t, h) = if pf.a <= 0.0 {
        // Ball: the sphere's section in the edge's vertical plane is a circle of radius
        // s = sqrt(R² - d²) resting on a line of slope m.
        let s = (pf.big_r2 - d * d).max(0.0).sqrt();
        let c = 1.0 / (1.0 + m * m).sqrt();
        let t = s * m * c;
        // h = R - sqrt(R² - ρ²) with ρ² = d² + t².
        let rho2 = d * d + t * t;
        (t, pf.r - (pf.big_r2 - rho2).max(0.0).sqrt())
    } else if pf.r <= 0.0 {
        // Flat: the disk's chord on the edge line, highest end.
        let w = (pf.big_r2 - d * d).max(0.0).sqrt();
        let t = if m > 0.0 {
            w
        } else if m < 0.0 {
            -w
        } else {
            0.0
        };
        (t, 0.0)
    } else {
        debug_assert!(torus);
        torus_edge(pf, d, m)
    };
    let s = u0 + t;
    if s <= 0.0 || s >= len {
        return None;
    }
    let zc = p1.z + m * s;
    Some((zc - h, DVec3::new(p1.x + tx * s, p1.y + ty * s, zc)))
}

/// Slack (mm) added to [`tangent_bound`] before it turns an edge away, so that its rounding
/// can never drop a contact that would have won: results are exactly those without it.
const BOUND_MARGIN_MM: f64 = 1e-9;

/// An upper bound on `max_σ m·σ − h(sqrt(d² + σ²))` over `σ ∈ [σ0, σ1]`: the tip's height
/// (relative to the edge's height at the foot of the axis) along the stretch of an edge at
/// XY distance `d` with slope `m` that the torus can reach; `hd = h(d)`.
///
/// `h` is convex on `[0, R]`, so it lies above its tangent `h(ρ0) + k·(ρ − ρ0)` at any
/// `ρ0`, and `m·σ − k·sqrt(d² + σ²)` has its maximum in closed form (concave in `σ`: at
/// `σ* = m·d / sqrt(k² − m²)` clamped to the stretch when `k > |m|`, else at the uphill
/// end). The tangent is taken where it binds: at `ρ_m`, where the corner's slope is `|m|`
/// (the contact lies no nearer the axis: there `h'(ρ)·sqrt(ρ² − d²)/ρ = |m|`), or at `d`
/// if that is farther. Where the old bound `max z − h(d)` only knew the contact is at least
/// `d` out, this one charges every mm the contact must climb the corner.
#[inline]
fn tangent_bound(pf: &Profile, d: f64, m: f64, hd: f64, (s0, s1): (f64, f64)) -> f64 {
    let (a, r) = (pf.a, pf.r);
    let am = m.abs();
    let hyp = (1.0 + am * am).sqrt();
    let rho_m = a + r * am / hyp;
    let (rho0, h0, k) = if d <= rho_m {
        // h(ρ_m) = r·(1 − cos φ) with tan φ = |m|.
        (rho_m, r * (am * am) / (hyp * (1.0 + hyp)), am)
    } else {
        let e = d - a;
        let q = (r * r - e * e).sqrt();
        // At d = R (or NaN) the tangent is vertical: no bound.
        if q.is_nan() || q <= 0.0 {
            return f64::INFINITY;
        }
        (d, hd, e / q)
    };
    let sigma = if k > am {
        (m * d / ((k - am) * (k + am)).sqrt()).clamp(s0, s1)
    } else if m > 0.0 {
        s1
    } else {
        s0
    };
    m * sigma - k * (d * d + sigma * sigma).sqrt() - h0 + k * rho0
}

/// Torus on a line at XY distance `d` from the axis with slope `m`: the offset `t` (signed
/// like `m`) from the foot of the axis to the contact and the cutter height `h` there.
///
/// With the corner angle φ (ρ = a + r·sin φ, h = r·(1 − cos φ), h' = tan φ) the stationarity
/// of `z(t) − h(ρ(t))` reads `g(φ) = tan φ · t/ρ − |m| = 0`, `t = sqrt(ρ² − d²)`; `g` is
/// increasing on `[φ_lo, π/2)`, negative at `φ_lo` and unbounded above, so a Newton
/// iteration safeguarded by bisection converges to the unique root (steps of 1e-15 rad).
///
/// The angle is carried as its unit vector `(sin φ, cos φ)`, never as a number of radians:
/// a Newton step `δ` turns it by `atan δ` (the vector `(1, δ)` normalised, which agrees with
/// `δ` to third order, so the convergence stays quadratic), bisection takes the normalised
/// sum of the bracket's vectors, and order along the arc is the sign of a cross product.
/// No trigonometric function is evaluated (they were a fifth of a bull cutter's plan), and
/// both `sin φ` and `cos φ` keep full relative precision at either end of the quarter.
#[inline]
fn torus_edge(pf: &Profile, d: f64, m: f64) -> (f64, f64) {
    let (a, r) = (pf.a, pf.r);
    let am = m.abs();
    if am == 0.0 || d >= pf.big_r {
        let h = pf.height(d.min(pf.big_r));
        return (0.0, h);
    }
    // Unit vectors (sin φ, cos φ) of the quarter [0, π/2].
    let unit = |sn: f64, cs: f64| {
        let n = (sn * sn + cs * cs).sqrt();
        (sn / n, cs / n)
    };
    // φ1 < φ2 on the quarter.
    let before = |p: (f64, f64), q: (f64, f64)| p.1 * q.0 - p.0 * q.1 > 0.0;
    // φ_lo: where ρ reaches max(a, d) (sin φ = (d − a)/r), and atan |m| (tan φ ≥ |m| at the
    // root because t/ρ ≤ 1): the later of the two.
    let s_lo = ((d - a) / r).clamp(0.0, 1.0);
    let by_reach = (s_lo, ((1.0 - s_lo) * (1.0 + s_lo)).sqrt());
    let by_slope = unit(am, 1.0);
    let mut lo = if before(by_reach, by_slope) {
        by_slope
    } else {
        by_reach
    };
    let mut hi = (1.0, 0.0);
    let g = |(sn, cs): (f64, f64)| -> (f64, f64, f64) {
        let rho = a + r * sn;
        let t = (rho * rho - d * d).max(0.0).sqrt();
        let tan = sn / cs;
        let val = tan * t / rho - am;
        // derivative: t/(ρ cos²φ) + tan φ · d²/(ρ² t) · r cos φ
        let dv = t / (rho * cs * cs)
            + if t > 0.0 {
                r * sn * d * d / (rho * rho * t)
            } else {
                f64::INFINITY
            };
        (val, dv, t / rho)
    };
    let inside = |p: (f64, f64), lo: (f64, f64), hi: (f64, f64)| {
        p.0.is_finite() && p.1.is_finite() && before(lo, p) && before(p, hi)
    };
    // Start from one fixed-point step φ = atan(|m| ρ / t) taken at the lower bracket.
    let (_, _, q) = g(lo);
    let mid = |lo: (f64, f64), hi: (f64, f64)| unit(lo.0 + hi.0, lo.1 + hi.1);
    let mut phi = if q > 0.0 { unit(am, q) } else { mid(lo, hi) };
    if !inside(phi, lo, hi) {
        phi = mid(lo, hi);
    }
    for _ in 0..100 {
        let (v, dv, _) = g(phi);
        if v > 0.0 {
            hi = phi;
        } else {
            lo = phi;
        }
        let step = -v / dv;
        // Turn φ by atan(step).
        let newton = unit(phi.0 + step * phi.1, phi.1 - step * phi.0);
        // Converged: the step is below the tolerance (it may land on the bracket's end
        // just set to φ, which must not send the search back to bisecting).
        if step.is_finite() && step.abs() <= 1e-15 {
            phi = if before(newton, lo) {
                lo
            } else if before(hi, newton) {
                hi
            } else {
                newton
            };
            break;
        }
        let next = if step.is_finite() && inside(newton, lo, hi) {
            newton
        } else {
            mid(lo, hi)
        };
        // Bracket and step below 1e-15 rad: the cross product of the ends is the sine of
        // the angle between them.
        let turn = (phi.1 * next.0 - phi.0 * next.1).abs();
        let width = hi.0 * lo.1 - hi.1 * lo.0;
        phi = next;
        if turn <= 1e-15 || width <= 1e-15 {
            break;
        }
    }
    let (sn, cs) = phi;
    let rho = a + r * sn;
    let t = (rho * rho - d * d).max(0.0).sqrt();
    // r·(1 − cos φ) without cancellation near φ = 0.
    (t * m.signum(), r * sn * sn / (1.0 + cs))
}

#[cfg(test)]
mod tests {
    use super::{Profile, tangent_bound, torus_edge};
    use proptest::prelude::*;

    /// The cutter's highest tip along the line `z = m·s` at XY distance `d` from its axis,
    /// `max_s m·s − h(sqrt(d² + s²))`, by golden-section search: the objective is concave
    /// (`h` convex and increasing, `ρ` convex in `s`), so the bracket keeps the maximum.
    fn brute(pf: &Profile, d: f64, m: f64) -> f64 {
        let w = (pf.big_r2 - d * d).max(0.0).sqrt();
        brute_on(pf, d, m, (-w, w))
    }

    /// [`brute`] on the stretch `s ∈ [s0, s1]` only.
    fn brute_on(pf: &Profile, d: f64, m: f64, (s0, s1): (f64, f64)) -> f64 {
        let f = |s: f64| m * s - pf.height((d * d + s * s).sqrt().min(pf.big_r));
        let (mut lo, mut hi) = (s0, s1);
        let k = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..200 {
            let (x1, x2) = (hi - k * (hi - lo), lo + k * (hi - lo));
            if f(x1) < f(x2) {
                lo = x1;
            } else {
                hi = x2;
            }
        }
        f(0.5 * (lo + hi))
    }

    fn profile(big_r: f64, r: f64) -> Profile {
        Profile {
            big_r,
            big_r2: big_r * big_r,
            r,
            a: big_r - r,
        }
    }

    proptest! {
        /// The contact is a point of the line and the cutter (height m·t − h equals the
        /// brute-force maximum) for shallow, steep and nearly vertical edges, near and far
        /// from the axis.
        #[test]
        fn torus_edge_contact_is_the_highest_tip(
            big_r in 0.5..10.0f64,
            share in 0.05..0.95f64,
            dd in 0.0..0.999f64,
            m in prop_oneof![-3.0..3.0f64, -1e3..1e3f64, (-9.0..9.0f64).prop_map(|e| 10f64.powf(e))],
        ) {
            let pf = profile(big_r, share * big_r);
            let d = dd * big_r;
            let (t, h) = torus_edge(&pf, d, m);
            // The contact lies on the corner circle at ρ = sqrt(d² + t²): (ρ − a, r − h) has
            // length r (checked as a residual: h from ρ is ill-conditioned near ρ = R).
            let rho = (d * d + t * t).sqrt();
            prop_assert!(rho <= big_r * (1.0 + 1e-12), "rho {rho} beyond R {big_r}");
            let (x, y) = ((rho - pf.a).max(0.0), pf.r - h);
            prop_assert!(
                (x * x + y * y - pf.r * pf.r).abs() <= 1e-12 * big_r * big_r || (rho <= pf.a && h == 0.0),
                "({x}, {y}) off the corner circle of radius {}", pf.r
            );
            // It is the highest tip along the line (its height no lower than the search's;
            // a nearly vertical line's is ill-conditioned in s, so relative to |m|·R).
            let tol = 1e-12 * big_r * (1.0 + m.abs());
            let best = brute(&pf, d, m);
            prop_assert!((m * t - h - best).abs() <= tol, "{} vs {best}", m * t - h);
        }

        /// The tangent bound is never below the highest tip on any stretch within reach.
        #[test]
        fn tangent_bound_is_an_upper_bound(
            big_r in 0.5..10.0f64,
            share in 0.05..0.95f64,
            dd in 0.0..1.0f64,
            m in prop_oneof![-3.0..3.0f64, -1e3..1e3f64, (-9.0..9.0f64).prop_map(|e| 10f64.powf(e))],
            (f0, f1) in (0.0..1.0f64, 0.0..1.0f64),
        ) {
            let pf = profile(big_r, share * big_r);
            let d = dd * big_r;
            let w = (pf.big_r2 - d * d).max(0.0).sqrt();
            let (s0, s1) = (-w + 2.0 * w * f0.min(f1), -w + 2.0 * w * f0.max(f1));
            let bound = tangent_bound(&pf, d, m, pf.height(d), (s0, s1));
            let best = brute_on(&pf, d, m, (s0, s1));
            prop_assert!(bound >= best - 1e-12 * big_r * (1.0 + m.abs()), "{bound} < {best}");
        }
    }
}
