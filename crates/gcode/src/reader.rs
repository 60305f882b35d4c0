//! The 3-axis G-code reader: RS274/NGC subset → [`Toolpath`] in mm, tool tip, axis +Z.
//!
//! # Initial position
//! The machine position before the program is unknown. Each axis becomes known when a word
//! sets it (absolute mode). Until X, Y and Z are all known, G0/G1 moves only update the known
//! axes and produce **no** [`Move`]: the first move whose end is fully known starts the path
//! (its own pose is its start, as [`Toolpath`] defines). A posted program that begins with
//! `G0 Z5` then `G0 X1 Y2` therefore starts at (1, 2, 5). Arcs and incremental (G91) moves
//! from an unknown position are errors. [`ReadConfig::initial_position_mm`] sets a known start
//! instead (rs274 starts at the origin, for example).
//!
//! # Program end
//! Lines after M2 or M30 are not executed, but they are still checked for syntax.

use cam_core::{Move, MoveKind, Pose, Toolpath};
use glam::DVec3;
use rayon::prelude::*;
use std::path::Path;

use crate::arc::{ArcSpec, Plane, centre_from_radius};
use crate::error::{GcodeError, ReadError};
use crate::words::{Line, Word, split_words};

/// Options for [`parse_gcode`].
#[derive(Debug, Clone, PartialEq)]
pub struct ReadConfig {
    /// Largest chordal deviation (mm) allowed between an arc and the chords that replace it.
    /// Default 0.001 mm.
    pub arc_tolerance_mm: f64,
    /// Largest difference (mm) between the start and end radius of an IJK arc, and by which an
    /// R-form chord may exceed the diameter. Default 0.002 mm (LinuxCNC uses 0.00127 mm).
    /// Within it the radius is interpolated linearly from start to end.
    pub arc_radius_tolerance_mm: f64,
    /// Machine position (mm) before the first line, if known; `None` (default): unknown, see
    /// the module documentation.
    pub initial_position_mm: Option<DVec3>,
    /// The block-delete switch: when `true` (default) lines starting with `/` are skipped.
    pub block_delete: bool,
}

impl Default for ReadConfig {
    fn default() -> Self {
        ReadConfig {
            arc_tolerance_mm: 0.001,
            arc_radius_tolerance_mm: 0.002,
            initial_position_mm: None,
            block_delete: true,
        }
    }
}

/// Most chords one arc may become. At the default tolerance (0.001 mm) a full circle of
/// radius 200 km needs about this many; more means the centre words are wrong, and the
/// chords would not fit in memory.
pub const MAX_ARC_CHORDS: f64 = 1.0e6;

/// Most moves a program may expand to (arcs counted by their chords): about 1.6 GB of
/// [`Move`]s.
pub const MAX_MOVES: f64 = 2.0e7;

/// A tool position (mm) must lie within [`cam_core::mesh::MAX_COORD_MM`] of the origin, as a
/// part's coordinates do: beyond that (a word a few digits too long, incremental moves adding
/// up) it is an error at the word, not a pose the planner and verifier cannot hold.
pub(crate) fn check_coordinate(
    v: f64,
    axis: usize,
    line: usize,
    col: usize,
) -> Result<(), GcodeError> {
    let limit = cam_core::mesh::MAX_COORD_MM;
    if v.abs() <= limit {
        return Ok(());
    }
    Err(GcodeError::new(
        line,
        col,
        format!(
            "{} coordinate {v:e} mm is beyond ±{limit:e} mm (1 km) of the origin",
            ["X", "Y", "Z"][axis.min(2)]
        ),
    ))
}

/// Reads the G-code file at `path` (see [`parse_gcode`]); errors carry the path.
///
/// # Errors
/// [`ReadError::Io`] if the file cannot be read, [`ReadError::Parse`] as [`parse_gcode`].
pub fn read_gcode(path: impl AsRef<Path>, cfg: &ReadConfig) -> Result<Toolpath, ReadError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|source| ReadError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_gcode(&text, cfg).map_err(|mut e| {
        e.path = Some(path.to_path_buf());
        ReadError::Parse(e)
    })
}

