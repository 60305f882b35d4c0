//! Near-equilateral remeshing of the design faces, the first step of the refinement
//! ([`crate::refine`]).
//!
//! Longest-edge bisection alone ends with right-angled faces whose edges lie between `s/2`
//! and `s`: on the dome about 3.3 times as many faces as equilateral triangles of side `s`
//! would need, each vertex one normal vector to measure. So each face whose longest edge
//! exceeds `s` is first remeshed in its own plane:
//!
//! * every edge longer than `s` next to such a face is divided into `⌈L/s⌉` equal parts (the
//!   same points for both faces sharing it, so the mesh stays conforming);
//! * the face's interior gets a triangular lattice, rows parallel to its longest edge and
//!   spaced as that edge's points (`L/⌈L/s⌉ ≤ s`), every other row shifted half a spacing,
//!   kept half a spacing from the sides: its first row makes near-equilateral triangles
//!   with the longest edge's points (a lattice of its own spacing drifted against them and
//!   needed a midpoint in every other gap: 12 % more vertices on the dome);
//! * boundary and lattice points are joined by a constrained Delaunay triangulation of the
//!   face's plane (the crate's own small one, Lawson flips on exact predicates: the
//!   lattice's rows laid out directly and the band between them and the sides zipped and
//!   flipped, see `PolyCdt::reset_lattice`; spade where that cannot place a point, with
//!   the same result wherever the triangulation is unique).
//!
//! Inner edges still longer than `s` (where the lattice meets the other sides) get their
//! midpoints in two rounds, only the longest such edge of a triangle in each
//! (see `Midpoints`); what is left longer (and faces only partly in the region) the
//! conforming bisection splits. Every new vertex lies on its face (an edge point
//! or a point of the face's plane inside it), so the refined faces lie on the design surface
//! as before. With a region ([`crate::refine::Region`]), faces whose vectors cannot reach it
//! are left alone, and new points are placed only where a vector from within `s` of them
//! can (inside a face along its normal, on an edge in any direction): the points placed are
//! those placed without a region, so a vertex reads the same with or without one.
//!
//! A face whose triangulation is not what it must be (a conflict, a lost point, a count that
//! a triangulation of that polygon cannot have) is fanned from its centroid instead, and the
//! bisection finishes it: a fallback, never a panic. None of the bundled or shared fixtures
//! needs it.

use std::collections::HashMap;
use std::hash::BuildHasherDefault;

use cam_core::DVec3;
use rayon::prelude::*;
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

use crate::polycdt::PolyCdt;

/// Rounds of midpoint insertion per face (see [`Midpoints`]); the bisection splits what is
/// left. One round leaves more to the bisection, whose right-angled splits cost more points;
/// more than two add points too: a lattice whose spacing is close to `s` answers each
/// round's midpoints with new long edges beside them, and the splits run on across it
/// (on the dome's ball program 1 round leaves 118,654 vertices; 2, 117,414; 3, 117,570;
/// 8, 118,610).
const MID_ROUNDS: usize = 2;

/// The room left in the remesh's arrays for the bisection, as a divisor of their lengths
/// (1/16 more; on sphere_on_plate's ball program the bisection adds 0.6 % to the faces).
/// Where it adds more, the arrays grow as they would have.
const HEADROOM: usize = 16;

/// The remeshed design surface: positions, faces (oriented as their sources), each
/// face's source face, and each point's place on the design ([`crate::refine::HOME_CORNER`]).
pub(crate) struct Remeshed {
    pub pos: Vec<DVec3>,
    pub tris: Vec<[u32; 3]>,
    pub src: Vec<u32>,
    pub home: Vec<u64>,
}

type IntMap<K, V> = HashMap<K, V, BuildHasherDefault<crate::refine::IntHasher>>;

/// A face's vertex in its local triangulation: a boundary point (global index) or its
/// `i`-th lattice point.
#[derive(Clone, Copy)]
enum Local {
    Global(u32),
    Lattice(u32),
}

/// One face's remesh: its lattice points, its boundary points (global indices) and its
/// triangles, whose corners are numbered locally: boundary points first, then the lattice
/// (half the bytes of [`Local`]s, which the assembly waits on).
struct FaceMesh {
    lattice: Vec<DVec3>,
    ids: Vec<u32>,
    tris: Vec<[u32; 3]>,
}

impl FaceMesh {
    /// Local corner `i`.
    fn local(&self, i: u32) -> Local {
        local(&self.ids, i as usize)
    }
}

