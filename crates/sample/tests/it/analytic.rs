//! Analytic truths: tilted planes, walls, holes, spheres.

use cam_core::assert_near;
use cam_sample::{RasterFrame, Sectioner, resample_u};

use crate::util::{Rng, box_tris, check_profile, compare, grid_mesh, mesh, sphere_mesh};

/// The top profile of a plane tilted by θ is a line of slope tan θ, and constant-arc-length
/// resampling spaces it by step·cos θ.
#[test]
fn tilted_plane_slope_and_spacing() {
    for theta_deg in [0.0f64, 10.0, 30.0, 45.0, 60.0, 80.0] {
        let tan = theta_deg.to_radians().tan();
        let cos = theta_deg.to_radians().cos();
        let m = grid_mesh((0.0, 0.0), (10, 5), 2.0, |x, _| x * tan, |_, _| true);
        let s = Sectioner::new(&m, RasterFrame::new(0.0));
        for v in [0.0, 3.3, 4.0, 10.0] {
            let ps = s.top_profile(v);
            assert_eq!(ps.len(), 1, "θ = {theta_deg}, v = {v}");
            let p = &ps[0];
            check_profile(p);
            assert_eq!(p.u_range(), Some((0.0, 20.0)));
            for &(u, z) in &p.points {
                assert_near!(
                    z,
                    u * tan,
                    1e-12 * (1.0 + u * tan),
                    "θ = {theta_deg}, v = {v}"
                );
            }
            for step in [0.7, 1.0, 3.0] {
                let us = resample_u(p, step);
                assert_eq!(us[0], 0.0);
                assert_eq!(*us.last().unwrap(), 20.0);
                let n_inner = us.len() - 2;
                for (k, w) in us.windows(2).enumerate() {
                    if k < n_inner {
                        assert_near!(
                            w[1] - w[0],
                            step * cos,
                            1e-12,
                            "θ = {theta_deg} step {step}"
                        );
                    } else {
                        assert!(w[1] - w[0] <= step * cos + 1e-12 && w[1] > w[0]);
                    }
                }
                // Count: one sample per step of arc, plus the end.
                let arc = 20.0 / cos;
                assert_eq!(
                    us.len(),
                    (arc / step - 1e-9).ceil() as usize + 1,
                    "θ = {theta_deg} step {step}"
                );
            }
        }
    }
}

/// The same tilted plane seen in rotated raster frames: along `u` the slope is
/// tan θ·cos α, so the spacing is step / sqrt(1 + (tan θ cos α)²).
#[test]
fn tilted_plane_in_rotated_frames() {
    let theta: f64 = 35f64.to_radians();
    let m = grid_mesh(
        (-10.0, -10.0),
        (20, 20),
        1.0,
        |x, _| x * theta.tan(),
        |_, _| true,
    );
    for alpha_deg in [0.0f64, 30.0, 90.0, 135.0, 210.0] {
        let frame = RasterFrame::new(alpha_deg);
        let s = Sectioner::new(&m, frame);
        let slope = theta.tan() * alpha_deg.to_radians().cos();
        let spacing = 0.5 / (1.0 + slope * slope).sqrt();
        let ps = s.top_profile(0.5);
        assert_eq!(ps.len(), 1, "α = {alpha_deg}");
        let p = &ps[0];
        check_profile(p);
        for &(u, z) in &p.points {
            let (x, _) = frame.to_xy(u, 0.5);
            assert_near!(z, x * theta.tan(), 1e-12, "α = {alpha_deg}");
        }
        let us = resample_u(p, 0.5);
        let n = us.len();
        for w in &us.windows(2).collect::<Vec<_>>()[..n - 2] {
            assert_near!(w[1] - w[0], spacing, 1e-12, "α = {alpha_deg}");
        }
    }
}

