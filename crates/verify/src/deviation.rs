//! Signed deviation of the design surface from the swept surfaces: the normal-vector method,
//! on a triangle soup (the paper's piecewise-linear surface). `cam_verify::verify` measures
//! through [`crate::measure`] instead (same conventions, the triangles generated from the
//! sweep model, crossings refined onto the exact swept volume); [`TriangleBvh`] is the
//! reference it is tested against.
//!
//! From every vertex `p` of the refined design surface (normal `n`) a vector is grown from
//! `p − L_in·n` (inside the part) to `p + L_out·n` (outside). The material left along it spans
//! from its inner start to the **lowest** (most inward) point where it enters the volume
//! swept by the tool. The signed deviation is that point's distance from `p` along `n`:
//! negative = gouge (the tool went below the design), positive = excess (material left).
//!
//! # Which crossings count
//! Swept-surface triangles are expected to be oriented with their normals pointing **out of
//! the tool's swept volume** (towards the material). A vector enters the swept volume where
//! it crosses a triangle whose normal faces against it (`dot(normal, n) < 0`); crossings with
//! `dot ≥ 0` are exits (e.g. a steep wall's vector grazing the back of a neighbouring pass's
//! sweep) and are ignored under [`Facing::AgainstVector`] (the default). [`Facing::Any`]
//! accepts both, for sweeps of unknown orientation.
//!
//! # Limits
//! A vector with no entry crossing is unmachined (`signed_mm = None`): the excess there is at
//! least `L_out`. Swept surfaces are open sheets (the tool's envelope, open towards the
//! spindle), so a vector whose inner start already lies inside the swept volume (a gouge
//! deeper than `L_in`) may cross nothing and also read as unmachined: choose `L_in` larger
//! than any gouge worth telling apart (default 1 mm, or 20 × the tolerance).

use cam_core::{DVec3, Triangle};
use rayon::prelude::*;

use crate::refine::RefinedMesh;

/// Which swept-surface crossings count as entries into the swept volume.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Facing {
    /// Only triangles whose normal faces against the vector (`dot < 0`): the swept surface
    /// seen from outside the tool. Needs triangles oriented out of the swept volume.
    AgainstVector,
    /// Every crossing, whatever the triangle's orientation.
    Any,
}

/// Settings of the normal-vector method.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct DeviationConfig {
    /// How far the vector reaches inside the part, `L_in` (mm, default 1).
    pub inside_mm: f64,
    /// How far the vector reaches outside the part, `L_out` (mm, default 5).
    pub outside_mm: f64,
    /// Which crossings count (default [`Facing::AgainstVector`]).
    pub facing: Facing,
}

impl Default for DeviationConfig {
    fn default() -> Self {
        DeviationConfig {
            inside_mm: 1.0,
            outside_mm: 5.0,
            facing: Facing::AgainstVector,
        }
    }
}

impl DeviationConfig {
    /// Default lengths, but with `L_in = max(1 mm, 20 × tolerance)`.
    pub fn for_tolerance(tolerance_mm: f64) -> Self {
        DeviationConfig {
            inside_mm: (20.0 * tolerance_mm).max(1.0),
            ..Default::default()
        }
    }
}

/// The deviation measured at one vertex of the refined design surface.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Deviation {
    /// The vertex (mm).
    pub position: DVec3,
    /// Its unit normal.
    pub normal: DVec3,
    /// Signed deviation along the normal (mm): negative = gouge, positive = excess; `None`
    /// when no swept surface crosses the vector (unmachined, excess ≥ `L_out`).
    pub signed_mm: Option<f64>,
    /// Index of the toolpath move whose swept triangle gave the crossing.
    pub source_move: Option<u32>,
}

/// Why deviation could not be measured.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DeviationError {
    /// `source_move` does not give one move index per swept triangle.
    #[error("{triangles} swept triangles but {moves} move indices")]
    LengthMismatch {
        /// Number of swept triangles.
        triangles: usize,
        /// Number of move indices.
        moves: usize,
    },
    /// `L_in` or `L_out` is negative or not finite.
    #[error(
        "vector lengths must be finite and non-negative (inside {inside_mm}, outside {outside_mm})"
    )]
    BadLength {
        /// `L_in` given (mm).
        inside_mm: f64,
        /// `L_out` given (mm).
        outside_mm: f64,
    },
}

/// A bounding-volume hierarchy over triangles for segment queries.
///
/// Built by median splits on the longest axis of the centroid bounds (leaves of ≤ 4
/// triangles); deterministic. Degenerate triangles are kept but never hit.
#[derive(Debug, Clone)]
pub struct TriangleBvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    tris: Vec<Triangle>,
}

#[derive(Debug, Clone, Copy)]
struct Node {
    min: DVec3,
    max: DVec3,
    /// Leaf: first index into `order`; inner: index of the left child (right = left + 1).
    first: u32,
    /// Leaf: number of triangles (> 0); inner: 0.
    count: u32,
}

/// One crossing of a segment with a triangle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Index of the triangle (in the slice the BVH was built from).
    pub triangle: u32,
    /// Parameter along the segment: point = origin + t·dir.
    pub t: f64,
    /// Dot product of the triangle's unit normal with the (unnormalised) direction.
    pub facing: f64,
}

const LEAF: usize = 4;

