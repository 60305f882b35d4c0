//! Rapid moves checked against the part (`cam_verify::rapids`): a rapid that runs into the
//! part sinks below the CL surface, by a depth known in closed form on a block and checked
//! against dense drops on the dome.

use cam_core::{Cutter, DVec3, Mesh, Move, MoveKind, Pose, Toolpath, Triangle, Units};
use cam_offset::DropCutter;
use cam_verify::rapids::{RapidReport, check_rapids};

use crate::pipeline::box_mesh;

fn mv(kind: MoveKind, tip: DVec3, axis: DVec3) -> Move {
    Move {
        kind,
        pose: Pose { tip, axis },
        feed_mm_per_min: None,
        line: None,
        pass: None,
    }
}

/// One rapid from `a` to `b` (axis +Z).
fn rapid(a: DVec3, b: DVec3) -> Toolpath {
    Toolpath {
        moves: vec![
            mv(MoveKind::Rapid, a, DVec3::Z),
            mv(MoveKind::Rapid, b, DVec3::Z),
        ],
    }
}

fn check(part: &Mesh, spec: &str, a: DVec3, b: DVec3) -> RapidReport {
    let cutter: Cutter = spec.parse().unwrap();
    check_rapids(part, &cutter, &rapid(a, b), 0.01)
}

/// The block x ∈ [0, 20], y ∈ [−10, 10], top at z = 0: through it, over it, along its wall
/// with the side of the tool in it, and straight down into it.
#[test]
fn rapids_into_a_block_read_their_depth_below_the_cl_surface() {
    let part = box_mesh(0.0, 20.0);
    let p = DVec3::new;
    for (spec, a, r) in [
        ("flat:6", 3.0f64, 0.0f64),
        ("ball:6", 0.0, 3.0),
        ("bull:6:1.5", 1.5, 1.5),
    ] {
        // Across the middle, 2 mm below the top: the tool would rest on the top face.
        let rep = check(&part, spec, p(-10.0, 0.0, -2.0), p(30.0, 0.0, -2.0));
        // (The path's first move, a rapid to the start, is checked where it arrives.)
        assert_eq!(rep.checked, 2, "{spec}");
        let c = &rep.collisions[..];
        assert!(
            c.len() == 1 && (c[0].depth_mm - 2.0).abs() < 1e-9,
            "{spec}: {rep:?}"
        );
        assert!(
            (c[0].tip[2] + 2.0).abs() < 1e-12 && c[0].move_index == 1,
            "{spec}"
        );
        // Along the wall x = 0 with the axis 2.9 mm from it, 5 mm down: the tool would rest
        // on the top edge, where its outline at radius 2.9 lies `a + r − …` above the tip.
        let h = if 2.9 <= a {
            0.0
        } else {
            r - (r * r - (2.9 - a) * (2.9 - a)).sqrt()
        };
        let rep = check(&part, spec, p(-2.9, -30.0, -5.0), p(-2.9, 30.0, -5.0));
        let want = 5.0 - h;
        assert!(
            (rep.max_depth_mm - want).abs() < 1e-9 && rep.collisions.len() == 1,
            "{spec}: beside the wall {} (want {want})",
            rep.max_depth_mm
        );
        // Just over the top: clear; just under it by less than the tolerance: no collision,
        // but the depth is read.
        let rep = check(&part, spec, p(-10.0, 0.0, 0.005), p(30.0, 0.0, 0.005));
        assert!(
            rep.collisions.is_empty() && rep.max_depth_mm == 0.0,
            "{spec}: {rep:?}"
        );
        let rep = check(&part, spec, p(-10.0, 0.0, -0.005), p(30.0, 0.0, -0.005));
        assert!(rep.collisions.is_empty(), "{spec}: {rep:?}");
        assert!((rep.max_depth_mm - 0.005).abs() < 1e-9, "{spec}: {rep:?}");
        // Straight down into the top.
        let rep = check(&part, spec, p(10.0, 0.0, 10.0), p(10.0, 0.0, -1.0));
        assert!((rep.max_depth_mm - 1.0).abs() < 1e-9, "{spec}: {rep:?}");
        assert_eq!(rep.collisions[0].tip, [10.0, 0.0, -1.0], "{spec}");
        // Far from the block: nothing.
        let rep = check(&part, spec, p(-10.0, 0.0, -9.0), p(-10.0, 30.0, -9.0));
        assert!(
            rep.collisions.is_empty() && rep.max_depth_mm == 0.0,
            "{spec}"
        );
    }
}

