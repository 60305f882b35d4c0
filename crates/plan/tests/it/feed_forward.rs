//! Feed-forward marching: every cut move within τ of the exact CL surface, checked densely
//! and independently of the planner's own check.

use cam_core::Cutter;
use cam_plan::{UniformSampler, plan};

use crate::surfaces::{CylinderAlong, Dome, Tilted, cfg, dense_deviation};

#[test]
fn dome_moves_stay_within_tolerance() {
    let ball = Cutter::ball(6.0).unwrap();
    let s = Dome {
        rho: 15.0,
        r: 3.0,
        edge: None,
    };
    let sampler = UniformSampler {
        u_range: (-22.0, 22.0),
        v_range: (-10.0, 10.0),
        step_mm: 0.5,
    };
    let mut c = cfg(ball);
    c.scallop_mm = 0.05;
    let p = plan(&s, &sampler, &c, None).unwrap();
    let (_, excess) = dense_deviation(&s, &p.toolpath, 400);
    // Exact penetration of the ball: the part is the hemisphere of radius 15 on the plane
    // z = 0, so the ball centre's distance to it is min(|c| − 15, c.z) (above the plane).
    let mut pen = 0.0f64;
    for w in p.toolpath.moves.windows(2) {
        if w[1].kind != cam_core::MoveKind::Cut || w[1].pass.is_none() {
            continue;
        }
        for k in 0..=400 {
            let tip = w[0].pose.tip.lerp(w[1].pose.tip, k as f64 / 400.0);
            let c = tip + cam_core::DVec3::Z * 3.0;
            let d = (c.length() - 15.0).min(c.z);
            pen = pen.max(3.0 - d);
        }
    }
    assert!(
        pen <= 0.01 + 1e-12 && excess <= 0.01,
        "penetration {pen} excess {excess}"
    );
    assert!(
        p.max_chord_deviation_mm <= 0.01 + 1e-12,
        "{}",
        p.max_chord_deviation_mm
    );
    assert!(pen > 0.004, "march not too timid: penetration {pen}");
    assert_eq!(p.unresolved_joins, 0);
}

#[test]
fn cylinder_along_pass_steps_match_eq1() {
    let ball = Cutter::ball(6.0).unwrap();
    let s = CylinderAlong { rho: 20.0, r: 3.0 };
    let sampler = UniformSampler {
        u_range: (-15.0, 15.0),
        v_range: (0.0, 0.5),
        step_mm: 0.5,
    };
    let p = plan(&s, &sampler, &cfg(ball), None).unwrap();
    let (gouge, excess) = dense_deviation(&s, &p.toolpath, 400);
    assert!(
        gouge <= 0.01 && excess < 1e-12,
        "gouge {gouge} excess {excess}"
    );
    // Chord lengths against Eq. 1 with ρ_cl = ρ + R = 23 mm (interior moves of the first
    // pass). No move may beat Eq. 1 (its own sag would exceed τ). A proven move spends part
    // of τ on the CL between its interior samples: samples l ≈ 0.375 mm apart (3 mm halved
    // three times to fit the lemma's 0.49 mm) cost up to l²/(8R) ≈ 0.0059, leaving a sag of
    // about 0.0041 for the chord: L ≈ sqrt(8·23·0.0041) ≈ 0.64 of Eq. 1 at the least.
    let eq1 = 2.0 * (2.0 * 0.01 * 23.0 - 1e-4f64).sqrt();
    let lens: Vec<f64> = p
        .toolpath
        .moves
        .windows(2)
        .filter(|w| {
            w[1].kind == cam_core::MoveKind::Cut && w[1].pass == Some(0) && w[0].pass == Some(0)
        })
        .map(|w| w[0].pose.tip.distance(w[1].pose.tip))
        .collect();
    let mut sorted = lens.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    assert!(
        median > 0.6 * eq1 && sorted[sorted.len() - 1] <= eq1,
        "median chord {median} vs Eq. 1 {eq1}"
    );
}

#[test]
fn flat_ground_is_one_move_per_pass() {
    let ball = Cutter::ball(6.0).unwrap();
    let s = Tilted {
        m: 0.0,
        cutter: ball,
    };
    let sampler = UniformSampler {
        u_range: (0.0, 50.0),
        v_range: (0.0, 2.0),
        step_mm: 0.5,
    };
    let p = plan(&s, &sampler, &cfg(ball), None).unwrap();
    assert_eq!(p.cl_points, 2 * p.passes);
    let mut c = cfg(ball);
    c.max_step_mm = Some(7.0);
    let p = plan(&s, &sampler, &c, None).unwrap();
    assert_eq!(
        p.cl_points,
        9 * p.passes,
        "50 mm in moves of at most 7 mm: 8 moves"
    );
}

#[test]
fn same_plan_for_one_and_many_threads() {
    let ball = Cutter::ball(6.0).unwrap();
    let s = Dome {
        rho: 15.0,
        r: 3.0,
        edge: Some(12.0),
    };
    let sampler = UniformSampler {
        u_range: (-20.0, 20.0),
        v_range: (-10.0, 10.0),
        step_mm: 0.37,
    };
    let mut c = cfg(ball);
    c.scallop_mm = 0.05;
    c.angle_deg = 30.0;
    let a = crate::on_threads(1, || plan(&s, &sampler, &c, None).unwrap());
    let b = crate::on_threads(4, || plan(&s, &sampler, &c, None).unwrap());
    assert_eq!(a, b);
}
