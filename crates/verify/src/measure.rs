//! The normal-vector deviation against swept-surface models: locate crossings on the
//! piecewise-linear imprint surface ([`crate::locate`]), then, for the [`SurfaceModel::Exact`]
//! surface, refine them onto the exact swept volume ([`crate::exact`]).
//!
//! # Why refine, and which crossings
//! The imprint surface joins exact points by chords, so it lies inside the swept volume by
//! up to the chord sag (`r(1 − cos π/Q)` across a ball's groove, 9.25 µm at Q = 40; more for
//! a bull's long chords along its rim). A vector meets it that much (divided by the cosine
//! of its incidence) beyond the true surface, and near a sheet's curved edge it can enter
//! the true sheet and miss the chords: strip triangles are located with a margin of twice
//! the sag ([`edge_margin`]). Refinement solves for the true entry near each crossing. Where
//! two sheets cross (the crest between passes) the lowest triangle may not belong to the
//! lowest true sheet, so every crossing `c` with `s_c ≤ s_min + δ_c` is a candidate,
//! `δ_c = 4·sag / max(|facing_c|, 0.2)` with `sag` the tool's chord sag (the largest
//! window, [`window`], for a step ending at a pose that joins two moves, where the true
//! surface holds the tool at that pose); candidates are refined lowest first, skipping those
//! whose window cannot reach below the best entry found, and the lowest entry wins.
//!
//! # What a refined value means
//! Every refined entry is a point where the vector enters the cutter at some pose of the
//! path, so it is never below the true first entry; for the move searched it is exact (see
//! [`crate::exact`]). Where no crossing of a vector can be refined, its lowest crossing on the
//! imprint surface is kept and counted in [`MeasureStats::kept_linear`].

use cam_core::{DVec3, Toolpath};
use rayon::prelude::*;

use crate::deviation::{Deviation, DeviationConfig, DeviationError, Facing};
use crate::exact::{BodyFrame, Entry, Line, MoveGeometry, Puck, across, from_segment, inv_or_zero};
use crate::locate::{Crossing, PatchBvh, Vector, locate};
use crate::model::{Piece, SweepModel, unkey};
use crate::refine::RefinedMesh;

/// Which swept surface the deviations are measured against.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum SurfaceModel {
    /// The paper's piecewise-linear imprint surface (triangles between imprint points).
    Linear,
    /// Crossings refined onto the exact swept volume (default).
    Exact,
}

/// Counts of what the measurement did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct MeasureStats {
    /// Vectors with at least one crossing.
    pub crossed: usize,
    /// Crossings refined (after removing duplicates of one move or piece).
    pub refinements: usize,
    /// Vectors whose value is a refined entry.
    pub refined: usize,
    /// Vectors whose crossings could not be refined: their linear value is kept.
    pub kept_linear: usize,
    /// Vectors with more qualifying crossings than kept.
    pub overflow: usize,
}

/// The measurement.
#[derive(Debug, Clone)]
pub struct Measurement {
    /// Per refined vertex, in vertex order.
    pub deviations: Vec<Deviation>,
    /// Per vertex: the outward normal of the swept surface at the answer dotted with the
    /// vector (`< 0`), or 0 where nothing was crossed.
    pub facing: Vec<f64>,
    /// Per vertex: the lowest crossing of the piecewise-linear surface (mm).
    pub linear_mm: Vec<Option<f64>>,
    /// Per vertex: what gave the answer (for the depth at creases).
    pub source: Vec<Option<Source>>,
    /// Per vertex: the answer is the vector's start, which lies inside the cutter: the
    /// vertex is gouged at least as deep as the vector reaches.
    pub from_start: Vec<bool>,
    /// What was done.
    pub stats: MeasureStats,
}

/// What a measured value is the entry into.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// The volume swept along toolpath move `mv` (index into `Toolpath::moves`).
    Move(u32),
    /// The tool at one pose: frame `frame` of model `model`.
    Pose {
        /// Index of the model in the slice measured.
        model: u8,
        /// Frame index in that model.
        frame: u32,
    },
}

/// How deep (mm) `p` lies inside the puck swept by `source` (along a move, or the tool at a
/// pose): `r` minus the distance to the swept disk ([`MoveGeometry::depth_at`], exact for a
/// translation); 0 when outside.
pub fn depth_inside(models: &[&SweepModel], toolpath: &Toolpath, source: Source, p: DVec3) -> f64 {
    source_geometry(models, toolpath, source).map_or(0.0, |g| g.depth_at(p))
}

/// How deep (mm) `p` lies inside the whole cutter swept by `source`, puck or column
/// ([`MoveGeometry::cutter_depth_at`]: in the column, a lower bound); 0 when outside.
pub fn cutter_depth_inside(
    models: &[&SweepModel],
    toolpath: &Toolpath,
    source: Source,
    p: DVec3,
) -> f64 {
    source_geometry(models, toolpath, source).map_or(0.0, |g| g.cutter_depth_at(p))
}

/// The move (or the one pose) that `source` names.
fn source_geometry(
    models: &[&SweepModel],
    toolpath: &Toolpath,
    source: Source,
) -> Option<MoveGeometry> {
    let first = models.first()?;
    let puck = Puck::of(first.cutter());
    let g = match source {
        Source::Move(mv) => {
            let i = mv as usize;
            if i == 0 || i >= toolpath.moves.len() {
                return None;
            }
            MoveGeometry {
                a: toolpath.moves[i - 1].pose,
                b: toolpath.moves[i].pose,
                puck,
            }
        }
        Source::Pose { model, frame } => {
            let f = models
                .get(model as usize)
                .and_then(|m| m.frames.get(frame as usize))?;
            let pose = cam_core::Pose {
                tip: f.tip(puck.r),
                axis: f.axis,
            };
            MoveGeometry {
                a: pose,
                b: pose,
                puck,
            }
        }
    };
    Some(g)
}

/// What a measurement lays out from the program alone, before any vector: the moves' trees
/// (their columns; for the direct search of a program of translations their volumes and a
/// ball's runs, with the lists every group of vectors copies from; otherwise the pucks and
/// the imprint surface's caps and gaps). Laid out for the vectors within a box: [`layout`]
/// builds it ahead (beside the refinement, in [`crate::pipeline`]), and a measurement
/// whose vectors leave that box lays out its own.
pub struct Layout<'a> {
    models: &'a [&'a SweepModel],
    toolpath: &'a Toolpath,
    reach: (DVec3, DVec3),
    surface: SurfaceModel,
    locator: Locator,
    extras: Option<Extras>,
    columns: Extras,
    pucks: Extras,
    volumes: Extras,
    runs: Option<crate::chains::Runs>,
    run_tree: Extras,
    run_lay: Vec<RunListed>,
    member_lay: Vec<Listed>,
    column_lay: Vec<Option<ColumnListed>>,
    puck_lay: Vec<PuckListed>,
}

/// The layout of `toolpath`'s moves (swept as `models`) for measuring `surface` with the
/// fast locator, for vectors that lie in the box `reach` (mm; both their ends). See
/// [`Layout`] and [`measure_then`].
pub fn layout<'a>(
    models: &'a [&'a SweepModel],
    toolpath: &'a Toolpath,
    surface: SurfaceModel,
    reach: (DVec3, DVec3),
) -> Layout<'a> {
    Layout::new(models, toolpath, surface, Locator::Fast, reach)
}

impl<'a> Layout<'a> {
    fn new(
        models: &'a [&'a SweepModel],
        toolpath: &'a Toolpath,
        surface: SurfaceModel,
        locator: Locator,
        reach: (DVec3, DVec3),
    ) -> Layout<'a> {
        let exact = surface == SurfaceModel::Exact;
        let direct = exact && locator == Locator::Fast && keeps_axes(toolpath);
        let puck = models
            .first()
            .map_or(Puck { a: 0.0, r: 0.0 }, |m| Puck::of(m.cutter()));
        let rr = puck.a + puck.r;
        let ball = puck.a == 0.0;
        let bull = puck.a > 0.0 && puck.r > 0.0;
        let none = || Extras::from_items(Vec::new(), Vec::new(), 0.0);
        // Independent trees: built side by side; a ball's moves in runs too (see
        // `BallRuns`), after its volumes.
        let ((columns, (pucks, extras)), (volumes, ball_runs)) = rayon::join(
            || {
                rayon::join(
                    || Extras::columns(models, toolpath, reach),
                    // The direct search enters each move's puck itself (`direct_one`).
                    || {
                        if direct {
                            (none(), None)
                        } else {
                            (
                                Extras::pucks(models, toolpath),
                                exact.then(|| Extras::new(models)),
                            )
                        }
                    },
                )
            },
            || {
                if direct {
                    let volumes = Extras::volumes(toolpath, puck, !ball);
                    let runs = ball.then(|| BallRuns::of(&volumes, rr));
                    (volumes, runs)
                } else {
                    (none(), None)
                }
            },
        );
        let (runs, run_tree, run_lay, member_lay) = match ball_runs {
            Some(b) => (Some(b.runs), b.tree, b.lay, b.members),
            None => (None, none(), Vec::new(), Vec::new()),
        };
        // Each column laid out once for every group that lists it (by item; `None` for a
        // rotating move's), and a bull's moves likewise.
        let column_lay: Vec<Option<ColumnListed>> = if direct {
            (0..columns.items.len() as u32)
                .into_par_iter()
                .map(|ci| ColumnListed::of(&columns, ci, toolpath))
                .collect()
        } else {
            Vec::new()
        };
        let puck_lay: Vec<PuckListed> = if direct && bull {
            (0..volumes.items.len() as u32)
                .into_par_iter()
                .map(|ci| {
                    let mv = volumes.items[ci as usize].1;
                    PuckListed::of(&volumes, ci, rr, toolpath.moves[mv as usize].pose.axis)
                })
                .collect()
        } else {
            Vec::new()
        };
        Layout {
            models,
            toolpath,
            reach,
            surface,
            locator,
            extras,
            columns,
            pucks,
            volumes,
            runs,
            run_tree,
            run_lay,
            member_lay,
            column_lay,
            puck_lay,
        }
    }

    /// Whether this layout serves a search of `toolpath` (swept as `models`) on `surface` by
    /// `locator` for vectors in `reach`.
    fn serves(
        &self,
        models: &[&SweepModel],
        toolpath: &Toolpath,
        surface: SurfaceModel,
        locator: Locator,
        reach: (DVec3, DVec3),
    ) -> bool {
        std::ptr::eq(self.toolpath, toolpath)
            && self.models.len() == models.len()
            && self
                .models
                .iter()
                .zip(models)
                .all(|(a, b)| std::ptr::eq(*a, *b))
            && self.surface == surface
            && self.locator == locator
            && (reach.0.cmpgt(reach.1).any()
                || (reach.0.cmpge(self.reach.0).all() && reach.1.cmple(self.reach.1).all()))
    }
}

/// Progress callback: `(vectors done, vectors in all)`; called between chunks.
pub type Progress<'a> = &'a (dyn Fn(usize, usize) + Sync);

/// How deep (mm) a reading may lie inside a rotating move's swept puck and still stand
/// (rounding of the Newton solve and the pose search); deeper, that move is searched below
/// it.
const INSIDE_MM: f64 = 1e-9;

/// Vectors located and refined per chunk (progress is reported between chunks), where the
/// swept surface is located.
const MEASURE_CHUNK: usize = 1 << 17;

/// The most vectors the direct search takes at once, in chunks of equal size (progress is
/// reported per tile): its tiles' readings for a chunk are held until they are put back in
/// order, some 64 bytes a vector.
const DIRECT_CHUNK: usize = 1 << 20;

/// The interval of `s` where `line` lies within `r` of the range between `z0` and `z1` along
/// the unit `k` (unbounded when the line runs across `k` inside it), if any.
fn slab_interval(line: &Line, k: DVec3, z0: f64, z1: f64, r: f64) -> Option<(f64, f64)> {
    slab_interval_at((line.o.dot(k), line.n.dot(k)), z0, z1, r)
}

/// [`slab_interval`] for the line's origin and direction seen along `k`: `(o·k, n·k)`.
#[inline]
fn slab_interval_at((q, nk): (f64, f64), z0: f64, z1: f64, r: f64) -> Option<(f64, f64)> {
    let (lo, hi) = (z0.min(z1) - r, z0.max(z1) + r);
    if nk == 0.0 {
        return (lo..=hi)
            .contains(&q)
            .then_some((f64::NEG_INFINITY, f64::INFINITY));
    }
    let (a, b) = ((lo - q) / nk, (hi - q) / nk);
    Some((a.min(b), a.max(b)))
}

/// Whether the segment `lo..hi` of `line` passes within `rr` of a segment by the bounding
/// sphere of that segment's capsule (a cheap necessary test); `(m, half)` is the segment's
/// middle and half its length ([`Extras::mids`]).
fn near_capsule(line: &Line, hi: f64, (m, half): (DVec3, f64), rr: f64) -> bool {
    meets_sphere(line, hi, m, sphere_rho2(half, rr))
}

/// The squared radius of a capsule's bounding sphere (a segment of half length `half`,
/// radius `rr`), with an allowance for rounding.
#[inline]
fn sphere_rho2(half: f64, rr: f64) -> f64 {
    let rho = half + rr;
    rho * rho * (1.0 + 1e-12)
}

/// Whether the segment `lo..hi` of `line` meets the sphere about `m` of squared radius
/// `rho2`.
#[inline]
fn meets_sphere(line: &Line, hi: f64, m: DVec3, rho2: f64) -> bool {
    let t = (m - line.o).dot(line.n).clamp(line.lo, hi);
    (line.o + t * line.n).distance_squared(m) <= rho2
}

/// The top tests' decision (see [`misses_capsule_at_top`]) from `w`, the offset of the
/// segment's top from the nearest point of a convex set: the distance still falls towards
/// the top along `n`, and is more than `√rr2` there but for a relative margin of 1e-6 in
/// the squared distance.
#[inline]
fn clear_at_top(w: DVec3, n: DVec3, rr2: f64) -> bool {
    w.dot(n) <= 0.0 && w.length_squared() > rr2 * (1.0 + 1e-6)
}

/// Whether the line from `q` along `m` provably stays farther than `√rr2` from every point
/// of the box `lo..=hi`, as [`clear_at_top`] decides for one convex set: no point of the box
/// lies ahead of `q` along `m` (so the distance from each convex set in it only grows along
/// `m`), and the box lies farther than `√rr2` from `q` (with the same margin).
#[inline]
fn clear_of_box(q: DVec3, m: DVec3, lo: DVec3, hi: DVec3, rr2: f64) -> bool {
    let ahead = ((lo - q) * m).max((hi - q) * m);
    if ahead.x + ahead.y + ahead.z > 0.0 {
        return false;
    }
    let gap = (lo - q).max(q - hi).max(DVec3::ZERO);
    gap.length_squared() > rr2 * (1.0 + 1e-6)
}

/// Whether the segment `lo..hi` of `line` provably stays farther than `rr` from the segment
/// `c0`–`c1`, decided at its upper end alone (a cheap sufficient test, exact but for a
/// relative margin of 1e-6 in the squared distance). The distance from a convex set is
/// convex along a line, and its slope at `hi` is `n·w/|w|`, `w` running from the set's
/// point nearest to the line's point at `hi`: where `n·w ≤ 0` the distance only falls
/// towards `hi`, so the least over the segment is `|w|`. Vectors grow outwards, towards the
/// moves that cut their surface: of the capsules that reach their neighbourhood (a dome's
/// ball passes a side-step apart each side, whose bounding spheres its vectors pass), most
/// are decided here.
fn misses_capsule_at_top(line: &Line, hi: f64, c0: DVec3, c1: DVec3, rr: f64) -> bool {
    clear_of_capsule(line.o + hi * line.n, line.n, c0, c1, rr)
}

/// [`clear_at_top`] for the capsule of radius `rr` about `c0`–`c1` at the point `q`, the
/// segment's end the distance falls towards along `n`.
fn clear_of_capsule(q: DVec3, n: DVec3, c0: DVec3, c1: DVec3, rr: f64) -> bool {
    let d = c1 - c0;
    let w = q - from_segment(q, c0, d, inv_or_zero(d.length_squared()));
    clear_at_top(w, n, rr * rr)
}

/// [`misses_capsule_at_top`] at the other end: the distance at `lo` already rises along
/// `n`, so the least over the segment is there. Vectors whose normal points away from the
/// tool (a folded skin's, measured again from the surface) are decided here; no seed
/// enters them, so only their searches test it: the trees', and a group's list of the
/// vectors that follow one that entered nothing (see `measure_vectors`; in every listed
/// search it cost the dome's ball program 1.3 % and saved mount_rush's 1 %).
fn misses_capsule_at_bottom(line: &Line, c0: DVec3, c1: DVec3, rr: f64) -> bool {
    clear_of_capsule(line.o + line.lo * line.n, -line.n, c0, c1, rr)
}

/// A listed move of a group, laid out for the tests every vector of the group runs on it
/// ([`near_capsule`] and [`misses_capsule_at_top`]): its item, the
/// centres' segment `c0 + u·d` and `1/|d|²` (0 for a point), and its bounding sphere
/// (middle, squared radius with the same allowance).
#[derive(Clone, Copy)]
struct Listed {
    ci: u32,
    mv: u32,
    c0: DVec3,
    d: DVec3,
    inv_dd: f64,
    mid: DVec3,
    rho2: f64,
}

