//! Constrained Delaunay triangulation of one design face's points in its own plane, for the
//! remesh ([`crate::remesh`]): a convex polygon (the face's corners and the points dividing
//! its edges, counter-clockwise) and points strictly inside it.
//!
//! Lawson's algorithm on exact predicates (the `robust` crate): the polygon is triangulated
//! by zipping its longest side against the rest (no triangle with all three corners on one
//! side), each inner point splits the triangle (or the inner edge) it falls in, and edges
//! that are not locally Delaunay are flipped. Hull edges (the polygon's sides) are never
//! flipped, so they are the constraints, and no triangle ever lies outside the polygon,
//! even where rounding puts an edge point a hair off its side. Where the Delaunay
//! triangulation is unique (no four points on one empty circle) the result is the
//! constrained Delaunay triangulation spade builds, at a fraction of its cost for the few
//! dozen points of a typical face; where it is not, ties are broken by the points'
//! coordinates (see `PolyCdt::first_of`), so the result does not depend on the order the
//! points came in nor on the triangulation the flips start from; a point that cannot be
//! placed (a duplicate, or one outside the polygon) makes the whole triangulation fail and
//! the caller falls back to spade.

use std::collections::HashMap;
use std::hash::BuildHasherDefault;

use robust::{Coord, incircle, orient2d};

/// Directed edges `a << 32 | b` and where they lie: (triangle, edge index).
type EdgeMap = HashMap<u64, (u32, usize), BuildHasherDefault<crate::refine::IntHasher>>;

/// No neighbour across an edge: a side of the polygon.
const NONE: u32 = u32::MAX;

/// A triangulation under construction: counter-clockwise triangles over `pts`, and per
/// triangle the neighbour across each edge `k` (from corner `k` to corner `k + 1`).
#[derive(Default)]
pub(crate) struct PolyCdt {
    pts: Vec<[f64; 2]>,
    tris: Vec<[u32; 3]>,
    adj: Vec<[u32; 3]>,
    /// The triangle a walk starts from (the last one made).
    last: u32,
    /// Edges waiting for the Delaunay test: (triangle, edge index).
    stack: Vec<(u32, usize)>,
    /// Scratch for [`PolyCdt::reset_lattice`]: directed edges `a << 32 | b` waiting for
    /// their reverse, with their triangle and edge index.
    open: EdgeMap,
    /// Scratch for [`PolyCdt::reset_lattice`]: the lattice rows' outline.
    outline: Vec<u32>,
    /// Scratch for [`PolyCdt::reset_lattice`]: per lattice point `k`, the strip triangle
    /// below the row's edge from `k` to the next point (its edge 1 runs back along it).
    top_of: Vec<u32>,
}

/// Whether `corners` index the polygon `boundary` as [`PolyCdt::reset`] takes them (the
/// first 0, increasing) and turn counter-clockwise (exact predicate).
fn corners_turn_left(boundary: &[[f64; 2]], [c0, c1, c2]: [usize; 3]) -> bool {
    c0 == 0
        && c0 < c1
        && c1 < c2
        && c2 < boundary.len()
        && orient2d(
            coord(boundary[c0]),
            coord(boundary[c1]),
            coord(boundary[c2]),
        ) > 0.0
}

/// How many of the lattice's leading `rows` (row number, first and end point index, in
/// order) [`PolyCdt::reset_lattice`] can lay out: rows of two or more points, each the row
/// after the one before. A row that does not follow on (a gap a region left) ends them.
pub(crate) fn leading_rows(rows: &[(u32, usize, usize)]) -> usize {
    rows.iter()
        .enumerate()
        .position(|(k, r)| r.2 < r.1 + 2 || (k > 0 && r.0 != rows[k - 1].0 + 1))
        .unwrap_or(rows.len())
}

fn coord(p: [f64; 2]) -> Coord<f64> {
    Coord { x: p[0], y: p[1] }
}

impl PolyCdt {
    /// The polygon `boundary` (counter-clockwise; `corners` the indices within it of the
    /// three corners, the first being 0), triangulated, with room for `inner` more points.
    /// `None` when the corners do not turn counter-clockwise or a point cannot be placed.
    #[cfg(test)]
    pub(crate) fn new(boundary: &[[f64; 2]], corners: [usize; 3], inner: usize) -> Option<PolyCdt> {
        let mut cdt = PolyCdt::default();
        cdt.reset(boundary, corners, inner)?;
        Some(cdt)
    }

