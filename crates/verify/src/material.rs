//! How far each normal vector may reach into the part.
//!
//! The normal-vector method grows each vector from `p − L_in·n`, assumed inside the
//! material, and reads a vector whose inner start is already inside the swept volume as a
//! gouge of `L_in`. That assumption fails in two places, and both read as false gouges of
//! exactly `L_in` on programs that never touch the part:
//! - **thin material**: a wall, fin or sheet thinner than `L_in`; the inner start lies past
//!   the far face, in the air the tool legitimately cuts on the other side;
//! - **open meshes whose inner side is open to the sky**: a scanned shell with folded
//!   (downward-facing) triangles on its top skin; the inner side of such a face is above
//!   every surface, where a 3-axis tool is free to be.
//!
//! [`inner_lengths`] gives each vertex its own `L_in(v)`, from one ray cast along `−n`
//! against the design mesh:
//! - the ray meets the design surface again at `t` (any facing): `L_in(v) = min(L_in, t/2)`.
//!   The inner start stays in the material's first half, so a tool found there has cut at
//!   least `t/2` into it from this side (a real gouge), while a tool resting on the far
//!   face within its tolerance `τ < t/2` is not reported;
//! - on a 3-axis path (every pose's axis +Z) and a mesh that is not closed and consistently
//!   oriented: the inner start so found, `p − L_in(v)·n`, has no face above it:
//!   `L_in(v) = 0`. The inner side is sky: a 3-axis tool reaches the
//!   part from above only, material lies under the surface, and nothing is over this
//!   segment (a downward-facing fold on a scanned skin, a free-standing fin's far side).
//!   Deviations there read 0 at worst (counted);
//! - otherwise (material under the surface, a closed mesh, or a 5-axis path): `L_in`
//!   unchanged.

use cam_core::{DVec3, Mesh, Toolpath};
use rayon::prelude::*;

use crate::deviation::{TriangleBvh, TriangleGrid};
use crate::refine::RefinedMesh;

/// Per-vertex inner vector lengths and how many were shortened.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct InnerLengths {
    /// `L_in(v)` per vertex asked for (mm, `0 ≤ L_in(v) ≤ L_in`).
    pub inner_mm: Vec<f64>,
    /// Vertices whose inner ray met the part within `2·L_in` (thin material).
    pub thin: usize,
    /// Vertices given `L_in(v) = 0`: inner side open to the sky on a 3-axis path.
    pub open_above: usize,
}

/// True when the unit axis `k` is +Z (to 1e-12).
pub fn is_vertical(k: DVec3) -> bool {
    (k - DVec3::Z).length() <= 1e-12
}

/// True when every pose of `toolpath` has the axis +Z ([`is_vertical`]).
pub fn is_three_axis(toolpath: &Toolpath) -> bool {
    toolpath.moves.iter().all(|m| is_vertical(m.pose.axis))
}

/// The inner length of every vector of `refined` (see the module documentation): at most
/// `inside_mm`, shortened where the part is thinner than `2·inside_mm` along the vector,
/// zero where the inner side is open to the sky and `three_axis`. `closed`: the mesh is
/// closed and consistently oriented ([`crate::refine::Topology::is_closed_and_oriented`]),
/// so no inner side is open and only the short thin-material rays are cast. Parallel; the
/// result does not depend on the number of threads.
pub fn inner_lengths(
    part: &Mesh,
    refined: &RefinedMesh,
    inside_mm: f64,
    three_axis: bool,
    closed: bool,
) -> InnerLengths {
    let all: Vec<usize> = (0..refined.len()).collect();
    let bvh = TriangleBvh::new(part.triangles());
    inner_lengths_at(&bvh, refined, &all, inside_mm, three_axis, closed)
}

