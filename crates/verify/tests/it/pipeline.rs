//! The whole verification (`cam_verify::verify`) on cases with known answers.

use cam_core::{Cutter, DVec3, Mesh, Move, MoveKind, Pose, Toolpath, Triangle};
use cam_verify::{VerifyConfig, verify};

/// A block x ∈ [-20, 0], y ∈ [-10, 10], z ∈ [-10, 0] (closed, outward winding).
fn block() -> Mesh {
    box_mesh(-20.0, 0.0)
}

/// A box x ∈ [x0, x1], y ∈ [-10, 10], z ∈ [-10, 0] (closed, outward winding).
pub(crate) fn box_mesh(x0: f64, x1: f64) -> Mesh {
    box_mesh_z(x0, x1, -10.0)
}

/// A box x ∈ [x0, x1], y ∈ [-10, 10], z ∈ [z0, 0] (closed, outward winding).
fn box_mesh_z(x0: f64, x1: f64, z0: f64) -> Mesh {
    let (y0, y1, z1) = (-10.0, 10.0, 0.0);
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

/// A fin 0.4 mm thick (x ∈ [-0.4, 0], top z = 0) and a flat end mill running along its +x
/// face, tangent to it, its bottom 0.5 mm below the top. Nothing is cut. Two false gouges
/// this guards against:
/// - the vectors at the fin's −x top edge run along the bisector, (0.71, 0, −0.71) inward:
///   through the fin (out of its +x face at 0.57 mm) and, before `L_in` = 1 mm, into the
///   mill's bottom, unless the vector is clipped to the material (half the fin along it);
/// - top-face vectors within a few µm of the +x edge pass just outside the mill's rim but
///   inside the swept triangles' margin: the exact test says no entry, and that answer
///   stands (the linear crossing is not kept in its place).
#[test]
fn a_thin_fin_is_not_gouged_through_from_the_far_side() {
    let cutter: Cutter = "flat:6".parse().unwrap();
    let fin = box_mesh(-0.4, 0.0);
    let mut cfg = VerifyConfig::new(0.01);
    cfg.resolution_mm = 0.02;
    let v = verify(&fin, &pass(3.0, -0.5), &cutter, &cfg).expect("verify");
    let far_edge: Vec<f64> = (0..v.refined.len())
        .filter(|&i| v.refined.normals[i].x < -0.5 && v.refined.normals[i].z > 0.5)
        .filter_map(|i| v.deviations[i].signed_mm)
        .collect();
    assert!(
        far_edge.iter().all(|&s| s >= -1e-9),
        "the −x top edge reads {far_edge:?}"
    );
    assert!(v.inner.thin > 0, "no vector clipped to the material");
    assert_eq!(v.inner.open_above, 0, "a closed fin has no open side");
    assert!(
        v.report.max_gouge_mm <= 1e-9,
        "max gouge {}, worst {:?}",
        v.report.max_gouge_mm,
        v.report.worst_gouges.first()
    );
}

/// The block with its top face flipped (normals into the material, misoriented edges at
/// its sides): along those vertices' normals the vectors start inside the ball and read
/// false gouges of up to `L_in`. Where orientation is unknown the reading is the vertex's
/// depth in the swept volume: none for a ball tangent to the top, and never more than the
/// true 0.05 mm for a ball 0.05 mm low (a vector facing the wrong way may also see nothing:
/// the limit `cam verify` warns about for such meshes).
#[test]
fn a_flipped_face_reads_depths_not_false_gouges() {
    let cutter = Cutter::ball(6.0).unwrap();
    let block = block();
    let flipped: Vec<Triangle> = block
        .triangles()
        .iter()
        .enumerate()
        .map(|(k, t)| {
            if k < 2 {
                Triangle::new(t.v[0], t.v[2], t.v[1])
            } else {
                *t
            }
        })
        .collect();
    let part = Mesh::from_triangles(flipped, "<flipped>").unwrap();
    for (z, most) in [(0.0, 0.0), (-0.05, 0.05)] {
        let mut cfg = VerifyConfig::new(0.01);
        cfg.resolution_mm = 0.02;
        cfg.sweep.inserts = 160;
        let v = verify(&part, &pass(-10.0, z), &cutter, &cfg).expect("verify");
        assert!(v.topology.misoriented_edges > 0);
        let g = v.report.max_gouge_mm;
        assert!(
            g <= most + 1e-6,
            "tip z {z}: max gouge {g}, at most {most}, worst {:?}",
            v.report.worst_gouges.first()
        );
    }
}

/// `verify_with_progress` reports every stage in order, ends the measurement at the number
/// of refined vertices, and gives the same report as `verify`.
#[test]
fn progress_reports_every_stage_and_changes_nothing() {
    use std::sync::Mutex;
    let cutter = Cutter::ball(6.0).unwrap();
    let mut cfg = VerifyConfig::new(0.01);
    cfg.resolution_mm = 0.02;
    let plain = verify(&block(), &pass(0.0, -0.05), &cutter, &cfg).unwrap();
    let seen: Mutex<Vec<(cam_verify::Stage, usize, usize)>> = Mutex::new(Vec::new());
    let report = |st, done, total| seen.lock().unwrap().push((st, done, total));
    let v =
        cam_verify::verify_with_progress(&block(), &pass(0.0, -0.05), &cutter, &cfg, Some(&report))
            .unwrap();
    assert_eq!(
        serde_json::to_string(&v.report).unwrap(),
        serde_json::to_string(&plain.report).unwrap()
    );
    let seen = seen.into_inner().unwrap();
    use cam_verify::Stage::{Measure, Refine, Sweep};
    assert_eq!(
        &seen[..4],
        &[(Sweep, 0, 1), (Sweep, 1, 1), (Refine, 0, 1), (Refine, 1, 1)]
    );
    let n = v.refined.positions.len();
    assert!(
        seen[4..]
            .iter()
            .all(|&(st, d, t)| st == Measure && d <= t && t == n)
    );
    assert_eq!(seen.last(), Some(&(Measure, n, n)));
}

/// Refining only where a vector can meet the swept volume changes no reading: a pass along
/// the edge of a 60 mm block, gouging 0.05 mm, reads the same with the whole block refined,
/// from far fewer vertices.
#[test]
fn refining_within_reach_changes_no_reading() {
    let cutter = Cutter::ball(6.0).unwrap();
    let mut cfg = VerifyConfig::new(0.01);
    cfg.resolution_mm = 0.02;
    let part = box_mesh(-60.0, 0.0);
    let path = pass(-5.0, -0.05);
    let near = verify(&part, &path, &cutter, &cfg).unwrap();
    cfg.refine_everywhere = true;
    let all = verify(&part, &path, &cutter, &cfg).unwrap();
    let (a, b) = (&near.report, &all.report);
    eprintln!(
        "within reach: {} vertices, {} measured, gouge {}; everywhere: {} vertices, {} measured, gouge {}",
        near.refined.positions.len(),
        a.measured,
        a.max_gouge_mm,
        all.refined.positions.len(),
        b.measured,
        b.max_gouge_mm
    );
    assert_eq!(a.measured, b.measured);
    assert_eq!(a.max_gouge_mm, b.max_gouge_mm);
    assert_eq!(a.max_excess_mm, b.max_excess_mm);
    assert_eq!(a.mean_mm, b.mean_mm);
    // The vertices sample the 0.05 mm gouge to within the resolution e (paper §3.4).
    assert!(
        a.max_gouge_mm <= 0.05 + 1e-9 && a.max_gouge_mm >= 0.05 - 0.02,
        "{}",
        a.max_gouge_mm
    );
    assert!(near.refined.positions.len() * 2 < all.refined.positions.len());
}

/// A plate 4 mm thick under a pass: its bottom lies within a vector's length (5 mm out) of
/// the swept volume, but its vectors point down, away from it, so it stays coarse (no
/// vertex inside it). Every reading of the whole plate refined is read at the same vertex
/// (position and normal) within reach; where the coarse part meets the fine one, the
/// bisection adds a few vertices of its own.
#[test]
fn a_bottom_facing_away_is_not_refined_and_changes_no_reading() {
    let cutter = Cutter::ball(6.0).unwrap();
    let mut cfg = VerifyConfig::new(0.01);
    cfg.resolution_mm = 0.02;
    let part = box_mesh_z(-30.0, 0.0, -4.0);
    let path = pass(-5.0, -0.05);
    let near = verify(&part, &path, &cutter, &cfg).unwrap();
    cfg.refine_everywhere = true;
    let all = verify(&part, &path, &cutter, &cfg).unwrap();
    let inside_bottom =
        |v: &&DVec3| v.z == -4.0 && v.x > -30.0 && v.x < 0.0 && v.y > -10.0 && v.y < 10.0;
    let count =
        |r: &cam_verify::refine::RefinedMesh| r.positions.iter().filter(inside_bottom).count();
    let (cn, ca) = (count(&near.refined), count(&all.refined));
    eprintln!(
        "bottom interior vertices: {cn} within reach, {ca} everywhere; vertices {} against {}; \
         measured {} against {}",
        near.refined.positions.len(),
        all.refined.positions.len(),
        near.report.measured,
        all.report.measured
    );
    assert_eq!(cn, 0);
    assert!(ca > 1000, "{ca}");
    let key = |d: &cam_verify::deviation::Deviation| {
        (
            d.position.to_array().map(f64::to_bits),
            d.normal.to_array().map(f64::to_bits),
        )
    };
    let read: std::collections::HashMap<_, _> = near
        .deviations
        .iter()
        .map(|d| (key(d), d.signed_mm))
        .collect();
    let mut compared = 0;
    for d in all.deviations.iter().filter(|d| d.signed_mm.is_some()) {
        assert_eq!(read.get(&key(d)), Some(&d.signed_mm), "at {:?}", d.position);
        compared += 1;
    }
    assert!(compared > 400, "{compared}");
    assert_eq!(near.report.max_gouge_mm, all.report.max_gouge_mm);
}

/// Settings whose imprint curves would not fit in memory are a typed error before anything
/// is swept (found probing the CLI: `--max-step 1e-9` hung and `--inserts 1000000` aborted
/// on allocation).
#[test]
fn settings_beyond_memory_or_reach_are_config_errors() {
    let cutter = Cutter::ball(6.0).unwrap();
    let path = pass(-10.0, 0.0);
    // A gouge tolerance above 1 mm (the vectors reach 20 times it into the part: 1e300 ran
    // for ever) and vectors longer than 100 mm.
    for tol in [1.5, 1e300] {
        let cfg = VerifyConfig::new(tol);
        assert!(matches!(
            verify(&block(), &path, &cutter, &cfg),
            Err(cam_verify::VerifyError::Config(_))
        ));
    }
    let mut cfg = VerifyConfig::new(0.01);
    cfg.deviation.outside_mm = 1e9;
    assert!(matches!(
        verify(&block(), &path, &cutter, &cfg),
        Err(cam_verify::VerifyError::Config(_))
    ));
    for (step, q) in [(1e-9, 40), (0.5, 1_000_000)] {
        let mut cfg = VerifyConfig::new(0.01);
        cfg.sweep.max_step_mm = step;
        cfg.sweep.inserts = q;
        match verify(&block(), &path, &cutter, &cfg) {
            Err(cam_verify::VerifyError::Config(m)) => {
                assert!(m.contains("imprint points"), "{m}")
            }
            other => panic!(
                "step {step}, Q {q}: {:?}",
                other.map(|v| v.report.max_gouge_mm)
            ),
        }
    }
    // The count is the steps the sweep takes: a 5 mm plunge, 24 mm of cut and a 5 mm
    // retract at 0.5 mm (the rapid is not swept).
    let poses = cam_verify::model::pose_count(&path, &cutter, &VerifyConfig::new(0.01).sweep);
    assert_eq!(poses, 10.0 + 48.0 + 10.0);
}

/// A program of translations is measured against the moves' exact volumes, not the imprint
/// surface: that surface is built only when kept (for `--swept`), and keeping it changes no
/// reading. A rotating program builds it, since its crossings are located on it.
#[test]
fn the_imprint_surface_is_built_only_when_used_or_kept() {
    let cutter = Cutter::bull(6.0, 1.0).unwrap();
    let part = box_mesh(-60.0, 0.0);
    let path = pass(-5.0, -0.05);
    let mut cfg = VerifyConfig::new(0.01);
    cfg.resolution_mm = 0.02;
    let lean = verify(&part, &path, &cutter, &cfg).unwrap();
    cfg.keep_swept = true;
    let kept = verify(&part, &path, &cutter, &cfg).unwrap();
    assert!(lean.swept.pieces.is_empty() && lean.swept.imprint_points == 0);
    assert!(!kept.swept.pieces.is_empty() && kept.swept_surface().triangles.len() > 100);
    assert_eq!(lean.deviations.len(), kept.deviations.len());
    for (a, b) in lean.deviations.iter().zip(&kept.deviations) {
        assert_eq!(a.signed_mm, b.signed_mm);
        assert_eq!(a.source_move, b.source_move);
    }
    assert!(
        (lean.report.max_gouge_mm - 0.05).abs() < 0.02,
        "{}",
        lean.report.max_gouge_mm
    );
    // The same pass with the axis turning along it: the imprint surface is measured.
    let mut turning = path.clone();
    let tilted = DVec3::new(0.0, 0.2, 1.0).normalize();
    turning.moves[2].pose.axis = tilted;
    turning.moves[3].pose.axis = tilted;
    cfg.keep_swept = false;
    let rot = verify(&part, &turning, &cutter, &cfg).unwrap();
    assert!(!rot.swept.pieces.is_empty());
}
