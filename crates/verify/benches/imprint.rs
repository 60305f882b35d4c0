//! Imprint points per second: curves for a 5-axis pass (bull:38:3, Q = 40, 21 points per
//! curve), all poses in parallel (rayon) and on one thread.

#![allow(missing_docs)] // criterion_group! generates an undocumented function
use cam_core::Cutter;
use cam_verify::imprint::{Half, ImprintConfig, Imprinter, Placement, transport_frames};
use cam_verify::testpaths::{PassSpec, TestSurface, pass};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};

fn bench(c: &mut Criterion) {
    let cutter = Cutter::bull(38.0, 3.0).expect("valid cutter");
    let spec = PassSpec {
        surface: TestSurface::Cylinder { radius_mm: 80.0 },
        v_mm: 0.0,
        u0_mm: -150.0,
        poses: 20_000,
        step_mm: 0.015,
        lead_deg: 8.0,
        lead_wobble_deg: 2.0,
        wobble_period_mm: 60.0,
        tilt_deg: 3.0,
    };
    let poses: Vec<_> = pass(&spec, &cutter).moves.iter().map(|m| m.pose).collect();
    let frames = transport_frames(&poses, cutter.corner_radius());
    let mut g = c.benchmark_group("imprint");
    for placement in [Placement::Uniform, Placement::Adaptive] {
        let imp = Imprinter::new(
            &cutter,
            &ImprintConfig {
                inserts: 40,
                placement,
                ..ImprintConfig::default()
            },
        );
        let mut out = vec![cam_core::DVec3::ZERO; frames.len() * imp.points_per_curve()];
        g.throughput(Throughput::Elements(out.len() as u64));
        g.bench_function(format!("{placement:?}/parallel"), |b| {
            b.iter(|| imp.curves(&frames, Half::Cutting, &mut out));
        });
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("pool");
        g.bench_function(format!("{placement:?}/1-thread"), |b| {
            b.iter(|| one.install(|| imp.curves(&frames, Half::Cutting, &mut out)));
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
