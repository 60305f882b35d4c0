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
//!
//! Each drop-cutter holds only the triangles that can raise the CL surface above one of its
//! rapids: those whose top lies above the rapid's lower end and whose XY box comes within
//! the cutter's radius of the chord's. The depths are bit for bit those of the whole part
//! (a test compares them), and a program whose rapids run at a safe height builds none
//! (sphere_on_plate's ball program: 35 M instructions of 1,586 M went to building one for
//! its single rapid).

use cam_core::{Cutter, DVec3, Mesh, MeshError, MoveKind, Toolpath, Triangle};
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
            let ends: Vec<(DVec3, DVec3)> = idx
                .iter()
                .map(|&i| (start(i).tip, toolpath.moves[i].pose.tip))
                .collect();
            measure_group(part, cutter, *k, &ends, true).ok().map(|d| {
                idx.iter()
                    .zip(d)
                    .map(|(&i, (depth, tip))| (i, depth, tip))
                    .collect()
            })
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

/// Each rapid's depth below the CL surface and its deepest tip, for rapids from `a` to `b`
/// (tips, part coordinates) along the fixed axis `k`, measured in the frame where `k` is +Z.
/// With `prune`, the drop-cutter holds only the triangles that can raise the CL surface
/// above some rapid (see [`reaches`]): the same depths and tips, bit for bit, as the whole
/// part gives (`prune = false`, the reference the tests compare with). `Err` when the
/// turned triangles make no mesh for another reason than being none or degenerate (not
/// expected: turning keeps lengths).
fn measure_group(
    part: &Mesh,
    cutter: &Cutter,
    k: DVec3,
    ends: &[(DVec3, DVec3)],
    prune: bool,
) -> Result<Vec<(f64, DVec3)>, MeshError> {
    let frame = AxisFrame::new(k);
    let local: Vec<(DVec3, DVec3)> = ends
        .iter()
        .map(|&(a, b)| (frame.to(a), frame.to(b)))
        .collect();
    let big_r = cutter.radius();
    let keep = |t: &Triangle| !prune || local.iter().any(|&(a, b)| reaches(t, a, b, big_r));
    let dc = if frame.k == DVec3::Z && !prune {
        Some(DropCutter::new(part, *cutter))
    } else {
        let tris: Vec<Triangle> = part
            .triangles()
            .iter()
            .map(|t| frame.turn(t))
            .filter(|t| keep(t))
            .collect();
        let src = part.source().unwrap_or(std::path::Path::new("<part>"));
        // None kept, or only triangles that turning made degenerate (the whole turned part
        // drops them too): nothing can rise above the rapids.
        match Mesh::from_triangles(tris, src) {
            Ok(m) => Some(DropCutter::new(&m, *cutter)),
            Err(MeshError::NoTriangles { .. } | MeshError::AllDegenerate { .. }) => None,
            Err(e) => return Err(e),
        }
    };
    // No triangle can raise the CL surface above any rapid: every depth is 0, at the rapid's
    // start (the chord's) or its lower end (along the axis), as the search reports it.
    let depth = |(a0, b0): (DVec3, DVec3), (a, b): (DVec3, DVec3)| -> (f64, DVec3) {
        if a.x == b.x && a.y == b.y {
            let (low, low0) = if a.z <= b.z { (a, a0) } else { (b, b0) };
            let z = dc.as_ref().and_then(|dc| dc.drop(a.x, a.y));
            return (z.map_or(0.0, |z| (z - low.z).max(0.0)), low0);
        }
        let Some(dc) = &dc else {
            return (0.0, a0.lerp(b0, 0.0));
        };
        let r = dc.chord_rise((a.x, a.y), (b.x, b.y), a.z, b.z, 0.0, f64::INFINITY);
        (r.rise_mm.max(0.0), a0.lerp(b0, r.at))
    };
    // Each rapid on its own: a long one's rise along the part costs thousands of drops
    // (31 M instructions on the dome's 19 rapids, on one thread).
    Ok(ends
        .par_iter()
        .zip(&local)
        .map(|(&e, &l)| depth(e, l))
        .collect())
}

