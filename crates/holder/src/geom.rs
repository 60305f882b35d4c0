//! Exact small geometry: the XY distance from the tool axis to a convex body clipped to a
//! z-slab, and an AABB tree over the part's triangles.
//!
//! The key fact used everywhere: for a convex polytope `K = conv(points)`, the slab-clipped
//! body `K ∩ {z0 ≤ z ≤ z1}` is the convex hull of the points inside the slab together with
//! the crossings of `K`'s edges with the planes `z = z0`, `z = z1` (every vertex of the
//! clipped body is a vertex of `K` in the slab or an edge of `K` crossing a plane). Any
//! superset of the edges made of segments inside `K` gives the same hull. Its XY projection
//! is the convex hull of the projected points. Both steps are exact up to rounding.

use cam_core::{Aabb, Triangle};
use glam::{DVec2, DVec3};

fn cross2(o: DVec2, a: DVec2, b: DVec2) -> f64 {
    (a - o).perp_dot(b - o)
}

/// Convex hull (counter-clockwise, no collinear points) of `pts` by the monotone chain,
/// written to `out` (at least `pts.len() + 1` long); returns its length (0, 1 or 2 for
/// degenerate input). Sorts `pts`.
pub(crate) fn hull_into(pts: &mut [DVec2], out: &mut [DVec2]) -> usize {
    pts.sort_unstable_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    if pts.is_empty() {
        return 0;
    }
    let mut k = 0;
    for &p in pts.iter() {
        while k >= 2 && cross2(out[k - 2], out[k - 1], p) <= 0.0 {
            k -= 1;
        }
        out[k] = p;
        k += 1;
    }
    let lower = k + 1;
    for &p in pts.iter().rev().skip(1) {
        while k >= lower && cross2(out[k - 2], out[k - 1], p) <= 0.0 {
            k -= 1;
        }
        out[k] = p;
        k += 1;
    }
    k -= 1;
    if k == 0 {
        out[0] = pts[0];
        k = 1;
    }
    k
}

/// [`hull_into`] returning a vector.
#[cfg(test)]
pub(crate) fn hull(pts: &mut [DVec2]) -> Vec<DVec2> {
    let mut out = vec![DVec2::ZERO; pts.len() + 1];
    let k = hull_into(pts, &mut out);
    out.truncate(k);
    out
}

