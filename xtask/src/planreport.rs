//! `cargo xtask plan-report`: what a planned program leaves on the part, measured
//! independently of the planner. For each part and cutter: plan with `cam_plan::plan_part`,
//! post for LinuxCNC, read the G-code back, machine a z-map of the re-read program
//! (`cam_verify::zmap`, exact per node) and compare it with the design surface:
//!
//! - **gouge**: the deepest design point inside the swept volume. Where the z-map's vertical
//!   depth exceeds τ, ball and bull depths are computed exactly (the swept volume is the swept
//!   core grown by the corner radius r, so the depth is r minus the distance to the swept
//!   core); the vertical depth over-states it where the cutter's surface is steep. Flat end
//!   mills report the vertical depth.
//! - **scallop**: the largest material left (vertical excess × the design normal's z, first
//!   order) at design points the cutter can touch: the cutter placed to touch the point along
//!   its normal is clear of the part (checked with the exact drop-cutter). Points it cannot
//!   touch (corners narrower than the cutter) are counted, not measured.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use cam_core::{Cutter, CutterKind, DVec3, Toolpath};
use cam_gcode::{Post, PostJob, ReadConfig, parse_gcode, post_to_string};
use cam_offset::DropCutter;
use cam_plan::PlanConfig;
use cam_verify::zmap::{DesignHeights, ZmapConfig, ZmapGrid, compare_with_heights, machine};

use crate::planbench::{load, part_name};

/// One measured plan.
struct Row {
    part: String,
    cutter: String,
    tau: f64,
    h: f64,
    passes: usize,
    cl_points: usize,
    plan_s: f64,
    bound: f64,
    gouge: f64,
    gouge_exact: bool,
    scallop: f64,
    scallop_at: (f64, f64),
    unreachable: usize,
    nodes: usize,
}

/// Runs the report on `parts` × `cutters` at τ = 0.01 mm, h = 0.05 mm, z-map grid `res`.
pub fn plan_report(parts: &[PathBuf], cutters: &[String], res: f64) -> Result<()> {
    let (tau, h) = (0.01, 0.05);
    println!(
        "plan report: tau {tau} mm, h {h} mm, z-map grid {res} mm, LinuxCNC post read back; {}\n",
        crate::load_average()
    );
    println!(
        "| part | cutter | τ mm | h mm | passes | CL points | plan s | planner's bound mm | \
         max gouge mm | max scallop mm (at) | unreachable nodes / nodes |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"
    );
    for path in parts {
        let mesh = load(path)?;
        let dh = DesignHeights::new(&mesh);
        for spec in cutters {
            let cutter: Cutter = spec.parse()?;
            let cfg = PlanConfig {
                cutter,
                tolerance_mm: tau,
                scallop_mm: h,
                ..PlanConfig::default()
            };
            let t = Instant::now();
            let plan = cam_plan::plan_part(&mesh, &cfg, None)
                .with_context(|| format!("planning {} with {spec}", path.display()))?;
            let plan_s = t.elapsed().as_secs_f64();
            let job = PostJob {
                part_name: part_name(path),
                tool_spec: spec.clone(),
                tolerance_mm: tau,
                scallop_mm: h,
                safe_z_mm: plan.safe_z_mm,
                ..PostJob::default()
            };
            let text = post_to_string(&plan.toolpath, &job, Post::LinuxCnc)?;
            let tp = parse_gcode(&text, &ReadConfig::default())?;
            let b = mesh.bounds();
            let grid = ZmapGrid::covering(b.min.x, b.min.y, b.max.x, b.max.y, res)?;
            let z = machine(&tp, &cutter, &ZmapConfig::new(grid))?;
            let cmp = compare_with_heights(&z, &dh);
            let dc = DropCutter::new(&mesh, cutter);
            let moves = MoveIndex::new(&tp, cutter.radius());
            let mut row = Row {
                part: part_name(path),
                cutter: spec.clone(),
                tau,
                h,
                passes: plan.passes,
                cl_points: plan.cl_points,
                plan_s,
                bound: plan.max_chord_deviation_mm,
                gouge: 0.0,
                gouge_exact: cutter.kind() != CutterKind::Flat,
                scallop: 0.0,
                scallop_at: (f64::NAN, f64::NAN),
                unreachable: 0,
                nodes: cmp.nodes.len(),
            };
            for n in &cmp.nodes {
                let (x, y) = (z.grid.x(n.i as usize), z.grid.y(n.j as usize));
                let p = DVec3::new(x, y, n.design_z_mm);
                if -n.vertical_mm > tau {
                    let g = if row.gouge_exact {
                        moves.depth(&cutter, p)
                    } else {
                        -n.vertical_mm
                    };
                    row.gouge = row.gouge.max(g);
                } else {
                    row.gouge = row.gouge.max(-n.vertical_mm);
                }
                if n.vertical_mm > 0.0 {
                    let Some(normal) = dh
                        .top(x, y)
                        .and_then(|(_, t)| dh.triangles()[t as usize].normal())
                    else {
                        continue;
                    };
                    let normal = if normal.z < 0.0 { -normal } else { normal };
                    if !reachable(&dc, &cutter, p, normal) {
                        row.unreachable += 1;
                        continue;
                    }
                    let s = n.vertical_mm * n.normal_z;
                    if s > row.scallop {
                        row.scallop = s;
                        row.scallop_at = (x, y);
                    }
                }
            }
            println!(
                "| {} | {} | {} | {} | {} | {} | {:.3} | {:.6} | {:.6}{} | {:.6} ({:.2}, {:.2}) | {} / {} |",
                row.part,
                row.cutter,
                row.tau,
                row.h,
                row.passes,
                row.cl_points,
                row.plan_s,
                row.bound,
                row.gouge,
                if row.gouge_exact { "" } else { " (vertical)" },
                row.scallop,
                row.scallop_at.0,
                row.scallop_at.1,
                row.unreachable,
                row.nodes
            );
        }
    }
    println!(
        "\nplanner's bound: the largest penetration or vertical excess the planner proved for a \
         cut move (flat end mills: checked at samples). max gouge: deepest design point in the \
         swept volume of the re-read program (exact for ball and bull). max scallop: largest \
         material left at a design point the cutter can touch, normal to the surface (first \
         order), so it includes the up-to-τ excess a move may keep over the CL surface."
    );
    Ok(())
}

