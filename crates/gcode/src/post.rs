//! Post-processors: a 3-axis [`Toolpath`] (tool tip, mm) → G-code for LinuxCNC, Grbl or Fanuc.
//!
//! Every program has the same shape:
//! 1. framing and header comments (part, tool, tolerance τ, scallop h, post, units, feeds and
//!    `(CL convention: tool tip)`; Fanuc: `%`, `O<n>`, upper-case comments of at most 32
//!    characters);
//! 2. modal preamble `G21|G20 G90 G17 G94 ...`, tool change `T<n> M6` (LinuxCNC, Fanuc; Grbl
//!    gets a comment only), spindle `S<rpm> M3|M4`, approach `G0 G43 H<n> Z<safe>` (Grbl:
//!    `G0 Z<safe>`, it has no tool table);
//! 3. one line per move: `G0` for rapids, `G1` at the plunge feed for [`MoveKind::Plunge`] and
//!    at the cutting feed otherwise; unchanged coordinates, feeds and motion codes are not
//!    repeated, and a move that changes no printed coordinate is dropped; when the first move
//!    is not a rapid, `G0 X Y` at safe Z goes first;
//! 4. `G0 Z<safe>` if the last move ends below safe Z, `M5`, `M30` (Fanuc: then `%`).
//!
//! Coordinates have fixed decimals: 4 in mm, 5 in inch; feeds 1 decimal (mm/min) or 2
//! (in/min). Rapids are emitted only at or above safe Z (a pure upward Z rapid from below is
//! allowed, since it leaves the part); anything else is [`PostError::RapidBelowSafeZ`].

use cam_core::{MoveKind, Toolpath, Units};
use glam::DVec3;
use std::fmt;
use std::io::Write;
use std::str::FromStr;

use crate::error::PostError;
use crate::format::fixed;

/// The controls we post for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub enum Post {
    /// LinuxCNC (RS274/NGC): `( )` comments, `T M6`, `G43 H`.
    #[default]
    LinuxCnc,
    /// Grbl 1.1: no tool changer and no tool-length offset words (tool named in a comment).
    Grbl,
    /// Fanuc-style: `%` framing, `O` program number, upper-case comments ≤ 32 characters.
    Fanuc,
}

impl Post {
    /// Every post, in a fixed order.
    pub const ALL: [Post; 3] = [Post::LinuxCnc, Post::Grbl, Post::Fanuc];

    /// The post's name as used on the command line: `linuxcnc`, `grbl`, `fanuc`.
    pub fn name(self) -> &'static str {
        match self {
            Post::LinuxCnc => "linuxcnc",
            Post::Grbl => "grbl",
            Post::Fanuc => "fanuc",
        }
    }
}

impl fmt::Display for Post {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Post {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "linuxcnc" => Ok(Post::LinuxCnc),
            "grbl" => Ok(Post::Grbl),
            "fanuc" => Ok(Post::Fanuc),
            _ => Err(format!(
                "unknown post '{s}' (expected linuxcnc, grbl or fanuc)"
            )),
        }
    }
}

/// Job parameters for [`post`]. All lengths in mm, feeds in mm/min, whatever `units` says
/// about the output.
#[derive(Debug, Clone, PartialEq)]
pub struct PostJob {
    /// Part name for the header.
    pub part_name: String,
    /// Tool specification for the header, e.g. `ball:6`.
    pub tool_spec: String,
    /// Tool number (T and H words).
    pub tool_number: u32,
    /// Chordal tolerance τ the path was planned with (mm), for the header.
    pub tolerance_mm: f64,
    /// Scallop height h the path was planned with (mm), for the header.
    pub scallop_mm: f64,
    /// Cutting feed (mm/min) for [`MoveKind::Cut`] and [`MoveKind::Retract`] moves; > 0.
    pub feed_mm_per_min: f64,
    /// Plunge feed (mm/min) for [`MoveKind::Plunge`] moves; > 0.
    pub plunge_feed_mm_per_min: f64,
    /// Spindle speed (rev/min); ≥ 0.
    pub rpm: f64,
    /// Spindle clockwise (M3) when `true`, counter-clockwise (M4) when `false`.
    pub spindle_cw: bool,
    /// Safe Z for rapids (mm, tool tip).
    pub safe_z_mm: f64,
    /// Output units (G21 mm or G20 inch); the toolpath is converted from mm.
    pub units: Units,
    /// Fanuc program number (`O<n>`), 1..=9999.
    pub program_number: u32,
    /// When `true`, a feed move's own `feed_mm_per_min` (if `Some`) overrides the job feeds.
    pub use_move_feeds: bool,
}