fn seg_dist(a: DVec2, b: DVec2, o: DVec2) -> f64 {
    let ab = b - a;
    let l2 = ab.length_squared();
    let t = if l2 > 0.0 {
        ((o - a).dot(ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + ab * t - o).length()
}

/// Distance (mm) from `o` to the convex polygon `h` (CCW hull as from [`hull`]); 0 inside.
pub(crate) fn hull_dist(h: &[DVec2], o: DVec2) -> f64 {
    match h.len() {
        0 => f64::INFINITY,
        1 => (h[0] - o).length(),
        2 => seg_dist(h[0], h[1], o),
        n => {
            let mut inside = true;
            let mut best = f64::INFINITY;
            for i in 0..n {
                let (a, b) = (h[i], h[(i + 1) % n]);
                if cross2(a, b, o) < 0.0 {
                    inside = false;
                }
                best = best.min(seg_dist(a, b, o));
            }
            if inside { 0.0 } else { best }
        }
    }
}

/// Edges (index pairs into [`swept_points`]) of the prism `T ⊕ segment`: the triangle's
/// edges at both ends and the three vertex sweeps. Every edge of the convex hull of the six
/// points is one of these (the faces of a triangle ⊕ segment are the two triangles and the
/// three parallelograms `edge ⊕ segment`), also when the points are coplanar.
pub(crate) const PRISM_EDGES: [(usize, usize); 9] = [
    (0, 1),
    (1, 2),
    (2, 0),
    (3, 4),
    (4, 5),
    (5, 3),
    (0, 3),
    (1, 4),
    (2, 5),
];

/// Edges of a single triangle (three points).
#[cfg(test)]
pub(crate) const TRI_EDGES: [(usize, usize); 3] = [(0, 1), (1, 2), (2, 0)];

/// Most points [`slab_projection`] can produce for [`PRISM_EDGES`]: 6 + 2·9.
const MAX_PROJ: usize = 24;

/// XY projection of `conv(pts) ∩ {z0 ≤ z ≤ z1}` given a superset `edges` of the hull's
/// edges, written to `out`; returns the count (0 when the slab misses the body). `z1` may be
/// `+∞`, `z0` may be `-∞`.
pub(crate) fn slab_projection(
    pts: &[DVec3],
    edges: &[(usize, usize)],
    z0: f64,
    z1: f64,
    out: &mut [DVec2; MAX_PROJ],
) -> usize {
    let mut n = 0;
    for p in pts {
        if p.z >= z0 && p.z <= z1 {
            out[n] = p.truncate();
            n += 1;
        }
    }
    for &(i, j) in edges {
        let (a, b) = (pts[i], pts[j]);
        for c in [z0, z1] {
            if (a.z - c) * (b.z - c) < 0.0 {
                let t = (c - a.z) / (b.z - a.z);
                out[n] = a.truncate() + (b.truncate() - a.truncate()) * t;
                n += 1;
            }
        }
    }
    n
}

/// XY distance from the z axis (the origin of `pts`' frame) to `conv(pts) ∩ slab`, or `None`
/// when the slab misses the body or the body is provably not closer than `reject` (its XY
/// bounding box is that far). `pts` has at most 6 points and `edges` at most 9.
pub(crate) fn axis_distance_below(
    pts: &[DVec3],
    edges: &[(usize, usize)],
    z0: f64,
    z1: f64,
    reject: f64,
) -> Option<f64> {
    let mut proj = [DVec2::ZERO; MAX_PROJ];
    let n = slab_projection(pts, edges, z0, z1, &mut proj);
    if n == 0 {
        return None;
    }
    let (mut lo, mut hi) = (proj[0], proj[0]);
    for p in &proj[1..n] {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let gap = DVec2::new(lo.x.max(-hi.x).max(0.0), lo.y.max(-hi.y).max(0.0));
    if gap.length() >= reject {
        return None;
    }
    let mut h = [DVec2::ZERO; MAX_PROJ + 1];
    let k = hull_into(&mut proj[..n], &mut h);
    Some(hull_dist(&h[..k], DVec2::ZERO))
}

/// Edges for a point set from [`swept_points`] (6) or a triangle (3).
#[cfg(test)]
pub(crate) fn edges_of(pts: &[DVec3]) -> &'static [(usize, usize)] {
    if pts.len() == 6 {
        &PRISM_EDGES
    } else {
        &TRI_EDGES
    }
}

/// XY distance from the z axis to `conv(pts) ∩ slab` (`pts` from [`swept_points`] or a
/// triangle), or `None` when the slab misses the body.
#[cfg(test)]
pub(crate) fn axis_distance(pts: &[DVec3], z0: f64, z1: f64) -> Option<f64> {
    axis_distance_below(pts, edges_of(pts), z0, z1, f64::INFINITY)
}

/// The six points whose hull is the triangle seen from a tool tip moving `p → q`:
/// `{v - p} ∪ {v - q}` (the Minkowski sum of the triangle with the reversed move).
pub(crate) fn swept_points(t: &Triangle, p: DVec3, q: DVec3) -> [DVec3; 6] {
    let [a, b, c] = t.v;
    [a - p, b - p, c - p, a - q, b - q, c - q]
}

/// An axis-aligned bounding-box tree over triangles (median split, leaves of ≤ 4).
#[derive(Debug, Clone)]
pub(crate) struct Bvh {
    nodes: Vec<Node>,
    /// Piece indices, leaves refer to ranges of this.
    order: Vec<u32>,
    /// Bounding box of each piece.
    boxes: Vec<Aabb>,
    /// The pieces tested. Today each is one mesh triangle; splitting huge triangles (into
    /// pieces whose union is the triangle, keeping every test exact) or keeping them out of
    /// the tree was tried and did not pay on the fixtures.
    pieces: Vec<Triangle>,
    /// Mesh index of each piece's triangle.
    origin: Vec<u32>,
}

#[derive(Debug, Clone)]
struct Node {
    bounds: Aabb,
    /// Leaf: `start..end` into `order`; inner: children at `left`, `left + 1`… stored as
    /// (left, right) with `count == 0`.
    a: u32,
    b: u32,
    leaf: bool,
}

fn overlaps(a: &Aabb, b: &Aabb) -> bool {
    a.min.x <= b.max.x
        && a.max.x >= b.min.x
        && a.min.y <= b.max.y
        && a.max.y >= b.min.y
        && a.min.z <= b.max.z
        && a.max.z >= b.min.z
}

impl Bvh {
    pub(crate) fn new(tris: &[Triangle]) -> Bvh {
        let pieces = tris.to_vec();
        let origin: Vec<u32> = (0..tris.len() as u32).collect();
        let boxes: Vec<Aabb> = pieces.iter().map(|t| t.aabb()).collect();
        let mut order: Vec<u32> = (0..pieces.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * pieces.len() / 3 + 2);
        Self::build(&boxes, &mut order, 0, pieces.len(), &mut nodes);
        Bvh {
            nodes,
            order,
            boxes,
            pieces,
            origin,
        }
    }

    /// Piece `i` (a triangle or part of one).
    pub(crate) fn piece(&self, i: u32) -> &Triangle {
        &self.pieces[i as usize]
    }

    /// Mesh index of the triangle piece `i` belongs to.
    pub(crate) fn origin(&self, i: u32) -> u32 {
        self.origin[i as usize]
    }

    fn build(
        boxes: &[Aabb],
        order: &mut [u32],
        start: usize,
        end: usize,
        nodes: &mut Vec<Node>,
    ) -> u32 {
        let mut bounds = Aabb::empty();
        let mut cb = Aabb::empty();
        for &i in &order[start..end] {
            let b = boxes[i as usize];
            bounds.grow(b.min);
            bounds.grow(b.max);
            cb.grow((b.min + b.max) * 0.5);
        }
        let id = nodes.len() as u32;
        nodes.push(Node {
            bounds,
            a: start as u32,
            b: end as u32,
            leaf: true,
        });
        if end - start <= 4 {
            return id;
        }
        let s = cb.size();
        let axis = if s.x >= s.y && s.x >= s.z {
            0
        } else if s.y >= s.z {
            1
        } else {
            2
        };
        let mid = (start + end) / 2;
        let key = |i: &u32| {
            let b = boxes[*i as usize];
            (b.min + b.max)[axis]
        };
        order[start..end].select_nth_unstable_by(mid - start, |x, y| key(x).total_cmp(&key(y)));
        let l = Self::build(boxes, order, start, mid, nodes);
        let r = Self::build(boxes, order, mid, end, nodes);
        nodes[id as usize] = Node {
            bounds,
            a: l,
            b: r,
            leaf: false,
        };
        id
    }

    /// Indices of triangles whose bounding box overlaps `q`, in tree order (deterministic).
    pub(crate) fn query(&self, q: &Aabb, out: &mut Vec<u32>) {
        let mut outs = [std::mem::take(out)];
        self.query_multi(std::slice::from_ref(q), &mut outs);
        *out = std::mem::take(&mut outs[0]);
    }

    /// For each box `qs[k]`, the triangles whose bounding box overlaps it, into `outs[k]`, in
    /// one walk of the tree (a node is entered when it overlaps any of the boxes).
    pub(crate) fn query_multi(&self, qs: &[Aabb], outs: &mut [Vec<u32>]) {
        for o in outs.iter_mut() {
            o.clear();
        }
        if self.nodes.is_empty() {
            return;
        }
        // Median splits keep the depth ≤ log2(n) + 1 < 64.
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if !qs.iter().any(|q| overlaps(&node.bounds, q)) {
                continue;
            }
            if node.leaf {
                for &ti in &self.order[node.a as usize..node.b as usize] {
                    let b = &self.boxes[ti as usize];
                    for (q, o) in qs.iter().zip(outs.iter_mut()) {
                        if overlaps(b, q) {
                            o.push(ti);
                        }
                    }
                }
            } else {
                stack[top] = node.a;
                stack[top + 1] = node.b;
                top += 2;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_and_distance() {
        let mut p = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(2.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(2.0, 2.0),
            DVec2::new(0.0, 2.0),
            DVec2::new(1.0, 1.0),
        ];
        let h = hull(&mut p);
        assert_eq!(h.len(), 4);
        assert_eq!(hull_dist(&h, DVec2::new(1.0, 1.0)), 0.0);
        assert_eq!(hull_dist(&h, DVec2::new(5.0, 2.0)), 3.0);
        assert_eq!(hull_dist(&h, DVec2::new(-3.0, -4.0)), 5.0);
        let mut seg = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(2.0, 2.0),
        ];
        let h = hull(&mut seg);
        assert_eq!(h.len(), 2);
        assert!((hull_dist(&h, DVec2::new(2.0, 0.0)) - 2f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn slab_clip_of_vertical_triangle() {
        // Triangle in the plane x = 4 from z = 0 to z = 10; slab [5, 6].
        let pts = [
            DVec3::new(4.0, -1.0, 0.0),
            DVec3::new(4.0, 1.0, 0.0),
            DVec3::new(4.0, 0.0, 10.0),
        ];
        assert_eq!(axis_distance(&pts, 5.0, 6.0), Some(4.0));
        assert_eq!(axis_distance(&pts, 11.0, f64::INFINITY), None);
        assert_eq!(axis_distance(&pts, 10.0, f64::INFINITY), Some(4.0));
    }
}