/// Parses a 3-axis G-code program into a toolpath (tool tip in mm, axis +Z).
///
/// Supported: G0, G1, G2, G3 (IJK and R forms, full circles, helices; G17/G18/G19), G4 P,
/// G17–G19, G20/G21, G40, G43 H, G49, G54, G61, G61.1, G64 (optional P), G80, G90/G91, G90.1/G91.1,
/// G94; M0, M1, M2, M3, M4, M5, M6, M7, M8, M9, M30; words N, O (program number), F, S, T,
/// H, P; comments `( )` and `;`; `%`; block delete `/`. Coordinates without a motion code
/// continue the modal motion. Arcs become chords within [`ReadConfig::arc_tolerance_mm`].
///
/// Each move carries its 1-based source line, its feed (mm/min, `None` for rapids or when no
/// F was given) and a kind: [`MoveKind::Rapid`] for G0, [`MoveKind::Plunge`] for a G1 that
/// only descends in Z, [`MoveKind::Retract`] for a G1 that only rises in Z, otherwise
/// [`MoveKind::Cut`]. Work offsets and tool-length offsets are not applied (the posts of this
/// crate program the tool tip with zero offsets).
///
/// # Errors
/// A [`GcodeError`] naming the line and column for anything else: an unknown G or M code, an
/// unsupported letter (A, B, C, U, V, W, D, E, ...), a malformed number, two codes of one
/// modal group on a line, a repeated word, an inconsistent arc, I/J/K/R without an arc, an arc
/// or incremental move from an unknown position.
pub fn parse_gcode(text: &str, cfg: &ReadConfig) -> Result<Toolpath, GcodeError> {
    let mut st = State::new(cfg);
    // Each line's words are read on their own, in parallel, a chunk of lines at a time;
    // the blocks are then executed in order, so the first error in line order is the one
    // returned, as reading line by line gives (a program of 100 k lines spent 65 M
    // instructions here, on one thread, before anything else could start).
    let lines: Vec<&str> = text.lines().collect();
    for (c, chunk) in lines.chunks(PARSE_CHUNK).enumerate() {
        let first = c * PARSE_CHUNK + 1;
        let blocks: Vec<Result<Option<Block>, GcodeError>> = chunk
            .par_iter()
            .enumerate()
            .map(|(k, raw)| {
                let line = first + k;
                match split_words(raw, line, cfg.block_delete)? {
                    Line::Words(words) => Block::from_words(&words, line).map(Some),
                    Line::Empty => Ok(None),
                }
            })
            .collect();
        for (k, block) in blocks.into_iter().enumerate() {
            if let Some(block) = block?
                && !st.ended
            {
                st.execute(&block, first + k)?;
            }
        }
    }
    Ok(Toolpath { moves: st.moves })
}

/// Lines whose words are read together (in parallel) before their blocks are executed.
const PARSE_CHUNK: usize = 8192;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Motion {
    Rapid,
    Linear,
    Cw,
    Ccw,
}

/// One line's words, classified.
#[derive(Default)]
struct Block {
    motion: Option<(Option<Motion>, usize)>, // None inside = G80
    plane: Option<Plane>,
    units_mm: Option<f64>,
    absolute: Option<bool>,
    arc_absolute: Option<bool>,
    dwell: bool,
    g43: bool,
    g64: bool,
    end: bool,
    axes: [Option<(f64, usize)>; 3],
    ijk: [Option<(f64, usize)>; 3],
    r: Option<(f64, usize)>,
    f: Option<(f64, usize)>,
    h: Option<(f64, usize)>,
    p: Option<(f64, usize)>,
}

fn code_of(w: &Word) -> Option<u32> {
    let t = w.value * 10.0;
    let r = t.round();
    ((t - r).abs() < 1e-6 && r >= 0.0).then_some(r as u32)
}

