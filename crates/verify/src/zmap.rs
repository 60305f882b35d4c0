//! An independent 3-axis material-removal computation: a height map (z-map) swept by the
//! cutter, compared with the design part.
//!
//! This shares no code with the imprint/swept-surface verifier on purpose: it is the truth
//! that verifier (and the planner) are checked against.
//!
//! For a vertical-axis toolpath each move goes straight from tip `A` to tip `B`. A grid node
//! `q` is lowered to the minimum over the move of the cutter's lower surface above it,
//! `f(t) = z(t) + h(|q − tip_xy(t)|)` for `t ∈ [0, 1]` where the node is within the cutter
//! radius `R` ([`Cutter::height_at`] is `h`). The distance is convex in `t` and `h` is convex
//! and non-decreasing, so `f` is convex on that interval (one interval: the disk of radius `R`
//! about `q` meets the line in a segment) and its minimum is found exactly:
//! - ball: closed form, minimiser at horizontal offset `u* = −m·c/√(1+m²)` from the closest
//!   point (`m` = slope of the move, `c = √(R² − ρ²)`, `ρ` = distance of `q` from the line),
//! - flat: the end of the reach interval in the descending direction,
//! - bull: the root of `f'` (in a finite form, no division by zero at the rim) by
//!   safeguarded regula falsi (Illinois, with bisection steps), to
//!   machine precision,
//!
//! then clamped to the reach interval and `[0, 1]`. Pure vertical moves take the lower end.
//! Every move kind is swept, rapids included, so a rapid through the part shows as a gouge.

use cam_core::{Cutter, CutterKind, DVec3, Mesh, Toolpath};
use rayon::prelude::*;

/// A regular XY grid of nodes `(x0 + i·res, y0 + j·res)`, `i < nx`, `j < ny` (mm).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ZmapGrid {
    /// X of node column 0 (mm).
    pub x0_mm: f64,
    /// Y of node row 0 (mm).
    pub y0_mm: f64,
    /// Node spacing (mm).
    pub res_mm: f64,
    /// Number of columns.
    pub nx: usize,
    /// Number of rows.
    pub ny: usize,
}

impl ZmapGrid {
    /// The grid of spacing `res_mm` starting at `(min_x, min_y)` whose nodes cover the
    /// rectangle up to `(max_x, max_y)` (the last node may lie up to one spacing beyond).
    ///
    /// # Errors
    /// [`ZmapError::BadGrid`] for a non-positive spacing, non-finite or inverted bounds, or
    /// more than 2³¹ nodes.
    pub fn covering(
        min_x: f64,
        min_y: f64,
        max_x: f64,
        max_y: f64,
        res_mm: f64,
    ) -> Result<ZmapGrid, ZmapError> {
        let ok = [min_x, min_y, max_x, max_y].iter().all(|v| v.is_finite())
            && max_x >= min_x
            && max_y >= min_y
            && res_mm.is_finite()
            && res_mm > 0.0;
        if !ok {
            return Err(ZmapError::BadGrid {
                why: format!("bounds ({min_x}, {min_y})–({max_x}, {max_y}), spacing {res_mm}"),
            });
        }
        let nx = ((max_x - min_x) / res_mm).ceil() as usize + 1;
        let ny = ((max_y - min_y) / res_mm).ceil() as usize + 1;
        let g = ZmapGrid {
            x0_mm: min_x,
            y0_mm: min_y,
            res_mm,
            nx,
            ny,
        };
        g.validate()?;
        Ok(g)
    }

    fn validate(&self) -> Result<(), ZmapError> {
        let ok = self.x0_mm.is_finite()
            && self.y0_mm.is_finite()
            && self.res_mm.is_finite()
            && self.res_mm > 0.0
            && self.nx > 0
            && self.ny > 0
            && (self.nx as u128) * (self.ny as u128) <= 1 << 31;
        if ok {
            Ok(())
        } else {
            Err(ZmapError::BadGrid {
                why: format!("{self:?}"),
            })
        }
    }

    /// X of column `i` (mm).
    pub fn x(&self, i: usize) -> f64 {
        self.x0_mm + i as f64 * self.res_mm
    }
    /// Y of row `j` (mm).
    pub fn y(&self, j: usize) -> f64 {
        self.y0_mm + j as f64 * self.res_mm
    }
    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.nx * self.ny
    }
    /// True when the grid has no node (never for a validated grid).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Settings of the z-map simulation.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ZmapConfig {
    /// The grid.
    pub grid: ZmapGrid,
    /// Initial height of every node (mm): the stock top, or `+∞` (default) for "no stock".
    pub stock_top_mm: f64,
}

