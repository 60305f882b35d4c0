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

/// Candidate next passes the side-step search builds at most per pass.
const MAX_TRIES: usize = 10;

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
    /// Largest bound (mm) proven for a cut move on a pass: the cutter's penetration into the
    /// part (normal depth) or the move's vertical excess over the exact CL surface; ≤ τ by
    /// construction (≤ τ − η at samples for moves on the sampled path).
    pub max_chord_deviation_mm: f64,
    /// Joins of profile samples closer than 1e-5 mm that could not be certified (vertical CL
    /// walls); their z step is in [`Plan::unresolved_deviation_mm`], not above.
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
    /// Passes whose interval to the next pass reached the floor with a predicted scallop
    /// still above h (by more than [`VERIFY_SLACK`]): steep CL walls, or passes running
    /// nearly tangent to a concave crease the cutter cannot reach into.
    pub floor_limited_passes: usize,
    /// Links that followed the surface.
    pub surface_links: usize,
    /// Retract–rapid–plunge sequences between runs.
    pub retracts: usize,
    /// Largest gap between profile samples (mm): 3-D for ball and bull cutters (the lemma's
    /// spacing), along the pass for a flat end mill.
    pub check_spacing_mm: f64,
    /// Safe Z used (mm, tool tip).
    pub safe_z_mm: f64,
    /// `v` (mm, raster frame) of every pass that cuts, in machining order.
    pub pass_v_mm: Vec<f64>,
    /// Exact CL samples (drop-cutter queries) the plan cost.
    pub drops: usize,
    /// Pass profiles built: the passes kept, the candidates the side-step search rejected,
    /// and the pass behind the first one.
    pub pass_builds: usize,
    /// Cut moves on passes whose bound rests on sampling somewhere (surfaces without
    /// certificates; a flat end mill's move whose excess side the contact pieces could not
    /// bound); every other move's bound is proven (see the crate docs).
    pub sampled_moves: usize,
}

/// One pass before marching.
struct PassPlan {
    v: f64,
    predicted: f64,
    steep: usize,
    floor_limited: bool,
}

/// A pass's profile and its marched runs.
struct Pass {
    v: f64,
    prof: Profile,
    marched: feed::Marched,
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
    // Run on a worker of the thread pool: the passes are sequential, and the many small
    // parallel batches inside each pass are then cheap to fork instead of being injected
    // into the pool from outside one by one.
    rayon::scope(|_| plan_passes(surface, sampler, cfg, progress))
}

/// Everything a range of passes needs, shared by the chunks planned in parallel.
struct Ctx<'a> {
    surface: &'a dyn ClSurface,
    sampler: &'a dyn PassSampler,
    cfg: &'a PlanConfig,
    frame: Raster,
    model: sidestep::SideStepModel,
    chk: Check,
    initial: f64,
    floor: f64,
    w_ref: f64,
}

/// The passes of one chunk of the `v` range, in order (the last lands on the chunk's end).
struct Range {
    passes: Vec<PassPlan>,
    marched: Vec<feed::Marched>,
    drops: usize,
    builds: usize,
}

/// Passes are planned in chunks of the `v` range this many flat-ground steps wide (at least
/// one chunk, at most [`MAX_CHUNKS`]), in parallel. The chunks depend on the part and the
/// settings only, so the plan is the same for any number of threads; each chunk costs about
/// two extra pass profiles (the pass behind its first one, and its last pass, which the next
/// chunk's first pass repeats).
const CHUNK_STEPS: f64 = 10.0;

/// Most chunks a plan is split into.
const MAX_CHUNKS: usize = 16;