impl Block {
    fn from_words(words: &[Word], line: usize) -> Result<Block, GcodeError> {
        let err = |w: &Word, m: String| GcodeError::new(line, w.col, m);
        let mut b = Block::default();
        let mut seen: Vec<char> = Vec::new();
        let mut groups: Vec<(&str, usize)> = Vec::new();
        let mut group = |name: &'static str, w: &Word| -> Result<(), GcodeError> {
            if let Some(&(_, col)) = groups.iter().find(|(g, _)| *g == name) {
                let what = if name == "motion" {
                    "two motion codes".to_string()
                } else {
                    format!("two {name} codes")
                };
                return Err(GcodeError::new(
                    line,
                    w.col,
                    format!("{what} on one line (the first at column {col})"),
                ));
            }
            groups.push((name, w.col));
            Ok(())
        };
        for (k, w) in words.iter().enumerate() {
            let c = w.letter;
            if !matches!(c, 'G' | 'M') {
                if seen.contains(&c) {
                    return Err(err(w, format!("word '{c}' appears twice on one line")));
                }
                seen.push(c);
            }
            let slot = Some((w.value, w.col));
            match c {
                'G' => {
                    let code =
                        code_of(w).ok_or_else(|| err(w, format!("unknown G code G{}", w.value)))?;
                    match code {
                        0 | 10 | 20 | 30 => {
                            group("motion", w)?;
                            let m = match code {
                                0 => Motion::Rapid,
                                10 => Motion::Linear,
                                20 => Motion::Cw,
                                _ => Motion::Ccw,
                            };
                            b.motion = Some((Some(m), w.col));
                        }
                        800 => {
                            group("motion", w)?;
                            b.motion = Some((None, w.col));
                        }
                        170 | 180 | 190 => {
                            group("plane", w)?;
                            b.plane = Some(match code {
                                170 => Plane::Xy,
                                180 => Plane::Zx,
                                _ => Plane::Yz,
                            });
                        }
                        200 | 210 => {
                            group("units", w)?;
                            b.units_mm = Some(if code == 200 { 25.4 } else { 1.0 });
                        }
                        900 | 910 => {
                            group("distance mode", w)?;
                            b.absolute = Some(code == 900);
                        }
                        901 | 911 => {
                            group("arc distance mode", w)?;
                            b.arc_absolute = Some(code == 901);
                        }
                        40 => {
                            group("non-modal", w)?;
                            b.dwell = true;
                        }
                        430 | 490 => {
                            group("tool length offset", w)?;
                            b.g43 = code == 430;
                        }
                        610 | 611 | 640 => {
                            group("path control", w)?;
                            b.g64 = code == 640;
                        }
                        540 => group("work offset", w)?,
                        400 => group("cutter compensation", w)?,
                        940 => group("feed mode", w)?,
                        _ => return Err(err(w, format!("unsupported G code G{}", fmt_code(code)))),
                    }
                }
                'M' => {
                    let code = code_of(w).filter(|c| c.is_multiple_of(10)).map(|c| c / 10);
                    match code {
                        Some(0 | 1 | 6) => group("stop/tool change", w)?,
                        Some(2 | 30) => {
                            group("program end", w)?;
                            b.end = true;
                        }
                        Some(3..=5) => group("spindle", w)?,
                        Some(7..=9) => group("coolant", w)?,
                        _ => return Err(err(w, format!("unsupported M code M{}", w.value))),
                    }
                }
                'X' => b.axes[0] = slot,
                'Y' => b.axes[1] = slot,
                'Z' => b.axes[2] = slot,
                'I' => b.ijk[0] = slot,
                'J' => b.ijk[1] = slot,
                'K' => b.ijk[2] = slot,
                'R' => b.r = slot,
                'F' => {
                    if w.value < 0.0 {
                        return Err(err(w, "negative feed rate".into()));
                    }
                    // In inch programs too (25.4 mm per unit).
                    if !(w.value * 25.4).is_finite() {
                        return Err(err(w, format!("feed rate {:e} is out of range", w.value)));
                    }
                    b.f = slot;
                }
                'H' => b.h = slot,
                'P' => b.p = slot,
                'N' | 'S' | 'T' => {
                    if w.value < 0.0 {
                        return Err(err(w, format!("negative {c} word")));
                    }
                }
                'O' => {
                    if k != 0 && !(k == 1 && words[0].letter == 'N') {
                        return Err(err(w, "O program number must start the line".into()));
                    }
                    if words.len() > k + 1 {
                        return Err(err(
                            &words[k + 1],
                            "O words (subroutines, control flow) are not supported".into(),
                        ));
                    }
                }
                'A' | 'B' | 'C' | 'U' | 'V' | 'W' => {
                    return Err(err(
                        w,
                        format!("axis {c} is not supported by the 3-axis reader (use APT CL data)"),
                    ));
                }
                _ => return Err(err(w, format!("unsupported word letter '{c}'"))),
            }
        }
        if let Some((_, col)) = b.h
            && !b.g43
        {
            return Err(GcodeError::new(line, col, "H word without G43"));
        }
        if let Some((_, col)) = b.p
            && !(b.dwell || b.g64)
        {
            return Err(GcodeError::new(line, col, "P word without G4 or G64"));
        }
        if b.dwell && b.p.is_none() {
            let col = groups
                .iter()
                .find(|(g, _)| *g == "non-modal")
                .map_or(1, |g| g.1);
            return Err(GcodeError::new(line, col, "G4 dwell needs a P word"));
        }
        Ok(b)
    }
}

fn fmt_code(code: u32) -> String {
    if code.is_multiple_of(10) {
        format!("{}", code / 10)
    } else {
        format!("{}.{}", code / 10, code % 10)
    }
}

