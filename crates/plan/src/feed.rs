//! Feed-forward marching along one pass: exact CL profile, then the longest chords that stay
//! within the tolerance of the exact CL surface at every check point.
//!
//! A pass is the line `v = const` of the raster frame. Its profile is the exact tool-tip z at
//! a set of `u` positions: the caller's samples (constant arc length on the part) merged with
//! a uniform grid of spacing `c`, then refined ([`refine`]) until every neighbour pair passes
//! the linearity test (the exact z at their midpoint within η/2 of their chord, η = 0.2·τ).
//! Marching (the paper's Algorithm 1 with an exact check) goes from CL point `L_i` to the
//! farthest profile point `L_k` it can find for which the straight move `L_i → L_k` differs
//! from the exact CL z by at most `τ − η` at every profile point strictly between them. The
//! search starts at the Eq. 1 step estimate and gallops up or bisects down from there.
//! Between profile points the CL surface is within η of the profile polyline (for a single
//! crease or constant curvature between them), so the move is within τ.

use crate::{ClSurface, frame::Raster};

/// Fraction η/τ of the tolerance reserved for the CL surface between profile points: the
/// profile is refined until every neighbour pair's fresh midpoint is within η/2 of their
/// chord, and moves are accepted at 1 − η/τ of τ at the profile points.
pub const LINEARITY_FRACTION: f64 = 0.2;

/// Two profile points closer than this (mm, along `u`) are joined without a check.
pub const MIN_DU_MM: f64 = 1e-5;

/// Where the CL surface ends, located to this precision (mm, along `u`).
pub const EDGE_TOL_MM: f64 = 1e-5;

/// A pass's exact profile: points `(u, z_tip)` in increasing `u`; `brk[j]` is true when the
/// cutter touches nothing somewhere between point `j` and `j + 1` (they must not be joined).
#[derive(Debug, Clone, Default)]
pub(crate) struct Profile {
    pub pts: Vec<(f64, f64)>,
    pub brk: Vec<bool>,
    /// Exact z at the midpoint of each pair `j, j + 1` where it was dropped (refinement).
    pub mids: Vec<Option<f64>>,
}

/// Parameters of the chord check.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Check {
    /// Largest accepted deviation at profile points (mm): τ − η = 0.8·τ.
    pub accept: f64,
    /// Check spacing (mm).
    pub spacing: f64,
    /// τ (mm).
    pub tau: f64,
    /// Longest move (mm, 3-D).
    pub max_step: f64,
    /// Cutter radius (mm), the scale of the curvature estimate.
    pub radius: f64,
}

/// Outcome of marching one pass.
#[derive(Debug, Clone, Default)]
pub(crate) struct Marched {
    /// Runs of CL points `(u, z)`, each joined by cut moves; runs are separated by gaps.
    pub runs: Vec<Vec<(f64, f64)>>,
    /// Largest checked deviation (mm) over accepted moves.
    pub max_dev: f64,
    /// Neighbours closer than [`MIN_DU_MM`] joined although their check failed
    /// (a vertical CL wall, e.g. a flat cutter stepping over an edge).
    pub unresolved: usize,
    /// Largest deviation (mm) at those unresolved joins.
    pub unresolved_dev: f64,
}

