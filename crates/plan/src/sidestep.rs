//! Side-step (scallop) geometry: the scallop-limited interval between neighbouring passes.
//!
//! Derivation in `docs/plan-math.md`. All lengths in mm. Curvature radii are *signed*:
//! positive where the surface is convex (a hill) across the passes, negative where concave.

use cam_core::{Cutter, CutterKind};

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

/// Along-surface distances `(d_minus, d_plus)` (mm) from the contact point at which the
/// cutter's axial profile rises `h` mm (normal to the surface) above a straight surface that
/// slopes at `theta` radians across the passes. Exact for the ball; for flat and bull cutters
/// the profile (flat bottom, corner arcs of radius `r`, cylindrical side) is walked
/// numerically in a frame aligned with the surface.
pub fn flat_surface_reach(cutter: &Cutter, theta: f64, h: f64) -> (f64, f64) {
    if cutter.kind() == CutterKind::Ball {
        let r = cutter.radius();
        let d = (2.0 * r * h - h * h).max(0.0).sqrt();
        return (d, d);
    }
    reach_on(&profile_points(cutter), theta, h)
}

/// [`flat_surface_reach`] on a precomputed outline ([`profile_points`]).
fn reach_on(pts: &[(f64, f64)], theta: f64, h: f64) -> (f64, f64) {
    let th = theta.abs().min(std::f64::consts::FRAC_PI_2);
    let (sn, cs) = th.sin_cos();
    // Rotate so the surface is horizontal: along-surface s, normal height t.
    let rot: Vec<(f64, f64)> = pts
        .iter()
        .map(|&(x, z)| (x * cs - z * sn, x * sn + z * cs))
        .collect();
    let (kmin, _) = rot
        .iter()
        .enumerate()
        .fold((0, f64::INFINITY), |(bk, bt), (k, p)| {
            if p.1 < bt { (k, p.1) } else { (bk, bt) }
        });
    let (s0, t0) = rot[kmin];
    let target = t0 + h;
    let cross = |range: &mut dyn Iterator<Item = usize>| -> f64 {
        let mut prev = rot[kmin];
        for k in range {
            let p = rot[k];
            if p.1 >= target {
                let f = if p.1 > prev.1 {
                    (target - prev.1) / (p.1 - prev.1)
                } else {
                    1.0
                };
                return (prev.0 + f * (p.0 - prev.0) - s0).abs();
            }
            prev = p;
        }
        (prev.0 - s0).abs()
    };
    let dm = cross(&mut (0..kmin).rev());
    let dp = cross(&mut (kmin + 1..rot.len()));
    (dm, dp)
}

/// The cutter's lower outline in its axial plane, from the top of the left side round the
/// bottom to the top of the right side, as (x, z) with the tip at the origin.
fn profile_points(cutter: &Cutter) -> Vec<(f64, f64)> {
    let rr = cutter.radius();
    let a = cutter.major_radius();
    let r = cutter.corner_radius();
    let top = 2.0 * rr + 1.0;
    const N: usize = 4000;
    let mut right = Vec::with_capacity(N + 2);
    right.push((0.0, 0.0));
    if a > 0.0 {
        right.push((a, 0.0));
    }
    if r > 0.0 {
        for k in 1..=N {
            let phi = k as f64 / N as f64 * std::f64::consts::FRAC_PI_2;
            right.push((a + r * phi.sin(), r - r * phi.cos()));
        }
    }
    right.push((rr, top));
    let mut pts: Vec<(f64, f64)> = right.iter().rev().map(|&(x, z)| (-x, z)).collect();
    pts.pop(); // the shared tip point
    pts.extend(right);
    pts
}

/// Effective radius (mm) of the cutter across the passes on a surface sloping at `theta`
/// radians for cusp height `h`: the radius of the circle that leaves the same cusp at the
/// same flat-surface side step, `r_eff = ((w/2)² + h²) / (2h)` with `w = d₋ + d₊` from
/// [`flat_surface_reach`]. Exactly `R` for a ball; the corner radius `r` for a bull whose
/// contact stays on the corner (slopes with `r(1 − cos θ) ≥ h`); larger on flatter ground,
/// where the flat bottom widens the step (`w = 2a + 2·sqrt(2rh − h²)` at θ = 0).
pub fn effective_radius(cutter: &Cutter, theta: f64, h: f64) -> f64 {
    if cutter.kind() == CutterKind::Ball {
        return cutter.radius();
    }
    let (dm, dp) = flat_surface_reach(cutter, theta, h);
    let w = (dm + dp).min(MAX_STEPOVER_FRACTION * cutter.diameter());
    ((w / 2.0).powi(2) + h * h) / (2.0 * h)
}

/// The radius (mm) of the cutter's profile at its contact point: `R` for a ball, the corner
/// radius `r` for a bull, 0 for a flat end mill. The CL section's curvature radius is the
/// part's plus this (where the contact stays on the corner).
pub fn contact_radius(cutter: &Cutter) -> f64 {
    cutter.corner_radius()
}

