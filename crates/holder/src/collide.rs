//! Exact collision check of the non-cutting parts of a tool assembly (shank, holder
//! cylinders) against the part's triangles along every straight move of a 3-axis toolpath.
//!
//! # Method (exact, no sampling)
//! A part is a vertical cylinder of radius ρ spanning heights `[z0, z1]` above the tip. On
//! the move `p → q` the tip is `p + t·(q − p)`, `t ∈ [0, 1]`. In the tool's frame a triangle
//! `T` sweeps the convex body `M = T ⊕ [−(q − p), 0] − p = conv{v − p, v − q : v ∈ T}`
//! (six points). The part collides with `T` somewhere on the move iff `M` meets the cylinder,
//! i.e. iff the XY projection of `M ∩ {z0 ≤ z ≤ z1}` comes closer than ρ to the axis. That
//! clipped projection is computed exactly (see `geom.rs`): it is the hull of the six
//! points in the slab and of the crossings of the prism's nine edges (the triangle's edges
//! at both ends and the three vertex sweeps) with the two planes. This holds for horizontal
//! and for oblique moves alike.
//!
//! **Penetration depth** of a triangle on a move is the radial depth
//! `ρ − min dist_xy(axis, x)` over the points `x` of the triangle inside the part's height
//! range at any instant of the move: how far, measured from the cylinder's surface toward
//! its axis, the triangle reaches into the part at the worst instant (0 … ρ). A finding is a
//! triangle whose depth exceeds `min_depth_mm`.
//!
//! **Position** is the tip at the first instant of the move at which the part collides with
//! any triangle, found by bisection on `t` of the exact swept test over the sub-move
//! `p → p + t·(q − p)`: that predicate is monotone in `t`, so the bisection converges to the
//! onset (to 2⁻⁵⁰ of the move).

use cam_core::{Aabb, Mesh, MoveKind, Toolpath, Triangle};
use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;

use crate::geom::{Bvh, PRISM_EDGES, axis_distance_below, swept_points};
use crate::library::{AssemblyPart, PartCylinder, ToolAssembly};

/// Settings of the collision check.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CheckConfig {
    /// Safety margin added to every non-cutting part's radius (mm, default 0).
    pub clearance_mm: f64,
    /// Depths at or below this are contacts, not collisions (mm, default 1e-9).
    pub min_depth_mm: f64,
    /// Check rapid moves too (default true).
    pub check_rapids: bool,
}

impl Default for CheckConfig {
    fn default() -> Self {
        CheckConfig {
            clearance_mm: 0.0,
            min_depth_mm: 1e-9,
            check_rapids: true,
        }
    }
}

/// One collision: a part of the assembly against the part mesh during one move.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Collision {
    /// Index of the move in the toolpath (the move from pose `i-1` to pose `i`).
    pub move_index: usize,
    /// The move's source line (G-code line), if known.
    pub line: Option<usize>,
    /// The move's finishing pass, if known.
    pub pass: Option<usize>,
    /// The move's kind.
    pub kind: MoveKind,
    /// Tool tip (mm) at the first instant of the move at which the part collides.
    pub position: DVec3,
    /// Which part collides.
    pub part: AssemblyPart,
    /// Largest radial penetration depth (mm) over the move, see the module docs.
    pub depth_mm: f64,
    /// The triangle reaching deepest.
    pub triangle: usize,
}

/// The result of checking a toolpath.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct CollisionReport {
    /// Findings ordered by move index, then part (shank, holder 0, 1, …).
    pub collisions: Vec<Collision>,
    /// Moves checked.
    pub moves_checked: usize,
    /// Moves skipped because an end pose's axis is not +Z (5-axis moves are not checked).
    pub moves_skipped_not_vertical: usize,
    /// Largest depth over all findings (mm), 0 without findings.
    pub max_depth_mm: f64,
}

impl CollisionReport {
    /// True when nothing collides.
    pub fn is_clear(&self) -> bool {
        self.collisions.is_empty()
    }
}

