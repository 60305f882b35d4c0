//! Impossible settings are typed errors.

use cam_core::Cutter;
use cam_plan::{PlanConfig, PlanError, UniformSampler, plan};

use crate::surfaces::{Tilted, cfg};

#[test]
fn bad_values_are_rejected() {
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
    let base = cfg(ball);
    type Case = (PlanConfig, fn(&PlanError) -> bool);
    let cases: Vec<Case> = vec![
        (
            PlanConfig {
                tolerance_mm: 0.0,
                ..base
            },
            |e| matches!(e, PlanError::Tolerance(_)),
        ),
        (
            PlanConfig {
                tolerance_mm: f64::NAN,
                ..base
            },
            |e| matches!(e, PlanError::Tolerance(_)),
        ),
        (
            PlanConfig {
                scallop_mm: -1.0,
                ..base
            },
            |e| matches!(e, PlanError::Scallop(_)),
        ),
        (
            PlanConfig {
                scallop_mm: 3.0,
                ..base
            },
            |e| matches!(e, PlanError::ScallopTooLarge { .. }),
        ),
        (
            PlanConfig {
                angle_deg: f64::INFINITY,
                ..base
            },
            |e| matches!(e, PlanError::Angle(_)),
        ),
        (
            PlanConfig {
                safe_z_mm: Some(-1.0),
                ..base
            },
            |e| matches!(e, PlanError::SafeZ { .. }),
        ),
        (
            PlanConfig {
                boundary: Some((1.0, 0.0, 0.0, 1.0)),
                ..base
            },
            |e| matches!(e, PlanError::Boundary(_)),
        ),
        (
            PlanConfig {
                check_spacing_mm: Some(10.0),
                ..base
            },
            |e| matches!(e, PlanError::CheckSpacing(_)),
        ),
        (
            PlanConfig {
                max_step_mm: Some(0.0),
                ..base
            },
            |e| matches!(e, PlanError::MaxStep(_)),
        ),
        (
            PlanConfig {
                boundary: Some((100.0, 101.0, 100.0, 101.0)),
                ..base
            },
            |e| matches!(e, PlanError::NothingToCut),
        ),
    ];
    for (c, want) in cases {
        let e = plan(&s, &sampler, &c, None).unwrap_err();
        assert!(want(&e), "{e}");
    }
    let nothing = |_: f64, _: f64| None;
    assert_eq!(
        plan(&nothing, &sampler, &base, None).unwrap_err(),
        PlanError::NothingToCut
    );
}
