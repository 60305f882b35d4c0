//! The planner: passes across the part, side steps from the scallop, feed-forward marching
//! along each pass, links, and the toolpath.

use cam_core::{DVec3, Move, MoveKind, Pose, Toolpath};
use rayon::prelude::*;

use crate::ClSurface;
use crate::config::{Direction, Milling, PlanConfig, PlanError};
use crate::feed::{self, Check, Profile};
use crate::frame::Raster;
use crate::{interval, sidestep};

/// Floor of the pass interval as a fraction of a ball's flat-ground step of the cutter's
/// radius; reached only on CL sections steeper than about 89° across the passes.
pub const STEEP_FLOOR_FRACTION: f64 = 0.02;

/// Besides every CL point, the side-step model is evaluated at profile points this far apart
/// (mm), so passes with few CL points (straight along `u`) are still covered.
pub const EVAL_SPACING_MM: f64 = 1.0;

/// Relative accuracy allowed to the CL-space scallop verification before it shrinks a step
/// (its sampling of the ideal surface is accurate to about this).
pub const VERIFY_SLACK: f64 = 1e-3;

/// Where passes go and where along them to sample: the constant-arc-length samples of the
/// part's top section, or a uniform grid for analytic surfaces.
pub trait PassSampler: Sync {
    /// The range of `v` (mm, raster frame) the passes must cover, `None` if empty.
    fn v_range(&self) -> Option<(f64, f64)>;
    /// Sorted `u` positions (mm) worth sampling on the pass at `v`; the pass spans from the
    /// first to the last. Empty when the pass misses the part.
    fn u_samples(&self, v: f64) -> Vec<f64>;
}

/// Uniform sampling of a rectangle of the raster frame (for analytic CL surfaces).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UniformSampler {
    /// Extent of every pass `(u_min, u_max)` (mm).
    pub u_range: (f64, f64),
    /// Range of pass positions `(v_min, v_max)` (mm).
    pub v_range: (f64, f64),
    /// Spacing of the samples along `u` (mm).
    pub step_mm: f64,
}

impl PassSampler for UniformSampler {
    fn v_range(&self) -> Option<(f64, f64)> {
        (self.v_range.0 <= self.v_range.1).then_some(self.v_range)
    }
    fn u_samples(&self, _v: f64) -> Vec<f64> {
        let (a, b) = self.u_range;
        if a.is_nan() || b.is_nan() || a >= b || self.step_mm.is_nan() || self.step_mm <= 0.0 {
            return Vec::new();
        }
        let n = ((b - a) / self.step_mm).ceil().max(1.0) as usize;
        (0..=n).map(|k| a + (b - a) * k as f64 / n as f64).collect()
    }
}

/// Progress callback: `(done, total)` work units; called from worker threads.
pub type Progress<'a> = &'a (dyn Fn(usize, usize) + Sync);

/// A finished plan: the toolpath and what was measured while making it.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Plan {
    /// Tool-tip poses (axis +Z): Rapid at safe Z, Plunge onto the surface, Cut along passes
    /// and surface links (links carry `pass: None`), Retract to safe Z.
    pub toolpath: Toolpath,
    /// Number of passes that cut.
    pub passes: usize,
    /// Number of CL points on passes (cut poses, including each run's first point).
    pub cl_points: usize,
    /// Length (mm) of cutting moves, links included.
    pub cut_length_mm: f64,
    /// Length (mm) of rapid moves.
    pub rapid_length_mm: f64,
    /// Length (mm) of plunge and retract moves.
    pub plunge_retract_length_mm: f64,
    /// Largest vertical deviation (mm) between a cut move on a pass and the exact CL surface
    /// at the refined profile points it spans; ≤ 0.8·τ by construction (the remaining 0.2·τ
    /// covers the CL surface between profile points, see the crate docs).
    pub max_chord_deviation_mm: f64,
    /// Joins of profile points closer than 1e-5 mm whose check still failed (vertical CL
    /// walls); their deviation is in [`Plan::unresolved_deviation_mm`], not above.
    pub unresolved_joins: usize,
    /// Largest deviation (mm) at unresolved joins (0 when there are none).
    pub unresolved_deviation_mm: f64,
    /// Largest scallop (mm) predicted for the chosen pass positions: the side-step model's
    /// value, or the CL-space verification's where that is larger.
    pub predicted_max_scallop_mm: f64,
    /// CL points where the model's side step fell below its floor
    /// ([`STEEP_FLOOR_FRACTION`] of a ball's flat-ground step) on a CL surface steeper than
    /// about 89° across the passes; the scallop there may exceed h.
    pub steep_limited_points: usize,
    /// Links that followed the surface.
    pub surface_links: usize,
    /// Retract–rapid–plunge sequences between runs.
    pub retracts: usize,
    /// Largest spacing of the exact profile points before refinement (mm).
    pub check_spacing_mm: f64,
    /// Safe Z used (mm, tool tip).
    pub safe_z_mm: f64,
    /// `v` (mm, raster frame) of every pass that cuts, in machining order.
    pub pass_v_mm: Vec<f64>,
}