impl Listed {
    /// The segment `c0`–`c1` with radius `rr`, as item `ci` of move `mv`.
    fn segment(ci: u32, mv: u32, c0: DVec3, c1: DVec3, rr: f64) -> Listed {
        let d = c1 - c0;
        Listed {
            ci,
            mv,
            c0,
            d,
            inv_dd: inv_or_zero(d.length_squared()),
            mid: 0.5 * (c0 + c1),
            rho2: sphere_rho2(0.5 * c0.distance(c1), rr),
        }
    }

    /// Item `ci` of `volumes` (its middle and half length as [`Extras::mids`] keeps them).
    fn of(volumes: &Extras, ci: u32, rr: f64) -> Listed {
        let (_, mv, c0, c1) = volumes.items[ci as usize];
        Listed::segment(ci, mv, c0, c1, rr)
    }

    /// Whether the segment `lo..hi` of `line` may come within `√rr2` of the centres'
    /// segment: [`near_capsule`], then not rejected by [`misses_capsule_at_top`].
    #[inline]
    fn may_reach(&self, line: &Line, hi: f64, rr2: f64) -> bool {
        if !meets_sphere(line, hi, self.mid, self.rho2) {
            return false;
        }
        let q = line.o + hi * line.n;
        !clear_at_top(
            q - from_segment(q, self.c0, self.d, self.inv_dd),
            line.n,
            rr2,
        )
    }

    /// Whether the segment of `line` from its start provably stays farther than `√rr2`
    /// from the centres' segment, decided at the start as [`misses_capsule_at_bottom`] does.
    #[inline]
    fn missed_from_start(&self, line: &Line, rr2: f64) -> bool {
        let q = line.o + line.lo * line.n;
        clear_at_top(
            q - from_segment(q, self.c0, self.d, self.inv_dd),
            -line.n,
            rr2,
        )
    }
}

/// A run's members (laid out as [`Listed`], in the run's order) tried for the segment
/// `lo..best` of `line` (`best` the least entry in `found`, else `hi0`): each that may reach
/// the segment (and, with `at_start`, is not turned away at its start either) and could
/// change the answer, skipping the move that holds the best (its entry is computed) and, at
/// the segment's start, any move numbered higher than it (only a lower one's tie could
/// replace it).
#[inline(always)]
fn try_members(
    line: &Line,
    hi0: f64,
    members: &[Listed],
    rr2: f64,
    at_start: bool,
    found: &mut Option<(Entry, u32)>,
    mut try_move: impl FnMut(usize, &mut Option<(Entry, u32)>),
) {
    for c in members {
        let hi = found.map_or(hi0, |(f, _)| f.s.min(hi0));
        if found.is_some_and(|(f, m)| m == c.mv || (hi <= line.lo && f.s <= line.lo && c.mv >= m)) {
            continue;
        }
        if c.may_reach(line, hi, rr2) && !(at_start && c.missed_from_start(line, rr2)) {
            try_move(c.ci as usize, found);
        }
    }
}

/// A listed run of a ball's moves ([`crate::chains`]): its chord laid out as a [`Listed`]
/// of radius `r + slack` (squared: `rr2`), and where its members lie in the list of every
/// run's members (laid out in the order of `Runs::members`): `count` from `first`.
#[derive(Clone, Copy)]
struct RunListed {
    chord: Listed,
    rr2: f64,
    first: u32,
    count: u32,
}

impl RunListed {
    /// Run `k` of `runs` for a ball of radius `rr` (its members laid out as `runs.members`).
    fn of(runs: &crate::chains::Runs, k: usize, rr: f64) -> RunListed {
        let (a, b, slack) = runs.chords[k];
        let (first, count) = runs.ranges[k];
        let r = rr + slack;
        RunListed {
            chord: Listed::segment(k as u32, 0, a, b, r),
            rr2: r * r,
            first,
            count,
        }
    }

    /// Whether the segment `lo..hi` of `line` may enter a member's capsule
    /// ([`Listed::may_reach`] on the run's capsule, which holds theirs).
    #[inline]
    fn may_reach(&self, line: &Line, hi: f64) -> bool {
        self.chord.may_reach(line, hi, self.rr2)
    }
}

/// Whether the segment `lo..hi` of `line` provably misses the column of a translation (its
/// centres `c0`–`c1`, axis `k`, radius `rr`), decided at the top as
/// [`misses_capsule_at_top`] does, across the axis: the column lies in the prism over the
/// stadium of radius `rr` about the centres' segment seen along `k`, whose distance (in the
/// plane across `k`) is convex along the line too. On the dome's ball program it turns
/// away 98 % of the columns whose boxes the segments meet, and none of those was entered.
fn misses_column_at_top(line: &Line, c0: DVec3, c1: DVec3, k: DVec3, rr: f64) -> bool {
    let d = across(c1 - c0, k);
    let seen = (across(c0, k), d, inv_or_zero(d.length_squared()));
    clear_of_column(line.o + line.hi * line.n, line.n, seen, k, rr)
}

/// [`misses_column_at_top`] at the segment's top `p` (direction `n`), with the centres'
/// segment already seen along `k`: its start `a`, its run `d` and `1/|d|²`.
#[inline]
fn clear_of_column(
    p: DVec3,
    n: DVec3,
    (a, d, inv_dd): (DVec3, DVec3, f64),
    k: DVec3,
    rr: f64,
) -> bool {
    let q = across(p, k);
    clear_at_top(q - from_segment(q, a, d, inv_dd), n, rr * rr)
}

/// A bull's listed move laid out for its group's vectors, as [`Listed`] for a ball: its
/// box, its bounding sphere's squared radius as [`near_capsule`] computes it, and its
/// centres' heights along its axis (for [`slab_interval`]): the same tests, without the
/// tables.
#[derive(Clone, Copy)]
struct PuckListed {
    ci: u32,
    bl: DVec3,
    bh: DVec3,
    mid: DVec3,
    rho2: f64,
    k: DVec3,
    z0: f64,
    z1: f64,
}

impl PuckListed {
    /// Item `ci` of `volumes`, a translation along the axis `k`, for a puck within `rr` of
    /// its centres.
    fn of(volumes: &Extras, ci: u32, rr: f64, k: DVec3) -> PuckListed {
        let (_, _, c0, c1) = volumes.items[ci as usize];
        let (bl, bh) = volumes.bounds[ci as usize];
        let (mid, half) = volumes.mids[ci as usize];
        PuckListed {
            ci,
            bl,
            bh,
            mid,
            rho2: sphere_rho2(half, rr),
            k,
            z0: c0.dot(k),
            z1: c1.dot(k),
        }
    }
}

/// A listed column of a group (a translation's: axis `k` at both poses), laid out for the
/// tests every vector of the group runs on it in `column_entry`: its box, and its centres'
/// segment seen along `k`.
#[derive(Clone, Copy)]
struct ColumnListed {
    mv: u32,
    bl: DVec3,
    bh: DVec3,
    c0: DVec3,
    c1: DVec3,
    k: DVec3,
    /// The centres' segment seen along `k` ([`clear_of_column`]).
    across: (DVec3, DVec3, f64),
}

impl ColumnListed {
    /// Item `ci` of `columns`, or `None` where the move turns its axis.
    fn of(columns: &Extras, ci: u32, toolpath: &Toolpath) -> Option<ColumnListed> {
        let (_, mv, c0, c1) = columns.items[ci as usize];
        let (a, b) = (
            toolpath.moves[mv as usize - 1].pose,
            toolpath.moves[mv as usize].pose,
        );
        if a.axis != b.axis {
            return None;
        }
        let k = a.axis;
        let (bl, bh) = columns.bounds[ci as usize];
        let d = across(c1 - c0, k);
        Some(ColumnListed {
            mv,
            bl,
            bh,
            c0,
            c1,
            k,
            across: (across(c0, k), d, inv_or_zero(d.length_squared())),
        })
    }
}

/// A ball's moves in runs ([`crate::chains`]): the tiles and groups gather the runs, whose
/// chords' capsules hold their members'. The runs, their tree (items `(PUCK, run, chord's
/// ends)` boxed by their members' boxes together), and, laid out once for every group that
/// lists them, each run (by its index) and its members (in the order of `Runs::members`).
struct BallRuns {
    runs: crate::chains::Runs,
    tree: Extras,
    lay: Vec<RunListed>,
    members: Vec<Listed>,
}

impl BallRuns {
    /// The runs of the moves in `volumes`, for a ball of radius `rr`.
    fn of(volumes: &Extras, rr: f64) -> BallRuns {
        let runs = crate::chains::runs(
            (0u32..)
                .zip(&volumes.items)
                .map(|(ci, &(_, mv, c0, c1))| (mv, ci, c0, c1))
                .collect(),
        );
        // A run's box: its members' boxes together (each its centres' box grown by `rr` and a
        // hair), tighter than its chord's grown by `rr + slack`: most of all at the bottom,
        // where a vector that starts on the floor of a pass (pointing away from it, on the
        // underside of a fold) meets every box that reaches below the pass by the slack.
        let (items, bounds) = runs
            .chords
            .iter()
            .zip(&runs.ranges)
            .enumerate()
            .map(|(k, (&(a, b, _), &(first, count)))| {
                let members = &runs.members[first as usize..(first + count) as usize];
                let (lo, hi) = members.iter().fold(
                    (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                    |(lo, hi), &m| {
                        let (bl, bh) = volumes.bounds[m as usize];
                        (lo.min(bl), hi.max(bh))
                    },
                );
                ((PUCK, k as u32, a, b), (lo, hi))
            })
            .unzip();
        let tree = Extras::from_items(items, bounds, 0.0);
        let lay = (0..runs.ranges.len())
            .map(|k| RunListed::of(&runs, k, rr))
            .collect();
        let members = runs
            .members
            .par_iter()
            .map(|&m| Listed::of(volumes, m, rr))
            .collect();
        BallRuns {
            runs,
            tree,
            lay,
            members,
        }
    }
}

/// How far below the best entry a column's entry must lie to replace it (mm; see
/// `column_entry` in `measure_vectors`), for a cutter of reach `rr`.
fn column_tie(rr: f64) -> f64 {
    2e-9 * (1.0 + rr)
}

/// A bull's move `mv` (centres `c0 → c1`, axis `k`) tried for the segment `lo..best` of a
/// line running along `k` by [`crate::exact::axial_entry`], its entry kept in `found` as
/// [`take_least`] keeps it where it faces as `facing` asks; `false` where that cannot decide
/// (the general search then tries the move). Out of line: inlined, it cost every other
/// vector's tests (mount_rush's bull program, which has no such line, 1 % more
/// instructions).
#[inline(never)]
#[allow(clippy::too_many_arguments)]
fn consider_axial(
    line: &Line,
    best: f64,
    puck: &Puck,
    (c0, c1): (DVec3, DVec3),
    k: DVec3,
    mv: u32,
    facing: Facing,
    found: &mut Option<(Entry, u32)>,
) -> bool {
    let upto = Line { hi: best, ..*line };
    let Some(e) = crate::exact::axial_entry(&upto, puck, c0, c1, k) else {
        return false;
    };
    if let Some(e) = e
        && (facing == Facing::Any || e.normal.dot(line.n) < 0.0)
    {
        take_least(e, mv, found);
    }
    true
}

/// Whether move `mv`, whose slab a line enters at `s0`, cannot change the best entry
/// `found`: it holds it (its entry is known), or enters its slab after it, or at it (the
/// segment's start, or a floor that level moves share) where only a lower-numbered move's
/// tie could replace it (see [`take_least`]).
#[inline]
fn cannot_beat(found: Option<(Entry, u32)>, mv: u32, s0: f64) -> bool {
    found.is_some_and(|(f, m)| m == mv || s0 > f.s || (s0 == f.s && mv >= m))
}

/// Keeps in `found` the least entry, among equal ones the lowest-numbered move's.
fn take_least(e: Entry, mv: u32, found: &mut Option<(Entry, u32)>) {
    if found.is_none_or(|(f, fm)| e.s < f.s || (e.s == f.s && mv < fm)) {
        *found = Some((e, mv));
    }
}

/// Vectors per tile of the direct search (see `measure_vectors`).
const DIRECT_TILE: usize = 256;

/// Vectors per group of a tile that share one gathering of the moves near them (see
/// `measure_vectors`). Fewer gather more often, over smaller boxes; with listed moves tried
/// by their spheres alone (a ball) or their boxes, 8 beat 16: dome ball 5.04 G -> 4.74 G
/// instructions, dome flat 7.73 G -> 7.49 G, mount_rush ball 40.8 G -> 39.2 G (4: dome ball
/// 4.82 G; 32: 5.65 G).
const DIRECT_GROUP: usize = 8;

/// The moves that last answered a tile's vectors, the seeds (see `measure_vectors`): the one
/// whose core lies nearest a vector is tried first, then the others in turn (latest first)
/// should it miss; a vector no seed enters searches with its whole segment. On mount_rush's
/// ball program, whose seeds miss the vectors of walls beside and below the passes, the
/// first measure's tree walk visited 41.3 M nodes with the latest move alone, 29.5 M with
/// the last 4 and 25.0 M with the last 8 (tried latest first). With the nearest tried first,
/// 16 cost sphere_on_plate's and the dome's ball programs 1 % to 2 % more than 8, and 4 the
/// same.
const RECENT_SEEDS: usize = 8;

/// The most moves a group's vectors search in a list in place of the tree; beyond it the
/// tree, which prunes by each vector's own segment, is faster. A listed move costs a box
/// test (see [`DIRECT_BALL_MOVES`] for a ball, [`DIRECT_BULL_MOVES`] for a bull).
const DIRECT_MOVES: usize = 256;

/// [`DIRECT_MOVES`] for a ball, whose listed moves cost one bounding-sphere test each: the
/// list pays off far beyond. On the dense mount_rush program (about a thousand moves near
/// each group; callgrind, 1 thread) the ball's verify took 51.6 G instructions at 256,
/// 43.6 G at 1024 and 40.8 G at 4096 (columns' limit raised alike), 39.8 G at 4096 with the
/// columns kept at [`DIRECT_COLUMNS`]. A flat end mill's listed moves tested by spheres
/// alone took 33.8 G at 4096 against 31.2 G at 256, by boxes 32.1 G at 4096: a flat end mill
/// keeps [`DIRECT_MOVES`] and the box test.
const DIRECT_BALL_MOVES: usize = 4096;

/// [`DIRECT_MOVES`] for a bull, whose listed moves are laid out with their boxes, spheres
/// and slabs ([`PuckListed`]) and cost about what the tree's own tests do, while a
/// vector's walk of the tree costs a descent: on the dense mount_rush program (callgrind,
/// 1 thread) 78.8 G instructions at 256, 70.7 G at 1024, 68.5 G at 4096; the dome's and
/// sphere_on_plate's bull programs 8.04 -> 8.00 G and 11.09 -> 11.05 G at 4096.
const DIRECT_BULL_MOVES: usize = 4096;

/// The most columns a group's vectors search in a list in place of the tree (each listed
/// column costs a box test). Raised to 4096 with the ball's moves, it cost mount_rush's
/// ball program 40.8 G instructions against 39.8 G at 256.
const DIRECT_COLUMNS: usize = 256;

/// How far out (mm) a tile's box reaches along its vectors: their groups' boxes, which
/// reach to their seeds' entries, mostly lie within it (see `measure_vectors`); a group
/// whose box leaves it gathers from the trees. Seeded by the nearest recent move, most
/// entries lie close to the surface, and a shorter reach lists fewer moves for every group
/// to filter. Callgrind, one thread, M instructions, at 1.0 / 0.3 mm: sphere_on_plate ball
/// 1,682 / 1,664, dome ball 1,736 / 1,714, mount_rush ball 12,332 / 12,258,
/// sphere_on_plate bull 6,048 / 5,991, sphere_on_plate flat 4,218 / 4,177 (0.1 mm: within
/// 0.1 % of 0.3 mm on the two balls; 2.0 mm: more on all; measured on 0b40c5d).
const TILE_REACH_MM: f64 = 0.3;

/// The most moves (columns) a tile lists for its groups to filter; beyond, each group
/// walks the tree.
const TILE_MOVES: usize = 8192;
const TILE_COLUMNS: usize = 2048;

const SAFETY: f64 = 4.0;
const MIN_FACING: f64 = 0.5;

/// Largest chord sag (mm) of the imprint surface's caps, also a scale for its strips: the
/// rim's chord over one sector and the corner's over one ring.
fn tool_sag(model: &SweepModel) -> f64 {
    let c = model.cutter();
    let (a, r) = (c.major_radius(), c.corner_radius());
    let q = model.inserts() as f64;
    let rings = model.rings() as f64;
    ((a + r) * (1.0 - (std::f64::consts::PI / q).cos()))
        .max(r * (1.0 - (std::f64::consts::FRAC_PI_4 / rings).cos()))
}

/// How far outside a strip triangle (mm) a line still locates it on the exact surface:
/// twice the tool's chord sag.
pub fn edge_margin(models: &[&SweepModel]) -> f64 {
    models.iter().map(|m| 2.0 * tool_sag(m)).fold(0.0, f64::max)
}

/// The search window above the lowest crossing (mm): the largest `δ_c` allowed.
pub fn window(models: &[&SweepModel]) -> f64 {
    models
        .iter()
        .map(|m| SAFETY * tool_sag(m) / MIN_FACING)
        .fold(1e-6, f64::max)
}

/// The strip slot's corners as (pose 0 or 1, point index), in the order of the unoriented
/// triangle.
fn slot_corners(slot: usize) -> [(usize, usize); 3] {
    let j = slot / 2;
    if slot.is_multiple_of(2) {
        [(0, j), (0, j + 1), (1, j + 1)]
    } else {
        [(0, j), (1, j + 1), (1, j)]
    }
}

/// The corners of a strip triangle in the oriented triangle's order.
fn oriented_corners(model: &SweepModel, piece: usize, slot: usize) -> Option<[(usize, usize); 3]> {
    let Piece::Strip { frame, .. } = model.pieces[piece] else {
        return None;
    };
    let t = model.slot_triangle(piece, slot)?;
    let mut c = slot_corners(slot);
    let p1 = model.curve(frame + c[1].0 as u32)[c[1].1];
    if t.v[1] != p1 {
        c.swap(1, 2);
    }
    Some(c)
}

/// The refinement context: the toolpath's moves, the cutter's puck, the line bounds.
struct Refiner<'a> {
    models: &'a [&'a SweepModel],
    toolpath: &'a Toolpath,
    puck: Puck,
}