/// Two stacked closed boxes: a wall at x = 5 is a vertical jump; also when the plane lies in
/// the boxes' side faces (coplanar triangles) and in a frame turned 90°.
#[test]
fn box_with_vertical_wall() {
    let mut t = box_tris([0.0, 0.0, 0.0], [10.0, 4.0, 1.0]);
    t.extend(box_tris([5.0, 0.0, 0.0], [10.0, 4.0, 3.0]));
    let m = mesh(&t);
    let s = Sectioner::new(&m, RasterFrame::new(0.0));
    for v in [0.0, 1.0, 2.5, 4.0] {
        let ps = s.top_profile(v);
        assert_eq!(ps.len(), 1, "v = {v}");
        assert_eq!(
            ps[0].points,
            vec![(0.0, 1.0), (5.0, 1.0), (5.0, 3.0), (10.0, 3.0)],
            "v = {v}"
        );
        // Arc step 0.75: 0, .75, …, 4.5 on the floor; the wall (arc 5..7) all at u = 5;
        // then arc 7.5 → u = 5.5, …
        let us = resample_u(&ps[0], 0.75);
        let expect: Vec<f64> = [
            0.0, 0.75, 1.5, 2.25, 3.0, 3.75, 4.5, 5.0, 5.5, 6.25, 7.0, 7.75, 8.5, 9.25, 10.0,
        ]
        .to_vec();
        assert_eq!(us.len(), expect.len(), "{us:?}");
        for (a, b) in us.iter().zip(&expect) {
            assert_near!(*a, *b, 1e-12);
        }
    }
    // Outside the part: nothing.
    assert!(s.top_profile(4.000001).is_empty());
    assert!(s.top_profile(-1e-12).is_empty());
    assert!(s.top_profile(f64::NAN).is_empty());
    // Passes along +Y (v = -x): the plane x = 7 sees the high box only, x = 5 the wall top.
    let s90 = Sectioner::new(&m, RasterFrame::new(90.0));
    assert_eq!(
        s90.top_profile(-7.0)[0].points,
        vec![(0.0, 3.0), (4.0, 3.0)]
    );
    assert_eq!(
        s90.top_profile(-5.0)[0].points,
        vec![(0.0, 3.0), (4.0, 3.0)]
    );
    assert_eq!(
        s90.top_profile(-2.0)[0].points,
        vec![(0.0, 1.0), (4.0, 1.0)]
    );
}

/// Open top surface with a wall made of vertical triangles: jump inside one profile.
#[test]
fn open_step_surface_wall() {
    let m = mesh(&[
        [[0.0, 0.0, 0.0], [5.0, 0.0, 0.0], [5.0, 4.0, 0.0]],
        [[0.0, 0.0, 0.0], [5.0, 4.0, 0.0], [0.0, 4.0, 0.0]],
        [[5.0, 0.0, 0.0], [5.0, 4.0, 0.0], [5.0, 4.0, 3.0]],
        [[5.0, 0.0, 0.0], [5.0, 4.0, 3.0], [5.0, 0.0, 3.0]],
        [[5.0, 0.0, 3.0], [10.0, 0.0, 3.0], [10.0, 4.0, 3.0]],
        [[5.0, 0.0, 3.0], [10.0, 4.0, 3.0], [5.0, 4.0, 3.0]],
    ]);
    let s = Sectioner::new(&m, RasterFrame::new(0.0));
    for v in [0.0, 0.3, 2.0, 4.0] {
        let ps = s.top_profile(v);
        assert_eq!(ps.len(), 1);
        assert_eq!(
            ps[0].points,
            vec![(0.0, 0.0), (5.0, 0.0), (5.0, 3.0), (10.0, 3.0)],
            "v = {v}"
        );
    }
    // A wall going down: flipped in a 180° frame (u = -x).
    let s = Sectioner::new(&m, RasterFrame::new(180.0));
    assert_eq!(
        s.top_profile(-2.0)[0].points,
        vec![(-10.0, 3.0), (-5.0, 3.0), (-5.0, 0.0), (0.0, 0.0)]
    );
}

/// A square annulus (closed, as four overlapping boxes, and open, as a grid with the middle
/// cell removed) gives two segments in the middle section.
#[test]
fn square_annulus_two_segments() {
    let mut t = box_tris([0.0, 0.0, 0.0], [30.0, 10.0, 5.0]);
    t.extend(box_tris([0.0, 20.0, 0.0], [30.0, 30.0, 5.0]));
    t.extend(box_tris([0.0, 0.0, 0.0], [10.0, 30.0, 5.0]));
    t.extend(box_tris([20.0, 0.0, 0.0], [30.0, 30.0, 5.0]));
    let closed = mesh(&t);
    let open = grid_mesh(
        (0.0, 0.0),
        (3, 3),
        10.0,
        |_, _| 5.0,
        |i, j| !(i == 1 && j == 1),
    );
    for (name, m) in [("closed", &closed), ("open", &open)] {
        let s = Sectioner::new(m, RasterFrame::new(0.0));
        for v in [10.5, 15.0, 19.999] {
            let ps = s.top_profile(v);
            assert_eq!(ps.len(), 2, "{name} v = {v}");
            assert_eq!(ps[0].points, vec![(0.0, 5.0), (10.0, 5.0)], "{name}");
            assert_eq!(ps[1].points, vec![(20.0, 5.0), (30.0, 5.0)], "{name}");
        }
        // On the hole's edges the closed cells are still there: one segment.
        for v in [10.0, 20.0, 5.0] {
            let ps = s.top_profile(v);
            assert_eq!(ps.len(), 1, "{name} v = {v}");
            assert_eq!(ps[0].u_range(), Some((0.0, 30.0)));
            assert!(ps[0].points.iter().all(|p| p.1 == 5.0));
        }
        // Turned 90°: the same by symmetry.
        let s = Sectioner::new(m, RasterFrame::new(90.0));
        assert_eq!(s.top_profile(-15.0).len(), 2, "{name}");
    }
}

