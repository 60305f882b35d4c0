//! A brute-force reference for the swept volume, independent of the imprint method: the union
//! of exact cutter instances along the path, for validating [`crate::sweep`].
//!
//! Every feed move (as in `sweep`: Cut, Plunge, Retract; rapids do not cut) moves the tool with
//! the tip interpolated linearly and the axis interpolated linearly and renormalised. The
//! cutter instance at parameter `t` is the exact solid of revolution: flat disk of radius `a`,
//! corner torus of radius `r`, cylinder of radius `R = a + r` up to
//! [`EnvelopeConfig::height_mm`] above the tip (rounded off there; only the lower surface
//! matters for verification). Its signed distance in the tool frame is exact: with `ρ` the
//! distance from the axis and `z` the height above the tip, the solid is the set within `r` of
//! the rectangle `0 ≤ ρ ≤ a`, `r ≤ z ≤ height − r`.
//!
//! [`BruteEnvelope::signed_distance`] is the minimum over `t` of the instance distance — the
//! exact signed distance to the union for points outside it (and near its boundary inside).
//! Per move it samples [`EnvelopeConfig::instances_per_move`] instances uniformly in `t` and
//! refines the best one by golden-section search over its two neighbouring intervals until the
//! instance distance is resolved to [`EnvelopeConfig::tolerance_mm`]. Moves are skipped only
//! when a rigorous bound proves they cannot come nearer: the distance to the bounding sphere,
//! or the Lipschitz bound in `t` (no point of the tool moves faster than
//! `|Δtip| + ρ_max·|Δk|/cos(θ/2)` per unit `t`).

use cam_core::{Cutter, DVec3, MoveKind, Pose, Toolpath};

/// How the brute-force envelope is evaluated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnvelopeConfig {
    /// Uniformly spaced tool instances per move sampled before refinement. Default 2000.
    pub instances_per_move: usize,
    /// The minimum over instances is refined to this absolute accuracy (mm). Default 1e-9.
    pub tolerance_mm: f64,
    /// Height of the modelled cutter above its tip (mm); `None` = D/2 + r.
    pub height_mm: Option<f64>,
}

impl Default for EnvelopeConfig {
    fn default() -> Self {
        EnvelopeConfig {
            instances_per_move: 2000,
            tolerance_mm: 1e-9,
            height_mm: None,
        }
    }
}

/// Exact signed distance (mm) from `p` to a cutter with flat radius `a`, corner radius `r`
/// and cylinder top `height` above the tip, at `tip` with unit `axis`; negative inside.
pub fn cutter_signed_distance(
    a: f64,
    r: f64,
    height: f64,
    tip: DVec3,
    axis: DVec3,
    p: DVec3,
) -> f64 {
    let d = p - tip;
    let z = d.dot(axis);
    let rho = (d - z * axis).length();
    // Rectangle ρ ∈ [−a, a] (mirrored), z ∈ [r, top], then rounded by r.
    let top = (height - r).max(r);
    let cz = 0.5 * (r + top);
    let hz = 0.5 * (top - r);
    let qx = rho - a;
    let qy = (z - cz).abs() - hz;
    let outside = qx.max(0.0).hypot(qy.max(0.0));
    let inside = qx.max(qy).min(0.0);
    outside + inside - r
}

#[derive(Debug, Clone, Copy)]
struct Span {
    a: Pose,
    b: Pose,
    lipschitz: f64,
    move_index: u32,
}

/// The union of cutter instances along the feed moves of a toolpath.
#[derive(Debug, Clone)]
pub struct BruteEnvelope {
    a: f64,
    r: f64,
    height: f64,
    reach: f64,
    cfg: EnvelopeConfig,
    spans: Vec<Span>,
}

fn pose_at(s: &Span, t: f64) -> Pose {
    let axis = s.a.axis.lerp(s.b.axis, t);
    let l = axis.length();
    Pose {
        tip: s.a.tip.lerp(s.b.tip, t),
        axis: if l > 1e-12 { axis / l } else { s.a.axis },
    }
}