impl TriangleBvh {
    /// Builds the hierarchy over `tris` (copied, in tree order for locality).
    ///
    /// Triangles are sorted by the Morton code of their centroid (ties by index, so the
    /// build is deterministic) and split at the median of that order; box bounds are
    /// computed bottom-up. One parallel sort plus one linear pass.
    pub fn new(tris: &[Triangle]) -> TriangleBvh {
        let cent: Vec<DVec3> = tris
            .par_iter()
            .map(|t| (t.v[0] + t.v[1] + t.v[2]) / 3.0)
            .collect();
        let (lo, hi) = cent.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(a, b), &c| (a.min(c), b.max(c)),
        );
        let scale = (hi - lo).max(DVec3::splat(1e-300));
        let mut keyed: Vec<(u64, u32)> = cent
            .par_iter()
            .enumerate()
            .map(|(i, &c)| {
                let q =
                    ((c - lo) / scale * 2_097_151.0).clamp(DVec3::ZERO, DVec3::splat(2_097_151.0));
                let code =
                    spread(q.x as u64) | (spread(q.y as u64) << 1) | (spread(q.z as u64) << 2);
                (code, i as u32)
            })
            .collect();
        drop(cent);
        crate::radix::sort_by_key(&mut keyed, |k| k.0);
        let order: Vec<u32> = keyed.iter().map(|&(_, i)| i).collect();
        drop(keyed);
        let sorted: Vec<Triangle> = order.par_iter().map(|&i| tris[i as usize]).collect();
        let mut nodes = Vec::with_capacity(2 * tris.len() / LEAF + 2);
        nodes.push(Node {
            min: DVec3::ZERO,
            max: DVec3::ZERO,
            first: 0,
            count: 0,
        });
        if !sorted.is_empty() {
            build(&sorted, &mut nodes, 0, 0, sorted.len());
        }
        TriangleBvh {
            nodes,
            order,
            tris: sorted,
        }
    }

    /// The box around every triangle (`min`, `max`, mm); `None` when empty.
    pub fn bounds(&self) -> Option<(DVec3, DVec3)> {
        (!self.tris.is_empty()).then(|| (self.nodes[0].min, self.nodes[0].max))
    }

    /// The triangles, in the tree's order (a [`TriangleGrid`] over them numbers them so).
    pub(crate) fn tree_triangles(&self) -> &[Triangle] {
        &self.tris
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    /// True when built from no triangles.
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// Calls `f` for every triangle crossed by the segment `origin + t·dir`, `t ∈ [t0, t1]`
    /// (in unspecified order). Barycentric tests are inclusive to 1e-12, so a segment through
    /// a shared edge reports both triangles.
    pub fn segment_hits(
        &self,
        origin: DVec3,
        dir: DVec3,
        t0: f64,
        t1: f64,
        mut f: impl FnMut(Hit),
    ) {
        if self.tris.is_empty() {
            return;
        }
        let inv = DVec3::new(1.0 / dir.x, 1.0 / dir.y, 1.0 / dir.z);
        // A median-split tree over at most 2³² triangles is at most 32 levels deep, so the
        // stack never holds more than 33 entries.
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let ni = stack[top];
            let n = self.nodes[ni as usize];
            if !slab(origin, inv, n.min, n.max, t0, t1) {
                continue;
            }
            if n.count > 0 {
                for k in n.first as usize..(n.first + n.count) as usize {
                    if let Some(h) = intersect(&self.tris[k], origin, dir, t0, t1) {
                        f(Hit {
                            triangle: self.order[k],
                            ..h
                        });
                    }
                }
            } else {
                stack[top] = n.first + 1;
                stack[top + 1] = n.first;
                top += 2;
            }
        }
    }
}

impl TriangleBvh {
    /// The distance (mm) from `p` to the nearest triangle, when some triangle is nearer
    /// than `r`; `None` otherwise. Boxes farther than the best so far are pruned.
    pub fn nearest_within(&self, p: DVec3, r: f64) -> Option<f64> {
        let mut best = r;
        self.walk_near(p, r, |t| {
            best = best.min(distance_to_triangle(p, t));
            Some(best)
        });
        (best < r).then_some(best)
    }

    /// Calls `f` on each triangle of the leaves whose boxes lie nearer to `p` than the
    /// current radius: `r` at first, then what `f` returns; `None` stops the walk. Nothing
    /// when empty or `r` is not positive.
    fn walk_near(&self, p: DVec3, r: f64, mut f: impl FnMut(&Triangle) -> Option<f64>) {
        if self.tris.is_empty() || r.is_nan() || r <= 0.0 {
            return;
        }
        let mut r = r;
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let n = self.nodes[stack[top] as usize];
            let gap = (n.min - p).max(p - n.max).max(DVec3::ZERO);
            if gap.length() >= r {
                continue;
            }
            if n.count > 0 {
                for t in &self.tris[n.first as usize..(n.first + n.count) as usize] {
                    match f(t) {
                        Some(next) => r = next,
                        None => return,
                    }
                }
            } else {
                stack[top] = n.first + 1;
                stack[top + 1] = n.first;
                top += 2;
            }
        }
    }
}

impl TriangleBvh {
    /// Whether some triangle lies nearer to `p` than `r` (mm): the answer of
    /// [`TriangleBvh::nearest_within`]`(p, r).is_some()`, by the same distance and the same
    /// boxes, stopping at the first such triangle and passing over those whose plane alone
    /// lies farther than `r` by more than rounding (the distance to a triangle is never less
    /// than to its plane). A point just under a large flat face (a gouge read a micrometre
    /// deep in a plate) meets many boxes of coplanar triangles; the plane tells each apart in
    /// a few products.
    pub fn any_within(&self, p: DVec3, r: f64) -> bool {
        let mut found = false;
        self.walk_near(p, r, |t| {
            found = nearer_than(p, t, r);
            (!found).then_some(r)
        });
        found
    }
}

/// Triangles binned in a uniform grid of cubes, each listed in every cube its box meets: for
/// [`TriangleGrid::any_within`] at radii small against a cube, where a tree's boxes answer
/// poorly on parts with large faces (each large face's box spans the tree: on
/// sphere_on_plate a query walked some 100 boxes).
pub struct TriangleGrid<'a> {
    tris: &'a [Triangle],
    /// Per triangle, its plane as [`beyond_plane`] tests it.
    planes: Vec<Plane>,
    lo: DVec3,
    inv: f64,
    dims: [usize; 3],
    /// Per cube (x fastest), where its triangles start in `items`; one more at the end.
    start: Vec<u32>,
    items: Vec<u32>,
}

/// The most cubes a [`TriangleGrid`] query looks into; beyond, it leaves the answer to the
/// caller.
const GRID_QUERY_CELLS: usize = 64;

