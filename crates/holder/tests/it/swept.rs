//! The exact swept test against a brute-force reference: dense static checks along the move.

use cam_core::{Mesh, MoveKind, Triangle};
use cam_holder::{CheckConfig, HolderChecker, HolderCylinder};
use glam::DVec3;

use crate::common::{Rng, ball6, path};

#[test]
fn swept_depth_matches_dense_static_sampling() {
    let mut rng = Rng(0x9E3779B97F4A7C15);
    let mut a = ball6(20.0);
    a.holder = vec![
        HolderCylinder {
            diameter: 20.0,
            length: 15.0,
        },
        HolderCylinder {
            diameter: 32.0,
            length: 40.0,
        },
    ];
    let cfg = CheckConfig::default();
    let mut compared = 0;
    for _case in 0..60 {
        let mut r = |lo: f64, hi: f64| lo + (hi - lo) * rng.next();
        let tri = Triangle::new(
            DVec3::new(r(-15.0, 15.0), r(-15.0, 15.0), r(0.0, 40.0)),
            DVec3::new(r(-15.0, 15.0), r(-15.0, 15.0), r(0.0, 40.0)),
            DVec3::new(r(-15.0, 15.0), r(-15.0, 15.0), r(0.0, 40.0)),
        );
        let Ok(mesh) = Mesh::from_triangles(vec![tri], "<random>") else {
            continue;
        };
        let p = DVec3::new(r(-20.0, 20.0), r(-20.0, 20.0), r(-10.0, 10.0));
        let q = DVec3::new(r(-20.0, 20.0), r(-20.0, 20.0), r(-10.0, 10.0));
        let checker = HolderChecker::new(&mesh);
        let rep = checker.check(&a, &path(&[(MoveKind::Cut, p), (MoveKind::Cut, q)]), &cfg);
        let n = 4000;
        for part_index in 0..3 {
            let part = a.parts()[part_index].part;
            let swept = rep
                .collisions
                .iter()
                .filter(|c| c.move_index == 1 && c.part == part)
                .map(|c| c.depth_mm)
                .fold(0.0, f64::max);
            let mut sampled: f64 = 0.0;
            for k in 0..=n {
                let tip = p + (q - p) * (k as f64 / n as f64);
                for (pp, d, _) in checker.check_pose(&a, tip, &cfg) {
                    if pp == part {
                        sampled = sampled.max(d);
                    }
                }
            }
            // Sound: never below a sample. Tight: dense samples come within a step's motion.
            assert!(swept >= sampled - 1e-9, "swept {swept} < sampled {sampled}");
            assert!(
                swept <= sampled + 0.05,
                "swept {swept} > sampled {sampled} + 0.05 ({p} → {q}, {tri:?})"
            );
            if swept > 0.0 {
                compared += 1;
            }
        }
    }
    assert!(compared >= 10, "only {compared} colliding cases");
}