impl Default for PostJob {
    fn default() -> Self {
        PostJob {
            part_name: "part".into(),
            tool_spec: "ball:6".into(),
            tool_number: 1,
            tolerance_mm: 0.01,
            scallop_mm: 0.005,
            feed_mm_per_min: 1000.0,
            plunge_feed_mm_per_min: 300.0,
            rpm: 10000.0,
            spindle_cw: true,
            safe_z_mm: 5.0,
            units: Units::Mm,
            program_number: 1000,
            use_move_feeds: false,
        }
    }
}

/// Writes `toolpath` (3-axis, tool tip in mm) as a G-code program for `post` to `w`.
///
/// # Errors
/// [`PostError::InvalidJob`], [`PostError::NonFinite`], [`PostError::NotThreeAxis`] or
/// [`PostError::RapidBelowSafeZ`] before anything is written; [`PostError::Io`] if writing
/// fails.
pub fn post(
    toolpath: &Toolpath,
    job: &PostJob,
    post: Post,
    w: &mut dyn Write,
) -> Result<(), PostError> {
    validate(toolpath, job)?;
    let mut out = Writer::new(job, post);
    out.header();
    let safe = job.safe_z_mm;
    for (i, m) in toolpath.moves.iter().enumerate() {
        let t = m.pose.tip;
        if i == 0 && m.kind != MoveKind::Rapid {
            out.motion(0, Some(t.x), Some(t.y), Some(safe), None);
        }
        if m.kind == MoveKind::Rapid {
            out.motion(0, Some(t.x), Some(t.y), Some(t.z), None);
        } else {
            let feed = match (job.use_move_feeds, m.feed_mm_per_min) {
                (true, Some(f)) => f,
                _ if m.kind == MoveKind::Plunge => job.plunge_feed_mm_per_min,
                _ => job.feed_mm_per_min,
            };
            out.motion(1, Some(t.x), Some(t.y), Some(t.z), Some(feed));
        }
    }
    if toolpath.moves.last().is_some_and(|m| m.pose.tip.z < safe) {
        out.motion(0, None, None, Some(safe), None);
    }
    out.footer();
    w.write_all(out.text.as_bytes())?;
    w.flush()?;
    Ok(())
}

/// [`post`] into a `String`.
///
/// # Errors
/// As [`post`] (never [`PostError::Io`]).
pub fn post_to_string(toolpath: &Toolpath, job: &PostJob, p: Post) -> Result<String, PostError> {
    let mut buf = Vec::new();
    post(toolpath, job, p, &mut buf)?;
    Ok(String::from_utf8(buf).expect("the posts write ASCII"))
}

const EPS_MM: f64 = 1e-9;

