//! 5-axis swept surfaces against the brute-force envelope (many exact tool instances):
//! paths with lead, tilt and a rotating axis over a plane, a cylinder and a twisted blade,
//! the paper's bull cutter R = 16, r = 3 (bull:38:3).
//!
//! What is measured (see `envelope::sweep_error` and `envelope::line_error`):
//! - vertices: imprint points against the local envelope (moves ±1). They lie on the tool at
//!   their pose, so the error is how far off the characteristic curve they are (motion
//!   direction by central differences, pose spacing) — independent of Q.
//! - centroids: strip triangle centroids against the local envelope: the chord (sagitta) error
//!   of the piecewise-linear joining, across the imprint curve (set by Q) and along the motion
//!   (set by the pose spacing).
//! - lines: first hits along the design surface's normals on the forward ∪ reverse sweep
//!   against the envelope's — what the normal-vector deviation sees — on the paper's
//!   piecewise-linear surface and on the exact surface (crossings refined, see
//!   `cam_verify::measure`).

use cam_core::Cutter;
use cam_verify::envelope::{
    BruteEnvelope, EnvelopeConfig, compare_hits, envelope_hits, line_error, sweep_error,
};
use cam_verify::measure::{SurfaceModel, first_entries};
use cam_verify::model::SweepModel;
use cam_verify::sweep::{SweepConfig, sweep};
use cam_verify::testpaths::{PassSpec, TestSurface, normal_lines, pass};

struct Row {
    q: usize,
    vert_um: f64,
    cent_um: f64,
    line_um: f64,
    line_rms_um: f64,
    exact_um: f64,
    exact_rms_um: f64,
}

fn measure(surface: TestSurface, v: f64) -> Vec<Row> {
    let cutter = Cutter::bull(38.0, 3.0).unwrap();
    let (poses, step) = (16, 1.5);
    let spec = PassSpec {
        surface,
        v_mm: v,
        u0_mm: 0.0,
        poses,
        step_mm: step,
        lead_deg: 8.0,
        lead_wobble_deg: 2.0,
        wobble_period_mm: 30.0,
        tilt_deg: 3.0,
    };
    let path = pass(&spec, &cutter);
    let env = BruteEnvelope::new(
        &path,
        &cutter,
        &EnvelopeConfig {
            instances_per_move: 48,
            ..Default::default()
        },
    );
    let u_end = (poses - 1) as f64 * step;
    let lines = normal_lines(&surface, (6.0, u_end - 6.0), (v - 8.0, v + 8.0), 5, 9, 2.0);
    let truth = envelope_hits(&env, &lines, 40.0, 1e-9);
    [10, 20, 40, 80]
        .into_iter()
        .map(|q| {
            let cfg = SweepConfig {
                inserts: q,
                max_step_mm: 0.25,
                ..SweepConfig::default()
            };
            let fwd = sweep(&path, &cutter, &cfg);
            let rev = sweep(
                &path,
                &cutter,
                &SweepConfig {
                    reverse: true,
                    ..cfg
                },
            );
            let e = sweep_error(&fwd, &env, 7, 1);
            let l = line_error(&[&fwd, &rev], &env, &lines, 40.0, 1e-9);
            assert_eq!(
                l.disagreements + l.misses,
                0,
                "Q {q}: {:?} {:?}",
                l.disagreeing,
                l.disagreeing.iter().map(|d| lines[d.0]).collect::<Vec<_>>()
            );
            let models = [
                SweepModel::new(&path, &cutter, &cfg),
                SweepModel::new(
                    &path,
                    &cutter,
                    &SweepConfig {
                        reverse: true,
                        ..cfg
                    },
                ),
            ];
            let exact = first_entries(
                &[&models[0], &models[1]],
                &path,
                &lines,
                40.0,
                SurfaceModel::Exact,
            );
            let x = compare_hits(&exact, &truth);
            assert_eq!(x.disagreements + x.misses, 0, "Q {q}: {:?}", x.disagreeing);
            Row {
                q,
                vert_um: 1e3 * e.vertices.max_abs_mm,
                cent_um: 1e3 * e.centroids.max_abs_mm,
                line_um: 1e3 * l.stats.max_abs_mm,
                line_rms_um: 1e3 * l.stats.rms_mm,
                exact_um: 1e3 * x.stats.max_abs_mm,
                exact_rms_um: 1e3 * x.stats.rms_mm,
            }
        })
        .collect()
}

