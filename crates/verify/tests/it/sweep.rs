//! Swept surfaces of 3-axis passes against the analytic groove, hole-freeness, export and
//! thread independence.

use cam_core::{Cutter, DVec3, Move, MoveKind, Pose, Toolpath};
use cam_verify::envelope::{BruteEnvelope, EnvelopeConfig, line_error};
use cam_verify::sweep::{
    FacetKind, SweepConfig, SweptSurface, first_hit, sweep, write_obj, write_ply, write_stl,
};
use cam_verify::testpaths::straight;

/// Distance in XY from `p` to the segment `a b`.
fn xy_distance(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let (p, a, b) = (p.truncate(), a.truncate(), b.truncate());
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    p.distance(a + t * ab)
}

/// Lowest hit from below at (x, y), as a z.
fn lowest(s: &SweptSurface, x: f64, y: f64) -> Option<f64> {
    first_hit(s, DVec3::new(x, y, -10.0), DVec3::Z, 100.0).map(|t| t - 10.0)
}

/// A horizontal straight pass cuts a groove whose cross-section is the tool profile:
/// z(d) = height_at(d), d = XY distance from the tip path. The flat part is exact; the corner
/// is a polyline through exact points (inscribed), so the surface may lie above the corner by
/// at most its chord sagitta and below never.
#[test]
fn horizontal_pass_is_the_tool_profile() {
    for cutter in [
        Cutter::bull(10.0, 2.0).unwrap(),
        Cutter::ball(6.0).unwrap(),
        Cutter::flat(8.0).unwrap(),
    ] {
        let (a, b) = (DVec3::ZERO, DVec3::new(20.0, 0.0, 0.0));
        let s = sweep(&straight(a, b), &cutter, &SweepConfig::default());
        let big_r = cutter.radius();
        let (mut worst_flat, mut worst_corner, mut holes) = (0.0f64, 0.0f64, 0);
        let n = 61;
        for i in 0..n {
            for j in 0..n {
                let x = -big_r + (20.0 + 2.0 * big_r) * i as f64 / (n - 1) as f64;
                let y = -big_r + 2.0 * big_r * j as f64 / (n - 1) as f64;
                let d = xy_distance(DVec3::new(x, y, 0.0), a, b);
                if d > 0.98 * big_r {
                    continue;
                }
                let Some(z) = lowest(&s, x, y) else {
                    holes += 1;
                    continue;
                };
                let exact = cutter.height_at(d).unwrap();
                // Inscribed polygon of the rim: exact inside a·cos(π/Q).
                if d <= cutter.major_radius() * (std::f64::consts::PI / 40.0).cos() {
                    worst_flat = worst_flat.max((z - exact).abs());
                } else {
                    assert!(
                        z >= exact - 1e-9,
                        "{cutter}: below the tool at ({x}, {y}): {z} < {exact}"
                    );
                    worst_corner = worst_corner.max(z - exact);
                }
            }
        }
        println!(
            "{cutter}: holes {holes}, flat |dz| {worst_flat:.2e}, corner dz {worst_corner:.2e}"
        );
        assert_eq!(holes, 0, "{cutter}");
        assert!(worst_flat < 1e-9, "{cutter}: {worst_flat}");
        // Sagitta bound: the polylines step at most 9° along the profile (strips and Q/4 cap
        // rings) and around the rim (Q = 40 cap sectors); each chord lies within
        // ρ(1 − cos 4.5°) of the surface along its normal, ρ ≤ r + R, which is at most
        // `slope` times that vertically, slope = the corner's dz/dd at the 0.98·R cut-off.
        let (a0, r0) = (cutter.major_radius(), cutter.corner_radius());
        let c = 1.0 - (4.5f64).to_radians().cos();
        let t = 0.98 * big_r - a0;
        let slope = if r0 > 0.0 {
            (1.0 + (t / (r0 * r0 - t * t).sqrt()).powi(2)).sqrt()
        } else {
            1.0
        };
        let bound = (r0 + big_r) * c * slope;
        assert!(worst_corner <= bound, "{cutter}: {worst_corner} > {bound}");
    }
}