impl<'a> TriangleGrid<'a> {
    /// The grid of `tris`: cubes the median triangle's box size (at least 1/256 of the
    /// part's box), `None` when empty or when the listing would exceed 16 entries per
    /// triangle (and a million).
    pub fn new(tris: &'a [Triangle]) -> Option<TriangleGrid<'a>> {
        let boxes: Vec<(DVec3, DVec3)> = tris
            .iter()
            .map(|t| {
                let [a, b, c] = t.v;
                (a.min(b).min(c), a.max(b).max(c))
            })
            .collect();
        let (lo, hi) = boxes.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(l, h), &(a, b)| (l.min(a), h.max(b)),
        );
        if boxes.is_empty() || !(lo.is_finite() && hi.is_finite()) {
            return None;
        }
        let mut sizes: Vec<f64> = boxes.iter().map(|(a, b)| (*b - *a).max_element()).collect();
        let mid = sizes.len() / 2;
        let median = *sizes.select_nth_unstable_by(mid, f64::total_cmp).1;
        let cell = median.max((hi - lo).max_element() / 256.0);
        if !(cell > 0.0 && cell.is_finite()) {
            return None;
        }
        let inv = 1.0 / cell;
        let dim = |e: f64| ((e * inv).floor() as usize).saturating_add(1);
        let dims = [dim(hi.x - lo.x), dim(hi.y - lo.y), dim(hi.z - lo.z)];
        let cells = dims[0].checked_mul(dims[1])?.checked_mul(dims[2])?;
        let cap = 16 * tris.len() + (1 << 20);
        if cells > cap {
            return None;
        }
        let range = |a: DVec3, b: DVec3| {
            let f = |x: f64, d: usize| ((x * inv).floor().max(0.0) as usize).min(d - 1);
            let l = [
                f(a.x - lo.x, dims[0]),
                f(a.y - lo.y, dims[1]),
                f(a.z - lo.z, dims[2]),
            ];
            let h = [
                f(b.x - lo.x, dims[0]),
                f(b.y - lo.y, dims[1]),
                f(b.z - lo.z, dims[2]),
            ];
            (l, h)
        };
        let span =
            |(l, h): ([usize; 3], [usize; 3])| (0..3).map(|i| h[i] - l[i] + 1).product::<usize>();
        let total: usize = boxes.iter().map(|&(a, b)| span(range(a, b))).sum();
        if total > cap {
            return None;
        }
        let mut count = vec![0u32; cells + 1];
        let each = |(l, h): ([usize; 3], [usize; 3]), f: &mut dyn FnMut(usize)| {
            for z in l[2]..=h[2] {
                for y in l[1]..=h[1] {
                    for x in l[0]..=h[0] {
                        f((z * dims[1] + y) * dims[0] + x);
                    }
                }
            }
        };
        for &(a, b) in &boxes {
            each(range(a, b), &mut |c| count[c + 1] += 1);
        }
        for c in 0..cells {
            count[c + 1] += count[c];
        }
        let start = count.clone();
        let mut items = vec![0u32; total];
        for (i, &(a, b)) in boxes.iter().enumerate() {
            each(range(a, b), &mut |c| {
                items[count[c] as usize] = i as u32;
                count[c] += 1;
            });
        }
        Some(TriangleGrid {
            tris,
            planes: tris.iter().map(Plane::of).collect(),
            lo,
            inv,
            dims,
            start,
            items,
        })
    }

    /// The range of cubes (lowest and highest index per axis) that the box `a..=b` meets:
    /// `Some(None)` where it lies outside the grid, `None` where its bounds are not finite or
    /// it meets more than [`GRID_QUERY_CELLS`] cubes.
    fn cubes(&self, a: DVec3, b: DVec3) -> Option<Option<([usize; 3], [usize; 3])>> {
        let (a, b) = (a - self.lo, b - self.lo);
        let d = self.dims;
        let mut l = [0usize; 3];
        let mut h = [0usize; 3];
        for i in 0..3 {
            let (x0, x1) = (a[i] * self.inv, b[i] * self.inv);
            if !(x0.is_finite() && x1.is_finite()) {
                return None;
            }
            if x1 < 0.0 || x0 >= d[i] as f64 {
                return Some(None);
            }
            l[i] = (x0.floor().max(0.0) as usize).min(d[i] - 1);
            h[i] = (x1.floor().max(0.0) as usize).min(d[i] - 1);
        }
        if (0..3).map(|i| h[i] - l[i] + 1).product::<usize>() > GRID_QUERY_CELLS {
            return None;
        }
        Some(Some((l, h)))
    }

    /// [`TriangleBvh::any_within`] for the same triangles, from the cubes the box of the
    /// ball about `p` (radius `r`, padded for rounding) meets; `None` when that box meets
    /// more than 64 cubes (ask the tree). A triangle nearer than `r`
    /// lists itself in a cube holding its nearest point, which that box meets.
    pub fn any_within(&self, p: DVec3, r: f64) -> Option<bool> {
        if r.is_nan() || r <= 0.0 {
            return Some(false);
        }
        let pad = r * (1.0 + 1e-9) + 1e-9 * (1.0 + p.abs().max_element());
        let Some((l, h)) = self.cubes(p - pad, p + pad)? else {
            return Some(false);
        };
        let d = self.dims;
        for z in l[2]..=h[2] {
            for y in l[1]..=h[1] {
                for x in l[0]..=h[0] {
                    let c = (z * d[1] + y) * d[0] + x;
                    for &i in &self.items[self.start[c] as usize..self.start[c + 1] as usize] {
                        let i = i as usize;
                        let t = &self.tris[i];
                        if !self.planes[i].beyond(p, r, t.v[0]) && distance_to_triangle(p, t) < r {
                            return Some(true);
                        }
                    }
                }
            }
        }
        Some(false)
    }

