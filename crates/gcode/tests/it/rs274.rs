//! The real client: every post's output through LinuxCNC's `rs274`; its canonical motions must
//! match the planned tool-tip points. Skipped when `rs274` is missing, except on CI
//! (`CI=true`), where a missing `rs274` fails the test.

use crate::post::job;
use crate::support::{mv, small_path};
use cam_core::{MoveKind, Toolpath, Units};
use cam_gcode::rs274::{CanonKind, Rs274Error, rs274_for_tests, run_rs274};
use cam_gcode::{Post, post_to_string};

/// Zig-zag rows over a spherical cap (R 40) with retract/rapid links: 8 rows × 41 points.
fn cap_path() -> Toolpath {
    let z = |x: f64, y: f64| (1600.0 - x * x - y * y).max(0.0).sqrt() - 35.0;
    let mut m = vec![mv(MoveKind::Rapid, -10.0, -10.0, 8.0)];
    for row in 0..8 {
        let y = -10.0 + row as f64 * 20.0 / 7.0;
        let xs: Vec<f64> = (0..=40)
            .map(|i| -10.0 + i as f64 * 0.5 + 0.000_037 * row as f64)
            .collect();
        let xs: Vec<f64> = if row % 2 == 0 {
            xs
        } else {
            xs.into_iter().rev().collect()
        };
        if row > 0 {
            m.push(mv(MoveKind::Rapid, xs[0], y, 8.0));
        }
        m.push(mv(MoveKind::Plunge, xs[0], y, z(xs[0], y)));
        for &x in &xs[1..] {
            m.push(mv(MoveKind::Cut, x, y, z(x, y)));
        }
        let last = m.last().unwrap().pose.tip;
        m.push(mv(MoveKind::Rapid, last.x, last.y, 8.0));
    }
    Toolpath { moves: m }
}

#[test]
fn rs274_runs_every_post_and_reproduces_the_tool_tips() {
    if !rs274_for_tests() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for (pname, tp, safe) in [("small", small_path(), 5.0), ("cap", cap_path(), 8.0)] {
        for p in Post::ALL {
            for units in [Units::Mm, Units::Inch] {
                let j = cam_gcode::PostJob {
                    safe_z_mm: safe,
                    ..job(units)
                };
                let text = post_to_string(&tp, &j, p).unwrap();
                let file = dir.path().join(format!("{pname}_{p}_{units}.ngc"));
                std::fs::write(&file, &text).unwrap();
                let canon = run_rs274(&file).unwrap_or_else(|e| panic!("{p} {units}: {e}"));
                // rs274 starts at the origin: the preamble `G0 Z<safe>` is one extra traverse.
                assert_eq!(canon.len(), tp.moves.len() + 1, "{p} {units}");
                assert_eq!(canon[0].kind, CanonKind::Traverse);
                let k = units.mm_per_unit();
                // Program rounding (half a unit of 4 decimals in mm, 5 in inch) plus canon's
                // own 4 decimals in program units (so in inch mode the canon rounding alone
                // is up to 0.00005 in = 1.27 µm: 1e-4 mm cannot be met there).
                let bound_mm = match units {
                    Units::Mm => 1e-4,
                    Units::Inch => (0.5e-4 + 0.5e-5) * k + 1e-9,
                };
                assert!((canon[0].tip_mm().z - safe).abs() <= bound_mm);
                let mut max_mm: f64 = 0.0;
                for (m, c) in tp.moves.iter().zip(&canon[1..]) {
                    assert_eq!(c.units, units);
                    let want = if m.kind == MoveKind::Rapid {
                        CanonKind::Traverse
                    } else {
                        CanonKind::Feed
                    };
                    assert_eq!(c.kind, want, "{p} {units} canon line {}", c.canon_line);
                    max_mm = max_mm.max((c.tip_mm() - m.pose.tip).abs().max_element());
                }
                println!(
                    "rs274 {pname} {p} {units}: {} moves, max |Δtip| = {max_mm:.3e} mm (bound {bound_mm:.3e})",
                    tp.moves.len()
                );
                assert!(max_mm <= bound_mm, "{pname} {p} {units}: {max_mm:e} mm");
            }
        }
    }
}

#[test]
fn rs274_errors_are_reported() {
    if !rs274_for_tests() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("bad.ngc");
    std::fs::write(&file, "G21\nG0 X1 Y2\nG1 X3\nM2\n").unwrap();
    match run_rs274(&file) {
        Err(Rs274Error::Failed { output, .. }) => {
            assert!(output.contains("zero feed rate"), "{output}")
        }
        other => panic!("expected a failure, got {other:?}"),
    }
}

/// Tiny deterministic generator (xorshift64*), uniform in [lo, hi).
struct Rng(u64);
impl Rng {
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let u = (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * u
    }
}

