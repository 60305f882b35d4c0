//! Side step: the scallop left, measured independently, against the analytic value.

use cam_core::Cutter;
use cam_plan::sidestep::{SideStepModel, Silhouette, ball_scallop, ball_step};
use cam_plan::{Plan, ScallopProbe, UniformSampler, measure_scallop, plan};

use crate::surfaces::{Analytic, Cylinder, Plane, Tilted, Trough, cfg};

fn run(s: &dyn Analytic, cutter: Cutter, v: (f64, f64)) -> Plan {
    let sampler = UniformSampler {
        u_range: (0.0, 10.0),
        v_range: v,
        step_mm: 0.5,
    };
    plan(s, &sampler, &cfg(cutter), None).unwrap()
}

/// Scallop measured between the contact points of passes `k` and `k+1` (`cc` maps a pass's
/// `v` to its contact point's `y`) at three stations.
fn measured_between(
    s: &dyn Analytic,
    cutter: &Cutter,
    p: &Plan,
    k: usize,
    cc: &dyn Fn(f64) -> f64,
) -> f64 {
    measured_at(s, cutter, p, k, cc, &[2.5, 5.0, 7.5])
}

/// [`measured_between`] at the given stations `u`.
fn measured_at(
    s: &dyn Analytic,
    cutter: &Cutter,
    p: &Plan,
    k: usize,
    cc: &dyn Fn(f64) -> f64,
    stations: &[f64],
) -> f64 {
    let (a, b) = (cc(p.pass_v_mm[k]), cc(p.pass_v_mm[k + 1]));
    let probe = ScallopProbe {
        angle_deg: 0.0,
        stations_u: stations.to_vec(),
        v_range: (a.min(b), a.max(b)),
        dv_mm: 1e-3,
    };
    let part = |x: f64, y: f64| s.part(x, y);
    let r = measure_scallop(&part, cutter, &p.toolpath, &probe);
    assert!(r.max_gouge_mm < 1e-9, "gouge {}", r.max_gouge_mm);
    r.max_scallop_mm
}

#[test]
fn plane_ball_step_is_exact_and_leaves_h() {
    let ball = Cutter::ball(6.0).unwrap();
    let s = Tilted {
        m: 0.0,
        cutter: ball,
    };
    let p = run(&s, ball, (0.0, 3.0));
    let w = 2.0 * (2.0 * 3.0 * 0.01 - 1e-4f64).sqrt();
    for k in 0..p.passes - 2 {
        cam_core::assert_near!(p.pass_v_mm[k + 1] - p.pass_v_mm[k], w, 1e-12);
    }
    let h = measured_between(&s, &ball, &p, 1, &|v| v);
    cam_core::assert_near!(h, 0.01, 1e-7);
    cam_core::assert_near!(p.predicted_max_scallop_mm, 0.01, 1e-12);
}

#[test]
fn convex_and_concave_cylinder_ball_scallop_matches_formula() {
    let ball = Cutter::ball(6.0).unwrap();
    for (name, s, rho) in [
        (
            "convex",
            &Cylinder {
                rho: 20.0,
                cutter: ball,
            } as &dyn Analytic,
            20.0,
        ),
        (
            "concave",
            &Trough {
                rho: 20.0,
                cutter: ball,
            } as &dyn Analytic,
            -20.0,
        ),
    ] {
        let cc = |v: f64| v * rho / (rho + 3.0);
        let p = run(s, ball, (0.0, 6.0));
        let mut worst = 0.0f64;
        for k in 0..p.passes - 2 {
            let (v0, v1) = (p.pass_v_mm[k], p.pass_v_mm[k + 1]);
            let (z0, z1) = (s.z_tip(0.0, v0).unwrap(), s.z_tip(0.0, v1).unwrap());
            let chord = ((v1 - v0).powi(2) + (z1 - z0).powi(2)).sqrt();
            let want = ball_scallop(3.0, rho, chord).unwrap();
            let got = measured_between(s, &ball, &p, k, &cc);
            cam_core::assert_near!(got, want, 1e-7, "{name} pair {k}");
            assert!(got <= 0.01 + 5e-6, "{name} pair {k}: {got}");
            worst = worst.max(got);
        }
        // Not over-conservative: the worst pair is within 5 % of h.
        assert!(worst > 0.0095, "{name}: worst {worst}");
    }
}

