//! Pass ends, boundary box, links, direction options, progress.

use std::sync::Mutex;

use cam_core::{Cutter, MoveKind};
use cam_plan::{ClSurface, Direction, Milling, UniformSampler, plan};

use crate::surfaces::{Dome, Tilted, cfg};

#[test]
fn passes_end_on_the_part_and_never_plunge_into_the_void() {
    let ball = Cutter::ball(6.0).unwrap();
    let s = Dome {
        rho: 15.0,
        r: 3.0,
        edge: Some(10.0),
    };
    let sampler = UniformSampler {
        u_range: (-20.0, 20.0),
        v_range: (-5.0, 5.0),
        step_mm: 0.5,
    };
    let mut c = cfg(ball);
    c.scallop_mm = 0.05;
    let p = plan(&s, &sampler, &c, None).unwrap();
    let mut min_x = f64::INFINITY;
    let mut max_x = f64::NEG_INFINITY;
    for m in &p.toolpath.moves {
        let t = m.pose.tip;
        match m.kind {
            MoveKind::Cut | MoveKind::Plunge => {
                let z = s
                    .z_tip(t.x, t.y)
                    .expect("every cut or plunge ends on the part");
                cam_core::assert_near!(t.z, z, 1e-12);
                min_x = min_x.min(t.x);
                max_x = max_x.max(t.x);
            }
            MoveKind::Rapid => cam_core::assert_near!(t.z, p.safe_z_mm, 0.0),
            MoveKind::Retract => cam_core::assert_near!(t.z, p.safe_z_mm, 0.0),
        }
    }
    assert!((10.0 - 1e-4..=10.0).contains(&max_x), "max x {max_x}");
    assert!((-10.0..=-10.0 + 1e-4).contains(&min_x), "min x {min_x}");
    // Plunges and retracts are vertical.
    for w in p.toolpath.moves.windows(2) {
        if matches!(w[1].kind, MoveKind::Plunge | MoveKind::Retract) {
            assert_eq!(w[0].pose.tip.truncate(), w[1].pose.tip.truncate());
        }
    }
}

#[test]
fn boundary_box_clips_every_tip() {
    let ball = Cutter::ball(6.0).unwrap();
    let s = Dome {
        rho: 15.0,
        r: 3.0,
        edge: None,
    };
    let sampler = UniformSampler {
        u_range: (-25.0, 25.0),
        v_range: (-25.0, 25.0),
        step_mm: 0.5,
    };
    let mut c = cfg(ball);
    c.scallop_mm = 0.05;
    c.angle_deg = 30.0;
    c.boundary = Some((-5.0, 6.0, -3.0, 4.0));
    let p = plan(&s, &sampler, &c, None).unwrap();
    for m in &p.toolpath.moves {
        let t = m.pose.tip;
        assert!(
            t.x >= -5.0 - 1e-9 && t.x <= 6.0 + 1e-9 && t.y >= -3.0 - 1e-9 && t.y <= 4.0 + 1e-9,
            "{t}"
        );
    }
}

#[test]
fn zigzag_links_follow_flat_ground_one_way_retracts() {
    let ball = Cutter::ball(6.0).unwrap();
    let s = Tilted {
        m: 0.0,
        cutter: ball,
    };
    let sampler = UniformSampler {
        u_range: (0.0, 10.0),
        v_range: (0.0, 2.0),
        step_mm: 0.5,
    };
    let p = plan(&s, &sampler, &cfg(ball), None).unwrap();
    assert_eq!((p.surface_links, p.retracts), (p.passes - 1, 0));
    let mut c = cfg(ball);
    c.direction = Direction::OneWay;
    let p = plan(&s, &sampler, &c, None).unwrap();
    assert_eq!((p.surface_links, p.retracts), (0, p.passes - 1));
    // One-way climb: every pass along +x; conventional: along −x.
    for (milling, sign) in [(Milling::Climb, 1.0), (Milling::Conventional, -1.0)] {
        c.milling = milling;
        let p = plan(&s, &sampler, &c, None).unwrap();
        for w in p.toolpath.moves.windows(2) {
            if w[1].kind == MoveKind::Cut {
                assert!((w[1].pose.tip.x - w[0].pose.tip.x) * sign > 0.0);
            }
        }
    }
}

/// A ridge between pass ends: the exact CL surface of a ball of radius 3 over the plane
/// z = 0 and a horizontal ridge segment 1 mm high from (9.5, 1.5) to (10.5, 1.5) (the tip
/// rests on the segment at XY distance d ≤ 3 with z = 1 − 3 + sqrt(9 − d²)). Passes at
/// y = 0 and y = 3 end at x = 10 with the tip 0.60 mm high; the zig-zag link between them
/// would cross the ridge's 1 mm: it must retract.
struct RidgeAtEnds;
impl ClSurface for RidgeAtEnds {
    fn z_tip(&self, x: f64, y: f64) -> Option<f64> {
        let dx = (x - x.clamp(9.5, 10.5)).abs();
        let d2 = dx * dx + (y - 1.5) * (y - 1.5);
        let ridge = if d2 <= 9.0 {
            1.0 - 3.0 + (9.0 - d2).sqrt()
        } else {
            0.0
        };
        Some(ridge.max(0.0))
    }
}

#[test]
fn links_retract_when_they_would_gouge() {
    let ball = Cutter::ball(6.0).unwrap();
    let sampler = UniformSampler {
        u_range: (0.0, 10.0),
        v_range: (0.0, 3.0),
        step_mm: 0.5,
    };
    let mut c = cfg(ball);
    c.scallop_mm = 0.5;
    let p = plan(&RidgeAtEnds, &sampler, &c, None).unwrap();
    assert_eq!(
        p.pass_v_mm,
        vec![0.0, 3.0],
        "two passes straddling the ridge"
    );
    assert!(
        p.retracts >= 1,
        "{} retracts, {} links",
        p.retracts,
        p.surface_links
    );
    // Every surface link, checked densely, is nowhere below the CL surface by more than τ.
    for w in p.toolpath.moves.windows(2) {
        if w[1].kind == MoveKind::Cut && w[1].pass.is_none() {
            for k in 0..=1000 {
                let q = w[0].pose.tip.lerp(w[1].pose.tip, k as f64 / 1000.0);
                assert!(q.z >= RidgeAtEnds.z_tip(q.x, q.y).unwrap() - 0.01);
            }
        }
    }
}

#[test]
fn progress_reaches_the_end() {
    let ball = Cutter::ball(6.0).unwrap();
    let s = Tilted {
        m: 0.0,
        cutter: ball,
    };
    let sampler = UniformSampler {
        u_range: (0.0, 10.0),
        v_range: (0.0, 2.0),
        step_mm: 0.5,
    };
    let seen = Mutex::new(Vec::new());
    let cb = |d: usize, t: usize| seen.lock().unwrap().push((d, t));
    plan(&s, &sampler, &cfg(ball), Some(&cb)).unwrap();
    let seen = seen.into_inner().unwrap();
    assert!(seen.iter().all(|&(d, t)| t == 1000 && d <= t));
    assert_eq!(seen.iter().map(|s| s.0).max(), Some(1000));
}