/// One pass before marching.
struct PassPlan {
    v: f64,
    predicted: f64,
    steep: usize,
}

/// Plans finishing passes over `surface` (see the crate docs for the guarantees).
///
/// # Errors
/// [`PlanError`] on impossible settings, or [`PlanError::NothingToCut`] when the cutter
/// touches nothing in the region.
pub fn plan(
    surface: &dyn ClSurface,
    sampler: &dyn PassSampler,
    cfg: &PlanConfig,
    progress: Option<Progress<'_>>,
) -> Result<Plan, PlanError> {
    let (c, accept) = cfg.validate()?;
    let frame = Raster::new(cfg.angle_deg);
    let cutter = cfg.cutter;
    let h = cfg.scallop_mm;
    let model = sidestep::SideStepModel::new(cutter, h);
    let w0 = model.xy_interval(0.0, 0.0, f64::INFINITY);
    // Reference step: a ball of the cutter's radius on flat ground. It sets the floor of the
    // interval (steep walls) and the reach of the local slope/curvature estimate.
    let rr = cutter.radius();
    let w_ref = 2.0 * (2.0 * rr * h - h * h).max(0.0).sqrt();
    let floor = STEEP_FLOOR_FRACTION * w_ref;
    let delta = 0.5 * w_ref;
    let verify_spacing = (2.0 * cutter.radius()).max(1.0);
    let (mut v_lo, mut v_hi) = sampler.v_range().ok_or(PlanError::NothingToCut)?;
    if let Some(b) = cfg.boundary {
        let (a, z) = frame.v_range_of(b);
        v_lo = v_lo.max(a);
        v_hi = v_hi.min(z);
    }
    if v_lo.is_nan() || v_hi.is_nan() || v_lo > v_hi {
        return Err(PlanError::NothingToCut);
    }
    let report = |done: usize| {
        if let Some(p) = progress {
            p(done.min(1000), 1000);
        }
    };
    let chk = Check {
        accept,
        spacing: c,
        tau: cfg.tolerance_mm,
        max_step: cfg.max_step_mm.unwrap_or(f64::INFINITY),
        radius: cutter.radius(),
    };
    let eta = feed::LINEARITY_FRACTION * cfg.tolerance_mm;
    // In v order (each interval needs the previous pass), parallel inside a pass: the exact
    // profile, its refinement and marching, then the interval to the next pass.
    let mut passes: Vec<PassPlan> = Vec::new();
    let mut marched: Vec<feed::Marched> = Vec::new();
    let mut v = v_lo;
    loop {
        let samples = sampler.u_samples(v);
        let mut range = match (samples.first(), samples.last()) {
            (Some(&a), Some(&b)) if a <= b => Some((a, b)),
            _ => None,
        };
        if let (Some((a, b)), Some(bx)) = (range, cfg.boundary) {
            range = frame.clip(v, bx).and_then(|(p, q)| {
                let (lo, hi) = (a.max(p), b.min(q));
                (lo <= hi).then_some((lo, hi))
            });
        }
        let prof = match range {
            Some(r) => feed::profile(surface, &frame, v, r, &samples, c),
            None => Profile::default(),
        };
        let (prof, unresolved, unresolved_dev) = feed::refine(surface, &frame, v, prof, eta);
        let sparse = verify_points(&prof, EVAL_SPACING_MM);
        let probes = verify_points(&prof, verify_spacing);
        let slopes = interval::AlongSlopes::new(&prof, cutter.corner_radius());
        let probes: Vec<interval::Probe> = probes
            .par_iter()
            .map(|&(u, _)| interval::Probe::new(&model, &slopes, u))
            .collect();
        let mut m = feed::march(prof, &chk);
        m.unresolved += unresolved;
        m.unresolved_dev = m.unresolved_dev.max(unresolved_dev);
        // The side-step model at every CL point and at profile points ≥ 1 mm apart.
        let mut at: Vec<(f64, f64)> = m.runs.iter().flatten().copied().collect();
        at.extend(sparse);
        at.sort_by(|a, b| a.0.total_cmp(&b.0));
        at.dedup_by(|a, b| a.0 == b.0);
        let evals: Vec<(f64, [interval::ModelInput; 2])> = at
            .par_iter()
            .map(|&p| interval::model_at(surface, &frame, &model, p, slopes.at(p.0), v, delta))
            .collect();
        let raw = evals.iter().map(|e| e.0).reduce(f64::min).unwrap_or(w0);
        let steep = evals.iter().filter(|e| e.0 < floor).count();
        let mut dv = raw.max(floor);
        // Verify in CL space at points spread along the pass; shrink until it holds.
        let mut verified_scallop = 0.0f64;
        for _ in 0..12 {
            let worst = probes
                .par_iter()
                .filter_map(|pr| interval::cl_scallop(surface, &frame, &model, pr, v, dv))
                .reduce(|| 0.0, f64::max);
            verified_scallop = worst;
            if worst <= h * (1.0 + VERIFY_SLACK) || dv <= floor {
                break;
            }
            dv = (dv * (0.995 * (h / worst).sqrt()).clamp(0.3, 0.995)).max(floor);
        }
        let last = v >= v_hi;
        let next = if last { v } else { (v + dv).min(v_hi) };
        let actual = if last { 0.0 } else { next - v };
        let predicted = if actual > 0.0 {
            let modelled = evals
                .iter()
                .flat_map(|e| e.1)
                .map(|(p, q, rho)| model.predicted_scallop(p, q, rho, actual))
                .fold(0.0, f64::max);
            modelled.max(verified_scallop)
        } else {
            0.0
        };
        passes.push(PassPlan {
            v,
            predicted,
            steep,
        });
        marched.push(m);
        report(((v - v_lo) / (v_hi - v_lo).max(1e-12) * 1000.0) as usize);
        if last {
            break;
        }
        v = next;
    }
    report(1000);
    assemble(surface, &frame, cfg, &chk, &passes, marched)
}