impl Refiner<'_> {
    fn geometry(&self, mv: u32) -> Option<MoveGeometry> {
        let i = mv as usize;
        (i >= 1 && i < self.toolpath.moves.len()).then(|| MoveGeometry {
            a: self.toolpath.moves[i - 1].pose,
            b: self.toolpath.moves[i].pose,
            puck: self.puck,
        })
    }

    /// Refines one crossing: the entry and the move (or, for a cap, the move it is attributed
    /// to) it lies on; `None` if it cannot be refined.
    fn refine(&self, line: &Line, c: &Crossing) -> Option<(Entry, u32)> {
        let model = self.models[c.model as usize];
        let (piece, slot) = unkey(c.key);
        match model.pieces[piece] {
            Piece::Gap { .. } => None,
            Piece::Cap { frame, .. } => {
                let fr = &model.frames[frame as usize];
                let g = MoveGeometry {
                    a: cam_core::Pose {
                        tip: fr.tip(self.puck.r),
                        axis: fr.axis,
                    },
                    b: cam_core::Pose {
                        tip: fr.tip(self.puck.r),
                        axis: fr.axis,
                    },
                    puck: self.puck,
                };
                g.entry_at(line, 0.0)
                    .map(|e| (e, model.pieces[piece].source_move()))
            }
            Piece::Strip { frame, step } => {
                let g = self.geometry(step.mv)?;
                if g.is_translation() {
                    return g.translation_entry(line).map(|e| (e, step.mv));
                }
                self.refine_rotating(line, c, model, piece, slot, frame, step, &g)
            }
        }
    }

    /// True when [`Refiner::refine`] answers `c` exactly (a cap, or a strip of a
    /// translation: closed forms, or a root search on a convex distance that cannot miss),
    /// so that finding no entry means the line misses that volume.
    fn answers_exactly(&self, c: &Crossing) -> bool {
        let model = self.models[c.model as usize];
        match model.pieces[unkey(c.key).0] {
            Piece::Cap { .. } => true,
            Piece::Strip { step, .. } => self.geometry(step.mv).is_some_and(|g| g.is_translation()),
            Piece::Gap { .. } => false,
        }
    }

    /// The geometry of feed move `mv`, if it is one.
    fn feed_geometry(&self, mv: u32) -> Option<MoveGeometry> {
        let m = self.toolpath.moves.get(mv as usize)?;
        (m.kind != cam_core::MoveKind::Rapid)
            .then(|| self.geometry(mv))
            .flatten()
    }

    /// Refines a crossing of a rotating move's strip: Newton on the move's continuous imprint
    /// surface (a ball: the entry minimised over the pose parameter), else the entry
    /// minimised over the step and its neighbours; where the step ends at a pose joining
    /// another move, also the tool at that pose and the other move's surface near it (the
    /// true surface there may be the tool at the joint, or the other move's sheet).
    #[allow(clippy::too_many_arguments)]
    fn refine_rotating(
        &self,
        line: &Line,
        c: &Crossing,
        model: &SweepModel,
        piece: usize,
        slot: usize,
        frame: u32,
        step: crate::model::StepParam,
        g: &MoveGeometry,
    ) -> Option<(Entry, u32)> {
        let mut best: Option<(Entry, u32)> = None;
        let take = |e: Option<Entry>, mv: u32, best: &mut Option<(Entry, u32)>| {
            if let Some(e) = e
                && best.is_none_or(|(b, _)| e.s < b.s)
            {
                *best = Some((e, mv));
            }
        };
        let (u0, u1) = (step.u_from.min(step.u_to), step.u_from.max(step.u_to));
        let du = u1 - u0;
        let (lo, hi) = ((u0 - du).max(0.0), (u1 + du).min(1.0));
        // Guess: barycentric interpolation of the corners' (u, ψ), ψ in the body frame.
        let guess = (self.puck.a > 0.0)
            .then(|| {
                let corners = oriented_corners(model, piece, slot)?;
                let params = corners.map(|(p, j)| {
                    let f = &model.frames[frame as usize + p];
                    let y = model.curve(frame + p as u32)[j] - f.centre;
                    let psi = y.dot(f.e2).atan2(y.dot(f.e1));
                    (if p == 0 { step.u_from } else { step.u_to }, psi)
                });
                let (b1, b2) = c.bary;
                let b0 = 1.0 - b1 - b2;
                let base = params[0].1;
                let unwrap = |x: f64| {
                    base + (x - base + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI)
                        - std::f64::consts::PI
                };
                let u = b0 * params[0].0 + b1 * params[1].0 + b2 * params[2].0;
                let psi = b0 * base + b1 * unwrap(params[1].1) + b2 * unwrap(params[2].1);
                Some((u, psi))
            })
            .flatten();
        let body_at = |f: usize| {
            let fr = &model.frames[f];
            BodyFrame {
                k_ref: fr.axis,
                e1_ref: fr.e1,
            }
        };
        // Body frame at the step's pose with parameter `u`: frame `frame` at u_from, the next
        // at u_to.
        let frame_at = |u: f64| {
            if u == step.u_from {
                frame as usize
            } else {
                frame as usize + 1
            }
        };
        let own = guess
            .and_then(|(u, psi)| g.imprint_entry(line, &body_at(frame as usize), [u, psi, c.s]))
            .or_else(|| g.entry_min_over(line, lo, hi));
        // Near a move end (the step's own or the solution's), the neighbouring move and the
        // tool at the joint.
        let u_sol = own.map_or(0.5 * (u0 + u1), |(_, u)| u);
        take(own.map(|(e, _)| e), step.mv, &mut best);
        let reach = 2.0 * du.max(1e-9);
        for (touch, at, adj, u_adj) in [
            (
                u0 == 0.0 || u_sol <= reach,
                0.0,
                step.mv.checked_sub(1),
                1.0,
            ),
            (
                u1 == 1.0 || u_sol >= 1.0 - reach,
                1.0,
                Some(step.mv + 1),
                0.0,
            ),
        ] {
            if !touch {
                continue;
            }
            take(g.entry_at(line, at), step.mv, &mut best);
            let Some((m, ga)) = adj.and_then(|m| Some((m, self.feed_geometry(m)?))) else {
                continue;
            };
            if ga.is_translation() {
                take(ga.translation_entry(line), m, &mut best);
                continue;
            }
            // The joint's frame: the step's pose at `at` if it has one, else carried there.
            let body = if (at == step.u_from) || (at == step.u_to) {
                body_at(frame_at(at))
            } else {
                let (_, k) = g.centre_axis(at);
                let b0 = body_at(frame as usize);
                BodyFrame {
                    k_ref: k,
                    e1_ref: crate::imprint::minimal_rotation(b0.e1_ref, b0.k_ref, k),
                }
            };
            let near = if u_adj == 1.0 { (0.5, 1.0) } else { (0.0, 0.5) };
            // The search over the neighbour's poses only matters below the best entry so
            // far (a later one is not taken): the line is cut there.
            let below = Line {
                hi: best.map_or(line.hi, |(b, _)| b.s),
                ..*line
            };
            let adj_entry = guess
                .and_then(|(_, psi)| ga.imprint_entry(line, &body, [u_adj, psi, c.s]))
                .or_else(|| ga.entry_min_over(&below, near.0, near.1));
            take(adj_entry.map(|(e, _)| e), m, &mut best);
        }
        best
    }

    /// True when `line` provably enters none of the pucks of the rotating move whose strip
    /// `c` crosses ([`MoveGeometry::misses_pucks`]): a crossing whose refinement found
    /// nothing is then refuted rather than inconclusive.
    fn proves_miss(&self, line: &Line, c: &Crossing) -> bool {
        let model = self.models[c.model as usize];
        let (piece, _) = unkey(c.key);
        match model.pieces[piece] {
            Piece::Strip { step, .. } => {
                self.geometry(step.mv).is_some_and(|g| g.misses_pucks(line))
            }
            _ => false,
        }
    }

    /// A key naming what a refinement of `c` computes, to refine it once per vector.
    fn identity(&self, c: &Crossing) -> (u8, u64) {
        let model = self.models[c.model as usize];
        let (piece, _) = unkey(c.key);
        match model.pieces[piece] {
            Piece::Strip { step, .. } => match self.geometry(step.mv) {
                // The whole move's volume: the same for every strip of the move, either sweep.
                Some(g) if g.is_translation() => (u8::MAX, step.mv as u64),
                _ => (c.model, piece as u64),
            },
            Piece::Cap { .. } | Piece::Gap { .. } => (c.model, piece as u64),
        }
    }
}

/// What the measurement searches directly rather than locating by triangles, in a
/// hierarchy of boxes. Two sets:
/// * for the exact surface, caps (the tool at one pose) and gaps (a step whose strip is missing because the
///   imprinted half flips, or a step along the axis). Box: for a cap, or a gap whose axis
///   does not turn, the box of its puck at its pose(s), exact for a torus of major radius
///   `a` and tube `r` about the unit axis `k` (half-extent `a·√(1 − k_i²) + r` along axis
///   `i`; a translation's swept volume lies in the box of its two ends' pucks); for a gap
///   whose axis turns, the capsule's box. Each is also bounded by the capsule of radius `R`
///   about its centre segment (a cap's sphere), exact for a ball; the box is much tighter
///   along a vertical axis (a flat end mill's disk is `2R` wide but has no height);
/// * for both surfaces, every feed move's whole cutter, puck and column
///   ([`crate::column`]), whose column is entered exactly and whose puck is tested for the
///   vector's start: the box of the radius-`R` disks at its two ends' centres grown by
///   `r` (the puck below), unbounded along every coordinate the axis climbs in (both ways
///   where the axis turns through it).
struct Extras {
    /// `(model, piece, centre at the first pose, centre at the second)`, in tree order; a
    /// column is `(COLUMN, move, …)`.
    items: Vec<(u8, u32, DVec3, DVec3)>,
    /// Per item: its box (mm).
    bounds: Vec<(DVec3, DVec3)>,
    /// Per item: the middle of its centres' segment and half that segment's length (mm),
    /// for [`near_capsule`].
    mids: Vec<(DVec3, f64)>,
    /// Per item: its centres' segment's unit direction (`+x` for a point) and length (mm),
    /// for [`Extras::near_box`].
    axes: Vec<(DVec3, f64)>,
    /// Nodes: box and, for a leaf, the item range; inner nodes point at two children.
    nodes: Vec<(DVec3, DVec3, u32, u32)>,
    radius: f64,
}

/// The model index that marks a column in [`Extras::items`].
const COLUMN: u8 = u8::MAX;

/// The model index that marks a move's puck in [`Extras::items`].
const PUCK: u8 = u8::MAX - 1;

/// The feed moves of `toolpath` that go somewhere: `(move index, pose before, pose after,
/// torus centre before, after)` for a cutter of corner radius `r`.
fn feed_moves(
    toolpath: &Toolpath,
    r: f64,
) -> impl Iterator<Item = (u32, cam_core::Pose, cam_core::Pose, DVec3, DVec3)> + '_ {
    toolpath
        .moves
        .windows(2)
        .enumerate()
        .filter(|(_, w)| {
            let (a, b) = (w[0].pose, w[1].pose);
            w[1].kind != cam_core::MoveKind::Rapid && (a.tip != b.tip || a.axis != b.axis)
        })
        .map(move |(i, w)| {
            let (a, b) = (w[0].pose, w[1].pose);
            ((i + 1) as u32, a, b, a.tip + r * a.axis, b.tip + r * b.axis)
        })
}

/// Whether every feed move of `toolpath` keeps its tool axis (every 3-axis program): the
/// exact measurement then reads the moves' convex volumes directly, without the imprint
/// surface.
pub fn keeps_axes(toolpath: &Toolpath) -> bool {
    feed_moves(toolpath, 0.0).all(|(_, a, b, _, _)| a.axis == b.axis)
}

/// Half-extents (mm) of a torus puck (major radius `a`, tube `r`) about the unit axis `k`,
/// padded for rounding.
fn puck_extent(a: f64, r: f64, k: DVec3, pad: f64) -> DVec3 {
    let e = |ki: f64| a * (1.0 - ki * ki).max(0.0).sqrt() + r + pad;
    DVec3::new(e(k.x), e(k.y), e(k.z))
}

impl Extras {
    fn new(models: &[&SweepModel]) -> Extras {
        // A step rotating the axis moves its centre along a slightly curved path: pad.
        let radius = models
            .first()
            .map_or(0.0, |m| m.cutter().radius() * (1.0 + 1e-9) + 1e-9);
        let mut items = Vec::new();
        let mut bounds = Vec::new();
        for (mi, m) in models.iter().enumerate() {
            let puck = Puck::of(m.cutter());
            let pad = 1e-9 * (1.0 + puck.a + puck.r);
            for (pi, p) in m.pieces.iter().enumerate() {
                match *p {
                    Piece::Cap { frame, .. } => {
                        let f = &m.frames[frame as usize];
                        let e = puck_extent(puck.a, puck.r, f.axis, pad);
                        items.push((mi as u8, pi as u32, f.centre, f.centre));
                        bounds.push((f.centre - e, f.centre + e));
                    }
                    Piece::Gap { frame, .. } => {
                        let (f0, f1) = (&m.frames[frame as usize], &m.frames[frame as usize + 1]);
                        let (a, b) = (f0.centre, f1.centre);
                        items.push((mi as u8, pi as u32, a, b));
                        if f0.axis == f1.axis {
                            let e = puck_extent(puck.a, puck.r, f0.axis, pad);
                            bounds.push((a.min(b) - e, a.max(b) + e));
                        } else {
                            let r = DVec3::splat(radius);
                            bounds.push((a.min(b) - r, a.max(b) + r));
                        }
                    }
                    Piece::Strip { .. } => {}
                }
            }
        }
        Extras::from_items(items, bounds, radius)
    }

    /// The columns of every feed move of `toolpath` for the cutter of `models` (the same for
    /// both sweeps: once), as far as they reach into `reach` (a box holding every vector):
    /// items `(COLUMN, move, centre at its start, centre at its end)`. A column is cut off
    /// at the length `L` along its axis beyond which it leaves `reach`; its box holds the
    /// radius-`R` disks at the two centres and `L` up their axes. For a translation `L` is
    /// the largest `(corner − c)·k` over the corners of `reach` and the two centres (linear
    /// along the move); for a rotating move, where the axis point at length `L` runs on an
    /// arc, the box grows by that arc's sagitta `(r + L)(1 − cos(θ/2))` (`θ` the turn), and
    /// `L` is the farthest corner's distance from the start centre plus the move's length.
    fn columns(models: &[&SweepModel], toolpath: &Toolpath, reach: (DVec3, DVec3)) -> Extras {
        let (mut items, mut bounds) = (Vec::new(), Vec::new());
        let Some(m) = models.first().filter(|_| reach.0.cmple(reach.1).all()) else {
            return Extras::from_items(items, bounds, 0.0);
        };
        let puck = Puck::of(m.cutter());
        let rr = puck.a + puck.r;
        let pad = 1e-9 * (1.0 + rr);
        let corners: Vec<DVec3> = (0..8)
            .map(|i| {
                DVec3::new(
                    if i & 1 == 0 { reach.0.x } else { reach.1.x },
                    if i & 2 == 0 { reach.0.y } else { reach.1.y },
                    if i & 4 == 0 { reach.0.z } else { reach.1.z },
                )
            })
            .collect();
        for (mv, a, b, c0, c1) in feed_moves(toolpath, puck.r) {
            let far = |f: &dyn Fn(DVec3) -> f64| corners.iter().map(|&q| f(q)).fold(0.0, f64::max);
            let (l, e) = if a.axis == b.axis {
                let k = a.axis;
                let l = far(&|q| (q - c0).dot(k).max((q - c1).dot(k)));
                (l, puck_extent(rr, 0.0, k, pad))
            } else {
                let l = far(&|q| q.distance(c0)) + c0.distance(c1) + puck.r;
                let sag = (puck.r + l) * (1.0 - (0.5 * a.axis.angle_between(b.axis)).cos());
                (l, DVec3::splat(rr + sag + pad))
            };
            let (top0, top1) = (c0 + l * a.axis, c1 + l * b.axis);
            let lo = c0.min(c1).min(top0).min(top1) - e;
            let hi = c0.max(c1).max(top0).max(top1) + e;
            // Wholly outside the vectors' reach: never entered.
            if lo.cmpgt(reach.1).any() || hi.cmplt(reach.0).any() {
                continue;
            }
            items.push((COLUMN, mv, c0, c1));
            bounds.push((lo, hi));
        }
        Extras::from_items(items, bounds, 0.0)
    }

