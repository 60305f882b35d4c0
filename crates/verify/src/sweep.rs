//! The surface swept by a cutter along a 3- or 5-axis toolpath, from imprint curves
//! (Roth, Bedi, Ismail, Mann 2000, §3.3), as a triangle soup generated from the compact
//! [`crate::model::SweepModel`].
//!
//! # What sweeps
//! Only feed moves ([`MoveKind::Cut`], [`MoveKind::Plunge`], [`MoveKind::Retract`]) sweep; a
//! [`MoveKind::Rapid`] is assumed to move through air and ends the current *stretch* of
//! consecutive feed moves (rapids that hit the part are the job of a collision check, not of
//! the swept surface). Each feed move is subdivided into steps no longer than
//! [`SweepConfig::max_step_mm`], the tip and the axis interpolated linearly (the axis
//! renormalised); the length of a move counts the tip displacement plus the displacement of the
//! tool's rim caused by the axis rotation. Steps that move nothing are dropped.
//!
//! # Surface
//! One imprint curve per pose ([`Imprinter::curves`]: the outgoing curve, the incoming one at
//! the last pose), neighbouring curves joined point by point from the first demarcation point
//! on; each quadrilateral is split in two triangles (degenerate ones are skipped). A stretch is
//! broken into *segments* at every pose where the direction of the torus centre's motion turns
//! by more than [`SweepConfig::sharp_turn_deg`] (a reversal is a turn of 180°), or where the
//! imprinted half turns by as much between two poses ([`crate::imprint::CurveInfo::front`]);
//! every segment
//! ends in *caps*: the tool's own lower surface (flat disk and corner quarter, tessellated with
//! `Q` sectors and `max(2, Q/4)` rings) at its first and last pose, so that the union of strips
//! and caps has no holes over the tool's footprint. Triangles face away from the tool (outward
//! from the removed volume).
//!
//! # Flat end mills
//! With `r = 0` every imprint point is a rim point of the flat bottom, and the strip between
//! two curves is the ruled surface swept by the front rim half-circle; together with the caps
//! (flat disks) at segment ends it covers the flat bottom's footprint exactly.
//!
//! # Back gouges
//! The imprint method follows one half of the tool (see [`crate::imprint`]). With
//! [`SweepConfig::reverse`] the path is swept backwards and the *other* half is imprinted,
//! as the paper suggests for back-gouge detection.
//!
//! [`MoveKind::Cut`]: cam_core::MoveKind::Cut
//! [`MoveKind::Plunge`]: cam_core::MoveKind::Plunge
//! [`MoveKind::Retract`]: cam_core::MoveKind::Retract
//! [`MoveKind::Rapid`]: cam_core::MoveKind::Rapid
//! [`Imprinter::curves`]: crate::imprint::Imprinter::curves

use std::io::{self, Write};

use cam_core::{Cutter, DVec3, Toolpath, Triangle};

use crate::imprint::{Difference, Placement};
use crate::model::SweepModel;

/// How to sweep.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SweepConfig {
    /// Pseudo-inserts Q (even, ≥ 4). Default 40.
    pub inserts: usize,
    /// Insert placement ([`Placement::Adaptive`] by default; [`Placement::Uniform`] is the
    /// paper's).
    pub placement: Placement,
    /// Motion direction per pose ([`Difference::Central`] by default; [`Difference::Forward`]
    /// is the paper's).
    pub difference: Difference,
    /// Longest step (mm) between poses; longer moves are subdivided. Default 0.5.
    pub max_step_mm: f64,
    /// Sweep the path backwards, imprinting the other half of the tool (back gouges).
    pub reverse: bool,
    /// A turn of the motion direction above this angle (degrees) breaks the surface and caps
    /// both sides. Default 30.
    pub sharp_turn_deg: f64,
    /// Sweep only the moves whose tool axis turns; the others end a stretch like a rapid.
    /// The verifier's back-gouge sweep uses it when it refines onto the exact swept volume,
    /// which for a move without rotation already holds the whole tool (see
    /// [`crate::measure`]). Default false.
    pub rotating_only: bool,
}

impl Default for SweepConfig {
    fn default() -> Self {
        SweepConfig {
            inserts: 40,
            placement: Placement::Adaptive,
            difference: Difference::Central,
            max_step_mm: 0.5,
            reverse: false,
            sharp_turn_deg: 30.0,
            rotating_only: false,
        }
    }
}

/// Which part of the swept surface a triangle belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FacetKind {
    /// Between two imprint curves.
    Strip,
    /// On the tool's own lower surface at a segment end.
    Cap,
}

