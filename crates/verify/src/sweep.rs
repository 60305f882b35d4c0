//! The surface swept by a cutter along a 3- or 5-axis toolpath, from imprint curves
//! (Roth, Bedi, Ismail, Mann 2000, §3.3), as a triangle soup.
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

use std::io::{self, Write};

use cam_core::{Cutter, DVec3, MoveKind, Pose, Toolpath, Triangle};

use crate::imprint::{
    CurveStatus, Difference, Half, ImprintConfig, Imprinter, Placement, PoseFrame, transport_frames,
};

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

/// A run of poses joined by feed steps; `step_move[i]` is the move of step `i → i+1`.
#[derive(Debug, Clone, Default)]
struct Stretch {
    poses: Vec<Pose>,
    step_move: Vec<u32>,
}

fn interpolate(a: &Pose, b: &Pose, t: f64) -> Pose {
    let axis = a.axis.lerp(b.axis, t);
    let l = axis.length();
    Pose {
        tip: a.tip.lerp(b.tip, t),
        axis: if l > 1e-12 { axis / l } else { a.axis },
    }
}

/// The stretches of consecutive feed moves, subdivided.
fn stretches(path: &Toolpath, cutter: &Cutter, cfg: &SweepConfig) -> Vec<Stretch> {
    let max_step = if cfg.max_step_mm.is_finite() && cfg.max_step_mm > 0.0 {
        cfg.max_step_mm
    } else {
        f64::INFINITY
    };
    let mut out = Vec::new();
    let mut cur = Stretch::default();
    for (i, w) in path.moves.windows(2).enumerate() {
        let idx = (i + 1) as u32;
        let (a, b) = (&w[0].pose, &w[1].pose);
        if w[1].kind == MoveKind::Rapid {
            if cur.poses.len() >= 2 {
                out.push(std::mem::take(&mut cur));
            }
            cur = Stretch::default();
            continue;
        }
        let len = a.tip.distance(b.tip) + a.axis.distance(b.axis) * cutter.radius();
        let n = if len.is_finite() && max_step.is_finite() {
            ((len / max_step).ceil() as usize).clamp(1, 1_000_000)
        } else {
            1
        };
        if cur.poses.is_empty() {
            cur.poses.push(*a);
        }
        for s in 1..=n {
            let p = interpolate(a, b, s as f64 / n as f64);
            let last = cur.poses.last().copied().unwrap_or(p);
            if p.tip.distance(last.tip) <= 1e-12 && p.axis.distance(last.axis) <= 1e-12 {
                continue;
            }
            cur.poses.push(p);
            cur.step_move.push(idx);
        }
    }
    if cur.poses.len() >= 2 {
        out.push(cur);
    }
    if cfg.reverse {
        out.reverse();
        for s in &mut out {
            s.poses.reverse();
            s.step_move.reverse();
        }
    }
    out
}

/// Pose indices where a stretch breaks (first and last included).
fn breaks(frames: &[PoseFrame], sharp_turn_deg: f64) -> Vec<usize> {
    let cos_limit = sharp_turn_deg.to_radians().cos();
    let mut out = vec![0];
    let dir = |i: usize| {
        let d = frames[i + 1].centre - frames[i].centre;
        let l = d.length();
        (l > 1e-12).then(|| d / l)
    };
    for p in 1..frames.len() - 1 {
        if let (Some(a), Some(b)) = (dir(p - 1), dir(p))
            && a.dot(b) < cos_limit
        {
            out.push(p);
        }
    }
    out.push(frames.len() - 1);
    out
}

/// Appends the triangle `(a, b, c)` oriented away from `inside`, unless degenerate.
fn push(surface: &mut SweptSurface, t: [DVec3; 3], inside: DVec3, mv: u32, kind: FacetKind) {
    let mut tri = Triangle::new(t[0], t[1], t[2]);
    if tri.is_degenerate() {
        return;
    }
    let centroid = (t[0] + t[1] + t[2]) / 3.0;
    if tri.cross().dot(centroid - inside) < 0.0 {
        tri.v.swap(1, 2);
    }
    surface.triangles.push(tri);
    surface.source_move.push(mv);
    surface.kind.push(kind);
}

