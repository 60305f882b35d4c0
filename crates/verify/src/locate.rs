//! Finding where each normal vector crosses the piecewise-linear swept surface: the lowest
//! entry crossing and every other entry crossing close enough above it to matter once the
//! crossings are refined onto the exact surface ([`crate::measure`]).
//!
//! # Method
//! The triangles are never stored. A [`PatchBvh`] bounds small *patches* of a
//! [`SweepModel`] (4 quads of a strip, or a block of cap sectors and rings) and the vectors
//! are processed in *tiles* of up to [`TILE`] vectors that are neighbours on the design
//! surface (Morton order of their vertices). A tile walks the hierarchy once, nearest boxes
//! first along its mean direction, skipping boxes outside the union of its vectors' live
//! ranges; at a patch, only vectors whose range meets the patch's box test its triangles,
//! which are generated then. A vector's live range is `[−L_in, min(L_out, lowest + δ)]`:
//! it shrinks as soon as a low crossing is found, so the sheets cut away by later passes,
//! which lie above, are mostly never looked at.
//!
//! # What is kept
//! Per vector: the lowest accepted crossing `s_min` (an entry: the triangle faces against
//! the vector, as in [`crate::deviation`]) and, of the accepted crossings with
//! `s ≤ s_min + δ`, the lowest of each piece (strip or cap), the [`MAX_CANDIDATES`] lowest of
//! those by `(s, key)`. That set depends only on the triangles, not on the order they are
//! met, so it equals what [`locate_reference`] finds by testing every triangle, and it is the
//! same for any number of threads.

use cam_core::{DVec3, Triangle};
use rayon::prelude::*;

use crate::deviation::TriangleBvh;
use crate::model::{Piece, SweepModel, key};

/// Vectors per tile.
pub const TILE: usize = 64;
/// Crossings kept per vector.
pub const MAX_CANDIDATES: usize = 64;
/// Quads per strip patch.
const STRIP_QUADS: usize = 4;
/// Sectors per cap patch.
const CAP_SECTORS: usize = 2;
/// Rings per cap patch.
const CAP_RINGS: usize = 2;

/// One normal vector: `o + s·n`, `s ∈ [lo, hi]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vector {
    /// The design vertex (mm).
    pub o: DVec3,
    /// Unit normal.
    pub n: DVec3,
    /// `−L_in` (mm).
    pub lo: f64,
    /// `L_out` (mm).
    pub hi: f64,
}

/// A crossing of a vector with a swept triangle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    /// Parameter along the vector (mm from the vertex).
    pub s: f64,
    /// Which model (index into the slice of models searched).
    pub model: u8,
    /// The triangle's key in that model ([`crate::model::key`]).
    pub key: u64,
    /// Unit normal of the triangle dotted with the vector (< 0: an entry).
    pub facing: f64,
    /// Barycentric weights of the triangle's second and third corner at the crossing.
    pub bary: (f64, f64),
}

impl Crossing {
    fn order(&self) -> (f64, u8, u64) {
        (self.s, self.model, self.key)
    }
    fn before(&self, other: &Crossing) -> bool {
        let (a, b) = (self.order(), other.order());
        a.0 < b.0 || (a.0 == b.0 && (a.1, a.2) < (b.1, b.2))
    }
}

/// What was found for one vector.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Found {
    /// The kept crossings, lowest first.
    pub crossings: Vec<Crossing>,
    /// True when more than [`MAX_CANDIDATES`] crossings qualified.
    pub overflow: bool,
}

/// Per-vector state during a search. The crossing list is a `Vec` of capacity
/// [`MAX_CANDIDATES`], reused from tile to tile ([`State::reset`]).
#[derive(Debug, Clone)]
struct State {
    best: f64,
    hi: f64,
    delta: f64,
    overflow: bool,
    cands: Vec<Crossing>,
}

impl State {
    fn new(v: &Vector, delta: f64) -> State {
        State {
            best: f64::INFINITY,
            hi: v.hi,
            delta,
            overflow: false,
            cands: Vec::with_capacity(MAX_CANDIDATES),
        }
    }

    /// Empties the state for vector `v`, keeping the list's allocation.
    fn reset(&mut self, v: &Vector, delta: f64) {
        self.best = f64::INFINITY;
        self.hi = v.hi;
        self.delta = delta;
        self.overflow = false;
        self.cands.clear();
    }

    /// Records an accepted crossing; returns true when the live range shrank.
    fn add(&mut self, c: Crossing, v: &Vector) -> bool {
        let mut shrank = false;
        if c.s < self.best {
            self.best = c.s;
            let hi = (c.s + self.delta).min(v.hi);
            if hi < self.hi {
                self.hi = hi;
                shrank = true;
            }
            let hi = self.hi;
            self.cands.retain(|x| x.s <= hi);
        }
        if c.s > self.hi {
            return shrank;
        }
        // One crossing per piece: its lowest.
        let piece = c.key >> 32;
        if let Some(x) = self
            .cands
            .iter_mut()
            .find(|x| x.model == c.model && x.key >> 32 == piece)
        {
            if c.before(x) {
                *x = c;
            }
            return shrank;
        }
        if self.cands.len() == MAX_CANDIDATES {
            // Keep the lowest: drop the highest of the list and the new one.
            let mut wi = 0;
            for i in 1..self.cands.len() {
                if self.cands[wi].before(&self.cands[i]) {
                    wi = i;
                }
            }
            self.overflow = true;
            if c.before(&self.cands[wi]) {
                self.cands[wi] = c;
            }
        } else {
            self.cands.push(c);
        }
        shrank
    }