/// A swept surface: triangles (mm) with, per triangle, the index of the toolpath move that
/// produced it and whether it is a strip or a cap.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SweptSurface {
    /// The triangles, outward (away from the removed volume) by the right-hand rule.
    pub triangles: Vec<Triangle>,
    /// Per triangle: index into `Toolpath::moves` of the move that swept it.
    pub source_move: Vec<u32>,
    /// Per triangle: strip or cap.
    pub kind: Vec<FacetKind>,
}

impl SweptSurface {
    /// The triangles of `model`, in emission order (see [`crate::model`]).
    pub fn from_model(model: &SweepModel) -> SweptSurface {
        let mut surface = SweptSurface::default();
        for (i, piece) in model.pieces.iter().enumerate() {
            let (mv, kind) = (piece.source_move(), piece.kind());
            model.for_each_triangle(i, |_, t| {
                surface.triangles.push(t);
                surface.source_move.push(mv);
                surface.kind.push(kind);
            });
        }
        surface
    }
}

/// Sweeps `cutter` along the feed moves of `toolpath`: imprint strips plus caps at segment
/// ends (see the module docs). Deterministic and independent of the number of threads.
pub fn sweep(toolpath: &Toolpath, cutter: &Cutter, cfg: &SweepConfig) -> SweptSurface {
    SweptSurface::from_model(&SweepModel::new(toolpath, cutter, cfg))
}

/// Writes the surface as binary STL.
///
/// # Errors
/// Any I/O error of `w`.
pub fn write_stl(surface: &SweptSurface, w: &mut dyn Write) -> io::Result<()> {
    cam_core::io::stl::write_binary_stl(w, &surface.triangles)
}

/// Writes the surface as Wavefront OBJ (three vertices per triangle, no sharing), mm.
///
/// # Errors
/// Any I/O error of `w`.
pub fn write_obj(surface: &SweptSurface, w: &mut dyn Write) -> io::Result<()> {
    writeln!(
        w,
        "# cam swept surface, {} triangles, mm",
        surface.triangles.len()
    )?;
    for t in &surface.triangles {
        for p in t.v {
            writeln!(w, "v {} {} {}", p.x, p.y, p.z)?;
        }
    }
    for i in 0..surface.triangles.len() {
        writeln!(w, "f {} {} {}", 3 * i + 1, 3 * i + 2, 3 * i + 3)?;
    }
    Ok(())
}

/// Writes the surface as ASCII PLY with a per-face `source_move` property, mm.
///
/// # Errors
/// Any I/O error of `w`.
pub fn write_ply(surface: &SweptSurface, w: &mut dyn Write) -> io::Result<()> {
    let n = surface.triangles.len();
    writeln!(w, "ply\nformat ascii 1.0\ncomment cam swept surface, mm")?;
    writeln!(
        w,
        "element vertex {}\nproperty double x\nproperty double y\nproperty double z",
        3 * n
    )?;
    writeln!(
        w,
        "element face {n}\nproperty list uchar int vertex_indices\nproperty uint source_move"
    )?;
    writeln!(w, "end_header")?;
    for t in &surface.triangles {
        for p in t.v {
            writeln!(w, "{} {} {}", p.x, p.y, p.z)?;
        }
    }
    for (i, m) in surface.source_move.iter().enumerate() {
        writeln!(w, "3 {} {} {} {m}", 3 * i, 3 * i + 1, 3 * i + 2)?;
    }
    Ok(())
}

/// Distance (mm) along the unit direction `dir` from `origin` to the first triangle of
/// `surface` (either side), by testing every triangle (Möller–Trumbore); `None` if the line
/// misses all within `max_mm`. For tests and validation, not for speed.
pub fn first_hit(surface: &SweptSurface, origin: DVec3, dir: DVec3, max_mm: f64) -> Option<f64> {
    let mut best: Option<f64> = None;
    for t in &surface.triangles {
        let [a, b, c] = t.v;
        let (e1, e2) = (b - a, c - a);
        let p = dir.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-300 {
            continue;
        }
        let inv = 1.0 / det;
        let s = origin - a;
        let u = s.dot(p) * inv;
        if !(-1e-12..=1.0 + 1e-12).contains(&u) {
            continue;
        }
        let q = s.cross(e1);
        let v = dir.dot(q) * inv;
        if v < -1e-12 || u + v > 1.0 + 1e-12 {
            continue;
        }
        let d = e2.dot(q) * inv;
        if d >= 0.0 && d <= max_mm && best.is_none_or(|b| d < b) {
            best = Some(d);
        }
    }
    best
}
