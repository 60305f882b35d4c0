//! The part's smallest concave radius of curvature, robust to tessellation.
//!
//! # Method
//! For every interior edge shared by two consistently oriented triangles with outward
//! normals `n1`, `n2`, the edge is concave when the far corner of one triangle lies on the
//! outer side of the other's plane. Its dihedral (turning) angle is `θ = ∠(n1, n2)`. A
//! smooth surface of radius ρ tessellated by facets of widths `h1`, `h2` across the edge
//! (the heights of the two triangles over it) turns by `θ` over the arc between the facet
//! mid-lines, whose chord half-widths sum to `(h1 + h2)/2 = ρ·(sin(α1/2) + sin(α2/2))`, so
//!
//! `ρ_e = (h1 + h2) / (4·sin(θ/2))`.
//!
//! This is **exact** for a cylinder (fillet) tessellated with equal arc steps, whatever the
//! step count and whatever the triangulation along the axis (every triangle of such a
//! tessellation spans one strip between two ruling lines, so its height over a ruling edge is
//! the strip's chord), and within `(α1 − α2)²/32` relative for unequal steps `α1`, `α2`.
//! Edges turning by less than `flat_angle_deg` are flat (diagonals inside a strip); edges
//! turning by at least `sharp_angle_deg` are **sharp** concave edges (radius 0, no rounded
//! tool reaches them) and are listed separately.
//!
//! **Dents.** Tessellations of convex or flat regions (boolean results, slivers) contain
//! isolated folds that turn the wrong way; read alone they give tiny "concave radii". The
//! discrete mean-curvature integral `½ Σ θ_e |e|` over a region that contains a local
//! perturbation is unchanged to first order by it, so an edge is kept only if the signed
//! turning `Σ ±θ_e |e|` over the edges whose midpoints lie within
//! `max(ρ_e, neighbourhood_widths · max(h1, h2))` of it is concave on balance. A real
//! fillet or bowl passes (its neighbourhood is concave or flat); a dent in a convex surface
//! does not. Edges are tested smallest radius first, until each class has its minimum.
//!
//! Each smooth concave edge is classed by its direction: **wall** edges (within 45° of the
//! tool axis, e.g. the rounded corner of a pocket seen from above) need a cutter whose radius
//! `D/2` fits; **floor** edges (the rest, e.g. a fillet between floor and wall) need a cutter
//! whose corner radius fits.

use std::collections::HashMap;

use cam_core::Mesh;
use glam::DVec3;
use serde::Serialize;

/// Settings of [`concave_curvature`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurvatureConfig {
    /// Edges turning by less than this are flat (degrees, default 0.05).
    pub flat_angle_deg: f64,
    /// Edges turning by this much or more are sharp (degrees, default 30).
    pub sharp_angle_deg: f64,
    /// Vertices closer than this are the same vertex when welding the soup (mm, default 1e-7).
    pub weld_mm: f64,
    /// Neighbourhood of the net-concavity test, in widths of the edge's triangles (default 3):
    /// the ball around an edge has radius max(its radius estimate, this × the larger width).
    /// Zero or less turns the test off (every concave edge counts).
    pub neighbourhood_widths: f64,
}

impl Default for CurvatureConfig {
    fn default() -> Self {
        CurvatureConfig {
            flat_angle_deg: 0.05,
            sharp_angle_deg: 30.0,
            weld_mm: 1e-7,
            neighbourhood_widths: 3.0,
        }
    }
}

/// The smallest radius of one class of concave edges and where it is.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ConcaveMin {
    /// Estimated radius (mm).
    pub radius_mm: f64,
    /// Midpoint (mm) of the edge giving it.
    pub region: DVec3,
}

/// A sharp concave edge (turning by at least `sharp_angle_deg`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SharpEdge {
    /// Edge midpoint (mm).
    pub midpoint: DVec3,
    /// Turning angle (degrees).
    pub angle_deg: f64,
}

