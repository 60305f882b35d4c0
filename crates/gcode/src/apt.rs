//! APT-style cutter-location (CL) data: `GOTO/x,y,z,i,j,k` (tool tip and tool axis), for
//! 5-axis toolpaths and exchange.
//!
//! Read: `GOTO/x,y,z[,i,j,k]` (a 3-value GOTO uses the current `TLAXIS`, +Z by default),
//! `FROM/` (same as a rapid GOTO), `RAPID` (the next GOTO is a rapid), `FEDRAT/f[,MMPM|IPM]`,
//! `UNITS/MM|INCHES`, `TLAXIS/i,j,k`, `$$` comments, a trailing `$` continues a statement on
//! the next line; accepted and ignored: `PARTNO`, `PPRINT`, `CUTTER`, `MULTAX`, `LOADTL`,
//! `SPINDL`, `COOLNT`, `INTOL`, `OUTTOL`, `TOLER`, `CLPRNT`, `NOPOST`, `END`; `FINI` ends the
//! data. Any other word is an error naming its line and column.

use cam_core::{Cutter, Move, MoveKind, Pose, Toolpath};
use glam::DVec3;
use std::io::{self, Write};
use std::path::Path;

use crate::error::{GcodeError, ReadError};
use crate::reader::classify;

/// What [`write_apt`] puts before the motion.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct AptHeader {
    /// Part name for `PARTNO` (sanitised to printable ASCII).
    pub part_name: String,
    /// The cutter, written as `CUTTER/diameter,corner_radius` (mm) when given.
    pub cutter: Option<Cutter>,
}

/// Reads the APT CL file at `path` (see [`parse_apt`]); errors carry the path.
///
/// # Errors
/// [`ReadError::Io`] if the file cannot be read, [`ReadError::Parse`] as [`parse_apt`].
pub fn read_apt(path: impl AsRef<Path>) -> Result<Toolpath, ReadError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|source| ReadError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_apt(&text).map_err(|mut e| {
        e.path = Some(path.to_path_buf());
        ReadError::Parse(e)
    })
}

