//! A move across a thin tall rib whose end poses are clear but whose middle collides: the
//! check along the move must find it, a check at the CL points alone must not.

use cam_core::{MoveKind, assert_near};
use cam_holder::{AssemblyPart, CheckConfig, HolderChecker, check_toolpath, min_stick_out};

use crate::common::{ball6, path, rib, v};

/// Onset of the Ø20 holder on the line x = 8 against the rib corner (0.5, -10):
/// (8 - 0.5)² + (y + 10)² = 10².
fn onset_y() -> f64 {
    -10.0 - (100.0f64 - 7.5 * 7.5).sqrt()
}

#[test]
fn middle_of_move_collides_end_points_clear() {
    let mesh = rib(1.0, 20.0, 30.0);
    let a = ball6(20.0);
    let cfg = CheckConfig::default();
    let (p, q) = (v(8.0, -30.0, 5.0), v(8.0, 30.0, 5.0));
    let checker = HolderChecker::new(&mesh);
    assert!(checker.check_pose(&a, p, &cfg).is_empty());
    assert!(checker.check_pose(&a, q, &cfg).is_empty());
    // CL points only (each pose a zero-length move) find nothing ...
    let points = path(&[(MoveKind::Cut, p)]);
    assert!(check_toolpath(&mesh, &a, &points, &cfg).is_clear());
    let points = path(&[(MoveKind::Cut, q)]);
    assert!(check_toolpath(&mesh, &a, &points, &cfg).is_clear());
    // ... the move between them collides: holder radius 10, rib face 7.5 away: depth 2.5.
    let tp = path(&[(MoveKind::Cut, p), (MoveKind::Cut, q)]);
    let rep = checker.check(&a, &tp, &cfg);
    assert_eq!(rep.collisions.len(), 1);
    let c = rep.collisions[0];
    assert_eq!((c.move_index, c.part), (1, AssemblyPart::Holder(0)));
    eprintln!(
        "rib: depth expected 2.5, found {:.12}; onset y expected {:.12}, found {:.12}",
        c.depth_mm,
        onset_y(),
        c.position.y
    );
    assert_near!(c.depth_mm, 2.5, 1e-9);
    assert_near!(c.position.y, onset_y(), 1e-6);
    assert_near!(c.position.z, 5.0, 1e-12);
    // Minimum stick-out: holder bottom above the rib top 30 with the tip at 5.
    let so = min_stick_out(&mesh, &a, &tp, &cfg);
    assert_near!(so.min_mm.unwrap(), 25.0, 1e-9);
    assert!(check_toolpath(&mesh, &ball6(25.0 + 1e-6), &tp, &cfg).is_clear());
    assert!(!check_toolpath(&mesh, &ball6(25.0 - 1e-3), &tp, &cfg).is_clear());
}

#[test]
fn oblique_move_over_rib() {
    // Tip climbs 5 → 15 while crossing: the holder bottom (tip + 20) is below the rib top 30
    // while the tip is below 10, i.e. for y ≤ 0, and the rib is within reach from y = onset.
    let mesh = rib(1.0, 20.0, 30.0);
    let a = ball6(20.0);
    let cfg = CheckConfig::default();
    let tp = path(&[
        (MoveKind::Cut, v(8.0, -30.0, 5.0)),
        (MoveKind::Cut, v(8.0, 30.0, 15.0)),
    ]);
    let rep = check_toolpath(&mesh, &a, &tp, &cfg);
    assert_eq!(rep.collisions.len(), 1);
    let c = rep.collisions[0];
    assert_near!(c.depth_mm, 2.5, 1e-9);
    let t_on = (onset_y() + 30.0) / 60.0;
    assert_near!(c.position.y, onset_y(), 1e-6);
    assert_near!(c.position.z, 5.0 + 10.0 * t_on, 1e-6);
    // The holder must clear the rib top at the onset, the lowest tip within reach:
    // s* = 30 - (5 + 10 t_on).
    let want = 30.0 - (5.0 + 10.0 * t_on);
    let so = min_stick_out(&mesh, &a, &tp, &cfg);
    let s = so.min_mm.unwrap();
    eprintln!(
        "rib oblique: min stick-out expected {want:.12}, found {s:.12}; depth expected 2.5, found {:.12}",
        c.depth_mm
    );
    assert_near!(s, want, 1e-9);
    assert!(check_toolpath(&mesh, &ball6(s + 1e-6), &tp, &cfg).is_clear());
    assert!(!check_toolpath(&mesh, &ball6(s - 1e-3), &tp, &cfg).is_clear());
}

#[test]
fn results_do_not_depend_on_thread_count() {
    let mesh = rib(1.0, 20.0, 30.0);
    let a = ball6(20.0);
    let mut moves = Vec::new();
    for k in 0..60 {
        let x = -20.0 + k as f64 * 0.7;
        moves.push((MoveKind::Cut, v(x, -30.0, 5.0)));
        moves.push((MoveKind::Cut, v(x, 30.0, 5.0 + (k % 5) as f64)));
    }
    let tp = path(&moves);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let r1 = one.install(|| check_toolpath(&mesh, &a, &tp, &CheckConfig::default()));
    let r2 = check_toolpath(&mesh, &a, &tp, &CheckConfig::default());
    assert!(!r1.is_clear());
    assert_eq!(r1, r2);
}
