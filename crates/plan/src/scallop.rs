//! Independent measurement of the material a toolpath leaves: the cutter's swept lower
//! surface sampled in cross-sections across the passes, and its 3-D distance to the part.

use cam_core::{Cutter, MoveKind, Toolpath};

use crate::frame::Raster;

/// Where to measure: cross-sections `u = const` of the raster frame, each sampled along `v`.
#[derive(Debug, Clone, PartialEq)]
pub struct ScallopProbe {
    /// Raster angle (degrees) of the frame the stations are given in.
    pub angle_deg: f64,
    /// `u` (mm) of each cross-section.
    pub stations_u: Vec<f64>,
    /// `v` range (mm) measured in each cross-section (typically first to last pass).
    pub v_range: (f64, f64),
    /// Sample spacing along `v` (mm).
    pub dv_mm: f64,
}

/// What [`measure_scallop`] found.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ScallopReport {
    /// Largest thickness (mm) of material left above the part: the 3-D distance from a point
    /// of the swept surface to the nearest point of the part (so along the part's normal
    /// there), largest over the cusps found in the cross-sections.
    pub max_scallop_mm: f64,
    /// XY (mm) of the worst sample.
    pub at_xy: (f64, f64),
    /// Largest vertical depth (mm) of the swept surface below the part (gouge), 0 if none.
    pub max_gouge_mm: f64,
    /// Samples where some cut move covered the point and the part was there.
    pub samples: usize,
}

/// Lowest z (mm) of the cutter's lower surface over XY `p` while it moves in a straight line
/// from tip `a` to tip `b`, or `None` if it never passes over `p`. The height along the move
/// is the tip's z plus the profile height at the XY distance, a convex function of the
/// move parameter, minimised by ternary search.
fn swept_low(
    cutter: &Cutter,
    a: cam_core::DVec3,
    b: cam_core::DVec3,
    p: (f64, f64),
) -> Option<f64> {
    let rr = cutter.radius();
    let d = b.truncate() - a.truncate();
    let w = glam::DVec2::new(p.0, p.1) - a.truncate();
    let dd = d.length_squared();
    // Parameter interval where the XY distance is ≤ R.
    let (t0, t1) = if dd < 1e-24 {
        if w.length_squared() > rr * rr {
            return None;
        }
        (0.0, 0.0)
    } else {
        let tc = w.dot(d) / dd;
        let perp2 = (w - d * tc).length_squared();
        if perp2 > rr * rr {
            return None;
        }
        let half = ((rr * rr - perp2) / dd).sqrt();
        let (lo, hi) = ((tc - half).max(0.0), (tc + half).min(1.0));
        if lo > hi {
            return None;
        }
        (lo, hi)
    };
    let f = |t: f64| {
        let q = a.lerp(b, t);
        let dist = (glam::DVec2::new(p.0, p.1) - q.truncate()).length().min(rr);
        q.z + cutter.height_at(dist).unwrap_or(cutter.corner_radius())
    };
    let (mut lo, mut hi) = (t0, t1);
    for _ in 0..100 {
        if hi - lo < 1e-13 {
            break;
        }
        let m1 = lo + (hi - lo) / 3.0;
        let m2 = hi - (hi - lo) / 3.0;
        if f(m1) <= f(m2) {
            hi = m2;
        } else {
            lo = m1;
        }
    }
    Some(f(0.5 * (lo + hi)).min(f(t0)).min(f(t1)))
}

/// Distance (mm) from `x` to the nearest point of the part's surface `(x', y', part(x', y'))`
/// found by a pattern search (8 directions, step halved down to 1e-11 mm) from the best of
/// `seeds` (XY points). Always the distance to a point of the part, so never below the true
/// distance; it is the true distance where the part is smooth and `x` is closer to it than
/// its radius of curvature (the nearest point is then a local minimum reached from a seed
/// near it).
fn distance_to_part(
    part: &(dyn Fn(f64, f64) -> Option<f64> + Sync),
    x: (f64, f64, f64),
    seeds: &[(f64, f64)],
) -> Option<f64> {
    let d = |q: (f64, f64)| {
        part(q.0, q.1)
            .map(|z| ((q.0 - x.0).powi(2) + (q.1 - x.1).powi(2) + (z - x.2).powi(2)).sqrt())
    };
    let mut best: Option<((f64, f64), f64)> = None;
    for &q in seeds {
        if let Some(dq) = d(q)
            && best.is_none_or(|b| dq < b.1)
        {
            best = Some((q, dq));
        }
    }
    let (mut at, mut dist) = best?;
    let mut step = (0.5 * dist).max(1e-6);
    let dirs = [
        (1.0, 0.0),
        (-1.0, 0.0),
        (0.0, 1.0),
        (0.0, -1.0),
        (
            std::f64::consts::FRAC_1_SQRT_2,
            std::f64::consts::FRAC_1_SQRT_2,
        ),
        (
            -std::f64::consts::FRAC_1_SQRT_2,
            std::f64::consts::FRAC_1_SQRT_2,
        ),
        (
            std::f64::consts::FRAC_1_SQRT_2,
            -std::f64::consts::FRAC_1_SQRT_2,
        ),
        (
            -std::f64::consts::FRAC_1_SQRT_2,
            -std::f64::consts::FRAC_1_SQRT_2,
        ),
    ];
    let mut evals = 0;
    while step > 1e-11 && evals < 20_000 {
        let mut moved = false;
        for (dx, dy) in dirs {
            let q = (at.0 + step * dx, at.1 + step * dy);
            evals += 1;
            if let Some(dq) = d(q)
                && dq < dist
            {
                (at, dist) = (q, dq);
                moved = true;
            }
        }
        if !moved {
            step *= 0.5;
        }
    }
    Some(dist)
}