/// Whether triangle `t` (in the rapid's frame) may raise the CL surface of a cutter of
/// radius `big_r` above the rapid from `a` to `b`: its XY box comes within `big_r` of the
/// chord's XY box and its top lies above the rapid's lower end. A triangle that fails
/// either test holds the tool tip at or below its own top, and only where the tool is
/// over it, so it gives no depth above 0 anywhere on the rapid. Both tests keep a margin of
/// 1e-9 mm (plus 1e-12 of the coordinates) so that rounding decides nothing: what they
/// turn away lies clear of the rapid.
fn reaches(t: &Triangle, a: DVec3, b: DVec3, big_r: f64) -> bool {
    let [p, q, r] = t.v;
    let eps = |v: f64| 1e-9 + 1e-12 * v.abs();
    let z_low = a.z.min(b.z);
    if p.z.max(q.z).max(r.z) + eps(z_low) <= z_low {
        return false;
    }
    let reach = |lo: f64, hi: f64, tlo: f64, thi: f64| {
        tlo <= hi + big_r + eps(hi) && thi >= lo - big_r - eps(lo)
    };
    reach(
        a.x.min(b.x),
        a.x.max(b.x),
        p.x.min(q.x).min(r.x),
        p.x.max(q.x).max(r.x),
    ) && reach(
        a.y.min(b.y),
        a.y.max(b.y),
        p.y.min(q.y).min(r.y),
        p.y.max(q.y).max(r.y),
    )
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

    /// Triangle `t` in the frame; itself when the frame is the identity (axis +Z), so a
    /// 3-axis program's rapids are measured on the part as given.
    fn turn(&self, t: &Triangle) -> Triangle {
        if self.k == DVec3::Z {
            return *t;
        }
        Triangle::new(self.to(t.v[0]), self.to(t.v[1]), self.to(t.v[2]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The dome's triangles.
    fn dome() -> Mesh {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/parts");
        Mesh::load(root.join("dome.obj"), cam_core::Units::Mm).unwrap()
    }

    /// Pruning the drop-cutter to the triangles that may reach a rapid changes no depth and
    /// no tip, bit for bit, for each cutter along +Z and three tilted axes, against the
    /// whole part, pruned for two rapids at a time: 400 rapids over the dome at every height from below its base to above
    /// its top (some along the axis, some a few µm long, some short, some long), and 200
    /// that graze it, placed from a drop so that their lower end lies between 0.3 mm below
    /// the CL surface and 0.05 mm above it (half along the axis, half level).
    #[test]
    fn pruned_rapids_read_what_the_whole_part_reads() {
        let part = dome();
        let b = part.bounds();
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut rnd = move || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let axes = [
            DVec3::Z,
            DVec3::new(0.2, -0.1, 1.0).normalize(),
            DVec3::new(1.0, 0.5, 0.3).normalize(),
            DVec3::new(-0.3, 0.2, -1.0).normalize(),
        ];
        let (lo, hi) = (b.min - DVec3::splat(8.0), b.max + DVec3::splat(8.0));
        let (mut deep, mut grazing) = (0, 0);
        for k in axes {
            let f = AxisFrame::new(k);
            let back = |p: DVec3| f.u * p.x + f.v * p.y + f.k * p.z;
            let turned: Vec<Triangle> = part.triangles().iter().map(|t| f.turn(t)).collect();
            let turned = Mesh::from_triangles(turned, "<turned>").unwrap();
            let tb = turned.bounds();
            for spec in ["ball:6", "bull:6:1.5", "flat:6"] {
                let cutter: Cutter = spec.parse().unwrap();
                let dc = DropCutter::new(&turned, cutter);
                let mut ends = Vec::new();
                for n in 0..400 {
                    let a = lo + (hi - lo) * DVec3::new(rnd(), rnd(), rnd());
                    let d = match n % 4 {
                        0 => k * (rnd() - 0.5) * 20.0,
                        1 => DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 1e-2,
                        2 => DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 10.0,
                        _ => DVec3::new(rnd() - 0.5, rnd() - 0.5, 0.1 * (rnd() - 0.5)) * 80.0,
                    };
                    ends.push((a, a + d));
                }
                while ends.len() < 600 {
                    let (x, y) = (
                        tb.min.x + tb.size().x * rnd(),
                        tb.min.y + tb.size().y * rnd(),
                    );
                    let Some(z) = dc.drop(x, y) else { continue };
                    let a = DVec3::new(x, y, z - 0.3 + 0.35 * rnd());
                    let d = if ends.len() % 2 == 0 {
                        DVec3::new(0.0, 0.0, 5.0)
                    } else {
                        let t = std::f64::consts::TAU * rnd();
                        DVec3::new(t.cos(), t.sin(), 0.0) * 6.0 * rnd()
                    };
                    ends.push((back(a), back(a + d)));
                }
                // Pruned for two rapids at a time (a group's drop-cutter keeps what any of
                // its rapids may reach).
                let pruned: Vec<(f64, DVec3)> = ends
                    .chunks(2)
                    .flat_map(|e| measure_group(&part, &cutter, k, e, true).unwrap())
                    .collect();
                let whole = measure_group(&part, &cutter, k, &ends, false).unwrap();
                for (n, (p, w)) in pruned.iter().zip(&whole).enumerate() {
                    assert!(
                        p.0.to_bits() == w.0.to_bits()
                            && p.1.to_array().map(f64::to_bits) == w.1.to_array().map(f64::to_bits),
                        "{spec} {k} rapid {n} {:?}: {p:?} against {w:?}",
                        ends[n]
                    );
                    deep += usize::from(w.0 > 0.0);
                    grazing += usize::from(n >= 400 && w.0 > 0.0 && w.0 < 0.3);
                }
            }
        }
        // Many run into the part; among those that graze it, many by less than 0.3 mm.
        assert!(
            deep > 1000 && grazing > 500,
            "{deep} deep, {grazing} grazing"
        );
    }

    /// A triangle turned away by [`reaches`] lies below the rapid or beyond the cutter's
    /// radius from it; one that reaches it is kept.
    #[test]
    fn reaches_keeps_what_the_tool_can_touch() {
        let t = Triangle::new(
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 1.0),
        );
        let p = DVec3::new;
        // Over it, below its top: kept; above its top: not.
        assert!(reaches(&t, p(0.2, 0.2, 0.5), p(0.3, 0.2, 0.5), 3.0));
        assert!(!reaches(&t, p(0.2, 0.2, 1.5), p(0.3, 0.2, 1.5), 3.0));
        // A descending rapid whose lower end is under the top: kept.
        assert!(reaches(&t, p(0.2, 0.2, 5.0), p(0.2, 0.2, 0.9), 3.0));
        // Beside it within the radius in X and in Y: kept; beyond: not.
        assert!(reaches(&t, p(3.9, 0.5, 0.0), p(5.0, 0.5, 0.0), 3.0));
        assert!(!reaches(&t, p(4.1, 0.5, 0.0), p(5.0, 0.5, 0.0), 3.0));
        assert!(reaches(&t, p(0.5, -2.9, 0.0), p(0.5, -8.0, 0.0), 3.0));
        assert!(!reaches(&t, p(0.5, -3.1, 0.0), p(0.5, -8.0, 0.0), 3.0));
        // A chord passing over it with both ends beyond the radius: kept.
        assert!(reaches(&t, p(-9.0, 0.5, 0.0), p(9.0, 0.5, 0.0), 3.0));
    }
}
