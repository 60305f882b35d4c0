//! Side-step (scallop) geometry: the scallop-limited interval between neighbouring passes.
//!
//! Two neighbouring passes are (locally) two parallel straight motions of the cutter along the
//! direction `d` of the pass on the CL surface, inclined `α = atan|∂z/∂u|` to the horizontal.
//! The surface each motion sweeps is a cylinder with generators along `d`, so the scallop is
//! formed in the plane perpendicular to `d`, where each swept surface shows the cutter's
//! outline seen along `d` ([`Silhouette`]): its axial profile only when `α = 0` (and for a ball,
//! whose outline is always a circle of radius R). [`SideStepModel`] walks that outline for
//! the along-surface step on straight ground, converts it to an effective radius for the
//! re-derived Eq. 2 on curved sections, and back to an XY interval. Derivation in
//! `docs/plan-math.md` §2. All lengths in mm, angles in radians. Curvature radii are
//! *signed*: positive where the section is convex (a hill) across the passes, negative where
//! concave, `f64::INFINITY` where straight.

use std::f64::consts::FRAC_PI_2;

use cam_core::Cutter;

/// Largest stepover as a fraction of the cutter diameter, whatever the scallop allows.
pub const MAX_STEPOVER_FRACTION: f64 = 0.95;

/// Side step (mm) between the centres of two circles of radius `r` (the cutter's profile in
/// the cross-section) resting on a section of signed curvature radius `rho` (mm; +convex,
/// −concave, `f64::INFINITY` for a straight section) that leaves a cusp of height `h` mm,
/// measured along the section normal:
///
/// `w = 2·sqrt(r² − s²)`, `s = (2ρr − h(2ρ + h)) / (2(ρ + h))`,
/// which is `2·sqrt(2rh − h²)` on a straight section. The chord `w` joins the circle centres
/// (equivalently the tool tips, which sit a fixed `r` below them).
///
/// Returns `None` when no side step leaves a cusp of exactly `h` below the circle centres (`h ≥ r` on a
/// straight section, or a concave section tighter than the cutter, `-r ≤ ρ < 0`).
pub fn ball_step(r: f64, rho: f64, h: f64) -> Option<f64> {
    if !(r > 0.0 && h > 0.0) {
        return None;
    }
    let s = if rho.is_infinite() {
        r - h
    } else {
        if rho > -r && rho <= 0.0 {
            return None;
        }
        (2.0 * rho * r - h * (2.0 * rho + h)) / (2.0 * (rho + h))
    };
    let q = r * r - s * s;
    (q > 0.0 && s > 0.0).then(|| 2.0 * q.sqrt())
}

/// Inverse of [`ball_step`]: the cusp height (mm) left between two circles of radius `r`
/// whose centres are `w` mm apart along a section of signed curvature radius `rho`:
/// `h = sqrt((ρ+r)² − w²/4) − sqrt(r² − w²/4) − ρ` (convex and concave alike), `r − sqrt(r² − w²/4)`
/// on a straight section. `None` if `w > 2r`.
pub fn ball_scallop(r: f64, rho: f64, w: f64) -> Option<f64> {
    let q = w * w / 4.0;
    if q > r * r {
        return None;
    }
    if rho.is_infinite() {
        return Some(r - (r * r - q).sqrt());
    }
    let big = (rho + r) * (rho + r) - q;
    if big < 0.0 {
        return None;
    }
    let sgn = if rho + r >= 0.0 { 1.0 } else { -1.0 };
    // Distance from the section's centre of curvature to the cusp, signed along the normal.
    Some(sgn * big.sqrt() - (r * r - q).sqrt() - rho)
}

/// The slope angles `(α, θ)` (radians, both in `[0, π/2]`) of the side-step geometry at a CL
/// point where the CL surface has gradient `p = ∂z/∂u` along the passes and `q = ∂z/∂v` across
/// them (a chord slope is fine): `α = atan|p|` inclines the motion direction `d = (1, 0, p)`,
/// and `θ` is the slope of the CL section in the plane perpendicular to `d`,
/// `tan θ = |q| / sqrt(1 + p²)`. An XY interval `dv` between passes is an along-section
/// distance `dv / cos θ` there, `cos θ = sqrt((1 + p²) / (1 + p² + q²))`. NaN counts as 0.
pub fn section_angles(p: f64, q: f64) -> (f64, f64) {
    let p = if p.is_nan() { 0.0 } else { p.abs() };
    let q = if q.is_nan() { 0.0 } else { q.abs() };
    let alpha = p.atan();
    let theta = if p.is_finite() {
        (q / (1.0 + p * p).sqrt()).atan()
    } else {
        0.0
    };
    (alpha, theta)
}

/// Signed radius of curvature (mm) in the plane perpendicular to the motion direction of the
/// CL section whose vertical cross-section `u = const` has signed radius `rho_cl` (mm) and
/// slope `q`, on a CL surface sloping `p` along the passes: the vertical section projected
/// along `d` onto that plane (heights scale by `cos α`),
/// `ρ⊥ = ρ_cl · (1 + p² + q²)^{3/2} / ((1 + p²)·(1 + q²)^{3/2})`.
/// Exact for a CL surface that is a cylinder with generators along `d`; `ρ_cl` itself when
/// `p = 0`; `ρ_cl / cos α` when `q = 0` (the normal section of a sphere from its vertical
/// section through a point inclined `α` along the pass).
pub fn section_radius(rho_cl: f64, p: f64, q: f64) -> f64 {
    let (p2, q2) = (p * p, q * q);
    if !(p2.is_finite() && q2.is_finite()) {
        return rho_cl;
    }
    rho_cl * ((1.0 + p2 + q2) / (1.0 + q2)).powf(1.5) / (1.0 + p2)
}

/// The lower outline of a cutter (axis vertical, tip at the origin) seen along a motion
/// direction inclined `α` to the horizontal: the lower boundary of the cutter projected along
/// `d = (cos α, 0, sin α)` onto the plane perpendicular to `d`, in coordinates `(y, z)`: `y`
/// across the motion (horizontal), `z` along `(−sin α, 0, cos α)` (up in that plane).
///
/// The cutter's lower part is a horizontal disk of radius `a = R − r` (the corner centres,
/// at height `r`) plus a ball of radius `r`, so its outline is the `r`-offset of the disk's
/// projection, the ellipse with semi-axes `a` (across) and `b = a·sin α` (up) centred at
/// `(0, r·cos α)`, continued by the vertical sides `y = ±R` above `z = r·cos α`.
/// A ball (a = 0) shows a circle of radius R for every α; a flat end mill (r = 0) the ellipse
/// itself, whose radius of curvature at its lowest point is `R / sin α`; a bull moving along a
/// slope α without side slope touches with radius `r + a / sin α` (Koenderink's apparent
/// contour: the curvature across the motion is the Gaussian curvature over the normal
/// curvature along it). At α = 0 it is the axial profile.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Silhouette {
    a: f64,
    b: f64,
    r: f64,
    zc: f64,
    rr: f64,
}