/// Concave curvature of a part.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Curvature {
    /// Smallest radius over all smooth concave edges, if any.
    pub min: Option<ConcaveMin>,
    /// Smallest radius over wall edges (within 45° of +Z): needs cutter radius D/2 ≤ it.
    pub min_wall: Option<ConcaveMin>,
    /// Smallest radius over floor edges: needs cutter corner radius ≤ it.
    pub min_floor: Option<ConcaveMin>,
    /// Sharp concave edges, in mesh order.
    pub sharp_edges: Vec<SharpEdge>,
    /// Edges skipped because they are open, non-manifold or inconsistently oriented.
    pub edges_skipped: usize,
    /// Smaller concave edges passed over because the surface around them is not concave on
    /// balance (tessellation dents), see the module docs. Counted only up to the minima found.
    pub dents_ignored: usize,
}

/// A uniform grid over the midpoints of turning edges.
struct MidGrid {
    cell: f64,
    cells: HashMap<[i64; 3], Vec<u32>>,
}

impl MidGrid {
    fn new(items: &[(DVec3, f64)], extent: f64) -> MidGrid {
        let cell = (extent / 64.0).max(1e-6);
        let mut cells: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for (i, (m, _)) in items.iter().enumerate() {
            cells.entry(Self::key(*m, cell)).or_default().push(i as u32);
        }
        MidGrid { cell, cells }
    }

    fn key(p: DVec3, cell: f64) -> [i64; 3] {
        [
            (p.x / cell).floor() as i64,
            (p.y / cell).floor() as i64,
            (p.z / cell).floor() as i64,
        ]
    }

    /// Σ signed turning × length over edges whose midpoint is within `r` of `at`.
    fn net_turning(&self, items: &[(DVec3, f64)], at: DVec3, r: f64) -> f64 {
        let k = (r / self.cell).ceil() as i64;
        let c = Self::key(at, self.cell);
        let mut ids: Vec<u32> = Vec::new();
        if (2 * k + 1).pow(3) as usize > 4 * self.cells.len() {
            ids.extend(self.cells.values().flatten().copied());
        } else {
            for i in -k..=k {
                for j in -k..=k {
                    for l in -k..=k {
                        if let Some(v) = self.cells.get(&[c[0] + i, c[1] + j, c[2] + l]) {
                            ids.extend_from_slice(v);
                        }
                    }
                }
            }
        }
        ids.sort_unstable();
        ids.iter()
            .map(|&i| items[i as usize])
            .filter(|(m, _)| m.distance(at) <= r)
            .map(|(_, t)| t)
            .sum()
    }
}

fn keep_min(slot: &mut Option<ConcaveMin>, r: f64, at: DVec3) {
    if slot.is_none_or(|m| r < m.radius_mm) {
        *slot = Some(ConcaveMin {
            radius_mm: r,
            region: at,
        });
    }
}

