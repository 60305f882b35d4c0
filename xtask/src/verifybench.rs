//! `cargo xtask bench verify`: imprint points per second, and `cam_verify::verify` time next
//! to `cam_plan::plan_part` time for the same path.

use std::time::Instant;

use anyhow::{Context, Result};
use cam_core::{Cutter, DVec3, MoveKind, Pose, Toolpath};
use cam_verify::imprint::{Half, ImprintConfig, Imprinter, Placement, transport_frames};
use cam_verify::testpaths::{PassSpec, TestSurface, pass, surface_triangles, zigzag};
use cam_verify::{VerifyConfig, verify};

use crate::planbench::{self, PlanBenchConfig, best_of};

/// Settings of `bench verify`.
#[derive(Debug, Clone)]
pub struct VerifyBenchConfig {
    /// Parts, cutters, τ, h and runs of the plans (the verify tolerance is τ).
    pub plan: PlanBenchConfig,
    /// Poses of the 5-axis imprint path.
    pub imprint_poses: usize,
    /// Minimum seconds spent per imprint measurement (repeats until reached).
    pub imprint_min_s: f64,
}

/// One imprint measurement.
#[derive(Debug, Clone, Copy)]
pub struct ImprintTiming {
    /// Poses (curves).
    pub poses: usize,
    /// Points written (`poses × (Q/2 + 1)`).
    pub points: usize,
    /// Best seconds for `transport_frames` (serial).
    pub frames_s: f64,
    /// Best seconds for `Imprinter::curves` on a 1-thread pool.
    pub curves_1t_s: f64,
    /// Best seconds for `Imprinter::curves` on a 2-thread pool.
    pub curves_2t_s: f64,
}

fn pool(n: usize) -> Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .context("building a rayon pool")
}

/// Best seconds of `f` over at least `runs` calls and at least `min_s` seconds in total.
fn best_repeated(runs: usize, min_s: f64, mut f: impl FnMut()) -> f64 {
    let start = Instant::now();
    let mut best = f64::INFINITY;
    let mut n = 0;
    while n < runs.max(1) || start.elapsed().as_secs_f64() < min_s {
        let t = Instant::now();
        f();
        best = best.min(t.elapsed().as_secs_f64());
        n += 1;
    }
    best
}

/// Times frames and curves for `poses` (Q = 40, `placement`), cutting half.
pub fn time_imprint(
    poses: &[Pose],
    cutter: &Cutter,
    placement: Placement,
    runs: usize,
    min_s: f64,
) -> Result<ImprintTiming> {
    let imp = Imprinter::new(
        cutter,
        &ImprintConfig {
            inserts: 40,
            placement,
            ..ImprintConfig::default()
        },
    );
    let r = cutter.corner_radius();
    let frames_s = best_repeated(runs, min_s, || {
        std::hint::black_box(transport_frames(poses, r));
    });
    let frames = transport_frames(poses, r);
    let mut out = vec![DVec3::ZERO; frames.len() * imp.points_per_curve()];
    let mut curves_on = |threads: usize| -> Result<f64> {
        let p = pool(threads)?;
        Ok(best_repeated(runs, min_s, || {
            std::hint::black_box(p.install(|| imp.curves(&frames, Half::Cutting, &mut out)));
        }))
    };
    let curves_1t_s = curves_on(1)?;
    let curves_2t_s = curves_on(2)?;
    if out.iter().any(|p| !p.is_finite()) {
        anyhow::bail!("imprint points not finite");
    }
    Ok(ImprintTiming {
        poses: frames.len(),
        points: out.len(),
        frames_s,
        curves_1t_s,
        curves_2t_s,
    })
}

/// The 5-axis pass of the imprint criterion bench (bull:38:3 over a cylinder of radius 80 mm,
/// lead 8° ± 2°, tilt 3°), with `poses` poses 0.015 mm apart.
pub fn five_axis_poses(poses: usize, cutter: &Cutter) -> Vec<Pose> {
    let spec = PassSpec {
        surface: TestSurface::Cylinder { radius_mm: 80.0 },
        v_mm: 0.0,
        u0_mm: -0.0075 * poses as f64,
        poses,
        step_mm: 0.015,
        lead_deg: 8.0,
        lead_wobble_deg: 2.0,
        wobble_period_mm: 60.0,
        tilt_deg: 3.0,
    };
    pass(&spec, cutter).moves.iter().map(|m| m.pose).collect()
}