/// Boundary of `pred` between `lo` (false) and `hi` (true), by bisection to the last bit;
/// returns a point where `pred` holds. `lo` may exceed `hi`.
fn bisect(mut lo: f64, mut hi: f64, pred: impl Fn(f64) -> bool) -> f64 {
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid == lo || mid == hi {
            break;
        }
        if pred(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

/// Root of `f` between `a`, where `f < 0`, and `b`, where `f ≥ 0` (`a` may exceed `b`), by
/// Newton's method from `guess` on `f`'s value and derivative `(f, f')`, safeguarded by
/// bisection of the bracket; to a relative step of 1e-15.
fn newton(a: f64, b: f64, guess: f64, f: impl Fn(f64) -> (f64, f64)) -> f64 {
    let (mut neg, mut pos) = (a, b);
    let inside = |x: f64, p: f64, q: f64| x > p.min(q) && x < p.max(q);
    let mut x = if inside(guess, a, b) {
        guess
    } else {
        0.5 * (a + b)
    };
    for _ in 0..100 {
        let (fx, dfx) = f(x);
        if fx >= 0.0 {
            pos = x;
        } else {
            neg = x;
        }
        if fx == 0.0 {
            return x;
        }
        let mut nx = x - fx / dfx;
        // Converged: a Newton step below the tolerance ends the search, even where it lands
        // on the bracket's end just set to x (bisecting then would start over).
        if nx.is_finite() && (nx - x).abs() <= 1e-15 * (1.0 + x.abs()) {
            return nx.clamp(neg.min(pos), neg.max(pos));
        }
        if !(nx.is_finite() && inside(nx, neg, pos)) {
            nx = 0.5 * (neg + pos);
        }
        if (nx - x).abs() <= 1e-15 * (1.0 + x.abs()) || nx == neg || nx == pos {
            return nx;
        }
        x = nx;
    }
    x
}

impl Silhouette {
    /// The outline of `cutter` seen along a motion inclined `alpha` radians (its sign does not
    /// matter; clamped to `[0, π/2]`, NaN counts as 0).
    pub fn new(cutter: &Cutter, alpha: f64) -> Silhouette {
        let al = if alpha.is_nan() {
            0.0
        } else {
            alpha.abs().min(FRAC_PI_2)
        };
        let (s, c) = al.sin_cos();
        let a = cutter.major_radius();
        let r = cutter.corner_radius();
        Silhouette {
            a,
            b: a * s,
            r,
            zc: r * c,
            rr: cutter.radius(),
        }
    }

    /// The point `(y, z)` (mm) of the outline whose outward normal is `(sin γ, −cos γ)`,
    /// `γ` in `[−π/2, π/2]` (clamped; 0 is the lowest point). Where a flat bottom (α = 0) has
    /// that normal along a whole segment, its middle.
    pub fn point(&self, gamma: f64) -> (f64, f64) {
        let (s, c) = gamma.clamp(-FRAC_PI_2, FRAC_PI_2).sin_cos();
        self.point_sc(s, c)
    }

    /// [`Silhouette::point`] from the normal angle's sine and cosine (`c ≥ 0`).
    fn point_sc(&self, s: f64, c: f64) -> (f64, f64) {
        let (a, b) = (self.a, self.b);
        let d = (a * a * s * s + b * b * c * c).sqrt();
        let (ey, ez) = if d > 0.0 {
            (a * a * s / d, -b * b * c / d)
        } else {
            (0.0, 0.0)
        };
        (ey + self.r * s, self.zc + ez - self.r * c)
    }

    /// Height (mm, along the outline's `z`) of the lowest point above the tip:
    /// `r·cos α − a·sin α − r` (≤ 0).
    pub fn lowest(&self) -> f64 {
        self.point(0.0).1
    }

    /// Radius of curvature (mm) of the outline at the point of normal angle `gamma`:
    /// `r + a²b² / (a² sin²γ + b² cos²γ)^{3/2}` (the corner plus the ellipse); `r` where the
    /// ellipse degenerates to the flat bottom (α = 0), whose contact with a slope is its rim.
    pub fn radius(&self, gamma: f64) -> f64 {
        let (a, b) = (self.a, self.b);
        if a > 0.0 && b > 0.0 {
            let (s, c) = gamma.clamp(-FRAC_PI_2, FRAC_PI_2).sin_cos();
            let d = (a * a * s * s + b * b * c * c).sqrt();
            self.r + a * a * b * b / (d * d * d)
        } else {
            self.r
        }
    }

    /// The outline's smallest radius of curvature (mm): `r + b²/a` (`r + a·sin²α`, at the
    /// ellipse's ends; r when α = 0; R for a ball). Its sides and flat bottom are straight, so
    /// (Blaschke's rolling theorem) a circle of this radius touching the outline anywhere
    /// from inside lies inside the cutter's outline.
    pub fn min_radius(&self) -> f64 {
        if self.a > 0.0 {
            self.r + self.b * self.b / self.a
        } else {
            self.r
        }
    }

    /// Along-surface distances `(d₋, d₊)` (mm) from the contact at which the outline, resting
    /// on a straight section of slope `theta` radians (clamped to `[0, π/2]`), rises `h` mm
    /// above it, measured normal to the section: downhill and uphill of the contact. Two
    /// copies `w` apart along the section leave a cusp of exactly `h` when `w = d₋ + d₊`.
    ///
    /// Uphill the outline is followed to its side `y = R` and up that side; downhill to its
    /// extreme point along the section (normal angle `θ − π/2`): beyond it the outline
    /// overhangs, and the cusp with the neighbouring copy forms there. `INFINITY` uphill when
    /// the section is vertical (the side lies on it). Closed form for a ball; otherwise
    /// Newton's method on the normal angle (safeguarded by bisection) to a relative 1e-15.
    pub fn reach(&self, theta: f64, h: f64) -> (f64, f64) {
        self.reach_with(theta, h, true)
    }

    /// [`Silhouette::reach`]; `closed` takes a flat end mill's ellipse in closed form, else
    /// Newton's method as for a bull (the reference the closed form is tested against).
    fn reach_with(&self, theta: f64, h: f64, closed: bool) -> (f64, f64) {
        if h.is_nan() || h <= 0.0 {
            return (0.0, 0.0);
        }
        let th = if theta.is_nan() {
            0.0
        } else {
            theta.abs().min(FRAC_PI_2)
        };
        let (sn, cs) = th.sin_cos();
        if self.a == 0.0 {
            // A ball: a circle of radius R with its sides; the walk in closed form.
            let rr = self.rr;
            let d = if h < rr {
                (2.0 * rr * h - h * h).sqrt()
            } else {
                rr
            };
            // Uphill the circle reaches its side at height R(1 − sin θ), then the side.
            let h_side = rr * (1.0 - sn);
            let dp = if h <= h_side {
                d
            } else if cs > 1e-12 {
                rr * cs + (h - h_side) / cs * sn
            } else {
                f64::INFINITY
            };
            return (d, dp);
        }
        let x0 = self.point(th);
        // Height above the section line through the contact, and distance along it; the
        // height's derivative along the outline is its radius of curvature times sin(γ − θ).
        let height = |p: (f64, f64)| (x0.0 - p.0) * sn - (x0.1 - p.1) * cs;
        let along = |p: (f64, f64)| (p.0 - x0.0) * cs + (p.1 - x0.1) * sn;
        let f = |g: f64| (height(self.point(g)) - h, self.radius(g) * (g - th).sin());
        // A flat end mill on a slope (r = 0, b > 0): the outline is the lower half of the
        // ellipse (a cos φ, b sin φ), and its height above the section line through the
        // contact φ_c is R_s(1 − cos(φ − φ_c)) with R_s = sqrt(a² sin²θ + b² cos²θ), so the
        // points at height h lie at φ_c ± 2 asin(sqrt(h / 2R_s)). Whether they lie on the
        // arcs walked is decided below as for the other outlines.
        let ellipse = (closed && self.r == 0.0 && self.b > 0.0).then(|| {
            let rs = (self.a * self.a * sn * sn + self.b * self.b * cs * cs).sqrt();
            let phi_c = (x0.1 / self.b).atan2(x0.0 / self.a);
            (phi_c, 2.0 * (h / (2.0 * rs)).min(1.0).sqrt().asin())
        });
        let on_ellipse = |(phi_c, eps): (f64, f64), side: f64| {
            let phi = phi_c + side * eps;
            (self.a * phi.cos(), self.b * phi.sin())
        };
        // First guess: the osculating circle at the contact.
        let turn = {
            let rc = self.radius(th);
            if h < rc {
                (1.0 - h / rc).acos()
            } else {
                FRAC_PI_2
            }
        };
        let side = self.point(FRAC_PI_2);
        let h_side = height(side);
        let dp = if let Some(e) = ellipse.filter(|_| h_side >= h) {
            along(on_ellipse(e, 1.0))
        } else if h_side >= h {
            along(self.point(newton(th, FRAC_PI_2, th + turn, f)))
        } else if cs > 1e-12 {
            along(side) + (h - h_side) / cs * sn
        } else {
            f64::INFINITY
        };
        let g_end = th - FRAC_PI_2;
        let end = self.point(g_end);
        let on_arc = |from: f64, guess: f64| -along(self.point(newton(from, g_end, guess, f)));
        let dm = if height(end) < h {
            -along(end)
        } else if let Some(e) = ellipse {
            -along(on_ellipse(e, -1.0))
        } else if self.b == 0.0 && th > 0.0 {
            // α = 0: the flat bottom, a segment at normal angle 0 between the corner arcs.
            let z = self.zc - self.r;
            let (sr, sl) = ((self.a, z), (-self.a, z));
            let (hr, hl) = (height(sr), height(sl));
            if hr >= h {
                on_arc(th, th - turn)
            } else if hl >= h {
                let t = (h - hr) / (hl - hr);
                -along((sr.0 + t * (sl.0 - sr.0), z))
            } else {
                // On the left corner arc, γ < 0 (γ = −0 would be the segment's middle).
                on_arc(-f64::MIN_POSITIVE, 0.5 * g_end)
            }
        } else {
            on_arc(th, th - turn)
        };
        (dm.max(0.0), dp.max(0.0))
    }

    /// Height (mm, along the outline's `z`) of the outline above its lowest point at `y` mm
    /// across from it, `None` for `|y| > R`. Closed form for a ball, for α = 0 (the axial
    /// profile) and for a flat end mill (the ellipse); bisection on the normal angle to the
    /// last bit for a bull moving on a slope.
    #[inline]
    pub fn height_at(&self, y: f64) -> Option<f64> {
        let ya = y.abs();
        if ya.is_nan() || ya > self.rr {
            return None;
        }
        if self.b == 0.0 {
            let t = ya - self.a;
            return Some(if t <= 0.0 {
                0.0
            } else {
                self.r - (self.r * self.r - t * t).max(0.0).sqrt()
            });
        }
        if self.r == 0.0 {
            let u = ya / self.rr;
            return Some(self.b * (1.0 - (1.0 - u * u).max(0.0).sqrt()));
        }
        let g = bisect(0.0, FRAC_PI_2, |g| self.point(g).0 >= ya);
        Some(self.point(g).1 - self.lowest())
    }
}

/// Resolution of the tabulated outline of [`SectionProfile`]: nodes per quarter outline in
/// normal angle and in ellipse parameter, and intervals of the resampled table.
const OUTLINE_NODES: usize = 2048;
const TABLE_INTERVALS: usize = 4096;

/// [`Silhouette::height_at`] for many offsets: exact (closed form) for a ball, a flat end
/// mill and α = 0; for a bull on a slope a table over `ξ = 1 − sqrt(1 − |y|/R)` (which keeps
/// the outline smooth up to its vertical end), resampled from exact outline points spaced at
/// most π/4096 in normal angle and in ellipse parameter: within 3e-7 mm of the outline,
/// measured normal to it, for bull:6:1.5 and bull:10:0.5 (`outline_heights_match_brute_force_and_table`).
#[derive(Debug, Clone)]
pub struct SectionProfile {
    sil: Silhouette,
    table: Vec<f64>,
}

impl SectionProfile {
    /// The profile of `sil`.
    pub fn new(sil: Silhouette) -> SectionProfile {
        let table = if sil.b == 0.0 || sil.r == 0.0 {
            Vec::new()
        } else {
            Self::tabulate(&sil)
        };
        SectionProfile { sil, table }
    }

    fn tabulate(sil: &Silhouette) -> Vec<f64> {
        let n = OUTLINE_NODES;
        // Normal angles uniform in themselves and in the ellipse parameter t (both sorted),
        // merged; each as (sin γ, cos γ), which is all a point needs. The parameter t's
        // point has its normal along (b sin t, a cos t) normalised, so no angle is formed,
        // and the uniform angles' sines and cosines are shared by every table.
        static UNIFORM: std::sync::OnceLock<Vec<(f64, f64)>> = std::sync::OnceLock::new();
        let by_g = UNIFORM.get_or_init(|| {
            (0..=n)
                .map(|k| (k as f64 / n as f64 * FRAC_PI_2).sin_cos())
                .collect()
        });
        let by_t: Vec<(f64, f64)> = by_g
            .iter()
            .map(|&(st, ct)| {
                let (y, x) = (sil.b * st, sil.a * ct);
                let h = (x * x + y * y).sqrt();
                (y / h, x / h)
            })
            .collect();
        // γ₁ < γ₂ in [0, π/2] exactly when sin γ₁ cos γ₂ < cos γ₁ sin γ₂.
        let below = |p: (f64, f64), q: (f64, f64)| p.0 * q.1 < p.1 * q.0;
        let mut gs: Vec<(f64, f64)> = Vec::with_capacity(2 * n + 2);
        let (mut i, mut j) = (0, 0);
        while i <= n || j <= n {
            let g = if j > n || (i <= n && !below(by_t[j], by_g[i])) {
                i += 1;
                by_g[i - 1]
            } else {
                j += 1;
                by_t[j - 1]
            };
            if gs.last().is_none_or(|&l| below(l, g)) {
                gs.push(g);
            }
        }
        let z0 = sil.lowest();
        let pts: Vec<(f64, f64)> = gs
            .iter()
            .map(|&(sg, cg)| {
                let (y, z) = sil.point_sc(sg, cg);
                (y, z - z0)
            })
            .collect();
        let m = TABLE_INTERVALS;
        let mut out = Vec::with_capacity(m + 1);
        let mut i = 0;
        for j in 0..=m {
            let xi = j as f64 / m as f64;
            let y = sil.rr * (1.0 - (1.0 - xi) * (1.0 - xi));
            while i + 2 < pts.len() && pts[i + 1].0 < y {
                i += 1;
            }
            let (p, q) = (pts[i], pts[i + 1]);
            let f = if q.0 > p.0 {
                ((y - p.0) / (q.0 - p.0)).clamp(0.0, 1.0)
            } else {
                1.0
            };
            out.push(p.1 + f * (q.1 - p.1));
        }
        out
    }

    /// Height (mm) of the outline above its lowest point at `y` mm across, `None` for
    /// `|y| > R`.
    #[inline]
    pub fn height(&self, y: f64) -> Option<f64> {
        if self.table.is_empty() {
            return self.sil.height_at(y);
        }
        let rr = self.sil.rr;
        let ya = y.abs();
        if ya.is_nan() || ya > rr {
            return None;
        }
        let m = TABLE_INTERVALS;
        let xi = 1.0 - (1.0 - ya / rr).max(0.0).sqrt();
        let x = xi * m as f64;
        // x ≥ 0: truncation is the floor.
        let k = (x as usize).min(m - 1);
        let f = x - k as f64;
        Some(self.table[k] + f * (self.table[k + 1] - self.table[k]))
    }
}

/// The side-step model of one cutter and scallop height `h` (mm): pure geometry, evaluated
/// from the CL surface's slopes and curvature at a point (no drops). Evaluation is O(1): a
/// fixed number of bisection steps on the closed-form outline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SideStepModel {
    cutter: Cutter,
    h: f64,
}

impl SideStepModel {
    /// The model for `cutter` and scallop height `h` mm.
    pub fn new(cutter: Cutter, h: f64) -> SideStepModel {
        SideStepModel { cutter, h }
    }

    /// The cutter.
    pub fn cutter(&self) -> &Cutter {
        &self.cutter
    }

    /// The scallop height h (mm).
    pub fn h(&self) -> f64 {
        self.h
    }

    /// The outline of the cutter for a motion of slope `p` (`∂z/∂u`) along the passes.
    pub fn silhouette(&self, p: f64) -> Silhouette {
        Silhouette::new(&self.cutter, section_angles(p, 0.0).0)
    }

    /// Along-surface step (mm, in the plane perpendicular to the motion) between two passes
    /// on a straight CL section of gradient `(p, q)` that leaves a cusp of exactly h:
    /// `d₋ + d₊` of [`Silhouette::reach`], capped at [`MAX_STEPOVER_FRACTION`]·D.
    pub fn straight_step(&self, p: f64, q: f64) -> f64 {
        let (alpha, theta) = section_angles(p, q);
        let (dm, dp) = Silhouette::new(&self.cutter, alpha).reach(theta, self.h);
        (dm + dp).min(MAX_STEPOVER_FRACTION * self.cutter.diameter())
    }

    /// Effective radius (mm) across the passes at gradient `(p, q)`: the circle leaving the
    /// same cusp h at the same straight-section step `w` ([`SideStepModel::straight_step`]),
    /// `r_eff = ((w/2)² + h²) / (2h)`. R for a ball; for a bull on its corner with no slope
    /// along the passes, r; `≈ r + a / sin α` for a bull moving on a slope α (small h),
    /// `≈ R / sin α` for a flat end mill.
    pub fn effective_radius(&self, p: f64, q: f64) -> f64 {
        let w = self.straight_step(p, q);
        let h = self.h;
        ((w / 2.0).powi(2) + h * h) / (2.0 * h)
    }

    /// What the curvature treatment needs at gradient `(p, q)`, independent of the section's
    /// radius.
    fn straight(&self, p: f64, q: f64) -> Straight {
        let (alpha, theta) = section_angles(p, q);
        let sil = Silhouette::new(&self.cutter, alpha);
        let h = self.h;
        let (dm, dp) = sil.reach(theta, h);
        let w = (dm + dp).min(MAX_STEPOVER_FRACTION * self.cutter.diameter());
        Straight {
            r_eff: ((w / 2.0).powi(2) + h * h) / (2.0 * h),
            r_c: sil.radius(theta),
            r_in: sil.min_radius(),
            theta,
        }
    }

    /// The circle radius (mm) and the part's radius (mm) for vertical-section radius `rho_cl`:
    /// the effective radius, or on a concave section it cannot sit in, the outline's
    /// smallest radius.
    fn circle(&self, st: &Straight, p: f64, q: f64, rho_cl: f64) -> (f64, f64) {
        let rho = part_radius(section_radius(rho_cl, p, q), st.r_c);
        let r = if ball_step(st.r_eff, rho, self.h).is_none() && rho < 0.0 {
            st.r_in
        } else {
            st.r_eff
        };
        (r, rho)
    }

    /// The XY interval (mm) to the next pass at a CL point where the CL surface has gradient
    /// `(p, q)` (`q` best the chord slope to the next pass, the seed's Algorithm 2) and the
    /// vertical section `u = const` signed radius `rho_cl` (mm; `INFINITY` straight):
    /// `w·cos θ` with `w` [`ball_step`] of the effective radius on the part's radius in the
    /// plane perpendicular to the motion, `ρ = ρ⊥ − r_c` ([`section_radius`], `r_c` the
    /// outline's [`Silhouette::radius`] at the contact), capped at [`MAX_STEPOVER_FRACTION`]·D.
    /// On a concave section tighter than the effective circle (a bull's flat bottom across a
    /// valley, or a concave crease of the CL surface such as the foot of a boss), [`ball_step`]
    /// of the outline's smallest radius instead ([`Silhouette::min_radius`], the corner
    /// radius r when α = 0): conservative, since that circle touching where the cutter
    /// touches lies inside the cutter and leaves a cusp at least as high. Exact on straight
    /// sections and for a ball on cylinders; the cap on a convex section so sharp that no step
    /// leaves h (the cutter rolls round an edge); 0 when no step leaves h on a concave one (a
    /// flat end mill moving level on a concave section narrower than its effective circle).
    pub fn xy_interval(&self, p: f64, q: f64, rho_cl: f64) -> f64 {
        self.xy_interval_min(p, q, &[rho_cl])
    }

    /// The smallest [`SideStepModel::xy_interval`] (mm) over several vertical-section radii
    /// `rhos` at the same gradient (the outline is walked once).
    pub fn xy_interval_min(&self, p: f64, q: f64, rhos: &[f64]) -> f64 {
        let at = self.at(p, q);
        rhos.iter()
            .map(|&rho_cl| at.interval(rho_cl))
            .fold(f64::INFINITY, f64::min)
    }

    /// Predicted cusp height (mm) when neighbouring passes are `dv` mm apart in XY at a CL
    /// point of gradient `(p, q)` and vertical-section radius `rho_cl`: the forward model of
    /// [`SideStepModel::xy_interval`] (exactly h at its own interval below the cap; the
    /// circle's radius where the step does not fit it).
    pub fn predicted_scallop(&self, p: f64, q: f64, rho_cl: f64, dv: f64) -> f64 {
        self.at(p, q).scallop(rho_cl, dv)
    }

    /// The model at gradient `(p, q)`, the outline walked once for several questions (the
    /// same answers as the methods above).
    pub(crate) fn at(&self, p: f64, q: f64) -> ModelAt<'_> {
        ModelAt {
            model: self,
            st: self.straight(p, q),
            p,
            q,
        }
    }

    /// Height (mm) of the cutter's outline seen along a motion of slope `p` along the passes
    /// ([`Silhouette::height_at`]) at `y` mm across from its lowest point, measured in the
    /// plane perpendicular to the motion; `None` for `|y| > R`.
    pub fn section_height(&self, p: f64, y: f64) -> Option<f64> {
        self.silhouette(p).height_at(y)
    }

    /// [`SideStepModel::section_height`] for many offsets at one slope `p`
    /// ([`SectionProfile`]).
    pub fn section(&self, p: f64) -> SectionProfile {
        SectionProfile::new(self.silhouette(p))
    }
}