/// Parses APT CL data into a toolpath (tool tip in mm, unit axis).
///
/// Moves get kind [`MoveKind::Rapid`] after `RAPID` (or for `FROM`), otherwise
/// [`MoveKind::Plunge`] / [`MoveKind::Retract`] when the tip moves only along −axis / +axis,
/// else [`MoveKind::Cut`]; the current `FEDRAT` (mm/min) for feed moves; the 1-based line of
/// the statement. Axis vectors are normalised.
///
/// # Errors
/// A [`GcodeError`] naming line and column: unknown word, wrong number of values, a value that
/// is not a finite number, a zero tool axis, an unknown unit.
pub fn parse_apt(text: &str) -> Result<Toolpath, GcodeError> {
    let mut moves = Vec::new();
    let mut mm_per_unit = 1.0;
    let mut feed: Option<f64> = None;
    let mut rapid_next = false;
    let mut axis = DVec3::Z;
    let mut prev: Option<DVec3> = None;
    let mut pending: Option<(usize, String)> = None;
    for (idx, raw) in text.lines().enumerate() {
        let line_no = idx + 1;
        let body = match raw.find("$$") {
            Some(p) => &raw[..p],
            None => raw,
        };
        let (start_line, mut stmt) = match pending.take() {
            Some((l, s)) => (l, s),
            None => (line_no, String::new()),
        };
        let trimmed = body.trim_end();
        if let Some(cont) = trimmed.strip_suffix('$') {
            stmt.push_str(cont);
            pending = Some((start_line, stmt));
            continue;
        }
        stmt.push_str(trimmed);
        let s = Statement::parse(&stmt, start_line)?;
        let Some(s) = s else { continue };
        match s.word.as_str() {
            "GOTO" | "FROM" => {
                let v = s.numbers(3, 6)?;
                let tip = DVec3::new(v[0], v[1], v[2]) * mm_per_unit;
                for k in 0..3 {
                    crate::reader::check_coordinate(tip[k], k, start_line, s.arg_col(k))?;
                }
                if v.len() == 6 {
                    let a = DVec3::new(v[3], v[4], v[5]);
                    axis = unit_axis(a).ok_or_else(|| s.err(s.arg_col(3), "tool axis is zero"))?;
                }
                let kind = if rapid_next || s.word == "FROM" {
                    MoveKind::Rapid
                } else {
                    classify(prev.unwrap_or(tip), tip, axis)
                };
                rapid_next = false;
                moves.push(Move {
                    kind,
                    pose: Pose { tip, axis },
                    feed_mm_per_min: if kind == MoveKind::Rapid { None } else { feed },
                    line: Some(start_line),
                    pass: None,
                });
                prev = Some(tip);
            }
            "RAPID" => {
                s.no_args()?;
                rapid_next = true;
            }
            "FEDRAT" => {
                let mut value = None;
                let mut scale = mm_per_unit;
                for (i, a) in s.args.iter().enumerate() {
                    match a.text.to_ascii_uppercase().as_str() {
                        "MMPM" => scale = 1.0,
                        "IPM" => scale = 25.4,
                        _ if value.is_none() => value = Some(s.number(i)?),
                        _ => {
                            return Err(s.err(
                                a.col,
                                "FEDRAT takes one feed value and an optional MMPM or IPM",
                            ));
                        }
                    }
                }
                let f = value.ok_or_else(|| s.err(s.col, "FEDRAT needs a feed value"))?;
                if f <= 0.0 {
                    return Err(s.err(s.arg_col(0), "feed must be positive"));
                }
                if !(f * scale).is_finite() {
                    return Err(s.err(s.arg_col(0), &format!("feed {f:e} is out of range")));
                }
                feed = Some(f * scale);
            }
            "UNITS" => {
                let a = s
                    .args
                    .first()
                    .ok_or_else(|| s.err(s.col, "UNITS needs MM or INCHES"))?;
                mm_per_unit = match a.text.to_ascii_uppercase().as_str() {
                    "MM" => 1.0,
                    "INCHES" | "INCH" => 25.4,
                    other => {
                        return Err(s.err(
                            a.col,
                            &format!("unknown unit '{other}' (expected MM or INCHES)"),
                        ));
                    }
                };
            }
            "TLAXIS" => {
                let v = s.numbers(3, 3)?;
                axis = unit_axis(DVec3::new(v[0], v[1], v[2]))
                    .ok_or_else(|| s.err(s.arg_col(0), "tool axis is zero"))?;
            }
            "FINI" => break,
            "PARTNO" | "PPRINT" | "CUTTER" | "MULTAX" | "LOADTL" | "SPINDL" | "COOLNT"
            | "INTOL" | "OUTTOL" | "TOLER" | "CLPRNT" | "NOPOST" | "END" => {}
            other => return Err(s.err(s.col, &format!("unknown APT word '{other}'"))),
        }
    }
    if let Some((l, _)) = pending {
        return Err(GcodeError::new(
            l,
            1,
            "statement continued with '$' at the end of the file",
        ));
    }
    Ok(Toolpath { moves })
}

fn unit_axis(a: DVec3) -> Option<DVec3> {
    let l = a.length();
    (l.is_finite() && l > 1e-12).then(|| a / l)
}

struct Arg {
    text: String,
    col: usize,
}

struct Statement {
    word: String,
    col: usize,
    line: usize,
    args: Vec<Arg>,
}

