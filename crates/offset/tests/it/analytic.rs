//! Drop-cutter against closed-form answers.

use cam_core::{Cutter, DVec3, Triangle, assert_near};
use cam_offset::{ContactKind, DropCutter};

use crate::support::{Rng, cutters, mesh, square, uv_sphere};

/// Tip height of a cutter resting on the plane z = tanθ·(x cosψ + y sinψ): from the support
/// function of the cutter (disk of radius a ⊕ ball of radius r).
fn plane_tip(c: &Cutter, th: f64, ps: f64, x: f64, y: f64) -> f64 {
    let (a, r) = (c.major_radius(), c.corner_radius());
    th.tan() * (x * ps.cos() + y * ps.sin()) + a * th.tan() + r / th.cos() - r
}

#[test]
fn horizontal_plane_all_cutters() {
    let m = mesh(square(50.0, |_, _| 2.5));
    for c in cutters() {
        let dc = DropCutter::new(&m, c);
        for &(x, y) in &[(0.0, 0.0), (12.3, -7.7), (49.0, 49.0), (-50.0, 0.0)] {
            assert_near!(dc.drop(x, y).unwrap(), 2.5, 1e-12, "{c} at {x},{y}");
        }
        // Overhanging the square's edge by d: the cutter rests on the edge, z = 2.5 - h(d).
        for f in [0.1, 0.5, 0.9, 0.999] {
            let d = f * c.radius();
            let want = 2.5 - c.height_at(d).unwrap();
            assert_near!(
                dc.drop(50.0 + d, 3.0).unwrap(),
                want,
                1e-12,
                "{c} overhang {d}"
            );
        }
        // Just out of reach: the cutter edge misses the square by 1 µm.
        assert_eq!(dc.drop(50.0 + c.radius() + 1e-3, 0.0), None, "{c}");
    }
}

#[test]
fn tilted_planes_all_cutters() {
    let mut rng = Rng(7);
    for &deg in &[5.0f64, 20.0, 45.0, 70.0] {
        for &ps in &[0.0f64, 0.7, 2.9, 4.4] {
            let th = deg.to_radians();
            let f = |x: f64, y: f64| th.tan() * (x * ps.cos() + y * ps.sin());
            let m = mesh(square(40.0, f));
            for c in cutters() {
                let dc = DropCutter::new(&m, c);
                for _ in 0..20 {
                    let (x, y) = (rng.range(-25.0, 25.0), rng.range(-25.0, 25.0));
                    let want = plane_tip(&c, th, ps, x, y);
                    let got = dc.contact(x, y).unwrap();
                    assert_near!(got.z_tip, want, 1e-9, "{c} θ={deg} ψ={ps} at {x},{y}");
                    // The CC point lies on the plane.
                    assert_near!(got.cc.z, f(got.cc.x, got.cc.y), 1e-9);
                }
            }
        }
    }
}

#[test]
fn vertex_contact() {
    // Apex at (0,0,5); the triangle falls away towards -x, so for a cutter at x > 0 the
    // apex is the only contact and z = 5 - h(x).
    let m = mesh(vec![Triangle::new(
        DVec3::new(0.0, 0.0, 5.0),
        DVec3::new(-10.0, -1.0, 0.0),
        DVec3::new(-10.0, 1.0, 0.0),
    )]);
    for c in cutters() {
        let dc = DropCutter::new(&m, c);
        for k in 1..=20 {
            let x = c.radius() * k as f64 / 20.0 - 1e-9;
            let got = dc.contact(x, 0.0).unwrap();
            assert_near!(got.z_tip, 5.0 - c.height_at(x).unwrap(), 1e-12, "{c} x={x}");
            assert_eq!(got.kind, ContactKind::Vertex);
        }
    }
}

#[test]
fn horizontal_ridge_edge_contact() {
    // A roof with its ridge along x at z = 5, facets falling at slope 0.5 to both sides.
    let p = DVec3::new;
    let m = mesh(vec![
        Triangle::new(p(-20.0, 0.0, 5.0), p(20.0, 0.0, 5.0), p(0.0, 10.0, 0.0)),
        Triangle::new(p(20.0, 0.0, 5.0), p(-20.0, 0.0, 5.0), p(0.0, -10.0, 0.0)),
    ]);
    for c in cutters() {
        let dc = DropCutter::new(&m, c);
        for k in 0..=20 {
            let y = c.radius() * k as f64 / 20.0 * 0.999;
            let got = dc.contact(1.0, y).unwrap();
            // Either the ridge or (for y near the cutter rim on a slope-0.5 facet) a facet:
            // the ridge gives 5 - h(y); a facet can only be higher if its tangency lies on it.
            let ridge = 5.0 - c.height_at(y).unwrap();
            assert!(
                got.z_tip >= ridge - 1e-12,
                "{c} y={y}: {} < ridge {ridge}",
                got.z_tip
            );
            if got.kind == ContactKind::Edge {
                assert_near!(got.z_tip, ridge, 1e-12, "{c} y={y}");
                assert_near!(got.cc.y, 0.0, 1e-12);
            }
        }
        // Straight above the ridge every cutter sits on it.
        assert_near!(dc.drop(3.0, 0.0).unwrap(), 5.0, 1e-12, "{c}");
    }
}

