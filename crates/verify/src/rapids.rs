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
//! Rapids with the axis off +Z at either end (5-axis repositioning) are not checked; they
//! are counted in [`RapidReport::unchecked`].

use cam_core::{Cutter, DVec3, Mesh, MoveKind, Toolpath};
use cam_offset::DropCutter;
use rayon::prelude::*;

/// A rapid that runs into the part deeper than the tolerance.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RapidCollision {
    /// Index of the rapid in the toolpath's moves.
    pub move_index: usize,
    /// Its line in the toolpath file (1-based), when known.
    pub line: Option<usize>,
    /// How far (mm, vertical) the tool sinks below the CL surface, at its deepest.
    pub depth_mm: f64,
    /// The tool tip there (mm).
    pub tip: [f64; 3],
}

/// The rapids checked and those that run into the part.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct RapidReport {
    /// Rapids checked (axis +Z at both ends, and moving; a first move that is a rapid is
    /// checked at the pose it reaches).
    pub checked: usize,
    /// Rapids not checked: the axis is off +Z at an end.
    pub unchecked: usize,
    /// Deepest a rapid sinks below the CL surface (mm, ≥ 0).
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
    let vertical = crate::material::is_vertical;
    let (checked, unchecked): (Vec<usize>, Vec<usize>) = rapids
        .into_iter()
        .partition(|&i| vertical(start(i).axis) && vertical(toolpath.moves[i].pose.axis));
    if checked.is_empty() {
        return RapidReport {
            unchecked: unchecked.len(),
            ..RapidReport::default()
        };
    }
    let dc = DropCutter::new(part, *cutter);
    let depths: Vec<(f64, DVec3)> = checked
        .par_iter()
        .map(|&i| {
            let (a, b) = (start(i).tip, toolpath.moves[i].pose.tip);
            if a.x == b.x && a.y == b.y {
                let low = if a.z <= b.z { a } else { b };
                let depth = dc.drop(a.x, a.y).map_or(0.0, |z| (z - low.z).max(0.0));
                return (depth, low);
            }
            let r = dc.chord_rise((a.x, a.y), (b.x, b.y), a.z, b.z, 0.0, f64::INFINITY);
            (r.rise_mm.max(0.0), a.lerp(b, r.at))
        })
        .collect();
    let max_depth_mm = depths.iter().map(|d| d.0).fold(0.0, f64::max);
    let collisions = checked
        .iter()
        .zip(&depths)
        .filter(|(_, d)| d.0 > tolerance_mm)
        .map(|(&i, &(depth_mm, tip))| RapidCollision {
            move_index: i,
            line: toolpath.moves[i].line,
            depth_mm,
            tip: tip.to_array(),
        })
        .collect();
    RapidReport {
        checked: checked.len(),
        unchecked: unchecked.len(),
        max_depth_mm,
        collisions,
    }
}