/// A 3-axis ramp and a zig-zag with a reversal agree with the brute-force envelope along
/// vertical lines, with no holes.
#[test]
fn ramp_and_zigzag_agree_with_brute_force() {
    let cutter = Cutter::bull(10.0, 2.0).unwrap();
    let mk = |kind, tip| Move {
        kind,
        pose: Pose::vertical(tip),
        feed_mm_per_min: None,
        line: None,
        pass: None,
    };
    let path = Toolpath {
        moves: vec![
            mk(MoveKind::Rapid, DVec3::new(0.0, 0.0, 0.0)),
            mk(MoveKind::Cut, DVec3::new(15.0, 0.0, 3.0)),
            mk(MoveKind::Cut, DVec3::new(15.0, 4.0, 3.0)),
            mk(MoveKind::Cut, DVec3::new(0.0, 4.0, 0.5)),
        ],
    };
    let s = sweep(&path, &cutter, &SweepConfig::default());
    let caps = s.kind.iter().filter(|k| **k == FacetKind::Cap).count();
    assert!(caps > 0);
    let env = BruteEnvelope::new(
        &path,
        &cutter,
        &EnvelopeConfig {
            instances_per_move: 200,
            ..Default::default()
        },
    );
    let mut lines = Vec::new();
    for i in 0..24 {
        for j in 0..12 {
            let (x, y) = (-3.0 + 21.0 * i as f64 / 23.0, -3.0 + 10.0 * j as f64 / 11.0);
            lines.push((DVec3::new(x, y, -5.0), DVec3::Z));
        }
    }
    let rep = line_error(&[&s], &env, &lines, 30.0, 1e-9);
    println!("3-axis ramp + zig-zag, Q = 40: {rep:?}");
    assert_eq!(rep.disagreements, 0);
    // The lines meet the flat bottom, the corner and the caps; the polylines (9° steps) lie
    // inside the tool by up to (r + R)(1 − cos 4.5°) = 21.6 µm along the normal. Measured on
    // 2026-11-22: max 18.7 µm, rms 6.1 µm, never deeper than the tool reaches.
    assert!(rep.stats.max_abs_mm < 0.02, "{rep:?}");
    assert!(
        rep.stats.min_mm > -1e-6,
        "swept surface deeper than the tool reaches: {rep:?}"
    );
}

/// A repeated pose (no motion) changes nothing; the sweep is independent of thread count.
#[test]
fn no_motion_and_threads() {
    let cutter = Cutter::bull(10.0, 2.0).unwrap();
    let mk = |kind, tip| Move {
        kind,
        pose: Pose::vertical(tip),
        feed_mm_per_min: None,
        line: None,
        pass: None,
    };
    let p = [
        DVec3::ZERO,
        DVec3::new(5.0, 1.0, 0.5),
        DVec3::new(9.0, 3.0, 0.2),
    ];
    let plain = Toolpath {
        moves: vec![
            mk(MoveKind::Rapid, p[0]),
            mk(MoveKind::Cut, p[1]),
            mk(MoveKind::Cut, p[2]),
        ],
    };
    let dup = Toolpath {
        moves: vec![
            mk(MoveKind::Rapid, p[0]),
            mk(MoveKind::Cut, p[1]),
            mk(MoveKind::Cut, p[1]),
            mk(MoveKind::Cut, p[2]),
        ],
    };
    let cfg = SweepConfig::default();
    let a = sweep(&plain, &cutter, &cfg);
    let b = sweep(&dup, &cutter, &cfg);
    assert_eq!(a.triangles, b.triangles);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| sweep(&plain, &cutter, &cfg));
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap()
        .install(|| sweep(&plain, &cutter, &cfg));
    assert_eq!(one, two);
    assert_eq!(one, a);
}