/// Whether the cutter can touch the design point `p` with outward normal `n`: placed so its
/// surface meets `p` with the same normal, is it clear of the part?
fn reachable(dc: &DropCutter, c: &Cutter, p: DVec3, n: DVec3) -> bool {
    let (a, r) = (c.major_radius(), c.corner_radius());
    let nxy = (n.x * n.x + n.y * n.y).sqrt();
    let tip = if nxy < 1e-9 {
        p
    } else {
        // The corner-circle point with normal n is p + r·n; the axis is a further a along the
        // horizontal normal; the tip lies r below the corner circle's plane.
        let g = p + n * r;
        DVec3::new(g.x + a * n.x / nxy, g.y + a * n.y / nxy, g.z - r)
    };
    match dc.drop(tip.x, tip.y) {
        Some(z) => z <= tip.z + 1e-6,
        None => true,
    }
}

/// Moves of a toolpath bucketed by XY cells, for exact depths.
struct MoveIndex {
    moves: Vec<(DVec3, DVec3)>,
    cell: f64,
    x0: f64,
    y0: f64,
    nx: usize,
    ny: usize,
    buckets: Vec<Vec<u32>>,
}

impl MoveIndex {
    fn new(tp: &Toolpath, reach: f64) -> MoveIndex {
        let moves: Vec<(DVec3, DVec3)> = tp
            .moves
            .windows(2)
            .map(|w| (w[0].pose.tip, w[1].pose.tip))
            .collect();
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for &(a, b) in &moves {
            lo = lo.min(a).min(b);
            hi = hi.max(a).max(b);
        }
        let cell = reach.max(1.0);
        let (x0, y0) = (lo.x - reach, lo.y - reach);
        let nx = (((hi.x + reach - x0) / cell).ceil() as usize).max(1);
        let ny = (((hi.y + reach - y0) / cell).ceil() as usize).max(1);
        let mut buckets = vec![Vec::new(); nx * ny];
        let ci = |v: f64, o: f64, n: usize| (((v - o) / cell).floor().max(0.0) as usize).min(n - 1);
        for (k, &(a, b)) in moves.iter().enumerate() {
            let (l, h) = (a.min(b), a.max(b));
            for j in ci(l.y - reach, y0, ny)..=ci(h.y + reach, y0, ny) {
                for i in ci(l.x - reach, x0, nx)..=ci(h.x + reach, x0, nx) {
                    buckets[j * nx + i].push(k as u32);
                }
            }
        }
        MoveIndex {
            moves,
            cell,
            x0,
            y0,
            nx,
            ny,
            buckets,
        }
    }

    /// Exact depth (mm) of `p` in the volume a ball or bull cutter sweeps along the moves:
    /// r minus the distance from `p` to the swept core (convex along each move).
    fn depth(&self, c: &Cutter, p: DVec3) -> f64 {
        let (a, r) = (c.major_radius(), c.corner_radius());
        let i = (((p.x - self.x0) / self.cell).floor().max(0.0) as usize).min(self.nx - 1);
        let j = (((p.y - self.y0) / self.cell).floor().max(0.0) as usize).min(self.ny - 1);
        let dist = |tip: DVec3| {
            let q = p - (tip + DVec3::Z * r);
            let rad = (q.x * q.x + q.y * q.y).sqrt();
            ((rad - a).max(0.0).powi(2) + q.z * q.z).sqrt()
        };
        let mut depth = f64::NEG_INFINITY;
        for &k in &self.buckets[j * self.nx + i] {
            let (s, e) = self.moves[k as usize];
            let (mut t0, mut t1) = (0.0f64, 1.0f64);
            for _ in 0..100 {
                let m1 = t0 + (t1 - t0) / 3.0;
                let m2 = t1 - (t1 - t0) / 3.0;
                if dist(s.lerp(e, m1)) <= dist(s.lerp(e, m2)) {
                    t1 = m2;
                } else {
                    t0 = m1;
                }
            }
            let d = dist(s.lerp(e, 0.5 * (t0 + t1))).min(dist(s)).min(dist(e));
            depth = depth.max(r - d);
        }
        depth
    }
}
