//! The interval from one pass to the next: the side-step model evaluated along the pass, then
//! verified in CL space and shrunk until the verified scallop is at most h.

use crate::config::PlanConfig;
use crate::feed::{Gap, Profile};
use crate::frame::Raster;
use crate::{ClSurface, sidestep};

/// Besides every sample of both passes, the side-step model is evaluated at points this far
/// apart (mm) along the pass, so passes with few samples (planar stretches) are covered.
pub const EVAL_SPACING_MM: f64 = 1.0;

/// A concave circle through three passes whose radius is below this many pass spacings may
/// be a crease of the CL surface; the scallop there is measured (see [`needed`]). Through
/// three points spaced d across a kink sharper than about 25°, the circle's radius is 2d–10d
/// depending on where the kink falls.
pub const CREASE_SPACINGS: f64 = 10.0;

/// The side-step model evaluated between two passes.
#[derive(Debug, Clone, Default)]
pub(crate) struct Need {
    /// The largest XY interval (mm) the model allows at every evaluation point.
    pub interval: f64,
    /// Evaluation points where it fell below `floor`.
    pub steep: usize,
    /// Evaluation points on a suspected concave CL crease, where the scallop was measured
    /// (see [`needed`]).
    pub creases: usize,
    /// Largest scallop (mm) measured there at the interval evaluated.
    pub crease_scallop: f64,
    /// Drops spent measuring.
    pub drops: usize,
    /// The `(ρ_cl, θ)` of every evaluation point.
    pub evals: Vec<(f64, f64)>,
}

impl Profile {
    /// The profile's z (mm) at `u`, linear between samples; `None` outside it or across a
    /// break.
    pub(crate) fn z_at(&self, u: f64) -> Option<f64> {
        let pts = &self.pts;
        let (first, last) = (pts.first()?, pts.last()?);
        if !(u >= first.0 && u <= last.0) {
            return None;
        }
        let j = pts.partition_point(|p| p.0 <= u).saturating_sub(1);
        if pts[j].0 == u {
            return Some(pts[j].1);
        }
        if j + 1 >= pts.len() || self.gaps[j] == Gap::Break {
            return None;
        }
        let ((u0, z0), (u1, z1)) = (pts[j], pts[j + 1]);
        Some(z0 + (z1 - z0) * (u - u0) / (u1 - u0))
    }
}

/// The side-step model between the pass `cur` and the pass `next` `dv` mm further along `v`
/// (the seed's Algorithm 2): at every sample of both passes and every
/// [`EVAL_SPACING_MM`] along `cur`, θ is the slope of the chord from `cur` to `next` across
/// the passes and ρ_cl the signed radius of the circle through the pass `behind` (`dvb` mm
/// back), `cur` and `next` (straight where there is no pass behind). The interval is the
/// minimum over those points; `floor` only counts the points below it.
///
/// Where that circle is concave and tighter than [`CREASE_SPACINGS`] pass spacings, it may
/// be a crease of the CL surface (the cutter bridging a part corner) rather than a curvature
/// the passes resolve — its radius would shrink with the spacing and drive the step to zero.
/// There the scallop is measured instead of modelled: the CL surface is dropped at a quarter,
/// half and three quarters of the interval and the scallop taken as the straight-section
/// cusp for the chord plus the CL's largest dip below the chord (normal to it): to second
/// order this is the re-derived Eq. 2 on a concave section, and at a crease it is the
/// material the two passes leave above the cutter standing in the corner.
#[allow(clippy::too_many_arguments)]
pub(crate) fn needed(
    s: &dyn ClSurface,
    f: &Raster,
    v: f64,
    model: &sidestep::SideStepModel,
    behind: Option<(&Profile, f64)>,
    cur: &Profile,
    next: &Profile,
    dv: f64,
    floor: f64,
) -> Need {
    let mut us: Vec<f64> = cur.pts.iter().chain(next.pts.iter()).map(|p| p.0).collect();
    if let (Some(a), Some(b)) = (cur.pts.first(), cur.pts.last()) {
        let n = ((b.0 - a.0) / EVAL_SPACING_MM).ceil() as usize;
        us.extend((1..n).map(|k| a.0 + (b.0 - a.0) * k as f64 / n as f64));
    }
    us.sort_by(f64::total_cmp);
    us.dedup();
    let h = model.scallop();
    let mut need = Need {
        interval: f64::INFINITY,
        ..Need::default()
    };
    let mut creases: Vec<(f64, f64, f64, f64)> = Vec::new(); // u, z, z1, θ
    for u in us {
        let (Some(z), Some(z1)) = (cur.z_at(u), next.z_at(u)) else {
            continue;
        };
        let theta = ((z1 - z) / dv).abs().atan();
        let mut rho = behind
            .and_then(|(b, dvb)| b.z_at(u).map(|z0| (dvb, z0)))
            .map_or(f64::INFINITY, |(dvb, z0)| {
                sidestep::signed_radius((-dvb, z0), (0.0, z), (dv, z1))
            });
        if rho.is_nan() {
            rho = f64::INFINITY;
        }
        let spacing = behind.map_or(dv, |(_, dvb)| dv.max(dvb));
        if rho < 0.0 && -rho < CREASE_SPACINGS * spacing {
            creases.push((u, z, z1, theta));
            continue;
        }
        let w = model.xy_interval(rho, theta);
        if w < floor {
            need.steep += 1;
        }
        need.interval = need.interval.min(w);
        need.evals.push((rho, theta));
    }
    // Suspected creases: measure the dip.
    need.creases = creases.len();
    let dips: Vec<Option<f64>> = {
        use rayon::prelude::*;
        creases
            .par_iter()
            .map(|&(u, z, z1, _)| {
                let mut dip = 0.0f64;
                for k in 1..4 {
                    let t = k as f64 / 4.0;
                    let (x, y) = f.to_xy(u, v + t * dv);
                    let zq = s.z_tip(x, y)?;
                    dip = dip.max(z + t * (z1 - z) - zq);
                }
                Some(dip)
            })
            .collect()
    };
    need.drops += 3 * creases.len();
    for (&(_, z, z1, theta), dip) in creases.iter().zip(dips) {
        let Some(dip) = dip else { continue };
        let w = ((dv * dv) + (z1 - z) * (z1 - z)).sqrt();
        let re = model.effective_radius(theta);
        let cusp = if w < 2.0 * re {
            re - (re * re - w * w / 4.0).sqrt()
        } else {
            re
        };
        let scallop = cusp + dip * theta.cos();
        // The interval scaled for this point: linear in the measured scallop (the dip grows
        // about linearly with the interval at a crease), never above the straight model.
        let straight = model.xy_interval(f64::INFINITY, theta);
        let w_need = if scallop > 0.0 {
            (dv * h / scallop).min(straight)
        } else {
            straight
        };
        if w_need < floor {
            need.steep += 1;
        }
        need.interval = need.interval.min(w_need);
        need.evals.push((f64::INFINITY, theta));
        need.crease_scallop = need.crease_scallop.max(scallop);
    }
    if !need.interval.is_finite() {
        need.interval = model.xy_interval(f64::INFINITY, 0.0);
    }
    need
}

#[cfg(test)]
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
pub(crate) const VERIFY_Q: usize = 32;

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