/// Remeshes the faces `tris0` (on `pos0`) that meet `region` (all without one) and whose
/// longest edge exceeds `s` (see the module documentation); faces sharing a divided edge
/// with them are re-triangulated on their boundary points only. `Err(cap)` when the points
/// would pass the vertex cap (checked before any face is triangulated).
pub(crate) fn remesh(
    pos0: &[DVec3],
    tris0: &[[u32; 3]],
    s: f64,
    region: crate::refine::RegionOf<'_>,
    cap: Option<usize>,
) -> Result<Remeshed, usize> {
    let len = |a: u32, b: u32| pos0[a as usize].distance(pos0[b as usize]);
    let active: Vec<bool> = tris0
        .par_iter()
        .enumerate()
        .map(|(f, t)| {
            (0..3).any(|k| len(t[k], t[(k + 1) % 3]) > s)
                && crate::refine::meets_region(region, pos0, t, f as u32)
        })
        .collect();
    // New points only where a vector from within `s` of them can reach the region (the rest
    // of a face that reaches out of it keeps long triangles, as the bisection would): inside
    // face `f` along its normal, on an edge in any direction (`f = None`).
    let near_of = |f: Option<usize>| {
        move |p: DVec3| {
            region.is_none_or(|(r, normals)| r.reached(&[p], f.and_then(|f| normals[f]), s))
        }
    };
    let near = near_of(None);
    // Divided edges: key -> (first new vertex, count), points from the lower-numbered end.
    let mut pos = pos0.to_vec();
    let mut home = vec![crate::refine::HOME_CORNER; pos0.len()];
    let mut divided: IntMap<u64, (u32, u32)> = IntMap::default();
    for (t, _) in tris0.iter().zip(&active).filter(|(_, a)| **a) {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let l = len(a, b);
            let key = crate::refine::edge_key(a, b);
            if l <= s || divided.contains_key(&key) {
                continue;
            }
            let m = divisions(l, s);
            let (lo, hi) = (a.min(b), a.max(b));
            let (p, q) = (pos0[lo as usize], pos0[hi as usize]);
            let first = pos.len() as u32;
            for i in 1..m {
                let e = p + (f64::from(i) / f64::from(m)) * (q - p);
                if near(e) {
                    pos.push(e);
                    home.push(key);
                }
            }
            divided.insert(key, (first, pos.len() as u32 - first));
        }
    }
    // Past the vertex cap before anything is triangulated: counted, not built (a face of a
    // square metre at s = 0.05 mm would hold some 5e8 lattice points). Counted only where
    // the lattices' bounds (`lattice_bound`, about twice their sizes, with no region test
    // per point) do not already fit: the count cost the dome's ball program 10 M and
    // sphere_on_plate's 19 M instructions.
    let fits = |room: usize| {
        tris0
            .par_iter()
            .zip(&active)
            .filter(|(_, a)| **a)
            .map(|(t, _)| {
                let (t, h) = lattice_plan(pos0, t, s);
                Frame::new(pos0, &t).map_or(0, |fr| lattice_bound(&fr, h))
            })
            .reduce(|| 0, usize::saturating_add)
            <= room
    };
    if let Some(c) = cap
        && !(pos.len() <= c && fits(c - pos.len()))
    {
        let room = c.saturating_sub(pos.len());
        let lattice: usize = tris0
            .par_iter()
            .zip(&active)
            .enumerate()
            .filter(|(_, (_, a))| **a)
            .map(|(f, (t, _))| {
                let (t, h) = lattice_plan(pos0, t, s);
                Frame::new(pos0, &t).map_or(0, |fr| {
                    lattice_points(&fr, h, &near_of(Some(f)), room + 1, |_, _, _, _| {})
                })
            })
            .sum();
        if pos.len() > c || lattice > room {
            return Err(c);
        }
    }
    // Faces differ in cost by orders of magnitude (a large plate face holds thousands of
    // lattice points, a dome's sliver a handful) and neighbours alike: in pieces of at most
    // 64 faces, so that the threads can even out the work (split only as far as the default
    // allows, the dome's face map ran on one thread for 80 % of its time).
    let meshes: Vec<Option<FaceMesh>> = tris0
        .par_iter()
        .zip(&active)
        .with_max_len(64)
        .enumerate()
        .map_init(Scratch::default, |scratch, (f, (t, &act))| {
            let touched = (0..3)
                .any(|k| divided.contains_key(&crate::refine::edge_key(t[k], t[(k + 1) % 3])));
            if !act && !touched {
                return None;
            }
            let (t, h) = if act {
                lattice_plan(pos0, t, s)
            } else {
                (*t, 0.0)
            };
            let fm = face_mesh(scratch, pos0, &pos, &divided, &t, h, s, &near_of(Some(f)));
            Some(fm.unwrap_or_else(|| fan(pos0, &divided, &t)))
        })
        .collect();
    // Each face's points and triangles go where the faces before it leave off (in face
    // order, as one pass would put them), written side by side.
    let (mut np, mut nt) = (pos.len(), 0);
    let mut bases = Vec::with_capacity(meshes.len());
    for m in &meshes {
        bases.push(np as u32);
        match m {
            None => nt += 1,
            Some(fm) => {
                np += fm.lattice.len();
                nt += fm.tris.len();
            }
        }
    }
    let first_new = pos.len();
    // With room for the bisection that follows (`refine::split_edges`), which adds points
    // and faces where the lattice leaves long edges: growing these arrays there moved them
    // (on sphere_on_plate's ball program the split took 7.9 ms on one thread, averaged over
    // ten calls, and 4.0 ms with the room).
    pos.reserve_exact(np - pos.len() + np / HEADROOM);
    pos.resize(np, DVec3::ZERO);
    home.reserve_exact(np - home.len() + np / HEADROOM);
    home.resize(np, 0);
    let mut tris = Vec::with_capacity(nt + nt / HEADROOM);
    tris.resize(nt, [0u32; 3]);
    let mut src = Vec::with_capacity(nt + nt / HEADROOM);
    src.resize(nt, 0u32);
    let mut parts = Vec::with_capacity(meshes.len());
    let (mut prest, mut hrest) = (&mut pos[first_new..], &mut home[first_new..]);
    let (mut trest, mut srest) = (&mut tris[..], &mut src[..]);
    for m in &meshes {
        let (lp, lt) = m
            .as_ref()
            .map_or((0, 1), |fm| (fm.lattice.len(), fm.tris.len()));
        let (p, pr) = prest.split_at_mut(lp);
        let (h, hr) = hrest.split_at_mut(lp);
        let (t, tr) = trest.split_at_mut(lt);
        let (s, sr) = srest.split_at_mut(lt);
        parts.push(((p, h), t, s));
        (prest, hrest, trest, srest) = (pr, hr, tr, sr);
    }
    parts
        .into_par_iter()
        .zip(&meshes)
        .zip(&bases)
        .enumerate()
        .with_max_len(256)
        .for_each(|(f, ((((p, h), t, s), m), &base))| match m {
            None => {
                t[0] = tris0[f];
                s[0] = f as u32;
            }
            Some(fm) => {
                p.copy_from_slice(&fm.lattice);
                h.fill(crate::refine::HOME_FACE | f as u64);
                for (out, lt) in t.iter_mut().zip(&fm.tris) {
                    *out = lt.map(|l| match fm.local(l) {
                        Local::Global(g) => g,
                        Local::Lattice(i) => base + i,
                    });
                }
                s.fill(f as u32);
            }
        });
    Ok(Remeshed {
        pos,
        tris,
        src,
        home,
    })
}