fn plan_passes(
    surface: &dyn ClSurface,
    sampler: &dyn PassSampler,
    cfg: &PlanConfig,
    progress: Option<Progress<'_>>,
) -> Result<Plan, PlanError> {
    let (c, _) = cfg.validate()?;
    let frame = Raster::new(cfg.angle_deg);
    let cutter = cfg.cutter;
    let h = cfg.scallop_mm;
    // Reference step: a ball of the cutter's radius on flat ground. It sets the floor of the
    // interval (steep walls) and the chunk width.
    let rr = cutter.radius();
    let w_ref = 2.0 * (2.0 * rr * h - h * h).max(0.0).sqrt();
    let (mut v_lo, mut v_hi) = sampler.v_range().ok_or(PlanError::NothingToCut)?;
    if let Some(b) = cfg.boundary {
        let (a, z) = frame.v_range_of(b);
        v_lo = v_lo.max(a);
        v_hi = v_hi.min(z);
    }
    if v_lo.is_nan() || v_hi.is_nan() || v_lo > v_hi {
        return Err(PlanError::NothingToCut);
    }
    let mut chk = Check::new(
        cfg.tolerance_mm,
        cutter.corner_radius(),
        rr,
        c,
        cfg.max_step_mm.unwrap_or(f64::INFINITY),
    );
    // A flat end mill's moves are proven by the exact rise where the surface gives one (a
    // surface that cannot answers `None` for any move, so one degenerate move tells).
    chk.exact_gouge = cutter.corner_radius() == 0.0
        && surface
            .chord_rise((0.0, 0.0), (0.0, 0.0), 0.0, 0.0, 0.0)
            .is_some();
    let ctx = Ctx {
        surface,
        sampler,
        cfg,
        frame,
        model: sidestep::SideStepModel::new(cutter, h),
        chk,
        initial: cfg.section_step_mm()?,
        floor: STEEP_FLOOR_FRACTION * w_ref,
        w_ref,
    };
    let width = v_hi - v_lo;
    let chunks = ((width / (CHUNK_STEPS * w_ref)).floor() as usize).clamp(1, MAX_CHUNKS);
    let bounds: Vec<(f64, f64)> = (0..chunks)
        .map(|k| {
            let a = v_lo + width * k as f64 / chunks as f64;
            let b = if k + 1 == chunks {
                v_hi
            } else {
                v_lo + width * (k + 1) as f64 / chunks as f64
            };
            (a, b)
        })
        .collect();
    // Progress: the v covered so far over all chunks, in µm.
    let covered = std::sync::atomic::AtomicU64::new(0);
    let total_um = (width * 1000.0).max(1.0);
    let report = |dv: f64| {
        if let Some(p) = progress {
            let add = (dv * 1000.0).max(0.0) as u64;
            let done = covered.fetch_add(add, std::sync::atomic::Ordering::Relaxed) + add;
            p(
                ((done as f64 / total_um) * 1000.0).min(1000.0) as usize,
                1000,
            );
        }
    };
    let ranges: Vec<Range> = bounds
        .par_iter()
        .map(|&(a, b)| plan_range(&ctx, a, b, &report))
        .collect();
    if let Some(p) = progress {
        p(1000, 1000);
    }
    // Join: each chunk's last pass is the next chunk's first one (same v, same profile);
    // keep the later record, which carries the interval to the pass after it.
    let mut passes: Vec<PassPlan> = Vec::new();
    let mut marched: Vec<feed::Marched> = Vec::new();
    let (mut drops, mut builds) = (0, 0);
    for (k, r) in ranges.into_iter().enumerate() {
        if k > 0 {
            passes.pop();
            marched.pop();
        }
        passes.extend(r.passes);
        marched.extend(r.marched);
        drops += r.drops;
        builds += r.builds;
    }
    let mut plan = assemble(surface, &ctx.frame, cfg, &ctx.chk, &passes, marched)?;
    plan.drops = drops;
    plan.pass_builds = builds;
    Ok(plan)
}

