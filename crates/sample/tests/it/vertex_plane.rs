//! Planes through rows of mesh vertices: no duplicate or missing points, brute-force
//! agreement.

use cam_sample::{RasterFrame, Sectioner};

use crate::util::{Rng, check_profile, compare, grid_mesh};

fn bumpy(x: f64, y: f64) -> f64 {
    2.0 * (x / 3.0).sin() * (y / 2.0).cos() + 0.1 * x + 0.05 * x * y + 0.02 * x * x + 0.03 * y * y
}

/// A plane through a row of grid vertices: the top profile is exactly the polyline through
/// that row's vertices: every vertex once, nothing else.
#[test]
fn plane_through_vertex_rows_is_the_row_polyline() {
    let m = grid_mesh((0.0, 0.0), (20, 10), 1.0, bumpy, |_, _| true);
    let s = Sectioner::new(&m, RasterFrame::new(0.0));
    for k in 0..=10 {
        let y = k as f64;
        let ps = s.top_profile(y);
        assert_eq!(ps.len(), 1, "y = {y}");
        let expect: Vec<(f64, f64)> = (0..=20).map(|i| (i as f64, bumpy(i as f64, y))).collect();
        assert_eq!(ps[0].points, expect, "y = {y}");
    }
    // Passes along +Y: planes x = i, v = -x.
    let s = Sectioner::new(&m, RasterFrame::new(90.0));
    for i in 0..=20 {
        let x = i as f64;
        let ps = s.top_profile(-x);
        assert_eq!(ps.len(), 1, "x = {x}");
        let expect: Vec<(f64, f64)> = (0..=10).map(|k| (k as f64, bumpy(x, k as f64))).collect();
        assert_eq!(ps[0].points, expect, "x = {x}");
    }
}

/// Planes through vertex rows, just beside them, and between them, in axis-aligned and
/// rotated frames, compared with dense vertical-ray sampling of every triangle.
#[test]
fn vertex_rows_against_brute_force() {
    let m = grid_mesh((0.0, 0.0), (20, 10), 1.0, bumpy, |i, j| {
        (i + 2 * j) % 7 != 3
    });
    let mut rng = Rng(11);
    let mut worst: f64 = 0.0;
    let mut compared = 0;
    let (mut boundary, mut isolated) = (0, 0);
    for angle in [0.0, 90.0, 180.0, 45.0, 33.0] {
        let s = Sectioner::new(&m, RasterFrame::new(angle));
        let (v0, v1) = s.v_range();
        let (u0, u1) = s.u_range();
        // Planes: through vertices (exact for the axis-aligned frames), ±1 ulp-ish, between.
        let mut vs: Vec<f64> = m
            .triangles()
            .iter()
            .take(40)
            .map(|t| s.frame().to_uv(t.v[0].x, t.v[0].y).1)
            .collect();
        vs.extend(vs.clone().iter().flat_map(|&v| [v + 1e-11, v - 1e-11]));
        vs.extend((0..10).map(|_| rng.range(v0, v1)));
        for v in vs {
            for p in s.top_profile(v) {
                check_profile(&p);
            }
            // Dense and random u, plus the vertices' u.
            let mut us: Vec<f64> = (0..=400)
                .map(|i| u0 + (u1 - u0) * i as f64 / 400.0)
                .collect();
            us.extend((0..100).map(|_| rng.range(u0, u1)));
            let a = compare(&s, v, &us);
            // Coverage may differ only where a profile ends exactly at a sample u on a
            // boundary both methods treat as closed; require agreement.
            assert_eq!(a.coverage_mismatch, 0, "angle {angle} v {v}: {a:?}");
            assert!(a.max_dz <= 1e-12, "angle {angle} v {v}: {a:?}");
            worst = worst.max(a.max_dz);
            compared += a.both;
            boundary += a.boundary_mismatch;
            isolated += a.isolated_touch;
        }
    }
    eprintln!(
        "vertex rows: {compared} samples, max |dz| vs brute force {worst:e} mm; \
         tolerated: {boundary} at profile ends, {isolated} isolated touch points"
    );
}