/// Face `t` turned so that its longest edge comes first (the first of equally long ones),
/// and the spacing of its lattice: that edge's division (see [`divisions`]), so that the
/// lattice's first row makes near-equilateral triangles with the points on it and its
/// columns run on across the face.
fn lattice_plan(pos0: &[DVec3], t: &[u32; 3], s: f64) -> ([u32; 3], f64) {
    let len = |k: usize| pos0[t[k] as usize].distance(pos0[t[(k + 1) % 3] as usize]);
    let mut k = 0;
    for j in 1..3 {
        if len(j) > len(k) {
            k = j;
        }
    }
    let l = len(k);
    (
        [t[k], t[(k + 1) % 3], t[(k + 2) % 3]],
        l / f64::from(divisions(l, s)),
    )
}

/// The number of equal parts, each at most `s`, an edge of length `l` (mm) is divided into:
/// `⌈l/s⌉`, a hair more so that the parts stay ≤ s despite rounding.
fn divisions(l: f64, s: f64) -> u32 {
    ((l / s * (1.0 + 1e-12)).ceil() as u32).max(1)
}

/// The boundary points of face `t` (global indices, in its own order): corners and the
/// points of its divided edges.
fn boundary(divided: &IntMap<u64, (u32, u32)>, t: &[u32; 3]) -> Vec<u32> {
    let mut ids = Vec::new();
    for k in 0..3 {
        let (p, q) = (t[k], t[(k + 1) % 3]);
        ids.push(p);
        if let Some(&(first, n)) = divided.get(&crate::refine::edge_key(p, q)) {
            let run = first..first + n;
            if p < q {
                ids.extend(run);
            } else {
                ids.extend(run.rev());
            }
        }
    }
    ids
}

