//! Test support: run LinuxCNC's standalone interpreter `rs274` on a program and read its
//! canonical straight motions back.
//!
//! `rs274 -g -t TOOL_TABLE PROGRAM CANON` interprets the whole program and writes one
//! canonical machining command per line (`STRAIGHT_TRAVERSE(x, y, z, a, b, c)`,
//! `STRAIGHT_FEED(...)`, `USE_LENGTH_UNITS(CANON_UNITS_MM)`, ...). Coordinates are printed in
//! the program's units (G20 → inches) with 4 decimals; work and tool-length offsets are not
//! applied. The interpreter starts at the origin. Debian package: `linuxcnc-uspace`.

use cam_core::Units;
use glam::DVec3;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// Kind of a canonical motion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CanonKind {
    /// `STRAIGHT_TRAVERSE` (G0).
    Traverse,
    /// `STRAIGHT_FEED` (G1).
    Feed,
    /// `ARC_FEED` (G2/G3) in the plane selected by the last `SELECT_PLANE`.
    Arc {
        /// The arc centre X, Y, Z in the move's units; its coordinate along the plane normal
        /// is the arc's end value on that axis.
        centre: [f64; 3],
        /// rs274's rotation: positive counter-clockwise, negative clockwise (seen from the
        /// positive normal axis); |rotation| > 1 adds full turns.
        rotation: i32,
        /// Index of the plane normal axis: 2 for G17 (XY), 1 for G18 (XZ), 0 for G19 (YZ).
        normal_axis: usize,
    },
}

/// One canonical motion as `rs274` printed it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CanonMove {
    /// Traverse, feed or arc.
    pub kind: CanonKind,
    /// End point X, Y, Z in `units` (as printed, 4 decimals).
    pub xyz: [f64; 3],
    /// The length units in force (`USE_LENGTH_UNITS`) when the move was printed.
    pub units: Units,
    /// 1-based line of the canon output.
    pub canon_line: usize,
}

impl CanonMove {
    /// End point in mm.
    pub fn tip_mm(&self) -> DVec3 {
        DVec3::from_array(self.xyz) * self.units.mm_per_unit()
    }
}

/// Where `rs274` and its tool table are.
#[derive(Debug, Clone, PartialEq)]
pub struct Rs274Config {
    /// The executable (default `rs274`, searched on `PATH`).
    pub program: PathBuf,
    /// Tool table passed with `-t` (default: the workspace's `fixtures/rs274/tool-table.tbl`,
    /// T1..T10 with zero length offsets).
    pub tool_table: PathBuf,
}

impl Default for Rs274Config {
    fn default() -> Self {
        Rs274Config {
            program: PathBuf::from("rs274"),
            tool_table: default_tool_table(),
        }
    }
}

/// The workspace's `fixtures/rs274/tool-table.tbl` (located from this crate's source dir).
pub fn default_tool_table() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/rs274/tool-table.tbl")
}