/// A part mesh prepared for repeated holder checks (an AABB tree over its triangles).
#[derive(Debug, Clone)]
pub struct HolderChecker<'m> {
    mesh: &'m Mesh,
    bvh: Bvh,
}

/// True when the pose axis is +Z to 1e-9.
pub(crate) fn vertical(axis: DVec3) -> bool {
    (axis - DVec3::Z).length() <= 1e-9
}

/// The tip at the start of move `i` (move 0 starts at its own pose).
pub(crate) fn move_start(tp: &Toolpath, i: usize) -> DVec3 {
    if i == 0 {
        tp.moves[0].pose.tip
    } else {
        tp.moves[i - 1].pose.tip
    }
}

/// Query box of a part cylinder swept along `p → q`, z limited to `[zlo, zhi]` above tips.
pub(crate) fn swept_box(p: DVec3, q: DVec3, rho: f64, zlo: f64, zhi: f64) -> Aabb {
    let lo = p.min(q);
    let hi = p.max(q);
    Aabb {
        min: DVec3::new(lo.x - rho, lo.y - rho, lo.z + zlo),
        max: DVec3::new(hi.x + rho, hi.y + rho, hi.z + zhi),
    }
}

impl<'m> HolderChecker<'m> {
    /// Builds the triangle tree (O(n log n)).
    pub fn new(mesh: &'m Mesh) -> HolderChecker<'m> {
        HolderChecker {
            mesh,
            bvh: Bvh::new(mesh.triangles()),
        }
    }

    /// The mesh.
    pub fn mesh(&self) -> &'m Mesh {
        self.mesh
    }

    pub(crate) fn candidates(&self, q: &Aabb, out: &mut Vec<u32>) {
        self.bvh.query(q, out);
    }

    pub(crate) fn candidates_multi(&self, qs: &[Aabb], outs: &mut [Vec<u32>]) {
        self.bvh.query_multi(qs, outs);
    }

    /// Piece `i` of the tree (a triangle or a part of one, see `geom::Bvh`).
    pub(crate) fn tri(&self, i: u32) -> &Triangle {
        self.bvh.piece(i)
    }

    /// Checks every move of `toolpath` (see the module docs). Deterministic: findings are in
    /// move order whatever the number of threads.
    pub fn check(
        &self,
        assembly: &ToolAssembly,
        toolpath: &Toolpath,
        cfg: &CheckConfig,
    ) -> CollisionReport {
        let parts = assembly.parts();
        let n = toolpath.moves.len();
        let per_move: Vec<(bool, Vec<Collision>)> = (0..n)
            .into_par_iter()
            .map(|i| {
                let m = &toolpath.moves[i];
                let start_axis = if i == 0 {
                    m.pose.axis
                } else {
                    toolpath.moves[i - 1].pose.axis
                };
                if !vertical(m.pose.axis) || !vertical(start_axis) {
                    return (false, Vec::new());
                }
                if m.kind == MoveKind::Rapid && !cfg.check_rapids {
                    return (true, Vec::new());
                }
                let p = move_start(toolpath, i);
                let q = m.pose.tip;
                let mut found = Vec::new();
                // One walk of the tree for all parts.
                let boxes: Vec<Aabb> = parts
                    .iter()
                    .map(|pc| {
                        swept_box(
                            p,
                            q,
                            pc.radius_mm + cfg.clearance_mm,
                            pc.z_min_mm,
                            pc.z_max_mm,
                        )
                    })
                    .collect();
                let mut lists = vec![Vec::new(); parts.len()];
                self.bvh.query_multi(&boxes, &mut lists);
                for (pc, cands) in parts.iter().zip(&lists) {
                    if let Some((depth, tri, t)) = self.check_part(pc, p, q, cfg, cands) {
                        found.push(Collision {
                            move_index: i,
                            line: m.line,
                            pass: m.pass,
                            kind: m.kind,
                            position: p + (q - p) * t,
                            part: pc.part,
                            depth_mm: depth,
                            triangle: self.bvh.origin(tri) as usize,
                        });
                    }
                }
                (true, found)
            })
            .collect();
        let mut rep = CollisionReport::default();
        for (checked, f) in per_move {
            if checked {
                rep.moves_checked += 1;
            } else {
                rep.moves_skipped_not_vertical += 1;
            }
            for c in f {
                rep.max_depth_mm = rep.max_depth_mm.max(c.depth_mm);
                rep.collisions.push(c);
            }
        }
        rep
    }