/// A face whose triangulation failed its checks: its boundary points joined to its centroid,
/// which lies strictly inside, so every triangle keeps the face's orientation (the
/// bisection then splits what is longer than `s`).
fn fan(pos0: &[DVec3], divided: &IntMap<u64, (u32, u32)>, t: &[u32; 3]) -> FaceMesh {
    let ids = boundary(divided, t);
    let centroid = t.iter().map(|&i| pos0[i as usize]).sum::<DVec3>() / 3.0;
    let n = ids.len();
    let tris = (0..n)
        .map(|i| [i as u32, ((i + 1) % n) as u32, n as u32])
        .collect();
    FaceMesh {
        lattice: vec![centroid],
        ids,
        tris,
    }
}

/// A face's plane: its corners, `x` along its first edge and `y` across it towards its
/// third corner, so that the face runs counter-clockwise in `(x, y)`.
struct Frame {
    a: DVec3,
    b: DVec3,
    c: DVec3,
    x: DVec3,
    y: DVec3,
}

impl Frame {
    fn new(pos0: &[DVec3], t: &[u32; 3]) -> Option<Frame> {
        let [a, b, c] = t.map(|i| pos0[i as usize]);
        let x = (b - a).normalize();
        let y = (b - a).cross(c - a).normalize().cross(x);
        (x.is_finite() && y.is_finite()).then_some(Frame { a, b, c, x, y })
    }

    fn to2(&self, p: DVec3) -> Point2<f64> {
        Point2::new((p - self.a).dot(self.x), (p - self.a).dot(self.y))
    }
}

/// An inner edge longer than `s`: its midpoint, squared length and the triangles beside it.
type Candidate = ([f64; 2], f64, [usize; 2]);

/// Which inner edges of a face's triangulation get their midpoint, in each of
/// [`MID_ROUNDS`] rounds: those longer than `s` whose midpoint lies strictly inside the face
/// (in its frame) and `near` the region, and that are not shorter than another such edge
/// (region or not) of either triangle beside them.
///
/// Splitting only the longest edge of a triangle leaves its other long edges to the
/// triangles the split makes, which are often short enough already; splitting every long
/// edge at once put two or three points into one gap. The test ignores the region so that
/// a point is placed or not the same with a region as without one.
struct Midpoints<'a> {
    frame: &'a Frame,
    b2: [f64; 2],
    c2: [f64; 2],
    s: f64,
    near: &'a dyn Fn(DVec3) -> bool,
}

impl<'a> Midpoints<'a> {
    fn new(frame: &'a Frame, s: f64, near: &'a dyn Fn(DVec3) -> bool) -> Midpoints<'a> {
        let (b2, c2) = (frame.to2(frame.b), frame.to2(frame.c));
        Midpoints {
            frame,
            b2: [b2.x, b2.y],
            c2: [c2.x, c2.y],
            s,
            near,
        }
    }

    /// The midpoint and squared length of the inner edge `p`–`q` (frame coordinates) if it
    /// is longer than `s` and its midpoint lies strictly inside the face: a candidate.
    fn candidate(&self, p: [f64; 2], q: [f64; 2]) -> Option<([f64; 2], f64)> {
        let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
        let l2 = dx * dx + dy * dy;
        let m = [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])];
        (l2 > self.s * self.s && self.inside(m)).then_some((m, l2))
    }

    /// The candidates that get their midpoint this round, as [`Midpoints`] says, appended
    /// to `out` as (midpoint, the first triangle beside the edge); `longest` is scratch
    /// for each of the `triangles` triangles' longest candidate.
    fn choose(
        &self,
        cands: &[Candidate],
        triangles: usize,
        longest: &mut Vec<f64>,
        out: &mut Vec<([f64; 2], usize)>,
    ) {
        longest.clear();
        longest.resize(triangles, 0.0);
        for &(_, l2, sides) in cands {
            for f in sides {
                longest[f] = longest[f].max(l2);
            }
        }
        out.extend(
            cands
                .iter()
                .filter(|&&(m, l2, [f, g])| {
                    l2 >= longest[f] && l2 >= longest[g] && (self.near)(self.at(m))
                })
                .map(|&(m, _, [f, _])| (m, f)),
        );
    }

    /// Strictly inside the face, by a margin of 1e-9·s² in the corner cross products.
    fn inside(&self, p: [f64; 2]) -> bool {
        let cross = |o: [f64; 2], q: [f64; 2]| {
            (q[0] - o[0]) * (p[1] - o[1]) - (q[1] - o[1]) * (p[0] - o[0])
        };
        let tol = 1e-9 * self.s * self.s;
        let (b2, c2) = (self.b2, self.c2);
        cross([0.0, 0.0], b2) > tol && cross(b2, c2) > tol && cross(c2, [0.0, 0.0]) > tol
    }

    /// The frame point `m` on the face (mm).
    fn at(&self, m: [f64; 2]) -> DVec3 {
        self.frame.a + m[0] * self.frame.x + m[1] * self.frame.y
    }
}

