//! Refinement of the design surface for the normal-vector method (imprint paper §3.4).
//!
//! The design mesh is welded (corners with bit-identical coordinates become one vertex),
//! remeshed into near-equilateral faces ([`crate::remesh`]), then refined by conforming
//! longest-edge bisection (Rivara's 4-triangle partition) until no edge is longer than `s`.
//! With the paper's rule `s = sqrt(6·r·e)` a sphere of radius `r` (the pseudo-insert radius,
//! i.e. the cutter's corner radius) cannot sink deeper than `e` into an equilateral triangle
//! of side `s` without covering one of its vertices (nor into any triangle whose edges are
//! at most `s`: its smallest enclosing circle is no larger), so sampling the vertices bounds
//! the undetected gouge by `e`. Bisection alone leaves right-angled faces with edges between
//! `s/2` and `s`; the remesh reaches the same bound with 0.15–0.6 times the vertices (0.44 on
//! the dome, 0.23 on sphere_on_plate, 0.56 on mount_rush at s = 0.3), each one normal vector
//! fewer to measure.
//!
//! Every new vertex lies on an edge of an original triangle or inside it, in its plane, so
//! all refined faces lie exactly (up to rounding) on the design surface; `face_source` names
//! that original triangle.
//!
//! Vertex normals are angle-weighted averages of the normals of incident faces in the same
//! smooth group: a face contributes to a corner's normal only when its normal is within
//! `crease_angle_deg` of the corner's own face normal. Where the groups differ (a crease) the
//! vertex is duplicated, one copy per distinct normal, so vectors grown from a plane stay
//! perpendicular to it.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use cam_core::{Cutter, DVec3, Mesh};
use rayon::prelude::*;

/// What [`refine`] does when the refined mesh would exceed [`RefineConfig::max_vertices`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum CapPolicy {
    /// Return [`RefineError::TooManyVertices`].
    Error,
    /// Retry with the edge length multiplied by 1.25 until the mesh fits; the length used is
    /// reported in [`RefinedMesh::max_edge_mm`]. Still an error when the design mesh alone
    /// has more vertices than the cap.
    Coarsen,
}

/// Settings of the refinement.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct RefineConfig {
    /// Longest edge allowed after refinement (mm); see [`max_edge_for`].
    pub max_edge_mm: f64,
    /// Faces whose normals differ by more than this angle (degrees) belong to different smooth
    /// groups at a shared vertex (default 30°).
    pub crease_angle_deg: f64,
    /// Largest number of refined vertices (before crease duplication); `None` = no cap.
    pub max_vertices: Option<usize>,
    /// What to do when the cap is hit.
    pub on_cap: CapPolicy,
    /// Only where a normal vector can meet this region are faces refined (and their
    /// neighbours as far as conforming bisection needs); `None` refines everything. A
    /// verification passes a box holding the swept volume and its vectors' lengths: outside
    /// their reach no vertex can read anything but "nothing swept".
    pub region: Option<Region>,
    /// Remesh the faces into near-equilateral triangles before bisecting (default; see
    /// [`crate::remesh`]): about half the vertices for the same edge bound. `false`
    /// bisects the design faces alone, so a square's vertices stay on a dyadic grid.
    pub remesh: bool,
}

impl RefineConfig {
    /// The paper's settings for `cutter` at resolution `resolution_mm` (default 0.005 mm):
    /// `max_edge_mm = max_edge_for(cutter, resolution_mm)`, 30° creases, a cap of 20 million
    /// vertices that makes refinement fail rather than coarsen.
    pub fn for_cutter(cutter: &Cutter, resolution_mm: f64) -> RefineConfig {
        RefineConfig {
            max_edge_mm: max_edge_for(cutter, resolution_mm),
            crease_angle_deg: 30.0,
            max_vertices: Some(20_000_000),
            on_cap: CapPolicy::Error,
            region: None,
            remesh: true,
        }
    }
}

/// Where refinement is needed (see [`RefineConfig::region`]): a box that holds the swept
/// volume, and how far the normal vectors reach into the material and out of it.
///
/// A point inside a design face grows its vector along the face's normal, so a face is
/// refined, and a point inside it placed, only if that segment can meet the box (the face
/// swept along its normal, bounded by boxes). Points on the design edges, whose vertex
/// normals average the faces around, are placed if the box lies within a vector's length
/// in any direction. The bottom of a part machined from above lies beyond the vectors of
/// its faces and is left coarse (on the dome, a third of the vertices).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Region {
    /// `[x0, y0, z0, x1, y1, z1]` (mm): a box holding everything the vectors are measured
    /// against.
    pub bounds: [f64; 6],
    /// How far a vector reaches into the material, against its normal (mm, ≥ 0).
    pub inside_mm: f64,
    /// How far a vector reaches out of the material, along its normal (mm, ≥ 0).
    pub outside_mm: f64,
}

impl Region {
    /// Whether the segments from the points `pts` along `n` (`-inside_mm..outside_mm`), or
    /// the balls of the longer length about them without a direction, can come within
    /// `slack` (mm) of the box: their bounding boxes against the box grown by `slack`.
    pub(crate) fn reached(&self, pts: &[DVec3], n: Option<DVec3>, slack: f64) -> bool {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for &p in pts {
            lo = lo.min(p);
            hi = hi.max(p);
        }
        let (dlo, dhi) = match n {
            Some(n) => {
                let (a, b) = (-self.inside_mm * n, self.outside_mm * n);
                (a.min(b), a.max(b))
            }
            None => {
                let r = self.inside_mm.max(self.outside_mm);
                (DVec3::splat(-r), DVec3::splat(r))
            }
        };
        let (lo, hi) = (lo + dlo - slack, hi + dhi + slack);
        let b = &self.bounds;
        lo.x <= b[3] && hi.x >= b[0] && lo.y <= b[4] && hi.y >= b[1] && lo.z <= b[5] && hi.z >= b[2]
    }
}

/// The unit normal of face `t`, `None` for a degenerate face (its points are then tested
/// without a direction).
pub(crate) fn face_normal(pos: &[DVec3], t: &[u32; 3]) -> Option<DVec3> {
    let [a, b, c] = t.map(|i| pos[i as usize]);
    let n = (b - a).cross(c - a).normalize();
    n.is_finite().then_some(n)
}

/// Default resolution `e` of the normal-vector method (mm), as in the paper.
pub const DEFAULT_RESOLUTION_MM: f64 = 0.005;

/// The paper's edge length `s = sqrt(6·r·e)` (mm) for the cutter's corner radius `r` and the
/// resolution `e` (mm).
///
/// A flat end mill has `r = 0`, for which the rule gives no finite length: its cutting edge is
/// the circle of radius `R` bounding the flat bottom, so the substitute is `r = R` (the
/// curvature radius of that edge), giving `s = sqrt(6·R·e)`. Callers wanting another length
/// set [`RefineConfig::max_edge_mm`] directly.
pub fn max_edge_for(cutter: &Cutter, resolution_mm: f64) -> f64 {
    let r = if cutter.corner_radius() > 0.0 {
        cutter.corner_radius()
    } else {
        cutter.radius()
    };
    (6.0 * r * resolution_mm).sqrt()
}

/// Why the design surface could not be refined.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RefineError {
    /// `max_edge_mm` is not a finite positive number.
    #[error("refinement edge length must be a positive number of mm, got {max_edge_mm}")]
    BadEdgeLength {
        /// The value given.
        max_edge_mm: f64,
    },
    /// The refined mesh would have more vertices than allowed ([`CapPolicy::Error`]).
    #[error(
        "refining to edges of {max_edge_mm} mm needs more than {cap} vertices \
         (about {estimated} expected); raise the cap or use a coarser resolution \
         (edges of about {suggested_max_edge_mm:.4} mm would fit)"
    )]
    TooManyVertices {
        /// The edge length tried (mm).
        max_edge_mm: f64,
        /// The cap.
        cap: usize,
        /// Rough estimate of the vertices needed (from the surface area).
        estimated: usize,
        /// An edge length (mm) whose estimated vertex count is below the cap.
        suggested_max_edge_mm: f64,
    },
}