    /// The pucks of every feed move, for cutters with a corner radius (a flat end mill's
    /// puck is a disk, which holds no volume): items `(PUCK, move, centre at its start,
    /// centre at its end)` boxed by the pucks at the two ends (translations) or by the
    /// centres grown by `R + r` (rotating moves, whose centre runs on a slightly curved
    /// path).
    fn pucks(models: &[&SweepModel], toolpath: &Toolpath) -> Extras {
        let (mut items, mut bounds) = (Vec::new(), Vec::new());
        let Some(m) = models.first().filter(|m| m.cutter().corner_radius() > 0.0) else {
            return Extras::from_items(items, bounds, 0.0);
        };
        let puck = Puck::of(m.cutter());
        let pad = 1e-9 * (1.0 + puck.a + puck.r);
        for (mv, a, b, c0, c1) in feed_moves(toolpath, puck.r) {
            let e = if a.axis == b.axis {
                puck_extent(puck.a, puck.r, a.axis, pad)
            } else {
                DVec3::splat(puck.a + 2.0 * puck.r + pad)
            };
            items.push((PUCK, mv, c0, c1));
            bounds.push((c0.min(c1) - e, c0.max(c1) + e));
        }
        Extras::from_items(items, bounds, 0.0)
    }

    /// The pucks of every feed move of `toolpath`, all translations, for the cutter's `puck`
    /// (a flat end mill's disk included): items `(PUCK, move, centre at its start, centre at
    /// its end)`, each boxed by the pucks at its two ends.
    ///
    /// With `tree`, their hierarchy ([`Extras::from_items`]); without, the moves in program
    /// order and no hierarchy ([`Extras::listed`]): a ball's are searched through its runs
    /// (`BallRuns`), never through this tree (sphere_on_plate's ball program 1,694 ->
    /// 1,682 M instructions without it, the dome's 1,750 -> 1,736 M, mount_rush's 12,430 ->
    /// 12,332 M).
    fn volumes(toolpath: &Toolpath, puck: Puck, tree: bool) -> Extras {
        let (mut items, mut bounds) = (Vec::new(), Vec::new());
        let pad = 1e-9 * (1.0 + puck.a + puck.r);
        for (mv, a, _, c0, c1) in feed_moves(toolpath, puck.r) {
            let e = puck_extent(puck.a, puck.r, a.axis, pad);
            items.push((PUCK, mv, c0, c1));
            bounds.push((c0.min(c1) - e, c0.max(c1) + e));
        }
        if tree {
            Extras::from_items(items, bounds, 0.0)
        } else {
            Extras::listed(items, bounds, 0.0)
        }
    }

    /// The hierarchy over `items` with their boxes.
    fn from_items(
        items: Vec<(u8, u32, DVec3, DVec3)>,
        bounds: Vec<(DVec3, DVec3)>,
        radius: f64,
    ) -> Extras {
        let mids: Vec<DVec3> = items.iter().map(|c| 0.5 * (c.2 + c.3)).collect();
        let codes = crate::locate::morton_codes(&mids);
        let mut order: Vec<(u64, usize)> =
            codes.into_iter().enumerate().map(|(i, c)| (c, i)).collect();
        crate::radix::sort_by_key(&mut order, |k| k.0);
        let bounds: Vec<_> = order.iter().map(|&(_, i)| bounds[i]).collect();
        let items: Vec<_> = order.iter().map(|&(_, i)| items[i]).collect();
        let mut e = Extras::listed(items, bounds, radius);
        if !e.items.is_empty() {
            e.nodes.push((DVec3::ZERO, DVec3::ZERO, 0, 0));
            e.build(0, 0, e.items.len());
        }
        e
    }

    /// `items` with their boxes, in the order given, without a hierarchy (walking it visits
    /// nothing).
    fn listed(
        items: Vec<(u8, u32, DVec3, DVec3)>,
        bounds: Vec<(DVec3, DVec3)>,
        radius: f64,
    ) -> Extras {
        let mids = items
            .iter()
            .map(|&(_, _, c0, c1)| (0.5 * (c0 + c1), 0.5 * c0.distance(c1)))
            .collect();
        let axes = items
            .iter()
            .map(|&(_, _, c0, c1)| {
                let d = c1 - c0;
                let len = d.length();
                (if len > 0.0 { d / len } else { DVec3::X }, len)
            })
            .collect();
        Extras {
            items,
            bounds,
            mids,
            axes,
            nodes: Vec::new(),
            radius,
        }
    }

    fn build(&mut self, ni: usize, lo: usize, hi: usize) {
        if hi - lo <= 2 {
            let (mut a, mut b) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
            for c in &self.bounds[lo..hi] {
                a = a.min(c.0);
                b = b.max(c.1);
            }
            self.nodes[ni] = (a, b, lo as u32, (hi - lo) as u32);
            return;
        }
        let left = self.nodes.len();
        self.nodes.push((DVec3::ZERO, DVec3::ZERO, 0, 0));
        self.nodes.push((DVec3::ZERO, DVec3::ZERO, 0, 0));
        let mid = (lo + hi) / 2;
        self.build(left, lo, mid);
        self.build(left + 1, mid, hi);
        let (l, rr) = (self.nodes[left], self.nodes[left + 1]);
        self.nodes[ni] = (l.0.min(rr.0), l.1.max(rr.1), left as u32, 0);
    }

    /// Depth first over the tree, left child first (so leaves in ascending item order):
    /// `f(box min, box max, first, count)` for each node reached. For an inner node
    /// (`count == 0`) its children are reached when `f` returns true; for a leaf (items
    /// `first..first + count`, handled by `f`) the walk stops when `f` returns false.
    fn walk(&self, mut f: impl FnMut(DVec3, DVec3, u32, u32) -> bool) {
        if self.nodes.is_empty() {
            return;
        }
        // The tree is balanced (median splits): its depth is below 64.
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let (a, b, first, count) = self.nodes[stack[top] as usize];
            let go_on = f(a, b, first, count);
            if count > 0 {
                if !go_on {
                    return;
                }
            } else if go_on {
                stack[top] = first + 1;
                stack[top + 1] = first;
                top += 2;
            }
        }
    }

    /// Whether item `ci` may be entered by the segment `lo..hi` of `line` (`inv` the
    /// reciprocal of its direction): its box (unless `boxed`, already tested), then its
    /// capsule (tight for a ball; a column has its box only, and a move's puck is tested as
    /// tightly by its visitor).
    fn reaches(&self, ci: usize, line: &Line, inv: DVec3, hi: f64, boxed: bool) -> bool {
        let (model, _, c0, c1) = self.items[ci];
        let (bl, bh) = self.bounds[ci];
        if !boxed && !segment_box(line.o, inv, bl, bh, line.lo, hi) {
            return false;
        }
        model >= PUCK
            || crate::exact::capsule_entry(&Line { hi, ..*line }, c0, c1, self.radius).is_some()
    }

    /// [`Extras::visit`] over a ball's volumes (every item a capsule of radius `r` about its
    /// centres' segment, boxed by that segment's box grown by `r` and a hair): also passes
    /// over a node whose capsules the segment provably misses, decided at either end as
    /// [`misses_capsule_at_bottom`] and [`misses_capsule_at_top`] decide one capsule, against
    /// the box that holds the node's centres' segments. `f` is called for the items `visit`
    /// calls it for but those.
    fn visit_capsules(&self, line: &Line, hi: f64, r: f64, f: impl FnMut(usize, f64) -> f64) {
        let rr2 = r * r;
        let start = line.o + line.lo * line.n;
        let clear = |a: DVec3, b: DVec3, hi: f64| {
            // The box of the node's centres' segments: its box shrunk by `r`, less a margin
            // for the rounding of the growth.
            let eps = 1e-9 * (1.0 + r + a.abs().max(b.abs()).max_element());
            let (ca, cb) = (a + (r - eps), b - (r - eps));
            clear_of_box(start, line.n, ca, cb, rr2)
                || clear_of_box(line.o + hi * line.n, -line.n, ca, cb, rr2)
        };
        self.visit_unless(line, hi, clear, f);
    }

    /// Calls `f` for every item whose bound the segment `lo..hi(current)` of `line` meets;
    /// `f` returns the new upper end of the segment.
    fn visit(&self, line: &Line, hi: f64, f: impl FnMut(usize, f64) -> f64) {
        self.visit_unless(line, hi, |_, _, _| false, f);
    }

    /// [`Extras::visit`], passing over the nodes (box `a..b`) for which `clear(a, b, hi)`
    /// holds.
    fn visit_unless(
        &self,
        line: &Line,
        mut hi: f64,
        clear: impl Fn(DVec3, DVec3, f64) -> bool,
        mut f: impl FnMut(usize, f64) -> f64,
    ) {
        let inv = DVec3::new(1.0 / line.n.x, 1.0 / line.n.y, 1.0 / line.n.z);
        let (slo, shi) = segment_bounds(line, hi);
        self.walk(|a, b, first, count| {
            if !(boxes_meet(a, b, slo, shi) && segment_box(line.o, inv, a, b, line.lo, hi))
                || clear(a, b, hi)
            {
                return count > 0;
            }
            // A leaf of one item: its box is the node's.
            for ci in first as usize..(first + count) as usize {
                if self.reaches(ci, line, inv, hi, count == 1) {
                    hi = f(ci, hi);
                }
            }
            true
        });
    }
}

impl Extras {
    /// Whether item `ci`'s centres' segment lies within `round` of the box `lo..=hi`.
    fn near_box(&self, ci: u32, lo: DVec3, hi: DVec3, round: f64) -> bool {
        // The segment's bounding sphere first: most of a dense program's short moves are
        // decided by it.
        let (mid, half) = self.mids[ci as usize];
        let gap = (lo - mid).max(mid - hi).max(DVec3::ZERO);
        let reach = (half + round) * (1.0 + 1e-12);
        if gap.length_squared() > reach * reach {
            return false;
        }
        // Then its ends: one within `round` decides it (most of those the sphere passes).
        let (_, _, c0, c1) = self.items[ci as usize];
        let off = |p: DVec3| (p - p.clamp(lo, hi)).length_squared();
        if off(c0) <= round * round || off(c1) <= round * round {
            return true;
        }
        let (n, len) = self.axes[ci as usize];
        // Then the segment against the box's bounding sphere (the segment's nearest point to
        // the box's middle), which holds the box: a cheap necessary test that turns away
        // about half of what is left (on mount_rush's ball program 0.86 M of the 1.85 M
        // segments left here), the distance to the box proper (below) the rest.
        let (centre, radius) = (0.5 * (lo + hi), 0.5 * (hi - lo).length());
        let near = c0 + (centre - c0).dot(n).clamp(0.0, len) * n;
        let reach = (radius + round) * (1.0 + 1e-9);
        if near.distance_squared(centre) > reach * reach {
            return false;
        }
        let axis = Line {
            o: c0,
            n,
            lo: 0.0,
            hi: len,
        };
        crate::proximity::segment_box_distance2(&axis, lo, hi) <= round * round
    }

    /// The items whose boxes meet the box `lo..=hi` (boundaries included), in ascending
    /// order (the order [`Extras::visit`] meets them in), appended to `out`. With `round`
    /// positive, only those whose centres' segment also lies within `round` of that box.
    /// Stops, returning `false`, once `out` holds more than `limit` items.
    fn gather(&self, lo: DVec3, hi: DVec3, round: f64, limit: usize, out: &mut Vec<u32>) -> bool {
        let meets = |a: DVec3, b: DVec3| boxes_meet(a, b, lo, hi);
        let near = |ci: u32| self.near_box(ci, lo, hi, round);
        let mut room = true;
        self.walk(|a, b, first, count| {
            if !meets(a, b) {
                return count > 0;
            }
            for ci in first..first + count {
                let (bl, bh) = self.bounds[ci as usize];
                if meets(bl, bh) && (round <= 0.0 || near(ci)) {
                    out.push(ci);
                    if out.len() > limit {
                        room = false;
                        return false;
                    }
                }
            }
            true
        });
        room
    }

    /// [`Extras::gather`] among the items `from` (ascending, holding every item `gather`
    /// would list for this box: those it lists for a box holding this one): the same items,
    /// in the same order, and the same answer about the limit, without the tree.
    fn gather_from(
        &self,
        from: &[u32],
        lo: DVec3,
        hi: DVec3,
        round: f64,
        limit: usize,
        out: &mut Vec<u32>,
    ) -> bool {
        let meets = |a: DVec3, b: DVec3| boxes_meet(a, b, lo, hi);
        for &ci in from {
            let (bl, bh) = self.bounds[ci as usize];
            if meets(bl, bh) && (round <= 0.0 || self.near_box(ci, lo, hi, round)) {
                out.push(ci);
                if out.len() > limit {
                    return false;
                }
            }
        }
        true
    }

    /// [`Extras::visit`] over the items `among` only (ascending, and holding every item
    /// whose box the segment meets, as [`Extras::gather`] returns for a box holding the
    /// segment): the same calls of `f`, in the same order.
    fn visit_among(
        &self,
        among: &[u32],
        line: &Line,
        mut hi: f64,
        mut f: impl FnMut(usize, f64) -> f64,
    ) {
        let inv = DVec3::new(1.0 / line.n.x, 1.0 / line.n.y, 1.0 / line.n.z);
        let (slo, shi) = segment_bounds(line, hi);
        for &ci in among {
            let (bl, bh) = self.bounds[ci as usize];
            if boxes_meet(bl, bh, slo, shi) && self.reaches(ci as usize, line, inv, hi, false) {
                hi = f(ci as usize, hi);
            }
        }
    }
}

/// Whether the segment `o + s·n`, `s ∈ [t0, t1]`, meets the box (boundary included).
/// Without a branch per axis: the same decisions as [`segment_box_axes`], whose interval
/// only ever narrows. A line parallel to a slab (infinite `inv`) gets `±∞` bounds from it,
/// which leave the interval whole inside the slab and empty outside; only where it runs in
/// the slab's boundary plane (`0·∞`) is the axis-by-axis test needed.
#[inline(always)]
fn segment_box(o: DVec3, inv: DVec3, min: DVec3, max: DVec3, t0: f64, t1: f64) -> bool {
    let (ta, tb) = ((min - o) * inv, (max - o) * inv);
    if (ta.is_nan_mask() | tb.is_nan_mask()).any() {
        return segment_box_axes(o, inv, min, max, t0, t1);
    }
    slabs_meet(ta, tb, t0, t1)
}

/// The box of the segment `lo..hi` of `line` (everything where an end is not finite): the
/// box of every shorter segment from `lo`, for [`boxes_meet`].
fn segment_bounds(line: &Line, hi: f64) -> (DVec3, DVec3) {
    let (p, q) = (line.o + line.lo * line.n, line.o + hi * line.n);
    if p.is_finite() && q.is_finite() {
        (p.min(q), p.max(q))
    } else {
        (DVec3::NEG_INFINITY, DVec3::INFINITY)
    }
}

/// Whether the boxes `a..=b` and `lo..=hi` share a point: a segment's box against an item's
/// before the slab test ([`segment_box_of`]), comparisons where that divides.
#[inline(always)]
fn boxes_meet(a: DVec3, b: DVec3, lo: DVec3, hi: DVec3) -> bool {
    a.cmple(hi).all() && b.cmpge(lo).all()
}

/// Whether the slabs' intervals `ta..tb` (per axis, either order) and `t0..t1` share a point.
#[inline(always)]
fn slabs_meet(ta: DVec3, tb: DVec3, t0: f64, t1: f64) -> bool {
    ta.min(tb).max_element().max(t0) <= ta.max(tb).min_element().min(t1)
}

/// [`segment_box`] for a line whose `inv` is finite in every axis (`finite`, decided once
/// per line): then no product is NaN, and the test per box is its first path alone.
#[inline(always)]
fn segment_box_of(
    finite: bool,
    o: DVec3,
    inv: DVec3,
    min: DVec3,
    max: DVec3,
    t0: f64,
    t1: f64,
) -> bool {
    if finite {
        slabs_meet((min - o) * inv, (max - o) * inv, t0, t1)
    } else {
        segment_box(o, inv, min, max, t0, t1)
    }
}

/// [`segment_box`] axis by axis, a line parallel to a slab (infinite `inv`) inside it or
/// nowhere.
fn segment_box_axes(o: DVec3, inv: DVec3, min: DVec3, max: DVec3, t0: f64, t1: f64) -> bool {
    let (mut lo, mut hi) = (t0, t1);
    for a in 0..3 {
        if inv[a].is_infinite() {
            if o[a] < min[a] || o[a] > max[a] {
                return false;
            }
            continue;
        }
        let ta = (min[a] - o[a]) * inv[a];
        let tb = (max[a] - o[a]) * inv[a];
        let (ta, tb) = if ta <= tb { (ta, tb) } else { (tb, ta) };
        lo = lo.max(ta);
        hi = hi.min(tb);
        if lo > hi {
            return false;
        }
    }
    true
}