fn validate(tp: &Toolpath, job: &PostJob) -> Result<(), PostError> {
    let bad = |m: &str| Err(PostError::InvalidJob(m.to_string()));
    if !(job.feed_mm_per_min.is_finite() && job.feed_mm_per_min > 0.0) {
        return bad("feed_mm_per_min must be a positive number");
    }
    if !(job.plunge_feed_mm_per_min.is_finite() && job.plunge_feed_mm_per_min > 0.0) {
        return bad("plunge_feed_mm_per_min must be a positive number");
    }
    if !(job.rpm.is_finite() && job.rpm >= 0.0) {
        return bad("rpm must be a number >= 0");
    }
    if !job.safe_z_mm.is_finite() {
        return bad("safe_z_mm must be finite");
    }
    if !(1..=9999).contains(&job.program_number) {
        return bad("program_number must be in 1..=9999");
    }
    let safe = job.safe_z_mm;
    let mut prev: Option<DVec3> = None;
    for (i, m) in tp.moves.iter().enumerate() {
        let t = m.pose.tip;
        if !t.is_finite() {
            return Err(PostError::NonFinite { move_index: i });
        }
        if (m.pose.axis - DVec3::Z).length() > 1e-9 {
            return Err(PostError::NotThreeAxis {
                move_index: i,
                axis: m.pose.axis.to_array(),
            });
        }
        if m.kind == MoveKind::Rapid {
            let start_ok = match prev {
                None => true,
                Some(p) => {
                    p.z >= safe - EPS_MM
                        || (p.truncate().distance(t.truncate()) <= EPS_MM && t.z >= p.z)
                }
            };
            if t.z < safe - EPS_MM || !start_ok {
                let z = prev.map_or(t.z, |p| p.z.min(t.z));
                return Err(PostError::RapidBelowSafeZ {
                    move_index: i,
                    line: m.line,
                    z_mm: z,
                    safe_z_mm: safe,
                });
            }
        }
        prev = Some(t);
    }
    Ok(())
}

/// Fixed decimals of coordinates in a program of `units`.
fn coordinate_decimals(units: Units) -> usize {
    match units {
        Units::Mm => 4,
        Units::Inch => 5,
    }
}

/// The largest distance (mm) between a tool position and the position a program in `units`
/// writes for it: half the last written decimal on each of X, Y and Z, `√3 · ½·10⁻ᵈ` units
/// (8.7e-5 mm for mm programs, 2.2e-4 mm for inch). A move between written points lies
/// within this of the move between the exact ones, so the cutter's penetration and excess
/// change by at most this much: a planner that must hold a tolerance in the written program
/// plans to the tolerance less this.
pub fn rounding_mm(units: Units) -> f64 {
    3f64.sqrt() * 0.5 * 10f64.powi(-(coordinate_decimals(units) as i32)) * units.mm_per_unit()
}

struct Writer<'a> {
    job: &'a PostJob,
    post: Post,
    mm_per_unit: f64,
    decimals: usize,
    feed_decimals: usize,
    last_xyz: [Option<String>; 3],
    last_g: Option<u8>,
    last_f: Option<String>,
    text: String,
}

impl<'a> Writer<'a> {
    fn new(job: &'a PostJob, post: Post) -> Self {
        let decimals = coordinate_decimals(job.units);
        let feed_decimals = match job.units {
            Units::Mm => 1,
            Units::Inch => 2,
        };
        Writer {
            job,
            post,
            mm_per_unit: job.units.mm_per_unit(),
            decimals,
            feed_decimals,
            last_xyz: Default::default(),
            last_g: None,
            last_f: None,
            text: String::new(),
        }
    }

    fn line(&mut self, s: &str) {
        self.text.push_str(s);
        self.text.push('\n');
    }

    fn comment(&mut self, s: &str) {
        let c = sanitize_comment(s, self.post);
        self.line(&format!("({c})"));
    }