/// Why `rs274` could not produce canonical motions.
#[derive(Debug, thiserror::Error)]
pub enum Rs274Error {
    /// The executable could not be started (not installed, not on `PATH`).
    #[error("cannot run {}: {source}", program.display())]
    Spawn {
        /// The executable.
        program: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// `rs274` exited with a failure status (interpreter error); its output is kept.
    #[error("rs274 failed on {} ({status}): {output}", program_file.display())]
    Failed {
        /// The G-code file.
        program_file: PathBuf,
        /// Exit status as text.
        status: String,
        /// stdout and stderr.
        output: String,
    },
    /// The canon file could not be read.
    #[error("cannot read canon output {}: {source}", path.display())]
    Io {
        /// The canon file.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// A canon line could not be parsed.
    #[error("canon line {line}: {message}")]
    Canon {
        /// 1-based canon line.
        line: usize,
        /// What is wrong.
        message: String,
    },
}

/// Whether `rs274` can be started from `PATH`.
pub fn rs274_available() -> bool {
    let Some(path) = std::env::var_os("PATH") else {
        return false;
    };
    std::env::split_paths(&path).any(|d| d.join("rs274").is_file())
}

/// For test suites that run programs through `rs274`: `true` when it is on `PATH`; when it
/// is not, `false` (the caller skips, with a note on stderr), except under `CI=true`, where
/// a missing interpreter is a failure (`.ci/run` installs it).
///
/// # Panics
/// When `rs274` is missing and the environment has `CI=true`.
pub fn rs274_for_tests() -> bool {
    if rs274_available() {
        return true;
    }
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        panic!("rs274 is not on PATH but CI=true: install linuxcnc-uspace (see .ci/run)");
    }
    eprintln!("rs274 not on PATH: skipping the real-client test (CI=true makes this a failure)");
    false
}

/// Runs `rs274` with the default [`Rs274Config`] on `ngc_path`; the canon text goes next to it
/// (`<ngc_path>.canon.txt`). Returns the straight motions in order.
///
/// # Errors
/// See [`Rs274Error`].
pub fn run_rs274(ngc_path: impl AsRef<Path>) -> Result<Vec<CanonMove>, Rs274Error> {
    run_rs274_with(ngc_path, &Rs274Config::default())
}

/// [`run_rs274`] with an explicit executable and tool table.
///
/// # Errors
/// See [`Rs274Error`].
pub fn run_rs274_with(
    ngc_path: impl AsRef<Path>,
    cfg: &Rs274Config,
) -> Result<Vec<CanonMove>, Rs274Error> {
    let ngc = ngc_path.as_ref();
    let mut canon = ngc.as_os_str().to_owned();
    canon.push(".canon.txt");
    let canon = PathBuf::from(canon);
    // Concurrent rs274 processes crash (SIGBUS) even in separate directories: the
    // standalone interpreter shares state machine-wide. Serialise runs across threads and
    // processes with an exclusive lock on a file in the temporary directory.
    let lock_path = std::env::temp_dir().join("cam-rs274.lock");
    let lock = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&lock_path)
        .map_err(|source| Rs274Error::Io {
            path: lock_path.clone(),
            source,
        })?;
    lock.lock().map_err(|source| Rs274Error::Io {
        path: lock_path.clone(),
        source,
    })?;
    let out = Command::new(&cfg.program)
        .arg("-g")
        .arg("-t")
        .arg(&cfg.tool_table)
        .arg(ngc)
        .arg(&canon)
        .stdin(Stdio::null())
        .output()
        .map_err(|source| Rs274Error::Spawn {
            program: cfg.program.clone(),
            source,
        })?;
    if !out.status.success() {
        return Err(Rs274Error::Failed {
            program_file: ngc.to_path_buf(),
            status: out.status.to_string(),
            output: format!(
                "{}{}",
                String::from_utf8_lossy(&out.stdout),
                String::from_utf8_lossy(&out.stderr)
            ),
        });
    }
    let text = std::fs::read_to_string(&canon).map_err(|source| Rs274Error::Io {
        path: canon.clone(),
        source,
    })?;
    parse_canon(&text)
}

