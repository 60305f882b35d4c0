//! Criterion benches of the drop-cutter: index build and single-thread drops on a fixture.
#![allow(missing_docs)] // criterion_group! generates undocumented items
//! Run: `cargo bench -p cam-offset`.

use cam_core::{Cutter, Mesh, Units};
use cam_offset::{DropCutter, Grid};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};

fn fixture(name: &str) -> Mesh {
    let p = format!(
        "{}/../../../shared/fixtures/{name}",
        env!("CARGO_MANIFEST_DIR")
    );
    Mesh::load(p, Units::Mm).expect("fixture")
}

fn bench(c: &mut Criterion) {
    let mesh = fixture("ocl_mount_rush.stl");
    let b = mesh.bounds();
    // A 64x16 patch in the middle of the relief: single-thread inner loop.
    let grid = Grid {
        x0: b.min.x + 0.3 * b.size().x,
        y0: b.min.y + 0.4 * b.size().y,
        step: 0.5,
        nx: 64,
        ny: 16,
    };
    let pts: Vec<(f64, f64)> = (0..grid.len()).map(|k| grid.xy(k)).collect();
    let mut g = c.benchmark_group("drop");
    g.throughput(Throughput::Elements(pts.len() as u64));
    for spec in ["ball:6", "flat:6", "bull:6:1.5"] {
        let cutter: Cutter = spec.parse().unwrap();
        let dc = DropCutter::new(&mesh, cutter);
        g.bench_with_input(BenchmarkId::new("mount_rush", spec), &pts, |bch, pts| {
            bch.iter(|| {
                pts.iter()
                    .map(|&(x, y)| dc.drop(x, y).unwrap_or(0.0))
                    .sum::<f64>()
            })
        });
    }
    g.finish();
    let mut g = c.benchmark_group("build");
    g.bench_function("mount_rush_ball6", |bch| {
        bch.iter(|| DropCutter::new(&mesh, Cutter::ball(6.0).unwrap()))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