    /// [`TriangleBvh::lowest_hit`] for the same triangles, every crossing accepted, from the
    /// cubes that the segment `origin + t·dir`, `t ∈ [t0, t1]`, meets (padded for rounding):
    /// the crossing with the smallest `t`, ties to the smaller triangle index. `None` when
    /// the segment's box spans more than 64 cubes (ask the tree). A triangle the segment
    /// crosses lists itself in the cube that holds the crossing, which the segment meets.
    pub fn lowest_hit(&self, origin: DVec3, dir: DVec3, t0: f64, t1: f64) -> Option<Option<Hit>> {
        let mut best: Option<Hit> = None;
        self.along(origin, dir, t0, t1, |items, hi| {
            for &i in items {
                let top = best.map_or(t1, |b| b.t);
                if let Some(h) = intersect(&self.tris[i as usize], origin, dir, t0, top)
                    && best.is_none_or(|b| h.t < b.t || (h.t == b.t && i < b.triangle))
                {
                    best = Some(Hit { triangle: i, ..h });
                }
            }
            *hi = best.map_or(t1, |b| b.t);
            true
        })?;
        Some(best)
    }

    /// [`TriangleBvh::any_hit`] for the same triangles, from the cubes as
    /// [`TriangleGrid::lowest_hit`] takes them; `None` where that asks the tree.
    pub fn any_hit(&self, origin: DVec3, dir: DVec3, t0: f64, t1: f64) -> Option<bool> {
        let mut found = false;
        self.along(origin, dir, t0, t1, |items, _| {
            found = items
                .iter()
                .any(|&i| intersect(&self.tris[i as usize], origin, dir, t0, t1).is_some());
            !found
        })?;
        Some(found)
    }

    /// Calls `f(triangles, hi)` for each cube, in turn, that the segment from `t0` to `hi`
    /// meets (`hi` from `t1`, lowered by `f`, padded for rounding) and that lists some; `f`
    /// returns whether to go on. `None`, calling nothing, when the segment's box spans
    /// more than [`GRID_QUERY_CELLS`] cubes.
    fn along(
        &self,
        origin: DVec3,
        dir: DVec3,
        t0: f64,
        t1: f64,
        mut f: impl FnMut(&[u32], &mut f64) -> bool,
    ) -> Option<()> {
        if t0 > t1 || t0.is_nan() || t1.is_nan() {
            return Some(());
        }
        let (p, q) = (origin + t0 * dir, origin + t1 * dir);
        let pad = DVec3::splat(1e-9 * (1.0 + p.abs().max(q.abs()).max_element()));
        let Some((l, h)) = self.cubes(p.min(q) - pad, p.max(q) + pad)? else {
            return Some(());
        };
        let d = self.dims;
        let inv_dir = DVec3::new(1.0 / dir.x, 1.0 / dir.y, 1.0 / dir.z);
        let cell = 1.0 / self.inv;
        let mut hi = t1;
        for z in l[2]..=h[2] {
            for y in l[1]..=h[1] {
                for x in l[0]..=h[0] {
                    let c = (z * d[1] + y) * d[0] + x;
                    let items = &self.items[self.start[c] as usize..self.start[c + 1] as usize];
                    if items.is_empty() {
                        continue;
                    }
                    // The cube's box, grown by the pad.
                    let at = self.lo + DVec3::new(x as f64, y as f64, z as f64) * cell;
                    if slab_entry(origin, inv_dir, at - pad, at + cell + pad, t0, hi).is_some()
                        && !f(items, &mut hi)
                    {
                        return Some(());
                    }
                }
            }
        }
        Some(())
    }
}

/// Whether triangle `t` lies nearer to `p` than `r` by [`distance_to_triangle`], passing
/// over it first when its plane alone lies farther ([`beyond_plane`]).
#[inline]
fn nearer_than(p: DVec3, t: &Triangle, r: f64) -> bool {
    !beyond_plane(p, t, r) && distance_to_triangle(p, t) < r
}

/// A triangle's plane kept for [`Plane::beyond`]: the normal `(b − a) × (c − a)` (not
/// unit), its product with the first corner `a` and its squared length. On
/// sphere_on_plate's bull program the grid's queries (a plate's gouges a micrometre deep)
/// test some 20 triangles each, most of them passed over by their planes: computing each
/// plane once took their cost from 285 M to 208 M instructions. The tree's queries, far
/// fewer, keep [`beyond_plane`], which computes the same test from the corners.
#[derive(Debug, Clone, Copy)]
struct Plane {
    n: DVec3,
    na: f64,
    nn: f64,
}

impl Plane {
    fn of(t: &Triangle) -> Plane {
        let [a, b, c] = t.v;
        let n = (b - a).cross(c - a);
        Plane {
            n,
            na: n.dot(a),
            nn: n.length_squared(),
        }
    }

    /// [`beyond_plane`] for this triangle, with the same margin (`n·p − n·a` rounds to
    /// some 1e-16 of the coordinates, far below it).
    #[inline]
    fn beyond(&self, p: DVec3, r: f64, a: DVec3) -> bool {
        let h = self.n.dot(p) - self.na;
        let m = r + 1e-12 * (1.0 + (p - a).abs().max_element());
        h * h > m * m * self.nn
    }
}

/// Whether `p` lies farther than `r` from the plane of triangle `t`, by more than the
/// rounding of either distance (1e-12 of the coordinates' size; a degenerate triangle has no
/// plane and is never beyond it).
fn beyond_plane(p: DVec3, t: &Triangle, r: f64) -> bool {
    let [a, b, c] = t.v;
    let n = (b - a).cross(c - a);
    let w = p - a;
    let h = n.dot(w);
    let m = r + 1e-12 * (1.0 + w.abs().max_element());
    h * h > m * m * n.length_squared()
}

/// The distance (mm) from `p` to triangle `t`, as [`TriangleBvh::nearest_within`] measures
/// it.
pub(crate) fn distance_to_triangle(p: DVec3, t: &Triangle) -> f64 {
    p.distance(closest_on_triangle(p, t))
}

/// The point of triangle `t` closest to `p` (Voronoi regions of its corners, edges and
/// face).
fn closest_on_triangle(p: DVec3, t: &Triangle) -> DVec3 {
    let [a, b, c] = t.v;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = va + vb + vc;
    if denom == 0.0 {
        // Degenerate: the nearest of the corners.
        return [a, b, c]
            .into_iter()
            .min_by(|x, y| p.distance_squared(*x).total_cmp(&p.distance_squared(*y)))
            .unwrap_or(a);
    }
    a + ab * (vb / denom) + ac * (vc / denom)
}