/// How crossings are located: the fast tile search, or the brute-force reference (tests).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Locator {
    /// [`crate::locate::locate`].
    Fast,
    /// [`crate::locate::locate_reference`] and every cap tested.
    Reference,
}

/// Measures the signed deviation of every vertex of `refined` against the swept surfaces
/// `models` of `toolpath`. Parallel; the result does not depend on the number of threads.
///
/// # Errors
/// [`DeviationError::BadLength`] for negative or non-finite vector lengths.
pub fn measure(
    refined: &RefinedMesh,
    models: &[&SweepModel],
    toolpath: &Toolpath,
    cfg: &DeviationConfig,
    surface: SurfaceModel,
) -> Result<Measurement, DeviationError> {
    measure_with(refined, models, toolpath, cfg, surface, Locator::Fast)
}

/// [`measure`] with a choice of locator: [`Locator::Reference`] must give the same result
/// (it is the straightforward method the fast one is tested against).
///
/// # Errors
/// As [`measure`].
pub fn measure_with(
    refined: &RefinedMesh,
    models: &[&SweepModel],
    toolpath: &Toolpath,
    cfg: &DeviationConfig,
    surface: SurfaceModel,
    locator: Locator,
) -> Result<Measurement, DeviationError> {
    let inner = vec![cfg.inside_mm; refined.positions.len()];
    measure_with_inner(refined, &inner, models, toolpath, cfg, surface, locator)
}

/// [`measure_with`] with each vector's inner length `L_in(v)` given per vertex (mm, in
/// place of `cfg.inside_mm`; see [`crate::material::inner_lengths`]).
///
/// # Errors
/// [`DeviationError::BadLength`] for a negative or non-finite length, or when `inner_mm`
/// does not hold one length per vertex.
pub fn measure_with_inner(
    refined: &RefinedMesh,
    inner_mm: &[f64],
    models: &[&SweepModel],
    toolpath: &Toolpath,
    cfg: &DeviationConfig,
    surface: SurfaceModel,
    locator: Locator,
) -> Result<Measurement, DeviationError> {
    measure_inner(
        refined,
        Inner::Each(inner_mm),
        models,
        toolpath,
        cfg,
        surface,
        locator,
        None,
        None,
        None,
    )
}

/// [`measure`] reporting progress (`(vectors done, vectors in all)`) between chunks of
/// vectors; the result is the same.
///
/// # Errors
/// As [`measure`].
pub fn measure_progress(
    refined: &RefinedMesh,
    models: &[&SweepModel],
    toolpath: &Toolpath,
    cfg: &DeviationConfig,
    surface: SurfaceModel,
    progress: Progress<'_>,
) -> Result<Measurement, DeviationError> {
    measure_inner(
        refined,
        Inner::All(cfg.inside_mm),
        models,
        toolpath,
        cfg,
        surface,
        Locator::Fast,
        Some(progress),
        None,
        None,
    )
}

/// Picks vertices to measure again from a first measurement: `(vertex, inner length mm)`
/// for each (see [`measure_then`]).
pub type Redo<'a> = &'a mut dyn FnMut(&Measurement) -> Vec<(usize, f64)>;

/// [`measure_progress`], then once more for the vertices `redo` picks from that first
/// reading, each from its own inner length (mm, in place of `cfg.inside_mm`): their
/// readings replace the first ones; the counts stay the first pass's. The same result as
/// [`measure_progress`] followed by [`measure_with_inner`] on the picked vertices, with the
/// moves' trees and lists laid out once for both passes (on mount_rush some 40 thousand
/// vectors that start outside an open relief's material are measured again): the program,
/// its models and the surface model are `layout`'s, and so are the trees where its box holds
/// every vector (see [`layout`]).
///
/// # Errors
/// As [`measure`], and [`DeviationError::BadLength`] for a picked length that is negative
/// or not finite, or a picked vertex out of range.
pub fn measure_then(
    refined: &RefinedMesh,
    layout: &Layout<'_>,
    cfg: &DeviationConfig,
    progress: Progress<'_>,
    redo: Redo<'_>,
) -> Result<Measurement, DeviationError> {
    let n = refined.positions.len();
    let mut bad: Option<f64> = None;
    let mut checked = |m: &Measurement| {
        let picks = redo(m);
        match picks
            .iter()
            .find(|&&(i, l)| i >= n || !(l.is_finite() && l >= 0.0))
        {
            Some(&(_, l)) => {
                bad = Some(l);
                Vec::new()
            }
            None => picks,
        }
    };
    let m = measure_inner(
        refined,
        Inner::All(cfg.inside_mm),
        layout.models,
        layout.toolpath,
        cfg,
        layout.surface,
        Locator::Fast,
        Some(progress),
        Some(&mut checked),
        Some(layout),
    )?;
    match bad {
        Some(l) => Err(DeviationError::BadLength {
            inside_mm: l,
            outside_mm: cfg.outside_mm,
        }),
        None => Ok(m),
    }
}

/// The vectors' inner lengths (mm): one for all, or one per vertex.
#[derive(Clone, Copy)]
enum Inner<'a> {
    All(f64),
    Each(&'a [f64]),
}

#[allow(clippy::too_many_arguments)]
fn measure_inner(
    refined: &RefinedMesh,
    inner: Inner<'_>,
    models: &[&SweepModel],
    toolpath: &Toolpath,
    cfg: &DeviationConfig,
    surface: SurfaceModel,
    locator: Locator,
    progress: Option<Progress<'_>>,
    redo: Option<Redo<'_>>,
    layout: Option<&Layout<'_>>,
) -> Result<Measurement, DeviationError> {
    let ok = |x: f64| x.is_finite() && x >= 0.0;
    let (bad, sized) = match inner {
        Inner::All(l) => ((!ok(l)).then_some(l), true),
        Inner::Each(ls) => (
            ls.par_iter().copied().find_first(|&x| !ok(x)),
            ls.len() == refined.positions.len(),
        ),
    };
    if !ok(cfg.inside_mm) || !ok(cfg.outside_mm) || bad.is_some() || !sized {
        return Err(DeviationError::BadLength {
            inside_mm: bad.unwrap_or(cfg.inside_mm),
            outside_mm: cfg.outside_mm,
        });
    }
    // One inner length for all: the vectors are read from the mesh as they are needed (a
    // copy of them all, 64 bytes a vertex, cost sphere_on_plate's ball program 3 ms of
    // its measure stage on two threads, most of it in the pages it touched first).
    let owned: Vec<Vector>;
    let vectors = match inner {
        Inner::All(l) => Vectors::Mesh {
            o: &refined.positions,
            n: &refined.normals,
            lo: -l,
            hi: cfg.outside_mm,
        },
        Inner::Each(ls) => {
            owned = refined
                .positions
                .par_iter()
                .zip(&refined.normals)
                .zip(ls)
                .map(|((&o, &n), &l)| Vector {
                    o,
                    n,
                    lo: -l,
                    hi: cfg.outside_mm,
                })
                .collect();
            Vectors::Given(&owned)
        }
    };
    Ok(measure_vectors(
        vectors, models, toolpath, cfg.facing, surface, locator, progress, redo, layout,
    ))
}

/// First entries of the lines `(origin, unit direction)` into the swept volume, for
/// `s ∈ [0, max_mm]` along each: the method of [`measure`] on arbitrary lines (for
/// validation against [`crate::envelope`]). `None` where nothing is entered.
pub fn first_entries(
    models: &[&SweepModel],
    toolpath: &Toolpath,
    lines: &[(DVec3, DVec3)],
    max_mm: f64,
    surface: SurfaceModel,
) -> Vec<Option<f64>> {
    let vectors: Vec<Vector> = lines
        .iter()
        .map(|&(o, n)| Vector {
            o,
            n,
            lo: 0.0,
            hi: max_mm,
        })
        .collect();
    measure_vectors(
        Vectors::Given(&vectors),
        models,
        toolpath,
        Facing::AgainstVector,
        surface,
        Locator::Fast,
        None,
        None,
        None,
    )
    .deviations
    .iter()
    .map(|d| d.signed_mm)
    .collect()
}

