//! Posts: post → parse round trip for every post and unit, safe-Z enforcement, header,
//! modal suppression, fixed decimals.

use crate::support::{mv, small_path};
use cam_core::{DVec3, MoveKind, Toolpath, Units};
use cam_gcode::{
    Post, PostError, PostJob, ReadConfig, parse_gcode, post, post_to_string, rounding_mm,
};

pub fn job(units: Units) -> PostJob {
    PostJob {
        part_name: "bump (small) ; test".into(),
        tool_spec: "ball:6".into(),
        tool_number: 3,
        tolerance_mm: 0.01,
        scallop_mm: 0.005,
        feed_mm_per_min: 1200.0,
        plunge_feed_mm_per_min: 250.0,
        rpm: 12000.0,
        spindle_cw: true,
        safe_z_mm: 5.0,
        units,
        program_number: 1234,
        use_move_feeds: false,
    }
}

/// One unit of the last printed decimal, in mm.
pub fn last_digit_mm(units: Units) -> f64 {
    match units {
        Units::Mm => 1e-4,
        Units::Inch => 1e-5 * 25.4,
    }
}

#[test]
fn every_post_reads_back_to_the_planned_tips() {
    let tp = small_path();
    for p in Post::ALL {
        for units in [Units::Mm, Units::Inch] {
            let j = job(units);
            let text = post_to_string(&tp, &j, p).unwrap();
            let back = parse_gcode(&text, &ReadConfig::default())
                .unwrap_or_else(|e| panic!("{p} {units}: {e}\n{text}"));
            assert_eq!(back.moves.len(), tp.moves.len(), "{p} {units}\n{text}");
            let (mut max, mut dist): (f64, f64) = (0.0, 0.0);
            for (a, b) in tp.moves.iter().zip(&back.moves) {
                max = max.max((a.pose.tip - b.pose.tip).abs().max_element());
                dist = dist.max(a.pose.tip.distance(b.pose.tip));
                assert_eq!(a.kind, b.kind, "{p} {units}: {a:?} vs {b:?}");
                let want_feed = match a.kind {
                    MoveKind::Rapid => None,
                    MoveKind::Plunge => Some(j.plunge_feed_mm_per_min),
                    _ => Some(j.feed_mm_per_min),
                };
                match (want_feed, b.feed_mm_per_min) {
                    (None, None) => {}
                    (Some(w), Some(g)) => {
                        assert!((w - g).abs() <= 0.01 * units.mm_per_unit(), "{w} vs {g}")
                    }
                    other => panic!("{p} {units}: feed {other:?}"),
                }
            }
            println!("post {p} {units}: max |Δtip| after read-back = {max:e} mm");
            assert!(
                max <= last_digit_mm(units) / 2.0 + 1e-12,
                "{p} {units}: {max:e}"
            );
            // The bound the planner subtracts from τ: √3 half-digits, and it holds.
            let bound = rounding_mm(units);
            assert!(
                (bound - 3f64.sqrt() * last_digit_mm(units) / 2.0).abs() < 1e-15,
                "{units}: rounding_mm {bound:e}"
            );
            assert!(dist <= bound + 1e-12, "{p} {units}: {dist:e} > {bound:e}");
        }
    }
}

#[test]
fn header_tool_change_and_framing_per_post() {
    let tp = small_path();
    let lc = post_to_string(&tp, &job(Units::Mm), Post::LinuxCnc).unwrap();
    assert!(lc.contains("\n(CL convention: tool tip)\n"));
    assert!(lc.contains("(part: bump [small] , test)"));
    assert!(lc.contains("(tool: T3 ball:6)"));
    assert!(lc.contains("(tolerance: 0.01 mm)") && lc.contains("(scallop: 0.005 mm)"));
    assert!(lc.contains("(post: linuxcnc, units: mm)"));
    assert!(
        lc.contains("\nG21 G90 G17 G94")
            && lc.contains("\nT3 M6\nS12000 M3\nG0 G43 H3 Z5.0000\nX0.0000 Y0.0000\n")
    );
    assert!(lc.ends_with("M5\nM30\n"));
    let grbl = post_to_string(&tp, &job(Units::Inch), Post::Grbl).unwrap();
    assert!(grbl.contains("\nG20 G90 G17 G94"));
    assert!(!grbl.contains("M6") && !grbl.contains("G43") && !grbl.contains("\nT"));
    assert!(grbl.contains("\nS12000 M3\nG0 Z0.19685\n"));
    assert!(grbl.contains("(CL convention: tool tip)"));
    let fanuc = post_to_string(
        &tp,
        &PostJob {
            spindle_cw: false,
            ..job(Units::Mm)
        },
        Post::Fanuc,
    )
    .unwrap();
    assert!(fanuc.starts_with("%\nO1234 (BUMP [SMALL] , TEST)\n"));
    assert!(
        fanuc.contains("(CL CONVENTION: TOOL TIP)")
            && fanuc.contains("\nG0 G43 H3 Z5.0000\n")
            && fanuc.contains("S12000 M4")
    );
    assert!(fanuc.ends_with("M5\nM30\n%\n"));
    for (name, text) in [("linuxcnc", &lc), ("grbl", &grbl), ("fanuc", &fanuc)] {
        for l in text.lines().filter(|l| l.contains('(')) {
            assert_eq!(l.matches('(').count(), 1, "{name}: {l}");
            assert_eq!(l.matches(')').count(), 1, "{name}: {l}");
            assert!(l.ends_with(')'), "{name}: {l}");
            if name == "fanuc" {
                let body = &l[l.find('(').unwrap() + 1..l.len() - 1];
                assert!(body.len() <= 32 && body == body.to_ascii_uppercase(), "{l}");
            }
        }
    }
}