    /// Makes this the triangulation of the polygon `boundary` (as for `new`: corners at
    /// `corners`, the first 0, room for `inner` more points), reusing its memory. `None`
    /// when the corners do not turn counter-clockwise or a point cannot be placed.
    pub(crate) fn reset(
        &mut self,
        boundary: &[[f64; 2]],
        corners: [usize; 3],
        inner: usize,
    ) -> Option<()> {
        if !corners_turn_left(boundary, corners) {
            return None;
        }
        let [c0, c1, c2] = corners;
        let n = boundary.len() + inner;
        self.pts.clear();
        self.pts.reserve(n);
        self.pts.extend_from_slice(boundary);
        self.tris.clear();
        self.tris.reserve(2 * n);
        self.adj.clear();
        self.adj.reserve(2 * n);
        self.last = 0;
        self.stack.clear();
        // Zipped along the side with the most points (`a`, corner to corner) against the
        // rest of the polygon run backwards from the same corner (`b`), each step along the
        // one whose new diagonal is shorter, of the steps that make a counter-clockwise
        // triangle of points not all on one side; then Lawson's flips. One triangle ends
        // at the far corner, where both chains meet. (Splitting the hull edge point by
        // point, each split flipping the long triangles before it, cost sphere_on_plate's
        // ball verification 99 M instructions for 73 thousand boundary points.)
        let n = boundary.len();
        let ends = [c0, c1, c2, n];
        let s = (0..3).max_by_key(|&k| (ends[k + 1] - ends[k], 3 - k))?;
        let (from, to) = (ends[s], ends[s + 1] % n);
        let len_a = ends[s + 1] - ends[s];
        let len_b = n - len_a;
        let at = |i: usize| ((from + i) % n) as u32;
        let back = |k: usize| ((from + n - k) % n) as u32;
        // `b` runs first along the side before `a` (to its own first corner, `before` points
        // back), and only a `b` step from `a`'s first corner can make a triangle on one side.
        let before = ends[s] + n - ends[(s + 2) % 3];
        let before = if before > n { before - n } else { before };
        let (pts, tris, adj) = (&self.pts, &mut self.tris, &mut self.adj);
        let pt = |i: u32| coord(pts[i as usize]);
        let d2 = |a: u32, b: u32| {
            let (p, r) = (pts[a as usize], pts[b as usize]);
            (p[0] - r[0]).powi(2) + (p[1] - r[1]).powi(2)
        };
        // Each triangle's third edge (back to `a`) is the rung the one before it left, its
        // first (an `a` step) or second (a `b` step) edge: neighbours without a search.
        let mut rung: Option<(u32, usize)> = None;
        let mut push = |t: [u32; 3], next: usize| {
            let id = tris.len() as u32;
            tris.push(t);
            adj.push([NONE; 3]);
            if let Some((u, e)) = rung {
                adj[id as usize][2] = u;
                adj[u as usize][e] = id;
            }
            rung = Some((id, next));
        };
        let (mut i, mut k) = (0, 1);
        while i + 1 < len_a || k + 1 < len_b {
            let ta = [at(i), at(i + 1), back(k)];
            let tb = [at(i), back(k + 1), back(k)];
            let ok = |t: [u32; 3]| orient2d(pt(t[0]), pt(t[1]), pt(t[2])) > 0.0;
            let step_a = i + 1 < len_a && ok(ta);
            let step_b = k + 1 < len_b && !(i == 0 && k < before) && ok(tb);
            let take_a = match (step_a, step_b) {
                (true, true) => d2(at(i + 1), back(k)) <= d2(at(i), back(k + 1)),
                (true, false) => true,
                (false, true) => false,
                (false, false) => return None,
            };
            if take_a {
                push(ta, 1);
                i += 1;
            } else {
                push(tb, 0);
                k += 1;
            }
        }
        let last = [at(i), to as u32, back(k)];
        if orient2d(pt(last[0]), pt(last[1]), pt(last[2])) <= 0.0 {
            return None;
        }
        push(last, 0);
        self.flip_inner();
        Some(())
    }