/// Refines the profile until every joinable neighbour pair passes two tests:
///
/// 1. **midpoint**: the exact z at the pair's midpoint is within `eta / 2` of their chord;
/// 2. **crease**: the pair's length times the change of chord slope to either joinable
///    neighbour pair is at most `eta` (a crease of the CL section near the pair, or strong
///    curvature, shows as a slope jump even when the midpoint happens to fit).
///
/// Failing pairs are split at their (already dropped) midpoint and tested again, down to
/// [`MIN_DU_MM`]; pairs that still fail there are counted, with the larger of their two test
/// values. Midpoints where the cutter touches nothing split the profile at edges located by
/// bisection. The tested midpoints are kept (`mids`) as extra check points for marching.
pub(crate) fn refine(
    s: &dyn ClSurface,
    f: &Raster,
    v: f64,
    prof: Profile,
    eta: f64,
) -> (Profile, usize, f64) {
    use rayon::prelude::*;
    let Profile {
        mut pts, mut brk, ..
    } = prof;
    let mut mids: Vec<Option<f64>> = vec![None; pts.len()];
    loop {
        // Midpoints still to drop.
        let need: Vec<usize> = (0..pts.len().saturating_sub(1))
            .filter(|&j| !brk[j] && mids[j].is_none() && pts[j + 1].0 - pts[j].0 > MIN_DU_MM)
            .collect();
        let dropped: Vec<Option<f64>> = need
            .par_iter()
            .map(|&j| z_at(s, f, 0.5 * (pts[j].0 + pts[j + 1].0), v))
            .collect();
        let mut gaps = Vec::new();
        for (&j, z) in need.iter().zip(dropped) {
            match z {
                Some(z) => mids[j] = Some(z),
                None => gaps.push(j),
            }
        }
        let slope = |j: usize| (pts[j + 1].1 - pts[j].1) / (pts[j + 1].0 - pts[j].0);
        let n = pts.len();
        let split: Vec<bool> = (0..n.saturating_sub(1))
            .map(|j| {
                let Some(zm) = mids[j] else { return false };
                let len = pts[j + 1].0 - pts[j].0;
                if len <= MIN_DU_MM {
                    return false;
                }
                if (0.5 * (pts[j].1 + pts[j + 1].1) - zm).abs() > eta / 2.0 {
                    return true;
                }
                let sj = slope(j);
                let left = if j > 0 && !brk[j - 1] {
                    (sj - slope(j - 1)).abs()
                } else {
                    0.0
                };
                let right = if j + 2 < n && !brk[j + 1] {
                    (slope(j + 1) - sj).abs()
                } else {
                    0.0
                };
                len * left.max(right) > eta
            })
            .collect();
        if gaps.is_empty() && !split.iter().any(|&b| b) {
            break;
        }
        // Rebuild with midpoints inserted and gaps cut at their edges.
        let mut np = Vec::with_capacity(n * 2);
        let mut nb = Vec::with_capacity(n * 2);
        let mut nm = Vec::with_capacity(n * 2);
        let mut gi = 0;
        for j in 0..n {
            np.push(pts[j]);
            if j + 1 == n {
                nb.push(brk[j]);
                nm.push(None);
                break;
            }
            if gi < gaps.len() && gaps[gi] == j {
                gi += 1;
                let (a, b) = (pts[j], pts[j + 1]);
                let um = 0.5 * (a.0 + b.0);
                let e0 = edge(s, f, v, (a.0, Some(a.1)), (um, None));
                let e1 = edge(s, f, v, (b.0, Some(b.1)), (um, None));
                if e0.0 > a.0 {
                    nb.push(false);
                    nm.push(None);
                    np.push(e0);
                }
                nb.push(true);
                nm.push(None);
                if e1.0 < b.0 {
                    np.push(e1);
                    nb.push(false);
                    nm.push(None);
                }
            } else if split[j] {
                let um = 0.5 * (pts[j].0 + pts[j + 1].0);
                nb.push(false);
                nm.push(None);
                np.push((um, mids[j].expect("split pairs have a midpoint")));
                nb.push(false);
                nm.push(None);
            } else {
                nb.push(brk[j]);
                nm.push(mids[j]);
            }
        }
        pts = np;
        brk = nb;
        mids = nm;
    }
    // Count pairs left failing at the minimum length.
    let mut unresolved = 0;
    let mut worst = 0.0f64;
    for j in 0..pts.len().saturating_sub(1) {
        if brk[j] || pts[j + 1].0 - pts[j].0 > MIN_DU_MM {
            continue;
        }
        let dz = (pts[j + 1].1 - pts[j].1).abs();
        if dz > eta {
            unresolved += 1;
            worst = worst.max(dz);
        }
    }
    (Profile { pts, brk, mids }, unresolved, worst)
}