/// Ball centre height touching the infinite 3-D line through p1 with unit direction e, the
/// larger root of |(C - p1) × e|² = R² for C = (x, y, zc).
fn ball_line_centre(x: f64, y: f64, p1: DVec3, e: DVec3, big_r: f64) -> f64 {
    // (C - p1) = w + zc·ẑ with w = (x - p1.x, y - p1.y, -p1.z).
    // |v|² - (v·e)² = R², v = w + zc ẑ: quadratic A zc² + B zc + C0 = 0.
    let w = DVec3::new(x - p1.x, y - p1.y, -p1.z);
    let a = 1.0 - e.z * e.z;
    let b = 2.0 * (w.z - w.dot(e) * e.z);
    let c0 = w.length_squared() - w.dot(e).powi(2) - big_r * big_r;
    (-b + (b * b - 4.0 * a * c0).sqrt()) / (2.0 * a)
}

#[test]
fn sloped_edge_ball_matches_3d_line_distance() {
    // A vertical "knife" triangle: its top edge p1→p2 rises with slope 0.6; the rest of the
    // triangle lies below that edge in its vertical plane, so the top edge is the contact.
    let p1 = DVec3::new(-10.0, 0.0, 0.0);
    let p2 = DVec3::new(10.0, 3.0, 12.0);
    let foot = DVec3::new(0.0, 1.5, -30.0);
    let m = mesh(vec![Triangle::new(p1, p2, foot)]);
    let e = (p2 - p1).normalize();
    for d in [3.0, 6.0, 10.0] {
        let c = Cutter::ball(d).unwrap();
        let dc = DropCutter::new(&m, c);
        let mut rng = Rng(11);
        for _ in 0..50 {
            let s = rng.range(0.2, 0.8);
            let q = p1 + (p2 - p1) * s;
            let side = rng.range(-0.99, 0.99) * c.radius();
            let n = DVec3::new(-3.0, 20.0, 0.0).normalize();
            let (x, y) = (q.x + n.x * side, q.y + n.y * side);
            let got = dc.contact(x, y).unwrap();
            let want = ball_line_centre(x, y, p1, e, c.radius()) - c.radius();
            assert_near!(got.z_tip, want, 1e-9, "D={d} at {x},{y}");
            assert_eq!(got.kind, ContactKind::Edge);
        }
    }
}

/// Tip height of a cutter resting on a sphere of radius rho centred at the origin, axis at
/// horizontal distance q: the disk of radius a at the corner-centre height touches the
/// sphere grown by r.
fn sphere_tip(c: &Cutter, rho: f64, q: f64) -> Option<f64> {
    let (a, r) = (c.major_radius(), c.corner_radius());
    let dq = (q - a).max(0.0);
    let rr = rho + r;
    (dq < rr).then(|| (rr * rr - dq * dq).sqrt() - r)
}

#[test]
fn sphere_mesh_within_tessellation_error() {
    let rho = 20.0;
    let tris = uv_sphere(rho, 60, 120);
    // Inscribed polyhedron: it contains the ball of radius rho_in = min distance from the
    // centre to a face plane, and lies inside the ball of radius rho. Drop heights are
    // monotone in the sphere radius, so analytic(rho_in) <= mesh <= analytic(rho).
    let rho_in = tris
        .iter()
        .map(|t| t.normal().unwrap().dot(t.v[0]).abs())
        .fold(f64::INFINITY, f64::min);
    assert!(
        rho - rho_in < 0.03,
        "tessellation too coarse for a meaningful test"
    );
    let m = mesh(tris);
    let mut rng = Rng(3);
    for c in cutters() {
        let dc = DropCutter::new(&m, c);
        for _ in 0..300 {
            let (x, y) = (rng.range(-24.0, 24.0), rng.range(-24.0, 24.0));
            let q = (x * x + y * y).sqrt();
            let (Some(hi), Some(lo)) = (sphere_tip(&c, rho, q), sphere_tip(&c, rho_in, q)) else {
                continue;
            };
            let got = dc.drop(x, y).unwrap();
            assert!(
                got <= hi + 1e-9 && got >= lo - 1e-9,
                "{c} q={q}: {got} not in [{lo}, {hi}]"
            );
        }
    }
}