impl ZmapConfig {
    /// A config over `grid` with no stock (initial heights `+∞`).
    pub fn new(grid: ZmapGrid) -> Self {
        ZmapConfig {
            grid,
            stock_top_mm: f64::INFINITY,
        }
    }
}

/// Why a z-map could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ZmapError {
    /// The grid is unusable.
    #[error("bad z-map grid: {why}")]
    BadGrid {
        /// What is wrong.
        why: String,
    },
    /// A move's tool axis is not +Z: the z-map handles 3-axis paths only.
    #[error("move {index} has tool axis {axis:?}; the z-map needs a vertical (+Z) axis")]
    NotVertical {
        /// 0-based move index.
        index: usize,
        /// The axis found.
        axis: DVec3,
    },
    /// A move has a non-finite tip.
    #[error("move {index} has a non-finite tool tip {tip:?}")]
    NonFinite {
        /// 0-based move index.
        index: usize,
        /// The tip found.
        tip: DVec3,
    },
}

/// The machined height map.
#[derive(Debug, Clone, PartialEq)]
pub struct Zmap {
    /// The grid.
    pub grid: ZmapGrid,
    /// Height per node (mm), row-major (`j·nx + i`); the initial height where nothing cut.
    pub heights: Vec<f64>,
    /// Per node, the move (0-based index into `Toolpath::moves`) that cut it lowest, the
    /// smallest index among equals; `None` where no move reached below the initial height.
    pub lowered_by: Vec<Option<u32>>,
}

impl Zmap {
    /// Height at node `(i, j)` (mm).
    pub fn height(&self, i: usize, j: usize) -> f64 {
        self.heights[j * self.grid.nx + i]
    }
}

/// The cutter's lower-surface profile and how to minimise it along a move.
#[derive(Debug, Clone, Copy)]
struct Profile {
    kind: CutterKind,
    big_r: f64,
    a: f64,
    r: f64,
}

impl Profile {
    fn new(c: &Cutter) -> Self {
        Profile {
            kind: c.kind(),
            big_r: c.radius(),
            a: c.major_radius(),
            r: c.corner_radius(),
        }
    }

    /// Height of the lower surface above the tip at radial distance `d` (clamped to `R`).
    fn h(&self, d: f64) -> f64 {
        let d = d.min(self.big_r);
        if d <= self.a {
            0.0
        } else {
            let t = d - self.a;
            self.r - (self.r * self.r - t * t).max(0.0).sqrt()
        }
    }

    /// Minimum over the move `a → b` of the lower surface above `(qx, qy)`, or `None` when
    /// the node is out of reach for the whole move.
    fn move_min(&self, qx: f64, qy: f64, a: DVec3, b: DVec3) -> Option<f64> {
        let (wx, wy) = (qx - a.x, qy - a.y);
        let (dx, dy, dz) = (b.x - a.x, b.y - a.y, b.z - a.z);
        let l2 = dx * dx + dy * dy;
        let rr = self.big_r;
        // The disc is closed: a node exactly on its rim (a side step passing at distance `R`)
        // is reached, though the distance rounds a few ulps above `R`.
        let reach = rr * (1.0 + 8.0 * f64::EPSILON);
        if l2 <= 1e-24 * (1.0 + wx * wx + wy * wy) {
            let d = (wx * wx + wy * wy).sqrt();
            return (d <= reach).then(|| a.z.min(b.z) + self.h(d));
        }
        let l = l2.sqrt();
        let rho = (wx * dy - wy * dx).abs() / l;
        if rho > reach {
            return None;
        }
        let rho = rho.min(rr);
        let tc = (wx * dx + wy * dy) / l2;
        let c = (rr * rr - rho * rho).max(0.0).sqrt();
        let lo = (tc - c / l).max(0.0);
        let hi = (tc + c / l).min(1.0);
        if lo > hi {
            return None;
        }
        let f = |t: f64| {
            let (px, py) = (qx - (a.x + t * dx), qy - (a.y + t * dy));
            a.z + t * dz + self.h((px * px + py * py).sqrt())
        };
        let m = dz / l; // slope: z per horizontal mm
        let t_star = match self.kind {
            CutterKind::Ball => tc + (-m * c / (1.0 + m * m).sqrt()) / l,
            CutterKind::Flat => tc - dz.signum() * c / l,
            CutterKind::Bull => {
                // Sign of f'(t) multiplied by the positive d·sqrt(r² − (d − a)²).
                let g = |t: f64| {
                    let u = (t - tc) * l; // signed horizontal offset from the closest point
                    let d = (rho * rho + u * u).sqrt();
                    if d <= self.a {
                        dz
                    } else {
                        let e = (d - self.a).min(self.r);
                        let s = (self.r * self.r - e * e).max(0.0).sqrt();
                        m * s * d + e * u
                    }
                };
                root_increasing(g, lo, hi)
            }
        };
        let t = t_star.clamp(lo, hi);
        Some(f(t).min(f(lo)).min(f(hi)))
    }
}