/// Plans the passes from `v_lo` to `v_hi` (the first at `v_lo`, the last at `v_hi`).
fn plan_range(ctx: &Ctx<'_>, v_lo: f64, v_hi: f64, report: &(dyn Fn(f64) + Sync)) -> Range {
    let Ctx {
        surface,
        sampler,
        cfg,
        frame,
        ref model,
        ref chk,
        initial,
        floor,
        w_ref,
    } = *ctx;
    let frame = &frame;
    let cutter = cfg.cutter;
    let h = cfg.scallop_mm;
    let verify_spacing = (2.0 * cutter.radius()).max(1.0);
    let mut drops = 0usize;
    let builds = std::cell::Cell::new(0usize);
    let build = |v: f64, drops: &mut usize| -> Pass {
        builds.set(builds.get() + 1);
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
            Some(r) => feed::profile(surface, frame, v, r, &samples, initial, chk),
            None => Profile::default(),
        };
        *drops += prof.drops;
        let marched = feed::march(&prof, chk);
        Pass { v, prof, marched }
    };
    // A kept pass's moves, with the gouge side of sampled ones proven where the surface can.
    let finish = |pass: &mut Pass, drops: &mut usize| -> feed::Marched {
        let before = pass.prof.drops;
        let m = std::mem::take(&mut pass.marched);
        let m = feed::prove_moves(surface, frame, pass.v, &mut pass.prof, m, chk);
        *drops += pass.prof.drops - before;
        m
    };
    // The first interval's curvature needs a pass behind the first one.
    let w0 = model.xy_interval(0.0, 0.0, f64::INFINITY);
    let mut behind: Option<Pass> = Some(build(v_lo - w0.min(0.5 * w_ref).max(floor), &mut drops));
    let mut cur = build(v_lo, &mut drops);
    let mut dv_prev = cur.v - behind.as_ref().map_or(cur.v, |b| b.v);
    let mut dv_pred = w0;
    // Running mean of the relative change of the allowed interval from pass to pass: where it
    // jitters (a crease's measured scallop moves with the passes) the prediction leaves a
    // margin, since a rejected candidate costs a pass profile; on smooth sections it is 0.
    let mut jitter = 0.0f64;
    let mut allowed_prev: Option<f64> = None;
    let mut passes: Vec<PassPlan> = Vec::new();
    let mut marched: Vec<feed::Marched> = Vec::new();
    loop {
        let v = cur.v;
        let last = v >= v_hi;
        if last {
            passes.push(PassPlan {
                v,
                predicted: 0.0,
                steep: 0,
                floor_limited: false,
            });
            marched.push(finish(&mut cur, &mut drops));
            break;
        }
        // Predictor–corrector: build the next pass at the predicted interval and evaluate the
        // side-step model against it (Algorithm 2: the chord slope to the next pass; the
        // curvature through the passes behind, here and next). The allowed interval is not
        // monotonic near a feature (a step that lands past a crease fails where a shorter
        // one may not), so shrink by the model's own estimate (at least 0.5 %) until a
        // candidate holds; the prediction grows at most twofold per pass, so passes
        // approaching a feature across flat ground do not creep towards it.
        let slopes = interval::AlongSlopes::new(&cur.prof, cutter.corner_radius());
        // The side-step model between this pass and a candidate next one `dv` away.
        let evaluate = |next: &Pass, dv: f64| {
            interval::needed(
                surface,
                frame,
                v,
                model,
                behind.as_ref().map(|b| (&b.prof, dv_prev)),
                (&cur.prof, &slopes),
                &next.prof,
                dv,
                floor,
            )
        };
        let mut dv = dv_pred.max(floor).min(v_hi - v);
        let mut good: Option<(f64, Pass, interval::Need)> = None;
        let mut tries = 0;
        loop {
            let cand = build(v + dv, &mut drops);
            let nd = evaluate(&cand, dv);
            tries += 1;
            drops += nd.drops;
            let allowed = nd.interval.max(floor);
            // The first shrink goes to what the model allows (exact on smooth sections);
            // where that still fails (a crease's measured scallop moves with the passes)
            // later ones leave a margin.
            let margin = if tries == 1 { 1.0 } else { 0.97 };
            let shrink = (margin * allowed).min(0.995 * dv).max(floor);
            if dv <= allowed * (1.0 + 1e-9) || dv <= floor {
                good = Some((dv, cand, nd));
            }
            if tries >= MAX_TRIES {
                break;
            }
            // The first interval that holds is taken: searching above it costs a pass build
            // per candidate, more than the passes it saves.
            if good.is_some() {
                break;
            }
            dv = shrink.min(v_hi - v);
        }
        let (mut dv, mut next, mut need) = match good {
            Some(g) => g,
            None => {
                // Out of tries: the floor always holds.
                let dv = floor.min(v_hi - v);
                let cand = build(v + dv, &mut drops);
                let nd = evaluate(&cand, dv);
                drops += nd.drops;
                (dv, cand, nd)
            }
        };
        // Flat and bull cutters: verify in CL space at points spread along the pass (the
        // model cannot see the part under a CL plateau); shrink until it holds.
        let mut verified_scallop = 0.0f64;
        if cutter.kind() != cam_core::CutterKind::Ball {
            // Where both passes are certified planar on one plane at u, the CL surface
            // between them is that plane (the certificates cover everything within R of
            // either pass, and passes are less than 2R apart), where the model is exact.
            let planar = |u: f64, next: &Pass| match (cur.prof.plane_at(u), next.prof.plane_at(u)) {
                (Some((na, da)), Some((nb, db))) => {
                    (na - nb).length() <= 1e-12 && (da - db).abs() <= 1e-9
                }
                _ => false,
            };
            let probes: Vec<interval::Probe> = verify_points(&cur.prof, verify_spacing)
                .par_iter()
                .map(|&(u, _)| interval::Probe::new(model, &slopes, u))
                .collect();
            for _ in 0..12 {
                let live: Vec<&interval::Probe> =
                    probes.iter().filter(|pr| !planar(pr.u(), &next)).collect();
                let worst = live
                    .par_iter()
                    .filter_map(|pr| interval::cl_scallop(surface, frame, model, pr, v, dv))
                    .reduce(|| 0.0, f64::max);
                drops += live.len() * (interval::VERIFY_Q + 1);
                verified_scallop = worst;
                if worst <= h * (1.0 + VERIFY_SLACK) || dv <= floor {
                    break;
                }
                dv = (dv * (0.995 * (h / worst).sqrt()).clamp(0.3, 0.995)).max(floor);
                next = build(v + dv, &mut drops);
                need = evaluate(&next, dv);
            }
        }
        let predicted = need
            .predicted
            .max(verified_scallop)
            .max(need.crease_scallop);
        passes.push(PassPlan {
            v,
            predicted,
            steep: need.steep,
            floor_limited: predicted > h * (1.0 + VERIFY_SLACK),
        });
        report(dv);
        // Next prediction: what the model allowed here (less the jitter margin), growing at
        // most twofold per pass.
        let allowed = need.interval.max(floor);
        if let Some(prev) = allowed_prev {
            jitter = 0.7 * jitter + 0.3 * ((allowed - prev).abs() / prev);
        }
        allowed_prev = Some(allowed);
        dv_pred = (allowed * (1.0 - (2.0 * jitter).min(0.05)))
            .max(floor)
            .min(2.0 * dv);
        dv_prev = dv;
        let mut done = std::mem::replace(&mut cur, next);
        marched.push(finish(&mut done, &mut drops));
        behind = Some(Pass {
            v: done.v,
            prof: done.prof,
            marched: feed::Marched::default(),
        });
    }
    Range {
        passes,
        marched,
        drops,
        builds: builds.into_inner(),
    }
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
    let mut floor_limited = 0;
    let mut sampled_moves = 0;
    // Runs of each cutting pass as 3-D tool tips, in increasing u.
    let mut cutting: Vec<(f64, Vec<Vec<DVec3>>)> = Vec::new();
    for (p, m) in passes.iter().zip(marched) {
        max_dev = max_dev.max(m.max_dev);
        unresolved += m.unresolved;
        unresolved_dev = unresolved_dev.max(m.unresolved_dev);
        predicted = predicted.max(p.predicted);
        steep += p.steep;
        floor_limited += usize::from(p.floor_limited);
        sampled_moves += m.sampled_moves;
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
        floor_limited_passes: floor_limited,
        surface_links,
        retracts,
        check_spacing_mm: chk.spacing,
        safe_z_mm: safe_z,
        pass_v_mm: pass_v,
        drops: 0,
        pass_builds: 0,
        sampled_moves,
    })
}