impl TriangleBvh {
    /// The accepted crossing of the segment `origin + t·dir`, `t ∈ [t0, t1]`, with the
    /// smallest `t` (ties: the smaller triangle index). Visits near boxes first and prunes
    /// boxes entered beyond the best crossing so far, so a segment through many stacked
    /// sheets costs about one path down the tree; the answer is the same as scanning every
    /// hit with [`TriangleBvh::segment_hits`] (box tests include their boundary).
    pub fn lowest_hit(
        &self,
        origin: DVec3,
        dir: DVec3,
        t0: f64,
        t1: f64,
        accept: impl Fn(&Hit) -> bool,
    ) -> Option<Hit> {
        if self.tris.is_empty() {
            return None;
        }
        let inv = DVec3::new(1.0 / dir.x, 1.0 / dir.y, 1.0 / dir.z);
        let mut best: Option<Hit> = None;
        let root = &self.nodes[0];
        let e = slab_entry(origin, inv, root.min, root.max, t0, t1)?;
        // Each node with where the segment enters its box, tested once (by its parent):
        // the box still meets the segment when that entry lies before the best crossing.
        let mut stack = [(0u32, 0f64); 64];
        stack[0] = (0, e);
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let (ni, e) = stack[top];
            let hi = best.map_or(t1, |b| b.t);
            if e > hi {
                continue;
            }
            let n = self.nodes[ni as usize];
            if n.count > 0 {
                for k in n.first as usize..(n.first + n.count) as usize {
                    let ti = self.order[k];
                    let hi = best.map_or(t1, |b| b.t);
                    if let Some(h) = intersect(&self.tris[k], origin, dir, t0, hi) {
                        let h = Hit { triangle: ti, ..h };
                        let better =
                            best.is_none_or(|b| h.t < b.t || (h.t == b.t && ti < b.triangle));
                        if better && accept(&h) {
                            best = Some(h);
                        }
                    }
                }
            } else {
                let entry = |c: u32| {
                    let m = &self.nodes[c as usize];
                    slab_entry(origin, inv, m.min, m.max, t0, hi).map(|e| (c, e))
                };
                // The nearer child is visited first (pushed last).
                match (entry(n.first), entry(n.first + 1)) {
                    (Some(l), Some(r)) => {
                        let (near, far) = if r.1 < l.1 { (r, l) } else { (l, r) };
                        stack[top] = far;
                        stack[top + 1] = near;
                        top += 2;
                    }
                    (Some(c), None) | (None, Some(c)) => {
                        stack[top] = c;
                        top += 1;
                    }
                    (None, None) => {}
                }
            }
        }
        best
    }

    /// Whether the segment `origin + t·dir`, `t ∈ [t0, t1]`, crosses any triangle: the same
    /// answer as `lowest_hit(origin, dir, t0, t1, |_| true).is_some()`, ending at the
    /// first crossing found (boxes in the tree's order, none pruned by a best).
    pub fn any_hit(&self, origin: DVec3, dir: DVec3, t0: f64, t1: f64) -> bool {
        if self.tris.is_empty() {
            return false;
        }
        let inv = DVec3::new(1.0 / dir.x, 1.0 / dir.y, 1.0 / dir.z);
        let meets = |ni: u32| {
            let m = &self.nodes[ni as usize];
            slab_entry(origin, inv, m.min, m.max, t0, t1).is_some()
        };
        if !meets(0) {
            return false;
        }
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let n = self.nodes[stack[top] as usize];
            if n.count > 0 {
                let tris = &self.tris[n.first as usize..(n.first + n.count) as usize];
                if tris
                    .iter()
                    .any(|t| intersect(t, origin, dir, t0, t1).is_some())
                {
                    return true;
                }
            } else {
                for c in [n.first, n.first + 1] {
                    if meets(c) {
                        stack[top] = c;
                        top += 1;
                    }
                }
            }
        }
        false
    }
}

/// Entry parameter of the segment into the box, or `None` if it misses (boundary included).
#[inline]
fn slab_entry(o: DVec3, inv: DVec3, min: DVec3, max: DVec3, t0: f64, t1: f64) -> Option<f64> {
    // Axis by axis, written out: indexing a vector by a loop counter costs a branch per
    // access, and rays cast along an axis (the material check's vertical ones) test many
    // boxes each.
    #[inline(always)]
    fn axis(o: f64, inv: f64, min: f64, max: f64, lo: &mut f64, hi: &mut f64) -> bool {
        if inv.is_infinite() {
            return !(o < min || o > max);
        }
        let ta = (min - o) * inv;
        let tb = (max - o) * inv;
        let (ta, tb) = if ta <= tb { (ta, tb) } else { (tb, ta) };
        let pad = 1e-12 * (1.0 + ta.abs().max(tb.abs()));
        *lo = lo.max(ta - pad);
        *hi = hi.min(tb + pad);
        *lo <= *hi
    }
    let (mut lo, mut hi) = (t0, t1);
    (axis(o.x, inv.x, min.x, max.x, &mut lo, &mut hi)
        && axis(o.y, inv.y, min.y, max.y, &mut lo, &mut hi)
        && axis(o.z, inv.z, min.z, max.z, &mut lo, &mut hi))
    .then_some(lo)
}

/// Spreads the low 21 bits of `v` to every third bit (Morton interleaving).
fn spread(v: u64) -> u64 {
    let mut x = v & 0x1f_ffff;
    x = (x | (x << 32)) & 0x1f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x1f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    (x | (x << 2)) & 0x1249_2492_4924_9249
}

