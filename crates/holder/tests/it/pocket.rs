//! A 40 × 40 pocket 25 deep: the Ø20 holder of a ball-6 tool at stick-out 20 must touch the
//! wall and the rim at known places and depths; the minimum stick-out is exactly 25.

use cam_core::{MoveKind, assert_near};
use cam_holder::{AssemblyPart, CheckConfig, check_toolpath, min_stick_out};

use crate::common::{ball6, path, pocket, v};

fn floor_path() -> cam_core::Toolpath {
    path(&[
        (MoveKind::Rapid, v(0.0, 0.0, 50.0)),
        (MoveKind::Plunge, v(0.0, 0.0, 0.0)),
        (MoveKind::Cut, v(16.0, 0.0, 0.0)),
        (MoveKind::Cut, v(16.0, 16.0, 0.0)),
        (MoveKind::Retract, v(16.0, 16.0, 50.0)),
    ])
}

#[test]
fn holder_touches_wall_at_known_depth_and_place() {
    let mesh = pocket(20.0, 25.0, 40.0);
    let rep = check_toolpath(&mesh, &ball6(20.0), &floor_path(), &CheckConfig::default());
    let got: Vec<(usize, AssemblyPart)> = rep
        .collisions
        .iter()
        .map(|c| (c.move_index, c.part))
        .collect();
    assert_eq!(
        got,
        vec![
            (2, AssemblyPart::Holder(0)),
            (3, AssemblyPart::Holder(0)),
            (4, AssemblyPart::Holder(0))
        ]
    );
    // Holder radius 10, tip 4 mm from the wall x = 20 at the end of move 2: depth 10 - 4 = 6.
    for c in &rep.collisions {
        assert_near!(c.depth_mm, 6.0, 1e-9);
    }
    // Move 2 runs x 0 → 16 on the floor: the holder reaches the wall x = 20 when x > 10.
    let c = rep.collisions[0];
    eprintln!(
        "pocket: depth expected 6, found {:.12}; onset x expected 10, found {:.12}",
        c.depth_mm, c.position.x
    );
    assert_near!(c.position.x, 10.0, 1e-6);
    assert_near!(c.position.y, 0.0, 1e-12);
    assert_eq!(c.line, Some(12));
    // Moves 3 and 4 start inside the collision.
    assert_eq!(rep.collisions[1].position, v(16.0, 0.0, 0.0));
    assert_eq!(rep.collisions[2].position, v(16.0, 16.0, 0.0));
    assert_near!(rep.max_depth_mm, 6.0, 1e-9);
}

#[test]
fn plunge_collides_from_known_height() {
    // Plunge at x = 16: the holder bottom (tip + 20) reaches the rim z = 25 at tip z = 5.
    let mesh = pocket(20.0, 25.0, 40.0);
    let tp = path(&[
        (MoveKind::Rapid, v(16.0, 0.0, 50.0)),
        (MoveKind::Plunge, v(16.0, 0.0, 0.0)),
    ]);
    let rep = check_toolpath(&mesh, &ball6(20.0), &tp, &CheckConfig::default());
    assert_eq!(rep.collisions.len(), 1);
    assert_near!(rep.collisions[0].position.z, 5.0, 1e-9);
    eprintln!(
        "pocket plunge: onset z expected 5, found {:.12}",
        rep.collisions[0].position.z
    );
    assert_near!(rep.collisions[0].depth_mm, 6.0, 1e-9);
}

#[test]
fn clearance_increases_depth_exactly() {
    let mesh = pocket(20.0, 25.0, 40.0);
    let cfg = CheckConfig {
        clearance_mm: 0.5,
        ..Default::default()
    };
    let rep = check_toolpath(&mesh, &ball6(20.0), &floor_path(), &cfg);
    assert_near!(rep.max_depth_mm, 6.5, 1e-9);
    // With clearance the shank (radius 3.5) still clears the wall 4 mm away.
    assert!(
        rep.collisions
            .iter()
            .all(|c| c.part == AssemblyPart::Holder(0))
    );
}

#[test]
fn minimum_stick_out_is_pocket_depth() {
    let mesh = pocket(20.0, 25.0, 40.0);
    let tp = floor_path();
    let cfg = CheckConfig::default();
    let so = min_stick_out(&mesh, &ball6(20.0), &tp, &cfg);
    let s = so.min_mm.expect("a stick-out exists");
    eprintln!("pocket: min stick-out expected 25, found {s:.12}");
    assert_near!(s, 25.0, 1e-9);
    assert_eq!(so.limiting_part, Some(AssemblyPart::Holder(0)));
    let (mi, pos) = so.limiting.unwrap();
    assert_eq!(mi, 2);
    assert_near!(pos.x, 10.0, 1e-6);
    assert!(check_toolpath(&mesh, &ball6(s + 1e-6), &tp, &cfg).is_clear());
    assert!(!check_toolpath(&mesh, &ball6(s - 1e-3), &tp, &cfg).is_clear());
}

#[test]
fn minimum_stick_out_for_a_path_far_from_walls_is_flute_length() {
    let mesh = pocket(20.0, 25.0, 40.0);
    let tp = path(&[
        (MoveKind::Cut, v(-5.0, 0.0, 0.0)),
        (MoveKind::Cut, v(5.0, 0.0, 0.0)),
    ]);
    let so = min_stick_out(&mesh, &ball6(20.0), &tp, &CheckConfig::default());
    assert_eq!(so.min_mm, Some(12.0));
    assert_eq!(so.limiting, None);
}

#[test]
fn narrow_slot_makes_the_shank_collide_for_every_stick_out() {
    // A 7 mm wide pocket (tip 3.5 from the walls): the Ø6 shank clears by 0.5, but a Ø8 shank
    // above the flute touches the walls at any stick-out.
    let mesh = pocket(3.5, 25.0, 40.0);
    let tp = path(&[
        (MoveKind::Cut, v(0.0, 0.0, 0.0)),
        (MoveKind::Cut, v(0.0, 0.0, 0.0)),
    ]);
    let mut a = ball6(30.0);
    a.shank_diameter_mm = 8.0;
    let rep = check_toolpath(&mesh, &a, &tp, &CheckConfig::default());
    let shank: Vec<_> = rep
        .collisions
        .iter()
        .filter(|c| c.part == AssemblyPart::Shank)
        .collect();
    assert_eq!(shank.len(), 2);
    assert_near!(shank[0].depth_mm, 0.5, 1e-9);
    let so = min_stick_out(&mesh, &a, &tp, &CheckConfig::default());
    assert_eq!(so.min_mm, None);
}

#[test]
fn tilted_moves_are_skipped_and_counted() {
    let mesh = pocket(20.0, 25.0, 40.0);
    let mut tp = floor_path();
    tp.moves[3].pose.axis = glam::DVec3::new(0.0, 0.6, 0.8);
    let rep = check_toolpath(&mesh, &ball6(20.0), &tp, &CheckConfig::default());
    // Moves 3 and 4 touch the tilted pose: not checked (3-axis only).
    assert_eq!(rep.moves_skipped_not_vertical, 2);
    assert_eq!(rep.moves_checked, 3);
    assert_eq!(
        rep.collisions
            .iter()
            .map(|c| c.move_index)
            .collect::<Vec<_>>(),
        vec![2]
    );
}