/// The CL poses of a planned 3-axis path in machine order (plunge and cut tips).
pub fn plan_poses(toolpath: &Toolpath) -> Vec<Pose> {
    toolpath
        .moves
        .iter()
        .filter(|m| matches!(m.kind, MoveKind::Cut | MoveKind::Plunge))
        .map(|m| m.pose)
        .collect()
}

/// What the measure stage worked on, for one verification.
#[derive(Debug, Clone, Copy)]
pub struct MeasureBreakdown {
    /// Forward strips (one per step between imprint curves).
    pub strips: usize,
    /// Forward caps (tool at segment ends and sharp turns).
    pub caps: usize,
    /// Imprint points of the forward sweep.
    pub imprint_points: usize,
    /// Exact refinements (one per move, strip or cap tried per vector).
    pub refinements: usize,
    /// Vectors whose crossings could not be refined (linear value kept).
    pub kept_linear: usize,
    /// Microseconds of measure stage per refined-mesh vertex (2 threads).
    pub us_per_vertex: f64,
}

/// Counts of the measure stage of `v`.
pub fn measure_breakdown(v: &cam_verify::Verification) -> MeasureBreakdown {
    use cam_verify::model::Piece;
    let caps = v
        .swept
        .pieces
        .iter()
        .filter(|p| matches!(p, Piece::Cap { .. }))
        .count();
    MeasureBreakdown {
        strips: v.swept.pieces.len() - caps,
        caps,
        imprint_points: v.swept.imprint_points,
        refinements: v.stats.refinements,
        kept_linear: v.stats.kept_linear,
        us_per_vertex: v.timings.measure_s * 1e6 / v.refined.len().max(1) as f64,
    }
}

fn rate(points: usize, s: f64) -> String {
    format!("{:.1}M", points as f64 / s / 1e6)
}

/// `plan` and `check` (which checks what `plan` returned) timed in alternation, `runs` times
/// (at least once), so that both see the machine as it is at the moment: the fastest plan
/// and its seconds, the result of the fastest check and its seconds, and the median of the
/// runs' ratios `check s / plan s`. Stops at the first plan that fails, with its error.
pub fn alternate<P, C, E>(
    runs: usize,
    plan: impl FnMut() -> Result<P, E>,
    check: impl FnMut(&P) -> C,
) -> Result<Paired<P, C>, E> {
    let start = Instant::now();
    alternate_on(runs, || start.elapsed().as_secs_f64(), plan, check)
}

/// [`alternate`] on the clock `now` (seconds).
fn alternate_on<P, C, E>(
    runs: usize,
    mut now: impl FnMut() -> f64,
    mut plan: impl FnMut() -> Result<P, E>,
    mut check: impl FnMut(&P) -> C,
) -> Result<Paired<P, C>, E> {
    let mut best_plan: Option<(P, f64)> = None;
    let mut best_check: Option<(C, f64)> = None;
    let mut ratios = Vec::new();
    for _ in 0..runs.max(1) {
        let t0 = now();
        let p = plan()?;
        let t1 = now();
        let c = check(&p);
        let check_s = now() - t1;
        let plan_s = t1 - t0;
        ratios.push(check_s / plan_s);
        if best_plan.as_ref().is_none_or(|b| plan_s < b.1) {
            best_plan = Some((p, plan_s));
        }
        if best_check.as_ref().is_none_or(|b| check_s < b.1) {
            best_check = Some((c, check_s));
        }
    }
    ratios.sort_by(f64::total_cmp);
    let n = ratios.len();
    let median_ratio = if n % 2 == 1 {
        ratios[n / 2]
    } else {
        0.5 * (ratios[n / 2 - 1] + ratios[n / 2])
    };
    let ((plan, plan_s), (check, check_s)) = (
        best_plan.expect("at least one run"),
        best_check.expect("at least one run"),
    );
    Ok(Paired {
        plan,
        plan_s,
        check,
        check_s,
        median_ratio,
    })
}

/// What [`alternate`] measured.
#[derive(Debug)]
pub struct Paired<P, C> {
    /// The fastest plan's result and seconds.
    pub plan: P,
    pub plan_s: f64,
    /// The fastest check's result and seconds.
    pub check: C,
    pub check_s: f64,
    /// The median over the runs of `check s / plan s` (each run's own pair).
    pub median_ratio: f64,
}

