//! Checks a raster finishing path on a part for holder collisions and prints the report
//! summary and the minimum stick-out.
//!
//! `cargo run --release -p cam-holder --example check_fixture -- PART.stl [ball:6]`

use std::time::Instant;

use cam_core::{Cutter, Mesh, Move, MoveKind, Pose, Toolpath, Units};
use cam_holder::{
    AssemblyDefaults, CheckConfig, CurvatureConfig, HolderChecker, ToolAssembly, concave_curvature,
    min_stick_out,
};
use cam_offset::{DropCutter, Grid};
use glam::DVec3;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let part = args.get(1).ok_or("usage: check_fixture PART.stl [SPEC]")?;
    let cutter: Cutter = args.get(2).map_or("ball:6", |s| s.as_str()).parse()?;
    let mesh = Mesh::load(part, Units::Mm)?;
    let b = mesh.bounds();
    let g = Grid::covering(b.min.x, b.max.x, b.min.y, b.max.y, 0.5);
    let t0 = Instant::now();
    let dc = DropCutter::new(&mesh, cutter);
    let mut moves = Vec::new();
    for j in (0..g.ny).step_by(2) {
        let mut row: Vec<(f64, f64)> = (0..g.nx)
            .map(|i| (g.x0 + i as f64 * g.step, g.y0 + j as f64 * g.step))
            .collect();
        if (j / 2) % 2 == 1 {
            row.reverse();
        }
        for p in dc.drop_points(&row) {
            if let Some(z) = p.z_tip {
                moves.push(Move {
                    kind: MoveKind::Cut,
                    pose: Pose::vertical(DVec3::new(p.x, p.y, z)),
                    feed_mm_per_min: None,
                    line: None,
                    pass: Some(j / 2),
                });
            }
        }
    }
    let path = Toolpath { moves };
    let t_drop = t0.elapsed();
    let assembly = ToolAssembly::from_spec(cutter, &AssemblyDefaults::default());
    let cfg = CheckConfig::default();
    // Best of five runs each (the machine may be shared).
    let mut t_check = std::time::Duration::MAX;
    let mut rep = cam_holder::CollisionReport::default();
    for _ in 0..5 {
        let t1 = Instant::now();
        rep = HolderChecker::new(&mesh).check(&assembly, &path, &cfg);
        t_check = t_check.min(t1.elapsed());
    }
    let mut t_so = std::time::Duration::MAX;
    let mut so = None;
    for _ in 0..5 {
        let t2 = Instant::now();
        so = Some(min_stick_out(&mesh, &assembly, &path, &cfg));
        t_so = t_so.min(t2.elapsed());
    }
    let so = so.expect("ran");
    let mut t_drop = t_drop;
    for _ in 0..4 {
        let t0 = Instant::now();
        let dc = DropCutter::new(&mesh, cutter);
        for j in (0..g.ny).step_by(2) {
            let row: Vec<(f64, f64)> = (0..g.nx)
                .map(|i| (g.x0 + i as f64 * g.step, g.y0 + j as f64 * g.step))
                .collect();
            std::hint::black_box(dc.drop_points(&row));
        }
        t_drop = t_drop.min(t0.elapsed());
    }
    // CPU time (all threads, from /proc, 10 ms ticks) over repeated runs: robust to a shared
    // machine.
    let cpu = || -> f64 {
        let st = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
        let f: Vec<&str> = st
            .rsplit(')')
            .next()
            .unwrap_or("")
            .split_whitespace()
            .collect();
        let t = |i: usize| f.get(i).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
        (t(11) + t(12)) * 10.0 // utime + stime in ms (USER_HZ = 100)
    };
    let reps = 30;
    let c0 = cpu();
    for _ in 0..reps {
        let dc = DropCutter::new(&mesh, cutter);
        for j in (0..g.ny).step_by(2) {
            let row: Vec<(f64, f64)> = (0..g.nx)
                .map(|i| (g.x0 + i as f64 * g.step, g.y0 + j as f64 * g.step))
                .collect();
            std::hint::black_box(dc.drop_points(&row));
        }
    }
    let c1 = cpu();
    for _ in 0..reps {
        std::hint::black_box(HolderChecker::new(&mesh).check(&assembly, &path, &cfg));
    }
    let c2 = cpu();
    for _ in 0..reps {
        std::hint::black_box(min_stick_out(&mesh, &assembly, &path, &cfg));
    }
    let c3 = cpu();
    let per = |a: f64, b: f64| (b - a) / reps as f64;
    println!(
        "CPU per run: drop-cutter path {:.1} ms, holder check {:.1} ms ({:.0} %), min stick-out {:.1} ms ({:.0} %)",
        per(c0, c1),
        per(c1, c2),
        100.0 * per(c1, c2) / per(c0, c1),
        per(c2, c3),
        100.0 * per(c2, c3) / per(c0, c1)
    );
    println!(
        "{} triangles, {} moves; drop-cutter path {:.1} ms",
        mesh.len(),
        path.moves.len(),
        t_drop.as_secs_f64() * 1e3
    );
    println!(
        "holder check at stick-out {} mm: {} collisions, max depth {:.3} mm, {:.1} ms ({:.0} % of the path time)",
        assembly.stick_out_mm,
        rep.collisions.len(),
        rep.max_depth_mm,
        t_check.as_secs_f64() * 1e3,
        100.0 * t_check.as_secs_f64() / t_drop.as_secs_f64()
    );
    println!(
        "minimum stick-out {:?} (limiting {:?}) in {:.1} ms",
        so.min_mm,
        so.limiting,
        t_so.as_secs_f64() * 1e3
    );
    let t3 = Instant::now();
    let c = concave_curvature(&mesh, &CurvatureConfig::default());
    println!(
        "concave radius: min {:?}, wall {:?}, floor {:?}, {} sharp concave edges, {} edges skipped, {} dents ignored ({:.1} ms)",
        c.min.map(|m| (m.radius_mm, m.region)),
        c.min_wall.map(|m| m.radius_mm),
        c.min_floor.map(|m| m.radius_mm),
        c.sharp_edges.len(),
        c.edges_skipped,
        c.dents_ignored,
        t3.elapsed().as_secs_f64() * 1e3
    );
    Ok(())
}