/// The root of a non-decreasing `g` on `[lo, hi]` (or the end where it keeps its sign):
/// Illinois regula falsi with a bisection step every fourth iteration, to the resolution of
/// `f64`. Converges superlinearly where `g` is smooth and never leaves the bracket.
fn root_increasing(g: impl Fn(f64) -> f64, lo: f64, hi: f64) -> f64 {
    let (mut a, mut b) = (lo, hi);
    let (mut ga, mut gb) = (g(a), g(b));
    if ga >= 0.0 {
        return a;
    }
    if gb <= 0.0 {
        return b;
    }
    let mut side = 0i8;
    for k in 0..200 {
        let mut t = if k % 4 == 3 {
            0.5 * (a + b)
        } else {
            (a * gb - b * ga) / (gb - ga)
        };
        if !(t > a && t < b) {
            t = 0.5 * (a + b);
            if t <= a || t >= b {
                break;
            }
        }
        let gt = g(t);
        if gt == 0.0 {
            return t;
        }
        if gt > 0.0 {
            b = t;
            gb = gt;
            if side == 1 {
                ga *= 0.5;
            }
            side = 1;
        } else {
            a = t;
            ga = gt;
            if side == -1 {
                gb *= 0.5;
            }
            side = -1;
        }
        if b - a <= 1e-15 * (1.0 + a.abs().max(b.abs())) {
            break;
        }
    }
    if -ga < gb { a } else { b }
}

const BAND_ROWS: usize = 32;

/// The moves of `toolpath` as tip segments (the first move's start is its own pose),
/// checked to be 3-axis and finite.
fn segments(toolpath: &Toolpath) -> Result<Vec<(DVec3, DVec3)>, ZmapError> {
    for (index, mv) in toolpath.moves.iter().enumerate() {
        if (mv.pose.axis - DVec3::Z).length() > 1e-9 {
            return Err(ZmapError::NotVertical {
                index,
                axis: mv.pose.axis,
            });
        }
        if !mv.pose.tip.is_finite() {
            return Err(ZmapError::NonFinite {
                index,
                tip: mv.pose.tip,
            });
        }
    }
    Ok(toolpath
        .moves
        .iter()
        .enumerate()
        .map(|(i, mv)| {
            let a = if i == 0 {
                mv.pose.tip
            } else {
                toolpath.moves[i - 1].pose.tip
            };
            (a, mv.pose.tip)
        })
        .collect())
}