/// The measurement for explicit vectors; then, if `redo` picks any from it (`(index,
/// inner length)`), those again from `−length` (see [`measure_then`]).
#[allow(clippy::too_many_arguments)]
fn measure_vectors(
    vectors: Vectors<'_>,
    models: &[&SweepModel],
    toolpath: &Toolpath,
    facing: Facing,
    surface: SurfaceModel,
    locator: Locator,
    progress: Option<Progress<'_>>,
    redo: Option<Redo<'_>>,
    layout: Option<&Layout<'_>>,
) -> Measurement {
    let exact = surface == SurfaceModel::Exact;
    let delta = window(models);
    // Exact: caps are tested exactly below, the triangles locate strips only, and a line
    // passing just outside a triangle counts: the true sheet bulges past its chords by up to
    // the sag, so near a sheet's curved edge a line can enter it and miss its triangles.
    let margin = if exact { edge_margin(models) } else { 0.0 };
    let puck = models
        .first()
        .map_or(Puck { a: 0.0, r: 0.0 }, |m| Puck::of(m.cutter()));
    // Every feed move a translation (every 3-axis program): the swept volume is the union of
    // the moves' convex volumes (puck and column), each entered exactly, so the first entry
    // is found among them directly (see `direct_one`) and no crossing is located.
    let direct = exact && locator == Locator::Fast && keeps_axes(toolpath);
    let bvhs: Vec<PatchBvh> = match locator {
        Locator::Fast if direct => Vec::new(),
        Locator::Fast => models
            .iter()
            .map(|m| PatchBvh::new(m, !exact, margin))
            .collect(),
        Locator::Reference => Vec::new(),
    };
    let pairs: Vec<(&SweepModel, &PatchBvh)> = models.iter().copied().zip(&bvhs).collect();
    let find = |vs: &[Vector]| match locator {
        Locator::Fast => locate(&pairs, vs, delta, margin),
        Locator::Reference => crate::locate::locate_reference(models, vs, delta, margin, !exact),
    };
    let rf = Refiner {
        models,
        toolpath,
        puck,
    };
    // Every vector lies in this box.
    let empty = || (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let reach = (0..vectors.len())
        .into_par_iter()
        .fold(empty, |(lo, hi), i| {
            let v = vectors.get(i);
            let (p, q) = (v.o + v.lo * v.n, v.o + v.hi * v.n);
            (lo.min(p).min(q), hi.max(p).max(q))
        })
        .reduce(empty, |(a, b), (c, d)| (a.min(c), b.max(d)));
    let rr = puck.a + puck.r;
    let ball = puck.a == 0.0;
    // The moves' trees and lists: the caller's where they were laid out for this search and
    // a box that holds every vector, else laid out here.
    let own;
    let lay = match layout.filter(|l| l.serves(models, toolpath, surface, locator, reach)) {
        Some(l) => l,
        None => {
            own = Layout::new(models, toolpath, surface, locator, reach);
            &own
        }
    };
    let (columns, pucks, volumes) = (&lay.columns, &lay.pucks, &lay.volumes);
    let (runs, run_tree, run_lay, member_lay) =
        (&lay.runs, &lay.run_tree, &lay.run_lay, &lay.member_lay);
    let (column_lay, puck_lay) = (&lay.column_lay, &lay.puck_lay);
    let max_slack = runs
        .as_ref()
        .map_or(0.0, |r| r.chords.iter().fold(0.0f64, |m, c| m.max(c.2)));
    // A ball's volumes are capsules, which their bounding spheres fit well enough to test
    // listed moves by them alone; a flat end mill's and a bull's pucks are flatter than
    // their spheres, and their boxes prune more (see `Listed` and `PuckListed`).
    let bull = puck.a > 0.0 && puck.r > 0.0;
    let move_limit = if ball {
        DIRECT_BALL_MOVES
    } else if bull {
        DIRECT_BULL_MOVES
    } else {
        DIRECT_MOVES
    };
    // Every move's volume lies within `rr` of its centres' segment: `round` allows for
    // rounding (see `Extras::gather`).
    let scale = volumes.items.iter().fold(0.0f64, |m, it| {
        m.max(it.2.abs().max_element())
            .max(it.3.abs().max_element())
    });
    let round = rr + 1e-9 * (1.0 + rr + scale);
    // A run's chord lies within `r + slack` of every point of its members' capsules.
    let run_round = round + max_slack;
    // What the tiles and groups gather for the moves: a ball's runs, or the moves.
    let (move_tree, move_round) = if runs.is_some() {
        (run_tree, run_round)
    } else {
        (volumes, round)
    };
    // Entries through a column's bottom are the puck's (found before, or by the imprint
    // surface): only sides and starts are searched. An entry less than `tie` below the best
    // found does not replace it, so boxes that reach the best only by their padding (half
    // that: the bottoms of the many moves over level ground where the best lies) are pruned
    // whole.
    let column_entry =
        |line: &Line, hi: f64, found: &mut Option<(Entry, u32)>, tests: &mut usize| {
            let tie = column_tie(rr);
            let hi = found.map_or(hi, |(e, _)| e.s) - tie;
            let f = |ci: usize, hi: f64| {
                let (_, mv, c0, c1) = columns.items[ci];
                *tests += 1;
                let (a, b) = (
                    toolpath.moves[mv as usize - 1].pose,
                    toolpath.moves[mv as usize].pose,
                );
                let seg = Line { hi, ..*line };
                let e = if a.axis == b.axis {
                    if misses_column_at_top(&seg, c0, c1, a.axis, rr) {
                        return hi;
                    }
                    crate::column::column_translation_entry(&seg, c0, c1, a.axis, rr, false)
                } else {
                    // The closed-form hull first: most lines pass clear of a rotating
                    // move's columns, whose search costs some 90 poses.
                    rf.geometry(mv)
                        .filter(|g| g.column_hull_entry(&seg).is_some())
                        .and_then(|g| g.column_entry(&seg, false))
                };
                match e {
                    Some(e) => {
                        take_least(e, mv, found);
                        hi.min(e.s - tie)
                    }
                    None => hi,
                }
            };
            columns.visit(line, hi, f);
        };
    // `column_entry` over a group's laid-out columns: the same tests, in the same order.
    let column_listed = |line: &Line,
                         hi: f64,
                         found: &mut Option<(Entry, u32)>,
                         tests: &mut usize,
                         listed: &[&ColumnListed]| {
        let tie = column_tie(rr);
        let mut hi = found.map_or(hi, |(e, _)| e.s) - tie;
        let inv = DVec3::new(1.0 / line.n.x, 1.0 / line.n.y, 1.0 / line.n.z);
        let finite = inv.is_finite();
        // The segment's box (to `hi` as it stands now: it only shrinks) against each
        // column's first: comparisons where the slab test divides.
        let (slo, shi) = segment_bounds(line, hi);
        for c in listed {
            if !(boxes_meet(c.bl, c.bh, slo, shi)
                && segment_box_of(finite, line.o, inv, c.bl, c.bh, line.lo, hi))
            {
                continue;
            }
            *tests += 1;
            if clear_of_column(line.o + hi * line.n, line.n, c.across, c.k, rr) {
                continue;
            }
            let seg = Line { hi, ..*line };
            if let Some(e) =
                crate::column::column_translation_entry(&seg, c.c0, c.c1, c.k, rr, false)
            {
                take_least(e, c.mv, found);
                hi = hi.min(e.s - tie);
            }
        }
    };
    // Both surface models: the imprint surface holds the cutter's corner only. The rest of
    // the cutter is searched directly, move by move: its column (the cutter above its
    // corner, which cuts a wall with its side and reaches deeper than the vectors do) is
    // entered exactly, and a vector that starts inside a move's puck (which may cross none
    // of its triangles) is entered at its start. The least entry below `hi` and its move:
    // among starts the lowest-numbered move; a column's entry only if it lies below the
    // best found by more than rounding (see `tie`).
    let cutter_entry = |line: &Line, hi: f64, tests: &mut usize| -> Option<(Entry, u32)> {
        let mut found: Option<(Entry, u32)> = None;
        let start = line.o + line.lo * line.n;
        pucks.visit(line, line.lo, |ci, hi| {
            let mv = pucks.items[ci].1;
            // Held by a lower-numbered move already: the start is the least entry.
            if found.is_some_and(|(_, fm)| mv >= fm) {
                return hi;
            }
            *tests += 1;
            if let Some(g) = rf.geometry(mv)
                && g.puck_holds(start)
            {
                let e = Entry {
                    s: line.lo,
                    normal: -line.n,
                };
                take_least(e, mv, &mut found);
            }
            hi
        });
        column_entry(line, hi, &mut found, tests);
        found
    };
    let facing_ok = |f: f64| facing == Facing::Any || f < 0.0;
    type PerVector = (Deviation, f64, Option<f64>, Option<Source>, [usize; 5]);
    // A vector's first entry into the union of the moves' volumes, every move a translation:
    // the least entry into a move's puck (closed form for a ball and a flat end mill, Newton
    // for a bull, whose puck lies in the capsule of radius `a + r` about the centre's
    // segment, tested first), then into a column's side (`column_entry`); among equal
    // entries the lowest-numbered move's. This is the brute force over every move, pruned by
    // the boxes the shrinking segment `lo..best` still meets.
    let common_axis = {
        let mut axes = feed_moves(toolpath, 0.0).map(|(_, a, _, _, _)| a.axis);
        let first = axes.next();
        first.filter(|&k| axes.all(|a| a == k))
    };
    let axis_of = |mv: u32| common_axis.unwrap_or_else(|| toolpath.moves[mv as usize].pose.axis);
    let entry_of = |line: &Line, mv: u32, c0: DVec3, c1: DVec3| {
        crate::exact::translation_entry(line, &puck, c0, c1, axis_of(mv))
    };
    let seed_of = |mv: u32| {
        let (a, b) = (
            toolpath.moves[mv as usize - 1].pose,
            toolpath.moves[mv as usize].pose,
        );
        Some((mv, a.tip + puck.r * a.axis, b.tip + puck.r * b.axis))
    };
    // The squared distance from `p` to a seed's core: the disk of radius `a` about its
    // centres, swept (for a ball, the centres' segment). The puck's surface lies `r` out
    // from the core, so the move whose core lies nearest a vector's origin is the one whose
    // puck most likely holds its first entry (exactly so for a ball where the nearest centre
    // lies along the vector's normal). Taken from the moves' segment alone: its nearest
    // point to `p`, with the offset across the axis shortened by `a`.
    let core_distance2 = |p: DVec3, seed: &Seed| {
        let (mv, c0, d) = (seed.at.0, seed.at.1, seed.d);
        let w = p - from_segment(p, c0, d, seed.inv_dd);
        if puck.a > 0.0 {
            let k = axis_of(mv);
            let along = w.dot(k);
            let across = ((w - along * k).length() - puck.a).max(0.0);
            across * across + along * along
        } else {
            w.length_squared()
        }
    };
    // `among`: the items of `volumes` to search instead of the tree (a superset of those the
    // vector's segment up to its seed's entry meets; see the tiles below), or `None` for the
    // tree; the columns likewise, laid out (`columns_listed`, see `column_listed`).
    // The entry of `v` into the seed's move (a move that cut a neighbour), if it faces
    // right: it bounds the search from the start. The search skips that move while it holds
    // the best (its first entry is known).
    let seed_entry = |v: &Vector, (mv, c0, c1): (u32, DVec3, DVec3)| {
        let line = Line {
            o: v.o,
            n: v.n,
            lo: v.lo,
            hi: v.hi,
        };
        // A bull's without the test at the segment's top (see `exact::convex_entry`).
        let e = if bull {
            let k = axis_of(mv);
            common_axis
                .filter(|&axis| line.n == axis)
                .and_then(|axis| crate::exact::axial_entry(&line, &puck, c0, c1, axis))
                .unwrap_or_else(|| crate::exact::convex_entry(&line, &puck, (c0, c1), k, false))
        } else {
            entry_of(&line, mv, c0, c1)
        };
        e.filter(|e| facing_ok(e.normal.dot(v.n))).map(|e| (e, mv))
    };
    // `seeded`: whether a seed was tried, and its entry (`seed_entry`).
    let direct_one = |v: &Vector,
                      seeded: (bool, Option<(Entry, u32)>),
                      among: Option<&[u32]>,
                      listed: Option<(&[&RunListed], &[Listed])>,
                      pucks_listed: Option<&[&PuckListed]>,
                      columns_listed: Option<&[&ColumnListed]>|
     -> PerVector {
        let mut stats = [0usize; 5];
        let line = Line {
            o: v.o,
            n: v.n,
            lo: v.lo,
            hi: v.hi,
        };
        let (tried, mut found) = seeded;
        stats[1] += usize::from(tried);
        let mut try_move = |ci: usize, found: &mut Option<(Entry, u32)>| {
            let (_, mv, c0, c1) = volumes.items[ci];
            let seg = Line {
                hi: found.map_or(v.hi, |(f, _)| f.s),
                ..line
            };
            stats[1] += 1;
            if let Some(e) = entry_of(&seg, mv, c0, c1)
                && facing_ok(e.normal.dot(v.n))
            {
                take_least(e, mv, found);
            }
        };
        let hi0 = found.map_or(v.hi, |(f, _)| f.s);
        if puck.a > 0.0 && puck.r > 0.0 {
            // The programme's one axis, where the line runs along it (see
            // `exact::axial_entry`).
            let axial = common_axis.filter(|&k| line.n == k);
            // A bull's entry costs a Newton search. The moves near the segment up to the best
            // entry so far are taken as they come, each only while where the line enters its
            // slab (the puck lies within `r` of the centres along `k`) is no later than that
            // best. Two closed-form tests turn most away: the distance at the segment's top
            // to the capsule of radius `a + r` (which holds the puck), and a plane between
            // the segment and the puck itself (`exact::separated_by_plane`; on the dome's
            // bull program 15.0 -> 13.1 G instructions). The capsule's entry, once a third
            // test, turned away 1 in 760 of the moves these leave on the dome (1 in 7 on
            // mount_rush) and cost more than the Newton searches it saved: dome bull 8.00 ->
            // 7.48 G, mount_rush 68.5 -> 66.4 G. It also decided a line grazing the puck's rim
            // (where the capsule touches the puck) apart from the puck's own search, which
            // a seed's entry uses. Queueing the moves in the order of their slabs' entries
            // instead, tested against the seed's entry, cost more than the order pruned:
            // dome bull 10.22 G with the queue, 9.55 G without.
            let mut consider = |s0: f64, s1: f64, ci: usize, found: &mut Option<(Entry, u32)>| {
                let (_, mv, c0, c1) = volumes.items[ci];
                // The move that holds the best (the seed's, mostly) has had its first entry
                // searched already.
                if cannot_beat(*found, mv, s0) {
                    return;
                }
                let best = found.map_or(hi0, |(f, _)| f.s);
                let seg = Line {
                    lo: s0,
                    hi: best.min(s1),
                    ..line
                };
                if seg.lo > seg.hi
                    || misses_capsule_at_top(&seg, seg.hi, c0, c1, rr)
                    || crate::exact::separated_by_plane(&seg, &puck, c0, c1, axis_of(mv))
                {
                    return;
                }
                try_move(ci, found);
            };
            // A line along the axis (a floor's) meets the envelope below the move: whether
            // that decided the move (the same early turn-aways as in `consider`).
            let axial_decides = |s0: f64, ci: usize, found: &mut Option<(Entry, u32)>| {
                let Some(k) = axial else {
                    return false;
                };
                let (_, mv, c0, c1) = volumes.items[ci];
                if cannot_beat(*found, mv, s0) {
                    return true;
                }
                let best = found.map_or(hi0, |(f, _)| f.s);
                consider_axial(&line, best, &puck, (c0, c1), k, mv, facing, found)
            };
            let mut f = |ci: usize, hi: f64| {
                let (_, mv, c0, c1) = volumes.items[ci];
                if near_capsule(&line, hi, volumes.mids[ci], rr) {
                    let k = axis_of(mv);
                    if let Some((s0, s1)) = slab_interval(&line, k, c0.dot(k), c1.dot(k), puck.r) {
                        let (s0, s1) = (line.lo.max(s0), hi.min(s1));
                        if s0 <= s1 && !axial_decides(s0, ci, &mut found) {
                            consider(s0, s1, ci, &mut found);
                        }
                    }
                }
                found.map_or(hi, |(f, _)| f.s.min(hi))
            };
            match (pucks_listed, among) {
                (Some(listed), _) => {
                    // `f` on the laid-out moves: the same tests in the same order.
                    let inv = DVec3::new(1.0 / line.n.x, 1.0 / line.n.y, 1.0 / line.n.z);
                    let finite = inv.is_finite();
                    // The line seen along the programme's one axis, if it has one.
                    let along = common_axis.map(|k| (line.o.dot(k), line.n.dot(k)));
                    // The segment's box to `hi0` (it only shrinks) against each move's
                    // first, as for the columns.
                    let (slo, shi) = segment_bounds(&line, hi0);
                    for c in listed {
                        let hi = found.map_or(hi0, |(f, _)| f.s.min(hi0));
                        if !(boxes_meet(c.bl, c.bh, slo, shi)
                            && segment_box_of(finite, line.o, inv, c.bl, c.bh, line.lo, hi))
                        {
                            continue;
                        }
                        if !meets_sphere(&line, hi, c.mid, c.rho2) {
                            continue;
                        }
                        let seen = along.unwrap_or_else(|| (line.o.dot(c.k), line.n.dot(c.k)));
                        let Some((s0, s1)) = slab_interval_at(seen, c.z0, c.z1, puck.r) else {
                            continue;
                        };
                        let (s0, s1) = (line.lo.max(s0), hi.min(s1));
                        if s0 <= s1 && !axial_decides(s0, c.ci as usize, &mut found) {
                            consider(s0, s1, c.ci as usize, &mut found);
                        }
                    }
                }
                (None, Some(vols)) => volumes.visit_among(vols, &line, hi0, &mut f),
                (None, None) => volumes.visit(&line, hi0, &mut f),
            }
        } else {
            let f = |ci: usize, hi: f64| {
                let (_, mv, c0, c1) = volumes.items[ci];
                // With the best at the segment's start, only a lower-numbered move's tie
                // could replace it (see `take_least`).
                if hi <= line.lo && found.is_some_and(|(f, m)| f.s <= line.lo && mv >= m) {
                    return hi;
                }
                if near_capsule(&line, hi, volumes.mids[ci], rr)
                    && !misses_capsule_at_top(&line, hi, c0, c1, rr)
                    && !misses_capsule_at_bottom(&line, c0, c1, rr)
                {
                    try_move(ci, &mut found);
                }
                found.map_or(hi, |(f, _)| f.s.min(hi))
            };
            match (listed, among) {
                (Some((runs, listed)), _) => {
                    let rr2 = rr * rr;
                    // A vector no seed entered (pointing away from the moves, as on a
                    // folded skin's underside) is also turned away at its start, as in the
                    // trees' search below.
                    let at_start = found.is_none();
                    for run in runs {
                        // A run the segment provably misses holds no move it enters.
                        let hi = found.map_or(hi0, |(f, _)| f.s.min(hi0));
                        if !run.may_reach(&line, hi)
                            || (at_start && run.chord.missed_from_start(&line, run.rr2))
                        {
                            continue;
                        }
                        let members = &listed[run.first as usize..(run.first + run.count) as usize];
                        try_members(
                            &line,
                            hi0,
                            members,
                            rr2,
                            at_start,
                            &mut found,
                            &mut try_move,
                        );
                    }
                }
                (None, Some(vols)) => volumes.visit_among(vols, &line, hi0, f),
                (None, None) if runs.is_some() => {
                    // A vector no seed entered (most of them far from any move) walks the
                    // runs' tree, a third as many items as moves on mount_rush, and tests a
                    // run's members only where it may reach the run: the same moves tried,
                    // so the same least entry. A node is passed over where the segment
                    // provably stays farther than `r` and the largest slack from the box of
                    // its chords (its box shrunk by `r`, less a margin for the growth's
                    // rounding), decided at either end as for one capsule.
                    let rr2 = rr * rr;
                    let reach = rr + max_slack;
                    let start = line.o + line.lo * line.n;
                    let clear = |a: DVec3, b: DVec3, hi: f64| {
                        let eps = 1e-9 * (1.0 + reach + a.abs().max(b.abs()).max_element());
                        let (ca, cb) = (a + (rr - eps), b - (rr - eps));
                        clear_of_box(start, line.n, ca, cb, reach * reach)
                            || clear_of_box(line.o + hi * line.n, -line.n, ca, cb, reach * reach)
                    };
                    run_tree.visit_unless(&line, hi0, clear, |ci, _| {
                        let run = &run_lay[run_tree.items[ci].1 as usize];
                        let hi = found.map_or(hi0, |(f, _)| f.s.min(hi0));
                        if run.may_reach(&line, hi) && !run.chord.missed_from_start(&line, run.rr2)
                        {
                            let members =
                                &member_lay[run.first as usize..(run.first + run.count) as usize];
                            try_members(&line, hi0, members, rr2, true, &mut found, &mut try_move);
                        }
                        found.map_or(hi0, |(f, _)| f.s.min(hi0))
                    });
                }
                (None, None) if ball => volumes.visit_capsules(&line, hi0, puck.r, f),
                (None, None) => volumes.visit(&line, hi0, f),
            }
        }
        match columns_listed {
            Some(cl) => column_listed(&line, v.hi, &mut found, &mut stats[1], cl),
            None => column_entry(&line, v.hi, &mut found, &mut stats[1]),
        }
        let Some((e, mv)) = found.filter(|(e, _)| facing_ok(e.normal.dot(v.n))) else {
            let dev = Deviation {
                position: v.o,
                normal: v.n,
                signed_mm: None,
                source_move: None,
            };
            return (dev, 0.0, None, None, stats);
        };
        stats[0] = 1;
        stats[2] = 1;
        let dev = Deviation {
            position: v.o,
            normal: v.n,
            signed_mm: Some(e.s),
            source_move: Some(mv),
        };
        (dev, e.normal.dot(v.n), None, Some(Source::Move(mv)), stats)
    };
    let move_of = |c: &Crossing| {
        let (piece, _) = unkey(c.key);
        models[c.model as usize].pieces[piece].source_move()
    };
    let one = |(v, f): (&Vector, &crate::locate::Found)| -> PerVector {
        let mut stats = [0usize; 5];
        let dev = |s: Option<f64>, mv: Option<u32>| Deviation {
            position: v.o,
            normal: v.n,
            signed_mm: s,
            source_move: mv,
        };
        stats[4] = usize::from(f.overflow);
        let low = f.crossings.first();
        let linear = low.map(|l| (l.s, move_of(l), l.facing));
        let source_of = |c: &Crossing| {
            let m = models[c.model as usize];
            match m.pieces[unkey(c.key).0] {
                Piece::Strip { step, .. } | Piece::Gap { step, .. } => Source::Move(step.mv),
                Piece::Cap { frame, .. } => Source::Pose {
                    model: c.model,
                    frame,
                },
            }
        };
        let low_src = low.map(source_of);
        if !exact {
            stats[0] = usize::from(low.is_some());
            let line = Line {
                o: v.o,
                n: v.n,
                lo: v.lo,
                hi: v.hi,
            };
            let hi = linear.map_or(v.hi, |l| l.0);
            if let Some((e, mv)) = cutter_entry(&line, hi, &mut stats[1])
                && facing_ok(e.normal.dot(v.n))
                && linear.is_none_or(|l| e.s < l.0)
            {
                stats[0] = 1;
                let src = Some(Source::Move(mv));
                let lin = linear.map(|l| l.0);
                return (dev(Some(e.s), Some(mv)), e.normal.dot(v.n), lin, src, stats);
            }
            return match linear {
                Some((s, mv, fc)) => (dev(Some(s), Some(mv)), fc, Some(s), low_src, stats),
                None => (dev(None, None), 0.0, None, None, stats),
            };
        }
        let line = Line {
            o: v.o,
            n: v.n,
            lo: v.lo,
            hi: v.hi,
        };
        // Best refined entry: (entry, move, order key, source).
        type Best = Option<(Entry, u32, (u8, u64), Source)>;
        let mut best: Best = None;
        let better = |e: Entry, mv: u32, k: (u8, u64), src: Source, best: &mut Best| {
            if facing_ok(e.normal.dot(v.n))
                && best.is_none_or(|(b, _, bk, _)| e.s < b.s || (e.s == b.s && k < bk))
            {
                *best = Some((e, mv, k, src));
            }
        };
        let mut done: Vec<(u8, u64)> = Vec::new();
        // A crossing whose refinement found no entry where the answer is not in closed
        // form (a rotating move's search): then the linear value stands in.
        let mut inconclusive = false;
        if let Some(low) = low {
            // Each crossing's true surface lies at most its window below it. In order of
            // the crossings (lowest first): none beyond the best entry found plus the
            // largest window can win; one whose own window does not reach below the best
            // entry, or below the lowest crossing, cannot either. The lowest crossing here
            // is the lowest not refuted: a crossing whose exact volume the line does not
            // enter (it grazes a sheet's edge, or a flat sheet with no window at all) says
            // nothing about where the line enters, and the next one stands in for it.
            let mut floor = low.s;
            let mut refuted: Vec<(u8, u64)> = Vec::new();
            let mut all_refuted = true;
            for c in &f.crossings {
                if best.is_some_and(|b| c.s - delta > b.0.s) {
                    break;
                }
                if all_refuted {
                    floor = c.s;
                }
                let id = rf.identity(c);
                if done.contains(&id) {
                    all_refuted &= refuted.contains(&id);
                    continue;
                }
                let (piece, _) = unkey(c.key);
                let m = models[c.model as usize];
                // Where the path turns at one of the step's poses the true surface holds
                // the tool there (the fan between the imprint curves of the two
                // directions), which the strips can miss by up to R(1 − cos(turn/2)).
                let fan = match m.pieces[piece] {
                    Piece::Strip { frame, .. } => {
                        let t = m.turn[frame as usize].max(m.turn[frame as usize + 1]);
                        m.cutter().radius() * (1.0 - (0.5 * t).cos())
                    }
                    _ => 0.0,
                };
                let sag = f64::from(m.sag[piece]);
                let d = ((SAFETY * sag + fan) / c.facing.abs().max(MIN_FACING)).min(delta);
                // A candidate whose surface cannot lie below the best entry (ties
                // included: they would not change the answer) is not refined.
                if c.s > floor + d || best.is_some_and(|b| c.s - d >= b.0.s) {
                    all_refuted = false;
                    continue;
                }
                done.push(id);
                stats[1] += 1;
                if let Some((e, mv)) = rf.refine(&line, c) {
                    let src = match source_of(c) {
                        Source::Move(_) => Source::Move(mv),
                        p => p,
                    };
                    better(e, mv, (c.model, c.key), src, &mut best);
                    all_refuted = false;
                } else if !rf.answers_exactly(c) && !rf.proves_miss(&line, c) {
                    inconclusive = true;
                    all_refuted = false;
                } else {
                    refuted.push(id);
                }
                // A translation's neighbours at the step's ends: near a joint the other
                // move's volume may be the lower one.
                if let Piece::Strip { step, .. } = m.pieces[piece]
                    && id.0 == u8::MAX
                {
                    let ends = [
                        (step.u_from.min(step.u_to) == 0.0, step.mv.checked_sub(1)),
                        (step.u_from.max(step.u_to) == 1.0, Some(step.mv + 1)),
                    ];
                    for (touch, adj) in ends {
                        let Some(am) = adj.filter(|_| touch) else {
                            continue;
                        };
                        let Some(ga) = rf.feed_geometry(am).filter(|g| g.is_translation()) else {
                            continue;
                        };
                        let aid = (u8::MAX, am as u64);
                        if done.contains(&aid) {
                            continue;
                        }
                        done.push(aid);
                        stats[1] += 1;
                        if let Some(e) = ga.translation_entry(&line) {
                            better(e, am, aid, Source::Move(am), &mut best);
                        }
                    }
                }
            }
        }
        if let Some(extras) = &lay.extras {
            let hi = best.map_or(v.hi, |b| b.0.s);
            extras.visit(&line, hi, |ci, hi| {
                let (mi, pi, c, _) = extras.items[ci];
                let seg = Line { hi, ..line };
                let model = models[mi as usize];
                match model.pieces[pi as usize] {
                    Piece::Cap { frame, mv } => {
                        let k = model.frames[frame as usize].axis;
                        // The puck lies in the cylinder of radius a + r, half-height
                        // r about its torus centre: much tighter than the bounding
                        // sphere along the axis (a tool resting on a face).
                        let bound =
                            crate::exact::cylinder_entry(&seg, c, k, puck.a + puck.r, puck.r);
                        if bound.is_none_or(|s| s > hi) {
                            return hi;
                        }
                        let pose = cam_core::Pose {
                            tip: c - puck.r * k,
                            axis: k,
                        };
                        let g = MoveGeometry {
                            a: pose,
                            b: pose,
                            puck,
                        };
                        stats[1] += 1;
                        if let Some(e) = g.entry_at(&seg, 0.0) {
                            let src = Source::Pose { model: mi, frame };
                            better(e, mv, (mi, (pi as u64) << 32), src, &mut best);
                        }
                    }
                    Piece::Gap { step, .. } => {
                        let Some(g) = rf.feed_geometry(step.mv) else {
                            return hi;
                        };
                        let id = if g.is_translation() {
                            (u8::MAX, step.mv as u64)
                        } else {
                            (mi, pi as u64)
                        };
                        if done.contains(&id) {
                            return hi;
                        }
                        done.push(id);
                        stats[1] += 1;
                        let e = if g.is_translation() {
                            g.translation_entry(&seg)
                        } else {
                            let (u0, u1) = (step.u_from.min(step.u_to), step.u_from.max(step.u_to));
                            let du = u1 - u0;
                            g.entry_min_over(&seg, (u0 - du).max(0.0), (u1 + du).min(1.0))
                                .map(|(e, _)| e)
                        };
                        if let Some(e) = e {
                            let k = (id.0, ((pi as u64) << 32) | (id.1 & 0xffff_ffff));
                            better(e, step.mv, k, Source::Move(step.mv), &mut best);
                        }
                    }
                    Piece::Strip { .. } => {}
                }
                best.map_or(hi, |b| b.0.s.min(hi))
            });
        }
        // The rest of the cutter (see `cutter_entry`).
        let hi = best.map_or(v.hi, |b| b.0.s);
        if let Some((e, mv)) = cutter_entry(&line, hi, &mut stats[1]) {
            better(e, mv, (COLUMN, mv as u64), Source::Move(mv), &mut best);
        }
        // A reading inside a rotating move's swept puck (its own move's, or a neighbour's
        // across a shared pose) by more than `INSIDE_MM` is provably not the first entry: the
        // line was inside just before it. That move's poses are searched below it, until no
        // such move holds the reading (a cap at a pass start, which is one pose, can stand
        // in front of its own move's sheet).
        for _ in 0..4 {
            let Some((e, mv, _, _)) = best else { break };
            let p = line.o + e.s * line.n;
            let holder = [mv.checked_sub(1), Some(mv), Some(mv + 1)]
                .into_iter()
                .flatten()
                .filter_map(|m| Some((m, rf.feed_geometry(m)?)))
                .find(|(_, g)| !g.is_translation() && g.depth_at(p) > INSIDE_MM);
            let Some((m, g)) = holder else { break };
            stats[1] += 1;
            let seg = Line { hi: e.s, ..line };
            match g.entry_min_over(&seg, 0.0, 1.0) {
                Some((ne, _)) if ne.s < e.s => {
                    better(ne, m, (u8::MAX, m as u64), Source::Move(m), &mut best);
                }
                _ => break,
            }
        }
        match (best, linear) {
            (Some((e, mv, _, src)), _) => {
                stats[0] = 1;
                stats[2] = 1;
                let lin = linear.map(|l| l.0);
                (
                    dev(Some(e.s), Some(mv)),
                    e.normal.dot(v.n),
                    lin,
                    Some(src),
                    stats,
                )
            }
            (None, Some(_)) if !inconclusive => {
                // Every located crossing was tested exactly and the line enters none of
                // their volumes: it passes within the triangles' margin of the swept
                // surface but outside it.
                stats[0] = 1;
                (dev(None, None), 0.0, linear.map(|l| l.0), None, stats)
            }
            (None, Some((s, mv, fc))) => {
                // Crossings located but none refined: keep the linear value.
                stats[0] = 1;
                stats[3] = 1;
                (dev(Some(s), Some(mv)), fc, Some(s), low_src, stats)
            }
            (None, None) => (dev(None, None), 0.0, None, None, stats),
        }
    };
    // Located in chunks, for progress; searched directly in chunks of equal size up to 2^20
    // vectors, progress reported per tile (in chunks of 2^17, sphere_on_plate's ball
    // program's 134,989 vectors made a second chunk of 3,917 whose 16 tiles, sorted apart
    // from their neighbours, took a twelfth of the search's time). Each vector's answer
    // depends on the vector alone.
    // Kept compact (the vector's position and normal are put back at the end) and the
    // counts summed per tile: these records are copied and placed, and at several hundred
    // thousand vectors their size is felt.
    let add = |sum: &mut [usize; 5], s: &[usize; 5]| {
        for (a, b) in sum.iter_mut().zip(s) {
            *a += b;
        }
    };
    let pass = |vectors: Vectors<'_>, progress: Option<Progress<'_>>| -> Measurement {
        let mut readings: Vec<Reading> = Vec::with_capacity(vectors.len());
        let mut stats = [0usize; 5];
        let chunk_len = if direct {
            vectors
                .len()
                .div_ceil(vectors.len().div_ceil(DIRECT_CHUNK).max(1))
        } else {
            MEASURE_CHUNK
        };
        // The vectors searched so far, reported in order under the lock.
        let searched = std::sync::Mutex::new(0usize);
        let chunk_len = chunk_len.max(1);
        for start in (0..vectors.len()).step_by(chunk_len) {
            let chunk = vectors.range(start..(start + chunk_len).min(vectors.len()));
            if direct {
                // In tiles of neighbouring vectors (Morton order of their origins), each seeded
                // by the move that cut one before it; the seeds only prune (the answers do not
                // depend on them, but for the last bits of a bull's Newton solve).
                let codes = match chunk {
                    Vectors::Given(vs) => crate::locate::morton_codes_by(vs, |v| v.o),
                    Vectors::Mesh { o, .. } => crate::locate::morton_codes_by(o, |&p| p),
                };
                let mut order: Vec<(u64, u32)> =
                    codes.into_par_iter().zip(0..chunk.len() as u32).collect();
                crate::radix::sort_by_key(&mut order, |k| k.0);
                let done: Vec<TileReadings> = order
                    .par_chunks(DIRECT_TILE)
                    // One tile per piece: tiles differ in cost with the part's shape (a flat
                    // floor, a steep wall), and rayon's default split can leave a whole half
                    // of them on one thread (the dome's measure scaled 1.5x to 2 threads).
                    .with_max_len(1)
                    .map(|tile| {
                        let (mut vols, mut cols, mut pending, mut unseeded) =
                            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
                        // The group's laid-out runs, moves and columns (by reference: copies
                        // of each for every group cost sphere_on_plate's ball program 1 %).
                        let mut rlay: Vec<&RunListed> = Vec::new();
                        let mut play: Vec<&PuckListed> = Vec::new();
                        let mut clay: Vec<&ColumnListed> = Vec::new();
                        // The moves and columns near the tile's vectors, from their starts to
                        // `TILE_REACH_MM` out, gathered once: a group whose box lies within
                        // filters these instead of walking the trees (the same lists).
                        let (mut tlo, mut thi) =
                            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
                        for &(_, i) in tile {
                            let v = &chunk.get(i as usize);
                            let (p, q) = (v.o + v.lo * v.n, v.o + v.hi.min(TILE_REACH_MM) * v.n);
                            (tlo, thi) = (tlo.min(p).min(q), thi.max(p).max(q));
                        }
                        let tpad = 1e-9 * (1.0 + tlo.abs().max(thi.abs()).max_element());
                        (tlo, thi) = (tlo - tpad, thi + tpad);
                        let (mut tile_vols, mut tile_cols) = (Vec::new(), Vec::new());
                        let tile_listed = (
                            move_tree.gather(tlo, thi, move_round, TILE_MOVES, &mut tile_vols),
                            columns.gather(tlo, thi, 0.0, TILE_COLUMNS, &mut tile_cols),
                        );
                        let mut out = Vec::with_capacity(tile.len());
                        let mut sum = [0usize; 5];
                        // The moves that answered last, distinct, oldest first: the seeds.
                        // (Each with its segment laid out once: worked out again for every
                        // vector it cost 1 % more: sphere_on_plate ball 1,601 against 1,587 M
                        // instructions, the dome's 1,696 against 1,681 M.)
                        let mut recent: Vec<Seed> = Vec::with_capacity(RECENT_SEEDS);
                        let mut keep = |i: u32, r: PerVector, recent: &mut Vec<Seed>| {
                            if let Some(mv) = r.0.source_move {
                                let seed = match recent.iter().position(|m| m.at.0 == mv) {
                                    Some(k) => Some(recent.remove(k)),
                                    None => {
                                        if recent.len() == RECENT_SEEDS {
                                            recent.remove(0);
                                        }
                                        seed_of(mv).map(Seed::of)
                                    }
                                };
                                recent.extend(seed);
                            }
                            add(&mut sum, &r.4);
                            out.push((i, Reading::of(&r)));
                        };
                        let mut alone = true;
                        for group in tile.chunks(DIRECT_GROUP) {
                            // A vector's entry into the latest of the recent moves it enters
                            // bounds its search; a vector they all miss is searched in the
                            // trees, and seeds the next. Once such a vector enters nothing
                            // (pointing away from the moves, as on a folded skin's underside),
                            // its neighbours that no seed enters likely enter nothing either
                            // and seed nothing: from then on each group's are searched
                            // together, until one of them enters a move.
                            pending.clear();
                            unseeded.clear();
                            for &(_, i) in group {
                                let v = &chunk.get(i as usize);
                                // The recent move nearest the vector first (the latest among
                                // equals), then the others, latest first. Tried latest first
                                // alone, half the vectors of sphere_on_plate's and the dome's
                                // ball programs were bounded more than 10 µm above their first
                                // entry, and searched twice as many runs as the others; the
                                // nearest first, a fifth. Callgrind (1 thread, M instructions):
                                // sphere_on_plate ball 1,806 -> 1,751, dome ball 1,870 ->
                                // 1,794, mount_rush ball 13,395 -> 13,113, sphere_on_plate
                                // bull 6,272 -> 6,120, dome bull 5,806 -> 5,718,
                                // sphere_on_plate flat 4,237 -> 4,242. Also trying the second
                                // nearest, and keeping the lower entry, cost more than it
                                // saved (sphere_on_plate ball 1,819).
                                let mut nearest: Option<(f64, (u32, DVec3, DVec3))> = None;
                                for seed in recent.iter().rev() {
                                    let d = core_distance2(v.o, seed);
                                    if nearest.is_none_or(|(best, _)| d < best) {
                                        nearest = Some((d, seed.at));
                                    }
                                }
                                let first = nearest.map(|(_, seed)| seed.0);
                                let bound = nearest
                                    .and_then(|(_, seed)| seed_entry(v, seed))
                                    .or_else(|| {
                                        recent
                                            .iter()
                                            .rev()
                                            .filter(|m| Some(m.at.0) != first)
                                            .find_map(|m| seed_entry(v, m.at))
                                    });
                                let tried = !recent.is_empty();
                                match bound {
                                    Some(b) => pending.push((i, (true, Some(b)))),
                                    None if alone => {
                                        let r =
                                            direct_one(v, (tried, None), None, None, None, None);
                                        alone = r.0.source_move.is_some();
                                        keep(i, r, &mut recent);
                                    }
                                    None => unseeded.push((i, (tried, None))),
                                }
                            }
                            for (set, together) in [(&unseeded, true), (&pending, false)] {
                                if set.is_empty() {
                                    continue;
                                }
                                // Each set searches only the moves and columns that can reach the
                                // box of its segments (up to their seeds' entries, or whole;
                                // padded for rounding), gathered once for the set. Where that box
                                // holds too many (a dense program), each vector searches the
                                // trees, which prune by its own segment. Searched so, the
                                // unseeded vectors of mount_rush's ball program (folded skin)
                                // cost it 15 % fewer instructions than searched one by one in
                                // the trees (16.1 G -> 13.6 G); all unseeded vectors searched
                                // together, 13.5 G, but sphere_on_plate's and the dome's
                                // programs 1 % to 9 % more.
                                let (mut lo, mut hi) =
                                    (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
                                for &(i, (_, seed)) in set.iter() {
                                    let v = &chunk.get(i as usize);
                                    let top = seed.map_or(v.hi, |(e, _)| e.s);
                                    let (p, q) = (v.o + v.lo * v.n, v.o + top * v.n);
                                    (lo, hi) = (lo.min(p).min(q), hi.max(p).max(q));
                                }
                                let pad = 1e-9 * (1.0 + lo.abs().max(hi.abs()).max_element());
                                (lo, hi) = (lo - pad, hi + pad);
                                vols.clear();
                                cols.clear();
                                let within = lo.cmpge(tlo).all() && hi.cmple(thi).all();
                                let listed = (
                                    if within && tile_listed.0 {
                                        move_tree.gather_from(
                                            &tile_vols, lo, hi, move_round, move_limit, &mut vols,
                                        )
                                    } else {
                                        move_tree.gather(lo, hi, move_round, move_limit, &mut vols)
                                    },
                                    if within && tile_listed.1 {
                                        columns.gather_from(
                                            &tile_cols,
                                            lo,
                                            hi,
                                            0.0,
                                            DIRECT_COLUMNS,
                                            &mut cols,
                                        )
                                    } else {
                                        columns.gather(lo, hi, 0.0, DIRECT_COLUMNS, &mut cols)
                                    },
                                );
                                // A ball's listed runs (their members laid out once for all
                                // groups).
                                let moves = (runs.is_some() && listed.0).then(|| {
                                    rlay.clear();
                                    rlay.extend(vols.iter().map(|&ci| {
                                        &run_lay[run_tree.items[ci as usize].1 as usize]
                                    }));
                                    (&rlay[..], &member_lay[..])
                                });
                                // The listed columns, likewise. Every move of a program searched
                                // here keeps its axis; were one not to, the group's vectors would
                                // walk the column tree instead.
                                let column_moves = listed
                                    .1
                                    .then(|| {
                                        clay.clear();
                                        clay.extend(
                                            cols.iter()
                                                .map_while(|&ci| column_lay[ci as usize].as_ref()),
                                        );
                                        &clay[..]
                                    })
                                    .filter(|c| c.len() == cols.len());
                                // A bull's, likewise.
                                let bull_moves = (bull && listed.0).then(|| {
                                    play.clear();
                                    play.extend(vols.iter().map(|&ci| &puck_lay[ci as usize]));
                                    &play[..]
                                });
                                for &(i, seeded) in set.iter() {
                                    let v = &chunk.get(i as usize);
                                    // A ball's list holds runs, not moves.
                                    let among = (listed.0 && runs.is_none()).then_some(&vols[..]);
                                    let r = direct_one(
                                        v,
                                        seeded,
                                        among,
                                        moves,
                                        bull_moves,
                                        column_moves,
                                    );
                                    alone |= together && r.0.source_move.is_some();
                                    keep(i, r, &mut recent);
                                }
                            }
                        }
                        if let Some(p) = progress {
                            let mut done = searched.lock().unwrap_or_else(|e| e.into_inner());
                            *done += tile.len();
                            p(*done, vectors.len());
                        }
                        (out, sum)
                    })
                    .collect();
                // Back in the vectors' order: where each index's reading lies (its tile, its
                // place there), then the readings gathered in parallel.
                let mut at = vec![(u32::MAX, 0u32); chunk.len()];
                for (t, (out, sum)) in done.iter().enumerate() {
                    add(&mut stats, sum);
                    for (k, &(i, _)) in out.iter().enumerate() {
                        at[i as usize] = (t as u32, k as u32);
                    }
                }
                readings.par_extend(at.par_iter().map(|&(t, k)| {
                    assert!(t != u32::MAX, "every vector of the chunk measured once");
                    done[t as usize].0[k as usize].1
                }));
            } else {
                let owned: Vec<Vector>;
                let chunk = match chunk {
                    Vectors::Given(vs) => vs,
                    Vectors::Mesh { .. } => {
                        owned = (0..chunk.len())
                            .into_par_iter()
                            .map(|i| chunk.get(i))
                            .collect();
                        &owned
                    }
                };
                let found = find(chunk);
                let per: Vec<(Reading, [usize; 5])> = chunk
                    .par_iter()
                    .zip(found.par_iter())
                    .map(|x| {
                        let r = one(x);
                        (Reading::of(&r), r.4)
                    })
                    .collect();
                for (r, s) in per {
                    add(&mut stats, &s);
                    readings.push(r);
                }
                if let Some(p) = progress {
                    p(readings.len(), vectors.len());
                }
            }
        }
        let deviations = readings
            .par_iter()
            .enumerate()
            .map(|(i, r)| {
                let v = vectors.get(i);
                Deviation {
                    position: v.o,
                    normal: v.n,
                    signed_mm: r.signed_mm,
                    source_move: r.source_move,
                }
            })
            .collect();
        let facing = readings.par_iter().map(|r| r.facing).collect();
        let linear_mm = readings.par_iter().map(|r| r.linear_mm).collect();
        let source = readings.par_iter().map(|r| r.source).collect();
        let from_start = readings
            .par_iter()
            .enumerate()
            .map(|(i, r)| r.signed_mm == Some(vectors.get(i).lo))
            .collect();
        Measurement {
            deviations,
            facing,
            linear_mm,
            source,
            from_start,
            stats: MeasureStats {
                crossed: stats[0],
                refinements: stats[1],
                refined: stats[2],
                kept_linear: stats[3],
                overflow: stats[4],
            },
        }
    };
    let mut m = pass(vectors, progress);
    // The vectors picked again, each from its new inner end: their readings replace the
    // first ones (the counts stay the first pass's).
    let picks = redo.map_or_else(Vec::new, |f| f(&m));
    if !picks.is_empty() {
        let again: Vec<Vector> = picks
            .iter()
            .map(|&(i, l)| Vector {
                lo: -l,
                ..vectors.get(i)
            })
            .collect();
        let a = pass(Vectors::Given(&again), None);
        for (k, &(i, _)) in picks.iter().enumerate() {
            m.deviations[i] = a.deviations[k];
            m.facing[i] = a.facing[k];
            m.linear_mm[i] = a.linear_mm[k];
            m.source[i] = a.source[k];
            m.from_start[i] = a.from_start[k];
        }
    }
    m
}

/// A recent move that seeds the direct search: the move and its centres' ends (`at`), and
/// its centres' segment laid out as [`from_segment`] takes it.
struct Seed {
    at: (u32, DVec3, DVec3),
    d: DVec3,
    inv_dd: f64,
}

impl Seed {
    fn of(at: (u32, DVec3, DVec3)) -> Seed {
        let d = at.2 - at.1;
        Seed {
            at,
            d,
            inv_dd: inv_or_zero(d.length_squared()),
        }
    }
}

/// The vectors a measurement reads: given, or a mesh's vertices along their normals with one
/// inner and outer length for all (read as they are needed rather than copied).
#[derive(Clone, Copy)]
enum Vectors<'a> {
    Given(&'a [Vector]),
    Mesh {
        o: &'a [DVec3],
        n: &'a [DVec3],
        lo: f64,
        hi: f64,
    },
}

impl<'a> Vectors<'a> {
    fn len(&self) -> usize {
        match self {
            Vectors::Given(vs) => vs.len(),
            Vectors::Mesh { o, .. } => o.len(),
        }
    }

    /// Vector `i`.
    #[inline]
    fn get(&self, i: usize) -> Vector {
        match *self {
            Vectors::Given(vs) => vs[i],
            Vectors::Mesh { o, n, lo, hi } => Vector {
                o: o[i],
                n: n[i],
                lo,
                hi,
            },
        }
    }

    /// The vectors `r` of these.
    fn range(&self, r: std::ops::Range<usize>) -> Vectors<'a> {
        match *self {
            Vectors::Given(vs) => Vectors::Given(&vs[r]),
            Vectors::Mesh { o, n, lo, hi } => Vectors::Mesh {
                o: &o[r.clone()],
                n: &n[r],
                lo,
                hi,
            },
        }
    }
}

/// A tile's readings (by vector index in its chunk) and its summed counts.
type TileReadings = (Vec<(u32, Reading)>, [usize; 5]);

/// One vector's answer as kept between its search and the [`Measurement`] (see there).
#[derive(Debug, Clone, Copy)]
struct Reading {
    signed_mm: Option<f64>,
    source_move: Option<u32>,
    facing: f64,
    linear_mm: Option<f64>,
    source: Option<Source>,
}

impl Reading {
    fn of(r: &(Deviation, f64, Option<f64>, Option<Source>, [usize; 5])) -> Reading {
        Reading {
            signed_mm: r.0.signed_mm,
            source_move: r.0.source_move,
            facing: r.1,
            linear_mm: r.2,
            source: r.3,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A coordinate that is often exactly one of a few values, so that lines run along box
    /// faces and parallel to slabs.
    fn coord() -> impl Strategy<Value = f64> {
        prop_oneof![-2.0..2.0f64, Just(-1.0), Just(0.0), Just(1.0)]
    }

    fn v3() -> impl Strategy<Value = DVec3> {
        (coord(), coord(), coord()).prop_map(|(x, y, z)| DVec3::new(x, y, z))
    }

    proptest! {
        /// A run a segment is turned away from holds no move whose capsule the segment
        /// enters. Passes along arcs (radius 4 to 30 mm, moves 0.3 to 1 mm, runs bulging
        /// off their chords by up to the slack), segments ending within 0.1 mm of a random
        /// member's capsule (across it, every other one inside), coming in towards it at
        /// random angles.
        #[test]
        fn a_run_turned_away_holds_no_move_entered(
            radius in 4.0..30.0f64,
            step in 0.3..1.0f64,
            tilt in (-1.0..1.0f64, -1.0..1.0f64, 0.2..1.0f64),
            picks in prop::collection::vec(
                (0.0..1.0f64, 0.0..1.0f64, (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64),
                 (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64), 0.0..0.1f64, 0.0..3.0f64),
                64),
        ) {
            let rr = 3.0;
            let up = DVec3::new(tilt.0, tilt.1, tilt.2).normalize();
            let u = up.any_orthonormal_vector();
            let at = |i: usize| {
                let t = i as f64 * step / radius;
                radius * (t.sin() * u + (t.cos() - 1.0) * up)
            };
            let moves: Vec<(u32, u32, DVec3, DVec3)> =
                (0..40).map(|i| (i as u32 + 1, i as u32, at(i), at(i + 1))).collect();
            let runs = crate::chains::runs(moves.clone());
            let mut turned = 0usize;
            for (i, &(which, along, dir, n, off, len)) in picks.iter().enumerate() {
                // Every other point outside the member's capsule, the others inside.
                let off = if i % 2 == 0 { off } else { -off };
                let k = ((which * runs.ranges.len() as f64) as usize).min(runs.ranges.len() - 1);
                let run = RunListed::of(&runs, k, rr);
                let (first, count) = runs.ranges[k];
                let members = &runs.members[first as usize..(first + count) as usize];
                let (dir, n) = (DVec3::new(dir.0, dir.1, dir.2), DVec3::new(n.0, n.1, n.2));
                if dir.length() < 1e-3 || n.length() < 1e-3 {
                    continue;
                }
                // A point within 0.1 mm of a member's capsule surface (off its segment
                // across it); the segment ends there.
                let pick = ((along * count as f64) as usize).min(count as usize - 1);
                let m = moves[members[pick] as usize];
                let t = (m.3 - m.2).normalize();
                let across = dir - dir.dot(t) * t;
                if across.length() < 1e-3 {
                    continue;
                }
                let dir = across.normalize();
                let q = m.2.lerp(m.3, along) + (rr + off) * dir;
                // Coming in towards the member, mostly.
                let n = (0.5 * n.normalize() - dir).normalize();
                let line = Line { o: q - len * n, n, lo: 0.0, hi: len };
                if run.may_reach(&line, len) {
                    continue;
                }
                turned += 1;
                for &ci in members {
                    let (_, _, c0, c1) = moves[ci as usize];
                    prop_assert!(
                        crate::exact::capsule_entry(&line, c0, c1, rr).is_none(),
                        "run {} turned away a segment entering its move {}", k, ci
                    );
                }
            }
            prop_assert!(turned > 0);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(20_000))]

        /// The branch-free box test decides as the axis-by-axis one, lines parallel to
        /// slabs and lying in their boundary planes included.
        #[test]
        fn segment_box_decides_as_axis_by_axis(
            o in v3(),
            n in v3(),
            a in v3(),
            b in v3(),
            t0 in prop_oneof![-3.0..3.0f64, Just(0.0)],
            len in prop_oneof![0.0..4.0f64, Just(0.0)],
        ) {
            prop_assume!(n.length() > 1e-3);
            let n = n.normalize();
            let inv = DVec3::new(1.0 / n.x, 1.0 / n.y, 1.0 / n.z);
            let (min, max) = (a.min(b), a.max(b));
            prop_assert_eq!(
                segment_box(o, inv, min, max, t0, t0 + len),
                segment_box_axes(o, inv, min, max, t0, t0 + len)
            );
        }

        /// A segment the top test or the bottom test rejects stays farther than `rr` from
        /// the centres' segment all along (sampled at 401 points) and enters no capsule: a
        /// top test that ignored the slope at the top would reject segments that dip into
        /// the capsule below it, and a bottom test that took the slope's sign at the bottom
        /// the wrong way would reject segments that rise into it (checked: it fails then).
        #[test]
        fn top_and_bottom_tests_reject_only_segments_clear_of_the_capsule(
            o in v3(),
            n in v3(),
            c0 in v3(),
            c1 in v3(),
            t0 in -3.0..0.0f64,
            len in 0.0..4.0f64,
            rr in 0.05..1.5f64,
        ) {
            prop_assume!(n.length() > 1e-3);
            let line = Line { o, n: n.normalize(), lo: t0, hi: t0 + len };
            if misses_capsule_at_top(&line, line.hi, c0, c1, rr)
                || misses_capsule_at_bottom(&line, c0, c1, rr)
            {
                clear_of_the_capsule(&line, c0, c1, rr)?;
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(20_000))]

        /// A node the box tests of `Extras::visit_capsules` pass over holds no capsule the
        /// segment comes near: any segment inside the box (corners and faces included) is
        /// clear of the segment as `clear_of_the_capsule` checks. Reversing the slope
        /// condition fails here (checked).
        #[test]
        fn box_tests_pass_over_only_boxes_clear_of_every_capsule_in_them(
            o in v3(),
            n in v3(),
            a in v3(),
            b in v3(),
            f0 in prop_oneof![Just(DVec3::splat(-2.0)), Just(DVec3::splat(2.0)), v3()],
            f1 in prop_oneof![Just(DVec3::splat(-2.0)), Just(DVec3::splat(2.0)), v3()],
            t0 in -3.0..0.0f64,
            len in 0.0..4.0f64,
            rr in 0.05..1.5f64,
        ) {
            prop_assume!(n.length() > 1e-3);
            let line = Line { o, n: n.normalize(), lo: t0, hi: t0 + len };
            let (lo, hi) = (a.min(b), a.max(b));
            let start = line.o + line.lo * line.n;
            let top = line.o + line.hi * line.n;
            let rr2 = rr * rr;
            if !(clear_of_box(start, line.n, lo, hi, rr2) || clear_of_box(top, -line.n, lo, hi, rr2)) {
                return Ok(());
            }
            // Points of the box: fractions in 0..=1 per axis (`v3` spans -2..2).
            let at = |f: DVec3| lo + (hi - lo) * ((f + 2.0) / 4.0).clamp(DVec3::ZERO, DVec3::ONE);
            clear_of_the_capsule(&line, at(f0), at(f1), rr)?;
        }
    }

    proptest! {
        /// `Extras::near_box` lists a segment exactly when it passes within `round` of the
        /// box: never when every point lies farther (the distance to the box sampled at
        /// 2001 points along it, less what the sampling can miss), always when a sampled
        /// point lies within.
        #[test]
        fn near_box_decides_by_the_distance_to_the_box(
            c0 in v3(),
            d in prop_oneof![Just(DVec3::ZERO), v3()],
            a in v3(),
            b in v3(),
            round in 0.0..1.5f64,
        ) {
            let c1 = c0 + d;
            let e = Extras::from_items(
                vec![(PUCK, 1, c0, c1)],
                vec![(c0.min(c1) - round, c0.max(c1) + round)],
                0.0,
            );
            let (lo, hi) = (a.min(b), a.max(b));
            let dist = (0..=2000)
                .map(|i| {
                    let p = c0.lerp(c1, i as f64 / 2000.0);
                    (p - p.clamp(lo, hi)).length()
                })
                .fold(f64::INFINITY, f64::min);
            // Between samples the distance to the box falls by at most half their spacing.
            let miss = 0.5 * d.length() / 2000.0;
            let near = e.near_box(0, lo, hi, round);
            if dist <= round {
                prop_assert!(near, "a point {dist} from the box, within {round}: not listed");
            }
            if dist - miss > round * (1.0 + 1e-9) {
                prop_assert!(!near, "every point beyond {round} (least {dist}): listed");
            }
        }
    }

    /// The segment `lo..hi` of `line` stays farther than `rr` from the segment `c0`–`c1`
    /// (sampled at 401 points, the distance computed here) and enters no capsule.
    fn clear_of_the_capsule(
        line: &Line,
        c0: DVec3,
        c1: DVec3,
        rr: f64,
    ) -> Result<(), TestCaseError> {
        let d = c1 - c0;
        let dd = d.length_squared();
        let dist = |t: f64| {
            let q = line.o + t * line.n;
            let u = if dd > 0.0 {
                ((q - c0).dot(d) / dd).clamp(0.0, 1.0)
            } else {
                0.0
            };
            q.distance(c0 + u * d)
        };
        for i in 0..=400 {
            let t = line.lo + (line.hi - line.lo) * f64::from(i) / 400.0;
            prop_assert!(dist(t) > rr, "at {t}: {} <= {rr}", dist(t));
        }
        prop_assert!(crate::exact::capsule_entry(line, c0, c1, rr).is_none());
        Ok(())
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(20_000))]

        /// A segment the column's top test rejects enters neither the columns (side or
        /// base, by `column::column_translation_entry`) nor any point of them: tilted axes,
        /// lines along the axis and moves along it included. Without the slope condition
        /// the test fails here (checked).
        #[test]
        fn column_top_test_rejects_only_segments_clear_of_the_column(
            o in v3(),
            n in v3(),
            c0 in v3(),
            step in prop_oneof![v3(), Just(DVec3::ZERO)],
            k in prop_oneof![Just(DVec3::Z), v3()],
            t0 in -3.0..0.0f64,
            len in 0.0..4.0f64,
            rr in 0.05..1.5f64,
        ) {
            prop_assume!(n.length() > 1e-3 && k.length() > 1e-3);
            let (n, k) = (n.normalize(), k.normalize());
            let line = Line { o, n: if n.dot(k).abs() > 0.999 { k } else { n }, lo: t0, hi: t0 + len };
            let c1 = c0 + step;
            if !misses_column_at_top(&line, c0, c1, k, rr) {
                return Ok(());
            }
            prop_assert!(
                crate::column::column_translation_entry(&line, c0, c1, k, rr, true).is_none()
            );
        }
    }

    /// The top test decides the common case: a vector rising from a surface towards a
    /// ball's centre line a side-step away, which passes its bounding sphere.
    #[test]
    fn top_test_rejects_a_neighbouring_pass() {
        let rr = 3.0;
        // A vector up from the origin, 1 mm deep to 0.01 mm out; a pass 0.5 mm aside with
        // its centres on the sphere of radius 3 about the origin's tangent plane.
        let line = Line {
            o: DVec3::ZERO,
            n: DVec3::Z,
            lo: -1.0,
            hi: 0.01,
        };
        let h = (rr * rr - 0.25f64).sqrt() + 0.05;
        let (c0, c1) = (DVec3::new(0.5, -0.3, h), DVec3::new(0.5, 0.3, h));
        assert!(near_capsule(&line, line.hi, (0.5 * (c0 + c1), 0.3), rr));
        assert!(misses_capsule_at_top(&line, line.hi, c0, c1, rr));
        // The same pass 0.06 mm lower reaches the vector's top: not rejected.
        let (c0, c1) = (c0 - 0.06 * DVec3::Z, c1 - 0.06 * DVec3::Z);
        assert!(!misses_capsule_at_top(&line, line.hi, c0, c1, rr));
        assert!(crate::exact::capsule_entry(&line, c0, c1, rr).is_some());
    }
}