/// Fills node `ni` over `tris[lo..hi]` (median split in Morton order), bounds bottom-up.
fn build(tris: &[Triangle], nodes: &mut Vec<Node>, ni: usize, lo: usize, hi: usize) {
    if hi - lo <= LEAF {
        let (mut bmin, mut bmax) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for t in &tris[lo..hi] {
            for p in t.v {
                bmin = bmin.min(p);
                bmax = bmax.max(p);
            }
        }
        nodes[ni] = Node {
            min: bmin,
            max: bmax,
            first: lo as u32,
            count: (hi - lo) as u32,
        };
        return;
    }
    let left = nodes.len();
    let empty = Node {
        min: DVec3::ZERO,
        max: DVec3::ZERO,
        first: 0,
        count: 0,
    };
    nodes.push(empty);
    nodes.push(empty);
    let mid = (lo + hi) / 2;
    build(tris, nodes, left, lo, mid);
    build(tris, nodes, left + 1, mid, hi);
    let (a, b) = (nodes[left], nodes[left + 1]);
    nodes[ni] = Node {
        min: a.min.min(b.min),
        max: a.max.max(b.max),
        first: left as u32,
        count: 0,
    };
}

fn slab(o: DVec3, inv: DVec3, min: DVec3, max: DVec3, t0: f64, t1: f64) -> bool {
    slab_entry(o, inv, min, max, t0, t1).is_some()
}

/// Möller–Trumbore segment/triangle intersection with inclusive barycentric bounds.
pub(crate) fn intersect(tri: &Triangle, o: DVec3, d: DVec3, t0: f64, t1: f64) -> Option<Hit> {
    const EPS: f64 = 1e-12;
    let [a, b, c] = tri.v;
    let e1 = b - a;
    let e2 = c - a;
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    let scale = e1.length() * e2.length() * d.length();
    if det.abs() <= 1e-15 * scale || scale == 0.0 {
        return None;
    }
    let inv = 1.0 / det;
    let tv = o - a;
    let u = tv.dot(pv) * inv;
    if !(-EPS..=1.0 + EPS).contains(&u) {
        return None;
    }
    let qv = tv.cross(e1);
    let v = d.dot(qv) * inv;
    if v < -EPS || u + v > 1.0 + EPS {
        return None;
    }
    let t = e2.dot(qv) * inv;
    if t < t0 || t > t1 {
        return None;
    }
    let n = e1.cross(e2);
    let facing = n.dot(d) / n.length();
    Some(Hit {
        triangle: 0,
        t,
        facing,
    })
}

/// The most inward entry of one vector into the swept volume, as `(t, move)`; `t` is the
/// signed distance from the vertex along its normal.
fn vector_deviation(
    bvh: &TriangleBvh,
    moves: &[u32],
    p: DVec3,
    n: DVec3,
    cfg: &DeviationConfig,
) -> (Option<f64>, Option<u32>) {
    // Lowest entry; ties broken by the smaller triangle index for determinism.
    let best = bvh
        .lowest_hit(p, n, -cfg.inside_mm, cfg.outside_mm, |h| match cfg.facing {
            Facing::AgainstVector => h.facing < 0.0,
            Facing::Any => true,
        })
        .map(|h| (h.t, h.triangle));
    match best {
        Some((t, i)) => (Some(t), Some(moves[i as usize])),
        None => (None, None),
    }
}

/// Measures the signed deviation at every vertex of `refined` against the swept surface
/// `swept` (triangles oriented out of the swept volume), `source_move[i]` being the
/// toolpath move that produced `swept[i]`. Results are in vertex order; parallel over
/// vertices and identical for any number of threads.
///
/// # Errors
/// [`DeviationError::LengthMismatch`] if `source_move.len() != swept.len()`;
/// [`DeviationError::BadLength`] for negative or non-finite vector lengths.
pub fn measure(
    refined: &RefinedMesh,
    swept: &[Triangle],
    source_move: &[u32],
    cfg: &DeviationConfig,
) -> Result<Vec<Deviation>, DeviationError> {
    let bvh = TriangleBvh::new(swept);
    measure_with_bvh(refined, &bvh, source_move, cfg)
}

/// As [`measure`] for a [`crate::sweep::SweptSurface`] (its triangles face away from the
/// removed volume, as [`Facing::AgainstVector`] expects).
///
/// # Errors
/// As [`measure`].
pub fn measure_swept(
    refined: &RefinedMesh,
    swept: &crate::sweep::SweptSurface,
    cfg: &DeviationConfig,
) -> Result<Vec<Deviation>, DeviationError> {
    measure(refined, &swept.triangles, &swept.source_move, cfg)
}

/// As [`measure`], with a hierarchy built beforehand (e.g. reused for a reversed sweep).
///
/// # Errors
/// As [`measure`].
pub fn measure_with_bvh(
    refined: &RefinedMesh,
    bvh: &TriangleBvh,
    source_move: &[u32],
    cfg: &DeviationConfig,
) -> Result<Vec<Deviation>, DeviationError> {
    if source_move.len() != bvh.len() {
        return Err(DeviationError::LengthMismatch {
            triangles: bvh.len(),
            moves: source_move.len(),
        });
    }
    let ok = |x: f64| x.is_finite() && x >= 0.0;
    if !ok(cfg.inside_mm) || !ok(cfg.outside_mm) {
        return Err(DeviationError::BadLength {
            inside_mm: cfg.inside_mm,
            outside_mm: cfg.outside_mm,
        });
    }
    Ok(refined
        .positions
        .par_iter()
        .zip(refined.normals.par_iter())
        .map(|(&p, &n)| {
            let (signed_mm, source_move) = vector_deviation(bvh, source_move, p, n, cfg);
            Deviation {
                position: p,
                normal: n,
                signed_mm,
                source_move,
            }
        })
        .collect())
}

