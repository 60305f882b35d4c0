//! The drop-cutter: an XY bucket index over the part's triangles for one cutter radius, and
//! the batch drivers.

use cam_core::{Cutter, DVec3, Mesh};
use rayon::prelude::*;

use crate::contact::{self, Hit, Profile};
use crate::{ClPoint, Contact, ContactKind, Grid};

/// Precomputed per-triangle data, stored in descending order of top z.
#[derive(Debug, Clone)]
pub(crate) struct Tri {
    pub(crate) v: [DVec3; 3],
    /// Unit normal turned upwards (n.z ≥ 0).
    pub(crate) n: DVec3,
    /// Highest z of the triangle: no contact with it can put the tip higher.
    pub(crate) top: f64,
    /// XY bounds.
    pub(crate) lo: [f64; 2],
    pub(crate) hi: [f64; 2],
    /// Index in the mesh.
    pub(crate) orig: u32,
    /// Bit k (k < 3): this triangle tests edge k (v[k] → v[k+1]); bit 3 + k: it tests
    /// vertex k. A shared edge or vertex is tested by the first triangle (in descending top
    /// order) that has it, which is never pruned after one that also has it.
    owns: u8,
}

/// Hash of exact vertex coordinates (FxHash-style; keys are bit patterns).
#[derive(Default)]
struct BitsHasher(u64);
impl std::hash::Hasher for BitsHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.write_u64(*b as u64);
        }
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}
type BitsMap<K> = std::collections::HashMap<K, u32, std::hash::BuildHasherDefault<BitsHasher>>;

fn vkey(p: DVec3) -> [u64; 3] {
    // +0.0 and -0.0 are the same point.
    [
        (p.x + 0.0).to_bits(),
        (p.y + 0.0).to_bits(),
        (p.z + 0.0).to_bits(),
    ]
}

/// Marks, for each triangle (already in final order), the edges and vertices it tests.
fn assign_ownership(tris: &mut [Tri]) {
    let mut vid: BitsMap<[u64; 3]> = BitsMap::default();
    vid.reserve(tris.len());
    let ids: Vec<[u32; 3]> = tris
        .iter()
        .map(|t| {
            t.v.map(|p| {
                let n = vid.len() as u32;
                *vid.entry(vkey(p)).or_insert(n)
            })
        })
        .collect();
    drop(vid);
    let nverts = ids
        .iter()
        .flatten()
        .map(|&i| i as usize + 1)
        .max()
        .unwrap_or(0);
    let mut vseen = vec![false; nverts];
    let mut eseen: BitsMap<u64> = BitsMap::default();
    eseen.reserve(tris.len() * 3 / 2);
    for (t, id) in tris.iter_mut().zip(&ids) {
        let mut owns = 0u8;
        for k in 0..3 {
            let (a, b) = (id[k], id[(k + 1) % 3]);
            let key = ((a.min(b) as u64) << 32) | a.max(b) as u64;
            if eseen.insert(key, 0).is_none() {
                owns |= 1 << k;
            }
            if !std::mem::replace(&mut vseen[id[k] as usize], true) {
                owns |= 1 << (3 + k);
            }
        }
        t.owns = owns;
    }
}

/// A part prepared for dropping one cutter: triangles with precomputed data in an XY bucket
/// grid whose cells list every triangle that can come within the cutter radius of a point in
/// the cell, sorted by descending top z, so a query reads one cell and stops as soon as no
/// remaining triangle can raise the cutter.
///
/// # Guarantees
/// Each query is exact (see the crate docs) and independent of every other, so batch results
/// are bit-for-bit identical for any number of threads.
///
/// # Performance
/// Building is O(n log n + n·k) for n triangles each listed in k cells (k ≈ 10–30); a query
/// scans one cell's list from the top and usually stops after a few triangles.
#[derive(Debug, Clone)]
pub struct DropCutter {
    cutter: Cutter,
    pub(crate) pf: Profile,
    pub(crate) tris: Vec<Tri>,
    /// Slot in `tris` of each mesh triangle.
    pub(crate) slot_of: Vec<u32>,
    /// Cell grid origin, cell size and counts.
    pub(crate) ox: f64,
    pub(crate) oy: f64,
    pub(crate) cell: f64,
    pub(crate) nx: usize,
    pub(crate) ny: usize,
    /// CSR: items[start[c]..start[c+1]] are the triangle slots of cell c (ascending slot =
    /// descending top z).
    pub(crate) start: Vec<u32>,
    pub(crate) items: Vec<u32>,
}

