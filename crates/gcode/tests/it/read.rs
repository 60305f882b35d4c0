//! The G-code reader: units, distance modes, modal motion, kinds, and errors that name the
//! line and column.

use cam_core::{DVec3, MoveKind};
use cam_gcode::{ReadConfig, ReadError, parse_gcode, read_gcode};

fn parse(text: &str) -> cam_core::Toolpath {
    parse_gcode(text, &ReadConfig::default()).unwrap_or_else(|e| panic!("{e}"))
}

fn tips(text: &str) -> Vec<[f64; 3]> {
    parse(text)
        .moves
        .iter()
        .map(|m| m.pose.tip.to_array())
        .collect()
}

/// Parses `text` expecting an error at `line`:`col` whose message contains `needle`.
fn fails_at(text: &str, line: usize, col: usize, needle: &str) {
    let e = parse_gcode(text, &ReadConfig::default()).expect_err(text);
    assert_eq!((e.line, e.col), (line, col), "{e} for {text:?}");
    assert!(
        e.message.contains(needle),
        "message {:?} lacks {needle:?}",
        e.message
    );
}

#[test]
fn g20_converts_inches_to_mm_including_feeds() {
    let tp = parse("G20 G90\nG0 X1 Y2 Z0.5\nG1 X1.5 F10\nG21 X3 F100\n");
    let near = |a: DVec3, b: [f64; 3]| (a - DVec3::from_array(b)).length() < 1e-12;
    assert!(near(tp.moves[0].pose.tip, [25.4, 50.8, 12.7]));
    assert!(near(tp.moves[1].pose.tip, [38.1, 50.8, 12.7]));
    cam_core::assert_near!(tp.moves[1].feed_mm_per_min.unwrap(), 254.0, 1e-12);
    assert!(near(tp.moves[2].pose.tip, [3.0, 50.8, 12.7]));
    assert_eq!(tp.moves[2].feed_mm_per_min, Some(100.0));
}

#[test]
fn g91_moves_are_relative_and_modal() {
    let t = tips("G21 G90\nG0 X1 Y1 Z1\nG91 G1 X1 F100\nX1 Y-2\nZ-0.5\nG90 X0\n");
    assert_eq!(
        t,
        vec![
            [1.0, 1.0, 1.0],
            [2.0, 1.0, 1.0],
            [3.0, -1.0, 1.0],
            [3.0, -1.0, 0.5],
            [0.0, -1.0, 0.5]
        ]
    );
    let t = tips("G20 G90\nG0 X0 Y0 Z0\nG91 G1 X1 F1\n");
    assert_eq!(t[1], [25.4, 0.0, 0.0]); // 1 × 25.4 is exact
}

/// Kind, tip, feed and line of a move.
type Summary = (MoveKind, [f64; 3], Option<f64>, Option<usize>);

#[test]
fn kinds_lines_and_feeds() {
    let tp = parse(
        "%\nO1000 (prog)\nN10 G21 G90 G17 G94 G40 G49 G80 G54\nT1 M6\nG43 H1\nS1000 M3 M8\nG64 P0.01\nG61\nG0 Z5 ; safe\nX1 Y2\nG1 Z-1 F200\nX4 F800\nG4 P0.5\nZ3\nG0 Z5\n/G0 X100\nM9\nM5\nM30\nG0 X7\n%\n",
    );
    let got: Vec<Summary> = tp
        .moves
        .iter()
        .map(|m| (m.kind, m.pose.tip.to_array(), m.feed_mm_per_min, m.line))
        .collect();
    assert_eq!(
        got,
        vec![
            (MoveKind::Rapid, [1.0, 2.0, 5.0], None, Some(10)),
            (MoveKind::Plunge, [1.0, 2.0, -1.0], Some(200.0), Some(11)),
            (MoveKind::Cut, [4.0, 2.0, -1.0], Some(800.0), Some(12)),
            (MoveKind::Retract, [4.0, 2.0, 3.0], Some(800.0), Some(14)),
            (MoveKind::Rapid, [4.0, 2.0, 5.0], None, Some(15)),
        ]
    );
    assert!(tp.moves.iter().all(|m| m.pose.axis == DVec3::Z));
}

#[test]
fn unknown_start_drops_partial_moves_unless_an_initial_position_is_given() {
    let text = "G0 Z5\nG0 X1 Y2\n";
    assert_eq!(tips(text), vec![[1.0, 2.0, 5.0]]);
    let cfg = ReadConfig {
        initial_position_mm: Some(DVec3::ZERO),
        ..ReadConfig::default()
    };
    let t: Vec<[f64; 3]> = parse_gcode(text, &cfg)
        .unwrap()
        .moves
        .iter()
        .map(|m| m.pose.tip.to_array())
        .collect();
    assert_eq!(t, vec![[0.0, 0.0, 5.0], [1.0, 2.0, 5.0]]);
}