    /// Makes this the triangulation of the polygon `boundary` (corners as for
    /// [`PolyCdt::reset`]) and the points `lattice`, laid out in `rows` (ranges of
    /// `lattice`, one after another, covering it): each row at least two points on one
    /// horizontal line, left to right, each row above the one before. Built without a
    /// search: the strips between neighbouring rows are zipped, the band between the
    /// polygon and the rows' outline is zipped (each triangle checked counter-clockwise on
    /// exact predicates, which makes the band a triangulation), and Lawson flips then make
    /// every edge locally Delaunay, which the rows' inner edges already are. The result is
    /// the constrained Delaunay triangulation, as inserting the points one by one gives
    /// wherever that is unique. `None` (the triangulation is then unusable) when the rows
    /// are not laid out so or the band cannot be zipped; `room` more points may follow.
    ///
    /// Inserting a lattice point by point cost some 4 k instructions a point (the walk,
    /// the split and the flips of its long triangles to the polygon's sides).
    pub(crate) fn reset_lattice(
        &mut self,
        boundary: &[[f64; 2]],
        corners: [usize; 3],
        lattice: &[[f64; 2]],
        rows: &[(usize, usize)],
        room: usize,
    ) -> Option<()> {
        let nb = boundary.len();
        if rows.len() < 2 || !corners_turn_left(boundary, corners) {
            return None;
        }
        let mut next = 0;
        let mut below = f64::NEG_INFINITY;
        for &(s, e) in rows {
            if s != next || e < s + 2 || e > lattice.len() {
                return None;
            }
            let y = lattice[s][1];
            if y.partial_cmp(&below) != Some(std::cmp::Ordering::Greater)
                || lattice[s..e].windows(2).any(|w| {
                    w[1][1] != y
                        || w[1][0].partial_cmp(&w[0][0]) != Some(std::cmp::Ordering::Greater)
                })
            {
                return None;
            }
            (next, below) = (e, y);
        }
        if next != lattice.len() {
            return None;
        }
        let n = nb + lattice.len() + room;
        self.pts.clear();
        self.pts.reserve(n);
        self.pts.extend_from_slice(boundary);
        self.pts.extend_from_slice(lattice);
        self.tris.clear();
        self.tris.reserve(2 * n);
        self.adj.clear();
        self.stack.clear();
        self.last = 0;
        let id = |i: usize| (nb + i) as u32;
        // The strips: rows merged by x, each triangle an edge of one row and a point of the
        // other (counter-clockwise, the rows being horizontal and ordered). Their neighbours
        // across the strips' diagonals and rows are known as they are made: a triangle's left
        // diagonal (edge 2) is the one before's right (edge 1 of a triangle standing on the
        // lower row, 0 of one hanging from the upper), and a row's edge `i → i + 1` (edge 0)
        // is the reverse of the strip below's edge on it (edge 1, kept in `top_of[i]`). Only
        // the outline's edges are left for `link_and_flip` to join.
        let mut top_of = std::mem::take(&mut self.top_of);
        top_of.clear();
        top_of.resize(lattice.len(), NONE);
        for w in rows.windows(2) {
            let ((mut i, be), (mut k, te)) = (w[0], w[1]);
            let mut before: Option<(u32, usize)> = None;
            while i + 1 < be || k + 1 < te {
                let t = self.tris.len() as u32;
                let bottom = k + 1 == te || (i + 1 < be && lattice[i + 1][0] <= lattice[k + 1][0]);
                self.adj.push([NONE; 3]);
                let right = if bottom {
                    self.tris.push([id(i), id(i + 1), id(k)]);
                    let u = top_of[i];
                    if u != NONE {
                        self.adj[t as usize][0] = u;
                        self.adj[u as usize][1] = t;
                    }
                    i += 1;
                    1
                } else {
                    self.tris.push([id(i), id(k + 1), id(k)]);
                    top_of[k] = t;
                    k += 1;
                    0
                };
                if let Some((u, e)) = before {
                    self.adj[t as usize][2] = u;
                    self.adj[u as usize][e] = t;
                }
                before = Some((t, right));
            }
        }
        self.top_of = top_of;
        let strips = self.tris.len();
        // The rows' outline, counter-clockwise: the first row, the rows' right ends, the last
        // row back, the rows' left ends.
        let (first, top) = (rows[0], rows[rows.len() - 1]);
        let mut q = std::mem::take(&mut self.outline);
        q.clear();
        q.extend((first.0..first.1).map(id));
        q.extend(rows[1..].iter().map(|r| id(r.1 - 1)));
        q.extend((top.0..top.1 - 1).rev().map(id));
        q.extend(rows[1..rows.len() - 1].iter().rev().map(|r| id(r.0)));
        // The band: the polygon and the outline zipped from the first corner and the first
        // row's first point, each step along the one whose new diagonal is shorter, of the
        // steps that make a counter-clockwise triangle. Every triangle counter-clockwise and
        // each chain gone round once, the triangles cover the band once.
        let nq = q.len();
        let pt = |i: u32| coord(self.pts[i as usize]);
        let d2 = |a: u32, b: u32| {
            let (p, r) = (self.pts[a as usize], self.pts[b as usize]);
            (p[0] - r[0]).powi(2) + (p[1] - r[1]).powi(2)
        };
        let pp = |i: usize| (i % nb) as u32;
        let qq = |k: usize| q[k % nq];
        let (mut i, mut k) = (0, 0);
        while i < nb || k < nq {
            let along_p = i < nb && orient2d(pt(pp(i)), pt(pp(i + 1)), pt(qq(k))) > 0.0;
            let along_q = k < nq && orient2d(pt(pp(i)), pt(qq(k + 1)), pt(qq(k))) > 0.0;
            let step_p = match (along_p, along_q) {
                (true, true) => d2(pp(i + 1), qq(k)) <= d2(pp(i), qq(k + 1)),
                (true, false) => true,
                (false, true) => false,
                (false, false) => break,
            };
            if step_p {
                self.tris.push([pp(i), pp(i + 1), qq(k)]);
                i += 1;
            } else {
                self.tris.push([pp(i), qq(k + 1), qq(k)]);
                k += 1;
            }
        }
        self.outline = q;
        if i < nb || k < nq {
            return None;
        }
        // Lawson's flips from every inner edge: the strips' edges are Delaunay among
        // themselves where the rows are the remesh's, evenly spaced and offset by half a
        // spacing (two equilateral triangles across each), but not across a gap a region
        // left in a row, nor where four of their points lie on one circle (rows of a square
        // grid) and the tie goes the other way.
        self.link_and_flip(nb, strips)
    }