/// Local side-step estimate at one CL point: `w·cos θ` (XY, mm) where `w` is
/// [`ball_step`] for the effective radius and the part's curvature radius
/// `ρ = ρ_cl − r_contact`, capped at [`MAX_STEPOVER_FRACTION`]·D. `rho_cl` is the CL
/// section's signed radius of curvature across the passes, `theta` its slope (radians).
pub fn xy_interval(cutter: &Cutter, rho_cl: f64, theta: f64, h: f64) -> f64 {
    interval_with(cutter, effective_radius(cutter, theta, h), rho_cl, theta, h)
}

/// Predicted cusp height (mm) at a CL point when neighbouring passes are `dv` mm apart in XY,
/// the forward model of [`xy_interval`].
pub fn predicted_scallop(cutter: &Cutter, rho_cl: f64, theta: f64, h: f64, dv: f64) -> f64 {
    scallop_with(
        cutter,
        effective_radius(cutter, theta, h),
        rho_cl,
        theta,
        dv,
    )
}

/// Number of slope steps over [0°, 90°] in [`SideStepModel`]'s effective-radius table.
const TABLE_STEPS: usize = 1800;

/// The side-step model of one cutter and scallop height, with the effective radius
/// tabulated over the slope (0.05° steps, linear interpolation) so evaluating it costs O(1).
#[derive(Debug, Clone)]
pub struct SideStepModel {
    cutter: Cutter,
    h: f64,
    table: Vec<f64>,
}

impl SideStepModel {
    /// Tabulates [`effective_radius`] for `cutter` and scallop `h` (mm).
    pub fn new(cutter: Cutter, h: f64) -> SideStepModel {
        let table = if cutter.kind() == CutterKind::Ball {
            Vec::new()
        } else {
            let pts = profile_points(&cutter);
            let cap = MAX_STEPOVER_FRACTION * cutter.diameter();
            (0..=TABLE_STEPS)
                .map(|k| {
                    let th = k as f64 / TABLE_STEPS as f64 * std::f64::consts::FRAC_PI_2;
                    let (dm, dp) = reach_on(&pts, th, h);
                    let w = (dm + dp).min(cap);
                    ((w / 2.0).powi(2) + h * h) / (2.0 * h)
                })
                .collect()
        };
        SideStepModel { cutter, h, table }
    }

    /// The scallop height h (mm) the model was built for.
    pub fn scallop(&self) -> f64 {
        self.h
    }

    /// Effective radius (mm) at slope `theta` (radians); see [`effective_radius`].
    pub fn effective_radius(&self, theta: f64) -> f64 {
        if self.table.is_empty() {
            return self.cutter.radius();
        }
        let x = (theta.abs() / std::f64::consts::FRAC_PI_2).min(1.0) * TABLE_STEPS as f64;
        let k = (x.floor() as usize).min(TABLE_STEPS - 1);
        let f = x - k as f64;
        self.table[k] * (1.0 - f) + self.table[k + 1] * f
    }

    /// [`xy_interval`] with the tabulated effective radius.
    pub fn xy_interval(&self, rho_cl: f64, theta: f64) -> f64 {
        interval_with(
            &self.cutter,
            self.effective_radius(theta),
            rho_cl,
            theta,
            self.h,
        )
    }

    /// [`predicted_scallop`] with the tabulated effective radius.
    pub fn predicted_scallop(&self, rho_cl: f64, theta: f64, dv: f64) -> f64 {
        scallop_with(
            &self.cutter,
            self.effective_radius(theta),
            rho_cl,
            theta,
            dv,
        )
    }
}

fn part_radius(cutter: &Cutter, rho_cl: f64) -> f64 {
    let rho = rho_cl - contact_radius(cutter);
    // A CL section more sharply convex than the contact radius cannot come from a smooth
    // part: treat it as straight (conservative against convex enlargement).
    if rho_cl.is_finite() && rho_cl > 0.0 && rho <= 0.0 {
        f64::INFINITY
    } else {
        rho
    }
}

fn interval_with(cutter: &Cutter, r_eff: f64, rho_cl: f64, theta: f64, h: f64) -> f64 {
    let cap = MAX_STEPOVER_FRACTION * cutter.diameter();
    let rho = part_radius(cutter, rho_cl);
    // No step leaves a cusp of h: on a convex section that sharp the cusp stays below h
    // at every step (the cutter rolls round the edge), so the cap applies; on a concave one
    // tighter than the cutter no step is safe.
    let w = ball_step(r_eff, rho, h).map_or(if rho > 0.0 { cap } else { 0.0 }, |w| w.min(cap));
    w * theta.cos()
}

fn scallop_with(cutter: &Cutter, r_eff: f64, rho_cl: f64, theta: f64, dv: f64) -> f64 {
    let c = theta.cos();
    let w = if c > 1e-12 { dv / c } else { f64::INFINITY };
    ball_scallop(r_eff, part_radius(cutter, rho_cl), w).unwrap_or(r_eff)
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
}