/// The distance from `p` to the segment `a`–`b` (mm).
pub(crate) fn segment_distance(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let l2 = ab.length_squared();
    let t = if l2 > 0.0 {
        ((p - a).dot(ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + t * ab)
}

impl BruteEnvelope {
    /// The envelope of `cutter` along the feed moves of `path`.
    pub fn new(path: &Toolpath, cutter: &Cutter, cfg: &EnvelopeConfig) -> BruteEnvelope {
        let a = cutter.major_radius();
        let r = cutter.corner_radius();
        let height = cfg
            .height_mm
            .unwrap_or(cutter.radius() + cutter.corner_radius())
            .max(2.0 * r);
        let reach = cutter.radius().hypot(height);
        let spans = path
            .moves
            .windows(2)
            .enumerate()
            .filter(|(_, w)| w[1].kind != MoveKind::Rapid)
            .map(|(i, w)| {
                let (pa, pb) = (w[0].pose, w[1].pose);
                let dk = pa.axis.distance(pb.axis);
                let half = (0.5 * (pa.axis + pb.axis)).length().max(1e-6);
                Span {
                    a: pa,
                    b: pb,
                    lipschitz: pa.tip.distance(pb.tip) + reach * dk / half,
                    move_index: (i + 1) as u32,
                }
            })
            .collect();
        BruteEnvelope {
            a,
            r,
            height,
            reach,
            cfg: *cfg,
            spans,
        }
    }

    fn instance(&self, s: &Span, t: f64, p: DVec3) -> f64 {
        let pose = pose_at(s, t);
        cutter_signed_distance(self.a, self.r, self.height, pose.tip, pose.axis, p)
    }

    /// Signed distance (mm) from `p` to the union of all instances (negative inside), with the
    /// index of the move whose instance is nearest; `(f64::INFINITY, None)` without feed moves.
    pub fn signed_distance_with_move(&self, p: DVec3) -> (f64, Option<u32>) {
        self.signed_distance_among(p, 0, u32::MAX)
    }

    /// As [`BruteEnvelope::signed_distance_with_move`] over the instances of the moves with
    /// index in `first_move ..= last_move` only: the *local* envelope, which measures how well
    /// a surface point lies on the envelope of its own neighbourhood even where other parts of
    /// the path (the inside of a curve, a later pass) hide it.
    pub fn signed_distance_among(
        &self,
        p: DVec3,
        first_move: u32,
        last_move: u32,
    ) -> (f64, Option<u32>) {
        let mut best = f64::INFINITY;
        let mut who = None;
        let n = self.cfg.instances_per_move.max(2);
        let tol = self.cfg.tolerance_mm.max(1e-12);
        for s in &self.spans {
            if s.move_index < first_move || s.move_index > last_move {
                continue;
            }
            if segment_distance(p, s.a.tip, s.b.tip) - self.reach > best {
                continue;
            }
            // Lipschitz cull: no instance of this move is nearer than f(½) − L/2.
            if self.instance(s, 0.5, p) - 0.5 * s.lipschitz > best {
                continue;
            }
            let (mut fi, mut ti) = (f64::INFINITY, 0usize);
            for i in 0..=n {
                let v = self.instance(s, i as f64 / n as f64, p);
                if v < fi {
                    (fi, ti) = (v, i);
                }
            }
            // Golden-section refinement in the two sample intervals around the best sample.
            let (mut lo, mut hi) = (
                ti.saturating_sub(1) as f64 / n as f64,
                (ti + 1).min(n) as f64 / n as f64,
            );
            const G: f64 = 0.618_033_988_749_894_9;
            let (mut x1, mut x2) = (hi - G * (hi - lo), lo + G * (hi - lo));
            let (mut f1, mut f2) = (self.instance(s, x1, p), self.instance(s, x2, p));
            while (hi - lo) * s.lipschitz > tol && hi - lo > 1e-15 {
                if f1 < f2 {
                    hi = x2;
                    (x2, f2) = (x1, f1);
                    x1 = hi - G * (hi - lo);
                    f1 = self.instance(s, x1, p);
                } else {
                    lo = x1;
                    (x1, f1) = (x2, f2);
                    x2 = lo + G * (hi - lo);
                    f2 = self.instance(s, x2, p);
                }
            }
            let v = fi.min(f1).min(f2);
            if v < best {
                best = v;
                who = Some(s.move_index);
            }
        }
        (best, who)
    }

    /// Signed distance (mm) from `p` to the union of all instances (negative inside).
    pub fn signed_distance(&self, p: DVec3) -> f64 {
        self.signed_distance_with_move(p).0
    }

    /// Distance (mm) along the unit direction `dir` from `origin` to the first point of the
    /// union, by sphere tracing on [`BruteEnvelope::signed_distance`] to within `tol_mm`;
    /// `Some(0.0)` when `origin` is inside, `None` when nothing is hit within `max_mm`.
    pub fn first_hit(&self, origin: DVec3, dir: DVec3, max_mm: f64, tol_mm: f64) -> Option<f64> {
        let mut t = 0.0;
        for _ in 0..10_000 {
            let d = self.signed_distance(origin + t * dir);
            if d <= tol_mm {
                return Some(t);
            }
            t += d;
            if t > max_mm {
                return None;
            }
        }
        None
    }
}

/// Statistics of signed distances (mm) of sample points to the envelope.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DistanceStats {
    /// Number of points.
    pub count: usize,
    /// Most negative distance (deepest inside the union), mm.
    pub min_mm: f64,
    /// Largest distance (farthest outside), mm.
    pub max_mm: f64,
    /// Largest `|distance|`, mm.
    pub max_abs_mm: f64,
    /// Root mean square distance, mm.
    pub rms_mm: f64,
}

impl DistanceStats {
    /// Statistics of `d` (summed in order: independent of threads).
    pub fn of(d: &[f64]) -> DistanceStats {
        if d.is_empty() {
            return DistanceStats::default();
        }
        let min = d.iter().copied().fold(f64::INFINITY, f64::min);
        let max = d.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let ss: f64 = d.iter().map(|x| x * x).sum();
        DistanceStats {
            count: d.len(),
            min_mm: min,
            max_mm: max,
            max_abs_mm: min.abs().max(max.abs()),
            rms_mm: (ss / d.len() as f64).sqrt(),
        }
    }
}

/// Error of a swept surface against the brute-force envelope.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SweepErrorReport {
    /// Signed distances of the strip triangles' vertices (imprint points).
    pub vertices: DistanceStats,
    /// Signed distances of the strip triangles' centroids.
    pub centroids: DistanceStats,
}

