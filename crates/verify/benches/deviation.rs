//! Speed of the measuring half of `cam verify` on a fixture part: refinement, the
//! normal-vector deviation, and the independent z-map.
//!
//! Run: `cargo bench -p cam-verify --bench deviation`.

// `criterion_group!` defines an undocumented public function.
#![allow(missing_docs)]

use std::hint::black_box;

use cam_core::{Cutter, DVec3, Mesh, Move, MoveKind, Pose, Toolpath, Triangle, Units};
use cam_verify::deviation::{self, DeviationConfig};
use cam_verify::refine::{self, CapPolicy, RefineConfig};
use cam_verify::zmap::{self, ZmapConfig, ZmapGrid};
use criterion::{Criterion, criterion_group, criterion_main};

fn part() -> Mesh {
    let p = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/fixtures/ocl_sphere_on_plate.stl"
    );
    Mesh::load(p, Units::Mm).expect("fixture")
}

fn bench(c: &mut Criterion) {
    let m = part();
    let cfg = RefineConfig {
        max_edge_mm: 0.6,
        crease_angle_deg: 30.0,
        max_vertices: None,
        on_cap: CapPolicy::Error,
        region: None,
        remesh: true,
    };
    let mut g = c.benchmark_group("deviation");
    g.sample_size(10);
    g.bench_function("refine sphere_on_plate s=0.6", |b| {
        b.iter(|| refine::refine(black_box(&m), &cfg).unwrap())
    });
    let r = refine::refine(&m, &cfg).unwrap();
    // A stand-in sweep: the part raised 0.01 mm, facing into it.
    let sw: Vec<Triangle> = m
        .triangles()
        .iter()
        .map(|t| {
            Triangle::new(
                t.v[0] + 0.01 * DVec3::Z,
                t.v[2] + 0.01 * DVec3::Z,
                t.v[1] + 0.01 * DVec3::Z,
            )
        })
        .collect();
    let mv: Vec<u32> = (0..sw.len() as u32).collect();
    g.bench_function(format!("measure {} vertices", r.len()), |b| {
        b.iter(|| deviation::measure(&r, black_box(&sw), &mv, &DeviationConfig::default()).unwrap())
    });
    // Z-map: a 20 × 20 mm zig-zag, step 0.5, CL points 0.2 apart, grid 0.05 mm.
    let mut moves = Vec::new();
    for k in 0..=40 {
        let y = 0.5 * k as f64;
        for i in 0..=100 {
            let x = if k % 2 == 0 {
                0.2 * i as f64
            } else {
                20.0 - 0.2 * i as f64
            };
            let tip = DVec3::new(x, y, 0.3 * (0.3 * x).sin());
            moves.push(Move {
                kind: MoveKind::Cut,
                pose: Pose::vertical(tip),
                feed_mm_per_min: None,
                line: None,
                pass: None,
            });
        }
    }
    let tp = Toolpath { moves };
    let zc = ZmapConfig::new(ZmapGrid::covering(0.0, 0.0, 20.0, 20.0, 0.05).unwrap());
    for spec in ["ball:6", "bull:10:2"] {
        let cutter: Cutter = spec.parse().unwrap();
        g.bench_function(
            format!("zmap {spec} 401x401 nodes {} moves", tp.moves.len()),
            |b| b.iter(|| zmap::machine(black_box(&tp), &cutter, &zc).unwrap()),
        );
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