fn z_at(s: &dyn ClSurface, f: &Raster, u: f64, v: f64) -> Option<f64> {
    let (x, y) = f.to_xy(u, v);
    s.z_tip(x, y).filter(|z| z.is_finite())
}

/// Bisects between `a` (where `ha` says whether the surface is hit) and `b` (the opposite) for
/// the edge; returns the hit-side point nearest the edge.
fn edge(
    s: &dyn ClSurface,
    f: &Raster,
    v: f64,
    mut a: (f64, Option<f64>),
    mut b: (f64, Option<f64>),
) -> (f64, f64) {
    debug_assert!(a.1.is_some() != b.1.is_some());
    while (b.0 - a.0).abs() > EDGE_TOL_MM {
        let m = 0.5 * (a.0 + b.0);
        let zm = z_at(s, f, m, v);
        if zm.is_some() == a.1.is_some() {
            a = (m, zm);
        } else {
            b = (m, zm);
        }
    }
    let hit = if a.1.is_some() { a } else { b };
    (hit.0, hit.1.unwrap_or(f64::NAN))
}

/// The exact profile of the pass at `v` over `[u_lo, u_hi]`, from the caller's `samples` and
/// a grid of spacing ≤ `c`. Edges of the touched region are located to [`EDGE_TOL_MM`].
pub(crate) fn profile(
    s: &dyn ClSurface,
    f: &Raster,
    v: f64,
    (u_lo, u_hi): (f64, f64),
    samples: &[f64],
    c: f64,
) -> Profile {
    use rayon::prelude::*;
    let n = (((u_hi - u_lo) / c).ceil() as usize).max(1);
    let mut us: Vec<f64> = (0..=n)
        .map(|k| u_lo + (u_hi - u_lo) * k as f64 / n as f64)
        .collect();
    us.extend(
        samples
            .iter()
            .copied()
            .filter(|u| u.is_finite() && *u > u_lo && *u < u_hi),
    );
    us.sort_by(f64::total_cmp);
    us.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    let zs: Vec<Option<f64>> = us.par_iter().map(|&u| z_at(s, f, u, v)).collect();
    let mut p = Profile::default();
    for k in 0..us.len() {
        match zs[k] {
            Some(z) => {
                if k > 0 && zs[k - 1].is_none() {
                    let e = edge(s, f, v, (us[k], zs[k]), (us[k - 1], None));
                    if e.0 < us[k] {
                        push(&mut p, e, true);
                    } else {
                        mark_break(&mut p);
                    }
                }
                push(&mut p, (us[k], z), false);
            }
            None => {
                if k > 0 && zs[k - 1].is_some() {
                    let e = edge(s, f, v, (us[k - 1], zs[k - 1]), (us[k], None));
                    if e.0 > us[k - 1] {
                        push(&mut p, e, false);
                    }
                    mark_break(&mut p);
                }
            }
        }
    }
    if let Some(b) = p.brk.last_mut() {
        *b = true;
    }
    p
}

fn push(p: &mut Profile, pt: (f64, f64), brk_before: bool) {
    if brk_before {
        mark_break(p);
    }
    p.pts.push(pt);
    p.brk.push(false);
}

fn mark_break(p: &mut Profile) {
    if let Some(b) = p.brk.last_mut() {
        *b = true;
    }
}

