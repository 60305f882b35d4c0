//! Impossible configurations are typed errors with clear messages, never panics.

use cam_sample::{
    MAX_POINTS, Profile, SampleConfig, SampleError, resample_u, sample_part, try_resample_u,
};

use crate::fixtures::load;
use crate::util::grid_mesh;

#[test]
fn invalid_configs_are_rejected() {
    let m = grid_mesh((0.0, 0.0), (4, 4), 1.0, |_, _| 0.0, |_, _| true);
    let ok = SampleConfig {
        angle_deg: 0.0,
        plane_spacing_mm: 1.0,
        arc_step_mm: 0.5,
    };
    assert!(sample_part(&m, &ok).is_ok());
    for (cfg, field) in [
        (
            SampleConfig {
                arc_step_mm: 0.0,
                ..ok
            },
            "arc_step_mm",
        ),
        (
            SampleConfig {
                arc_step_mm: -1.0,
                ..ok
            },
            "arc_step_mm",
        ),
        (
            SampleConfig {
                arc_step_mm: f64::NAN,
                ..ok
            },
            "arc_step_mm",
        ),
        (
            SampleConfig {
                arc_step_mm: f64::INFINITY,
                ..ok
            },
            "arc_step_mm",
        ),
        (
            SampleConfig {
                plane_spacing_mm: 0.0,
                ..ok
            },
            "plane_spacing_mm",
        ),
        (
            SampleConfig {
                plane_spacing_mm: -0.5,
                ..ok
            },
            "plane_spacing_mm",
        ),
        (
            SampleConfig {
                plane_spacing_mm: f64::NAN,
                ..ok
            },
            "plane_spacing_mm",
        ),
        (
            SampleConfig {
                angle_deg: f64::NAN,
                ..ok
            },
            "angle_deg",
        ),
        (
            SampleConfig {
                angle_deg: f64::NEG_INFINITY,
                ..ok
            },
            "angle_deg",
        ),
    ] {
        match sample_part(&m, &cfg) {
            Err(e @ SampleError::InvalidConfig { field: f, .. }) => {
                assert_eq!(f, field);
                let msg = e.to_string();
                assert!(msg.contains(field), "{msg}");
            }
            other => panic!("{cfg:?}: expected InvalidConfig, got {other:?}"),
        }
    }
}

#[test]
fn too_many_planes_or_points() {
    let m = load("ocl_mount_rush.stl");
    let cfg = SampleConfig {
        angle_deg: 0.0,
        plane_spacing_mm: 1e-9,
        arc_step_mm: 0.5,
    };
    match sample_part(&m, &cfg) {
        Err(e @ SampleError::TooManyPlanes { limit, .. }) => {
            assert_eq!(limit, MAX_POINTS);
            assert!(e.to_string().contains("plane_spacing_mm"), "{e}");
        }
        other => panic!("expected TooManyPlanes, got {other:?}"),
    }
    // 44 planes of ~100 mm arc at 1 µm: ~4.4M points fits; at 10 nm it does not.
    let cfg = SampleConfig {
        angle_deg: 0.0,
        plane_spacing_mm: 1.0,
        arc_step_mm: 1e-8,
    };
    match sample_part(&m, &cfg) {
        Err(e @ SampleError::TooManyPoints { estimated, .. }) => {
            assert!(estimated > MAX_POINTS as f64);
            assert!(e.to_string().contains("arc_step_mm"), "{e}");
        }
        other => panic!("expected TooManyPoints, got {other:?}"),
    }
}

#[test]
fn resample_degenerate_inputs() {
    let p = Profile {
        points: vec![(0.0, 0.0), (4.0, 3.0)],
    };
    assert_eq!(resample_u(&p, -1.0), vec![0.0, 4.0]);
    assert!(matches!(
        try_resample_u(&p, 0.0),
        Err(SampleError::InvalidConfig { .. })
    ));
    assert!(matches!(
        try_resample_u(&p, 1e-9),
        Err(SampleError::TooManyPoints { .. })
    ));
    // Arc 5 at step 1: u steps of 0.8.
    let us = resample_u(&p, 1.0);
    assert_eq!(us.len(), 6);
    for (k, u) in us.iter().enumerate() {
        cam_core::assert_near!(*u, 0.8 * k as f64, 1e-15);
    }
    assert_eq!(
        resample_u(
            &Profile {
                points: vec![(1.0, 1.0)]
            },
            1.0
        ),
        vec![1.0]
    );
}
