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

/// Torus on a line at XY distance `d` from the axis with slope `m`: the offset `t` (signed
/// like `m`) from the foot of the axis to the contact and the cutter height `h` there.
///
/// With the corner angle φ (ρ = a + r·sin φ, h = r·(1 − cos φ), h' = tan φ) the stationarity
/// of `z(t) − h(ρ(t))` reads `g(φ) = tan φ · t/ρ − |m| = 0`, `t = sqrt(ρ² − d²)`; `g` is
/// increasing on `[φ_lo, π/2)`, negative at `φ_lo` and unbounded above, so a Newton
/// iteration safeguarded by bisection converges to the unique root (steps of 1e-15 rad).
#[inline]
fn torus_edge(pf: &Profile, d: f64, m: f64) -> (f64, f64) {
    let (a, r) = (pf.a, pf.r);
    let am = m.abs();
    if am == 0.0 || d >= pf.big_r {
        let h = pf.height(d.min(pf.big_r));
        return (0.0, h);
    }
    let s_lo = ((d - a) / r).max(0.0);
    // φ_lo: where ρ reaches max(a, d); and tan φ ≥ |m| at the root because t/ρ ≤ 1.
    let mut lo = s_lo.min(1.0).asin().max(am.atan());
    let mut hi = std::f64::consts::FRAC_PI_2;
    let g = |phi: f64| -> (f64, f64, f64) {
        let (sn, cs) = phi.sin_cos();
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
    // Start from one fixed-point step φ = atan(|m| ρ / t) taken at the lower bracket.
    let (_, _, q) = g(lo);
    let mut phi = if q > 0.0 {
        (am / q).atan()
    } else {
        0.5 * (lo + hi)
    };
    if !(phi > lo && phi < hi) {
        phi = 0.5 * (lo + hi);
    }
    for _ in 0..100 {
        let (v, dv, _) = g(phi);
        if v > 0.0 {
            hi = phi;
        } else {
            lo = phi;
        }
        let newton = phi - v / dv;
        // Converged: the step is below the tolerance (it may land on the bracket's end
        // just set to φ, which must not send the search back to bisecting).
        if newton.is_finite() && (newton - phi).abs() <= 1e-15 {
            phi = newton.clamp(lo, hi);
            break;
        }
        let next = if newton.is_finite() && newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        let done = (next - phi).abs() <= 1e-15 || hi - lo <= 1e-15;
        phi = next;
        if done {
            break;
        }
    }
    let rho = a + r * phi.sin();
    let t = (rho * rho - d * d).max(0.0).sqrt();
    let half = (0.5 * phi).sin();
    (t * m.signum(), 2.0 * r * half * half)
}