impl Statement {
    /// `None` for a blank statement.
    fn parse(text: &str, line: usize) -> Result<Option<Statement>, GcodeError> {
        let lead = text.len() - text.trim_start().len();
        let body = text.trim_start();
        if body.is_empty() {
            return Ok(None);
        }
        let col = text[..lead].chars().count() + 1;
        let (word, rest, rest_at) = match body.find('/') {
            Some(p) => (&body[..p], Some(&body[p + 1..]), lead + p + 1),
            None => (body, None, text.len()),
        };
        let word = word.trim().to_ascii_uppercase();
        if word.is_empty() || !word.chars().all(|c| c.is_ascii_alphanumeric()) {
            return Err(GcodeError::new(
                line,
                col,
                format!("malformed APT statement '{}'", body.trim()),
            ));
        }
        let mut args = Vec::new();
        if let Some(rest) = rest
            && !matches!(word.as_str(), "PARTNO" | "PPRINT")
        {
            let mut at = rest_at;
            for piece in rest.split(',') {
                let lead = piece.len() - piece.trim_start().len();
                args.push(Arg {
                    text: piece.trim().to_string(),
                    col: text[..at + lead].chars().count() + 1,
                });
                at += piece.len() + 1;
            }
        }
        Ok(Some(Statement {
            word,
            col,
            line,
            args,
        }))
    }

    fn err(&self, col: usize, m: &str) -> GcodeError {
        GcodeError::new(self.line, col, m.to_string())
    }

    fn arg_col(&self, i: usize) -> usize {
        self.args.get(i).map_or(self.col, |a| a.col)
    }

    fn number(&self, i: usize) -> Result<f64, GcodeError> {
        let a = &self.args[i];
        a.text
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| self.err(a.col, &format!("'{}' is not a finite number", a.text)))
    }

    fn numbers(&self, min: usize, max: usize) -> Result<Vec<f64>, GcodeError> {
        let n = self.args.len();
        if n != min && n != max {
            let want = if min == max {
                format!("{min}")
            } else {
                format!("{min} or {max}")
            };
            return Err(self.err(
                self.col,
                &format!("{} needs {want} values, found {n}", self.word),
            ));
        }
        (0..n).map(|i| self.number(i)).collect()
    }

    fn no_args(&self) -> Result<(), GcodeError> {
        match self.args.first() {
            Some(a) => Err(self.err(a.col, &format!("{} takes no values", self.word))),
            None => Ok(()),
        }
    }
}

/// Writes `toolpath` as APT CL data in mm with 6 fixed decimals: a header (`$$` comment,
/// `PARTNO`, `UNITS/MM`, `CUTTER` when known, `MULTAX/ON`), then per move `RAPID` before
/// rapids, `FEDRAT/f` when a feed move's feed changes, `GOTO/x,y,z,i,j,k` (tool tip and unit
/// axis), and `FINI`. [`parse_apt`] reads it back (tips within 5e-7 mm).
///
/// # Errors
/// Only those of `w`.
pub fn write_apt(w: &mut dyn Write, toolpath: &Toolpath, header: &AptHeader) -> io::Result<()> {
    writeln!(w, "$$ cam APT CL data: tool tip and unit tool axis, mm")?;
    writeln!(w, "PARTNO/{}", sanitize(&header.part_name))?;
    writeln!(w, "UNITS/MM")?;
    if let Some(c) = &header.cutter {
        writeln!(w, "CUTTER/{},{}", f6(c.diameter()), f6(c.corner_radius()))?;
    }
    writeln!(w, "MULTAX/ON")?;
    let mut feed: Option<String> = None;
    for m in &toolpath.moves {
        if m.kind == MoveKind::Rapid {
            writeln!(w, "RAPID")?;
        } else if let Some(f) = m.feed_mm_per_min {
            let s = f6(f);
            if feed.as_deref() != Some(s.as_str()) {
                writeln!(w, "FEDRAT/{s}")?;
                feed = Some(s);
            }
        }
        let (p, a) = (m.pose.tip, m.pose.axis);
        writeln!(
            w,
            "GOTO/{},{},{},{},{},{}",
            f6(p.x),
            f6(p.y),
            f6(p.z),
            f6(a.x),
            f6(a.y),
            f6(a.z)
        )?;
    }
    writeln!(w, "FINI")
}

fn f6(v: f64) -> String {
    crate::format::fixed(v, 6)
}

fn sanitize(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_graphic() || c == ' ' {
                c
            } else {
                '_'
            }
        })
        .collect::<String>()
        .replace('$', "_")
}
