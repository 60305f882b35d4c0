//! The interval from one pass to the next: the side-step model evaluated along the pass, then
//! verified in CL space and shrunk until the verified scallop is at most h.

use crate::config::PlanConfig;
use crate::frame::Raster;
use crate::{ClSurface, sidestep};

/// Model evaluation at one profile point `(u, z0)` of the pass at `v`: the XY interval, and
/// the `(ρ_cl, θ)` pairs it came from. The slope θ is that of the chord to the CL point at
/// the interval on the next pass (the seed's Algorithm 2), found by fixed-point iteration, and
/// never less than the steepest chord over `[v − w₀/2, v + w₀]`'s first half; ρ_cl is the
/// signed circumradius of the CL section through `v − δ, v, v + δ` and `v, v + δ, v + 2δ`.
pub(crate) fn model_at(
    s: &dyn ClSurface,
    f: &Raster,
    model: &sidestep::SideStepModel,
    (u, z0): (f64, f64),
    v: f64,
    delta: f64,
) -> (f64, [(f64, f64); 2]) {
    let z = |vv: f64| {
        let (x, y) = f.to_xy(u, vv);
        s.z_tip(x, y).filter(|z| z.is_finite())
    };
    let zs = [-1.0, 1.0, 2.0].map(|k| z(v + k * delta));
    let pts = [
        zs[0].map(|z| (-delta, z)),
        Some((0.0, z0)),
        zs[1].map(|z| (delta, z)),
        zs[2].map(|z| (2.0 * delta, z)),
    ];
    let mut rhos = [f64::INFINITY; 2];
    for (j, w) in pts.windows(3).take(2).enumerate() {
        if let (Some(a), Some(b), Some(c)) = (w[0], w[1], w[2]) {
            rhos[j] = sidestep::signed_radius(a, b, c);
        }
    }
    // Local slope from the two chords at v, as the starting guess.
    let mut slope = 0.0f64;
    for w in pts[..3].windows(2) {
        if let (Some(a), Some(b)) = (w[0], w[1]) {
            slope = slope.max(((b.1 - a.1) / (b.0 - a.0)).abs());
        }
    }
    let interval = |theta: f64| {
        rhos.iter()
            .map(|&r| model.xy_interval(r, theta))
            .fold(f64::INFINITY, f64::min)
    };
    let mut theta = slope.atan();
    let mut dv = interval(theta);
    for _ in 0..4 {
        let Some(z1) = (dv > 0.0).then(|| z(v + dv)).flatten() else {
            break;
        };
        let t = ((z1 - z0) / dv).abs().atan();
        let next = interval(t);
        theta = t;
        if (next - dv).abs() <= 1e-9 * dv {
            dv = next;
            break;
        }
        dv = next;
    }
    (dv, [(rhos[0], theta), (rhos[1], theta)])
}

/// Number of CL samples across the interval for the CL-space verification.
const VERIFY_Q: usize = 32;