/// Asserts what holds (printed with `--nocapture`). Along the design normals (what
/// deviation checking sees):
/// - the paper's linear surface agrees with the envelope with an error that shrinks strictly
///   and at second order with Q (the chord error of `Q/2 + 1` points per imprint curve):
///   Q = 40 gives 30–47 µm max, Q = 80 9–14 µm;
/// - the exact surface (crossings refined onto the continuous imprint surface) agrees within
///   the 2 µm at every Q, in fact to the envelope's own accuracy (< 1 nm; measured
///   ~1e-6 µm; the test asserts 1 nm).
///
/// Vertices and centroids against the local envelope are printed, not asserted: their
/// maxima come from the tool's sides near the demarcations, where the rotating tool's
/// characteristic leaves the corner torus (onto the cylinder or across the flat bottom) and
/// the imprint point is clamped; those parts are walls hidden behind the first hits.
fn check(name: &str, rows: &[Row]) {
    for r in rows {
        println!(
            "{name:>8} Q {:>2}: vertices {:8.3} um, centroids {:8.3} um, lines max {:8.3} um rms {:8.3} um, exact max {:.2e} um rms {:.2e} um",
            r.q, r.vert_um, r.cent_um, r.line_um, r.line_rms_um, r.exact_um, r.exact_rms_um
        );
    }
    for r in rows {
        assert!(
            r.exact_um <= r.line_um,
            "{name}: exact worse than linear at Q {}",
            r.q
        );
        if r.q >= 20 {
            assert!(
                r.exact_um <= 2.0,
                "{name}: exact {} um at Q = {}",
                r.exact_um,
                r.q
            );
            assert!(
                r.exact_um <= 1e-3,
                "{name}: exact {} um at Q = {}",
                r.exact_um,
                r.q
            );
        }
    }
    for w in rows.windows(2) {
        assert!(
            w[1].line_um < w[0].line_um,
            "{name}: line error does not shrink from Q {} to {}",
            w[0].q,
            w[1].q
        );
        assert!(
            w[1].line_rms_um < w[0].line_rms_um,
            "{name}: rms does not shrink from Q {} to {}",
            w[0].q,
            w[1].q
        );
    }
    let (q40, q80) = (&rows[2], &rows[3]);
    assert!(
        q80.line_rms_um * 3.0 <= q40.line_rms_um,
        "{name}: not second order from Q 40 to 80"
    );
    assert!(q80.line_um <= 15.0, "{name}: {} um at Q = 80", q80.line_um);
}

#[test]
fn plane_with_lead_tilt_and_rotating_axis() {
    check("plane", &measure(TestSurface::Plane, 0.0));
}

#[test]
fn cylinder_with_lead_tilt_and_rotating_axis() {
    check(
        "cylinder",
        &measure(TestSurface::Cylinder { radius_mm: 80.0 }, 0.0),
    );
}

#[test]
fn twisted_blade_with_lead_tilt_and_rotating_axis() {
    check(
        "blade",
        &measure(
            TestSurface::Blade {
                twist_rad_per_mm: 0.004,
            },
            20.0,
        ),
    );
}

/// The exact first entries along `lines` (forward and reverse sweeps, Q = 40, 0.25 mm
/// steps, within 40 mm) against the brute-force envelope's (48 instances per move, refined
/// to 1e-9 mm).
fn exact_against_envelope(
    path: &cam_core::Toolpath,
    cutter: &Cutter,
    lines: &[(cam_core::DVec3, cam_core::DVec3)],
) -> cam_verify::envelope::LineErrorReport {
    let env = BruteEnvelope::new(
        path,
        cutter,
        &EnvelopeConfig {
            instances_per_move: 48,
            ..Default::default()
        },
    );
    let truth = envelope_hits(&env, lines, 40.0, 1e-9);
    let cfg = SweepConfig {
        inserts: 40,
        max_step_mm: 0.25,
        ..SweepConfig::default()
    };
    let reverse = SweepConfig {
        reverse: true,
        ..cfg
    };
    let models = [
        SweepModel::new(path, cutter, &cfg),
        SweepModel::new(path, cutter, &reverse),
    ];
    let exact = first_entries(
        &[&models[0], &models[1]],
        path,
        lines,
        40.0,
        SurfaceModel::Exact,
    );
    compare_hits(&exact, &truth)
}