    /// The kept crossings, lowest first.
    fn finish(&self) -> Found {
        let hi = self.best + self.delta;
        let mut crossings: Vec<Crossing> =
            self.cands.iter().filter(|x| x.s <= hi).copied().collect();
        crossings.sort_by(|a, b| {
            a.s.total_cmp(&b.s)
                .then((a.model, a.key).cmp(&(b.model, b.key)))
        });
        Found {
            crossings,
            overflow: self.overflow,
        }
    }
}

/// A triangle prepared for many segment tests: corner, edges, `|e1|·|e2|`.
#[derive(Debug, Clone, Copy)]
struct Prepared {
    key: u64,
    a: DVec3,
    e1: DVec3,
    e2: DVec3,
    ll: f64,
    /// Heights of the corners over their opposite edges (mm).
    h: [f64; 3],
}

impl Prepared {
    fn new(key: u64, t: &Triangle) -> Prepared {
        let [a, b, c] = t.v;
        let (e1, e2) = (b - a, c - a);
        let n = e1.cross(e2).length();
        Prepared {
            key,
            a,
            e1,
            e2,
            ll: e1.length() * e2.length(),
            h: [n / (e2 - e1).length(), n / e2.length(), n / e1.length()],
        }
    }

    /// Distance (mm) from the point `a + u·e1 + v·e2` of the triangle's plane to the triangle
    /// (0 inside): to the nearest of its edges.
    fn outside(&self, u: f64, v: f64) -> f64 {
        let p = u * self.e1 + v * self.e2;
        let seg = |a: DVec3, b: DVec3| {
            let ab = b - a;
            let l2 = ab.length_squared();
            let t = if l2 > 0.0 {
                ((p - a).dot(ab) / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            p.distance(a + t * ab)
        };
        let (a, b, c) = (DVec3::ZERO, self.e1, self.e2);
        seg(a, b).min(seg(b, c)).min(seg(c, a))
    }

    /// Möller–Trumbore with inclusive barycentric bounds (as [`crate::deviation`]) for an
    /// entry (facing < 0) only: parameter, barycentrics of corners 1 and 2, and the facing
    /// `unit normal · d`; `dl = |d|`. With `margin > 0` a line passing up to `margin` (mm)
    /// outside the triangle counts too (the triangle's share of the band between a sheet's
    /// chords and its curved edge).
    #[inline]
    fn entry(
        &self,
        o: DVec3,
        d: DVec3,
        dl: f64,
        t0: f64,
        t1: f64,
        margin: f64,
    ) -> Option<(f64, f64, f64, f64)> {
        const EPS: f64 = 1e-12;
        let (e1, e2) = (self.e1, self.e2);
        let pv = d.cross(e2);
        let det = e1.dot(pv);
        let scale = self.ll * dl;
        if det.abs() <= 1e-15 * scale || scale == 0.0 {
            return None;
        }
        let inv = 1.0 / det;
        let tv = o - self.a;
        let u = tv.dot(pv) * inv;
        if margin == 0.0 && !(-EPS..=1.0 + EPS).contains(&u) {
            return None;
        }
        let qv = tv.cross(e1);
        let v = d.dot(qv) * inv;
        let inside = (-EPS..=1.0 + EPS).contains(&u) && v >= -EPS && u + v <= 1.0 + EPS;
        if !inside {
            if margin == 0.0 {
                return None;
            }
            // Beyond an edge's line by more than the margin: beyond the triangle too.
            let w = [1.0 - u - v, u, v];
            if (0..3).any(|i| -w[i] * self.h[i] > margin) {
                return None;
            }
            let out = self.outside(u, v);
            if out.is_nan() || out > margin {
                return None;
            }
        }
        let t = e2.dot(qv) * inv;
        if t < t0 || t > t1 {
            return None;
        }
        let n = e1.cross(e2);
        let nd = n.dot(d);
        if nd.is_nan() || nd >= 0.0 {
            return None;
        }
        Some((t, u, v, nd / n.length()))
    }
}

/// Möller–Trumbore with inclusive barycentric bounds for an entry crossing (the triangle
/// facing against `d`): parameter, barycentrics of corners 1 and 2, facing `unit normal · d`.
pub fn entry_crossing(
    tri: &Triangle,
    o: DVec3,
    d: DVec3,
    t0: f64,
    t1: f64,
    margin: f64,
) -> Option<(f64, f64, f64, f64)> {
    Prepared::new(0, tri).entry(o, d, d.length(), t0, t1, margin)
}

const NO_SLOT: u32 = u32::MAX;

/// A quad (or fan triangle) of a patch: bounds in a tile's frame, its triangle slots, and
/// the triangles once prepared.
#[derive(Debug, Clone, Copy)]
struct Cell {
    lo: DVec3,
    hi: DVec3,
    slots: [u32; 2],
    ready: bool,
    tris: [Option<Prepared>; 2],
}

impl Cell {
    fn new(lo: DVec3, hi: DVec3, slots: [u32; 2], margin: f64) -> Cell {
        let p = margin + 1e-9 * (1.0 + lo.abs().max(hi.abs()).max_element());
        Cell {
            lo: lo - DVec3::splat(p),
            hi: hi + DVec3::splat(p),
            slots,
            ready: false,
            tris: [None; 2],
        }
    }

    fn prepare(&mut self, model: &SweepModel, piece: usize) {
        if self.ready {
            return;
        }
        for (t, &slot) in self.tris.iter_mut().zip(&self.slots) {
            if slot != NO_SLOT {
                *t = model
                    .slot_triangle(piece, slot as usize)
                    .map(|tri| Prepared::new(key(piece, slot as usize), &tri));
            }
        }
        self.ready = true;
    }
}

/// A patch: a block of triangle slots of one piece.
#[derive(Debug, Clone, Copy)]
struct Patch {
    piece: u32,
    /// Strip: quads `[a0, a1)`; cap: sectors `[a0, a1)`.
    a0: u16,
    a1: u16,
    /// Cap: rings `[g0, g1)` (the fan triangle belongs to ring 0); unused for strips.
    g0: u16,
    g1: u16,
}

#[derive(Debug, Clone, Copy)]
struct Node {
    min: [f32; 3],
    max: [f32; 3],
    /// Leaf: first patch; inner: left child (right = left + 1).
    first: u32,
    /// Leaf: number of patches (> 0); inner: 0.
    count: u32,
}

/// A bounding-volume hierarchy over the patches of one [`SweepModel`].
#[derive(Debug, Clone)]
pub struct PatchBvh {
    nodes: Vec<Node>,
    patches: Vec<Patch>,
}

fn down(x: f64) -> f32 {
    let f = x as f32;
    if f as f64 > x { f.next_down() } else { f }
}
fn up(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x { f.next_up() } else { f }
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

/// Morton codes of points within their bounds (ties keep index order when sorted with it).
pub fn morton_codes(points: &[DVec3]) -> Vec<u64> {
    morton_codes_by(points, |&p| p)
}

/// [`morton_codes`] of the points `at(item)` of `items`, without collecting them first.
pub(crate) fn morton_codes_by<T: Sync>(items: &[T], at: impl Fn(&T) -> DVec3 + Sync) -> Vec<u64> {
    let empty = || (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let (lo, hi) = items
        .par_iter()
        .fold(empty, |(a, b), it| {
            let c = at(it);
            (a.min(c), b.max(c))
        })
        .reduce(empty, |(a, b), (c, d)| (a.min(c), b.max(d)));
    let scale = (hi - lo).max(DVec3::splat(1e-300));
    items
        .par_iter()
        .map(|it| {
            let c = at(it);
            let q = ((c - lo) / scale * 2_097_151.0).clamp(DVec3::ZERO, DVec3::splat(2_097_151.0));
            if !q.is_finite() {
                return 0;
            }
            spread(q.x as u64) | (spread(q.y as u64) << 1) | (spread(q.z as u64) << 2)
        })
        .collect()
}

impl Patch {
    /// The patch's cells (a quad, or a cap's fan triangle) with their bounds in `tf`'s frame
    /// and their triangle slots, appended to `out`.
    fn cells(&self, model: &SweepModel, tf: &TileFrame, margin: f64, out: &mut Vec<Cell>) {
        let i = self.piece as usize;
        let bounds = |pts: &[DVec3]| {
            let mut lo = DVec3::splat(f64::INFINITY);
            let mut hi = DVec3::splat(f64::NEG_INFINITY);
            for &p in pts {
                let q = tf.to(p);
                lo = lo.min(q);
                hi = hi.max(q);
            }
            (lo, hi)
        };
        match model.pieces[i] {
            Piece::Gap { .. } => {}
            Piece::Strip { frame, .. } => {
                let (c0, c1) = (model.curve(frame), model.curve(frame + 1));
                let (a0, a1) = (self.a0 as usize, self.a1 as usize);
                let mut q0 = [DVec3::ZERO; STRIP_QUADS + 1];
                let mut q1 = [DVec3::ZERO; STRIP_QUADS + 1];
                for j in a0..=a1 {
                    q0[j - a0] = tf.to(c0[j]);
                    q1[j - a0] = tf.to(c1[j]);
                }
                for j in a0..a1 {
                    let k = j - a0;
                    let lo = q0[k].min(q0[k + 1]).min(q1[k]).min(q1[k + 1]);
                    let hi = q0[k].max(q0[k + 1]).max(q1[k]).max(q1[k + 1]);
                    out.push(Cell::new(lo, hi, [2 * j as u32, 2 * j as u32 + 1], margin));
                }
            }
            Piece::Cap { frame, .. } => {
                let fr = &model.frames[frame as usize];
                let per = model.cap_slots_per_sector();
                let fan = model.cutter().major_radius() > 0.0;
                let r = model.cutter().corner_radius();
                let (g0, g1) = (self.g0 as usize, self.g1 as usize);
                let tip = fr.tip(r);
                for s in self.a0 as usize..self.a1 as usize {
                    let base = (s * per) as u32;
                    let mut k = 0;
                    if fan {
                        if g0 == 0 {
                            let (lo, hi) = bounds(&[
                                tip,
                                model.cap_point(fr, s, 0),
                                model.cap_point(fr, s + 1, 0),
                            ]);
                            out.push(Cell::new(lo, hi, [base, NO_SLOT], margin));
                        }
                        k = 1;
                    }
                    if r > 0.0 {
                        for g in g0..g1 {
                            let (lo, hi) = bounds(&[
                                model.cap_point(fr, s, g),
                                model.cap_point(fr, s + 1, g),
                                model.cap_point(fr, s + 1, g + 1),
                                model.cap_point(fr, s, g + 1),
                            ]);
                            let slot = base + k + 2 * g as u32;
                            out.push(Cell::new(lo, hi, [slot, slot + 1], margin));
                        }
                    }
                }
            }
        }
    }

    /// Bounds of the patch's triangle corners.
    fn bounds(&self, model: &SweepModel) -> (DVec3, DVec3) {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        let i = self.piece as usize;
        match model.pieces[i] {
            Piece::Gap { .. } => {}
            Piece::Strip { frame, .. } => {
                let (c0, c1) = (model.curve(frame), model.curve(frame + 1));
                for j in self.a0 as usize..=self.a1 as usize {
                    for p in [c0[j], c1[j]] {
                        lo = lo.min(p);
                        hi = hi.max(p);
                    }
                }
            }
            Piece::Cap { frame, .. } => {
                let fr = &model.frames[frame as usize];
                for s in self.a0 as usize..=self.a1 as usize {
                    for g in self.g0 as usize..=self.g1 as usize {
                        let p = model.cap_point(fr, s, g);
                        lo = lo.min(p);
                        hi = hi.max(p);
                    }
                }
                if self.g0 == 0 && model.cutter().major_radius() > 0.0 {
                    let t = fr.tip(model.cutter().corner_radius());
                    lo = lo.min(t);
                    hi = hi.max(t);
                }
            }
        }
        (lo, hi)
    }
}

/// The patches of piece `i`.
fn patches_of(model: &SweepModel, i: usize, out: &mut Vec<Patch>) {
    let piece = i as u32;
    match model.pieces[i] {
        Piece::Gap { .. } => {}
        Piece::Strip { .. } => {
            let quads = model.per_curve() - 1;
            let mut a = 0;
            while a < quads {
                let b = (a + STRIP_QUADS).min(quads);
                out.push(Patch {
                    piece,
                    a0: a as u16,
                    a1: b as u16,
                    g0: 0,
                    g1: 0,
                });
                a = b;
            }
        }
        Piece::Cap { .. } => {
            let q = model.inserts();
            let rings = model.rings();
            let groups: Vec<(usize, usize)> = if model.cutter().corner_radius() > 0.0 {
                (0..rings)
                    .step_by(CAP_RINGS)
                    .map(|g| (g, (g + CAP_RINGS).min(rings)))
                    .collect()
            } else {
                vec![(0, 0)]
            };
            let mut s = 0;
            while s < q {
                let e = (s + CAP_SECTORS).min(q);
                for &(g0, g1) in &groups {
                    out.push(Patch {
                        piece,
                        a0: s as u16,
                        a1: e as u16,
                        g0: g0 as u16,
                        g1: g1 as u16,
                    });
                }
                s = e;
            }
        }
    }
}

impl PatchBvh {
    /// Builds the hierarchy over the patches of `model`'s strips, and of its caps when `caps`
    /// (Morton order of the patch centres, median splits, one patch per leaf), boxes padded by
    /// `margin` (mm, the band around each triangle that [`locate`] accepts). Deterministic.
    pub fn new(model: &SweepModel, caps: bool, margin: f64) -> PatchBvh {
        let per_piece: Vec<Vec<Patch>> = (0..model.pieces.len())
            .into_par_iter()
            .map(|i| {
                let mut v = Vec::new();
                if caps || matches!(model.pieces[i], Piece::Strip { .. }) {
                    patches_of(model, i, &mut v);
                }
                v
            })
            .collect();
        let patches: Vec<Patch> = per_piece.into_iter().flatten().collect();
        let boxes: Vec<(DVec3, DVec3)> = patches
            .par_iter()
            .map(|p| {
                let (a, b) = p.bounds(model);
                (a - DVec3::splat(margin), b + DVec3::splat(margin))
            })
            .collect();
        let centres: Vec<DVec3> = boxes.iter().map(|(a, b)| 0.5 * (*a + *b)).collect();
        let codes = morton_codes(&centres);
        let mut order: Vec<(u64, u32)> = codes
            .into_iter()
            .enumerate()
            .map(|(i, c)| (c, i as u32))
            .collect();
        crate::radix::sort_by_key(&mut order, |k| k.0);
        let sorted: Vec<Patch> = order.iter().map(|&(_, i)| patches[i as usize]).collect();
        let sboxes: Vec<(DVec3, DVec3)> = order.iter().map(|&(_, i)| boxes[i as usize]).collect();
        let mut nodes = Vec::with_capacity(2 * sorted.len() + 1);
        nodes.push(Node {
            min: [0.0; 3],
            max: [0.0; 3],
            first: 0,
            count: 0,
        });
        if !sorted.is_empty() {
            build(&sboxes, &mut nodes, 0, 0, sorted.len());
        } else {
            nodes.clear();
        }
        PatchBvh {
            nodes,
            patches: sorted,
        }
    }

    /// Number of patches.
    pub fn len(&self) -> usize {
        self.patches.len()
    }
    /// True without patches.
    pub fn is_empty(&self) -> bool {
        self.patches.is_empty()
    }
}

fn build(boxes: &[(DVec3, DVec3)], nodes: &mut Vec<Node>, ni: usize, lo: usize, hi: usize) {
    if hi - lo <= 1 {
        let (a, b) = boxes[lo];
        nodes[ni] = Node {
            min: [down(a.x), down(a.y), down(a.z)],
            max: [up(b.x), up(b.y), up(b.z)],
            first: lo as u32,
            count: (hi - lo) as u32,
        };
        return;
    }
    let left = nodes.len();
    let empty = Node {
        min: [0.0; 3],
        max: [0.0; 3],
        first: 0,
        count: 0,
    };
    nodes.push(empty);
    nodes.push(empty);
    let mid = (lo + hi) / 2;
    build(boxes, nodes, left, lo, mid);
    build(boxes, nodes, left + 1, mid, hi);
    let (a, b) = (nodes[left], nodes[left + 1]);
    nodes[ni] = Node {
        min: [0, 1, 2].map(|k| a.min[k].min(b.min[k])),
        max: [0, 1, 2].map(|k| a.max[k].max(b.max[k])),
        first: left as u32,
        count: 0,
    };
}

fn boxes_overlap(min: &[f32; 3], max: &[f32; 3], rmin: DVec3, rmax: DVec3) -> bool {
    (0..3).all(|a| (min[a] as f64) <= rmax[a] && (max[a] as f64) >= rmin[a])
}

/// Searches `bvh` (over `model`, index `mi` in the caller's list) for the vectors of one tile.
/// Side of the grid of vector masks over a tile's footprint.
const GRID: usize = 4;

/// Which of a tile's vectors reach each cell of a `GRID × GRID` grid over the tile's
/// footprint (the first two coordinates of its frame).
struct Lanes {
    x0: f64,
    y0: f64,
    inv: f64,
    masks: [u64; GRID * GRID],
}

impl Lanes {
    fn new(seg: &[(DVec3, DVec3)]) -> Lanes {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for (a, b) in seg {
            lo = lo.min(*a);
            hi = hi.max(*b);
        }
        let size = (hi.x - lo.x).max(hi.y - lo.y).max(1e-9);
        let mut l = Lanes {
            x0: lo.x,
            y0: lo.y,
            inv: GRID as f64 / size,
            masks: [0; GRID * GRID],
        };
        for (i, (a, b)) in seg.iter().enumerate() {
            l.set(i, *a, *b, true);
        }
        l
    }

    /// Cells `[a, b]` along one axis covered by `lo..hi`, or `None` outside the grid.
    #[inline]
    fn range(&self, lo: f64, hi: f64, origin: f64) -> Option<(usize, usize)> {
        let a = (lo - origin) * self.inv;
        let b = (hi - origin) * self.inv;
        if !(b >= 0.0 && a < GRID as f64) {
            return None;
        }
        // Truncation equals floor for non-negative values.
        Some((
            (a.max(0.0) as usize).min(GRID - 1),
            (b as usize).min(GRID - 1),
        ))
    }

    fn set(&mut self, i: usize, a: DVec3, b: DVec3, on: bool) {
        if let (Some((i0, i1)), Some((j0, j1))) =
            (self.range(a.x, b.x, self.x0), self.range(a.y, b.y, self.y0))
        {
            for j in j0..=j1 {
                for k in i0..=i1 {
                    if on {
                        self.masks[j * GRID + k] |= 1 << i;
                    } else {
                        self.masks[j * GRID + k] &= !(1 << i);
                    }
                }
            }
        }
    }

    /// The vectors that may reach the footprint box `lo..hi`.
    #[inline]
    fn under(&self, lo: DVec3, hi: DVec3) -> u64 {
        let (Some((i0, i1)), Some((j0, j1))) = (
            self.range(lo.x, hi.x, self.x0),
            self.range(lo.y, hi.y, self.y0),
        ) else {
            return 0;
        };
        let mut m = 0;
        for j in j0..=j1 {
            for k in i0..=i1 {
                m |= self.masks[j * GRID + k];
            }
        }
        m
    }
}

/// A tile's vectors in the tile's frame `(t1, t2, m)`, `m` their mean direction.
struct TileFrame {
    m: DVec3,
    t1: DVec3,
    t2: DVec3,
    /// Per vector: origin and direction in the frame, `(o·t1, o·t2, o·m)`, `(n·t1, n·t2, n·m)`.
    o: Vec<DVec3>,
    d: Vec<DVec3>,
}

impl TileFrame {
    fn new(vectors: &[Vector]) -> TileFrame {
        let m = vectors
            .iter()
            .fold(DVec3::ZERO, |a, v| a + v.n)
            .try_normalize()
            .unwrap_or(DVec3::Z);
        let t1 = crate::imprint::any_perpendicular(m);
        let t2 = m.cross(t1);
        let to = |p: DVec3| DVec3::new(p.dot(t1), p.dot(t2), p.dot(m));
        TileFrame {
            m,
            t1,
            t2,
            o: vectors.iter().map(|v| to(v.o)).collect(),
            d: vectors.iter().map(|v| to(v.n)).collect(),
        }
    }

    fn to(&self, p: DVec3) -> DVec3 {
        DVec3::new(p.dot(self.t1), p.dot(self.t2), p.dot(self.m))
    }

    /// Bounds, in the frame, of a node's box.
    fn box_bounds(&self, n: &Node) -> (DVec3, DVec3) {
        let axis = |d: DVec3| {
            let (mut a, mut b) = (0.0, 0.0);
            for k in 0..3 {
                let (x, y) = (d[k] * n.min[k] as f64, d[k] * n.max[k] as f64);
                a += x.min(y);
                b += x.max(y);
            }
            (a, b)
        };
        let (x, y, z) = (axis(self.t1), axis(self.t2), axis(self.m));
        pad_box(DVec3::new(x.0, y.0, z.0), DVec3::new(x.1, y.1, z.1))
    }

    /// Bounds, in the frame, of vector `i`'s segment `s ∈ [lo, hi]`.
    fn segment_bounds(&self, i: usize, lo: f64, hi: f64) -> (DVec3, DVec3) {
        let (a, b) = (self.o[i] + lo * self.d[i], self.o[i] + hi * self.d[i]);
        (a.min(b), a.max(b))
    }
}

/// The search of one tile's vectors in one model's hierarchy.
struct TileSearch<'a> {
    margin: f64,
    model: &'a SweepModel,
    bvh: &'a PatchBvh,
    mi: u8,
    vectors: &'a [Vector],
    frame: &'a TileFrame,
    /// Per vector: its live segment's bounds in the tile frame (padded).
    seg: Vec<(DVec3, DVec3)>,
    lanes: Lanes,
    /// World box of the live segments.
    rmin: DVec3,
    rmax: DVec3,
    /// Their extent along the mean direction.
    plo: f64,
    phi: f64,
    dls: Vec<f64>,
    cells: Vec<Cell>,
}

fn pad_box(lo: DVec3, hi: DVec3) -> (DVec3, DVec3) {
    let p = 1e-9 * (1.0 + lo.abs().max(hi.abs()).max_element());
    (lo - DVec3::splat(p), hi + DVec3::splat(p))
}

impl<'a> TileSearch<'a> {
    fn new(
        model: &'a SweepModel,
        bvh: &'a PatchBvh,
        mi: u8,
        vectors: &'a [Vector],
        frame: &'a TileFrame,
        states: &[State],
        margin: f64,
    ) -> TileSearch<'a> {
        let seg: Vec<(DVec3, DVec3)> = (0..vectors.len())
            .map(|i| {
                let (a, b) = frame.segment_bounds(i, vectors[i].lo, states[i].hi);
                pad_box(a, b)
            })
            .collect();
        let lanes = Lanes::new(&seg);
        let mut t = TileSearch {
            margin,
            model,
            bvh,
            mi,
            vectors,
            frame,
            seg,
            lanes,
            rmin: DVec3::ZERO,
            rmax: DVec3::ZERO,
            plo: 0.0,
            phi: 0.0,
            dls: vectors.iter().map(|v| v.n.length()).collect(),
            cells: Vec::with_capacity(64),
        };
        t.update_region(states);
        t
    }

    fn update_region(&mut self, states: &[State]) {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for (v, st) in self.vectors.iter().zip(states) {
            for p in [v.o + v.lo * v.n, v.o + st.hi * v.n] {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        (self.rmin, self.rmax) = pad_box(lo, hi);
        (self.plo, self.phi) = self
            .seg
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), (l, h)| {
                (a.min(l.z), b.max(h.z))
            });
    }

    /// A node box's extent along the mean direction.
    fn span(&self, n: &Node) -> (f64, f64) {
        let m = self.frame.m;
        let (mut a, mut b) = (0.0, 0.0);
        for k in 0..3 {
            let (x, y) = (m[k] * n.min[k] as f64, m[k] * n.max[k] as f64);
            a += x.min(y);
            b += x.max(y);
        }
        (a, b)
    }

    fn node_live(&self, n: &Node) -> bool {
        if !boxes_overlap(&n.min, &n.max, self.rmin, self.rmax) {
            return false;
        }
        let (na, nb) = self.span(n);
        na <= self.phi && nb >= self.plo
    }

    /// Tests the vectors under leaf `ni`'s patches against their triangles; returns true
    /// when some crossing was accepted.
    fn visit_leaf(&mut self, ni: u32, states: &mut [State]) -> bool {
        let node = self.bvh.nodes[ni as usize];
        let mut found = false;
        let mut shrank = false;
        // The node box's extent in the tile frame: no vector under it, no work.
        let (blo, bhi) = self.frame.box_bounds(&node);
        if blo.z > self.phi || bhi.z < self.plo || self.lanes.under(blo, bhi) == 0 {
            return false;
        }
        for patch in &self.bvh.patches[node.first as usize..(node.first + node.count) as usize] {
            self.cells.clear();
            patch.cells(self.model, self.frame, self.margin, &mut self.cells);
            let (mut pl, mut ph) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
            for c in &self.cells {
                pl = pl.min(c.lo);
                ph = ph.max(c.hi);
            }
            if pl.z > self.phi || ph.z < self.plo {
                continue;
            }
            let piece = patch.piece as usize;
            let mut under = self.lanes.under(pl, ph);
            while under != 0 {
                let i = under.trailing_zeros() as usize;
                under &= under - 1;
                let v = &self.vectors[i];
                let (sl, sh) = self.seg[i];
                if sl.x > ph.x
                    || sh.x < pl.x
                    || sl.y > ph.y
                    || sh.y < pl.y
                    || sl.z > ph.z
                    || sh.z < pl.z
                {
                    continue;
                }
                for c in self.cells.iter_mut() {
                    let (sl, sh) = self.seg[i];
                    if sl.x > c.hi.x
                        || sh.x < c.lo.x
                        || sl.y > c.hi.y
                        || sh.y < c.lo.y
                        || sl.z > c.hi.z
                        || sh.z < c.lo.z
                    {
                        continue;
                    }
                    c.prepare(self.model, piece);
                    let st = &mut states[i];
                    for p in c.tris.iter().flatten() {
                        if let Some((s, b1, b2, facing)) =
                            p.entry(v.o, v.n, self.dls[i], v.lo, st.hi, self.margin)
                        {
                            found = true;
                            let cr = Crossing {
                                s,
                                model: self.mi,
                                key: p.key,
                                facing,
                                bary: (b1, b2),
                            };
                            if st.add(cr, v) {
                                shrank = true;
                                let (a, b) = self.frame.segment_bounds(i, v.lo, st.hi);
                                let (old_a, old_b) = self.seg[i];
                                self.seg[i] = pad_box(a, b);
                                self.lanes.set(i, old_a, old_b, false);
                                self.lanes.set(i, self.seg[i].0, self.seg[i].1, true);
                            }
                        }
                    }
                }
            }
        }
        if shrank {
            self.update_region(states);
        }
        found
    }

    /// Visits the leaves in `hot` first (the ones that answered neighbouring tiles: they
    /// shrink the live ranges early), then walks the hierarchy nearest first, skipping
    /// them. Replaces `hot` by the leaves that gave crossings here.
    fn run(&mut self, states: &mut [State], hot: &mut Vec<u32>) {
        if self.bvh.nodes.is_empty() {
            return;
        }
        let mut answered: Vec<u32> = Vec::with_capacity(32);
        for &ni in hot.iter() {
            if self.node_live(&self.bvh.nodes[ni as usize]) && self.visit_leaf(ni, states) {
                answered.push(ni);
            }
        }
        let mut stack: Vec<u32> = Vec::with_capacity(64);
        stack.push(0);
        while let Some(ni) = stack.pop() {
            let node = self.bvh.nodes[ni as usize];
            if !self.node_live(&node) {
                continue;
            }
            if node.count == 0 {
                let (l, r) = (node.first, node.first + 1);
                let kl = self.span(&self.bvh.nodes[l as usize]).0;
                let kr = self.span(&self.bvh.nodes[r as usize]).0;
                if kl <= kr {
                    stack.push(r);
                    stack.push(l);
                } else {
                    stack.push(l);
                    stack.push(r);
                }
                continue;
            }
            if hot.contains(&ni) {
                continue;
            }
            if self.visit_leaf(ni, states) && answered.len() < 32 {
                answered.push(ni);
            }
        }
        *hot = answered;
    }
}

/// Splits Morton-ordered vector indices into tiles of at most [`TILE`] vectors whose
/// normals lie within about 18° of their mean (halving until they do).
fn tiles(order: &[u32], vectors: &[Vector]) -> Vec<std::ops::Range<usize>> {
    fn split(
        order: &[u32],
        vectors: &[Vector],
        lo: usize,
        hi: usize,
        out: &mut Vec<std::ops::Range<usize>>,
    ) {
        let idx = &order[lo..hi];
        let mean = idx
            .iter()
            .fold(DVec3::ZERO, |a, &i| a + vectors[i as usize].n)
            .try_normalize();
        let coherent =
            mean.is_some_and(|m| idx.iter().all(|&i| vectors[i as usize].n.dot(m) >= 0.95));
        if hi - lo <= 1 || (hi - lo <= TILE && coherent) {
            out.push(lo..hi);
            return;
        }
        let mid = if hi - lo > TILE {
            lo + TILE
        } else {
            (lo + hi) / 2
        };
        split(order, vectors, lo, mid, out);
        split(order, vectors, mid, hi, out);
    }
    let mut out = Vec::new();
    let mut lo = 0;
    while lo < order.len() {
        let hi = (lo + TILE).min(order.len());
        split(order, vectors, lo, hi, &mut out);
        lo = hi;
    }
    out
}

/// Searches the given vectors (indices into `vectors`, Morton-ordered) in coherent tiles,
/// each vector's range capped at `cap`; returns each vector's final state.
fn search_all(
    models: &[(&SweepModel, &PatchBvh)],
    vectors: &[Vector],
    order: &[u32],
    delta: f64,
    margin: f64,
    (floor, cap): (f64, f64),
) -> Vec<(u32, Option<Found>)> {
    let tl = tiles(order, vectors);
    // Runs of consecutive tiles are searched in sequence, each tile starting from the leaves
    // that answered the one before; the runs are fixed, so the work (not only the answer,
    // which does not depend on the order) is the same for any number of threads.
    tl.par_chunks(TILES_PER_RUN)
        .map(|run| {
            let mut hot: Vec<Vec<u32>> = vec![Vec::new(); models.len()];
            let mut out = Vec::new();
            let mut states: Vec<State> = Vec::new();
            for range in run {
                let idx = &order[range.clone()];
                let vs: Vec<Vector> = idx
                    .iter()
                    .map(|&i| {
                        let v = vectors[i as usize];
                        Vector {
                            lo: v.lo.max(floor),
                            hi: v.hi.min(cap),
                            ..v
                        }
                    })
                    .collect();
                states.truncate(vs.len());
                for (st, v) in states.iter_mut().zip(&vs) {
                    st.reset(v, delta);
                }
                for v in &vs[states.len()..] {
                    states.push(State::new(v, delta));
                }
                let frame = TileFrame::new(&vs);
                for (mi, (m, b)) in models.iter().enumerate() {
                    TileSearch::new(m, b, mi as u8, &vs, &frame, &states, margin)
                        .run(&mut states, &mut hot[mi]);
                }
                // Complete when the lowest crossing's window lies inside the searched range.
                for ((&i, st), v) in idx.iter().zip(&states).zip(&vs) {
                    let complete = st.best <= cap - delta || v.hi >= vectors[i as usize].hi;
                    out.push((i, complete.then(|| st.finish())));
                }
            }
            out
        })
        .collect::<Vec<_>>()
        .into_iter()
        .flatten()
        .collect()
}

/// Tiles searched in sequence by one task.
const TILES_PER_RUN: usize = 16;

/// First-phase range above the vertex (mm): most vectors' lowest crossing lies below it,
/// and their search then never looks further out.
const NEAR_MM: f64 = 0.3;

/// For every vector, the crossings with the models' swept surfaces (see the module docs),
/// `delta` being the window above the lowest crossing and `margin` (mm) how far outside a
/// triangle a line still counts as crossing it (0: the paper's triangles exactly; the
/// [`PatchBvh`]s must be built with the same margin). Vectors are searched first with their
/// range capped at `NEAR_MM + delta` above the vertex; the answer is complete when the
/// lowest crossing found lies within `NEAR_MM` (its window then lies inside the cap); the
/// other vectors have no crossing below `NEAR_MM` and are searched again from there to the
/// end of their range. Parallel over tiles; the result does not depend on the number of
/// threads.
pub fn locate(
    models: &[(&SweepModel, &PatchBvh)],
    vectors: &[Vector],
    delta: f64,
    margin: f64,
) -> Vec<Found> {
    let codes = morton_codes_by(vectors, |v| v.o);
    let mut keyed: Vec<(u64, u32)> = codes
        .into_iter()
        .enumerate()
        .map(|(i, c)| (c, i as u32))
        .collect();
    crate::radix::sort_by_key(&mut keyed, |k| k.0);
    let order: Vec<u32> = keyed.into_iter().map(|(_, i)| i).collect();
    let mut out = vec![Found::default(); vectors.len()];
    let mut again = Vec::new();
    let first = search_all(
        models,
        vectors,
        &order,
        delta,
        margin,
        (f64::NEG_INFINITY, NEAR_MM + delta),
    );
    for (i, f) in first {
        match f {
            Some(f) => out[i as usize] = f,
            None => again.push(i),
        }
    }
    // The first search held every crossing up to NEAR_MM: there is none, so the second
    // starts there.
    for (i, f) in search_all(
        models,
        vectors,
        &again,
        delta,
        margin,
        (NEAR_MM, f64::INFINITY),
    ) {
        out[i as usize] = f.unwrap_or_default();
    }
    out
}

/// The same as [`locate`] over [`PatchBvh`]s built with `caps`, by brute force: every
/// triangle of every model in one [`TriangleBvh`], every crossing of every vector collected
/// and then selected. For tests.
pub fn locate_reference(
    models: &[&SweepModel],
    vectors: &[Vector],
    delta: f64,
    margin: f64,
    caps: bool,
) -> Vec<Found> {
    let mut tris = Vec::new();
    let mut ids: Vec<(u8, u64)> = Vec::new();
    for (mi, m) in models.iter().enumerate() {
        for i in 0..m.pieces.len() {
            if !caps && matches!(m.pieces[i], Piece::Cap { .. }) {
                continue;
            }
            m.for_each_triangle(i, |k, t| {
                tris.push(t);
                ids.push((mi as u8, k));
            });
        }
    }
    // Boxes that hold each triangle's margin band: the triangle scaled about its incentre by
    // (inradius + margin) / inradius is its (mitred) offset by `margin`, which holds the band.
    let grown: Vec<Triangle> = tris
        .iter()
        .map(|t| {
            if margin == 0.0 {
                return *t;
            }
            let [a, b, c] = t.v;
            let (la, lb, lc) = ((b - c).length(), (c - a).length(), (a - b).length());
            let per = la + lb + lc;
            let area2 = (b - a).cross(c - a).length();
            if !(per > 0.0 && area2 > 0.0) {
                return *t;
            }
            let inc = (la * a + lb * b + lc * c) / per;
            let k = (area2 / per + margin) / (area2 / per);
            Triangle::new(
                inc + k * (a - inc),
                inc + k * (b - inc),
                inc + k * (c - inc),
            )
        })
        .collect();
    let bvh = TriangleBvh::new(&grown);
    vectors
        .par_iter()
        .map(|v| {
            let mut all = Vec::new();
            bvh.segment_hits(v.o, v.n, v.lo, v.hi, |h| all.push(h.triangle));
            let mut st = State::new(v, delta);
            let mut cs: Vec<Crossing> = all
                .into_iter()
                .filter_map(|ti| {
                    let (mi, k) = ids[ti as usize];
                    let (s, b1, b2, facing) =
                        entry_crossing(&tris[ti as usize], v.o, v.n, v.lo, v.hi, margin)?;
                    Some(Crossing {
                        s,
                        model: mi,
                        key: k,
                        facing,
                        bary: (b1, b2),
                    })
                })
                .collect();
            cs.sort_by(|a, b| {
                a.s.total_cmp(&b.s)
                    .then((a.model, a.key).cmp(&(b.model, b.key)))
            });
            for c in cs {
                st.add(c, v);
            }
            st.finish()
        })
        .collect()
}