/// A face's local vertex `i` of a triangulation whose first `ids.len()` points are its
/// boundary (global `ids`) and the rest its lattice and midpoints.
fn local(ids: &[u32], i: usize) -> Local {
    match ids.get(i) {
        Some(&g) => Local::Global(g),
        None => Local::Lattice((i - ids.len()) as u32),
    }
}

/// At least as many points as [`lattice_points`] calls back for the face's lattice of
/// spacing `h`, whatever its region: rows `j ≥ 1` lie `√3/2·h` apart below the third corner's
/// height less `h/2`, and each row, no wider than the first edge (the longest, so the
/// triangle narrows from it), holds at most `⌊L/h⌋ + 1` points. `usize::MAX` where that is
/// not a finite count.
fn lattice_bound(frame: &Frame, h: f64) -> usize {
    let (c2, b2) = (frame.to2(frame.c), frame.to2(frame.b));
    let dy_row = 0.5 * 3f64.sqrt() * h;
    let rows = ((c2.y - 0.5 * h) / dy_row).ceil().max(0.0);
    let per_row = (b2.x.abs() / h).floor() + 1.0;
    let n = rows * per_row;
    if n.is_finite() && n < usize::MAX as f64 {
        n as usize
    } else {
        usize::MAX
    }
}

/// Calls `f(j, px, py, p)` for each point of the face's lattice of spacing `h` (rows `j =
/// 1, 2, …` parallel to its first edge from its first corner, √3/2·h apart, odd rows
/// shifted by h/2, kept h/2 from the sides; each row left to right) for which `near(p)`
/// holds, at most `limit` of them; returns how many.
fn lattice_points(
    frame: &Frame,
    h: f64,
    near: &dyn Fn(DVec3) -> bool,
    limit: usize,
    mut f: impl FnMut(u32, f64, f64, DVec3),
) -> usize {
    let (c2, b2) = (frame.to2(frame.c), frame.to2(frame.b));
    let margin = 0.5 * h;
    // Distance from (px, py) to the lines b–c and c–a: linear in px along a row; the
    // interior lies left of a→b, b→c and c→a.
    let side = |p0: Point2<f64>, p1: Point2<f64>| {
        let (dx, dy) = (p1.x - p0.x, p1.y - p0.y);
        let l = (dx * dx + dy * dy).sqrt();
        // Signed distance (positive inside) = (dx·(py − p0y) − dy·(px − p0x)) / l.
        (dx / l, dy / l, p0)
    };
    let sides = [side(b2, c2), side(c2, Point2::new(0.0, 0.0))];
    let dy_row = 0.5 * 3f64.sqrt() * h;
    let mut count = 0;
    let mut j = 1u32;
    loop {
        let py = f64::from(j) * dy_row;
        if py >= c2.y - margin {
            return count;
        }
        // The interval of px where both distances are ≥ margin.
        let (mut u0, mut u1) = (f64::NEG_INFINITY, f64::INFINITY);
        for &(ux, uy, p0) in &sides {
            // ux·(py − p0.y) − uy·(px − p0.x) ≥ margin, i.e. k0 − uy·px ≥ 0.
            let k0 = ux * (py - p0.y) + uy * p0.x - margin;
            if uy > 0.0 {
                u1 = u1.min(k0 / uy);
            } else if uy < 0.0 {
                u0 = u0.max(k0 / uy);
            } else if k0 < 0.0 {
                u1 = f64::NEG_INFINITY;
            }
        }
        // Lattice columns: odd rows shifted by h/2, so neighbouring rows make equilateral
        // triangles.
        let shift = if j % 2 == 1 { 0.5 * h } else { 0.0 };
        let i0 = ((u0 - shift) / h).ceil();
        let mut px = shift + i0 * h;
        while px <= u1 {
            let p = frame.a + px * frame.x + py * frame.y;
            if near(p) {
                if count == limit {
                    return count;
                }
                f(j, px, py, p);
                count += 1;
            }
            px += h;
        }
        j += 1;
    }
}

/// The triangulation of face `t`: its boundary (corners and the points of its divided
/// edges, in its own order) and, when `h > 0`, a lattice of spacing `h` inside; then
/// midpoints on the inner edges still longer than `s`. Built by [`PolyCdt`]; where that
/// cannot place a point, by spade ([`face_mesh_spade`]), which gives the same triangles
/// wherever the Delaunay triangulation is unique.
#[allow(clippy::too_many_arguments)]
fn face_mesh(
    scratch: &mut Scratch,
    pos0: &[DVec3],
    pos: &[DVec3],
    divided: &IntMap<u64, (u32, u32)>,
    t: &[u32; 3],
    h: f64,
    s: f64,
    near: &dyn Fn(DVec3) -> bool,
) -> Option<FaceMesh> {
    face_mesh_own(scratch, pos0, pos, divided, t, h, s, near)
        .or_else(|| face_mesh_spade(pos0, pos, divided, t, h, s, near))
}