struct State<'a> {
    cfg: &'a ReadConfig,
    pos: [Option<f64>; 3],
    mm_per_unit: f64,
    absolute: bool,
    arc_absolute: bool,
    plane: Plane,
    motion: Option<Motion>,
    feed_units: Option<f64>,
    ended: bool,
    moves: Vec<Move>,
}

impl<'a> State<'a> {
    fn new(cfg: &'a ReadConfig) -> Self {
        let pos = match cfg.initial_position_mm {
            Some(p) => [Some(p.x), Some(p.y), Some(p.z)],
            None => [None; 3],
        };
        State {
            cfg,
            pos,
            mm_per_unit: 1.0,
            absolute: true,
            arc_absolute: false,
            plane: Plane::Xy,
            motion: None,
            feed_units: None,
            ended: false,
            moves: Vec::new(),
        }
    }

    fn execute(&mut self, b: &Block, line: usize) -> Result<(), GcodeError> {
        if let Some((f, _)) = b.f {
            self.feed_units = Some(f);
        }
        if let Some(p) = b.plane {
            self.plane = p;
        }
        if let Some(k) = b.units_mm {
            self.mm_per_unit = k;
        }
        if let Some(a) = b.absolute {
            self.absolute = a;
        }
        if let Some(a) = b.arc_absolute {
            self.arc_absolute = a;
        }
        if let Some((m, _)) = b.motion {
            self.motion = m;
        }
        let has_axes = b.axes.iter().any(Option::is_some);
        let first_arc_word = b.ijk.iter().chain([&b.r]).flatten().map(|&(_, c)| c).min();
        let motion_col = b.motion.map(|m| m.1);
        match self.motion {
            Some(Motion::Cw | Motion::Ccw)
                if has_axes || first_arc_word.is_some() || motion_col.is_some() =>
            {
                let col = motion_col
                    .or(b.axes.iter().flatten().map(|a| a.1).min())
                    .unwrap_or(1);
                self.arc(b, line, col)?;
            }
            Some(m @ (Motion::Rapid | Motion::Linear)) => {
                if let Some(col) = first_arc_word {
                    return Err(GcodeError::new(line, col, "I/J/K/R words need G2 or G3"));
                }
                if has_axes {
                    self.straight(b, line, m)?;
                }
            }
            None => {
                if let Some(col) = b.axes.iter().flatten().map(|a| a.1).min() {
                    return Err(GcodeError::new(
                        line,
                        col,
                        "coordinates without a motion mode (G0/G1/G2/G3)",
                    ));
                }
                if let Some(col) = first_arc_word {
                    return Err(GcodeError::new(line, col, "I/J/K/R words need G2 or G3"));
                }
            }
            _ => {}
        }
        if b.end {
            self.ended = true;
        }
        Ok(())
    }

    /// Target position (mm); `None` per axis where still unknown.
    fn target(&self, b: &Block, line: usize) -> Result<[Option<f64>; 3], GcodeError> {
        let mut t = self.pos;
        for (i, ti) in t.iter_mut().enumerate() {
            if let Some((v, col)) = b.axes[i] {
                let v = v * self.mm_per_unit;
                let v = if self.absolute {
                    v
                } else {
                    self.pos[i].ok_or_else(|| {
                        GcodeError::new(
                            line,
                            col,
                            "incremental (G91) move from an unknown position",
                        )
                    })? + v
                };
                check_coordinate(v, i, line, col)?;
                *ti = Some(v);
            }
        }
        Ok(t)
    }

    fn feed_mm(&self) -> Option<f64> {
        self.feed_units.map(|f| f * self.mm_per_unit)
    }

    fn straight(&mut self, b: &Block, line: usize, m: Motion) -> Result<(), GcodeError> {
        let t = self.target(b, line)?;
        let prev = self.known();
        self.pos = t;
        let Some(end) = self.known() else {
            return Ok(());
        };
        let kind = if m == Motion::Rapid {
            MoveKind::Rapid
        } else {
            classify(prev.unwrap_or(end), end, DVec3::Z)
        };
        let feed = if m == Motion::Rapid {
            None
        } else {
            self.feed_mm()
        };
        self.push(kind, end, feed, line);
        Ok(())
    }

    fn known(&self) -> Option<DVec3> {
        Some(DVec3::new(self.pos[0]?, self.pos[1]?, self.pos[2]?))
    }

    fn push(&mut self, kind: MoveKind, tip: DVec3, feed: Option<f64>, line: usize) {
        self.moves.push(Move {
            kind,
            pose: Pose::vertical(tip),
            feed_mm_per_min: feed,
            line: Some(line),
            pass: None,
        });
    }

