//! G2/G3 arcs in G17/G18/G19, IJK and R forms, full circles and helices: every chord point on
//! the analytic circle (1e-9 mm) and every chord's sagitta within the tolerance.

use cam_core::MoveKind;
use cam_gcode::{ReadConfig, parse_gcode};
use std::f64::consts::TAU;

/// (G code, first in-plane axis, second, normal) — right-handed: a × b = n.
const PLANES: [(u32, usize, usize, usize); 3] = [(17, 0, 1, 2), (18, 2, 0, 1), (19, 1, 2, 0)];
const LETTERS: [char; 3] = ['X', 'Y', 'Z'];
const CENTRE_LETTERS: [char; 3] = ['I', 'J', 'K'];

struct Case {
    plane: usize,
    sweep: f64,
    helix: f64,
    r_form: bool,
}

/// Builds the program, parses it and checks the chords; returns the max sagitta (mm).
fn check(case: &Case, tol: f64) -> f64 {
    let (g, a, b, n) = PLANES[case.plane];
    let (c, r, th0, n0) = ([1.5, -2.0], 7.3, 0.3, 0.5);
    let th1 = th0 + case.sweep;
    let mut s = [0.0; 3];
    let mut e = [0.0; 3];
    s[a] = c[0] + r * th0.cos();
    s[b] = c[1] + r * th0.sin();
    s[n] = n0;
    e[a] = c[0] + r * th1.cos();
    e[b] = c[1] + r * th1.sin();
    e[n] = n0 + case.helix;
    let code = if case.sweep > 0.0 { 3 } else { 2 };
    let mut text = format!(
        "G21 G90 G{g}\nG0 X{:.15} Y{:.15} Z{:.15}\nG{code}",
        s[0], s[1], s[2]
    );
    for i in 0..3 {
        text += &format!(" {}{:.15}", LETTERS[i], e[i]);
    }
    if case.r_form {
        let rr = if case.sweep.abs() > std::f64::consts::PI {
            -r
        } else {
            r
        };
        text += &format!(" R{rr:.15}");
    } else {
        text += &format!(
            " {}{:.15} {}{:.15}",
            CENTRE_LETTERS[a],
            c[0] - s[a],
            CENTRE_LETTERS[b],
            c[1] - s[b]
        );
    }
    text += " F500\n";
    let cfg = ReadConfig {
        arc_tolerance_mm: tol,
        ..ReadConfig::default()
    };
    let tp = parse_gcode(&text, &cfg).unwrap_or_else(|e| panic!("{e}\n{text}"));
    assert!(tp.moves.len() >= 2, "{text}");
    let start = tp.moves[0].pose.tip.to_array();
    let mut prev_angle = th0;
    let mut prev = start;
    let mut max_sag: f64 = 0.0;
    for m in &tp.moves[1..] {
        assert_eq!(m.kind, MoveKind::Cut);
        assert_eq!(m.line, Some(3));
        assert_eq!(m.feed_mm_per_min, Some(500.0));
        let p = m.pose.tip.to_array();
        let (u, v) = (p[a] - c[0], p[b] - c[1]);
        let dist = u.hypot(v);
        assert!(
            (dist - r).abs() <= 1e-9,
            "off circle by {:e}: {text}",
            dist - r
        );
        // Unwrap the angle in the arc's direction; each step advances by less than π.
        let mut ang = v.atan2(u);
        while (ang - prev_angle) * case.sweep.signum() <= 0.0 {
            ang += TAU * case.sweep.signum();
        }
        while (ang - prev_angle).abs() > TAU {
            ang -= TAU * case.sweep.signum();
        }
        let step = ang - prev_angle;
        assert!(step.abs() < std::f64::consts::PI, "step {step}");
        // Helix: the normal axis is linear in the angle.
        let want_n = n0 + case.helix * (ang - th0) / case.sweep;
        assert!(
            (p[n] - want_n).abs() <= 1e-9,
            "helix off by {:e}",
            p[n] - want_n
        );
        // Sagitta: distance from the chord midpoint to the circle, in the plane.
        let mid = [(prev[a] + p[a]) / 2.0 - c[0], (prev[b] + p[b]) / 2.0 - c[1]];
        max_sag = max_sag.max(r - mid[0].hypot(mid[1]));
        prev_angle = ang;
        prev = p;
    }
    assert!(
        (prev_angle - th1).abs() <= 1e-9,
        "swept to {prev_angle}, want {th1}: {text}"
    );
    for i in 0..3 {
        assert!((prev[i] - e[i]).abs() <= 1e-9);
    }
    assert!(max_sag <= tol, "sagitta {max_sag:e} > tolerance {tol:e}");
    // Not wastefully fine: with ceil(sweep / δmax) chords the sagitta is at least
    // tol·((n−1)/n)² ≥ tol/4 once there are two or more chords.
    if tp.moves.len() > 2 {
        assert!(
            max_sag >= tol / 4.0,
            "sagitta {max_sag:e} ≪ tolerance {tol:e}: over-subdivided"
        );
    }
    max_sag
}