/// A sphere mesh's top profile lies within the tessellation error of the sphere, covers the
/// section circle's chord and agrees with the brute force.
#[test]
fn sphere_within_tessellation_error() {
    let (c, r) = ([1.0, -2.0, 3.0], 10.0);
    let m = sphere_mesh(c, r, 32, 64);
    // Tessellation error: the sphere centre's distance to each triangle's plane is the
    // nearest any point of that triangle can be.
    let centre = cam_core::DVec3::from(c);
    let e = m
        .triangles()
        .iter()
        .map(|t| r - t.normal().unwrap().dot(t.v[0] - centre).abs())
        .fold(0.0, f64::max);
    assert!(e > 0.0 && e < 0.05, "e = {e}");
    let s = Sectioner::new(&m, RasterFrame::new(0.0));
    let mut max_dev: f64 = 0.0;
    for k in 0..=38 {
        let v = -2.0 - 9.5 + k as f64 * 0.5;
        let ps = s.top_profile(v);
        let dy = v - c[1];
        assert_eq!(ps.len(), 1, "v = {v}");
        let p = &ps[0];
        check_profile(p);
        // The mesh lies between the balls of radii r - e and r, so its section's extent lies
        // between those circles' chords.
        let rc = (r * r - dy * dy).sqrt();
        let rc_in = ((r - e) * (r - e) - dy * dy).max(0.0).sqrt();
        let (u0, u1) = p.u_range().unwrap();
        assert!(
            u0 >= c[0] - rc - 1e-12 && u0 <= c[0] - rc_in + 1e-12,
            "v = {v}: u0 = {u0}"
        );
        assert!(
            u1 <= c[0] + rc + 1e-12 && u1 >= c[0] + rc_in - 1e-12,
            "v = {v}: u1 = {u1}"
        );
        // Points and midpoints of the profile are on the mesh: within [r - e, r] of the centre,
        // and on the upper half.
        let mut check = |u: f64, z: f64| {
            let d = ((u - c[0]).powi(2) + dy * dy + (z - c[2]).powi(2)).sqrt();
            assert!(
                d <= r + 1e-12 && d >= r - e - 1e-12,
                "v = {v}: |p - c| = {d}"
            );
            assert!(z >= c[2] - e, "v = {v}: z = {z} below the equator");
            max_dev = max_dev.max(r - d);
        };
        for w in p.points.windows(2) {
            check(w[0].0, w[0].1);
            check(0.5 * (w[0].0 + w[1].0), 0.5 * (w[0].1 + w[1].1));
        }
        let us: Vec<f64> = (0..200)
            .map(|i| u0 + (u1 - u0) * (i as f64 + 0.5) / 200.0)
            .collect();
        let a = compare(&s, v, &us);
        assert_eq!(a.coverage_mismatch, 0);
        assert!(a.max_dz <= 1e-12, "v = {v}: {a:?}");
    }
    eprintln!(
        "sphere r = {r}: tessellation error {e:.6} mm, max profile deviation {max_dev:.6} mm"
    );
    // Random planes at random frames, against the brute force.
    let mut rng = Rng(7);
    for _ in 0..20 {
        let frame = RasterFrame::new(rng.range(0.0, 360.0));
        let s = Sectioner::new(&m, frame);
        let (v0, v1) = s.v_range();
        let v = rng.range(v0, v1);
        let (a0, a1) = s.u_range();
        let us: Vec<f64> = (0..300).map(|_| rng.range(a0, a1)).collect();
        let a = compare(&s, v, &us);
        assert_eq!(a.coverage_mismatch, 0);
        assert!(a.max_dz <= 1e-11, "{a:?}");
    }
}

