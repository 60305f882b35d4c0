//! The interval from one pass to the next: the side-step model evaluated along the pass, then
//! verified in CL space and shrunk until the verified scallop is at most h.

use crate::feed::{Gap, MIN_DU_MM, Profile};
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
    /// The largest cusp (mm) the model predicts at the evaluation points for the interval
    /// evaluated ([`sidestep::SideStepModel::predicted_scallop`]; 0 without points).
    pub predicted: f64,
}

impl Profile {
    /// Whether the cutter touches nothing somewhere between samples `j` and `j + 1`.
    pub(crate) fn brk(&self, j: usize) -> bool {
        matches!(self.gaps[j], Gap::Break)
    }

    /// The plane `(n, d)` of the planar gap containing `u`, if it is one (see `feed::Gap`).
    pub(crate) fn plane_at(&self, u: f64) -> Option<(cam_core::DVec3, f64)> {
        let pts = &self.pts;
        if pts.len() < 2 || !(u >= pts[0].0 && u <= pts[pts.len() - 1].0) {
            return None;
        }
        let j = pts
            .partition_point(|p| p.0 <= u)
            .saturating_sub(1)
            .min(pts.len() - 2);
        match self.gaps[j] {
            Gap::Planar { .. } => self.cert[j].plane,
            _ => None,
        }
    }

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
/// back), `cur` and `next` (straight where there is no pass behind), and the slope along the
/// pass the steeper of `cur`'s (`slopes`) and `next`'s there. The interval is the minimum
/// over those points; `floor` only counts the points below it.
///
/// Where that circle is concave and tighter than [`CREASE_SPACINGS`] pass spacings, it may
/// be a crease of the CL surface (the cutter bridging a part corner) rather than a curvature
/// the passes resolve — its radius would shrink with the spacing and drive the step to zero.
/// There, and wherever a concave circle's modelled step is below `dv`, the scallop is
/// measured instead of modelled: the CL surface is dropped at a quarter,
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
    (cur, slopes): (&Profile, &AlongSlopes),
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
    let h = model.h();
    let next_slopes = AlongSlopes::new(next, model.cutter().corner_radius());
    let mut need = Need {
        interval: f64::INFINITY,
        ..Need::default()
    };
    let mut creases: Vec<(f64, f64, f64, f64, f64)> = Vec::new(); // u, z, z1, p, q
    for u in us {
        let (Some(z), Some(z1)) = (cur.z_at(u), next.z_at(u)) else {
            continue;
        };
        // The steeper of the two passes' slopes at u. The outline narrows as the motion
        // steepens; and where the passes straddle a crease of the CL surface (one on the
        // plate, one climbing the foot of a wall) the steeper pass's swept surface runs
        // closest to the CL surface below their chord, since a point δ below a line of slope
        // p lies δ·cos α from it. With this pass's slope alone the same crease, mirrored, read
        // 1/cos α ≈ 5.5 times deeper where this pass was the one on the plate: dome.obj took
        // three times as many passes on its near side as on its far side.
        let p = slopes.at(u).max(next_slopes.at(u));
        let q = (z1 - z) / dv;
        let mut rho = behind
            .and_then(|(b, dvb)| b.z_at(u).map(|z0| (dvb, z0)))
            .map_or(f64::INFINITY, |(dvb, z0)| {
                sidestep::signed_radius((-dvb, z0), (0.0, z), (dv, z1))
            });
        if rho.is_nan() {
            rho = f64::INFINITY;
        }
        let spacing = behind.map_or(dv, |(_, dvb)| dv.max(dvb));
        let at = model.at(p, q);
        let w = at.interval(rho);
        // A concave circle whose model step is below the interval being judged is measured
        // too. Through three passes straddling the foot of a wall the circle's radius shrinks
        // with their spacing, so once the passes had closed up there the circle fell outside
        // the crease band and the model kept them close: bull:6:1.5 on dome.obj read
        // ρ_cl = −1.4 mm at 0.12 mm spacing on the dome's near side, where the measurement
        // allows 0.23 mm and did allow 0.32 mm on its far side. On a smooth concave section
        // the measurement is the model to second order. (This holds where the model fits no
        // step at all, steep across the passes: its scallop there is the cutter's radius.)
        if rho < 0.0 && (-rho < CREASE_SPACINGS * spacing || w < dv) {
            creases.push((u, z, z1, p, q));
            continue;
        }
        if w < floor {
            need.steep += 1;
        }
        need.interval = need.interval.min(w);
        need.predicted = need.predicted.max(at.scallop(rho, dv));
    }
    // Suspected creases: measure the dip.
    need.creases = creases.len();
    let dips: Vec<Option<f64>> = {
        use rayon::prelude::*;
        creases
            .par_iter()
            .map(|&(u, z, z1, _, _)| {
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
    for (&(_, _, _, p, q), dip) in creases.iter().zip(dips) {
        let Some(dip) = dip else { continue };
        // In the plane perpendicular to the motion: the chord w across, the CL's dip below it
        // (vertical heights scale by cos α there) taken normal to the chord.
        let (alpha, theta) = sidestep::section_angles(p, q);
        let w = dv / theta.cos();
        let at = model.at(p, q);
        let re = at.effective_radius();
        let cusp = if w < 2.0 * re {
            re - (re * re - w * w / 4.0).sqrt()
        } else {
            re
        };
        let scallop = cusp + dip * alpha.cos() * theta.cos();
        // The interval scaled for this point: linear in the measured scallop (the dip grows
        // about linearly with the interval at a crease), never above the straight model.
        let straight = at.interval(f64::INFINITY);
        let w_need = if scallop > 0.0 {
            (dv * h / scallop).min(straight)
        } else {
            straight
        };
        if w_need < floor {
            need.steep += 1;
        }
        need.interval = need.interval.min(w_need);
        need.predicted = need.predicted.max(at.scallop(f64::INFINITY, dv));
        need.crease_scallop = need.crease_scallop.max(scallop);
    }
    if !need.interval.is_finite() {
        need.interval = model.xy_interval(0.0, 0.0, f64::INFINITY);
    }
    need
}

/// Slope `∂z/∂u` of a pass's CL profile along the pass at its points: the steeper of the two
/// neighbouring pairs' chords (the outline narrows as the motion steepens, so the steeper is
/// the conservative choice). Left out, so that a point takes the nearest pair kept on each
/// side within its run (slope 0 if there is none):
/// - pairs across a gap;
/// - pairs no longer than [`MIN_DU_MM`] (the refinement's floor): the unresolved vertical
///   jumps where a flat or bull cutter's side meets a wall across the pass, motions that cut
///   that wall with the cutter's side rather than the surface between passes;
/// - pairs on a convex arc of the profile turning at least `1 / (EDGE_ARC·r)` (r the corner
///   radius): there the corner rolls over an edge of the part (the CL profile is an arc of
///   radius r about it), the contact is the edge itself, and the steep motion sweeps no face
///   that a scallop could be left on; the faces either side are covered by their own
///   profile points. A face of convex radius ρ along the pass turns at `1/(ρ + r)`, so
///   only faces sharper than `(EDGE_ARC − 1)·r` count as edges.
#[derive(Debug, Clone, Default)]
pub(crate) struct AlongSlopes {
    us: Vec<f64>,
    slopes: Vec<f64>,
}

/// Profile arcs turning faster than `1 / (EDGE_ARC·r)` are a corner of radius r rolling over
/// an edge ([`AlongSlopes`]).
const EDGE_ARC: f64 = 1.25;

impl AlongSlopes {
    /// The slopes of `prof`'s points for a cutter of corner radius `r` mm.
    pub(crate) fn new(prof: &Profile, r: f64) -> AlongSlopes {
        let pts = &prof.pts;
        let n = pts.len();
        let m = n.saturating_sub(1);
        let mut keep: Vec<bool> = (0..m)
            .map(|j| pts[j + 1].0 - pts[j].0 > MIN_DU_MM)
            .collect();
        if r > 0.0 {
            let turn = |j: usize| ((pts[j + 1].1 - pts[j].1) / (pts[j + 1].0 - pts[j].0)).atan();
            let len = |j: usize| (pts[j + 1].0 - pts[j].0).hypot(pts[j + 1].1 - pts[j].1);
            let mut edge = vec![false; m];
            for j in 0..m.saturating_sub(1) {
                if prof.brk(j) || prof.brk(j + 1) || !(keep[j] && keep[j + 1]) {
                    continue;
                }
                let k = (turn(j) - turn(j + 1)) / (0.5 * (len(j) + len(j + 1)));
                if k * EDGE_ARC * r >= 1.0 {
                    edge[j] = true;
                    edge[j + 1] = true;
                }
            }
            for j in 0..m {
                keep[j] &= !edge[j];
            }
        }
        let pair = |j: usize| -> Option<f64> {
            keep[j].then(|| ((pts[j + 1].1 - pts[j].1) / (pts[j + 1].0 - pts[j].0)).abs())
        };
        // Nearest kept pair before each point (pairs j < k) and after it (pairs j ≥ k), not
        // across a gap.
        let mut before = vec![None; n];
        for k in 1..n {
            before[k] = if prof.brk(k - 1) {
                None
            } else {
                pair(k - 1).or(before[k - 1])
            };
        }
        let mut after = vec![None; n];
        for k in (0..m).rev() {
            after[k] = if prof.brk(k) {
                None
            } else {
                pair(k).or(after[k + 1])
            };
        }
        let slopes = before
            .iter()
            .zip(&after)
            .map(|(b, a)| match (b, a) {
                (Some(x), Some(y)) => f64::max(*x, *y),
                (Some(x), None) | (None, Some(x)) => *x,
                (None, None) => 0.0,
            })
            .collect();
        AlongSlopes {
            us: pts.iter().map(|p| p.0).collect(),
            slopes,
        }
    }

    /// The slope at the profile point nearest `u` (0 on an empty profile).
    pub(crate) fn at(&self, u: f64) -> f64 {
        if self.us.is_empty() {
            return 0.0;
        }
        let k = self.us.partition_point(|&x| x < u).min(self.us.len() - 1);
        let k = if k > 0 && (u - self.us[k - 1]).abs() < (self.us[k] - u).abs() {
            k - 1
        } else {
            k
        };
        self.slopes[k]
    }
}

/// What the model used at one CL point: the slope along the pass `p`, the chord slope across
/// `q` and the vertical section's signed radius `ρ_cl` (mm).
#[cfg(test)]
pub(crate) type ModelInput = (f64, f64, f64);

/// Model evaluation at one profile point `(u, z0)` of the pass at `v` whose CL profile slopes
/// `p` along the pass: the XY interval, and the inputs it came from. The slope across is
/// that of the chord to the CL point at the interval on the next pass (the seed's Algorithm
/// 2), found by fixed-point iteration from the local slope; ρ_cl is the signed circumradius
/// of the CL section through `v − δ, v, v + δ` and `v, v + δ, v + 2δ`. (The planner evaluates
/// the model against the next pass's profile, [`needed`]; this standalone form is the
/// tests' reference.)
#[cfg(test)]
pub(crate) fn model_at(
    s: &dyn ClSurface,
    f: &Raster,
    model: &sidestep::SideStepModel,
    (u, z0): (f64, f64),
    p: f64,
    v: f64,
    delta: f64,
) -> (f64, [ModelInput; 2]) {
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
    let interval = |q: f64| model.xy_interval_min(p, q, &rhos);
    let mut q = slope;
    let mut dv = interval(q);
    for _ in 0..4 {
        let Some(z1) = (dv > 0.0).then(|| z(v + dv)).flatten() else {
            break;
        };
        let t = ((z1 - z0) / dv).abs();
        let next = interval(t);
        q = t;
        if (next - dv).abs() <= 1e-9 * dv {
            dv = next;
            break;
        }
        dv = next;
    }
    (dv, [(p, q, rhos[0]), (p, q, rhos[1])])
}

/// Number of CL samples across the interval for the CL-space verification.
pub(crate) const VERIFY_Q: usize = 32;

/// A station of the CL-space verification: `u` (mm), the slope `p` along the pass there,
/// and the cutter's outline seen along that motion (built once, used for every trial step).
#[derive(Debug, Clone)]
pub(crate) struct Probe {
    u: f64,
    p: f64,
    outline: sidestep::SectionProfile,
}

impl Probe {
    /// Where the probe stands along the pass (mm).
    pub(crate) fn u(&self) -> f64 {
        self.u
    }

    /// The probe at `u` on a pass whose slopes are `slopes`.
    pub(crate) fn new(model: &sidestep::SideStepModel, slopes: &AlongSlopes, u: f64) -> Probe {
        let p = slopes.at(u);
        Probe {
            u,
            p,
            outline: model.section(p),
        }
    }
}

/// One piece of the CL section's polyline in the verification: from `(q0, z0)` to `(q1, z1)`
/// (`q0 = q1` for a lone sample), slope `s`, and the outline's offset `xs` from its tip to
/// where a line of slope `s` touches it.
#[derive(Debug, Clone, Copy)]
struct Piece {
    q0: f64,
    z0: f64,
    q1: f64,
    s: f64,
    xs: f64,
}

/// Scallop (mm) left between the passes at `v` and `v + dv` about the station `u`, where the
/// CL profile slopes `p` along the passes, computed from the CL surface alone in the plane
/// perpendicular to the motion `d = (1, 0, p)`: there each pass's swept surface is the
/// cutter's outline seen along `d` ([`sidestep::Silhouette`]), and the CL section is the
/// polyline through samples at 33 points across the interval (on the line `u`, projected
/// along `d`: heights scale by `cos α`). The best surface the cutter can leave there is the
/// lower boundary `S*` of that polyline swept by the outline (exact for the polyline: on each
/// piece of slope s the lowest point of the outline against a line of slope s, clamped to
/// the piece); the machined one is `E(y)`, the lower of the two passes' outlines. The
/// scallop is the largest `(E − S*)·cos θ` between the two passes' contact points with S*,
/// θ the slope of S*'s secant between them: a distance normal to the surface in that plane,
/// which holds the surface normal. `E − S*` is evaluated on a grid of 201 points over the
/// outlines' span, 65 over the cusp region, and either side of every kink and jump of E
/// (the outlines' rims and flat ends, the crossing of the two passes), then refined by
/// ternary search about the largest. `None` if the cutter touches nothing at a pass.
pub(crate) fn cl_scallop(
    s: &dyn ClSurface,
    f: &Raster,
    model: &sidestep::SideStepModel,
    probe: &Probe,
    v: f64,
    dv: f64,
) -> Option<f64> {
    let Probe { u, p, outline } = probe;
    let (u, p) = (*u, *p);
    let c = model.cutter();
    let (rr, a) = (c.radius(), c.major_radius());
    let ca = 1.0 / (1.0 + p * p).sqrt();
    let ca = if ca.is_finite() { ca } else { 1.0 };
    let sil = model.silhouette(p);
    let z = |vv: f64| {
        let (x, y) = f.to_xy(u, vv);
        s.z_tip(x, y).filter(|z| z.is_finite()).map(|z| z * ca)
    };
    let za = z(v)?;
    let zb = z(v + dv)?;
    let qs: Vec<Option<(f64, f64)>> = (0..=VERIFY_Q)
        .map(|k| {
            let q = v + dv * k as f64 / VERIFY_Q as f64;
            match k {
                0 => Some((q, za)),
                _ if k == VERIFY_Q => Some((q, zb)),
                _ => z(q).map(|zq| (q, zq)),
            }
        })
        .collect();
    let contact = |slope: f64| sil.point(slope.atan()).0;
    let mut pieces = Vec::new();
    for k in 0..qs.len() {
        let Some((q0, z0)) = qs[k] else { continue };
        match qs.get(k + 1).copied().flatten() {
            Some((q1, z1)) => {
                let sl = (z1 - z0) / (q1 - q0);
                pieces.push(Piece {
                    q0,
                    z0,
                    q1,
                    s: sl,
                    xs: contact(sl),
                });
            }
            None if k == 0 || qs[k - 1].is_none() => pieces.push(Piece {
                q0,
                z0,
                q1: q0,
                s: 0.0,
                xs: 0.0,
            }),
            None => {}
        }
    }
    let prof = |d: f64| outline.height(d);
    let s_star = |y: f64| {
        pieces
            .iter()
            .filter_map(|pc| {
                let (lo, hi) = ((y - pc.q1).max(-rr), (y - pc.q0).min(rr));
                if lo > hi {
                    return None;
                }
                let x = pc.xs.clamp(lo, hi);
                prof(x).map(|hx| pc.z0 + pc.s * (y - x - pc.q0) + hx)
            })
            .fold(f64::INFINITY, f64::min)
    };
    let ea = |y: f64| prof(y - v).map(|hq| za + hq);
    let eb = |y: f64| prof(y - v - dv).map(|hq| zb + hq);
    // Grid: the whole span, the cusp region (between the contacts of a line of the chord's
    // slope), and both sides of every kink and jump of E.
    let n = 200;
    let (y0, y1) = (v - rr, v + dv + rr);
    let mut ys: Vec<f64> = (0..=n)
        .map(|k| y0 + (y1 - y0) * k as f64 / n as f64)
        .collect();
    let xc = contact((zb - za) / dv);
    let m = 64;
    ys.extend((0..=m).map(|k| v + xc - dv + 3.0 * dv * k as f64 / m as f64));
    let eps = 1e-9 * (1.0 + rr);
    for base in [v, v + dv] {
        for off in [-rr, -a, a, rr] {
            ys.extend([base + off - eps, base + off + eps]);
        }
    }
    ys.retain(|y| y.is_finite() && *y >= y0 && *y <= y1);
    ys.sort_by(f64::total_cmp);
    ys.dedup();
    let ss: Vec<f64> = ys.iter().map(|&y| s_star(y)).collect();
    let eas: Vec<Option<f64>> = ys.iter().map(|&y| ea(y)).collect();
    let ebs: Vec<Option<f64>> = ys.iter().map(|&y| eb(y)).collect();
    // Contact of each pass with S*: last minimiser of Ea − S*, first minimiser of Eb − S*.
    let mut ya = None;
    let mut best = f64::INFINITY;
    for k in 0..ys.len() {
        if let Some(e) = eas[k]
            && ss[k].is_finite()
            && e - ss[k] <= best + 1e-12
        {
            best = best.min(e - ss[k]);
            ya = Some(k);
        }
    }
    let mut yb = None;
    let mut best = f64::INFINITY;
    for k in (0..ys.len()).rev() {
        if let Some(e) = ebs[k]
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
    // Slope of S* across the cusp region (its secant between the two contacts).
    let slope = (ss[kb] - ss[ka]) / (ys[kb] - ys[ka]);
    let norm = 1.0 / (1.0 + slope * slope).sqrt();
    let thick_with = |sy: f64, ea: Option<f64>, eb: Option<f64>| -> f64 {
        let e = match (ea, eb) {
            (Some(a), Some(b)) => a.min(b),
            (Some(a), None) => a,
            (None, Some(b)) => b,
            (None, None) => return 0.0,
        };
        if !(sy.is_finite() && norm.is_finite()) {
            return 0.0;
        }
        (e - sy).max(0.0) * norm
    };
    let thick = |y: f64| thick_with(s_star(y), ea(y), eb(y));
    let mut kbest = ka;
    let mut tbest = 0.0f64;
    for k in ka..=kb {
        let t = thick_with(ss[k], eas[k], ebs[k]);
        if t > tbest {
            tbest = t;
            kbest = k;
        }
    }
    // Where the two passes cross (E's cusp), located by bisection.
    for k in ka..kb {
        if let (Some(a0), Some(b0), Some(a1), Some(b1)) = (eas[k], ebs[k], eas[k + 1], ebs[k + 1])
            && (a0 - b0 <= 0.0) != (a1 - b1 <= 0.0)
        {
            let (mut lo, mut hi) = (ys[k], ys[k + 1]);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                match (ea(mid), eb(mid)) {
                    (Some(x), Some(y)) if (x - y <= 0.0) == (a0 - b0 <= 0.0) => lo = mid,
                    _ => hi = mid,
                }
            }
            tbest = tbest.max(thick(lo)).max(thick(hi));
        }
    }
    // Refine about the best grid point; keep the best point evaluated (E may jump there).
    let (mut lo, mut hi) = (ys[kbest.saturating_sub(1).max(ka)], ys[(kbest + 1).min(kb)]);
    for _ in 0..60 {
        let m1 = lo + (hi - lo) / 3.0;
        let m2 = hi - (hi - lo) / 3.0;
        let (t1, t2) = (thick(m1), thick(m2));
        tbest = tbest.max(t1).max(t2);
        if t1 < t2 {
            lo = m1;
        } else {
            hi = m2;
        }
    }
    Some(tbest)
}

#[cfg(test)]
mod tests {
    use super::*;
    use cam_core::Cutter;

    fn profile(pts: Vec<(f64, f64)>) -> Profile {
        let n = pts.len();
        let mut gaps = vec![
            Gap::Open {
                dip: Some(0.0),
                mid: None
            };
            n
        ];
        if let Some(g) = gaps.last_mut() {
            *g = Gap::Break;
        }
        Profile {
            cert: pts.iter().map(|p| crate::ClSample::bare(p.1)).collect(),
            pts,
            gaps,
            drops: 0,
        }
    }

    /// The slope along a pass: a plane's own slope; a vertical jump (a wall across the pass)
    /// and a corner rolling over an edge (an arc of the corner radius) are left out, points
    /// on them take the faces' slopes either side; a convex face of radius 5r is kept.
    #[test]
    fn along_slopes_leave_out_walls_and_edges() {
        let r = 1.5;
        // Plane rising at 0.2, a wall 3 mm high at u = 5 (a pair 5 µm long), plane again.
        let mut pts: Vec<(f64, f64)> = (0..=50)
            .map(|k| (0.1 * k as f64, 0.02 * k as f64))
            .collect();
        pts.push((5.0 + 5e-6, 1.0 + 3.0));
        pts.extend((1..=50).map(|k| (5.0 + 5e-6 + 0.1 * k as f64, 4.0 + 0.02 * k as f64)));
        let sl = AlongSlopes::new(&profile(pts.clone()), r);
        for &(u, _) in &pts {
            cam_core::assert_near!(sl.at(u), 0.2, 1e-9, "u {u}");
        }
        // Level ground, then the corner rolls off the edge at u = 0: an arc of radius r
        // (tip z = −r + sqrt(r² − u²) for 0 ≤ u < r), down to slope −3.
        let arc_end = r * 3.0 / 10f64.sqrt();
        let mut pts: Vec<(f64, f64)> = (0..=20).map(|k| (-2.0 + 0.1 * k as f64, 0.0)).collect();
        pts.extend((1..=40).map(|k| {
            let u = arc_end * k as f64 / 40.0;
            (u, -r + (r * r - u * u).sqrt())
        }));
        let sl = AlongSlopes::new(&profile(pts.clone()), r);
        for &(u, _) in &pts {
            assert!(sl.at(u) < 1e-9, "u {u}: {}", sl.at(u));
        }
        // A convex face of radius 5r along the pass (turning at 1/(5r + r) < 1/(1.25 r)):
        // its slope counts.
        let big = 6.0 * r;
        let pts: Vec<(f64, f64)> = (0..=40)
            .map(|k| {
                let u = 0.1 * k as f64;
                (u, (big * big - u * u).sqrt())
            })
            .collect();
        let sl = AlongSlopes::new(&profile(pts.clone()), r);
        let (u, _) = pts[30];
        let want = (pts[31].1 - pts[30].1) / (pts[31].0 - pts[30].0);
        cam_core::assert_near!(sl.at(u), want.abs(), 1e-12);
    }

    /// On a convex cylinder (CL radius 23 mm, ball R = 3), the model's interval is the exact
    /// formula and the CL-space verification of that interval finds h (to its sampling).
    #[test]
    fn model_and_verification_agree_on_a_cylinder() {
        let ball = Cutter::ball(6.0).unwrap();
        let f = Raster::new(0.0);
        let cyl = |_x: f64, y: f64| -> Option<f64> {
            let q = 23.0f64 * 23.0 - y * y;
            (q >= 0.0).then(|| q.sqrt() - 3.0)
        };
        for v in [0.0, 1.5, 3.0] {
            let z0 = cyl(0.0, v).unwrap();
            let m = sidestep::SideStepModel::new(ball, 0.01);
            let (dv, info) = model_at(&cyl, &f, &m, (0.0, z0), 0.0, v, 0.245);
            assert!((info[0].2 - 23.0).abs() < 1e-6, "{info:?}");
            let z1 = cyl(0.0, v + dv).unwrap();
            let chord = (dv * dv + (z1 - z0).powi(2)).sqrt();
            let h = sidestep::ball_scallop(3.0, 20.0, chord).unwrap();
            assert!((h - 0.01).abs() < 1e-9, "v {v}: model scallop {h}");
            // The verification sweeps the chords between its 33 CL samples: on a convex CL
            // section they lie below it by at most their sagitta, which can only raise the
            // scallop it reports.
            let sag = (dv / VERIFY_Q as f64).powi(2) / (8.0 * 23.0);
            let probe = Probe::new(&m, &AlongSlopes::default(), 0.0);
            let sc = cl_scallop(&cyl, &f, &m, &probe, v, dv).unwrap();
            assert!(
                sc >= 0.01 - 1e-9 && sc <= 0.01 + sag,
                "v {v}: verified {sc}, sagitta {sag}"
            );
        }
        // A bull on the cylinder's plateau: the flat-ground model over-steps; the
        // verification sees the material the flat bottom bridges.
        let bull = Cutter::bull(10.0, 2.0).unwrap();
        let bc = |_x: f64, y: f64| -> Option<f64> {
            if y.abs() <= 3.0 {
                return Some(30.0);
            }
            let c = y.abs() - 3.0;
            let q = 32.0f64 * 32.0 - c * c;
            (q >= 0.0).then(|| q.sqrt() - 2.0)
        };
        let m = sidestep::SideStepModel::new(bull, 0.01);
        let (dv, _) = model_at(&bc, &f, &m, (0.0, 30.0), 0.0, 0.0, 0.2);
        assert!(dv > 6.0, "{dv}");
        let probe = Probe::new(&m, &AlongSlopes::default(), 0.0);
        let sc = cl_scallop(&bc, &f, &m, &probe, 0.0, dv).unwrap();
        assert!(sc > 0.1, "{dv} {sc}");
    }
}