/// [`inner_lengths`] for the vertices `idx` of `refined` only (`inner_mm[k]` is vertex
/// `idx[k]`'s), against the part's triangles in `bvh`: one ray cast per vertex, so callers
/// pass the vertices whose reading depends on it (the gouges).
pub fn inner_lengths_at(
    bvh: &TriangleBvh,
    refined: &RefinedMesh,
    idx: &[usize],
    inside_mm: f64,
    three_axis: bool,
    closed: bool,
) -> InnerLengths {
    // A closed, consistently oriented mesh's inner rays always meet it again: no long rays.
    let open_sky = three_axis && !closed;
    // Longer than any segment inside the part.
    let reach_mm = bvh.bounds().map_or(0.0, |(lo, hi)| (hi - lo).length()) + 1.0;
    // The rays through a grid of the part's triangles where there are at least as many
    // vertices as triangles, the tree where a ray's box spans too many cubes; only the
    // crossing's distance, or whether there is one, is kept: the same from both. On
    // mount_rush's ball program (41 k vertices, 15.6 k triangles) each short inner ray
    // tested 95 of the tree's boxes: 13,030 M instructions in all against 12,563 M with
    // the grid for those rays, and 12,458 M with the sky rays through it too (callgrind,
    // one thread).
    let grid = (idx.len() >= bvh.len())
        .then(|| TriangleGrid::new(bvh.tree_triangles()))
        .flatten();
    let out: Vec<(f64, u8)> = idx
        .par_iter()
        .map(|&i| {
            let (p, n) = (refined.positions[i], refined.normals[i]);
            // The vertex lies on its own faces; skip their rounding at the start.
            let t0 = 1e-7 * (1.0 + p.abs().max_element());
            let t1 = (2.0 * inside_mm).max(t0);
            let hit = grid
                .as_ref()
                .and_then(|g| g.lowest_hit(p, -n, t0, t1))
                .unwrap_or_else(|| bvh.lowest_hit(p, -n, t0, t1, |_| true));
            let (len, kind) = match hit {
                Some(h) => (0.5 * h.t, 1),
                None => (inside_mm, 0),
            };
            // The inner segment up to its start crosses no face, so it lies on one side of
            // the surface throughout (short of passing under an open rim): where its start
            // has no face above it, neither has the rest: sky.
            let start = p - len * n;
            if open_sky
                && !grid
                    .as_ref()
                    .and_then(|g| g.any_hit(start, DVec3::Z, 0.0, reach_mm))
                    .unwrap_or_else(|| bvh.any_hit(start, DVec3::Z, 0.0, reach_mm))
            {
                (0.0, 2)
            } else {
                (len, kind)
            }
        })
        .collect();
    InnerLengths {
        thin: out.iter().filter(|o| o.1 == 1).count(),
        open_above: out.iter().filter(|o| o.1 == 2).count(),
        inner_mm: out.into_iter().map(|o| o.0).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::refine::{RefineConfig, refine, topology};
    use cam_core::{Cutter, Mesh, Move, MoveKind, Pose, Toolpath, Triangle};

    fn quad(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> [Triangle; 2] {
        [Triangle::new(a, b, c), Triangle::new(a, c, d)]
    }

    /// An axis-aligned box `[0, 10] × [0, 10] × [0, h]`, outward normals.
    fn slab(h: f64) -> Mesh {
        let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        let (a, b, c, d) = (
            v(0., 0., 0.),
            v(10., 0., 0.),
            v(10., 10., 0.),
            v(0., 10., 0.),
        );
        let (e, f, g, k) = (v(0., 0., h), v(10., 0., h), v(10., 10., h), v(0., 10., h));
        let mut t = Vec::new();
        t.extend(quad(a, d, c, b)); // bottom, -Z
        t.extend(quad(e, f, g, k)); // top, +Z
        t.extend(quad(a, b, f, e)); // -Y
        t.extend(quad(b, c, g, f)); // +X
        t.extend(quad(c, d, k, g)); // +Y
        t.extend(quad(d, a, e, k)); // -X
        Mesh::from_triangles(t, "<memory>").expect("box")
    }

    fn refined(m: &Mesh) -> RefinedMesh {
        let mut cfg = RefineConfig::for_cutter(&"ball:3".parse::<Cutter>().unwrap(), 0.005);
        cfg.crease_angle_deg = 180.0;
        refine(m, &cfg).expect("refine")
    }

    #[test]
    fn a_thin_plate_halves_its_thickness_and_a_thick_one_keeps_l_in() {
        for (h, want) in [(0.4, 0.2), (5.0, 1.0)] {
            let m = slab(h);
            let r = refined(&m);
            let l = inner_lengths(&m, &r, 1.0, true, topology(&m).is_closed_and_oriented());
            // Interior vertices of the top face: straight down to the bottom at depth h.
            let mut n = 0;
            for (i, p) in r.positions.iter().enumerate() {
                if r.normals[i] == DVec3::Z && p.x > 1.0 && p.x < 9.0 && p.y > 1.0 && p.y < 9.0 {
                    assert!(
                        (l.inner_mm[i] - want).abs() < 1e-9,
                        "h {h}: {} at {p}",
                        l.inner_mm[i]
                    );
                    n += 1;
                }
            }
            assert!(n > 100, "{n} interior top vertices");
            assert_eq!(l.open_above, 0, "a closed box has no open side");
            assert!(l.inner_mm.iter().all(|&x| x > 0.0 && x <= 1.0));
        }
    }

    #[test]
    fn a_downward_skin_with_nothing_above_is_open_only_for_three_axis_paths() {
        // One downward-facing square (normal -Z) and, far off to the side, an upward one.
        let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        let mut t = Vec::new();
        t.extend(quad(
            v(0., 0., 0.),
            v(0., 5., 0.),
            v(5., 5., 0.),
            v(5., 0., 0.),
        ));
        t.extend(quad(
            v(20., 0., 0.),
            v(25., 0., 0.),
            v(25., 5., 0.),
            v(20., 5., 0.),
        ));
        let m = Mesh::from_triangles(t, "<memory>").expect("mesh");
        let r = refined(&m);
        let down: Vec<usize> = (0..r.len()).filter(|&i| r.normals[i].z < 0.0).collect();
        let up: Vec<usize> = (0..r.len()).filter(|&i| r.normals[i].z > 0.0).collect();
        assert!(!down.is_empty() && !up.is_empty());
        let three = inner_lengths(&m, &r, 1.0, true, topology(&m).is_closed_and_oriented());
        assert!(down.iter().all(|&i| three.inner_mm[i] == 0.0));
        assert!(up.iter().all(|&i| three.inner_mm[i] == 1.0));
        assert_eq!(three.open_above, down.len());
        let five = inner_lengths(&m, &r, 1.0, false, false);
        assert!(five.inner_mm.iter().all(|&x| x == 1.0));
        // The same downward skin under a lid 0.6 mm above: thin, not open.
        let mut t = m.triangles().to_vec();
        t.extend(quad(
            v(-1., -1., 0.6),
            v(6., -1., 0.6),
            v(6., 6., 0.6),
            v(-1., 6., 0.6),
        ));
        let lid = Mesh::from_triangles(t, "<memory>").expect("mesh");
        let r2 = refined(&lid);
        let l2 = inner_lengths(&lid, &r2, 1.0, true, false);
        for i in 0..r2.len() {
            let p = r2.positions[i];
            if r2.normals[i] == -DVec3::Z && p.x > 0.5 && p.x < 4.5 && p.y > 0.5 && p.y < 4.5 {
                assert!((l2.inner_mm[i] - 0.3).abs() < 1e-9, "{}", l2.inner_mm[i]);
            }
        }
        assert_eq!(l2.open_above, 0);
    }

    /// An open step terrain: floor z = 0 for x ≤ 5, a cliff at x = 5 facing −X, a plateau
    /// z = 4 for x ≥ 5 (no bottom, no sides), and far off a free-standing fence facing −X.
    #[test]
    fn a_cliff_keeps_its_material_and_a_fence_has_sky_behind_it() {
        let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        let mut t = Vec::new();
        t.extend(quad(
            v(0., 0., 0.),
            v(5., 0., 0.),
            v(5., 5., 0.),
            v(0., 5., 0.),
        ));
        t.extend(quad(
            v(5., 0., 0.),
            v(5., 0., 4.),
            v(5., 5., 4.),
            v(5., 5., 0.),
        ));
        t.extend(quad(
            v(5., 0., 4.),
            v(5., 5., 4.),
            v(10., 5., 4.),
            v(10., 0., 4.),
        ));
        t.extend(quad(
            v(30., 0., 0.),
            v(30., 0., 4.),
            v(30., 5., 4.),
            v(30., 5., 0.),
        ));
        let m = Mesh::from_triangles(t, "<memory>").expect("mesh");
        let r = refined(&m);
        let l = inner_lengths(&m, &r, 1.0, true, false);
        let (mut cliff, mut fence) = (0, 0);
        for i in 0..r.len() {
            let p = r.positions[i];
            if r.normals[i].x > -0.999_999 || p.y < 0.5 || p.y > 4.5 || p.z < 0.5 || p.z > 3.5 {
                continue;
            }
            if p.x == 5.0 {
                assert_eq!(l.inner_mm[i], 1.0, "cliff at {p}");
                cliff += 1;
            } else {
                assert_eq!(l.inner_mm[i], 0.0, "fence at {p}");
                fence += 1;
            }
        }
        assert!(cliff > 50 && fence > 50, "{cliff} {fence}");
        // The same fence verified as a 5-axis part keeps its full inner length.
        let five = inner_lengths(&m, &r, 1.0, false, false);
        assert_eq!(five.open_above, 0);
    }

    #[test]
    fn three_axis_means_every_axis_is_z() {
        let mv = |pose: Pose| Move {
            kind: MoveKind::Cut,
            pose,
            feed_mm_per_min: None,
            line: None,
            pass: None,
        };
        let mut tp = Toolpath::default();
        tp.moves.push(mv(Pose::vertical(DVec3::ZERO)));
        assert!(is_three_axis(&tp));
        tp.moves.push(mv(Pose {
            tip: DVec3::X,
            axis: DVec3::new(0.0, 0.6, 0.8),
        }));
        assert!(!is_three_axis(&tp));
    }
}