/// Rapids do not sweep; each feed stretch gets its caps.
#[test]
fn rapids_do_not_sweep() {
    let cutter = Cutter::ball(6.0).unwrap();
    let mk = |kind, tip| Move {
        kind,
        pose: Pose::vertical(tip),
        feed_mm_per_min: None,
        line: None,
        pass: None,
    };
    let path = Toolpath {
        moves: vec![
            mk(MoveKind::Rapid, DVec3::ZERO),
            mk(MoveKind::Cut, DVec3::new(10.0, 0.0, 0.0)),
            mk(MoveKind::Rapid, DVec3::new(10.0, 20.0, 0.0)),
            mk(MoveKind::Cut, DVec3::new(0.0, 20.0, 0.0)),
        ],
    };
    let s = sweep(&path, &cutter, &SweepConfig::default());
    assert!(
        s.source_move.iter().all(|&m| m == 1 || m == 3),
        "{:?}",
        s.source_move
    );
    assert!(lowest(&s, 5.0, 10.0).is_none(), "the rapid swept");
    assert!(lowest(&s, 5.0, 0.0).is_some() && lowest(&s, 5.0, 20.0).is_some());
}

/// OBJ, STL and PLY carry every triangle.
#[test]
fn export_formats() {
    let cutter = Cutter::bull(10.0, 2.0).unwrap();
    let s = sweep(
        &straight(DVec3::ZERO, DVec3::new(5.0, 0.0, 1.0)),
        &cutter,
        &SweepConfig::default(),
    );
    let n = s.triangles.len();
    let mut stl = Vec::new();
    write_stl(&s, &mut stl).unwrap();
    let back = cam_core::io::stl::parse_stl(&stl, std::path::Path::new("s.stl")).unwrap();
    assert_eq!(back.len(), n);
    let mut obj = Vec::new();
    write_obj(&s, &mut obj).unwrap();
    let obj = String::from_utf8(obj).unwrap();
    assert_eq!(obj.lines().filter(|l| l.starts_with("f ")).count(), n);
    let mut ply = Vec::new();
    write_ply(&s, &mut ply).unwrap();
    let ply = String::from_utf8(ply).unwrap();
    assert!(ply.contains(&format!("element face {n}")));
    assert_eq!(
        ply.lines().count(),
        3 * n + n + ply.lines().position(|l| l == "end_header").unwrap() + 1
    );
}

/// The reverse sweep imprints the other half: for an uphill bull:10:2 move with slope 0.2,
/// the heel. Its Eq. 2 solutions fall inside the ring and are clamped to the flat bottom's
/// rim (or, near the demarcations, to the equator), so every strip vertex is one of those,
/// behind the tip under it.
#[test]
fn reverse_sweep_imprints_the_heel() {
    let cutter = Cutter::bull(10.0, 2.0).unwrap();
    let (a, b) = (DVec3::ZERO, DVec3::new(10.0, 0.0, 2.0));
    let rev = sweep(
        &straight(a, b),
        &cutter,
        &SweepConfig {
            reverse: true,
            ..SweepConfig::default()
        },
    );
    let heel: Vec<DVec3> = rev
        .triangles
        .iter()
        .zip(&rev.kind)
        .filter(|(_, k)| **k == FacetKind::Strip)
        .flat_map(|(t, _)| t.v)
        .collect();
    assert!(!heel.is_empty());
    let (mut rim, mut side) = (0, 0);
    for v in heel {
        // Rim point: at tip height, 3 mm from the axis, behind it.
        let tip_x = 5.0 * v.z;
        if (0.0..=10.0).contains(&tip_x)
            && ((v.x - tip_x).hypot(v.y) - 3.0).abs() < 1e-9
            && v.x <= tip_x + 1e-9
        {
            rim += 1;
            continue;
        }
        // Equator point (clamped from above the equator, or a demarcation side point): centre
        // height (2 mm above the tip), 5 mm from the axis, not in front of it.
        let tip_x = 5.0 * (v.z - 2.0);
        assert!(
            (0.0..=10.0).contains(&tip_x)
                && ((v.x - tip_x).hypot(v.y) - 5.0).abs() < 1e-9
                && v.x <= tip_x + 1e-9,
            "heel vertex {v} neither on the rim nor on the equator behind the tip"
        );
        side += 1;
    }
    assert!(rim > side, "rim {rim}, side {side}");
}
