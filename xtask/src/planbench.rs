//! `cargo xtask bench plan`: `cam_plan::plan_part` on the fixtures next to the drop-cutter
//! time for the same number of CL points, and the holder check's share of the plan time.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use cam_core::{Cutter, Mesh, MoveKind, Toolpath, Units};
use cam_holder::{AssemblyDefaults, CheckConfig, ToolAssembly};
use cam_offset::DropCutter;
use cam_plan::{Plan, PlanConfig};

/// Benchmark settings shared by `bench plan` and `bench verify`.
#[derive(Debug, Clone)]
pub struct PlanBenchConfig {
    /// Runs per measurement; the best is reported.
    pub runs: usize,
    /// Feed-forward tolerance τ (mm).
    pub tolerance_mm: f64,
    /// Scallop height h (mm).
    pub scallop_mm: f64,
    /// The parts (paths).
    pub parts: Vec<PathBuf>,
    /// The cutters (specs).
    pub cutters: Vec<String>,
}

/// The cutters of both benches.
pub const CUTTERS: [&str; 3] = ["ball:6", "flat:6", "bull:6:1.5"];

/// The benchmark parts: the bundled dome and two shared OpenCAMLib meshes.
pub fn default_parts() -> Vec<PathBuf> {
    let shared = crate::shared_dir().join("fixtures");
    vec![
        crate::repo_root().join("fixtures/parts/dome.obj"),
        shared.join("ocl_sphere_on_plate.stl"),
        shared.join("ocl_mount_rush.stl"),
    ]
}

impl PlanBenchConfig {
    /// Best of `runs`, τ = 0.01 mm, h = 0.05 mm, the default parts and [`CUTTERS`].
    pub fn new(runs: usize) -> PlanBenchConfig {
        PlanBenchConfig {
            runs,
            tolerance_mm: 0.01,
            scallop_mm: 0.05,
            parts: default_parts(),
            cutters: CUTTERS.iter().map(|s| s.to_string()).collect(),
        }
    }

    /// The planner configuration for `cutter`.
    pub fn plan_config(&self, cutter: Cutter) -> PlanConfig {
        PlanConfig {
            cutter,
            tolerance_mm: self.tolerance_mm,
            scallop_mm: self.scallop_mm,
            ..Default::default()
        }
    }
}

/// Runs `f` `runs` times (at least once) and returns the result of the fastest run and its
/// seconds: what a table prints from the result (stage timings, counts) belongs to the run
/// whose time it prints.
pub fn best_of<T>(runs: usize, mut f: impl FnMut() -> T) -> (T, f64) {
    fastest((0..runs.max(1)).map(|_| {
        let t = Instant::now();
        let r = f();
        (r, t.elapsed().as_secs_f64())
    }))
    .expect("at least one run")
}

/// The first `(result, seconds)` with the fewest seconds.
fn fastest<T>(runs: impl Iterator<Item = (T, f64)>) -> Option<(T, f64)> {
    let mut best: Option<(T, f64)> = None;
    for (r, s) in runs {
        if best.as_ref().is_none_or(|b| s < b.1) {
            best = Some((r, s));
        }
    }
    best
}

/// Loads a part (mm).
pub fn load(path: &Path) -> Result<Mesh> {
    Mesh::load(path, Units::Mm).with_context(|| format!("loading {}", path.display()))
}

/// A part's file name for the tables.
pub fn part_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into(),
    )
}

/// The XY of every CL point of a plan: the tips of its plunges (the first point of each run)
/// and of its cut moves (pass points and the ends of surface links, which are the first
/// points of the next runs). Their number is [`Plan::cl_points`].
pub fn cl_xy(toolpath: &Toolpath) -> Vec<(f64, f64)> {
    toolpath
        .moves
        .iter()
        .filter(|m| matches!(m.kind, MoveKind::Cut | MoveKind::Plunge))
        .map(|m| (m.pose.tip.x, m.pose.tip.y))
        .collect()
}

/// Plans `cutter` on `mesh`, best of `runs`.
pub fn time_plan(
    mesh: &Mesh,
    cfg: &PlanBenchConfig,
    cutter: Cutter,
) -> Result<(Plan, f64), cam_plan::PlanError> {
    let pc = cfg.plan_config(cutter);
    let (r, s) = best_of(cfg.runs, || cam_plan::plan_part(mesh, &pc, None));
    r.map(|p| (p, s))
}

