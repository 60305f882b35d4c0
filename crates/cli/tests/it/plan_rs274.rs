//! Planned programs through the real client: for each cutter, a plan of dome.obj posted by
//! every post in mm and in inch runs through LinuxCNC's `rs274` without error, and its
//! canonical motions reproduce the planned tool tips (1e-4 mm in mm; in inch, what the
//! program's and rs274's 4–5 decimals allow). Skipped when `rs274` is missing, except on CI
//! (`CI=true`), where a missing `rs274` fails the test.

use cam_core::{Mesh, MoveKind, Units};
use cam_gcode::rs274::{CanonKind, rs274_for_tests, run_rs274};
use cam_gcode::{Post, PostJob, post_to_string};
use cam_plan::{PlanConfig, plan_part};

use crate::support::root;

#[test]
fn planned_programs_run_in_rs274_and_reproduce_the_tips() {
    if !rs274_for_tests() {
        return;
    }
    let mesh = Mesh::load(root().join("fixtures/parts/dome.obj"), Units::Mm).unwrap();
    let dir = tempfile::tempdir().unwrap();
    for spec in ["ball:6", "bull:6:1.5", "flat:6"] {
        let cfg = PlanConfig {
            cutter: spec.parse().unwrap(),
            tolerance_mm: 0.01,
            scallop_mm: 0.05,
            boundary: Some((-24.0, 24.0, -3.0, 3.0)),
            ..PlanConfig::default()
        };
        let plan = plan_part(&mesh, &cfg, None).unwrap();
        let tp = &plan.toolpath;
        assert!(tp.moves.len() > 100, "{spec}: {} moves", tp.moves.len());
        for post in Post::ALL {
            for units in [Units::Mm, Units::Inch] {
                let job = PostJob {
                    part_name: "dome.obj".into(),
                    tool_spec: spec.into(),
                    tolerance_mm: cfg.tolerance_mm,
                    scallop_mm: cfg.scallop_mm,
                    safe_z_mm: plan.safe_z_mm,
                    units,
                    ..PostJob::default()
                };
                let text = post_to_string(tp, &job, post).unwrap();
                let file = dir.path().join(format!(
                    "dome_{}_{post}_{units}.ngc",
                    spec.replace(':', "_")
                ));
                std::fs::write(&file, &text).unwrap();
                let canon =
                    run_rs274(&file).unwrap_or_else(|e| panic!("{spec} {post} {units}: {e}"));
                // rs274 starts at the origin: the preamble's `G0 Z<safe>` is one extra traverse.
                assert_eq!(canon.len(), tp.moves.len() + 1, "{spec} {post} {units}");
                assert_eq!(canon[0].kind, CanonKind::Traverse);
                // Program rounding (half a unit of 4 decimals in mm, 5 in inch) plus canon's
                // own 4 decimals in program units.
                let bound_mm = match units {
                    Units::Mm => 1e-4,
                    Units::Inch => (0.5e-4 + 0.5e-5) * units.mm_per_unit() + 1e-9,
                };
                let mut max_mm: f64 = 0.0;
                for (m, c) in tp.moves.iter().zip(&canon[1..]) {
                    let want = if m.kind == MoveKind::Rapid {
                        CanonKind::Traverse
                    } else {
                        CanonKind::Feed
                    };
                    assert_eq!(
                        c.kind, want,
                        "{spec} {post} {units} canon line {}",
                        c.canon_line
                    );
                    max_mm = max_mm.max((c.tip_mm() - m.pose.tip).abs().max_element());
                }
                eprintln!(
                    "rs274 dome.obj {spec} {post} {units}: {} moves, max |Δtip| = {max_mm:.3e} mm \
                     (bound {bound_mm:.3e})",
                    tp.moves.len()
                );
                assert!(max_mm <= bound_mm, "{spec} {post} {units}: {max_mm:e} mm");
            }
        }
    }
}
