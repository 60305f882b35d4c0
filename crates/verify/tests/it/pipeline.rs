//! The whole verification (`cam_verify::verify`) on cases with known answers.

use cam_core::{Cutter, DVec3, Mesh, Move, MoveKind, Pose, Toolpath, Triangle};
use cam_verify::{VerifyConfig, verify};

/// A block x ∈ [-20, 0], y ∈ [-10, 10], z ∈ [-10, 0] (closed, outward winding).
fn block() -> Mesh {
    let (x0, x1, y0, y1, z0, z1) = (-20.0, 0.0, -10.0, 10.0, -10.0, 0.0);
    let p = |x, y, z| DVec3::new(x, y, z);
    let quad =
        |a: DVec3, b: DVec3, c: DVec3, d: DVec3| [Triangle::new(a, b, c), Triangle::new(a, c, d)];
    let mut t = Vec::new();
    t.extend(quad(
        p(x0, y0, z1),
        p(x1, y0, z1),
        p(x1, y1, z1),
        p(x0, y1, z1),
    )); // top
    t.extend(quad(
        p(x0, y0, z0),
        p(x0, y1, z0),
        p(x1, y1, z0),
        p(x1, y0, z0),
    )); // bottom
    t.extend(quad(
        p(x1, y0, z0),
        p(x1, y1, z0),
        p(x1, y1, z1),
        p(x1, y0, z1),
    )); // +x side
    t.extend(quad(
        p(x0, y0, z0),
        p(x0, y0, z1),
        p(x0, y1, z1),
        p(x0, y1, z0),
    )); // -x side
    t.extend(quad(
        p(x0, y0, z0),
        p(x1, y0, z0),
        p(x1, y0, z1),
        p(x0, y0, z1),
    )); // -y side
    t.extend(quad(
        p(x0, y1, z0),
        p(x0, y1, z1),
        p(x1, y1, z1),
        p(x1, y1, z0),
    )); // +y side
    Mesh::from_triangles(t, "<block>").unwrap()
}

fn pass(x: f64, z: f64) -> Toolpath {
    let mv = |kind, y: f64, zz: f64| Move {
        kind,
        pose: Pose::vertical(DVec3::new(x, y, zz)),
        feed_mm_per_min: Some(500.0),
        line: None,
        pass: Some(0),
    };
    Toolpath {
        moves: vec![
            mv(MoveKind::Rapid, -12.0, 5.0),
            mv(MoveKind::Plunge, -12.0, z),
            mv(MoveKind::Cut, 12.0, z),
            mv(MoveKind::Retract, 12.0, 5.0),
        ],
    }
}

/// A ball 0.05 mm too low, its axis straight over the block's 90° top edge: the edge is cut
/// 0.05 mm deep (the ball centre is 2.95 from it). Along the edge's bisector the crossing is
/// 0.0700 mm in; the reported gouge must be the depth below the faces, 0.05, not 0.07.
/// Q = 160 keeps the imprint surface's chord sag, r·(1 − cos π/Q) = 0.58 µm, out of the way
/// (at Q = 40 it is 9.25 µm, which makes the sweep that much shallower).
#[test]
fn gouge_at_convex_edge_is_depth_not_bisector_distance() {
    let cutter = Cutter::ball(6.0).unwrap();
    let mut cfg = VerifyConfig::new(0.01);
    cfg.resolution_mm = 0.02;
    cfg.sweep.inserts = 160;
    let v = verify(&block(), &pass(0.0, -0.05), &cutter, &cfg).unwrap();
    let g = v.report.max_gouge_mm;
    assert!(
        (0.05 - 1e-3..=0.05 + 1e-9).contains(&g),
        "max gouge {g}, expected 0.05 (0.0700 along the bisector)"
    );
    // And a ball resting exactly on the edge gouges nothing.
    let v = verify(&block(), &pass(0.0, 0.0), &cutter, &cfg).unwrap();
    assert!(
        v.report.max_gouge_mm < 1e-6,
        "tangent pass: gouge {}",
        v.report.max_gouge_mm
    );
}

/// The top face 5 mm from the edge, cut 0.03 mm too deep, reads 0.03 (smooth vertices are
/// unaffected by the crease correction).
#[test]
fn gouge_on_a_face_reads_its_depth() {
    let cutter = Cutter::ball(6.0).unwrap();
    let mut cfg = VerifyConfig::new(0.01);
    cfg.resolution_mm = 0.02;
    cfg.sweep.inserts = 160;
    let v = verify(&block(), &pass(-5.0, -0.03), &cutter, &cfg).unwrap();
    let g = v.report.max_gouge_mm;
    assert!(
        (0.03 - 1e-3..=0.03 + 1e-9).contains(&g),
        "max gouge {g}, expected 0.03"
    );
}