/// Points dropped in sequence (sharing pruning floors) per parallel task.
const RUN: usize = 128;
/// Rounding margin (mm) below a neighbour's contact when it is used as a pruning floor.
const FLOOR_MARGIN: f64 = 1e-9;

/// Upper bound on the number of index cells (memory guard for tiny tools on huge parts).
const MAX_CELLS: f64 = 4.0e6;
/// Upper bound on the cell lists' total length, unless the triangles themselves need more
/// ([`ITEMS_PER_TRIANGLE`] each): long sliver triangles listed in every cell they span
/// would otherwise take gigabytes.
const MAX_ITEMS: u64 = 1 << 26;
/// Cell-list entries allowed per triangle on top of [`MAX_ITEMS`].
const ITEMS_PER_TRIANGLE: u64 = 8;

/// The XY bucket grid: cells of `cell` mm, `nx` × `ny` from the origin, and the CSR lists.
struct CellGrid {
    cell: f64,
    nx: usize,
    ny: usize,
    start: Vec<u32>,
    items: Vec<u32>,
}

impl CellGrid {
    /// Lists each triangle (by slot) in every cell within `big_r` of its XY box. Cells of
    /// half the cutter radius, grown until the grid has at most [`MAX_CELLS`] cells and the
    /// lists at most [`MAX_ITEMS`] entries (or [`ITEMS_PER_TRIANGLE`] per triangle): bounded
    /// memory for any part, however large or thin its triangles.
    fn build(tris: &[Tri], (ox, oy): (f64, f64), (w, h): (f64, f64), big_r: f64) -> CellGrid {
        let dims = |c: f64| {
            let n = |len: f64| ((len / c).floor() + 1.0).max(1.0);
            (n(w), n(h))
        };
        let fits = |c: f64| {
            let (fx, fy) = dims(c);
            fx * fy <= MAX_CELLS
        };
        let mut cell = 0.5 * big_r;
        if !fits(cell) {
            // The area's share, and no side longer than the whole budget.
            let even = w.sqrt() * h.sqrt() / MAX_CELLS.sqrt();
            cell = even.max(w / MAX_CELLS).max(h / MAX_CELLS).max(cell);
            for _ in 0..200 {
                if fits(cell) {
                    break;
                }
                cell *= 1.25;
            }
        }
        let budget = MAX_ITEMS.max(ITEMS_PER_TRIANGLE * tris.len() as u64);
        let (mut nx, mut ny);
        loop {
            let (fx, fy) = dims(cell);
            (nx, ny) = (fx as usize, fy as usize);
            let total: u64 = tris
                .iter()
                .map(|t| {
                    let (x0, x1, y0, y1) = span(t, (ox, oy), cell, (nx, ny), big_r);
                    ((x1 - x0 + 1) * (y1 - y0 + 1)) as u64
                })
                .sum();
            // Once the whole part fits a cell, coarser cells cannot shorten the lists.
            if total <= budget || (nx <= 2 && ny <= 2) {
                break;
            }
            cell *= 2.0;
        }
        let mut count = vec![0u32; nx * ny + 1];
        for t in tris {
            let (x0, x1, y0, y1) = span(t, (ox, oy), cell, (nx, ny), big_r);
            for j in y0..=y1 {
                for i in x0..=x1 {
                    count[j * nx + i + 1] += 1;
                }
            }
        }
        for k in 1..count.len() {
            count[k] += count[k - 1];
        }
        let start = count;
        let mut fill = start.clone();
        let mut items = vec![0u32; start[nx * ny] as usize];
        for (slot, t) in tris.iter().enumerate() {
            let (x0, x1, y0, y1) = span(t, (ox, oy), cell, (nx, ny), big_r);
            for j in y0..=y1 {
                for i in x0..=x1 {
                    let c = j * nx + i;
                    items[fill[c] as usize] = slot as u32;
                    fill[c] += 1;
                }
            }
        }
        CellGrid {
            cell,
            nx,
            ny,
            start,
            items,
        }
    }
}