/// A wall that is vertical in the world but not aligned with the frame: the plane–edge
/// crossings of its triangles may differ by a few ulp in `u`, so the wall can come out a
/// hair off vertical; resampling must still give one `u` there, not a cluster.
#[test]
fn skew_wall_gives_one_sample() {
    let rot = |p: [f64; 3]| {
        let (s, c) = 37f64.to_radians().sin_cos();
        [p[0] * c - p[1] * s, p[0] * s + p[1] * c, p[2]]
    };
    let mut tris = Vec::new();
    // Floor z = 0 on x in [0, 5], wall x = 5 up to 3, top z = 3 on x in [5, 10]; y in [0, 4],
    // split into many strips so the planes cut many wall triangles.
    for j in 0..8 {
        let (y0, y1) = (j as f64 * 0.5, (j + 1) as f64 * 0.5);
        for (xa, xb, za, zb) in [(0.0, 5.0, 0.0, 0.0), (5.0, 10.0, 3.0, 3.0)] {
            tris.push([rot([xa, y0, za]), rot([xb, y0, zb]), rot([xb, y1, zb])]);
            tris.push([rot([xa, y0, za]), rot([xb, y1, zb]), rot([xa, y1, za])]);
        }
        tris.push([
            rot([5.0, y0, 0.0]),
            rot([5.0, y1, 0.0]),
            rot([5.0, y1, 3.0]),
        ]);
        tris.push([
            rot([5.0, y0, 0.0]),
            rot([5.0, y1, 3.0]),
            rot([5.0, y0, 3.0]),
        ]);
    }
    let m = mesh(&tris);
    let frame = RasterFrame::new(37.0);
    let s = Sectioner::new(&m, frame);
    let mut planes = 0;
    for k in 1..40 {
        let v = k as f64 * 0.1 + 1e-3;
        let ps = s.top_profile(v);
        assert_eq!(ps.len(), 1, "v = {v}");
        let p = &ps[0];
        check_profile(p);
        // The wall: consecutive points at (nearly) u = 5, from z 0 to z 3.
        let w = p
            .points
            .windows(2)
            .find(|w| w[0].1 == 0.0 && (w[1].1 - 3.0).abs() < 1e-12)
            .expect("wall");
        assert!(
            (w[0].0 - 5.0).abs() < 1e-12 && (w[1].0 - w[0].0).abs() < 1e-12,
            "{w:?}"
        );
        let us = resample_u(p, 0.25);
        let near: Vec<f64> = us
            .iter()
            .copied()
            .filter(|u| (u - 5.0).abs() < 1e-9)
            .collect();
        assert_eq!(near.len(), 1, "v = {v}: {near:?}");
        for w in us.windows(2) {
            assert!(w[1] - w[0] > cam_sample::MERGE_U_MM);
        }
        planes += 1;
    }
    assert_eq!(planes, 39);
}

/// `sample_part` on the stacked boxes: the sample on the wall is the wall's top, the samples
/// are those of `resample_u`, and planes are v_min + i·spacing.
#[test]
fn sample_part_on_stacked_boxes() {
    let mut t = box_tris([0.0, 0.0, 0.0], [10.0, 4.0, 1.0]);
    t.extend(box_tris([5.0, 0.0, 0.0], [10.0, 4.0, 3.0]));
    let m = mesh(&t);
    let cfg = cam_sample::SampleConfig {
        angle_deg: 0.0,
        plane_spacing_mm: 1.5,
        arc_step_mm: 0.75,
    };
    let secs = cam_sample::sample_part(&m, &cfg).expect("samples");
    assert_eq!(
        secs.iter().map(|s| s.v).collect::<Vec<_>>(),
        vec![0.0, 1.5, 3.0]
    );
    for s in &secs {
        assert_eq!(s.segments.len(), 1);
        let pts = &s.segments[0];
        assert_eq!(pts.len(), 15);
        for p in pts {
            assert_eq!(p.y, s.v);
            let expect_z = if p.x < 5.0 { 1.0 } else { 3.0 };
            assert_eq!(p.z, expect_z, "{p}");
        }
        assert_eq!(pts[7].x, 5.0);
    }
}

/// A plane that only touches the part (a sphere's first plane at v_min) gives a section with
/// no segments; the section is still reported.
#[test]
fn touching_plane_gives_empty_section() {
    let m = sphere_mesh([0.0, 0.0, 0.0], 5.0, 8, 4);
    // With 4 meridians the sphere's extremes in y are single equator vertices (0, ±5, 0).
    let secs = cam_sample::sample_part(
        &m,
        &cam_sample::SampleConfig {
            angle_deg: 0.0,
            plane_spacing_mm: 1.0,
            arc_step_mm: 0.5,
        },
    )
    .expect("samples");
    let s = Sectioner::new(&m, RasterFrame::new(0.0));
    assert_eq!(secs[0].v, s.v_range().0);
    assert!(secs[0].segments.is_empty(), "{:?}", secs[0].segments);
    // Extent ±5 exactly: 11 planes, the last one touching the opposite vertex.
    assert_eq!(secs.len(), 11);
    assert!(secs[10].segments.is_empty());
    assert!(secs[1..10].iter().all(|s| s.segments.len() == 1));
}