/// The refined design surface: an indexed mesh with welded vertices and per-vertex normals.
#[derive(Debug, Clone, PartialEq)]
pub struct RefinedMesh {
    /// Vertex positions (mm). A vertex on a crease appears once per smooth group.
    pub positions: Vec<DVec3>,
    /// Unit vertex normals, one per position.
    pub normals: Vec<DVec3>,
    /// Faces as indices into `positions`, counter-clockwise as in the design mesh.
    pub triangles: Vec<[u32; 3]>,
    /// For each face, the index of the design triangle (in `Mesh::triangles`) it lies in.
    pub face_source: Vec<u32>,
    /// The longest edge allowed in this refinement (mm): the requested one, or a coarser one
    /// under [`CapPolicy::Coarsen`].
    pub max_edge_mm: f64,
}

impl RefinedMesh {
    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.positions.len()
    }
    /// True when there is no vertex (never for a refined [`Mesh`]).
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }
}

/// A small deterministic hasher for integer keys (FxHash-style multiply-rotate).
#[derive(Default)]
pub(crate) struct IntHasher(u64);

impl Hasher for IntHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }
    fn write_u64(&mut self, n: u64) {
        self.0 = (self.0.rotate_left(5) ^ n).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

type IntMap<K, V> = HashMap<K, V, BuildHasherDefault<IntHasher>>;

pub(crate) fn edge_key(a: u32, b: u32) -> u64 {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    (u64::from(lo) << 32) | u64::from(hi)
}

/// A corner's coordinates as bits, the weld's key: hashed as one word of the three (with
/// the default hasher a weld of the dome took 9.7 M instructions, with this 1.6 M).
#[derive(Clone, Copy, PartialEq, Eq)]
struct PosKey([u64; 3]);

impl std::hash::Hash for PosKey {
    fn hash<H: Hasher>(&self, h: &mut H) {
        let [x, y, z] = self.0;
        h.write_u64(x ^ y.rotate_left(21) ^ z.rotate_left(42));
    }
}

/// Welds the soup into an indexed mesh: bit-identical corners (with -0 read as +0) merge.
fn weld(mesh: &Mesh) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut map: IntMap<PosKey, u32> = IntMap::default();
    map.reserve(mesh.len());
    let mut positions = Vec::new();
    let mut tris = Vec::with_capacity(mesh.len());
    for t in mesh.triangles() {
        let mut idx = [0u32; 3];
        for (k, p) in t.v.iter().enumerate() {
            let key = PosKey([p.x, p.y, p.z].map(|c| (c + 0.0).to_bits()));
            idx[k] = *map.entry(key).or_insert_with(|| {
                positions.push(*p);
                (positions.len() - 1) as u32
            });
        }
        tris.push(idx);
    }
    (positions, tris)
}

/// How well the design mesh's faces join, counted on the welded mesh (corners with
/// bit-identical coordinates are one vertex). The normal-vector method reads the material
/// side from each face's orientation: it needs faces oriented consistently, and where they
/// are not, vectors start in the air and can read as gouges of `L_in`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct Topology {
    /// Edges used by one face (the rim of an open surface).
    pub boundary_edges: usize,
    /// Edges used by more than two faces.
    pub non_manifold_edges: usize,
    /// Edges used by exactly two faces that run along it the same way: the two faces
    /// disagree on which side is the material.
    pub misoriented_edges: usize,
}

impl Topology {
    /// True when every edge joins two faces that agree on orientation.
    pub fn is_closed_and_oriented(&self) -> bool {
        self.boundary_edges == 0 && self.non_manifold_edges == 0 && self.misoriented_edges == 0
    }
}

/// Per undirected edge (by [`edge_key`]): how many faces use it, and how many of those run
/// along it from the lower to the higher vertex index.
fn edge_uses(tris: &[[u32; 3]]) -> IntMap<u64, (u32, u32)> {
    let mut uses: IntMap<u64, (u32, u32)> = IntMap::default();
    for t in tris {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if a == b {
                continue;
            }
            let e = uses.entry(edge_key(a, b)).or_insert((0, 0));
            e.0 += 1;
            e.1 += u32::from(a < b);
        }
    }
    uses
}

/// The vertices of `refined` on its rim: on an edge used by one face only.
pub fn rim_vertices(refined: &RefinedMesh) -> Vec<bool> {
    let mut rim = vec![false; refined.positions.len()];
    for (&key, &(n, _)) in &edge_uses(&refined.triangles) {
        if n == 1 {
            rim[(key >> 32) as usize] = true;
            rim[(key & 0xffff_ffff) as usize] = true;
        }
    }
    rim
}

/// Per welded design triangle: 2 where one of its edges is a boundary edge (used by it
/// alone, `uses` as [`edge_uses`] counts them), 1 where it shares an edge with such a
/// triangle, else 0; for [`rim_vertices_near`].
fn rim_levels(tris: &[[u32; 3]], uses: &IntMap<u64, (u32, u32)>) -> Vec<u8> {
    let n = |a: u32, b: u32| uses.get(&edge_key(a, b)).map_or(0, |u| u.0);
    let edges = |t: &[u32; 3]| {
        let t = *t;
        (0..3).map(move |k| (t[k], t[(k + 1) % 3]))
    };
    let mut level: Vec<u8> = tris
        .iter()
        .map(|t| u8::from(edges(t).any(|(a, b)| a != b && n(a, b) == 1)) * 2)
        .collect();
    let near: std::collections::HashSet<u64, BuildHasherDefault<IntHasher>> = tris
        .iter()
        .zip(&level)
        .filter(|&(_, &l)| l == 2)
        .flat_map(|(t, _)| edges(t).map(|(a, b)| edge_key(a, b)))
        .collect();
    for (t, l) in tris.iter().zip(&mut level) {
        if *l == 0 && edges(t).any(|(a, b)| near.contains(&edge_key(a, b))) {
            *l = 1;
        }
    }
    level
}

/// [`rim_vertices`] of a refinement of the design whose rim levels ([`design_topology`])
/// are `rim`, counting
/// only the refined faces of design triangles on or next to its rim: a refined edge used by
/// one face lies on a boundary edge of the design (the refinement is conforming), and every
/// refined edge of a triangle on the rim is counted with all its faces (they lie in that
/// triangle or in one sharing the edge). The same vertices as [`rim_vertices`] where every
/// refined vertex is one point of the design (no vertex split at a crease: a crease angle
/// of 180°, as the verifier refines).
pub fn rim_vertices_near(refined: &RefinedMesh, rim: &[u8]) -> Vec<bool> {
    let level = |f: usize| {
        refined
            .face_source
            .get(f)
            .and_then(|&src| rim.get(src as usize))
            .copied()
            .unwrap_or(2)
    };
    let near: Vec<[u32; 3]> = (0..refined.triangles.len())
        .filter(|&f| level(f) > 0)
        .map(|f| refined.triangles[f])
        .collect();
    let uses = edge_uses(&near);
    let mut out = vec![false; refined.positions.len()];
    for (f, t) in refined.triangles.iter().enumerate() {
        if level(f) < 2 {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if a != b && uses.get(&edge_key(a, b)).is_some_and(|u| u.0 == 1) {
                out[a as usize] = true;
                out[b as usize] = true;
            }
        }
    }
    out
}

/// Counts the boundary, non-manifold and misoriented edges of `mesh` (see [`Topology`]).
pub fn topology(mesh: &Mesh) -> Topology {
    design_topology(mesh).0
}

