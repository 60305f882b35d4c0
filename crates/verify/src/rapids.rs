//! Rapid moves against the part.
//!
//! A rapid (`G0`) is assumed to move through air: it sweeps no material in the deviation
//! measurement ([`crate::sweep`]). A rapid that runs into the part is a crash, so every rapid
//! is checked here on its own.
//!
//! # Method
//! With the axis +Z the whole cutter (its lower surface and, above it, the flutes and shank
//! continued as a cylinder of radius `R` without end) is closed upward, so the tool at tip
//! `(x, y, z)` meets the part exactly when `z` lies below the drop-cutter height there, the
//! CL surface `CL(x, y)` ([`cam_offset::DropCutter`]). A straight rapid from tip `A` to tip
//! `B` therefore runs into the part by the largest height of the CL surface above its chord,
//! which [`cam_offset::DropCutter::chord_rise`] finds exactly (the CL surface is the maximum
//! over triangles of functions concave along the move); a rapid along the axis by
//! `CL − min(z_A, z_B)`. The depth is vertical: how far the tool sits below where it would
//! rest on the part.
//!
//! A rapid that keeps a tilted axis (3+2 or 5-axis repositioning along a fixed axis) is the
//! same problem in the frame where that axis is +Z: the part is turned into that frame (one
//! drop-cutter per distinct axis) and the depth is measured along the axis. Rapids that turn
//! the axis are not checked (how the tool moves between their end poses depends on the
//! machine's kinematics); they are counted in [`RapidReport::unchecked`].

use cam_core::{Cutter, DVec3, Mesh, MoveKind, Toolpath, Triangle};
use cam_offset::DropCutter;
use rayon::prelude::*;

/// A rapid that runs into the part deeper than the tolerance.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RapidCollision {
    /// Index of the rapid in the toolpath's moves.
    pub move_index: usize,
    /// Its line in the toolpath file (1-based), when known.
    pub line: Option<usize>,
    /// How far (mm, along the tool axis) the tool sinks below the CL surface, at its deepest.
    pub depth_mm: f64,
    /// The tool tip there (mm).
    pub tip: [f64; 3],
}

/// The rapids checked and those that run into the part.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct RapidReport {
    /// Rapids checked (moving, with the same axis at both ends; a first move that is a
    /// rapid is checked at the pose it reaches).
    pub checked: usize,
    /// Of those, rapids whose axis is off +Z (checked in the frame of their axis).
    pub tilted: usize,
    /// Rapids not checked: the axis turns between their ends.
    pub unchecked: usize,
    /// Deepest a rapid sinks below the CL surface (mm, ≥ 0, along the tool axis).
    pub max_depth_mm: f64,
    /// The rapids deeper than the tolerance, in toolpath order.
    pub collisions: Vec<RapidCollision>,
}