/// A link `a → b` may follow the surface when its XY length is at most `max_len` mm, the
/// cutter touches the part all along it, and the link provably does not gouge: with ball and
/// bull cutters, exact samples at most the check spacing apart (3-D) and the lemma of
/// `docs/plan-math.md` §1 bound the penetration by τ; with a flat end mill, samples that
/// close are within τ − η of the exact CL z (sampling argument). Excess is allowed: it is air.
pub(crate) fn link_ok(s: &dyn ClSurface, chk: &Check, a: DVec3, b: DVec3, max_len: f64) -> bool {
    let len = a.truncate().distance(b.truncate());
    if len > max_len {
        return false;
    }
    let n = (a.distance(b) / chk.spacing).ceil().max(1.0) as usize;
    let mut ups = Vec::with_capacity(n + 1);
    for j in 0..=n {
        let t = j as f64 / n as f64;
        let p = a.lerp(b, t);
        let z = if j == 0 || j == n {
            p.z
        } else {
            match s.z_tip(p.x, p.y) {
                Some(z) => z,
                None => return false,
            }
        };
        ups.push((z - p.z).max(0.0));
    }
    let r = chk.corner;
    if r <= 0.0 {
        return ups.iter().all(|&u| u <= chk.accept);
    }
    let l = a.distance(b) / n as f64;
    ups.windows(2).all(|w| {
        let up = w[0].max(w[1]);
        let q = (r - up) * (r - up) - l * l / 4.0;
        up < r && q >= 0.0 && r - q.sqrt() <= chk.tau
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