/// [`topology`]; per design triangle (in `Mesh::triangles` order) whether one of its edges
/// is non-manifold or misoriented (there the material side is unknown); and, for a mesh
/// with boundary edges, each triangle's level next to its rim (2 on it, 1 sharing an edge
/// with a triangle on it, else 0; for [`rim_vertices_near`]).
pub fn design_topology(mesh: &Mesh) -> (Topology, Vec<bool>, Option<Vec<u8>>) {
    let (_, tris) = weld(mesh);
    let uses = edge_uses(&tris);
    let mut topo = Topology::default();
    for &(n, forward) in uses.values() {
        match n {
            1 => topo.boundary_edges += 1,
            2 if forward != 1 => topo.misoriented_edges += 1,
            2 => {}
            _ => topo.non_manifold_edges += 1,
        }
    }
    let bad = |a: u32, b: u32| {
        uses.get(&edge_key(a, b))
            .is_some_and(|&(n, forward)| n > 2 || (n == 2 && forward != 1))
    };
    let unoriented = tris
        .iter()
        .map(|t| (0..3).any(|k| t[k] != t[(k + 1) % 3] && bad(t[k], t[(k + 1) % 3])))
        .collect();
    let rim = (topo.boundary_edges > 0).then(|| rim_levels(&tris, &uses));
    (topo, unoriented, rim)
}

fn estimate_vertices(area_mm2: f64, s: f64) -> usize {
    // Longest-edge refinement of typical meshes ends with edges between s/2 and s; a regular
    // triangulation of edge ~0.7·s has about 2·area/(√3·(0.7 s)²)/2 vertices.
    let e = 0.7 * s;
    (area_mm2 / (0.5 * 3f64.sqrt() * e * e)).ceil() as usize
}

/// Refines the design mesh so that no edge is longer than `cfg.max_edge_mm` and computes
/// vertex normals (see the module documentation). Deterministic: the same input gives the
/// same output, bit for bit.
///
/// # Errors
/// [`RefineError::BadEdgeLength`] for a non-positive or non-finite length;
/// [`RefineError::TooManyVertices`] when the cap is exceeded under [`CapPolicy::Error`].
pub fn refine(mesh: &Mesh, cfg: &RefineConfig) -> Result<RefinedMesh, RefineError> {
    if !(cfg.max_edge_mm.is_finite() && cfg.max_edge_mm > 0.0) {
        return Err(RefineError::BadEdgeLength {
            max_edge_mm: cfg.max_edge_mm,
        });
    }
    let (welded_pos, welded_tris) = weld(mesh);
    let normals0: Vec<Option<DVec3>> = if cfg.region.is_some() {
        welded_tris
            .iter()
            .map(|t| face_normal(&welded_pos, t))
            .collect()
    } else {
        Vec::new()
    };
    let area: f64 = mesh.triangles().iter().map(|t| t.area()).sum();
    let mut s = cfg.max_edge_mm;
    loop {
        // Near-equilateral faces first (see `crate::remesh`), then bisection where an edge
        // is still longer than `s`.
        let start = if cfg.remesh {
            crate::remesh::remesh(
                &welded_pos,
                &welded_tris,
                s,
                cfg.region.as_ref().map(|r| (r, normals0.as_slice())),
                cfg.max_vertices,
            )
            .map(|r| (r.pos, r.tris, r.src, r.home))
        } else {
            Ok((
                welded_pos.clone(),
                welded_tris.clone(),
                (0..welded_tris.len() as u32).collect(),
                vec![HOME_CORNER; welded_pos.len()],
            ))
        };
        let refined = start.and_then(|(pos, tris, src, home)| {
            split_edges(
                (pos, home),
                tris,
                src,
                s,
                cfg.max_vertices,
                cfg.region.as_ref().map(|r| (r, normals0.as_slice())),
            )
        });
        match refined {
            Ok(((pos, home), tris, src)) => {
                let (positions, normals, triangles) = vertex_normals(
                    mesh,
                    &welded_tris,
                    pos,
                    tris,
                    &src,
                    cfg.crease_angle_deg,
                    Some(&home),
                );
                return Ok(RefinedMesh {
                    positions,
                    normals,
                    triangles,
                    face_source: src,
                    max_edge_mm: s,
                });
            }
            Err(cap) => {
                // Coarsening cannot help once the design's own vertices exceed the cap.
                let hopeless = welded_pos.len() > cap;
                if cfg.on_cap == CapPolicy::Coarsen && !hopeless {
                    s *= 1.25;
                    continue;
                }
                let estimated = estimate_vertices(area, s);
                let mut suggested = s;
                for _ in 0..400 {
                    if estimate_vertices(area, suggested) <= cap {
                        break;
                    }
                    suggested *= 1.1;
                }
                return Err(RefineError::TooManyVertices {
                    max_edge_mm: s,
                    cap,
                    estimated: estimated.max(cap + 1),
                    suggested_max_edge_mm: suggested,
                });
            }
        }
    }
}

/// A region and the normals of the design faces (welded), which faces' points reach along.
pub(crate) type RegionOf<'a> = Option<(&'a Region, &'a [Option<DVec3>])>;

/// Whether face `t`, lying in design face `src`, can reach the region along that face's
/// normal (everywhere without a region).
pub(crate) fn meets_region(region: RegionOf<'_>, pos: &[DVec3], t: &[u32; 3], src: u32) -> bool {
    let Some((r, normals)) = region else {
        return true;
    };
    r.reached(&t.map(|i| pos[i as usize]), normals[src as usize], 0.0)
}

/// A refined vertex's place on the design (its home), which decides the design faces
/// around it without a pass over the refined faces (see [`vertex_normals`]): a design
/// corner (`HOME_CORNER`; its index is the design vertex's), a point of a design edge (the
/// edge's [`edge_key`], whose top bit is clear), or a point inside design face `f`
/// (`HOME_FACE | f`).
pub(crate) const HOME_CORNER: u64 = u64::MAX;

/// See [`HOME_CORNER`].
pub(crate) const HOME_FACE: u64 = 1 << 63;

/// The home ([`HOME_CORNER`]) of the midpoint of the edge `a`–`b` of a refined face in
/// design face `f`: on a design edge where both ends lie on it (a straight edge holds the
/// segment between two of its points, and a segment inside a face that meets the face's
/// side anywhere but at its ends runs along it), else inside `f`. Two corners of one design
/// face span one of its edges.
fn midpoint_home(home: &[u64], a: u32, b: u32, f: u32) -> u64 {
    let on = |e: u64, c: u32| e >> 32 == u64::from(c) || e & 0xffff_ffff == u64::from(c);
    let edge = |h: u64| h & HOME_FACE == 0;
    match (home[a as usize], home[b as usize]) {
        (HOME_CORNER, HOME_CORNER) => edge_key(a, b),
        (HOME_CORNER, e) if edge(e) && on(e, a) => e,
        (e, HOME_CORNER) if edge(e) && on(e, b) => e,
        (e, g) if e == g && edge(e) => e,
        _ => HOME_FACE | u64::from(f),
    }
}

/// The index `k` of the longest edge `t[k] → t[k+1]` of a face; ties go to the smaller edge
/// key, so the choice does not depend on how the face's corners are rotated.
fn longest_edge(pos: &[DVec3], t: &[u32; 3]) -> usize {
    let mut best = 0;
    let mut best_len = -1.0;
    let mut best_key = u64::MAX;
    for k in 0..3 {
        let (a, b) = (t[k], t[(k + 1) % 3]);
        let l = pos[a as usize].distance_squared(pos[b as usize]);
        let key = edge_key(a, b);
        if l > best_len || (l == best_len && key < best_key) {
            best = k;
            best_len = l;
            best_key = key;
        }
    }
    best
}

/// Removes the items of `v` at the indices `gone` (ascending), keeping the rest in order.
fn remove_at<T>(v: &mut Vec<T>, gone: impl Iterator<Item = usize>) {
    let mut gone = gone.peekable();
    let mut i = 0;
    v.retain(|_| {
        let drop = gone.next_if_eq(&i).is_some();
        i += 1;
        !drop
    });
}