    /// Joins the triangles made (covering the polygon of the first `nb` points once, each
    /// counter-clockwise) as neighbours, then flips them Delaunay ([`PolyCdt::flip_inner`]).
    /// The first `strips` triangles come with some neighbours joined already (the others
    /// with none). `None` where the edges left without a neighbour are not exactly the
    /// polygon's sides.
    fn link_and_flip(&mut self, nb: usize, strips: usize) -> Option<()> {
        // Neighbours: each directed edge meets its reverse once; what is left unmatched is
        // exactly the polygon's sides. A hash map's work: joining every edge through it
        // cost sphere_on_plate's ball verification 1,725 M instructions in all (callgrind),
        // against 1,704 M with the strips' own joined as they are made (the dome's ball
        // 1,768 M against 1,761 M).
        self.adj.resize(self.tris.len(), [NONE; 3]);
        self.open.clear();
        let key = |a: u32, b: u32| (u64::from(a) << 32) | u64::from(b);
        for t in 0..self.tris.len() {
            let v = self.tris[t];
            for e in 0..3 {
                if t < strips && self.adj[t][e] != NONE {
                    continue;
                }
                let (a, b) = (v[e], v[(e + 1) % 3]);
                if let Some((u, f)) = self.open.remove(&key(b, a)) {
                    self.adj[t][e] = u;
                    self.adj[u as usize][f] = t as u32;
                } else if self.open.insert(key(a, b), (t as u32, e)).is_some() {
                    return None;
                }
            }
        }
        let side = |i: usize| key(i as u32, ((i + 1) % nb) as u32);
        if self.open.len() != nb || (0..nb).any(|i| !self.open.contains_key(&side(i))) {
            return None;
        }
        self.flip_inner();
        Some(())
    }

    /// Lawson's flips from every inner edge until each is locally Delaunay. An edge whose
    /// two opposite angles are both clearly acute is locally Delaunay (their sum is below
    /// 180°) and stays so until a flip next to it, which stacks it again: it is left off
    /// (a lattice's equilateral pairs, most of its edges).
    fn flip_inner(&mut self) {
        let mut stack = std::mem::take(&mut self.stack);
        stack.clear();
        // Plain loops: as iterator chains (`flat_map`, `filter`, `extend`) this scan and
        // `for_each_inner_edge`'s cost sphere_on_plate's ball verification 1,856 M
        // instructions against 1,806 M (the face remesh 332 M against 280 M).
        for (t, nb) in self.adj.iter().enumerate() {
            let t = t as u32;
            for (e, &u) in nb.iter().enumerate() {
                if u != NONE && t < u && !self.clearly_delaunay(t, e, u) {
                    stack.push((t, e));
                }
            }
        }
        self.stack = stack;
        self.flip_all();
    }

    /// Flips every edge on the stack that is not locally Delaunay, and after each flip the
    /// four edges around it, until none is left: Lawson's algorithm, which ends with every
    /// edge locally Delaunay (the polygon's sides excepted, never flipped).
    fn flip_all(&mut self) {
        while let Some((t, k)) = self.stack.pop() {
            if let Some((t, u)) = self.flip(t, k) {
                self.stack.extend([(t, 0), (t, 2), (u, 0), (u, 1)]);
            }
        }
    }

    /// Number of points (boundary first, then the inner points in the order inserted).
    pub(crate) fn num_points(&self) -> usize {
        self.pts.len()
    }

    /// The triangles (counter-clockwise, as point indices).
    pub(crate) fn triangles(&self) -> &[[u32; 3]] {
        &self.tris
    }

    /// Calls `f` on the inner edges (each once) as point pairs, with the triangles on both
    /// sides (the first a place to start [`PolyCdt::insert_near`] from), in triangle order.
    pub(crate) fn for_each_inner_edge(&self, mut f: impl FnMut([f64; 2], [f64; 2], u32, u32)) {
        for (t, (v, nb)) in self.tris.iter().zip(&self.adj).enumerate() {
            for k in 0..3 {
                if nb[k] != NONE && (t as u32) < nb[k] {
                    let (p, q) = (self.pts[v[k] as usize], self.pts[v[(k + 1) % 3] as usize]);
                    f(p, q, t as u32, nb[k]);
                }
            }
        }
    }

    /// Inserts the point `p` strictly inside the polygon; `None` (the triangulation is then
    /// unusable) when it lies on a vertex, outside the polygon or on its sides.
    pub(crate) fn insert(&mut self, p: [f64; 2]) -> Option<()> {
        self.insert_near(p, self.last)
    }

    /// [`PolyCdt::insert`], the search for `p` starting at triangle `hint`.
    pub(crate) fn insert_near(&mut self, p: [f64; 2], hint: u32) -> Option<()> {
        let i = self.pts.len() as u32;
        self.pts.push(p);
        let q = coord(p);
        let mut t = if (hint as usize) < self.tris.len() {
            hint
        } else {
            self.last
        };
        // A walk towards `p`; bounded, as a guard against cycling.
        let mut steps = 0;
        loop {
            steps += 1;
            if steps > 4 * self.tris.len() + 16 {
                return None;
            }
            let v = self.tris[t as usize];
            let mut on = None;
            let mut moved = false;
            for k in 0..3 {
                let o = orient2d(
                    coord(self.pts[v[k] as usize]),
                    coord(self.pts[v[(k + 1) % 3] as usize]),
                    q,
                );
                if o < 0.0 {
                    let nb = self.adj[t as usize][k];
                    if nb == NONE {
                        return None;
                    }
                    t = nb;
                    moved = true;
                    break;
                }
                if o == 0.0 {
                    if on.is_some() {
                        // On two edges: a vertex.
                        return None;
                    }
                    on = Some(k);
                }
            }
            if moved {
                continue;
            }
            match on {
                None => self.split_triangle(t, i),
                Some(k) if self.adj[t as usize][k] != NONE => self.split_edge(t, k, i)?,
                Some(_) => return None,
            }
            self.legalize();
            return Some(());
        }
    }