#[test]
fn steep_slope_shrinks_the_step_by_cos_theta() {
    let ball = Cutter::ball(6.0).unwrap();
    let theta = 40f64.to_radians();
    let s = Tilted {
        m: theta.tan(),
        cutter: ball,
    };
    let p = run(&s, ball, (0.0, 3.0));
    let w = 2.0 * (2.0 * 3.0 * 0.01 - 1e-4f64).sqrt();
    cam_core::assert_near!(p.pass_v_mm[1] - p.pass_v_mm[0], w * theta.cos(), 1e-9);
    let h = measured_between(&s, &ball, &p, 1, &|v| v + 3.0 * theta.sin());
    cam_core::assert_near!(h, 0.01, 1e-7);
}

#[test]
fn bull_on_slope_uses_corner_radius_and_leaves_h() {
    let bull = Cutter::bull(10.0, 2.0).unwrap();
    let theta = 30f64.to_radians();
    let model = SideStepModel::new(bull, 0.01);
    cam_core::assert_near!(model.effective_radius(0.0, theta.tan()), 2.0, 1e-9);
    let s = Tilted {
        m: theta.tan(),
        cutter: bull,
    };
    let p = run(&s, bull, (0.0, 2.0));
    let w = 2.0 * (2.0 * 2.0 * 0.01 - 1e-4f64).sqrt();
    cam_core::assert_near!(p.pass_v_mm[1] - p.pass_v_mm[0], w * theta.cos(), 1e-12);
    let h = measured_between(&s, &bull, &p, 1, &|v| v + 3.0 + 2.0 * theta.sin());
    cam_core::assert_near!(h, 0.01, 1e-8);
}

#[test]
fn bull_and_flat_effective_radius_on_flat_ground() {
    let (h, bull) = (0.01, Cutter::bull(10.0, 2.0).unwrap());
    let (dm, dp) = Silhouette::new(&bull, 0.0).reach(0.0, h);
    let want = 3.0 + (2.0 * 2.0 * h - h * h).sqrt();
    cam_core::assert_near!(dm + dp, 2.0 * want, 1e-6);
    let w: f64 = 2.0 * want;
    cam_core::assert_near!(
        SideStepModel::new(bull, h).effective_radius(0.0, 0.0),
        ((w / 2.0).powi(2) + h * h) / (2.0 * h),
        1e-9
    );
    // Bull on flat ground: the measured scallop is h at the wider step.
    let s = Tilted {
        m: 0.0,
        cutter: bull,
    };
    let p = run(&s, bull, (0.0, 8.0));
    cam_core::assert_near!(p.pass_v_mm[1] - p.pass_v_mm[0], w, 1e-6);
    let got = measured_between(&s, &bull, &p, 0, &|v| v);
    cam_core::assert_near!(got, h, 1e-6);
    // Flat end mill on a 30° slope: a saw-tooth, w = h / (sin θ cos θ).
    let flat = Cutter::flat(10.0).unwrap();
    let th = 30f64.to_radians();
    let (dm, dp) = Silhouette::new(&flat, 0.0).reach(th, h);
    cam_core::assert_near!(dm + dp, h / (th.sin() * th.cos()), 1e-6);
    let s = Tilted {
        m: th.tan(),
        cutter: flat,
    };
    let p = run(&s, flat, (0.0, 0.3));
    let got = measured_between(&s, &flat, &p, 1, &|v| v + 5.0);
    cam_core::assert_near!(got, h, 1e-6, "flat on slope");
}

/// Planes sloping along the passes (and across them): the scallop forms in the plane
/// perpendicular to the motion, where the cutter shows its outline seen along the motion
/// (bull: radius r + a / sin α at the contact, flat: R / sin α), not its axial profile.
/// The interval is the model's (exact on a plane, no shrinking by the CL-space check), and
/// the scallop measured independently (swept cutter against the part, 3-D distance) is h.
#[test]
fn planes_sloping_along_the_passes_leave_h() {
    let h = 0.01;
    for spec in ["bull:6:1.5", "flat:6", "bull:10:2", "ball:6"] {
        let cutter: Cutter = spec.parse().unwrap();
        let model = SideStepModel::new(cutter, h);
        for (along, across) in [(20.0f64, 0.0f64), (20.0, 15.0), (40.0, 30.0), (5.0, 0.0)] {
            let (mx, my) = (along.to_radians().tan(), across.to_radians().tan());
            let s = Plane { mx, my, cutter };
            let dv = model.xy_interval(mx, my, f64::INFINITY);
            // Three passes at least, whatever the step.
            let p = run(&s, cutter, (0.0, 2.5 * dv));
            assert!(
                p.passes >= 3,
                "{spec} {along}°/{across}°: {} passes",
                p.passes
            );
            let step = p.pass_v_mm[1] - p.pass_v_mm[0];
            cam_core::assert_near!(step, dv, 1e-12, "{spec} {along}°/{across}°");
            // Stations where the swept surface is that of the passes' interior: more than R
            // (a flat end mill's reach uphill from its tip) from where the passes start.
            let off = s.contact_offset().1;
            let got = measured_at(&s, &cutter, &p, 0, &|v| v + off, &[5.5, 6.5, 7.5]);
            eprintln!(
                "plane {spec} along {along}° across {across}°: step {step:.6} mm \
                 (level ground {:.6}), measured scallop {got:.10} mm, h {h}",
                model.xy_interval(0.0, 0.0, f64::INFINITY)
            );
            assert!(
                got <= h * (1.0 + 1e-6) && got >= 0.9 * h,
                "{spec} along {along}° across {across}°: measured {got}"
            );
            cam_core::assert_near!(got, h, 1e-8, "{spec} along {along}° across {across}°");
        }
    }
}