/// Sweeps `cutter` along every move of `toolpath` (rapids included) over the grid of `cfg`.
/// Parallel over rows; the result is identical for any number of threads.
///
/// # Errors
/// [`ZmapError::BadGrid`], [`ZmapError::NotVertical`] (axis differs from +Z by more than
/// 1e-9), [`ZmapError::NonFinite`].
pub fn machine(toolpath: &Toolpath, cutter: &Cutter, cfg: &ZmapConfig) -> Result<Zmap, ZmapError> {
    let g = cfg.grid;
    g.validate()?;
    let segs = segments(toolpath)?;
    let prof = Profile::new(cutter);
    let rr = prof.big_r;
    // Moves per band of rows they may reach, in move order.
    let nbands = g.ny.div_ceil(BAND_ROWS);
    let mut bands: Vec<Vec<u32>> = vec![Vec::new(); nbands];
    let row_of = |y: f64| (y - g.y0_mm) / g.res_mm;
    for (k, (a, b)) in segs.iter().enumerate() {
        let lo = row_of(a.y.min(b.y) - rr).floor().max(0.0);
        let hi = row_of(a.y.max(b.y) + rr).ceil();
        if hi < 0.0 || lo > (g.ny - 1) as f64 {
            continue;
        }
        let (lo, hi) = (lo as usize, (hi as usize).min(g.ny - 1));
        for band in bands
            .iter_mut()
            .take(hi / BAND_ROWS + 1)
            .skip(lo / BAND_ROWS)
        {
            band.push(k as u32);
        }
    }
    let mut heights = vec![cfg.stock_top_mm; g.len()];
    let mut lowered_by = vec![None; g.len()];
    heights
        .par_chunks_mut(g.nx)
        .zip(lowered_by.par_chunks_mut(g.nx))
        .enumerate()
        .for_each(|(j, (hrow, lrow))| {
            let y = g.y(j);
            // Candidates for this row with a lower bound of what they can cut in it: the
            // lowest tip z plus the profile height at the row's distance from the move's
            // y-range. Nearest (lowest-bound) moves first, so later ones are mostly pruned;
            // the result does not depend on the order (ties go to the smaller move index).
            let mut cand: Vec<(f64, u32)> = bands[j / BAND_ROWS]
                .iter()
                .filter_map(|&k| {
                    let (a, b) = segs[k as usize];
                    let dy = (a.y.min(b.y) - y).max(y - a.y.max(b.y)).max(0.0);
                    (dy <= rr).then(|| (a.z.min(b.z) + prof.h(dy), k))
                })
                .collect();
            cand.sort_by(|p, q| p.0.total_cmp(&q.0).then(p.1.cmp(&q.1)));
            for (lb_row, k) in cand {
                let (a, b) = segs[k as usize];
                let (xmin, xmax) = (a.x.min(b.x), a.x.max(b.x));
                let x_lo = ((xmin - rr - g.x0_mm) / g.res_mm).floor().max(0.0);
                let x_hi = ((xmax + rr - g.x0_mm) / g.res_mm).ceil();
                if x_hi < 0.0 || x_lo > (g.nx - 1) as f64 {
                    continue;
                }
                let zlow = a.z.min(b.z);
                let dy = (a.y.min(b.y) - y).max(y - a.y.max(b.y)).max(0.0);
                for i in x_lo as usize..=(x_hi as usize).min(g.nx - 1) {
                    let h_now = hrow[i];
                    if lb_row > h_now {
                        continue;
                    }
                    let x = g.x(i);
                    let dx = (xmin - x).max(x - xmax).max(0.0);
                    let dbox = (dx * dx + dy * dy).sqrt();
                    if dbox > rr || zlow + prof.h(dbox) > h_now {
                        continue;
                    }
                    if let Some(z) = prof.move_min(x, y, a, b)
                        && (z < h_now || (z == h_now && lrow[i].is_some_and(|l| k < l)))
                    {
                        hrow[i] = z;
                        lrow[i] = Some(k);
                    }
                }
            }
        });
    Ok(Zmap {
        grid: g,
        heights,
        lowered_by,
    })
}

/// The machined height at arbitrary points `(x, y)` (mm): for each, the minimum over every
/// move (rapids included) of the cutter's lower surface above it, with the index of the
/// move (the smallest among equals), or `None` where no move reaches. The same per-move
/// minimisation as [`machine`], for points off a grid; moves are bucketed by their XY reach.
/// Parallel over points; independent of the number of threads.
///
/// # Errors
/// [`ZmapError::NotVertical`], [`ZmapError::NonFinite`] as [`machine`].
pub fn heights_at(
    toolpath: &Toolpath,
    cutter: &Cutter,
    points: &[(f64, f64)],
) -> Result<Vec<Option<(f64, u32)>>, ZmapError> {
    let segs = segments(toolpath)?;
    let prof = Profile::new(cutter);
    let rr = prof.big_r;
    if segs.is_empty() {
        return Ok(vec![None; points.len()]);
    }
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for (a, b) in &segs {
        lo = lo.min(a.min(*b));
        hi = hi.max(a.max(*b));
    }
    let cell = rr.max(1e-3);
    let nx = (((hi.x - lo.x + 2.0 * rr) / cell).ceil() as usize).clamp(1, 4096);
    let ny = (((hi.y - lo.y + 2.0 * rr) / cell).ceil() as usize).clamp(1, 4096);
    let (x0, y0) = (lo.x - rr, lo.y - rr);
    let cx = |x: f64| (((x - x0) / cell).floor().max(0.0) as usize).min(nx - 1);
    let cy = |y: f64| (((y - y0) / cell).floor().max(0.0) as usize).min(ny - 1);
    let mut buckets: Vec<Vec<u32>> = vec![Vec::new(); nx * ny];
    for (k, (a, b)) in segs.iter().enumerate() {
        for j in cy(a.y.min(b.y) - rr)..=cy(a.y.max(b.y) + rr) {
            for i in cx(a.x.min(b.x) - rr)..=cx(a.x.max(b.x) + rr) {
                buckets[j * nx + i].push(k as u32);
            }
        }
    }
    Ok(points
        .par_iter()
        .map(|&(x, y)| {
            if x < x0 || y < y0 || x > x0 + nx as f64 * cell || y > y0 + ny as f64 * cell {
                return None;
            }
            let mut best: Option<(f64, u32)> = None;
            for &k in &buckets[cy(y) * nx + cx(x)] {
                let (a, b) = segs[k as usize];
                if let Some(z) = prof.move_min(x, y, a, b)
                    && best.is_none_or(|(bz, bk)| z < bz || (z == bz && k < bk))
                {
                    best = Some((z, k));
                }
            }
            best
        })
        .collect())
}