/// Appends the tessellated lower surface of the tool at `f`: `sectors` around, `rings`
/// profile segments on the corner, a fan over the flat bottom.
pub fn push_cap(
    surface: &mut SweptSurface,
    cutter: &Cutter,
    f: &PoseFrame,
    sectors: usize,
    rings: usize,
    mv: u32,
) {
    let (a, r) = (cutter.major_radius(), cutter.corner_radius());
    let k = f.axis;
    let tip = f.tip(r);
    let inside = f.centre + cutter.radius() * k;
    let ring_pt = |phi: f64, ring: usize| {
        let u = phi.cos() * f.e1 + phi.sin() * f.e2;
        let theta = std::f64::consts::FRAC_PI_2 * ring as f64 / rings as f64;
        f.centre + a * u + r * (theta.sin() * u - theta.cos() * k)
    };
    let step = 2.0 * std::f64::consts::PI / sectors as f64;
    for s in 0..sectors {
        let (p0, p1) = (s as f64 * step, (s + 1) as f64 * step);
        if a > 0.0 {
            push(
                surface,
                [tip, ring_pt(p0, 0), ring_pt(p1, 0)],
                inside,
                mv,
                FacetKind::Cap,
            );
        }
        if r > 0.0 {
            for g in 0..rings {
                let q = [
                    ring_pt(p0, g),
                    ring_pt(p1, g),
                    ring_pt(p1, g + 1),
                    ring_pt(p0, g + 1),
                ];
                push(surface, [q[0], q[1], q[2]], inside, mv, FacetKind::Cap);
                push(surface, [q[0], q[2], q[3]], inside, mv, FacetKind::Cap);
            }
        }
    }
}

/// Joins two imprint curves into strip triangles.
fn push_strip(surface: &mut SweptSurface, c0: &[DVec3], c1: &[DVec3], inside: DVec3, mv: u32) {
    for j in 0..c0.len() - 1 {
        let (a, b, c, d) = (c0[j], c0[j + 1], c1[j + 1], c1[j]);
        push(surface, [a, b, c], inside, mv, FacetKind::Strip);
        push(surface, [a, c, d], inside, mv, FacetKind::Strip);
    }
}

/// Sweeps `cutter` along the feed moves of `toolpath`: imprint strips plus caps at segment
/// ends (see the module docs). Deterministic and independent of the number of threads.
pub fn sweep(toolpath: &Toolpath, cutter: &Cutter, cfg: &SweepConfig) -> SweptSurface {
    let imp = Imprinter::new(
        cutter,
        &ImprintConfig {
            inserts: cfg.inserts,
            placement: cfg.placement,
            difference: cfg.difference,
        },
    );
    let q = imp.inserts();
    let rings = (q / 4).max(2);
    let half = if cfg.reverse {
        Half::Complement
    } else {
        Half::Cutting
    };
    let l = imp.points_per_curve();
    let cos_limit = cfg.sharp_turn_deg.to_radians().cos();
    let mut surface = SweptSurface::default();
    for st in stretches(toolpath, cutter, cfg) {
        let frames = transport_frames(&st.poses, cutter.corner_radius());
        let cuts = breaks(&frames, cfg.sharp_turn_deg);
        for (si, w) in cuts.windows(2).enumerate() {
            let (s, e) = (w[0], w[1]);
            let seg = &frames[s..=e];
            let mut pts = vec![DVec3::ZERO; seg.len() * l];
            let info = imp.curves(seg, half, &mut pts);
            if si == 0 {
                push_cap(&mut surface, cutter, &seg[0], q, rings, st.step_move[s]);
            }
            for p in 0..seg.len() - 1 {
                let (i0, i1) = (&info[p], &info[p + 1]);
                if i0.status == CurveStatus::NoMotion || i1.status == CurveStatus::NoMotion {
                    continue;
                }
                let mv = st.step_move[s + p];
                if i0.front.dot(i1.front) < cos_limit {
                    // The imprinted half flips between these poses (a reversal relative to
                    // the tool): no strip; cap both poses.
                    push_cap(&mut surface, cutter, &seg[p], q, rings, mv);
                    push_cap(&mut surface, cutter, &seg[p + 1], q, rings, mv);
                    continue;
                }
                let (c0, c1) = (&pts[p * l..(p + 1) * l], &pts[(p + 1) * l..(p + 2) * l]);
                let inside = seg[p].centre + cutter.radius() * seg[p].axis;
                push_strip(&mut surface, c0, c1, inside, mv);
            }
            push_cap(
                &mut surface,
                cutter,
                &seg[seg.len() - 1],
                q,
                rings,
                st.step_move[e - 1],
            );
        }
    }
    surface
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