#[test]
fn bull_on_cylinders_stays_below_h() {
    let bull = Cutter::bull(10.0, 2.0).unwrap();
    // Measured where the bull can reach the part: all of the cylinder's top that the passes
    // finish, and the trough's walls outside the bottom its flat bridges (|y| > 3.2).
    for (s, range) in [
        (
            &Cylinder {
                rho: 30.0,
                cutter: bull,
            } as &dyn Analytic,
            (-4.5, 4.5),
        ),
        (
            &Trough {
                rho: 30.0,
                cutter: bull,
            },
            (3.5, 7.0),
        ),
    ] {
        let p = run(s, bull, (-8.0, 8.0));
        let probe = ScallopProbe {
            angle_deg: 0.0,
            stations_u: vec![5.0],
            v_range: range,
            dv_mm: 1e-3,
        };
        let part = |x: f64, y: f64| s.part(x, y);
        let r = measure_scallop(&part, &bull, &p.toolpath, &probe);
        assert!(r.max_gouge_mm < 1e-9);
        assert!(
            r.max_scallop_mm <= 0.01 + 2e-5,
            "bull scallop {} at {:?}",
            r.max_scallop_mm,
            r.at_xy
        );
    }
}

#[test]
fn formula_limits() {
    // Flat limit and the inverse.
    let w = ball_step(3.0, 1e12, 0.01).unwrap();
    cam_core::assert_near!(w, 2.0 * (0.06f64 - 1e-4).sqrt(), 1e-8);
    // Convex allows a longer chord than flat, concave a shorter one.
    assert!(ball_step(3.0, 20.0, 0.01).unwrap() > w);
    assert!(ball_step(3.0, -20.0, 0.01).unwrap() < w);
}

#[test]
fn measurement_sees_a_gouge() {
    let ball = Cutter::ball(6.0).unwrap();
    let s = Tilted {
        m: 0.0,
        cutter: ball,
    };
    let mut p = run(&s, ball, (0.0, 3.0));
    for m in &mut p.toolpath.moves {
        m.pose.tip.z -= 0.05;
    }
    let probe = ScallopProbe {
        angle_deg: 0.0,
        stations_u: vec![5.0],
        v_range: (0.0, 3.0),
        dv_mm: 1e-3,
    };
    let part = |x: f64, y: f64| s.part(x, y);
    let r = measure_scallop(&part, &ball, &p.toolpath, &probe);
    cam_core::assert_near!(r.max_gouge_mm, 0.05, 1e-9);
}

/// The outline along the motion (tables, Newton walks, slopes along the pass, edge arcs) is
/// evaluated in parallel: the plan must not depend on the number of threads.
#[test]
fn bull_on_a_slope_along_the_passes_same_plan_for_one_and_many_threads() {
    let bull = Cutter::bull(6.0, 1.5).unwrap();
    let s = Cylinder {
        rho: 20.0,
        cutter: bull,
    };
    let sampler = UniformSampler {
        u_range: (-10.0, 10.0),
        v_range: (-12.0, 12.0),
        step_mm: 0.37,
    };
    let mut c = cfg(bull);
    c.scallop_mm = 0.05;
    // Passes at 30° to the cylinder's axis: its slope shows along the passes too.
    c.angle_deg = 30.0;
    let a = crate::on_threads(1, || plan(&s, &sampler, &c, None).unwrap());
    let b = crate::on_threads(4, || plan(&s, &sampler, &c, None).unwrap());
    assert!(a.passes > 5, "{} passes", a.passes);
    assert_eq!(a, b);
}