/// Merges two measurements of the same refined surface (e.g. forward and reversed sweeps,
/// or several swept surfaces): per vertex, the lower deviation wins; `None` loses to any
/// value. Panics never; mismatched lengths merge up to the shorter one.
pub fn merge_lowest(a: &[Deviation], b: &[Deviation]) -> Vec<Deviation> {
    a.iter()
        .zip(b)
        .map(|(x, y)| match (x.signed_mm, y.signed_mm) {
            (Some(sx), Some(sy)) if sy < sx => *y,
            (None, Some(_)) => *y,
            _ => *x,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// One triangle's distance never says "near" where the tree would not: the crease pass
    /// tries a vertex's own design face before the tree (`pipeline::crease_depths`) and must
    /// decide as the tree alone does. Random triangles and points, radii just above, above
    /// and below a chosen triangle's distance.
    #[test]
    fn a_triangles_own_distance_agrees_with_the_tree() {
        let mut rng = crate::testkit::Lcg(5);
        let mut r = || 4.0 * rng.next() - 2.0;
        let mut v = || DVec3::new(r(), r(), r());
        let tris: Vec<Triangle> = (0..300)
            .map(|_| {
                let o = v();
                Triangle::new(o, o + 0.3 * v(), o + 0.3 * v())
            })
            .collect();
        let bvh = TriangleBvh::new(&tris);
        for i in 0..3000 {
            let p = v();
            let t = &tris[i % tris.len()];
            let d = distance_to_triangle(p, t);
            for radius in [d * (1.0 + 1e-12) + 1e-300, 1.5 * d, 0.5 * d] {
                let tree = bvh.nearest_within(p, radius);
                if d < radius {
                    assert!(
                        tree.is_some_and(|n| n <= d),
                        "{p} {radius}: {tree:?} vs {d}"
                    );
                }
                if let Some(n) = tree {
                    assert!(n < radius);
                }
            }
        }
    }

    /// The slab test as first written, axis by axis in a loop: the reference.
    fn slab_entry_loop(
        o: DVec3,
        inv: DVec3,
        min: DVec3,
        max: DVec3,
        t0: f64,
        t1: f64,
    ) -> Option<f64> {
        let (mut lo, mut hi) = (t0, t1);
        for a in 0..3 {
            if inv[a].is_infinite() {
                if o[a] < min[a] || o[a] > max[a] {
                    return None;
                }
                continue;
            }
            let ta = (min[a] - o[a]) * inv[a];
            let tb = (max[a] - o[a]) * inv[a];
            let (ta, tb) = if ta <= tb { (ta, tb) } else { (tb, ta) };
            let pad = 1e-12 * (1.0 + ta.abs().max(tb.abs()));
            lo = lo.max(ta - pad);
            hi = hi.min(tb + pad);
            if lo > hi {
                return None;
            }
        }
        Some(lo)
    }

    fn coord() -> impl Strategy<Value = f64> {
        // Whole numbers too, so rays start on box faces and run in their planes.
        prop_oneof![-4.0..4.0f64, (-4i32..4).prop_map(f64::from)]
    }

    fn dir() -> impl Strategy<Value = f64> {
        prop_oneof![-1.0..1.0f64, Just(0.0), Just(1.0), Just(-1.0)]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(20_000))]

        /// The written-out slab test decides and enters as the loop: rays along the axes
        /// (infinite inverse components), starting on faces and in their planes included.
        #[test]
        fn slab_entry_equals_the_loop(
            o in (coord(), coord(), coord()),
            d in (dir(), dir(), dir()),
            a in (coord(), coord(), coord()),
            b in (coord(), coord(), coord()),
            t0 in -2.0..1.0f64,
            len in 0.0..8.0f64,
        ) {
            let d = DVec3::new(d.0, d.1, d.2);
            prop_assume!(d != DVec3::ZERO);
            let o = DVec3::new(o.0, o.1, o.2);
            let (a, b) = (DVec3::new(a.0, a.1, a.2), DVec3::new(b.0, b.1, b.2));
            let (min, max) = (a.min(b), a.max(b));
            let inv = DVec3::new(1.0 / d.x, 1.0 / d.y, 1.0 / d.z);
            let got = slab_entry(o, inv, min, max, t0, t0 + len);
            let want = slab_entry_loop(o, inv, min, max, t0, t0 + len);
            prop_assert_eq!(got.map(f64::to_bits), want.map(f64::to_bits));
        }
    }

    /// A folded, wavy sheet of triangles over `[-5, 5]²` (two layers, the upper one
    /// overhanging the lower), for ray casts.
    fn folded_sheet() -> Vec<Triangle> {
        let at = |x: f64, y: f64, layer: f64| {
            DVec3::new(
                x,
                y,
                (0.7 * x).sin() * (0.5 * y).cos() + layer * (2.0 + 0.3 * x),
            )
        };
        let mut tris = Vec::new();
        for layer in [0.0, 1.0] {
            for i in 0..20 {
                for j in 0..20 {
                    let (x0, y0) = (-5.0 + 0.5 * i as f64, -5.0 + 0.5 * j as f64);
                    let (x1, y1) = (x0 + 0.5, y0 + 0.5);
                    let (a, b, c, d) = (
                        at(x0, y0, layer),
                        at(x1, y0, layer),
                        at(x1, y1, layer),
                        at(x0, y1, layer),
                    );
                    tris.push(Triangle::new(a, b, c));
                    tris.push(Triangle::new(a, c, d));
                }
            }
        }
        tris
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2_000))]

        /// `any_hit` answers as `lowest_hit` with every crossing accepted, and both as the
        /// brute force over every triangle: for vertical rays (the material check's sky
        /// rays) and any other direction, from below, between and above the layers.
        #[test]
        fn any_hit_equals_the_lowest_hit_and_brute_force(
            o in (-6.0..6.0f64, -6.0..6.0f64, -3.0..6.0f64),
            d in (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64),
            vertical in any::<bool>(),
            t0 in 0.0..1.0f64,
            len in 0.0..12.0f64,
        ) {
            let tris = folded_sheet();
            let bvh = TriangleBvh::new(&tris);
            let o = DVec3::new(o.0, o.1, o.2);
            let d = if vertical { DVec3::Z } else { DVec3::new(d.0, d.1, d.2) };
            prop_assume!(d.length() > 0.1);
            let d = d.normalize();
            let t1 = t0 + len;
            let brute = tris.iter().any(|t| intersect(t, o, d, t0, t1).is_some());
            prop_assert_eq!(bvh.any_hit(o, d, t0, t1), brute);
            prop_assert_eq!(bvh.lowest_hit(o, d, t0, t1, |_| true).is_some(), brute);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2_000))]

        /// The grid's lowest crossing is the brute force's over every triangle (least `t`,
        /// ties to the smaller index) and the tree's, and its `any_hit` whether there is one
        /// (also over longer segments): on the folded sheet and on the plate
        /// of long slivers under it, for short segments in any direction (some vertical),
        /// some starting at a triangle's corner as the material check's inner rays do, some
        /// passing through one (where the triangles around it tie).
        #[test]
        fn grid_lowest_hit_equals_the_tree_and_brute_force(
            plate in any::<bool>(),
            o in (-6.0..6.0f64, -6.0..6.0f64, -3.0..6.0f64),
            corner in proptest::option::of((0usize..10_000, 0usize..3, any::<bool>())),
            d in (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64),
            vertical in any::<bool>(),
            t0 in 0.0..0.5f64,
            len in 0.0..3.0f64,
        ) {
            let tris = if plate { plate_and_sheet() } else { folded_sheet() };
            let bvh = TriangleBvh::new(&tris);
            let grid = TriangleGrid::new(&tris).expect("a grid");
            let d = if vertical { DVec3::Z } else { DVec3::new(d.0, d.1, d.2) };
            prop_assume!(d.length() > 0.1);
            let d = d.normalize();
            let t1 = t0 + len;
            let o = match corner {
                Some((t, k, false)) => tris[t % tris.len()].v[k],
                Some((t, k, true)) => tris[t % tris.len()].v[k] - (t0 + 0.5 * len) * d,
                None => DVec3::new(o.0, o.1, o.2),
            };
            let brute = tris
                .iter()
                .enumerate()
                .filter_map(|(i, t)| intersect(t, o, d, t0, t1).map(|h| (h.t, i as u32)))
                .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let tree = bvh.lowest_hit(o, d, t0, t1, |_| true).map(|h| (h.t, h.triangle));
            prop_assert_eq!(tree, brute);
            if let Some(got) = grid.lowest_hit(o, d, t0, t1) {
                prop_assert_eq!(got.map(|h| (h.t, h.triangle)), brute);
            }
            if let Some(got) = grid.any_hit(o, d, t0, t1) {
                prop_assert_eq!(got, brute.is_some());
            }
            // And as far as the sky rays reach.
            let far = t1 + 20.0;
            if let Some(got) = grid.any_hit(o, d, t0, far) {
                let brute = tris.iter().any(|t| intersect(t, o, d, t0, far).is_some());
                prop_assert_eq!(got, brute);
            }
        }
    }

    /// A plate at z = −2 fanned from its corners to an octagon about its middle (long
    /// coplanar slivers whose boxes overlap, as sphere_on_plate's), under the folded sheet.
    fn plate_and_sheet() -> Vec<Triangle> {
        let mut tris = folded_sheet();
        let ring: Vec<DVec3> = (0..8)
            .map(|i| {
                let a = f64::from(i) * std::f64::consts::FRAC_PI_4;
                DVec3::new(1.5 * a.cos(), 1.5 * a.sin(), -2.0)
            })
            .collect();
        let corners = [(-8.0, -8.0), (8.0, -8.0), (8.0, 8.0), (-8.0, 8.0)]
            .map(|(x, y)| DVec3::new(x, y, -2.0));
        for (i, w) in ring.iter().zip(ring.iter().cycle().skip(1)).enumerate() {
            let c = corners[i / 2];
            tris.push(Triangle::new(c, *w.0, *w.1));
        }
        for i in 0..4 {
            tris.push(Triangle::new(corners[i], ring[2 * i], corners[(i + 3) % 4]));
        }
        tris
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2_000))]

        /// The grid answers as the tree and as the brute force over every triangle, where it
        /// answers: anywhere, and just under the plate at the reading's own depth less or
        /// more a millionth (the crease check's radius), where coplanar slivers lie at the
        /// radius itself.
        #[test]
        fn grid_any_within_equals_the_tree_and_brute_force(
            p in (-7.0..7.0f64, -7.0..7.0f64, -3.0..5.0f64),
            under in any::<bool>(),
            depth in 1e-6..1e-2f64,
            r in 1e-4..3.0f64,
            shrink in any::<bool>(),
        ) {
            let tris = plate_and_sheet();
            let bvh = TriangleBvh::new(&tris);
            let grid = TriangleGrid::new(&tris).expect("a grid for a small part");
            let (p, r) = if under {
                let f = if shrink { 1.0 - 1e-6 } else { 1.0 + 1e-6 };
                (DVec3::new(p.0, p.1, -2.0 - depth), depth * f)
            } else {
                (DVec3::new(p.0, p.1, p.2), r)
            };
            let brute = tris.iter().any(|t| distance_to_triangle(p, t) < r);
            prop_assert_eq!(bvh.any_within(p, r), brute);
            if let Some(g) = grid.any_within(p, r) {
                prop_assert_eq!(g, brute);
            }
        }
    }

    /// The sheet's sky: a vertical ray from under both layers meets them, one from above
    /// them or beside the sheet meets nothing.
    #[test]
    fn any_hit_sees_the_layers_above() {
        let bvh = TriangleBvh::new(&folded_sheet());
        assert!(bvh.any_hit(DVec3::new(0.3, -1.2, -4.0), DVec3::Z, 0.0, 20.0));
        assert!(!bvh.any_hit(DVec3::new(0.3, -1.2, 6.0), DVec3::Z, 0.0, 20.0));
        assert!(!bvh.any_hit(DVec3::new(5.5, 0.0, -4.0), DVec3::Z, 0.0, 20.0));
        // Between the layers: the upper one above, the lower one below, and neither within
        // 0.1 mm above.
        let mid = DVec3::new(0.3, -1.2, 1.0);
        assert!(bvh.any_hit(mid, DVec3::Z, 0.0, 20.0));
        assert!(bvh.any_hit(mid, -DVec3::Z, 0.0, 20.0));
        assert!(!bvh.any_hit(mid, DVec3::Z, 0.0, 0.1));
    }
}
