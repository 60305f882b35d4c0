//! Smallest concave radius: a fillet of radius 6 must read 6 ± 2 % for any tessellation.

use cam_core::{Mesh, Triangle, assert_near};
use cam_holder::{CurvatureConfig, concave_curvature};
use glam::DVec3;

use crate::common::Rng;

/// Tessellation of a floor (z = 0), a wall (y = 0) and a fillet of radius `r` between them
/// along X for x ∈ [0, 30]. `n` arc steps; `jitter` moves interior arc vertices by up to
/// that fraction of a step; `irregular` places each ruling's vertices at random x and zips
/// neighbouring rulings together (every triangle spans one strip).
pub fn fillet(r: f64, n: usize, jitter: f64, irregular: bool, seed: u64) -> Mesh {
    let mut rng = Rng(seed);
    // Profile in (y, z): wall top, wall bottom = arc start, arc, arc end = floor start, floor end.
    let mut prof: Vec<(f64, f64, DVec3)> = Vec::new(); // (y, z, outward normal)
    prof.push((0.0, r + 20.0, DVec3::Y));
    for k in 0..=n {
        let mut s = k as f64;
        if k > 0 && k < n {
            s += jitter * (2.0 * rng.next() - 1.0);
        }
        let psi = std::f64::consts::PI + std::f64::consts::FRAC_PI_2 * s / n as f64;
        let (y, z) = (r + r * psi.cos(), r + r * psi.sin());
        let (y, z) = if k == 0 {
            (0.0, r)
        } else if k == n {
            (r, 0.0)
        } else {
            (y, z)
        };
        prof.push((y, z, DVec3::new(0.0, -psi.cos(), -psi.sin())));
    }
    prof.push((r + 20.0, 0.0, DVec3::Z));
    // Ruling x positions.
    let xs: Vec<Vec<f64>> = prof
        .iter()
        .map(|_| {
            if irregular {
                let m = 3 + (rng.next() * 12.0) as usize;
                let mut v: Vec<f64> = (0..m).map(|_| 30.0 * rng.next()).collect();
                v.push(0.0);
                v.push(30.0);
                v.sort_by(f64::total_cmp);
                v.dedup_by(|a, b| (*a - *b).abs() < 0.05);
                v
            } else {
                vec![0.0, 10.0, 20.0, 30.0]
            }
        })
        .collect();
    let mut tris = Vec::new();
    for k in 0..prof.len() - 1 {
        let (y0, z0, n0) = prof[k];
        let (y1, z1, n1) = prof[k + 1];
        let want = n0 + n1;
        let (a, b) = (&xs[k], &xs[k + 1]);
        let (mut i, mut j) = (0, 0);
        let pa = |x: f64| DVec3::new(x, y0, z0);
        let pb = |x: f64| DVec3::new(x, y1, z1);
        while i + 1 < a.len() || j + 1 < b.len() {
            let t = if j + 1 >= b.len() || (i + 1 < a.len() && a[i + 1] <= b[j + 1]) {
                i += 1;
                Triangle::new(pa(a[i - 1]), pa(a[i]), pb(b[j]))
            } else {
                j += 1;
                Triangle::new(pa(a[i]), pb(b[j]), pb(b[j - 1]))
            };
            let t = if t.cross().dot(want) < 0.0 {
                Triangle::new(t.v[0], t.v[2], t.v[1])
            } else {
                t
            };
            tris.push(t);
        }
    }
    Mesh::from_triangles(tris, "<fillet>").unwrap()
}

#[test]
fn fillet_radius_six_over_tessellations() {
    let cfg = CurvatureConfig::default();
    let mut worst: f64 = 0.0;
    for n in [16, 24, 32, 48, 64, 96, 128] {
        for (jitter, irregular) in [(0.0, false), (0.0, true), (0.3, false), (0.3, true)] {
            let mesh = fillet(6.0, n, jitter, irregular, 17 + n as u64);
            let c = concave_curvature(&mesh, &cfg);
            let m = c.min.expect("concave edges");
            let rel = (m.radius_mm - 6.0).abs() / 6.0;
            worst = worst.max(rel);
            assert!(
                rel <= 0.02,
                "n = {n}, jitter {jitter}, irregular {irregular}: read {} mm",
                m.radius_mm
            );
            // Regular arc steps read the radius exactly.
            if jitter == 0.0 {
                assert_near!(m.radius_mm, 6.0, 1e-9, "n = {n}, irregular {irregular}");
            }
            // The region is on the fillet: 6 mm from its axis (y, z) = (6, 6).
            let d = ((m.region.y - 6.0).powi(2) + (m.region.z - 6.0).powi(2)).sqrt();
            assert!(
                (6.0 * (1.0 - 0.01)..=6.0 + 1e-9).contains(&d),
                "region {} off the fillet",
                m.region
            );
            assert!(c.min_wall.is_none());
            assert_eq!(c.min_floor, c.min);
            assert!(c.sharp_edges.is_empty());
        }
    }
    eprintln!("fillet r = 6: worst relative error {worst:e}");
}