    /// Replaces triangle `t` by three about the new point `p` inside it.
    fn split_triangle(&mut self, t: u32, p: u32) {
        let [a, b, c] = self.tris[t as usize];
        let [nab, nbc, nca] = self.adj[t as usize];
        let (t1, t2) = (self.tris.len() as u32, self.tris.len() as u32 + 1);
        self.tris[t as usize] = [a, b, p];
        self.adj[t as usize] = [nab, t1, t2];
        self.tris.push([b, c, p]);
        self.adj.push([nbc, t2, t]);
        self.tris.push([c, a, p]);
        self.adj.push([nca, t, t1]);
        self.repoint(nbc, t, t1);
        self.repoint(nca, t, t2);
        self.stack.extend([(t, 0), (t1, 0), (t2, 0)]);
        self.last = t;
    }

    /// Splits edge `k` of triangle `t` at the new point `p` on it (and the triangle across
    /// it, if any). `None`, changing nothing, when the neighbours do not agree on the edge
    /// (a broken triangulation: never expected, refused rather than a panic).
    fn split_edge(&mut self, t: u32, k: usize, p: u32) -> Option<()> {
        let v = self.tris[t as usize];
        let nb = self.adj[t as usize];
        let (a, b, c) = (v[k], v[(k + 1) % 3], v[(k + 2) % 3]);
        let (nbc, nca) = (nb[(k + 1) % 3], nb[(k + 2) % 3]);
        let u = nb[k];
        let t1 = self.tris.len() as u32;
        let u1 = t1 + 1;
        let has_u = u != NONE;
        // The triangle across: the edge's place in it.
        let j = if has_u {
            let w = self.tris[u as usize];
            Some((0..3).find(|&j| w[j] == b && w[(j + 1) % 3] == a)?)
        } else {
            None
        };
        self.tris[t as usize] = [a, p, c];
        self.adj[t as usize] = [if has_u { u1 } else { NONE }, t1, nca];
        self.tris.push([p, b, c]);
        self.adj.push([if has_u { u } else { NONE }, nbc, t]);
        self.repoint(nbc, t, t1);
        self.stack.extend([(t, 2), (t1, 1)]);
        if let Some(j) = j {
            let w = self.tris[u as usize];
            let wn = self.adj[u as usize];
            let d = w[(j + 2) % 3];
            let (nad, ndb) = (wn[(j + 1) % 3], wn[(j + 2) % 3]);
            self.tris[u as usize] = [b, p, d];
            self.adj[u as usize] = [t1, u1, ndb];
            self.tris.push([p, a, d]);
            self.adj.push([t, nad, u]);
            self.repoint(nad, u, u1);
            self.stack.extend([(u, 2), (u1, 1)]);
        }
        self.last = t;
        Some(())
    }

    /// Whether the first of the four points in the order of their coordinates (`x`, then
    /// `y`) is one of `ours` rather than one of `theirs`. Four points on one circle have two
    /// Delaunay diagonals; the one at that point is kept, as if it lay a hair inside the
    /// circle (and the second a smaller hair, and so on): a consistent perturbation, so
    /// the triangulation is the same whatever the order its points came in, and however
    /// many other points far from them there are.
    fn first_of(&self, ours: [u32; 2], theirs: [u32; 2]) -> bool {
        let key = |i: u32| self.pts[i as usize];
        let before =
            |u: [f64; 2], v: [f64; 2]| u[0].total_cmp(&v[0]).then(u[1].total_cmp(&v[1])).is_lt();
        let (o, t) = (ours.map(key), theirs.map(key));
        let o = if before(o[1], o[0]) { o[1] } else { o[0] };
        let t = if before(t[1], t[0]) { t[1] } else { t[0] };
        before(o, t)
    }

    /// In triangle `n` (if any), the neighbour `old` becomes `new`.
    fn repoint(&mut self, n: u32, old: u32, new: u32) {
        if n == NONE {
            return;
        }
        for x in &mut self.adj[n as usize] {
            if *x == old {
                *x = new;
                return;
            }
        }
    }

    /// Whether edge `k` of triangle `t` (across it, triangle `u`) is locally Delaunay with
    /// room to spare: the angles opposite it in both triangles are acute by a margin
    /// (cosine above 2e-6) that the rounding of the differences (each correctly rounded)
    /// and of the dot products cannot eat. `false` says nothing.
    #[inline]
    fn clearly_delaunay(&self, t: u32, k: usize, u: u32) -> bool {
        let v = self.tris[t as usize];
        let (a, b) = (self.pts[v[k] as usize], self.pts[v[(k + 1) % 3] as usize]);
        let acute = |o: u32| {
            let o = self.pts[o as usize];
            let (u, w) = ([a[0] - o[0], a[1] - o[1]], [b[0] - o[0], b[1] - o[1]]);
            let dot = u[0] * w[0] + u[1] * w[1];
            dot > 1e-6 * (u[0] * u[0] + u[1] * u[1] + w[0] * w[0] + w[1] * w[1])
        };
        let w = self.tris[u as usize];
        let q = (0..3).find(|&j| w[j] != v[k] && w[j] != v[(k + 1) % 3]);
        acute(v[(k + 2) % 3]) && q.is_some_and(|j| acute(w[j]))
    }