/// Top-surface heights of a part by exact vertical ray casts, with a 2-D bucket grid over
/// the triangles' XY bounds.
#[derive(Debug, Clone)]
pub struct DesignHeights {
    tris: Vec<cam_core::Triangle>,
    x0: f64,
    y0: f64,
    cell: f64,
    nx: usize,
    ny: usize,
    start: Vec<u32>,
    items: Vec<u32>,
}

impl DesignHeights {
    /// Buckets the part's non-vertical triangles.
    pub fn new(part: &Mesh) -> DesignHeights {
        let tris: Vec<_> = part.triangles().to_vec();
        let b = part.bounds();
        let sx = b.size().x.max(1e-9);
        let sy = b.size().y.max(1e-9);
        // About two triangles per cell on average, at most 4096² cells.
        let target = (tris.len() as f64 / 2.0).max(1.0);
        let cell = ((sx * sy) / target).sqrt().max(sx.max(sy) / 4096.0);
        let nx = (sx / cell).floor() as usize + 1;
        let ny = (sy / cell).floor() as usize + 1;
        let cell_of = |x: f64, y: f64| {
            let i = (((x - b.min.x) / cell).floor().max(0.0) as usize).min(nx - 1);
            let j = (((y - b.min.y) / cell).floor().max(0.0) as usize).min(ny - 1);
            (i, j)
        };
        let mut count = vec![0u32; nx * ny + 1];
        let keep = |t: &cam_core::Triangle| t.cross().z != 0.0;
        let ranges: Vec<_> = tris
            .iter()
            .map(|t| {
                let bb = t.aabb();
                let (i0, j0) = cell_of(bb.min.x, bb.min.y);
                let (i1, j1) = cell_of(bb.max.x, bb.max.y);
                (i0, j0, i1, j1)
            })
            .collect();
        for (t, &(i0, j0, i1, j1)) in tris.iter().zip(&ranges) {
            if !keep(t) {
                continue;
            }
            for j in j0..=j1 {
                for i in i0..=i1 {
                    count[j * nx + i + 1] += 1;
                }
            }
        }
        for k in 0..nx * ny {
            count[k + 1] += count[k];
        }
        let mut fill = count.clone();
        let mut items = vec![0u32; count[nx * ny] as usize];
        for (ti, (t, &(i0, j0, i1, j1))) in tris.iter().zip(&ranges).enumerate() {
            if !keep(t) {
                continue;
            }
            for j in j0..=j1 {
                for i in i0..=i1 {
                    items[fill[j * nx + i] as usize] = ti as u32;
                    fill[j * nx + i] += 1;
                }
            }
        }
        DesignHeights {
            tris,
            x0: b.min.x,
            y0: b.min.y,
            cell,
            nx,
            ny,
            start: count,
            items,
        }
    }

    /// The highest point of the part on the vertical line through `(x, y)` and the triangle
    /// it lies on, or `None` where the part is absent. Points on a shared edge count for
    /// both triangles (inclusive to 1e-12 relative).
    pub fn top(&self, x: f64, y: f64) -> Option<(f64, u32)> {
        let fi = ((x - self.x0) / self.cell).floor();
        let fj = ((y - self.y0) / self.cell).floor();
        if fi < -1.0 || fj < -1.0 || fi > self.nx as f64 || fj > self.ny as f64 {
            return None;
        }
        let i = (fi.max(0.0) as usize).min(self.nx - 1);
        let j = (fj.max(0.0) as usize).min(self.ny - 1);
        let k = j * self.nx + i;
        let mut best: Option<(f64, u32)> = None;
        for &ti in &self.items[self.start[k] as usize..self.start[k + 1] as usize] {
            let [a, b, c] = self.tris[ti as usize].v;
            let det = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
            let wb = ((x - a.x) * (c.y - a.y) - (c.x - a.x) * (y - a.y)) / det;
            let wc = ((b.x - a.x) * (y - a.y) - (x - a.x) * (b.y - a.y)) / det;
            let wa = 1.0 - wb - wc;
            const EPS: f64 = -1e-12;
            if wa < EPS || wb < EPS || wc < EPS {
                continue;
            }
            let z = wa * a.z + wb * b.z + wc * c.z;
            if best.is_none_or(|(bz, bi)| z > bz || (z == bz && ti < bi)) {
                best = Some((z, ti));
            }
        }
        best
    }

