//! APT CL data: write → read round trip of a 5-axis path, and reader errors.

use cam_core::{Cutter, DVec3, Move, MoveKind, Pose, Toolpath};
use cam_gcode::{AptHeader, parse_apt, read_apt, write_apt};

/// A 5-axis path: rapid in, then a helix-like sweep with a rotating, tilted axis.
fn five_axis_path() -> Toolpath {
    let mut moves = vec![Move {
        kind: MoveKind::Rapid,
        pose: Pose {
            tip: DVec3::new(0.0, 0.0, 20.0),
            axis: DVec3::Z,
        },
        feed_mm_per_min: None,
        line: None,
        pass: None,
    }];
    for i in 0..100 {
        let t = i as f64 * 0.0731;
        let tip = DVec3::new(30.0 * t.cos(), 30.0 * t.sin(), 2.0 - 0.1 * t);
        let axis = DVec3::new(0.3 * (2.0 * t).sin(), 0.2 * t.cos(), 1.0).normalize();
        moves.push(Move {
            kind: MoveKind::Cut,
            pose: Pose { tip, axis },
            feed_mm_per_min: Some(if i < 50 { 800.0 } else { 1234.5 }),
            line: None,
            pass: Some(0),
        });
    }
    Toolpath { moves }
}

#[test]
fn apt_round_trip_keeps_tips_axes_feeds_and_rapids() {
    let tp = five_axis_path();
    let mut buf = Vec::new();
    let header = AptHeader {
        part_name: "blade (test)".into(),
        cutter: Some(Cutter::bull(10.0, 2.0).unwrap()),
    };
    write_apt(&mut buf, &tp, &header).unwrap();
    let text = String::from_utf8(buf).unwrap();
    assert!(text.contains("CUTTER/10.000000,2.000000"));
    for l in text.lines().filter(|l| l.starts_with("GOTO/")) {
        assert!(
            l[5..]
                .split(',')
                .all(|v| v.split_once('.').unwrap().1.len() == 6),
            "{l}"
        );
    }
    let back = parse_apt(&text).unwrap();
    assert_eq!(back.moves.len(), tp.moves.len());
    let mut max_tip: f64 = 0.0;
    let mut max_axis: f64 = 0.0;
    for (a, b) in tp.moves.iter().zip(&back.moves) {
        max_tip = max_tip.max((a.pose.tip - b.pose.tip).abs().max_element());
        max_axis = max_axis.max((a.pose.axis - b.pose.axis).length());
        assert_eq!(a.kind, b.kind);
        assert_eq!(a.feed_mm_per_min, b.feed_mm_per_min);
        cam_core::assert_near!(b.pose.axis.length(), 1.0, 1e-12);
    }
    println!("apt round trip: max |Δtip| = {max_tip:e} mm, max |Δaxis| = {max_axis:e}");
    assert!(max_tip <= 5e-7 + 1e-12);
    assert!(max_axis <= 2e-6);
}

#[test]
fn apt_reader_units_axes_and_words() {
    let text = "$$ comment\nPARTNO/ any text, with commas\nUNITS/INCHES\nCUTTER/0.25\nRAPID\nGOTO/1,2,3\nFEDRAT/10,IPM\nTLAXIS/0,0,2\nGOTO/1,2,$\n  2.5 $$ continued\nFEDRAT/MMPM,500\nGOTO/2,2,2.5,0,3,4\nSPINDL/1000,CLW\nFINI\nGARBAGE/1\n";
    let tp = parse_apt(text).unwrap();
    let want = [
        (
            MoveKind::Rapid,
            [25.4, 50.8, 76.2],
            [0.0, 0.0, 1.0],
            None,
            Some(6),
        ),
        (
            MoveKind::Plunge,
            [25.4, 50.8, 63.5],
            [0.0, 0.0, 1.0],
            Some(254.0),
            Some(9),
        ),
        (
            MoveKind::Cut,
            [50.8, 50.8, 63.5],
            [0.0, 0.6, 0.8],
            Some(500.0),
            Some(12),
        ),
    ];
    assert_eq!(tp.moves.len(), want.len());
    for (m, (kind, tip, axis, feed, line)) in tp.moves.iter().zip(want) {
        assert_eq!((m.kind, m.line), (kind, line));
        assert!(
            (m.pose.tip - DVec3::from_array(tip)).length() < 1e-12,
            "{m:?}"
        );
        assert!(
            (m.pose.axis - DVec3::from_array(axis)).length() < 1e-12,
            "{m:?}"
        );
        assert_eq!(m.feed_mm_per_min.is_some(), feed.is_some());
        cam_core::assert_near!(m.feed_mm_per_min.unwrap_or(0.0), feed.unwrap_or(0.0), 1e-12);
    }
}

#[test]
fn apt_errors_name_line_and_column() {
    let cases: [(&str, usize, usize, &str); 7] = [
        ("UNITS/MM\nGOTO/1,2\n", 2, 1, "needs 3 or 6 values"),
        ("GOTO/1,2,3,0,0,0\n", 1, 12, "tool axis is zero"),
        ("GOTO/1,x,3\n", 1, 8, "not a finite number"),
        (
            "PARTNO/a\n  CYCLE/DRILL\n",
            2,
            3,
            "unknown APT word 'CYCLE'",
        ),
        ("UNITS/FEET\n", 1, 7, "unknown unit"),
        ("RAPID/1\n", 1, 7, "takes no values"),
        ("GOTO/1,2,$\n", 1, 1, "end of the file"),
    ];
    for (text, line, col, needle) in cases {
        let e = parse_apt(text).expect_err(text);
        assert_eq!((e.line, e.col), (line, col), "{e}");
        assert!(e.message.contains(needle), "{e}");
    }
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("x.apt");
    std::fs::write(&p, "GOTO/1,2,3\nFOO\n").unwrap();
    let msg = read_apt(&p).unwrap_err().to_string();
    assert!(msg.starts_with(&format!("{}:2:1:", p.display())), "{msg}");
}

/// APT positions beyond 1 km and feeds that overflow are errors naming line and column
/// (found by fuzzing: `UNITS/INCHES` then `GOTO/1e308,…` read as an infinite tip).
#[test]
fn apt_positions_beyond_a_kilometre_are_errors() {
    let e = parse_apt("UNITS/INCHES\nGOTO/1e308,0,0\n").unwrap_err();
    assert_eq!((e.line, e.col), (2, 6), "{e}");
    assert!(e.message.contains("X coordinate inf mm"), "{e}");
    let e = parse_apt("GOTO/0,0,2e6\n").unwrap_err();
    assert!(e.message.contains("Z coordinate"), "{e}");
    let e = parse_apt("FEDRAT/1e308,IPM\nGOTO/0,0,0\n").unwrap_err();
    assert!(e.message.contains("feed"), "{e}");
}