/// [`SideStepModel`] at one gradient ([`SideStepModel::at`]).
pub(crate) struct ModelAt<'m> {
    model: &'m SideStepModel,
    st: Straight,
    p: f64,
    q: f64,
}

impl ModelAt<'_> {
    /// [`SideStepModel::xy_interval`] (mm) here for vertical-section radius `rho_cl` (mm).
    pub(crate) fn interval(&self, rho_cl: f64) -> f64 {
        let m = self.model;
        let cap = MAX_STEPOVER_FRACTION * m.cutter.diameter();
        let (r, rho) = m.circle(&self.st, self.p, self.q, rho_cl);
        // No step leaves a cusp of h: on a convex section that sharp the cusp stays below h
        // at every step (the cutter rolls round the edge), so the cap applies; on a concave
        // one no step is safe.
        let none = if rho > 0.0 { cap } else { 0.0 };
        ball_step(r, rho, m.h).map_or(none, |w| w.min(cap)) * self.st.theta.cos()
    }

    /// [`SideStepModel::predicted_scallop`] (mm) here for passes `dv` mm apart.
    pub(crate) fn scallop(&self, rho_cl: f64, dv: f64) -> f64 {
        let (r, rho) = self.model.circle(&self.st, self.p, self.q, rho_cl);
        let c = self.st.theta.cos();
        let w = if c > 1e-12 { dv / c } else { f64::INFINITY };
        ball_scallop(r, rho, w).unwrap_or(r)
    }

    /// [`SideStepModel::effective_radius`] (mm) here.
    pub(crate) fn effective_radius(&self) -> f64 {
        self.st.r_eff
    }
}

