//! Holder check speed on the bundled fixtures: a raster finishing path (drop-cutter ball 6,
//! 0.5 mm along, 1 mm across, zig-zag) checked with a ball-6 default assembly, against the
//! time the drop-cutter takes to make that path (the bulk of `cam plan`).
//!
//! `cargo bench -p cam-holder --bench check`

// criterion_group! generates an undocumented function.
#![allow(missing_docs)]

use std::path::PathBuf;

use cam_core::{Cutter, Mesh, Move, MoveKind, Pose, Toolpath, Units};
use cam_holder::{AssemblyDefaults, CheckConfig, HolderChecker, ToolAssembly, min_stick_out};
use cam_offset::{DropCutter, Grid};
use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;

fn fixture(name: &str) -> Mesh {
    let p = PathBuf::from("/work/shared/fixtures").join(name);
    Mesh::load(p, Units::Mm).expect("fixture")
}

fn grid(mesh: &Mesh) -> Grid {
    let b = mesh.bounds();
    let mut g = Grid::covering(b.min.x, b.max.x, b.min.y, b.max.y, 0.5);
    // Same number of drop points as the raster (every other row of the 0.5 mm grid).
    g.ny = (g.ny as f64 * 0.5).ceil() as usize;
    g
}

/// Zig-zag rows of the grid (rows are `y0 + j·2·step`), tips from the drop-cutter.
fn raster(dc: &DropCutter, mesh: &Mesh) -> Toolpath {
    let b = mesh.bounds();
    let g = Grid::covering(b.min.x, b.max.x, b.min.y, b.max.y, 0.5);
    let mut moves = Vec::new();
    let mut j = 0;
    while j < g.ny {
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
        j += 2;
    }
    Toolpath { moves }
}

fn bench(c: &mut Criterion) {
    let cutter = Cutter::ball(6.0).unwrap();
    let assembly = ToolAssembly::from_spec(cutter, &AssemblyDefaults::default());
    let cfg = CheckConfig::default();
    let mut g = c.benchmark_group("holder");
    g.sample_size(10);
    for name in [
        "ocl_sphere_on_plate.stl",
        "ocl_wheel_in_box.stl",
        "ocl_mount_rush.stl",
    ] {
        let mesh = fixture(name);
        let dc = DropCutter::new(&mesh, cutter);
        let gr = grid(&mesh);
        let path = raster(&dc, &mesh);
        let checker = HolderChecker::new(&mesh);
        let rep = checker.check(&assembly, &path, &cfg);
        let so = min_stick_out(&mesh, &assembly, &path, &cfg);
        eprintln!(
            "{name}: {} moves, {} collisions at stick-out {} (max depth {:.3} mm), min stick-out {:?}",
            path.moves.len(),
            rep.collisions.len(),
            assembly.stick_out_mm,
            rep.max_depth_mm,
            so.min_mm
        );
        g.bench_function(format!("drop_grid_{name}"), |b| {
            b.iter(|| DropCutter::new(&mesh, cutter).drop_grid(&gr))
        });
        g.bench_function(format!("check_{name}"), |b| {
            b.iter(|| HolderChecker::new(&mesh).check(&assembly, &path, &cfg))
        });
        g.bench_function(format!("min_stick_out_{name}"), |b| {
            b.iter(|| min_stick_out(&mesh, &assembly, &path, &cfg))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
