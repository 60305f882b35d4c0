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
                scallop: 0.0,
                scallop_at: (f64::NAN, f64::NAN),
                unreachable: 0,
                nodes: cmp.nodes.len(),
            };
            for n in &cmp.nodes {
                let (x, y) = (z.grid.x(n.i as usize), z.grid.y(n.j as usize));
                let p = DVec3::new(x, y, n.design_z_mm);
                if -n.vertical_mm > tau {
                    let g = if cutter.kind() == CutterKind::Flat {
                        // The vertical depth bounds the depth from above as well.
                        moves.flat_depth(cutter.radius(), p).min(-n.vertical_mm)
                    } else {
                        moves.depth(&cutter, p)
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
                "| {} | {} | {} | {} | {} | {} | {:.3} | {:.6} | {:.6} | {:.6} ({:.2}, {:.2}) | {} / {} |",
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
                row.unreachable,
                row.nodes
            );
        }
    }
    println!(
        "\nplanner's bound: the largest penetration or vertical excess the planner proved for a \
         cut move (flat end mills: checked at samples). max gouge: deepest design point in the \
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

    /// Depth (mm) of `p` in the volume a flat end mill of radius `rr` sweeps along the moves,
    /// at least the exact depth: the largest over the moves of the depth in each move's convex
    /// swept volume, each the least `max(a·u, b·u) + rr·|u_xy| − p·u` over unit directions `u`
    /// with `u_z ≤ 0` (a grid of directions, then a local refinement about the best one).
    fn flat_depth(&self, rr: f64, p: DVec3) -> f64 {
        let i = (((p.x - self.x0) / self.cell).floor().max(0.0) as usize).min(self.nx - 1);
        let j = (((p.y - self.y0) / self.cell).floor().max(0.0) as usize).min(self.ny - 1);
        let dir = |az: f64, el: f64| {
            let (se, ce) = el.sin_cos();
            DVec3::new(ce * az.cos(), ce * az.sin(), -se)
        };
        let mut depth = f64::NEG_INFINITY;
        for &k in &self.buckets[j * self.nx + i] {
            let (a, b) = self.moves[k as usize];
            // Only a move whose flat bottom passes below p at p's XY contains it: the bottom
            // is at the tip's z wherever the tip is within rr of p in XY.
            let d = b.truncate() - a.truncate();
            let w = p.truncate() - a.truncate();
            let dd = d.length_squared();
            let (t0, t1) = if dd < 1e-24 {
                if w.length_squared() > rr * rr {
                    continue;
                }
                (0.0, 1.0)
            } else {
                let tc = w.dot(d) / dd;
                let perp2 = (w - d * tc).length_squared();
                if perp2 > rr * rr {
                    continue;
                }
                let half = ((rr * rr - perp2) / dd).sqrt();
                ((tc - half).max(0.0), (tc + half).min(1.0))
            };
            if t0 > t1 || a.z + (b.z - a.z) * t0 >= p.z && a.z + (b.z - a.z) * t1 >= p.z {
                continue;
            }
            let f = |az: f64, el: f64| {
                let u = dir(az, el.clamp(0.0, std::f64::consts::FRAC_PI_2));
                a.dot(u).max(b.dot(u)) + rr * (u.x * u.x + u.y * u.y).sqrt() - p.dot(u)
            };
            // Grid, then a pattern search (axis and diagonal steps, which follow the ridge
            // where the two end points' planes meet) from each of the best few grid
            // directions: the function is convex in u ∈ R³ but not on the sphere.
            const NA: usize = 180;
            const NE: usize = 45;
            let mut grid: Vec<(f64, f64, f64)> = Vec::with_capacity(NA * (NE + 1));
            for ia in 0..NA {
                for ie in 0..=NE {
                    let (az, el) = (
                        ia as f64 * std::f64::consts::TAU / NA as f64,
                        ie as f64 * std::f64::consts::FRAC_PI_2 / NE as f64,
                    );
                    grid.push((f(az, el), az, el));
                }
            }
            grid.sort_by(|x, y| x.0.total_cmp(&y.0));
            let mut best = f64::INFINITY;
            for &(v0, az0, el0) in grid.iter().take(4) {
                let (mut v, mut az, mut el) = (v0, az0, el0);
                let mut step = std::f64::consts::TAU / NA as f64;
                while step > 1e-9 {
                    let mut moved = false;
                    for (da, de) in [
                        (1.0, 0.0),
                        (-1.0, 0.0),
                        (0.0, 1.0),
                        (0.0, -1.0),
                        (1.0, 1.0),
                        (1.0, -1.0),
                        (-1.0, 1.0),
                        (-1.0, -1.0),
                    ] {
                        let e = (el + de * step).clamp(0.0, std::f64::consts::FRAC_PI_2);
                        let w = f(az + da * step, e);
                        if w < v {
                            (v, az, el) = (w, az + da * step, e);
                            moved = true;
                        }
                    }
                    if !moved {
                        step *= 0.5;
                    }
                }
                best = best.min(v);
            }
            depth = depth.max(best);
        }
        depth
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