/// The cells `(x0, x1, y0, y1)` (inclusive) within `big_r` of a triangle's XY box.
fn span(
    t: &Tri,
    (ox, oy): (f64, f64),
    cell: f64,
    (nx, ny): (usize, usize),
    big_r: f64,
) -> (usize, usize, usize, usize) {
    let c = |v: f64, o: f64, n: usize| (((v - o) / cell).floor().max(0.0) as usize).min(n - 1);
    (
        c(t.lo[0] - big_r, ox, nx),
        c(t.hi[0] + big_r, ox, nx),
        c(t.lo[1] - big_r, oy, ny),
        c(t.hi[1] + big_r, oy, ny),
    )
}

impl DropCutter {
    /// Prepares `mesh` for dropping `cutter` (axis +Z).
    pub fn new(mesh: &Mesh, cutter: Cutter) -> DropCutter {
        let pf = Profile::new(&cutter);
        let big_r = pf.big_r;
        let mut tris: Vec<Tri> = mesh
            .triangles()
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let n = t.normal().unwrap_or(DVec3::Z);
                let n = if n.z < 0.0 { -n } else { n };
                let [a, b, c] = t.v;
                Tri {
                    v: t.v,
                    n,
                    top: a.z.max(b.z).max(c.z),
                    lo: [a.x.min(b.x).min(c.x), a.y.min(b.y).min(c.y)],
                    hi: [a.x.max(b.x).max(c.x), a.y.max(b.y).max(c.y)],
                    orig: i as u32,
                    owns: 0,
                }
            })
            .collect();
        // Descending top z; ties by mesh order so the layout is deterministic.
        tris.sort_by(|p, q| q.top.total_cmp(&p.top).then(p.orig.cmp(&q.orig)));
        assign_ownership(&mut tris);
        let mut slot_of = vec![0u32; tris.len()];
        for (slot, t) in tris.iter().enumerate() {
            slot_of[t.orig as usize] = slot as u32;
        }

        let b = mesh.bounds();
        let (ox, oy) = (b.min.x - big_r, b.min.y - big_r);
        let (w, h) = (b.size().x + 2.0 * big_r, b.size().y + 2.0 * big_r);
        let CellGrid {
            cell,
            nx,
            ny,
            start,
            items,
        } = CellGrid::build(&tris, (ox, oy), (w, h), big_r);
        DropCutter {
            cutter,
            pf,
            tris,
            slot_of,
            ox,
            oy,
            cell,
            nx,
            ny,
            start,
            items,
        }
    }

    /// The cutter.
    pub fn cutter(&self) -> Cutter {
        self.cutter
    }

    /// Tool-tip z (mm) at `(x, y)`: the lowest tip height at which the cutter touches the
    /// part without penetrating any triangle, or `None` if no triangle comes within the
    /// cutter radius.
    pub fn drop(&self, x: f64, y: f64) -> Option<f64> {
        self.contact(x, y).map(|c| c.z_tip)
    }

    /// Like [`DropCutter::drop`] but also says where and how the cutter touches.
    pub fn contact(&self, x: f64, y: f64) -> Option<Contact> {
        self.contact_above(x, y, f64::NEG_INFINITY)
    }

    /// The exact contact, skipping features that cannot reach `floor`. `floor` must not
    /// exceed the true tip height (callers pass a proven lower bound minus a rounding
    /// margin); the result is then bit-for-bit the same as [`DropCutter::contact`].
    pub(crate) fn contact_above(&self, x: f64, y: f64, floor: f64) -> Option<Contact> {
        if !(x.is_finite() && y.is_finite()) {
            return None;
        }
        let fi = ((x - self.ox) / self.cell).floor();
        let fj = ((y - self.oy) / self.cell).floor();
        if fi < 0.0 || fj < 0.0 || fi >= self.nx as f64 || fj >= self.ny as f64 {
            return None;
        }
        let c = fj as usize * self.nx + fi as usize;
        let slots = &self.items[self.start[c] as usize..self.start[c + 1] as usize];
        let pf = &self.pf;
        let mut best = f64::NEG_INFINITY;
        let mut found: Option<(Hit, ContactKind, u32)> = None;
        let mut take = |hit: Option<Hit>, kind: ContactKind, t: &Tri, best: &mut f64| {
            if let Some(h) = hit.filter(|h| h.0 > *best) {
                *best = h.0;
                found = Some((h, kind, t.orig));
            }
        };
        for &s in slots {
            let t = &self.tris[s as usize];
            // Sorted by descending top: nothing below can raise the cutter.
            if t.top <= best || t.top < floor {
                break;
            }
            let dx = (t.lo[0] - x).max(x - t.hi[0]).max(0.0);
            let dy = (t.lo[1] - y).max(y - t.hi[1]).max(0.0);
            let d2 = dx * dx + dy * dy;
            if d2 > pf.big_r2 {
                continue;
            }
            // Every point of the triangle is at least d from the axis and no higher than
            // its top, and h never decreases: the contact cannot beat top - h(d).
            let prune = best.max(floor);
            if d2 > 0.0 && t.top - pf.height(d2.sqrt()) <= prune {
                continue;
            }
            // The cutter resting on the triangle's plane stands at least as high as on any
            // part of it (facet, edges, vertices): nothing here can beat that. Worth its cost
            // for a bull, whose edge contacts are iterative.
            if pf.a > 0.0
                && pf.r > 0.0
                && t.n.z > 1e-12
                && contact::plane_tip(pf, x, y, t.v[0], t.n) <= prune
            {
                continue;
            }
            for (k, &p) in t.v.iter().enumerate() {
                if t.owns & (8 << k) != 0 && p.z > best && p.z >= floor {
                    take(
                        contact::vertex(pf, x, y, p),
                        ContactKind::Vertex,
                        t,
                        &mut best,
                    );
                }
            }
            if t.n.z > 1e-12 {
                take(
                    contact::facet(pf, x, y, &t.v, t.n),
                    ContactKind::Facet,
                    t,
                    &mut best,
                );
            }
            for k in 0..3 {
                if t.owns & (1 << k) != 0 {
                    let (p1, p2) = (t.v[k], t.v[(k + 1) % 3]);
                    let hit = contact::edge(pf, x, y, p1, p2, prune.max(best));
                    take(hit, ContactKind::Edge, t, &mut best);
                }
            }
        }
        found.map(|((z_tip, cc), kind, triangle)| Contact {
            z_tip,
            cc,
            kind,
            triangle,
        })
    }

    /// Drops along a sequence, using each contact point as a pruning floor for the next.
    fn drop_run(&self, xy: impl Iterator<Item = (f64, f64)>, out: &mut [ClPoint]) {
        let mut prev: Option<DVec3> = None;
        for ((x, y), slot) in xy.zip(out.iter_mut()) {
            let c = self.contact_hinted(x, y, prev.as_slice());
            prev = c.map(|c| c.cc).or(prev);
            *slot = ClPoint {
                x,
                y,
                z_tip: c.map(|c| c.z_tip),
            };
        }
    }

    /// Like [`DropCutter::contact`], faster when `hints` holds points of the part near the
    /// contact (e.g. a neighbouring query's contact point): the cutter resting on a hint is
    /// a proven lower bound that prunes the search. The result is bit-for-bit the same as
    /// [`DropCutter::contact`] whatever the hints, as long as they are points of the part
    /// (contact points returned by this index are).
    pub fn contact_hinted(&self, x: f64, y: f64, hints: &[DVec3]) -> Option<Contact> {
        let floor = hints
            .iter()
            .filter_map(|&cc| contact::vertex(&self.pf, x, y, cc))
            .map(|(z, _)| z - FLOOR_MARGIN)
            .fold(f64::NEG_INFINITY, f64::max);
        self.contact_above(x, y, floor)
    }

    /// Contacts at every `(x, y)` in order, in parallel runs in which each contact point
    /// prunes the next query (so points along a line are cheap); identical for any thread
    /// count and to [`DropCutter::contact`] point by point.
    pub fn contact_points(&self, xy: &[(f64, f64)]) -> Vec<Option<Contact>> {
        let mut out = vec![None; xy.len()];
        out.par_chunks_mut(RUN)
            .zip(xy.par_chunks(RUN))
            .for_each(|(o, p)| {
                let mut prev: Option<DVec3> = None;
                for (&(x, y), slot) in p.iter().zip(o.iter_mut()) {
                    let c = self.contact_hinted(x, y, prev.as_slice());
                    prev = c.map(|c| c.cc).or(prev);
                    *slot = c;
                }
            });
        out
    }

    /// Drops at every `(x, y)` in order, in parallel; identical for any thread count (and
    /// to dropping each point alone with [`DropCutter::drop`]).
    pub fn drop_points(&self, xy: &[(f64, f64)]) -> Vec<ClPoint> {
        let mut out = vec![
            ClPoint {
                x: 0.0,
                y: 0.0,
                z_tip: None
            };
            xy.len()
        ];
        out.par_chunks_mut(RUN)
            .zip(xy.par_chunks(RUN))
            .for_each(|(o, p)| {
                self.drop_run(p.iter().copied(), o);
            });
        out
    }

    /// Drops over a grid, in parallel by rows, in row-major order; identical for any thread
    /// count.
    pub fn drop_grid(&self, grid: &Grid) -> Vec<ClPoint> {
        let mut out = vec![
            ClPoint {
                x: 0.0,
                y: 0.0,
                z_tip: None
            };
            grid.len()
        ];
        if grid.nx == 0 {
            return out;
        }
        out.par_chunks_mut(grid.nx)
            .enumerate()
            .for_each(|(j, row)| {
                self.drop_run((0..grid.nx).map(|i| grid.xy(j * grid.nx + i)), row);
            });
        out
    }

    /// Approximate heap bytes held by the index (triangle data and cell lists).
    pub fn heap_bytes(&self) -> usize {
        self.tris.len() * std::mem::size_of::<Tri>() + (self.start.len() + self.items.len()) * 4
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cam_core::{Mesh, Triangle};

    fn mesh(tris: Vec<Triangle>) -> Mesh {
        Mesh::from_triangles(tris, "<memory>").expect("mesh")
    }

    /// The drop over every triangle alone, maximised: the index must not lose any.
    fn brute(dc: &DropCutter, x: f64, y: f64, n: usize) -> Option<f64> {
        (0..n as u32)
            .filter_map(|t| dc.triangle_drop(t, x, y))
            .max_by(f64::total_cmp)
    }

    /// A fan of long sliver triangles, each spanning the whole part (found by fuzzing: 1100
    /// of them overflowed the u32 cell lists, 300 took 4.7 GB): the lists stay within their
    /// budget, and the drops still see every triangle.
    #[test]
    fn sliver_fans_keep_the_cell_lists_bounded_and_exact() {
        let n = 1100;
        let tris: Vec<Triangle> = (0..n)
            .map(|i| {
                Triangle::new(
                    DVec3::ZERO,
                    DVec3::new(3000.0, 3000.0, 0.0),
                    DVec3::new(3000.0, i as f64 * 0.001, (i % 7) as f64),
                )
            })
            .collect();
        let dc = DropCutter::new(&mesh(tris), "ball:6".parse().unwrap());
        let budget = MAX_ITEMS.max(ITEMS_PER_TRIANGLE * n as u64);
        assert!(
            dc.items.len() as u64 <= budget,
            "{} entries",
            dc.items.len()
        );
        assert!((dc.nx * dc.ny) as f64 <= MAX_CELLS);
        for (x, y) in [(1500.0, 1.0), (2999.0, 0.3), (2000.0, 1500.0), (10.0, 0.0)] {
            assert_eq!(dc.drop(x, y), brute(&dc, x, y, n), "at ({x}, {y})");
        }
    }

    /// A part 2 km long (the widest the mesh validation admits) and a millimetre wide: the
    /// grid's cell count is bounded with its extra row and column counted. The old guard
    /// bounded only the area's share and made 1 069 047 x 4 = 4.28M cells here.
    #[test]
    fn long_thin_parts_keep_the_grid_bounded() {
        let tris = vec![
            Triangle::new(
                DVec3::new(-1.0e6, 0.0, 0.0),
                DVec3::new(1.0e6, 0.0, 0.0),
                DVec3::new(-1.0e6, 0.0, 1000.0),
            ),
            Triangle::new(
                DVec3::new(-1.0e6, 1.0, 0.0),
                DVec3::new(1.0e6, 1.0, 5.0),
                DVec3::new(1.0e6, 0.0, 5.0),
            ),
        ];
        let dc = DropCutter::new(&mesh(tris), "ball:6".parse().unwrap());
        assert!((dc.nx * dc.ny) as f64 <= MAX_CELLS, "{} x {}", dc.nx, dc.ny);
        for x in [-999_999.0, 0.5, 12345.6, 999_999.0] {
            assert_eq!(dc.drop(x, 0.5), brute(&dc, x, 0.5, 2), "at x = {x}");
        }
    }
}