    /// The triangles (mm).
    pub fn triangles(&self) -> &[cam_core::Triangle] {
        &self.tris
    }
}

/// The comparison at one node where the part exists and some move cut.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct NodeDeviation {
    /// Column.
    pub i: u32,
    /// Row.
    pub j: u32,
    /// Design top-surface height (mm).
    pub design_z_mm: f64,
    /// Machined height (mm).
    pub machined_z_mm: f64,
    /// `machined − design` (mm): negative = gouge, positive = excess.
    pub vertical_mm: f64,
    /// Z component of the design triangle's unit normal: `vertical_mm · normal_z` is the
    /// deviation along the surface normal to first order.
    pub normal_z: f64,
    /// The move that cut the node lowest.
    pub source_move: u32,
}

/// The z-map against the design part.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ZmapComparison {
    /// Every compared node, row-major order.
    pub nodes: Vec<NodeDeviation>,
    /// Nodes with the part below but no move reaching below the initial height.
    pub unmachined: usize,
    /// Deepest gouge, `max(0, −min vertical)` (mm).
    pub max_gouge_mm: f64,
    /// Where it is (node x, y and design z), if any node was compared.
    pub max_gouge_at: Option<NodeDeviation>,
    /// Largest excess, `max(0, max vertical)` (mm).
    pub max_excess_mm: f64,
    /// Where it is.
    pub max_excess_at: Option<NodeDeviation>,
}

/// Compares the machined heights with the part's top surface at every node above the part.
pub fn compare_with_part(zmap: &Zmap, part: &Mesh) -> ZmapComparison {
    let dh = DesignHeights::new(part);
    compare_with_heights(zmap, &dh)
}

/// As [`compare_with_part`] with the part's heights prepared beforehand.
pub fn compare_with_heights(zmap: &Zmap, dh: &DesignHeights) -> ZmapComparison {
    let g = zmap.grid;
    let rows: Vec<(Vec<NodeDeviation>, usize)> = (0..g.ny)
        .into_par_iter()
        .map(|j| {
            let mut out = Vec::new();
            let mut unmachined = 0;
            for i in 0..g.nx {
                let Some((dz, tri)) = dh.top(g.x(i), g.y(j)) else {
                    continue;
                };
                let k = j * g.nx + i;
                let Some(mv) = zmap.lowered_by[k] else {
                    unmachined += 1;
                    continue;
                };
                let mz = zmap.heights[k];
                let nz = dh.tris[tri as usize].normal().map_or(1.0, |n| n.z.abs());
                out.push(NodeDeviation {
                    i: i as u32,
                    j: j as u32,
                    design_z_mm: dz,
                    machined_z_mm: mz,
                    vertical_mm: mz - dz,
                    normal_z: nz,
                    source_move: mv,
                });
            }
            (out, unmachined)
        })
        .collect();
    let mut nodes = Vec::new();
    let mut unmachined = 0;
    for (r, u) in rows {
        nodes.extend(r);
        unmachined += u;
    }
    let mut gouge: Option<NodeDeviation> = None;
    let mut excess: Option<NodeDeviation> = None;
    for n in &nodes {
        if gouge.is_none_or(|g| n.vertical_mm < g.vertical_mm) {
            gouge = Some(*n);
        }
        if excess.is_none_or(|e| n.vertical_mm > e.vertical_mm) {
            excess = Some(*n);
        }
    }
    ZmapComparison {
        max_gouge_mm: gouge.map_or(0.0, |g| (-g.vertical_mm).max(0.0)),
        max_gouge_at: gouge,
        max_excess_mm: excess.map_or(0.0, |e| e.vertical_mm.max(0.0)),
        max_excess_at: excess,
        nodes,
        unmachined,
    }
}