#[test]
fn block_delete_switch_off_runs_the_line() {
    let cfg = ReadConfig {
        block_delete: false,
        ..ReadConfig::default()
    };
    let tp = parse_gcode("G0 X0 Y0 Z0\n/G0 X100\n", &cfg).unwrap();
    assert_eq!(tp.moves.len(), 2);
}

#[test]
fn errors_name_line_and_column() {
    fails_at("G21\nG1 X1 Y2 G0 F1\n", 2, 10, "two motion codes");
    fails_at(
        "G21\n\nG0 X1 Y1 Z1\nG33 X1\n",
        4,
        1,
        "unsupported G code G33",
    );
    fails_at("G0 X0 Y0 Z0\n  G5.1 X1", 2, 3, "G5.1");
    fails_at("M98 P1\n", 1, 1, "unsupported M code");
    fails_at("G0 X1 A5\n", 1, 7, "axis A");
    fails_at("G0 X1 E5\n", 1, 7, "unsupported word letter 'E'");
    fails_at("G0 X1..2\n", 1, 7, "malformed number");
    fails_at("G0 X\n", 1, 5, "expected a number");
    fails_at("G0 X1 (open\n", 1, 7, "not closed");
    fails_at("G0 X1 (a (b))\n", 1, 10, "nested");
    fails_at("G0 X#1\n", 1, 5, "");
    fails_at("G0 X1 X2\n", 1, 7, "twice");
    fails_at(
        "G0 X0 Y0 Z0\nG2 X10 Y0 I4 J0 F100\n",
        2,
        1,
        "differs from radius to start",
    );
    fails_at(
        "G0 X0 Y0 Z0\nG2 X10 Y0 R4 F100\n",
        2,
        11,
        "less than half the chord",
    );
    fails_at("G0 X0 Y0 Z0\nG2 X10 Y0 I5 K1 F100\n", 2, 14, "K word");
    fails_at("G0 X0 Y0 Z0\nG1 X1 I1 F100\n", 2, 7, "need G2 or G3");
    fails_at("X1\n", 1, 1, "without a motion mode");
    fails_at("G80 X1\n", 1, 5, "without a motion mode");
    fails_at("G91 G0 X1\n", 1, 8, "unknown position");
    fails_at("G2 X1 Y1 I1\n", 1, 1, "unknown position");
    fails_at("G1 X1 F-5\n", 1, 7, "negative feed");
    fails_at("G0 X1 H1\n", 1, 7, "H word without G43");
    fails_at("G20 G21\n", 1, 5, "two units codes");
    fails_at("G0 X0 Y0 Z0\nG1 X1 F1 % \n", 2, 10, "'%'");
    fails_at("O100 sub\n", 1, 7, "expected a number after 'S'");
    fails_at("G0 X0 Y0 Z0 ?\n", 1, 13, "unexpected character");
}

#[test]
fn read_gcode_adds_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bad.ngc");
    std::fs::write(&p, "G21\nG0 X1 Q2\n").unwrap();
    let e = read_gcode(&p, &ReadConfig::default()).unwrap_err();
    let msg = e.to_string();
    assert!(msg.starts_with(&format!("{}:2:7:", p.display())), "{msg}");
    assert!(matches!(e, ReadError::Parse(ref g) if g.path.as_deref() == Some(p.as_path())));
    let e = read_gcode(dir.path().join("missing.ngc"), &ReadConfig::default()).unwrap_err();
    assert!(matches!(e, ReadError::Io { .. }));
}

/// Positions beyond 1 km of the origin, and feeds that overflow, are errors at the word
/// (found by fuzzing: they read as infinite tips, which the planner and verifier cannot
/// hold): an inch value scaled past f64, incremental moves adding up, a huge absolute word.
/// A position at the limit reads.
#[test]
fn positions_beyond_a_kilometre_are_errors() {
    let huge = format!("1{}", "0".repeat(308));
    fails_at(
        &format!("G20\nG0 X{huge} Y0 Z0\n"),
        2,
        4,
        "X coordinate inf mm",
    );
    fails_at(
        &format!("G0 X0 Y0 Z0\nG91\nG1 Y{huge} F100\nY{huge}\n"),
        3,
        4,
        "Y coordinate",
    );
    fails_at("G0 X0 Y0 Z1000001\n", 1, 10, "Z coordinate 1.000001e6 mm");
    fails_at(
        &format!("G20 G0 X0 Y0 Z0\nG1 X1 F{huge}\n"),
        2,
        7,
        "feed rate",
    );
    assert_eq!(tips("G0 X1000000 Y-1000000 Z0\n"), vec![[1e6, -1e6, 0.0]]);
}