/// Rapids across the dome at heights that cut it: the depth reported is reached at the
/// point reported (a drop there confirms it), and no drop among 4000 along the rapid finds
/// the tool deeper.
#[test]
fn rapids_over_the_dome_agree_with_dense_drops() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/parts");
    let part = Mesh::load(root.join("dome.obj"), Units::Mm).unwrap();
    for spec in ["ball:6", "bull:6:1.5", "flat:6"] {
        let cutter: Cutter = spec.parse().unwrap();
        let dc = DropCutter::new(&part, cutter);
        for (a, b) in [
            (DVec3::new(-35.0, -3.0, 12.0), DVec3::new(35.0, 4.0, 16.0)),
            (DVec3::new(-10.0, -30.0, 2.0), DVec3::new(12.0, 30.0, 19.0)),
            (DVec3::new(30.0, 30.0, 8.0), DVec3::new(-30.0, -25.0, 8.0)),
        ] {
            let rep = check_rapids(&part, &cutter, &rapid(a, b), 0.01);
            let c = rep.collisions.first().expect("the rapid cuts the dome");
            let t = DVec3::from_array(c.tip);
            let z = dc.drop(t.x, t.y).unwrap();
            assert!(
                (z - t.z - c.depth_mm).abs() < 1e-9,
                "{spec}: depth {} not reached at {t:?} (drop {z})",
                c.depth_mm
            );
            let n = 4000;
            let dense = (0..=n)
                .filter_map(|i| {
                    let p = a.lerp(b, i as f64 / n as f64);
                    dc.drop(p.x, p.y).map(|z| z - p.z)
                })
                .fold(f64::NEG_INFINITY, f64::max);
            assert!(
                c.depth_mm >= dense - 1e-9,
                "{spec}: {} below a drop's {dense}",
                c.depth_mm
            );
            assert!(
                c.depth_mm - dense < 0.01,
                "{spec}: {} vs {dense}",
                c.depth_mm
            );
        }
    }
}

/// A program's first move, when it is a rapid, comes from where the tool was (the program
/// does not say): the pose it reaches is checked.
#[test]
fn a_first_rapid_is_checked_where_it_arrives() {
    let part = box_mesh(0.0, 20.0);
    let cutter: Cutter = "flat:6".parse().unwrap();
    for (z, depth) in [(-1.5, 1.5), (0.5, 0.0)] {
        let tp = Toolpath {
            moves: vec![
                mv(MoveKind::Rapid, DVec3::new(10.0, 0.0, z), DVec3::Z),
                mv(MoveKind::Cut, DVec3::new(12.0, 0.0, 1.0), DVec3::Z),
            ],
        };
        let rep = check_rapids(&part, &cutter, &tp, 0.01);
        assert_eq!(rep.checked, 1);
        assert!((rep.max_depth_mm - depth).abs() < 1e-12, "{rep:?}");
        assert_eq!(rep.collisions.len(), usize::from(depth > 0.0));
    }
}

/// A rapid that turns the axis is not checked (the tool's motion between its poses depends
/// on the machine's kinematics), and says so.
#[test]
fn rapids_that_turn_the_axis_are_counted_unchecked() {
    let part = box_mesh(0.0, 20.0);
    let cutter: Cutter = "ball:6".parse().unwrap();
    let k = DVec3::new(0.0, 0.3, 1.0).normalize();
    let tp = Toolpath {
        moves: vec![
            mv(MoveKind::Rapid, DVec3::new(-10.0, 0.0, -2.0), DVec3::Z),
            mv(MoveKind::Rapid, DVec3::new(30.0, 0.0, -2.0), k),
        ],
    };
    let rep = check_rapids(&part, &cutter, &tp, 0.01);
    // (The first move is checked where it arrives, beside the block.)
    assert_eq!((rep.checked, rep.tilted, rep.unchecked), (1, 0, 1));
    assert!(rep.collisions.is_empty());
}

/// The part and `tips` turned by `q`, and the axis +Z turned with them.
fn turned(part: &Mesh, q: glam::DQuat) -> Mesh {
    let tris = part
        .triangles()
        .iter()
        .map(|t| Triangle::new(q * t.v[0], q * t.v[1], q * t.v[2]))
        .collect();
    Mesh::from_triangles(tris, "<turned>").unwrap()
}

