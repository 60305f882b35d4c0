//! Section throughput on `ocl_mount_rush.stl`: top profiles per second, and whole-part
//! sampling (1 mm planes, 0.5 mm arc step).

use std::hint::black_box;

use cam_core::{Mesh, Units};
use cam_sample::{RasterFrame, SampleConfig, Sectioner, resample_u, sample_part};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};

const FIXTURES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/fixtures/");

fn load(name: &str) -> Mesh {
    Mesh::load(format!("{FIXTURES}{name}"), Units::Mm).expect("fixture loads")
}

fn sections(c: &mut Criterion) {
    let mesh = load("ocl_mount_rush.stl");
    let mut g = c.benchmark_group("sections");
    g.sample_size(20);

    g.bench_function("sectioner_new/mount_rush", |b| {
        b.iter(|| black_box(Sectioner::new(black_box(&mesh), RasterFrame::new(0.0))))
    });

    let s = Sectioner::new(&mesh, RasterFrame::new(0.0));
    let (v0, v1) = s.v_range();
    let planes: Vec<f64> = (0..100)
        .map(|i| v0 + (v1 - v0) * (i as f64 + 0.5) / 100.0)
        .collect();
    g.throughput(Throughput::Elements(planes.len() as u64));
    g.bench_function("top_profile/mount_rush/100_planes", |b| {
        b.iter(|| {
            for &v in &planes {
                black_box(s.top_profile(black_box(v)));
            }
        })
    });
    g.bench_function("top_profile+resample_0.5/mount_rush/100_planes", |b| {
        b.iter(|| {
            for &v in &planes {
                for p in s.top_profile(v) {
                    black_box(resample_u(&p, 0.5));
                }
            }
        })
    });

    let cfg = SampleConfig {
        angle_deg: 0.0,
        plane_spacing_mm: 1.0,
        arc_step_mm: 0.5,
    };
    let n_planes = sample_part(&mesh, &cfg).expect("samples").len();
    g.throughput(Throughput::Elements(n_planes as u64));
    g.bench_function("sample_part/mount_rush/1mm_0.5mm", |b| {
        b.iter(|| black_box(sample_part(black_box(&mesh), &cfg).expect("samples")))
    });
    let cfg30 = SampleConfig {
        angle_deg: 30.0,
        ..cfg
    };
    g.bench_function("sample_part/mount_rush/1mm_0.5mm_angle30", |b| {
        b.iter(|| black_box(sample_part(black_box(&mesh), &cfg30).expect("samples")))
    });
    g.finish();
}

// `criterion_group!` defines an undocumented public function.
#[allow(missing_docs)]
mod group {
    use super::*;
    criterion_group!(benches, sections);
}
use group::benches;
criterion_main!(benches);
