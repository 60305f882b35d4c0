//! Shared helpers: a small 3-axis test toolpath and number-aware text comparison.

use cam_core::{DVec3, Move, MoveKind, Pose, Toolpath};

/// A move of `kind` to `(x, y, z)`, axis +Z, no feed.
pub fn mv(kind: MoveKind, x: f64, y: f64, z: f64) -> Move {
    Move {
        kind,
        pose: Pose::vertical(DVec3::new(x, y, z)),
        feed_mm_per_min: None,
        line: None,
        pass: None,
    }
}

/// A small finishing-like path with safe Z 5 mm: rapid in, plunge, two rows over a bump with
/// non-round coordinates, a step-over, a retract and a rapid out. No two consecutive poses
/// print the same in mm (4 decimals) or inch (5 decimals).
pub fn small_path() -> Toolpath {
    let bump = |x: f64, y: f64| {
        0.5 * (-(x - 6.0).powi(2) / 8.0 - (y - 1.0).powi(2) / 4.0).exp() - 1.0 / 3.0
    };
    let mut m = vec![
        mv(MoveKind::Rapid, 0.0, 0.0, 5.0),
        mv(MoveKind::Plunge, 0.0, 0.0, bump(0.0, 0.0)),
    ];
    for i in 1..=12 {
        let x = i as f64;
        m.push(mv(MoveKind::Cut, x, 0.0, bump(x, 0.0)));
    }
    let y = 2.0 / 3.0 + 1.0;
    for i in (0..=12).rev() {
        let x = i as f64 + 0.123456789;
        m.push(mv(MoveKind::Cut, x, y, bump(x, y)));
    }
    let last = m.last().unwrap().pose.tip;
    m.push(mv(MoveKind::Retract, last.x, last.y, 2.0));
    m.push(mv(MoveKind::Rapid, last.x, last.y, 5.0));
    m.push(mv(MoveKind::Rapid, -3.25, 7.5, 5.0));
    Toolpath { moves: m }
}

/// Splits text into tokens: maximal runs of number characters (`-`, digits, `.`) and single
/// other characters.
fn tokens(s: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut num = String::new();
    for c in s.chars() {
        if c.is_ascii_digit() || c == '.' || (c == '-' && num.is_empty()) {
            num.push(c);
        } else {
            if !num.is_empty() {
                out.push(std::mem::take(&mut num));
            }
            out.push(c.to_string());
        }
    }
    if !num.is_empty() {
        out.push(num);
    }
    out
}

/// Compares two texts line by line; numbers with a decimal point may differ by one unit of
/// their last printed decimal, everything else must be equal. Returns the first difference.
pub fn compare_numbers_within_last_digit(want: &str, got: &str) -> Result<(), String> {
    let (wl, gl): (Vec<&str>, Vec<&str>) = (want.lines().collect(), got.lines().collect());
    if wl.len() != gl.len() {
        return Err(format!(
            "line count differs: want {}, got {}",
            wl.len(),
            gl.len()
        ));
    }
    for (i, (w, g)) in wl.iter().zip(&gl).enumerate() {
        let (tw, tg) = (tokens(w), tokens(g));
        let same = tw.len() == tg.len()
            && tw.iter().zip(&tg).all(|(a, b)| {
                if a == b {
                    return true;
                }
                let decimals = a.split_once('.').map(|(_, d)| d.len());
                match (decimals, a.parse::<f64>(), b.parse::<f64>()) {
                    (Some(d), Ok(x), Ok(y))
                        if b.split_once('.').map(|(_, e)| e.len()) == Some(d) =>
                    {
                        (x - y).abs() <= 10f64.powi(-(d as i32)) * 1.000001
                    }
                    _ => false,
                }
            });
        if !same {
            return Err(format!("line {}: want {w:?}, got {g:?}", i + 1));
        }
    }
    Ok(())
}

#[test]
fn number_comparison_allows_one_unit_only() {
    assert!(compare_numbers_within_last_digit("G1 X1.2345 F10.0", "G1 X1.2346 F10.0").is_ok());
    assert!(compare_numbers_within_last_digit("G1 X1.2345", "G1 X1.2347").is_err());
    assert!(compare_numbers_within_last_digit("G1 X1.2345", "G0 X1.2345").is_err());
    assert!(compare_numbers_within_last_digit("G1 X1.2345", "G1 X1.23450").is_err());
    assert!(compare_numbers_within_last_digit("G1 X1.2345\n", "G1 X1.2345\nM2").is_err());
}