/// Scallop (mm) left between the passes at `v` and `v + dv` in the cross-section `u`,
/// computed from the CL surface alone: the best surface the cutter can leave there is
/// `S*(y) = min_q z_tip(q) + height(|y − q|)` over CL samples q in `[v, v + dv]`; the
/// machined one is `E(y)`, the same over the two passes only. The scallop is the largest
/// `(E − S*)·cos θ` between the two passes' contact points with S*, θ the slope of S*'s
/// secant between those contacts.
/// `None` if the cutter touches nothing at a pass.
pub(crate) fn cl_scallop(
    s: &dyn ClSurface,
    f: &Raster,
    cfg: &PlanConfig,
    u: f64,
    v: f64,
    dv: f64,
) -> Option<f64> {
    let c = &cfg.cutter;
    let rr = c.radius();
    let z = |vv: f64| {
        let (x, y) = f.to_xy(u, vv);
        s.z_tip(x, y).filter(|z| z.is_finite())
    };
    let za = z(v)?;
    let zb = z(v + dv)?;
    let qs: Vec<(f64, f64)> = (0..=VERIFY_Q)
        .filter_map(|k| {
            let q = v + dv * k as f64 / VERIFY_Q as f64;
            match k {
                0 => Some((q, za)),
                _ if k == VERIFY_Q => Some((q, zb)),
                _ => z(q).map(|zq| (q, zq)),
            }
        })
        .collect();
    let prof = |d: f64| c.height_at(d.abs());
    let s_star = |y: f64| {
        qs.iter()
            .filter_map(|&(q, zq)| prof(y - q).map(|hq| zq + hq))
            .fold(f64::INFINITY, f64::min)
    };
    let ea = |y: f64| prof(y - v).map(|hq| za + hq);
    let eb = |y: f64| prof(y - v - dv).map(|hq| zb + hq);
    let n = 400;
    let (y0, y1) = (v - rr, v + dv + rr);
    let ys: Vec<f64> = (0..=n)
        .map(|k| y0 + (y1 - y0) * k as f64 / n as f64)
        .collect();
    let ss: Vec<f64> = ys.iter().map(|&y| s_star(y)).collect();
    // Contact of each pass with S*: last minimiser of Ea − S*, first minimiser of Eb − S*.
    let mut ya = None;
    let mut best = f64::INFINITY;
    for (k, &y) in ys.iter().enumerate() {
        if let Some(e) = ea(y)
            && ss[k].is_finite()
            && e - ss[k] <= best + 1e-12
        {
            best = best.min(e - ss[k]);
            ya = Some(k);
        }
    }
    let mut yb = None;
    let mut best = f64::INFINITY;
    for (k, &y) in ys.iter().enumerate().rev() {
        if let Some(e) = eb(y)
            && ss[k].is_finite()
            && e - ss[k] <= best + 1e-12
        {
            best = best.min(e - ss[k]);
            yb = Some(k);
        }
    }
    let (ka, kb) = (ya?, yb?);
    if ka >= kb {
        return Some(0.0);
    }
    // Slope of S* across the cusp region (its secant between the two contacts: S* is a
    // staircase at the scale of the q samples for a flat end mill).
    let (ya_y, yb_y) = (ys[ka], ys[kb]);
    let slope = (s_star(yb_y) - s_star(ya_y)) / (yb_y - ya_y);
    let norm = 1.0 / (1.0 + slope * slope).sqrt();
    let thick = |y: f64| -> f64 {
        let e = match (ea(y), eb(y)) {
            (Some(a), Some(b)) => a.min(b),
            (Some(a), None) => a,
            (None, Some(b)) => b,
            (None, None) => return 0.0,
        };
        let sy = s_star(y);
        if !(sy.is_finite() && norm.is_finite()) {
            return 0.0;
        }
        (e - sy).max(0.0) * norm
    };
    let mut kbest = ka;
    let mut tbest = 0.0f64;
    for (k, &y) in ys.iter().enumerate().take(kb + 1).skip(ka) {
        let t = thick(y);
        if t > tbest {
            tbest = t;
            kbest = k;
        }
    }
    let (mut lo, mut hi) = (ys[kbest.saturating_sub(1).max(ka)], ys[(kbest + 1).min(kb)]);
    for _ in 0..60 {
        let m1 = lo + (hi - lo) / 3.0;
        let m2 = hi - (hi - lo) / 3.0;
        if thick(m1) < thick(m2) {
            lo = m1;
        } else {
            hi = m2;
        }
    }
    Some(tbest.max(thick(0.5 * (lo + hi))))
}

#[cfg(test)]
mod tests {
    use super::*;
    use cam_core::Cutter;

    /// On a convex cylinder (CL radius 23 mm, ball R = 3), the model's interval is the exact
    /// formula and the CL-space verification of that interval finds h (to its sampling).
    #[test]
    fn model_and_verification_agree_on_a_cylinder() {
        let ball = Cutter::ball(6.0).unwrap();
        let cfg = PlanConfig {
            cutter: ball,
            ..PlanConfig::default()
        };
        let f = Raster::new(0.0);
        let cyl = |_x: f64, y: f64| -> Option<f64> {
            let q = 23.0f64 * 23.0 - y * y;
            (q >= 0.0).then(|| q.sqrt() - 3.0)
        };
        for v in [0.0, 1.5, 3.0] {
            let z0 = cyl(0.0, v).unwrap();
            let m = sidestep::SideStepModel::new(ball, 0.01);
            let (dv, info) = model_at(&cyl, &f, &m, (0.0, z0), v, 0.245);
            assert!((info[0].0 - 23.0).abs() < 1e-6, "{info:?}");
            let z1 = cyl(0.0, v + dv).unwrap();
            let chord = (dv * dv + (z1 - z0).powi(2)).sqrt();
            let h = sidestep::ball_scallop(3.0, 20.0, chord).unwrap();
            assert!((h - 0.01).abs() < 1e-9, "v {v}: model scallop {h}");
            let sc = cl_scallop(&cyl, &f, &cfg, 0.0, v, dv).unwrap();
            assert!((sc - 0.01).abs() < 1e-6, "v {v}: verified {sc}");
        }
        // A bull on the cylinder's plateau: the flat-ground model over-steps; the
        // verification sees the material the flat bottom bridges.
        let bull = Cutter::bull(10.0, 2.0).unwrap();
        let cfg = PlanConfig {
            cutter: bull,
            ..PlanConfig::default()
        };
        let bc = |_x: f64, y: f64| -> Option<f64> {
            if y.abs() <= 3.0 {
                return Some(30.0);
            }
            let c = y.abs() - 3.0;
            let q = 32.0f64 * 32.0 - c * c;
            (q >= 0.0).then(|| q.sqrt() - 2.0)
        };
        let m = sidestep::SideStepModel::new(bull, 0.01);
        let (dv, _) = model_at(&bc, &f, &m, (0.0, 30.0), 0.0, 0.2);
        assert!(dv > 6.0, "{dv}");
        assert!(cl_scallop(&bc, &f, &cfg, 0.0, 0.0, dv).unwrap() > 0.1);
    }
}
