//! The `avoid` policy: lift over colliding stretches, account for the dropped cut length.

use cam_core::{MoveKind, assert_near};
use cam_holder::{AvoidConfig, CheckConfig, HolderPolicy, avoid, check_toolpath};

use crate::common::{ball6, path, rib, v};

#[test]
fn lifts_over_the_rib_and_reports_dropped_length() {
    let mesh = rib(1.0, 20.0, 30.0);
    let a = ball6(20.0);
    let cfg = CheckConfig::default();
    let pts: Vec<(MoveKind, glam::DVec3)> = [-30.0, -20.0, -10.0, 0.0, 10.0, 20.0, 30.0]
        .iter()
        .map(|&y| (MoveKind::Cut, v(8.0, y, 5.0)))
        .collect();
    let tp = path(&pts);
    let rep = check_toolpath(&mesh, &a, &tp, &cfg);
    let idx: Vec<usize> = rep.collisions.iter().map(|c| c.move_index).collect();
    // Move 1 ends at y = -20, 12.5 mm from the rib corner: clear; moves 2..=5 collide.
    assert_eq!(idx, vec![2, 3, 4, 5]);
    let (out, sum) = avoid(
        &tp,
        &rep.collisions,
        &AvoidConfig {
            safe_z_mm: 50.0,
            stepover_mm: 1.0,
        },
    );
    assert_eq!(sum.stretches.len(), 1);
    assert_eq!(
        (sum.stretches[0].first_move, sum.stretches[0].last_move),
        (2, 5)
    );
    assert_near!(sum.removed_cut_length_mm, 40.0, 1e-12);
    assert_near!(sum.unmachined_area_mm2, 40.0, 1e-12);
    let kinds: Vec<MoveKind> = out.moves.iter().map(|m| m.kind).collect();
    assert_eq!(
        kinds,
        vec![
            MoveKind::Cut,
            MoveKind::Cut,
            MoveKind::Retract,
            MoveKind::Rapid,
            MoveKind::Plunge,
            MoveKind::Cut
        ]
    );
    assert_eq!(out.moves[2].pose.tip, v(8.0, -20.0, 50.0));
    assert_eq!(out.moves[3].pose.tip, v(8.0, 20.0, 50.0));
    assert_eq!(out.moves[4].pose.tip, v(8.0, 20.0, 5.0));
    // The rewritten path is clear.
    assert!(check_toolpath(&mesh, &a, &out, &cfg).is_clear());
    assert_near!(out.length_where(|k| k == MoveKind::Cut), 20.0, 1e-12);
}

#[test]
fn policy_parses() {
    assert_eq!("avoid".parse::<HolderPolicy>(), Ok(HolderPolicy::Avoid));
    assert_eq!(HolderPolicy::default(), HolderPolicy::Fail);
    assert!("lift".parse::<HolderPolicy>().is_err());
}