/// A worker's memory for [`face_mesh_own`], reused from face to face.
#[derive(Default)]
struct Scratch {
    cdt: PolyCdt,
    pts: Vec<[f64; 2]>,
    flat: Vec<[f64; 2]>,
    mids: Vec<([f64; 2], usize)>,
    /// Candidate midpoints: point, squared length, the triangles beside the edge.
    cands: Vec<Candidate>,
    /// Per triangle, the squared length of its longest candidate edge.
    longest: Vec<f64>,
    /// The lattice's rows: row number, first and end index into `flat`.
    rows: Vec<(u32, usize, usize)>,
    /// The leading rows handed to `PolyCdt::reset_lattice`.
    ranges: Vec<(usize, usize)>,
}

/// [`face_mesh`] by [`PolyCdt`]; `None` where it cannot place a point or the result is not
/// a triangulation of the face.
#[allow(clippy::too_many_arguments)]
fn face_mesh_own(
    scratch: &mut Scratch,
    pos0: &[DVec3],
    pos: &[DVec3],
    divided: &IntMap<u64, (u32, u32)>,
    t: &[u32; 3],
    h: f64,
    s: f64,
    near: &dyn Fn(DVec3) -> bool,
) -> Option<FaceMesh> {
    let frame = Frame::new(pos0, t)?;
    let ids = boundary(divided, t);
    let nb = ids.len();
    let corner = |c: u32| ids.iter().position(|&i| i == c);
    let corners = [0, corner(t[1])?, corner(t[2])?];
    let Scratch {
        cdt,
        pts,
        flat,
        mids,
        cands,
        longest,
        rows,
        ranges,
    } = scratch;
    pts.clear();
    pts.extend(ids.iter().map(|&i| {
        let p = frame.to2(pos[i as usize]);
        [p.x, p.y]
    }));
    let mut lattice = Vec::new();
    flat.clear();
    rows.clear();
    if h > 0.0 {
        lattice_points(&frame, h, near, usize::MAX, |j, px, py, p| {
            // Rows as `polycdt::leading_rows` takes them.
            match rows.last_mut() {
                Some((rj, _, e)) if *rj == j => *e += 1,
                _ => rows.push((j, flat.len(), flat.len() + 1)),
            }
            flat.push([px, py]);
            lattice.push(p);
        });
    }
    // The leading rows are triangulated as a lattice; any points after them are inserted
    // one by one.
    let laid = crate::polycdt::leading_rows(rows);
    ranges.clear();
    ranges.extend(rows[..laid].iter().map(|&(_, s, e)| (s, e)));
    let upto = ranges.last().map_or(0, |r| r.1);
    // Room for the midpoints too (about half as many again).
    let room = flat.len() + flat.len() / 2 + nb;
    let rest = if cdt
        .reset_lattice(pts, corners, &flat[..upto], ranges, room - upto)
        .is_some()
    {
        upto
    } else {
        cdt.reset(pts, corners, room)?;
        0
    };
    for &p in &flat[rest..] {
        cdt.insert(p)?;
    }
    // Inner edges still longer than `s` get their midpoints (see `face_mesh_spade`).
    if h > 0.0 {
        let rule = Midpoints::new(&frame, s, near);
        for _ in 0..MID_ROUNDS {
            cands.clear();
            cdt.for_each_inner_edge(|p, q, t, u| {
                if let Some((m, l2)) = rule.candidate(p, q) {
                    cands.push((m, l2, [t as usize, u as usize]));
                }
            });
            mids.clear();
            rule.choose(cands, cdt.triangles().len(), longest, mids);
            if mids.is_empty() {
                break;
            }
            for &(m, t) in mids.iter() {
                cdt.insert_near(m, t as u32)?;
                lattice.push(rule.at(m));
            }
        }
    }
    // Numbered as the triangulation numbers its points: the boundary's, then the lattice's.
    let tris = cdt.triangles().to_vec();
    if tris.len() != nb + 2 * lattice.len() - 2 || cdt.num_points() != nb + lattice.len() {
        return None;
    }
    Some(FaceMesh { lattice, ids, tris })
}