/// Conforming longest-edge refinement (Rivara's 4-triangle longest-edge partition), in
/// rounds: every face whose longest edge exceeds `s` marks that edge; then, until nothing
/// changes, every face with a marked edge also marks its longest edge (conformity closure).
/// Each marked face is bisected at the midpoint `M` of its longest edge, and `M` is joined to
/// the midpoints of its other marked edges (2, 3 or 4 children). Shared edges get one
/// midpoint, so the mesh stays conforming; the partition keeps angles bounded away from zero
/// (no slivers from repeated closure). Returns `Err(cap)` when the vertex count passes the cap.
#[allow(clippy::type_complexity)]
fn split_edges(
    (mut pos, mut home): (Vec<DVec3>, Vec<u64>),
    mut tris: Vec<[u32; 3]>,
    mut src: Vec<u32>,
    s: f64,
    cap: Option<usize>,
    region: RegionOf<'_>,
) -> Result<((Vec<DVec3>, Vec<u64>), Vec<[u32; 3]>, Vec<u32>), usize> {
    let inside = |pos: &[DVec3], t: &[u32; 3], src: u32| meets_region(region, pos, t, src);
    let s2 = s * s;
    if let Some(c) = cap
        && pos.len() > c
    {
        return Err(c);
    }
    // A face whose longest edge is ≤ s is final: only edges longer than s are ever split.
    // Only the others (`active`) are revisited. Faces outside the region with an edge longer
    // than s (`dormant`): split only when a neighbour's split reaches them (to stay
    // conforming), else final once nothing is active.
    let long = |pos: &[DVec3], t: &[u32; 3]| {
        let k = longest_edge(pos, t);
        (pos[t[k] as usize].distance_squared(pos[t[(k + 1) % 3] as usize]) > s2).then_some(k)
    };
    // Splits a round's faces (the first round's are the remesh's: hundreds of thousands,
    // nearly all final) in parallel: the final ones kept in order, in place, and the long
    // ones `(face, source, longest edge, inside the region)` taken out in order.
    let classify = |mut tris: Vec<[u32; 3]>, mut src: Vec<u32>, pos: &[DVec3]| {
        let out: Vec<(usize, usize, bool)> = tris
            .par_iter()
            .zip(&src)
            .enumerate()
            .filter_map(|(i, (t, &sidx))| long(pos, t).map(|k| (i, k, inside(pos, t, sidx))))
            .collect();
        let taken: Vec<([u32; 3], u32, usize, bool)> = out
            .iter()
            .map(|&(i, k, ins)| (tris[i], src[i], k, ins))
            .collect();
        remove_at(&mut tris, out.iter().map(|f| f.0));
        remove_at(&mut src, out.iter().map(|f| f.0));
        (tris, src, taken)
    };
    let (mut done, mut done_src) = (Vec::new(), Vec::new());
    let mut dormant: Vec<([u32; 3], u32, usize)> = Vec::new();
    loop {
        let (fin, fin_src, taken) = classify(tris, src, &pos);
        if done.is_empty() {
            (done, done_src) = (fin, fin_src);
        } else {
            done.extend(fin);
            done_src.extend(fin_src);
        }
        let (mut active, mut active_src, mut longest) = (Vec::new(), Vec::new(), Vec::new());
        for (t, sidx, k, ins) in taken {
            if ins {
                active.push(t);
                active_src.push(sidx);
                longest.push(k);
            } else {
                dormant.push((t, sidx, k));
            }
        }
        if active.is_empty() {
            for (t, sidx, _) in dormant {
                done.push(t);
                done_src.push(sidx);
            }
            return Ok(((pos, home), done, done_src));
        }
        let mut marked: IntMap<u64, u32> = IntMap::default();
        for (t, &k) in active.iter().zip(&longest) {
            marked.insert(edge_key(t[k], t[(k + 1) % 3]), u32::MAX);
        }
        // Dormant faces reached by a marked edge join this round (and mark their longest).
        loop {
            let mut woke = false;
            let mut still = Vec::with_capacity(dormant.len());
            for (t, sidx, k) in dormant.drain(..) {
                if (0..3).any(|j| marked.contains_key(&edge_key(t[j], t[(j + 1) % 3]))) {
                    marked.insert(edge_key(t[k], t[(k + 1) % 3]), u32::MAX);
                    active.push(t);
                    active_src.push(sidx);
                    longest.push(k);
                    woke = true;
                } else {
                    still.push((t, sidx, k));
                }
            }
            dormant = still;
            if !woke {
                break;
            }
        }
        // Closure: a face with any marked edge marks its longest one. (A marked edge is
        // longer than s, so a face holding it has a longest edge longer than s and marked
        // itself: this loop only guards the invariant.)
        loop {
            let mut changed = false;
            for (t, &k) in active.iter().zip(&longest) {
                let lk = edge_key(t[k], t[(k + 1) % 3]);
                if marked.contains_key(&lk) {
                    continue;
                }
                if (0..3).any(|j| marked.contains_key(&edge_key(t[j], t[(j + 1) % 3]))) {
                    marked.insert(lk, u32::MAX);
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
        // Midpoints, numbered in face order for determinism.
        for (t, &sidx) in active.iter().zip(&active_src) {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if let Some(m) = marked.get_mut(&edge_key(a, b))
                    && *m == u32::MAX
                {
                    pos.push(0.5 * (pos[a as usize] + pos[b as usize]));
                    home.push(midpoint_home(&home, a, b, sidx));
                    *m = (pos.len() - 1) as u32;
                }
            }
            if let Some(c) = cap
                && pos.len() > c
            {
                return Err(c);
            }
        }
        let mut nt = Vec::with_capacity(active.len() * 3);
        let mut ns = Vec::with_capacity(active.len() * 3);
        for ((t, &k), &sidx) in active.iter().zip(&longest).zip(&active_src) {
            let before = nt.len();
            let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            let m = marked.get(&edge_key(a, b)).copied().unwrap_or(u32::MAX);
            // Child (a, m, c), split again at a marked c–a.
            match marked.get(&edge_key(c, a)) {
                Some(&p) => nt.extend([[a, m, p], [m, c, p]]),
                None => nt.push([a, m, c]),
            }
            // Child (m, b, c), split again at a marked b–c.
            match marked.get(&edge_key(b, c)) {
                Some(&q) => nt.extend([[m, b, q], [m, q, c]]),
                None => nt.push([m, b, c]),
            }
            ns.extend(std::iter::repeat_n(sidx, nt.len() - before));
        }
        tris = nt;
        src = ns;
    }
}

/// Design face `d`'s angle at vertex `v` (see [`vertex_normals`]): its corner's angle
/// where `v` is one of its corners, else π (a point of one of its edges).
fn design_angle(design: &[[u32; 3]], pos: &[DVec3], d: u32, v: u32) -> f64 {
    let t = design[d as usize];
    match t.iter().position(|&x| x == v) {
        Some(j) => corner_angle(
            pos[t[j] as usize],
            pos[t[(j + 1) % 3] as usize],
            pos[t[(j + 2) % 3] as usize],
        ),
        None => std::f64::consts::PI,
    }
}

/// [`vertex_normals`] from the vertices' homes, one normal per vertex: a point inside a
/// design face takes the face's normal; one on the design's edges or corners the normal of
/// its design faces (ascending) if they all have one, else their sum weighted by their
/// angles there, normalised. `None` where that is not what the passes over the refined
/// faces give: two of the faces farther apart than the crease angle (`cos_crease`, the
/// same products the passes compare), a sum without a length, or a home without a face.
fn normals_by_home(
    design: &[[u32; 3]],
    design_n: &[DVec3],
    pos: &[DVec3],
    home: &[u64],
    cos_crease: f64,
) -> Option<Vec<DVec3>> {
    // Design vertices numbered below 2^31: an edge's key keeps its top bit clear.
    if home.len() != pos.len() || pos.len() > 1 << 31 {
        return None;
    }
    // The design faces at each design corner (ascending), and each design edge's.
    let nd = design
        .iter()
        .flatten()
        .map(|&v| v as usize + 1)
        .max()
        .unwrap_or(0);
    let mut start = vec![0u32; nd + 1];
    for &v in design.iter().flatten() {
        start[v as usize + 1] += 1;
    }
    for i in 0..nd {
        start[i + 1] += start[i];
    }
    let mut at = start.clone();
    let mut around = vec![0u32; start[nd] as usize];
    for (d, t) in design.iter().enumerate() {
        for &v in t {
            around[at[v as usize] as usize] = d as u32;
            at[v as usize] += 1;
        }
    }
    drop(at);
    let mut edges: Vec<(u64, u32)> = design
        .iter()
        .enumerate()
        .flat_map(|(d, t)| (0..3).map(move |k| (edge_key(t[k], t[(k + 1) % 3]), d as u32)))
        .collect();
    edges.sort_unstable();
    // The normal of vertex `v` from its design faces (ascending, each once).
    let normal = |v: usize, faces: &[u32]| -> Option<DVec3> {
        let n0 = design_n[*faces.first()? as usize];
        let dn = |d: u32| design_n[d as usize];
        if faces.iter().all(|&d| dn(d) == n0) {
            return Some(n0);
        }
        // Each corner's sum takes the faces within the crease angle of its own (the same
        // products): here every face for every corner, so one sum.
        if !faces
            .iter()
            .all(|&a| faces.iter().all(|&b| dn(b).dot(dn(a)) >= cos_crease))
        {
            return None;
        }
        let mut sum = DVec3::ZERO;
        for &d in faces {
            sum += design_angle(design, pos, d, v as u32) * dn(d);
        }
        sum.try_normalize()
    };
    // `last`: the previous edge key looked up on this worker and its range in `edges`: an
    // edge's points are numbered one after another, so most lookups repeat the last one (a
    // search per point cost sphere_on_plate's ball program some 50 k binary searches).
    let at = |(faces, last): &mut (Vec<u32>, Option<(u64, usize, usize)>),
              v: usize,
              h: u64|
     -> Option<DVec3> {
        faces.clear();
        match h {
            HOME_CORNER => {
                let (a, b) = (*start.get(v)? as usize, *start.get(v + 1)? as usize);
                faces.extend_from_slice(&around[a..b]);
            }
            h if h & HOME_FACE != 0 => {
                return design_n.get((h & !HOME_FACE) as usize).copied();
            }
            key => {
                let (lo, hi) = match *last {
                    Some((k, lo, hi)) if k == key => (lo, hi),
                    _ => {
                        let lo = edges.partition_point(|e| e.0 < key);
                        let hi = lo + edges[lo..].partition_point(|e| e.0 == key);
                        *last = Some((key, lo, hi));
                        (lo, hi)
                    }
                };
                faces.extend(edges[lo..hi].iter().map(|e| e.1));
            }
        }
        // A degenerate face lists a corner or an edge twice: each face counts once.
        faces.dedup();
        normal(v, faces)
    };
    // Collected as the vertices' own array (a collect of options lists pieces and copies
    // them), a vertex without its normal flagged.
    let failed = std::sync::atomic::AtomicBool::new(false);
    let normals: Vec<DVec3> = home
        .par_iter()
        .enumerate()
        .map_init(
            || (Vec::new(), None),
            |state, (v, &h)| {
                at(state, v, h).unwrap_or_else(|| {
                    failed.store(true, std::sync::atomic::Ordering::Relaxed);
                    DVec3::NAN
                })
            },
        )
        .collect();
    (!failed.into_inner()).then_some(normals)
}

fn corner_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (u, v) = (b - a, c - a);
    u.cross(v).length().atan2(u.dot(v))
}

/// At or below this cosine of the crease angle, two faces within 178° of each other always
/// average: `cos 178° ≈ −0.99939`, with room for rounding.
const ALL_FACES_COS: f64 = -0.9995;

/// `cos 89°`: faces within 89° of a vertex's first face lie within 178° of each other.
const HEMISPHERE_COS: f64 = 0.017_452_406_437_283_5;

/// Vertex normals by smooth groups; duplicates vertices on creases.
///
/// Most vertices lie inside one design face (a remeshed face's lattice, a bisection's
/// midpoint): every face around them has that face's normal, which is theirs. Only the
/// vertices whose faces come from several design faces (on the design's edges and corners)
/// are averaged, over the design faces around them. A design face's weight is its angle at
/// the vertex, which its refined faces there divide among them: its corner's angle where the
/// vertex is one of its corners (`design`: the design faces' corners, numbered as the first
/// points of `pos`), else π (a point of one of its edges). The same sum as over the refined
/// corners' angles, but for their rounding.
///
/// With the vertices' homes ([`HOME_CORNER`]) the design faces around each vertex come from
/// the design's own corners and edges, not from passes over the refined faces (those that
/// list each vertex's corners, over some 800 k of them, took sphere_on_plate's ball program
/// 6.8–9.1 ms on one thread, by temporary timers): where every vertex then has one normal
/// (creases of 178.2° or more averaged, no pair of faces around a vertex farther apart than
/// that, every sum of a length to normalise), as with every crease the verifier averages,
/// those normals are the ones the passes give, bit for bit; else the passes decide.
fn vertex_normals(
    mesh: &Mesh,
    design: &[[u32; 3]],
    pos: Vec<DVec3>,
    tris: Vec<[u32; 3]>,
    src: &[u32],
    crease_deg: f64,
    home: Option<&[u64]>,
) -> (Vec<DVec3>, Vec<DVec3>, Vec<[u32; 3]>) {
    let cos_crease = crease_deg.to_radians().cos();
    let design_n: Vec<DVec3> = mesh
        .triangles()
        .par_iter()
        .map(|t| t.normal().unwrap_or(DVec3::Z))
        .collect();
    if cos_crease <= ALL_FACES_COS
        && let Some(home) = home
        && let Some(normals) = normals_by_home(design, &design_n, &pos, home, cos_crease)
    {
        return (pos, normals, tris);
    }
    let face_n = |f: u32| design_n[src[f as usize] as usize];
    // Per vertex: the one design face its faces lie in, `MIXED` where they lie in several,
    // `UNUSED` where no face uses it.
    const UNUSED: u32 = u32::MAX;
    const MIXED: u32 = u32::MAX - 1;
    let mut state = vec![UNUSED; pos.len()];
    for (t, &s) in tris.iter().zip(src) {
        for &v in t {
            let st = &mut state[v as usize];
            if *st == UNUSED {
                *st = s;
            } else if *st != s {
                *st = MIXED;
            }
        }
    }
    // The mixed vertices (numbered in vertex order) and their corners (face, k) in CSR
    // form, in face order.
    let mut index = vec![u32::MAX; pos.len()];
    let mut mixed: Vec<u32> = Vec::new();
    for (v, &st) in state.iter().enumerate() {
        if st == MIXED {
            index[v] = mixed.len() as u32;
            mixed.push(v as u32);
        }
    }
    let mut start = vec![0u32; mixed.len() + 1];
    for t in &tris {
        for &v in t {
            if state[v as usize] == MIXED {
                start[index[v as usize] as usize + 1] += 1;
            }
        }
    }
    for i in 0..mixed.len() {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut corners = vec![(0u32, 0u8); start[mixed.len()] as usize];
    for (f, t) in tris.iter().enumerate() {
        for (k, &v) in t.iter().enumerate() {
            if state[v as usize] == MIXED {
                let m = index[v as usize] as usize;
                corners[fill[m] as usize] = (f as u32, k as u8);
                fill[m] += 1;
            }
        }
    }
    drop(fill);
    // Design face `d`'s angle at vertex `v` (see above).
    let angle = |d: u32, v: u32| design_angle(design, &pos, d, v);
    // Per mixed vertex, in parallel over blocks of them: its distinct normals in the order
    // of its corners (`normals`, `count` per vertex) and each corner's index among them
    // (`slot`, aligned with `corners`). The same as one pass over the vertices in order.
    const BLOCK: usize = 1024;
    let mut slot = vec![0u32; corners.len()];
    let mut slices = Vec::new();
    let mut rest = slot.as_mut_slice();
    for b in (0..mixed.len()).step_by(BLOCK) {
        let e = (b + BLOCK).min(mixed.len());
        let (head, tail) = rest.split_at_mut((start[e] - start[b]) as usize);
        slices.push((b, e, head));
        rest = tail;
    }
    let blocks: Vec<(Vec<DVec3>, Vec<u32>)> = slices
        .into_par_iter()
        // One block per piece: the work lies on the design's edges, unevenly.
        .with_max_len(1)
        .map(|(b, e, slot)| {
            let (mut normals, mut count) = (Vec::new(), Vec::with_capacity(e - b));
            // The design faces around a vertex (ascending) and their angles there.
            let mut faces: Vec<u32> = Vec::new();
            let mut angles: Vec<f64> = Vec::new();
            let base = start[b] as usize;
            for m in b..e {
                let (c0, c1) = (start[m] as usize, start[m + 1] as usize);
                let cs = &corners[c0..c1];
                let slot = &mut slot[c0 - base..c1 - base];
                let first = normals.len();
                // Design faces apart, but of one normal (coplanar): the lowest-numbered
                // face's (normals that compare equal may differ in a zero's sign).
                let n0 = face_n(cs[0].0);
                if cs.iter().all(|&(f, _)| face_n(f) == n0) {
                    let first = cs.iter().map(|&(f, _)| src[f as usize]).min();
                    normals.push(first.map_or(n0, |d| design_n[d as usize]));
                    count.push(1);
                    slot.fill(0);
                    continue;
                }
                // Summed by design face in ascending order, whatever order the faces
                // around the vertex are listed in (a region leaving out points far from
                // it lists others): the same bits.
                faces.clear();
                faces.extend(cs.iter().map(|&(f, _)| src[f as usize]));
                faces.sort_unstable();
                faces.dedup();
                angles.clear();
                angles.extend(faces.iter().map(|&d| angle(d, mixed[m])));
                let dn = |d: u32| design_n[d as usize];
                // Averaging across every crease (180°, as the verifier does) and every face
                // within 89° of the first, so any two within 178°: every corner's sum takes
                // every face, in the same order, and is the same. Summed once.
                if cos_crease <= ALL_FACES_COS
                    && faces.iter().all(|&d| dn(d).dot(n0) >= HEMISPHERE_COS)
                {
                    let mut sum = DVec3::ZERO;
                    for (&d, &a) in faces.iter().zip(&angles) {
                        sum += a * dn(d);
                    }
                    normals.push(sum.try_normalize().unwrap_or(n0));
                    count.push(1);
                    slot.fill(0);
                    continue;
                }
                for (i, &(f, _)) in cs.iter().enumerate() {
                    let nf = face_n(f);
                    let mut sum = DVec3::ZERO;
                    for (&d, &a) in faces.iter().zip(&angles) {
                        let ng = dn(d);
                        if ng.dot(nf) >= cos_crease {
                            sum += a * ng;
                        }
                    }
                    let n = sum.try_normalize().unwrap_or(nf);
                    slot[i] = match normals[first..].iter().position(|&m| m == n) {
                        Some(j) => j as u32,
                        None => {
                            normals.push(n);
                            (normals.len() - 1 - first) as u32
                        }
                    };
                }
                count.push((normals.len() - first) as u32);
            }
            (normals, count)
        })
        .collect();
    let mut mixed_n = Vec::with_capacity(mixed.len());
    let mut mixed_count = Vec::with_capacity(mixed.len());
    for (n, c) in blocks {
        mixed_n.extend(n);
        mixed_count.extend(c);
    }
    // One normal per vertex (always so without creases, e.g. at 180°, and with every vertex
    // used): the vertices and faces stay as they are.
    if !state.contains(&UNUSED) && mixed_count.iter().all(|&c| c == 1) {
        let normals = state
            .par_iter()
            .zip(&index)
            .map(|(&st, &m)| match st {
                MIXED => mixed_n[m as usize],
                s => design_n[s as usize],
            })
            .collect();
        return (pos, normals, tris);
    }
    // Each vertex as many times as it has normals (none where unused), in order; each
    // corner to its copy.
    let mut base = Vec::with_capacity(pos.len());
    let mut out_pos = Vec::with_capacity(pos.len());
    let mut out_n = Vec::with_capacity(pos.len());
    let mut next_n = 0usize;
    for (v, &st) in state.iter().enumerate() {
        base.push(out_pos.len() as u32);
        match st {
            UNUSED => {}
            MIXED => {
                let c = mixed_count[index[v] as usize] as usize;
                out_pos.extend(std::iter::repeat_n(pos[v], c));
                out_n.extend_from_slice(&mixed_n[next_n..next_n + c]);
                next_n += c;
            }
            s => {
                out_pos.push(pos[v]);
                out_n.push(design_n[s as usize]);
            }
        }
    }
    let mut out_tris: Vec<[u32; 3]> = tris.iter().map(|t| t.map(|v| base[v as usize])).collect();
    for (m, &v) in mixed.iter().enumerate() {
        for ci in start[m] as usize..start[m + 1] as usize {
            let (f, k) = corners[ci];
            out_tris[f as usize][k as usize] = base[v as usize] + slot[ci];
        }
    }
    (out_pos, out_n, out_tris)
}

#[cfg(test)]
mod tests {
    use super::*;
    use cam_core::Triangle;

    fn mesh(t: Vec<Triangle>) -> Mesh {
        Mesh::from_triangles(t, "<memory>").expect("mesh")
    }

    /// A tetrahedron with outward faces.
    fn tetra() -> Vec<Triangle> {
        let (a, b, c, d) = (DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z);
        vec![
            Triangle::new(a, c, b),
            Triangle::new(a, b, d),
            Triangle::new(b, c, d),
            Triangle::new(c, a, d),
        ]
    }

    #[test]
    fn topology_counts_rims_flips_and_fins() {
        assert!(topology(&mesh(tetra())).is_closed_and_oriented());
        // One face flipped: its three edges each join two faces running the same way.
        let mut t = tetra();
        t[2] = Triangle::new(t[2].v[0], t[2].v[2], t[2].v[1]);
        let topo = topology(&mesh(t));
        assert_eq!(
            (
                topo.boundary_edges,
                topo.non_manifold_edges,
                topo.misoriented_edges
            ),
            (0, 0, 3)
        );
        // One face removed: its three edges are the rim.
        let topo = topology(&mesh(tetra()[..3].to_vec()));
        assert_eq!(
            (
                topo.boundary_edges,
                topo.non_manifold_edges,
                topo.misoriented_edges
            ),
            (3, 0, 0)
        );
        // A fin on edge a-b: that edge has three faces, the fin's other two edges are rims.
        let mut t = tetra();
        t.push(Triangle::new(
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(0.5, -1.0, 0.0),
        ));
        let topo = topology(&mesh(t));
        assert_eq!(
            (
                topo.boundary_edges,
                topo.non_manifold_edges,
                topo.misoriented_edges
            ),
            (2, 1, 0)
        );
    }

    #[test]
    fn rim_vertices_are_those_on_one_face_edges() {
        let mesh_of = |triangles: Vec<[u32; 3]>, n: usize| RefinedMesh {
            positions: vec![DVec3::ZERO; n],
            normals: vec![DVec3::Z; n],
            face_source: vec![0; triangles.len()],
            triangles,
            max_edge_mm: 1.0,
        };
        // A fan of three faces about vertex 0 (closed around it): 0 is inside, 1..=3 rim.
        let fan = mesh_of(vec![[0, 1, 2], [0, 2, 3], [0, 3, 1]], 4);
        assert_eq!(rim_vertices(&fan), vec![false, true, true, true]);
        // Closed tetrahedron: no rim.
        let tet = mesh_of(vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]], 4);
        assert_eq!(rim_vertices(&tet), vec![false; 4]);
    }

    /// On refined open meshes the rim found near the design's rim alone is the rim found
    /// over every face: a wavy grid with holes (square and triangular), a missing corner and
    /// a fin folded on a shared edge (non-manifold), refined as the verifier refines it
    /// (remeshed, crease 180°).
    #[test]
    fn rim_near_the_design_rim_is_the_whole_rim() {
        let z = |x: f64, y: f64| 0.3 * (0.7 * x).sin() * (0.5 * y).cos();
        let p = |i: usize, j: usize| {
            let (x, y) = (i as f64 * 1.3, j as f64 * 1.1);
            DVec3::new(x, y, z(x, y))
        };
        let mut tris = Vec::new();
        for i in 0..8 {
            for j in 0..7 {
                // Holes: one cell, one half cell, and the last corner cell.
                if (i, j) == (3, 3) || (i, j) == (7, 6) {
                    continue;
                }
                tris.push(Triangle::new(p(i, j), p(i + 1, j), p(i + 1, j + 1)));
                if (i, j) != (5, 1) {
                    tris.push(Triangle::new(p(i, j), p(i + 1, j + 1), p(i, j + 1)));
                }
            }
        }
        // A fin on the edge p(1,1)–p(2,1): a third face there.
        tris.push(Triangle::new(
            p(1, 1),
            p(2, 1),
            p(1, 1) + DVec3::new(0.6, 0.0, 1.5),
        ));
        let design = mesh(tris);
        for s in [0.35, 0.8] {
            let cfg = RefineConfig {
                max_edge_mm: s,
                crease_angle_deg: 180.0,
                max_vertices: None,
                on_cap: CapPolicy::Error,
                region: None,
                remesh: true,
            };
            let refined = refine(&design, &cfg).unwrap();
            let whole = rim_vertices(&refined);
            let rim = design_topology(&design).2.expect("an open design");
            let near = rim_vertices_near(&refined, &rim);
            assert!(whole.iter().filter(|&&r| r).count() > 40);
            assert_eq!(near, whole, "at s = {s}");
        }
    }

    /// A vertex no face uses is left out, and the faces keep their corners' positions and
    /// normals (a crease between them, so that vertices are duplicated too).
    #[test]
    fn vertex_normals_leave_out_unused_vertices() {
        let g = DVec3::new(40.0, 0.0, 0.0);
        let tris = vec![
            Triangle::new(g, g + DVec3::X, g + DVec3::Y),
            Triangle::new(g, g + DVec3::Z, g + DVec3::X),
        ];
        let m = mesh(tris);
        let (pos, faces) = weld(&m);
        // An unused point first: every index moves up by one.
        let mut with = vec![DVec3::splat(7.0)];
        with.extend(&pos);
        let shifted: Vec<[u32; 3]> = faces.iter().map(|t| t.map(|v| v + 1)).collect();
        let src = [0u32, 1];
        for deg in [180.0, 30.0] {
            let (p0, n0, t0) =
                vertex_normals(&m, &faces, pos.clone(), faces.clone(), &src, deg, None);
            let (p1, n1, t1) =
                vertex_normals(&m, &shifted, with.clone(), shifted.clone(), &src, deg, None);
            assert_eq!((p0.len(), n0.len()), (p1.len(), n1.len()), "{deg}°");
            assert!(!p1.contains(&DVec3::splat(7.0)), "{deg}°");
            for (a, b) in t0.iter().zip(&t1) {
                for k in 0..3 {
                    let (i, j) = (a[k] as usize, b[k] as usize);
                    assert_eq!((p0[i], n0[i]), (p1[j], n1[j]), "{deg}°");
                }
            }
        }
        // At 30° the fold's two vertices on the crease are duplicated: 4 + 2.
        let (p, _, _) = vertex_normals(&m, &shifted, with, shifted.clone(), &src, 30.0, None);
        assert_eq!(p.len(), 6);
    }

    /// The normals from the vertices' homes are the passes' normals, bit for bit, with the
    /// same points and faces, after the remesh and after the bisection alone (whose
    /// midpoints fall on design edges, on the edges' points and inside faces): on
    /// [`normals_design`] (gentle creases, folds of 90°, 60° and 179.9°), two faces of one
    /// plane whose normals differ in a zero's sign, a closed box, an open plate (a rim) and
    /// a tetrahedron. At 180° they serve every mesh; at 179.85° not the design,
    /// whose fin folds further than that.
    #[test]
    fn normals_from_homes_are_the_passes_normals() {
        let bits = |n: &[DVec3]| -> Vec<[u64; 3]> {
            n.iter().map(|v| v.to_array().map(f64::to_bits)).collect()
        };
        let (o, e) = (DVec3::new(5.0, 5.0, 5.0), 2.0);
        let c = |x: f64, y: f64, z: f64| o + e * DVec3::new(x, y, z);
        let quad = |a: DVec3, b: DVec3, cc: DVec3, d: DVec3| {
            [Triangle::new(a, b, cc), Triangle::new(a, cc, d)]
        };
        let mut boxed = Vec::new();
        for q in [
            quad(c(0., 0., 0.), c(0., 1., 0.), c(1., 1., 0.), c(1., 0., 0.)),
            quad(c(0., 0., 1.), c(1., 0., 1.), c(1., 1., 1.), c(0., 1., 1.)),
            quad(c(0., 0., 0.), c(1., 0., 0.), c(1., 0., 1.), c(0., 0., 1.)),
            quad(c(0., 1., 0.), c(0., 1., 1.), c(1., 1., 1.), c(1., 1., 0.)),
            quad(c(0., 0., 0.), c(0., 0., 1.), c(0., 1., 1.), c(0., 1., 0.)),
            quad(c(1., 0., 0.), c(1., 1., 0.), c(1., 1., 1.), c(1., 0., 1.)),
        ] {
            boxed.extend(q);
        }
        let plate = quad(c(0., 0., 0.), c(1.5, 0., 0.), c(1.5, 1., 0.), c(0., 1., 0.)).to_vec();
        // Two faces of one plane whose normals compare equal but differ in a zero's sign:
        // the points between them take the first face's.
        let (p, q, r, t) = (
            DVec3::new(3.0, 0.0, 0.0),
            DVec3::new(3.0, 0.0, 2.0),
            DVec3::ZERO,
            DVec3::new(0.0, 0.0, 2.0),
        );
        let wall = vec![Triangle::new(p, q, r), Triangle::new(q, t, r)];
        let wn = wall.iter().map(|t| t.normal().unwrap()).collect::<Vec<_>>();
        assert!(wn[0] == wn[1] && bits(&wn[..1]) != bits(&wn[1..]), "{wn:?}");
        let mut served = 0;
        for (name, tris) in [
            ("wall", wall),
            ("design", normals_design()),
            ("box", boxed),
            ("plate", plate),
            ("tetra", tetra()),
        ] {
            let m = mesh(tris);
            let (wp, wt) = weld(&m);
            let design_n: Vec<DVec3> = m
                .triangles()
                .iter()
                .map(|t| t.normal().unwrap_or(DVec3::Z))
                .collect();
            for remeshed in [true, false] {
                for s in [0.3, 0.7] {
                    let (pos, tris, src, home) = if remeshed {
                        let r = crate::remesh::remesh(&wp, &wt, s, None, None).unwrap();
                        (r.pos, r.tris, r.src, r.home)
                    } else {
                        let src = (0..wt.len() as u32).collect();
                        (wp.clone(), wt.clone(), src, vec![HOME_CORNER; wp.len()])
                    };
                    let ((pos, home), tris, src) =
                        split_edges((pos, home), tris, src, s, None, None).unwrap();
                    for deg in [180.0f64, 179.85, 150.0] {
                        let at = format!("{name}, remesh {remeshed}, s {s}, {deg}°");
                        let cos = deg.to_radians().cos();
                        let fast = normals_by_home(&wt, &design_n, &pos, &home, cos);
                        let (p1, n1, t1) =
                            vertex_normals(&m, &wt, pos.clone(), tris.clone(), &src, deg, None);
                        let (p2, n2, t2) = vertex_normals(
                            &m,
                            &wt,
                            pos.clone(),
                            tris.clone(),
                            &src,
                            deg,
                            Some(&home),
                        );
                        assert_eq!((&p1, &t1), (&p2, &t2), "{at}");
                        assert_eq!(bits(&n1), bits(&n2), "{at}");
                        if let Some(n) = &fast {
                            assert_eq!((&p1, &t1), (&pos, &tris), "{at}");
                            assert_eq!(bits(n), bits(&n1), "{at}");
                            served += 1;
                        }
                        match (name, deg) {
                            (_, 180.0) => assert!(fast.is_some(), "{at}"),
                            ("design", 179.85) => assert!(fast.is_none(), "{at}"),
                            _ => {}
                        }
                    }
                }
            }
        }
        assert!(served >= 40, "served {served}");
    }

    /// A faceted dome (gentle creases), a box corner (90° folds), a fin whose faces fold
    /// back 179.9° and a ridge (60°), apart.
    fn normals_design() -> Vec<Triangle> {
        let mut tris = Vec::new();
        // A faceted dome: 8 × 4 quads on a sphere of radius 10.
        let at = |i: usize, j: usize| {
            let (ph, th) = (
                std::f64::consts::TAU * i as f64 / 8.0,
                0.6 * j as f64 / 4.0 + 0.3,
            );
            DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()) * 10.0
        };
        for i in 0..8 {
            for j in 0..3 {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                tris.push(Triangle::new(a, c, b));
                tris.push(Triangle::new(a, d, c));
            }
        }
        // A box corner at (20, 0, 0) and a fin folded back on itself at (30, 0, 0).
        let o = DVec3::new(20.0, 0.0, 0.0);
        tris.push(Triangle::new(o, o + DVec3::X, o + DVec3::Y));
        tris.push(Triangle::new(o, o + DVec3::Z, o + DVec3::X));
        tris.push(Triangle::new(o, o + DVec3::Y, o + DVec3::Z));
        let f = DVec3::new(30.0, 0.0, 0.0);
        tris.push(Triangle::new(f, f + DVec3::X, f + DVec3::Y));
        let (sn, cs) = 0.1f64.to_radians().sin_cos();
        tris.push(Triangle::new(f, f + DVec3::new(0.3, cs, sn), f + DVec3::X));
        // A ridge at (40, 0, 0) whose faces' normals lie 60° apart.
        let g = DVec3::new(40.0, 0.0, 0.0);
        let (s30, c30) = 30f64.to_radians().sin_cos();
        tris.push(Triangle::new(
            g,
            g + DVec3::X,
            g + DVec3::new(0.0, c30, -s30),
        ));
        tris.push(Triangle::new(
            g,
            g + DVec3::new(0.0, -c30, -s30),
            g + DVec3::X,
        ));
        tris
    }

    /// The vertex normals against the definition, corner by corner: each corner's normal is
    /// the angle-weighted sum of the normals of the vertex's faces within the crease angle
    /// of its own face, in face order, normalised (their one normal where they share it).
    /// Across every crease (180°, where one sum serves every corner of a vertex whose faces
    /// lie within 89° of the first), and at 179.85° (the fin's fold, where the one sum must
    /// not be used) and 30°, on [`normals_design`].
    #[test]
    fn vertex_normals_equal_the_corner_by_corner_definition() {
        let m = mesh(normals_design());
        let (pos, faces) = weld(&m);
        let src: Vec<u32> = (0..faces.len() as u32).collect();
        let fn_: Vec<DVec3> = m
            .triangles()
            .iter()
            .map(|t| t.normal().unwrap_or(DVec3::Z))
            .collect();
        for deg in [180.0f64, 179.85, 30.0] {
            let cos = deg.to_radians().cos();
            let (out_pos, out_n, out_tris) =
                vertex_normals(&m, &faces, pos.clone(), faces.clone(), &src, deg, None);
            for (fi, t) in faces.iter().enumerate() {
                for k in 0..3 {
                    let v = t[k];
                    let mut sum = DVec3::ZERO;
                    for (gi, u) in faces.iter().enumerate() {
                        if let Some(j) = u.iter().position(|&x| x == v)
                            && fn_[gi].dot(fn_[fi]) >= cos
                        {
                            let p = |x: u32| pos[x as usize];
                            sum += corner_angle(p(u[j]), p(u[(j + 1) % 3]), p(u[(j + 2) % 3]))
                                * fn_[gi];
                        }
                    }
                    // A vertex inside a smooth patch (one normal) keeps its faces' normal.
                    let mut around = faces
                        .iter()
                        .enumerate()
                        .filter(|(_, u)| u.contains(&v))
                        .map(|(gi, _)| fn_[gi]);
                    let first = around.next().expect("the vertex's own face");
                    let want = if around.all(|n| n == first) {
                        first
                    } else {
                        sum.try_normalize().unwrap_or(fn_[fi])
                    };
                    let got = out_tris[fi][k] as usize;
                    assert_eq!(
                        out_pos[got], pos[v as usize],
                        "{deg}°: face {fi} corner {k}"
                    );
                    assert_eq!(out_n[got], want, "{deg}°: face {fi} corner {k}");
                }
            }
        }
    }

    /// On a refined mesh, where design edges and corners hold points of several refined
    /// faces of each design face, every corner's normal is the sum over the refined corners
    /// around its vertex (their angles, their design faces' normals, those within the crease
    /// angle of its own face's), normalised: weighting each design face once by its angle
    /// (π along an edge, its corner's at a corner) differs from it only by rounding; on
    /// [`normals_design`], at 180° and 30°. (Along an edge every face weighs π, so only the
    /// corners' weights can tell a wrong one.)
    #[test]
    fn refined_vertex_normals_equal_the_sum_over_refined_corners() {
        let design = mesh(normals_design());
        let fn_: Vec<DVec3> = design
            .triangles()
            .iter()
            .map(|t| t.normal().unwrap_or(DVec3::Z))
            .collect();
        for deg in [180.0f64, 30.0] {
            let cfg = RefineConfig {
                max_edge_mm: 0.3,
                crease_angle_deg: deg,
                max_vertices: None,
                on_cap: CapPolicy::Error,
                region: None,
                remesh: true,
            };
            let r = refine(&design, &cfg).unwrap();
            let cos = deg.to_radians().cos();
            // The refined corners around each position (copies on creases are one point).
            let mut around: HashMap<[u64; 3], Vec<(usize, usize)>> = HashMap::new();
            for (f, t) in r.triangles.iter().enumerate() {
                for (k, &v) in t.iter().enumerate() {
                    let key = r.positions[v as usize].to_array().map(f64::to_bits);
                    around.entry(key).or_default().push((f, k));
                }
            }
            let (mut edge_points, mut checked) = (0, 0);
            for corners in around.values() {
                let srcs: Vec<u32> = corners.iter().map(|&(f, _)| r.face_source[f]).collect();
                if srcs
                    .iter()
                    .all(|&d| fn_[d as usize] == fn_[srcs[0] as usize])
                {
                    continue;
                }
                let p = r.positions[r.triangles[corners[0].0][corners[0].1] as usize];
                edge_points += usize::from(design.triangles().iter().all(|t| !t.v.contains(&p)));
                for &(f, k) in corners {
                    let nf = fn_[r.face_source[f] as usize];
                    let mut sum = DVec3::ZERO;
                    for &(g, j) in corners {
                        let ng = fn_[r.face_source[g] as usize];
                        if ng.dot(nf) >= cos {
                            let u = r.triangles[g].map(|x| r.positions[x as usize]);
                            sum += corner_angle(u[j], u[(j + 1) % 3], u[(j + 2) % 3]) * ng;
                        }
                    }
                    let want = sum.normalize();
                    let got = r.normals[r.triangles[f][k] as usize];
                    assert!(got.distance(want) < 1e-12, "{deg}°: {got} against {want}");
                    checked += 1;
                }
            }
            assert!(edge_points > 50 && checked > 500, "{edge_points} {checked}");
        }
    }
}