/// Measures the strip triangles of `surface` (caps are the tool at one pose and partly hidden
/// inside the union by construction, so they are not measured) against the *local* envelope
/// of `env` ([`BruteEnvelope::signed_distance_among`] the moves within `window` of the
/// triangle's source move): the signed distance of every vertex and centroid of every
/// `every`-th strip triangle. Parallel, result independent of the number of threads.
pub fn sweep_error(
    surface: &crate::sweep::SweptSurface,
    env: &BruteEnvelope,
    every: usize,
    window: u32,
) -> SweepErrorReport {
    use rayon::prelude::*;
    let tris: Vec<(&cam_core::Triangle, u32)> = surface
        .triangles
        .iter()
        .zip(&surface.kind)
        .zip(&surface.source_move)
        .filter(|((_, k), _)| **k == crate::sweep::FacetKind::Strip)
        .map(|((t, _), m)| (t, *m))
        .step_by(every.max(1))
        .collect();
    let d: Vec<[f64; 4]> = tris
        .par_iter()
        .map(|&(t, m)| {
            let c = (t.v[0] + t.v[1] + t.v[2]) / 3.0;
            let (lo, hi) = (m.saturating_sub(window), m.saturating_add(window));
            let f = |p| env.signed_distance_among(p, lo, hi).0;
            [f(t.v[0]), f(t.v[1]), f(t.v[2]), f(c)]
        })
        .collect();
    let verts: Vec<f64> = d.iter().flat_map(|x| x[..3].to_vec()).collect();
    let cents: Vec<f64> = d.iter().map(|x| x[3]).collect();
    SweepErrorReport {
        vertices: DistanceStats::of(&verts),
        centroids: DistanceStats::of(&cents),
    }
}