/// [`face_mesh`] by spade's constrained Delaunay triangulation.
fn face_mesh_spade(
    pos0: &[DVec3],
    pos: &[DVec3],
    divided: &IntMap<u64, (u32, u32)>,
    t: &[u32; 3],
    h: f64,
    s: f64,
    near: &dyn Fn(DVec3) -> bool,
) -> Option<FaceMesh> {
    let frame = Frame::new(pos0, t)?;
    // Boundary, counter-clockwise in the face's frame.
    let ids = boundary(divided, t);
    let mut pts: Vec<Point2<f64>> = ids.iter().map(|&i| frame.to2(pos[i as usize])).collect();
    let nb = pts.len();
    // The lattice (see `lattice_points`), then any midpoints added below.
    let mut lattice = Vec::new();
    if h > 0.0 {
        lattice_points(&frame, h, near, usize::MAX, |_, px, py, p| {
            pts.push(Point2::new(px, py));
            lattice.push(p);
        });
    }
    let edges: Vec<[usize; 2]> = (0..nb).map(|i| [i, (i + 1) % nb]).collect();
    let n_in = pts.len();
    let mut conflict = false;
    let mut cdt: ConstrainedDelaunayTriangulation<Point2<f64>> =
        ConstrainedDelaunayTriangulation::try_bulk_load_cdt(pts, edges, |_| conflict = true)
            .ok()?;
    if conflict || cdt.num_vertices() != n_in {
        return None;
    }
    // Inner edges still longer than `s` (where the lattice meets the boundary) get their
    // midpoints, strictly inside the face, as `Midpoints` says: the boundary, whose parts are
    // at most `s`, is never touched, so the faces around stay conforming.
    if h > 0.0 {
        let rule = Midpoints::new(&frame, s, near);
        for _ in 0..MID_ROUNDS {
            let cands: Vec<Candidate> = cdt
                .undirected_edges()
                .filter(|e| !e.is_constraint_edge())
                .filter_map(|e| {
                    let [p, q] = e.positions();
                    let d = e.as_directed();
                    let sides = [d.face().fix().index(), d.rev().face().fix().index()];
                    rule.candidate([p.x, p.y], [q.x, q.y])
                        .map(|(m, l2)| (m, l2, sides))
                })
                .collect();
            let mut mids = Vec::new();
            rule.choose(&cands, cdt.num_all_faces(), &mut Vec::new(), &mut mids);
            if mids.is_empty() {
                break;
            }
            for (m, _) in mids {
                let before = cdt.num_vertices();
                cdt.insert(Point2::new(m[0], m[1])).ok()?;
                if cdt.num_vertices() != before + 1 {
                    return None;
                }
                lattice.push(rule.at(m));
            }
        }
    }
    // Faces outside the boundary: reached from the outer face without crossing it.
    let mut outside = vec![false; cdt.num_all_faces()];
    let mut stack = Vec::new();
    for f in cdt.inner_faces() {
        for e in f.adjacent_edges() {
            if e.rev().face().as_inner().is_none() && !e.as_undirected().is_constraint_edge() {
                stack.push(f.fix());
            }
        }
    }
    while let Some(fh) = stack.pop() {
        let f = cdt.face(fh);
        let i = fh.index();
        if outside[i] {
            continue;
        }
        outside[i] = true;
        for e in f.adjacent_edges() {
            if e.as_undirected().is_constraint_edge() {
                continue;
            }
            if let Some(g) = e.rev().face().as_inner()
                && !outside[g.fix().index()]
            {
                stack.push(g.fix());
            }
        }
    }
    // Spade numbers its points as inserted: the boundary's, then the lattice's.
    let tris: Vec<[u32; 3]> = cdt
        .inner_faces()
        .filter(|f| !outside[f.fix().index()])
        .map(|f| f.vertices().map(|v| v.fix().index() as u32))
        .collect();
    // A triangulation of a polygon with `nb` boundary and `l` inner points has nb + 2l − 2
    // triangles.
    if tris.len() != nb + 2 * lattice.len() - 2 {
        return None;
    }
    Some(FaceMesh { lattice, ids, tris })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fallback fan covers the face with its orientation: as many triangles as boundary
    /// points, each turning as the face does, their areas summing to the face's.
    #[test]
    fn fan_covers_the_face_with_its_orientation() {
        let pos0 = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(4.0, 0.0, 1.0),
            DVec3::new(1.0, 3.0, 2.0),
        ];
        let t = [0u32, 1, 2];
        let mut pos = pos0.clone();
        let mut divided: IntMap<u64, (u32, u32)> = IntMap::default();
        // Edge 0–1 divided in four, edge 2–0 in two.
        divided.insert(crate::refine::edge_key(0, 1), (3, 3));
        for i in 1..4 {
            pos.push(pos0[0].lerp(pos0[1], f64::from(i) / 4.0));
        }
        divided.insert(crate::refine::edge_key(2, 0), (6, 1));
        pos.push(pos0[0].lerp(pos0[2], 0.5));
        let fm = fan(&pos0, &divided, &t);
        assert_eq!(fm.tris.len(), 7);
        let n = (pos0[1] - pos0[0]).cross(pos0[2] - pos0[0]);
        let at = |l: Local| match l {
            Local::Global(g) => pos[g as usize],
            Local::Lattice(i) => fm.lattice[i as usize],
        };
        let mut area = 0.0;
        for tri in &fm.tris {
            let [a, b, c] = tri.map(|l| at(fm.local(l)));
            let cr = (b - a).cross(c - a);
            assert!(cr.dot(n) > 0.0, "a fan triangle is flipped or flat");
            area += 0.5 * cr.length();
        }
        assert!((area - 0.5 * n.length()).abs() < 1e-12, "{area}");
    }

    /// The cap's shortcut bounds every face's lattice from above, and not by much more than
    /// twice: on random faces from slivers to faces a hundred times the spacing across.
    #[test]
    fn lattice_bound_holds_every_lattice() {
        let mut rng = crate::testkit::Lcg(23);
        let mut rnd = || rng.next();
        let mut faces = 0;
        for _ in 0..2000 {
            let size = 0.1 + 30.0 * rnd() * rnd();
            let s = 0.05 + 0.5 * rnd();
            let pos0: Vec<DVec3> = (0..3)
                .map(|_| size * DVec3::new(rnd(), rnd(), rnd()))
                .collect();
            let (t, h) = lattice_plan(&pos0, &[0, 1, 2], s);
            let Some(fr) = Frame::new(&pos0, &t) else {
                continue;
            };
            let n = lattice_points(&fr, h, &|_| true, usize::MAX, |_, _, _, _| {});
            let b = lattice_bound(&fr, h);
            assert!(n <= b, "size {size}, s {s}: {n} points, bound {b}");
            if n > 1000 {
                assert!(b < 3 * n, "size {size}, s {s}: {n} points, bound {b}");
                faces += 1;
            }
        }
        assert!(faces > 50, "{faces} large faces");
    }

    /// The own triangulation and spade's give the same face meshes: the same lattice and
    /// midpoints (as a set of points) and the same triangles (as triples of points), on
    /// random faces from slivers to faces some fifty times the edge bound across.
    #[test]
    fn own_triangulation_matches_spade() {
        let mut rng = crate::testkit::Lcg(11);
        let mut rnd = || rng.next();
        let s = 0.3;
        let mut faces = 0;
        for _ in 0..300 {
            let size = 0.2 + 15.0 * rnd() * rnd();
            let pos0: Vec<DVec3> = (0..3)
                .map(|_| size * DVec3::new(rnd(), rnd(), 0.3 * rnd()))
                .collect();
            let t = [0u32, 1, 2];
            if Frame::new(&pos0, &t).is_none() {
                continue;
            }
            // Divide the edges longer than s as `remesh` does.
            let mut pos = pos0.clone();
            let mut divided: IntMap<u64, (u32, u32)> = IntMap::default();
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let l = pos0[a as usize].distance(pos0[b as usize]);
                if l <= s {
                    continue;
                }
                let m = divisions(l, s);
                let (lo, hi) = (a.min(b), a.max(b));
                let first = pos.len() as u32;
                for i in 1..m {
                    pos.push(
                        pos0[lo as usize].lerp(pos0[hi as usize], f64::from(i) / f64::from(m)),
                    );
                }
                divided.insert(crate::refine::edge_key(a, b), (first, m - 1));
            }
            let near = |_: DVec3| true;
            let (t, h) = lattice_plan(&pos0, &t, s);
            let own = face_mesh_own(
                &mut Scratch::default(),
                &pos0,
                &pos,
                &divided,
                &t,
                h,
                s,
                &near,
            )
            .expect("own triangulation");
            let theirs = face_mesh_spade(&pos0, &pos, &divided, &t, h, s, &near).expect("spade");
            let key = |fm: &FaceMesh| {
                let at = |l: Local| match l {
                    Local::Global(g) => pos[g as usize],
                    Local::Lattice(i) => fm.lattice[i as usize],
                };
                let mut tris: Vec<[[u64; 3]; 3]> = fm
                    .tris
                    .iter()
                    .map(|tri| {
                        let mut v = tri.map(|l| at(fm.local(l)).to_array().map(f64::to_bits));
                        let r = (0..3).min_by_key(|&k| v[k]).unwrap();
                        v.rotate_left(r);
                        v
                    })
                    .collect();
                tris.sort_unstable();
                let mut pts: Vec<[u64; 3]> = fm
                    .lattice
                    .iter()
                    .map(|p| p.to_array().map(f64::to_bits))
                    .collect();
                pts.sort_unstable();
                (pts, tris)
            };
            assert_eq!(key(&own), key(&theirs), "face of size {size}");
            faces += 1;
        }
        assert!(faces > 250);
    }
}