#[test]
fn sharp_pocket_has_sharp_edges_and_no_smooth_radius() {
    let mesh = crate::common::pocket(20.0, 25.0, 40.0);
    let c = concave_curvature(&mesh, &CurvatureConfig::default());
    assert!(c.min.is_none());
    // floor/wall edges (4) and wall/wall corners (4), each split in two by the quad diagonals? No:
    // quads share whole edges, so 8 concave edges at 90°.
    assert_eq!(c.sharp_edges.len(), 8);
    for e in &c.sharp_edges {
        assert_near!(e.angle_deg, 90.0, 1e-9);
    }
}

/// A pocket corner rounded with radius `r` about a vertical axis: two walls (x = 0 facing +x
/// and y = 0 facing +y) joined by a quarter cylinder, `n` steps, height 20, irregular rulings.
fn vertical_corner(r: f64, n: usize, seed: u64) -> Mesh {
    // Reuse the fillet builder in a rotated frame: (x, y, z) → (y, z, x) maps its X axis
    // (the fillet axis) onto Z.
    let m = fillet(r, n, 0.2, true, seed);
    let tris = m
        .triangles()
        .iter()
        .map(|t| {
            let f = |p: DVec3| DVec3::new(p.y, p.z, p.x);
            Triangle::new(f(t.v[0]), f(t.v[1]), f(t.v[2]))
        })
        .collect();
    Mesh::from_triangles(tris, "<corner>").unwrap()
}

#[test]
fn vertical_fillet_is_a_wall_radius() {
    for n in [16, 40, 128] {
        let c = concave_curvature(
            &vertical_corner(6.0, n, n as u64),
            &CurvatureConfig::default(),
        );
        let w = c.min_wall.expect("wall edges");
        assert!(
            (w.radius_mm - 6.0).abs() <= 0.12,
            "n = {n}: {}",
            w.radius_mm
        );
        assert!(c.min_floor.is_none());
    }
}

/// Inner surface of a hemisphere of radius `r` (normals toward the centre), `nu` × `nv` steps.
fn bowl(r: f64, nu: usize, nv: usize) -> Mesh {
    // Inner surface of the lower hemisphere centred at origin, normals toward the centre.
    let p = |i: usize, j: usize| {
        let phi = std::f64::consts::FRAC_PI_2 * i as f64 / nu as f64; // 0 at the bottom pole
        let th = std::f64::consts::TAU * j as f64 / nv as f64;
        DVec3::new(
            r * phi.sin() * th.cos(),
            r * phi.sin() * th.sin(),
            -r * phi.cos(),
        )
    };
    let mut t = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            for tri in [Triangle::new(a, b, c), Triangle::new(a, c, d)] {
                if tri.is_degenerate() {
                    continue;
                }
                let cen = (tri.v[0] + tri.v[1] + tri.v[2]) / 3.0;
                let tri = if tri.cross().dot(-cen) < 0.0 {
                    Triangle::new(tri.v[0], tri.v[2], tri.v[1])
                } else {
                    tri
                };
                t.push(tri);
            }
        }
    }
    Mesh::from_triangles(t, "<bowl>").unwrap()
}

#[test]
fn spherical_bowl_radius_ten() {
    // A doubly curved concave dish (UV tessellation, triangle fans at the pole) reads its
    // radius within 2 % in both edge classes.
    for (nu, nv) in [(8, 32), (12, 24), (16, 64), (32, 128)] {
        let c = concave_curvature(&bowl(10.0, nu, nv), &CurvatureConfig::default());
        for m in [c.min, c.min_wall, c.min_floor] {
            let r = m.expect("concave edges").radius_mm;
            assert!((r - 10.0).abs() <= 0.2, "{nu}x{nv}: {r}");
        }
        assert!(c.sharp_edges.is_empty());
    }
}

#[test]
fn dent_in_a_convex_sphere_is_not_a_concave_radius() {
    // Outer surface of a radius-10 dome (normals outward) with one vertex pushed 0.05 mm
    // inward: its edges turn concave (small radius read alone) but the surface is convex on
    // balance around them.
    let inner = bowl(10.0, 16, 64);
    let dent = DVec3::new(
        10.0 * (std::f64::consts::FRAC_PI_2 * 8.0 / 16.0).sin(),
        0.0,
        -10.0 * (std::f64::consts::FRAC_PI_2 * 8.0 / 16.0).cos(),
    );
    let push = |p: DVec3| {
        if p.distance(dent) < 1e-9 {
            p * (1.0 - 0.05 / 10.0)
        } else {
            p
        }
    };
    let tris = inner
        .triangles()
        .iter()
        .map(|t| Triangle::new(push(t.v[0]), push(t.v[2]), push(t.v[1]))) // flip: outward
        .collect();
    let dome = Mesh::from_triangles(tris, "<dome>").unwrap();
    let c = concave_curvature(&dome, &CurvatureConfig::default());
    assert!(c.min.is_none(), "{:?}", c.min);
    assert!(c.dents_ignored > 0);
    // Without the neighbourhood test (radius 0: only the edge itself) the dent reads as a
    // small concave radius.
    let raw = concave_curvature(
        &dome,
        &CurvatureConfig {
            neighbourhood_widths: 0.0,
            ..Default::default()
        },
    );
    let r = raw.min.expect("dent edges").radius_mm;
    assert!(r < 10.0, "{r}");
}