    fn header(&mut self) {
        let j = self.job;
        let u = match j.units {
            Units::Mm => "mm",
            Units::Inch => "inch",
        };
        if self.post == Post::Fanuc {
            self.line("%");
            let name = sanitize_comment(&j.part_name, self.post);
            self.line(&format!("O{:04} ({name})", j.program_number));
        }
        self.comment("cam finishing program");
        self.comment(&format!("part: {}", j.part_name));
        self.comment(&format!("tool: T{} {}", j.tool_number, j.tool_spec));
        self.comment(&format!("tolerance: {} mm", j.tolerance_mm));
        self.comment(&format!("scallop: {} mm", j.scallop_mm));
        self.comment(&format!("post: {}, units: {u}", self.post));
        self.comment(&format!("feed: {} mm/min", j.feed_mm_per_min));
        self.comment(&format!("plunge feed: {} mm/min", j.plunge_feed_mm_per_min));
        self.comment(&format!("safe Z: {} mm", j.safe_z_mm));
        self.comment("CL convention: tool tip");
        let units = match j.units {
            Units::Mm => "G21",
            Units::Inch => "G20",
        };
        match self.post {
            Post::LinuxCnc | Post::Fanuc => {
                self.line(&format!("{units} G90 G17 G94 G40 G49 G80 G54"));
                self.line(&format!("T{n} M6", n = j.tool_number));
            }
            Post::Grbl => {
                self.line(&format!("{units} G90 G17 G94 G54"));
                self.comment(&format!(
                    "load tool T{} {} now: Grbl has no tool changer",
                    j.tool_number, j.tool_spec
                ));
            }
        }
        let dir = if j.spindle_cw { "M3" } else { "M4" };
        self.line(&format!("S{:.0} {dir}", j.rpm));
        // Approach to safe Z; on controls with tool-length offsets it switches G43 on.
        let g43 = match self.post {
            Post::LinuxCnc | Post::Fanuc => format!(" G43 H{}", j.tool_number),
            Post::Grbl => String::new(),
        };
        let z = fixed(j.safe_z_mm / self.mm_per_unit, self.decimals);
        self.line(&format!("G0{g43} Z{z}"));
        self.last_g = Some(0);
        self.last_xyz[2] = Some(z);
    }

    fn footer(&mut self) {
        self.line("M5");
        self.line("M30");
        if self.post == Post::Fanuc {
            self.line("%");
        }
    }

    /// One motion line; coordinates (mm) that print the same as last time are left out, and
    /// the line is dropped if no coordinate changes.
    fn motion(&mut self, g: u8, x: Option<f64>, y: Option<f64>, z: Option<f64>, feed: Option<f64>) {
        let mut words = String::new();
        let mut new_xyz = self.last_xyz.clone();
        for (i, (letter, v)) in [('X', x), ('Y', y), ('Z', z)].into_iter().enumerate() {
            if let Some(v) = v {
                let s = fixed(v / self.mm_per_unit, self.decimals);
                if self.last_xyz[i].as_deref() != Some(s.as_str()) {
                    words.push_str(&format!(" {letter}{s}"));
                    new_xyz[i] = Some(s);
                }
            }
        }
        if words.is_empty() {
            return;
        }
        self.last_xyz = new_xyz;
        let mut s = String::new();
        if self.last_g != Some(g) {
            s.push_str(&format!("G{g}"));
            self.last_g = Some(g);
        }
        s.push_str(&words);
        if let Some(f) = feed {
            let fs = fixed(f / self.mm_per_unit, self.feed_decimals);
            if self.last_f.as_deref() != Some(fs.as_str()) {
                s.push_str(&format!(" F{fs}"));
                self.last_f = Some(fs);
            }
        }
        self.line(s.trim_start());
    }
}

/// A comment body safe for `post`: printable ASCII only, no parentheses (→ `[ ]`), no `;` or
/// `%`; at most 70 characters (Fanuc: 32, upper case).
fn sanitize_comment(s: &str, post: Post) -> String {
    let mut out: String = s
        .chars()
        .map(|c| match c {
            '(' => '[',
            ')' => ']',
            ';' => ',',
            '%' => '_',
            c if c.is_ascii_graphic() || c == ' ' => c,
            _ => '?',
        })
        .collect();
    let max = if post == Post::Fanuc {
        out = out.to_ascii_uppercase();
        32
    } else {
        70
    };
    out.truncate(max);
    out.trim_end().to_string()
}