fn assemble(
    s: &dyn ClSurface,
    f: &Raster,
    cfg: &PlanConfig,
    chk: &Check,
    passes: &[PassPlan],
    marched: Vec<feed::Marched>,
) -> Result<Plan, PlanError> {
    let mut max_dev = 0.0f64;
    let mut unresolved = 0;
    let mut unresolved_dev = 0.0f64;
    let mut predicted = 0.0f64;
    let mut steep = 0;
    // Runs of each cutting pass as 3-D tool tips, in increasing u.
    let mut cutting: Vec<(f64, Vec<Vec<DVec3>>)> = Vec::new();
    for (p, m) in passes.iter().zip(marched) {
        max_dev = max_dev.max(m.max_dev);
        unresolved += m.unresolved;
        unresolved_dev = unresolved_dev.max(m.unresolved_dev);
        predicted = predicted.max(p.predicted);
        steep += p.steep;
        let runs: Vec<Vec<DVec3>> = m
            .runs
            .into_iter()
            .filter(|r| r.len() >= 2)
            .map(|r| {
                r.into_iter()
                    .map(|(u, z)| {
                        let (x, y) = f.to_xy(u, p.v);
                        DVec3::new(x, y, z)
                    })
                    .collect()
            })
            .collect();
        if !runs.is_empty() {
            cutting.push((p.v, runs));
        }
    }
    if cutting.is_empty() {
        return Err(PlanError::NothingToCut);
    }
    let top = cutting
        .iter()
        .flat_map(|(_, r)| r.iter().flatten())
        .map(|p| p.z)
        .fold(f64::NEG_INFINITY, f64::max);
    let safe_z = cfg.safe_z_mm.unwrap_or(top + 5.0);
    if safe_z <= top {
        return Err(PlanError::SafeZ { safe_z, top });
    }
    let forward0 = cfg.milling == Milling::Climb;
    let mut tp = Toolpath::default();
    let mk = |kind, tip: DVec3, pass| Move {
        kind,
        pose: Pose::vertical(tip),
        feed_mm_per_min: None,
        line: None,
        pass,
    };
    let mut cl_points = 0;
    let mut surface_links = 0;
    let mut retracts = 0;
    let mut prev: Option<(DVec3, f64)> = None; // last tip and the v of its pass
    let mut pass_v = Vec::new();
    for (k, (v, mut runs)) in cutting.into_iter().enumerate() {
        let forward = match cfg.direction {
            Direction::OneWay => forward0,
            Direction::ZigZag => forward0 == (k % 2 == 0),
        };
        if !forward {
            runs.reverse();
            for r in &mut runs {
                r.reverse();
            }
        }
        pass_v.push(v);
        for run in runs {
            let start = run[0];
            match prev {
                None => {
                    tp.moves.push(mk(
                        MoveKind::Rapid,
                        DVec3::new(start.x, start.y, safe_z),
                        None,
                    ));
                    tp.moves.push(mk(MoveKind::Plunge, start, Some(k)));
                }
                Some((a, va)) => {
                    let same_pass = va == v;
                    let allowed = cfg.direction == Direction::ZigZag && !same_pass;
                    if allowed && link_ok(s, chk, a, start, 2.0 * (v - va).abs()) {
                        tp.moves.push(mk(MoveKind::Cut, start, None));
                        surface_links += 1;
                    } else {
                        tp.moves.push(mk(
                            MoveKind::Retract,
                            DVec3::new(a.x, a.y, safe_z),
                            tp.moves.last().and_then(|m| m.pass),
                        ));
                        tp.moves.push(mk(
                            MoveKind::Rapid,
                            DVec3::new(start.x, start.y, safe_z),
                            None,
                        ));
                        tp.moves.push(mk(MoveKind::Plunge, start, Some(k)));
                        retracts += 1;
                    }
                }
            }
            cl_points += run.len();
            for p in &run[1..] {
                tp.moves.push(mk(MoveKind::Cut, *p, Some(k)));
            }
            prev = Some((*run.last().expect("runs have two points"), v));
        }
    }
    if let Some((a, _)) = prev {
        tp.moves.push(mk(
            MoveKind::Retract,
            DVec3::new(a.x, a.y, safe_z),
            tp.moves.last().and_then(|m| m.pass),
        ));
    }
    let cut_length_mm = tp.length_where(|k| k == MoveKind::Cut);
    let rapid_length_mm = tp.length_where(|k| k == MoveKind::Rapid);
    let plunge_retract_length_mm =
        tp.length_where(|k| matches!(k, MoveKind::Plunge | MoveKind::Retract));
    Ok(Plan {
        toolpath: tp,
        passes: pass_v.len(),
        cl_points,
        cut_length_mm,
        rapid_length_mm,
        plunge_retract_length_mm,
        max_chord_deviation_mm: max_dev,
        unresolved_joins: unresolved,
        unresolved_deviation_mm: unresolved_dev,
        predicted_max_scallop_mm: predicted,
        steep_limited_points: steep,
        surface_links,
        retracts,
        check_spacing_mm: chk.spacing,
        safe_z_mm: safe_z,
        pass_v_mm: pass_v,
    })
}

/// A link `a → b` may follow the surface when its XY length is at most `max_len` mm and, at
/// check points no more than the check spacing apart, the cutter touches the part and the
/// straight move is nowhere more than the acceptance threshold below the exact CL surface.
pub(crate) fn link_ok(s: &dyn ClSurface, chk: &Check, a: DVec3, b: DVec3, max_len: f64) -> bool {
    let len = a.truncate().distance(b.truncate());
    if len > max_len {
        return false;
    }
    let n = (len / chk.spacing).ceil().max(1.0) as usize;
    (1..n).all(|j| {
        let t = j as f64 / n as f64;
        let p = a.lerp(b, t);
        matches!(s.z_tip(p.x, p.y), Some(z) if p.z >= z - chk.accept)
    })
}

/// Profile points spread along the pass: the first, then every point at least `spacing` mm
/// after the previous one.
fn verify_points(prof: &Profile, spacing: f64) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::new();
    for &p in &prof.pts {
        if out.last().is_none_or(|l| p.0 - l.0 >= spacing) {
            out.push(p);
        }
    }
    out
}