/// Turning the whole scene (part, tips and axis) changes no depth: rapids with a tilted
/// axis, checked in their axis's frame, read the depths (to 1e-9 mm) that the same rapids
/// read with the axis +Z, at tips where the tool sits that deep (turned back, a drop there
/// confirms it to 1e-9 mm); the depths of the +Z rapids
/// `rapids_into_a_block_read_their_depth_below_the_cl_surface` checks in closed form. The
/// turns include an axis lying flat and one pointing down. Each program is one path: its
/// rapids share an axis and one turned drop-cutter.
#[test]
fn tilted_rapids_read_the_depths_of_the_turned_scene() {
    let p = DVec3::new;
    let block = box_mesh(0.0, 20.0);
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/parts");
    let dome = Mesh::load(root.join("dome.obj"), Units::Mm).unwrap();
    let scenes: [(&Mesh, Vec<(DVec3, DVec3)>); 2] = [
        (
            &block,
            vec![
                (p(-10.0, 0.0, -2.0), p(30.0, 0.0, -2.0)),
                (p(-2.9, -30.0, -5.0), p(-2.9, 30.0, -5.0)),
                (p(-10.0, 0.0, 0.005), p(30.0, 0.0, 0.005)),
                (p(-10.0, 0.0, -0.005), p(30.0, 0.0, -0.005)),
                (p(10.0, 0.0, 10.0), p(10.0, 0.0, -1.0)),
                (p(-10.0, 0.0, -9.0), p(-10.0, 30.0, -9.0)),
            ],
        ),
        (
            &dome,
            vec![
                (p(-35.0, -3.0, 12.0), p(35.0, 4.0, 16.0)),
                (p(-10.0, -30.0, 2.0), p(12.0, 30.0, 19.0)),
                (p(30.0, 30.0, 8.0), p(-30.0, -25.0, 8.0)),
            ],
        ),
    ];
    let turns = [
        glam::DQuat::from_axis_angle(p(1.0, 2.0, 0.5).normalize(), 30f64.to_radians()),
        glam::DQuat::from_axis_angle(DVec3::Y, 90f64.to_radians()),
        glam::DQuat::from_axis_angle(p(1.0, -1.0, 0.0).normalize(), 150f64.to_radians()),
    ];
    // A path of one rapid per pair: into the start (checked where it arrives), then along
    // the pair, then up the axis to a far park position between pairs.
    let path = |pairs: &[(DVec3, DVec3)], q: glam::DQuat| {
        let k = q * DVec3::Z;
        let mut moves = Vec::new();
        for &(a, b) in pairs {
            moves.push(mv(MoveKind::Cut, q * p(a.x, a.y, 100.0), k));
            moves.push(mv(MoveKind::Cut, q * a, k));
            moves.push(mv(MoveKind::Rapid, q * b, k));
            moves.push(mv(MoveKind::Cut, q * p(b.x, b.y, 100.0), k));
        }
        Toolpath { moves }
    };
    let mut compared = 0;
    for (part, pairs) in &scenes {
        for spec in ["ball:6", "bull:6:1.5", "flat:6"] {
            let cutter: Cutter = spec.parse().unwrap();
            let dc = DropCutter::new(part, cutter);
            let flat = check_rapids(part, &cutter, &path(pairs, glam::DQuat::IDENTITY), 0.01);
            assert_eq!((flat.checked, flat.tilted), (pairs.len(), 0), "{spec}");
            for q in turns {
                let rep = check_rapids(&turned(part, q), &cutter, &path(pairs, q), 0.01);
                assert_eq!(
                    (rep.checked, rep.tilted, rep.unchecked),
                    (pairs.len(), pairs.len(), 0),
                    "{spec}"
                );
                assert!(
                    (rep.max_depth_mm - flat.max_depth_mm).abs() < 1e-9,
                    "{spec} {q:?}: {} against {}",
                    rep.max_depth_mm,
                    flat.max_depth_mm
                );
                assert_eq!(rep.collisions.len(), flat.collisions.len(), "{spec} {q:?}");
                for (c, f) in rep.collisions.iter().zip(&flat.collisions) {
                    assert_eq!(c.move_index, f.move_index, "{spec} {q:?}");
                    assert!(
                        (c.depth_mm - f.depth_mm).abs() < 1e-9,
                        "{spec} {q:?}: {c:?} against {f:?}"
                    );
                    // The deepest point need not be unique (a level rapid under a flat top):
                    // the tip reported, turned back, is one where the tool sits that deep.
                    let t = q.inverse() * DVec3::from_array(c.tip);
                    let z = dc.drop(t.x, t.y).unwrap();
                    assert!(
                        (z - t.z - c.depth_mm).abs() < 1e-9,
                        "{spec} {q:?}: depth {} not reached at {t} (drop {z})",
                        c.depth_mm
                    );
                    compared += 1;
                }
            }
        }
    }
    eprintln!("tilted rapids: {compared} collisions compared with their +Z twins");
    assert!(compared >= 30, "{compared}");
}