/// Measures the scallop (and any gouge) left by the cut moves of `toolpath` over the part
/// whose top surface is `part(x, y)` (mm; `None` off the part), in the cross-sections of
/// `probe`. Independent of the planner: it sweeps the cutter's exact lower profile along the
/// actual moves. In each cross-section the swept surface is sampled every `dv_mm`; where its
/// distance within the section down to the part's sampled section (a polyline) peaks (the
/// cusps), the peak is located by ternary search and the swept point's 3-D distance to the
/// part is measured ([`ScallopReport::max_scallop_mm`]): normal to the part, also where the
/// part slopes along the passes (where the in-section distance is longer by about
/// 1/cos α). Cusps are measured in decreasing order of their in-section distance while that
/// (an upper bound of the 3-D one, to the polyline's sagitta) can still exceed the largest
/// found.
pub fn measure_scallop(
    part: &(dyn Fn(f64, f64) -> Option<f64> + Sync),
    cutter: &Cutter,
    toolpath: &Toolpath,
    probe: &ScallopProbe,
) -> ScallopReport {
    use rayon::prelude::*;
    let f = Raster::new(probe.angle_deg);
    let rr = cutter.radius();
    let mut segs = Vec::new();
    for w in toolpath.moves.windows(2) {
        if w[1].kind == MoveKind::Cut {
            segs.push((w[0].pose.tip, w[1].pose.tip));
        }
    }
    let (v0, v1) = probe.v_range;
    let n = (((v1 - v0) / probe.dv_mm).ceil().max(1.0)) as usize;
    let per_station: Vec<ScallopReport> = probe
        .stations_u
        .par_iter()
        .map(|&u| {
            // Moves near this station (in frame coordinates, within R of the line u = const).
            let near: Vec<_> = segs
                .iter()
                .filter(|(a, b)| {
                    let (ua, _) = f.to_uv(a.x, a.y);
                    let (ub, _) = f.to_uv(b.x, b.y);
                    ua.min(ub) <= u + rr && ua.max(ub) >= u - rr
                })
                .copied()
                .collect();
            let vs: Vec<f64> = (0..=n)
                .map(|k| v0 + (v1 - v0) * k as f64 / n as f64)
                .collect();
            let part_z: Vec<Option<f64>> = vs
                .iter()
                .map(|&v| {
                    let (x, y) = f.to_xy(u, v);
                    part(x, y)
                })
                .collect();
            let swept_at = |v: f64| {
                let p = f.to_xy(u, v);
                near.iter()
                    .filter_map(|&(a, b)| swept_low(cutter, a, b, p))
                    .reduce(f64::min)
            };
            let swept: Vec<Option<f64>> = vs.iter().map(|&v| swept_at(v)).collect();
            // Thickness at (v, e) within the section: distance down to the part's polyline
            // near v, and the v of the nearest polyline point.
            let thick = |v: f64, e: f64| -> Option<(f64, f64)> {
                let k = (((v - v0) / (v1 - v0).max(1e-300)) * n as f64)
                    .round()
                    .clamp(0.0, n as f64) as usize;
                let sz = part_z[k]?;
                let reach = (e - sz).max(0.0) + probe.dv_mm;
                let mut best: Option<(f64, f64)> = None;
                let span = (reach / probe.dv_mm).ceil() as usize + 1;
                let lo = k.saturating_sub(span);
                let hi = (k + span).min(vs.len() - 1);
                for j in lo..hi {
                    if let (Some(z0), Some(z1)) = (part_z[j], part_z[j + 1]) {
                        let (d, t) = seg_dist((v, e), (vs[j], z0), (vs[j + 1], z1));
                        // Below the part's polyline counts as zero thickness (a gouge).
                        let below = e < z0
                            + (z1 - z0) * ((v - vs[j]) / (vs[j + 1] - vs[j])).clamp(0.0, 1.0)
                            && v >= vs[j]
                            && v <= vs[j + 1];
                        let d = if below { 0.0 } else { d };
                        if best.is_none_or(|b| d < b.0) {
                            best = Some((d, vs[j] + t * (vs[j + 1] - vs[j])));
                        }
                    }
                }
                best
            };
            let mut rep = ScallopReport {
                max_scallop_mm: 0.0,
                at_xy: f.to_xy(u, v0),
                max_gouge_mm: 0.0,
                samples: 0,
            };
            let mut t2 = vec![0.0f64; vs.len()];
            for k in 0..vs.len() {
                let (Some(e), Some(sz)) = (swept[k], part_z[k]) else {
                    continue;
                };
                rep.samples += 1;
                if e < sz {
                    rep.max_gouge_mm = rep.max_gouge_mm.max(sz - e);
                    continue;
                }
                if let Some((t, _)) = thick(vs[k], e) {
                    t2[k] = t;
                }
            }
            // Cusps: local maxima of the in-section thickness, largest first.
            let mut peaks: Vec<usize> = (0..vs.len())
                .filter(|&k| {
                    t2[k] > 0.0
                        && (k == 0 || t2[k] >= t2[k - 1])
                        && (k + 1 == vs.len() || t2[k] >= t2[k + 1])
                })
                .collect();
            peaks.sort_by(|&a, &b| t2[b].total_cmp(&t2[a]).then(a.cmp(&b)));
            // A sample is within about slope·dv/2 of its cusp, and the polyline within its
            // sagitta of the section: a cusp whose sample is more than dv below the largest
            // 3-D distance found cannot exceed it.
            let slack = probe.dv_mm;
            let g = |v: f64| swept_at(v).and_then(|e| thick(v, e)).map_or(0.0, |t| t.0);
            for &k in peaks.iter().take(MAX_CUSPS) {
                if t2[k] + slack < rep.max_scallop_mm {
                    break;
                }
                // Locate the cusp: the in-section thickness is unimodal about it. Keep the
                // best point evaluated: at a flat end mill's saw-tooth the cusp is the top of
                // a jump of the swept surface, approached but not attained.
                let (mut lo, mut hi) = (vs[k.saturating_sub(1)], vs[(k + 1).min(n)]);
                let mut top = (t2[k], vs[k]);
                for _ in 0..80 {
                    let m1 = lo + (hi - lo) / 3.0;
                    let m2 = hi - (hi - lo) / 3.0;
                    let (g1, g2) = (g(m1), g(m2));
                    for c in [(g1, m1), (g2, m2)] {
                        if c.0 > top.0 {
                            top = c;
                        }
                    }
                    if g1 < g2 {
                        lo = m1;
                    } else {
                        hi = m2;
                    }
                }
                for vm in [top.1, vs[k]] {
                    let Some(e) = swept_at(vm) else { continue };
                    let Some((_, foot)) = thick(vm, e) else {
                        continue;
                    };
                    let (x, y) = f.to_xy(u, vm);
                    let seeds = [(x, y), f.to_xy(u, foot)];
                    if let Some(t) = distance_to_part(part, (x, y, e), &seeds)
                        && t > rep.max_scallop_mm
                        && part(x, y).is_some_and(|z| e >= z)
                    {
                        rep.max_scallop_mm = t;
                        rep.at_xy = (x, y);
                    }
                }
            }
            rep
        })
        .collect();
    per_station.into_iter().fold(
        ScallopReport {
            max_scallop_mm: 0.0,
            at_xy: (f64::NAN, f64::NAN),
            max_gouge_mm: 0.0,
            samples: 0,
        },
        |acc, r| ScallopReport {
            max_scallop_mm: acc.max_scallop_mm.max(r.max_scallop_mm),
            at_xy: if r.max_scallop_mm > acc.max_scallop_mm {
                r.at_xy
            } else {
                acc.at_xy
            },
            max_gouge_mm: acc.max_gouge_mm.max(r.max_gouge_mm),
            samples: acc.samples + r.samples,
        },
    )
}

/// Most cusps measured in 3-D per cross-section.
const MAX_CUSPS: usize = 512;

/// Distance from `p` to the segment `a b`, and the segment parameter of the nearest point.
fn seg_dist(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (qx, qy) = (a.0 + t * dx, a.1 + t * dy);
    (((p.0 - qx).powi(2) + (p.1 - qy).powi(2)).sqrt(), t)
}
