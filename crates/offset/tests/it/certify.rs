//! The certificates a planner uses between samples, against dense exact drops.

use std::path::PathBuf;

use cam_core::{Cutter, DVec3, Mesh, Units};
use cam_offset::DropCutter;

use crate::support::{Rng, cutters, mesh, square, uv_sphere};

fn dome() -> Mesh {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/parts/dome.obj");
    Mesh::load(p, Units::Mm).expect("dome fixture")
}

/// A single triangle's drop is a lower bound of the drop everywhere, equal to it where that
/// triangle carries the contact, and concave along straight lines (the property the excess
/// certificate rests on): checked at random points and chords of the UV sphere and the dome.
#[test]
fn triangle_drop_is_a_concave_lower_bound() {
    let meshes = [mesh(uv_sphere(20.0, 24, 48)), dome()];
    let mut rng = Rng(7);
    for m in &meshes {
        let b = m.bounds();
        for c in cutters() {
            let dc = DropCutter::new(m, c);
            let mut checked = 0;
            for _ in 0..300 {
                let (x, y) = (rng.range(b.min.x, b.max.x), rng.range(b.min.y, b.max.y));
                let Some(ct) = dc.contact(x, y) else { continue };
                let here = dc
                    .triangle_drop(ct.triangle, x, y)
                    .expect("contact triangle");
                assert!(
                    (here - ct.z_tip).abs() <= 1e-12,
                    "{c}: {here} vs {}",
                    ct.z_tip
                );
                // Along a random chord through (x, y): lower bound and concavity.
                let ang = rng.range(0.0, std::f64::consts::TAU);
                let len = rng.range(0.1, 2.0 * c.radius());
                let (dx, dy) = (len * ang.cos(), len * ang.sin());
                let f = |t: f64| dc.triangle_drop(ct.triangle, x + t * dx, y + t * dy);
                let g = |t: f64| dc.drop(x + t * dx, y + t * dy);
                for k in 0..=20 {
                    let t = k as f64 / 20.0;
                    if let (Some(fv), Some(gv)) = (f(t), g(t)) {
                        assert!(fv <= gv + 1e-12, "{c}: piece {fv} above drop {gv}");
                    }
                }
                if let (Some(f0), Some(f1), Some(fm)) = (f(0.0), f(1.0), f(0.5)) {
                    assert!(
                        fm >= 0.5 * (f0 + f1) - 1e-11,
                        "{c}: not concave: {f0} {fm} {f1}"
                    );
                }
                checked += 1;
            }
            assert!(checked > 100, "{c}: only {checked} points touched the part");
        }
    }
}

/// On the dome's plate the plane certificate holds with no rise and full coverage away from
/// the hemisphere, and fails (or reports the rise) near it; wherever it holds, dense drops
/// along the segment lie within its bounds.
#[test]
fn plane_certificate_bounds_the_drop() {
    let m = dome();
    let n = DVec3::Z;
    for c in cutters() {
        let dc = DropCutter::new(&m, c);
        // Far from the hemisphere (radius 20 at the origin): clean.
        let cert = dc
            .plane_certificate((-29.0, -28.0), (29.0, -28.0), n, 0.0, 0.01)
            .expect("plate rows clear the hemisphere");
        assert_eq!(cert.rise_mm, 0.0, "{c}");
        assert!(cert.covered, "{c}");
        // A row across the hemisphere: refused.
        assert!(
            dc.plane_certificate((-29.0, 0.0), (29.0, 0.0), n, 0.0, 0.01)
                .is_none()
        );
        // Rows passing close to it: wherever accepted (with a generous rise), the drops obey.
        for y in [20.5, 21.0, 22.0, 23.0, 24.0] {
            let Some(cert) = dc.plane_certificate((-20.0, y), (20.0, y), n, 0.0, 30.0) else {
                continue;
            };
            assert!(cert.covered);
            for k in 0..=4000 {
                let x = -20.0 + 40.0 * k as f64 / 4000.0;
                let z = dc.drop(x, y).expect("on the plate");
                assert!(z >= -1e-9, "{c} y {y}: below the plate {z}");
                assert!(
                    z <= cert.rise_mm + 1e-9,
                    "{c} y {y}: {z} > {}",
                    cert.rise_mm
                );
            }
        }
    }
}

/// A tilted plane tessellated as two triangles: the certificate covers the diagonal and a
/// bump within reach is seen with its exact height above the plane.
#[test]
fn plane_certificate_on_a_tilted_plane_with_a_bump() {
    let slope = 20f64.to_radians().tan();
    let f = |x: f64, _y: f64| x * slope;
    let mut tris = square(20.0, f);
    // A small tetrahedral bump standing 0.05 mm (along the normal) above the plane near
    // (5, 6).
    let nrm = DVec3::new(-slope, 0.0, 1.0).normalize();
    let base = |x: f64, y: f64| DVec3::new(x, y, f(x, y));
    let apex = base(5.0, 6.0) + nrm * 0.05;
    let (p, q, r) = (base(4.5, 5.5), base(5.5, 5.5), base(5.0, 6.5));
    tris.push(cam_core::Triangle::new(p, q, apex));
    tris.push(cam_core::Triangle::new(q, r, apex));
    tris.push(cam_core::Triangle::new(r, p, apex));
    let m = mesh(tris);
    let d = 0.0; // the plane passes through the origin
    for c in cutters() {
        let dc = DropCutter::new(&m, c);
        let rr = c.radius();
        // Far from the bump (more than R + 1 mm away in y): rise 0.
        let cert = dc
            .plane_certificate((-10.0, -10.0), (10.0, 10.0 - 7.0 - rr), nrm, d, 1.0)
            .unwrap();
        assert_eq!(cert.rise_mm, 0.0, "{c}");
        assert!(cert.covered, "{c}");
        // Over the bump: the rise is the apex's height, 0.05, and a smaller cap refuses.
        let cert = dc
            .plane_certificate((-10.0, 6.0), (10.0, 6.0), nrm, d, 1.0)
            .unwrap();
        assert!((cert.rise_mm - 0.05).abs() < 1e-12, "{c}: {}", cert.rise_mm);
        assert!(
            dc.plane_certificate((-10.0, 6.0), (10.0, 6.0), nrm, d, 0.04)
                .is_none()
        );
        // Dense drops respect the bounds: plane CL ≤ z ≤ plane CL + rise / n.z.
        let flat = Mesh::from_triangles(square(40.0, f), "<plane>").unwrap();
        let fdc = DropCutter::new(&flat, c);
        for k in 0..=2000 {
            let x = -10.0 + 20.0 * k as f64 / 2000.0;
            let z = dc.drop(x, 6.0).unwrap();
            let z0 = fdc.drop(x, 6.0).unwrap();
            assert!(z >= z0 - 1e-9, "{c}: {z} < {z0}");
            assert!(z <= z0 + cert.rise_mm / nrm.z + 1e-9, "{c}: {z} vs {z0}");
        }
    }
}

