//! Independent measurement of the material a toolpath leaves: the cutter's swept lower
//! surface in cross-sections across the passes, against the part's section.

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
    /// Largest thickness (mm) of material left above the part, measured in the cross-section
    /// as the distance from the swept surface down to the part's section (≈ normal height).
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

/// Measures the scallop (and any gouge) left by the cut moves of `toolpath` over the part
/// whose top surface is `part(x, y)` (mm; `None` off the part), in the cross-sections of
/// `probe`. Independent of the planner: it sweeps the cutter's exact lower profile along the
/// actual moves. The thickness at a sample is the 2-D distance in the cross-section from the
/// swept surface down to the part's sampled section (a polyline at the same spacing).
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
            // Thickness at (v, e): distance in the section down to the part's polyline near v.
            let thick = |v: f64, e: f64| -> Option<f64> {
                let k = (((v - v0) / (v1 - v0).max(1e-300)) * n as f64)
                    .round()
                    .clamp(0.0, n as f64) as usize;
                let sz = part_z[k]?;
                let reach = (e - sz).max(0.0) + probe.dv_mm;
                let mut best = f64::INFINITY;
                let span = (reach / probe.dv_mm).ceil() as usize + 1;
                let lo = k.saturating_sub(span);
                let hi = (k + span).min(vs.len() - 1);
                for j in lo..hi {
                    if let (Some(z0), Some(z1)) = (part_z[j], part_z[j + 1]) {
                        let d = seg_dist((v, e), (vs[j], z0), (vs[j + 1], z1));
                        // Below the part's polyline counts as zero thickness (a gouge).
                        let below = e < z0
                            + (z1 - z0) * ((v - vs[j]) / (vs[j + 1] - vs[j])).clamp(0.0, 1.0)
                            && v >= vs[j]
                            && v <= vs[j + 1];
                        best = best.min(if below { 0.0 } else { d });
                    }
                }
                best.is_finite().then_some(best)
            };
            let mut rep = ScallopReport {
                max_scallop_mm: 0.0,
                at_xy: f.to_xy(u, v0),
                max_gouge_mm: 0.0,
                samples: 0,
            };
            let mut best_k = None;
            for k in 0..vs.len() {
                let (Some(e), Some(sz)) = (swept[k], part_z[k]) else {
                    continue;
                };
                rep.samples += 1;
                if e < sz {
                    rep.max_gouge_mm = rep.max_gouge_mm.max(sz - e);
                    continue;
                }
                if let Some(t) = thick(vs[k], e)
                    && t > rep.max_scallop_mm
                {
                    rep.max_scallop_mm = t;
                    rep.at_xy = f.to_xy(u, vs[k]);
                    best_k = Some(k);
                }
            }
            // Refine the worst sample: the thickness is unimodal about a cusp.
            if let Some(k) = best_k {
                let g = |v: f64| swept_at(v).and_then(|e| thick(v, e)).unwrap_or(0.0);
                let (mut lo, mut hi) = (vs[k.saturating_sub(1)], vs[(k + 1).min(n)]);
                for _ in 0..80 {
                    let m1 = lo + (hi - lo) / 3.0;
                    let m2 = hi - (hi - lo) / 3.0;
                    if g(m1) < g(m2) {
                        lo = m1;
                    } else {
                        hi = m2;
                    }
                }
                let vm = 0.5 * (lo + hi);
                let t = g(vm);
                if t > rep.max_scallop_mm {
                    rep.max_scallop_mm = t;
                    rep.at_xy = f.to_xy(u, vm);
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

fn seg_dist(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (qx, qy) = (a.0 + t * dx, a.1 + t * dy);
    ((p.0 - qx).powi(2) + (p.1 - qy).powi(2)).sqrt()
}