/// Parses `rs274` canon output: `STRAIGHT_TRAVERSE`, `STRAIGHT_FEED` and `ARC_FEED` lines
/// become [`CanonMove`]s, `USE_LENGTH_UNITS` sets their units and `SELECT_PLANE` the arc
/// plane; everything else is skipped.
///
/// # Errors
/// [`Rs274Error::Canon`] for a motion line whose arguments are not numbers.
pub fn parse_canon(text: &str) -> Result<Vec<CanonMove>, Rs274Error> {
    let mut units = Units::Mm;
    // (first in-plane axis, second, normal) of the selected plane.
    let mut plane = (0usize, 1usize, 2usize);
    let mut out = Vec::new();
    for (i, l) in text.lines().enumerate() {
        let line = i + 1;
        let Some(open) = l.find('(') else { continue };
        let name = l[..open].split_whitespace().last().unwrap_or("");
        let args = l[open + 1..].trim_end().trim_end_matches(')');
        let kind = match name {
            "USE_LENGTH_UNITS" => {
                units = if args.contains("INCHES") {
                    Units::Inch
                } else {
                    Units::Mm
                };
                continue;
            }
            "SELECT_PLANE" => {
                plane = if args.contains("XZ") {
                    (2, 0, 1)
                } else if args.contains("YZ") {
                    (1, 2, 0)
                } else {
                    (0, 1, 2)
                };
                continue;
            }
            "STRAIGHT_TRAVERSE" | "STRAIGHT_FEED" | "ARC_FEED" => name,
            _ => continue,
        };
        let need = if kind == "ARC_FEED" { 6 } else { 3 };
        let v: Vec<f64> = args
            .split(',')
            .take(need)
            .map(|s| s.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|e| Rs274Error::Canon {
                line,
                message: format!("{name}: {e}"),
            })?;
        if v.len() < need {
            return Err(Rs274Error::Canon {
                line,
                message: format!("{name}: fewer than {need} values"),
            });
        }
        let (kind, xyz) = match kind {
            "STRAIGHT_TRAVERSE" => (CanonKind::Traverse, [v[0], v[1], v[2]]),
            "STRAIGHT_FEED" => (CanonKind::Feed, [v[0], v[1], v[2]]),
            _ => {
                let (a, b, n) = plane;
                let mut end = [0.0; 3];
                let mut centre = [0.0; 3];
                (end[a], end[b], end[n]) = (v[0], v[1], v[5]);
                (centre[a], centre[b], centre[n]) = (v[2], v[3], v[5]);
                let rotation = v[4] as i32;
                if f64::from(rotation) != v[4] {
                    return Err(Rs274Error::Canon {
                        line,
                        message: format!("ARC_FEED: rotation {} is not an integer", v[4]),
                    });
                }
                (
                    CanonKind::Arc {
                        centre,
                        rotation,
                        normal_axis: n,
                    },
                    end,
                )
            }
        };
        out.push(CanonMove {
            kind,
            xyz,
            units,
            canon_line: line,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_canon_lines() {
        let t = "    1 N..... USE_LENGTH_UNITS(CANON_UNITS_MM)\n   23 N..... STRAIGHT_TRAVERSE(0.0000, 0.0000, 10.0000, 0.0000, 0.0000, 0.0000)\n   11 N..... USE_LENGTH_UNITS(CANON_UNITS_INCHES)\n   26 N..... STRAIGHT_FEED(1.2345, 2.0000, -1.0000, 0.0000, 0.0000, 0.0000)\n";
        let m = parse_canon(t).unwrap();
        assert_eq!(m.len(), 2);
        assert_eq!(
            (m[0].kind, m[0].xyz, m[0].units),
            (CanonKind::Traverse, [0.0, 0.0, 10.0], Units::Mm)
        );
        assert_eq!(
            (m[1].kind, m[1].units, m[1].canon_line),
            (CanonKind::Feed, Units::Inch, 4)
        );
        assert!((m[1].tip_mm().x - 1.2345 * 25.4).abs() < 1e-12);
        let t = "13 N..... SELECT_PLANE(CANON_PLANE_XZ)\n15 N..... ARC_FEED(1.0000, 10.0000, 2.0000, 3.0000, -1, 4.0000, 0.0000, 0.0000, 0.0000)\n";
        let m = parse_canon(t).unwrap();
        assert_eq!(m[0].xyz, [10.0, 4.0, 1.0]);
        assert_eq!(
            m[0].kind,
            CanonKind::Arc {
                centre: [3.0, 4.0, 2.0],
                rotation: -1,
                normal_axis: 1
            }
        );
    }
}