/// Contacts in a batch equal single contacts, and hints never change an answer.
#[test]
fn batches_and_hints_are_exact() {
    let m = dome();
    let c = Cutter::bull(6.0, 1.5).unwrap();
    let dc = DropCutter::new(&m, c);
    let xy: Vec<(f64, f64)> = (0..500)
        .map(|k| (-30.0 + 0.12 * k as f64, 3.0 + 0.01 * k as f64))
        .collect();
    let batch = dc.contact_points(&xy);
    let mut rng = Rng(3);
    for (k, &(x, y)) in xy.iter().enumerate() {
        let one = dc.contact(x, y);
        assert_eq!(batch[k], one);
        let hint = DVec3::new(rng.range(-30.0, 30.0), rng.range(-30.0, 30.0), 0.0);
        // A point of the part as hint: the plate's top.
        let hinted = dc.contact_hinted(x, y, &[hint]);
        assert_eq!(hinted.map(|h| h.z_tip), one.map(|o| o.z_tip));
    }
}

/// The CL surface's height above a move's chord, against dense exact drops along the move:
/// never below any dense sample, and reached at the point it names. On the dome and on
/// mount_rush (a scanned mesh with narrow features that a flat end mill's rim clips).
#[test]
fn chord_rise_is_the_maximum_of_dense_drops() {
    let rush = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/fixtures/ocl_mount_rush.stl");
    let meshes = [
        dome(),
        Mesh::load(rush, Units::Mm).expect("mount_rush fixture"),
    ];
    let mut rng = Rng(11);
    for m in &meshes {
        let b = m.bounds();
        for c in cutters() {
            let dc = DropCutter::new(m, c);
            let mut checked = 0;
            let mut positive = 0;
            for _ in 0..60 {
                let a = (rng.range(b.min.x, b.max.x), rng.range(b.min.y, b.max.y));
                let ang = rng.range(0.0, std::f64::consts::TAU);
                let len = rng.range(0.05, 3.0);
                let e = (a.0 + len * ang.cos(), a.1 + len * ang.sin());
                let (Some(za), Some(zb)) = (dc.drop(a.0, a.1), dc.drop(e.0, e.1)) else {
                    continue;
                };
                // Sometimes below the surface at the ends too (a move that gouges there).
                let (za, zb) = if checked % 3 == 2 {
                    (za - 0.05, zb - 0.02)
                } else {
                    (za, zb)
                };
                let r = dc.chord_rise(a, e, za, zb, f64::NEG_INFINITY, f64::INFINITY);
                let n = 4000;
                let mut dense = f64::NEG_INFINITY;
                for k in 0..=n {
                    let t = k as f64 / n as f64;
                    let (x, y) = (a.0 + t * (e.0 - a.0), a.1 + t * (e.1 - a.1));
                    if let Some(z) = dc.drop(x, y) {
                        dense = dense.max(z - (za + t * (zb - za)));
                    }
                }
                assert!(
                    r.rise_mm >= dense - 1e-9,
                    "{c}: rise {} below dense {dense} on {a:?} -> {e:?}",
                    r.rise_mm
                );
                let (x, y) = (a.0 + r.at * (e.0 - a.0), a.1 + r.at * (e.1 - a.1));
                let there =
                    dc.drop(x, y).expect("the rise is on the surface") - (za + r.at * (zb - za));
                assert!(
                    (there - r.rise_mm).abs() <= 1e-9,
                    "{c}: rise {} but {there} at t = {}",
                    r.rise_mm,
                    r.at
                );
                if r.rise_mm > 1e-6 {
                    positive += 1;
                    let early = dc.chord_rise(a, e, za, zb, f64::NEG_INFINITY, 0.5 * r.rise_mm);
                    assert!(early.rise_mm > 0.5 * r.rise_mm && early.rise_mm <= r.rise_mm + 1e-12);
                }
                // With a floor: the same height if it is above the floor, else the floor.
                let fl = dc.chord_rise(a, e, za, zb, 0.0, f64::INFINITY);
                assert!(
                    (fl.rise_mm - r.rise_mm.max(0.0)).abs() <= 1e-9,
                    "{c}: floored {} vs {}",
                    fl.rise_mm,
                    r.rise_mm
                );
                checked += 1;
            }
            assert!(
                checked >= 20 && positive >= 5,
                "{c}: {checked} moves, {positive} rising"
            );
        }
    }
}