/// Largest vertical deviation (mm) between the chord `i → k` and the profile points strictly
/// between, and the tested midpoints of every pair it spans.
fn chord_dev(pts: &[(f64, f64)], mids: &[Option<f64>], i: usize, k: usize) -> f64 {
    let (ua, za) = pts[i];
    let (ub, zb) = pts[k];
    let du = ub - ua;
    let line = |u: f64| za + (zb - za) * (u - ua) / du;
    let at_pts = pts[i + 1..k]
        .iter()
        .map(|&(u, z)| (line(u) - z).abs())
        .fold(0.0, f64::max);
    let at_mids = (i..k)
        .filter_map(|j| {
            mids.get(j)
                .copied()
                .flatten()
                .map(|z| (line(0.5 * (pts[j].0 + pts[j + 1].0)) - z).abs())
        })
        .fold(0.0, f64::max);
    at_pts.max(at_mids)
}

fn len3(a: (f64, f64), b: (f64, f64)) -> f64 {
    ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt()
}

/// Eq. 1 of the seed: δ = 2·sqrt(2τ|ρ| − τ²) with ρ the CL section's radius of curvature
/// at `i`, estimated through the profile points about `λ/2` and `λ` of arc ahead
/// (λ = 2·sqrt(2Rτ), the step for a CL radius R).
fn eq1_step(pts: &[(f64, f64)], i: usize, end: usize, chk: &Check) -> f64 {
    let lam = 2.0 * (2.0 * chk.radius * chk.tau).sqrt();
    let mut acc = 0.0;
    let (mut j1, mut j2) = (None, None);
    for j in i + 1..=end {
        acc += len3(pts[j - 1], pts[j]);
        if j1.is_none() && acc >= lam / 2.0 {
            j1 = Some(j);
        } else if j1.is_some() && acc >= lam {
            j2 = Some(j);
            break;
        }
    }
    let rho = match (j1, j2) {
        (Some(a), Some(b)) => crate::sidestep::signed_radius(pts[i], pts[a], pts[b]).abs(),
        _ => f64::INFINITY,
    };
    if rho.is_infinite() {
        chk.max_step
    } else if rho <= chk.tau {
        0.0
    } else {
        2.0 * (2.0 * chk.tau * rho - chk.tau * chk.tau).sqrt()
    }
}

/// Marches a refined profile (see the module docs).
pub(crate) fn march(prof: Profile, chk: &Check) -> Marched {
    let Profile { pts, brk, mids } = prof;
    let mut out = Marched::default();
    if pts.is_empty() {
        return out;
    }
    let mut run = vec![pts[0]];
    let mut i = 0;
    while i + 1 < pts.len() {
        if brk[i] {
            out.runs.push(std::mem::take(&mut run));
            i += 1;
            run.push(pts[i]);
            continue;
        }
        // Last index reachable without crossing a break.
        let end = (i..pts.len()).find(|&j| brk[j]).unwrap_or(pts.len() - 1);
        let ok = |k: usize| {
            len3(pts[i], pts[k]) <= chk.max_step && chord_dev(&pts, &mids, i, k) <= chk.accept
        };
        // Initial guess from Eq. 1, then gallop up / bisect down to a locally longest chord.
        let delta = eq1_step(&pts, i, end, chk);
        let mut acc = 0.0;
        let mut k0 = end;
        for j in i + 1..=end {
            acc += len3(pts[j - 1], pts[j]);
            if acc >= delta {
                k0 = j;
                break;
            }
        }
        let k0 = k0.max(i + 1);
        let (mut lo, mut hi) = if ok(k0) {
            let mut lo = k0;
            let mut step = 1;
            loop {
                let cand = (lo + step).min(end);
                if cand == lo {
                    break (lo, lo + 1);
                }
                if ok(cand) {
                    lo = cand;
                    step *= 2;
                } else {
                    break (lo, cand);
                }
            }
        } else {
            (i + 1, k0)
        };
        while hi > lo + 1 && hi <= end {
            let mid = (lo + hi) / 2;
            if ok(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let dev = if lo > i + 1 {
            chord_dev(&pts, &mids, i, lo)
        } else {
            0.0
        };
        out.max_dev = out.max_dev.max(dev);
        i = lo;
        run.push(pts[i]);
    }
    out.runs.push(run);
    out
}
