//! Property tests: posts read back within half a unit of the last decimal for random paths;
//! the readers never panic on arbitrary text.

use crate::post::{job, last_digit_mm};
use cam_core::{DVec3, Move, MoveKind, Pose, Toolpath, Units};
use cam_gcode::{Post, ReadConfig, parse_apt, parse_gcode, post_to_string};
use proptest::prelude::*;

/// A rapid in at safe Z then feed moves; X advances by at least 0.001 mm per move so that
/// no move prints the same as the one before.
fn path_strategy() -> impl Strategy<Value = Toolpath> {
    (
        (-100.0..100.0f64, -100.0..100.0f64),
        prop::collection::vec(
            (0.001..10.0f64, -50.0..50.0f64, -20.0..4.9f64, 0..3u8),
            1..40,
        ),
    )
        .prop_map(|((x0, y0), steps)| {
            let mut x = x0;
            let mut moves = vec![Move {
                kind: MoveKind::Rapid,
                pose: Pose::vertical(DVec3::new(x0, y0, 5.0)),
                feed_mm_per_min: None,
                line: None,
                pass: None,
            }];
            for (dx, y, z, k) in steps {
                x += dx;
                let kind = [MoveKind::Cut, MoveKind::Cut, MoveKind::Retract][k as usize];
                moves.push(Move {
                    kind,
                    pose: Pose::vertical(DVec3::new(x, y, z)),
                    feed_mm_per_min: None,
                    line: None,
                    pass: None,
                });
            }
            Toolpath { moves }
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn posted_paths_read_back(tp in path_strategy(), p in 0..3usize, inch in any::<bool>()) {
        let units = if inch { Units::Inch } else { Units::Mm };
        let text = post_to_string(&tp, &job(units), Post::ALL[p]).unwrap();
        let back = parse_gcode(&text, &ReadConfig::default()).unwrap();
        prop_assert_eq!(back.moves.len(), tp.moves.len() + 1); // + the final retract to safe Z
        for (a, b) in tp.moves.iter().zip(&back.moves) {
            let d = (a.pose.tip - b.pose.tip).abs().max_element();
            prop_assert!(d <= last_digit_mm(units) / 2.0 + 1e-9, "{} > half a unit", d);
            prop_assert_eq!(a.kind == MoveKind::Rapid, b.kind == MoveKind::Rapid);
        }
        let last = back.moves.last().unwrap();
        prop_assert_eq!(last.kind, MoveKind::Rapid);
        prop_assert!((last.pose.tip.z - 5.0).abs() <= last_digit_mm(units));
    }

    #[test]
    fn gcode_reader_never_panics(text in "[GMXYZIJKRFNST0-9 .;()%/\n-]{0,80}") {
        let _ = parse_gcode(&text, &ReadConfig::default());
    }

    #[test]
    fn apt_reader_never_panics(text in "(GOTO/|RAPID|FEDRAT/|UNITS/|[0-9,.$ ]|\n|é){0,30}") {
        let _ = parse_apt(&text);
    }
}