/// Runs the benchmark and prints the tables.
pub fn verify_bench(cfg: &VerifyBenchConfig) -> Result<()> {
    let pc = &cfg.plan;
    println!(
        "verify benchmark; best of {} (imprint: best call over >= {} s); {} rayon threads in \
         the global pool; {}\n",
        pc.runs,
        cfg.imprint_min_s,
        rayon::current_num_threads(),
        crate::load_average()
    );

    // (a) imprint points per second.
    let mut imprint = String::from(
        "| path | cutter | placement | poses | points (Q = 40, 21 per curve) | frames ms | \
         curves 1 thread ms | curves 2 threads ms | points/s 1 thread | points/s 2 threads \
         (target >= 10M) | points/s 2 threads incl. frames |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    let bull: Cutter = "bull:38:3".parse()?;
    let five = five_axis_poses(cfg.imprint_poses, &bull);
    let dome = planbench::load(&crate::repo_root().join("fixtures/parts/dome.obj"))?;
    let ball: Cutter = "ball:6".parse()?;
    let (dome_plan, _) = planbench::time_plan(&dome, pc, ball)?;
    let dome_poses = plan_poses(&dome_plan.toolpath);
    let paths: [(&str, &Cutter, &[Pose]); 2] = [
        ("5-axis pass on a cylinder (testpaths)", &bull, &five),
        ("dome.obj plan, 3-axis", &ball, &dome_poses),
    ];
    for (name, cutter, poses) in paths {
        for placement in [Placement::Adaptive, Placement::Uniform] {
            let t = time_imprint(poses, cutter, placement, pc.runs, cfg.imprint_min_s)?;
            let line = format!(
                "| {name} | {cutter} | {placement:?} | {} | {} | {:.2} | {:.2} | {:.2} | {} | {} \
                 | {} |\n",
                t.poses,
                t.points,
                t.frames_s * 1e3,
                t.curves_1t_s * 1e3,
                t.curves_2t_s * 1e3,
                rate(t.points, t.curves_1t_s),
                rate(t.points, t.curves_2t_s),
                rate(t.points, t.curves_2t_s + t.frames_s),
            );
            eprint!("{line}");
            imprint.push_str(&line);
        }
    }
    println!(
        "Imprint points per second ({}):\n\n{imprint}",
        crate::load_average()
    );
    println!(
        "curves: Imprinter::curves (all poses, cutting half) inside a rayon pool of 1 or 2 \
         threads; frames: transport_frames (serial, once per path). Imprinter::new (placement \
         tables) not included.\n"
    );

    // (b) verify vs plan.
    let mut breakdown = String::from(
        "| part | cutter | us per vertex (measure, 2 threads) | fwd strips | fwd caps | imprint \
         points (fwd) | exact refinements | vectors kept linear |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    let mut table = String::from(
        "| part | tris | cutter | moves | plan s | verify s | sweep s | refine s | measure s | \
         other s | refined vertices | swept triangle slots (fwd) | max gouge mm | max excess mm | \
         verify/plan (target <= 1) | median of the runs' verify/plan |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | \
         --- | --- |\n",
    );
    for path in &pc.parts {
        let mesh = planbench::load(path)?;
        let name = planbench::part_name(path);
        for spec in &pc.cutters {
            let cutter: Cutter = spec.parse()?;
            let pcfg = pc.plan_config(cutter);
            let vc = VerifyConfig::new(pc.tolerance_mm);
            let paired = alternate(
                pc.runs,
                || cam_plan::plan_part(&mesh, &pcfg, None),
                |plan| verify(&mesh, &plan.toolpath, &cutter, &vc),
            );
            let line = match paired {
                Err(e) => format!("| {name} | {} | {spec} | plan failed: {e} |\n", mesh.len()),
                Ok(Paired {
                    plan,
                    plan_s,
                    check: r,
                    check_s: verify_s,
                    median_ratio,
                }) => match r {
                    Err(e) => format!(
                        "| {name} | {} | {spec} | {} | {plan_s:.3} | verify failed after \
                             {verify_s:.3} s: {e} |\n",
                        mesh.len(),
                        plan.toolpath.moves.len()
                    ),
                    Ok(v) => {
                        let b = measure_breakdown(&v);
                        breakdown.push_str(&format!(
                            "| {name} | {spec} | {:.2} | {} | {} | {} | {} | {} |\n",
                            b.us_per_vertex,
                            b.strips,
                            b.caps,
                            b.imprint_points,
                            b.refinements,
                            b.kept_linear
                        ));
                        let t = v.timings;
                        format!(
                            "| {name} | {} | {spec} | {} | {plan_s:.3} | {verify_s:.3} | \
                                 {:.3} | {:.3} | {:.3} | {:.3} | {} | {} | {:.4} | {:.4} | \
                                 {:.2} | {median_ratio:.2} |\n",
                            mesh.len(),
                            plan.toolpath.moves.len(),
                            t.sweep_s,
                            t.refine_s,
                            t.measure_s,
                            verify_s - t.sweep_s - t.refine_s - t.measure_s,
                            v.refined.len(),
                            v.report
                                .settings
                                .as_ref()
                                .and_then(|st| st.extra.get("swept_triangle_slots").copied())
                                .unwrap_or(0.0),
                            v.report.max_gouge_mm,
                            v.report.max_excess_mm,
                            verify_s / plan_s,
                        )
                    }
                },
            };
            eprint!("{line}");
            table.push_str(&line);
        }
    }
    println!(
        "cam_verify::verify vs cam_plan::plan_part, tau = {} mm, h = {} mm, \
         VerifyConfig::new({}) (Q = 40, e = 0.005 mm, back gouges on); each row plans and \
         verifies in alternation, {} times: plan s and verify s are the fastest of each, \
         verify/plan their ratio, and the last column the median of the runs' own ratios \
         (each verify against the plan just before it); {}:\n\n{table}",
        pc.tolerance_mm,
        pc.scallop_mm,
        pc.tolerance_mm,
        pc.runs,
        crate::load_average()
    );
    println!(
        "Stage timings are from the best verify run (Verification::timings): sweep = forward \
         and back-gouge sweep models (imprint curves; a program of translations, every plan \
         here, is measured without them, so only the check that something sweeps is left), \
         refine = design-surface refinement (remesh, then bisection; the rapids' check, \
         the part's tree and the moves' layout for the measurement run beside it), \
         measure = each normal vector's first entry into the exact swept volume (for a \
         program of translations, every plan here, a direct search over the moves' volumes; \
         otherwise crossings of the imprint surface refined onto it), the material clip and \
         crease depths; other = the rest (report)."
    );
    println!(
        "\nMeasure stage of the best run: strips and caps of the forward sweep (both sweeps \
         hold rotating moves only unless the imprint surface is measured or kept: 0 for the \
         plans here), exact refinements (exact entries tried: one per \
         move, column or cap tried per vector) and vectors whose crossings could not be refined:\n\n{breakdown}"
    );
    five_axis_bench(pc.runs)?;
    Ok(())
}

/// A 5-axis zig-zag and its design surface: 13 passes 2 mm apart over the twisted blade
/// (`testpaths`, twist 0.01 rad/mm, u in [-30, 30], poses 0.5 mm apart, lead 5° ± 3° with a
/// period of 17 mm, tilt 2°), every other pass run backwards, for `cutter`; the blade as a
/// 120 × 60 grid over u in [-30, 30], v in [-15, 15].
pub fn five_axis_zigzag(cutter: &Cutter) -> Result<(Toolpath, cam_core::Mesh)> {
    let surface = TestSurface::Blade {
        twist_rad_per_mm: 0.01,
    };
    let spec = PassSpec {
        surface,
        v_mm: -12.0,
        u0_mm: -30.0,
        poses: 121,
        step_mm: 0.5,
        lead_deg: 5.0,
        lead_wobble_deg: 3.0,
        wobble_period_mm: 17.0,
        tilt_deg: 2.0,
    };
    let path = zigzag(&spec, 13, 2.0, cutter);
    let tris = surface_triangles(&surface, (-30.0, 30.0), (-15.0, 15.0), 120, 60);
    let mesh = cam_core::Mesh::from_triangles(tris, "<blade>")?;
    Ok((path, mesh))
}

/// (c) `cam_verify::verify` on [`five_axis_zigzag`] (rotating moves: crossings of the
/// imprint surface refined onto the exact volume); no plan to compare with.
fn five_axis_bench(runs: usize) -> Result<()> {
    let cutter: Cutter = "bull:10:2".parse()?;
    let (path, mesh) = five_axis_zigzag(&cutter)?;
    let vc = VerifyConfig::new(0.01);
    let (r, verify_s) = best_of(runs, || verify(&mesh, &path, &cutter, &vc));
    let v = r?;
    let t = v.timings;
    let extra = |k: &str| {
        v.report
            .settings
            .as_ref()
            .and_then(|st| st.extra.get(k).copied())
            .unwrap_or(0.0)
    };
    println!(
        "\n5-axis zig-zag over the twisted blade (testpaths::zigzag, 13 passes, 2 mm stepover, \
         lead 5° ± 3°, tilt 2°, every other pass backwards), {cutter}, {} moves, {} design \
         triangles, VerifyConfig::new(0.01); best of {runs}; {}:\n\n\
         | verify s | sweep s | refine s | measure s | refined vertices | us per vertex \
         (measure) | exact refinements | overflow vectors | vectors kept linear | max gouge mm \
         | max excess mm |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n\
         | {verify_s:.3} | {:.3} | {:.3} | {:.3} | {} | {:.2} | {} | {} | {} | {:.6} | {:.4} |\n",
        path.moves.len(),
        mesh.len(),
        crate::load_average(),
        t.sweep_s,
        t.refine_s,
        t.measure_s,
        v.refined.len(),
        t.measure_s * 1e6 / v.refined.len().max(1) as f64,
        v.stats.refinements,
        extra("overflow_vectors"),
        v.stats.kept_linear,
        v.report.max_gouge_mm,
        v.report.max_excess_mm,
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::{Cell, RefCell};

    #[test]
    fn five_axis_zigzag_has_every_pass_and_cell() {
        let cutter: Cutter = "bull:10:2".parse().unwrap();
        let (path, mesh) = five_axis_zigzag(&cutter).unwrap();
        assert_eq!(path.moves.len(), 13 * 121);
        let rapids = path
            .moves
            .iter()
            .filter(|m| m.kind == MoveKind::Rapid)
            .count();
        assert_eq!(rapids, 13);
        assert_eq!(mesh.len(), 2 * 120 * 60);
    }

    #[test]
    fn imprint_timing_counts_points() {
        let cutter: Cutter = "bull:10:2".parse().unwrap();
        let poses = five_axis_poses(50, &cutter);
        assert_eq!(poses.len(), 50);
        let t = time_imprint(&poses, &cutter, Placement::Uniform, 1, 0.0).unwrap();
        assert_eq!((t.poses, t.points), (50, 50 * 21));
        assert!(t.curves_1t_s > 0.0 && t.curves_2t_s > 0.0);
    }

    /// Plan and check alternate; the best of each is the fastest run's result, and the
    /// median ratio is that of the runs' own pairs (here 3, 1 and 0.5: median 1, while the
    /// ratio of the bests is 1/3).
    #[test]
    fn alternate_pairs_each_check_with_its_plan() {
        let clock = Cell::new(0.0);
        let log = RefCell::new(Vec::new());
        let plan_s = [1.0, 2.0, 4.0];
        let check_s = [3.0, 2.0, 2.0];
        let run = Cell::new(0);
        let r = alternate_on(
            3,
            || clock.get(),
            || {
                let k = run.get();
                log.borrow_mut().push(format!("plan {k}"));
                clock.set(clock.get() + plan_s[k]);
                Ok::<usize, ()>(k)
            },
            |&k| {
                log.borrow_mut().push(format!("check {k}"));
                clock.set(clock.get() + check_s[k]);
                run.set(k + 1);
                k * 10
            },
        )
        .unwrap();
        assert_eq!(
            log.into_inner(),
            [
                "plan 0", "check 0", "plan 1", "check 1", "plan 2", "check 2"
            ]
        );
        assert_eq!((r.plan, r.plan_s), (0, 1.0));
        // The first of the fastest checks.
        assert_eq!((r.check, r.check_s), (10, 2.0));
        assert_eq!(r.median_ratio, 1.0);
    }

    /// A failing plan ends the runs with its error; an even number of runs takes the
    /// middle pair's mean.
    #[test]
    fn alternate_stops_at_a_failed_plan_and_averages_an_even_median() {
        let calls = Cell::new(0);
        let r = alternate_on(
            4,
            || 0.0,
            || {
                calls.set(calls.get() + 1);
                if calls.get() == 2 {
                    Err("no plan")
                } else {
                    Ok(())
                }
            },
            |_| (),
        );
        assert_eq!(r.unwrap_err(), "no plan");
        assert_eq!(calls.get(), 2);
        let t = Cell::new(0.0);
        let ratios = [1.0, 4.0, 2.0, 8.0];
        let k = Cell::new(0);
        let r = alternate_on(
            4,
            || t.get(),
            || {
                t.set(t.get() + 1.0);
                Ok::<(), ()>(())
            },
            |_| {
                t.set(t.get() + ratios[k.get()]);
                k.set(k.get() + 1);
            },
        )
        .unwrap();
        assert_eq!(r.median_ratio, 3.0);
    }
}