/// Runs the benchmark and prints the table.
pub fn plan(cfg: &PlanBenchConfig) -> Result<()> {
    println!(
        "plan benchmark: cam_plan::plan_part, tau = {} mm, h = {} mm (coarse scallop so runs \
         take seconds), angle 0, zig-zag; best of {}; {} rayon threads; {}\n",
        cfg.tolerance_mm,
        cfg.scallop_mm,
        cfg.runs,
        rayon::current_num_threads(),
        crate::load_average()
    );
    let mut table = String::from(
        "| part | tris | cutter | passes | CL points | plan s | drop-cutter s (same points) | \
         overhead plan/drop (target <= 2x) | holder check s | min stick-out s | holder/plan \
         (target <= 50 %) | collisions | min stick-out mm | planner drop calls | calls per CL \
         point | drop s for those calls (est.) |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | \
         --- | --- |\n",
    );
    for path in &cfg.parts {
        let mesh = load(path)?;
        let name = part_name(path);
        for spec in &cfg.cutters {
            let cutter: Cutter = spec.parse()?;
            let line = match time_plan(&mesh, cfg, cutter) {
                Err(e) => format!(
                    "| {name} | {} | {spec} | plan failed: {e} | | | | | | | | | |\n",
                    mesh.len()
                ),
                Ok((plan, plan_s)) => {
                    let xy = cl_xy(&plan.toolpath);
                    if xy.len() != plan.cl_points {
                        eprintln!(
                            "warning: {name} {spec}: {} cut/plunge tips, plan says {} CL points",
                            xy.len(),
                            plan.cl_points
                        );
                    }
                    let (_, drop_s) = best_of(cfg.runs, || {
                        let dc = DropCutter::new(&mesh, cutter);
                        dc.drop_points(&xy)
                    });
                    let asm = ToolAssembly::from_spec(cutter, &AssemblyDefaults::default());
                    let check = CheckConfig::default();
                    let (rep, check_s) = best_of(cfg.runs, || {
                        cam_holder::check_toolpath(&mesh, &asm, &plan.toolpath, &check)
                    });
                    let (stick, stick_s) = best_of(cfg.runs, || {
                        cam_holder::min_stick_out(&mesh, &asm, &plan.toolpath, &check)
                    });
                    let holder_s = check_s + stick_s;
                    let n = plan.drops;
                    let (calls, per, est) = (
                        n.to_string(),
                        format!("{:.1}", n as f64 / xy.len() as f64),
                        format!("{:.2}", drop_s * n as f64 / xy.len() as f64),
                    );
                    format!(
                        "| {name} | {} | {spec} | {} | {} | {plan_s:.3} | {drop_s:.3} | {:.1}x | \
                         {check_s:.3} | {stick_s:.3} | {:.0} % | {} | {} | {calls} | {per} | {est} |\n",
                        mesh.len(),
                        plan.passes,
                        xy.len(),
                        plan_s / drop_s,
                        100.0 * holder_s / plan_s,
                        rep.collisions.len(),
                        stick
                            .min_mm
                            .map_or("none".to_string(), |m| format!("{m:.3}")),
                    )
                }
            };
            eprint!("{line}");
            table.push_str(&line);
        }
    }
    println!("{table}");
    println!(
        "plan s: cam_plan::plan_part (DropCutter::new, sections, marching, side step, links). \
         drop-cutter s: DropCutter::new + drop_points on the XY of the plan's CL points (its \
         cut and plunge tips). holder: cam_holder::check_toolpath and cam_holder::min_stick_out \
         (default ER-collet assembly of the cutter, CheckConfig::default()), each building its \
         own HolderChecker; holder/plan = (check + min stick-out) / plan. planner drop calls: \
         exact CL samples the plan made (Plan::drops); drop s for those calls = drop-cutter s x calls per CL point. {}",
        crate::load_average()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    #[test]
    fn best_of_keeps_the_fastest_runs_result() {
        let runs = [("a", 3.0), ("b", 1.0), ("c", 2.0), ("d", 1.0)];
        assert_eq!(fastest(runs.into_iter()), Some(("b", 1.0)));
        assert_eq!(fastest(std::iter::empty::<(u8, f64)>()), None);
    }

    use super::*;

    #[test]
    fn cl_xy_counts_the_plans_cl_points() {
        let mesh = load(&crate::repo_root().join("fixtures/parts/tilted_plane.obj")).unwrap();
        let cfg = PlanBenchConfig {
            runs: 1,
            tolerance_mm: 0.05,
            scallop_mm: 0.2,
            parts: vec![],
            cutters: vec![],
        };
        let (plan, _) = time_plan(&mesh, &cfg, "ball:6".parse().unwrap()).unwrap();
        let xy = cl_xy(&plan.toolpath);
        assert!(plan.passes > 1, "{}", plan.passes);
        assert_eq!(xy.len(), plan.cl_points);
        // The planner samples the CL surface at least once per CL point.
        assert!(
            plan.drops >= plan.cl_points,
            "{} < {}",
            plan.drops,
            plan.cl_points
        );
        // Every CL point is on the CL surface: dropping the cutter there gives the plan's z.
        let dc = DropCutter::new(&mesh, cfg.plan_config("ball:6".parse().unwrap()).cutter);
        let tips: Vec<f64> = plan
            .toolpath
            .moves
            .iter()
            .filter(|m| matches!(m.kind, MoveKind::Cut | MoveKind::Plunge))
            .map(|m| m.pose.tip.z)
            .collect();
        for (p, z) in dc.drop_points(&xy).iter().zip(tips) {
            let zd = p.z_tip.expect("CL points touch the part");
            assert!((zd - z).abs() < 1e-6, "{zd} vs {z} at ({}, {})", p.x, p.y);
        }
    }

    #[test]
    fn best_of_runs_at_least_once() {
        let mut n = 0;
        let (r, s) = best_of(0, || {
            n += 1;
            n
        });
        assert_eq!((r, n), (1, 1));
        assert!(s >= 0.0);
    }
}