/// Checks every rapid of `toolpath` (tool-tip poses) with `cutter` against `part`; those
/// that sink more than `tolerance_mm` below the CL surface are collisions. Parallel; the
/// result does not depend on the number of threads.
pub fn check_rapids(
    part: &Mesh,
    cutter: &Cutter,
    toolpath: &Toolpath,
    tolerance_mm: f64,
) -> RapidReport {
    // The pose a rapid starts from: the previous move's; the first move starts where it
    // ends (a program's first rapid comes from where the tool was, which it does not say:
    // the pose it reaches is checked).
    let start = |i: usize| toolpath.moves[i.saturating_sub(1)].pose;
    let rapids: Vec<usize> = (0..toolpath.moves.len())
        .filter(|&i| {
            toolpath.moves[i].kind == MoveKind::Rapid
                && (i == 0 || start(i).tip != toolpath.moves[i].pose.tip)
        })
        .collect();
    // Rapids whose axis does not turn, grouped by that axis (vertical first): each group is
    // checked in the frame where its axis is +Z.
    let same = |a: DVec3, b: DVec3| (a - b).length() <= 1e-12;
    let mut groups: Vec<(DVec3, Vec<usize>)> = Vec::new();
    let mut unchecked = 0;
    for i in rapids {
        let k = start(i).axis;
        if !same(k, toolpath.moves[i].pose.axis) {
            unchecked += 1;
            continue;
        }
        let k = if crate::material::is_vertical(k) {
            DVec3::Z
        } else {
            k
        };
        match groups.iter_mut().find(|(g, _)| *g == k) {
            Some((_, v)) => v.push(i),
            None => groups.push((k, vec![i])),
        }
    }
    // Per group, each rapid's depth and deepest tip; `None` when the turned part could not
    // be built (not expected: turning keeps lengths), and its rapids stay unchecked.
    let measured: Vec<Option<Vec<(usize, f64, DVec3)>>> = groups
        .par_iter()
        .map(|(k, idx)| {
            let frame = AxisFrame::new(*k);
            let turned = frame.turn_mesh(part).ok()?;
            let dc = DropCutter::new(turned.as_ref().unwrap_or(part), *cutter);
            let depth = |i: usize| {
                let (a0, b0) = (start(i).tip, toolpath.moves[i].pose.tip);
                let (a, b) = (frame.to(a0), frame.to(b0));
                if a.x == b.x && a.y == b.y {
                    let (low, low0) = if a.z <= b.z { (a, a0) } else { (b, b0) };
                    let depth = dc.drop(a.x, a.y).map_or(0.0, |z| (z - low.z).max(0.0));
                    return (i, depth, low0);
                }
                let r = dc.chord_rise((a.x, a.y), (b.x, b.y), a.z, b.z, 0.0, f64::INFINITY);
                (i, r.rise_mm.max(0.0), a0.lerp(b0, r.at))
            };
            // Each rapid on its own: a long one's rise along the part costs thousands of
            // drops (31 M instructions on the dome's 19 rapids, on one thread).
            Some(idx.par_iter().map(|&i| depth(i)).collect())
        })
        .collect();
    let (mut checked, mut tilted) = (0, 0);
    let mut depths: Vec<(usize, f64, DVec3)> = Vec::new();
    for ((k, idx), m) in groups.iter().zip(measured) {
        match m {
            Some(d) => {
                checked += d.len();
                if *k != DVec3::Z {
                    tilted += d.len();
                }
                depths.extend(d);
            }
            None => unchecked += idx.len(),
        }
    }
    depths.sort_by_key(|d| d.0);
    let max_depth_mm = depths.iter().map(|d| d.1).fold(0.0, f64::max);
    let collisions = depths
        .iter()
        .filter(|d| d.1 > tolerance_mm)
        .map(|&(i, depth_mm, tip)| RapidCollision {
            move_index: i,
            line: toolpath.moves[i].line,
            depth_mm,
            tip: tip.to_array(),
        })
        .collect();
    RapidReport {
        checked,
        tilted,
        unchecked,
        max_depth_mm,
        collisions,
    }
}

/// The frame in which a tool axis `k` is +Z: coordinates along `u`, `v` and `k`, with
/// `(u, v, k)` orthonormal and right-handed (a rotation, so lengths and depths keep).
#[derive(Debug, Clone, Copy)]
struct AxisFrame {
    u: DVec3,
    v: DVec3,
    k: DVec3,
}

impl AxisFrame {
    fn new(k: DVec3) -> AxisFrame {
        let k = k.normalize();
        let (u, _) = k.any_orthonormal_pair();
        AxisFrame {
            u,
            v: k.cross(u),
            k,
        }
    }

    /// `p` in the frame.
    fn to(&self, p: DVec3) -> DVec3 {
        DVec3::new(p.dot(self.u), p.dot(self.v), p.dot(self.k))
    }

    /// The part in the frame: `Ok(None)` when the frame is the identity (axis +Z), so a
    /// 3-axis program's rapids are measured on the part as given.
    fn turn_mesh(&self, part: &Mesh) -> Result<Option<Mesh>, cam_core::MeshError> {
        if self.k == DVec3::Z {
            return Ok(None);
        }
        let tris = part
            .triangles()
            .iter()
            .map(|t| Triangle::new(self.to(t.v[0]), self.to(t.v[1]), self.to(t.v[2])))
            .collect();
        Mesh::from_triangles(
            tris,
            part.source().unwrap_or(std::path::Path::new("<part>")),
        )
        .map(Some)
    }
}