#[test]
fn arcs_in_all_planes_forms_and_directions_stay_within_tolerance() {
    let mut worst: f64 = 0.0;
    let mut cases = 0;
    for plane in 0..3 {
        for sweep in [1.2, -1.2, 4.0, -4.0, TAU, -TAU, 0.01] {
            for helix in [0.0, -2.0] {
                for r_form in [false, true] {
                    if r_form && sweep.abs() == TAU {
                        continue; // full circles exist only in IJK form
                    }
                    for tol in [0.001, 0.01, 1e-5] {
                        worst = worst.max(
                            check(
                                &Case {
                                    plane,
                                    sweep,
                                    helix,
                                    r_form,
                                },
                                tol,
                            ) / tol,
                        );
                        cases += 1;
                    }
                }
            }
        }
    }
    println!("arcs: {cases} cases, max sagitta / tolerance = {worst:.6}");
    assert!(worst <= 1.0);
}

#[test]
fn chord_count_matches_the_sagitta_formula() {
    // Quarter circle r = 10, tol = 0.001: δmax = 2·acos(1 − 1e-4), n = ceil((π/2)/δmax).
    let text = "G21 G90 G17\nG0 X10 Y0 Z0\nG3 X0 Y10 I-10 J0 F100\n";
    let tp = parse_gcode(text, &ReadConfig::default()).unwrap();
    let dmax = 2.0 * (1.0f64 - 0.001 / 10.0).acos();
    let n = (std::f64::consts::FRAC_PI_2 / dmax).ceil() as usize;
    assert_eq!(tp.moves.len() - 1, n);
    assert_eq!(n, 56);
}

#[test]
fn absolute_arc_centres_with_g90_1() {
    let text = "G21 G90 G17 G90.1\nG0 X11 Y5 Z0\nG3 X1 Y15 I1 J5 F100\nG91.1\nG2 X11 Y5 I0 J-10\n";
    let tp = parse_gcode(text, &ReadConfig::default()).unwrap();
    for m in &tp.moves[1..] {
        let p = m.pose.tip;
        cam_core::assert_near!((p.x - 1.0).hypot(p.y - 5.0), 10.0, 1e-9);
    }
    let last = tp.moves.last().unwrap().pose.tip;
    assert_eq!((last.x, last.y), (11.0, 5.0));
}

#[test]
fn inch_arcs_are_converted() {
    let text = "G20 G90 G17\nG0 X1 Y0 Z0\nG3 X0 Y1 R1 F10\n";
    let tp = parse_gcode(text, &ReadConfig::default()).unwrap();
    for m in &tp.moves[1..] {
        cam_core::assert_near!(m.pose.tip.truncate().length(), 25.4, 1e-9);
        cam_core::assert_near!(m.feed_mm_per_min.unwrap(), 254.0, 1e-12);
    }
}

/// An arc whose radius is absurd for the tolerance (a centre word a few digits too long)
/// would need more chords than memory holds: it is an error naming the line, found by
/// fuzzing, where the reader used to allocate until it died. A large but sane arc is not.
#[test]
fn absurd_arcs_are_errors_not_allocations() {
    let known = ReadConfig {
        initial_position_mm: Some(glam::DVec3::ZERO),
        ..ReadConfig::default()
    };
    for (text, line) in [
        ("G2J7777777777", 1),
        ("G21 G90\nG0 X0 Y0 Z0\nG2 I9999999999900\n", 3),
        ("G3 X0 Y0 I1000000000000000000000000000000 J0", 1),
    ] {
        let err = match parse_gcode(text, &known) {
            Ok(tp) => panic!("{text}: parsed into {} moves", tp.moves.len()),
            Err(e) => e,
        };
        assert_eq!(err.line, line, "{text}: {err}");
        assert!(err.message.contains("chords"), "{text}: {err}");
    }
    // A full circle of 1 km radius: 70k chords within 0.001 mm.
    let tp = parse_gcode("G21 G90\nG0 X0 Y0 Z0\nG2 I1000000 J0\n", &known).unwrap();
    let n = (TAU / (2.0 * (1.0f64 - 0.001 / 1e6).acos())).ceil() as usize;
    assert_eq!(tp.moves.len() - 1, n);
    assert!(n > 70_000, "{n}");
}

/// Of two errors, the earlier line's is reported, whichever kind each is and however far
/// apart they are (the lines' words are read in parallel, in chunks of thousands of lines,
/// before their blocks are executed in order): an execution error (an incremental move
/// from an unknown position) before a malformed word, and a malformed word before an
/// execution error, in one chunk and across chunks.
#[test]
fn the_first_of_two_errors_in_line_order_is_reported() {
    let cfg = ReadConfig::default();
    let filler = |n: usize| "G1 X1 Y1 Z1 F100\n".repeat(n);
    for gap in [1, 5000, 20_000] {
        // Line 2: G91 then a move from an unknown position is an execution error.
        let exec_first = format!("G91\nG1 X1\n{}G1 X#\n", filler(gap));
        let e = parse_gcode(&exec_first, &cfg).unwrap_err();
        assert_eq!(e.line, 2, "{e}");
        // Line 2 malformed, then an execution error later.
        let word_first = format!("G21\nG1 X#\n{}G91\nG1 X1\n", filler(gap));
        let e = parse_gcode(&word_first, &cfg).unwrap_err();
        assert_eq!(e.line, 2, "{e}");
        // Only the later error: its own line.
        let later = format!("G21\n{}G1 Q1\n", filler(gap));
        let e = parse_gcode(&later, &cfg).unwrap_err();
        assert_eq!(e.line, gap + 2, "{e}");
    }
}