    fn arc(&mut self, b: &Block, line: usize, col: usize) -> Result<(), GcodeError> {
        let e = |c: usize, m: &str| GcodeError::new(line, c, m.to_string());
        let start = self
            .known()
            .ok_or_else(|| e(col, "arc from an unknown position"))?;
        let t = self.target(b, line)?;
        let end = DVec3::new(
            t[0].unwrap_or(start.x),
            t[1].unwrap_or(start.y),
            t[2].unwrap_or(start.z),
        );
        let (pa, pb, pn) = self.plane.axes();
        const L: [char; 3] = ['I', 'J', 'K'];
        if let Some((_, c)) = b.ijk[pn] {
            return Err(e(
                c,
                &format!("{} word is not allowed for an arc in this plane", L[pn]),
            ));
        }
        let clockwise = self.motion == Some(Motion::Cw);
        let k = self.mm_per_unit;
        let centre = if let Some((r, rc)) = b.r {
            if let Some(c) = [b.ijk[pa], b.ijk[pb]].iter().flatten().map(|x| x.1).min() {
                return Err(e(c, "arc has both R and I/J/K words"));
            }
            if r == 0.0 {
                return Err(e(rc, "arc radius R is zero"));
            }
            let s2 = [start[pa], start[pb]];
            let e2 = [end[pa], end[pb]];
            if (e2[0] - s2[0]).hypot(e2[1] - s2[1]) <= 1e-12 {
                return Err(e(
                    rc,
                    "R-form arc with the end equal to the start (use I/J/K for a full circle)",
                ));
            }
            let r = r * k;
            let slack = self.radius_tolerance(r.abs());
            centre_from_radius(s2, e2, r, clockwise, slack).ok_or_else(|| {
                e(
                    rc,
                    &format!("arc radius {:.6} mm is less than half the chord", r.abs()),
                )
            })?
        } else {
            if b.ijk[pa].is_none() && b.ijk[pb].is_none() {
                return Err(e(col, "arc needs I/J/K (centre) or R words"));
            }
            let off = |i: usize| b.ijk[i].map_or(0.0, |v| v.0) * k;
            if self.arc_absolute {
                [
                    b.ijk[pa].map_or(start[pa], |v| v.0 * k),
                    b.ijk[pb].map_or(start[pb], |v| v.0 * k),
                ]
            } else {
                [start[pa] + off(pa), start[pb] + off(pb)]
            }
        };
        let spec = ArcSpec {
            start,
            end,
            centre,
            plane: self.plane,
            clockwise,
        };
        let (r0, r1) = spec.radii();
        if r0 <= 1e-12 {
            return Err(e(col, "arc centre coincides with its start"));
        }
        if (r0 - r1).abs() > self.radius_tolerance(r0.max(r1)) {
            return Err(e(
                col,
                &format!(
                    "arc radius to end ({r1:.6} mm) differs from radius to start ({r0:.6} mm) by {:.6} mm",
                    (r0 - r1).abs()
                ),
            ));
        }
        let tol = self.cfg.arc_tolerance_mm;
        let chords = spec.chord_count(tol);
        if !(chords <= MAX_ARC_CHORDS && self.moves.len() as f64 + chords <= MAX_MOVES) {
            return Err(e(
                col,
                &format!(
                    "arc of radius {:.6} mm sweeping {:.3}° needs {chords:.3e} chords to stay \
                     within the arc tolerance {tol} mm: more than the {} allowed per arc ({} per \
                     program); check its centre words",
                    r0.max(r1),
                    spec.sweep().abs().to_degrees(),
                    MAX_ARC_CHORDS,
                    MAX_MOVES
                ),
            ));
        }
        let feed = self.feed_mm();
        for p in spec.chord_points(tol) {
            self.push(MoveKind::Cut, p, feed, line);
        }
        self.pos = [Some(end.x), Some(end.y), Some(end.z)];
        Ok(())
    }

    fn radius_tolerance(&self, _r: f64) -> f64 {
        self.cfg.arc_radius_tolerance_mm
    }
}

/// Kind of a feed move from `from` to `to` for tool axis `axis`: [`MoveKind::Plunge`] when it
/// moves only along −axis, [`MoveKind::Retract`] only along +axis, else [`MoveKind::Cut`].
pub(crate) fn classify(from: DVec3, to: DVec3, axis: DVec3) -> MoveKind {
    let d = to - from;
    let along = d.dot(axis);
    let across = (d - along * axis).length();
    if across > 1e-9 || along.abs() <= 1e-12 {
        MoveKind::Cut
    } else if along < 0.0 {
        MoveKind::Plunge
    } else {
        MoveKind::Retract
    }
}