/// [`SideStepModel`]'s straight-section results at one gradient: the effective radius, the
/// outline's radius at the contact and its smallest radius (mm), and the section's slope θ.
#[derive(Debug, Clone, Copy)]
struct Straight {
    r_eff: f64,
    r_c: f64,
    r_in: f64,
    theta: f64,
}

/// The part's signed radius (mm) in the section from the CL section's `rho_s` and the
/// outline's contact radius `r_c`: `ρ_s − r_c`. A CL section more sharply convex than the
/// contact radius cannot come from a smooth part: it is treated as straight (conservative
/// against convex enlargement).
fn part_radius(rho_s: f64, r_c: f64) -> f64 {
    let rho = rho_s - r_c;
    if rho_s.is_finite() && rho_s > 0.0 && rho <= 0.0 {
        f64::INFINITY
    } else {
        rho
    }
}

/// Signed radius of curvature (mm) of the circle through three section points `(s, z)`,
/// positive when the middle point lies above the chord of the outer two (convex),
/// `INFINITY` when they are collinear.
pub fn signed_radius(p0: (f64, f64), p1: (f64, f64), p2: (f64, f64)) -> f64 {
    let a = ((p1.0 - p0.0).powi(2) + (p1.1 - p0.1).powi(2)).sqrt();
    let b = ((p2.0 - p1.0).powi(2) + (p2.1 - p1.1).powi(2)).sqrt();
    let c = ((p2.0 - p0.0).powi(2) + (p2.1 - p0.1).powi(2)).sqrt();
    let cross = (p1.0 - p0.0) * (p2.1 - p0.1) - (p1.1 - p0.1) * (p2.0 - p0.0);
    if cross.abs() <= 1e-14 * (a * c).max(1e-300) {
        return f64::INFINITY;
    }
    // cross > 0: p2 above the line p0→p1 extended, i.e. middle below the chord: concave.
    -(a * b * c) / (2.0 * cross)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ball() -> Cutter {
        Cutter::ball(6.0).unwrap()
    }
    fn bull() -> Cutter {
        Cutter::bull(6.0, 1.5).unwrap()
    }
    fn flat() -> Cutter {
        Cutter::flat(6.0).unwrap()
    }

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    #[test]
    fn ball_step_round_trips() {
        for &rho in &[f64::INFINITY, 5.0, 40.0, -8.0, -50.0] {
            let w = ball_step(3.0, rho, 0.01).unwrap();
            let h = ball_scallop(3.0, rho, w).unwrap();
            assert!((h - 0.01).abs() < 1e-12, "rho {rho}: w {w} h {h}");
        }
        let flat = ball_step(3.0, f64::INFINITY, 0.01).unwrap();
        assert!((flat - 2.0 * (2.0 * 3.0 * 0.01 - 1e-4_f64).sqrt()).abs() < 1e-12);
        assert!(ball_step(3.0, f64::INFINITY, 3.0).is_none());
        assert!(ball_step(3.0, -2.0, 0.01).is_none());
    }

    #[test]
    fn signed_radius_sign() {
        let r = 10.0_f64;
        let pt = |a: f64| (r * a.sin(), r * a.cos());
        let rc = signed_radius(pt(-0.1), pt(0.0), pt(0.1));
        assert!((rc - 10.0).abs() < 1e-9, "{rc}");
        let pv = |a: f64| (r * a.sin(), -r * a.cos());
        let rv = signed_radius(pv(-0.1), pv(0.0), pv(0.1));
        assert!((rv + 10.0).abs() < 1e-9, "{rv}");
    }

    /// A ball's outline is a circle of radius R whatever the motion: the step on a straight
    /// section is 2·sqrt(2Rh − h²) for every slope along and across (while the cusp stays
    /// below the equator), and the XY interval is that times sqrt((1+p²)/(1+p²+q²)).
    #[test]
    fn ball_any_slope() {
        let (m, h) = (SideStepModel::new(ball(), 0.01), 0.01f64);
        let w = 2.0 * (2.0 * 3.0 * h - h * h).sqrt();
        for p in [0.0, 0.3, -1.0, 4.0] {
            for q in [0.0, 0.5, -1.2] {
                let (_, th) = section_angles(p, q);
                assert!(rel(m.straight_step(p, q), w) < 1e-12, "p {p} q {q}");
                let dv = m.xy_interval(p, q, f64::INFINITY);
                let tv = ((1.0 + p * p) / (1.0 + p * p + q * q)).sqrt();
                assert!(rel(dv, w * tv) < 1e-12, "p {p} q {q}: {dv}");
                assert!(rel(th.cos(), tv) < 1e-12);
                assert!((m.predicted_scallop(p, q, f64::INFINITY, dv) - h).abs() < 1e-12);
                assert!(rel(m.effective_radius(p, q), 3.0) < 1e-12);
            }
        }
    }

    /// Bull moving along a slope α with no side slope: its contact radius across the motion is
    /// r + a / sin α (the worked example: 5.886 mm for bull:6:1.5 at 20°), and the effective
    /// radius tends to it as h → 0. Flat end mill: R / sin α.
    #[test]
    fn bull_and_flat_along_a_slope_take_the_apparent_radius() {
        for deg in [2.0f64, 10.0, 20.0, 45.0, 80.0] {
            let al = deg.to_radians();
            let p = al.tan();
            let want_bull = 1.5 + 1.5 / al.sin();
            let want_flat = 3.0 / al.sin();
            let sb = Silhouette::new(&bull(), al);
            let sf = Silhouette::new(&flat(), al);
            assert!(rel(sb.radius(0.0), want_bull) < 1e-12);
            assert!(rel(sf.radius(0.0), want_flat) < 1e-12);
            // The effective radius tends to the contact radius as O(h): for h = 1e-7,
            // 9e-7 relative at 2°, 3e-9 at 80°.
            let h = 1e-7;
            let rb = SideStepModel::new(bull(), h).effective_radius(p, 0.0);
            let rf = SideStepModel::new(flat(), h).effective_radius(p, 0.0);
            assert!(
                rel(rb, want_bull) < 1e-5,
                "bull {deg}°: {rb} vs {want_bull}"
            );
            assert!(
                rel(rf, want_flat) < 1e-5,
                "flat {deg}°: {rf} vs {want_flat}"
            );
        }
        // The worked example: bull:6:1.5, 20° along the passes, h = 0.05. The outline's
        // radius falls away from its lowest point (r + a²b²/D³), so at this finite h the
        // effective radius is 2.4 % below the contact radius 5.886 mm: 5.7474 mm, step
        // 1.5129 mm (the level-ground step is 3.8 mm).
        let m = SideStepModel::new(bull(), 0.05);
        let p = 20f64.to_radians().tan();
        let r_eff = m.effective_radius(p, 0.0);
        cam_core::assert_near!(r_eff, 5.7474, 1e-4);
        let w = m.xy_interval(p, 0.0, f64::INFINITY);
        cam_core::assert_near!(w, 2.0 * (2.0 * r_eff * 0.05 - 0.0025f64).sqrt(), 1e-12);
        cam_core::assert_near!(w, 1.5129, 1e-4);
        // The level-ground step the planner took before leaves ≈ 0.37 mm there.
        let w_level = m.xy_interval(0.0, 0.0, f64::INFINITY);
        cam_core::assert_near!(
            w_level,
            3.0 + 2.0 * (2.0 * 1.5 * 0.05 - 0.0025f64).sqrt(),
            1e-9
        );
        let left = scallop_of(&m.silhouette(p), 0.0, w_level);
        assert!((left - 0.37).abs() < 0.01, "{left}");
    }

    /// A flat end mill's reach in closed form agrees with Newton's method on the same
    /// outline, on both sides, where the walk ends on the arc and where it leaves it.
    #[test]
    fn flat_reach_in_closed_form_is_newtons() {
        // Walks that end on the arc (where the closed form is used): downhill, uphill.
        let mut on_arc = [0usize; 2];
        for al_deg in [0.5f64, 5.0, 20.0, 45.0, 70.0, 89.0, 90.0] {
            let sil = Silhouette::new(&flat(), al_deg.to_radians());
            for th_deg in [0.0f64, 1.0, 10.0, 30.0, 60.0, 85.0, 89.9] {
                let th = th_deg.to_radians();
                let x0 = sil.point(th);
                let height = |p: (f64, f64)| (x0.0 - p.0) * th.sin() - (x0.1 - p.1) * th.cos();
                let (h_end, h_side) = (
                    height(sil.point(th - FRAC_PI_2)),
                    height(sil.point(FRAC_PI_2)),
                );
                for h in [1e-6, 1e-3, 0.01, 0.05, 0.3, 1.0, 2.5] {
                    let (cm, cp) = sil.reach_with(th, h, true);
                    let (nm, np) = sil.reach_with(th, h, false);
                    // Measured: 5.4e-13 at most.
                    let tol = 2e-12 * (1.0 + nm.max(np));
                    assert!(
                        (cm - nm).abs() <= tol && (cp - np).abs() <= tol,
                        "α {al_deg}° θ {th_deg}° h {h}: ({cm}, {cp}) vs ({nm}, {np})"
                    );
                    on_arc[0] += usize::from(h_end >= h);
                    on_arc[1] += usize::from(h_side >= h);
                }
            }
        }
        assert!(on_arc[0] > 100 && on_arc[1] > 100, "{on_arc:?}");
    }

    /// Cusp height left by two copies of `sil` `w` apart along a straight section of slope
    /// `theta`: inverts [`Silhouette::reach`] by bisection on h.
    fn scallop_of(sil: &Silhouette, theta: f64, w: f64) -> f64 {
        let mut lo = 0.0;
        let mut hi = 10.0;
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            let (a, b) = sil.reach(theta, mid);
            if a + b < w {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        hi
    }

    /// Slopes across the passes only: a flat end mill leaves a saw-tooth,
    /// w = h / (sin θ cos θ); a bull whose contact and cusp flanks stay on its corner,
    /// 2·sqrt(2rh − h²); on level ground the bull's flat bottom adds 2a.
    #[test]
    fn slopes_across_the_passes() {
        let h = 0.01;
        for deg in [5.0f64, 30.0, 60.0, 85.0] {
            let th = deg.to_radians();
            let (dm, dp) = Silhouette::new(&flat(), 0.0).reach(th, h);
            assert!(rel(dm + dp, h / (th.sin() * th.cos())) < 1e-12, "{deg}°");
            cam_core::assert_near!(dm, h / th.tan(), 1e-12);
        }
        for deg in [30.0f64, 60.0] {
            let th = deg.to_radians();
            let (dm, dp) = Silhouette::new(&bull(), 0.0).reach(th, h);
            assert!(
                rel(dm + dp, 2.0 * (2.0 * 1.5 * h - h * h).sqrt()) < 1e-12,
                "{deg}°"
            );
            let m = SideStepModel::new(bull(), h);
            assert!(rel(m.effective_radius(0.0, th.tan()), 1.5) < 1e-9);
        }
        let (dm, dp) = Silhouette::new(&bull(), 0.0).reach(0.0, h);
        assert!(rel(dm + dp, 3.0 + 2.0 * (2.0 * 1.5 * h - h * h).sqrt()) < 1e-12);
        // Near vertical: the uphill side of the cutter lies along the section.
        let (_, dp) = Silhouette::new(&bull(), 0.0).reach(FRAC_PI_2, h);
        assert!(dp.is_infinite());
    }

    /// The outline's radius of curvature at the contact against Koenderink's relation for the
    /// torus: `cos²β (r + a / sin φ) + sin²β r`, φ the contact normal's tilt, β the angle
    /// between the motion and the meridian at the contact.
    #[test]
    fn outline_radius_is_the_apparent_radius_of_the_torus() {
        let (a, r) = (1.5, 1.5);
        for (p, q) in [
            (0.364, 0.0),
            (0.364, 0.5),
            (1.0, 2.0),
            (0.1, 0.05),
            (3.0, 0.2),
        ] {
            let (al, th) = section_angles(p, q);
            let got = Silhouette::new(&bull(), al).radius(th);
            // Contact normal of the cutter (into the part) ∝ (p, q, −1).
            let n = (1.0f64 + p * p + q * q).sqrt();
            let phi = (1.0 / n).acos();
            let psi = q.atan2(p);
            let m = (phi.cos() * psi.cos(), phi.cos() * psi.sin(), phi.sin());
            let d = (1.0 / (1.0 + p * p).sqrt(), 0.0, p / (1.0 + p * p).sqrt());
            let cb = m.0 * d.0 + m.1 * d.1 + m.2 * d.2;
            let want = cb * cb * (r + a / phi.sin()) + (1.0 - cb * cb) * r;
            assert!(rel(got, want) < 1e-12, "p {p} q {q}: {got} vs {want}");
        }
    }

    /// Brute-force projection of the cutter: the outline's height at `y` is the minimum of
    /// `z cos α − x sin α` over the cutter's lower surface (`Cutter::height_at`) along the
    /// chord at `y` (convex in x: golden section).
    fn brute_outline(c: &Cutter, al: f64, y: f64) -> Option<f64> {
        let rr = c.radius();
        if y.abs() > rr {
            return None;
        }
        let xm = (rr * rr - y * y).max(0.0).sqrt();
        let f = |x: f64| {
            let d = (x * x + y * y).sqrt().min(rr);
            c.height_at(d).unwrap() * al.cos() - x * al.sin()
        };
        let (mut lo, mut hi) = (-xm, xm);
        let g = (5f64.sqrt() - 1.0) / 2.0;
        for _ in 0..90 {
            let m1 = hi - g * (hi - lo);
            let m2 = lo + g * (hi - lo);
            if f(m1) <= f(m2) {
                hi = m2;
            } else {
                lo = m1;
            }
        }
        Some(f(0.5 * (lo + hi)).min(f(xm)).min(f(-xm)))
    }

    /// Lower boundary of the brute-force outline (with vertical sides) in the frame of a
    /// section line of slope `th` through `c0`: the height at along-distance `s`.
    fn brute_lower(c: &Cutter, al: f64, th: f64, c0: (f64, f64), s: f64) -> f64 {
        let rr = c.radius();
        let (sn, cs) = th.sin_cos();
        // Points on the line along = s: (y, z) = c0 + s (cs, sn) + t (−sn, cs).
        let at = |t: f64| (c0.0 + s * cs - t * sn, c0.1 + s * sn + t * cs);
        let inside = |t: f64| {
            let (y, z) = at(t);
            brute_outline(c, al, y).map_or(f64::NEG_INFINITY, |p| z - p)
        };
        if sn < 1e-15 {
            let (y, z) = at(0.0);
            return brute_outline(c, al, y).map_or(f64::INFINITY, |p| p - z);
        }
        // Feasible t: y within [−R, R] and z above the outline (a concave condition).
        let t_lo = (c0.0 + s * cs - rr) / sn;
        let t_hi = (c0.0 + s * cs + rr) / sn;
        let (mut lo, mut hi) = (t_lo, t_hi);
        let g = (5f64.sqrt() - 1.0) / 2.0;
        for _ in 0..90 {
            let m1 = hi - g * (hi - lo);
            let m2 = lo + g * (hi - lo);
            if inside(m1) >= inside(m2) {
                hi = m2;
            } else {
                lo = m1;
            }
        }
        let t_max = 0.5 * (lo + hi);
        if inside(t_max) < 0.0 {
            return f64::INFINITY;
        }
        if inside(t_lo) >= 0.0 {
            return t_lo;
        }
        let (mut a, mut b) = (t_lo, t_max);
        for _ in 0..64 {
            let m = 0.5 * (a + b);
            if inside(m) >= 0.0 {
                b = m;
            } else {
                a = m;
            }
        }
        b
    }

    /// Cusp height, by brute force, of two copies of the projected cutter `w` apart along a
    /// straight section of slope `th` (the lowest point of the upper envelope of the two
    /// lower boundaries between the contacts).
    fn brute_cusp(c: &Cutter, al: f64, th: f64, w: f64) -> f64 {
        // Contact: the outline point lowest in the section's normal direction.
        let (sn, cs) = th.sin_cos();
        let rr = c.radius();
        let depth = |y: f64| {
            let z = brute_outline(c, al, y).unwrap();
            -y * sn + z * cs
        };
        let (mut lo, mut hi) = (-rr, rr);
        let g = (5f64.sqrt() - 1.0) / 2.0;
        for _ in 0..90 {
            let m1 = hi - g * (hi - lo);
            let m2 = lo + g * (hi - lo);
            if depth(m1) <= depth(m2) {
                hi = m2;
            } else {
                lo = m1;
            }
        }
        let yc = if depth(rr) < depth(0.5 * (lo + hi)) {
            rr
        } else {
            0.5 * (lo + hi)
        };
        let c0 = (yc, brute_outline(c, al, yc).unwrap());
        let low = |s: f64| brute_lower(c, al, th, c0, s);
        // The contact is the minimum (0); the cusp where the rising right branch of the first
        // copy meets the falling left branch of the second.
        let (mut a, mut b) = (0.0, w);
        for _ in 0..64 {
            let m = 0.5 * (a + b);
            if low(m) < low(m - w) {
                a = m;
            } else {
                b = m;
            }
        }
        low(0.5 * (a + b)).min(low(0.5 * (a + b) - w))
    }

    /// Mixed slopes along and across, and all three cutters: the step from the outline walk
    /// leaves, by a brute-force projection of the cutter, a cusp of h to 1e-10 relative
    /// (measured: 1e-13 or better).
    #[test]
    fn straight_step_against_brute_force_projection() {
        let cases = [
            (bull(), 20.0, 0.0, 0.05),
            (bull(), 20.0, 15.0, 0.05),
            (bull(), 5.0, 40.0, 0.01),
            (bull(), 60.0, 30.0, 0.01),
            (bull(), 1.0, 0.0, 0.01),
            (bull(), 0.3, 2.0, 0.01),
            (flat(), 20.0, 0.0, 0.01),
            (flat(), 10.0, 30.0, 0.01),
            (flat(), 45.0, 60.0, 0.05),
            (Cutter::bull(10.0, 2.0).unwrap(), 35.0, 20.0, 0.02),
            (ball(), 30.0, 50.0, 0.01),
            (bull(), 0.0, 10.0, 0.01),
            (bull(), 0.0, 0.5, 0.01),
            (flat(), 0.0, 30.0, 0.01),
            (Cutter::bull(10.0, 2.0).unwrap(), 0.0, 3.0, 0.02),
        ];
        for (c, ad, td, h) in cases {
            let (al, th) = (f64::to_radians(ad), f64::to_radians(td));
            let (dm, dp) = Silhouette::new(&c, al).reach(th, h);
            let got = brute_cusp(&c, al, th, dm + dp);
            assert!(
                rel(got, h) < 1e-10,
                "{c} α {ad}° θ {td}°: step {} leaves {got} by brute force, want {h}",
                dm + dp
            );
        }
    }

    /// The outline's closed forms and bisection against the brute-force projection, and the
    /// table used by the CL-space check against the exact heights.
    #[test]
    fn outline_heights_match_brute_force_and_table() {
        for c in [ball(), bull(), flat(), Cutter::bull(10.0, 0.5).unwrap()] {
            for ad in [0.0f64, 0.5, 7.0, 20.0, 70.0] {
                let al = ad.to_radians();
                let sil = Silhouette::new(&c, al);
                let base = brute_outline(&c, al, 0.0).unwrap();
                cam_core::assert_near!(sil.lowest(), base, 1e-12, "{c} {ad}°");
                let tab = SectionProfile::new(sil);
                let rr = c.radius();
                let mut worst = 0.0f64;
                for k in 0..=2000 {
                    let y = rr * (k as f64 / 2000.0) * if k % 2 == 0 { 1.0 } else { -1.0 };
                    let exact = sil.height_at(y).unwrap();
                    let brute = brute_outline(&c, al, y).unwrap() - base;
                    // At |y| = R the outline is vertical: y pins the height down only to
                    // about sqrt(ε)·r.
                    let tol = if k == 2000 { 1e-7 } else { 1e-11 };
                    cam_core::assert_near!(exact, brute, tol, "{c} {ad}° y {y}");
                    // The table's error normal to the outline (its vertical error grows where
                    // the outline turns vertical, where the normal is nearly horizontal).
                    let y2 = y - 1e-6 * y.signum();
                    let slope = (exact - sil.height_at(y2).unwrap()) / 1e-6;
                    let err = (tab.height(y).unwrap() - exact).abs() / slope.hypot(1.0);
                    worst = worst.max(err);
                }
                assert!(worst < 5e-7, "{c} {ad}°: table error {worst}");
                assert!(sil.height_at(rr * 1.0001).is_none());
                assert!(tab.height(-rr * 1.0001).is_none());
            }
        }
    }

    /// The model's forward and inverse agree, and curvature behaves: convex lengthens,
    /// concave shortens the interval; a vertical CL section projects along the pass to a
    /// longer radius.
    #[test]
    fn model_round_trips_and_curvature() {
        for c in [ball(), bull(), flat()] {
            let m = SideStepModel::new(c, 0.01);
            for (p, q) in [(0.0, 0.0), (0.364, 0.0), (0.2, 0.7), (1.5, 0.1)] {
                // Concave: wider than the effective circle, which cannot sit in a tighter one.
                let concave = -(2.0 * m.effective_radius(p, q) + 40.0);
                for rho in [f64::INFINITY, 40.0, concave] {
                    let dv = m.xy_interval(p, q, rho);
                    assert!(dv > 0.0, "{c} p {p} q {q} rho {rho}");
                    let back = m.predicted_scallop(p, q, rho, dv);
                    if dv < 0.95 * 6.0 * 0.999 {
                        assert!(
                            (back - 0.01).abs() < 1e-9,
                            "{c} p {p} q {q} rho {rho}: {back}"
                        );
                    }
                }
                let flat_dv = m.xy_interval(p, q, f64::INFINITY);
                assert!(m.xy_interval(p, q, 40.0) >= flat_dv);
                assert!(m.xy_interval(p, q, concave) <= flat_dv);
            }
        }
        assert!(rel(section_radius(20.0, 0.0, 0.7), 20.0) < 1e-15);
        let al = 0.3f64;
        assert!(rel(section_radius(20.0, al.tan(), 0.0), 20.0 / al.cos()) < 1e-14);
        assert!(section_radius(f64::INFINITY, 0.5, 0.5).is_infinite());
    }

    /// A concave section tighter than the effective circle: the bull's flat-ground circle
    /// (35.6 mm for h = 0.05) does not fit a CL valley of radius 5 mm; the corner circle does,
    /// and round-trips.
    #[test]
    fn concave_section_tighter_than_the_effective_circle_uses_the_corner() {
        let m = SideStepModel::new(bull(), 0.05);
        let r_eff = m.effective_radius(0.0, 0.0);
        cam_core::assert_near!(
            r_eff,
            ((1.5 + (0.15f64 - 0.0025).sqrt()).powi(2) + 0.0025) / 0.1,
            1e-9
        );
        assert!(ball_step(r_eff, -5.0 - 1.5, 0.05).is_none());
        let want = ball_step(1.5, -5.0 - 1.5, 0.05).unwrap();
        cam_core::assert_near!(m.xy_interval(0.0, 0.0, -5.0), want, 1e-12);
        cam_core::assert_near!(m.predicted_scallop(0.0, 0.0, -5.0, want), 0.05, 1e-12);
        // A flat end mill moving level has no corner: no step fits. Moving on a slope α its
        // outline's smallest radius is R sin²α.
        let fm = SideStepModel::new(flat(), 0.05);
        assert_eq!(fm.xy_interval(0.0, 0.0, -5.0), 0.0);
        let (p, al) = (1.0, std::f64::consts::FRAC_PI_4);
        cam_core::assert_near!(fm.silhouette(p).min_radius(), 3.0 * al.sin().powi(2), 1e-12);
        assert!(fm.xy_interval(p, 0.0, -0.1) > 0.0);
    }

    /// The outline's radius of curvature is nowhere below its smallest radius (the premise of
    /// the concave fallback), which it takes at its ends.
    #[test]
    fn outline_radius_is_never_below_its_smallest() {
        for c in [ball(), bull(), flat(), Cutter::bull(10.0, 0.5).unwrap()] {
            for ad in [0.0f64, 3.0, 20.0, 60.0, 90.0] {
                let sil = Silhouette::new(&c, ad.to_radians());
                let m = sil.min_radius();
                for k in -100..=100 {
                    let g = k as f64 / 100.0 * FRAC_PI_2;
                    assert!(sil.radius(g) >= m * (1.0 - 1e-12), "{c} {ad}° γ {g}");
                }
                cam_core::assert_near!(sil.radius(FRAC_PI_2), m, 1e-12 * m.max(1.0));
            }
        }
    }

    #[test]
    fn bad_inputs_do_not_panic() {
        let m = SideStepModel::new(bull(), 0.01);
        for x in [f64::NAN, f64::INFINITY, -f64::INFINITY, 1e300] {
            let _ = m.xy_interval(x, 0.1, 20.0);
            let _ = m.xy_interval(0.1, x, x);
            let _ = m.predicted_scallop(x, x, x, x);
            let _ = m.section_height(x, x);
            let _ = m.section(x).height(x);
        }
        assert_eq!(Silhouette::new(&bull(), 0.2).reach(0.1, 0.0), (0.0, 0.0));
    }
}
