//! Prints the error of the swept surface against the brute-force envelope for 5-axis passes
//! (bull R = 16, r = 3, i.e. `bull:38:3`) over a plane, a cylinder and a twisted blade, for
//! Q = 10, 20, 40, 80, 160: first hits along design-surface normals (forward and back-gouge
//! sweeps together), on the paper's piecewise-linear imprint surface ("linear") and with
//! every crossing refined onto the exact swept volume ("exact"), each against the envelope's
//! first hit (2000 exact tool instances per move refined by golden section, sphere-traced to
//! 1e-9 mm). The envelope models the cutter's lower part (corner torus and flat bottom, no
//! cylinder above it), as the verifier does. Also the signed distances of the linear
//! surface's strip vertices (imprint points) and triangle centroids to the local envelope
//! (moves within ±1 of the triangle's). "lines": lines both hit, of all lines, for the linear
//! and the exact surface (the others neither hits: the pass edges beyond the tool's reach).
//!
//! `cargo run --release -p cam-verify --example five_axis_error [poses] [step_mm] [max_step_mm] [every] [lead_wobble_deg]`

use cam_core::Cutter;
use cam_verify::envelope::{
    BruteEnvelope, EnvelopeConfig, compare_hits, envelope_hits, sweep_error,
};
use cam_verify::measure::{SurfaceModel, first_entries};
use cam_verify::model::SweepModel;
use cam_verify::sweep::{SweepConfig, SweptSurface};
use cam_verify::testpaths::{PassSpec, TestSurface, normal_lines, pass};

fn main() {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let poses = args.first().copied().unwrap_or(100.0) as usize;
    let step = args.get(1).copied().unwrap_or(1.5);
    let max_step = args.get(2).copied().unwrap_or(0.25);
    let every = args.get(3).copied().unwrap_or(1.0) as usize;
    let wobble = args.get(4).copied().unwrap_or(2.0);
    let cutter = Cutter::bull(38.0, 3.0).expect("valid cutter");
    let surfaces = [
        ("plane", TestSurface::Plane, 0.0),
        ("cylinder", TestSurface::Cylinder { radius_mm: 80.0 }, 0.0),
        (
            "blade",
            TestSurface::Blade {
                twist_rad_per_mm: 0.004,
            },
            20.0,
        ),
    ];
    println!(
        "bull:38:3 (R=16, r=3), {poses} poses, step {step} mm, max_step {max_step} mm, lead 8±{wobble} deg, tilt 3 deg, every {every}th strip triangle"
    );
    println!(
        "{:>9} {:>3} {:>6} | {:>9} {:>9} | {:>9} {:>9} | {:>10} {:>10} | {:>10} {:>10} | {:>7}",
        "surface",
        "Q",
        "tris",
        "vert max",
        "vert rms",
        "cent max",
        "cent rms",
        "linear max",
        "linear rms",
        "exact max",
        "exact rms",
        "lines"
    );
    for (name, surface, v) in surfaces {
        let u0 = -0.5 * poses as f64 * step;
        let spec = PassSpec {
            surface,
            v_mm: v,
            u0_mm: u0,
            poses,
            step_mm: step,
            lead_deg: 8.0,
            lead_wobble_deg: wobble,
            wobble_period_mm: 60.0,
            tilt_deg: 3.0,
        };
        let path = pass(&spec, &cutter);
        // The cutter's lower part, as the verifier models it (the real cutter's cylinder
        // continues upward from the corner; lines near the pass edges could meet it first).
        let env = BruteEnvelope::new(
            &path,
            &cutter,
            &EnvelopeConfig {
                height_mm: Some(2.0 * cutter.corner_radius()),
                ..EnvelopeConfig::default()
            },
        );
        let u_end = u0 + (poses - 1) as f64 * step;
        let lines = normal_lines(
            &surface,
            (u0 + 20.0, u_end - 20.0),
            (v - 12.0, v + 12.0),
            25,
            13,
            2.0,
        );
        let truth = envelope_hits(&env, &lines, 40.0, 1e-9);
        for q in [10usize, 20, 40, 80, 160] {
            let cfg = SweepConfig {
                inserts: q,
                max_step_mm: max_step,
                ..SweepConfig::default()
            };
            let fwd = SweepModel::new(&path, &cutter, &cfg);
            let rev = SweepModel::new(
                &path,
                &cutter,
                &SweepConfig {
                    reverse: true,
                    ..cfg
                },
            );
            let models = [&fwd, &rev];
            let lin = first_entries(&models, &path, &lines, 40.0, SurfaceModel::Linear);
            let ex = first_entries(&models, &path, &lines, 40.0, SurfaceModel::Exact);
            let (l, x) = (compare_hits(&lin, &truth), compare_hits(&ex, &truth));
            let surf = SweptSurface::from_model(&fwd);
            let e = sweep_error(&surf, &env, every, 1);
            println!(
                "{name:>9} {q:>3} {:>6} | {:>7.3}um {:>7.3}um | {:>7.3}um {:>7.3}um | {:>8.3}um {:>8.3}um | {:>8.1e}um {:>8.1e}um | {:>3}/{} {}/{}",
                surf.triangles.len(),
                1e3 * e.vertices.max_abs_mm,
                1e3 * e.vertices.rms_mm,
                1e3 * e.centroids.max_abs_mm,
                1e3 * e.centroids.rms_mm,
                1e3 * l.stats.max_abs_mm,
                1e3 * l.stats.rms_mm,
                1e3 * x.stats.max_abs_mm,
                1e3 * x.stats.rms_mm,
                l.stats.count,
                lines.len(),
                x.stats.count,
                lines.len(),
            );
        }
    }
}