    /// Deepest triangle, its depth and the onset parameter `t` of one part on `p → q`.
    fn check_part(
        &self,
        pc: &PartCylinder,
        p: DVec3,
        q: DVec3,
        cfg: &CheckConfig,
        cands: &[u32],
    ) -> Option<(f64, u32, f64)> {
        let rho = pc.radius_mm + cfg.clearance_mm;
        let thresh = rho - cfg.min_depth_mm;
        if thresh <= 0.0 {
            return None;
        }
        let mut best: Option<(f64, u32)> = None;
        let mut hits: Vec<u32> = Vec::new();
        for &ti in cands {
            let pts = swept_points(self.tri(ti), p, q);
            if let Some(d) =
                axis_distance_below(&pts, &PRISM_EDGES, pc.z_min_mm, pc.z_max_mm, thresh)
                && d < thresh
            {
                hits.push(ti);
                let depth = rho - d;
                if best.is_none_or(|(bd, _)| depth > bd) {
                    best = Some((depth, ti));
                }
            }
        }
        let (depth, tri) = best?;
        let t = self.onset(&hits, pc, p, q, thresh);
        Some((depth, tri, t))
    }

    /// First `t` at which any of `hits` collides: per triangle, a bisection on the monotone
    /// predicate "collides on the sub-move `[0, t]`", skipping triangles that do not collide
    /// before the best onset so far. Stops when the bracket is below 1e-10 mm of travel.
    fn onset(&self, hits: &[u32], pc: &PartCylinder, p: DVec3, q: DVec3, thresh: f64) -> f64 {
        let until = |ti: u32, t: f64| {
            let e = p + (q - p) * t;
            axis_distance_below(
                &swept_points(self.tri(ti), p, e),
                &PRISM_EDGES,
                pc.z_min_mm,
                pc.z_max_mm,
                thresh,
            )
            .is_some_and(|d| d < thresh)
        };
        let len = (q - p).length();
        let steps = if len > 0.0 {
            ((len / 1e-10).log2().ceil() as usize).clamp(1, 60)
        } else {
            0
        };
        let mut best = 1.0f64;
        for &ti in hits {
            if until(ti, 0.0) {
                return 0.0;
            }
            if best < 1.0 && !until(ti, best) {
                continue;
            }
            let (mut lo, mut hi) = (0.0f64, best);
            for _ in 0..steps {
                let mid = 0.5 * (lo + hi);
                if until(ti, mid) {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            best = hi;
        }
        best
    }

    /// Static check of the assembly standing at tip `tip` (one pose): the deepest finding per
    /// part as `(part, depth_mm, triangle)`.
    pub fn check_pose(
        &self,
        assembly: &ToolAssembly,
        tip: DVec3,
        cfg: &CheckConfig,
    ) -> Vec<(AssemblyPart, f64, usize)> {
        let mut buf = Vec::new();
        assembly
            .parts()
            .iter()
            .filter_map(|pc| {
                let rho = pc.radius_mm + cfg.clearance_mm;
                self.candidates(
                    &swept_box(tip, tip, rho, pc.z_min_mm, pc.z_max_mm),
                    &mut buf,
                );
                self.check_part(pc, tip, tip, cfg, &buf)
                    .map(|(d, t, _)| (pc.part, d, self.bvh.origin(t) as usize))
            })
            .collect()
    }
}

/// Checks `toolpath` for collisions of `assembly`'s shank and holder with `mesh`.
/// Builds a [`HolderChecker`]; reuse one for repeated checks on the same part.
pub fn check_toolpath(
    mesh: &Mesh,
    assembly: &ToolAssembly,
    toolpath: &Toolpath,
    cfg: &CheckConfig,
) -> CollisionReport {
    HolderChecker::new(mesh).check(assembly, toolpath, cfg)
}