    /// Flips the edges on the stack that are not locally Delaunay (the point opposite across
    /// an inner edge strictly inside the circle of the triangle), and the edges that then
    /// face the new point.
    fn legalize(&mut self) {
        while let Some((t, k)) = self.stack.pop() {
            if let Some((t, u)) = self.flip(t, k) {
                // The edges now facing p: a–q in t, q–b in u.
                self.stack.extend([(t, 0), (u, 0)]);
            }
        }
    }

    /// Flips edge `k` of triangle `t` (from `a` to `b`, `p` opposite) if it is an inner edge
    /// that is not locally Delaunay: the point `q` across it lies strictly inside the
    /// circle of `a, b, p`. Then `t` is `[a, q, p]` and `u`, the triangle that was across,
    /// `[q, b, p]`: returns them.
    #[inline(always)]
    fn flip(&mut self, t: u32, k: usize) -> Option<(u32, u32)> {
        let u = self.adj[t as usize][k];
        if u == NONE {
            return None;
        }
        let v = self.tris[t as usize];
        let (a, b, p) = (v[k], v[(k + 1) % 3], v[(k + 2) % 3]);
        let w = self.tris[u as usize];
        // The edge's place in `u` (written out: a search closure was not inlined here).
        let j = if w[0] == b && w[1] == a {
            0
        } else if w[1] == b && w[2] == a {
            1
        } else if w[2] == b && w[0] == a {
            2
        } else {
            return None;
        };
        let q = w[(j + 2) % 3];
        let pt = |i: u32| coord(self.pts[i as usize]);
        let o = incircle(pt(a), pt(b), pt(p), pt(q));
        if o < 0.0 || (o == 0.0 && !self.first_of([p, q], [a, b])) {
            return None;
        }
        // Quad a, q, b, p (counter-clockwise): the diagonal a–b becomes p–q.
        let tn = self.adj[t as usize];
        let un = self.adj[u as usize];
        let (nbp, npa) = (tn[(k + 1) % 3], tn[(k + 2) % 3]);
        let (naq, nqb) = (un[(j + 1) % 3], un[(j + 2) % 3]);
        self.tris[t as usize] = [a, q, p];
        self.adj[t as usize] = [naq, u, npa];
        self.tris[u as usize] = [q, b, p];
        self.adj[u as usize] = [nqb, nbp, t];
        self.repoint(naq, u, t);
        self.repoint(nbp, t, u);
        Some((t, u))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::Lcg;
    use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

    /// A random triangle's polygon (sides divided into 1–5 parts) and random points inside.
    fn case(rng: &mut Lcg) -> (Vec<[f64; 2]>, [usize; 3], Vec<[f64; 2]>) {
        let c = [
            [0.0, 0.0],
            [1.0 + rng.next(), 0.0],
            [rng.next() * 2.0 - 0.5, 0.3 + rng.next()],
        ];
        let mut boundary = Vec::new();
        let mut corners = [0; 3];
        for k in 0..3 {
            corners[k] = boundary.len();
            let (p, q) = (c[k], c[(k + 1) % 3]);
            let m = 1 + (rng.next() * 5.0) as usize;
            for i in 0..m {
                let f = i as f64 / m as f64;
                boundary.push([p[0] + f * (q[0] - p[0]), p[1] + f * (q[1] - p[1])]);
            }
        }
        let mut inner = Vec::new();
        while inner.len() < 30 {
            let (u, v) = (rng.next(), rng.next());
            if u + v < 0.96 && u > 0.02 && v > 0.02 {
                let w = 1.0 - u - v;
                inner.push([
                    u * c[0][0] + v * c[1][0] + w * c[2][0],
                    u * c[0][1] + v * c[1][1] + w * c[2][1],
                ]);
            }
        }
        (boundary, corners, inner)
    }

    fn sorted(mut t: Vec<[u32; 3]>) -> Vec<[u32; 3]> {
        for x in &mut t {
            let r = (0..3).min_by_key(|&k| x[k]).unwrap();
            x.rotate_left(r);
        }
        t.sort_unstable();
        t
    }

    /// Random faces, with their inner points and without (the polygon's own triangulation,
    /// zipped and flipped): the same triangles as spade's constrained Delaunay
    /// triangulation (its faces inside the polygon), each counter-clockwise, as many as a
    /// triangulation of the polygon with its inner points has.
    #[test]
    fn matches_spade_on_random_faces() {
        let mut rng = Lcg(7);
        for _ in 0..500 {
            let (boundary, corners, inner) = case(&mut rng);
            check_against_spade(&boundary, corners, &inner);
            check_against_spade(&boundary, corners, &[]);
        }
    }

    fn check_against_spade(boundary: &[[f64; 2]], corners: [usize; 3], inner: &[[f64; 2]]) {
        let mut ours = PolyCdt::new(boundary, corners, inner.len()).expect("polygon");
        for &p in inner {
            ours.insert(p).expect("inner point");
        }
        let nb = boundary.len();
        assert_eq!(ours.triangles().len(), nb + 2 * inner.len() - 2);
        for t in ours.triangles() {
            let [a, b, c] = t.map(|i| coord(ours.pts[i as usize]));
            assert!(orient2d(a, b, c) > 0.0);
        }
        let pts: Vec<Point2<f64>> = boundary
            .iter()
            .chain(inner)
            .map(|p| Point2::new(p[0], p[1]))
            .collect();
        let edges: Vec<[usize; 2]> = (0..nb).map(|i| [i, (i + 1) % nb]).collect();
        let cdt: ConstrainedDelaunayTriangulation<Point2<f64>> =
            ConstrainedDelaunayTriangulation::bulk_load_cdt(pts, edges).expect("spade");
        // Spade's faces outside the polygon: slivers between points of one side that
        // rounding put a hair inside it (all three corners on that side, turning
        // against the side's order).
        let along = |k: usize, i: u32| {
            let (from, to) = (corners[k], if k == 2 { nb } else { corners[k + 1] });
            let i = if k == 2 && i == 0 { nb } else { i as usize };
            (from..=to).contains(&i).then_some(i)
        };
        let outside = |t: &[u32; 3]| {
            (0..3).any(|k| match t.map(|i| along(k, i)) {
                [Some(a), Some(b), Some(c)] => {
                    let r = [a, b, c];
                    let m = (0..3).min_by_key(|&j| r[j]).unwrap();
                    r[(m + 1) % 3] > r[(m + 2) % 3]
                }
                _ => false,
            })
        };
        let theirs: Vec<[u32; 3]> = cdt
            .inner_faces()
            .map(|f| f.vertices().map(|v| v.fix().index() as u32))
            .filter(|t| !outside(t))
            .collect();
        assert_eq!(sorted(ours.triangles().to_vec()), sorted(theirs));
    }

    /// A polygon, its corners and lattice points by row.
    type LatticeCase = (Vec<[f64; 2]>, [usize; 3], Vec<(u32, [f64; 2])>);

    /// A random triangle's polygon (first side along x, sides divided into parts of about
    /// `h`), and the lattice of spacing `h` the remesh lays inside it (rows along the first
    /// side, √3/2·h apart, odd rows shifted by h/2, kept h/2 from the sides): its points by
    /// row (row number, point).
    fn lattice_case(rng: &mut Lcg) -> LatticeCase {
        let c = [
            [0.0, 0.0],
            [1.0 + 2.0 * rng.next(), 0.0],
            [rng.next() * 3.0 - 1.0, 0.2 + 1.5 * rng.next()],
        ];
        let h = 0.05 + 0.2 * rng.next();
        let mut boundary = Vec::new();
        let mut corners = [0; 3];
        for k in 0..3 {
            corners[k] = boundary.len();
            let (p, q) = (c[k], c[(k + 1) % 3]);
            let l = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
            let m = (l / h).ceil().max(1.0) as usize;
            for i in 0..m {
                let f = i as f64 / m as f64;
                boundary.push([p[0] + f * (q[0] - p[0]), p[1] + f * (q[1] - p[1])]);
            }
        }
        // Signed distance to side k (positive inside).
        let dist = |k: usize, x: f64, y: f64| {
            let (p, q) = (c[k], c[(k + 1) % 3]);
            let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
            (dx * (y - p[1]) - dy * (x - p[0])) / (dx * dx + dy * dy).sqrt()
        };
        let dy = 0.5 * 3f64.sqrt() * h;
        let mut lattice = Vec::new();
        for j in 1..200u32 {
            let y = f64::from(j) * dy;
            let shift = if j % 2 == 1 { 0.5 * h } else { 0.0 };
            for i in -200..200 {
                let x = shift + f64::from(i) * h;
                if (0..3).all(|k| dist(k, x, y) >= 0.5 * h) {
                    lattice.push((j, [x, y]));
                }
            }
        }
        (boundary, corners, lattice)
    }

    /// Random faces with the remesh's lattice: the leading rows laid out by
    /// `reset_lattice` and the rest inserted give the triangles of inserting every point
    /// one by one (unique here: no four points on an empty circle), each counter-clockwise.
    #[test]
    fn lattice_layout_matches_insertion_point_by_point() {
        let mut rng = Lcg(11);
        let mut laid_out = 0;
        for _ in 0..300 {
            let (boundary, corners, lattice) = lattice_case(&mut rng);
            let flat: Vec<[f64; 2]> = lattice.iter().map(|l| l.1).collect();
            let mut ours = PolyCdt::default();
            let mut labelled: Vec<(u32, usize, usize)> = Vec::new();
            for (i, &(j, _)) in lattice.iter().enumerate() {
                match labelled.last_mut() {
                    Some(r) if r.0 == j => r.2 = i + 1,
                    _ => labelled.push((j, i, i + 1)),
                }
            }
            let laid = leading_rows(&labelled);
            let rows: Vec<(usize, usize)> = labelled.iter().map(|r| (r.1, r.2)).collect();
            let upto = rows[..laid].last().map_or(0, |r| r.1);
            let rest = if ours
                .reset_lattice(
                    &boundary,
                    corners,
                    &flat[..upto],
                    &rows[..laid],
                    flat.len() - upto,
                )
                .is_some()
            {
                laid_out += 1;
                upto
            } else {
                assert!(laid < 2, "a lattice of {laid} rows not laid out");
                ours.reset(&boundary, corners, flat.len()).expect("polygon");
                0
            };
            for &p in &flat[rest..] {
                ours.insert(p).expect("lattice point");
            }
            let mut theirs = PolyCdt::new(&boundary, corners, flat.len()).expect("polygon");
            for &p in &flat {
                theirs.insert(p).expect("lattice point");
            }
            assert_eq!(ours.triangles().len(), boundary.len() + 2 * flat.len() - 2);
            for t in ours.triangles() {
                let [a, b, c] = t.map(|i| coord(ours.pts[i as usize]));
                assert!(orient2d(a, b, c) > 0.0);
            }
            assert_eq!(
                sorted(ours.triangles().to_vec()),
                sorted(theirs.triangles().to_vec())
            );
        }
        assert!(laid_out > 200, "only {laid_out} of 300 faces laid out");
    }

    /// Where four points lie on one empty circle (the unit squares of a grid of integer
    /// points in a right triangle) the triangulation is the same whatever order the inner
    /// points come in, and laid out as a lattice it is the same again: ties keep the
    /// diagonal at the first point by coordinates. Keeping the diagonal found first fails
    /// here (checked).
    #[test]
    fn ties_are_broken_the_same_whatever_the_order() {
        let n = 8;
        let mut boundary = Vec::new();
        for i in 0..n {
            boundary.push([f64::from(i), 0.0]);
        }
        for i in 0..n {
            boundary.push([f64::from(n - i), f64::from(i)]);
        }
        for i in 0..n {
            boundary.push([0.0, f64::from(n - i)]);
        }
        let corners = [0, n as usize, 2 * n as usize];
        let inner: Vec<[f64; 2]> = (1..n)
            .flat_map(|y| (1..n - y).map(move |x| [f64::from(x), f64::from(y)]))
            .collect();
        let build = |order: &[[f64; 2]]| {
            let mut cdt = PolyCdt::new(&boundary, corners, order.len()).expect("polygon");
            for &p in order {
                cdt.insert(p).expect("inner point");
            }
            sorted(cdt.triangles().to_vec())
        };
        // Triangles as point coordinates: the orders number the inner points differently.
        let pts = |order: &[[f64; 2]], t: Vec<[u32; 3]>| {
            let at = |i: u32| {
                let i = i as usize;
                let p = if i < boundary.len() {
                    boundary[i]
                } else {
                    order[i - boundary.len()]
                };
                (p[0] as i64, p[1] as i64)
            };
            let mut t: Vec<[(i64, i64); 3]> = t
                .into_iter()
                .map(|t| {
                    let mut c = t.map(at);
                    let r = (0..3).min_by_key(|&k| c[k]).unwrap();
                    c.rotate_left(r);
                    c
                })
                .collect();
            t.sort_unstable();
            t
        };
        let forward = pts(&inner, build(&inner));
        let backward: Vec<[f64; 2]> = inner.iter().rev().copied().collect();
        assert_eq!(pts(&backward, build(&backward)), forward);
        let mut shuffled = inner.clone();
        let mut rng = Lcg(5);
        for i in (1..shuffled.len()).rev() {
            shuffled.swap(i, (rng.next() * (i + 1) as f64) as usize % (i + 1));
        }
        assert_eq!(pts(&shuffled, build(&shuffled)), forward);
        // Rows of the grid laid out as a lattice (every row but the last two points or more).
        let mut laid = PolyCdt::default();
        let mut rows = Vec::new();
        let mut at = 0;
        for y in 1..n - 2 {
            let len = (n - 1 - y) as usize;
            rows.push((at, at + len));
            at += len;
        }
        laid.reset_lattice(&boundary, corners, &inner[..at], &rows, inner.len() - at)
            .expect("laid out");
        for &p in &inner[at..] {
            laid.insert(p).expect("inner point");
        }
        assert_eq!(pts(&inner, sorted(laid.triangles().to_vec())), forward);
    }

    /// A point on a vertex or outside the polygon is refused, not placed.
    #[test]
    fn refuses_duplicates_and_outside_points() {
        let boundary = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let mut cdt = PolyCdt::new(&boundary, [0, 1, 2], 2).unwrap();
        cdt.insert([0.25, 0.25]).unwrap();
        assert!(cdt.insert([0.25, 0.25]).is_none());
        let mut cdt = PolyCdt::new(&boundary, [0, 1, 2], 2).unwrap();
        assert!(cdt.insert([1.0, 1.0]).is_none());
        // Clockwise corners are refused.
        assert!(PolyCdt::new(&[[0.0, 0.0], [0.0, 1.0], [1.0, 0.0]], [0, 1, 2], 0).is_none());
    }
}