/// Estimates the concave curvature of `mesh` (see the module docs). Triangles must be
/// consistently oriented with outward normals (as STL requires).
pub fn concave_curvature(mesh: &Mesh, cfg: &CurvatureConfig) -> Curvature {
    let tris = mesh.triangles();
    // Weld vertices on a grid of `weld_mm`.
    let mut ids: HashMap<[i64; 3], u32> = HashMap::new();
    let mut pos: Vec<DVec3> = Vec::new();
    let mut face: Vec<[u32; 3]> = Vec::with_capacity(tris.len());
    for t in tris {
        let mut f = [0u32; 3];
        for (k, p) in t.v.iter().enumerate() {
            let key = [
                (p.x / cfg.weld_mm).round() as i64,
                (p.y / cfg.weld_mm).round() as i64,
                (p.z / cfg.weld_mm).round() as i64,
            ];
            f[k] = *ids.entry(key).or_insert_with(|| {
                pos.push(*p);
                (pos.len() - 1) as u32
            });
        }
        face.push(f);
    }
    // Directed edge -> faces.
    let mut edges: HashMap<(u32, u32), Vec<(usize, usize)>> = HashMap::new();
    for (fi, f) in face.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            if a == b {
                continue;
            }
            edges.entry((a.min(b), a.max(b))).or_default().push((fi, k));
        }
    }
    let mut keys: Vec<(u32, u32)> = edges.keys().copied().collect();
    keys.sort_unstable();
    let flat = cfg.flat_angle_deg.to_radians();
    let sharp = cfg.sharp_angle_deg.to_radians();
    let mut out = Curvature::default();
    // Every turning edge (signed: concave > 0) for the neighbourhood test, and the smooth
    // concave candidates (radius, midpoint, is_wall, neighbourhood radius).
    let mut turning: Vec<(DVec3, f64)> = Vec::new();
    let mut cands: Vec<(f64, DVec3, bool, f64)> = Vec::new();
    for key in keys {
        let list = &edges[&key];
        if list.len() != 2 {
            out.edges_skipped += 1;
            continue;
        }
        let (f1, k1) = list[0];
        let (f2, k2) = list[1];
        // Consistent orientation: the edge runs a→b in one face and b→a in the other.
        if face[f1][k1] == face[f2][k2] {
            out.edges_skipped += 1;
            continue;
        }
        let (Some(n1), Some(n2)) = (tris[f1].normal(), tris[f2].normal()) else {
            out.edges_skipped += 1;
            continue;
        };
        let a = pos[key.0 as usize];
        let b = pos[key.1 as usize];
        let c2 = pos[face[f2][(k2 + 2) % 3] as usize];
        let c1 = pos[face[f1][(k1 + 2) % 3] as usize];
        let theta = n1.cross(n2).length().atan2(n1.dot(n2));
        if theta < flat {
            continue;
        }
        let e = b - a;
        let len = e.length();
        let mid = 0.5 * (a + b);
        // Concave iff the far corner of one face is on the outer side of the other's plane.
        let concave = (c2 - a).dot(n1) > 0.0 || (c1 - a).dot(n2) > 0.0;
        turning.push((mid, if concave { theta * len } else { -theta * len }));
        if !concave {
            continue;
        }
        if theta >= sharp {
            out.sharp_edges.push(SharpEdge {
                midpoint: mid,
                angle_deg: theta.to_degrees(),
            });
            continue;
        }
        let h1 = 2.0 * tris[f1].area() / len;
        let h2 = 2.0 * tris[f2].area() / len;
        let r = (h1 + h2) / (4.0 * (0.5 * theta).sin());
        let wall = (e.z / len).abs() >= std::f64::consts::FRAC_1_SQRT_2;
        cands.push((r, mid, wall, r.max(cfg.neighbourhood_widths * h1.max(h2))));
    }
    // Smallest first; an edge counts only if the surface around it is concave on balance.
    cands.sort_by(|x, y| {
        x.0.total_cmp(&y.0)
            .then(x.1.x.total_cmp(&y.1.x))
            .then(x.1.y.total_cmp(&y.1.y))
            .then(x.1.z.total_cmp(&y.1.z))
    });
    let grid = MidGrid::new(&turning, mesh.bounds().size().max_element());
    for (r, mid, wall, rn) in cands {
        let slot_done = if wall {
            out.min_wall.is_some()
        } else {
            out.min_floor.is_some()
        };
        if slot_done {
            if out.min_wall.is_some() && out.min_floor.is_some() {
                break;
            }
            continue;
        }
        if cfg.neighbourhood_widths > 0.0 && grid.net_turning(&turning, mid, rn) <= 0.0 {
            out.dents_ignored += 1;
            continue;
        }
        keep_min(&mut out.min, r, mid);
        keep_min(
            if wall {
                &mut out.min_wall
            } else {
                &mut out.min_floor
            },
            r,
            mid,
        );
    }
    out
}