/// The reader's arcs against rs274's ARC_FEED for the same program: G17/G18/G19, G2/G3, IJK
/// and R forms, helices and full circles. Checks end point, centre (every chord point at the
/// start radius about rs274's centre) and signed sweep — an independent check of the plane
/// orientation and of which centre an R word selects.
#[test]
fn rs274_agrees_with_the_reader_on_arcs() {
    use cam_gcode::{ReadConfig, parse_gcode};
    use std::f64::consts::TAU;
    if !rs274_for_tests() {
        return;
    }
    const PLANES: [(u32, usize, usize, usize); 3] = [(17, 0, 1, 2), (18, 2, 0, 1), (19, 1, 2, 0)];
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let mut text = String::from("G21 G90 F500\n");
    let mut arc_lines = Vec::new();
    for i in 0..120 {
        let (g, a, b, n) = PLANES[i % 3];
        let cw = (i / 3) % 2 == 1;
        let r_form = (i / 6) % 2 == 1;
        let full = !r_form && i % 20 == 0;
        let c = [rng.uniform(-20.0, 20.0), rng.uniform(-20.0, 20.0)];
        let r = rng.uniform(1.0, 30.0);
        let th0 = rng.uniform(-3.0, 3.0);
        let mag = if full {
            TAU
        } else if rng.uniform(0.0, 1.0) < 0.5 {
            rng.uniform(0.2, 2.8)
        } else {
            rng.uniform(3.5, 6.0)
        };
        let sweep = if cw { -mag } else { mag };
        let n0 = rng.uniform(-5.0, 5.0);
        let dn = if i % 4 == 0 {
            rng.uniform(-3.0, 3.0)
        } else {
            0.0
        };
        let mut s = [0.0; 3];
        let mut e = [0.0; 3];
        (s[a], s[b], s[n]) = (c[0] + r * th0.cos(), c[1] + r * th0.sin(), n0);
        let th1 = th0 + sweep;
        (e[a], e[b], e[n]) = (c[0] + r * th1.cos(), c[1] + r * th1.sin(), n0 + dn);
        if full {
            (e[a], e[b]) = (s[a], s[b]);
        }
        let round = |v: f64| format!("{v:.4}");
        text += &format!(
            "G{g} G0 X{} Y{} Z{}\n",
            round(s[0]),
            round(s[1]),
            round(s[2])
        );
        text += &format!(
            "G{} X{} Y{} Z{}",
            if cw { 2 } else { 3 },
            round(e[0]),
            round(e[1]),
            round(e[2])
        );
        if r_form {
            let rr = if mag > std::f64::consts::PI { -r } else { r };
            text += &format!(" R{}\n", round(rr));
        } else {
            // Offsets from the rounded start so both readers see the same centre.
            let sr: Vec<f64> = s.iter().map(|v| round(*v).parse().unwrap()).collect();
            let letters = ['I', 'J', 'K'];
            text += &format!(
                " {}{} {}{}\n",
                letters[a],
                round(c[0] - sr[a]),
                letters[b],
                round(c[1] - sr[b])
            );
        }
        arc_lines.push(text.lines().count());
    }
    text += "M2\n";
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("arcs.ngc");
    std::fs::write(&file, &text).unwrap();
    let canon = run_rs274(&file).unwrap();
    let canon_arcs: Vec<_> = canon
        .iter()
        .filter(|c| matches!(c.kind, CanonKind::Arc { .. }))
        .collect();
    assert_eq!(canon_arcs.len(), arc_lines.len());
    let ours = parse_gcode(&text, &ReadConfig::default()).unwrap();
    let (mut max_end, mut max_radius, mut max_sweep): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for (k, (&line, c)) in arc_lines.iter().zip(&canon_arcs).enumerate() {
        let CanonKind::Arc {
            centre,
            rotation,
            normal_axis,
        } = c.kind
        else {
            unreachable!()
        };
        let (_, a, b, _) = PLANES.iter().copied().find(|p| p.3 == normal_axis).unwrap();
        let start_idx = ours
            .moves
            .iter()
            .position(|m| m.line == Some(line))
            .unwrap()
            - 1;
        let pts: Vec<[f64; 3]> = ours.moves[start_idx..]
            .iter()
            .take_while(|m| m.line == Some(line) || m.line == Some(line - 1))
            .map(|m| m.pose.tip.to_array())
            .collect();
        let end = pts.last().unwrap();
        for (e, w) in end.iter().zip(&c.xyz) {
            max_end = max_end.max((e - w).abs());
        }
        let ang = |p: &[f64; 3]| (p[b] - centre[b]).atan2(p[a] - centre[a]);
        let rad = |p: &[f64; 3]| (p[a] - centre[a]).hypot(p[b] - centre[b]);
        let (r0, r1) = (rad(&pts[0]), rad(end));
        let mut total = 0.0;
        for w in pts.windows(2) {
            let t = w[1]
                .iter()
                .zip(&w[0])
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
            if t == 0.0 {
                continue;
            }
            let mut d = ang(&w[1]) - ang(&w[0]);
            d -= TAU * (d / TAU).round();
            total += d;
            max_radius = max_radius.max((rad(&w[1]) - r0).abs() - (r1 - r0).abs());
        }
        let (a0, a1) = (ang(&pts[0]), ang(end));
        let want = if rotation > 0 {
            let s = (a1 - a0).rem_euclid(TAU);
            (if s < 1e-6 { TAU } else { s }) + TAU * f64::from(rotation - 1)
        } else {
            let s = (a0 - a1).rem_euclid(TAU);
            -((if s < 1e-6 { TAU } else { s }) + TAU * f64::from(-rotation - 1))
        };
        max_sweep = max_sweep.max((total - want).abs());
        assert!(
            (total - want).abs() < 1e-3,
            "arc {k} (line {line}): sweep {total} vs rs274 {want}"
        );
    }
    println!(
        "rs274 arcs: {} arcs, max |Δend| = {max_end:.2e} mm, max radius excess = {max_radius:.2e} mm, max |Δsweep| = {max_sweep:.2e} rad",
        arc_lines.len()
    );
    assert!(max_end <= 1e-4, "{max_end:e}");
    assert!(max_radius <= 1e-4, "{max_radius:e}");
}
