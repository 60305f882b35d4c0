//! `cargo xtask plan-report`: what a planned program leaves on the part, measured
//! independently of the planner. For each part and cutter: plan with `cam_plan::plan_part`,
//! post for LinuxCNC, read the G-code back, machine a z-map of the re-read program
//! (`cam_verify::zmap`, exact per node) and compare it with the design surface:
//!
//! - **gouge**: the deepest design point inside the swept volume. Where the z-map's vertical
//!   depth exceeds τ, ball and bull depths are computed exactly (the swept volume is the swept
//!   core grown by the corner radius r, so the depth is r minus the distance to the swept
//!   core); the vertical depth over-states it where the cutter's surface is steep. A flat end
//!   mill's volume swept along a move is convex (the segment ⊕ its disc ⊕ the shank ray up),
//!   so the depth is the least `h(u) − p·u` over directions `u` pointing down or level (h its
//!   support function); minimised over a set of directions refined about the best, so it
//!   can only be over-stated.
//! - **scallop**: the largest material left (vertical excess × the design normal's z, first
//!   order) at design points the cutter can touch: the cutter placed to touch the point along
//!   its normal is clear of the part (checked with the exact drop-cutter). Points it cannot
//!   touch (corners narrower than the cutter) are counted, not measured.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use cam_core::{Cutter, CutterKind, DVec3};
use cam_gcode::{Post, PostJob, ReadConfig, parse_gcode, post_to_string};
use cam_offset::DropCutter;
use cam_plan::PlanConfig;
use cam_verify::depth::SweptDepth;
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
    scallop: f64,
    scallop_at: (f64, f64),
    /// Reachable nodes left more than h.
    above_h: usize,
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
         max gouge mm | max scallop mm (at) | reachable nodes left > h | unreachable nodes / \
         nodes |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"
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
            let moves = SweptDepth::new(&tp, &cutter);
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
                scallop: 0.0,
                scallop_at: (f64::NAN, f64::NAN),
                above_h: 0,
                unreachable: 0,
                nodes: cmp.nodes.len(),
            };
            for n in &cmp.nodes {
                let (x, y) = (z.grid.x(n.i as usize), z.grid.y(n.j as usize));
                let p = DVec3::new(x, y, n.design_z_mm);
                if -n.vertical_mm > tau {
                    let g = if cutter.kind() == CutterKind::Flat {
                        // The vertical depth bounds the depth from above as well.
                        moves.depth(p).min(-n.vertical_mm)
                    } else {
                        moves.depth(p)
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
                    row.above_h += usize::from(s > h);
                    if s > row.scallop {
                        row.scallop = s;
                        row.scallop_at = (x, y);
                    }
                }
            }
            println!(
                "| {} | {} | {} | {} | {} | {} | {:.3} | {:.6} | {:.6} | {:.6} ({:.2}, {:.2}) | {} | {} / {} |",
                row.part,
                row.cutter,
                row.tau,
                row.h,
                row.passes,
                row.cl_points,
                row.plan_s,
                row.bound,
                row.gouge,
                row.scallop,
                row.scallop_at.0,
                row.scallop_at.1,
                row.above_h,
                row.unreachable,
                row.nodes
            );
        }
    }
    println!(
        "\nplanner's bound: the largest penetration or vertical excess the planner proved for a \
         cut move (a flat end mill: vertical, from the exact rise of the CL surface over the move). max gouge: deepest design point in the \
         swept volume of the re-read program (exact for ball and bull; for a flat end mill at \
         most over-stated by the direction search). max scallop: largest \
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