/// A multi-pass program: a zig-zag of four overlapping 5-axis passes (bull:10:2, stepover
/// 2.5 mm, lead 8° ± 3°, tilt 3°) over the twisted blade, where a line near the surface
/// meets the volumes of several passes and many moves whose columns and pucks the
/// measurement skips by their closed-form hulls. The exact first entries along the blade's
/// normals must equal the brute-force envelope's (tool instances refined to 1e-9 mm) to
/// 1 nm, every line hitting.
#[test]
fn overlapping_passes_read_the_envelope() {
    let cutter = Cutter::bull(10.0, 2.0).unwrap();
    let surface = TestSurface::Blade {
        twist_rad_per_mm: 0.01,
    };
    let spec = PassSpec {
        surface,
        v_mm: -4.0,
        u0_mm: 0.0,
        poses: 24,
        step_mm: 1.0,
        lead_deg: 8.0,
        lead_wobble_deg: 3.0,
        wobble_period_mm: 11.0,
        tilt_deg: 3.0,
    };
    let path = cam_verify::testpaths::zigzag(&spec, 4, 2.5, &cutter);
    let lines = normal_lines(&surface, (5.0, 18.0), (-3.0, 3.5), 6, 9, 2.0);
    let x = exact_against_envelope(&path, &cutter, &lines);
    println!(
        "zig-zag: {} lines, exact against the envelope max {:.2e} mm, rms {:.2e} mm",
        lines.len(),
        x.stats.max_abs_mm,
        x.stats.rms_mm
    );
    assert_eq!(x.disagreements + x.misses, 0, "{:?}", x.disagreeing);
    assert!(x.stats.max_abs_mm <= 1e-6, "{}", x.stats.max_abs_mm);
}

/// Where passes start and end: the tool at a pass's first pose is a cap of the swept
/// surface, which can stand in front of its own move's sheet (the line enters the first
/// pose's puck later than it enters the move's, a few hundredths of a pose on). The 986
/// lines over the ends of a zig-zag of two 5-axis passes (bull:10:2, lead 5° ± 3°, tilt 2°,
/// 0.5 mm poses) must read the brute-force envelope to 1e-6 mm (taking the cap's reading
/// there was up to 3.5e-4 mm late).
#[test]
fn pass_ends_read_the_envelope() {
    let cutter = Cutter::bull(10.0, 2.0).unwrap();
    let surface = TestSurface::Blade {
        twist_rad_per_mm: 0.01,
    };
    let spec = PassSpec {
        surface,
        v_mm: -1.0,
        u0_mm: 0.0,
        poses: 21,
        step_mm: 0.5,
        lead_deg: 5.0,
        lead_wobble_deg: 3.0,
        wobble_period_mm: 17.0,
        tilt_deg: 2.0,
    };
    let path = cam_verify::testpaths::zigzag(&spec, 2, 2.0, &cutter);
    let mut lines = normal_lines(&surface, (-0.3, 0.5), (-4.0, 3.0), 17, 29, 2.0);
    lines.extend(normal_lines(
        &surface,
        (9.5, 10.3),
        (-4.0, 3.0),
        17,
        29,
        2.0,
    ));
    let x = exact_against_envelope(&path, &cutter, &lines);
    println!(
        "pass ends: {} lines, {} hit, exact against the envelope max {:.2e} mm",
        lines.len(),
        lines.len() - x.misses,
        x.stats.max_abs_mm
    );
    assert_eq!(x.disagreements, 0, "{:?}", x.disagreeing);
    assert!(x.misses < lines.len() / 2, "{} misses", x.misses);
    assert!(x.stats.max_abs_mm <= 1e-6, "{}", x.stats.max_abs_mm);
}