#[test]
fn fixed_decimals_and_modal_suppression() {
    let tp = small_path();
    for p in Post::ALL {
        for (units, dec, fdec) in [(Units::Mm, 4, 1), (Units::Inch, 5, 2)] {
            let text = post_to_string(&tp, &job(units), p).unwrap();
            let mut last: std::collections::HashMap<char, String> = Default::default();
            let mut last_g = String::new();
            for l in text
                .lines()
                .filter(|l| !l.starts_with('(') && !l.starts_with('%') && !l.starts_with('O'))
            {
                for w in l.split_whitespace() {
                    let (c, v) = w.split_at(1);
                    let c = c.chars().next().unwrap();
                    if matches!(c, 'X' | 'Y' | 'Z' | 'F') {
                        let want = if c == 'F' { fdec } else { dec };
                        assert_eq!(v.split_once('.').map(|x| x.1.len()), Some(want), "{p}: {l}");
                        assert_ne!(
                            last.get(&c).map(String::as_str),
                            Some(v),
                            "{p}: repeated {w} in {l}"
                        );
                        last.insert(c, v.to_string());
                    }
                    if w == "G0" || w == "G1" {
                        assert_ne!(last_g, w, "{p}: repeated motion code in {l}");
                        last_g = w.to_string();
                    }
                }
            }
        }
    }
}

#[test]
fn rapids_below_safe_z_are_refused_and_nothing_is_written() {
    let base = small_path();
    // A rapid that ends below safe Z.
    let mut tp = base.clone();
    tp.moves[1] = mv(MoveKind::Rapid, 0.0, 0.0, 1.0);
    let mut buf = Vec::new();
    let e = post(&tp, &job(Units::Mm), Post::LinuxCnc, &mut buf).unwrap_err();
    assert!(
        matches!(e, PostError::RapidBelowSafeZ { move_index: 1, z_mm, .. } if z_mm == 1.0),
        "{e}"
    );
    assert!(buf.is_empty());
    // A rapid to safe Z that starts below it sideways (diagonal) is refused too.
    let tp = Toolpath {
        moves: vec![
            mv(MoveKind::Rapid, 0.0, 0.0, 5.0),
            mv(MoveKind::Plunge, 0.0, 0.0, 0.0),
            mv(MoveKind::Rapid, 3.0, 0.0, 5.0),
        ],
    };
    let e = post_to_string(&tp, &job(Units::Mm), Post::Grbl).unwrap_err();
    assert!(
        matches!(e, PostError::RapidBelowSafeZ { move_index: 2, .. }),
        "{e}"
    );
    // A pure upward rapid from below is a retract and allowed; the first non-rapid move gets a
    // rapid approach at safe Z.
    let tp = Toolpath {
        moves: vec![
            mv(MoveKind::Plunge, 1.0, 2.0, 0.0),
            mv(MoveKind::Rapid, 1.0, 2.0, 6.0),
        ],
    };
    let text = post_to_string(&tp, &job(Units::Mm), Post::LinuxCnc).unwrap();
    assert!(
        text.contains("G0 G43 H3 Z5.0000\nX1.0000 Y2.0000\nG1 Z0.0000 F250.0\nG0 Z6.0000\nM5\n"),
        "{text}"
    );
}

#[test]
fn other_post_errors() {
    let mut tp = small_path();
    tp.moves[3].pose.axis = DVec3::new(0.0, 0.6, 0.8);
    assert!(matches!(
        post_to_string(&tp, &job(Units::Mm), Post::LinuxCnc),
        Err(PostError::NotThreeAxis { move_index: 3, .. })
    ));
    let mut tp = small_path();
    tp.moves[4].pose.tip.x = f64::NAN;
    assert!(matches!(
        post_to_string(&tp, &job(Units::Mm), Post::Fanuc),
        Err(PostError::NonFinite { move_index: 4 })
    ));
    let j = PostJob {
        plunge_feed_mm_per_min: 0.0,
        ..job(Units::Mm)
    };
    assert!(matches!(
        post_to_string(&small_path(), &j, Post::Grbl),
        Err(PostError::InvalidJob(_))
    ));
    assert_eq!("FANUC".parse::<Post>().unwrap(), Post::Fanuc);
    assert!("haas".parse::<Post>().is_err());
    assert_eq!(Post::default(), Post::LinuxCnc);
}

#[test]
fn move_feeds_override_job_feeds_when_asked() {
    let mut tp = small_path();
    for m in &mut tp.moves {
        m.feed_mm_per_min = Some(777.0);
    }
    let j = PostJob {
        use_move_feeds: true,
        ..job(Units::Mm)
    };
    let text = post_to_string(&tp, &j, Post::LinuxCnc).unwrap();
    assert!(text.contains("F777.0") && !text.contains("F1200.0") && !text.contains("F250.0"));
}