/// Comparison of first hits along lines: swept surfaces against the brute-force envelope.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LineErrorReport {
    /// `t_swept − t_envelope` (mm) per line that both hit: positive = the swept surface lies
    /// beyond the true envelope along the line (it under-reports the cut), negative = short of
    /// it.
    pub stats: DistanceStats,
    /// Lines that one of the two hit and the other did not.
    pub disagreements: usize,
    /// Indices of those lines, with the swept and the envelope hit distance (mm).
    pub disagreeing: Vec<(usize, Option<f64>, Option<f64>)>,
    /// Lines that neither hit within the range.
    pub misses: usize,
}

/// First hits of the lines `(origin, unit dir)` on `env` (sphere tracing to `tol_mm`) up to
/// `max_mm`. Parallel over lines; independent of the number of threads.
pub fn envelope_hits(
    env: &BruteEnvelope,
    lines: &[(DVec3, DVec3)],
    max_mm: f64,
    tol_mm: f64,
) -> Vec<Option<f64>> {
    use rayon::prelude::*;
    lines
        .par_iter()
        .map(|&(o, d)| env.first_hit(o, d, max_mm, tol_mm))
        .collect()
}

/// Compares hit distances line by line: `swept[i] − envelope[i]` where both hit.
pub fn compare_hits(swept: &[Option<f64>], envelope: &[Option<f64>]) -> LineErrorReport {
    let mut diffs = Vec::new();
    let mut report = LineErrorReport::default();
    for (i, h) in swept.iter().zip(envelope).enumerate() {
        match h {
            (Some(a), Some(b)) => diffs.push(a - b),
            (None, None) => report.misses += 1,
            (a, b) => {
                report.disagreements += 1;
                report.disagreeing.push((i, *a, *b));
            }
        }
    }
    report.stats = DistanceStats::of(&diffs);
    report
}

/// Shoots each line `(origin, unit dir)` and compares the first hit on any of `surfaces`
/// with the first hit on `env` (sphere tracing to `tol_mm`), up to `max_mm`. Parallel over
/// lines; the result does not depend on the number of threads.
pub fn line_error(
    surfaces: &[&crate::sweep::SweptSurface],
    env: &BruteEnvelope,
    lines: &[(DVec3, DVec3)],
    max_mm: f64,
    tol_mm: f64,
) -> LineErrorReport {
    use rayon::prelude::*;
    let hits: Vec<(Option<f64>, Option<f64>)> = lines
        .par_iter()
        .map(|&(o, d)| {
            let swept = surfaces
                .iter()
                .filter_map(|s| crate::sweep::first_hit(s, o, d, max_mm))
                .min_by(f64::total_cmp);
            (swept, env.first_hit(o, d, max_mm, tol_mm))
        })
        .collect();
    let mut diffs = Vec::new();
    let mut report = LineErrorReport::default();
    for (i, h) in hits.into_iter().enumerate() {
        match h {
            (Some(a), Some(b)) => diffs.push(a - b),
            (None, None) => report.misses += 1,
            (a, b) => {
                report.disagreements += 1;
                report.disagreeing.push((i, a, b));
            }
        }
    }
    report.stats = DistanceStats::of(&diffs);
    report
}
