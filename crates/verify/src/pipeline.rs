//! The whole verification of one toolpath against one part: sweep the cutter (imprint
//! method), refine the design surface to the paper's edge length, grow normal vectors, cut
//! them with the swept surface (and, for back gouges, with the path swept in reverse), and
//! report the signed deviations.

use std::collections::BTreeMap;
use std::time::Instant;

use cam_core::{Cutter, DVec3, Mesh, Toolpath};
use rayon::prelude::*;

use crate::deviation::{Deviation, DeviationConfig, DeviationError, TriangleBvh};
use crate::material;
use crate::measure::{self, MeasureStats, SurfaceModel};
use crate::model::SweepModel;
use crate::rapids;
use crate::refine::{self, RefineConfig, RefineError, RefinedMesh};
use crate::report::{self, MeasureSettings, ReportConfig, VerifyReport};
use crate::sweep::{SweepConfig, SweptSurface};

/// Everything a verification needs besides the part, the path and the cutter.
#[derive(Debug, Clone, PartialEq)]
pub struct VerifyConfig {
    /// Pseudo-inserts, subdivision of long moves, sharp-turn handling.
    pub sweep: SweepConfig,
    /// Resolution `e` (mm) of the normal-vector method: design-surface edges are refined to
    /// `s = sqrt(6·r·e)` (paper §3.4). Default 0.005 mm.
    pub resolution_mm: f64,
    /// Gouge tolerance (mm): the report's bands and its pass/fail verdict.
    pub tolerance_mm: f64,
    /// Vector lengths inside and outside the part.
    pub deviation: DeviationConfig,
    /// Also sweep the path in reverse and merge (back gouges, as the paper suggests).
    pub back_gouge: bool,
    /// Cap on refined vertices; beyond it the refinement fails with a clear error.
    pub max_vertices: Option<usize>,
    /// The swept surface measured against: the imprint surface's crossings refined onto the
    /// exact swept volume (default), or the paper's piecewise-linear surface itself.
    pub surface: SurfaceModel,
    /// Refine the whole design surface, not only where a normal vector can meet the swept
    /// volume (same deviations; more vertices, for a finely coloured `--deviation` mesh of
    /// parts the path covers only in part).
    pub refine_everywhere: bool,
    /// Build the forward imprint surface even when the measurement does not use it (a
    /// program of translations measured against the exact volume): for exporting it
    /// ([`Verification::swept_surface`], `--swept`).
    pub keep_swept: bool,
}

impl VerifyConfig {
    /// Defaults for a gouge tolerance (mm): Q = 40, e = 0.005 mm, back gouges on.
    pub fn new(tolerance_mm: f64) -> VerifyConfig {
        VerifyConfig {
            sweep: SweepConfig::default(),
            resolution_mm: refine::DEFAULT_RESOLUTION_MM,
            tolerance_mm,
            deviation: DeviationConfig::for_tolerance(tolerance_mm),
            back_gouge: true,
            max_vertices: Some(20_000_000),
            surface: SurfaceModel::Exact,
            refine_everywhere: false,
            keep_swept: false,
        }
    }
}

/// Largest gouge tolerance (mm) a verification accepts. The normal vectors reach 20 times
/// the tolerance into the material ([`DeviationConfig::for_tolerance`]), and every search
/// walks their length: 1e300 mm made `cam verify` run for ever.
pub const MAX_TOLERANCE_MM: f64 = 1.0;

/// Longest normal vector (mm), inside or outside the part.
pub const MAX_VECTOR_MM: f64 = 100.0;

/// Most imprint points (both sweeps) a verification may compute: 1.4 GB of curves, and
/// about 8 GB in all with what the measurement builds on them (mount_rush with bull:6:1.5,
/// 5.8M points, peaks at 0.8 GB).
pub const MAX_IMPRINT_POINTS: f64 = 6.0e7;

/// Why a verification could not run.
#[derive(Debug, thiserror::Error)]
pub enum VerifyError {
    /// Impossible settings.
    #[error("{0}")]
    Config(String),
    /// The design surface could not be refined (e.g. too many vertices for the resolution).
    #[error(transparent)]
    Refine(#[from] RefineError),
    /// The deviation measurement rejected its input.
    #[error(transparent)]
    Deviation(#[from] DeviationError),
    /// The toolpath has no feed move to sweep.
    #[error("the toolpath has no cutting move to verify")]
    NothingSwept,
}

/// Seconds spent in each stage.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Timings {
    /// Sweeping (forward and reverse).
    pub sweep_s: f64,
    /// Refining the design surface (and, beside it, checking the rapids, building the
    /// part's tree and laying out the moves for the measurement).
    pub refine_s: f64,
    /// Growing and cutting the vectors.
    pub measure_s: f64,
    /// Checking the rapids against the part: its own time, spent beside the refinement
    /// (within `refine_s`).
    pub rapids_s: f64,
}

/// A finished verification.
#[derive(Debug, Clone)]
pub struct Verification {
    /// The report (JSON-serialisable).
    pub report: VerifyReport,
    /// The refined design surface the deviations refer to (vertex by vertex).
    pub refined: RefinedMesh,
    /// Signed deviation per refined vertex (negative = gouge).
    pub deviations: Vec<Deviation>,
    /// The forward sweep (imprint curves and pieces); [`Verification::swept_surface`] gives
    /// its triangles. Empty for a program of translations measured exactly, unless
    /// [`VerifyConfig::keep_swept`].
    pub swept: SweepModel,
    /// What the measurement did (refinements, crossings kept linear).
    pub stats: MeasureStats,
    /// Stage timings.
    pub timings: Timings,
    /// How the design mesh's faces join (misoriented or non-manifold edges make the
    /// normal-vector method unreliable next to them).
    pub topology: refine::Topology,
    /// The inner lengths of the vectors of gouges deeper than the tolerance, clipped to the
    /// material (see [`material`]; only those are checked).
    pub inner: material::InnerLengths,
    /// The rapids checked against the part ([`rapids`]): those that run into it deeper than
    /// the tolerance fail the check like a gouge.
    pub rapids: rapids::RapidReport,
}

impl Verification {
    /// The forward swept surface as triangles (for export).
    pub fn swept_surface(&self) -> SweptSurface {
        SweptSurface::from_model(&self.swept)
    }
}

/// The gouges whose vectors reached beyond the material (thin walls, skins open to the
/// sky, [`material`]), to be measured again with their inner length clipped to it
/// ([`measure::measure_then`]): `(vertex, clipped length)`, with the clipped lengths of
/// every gouge. Only gouges deeper than the tolerance are checked: a vector's reading
/// changes only when its entry lies deeper than its clipped length, and shallower readings
/// are within tolerance either way.
fn clip_to_material(
    part_bvh: &TriangleBvh,
    refined: &RefinedMesh,
    toolpath: &Toolpath,
    cfg: &VerifyConfig,
    topology: &refine::Topology,
    m: &measure::Measurement,
) -> (material::InnerLengths, Vec<(usize, f64)>) {
    let gouges: Vec<usize> = (0..refined.len())
        .into_par_iter()
        .filter(|&i| {
            m.deviations[i]
                .signed_mm
                .is_some_and(|s| s < -cfg.tolerance_mm)
        })
        .collect();
    if gouges.is_empty() {
        return (material::InnerLengths::default(), Vec::new());
    }
    let inner = material::inner_lengths_at(
        part_bvh,
        refined,
        &gouges,
        cfg.deviation.inside_mm,
        material::is_three_axis(toolpath),
        topology.is_closed_and_oriented(),
    );
    let redo = gouges
        .iter()
        .zip(&inner.inner_mm)
        .filter(|&(&i, &l)| m.deviations[i].signed_mm.is_some_and(|s| s < -l))
        .map(|(&i, &l)| (i, l))
        .collect();
    (inner, redo)
}

/// Vertices whose averaged normal is further than this from an adjacent face's normal sit
/// on a crease (degrees).
const CREASE_DEG: f64 = 10.0;

/// At crease vertices, turns a gouge's distance along the vector into the vertex's depth
/// inside the swept volume. There the vector runs along the averaged normal (roughly the
/// bisector), not normal to either face, and its distance to the crossing overstates the
/// depth (at a 90° edge by up to 1/cos 45°). On the exact surface the depth is the vertex's
/// depth inside the puck swept by the move that cut it ([`measure::depth_inside`], exact);
/// where the vertex lies outside that puck, and on the linear surface, its distance to the
/// plane tangent to the swept surface at the entry, `|t · (n_s · d)|` (`facing[i] = n_s · d`;
/// on the exact surface a supporting plane of the move's convex volume, so an upper bound of
/// the depth in it). A vector read at its start (the vertex gouged at least as deep as the
/// vector reaches, where that plane means nothing) reads the vertex's depth inside the
/// move's whole cutter, puck or column ([`measure::cutter_depth_inside`]; in the column the
/// largest depth over the move's poses, a lower bound). Smooth vertices keep the paper's
/// distance along the normal.
///
/// The rim of an open mesh is treated the same way: there the surface simply ends, a tool
/// passing beyond it reaches under the rim from outside, and the distance along the normal
/// measures the tool against the face's plane continued past the rim, not against the part
/// (on the open tilted plane a ball hanging over a corner read 0.0146 mm along the normal;
/// no rim vertex lies deeper than 0.0059 mm inside the swept volume).
///
/// And so is a vertex on a face next to a misoriented or non-manifold edge, where the
/// material side (the normal's sign and direction) is unknown: there the depth inside the
/// swept volume, which needs no orientation, is the reading (0 when the vertex is outside).
///
/// And so is a smooth vertex whose entry point `p + s·n` lies nearer to some face of the
/// design than `|s|` (on a plane its own face is exactly `|s|` away): its vector runs under
/// an edge, where a tool rolling over the edge is met at a glancing angle (on pycam-textbox
/// a top-face vertex 1.7 µm from the box's edge read 0.066 mm along its normal under a ball
/// that rolled off the edge within τ). The design face a vertex lies in is tried first (on
/// a curved surface, whose vertex normals lean off their faces, it is nearer than `|s|`),
/// then the whole design (`part`, the tree of `design`).
#[allow(clippy::too_many_arguments)]
fn crease_depths(
    refined: &RefinedMesh,
    devs: &mut [Deviation],
    m: &measure::Measurement,
    exact: Option<(&[&SweepModel], &Toolpath)>,
    rim: Option<&[u8]>,
    part: &TriangleBvh,
    design: &[cam_core::Triangle],
    unoriented: &[bool],
) {
    let nv = refined.positions.len();
    // The rim of an open mesh: vertices on an edge of one face.
    let on_rim = match rim {
        Some(rim) => refine::rim_vertices_near(refined, rim),
        None => vec![false; nv],
    };
    // Only a vertex read as a gouge is looked at below: each such vertex's slot among them
    // (`NONE` for the others).
    const NONE: u32 = u32::MAX;
    let mut slot: Vec<u32> = devs
        .par_iter()
        .map(|d| {
            if d.signed_mm.is_some_and(|s| s < 0.0) {
                0
            } else {
                NONE
            }
        })
        .collect();
    let mut ng = 0;
    for k in slot.iter_mut().filter(|k| **k != NONE) {
        *k = ng;
        ng += 1;
    }
    let ng = ng as usize;
    // Per such vertex, the least cosine between its normal and its faces' normals, and a
    // design face it lies in (the source of the last refined face around it): over the
    // faces in a few pieces side by side, then merged (the least of the pieces' least, the
    // last piece's face), the same as one pass in order whatever the number of pieces.
    let pieces = rayon::current_num_threads().clamp(1, 8);
    let len = refined.triangles.len().div_ceil(pieces).max(1);
    let parts: Vec<(Vec<f64>, Vec<u32>)> = refined
        .triangles
        .par_chunks(len)
        .enumerate()
        .map(|(p, ts)| {
            let (mut cos_min, mut own) = (vec![1.0f64; ng], vec![NONE; ng]);
            for (j, t) in ts.iter().enumerate() {
                if t.iter().all(|&i| slot[i as usize] == NONE) {
                    continue;
                }
                let gs = t.map(|i| slot[i as usize]);
                if let Some(&src) = refined.face_source.get(p * len + j) {
                    for g in gs.into_iter().filter(|&g| g != NONE) {
                        own[g as usize] = src;
                    }
                }
                let [a, b, c] = t.map(|i| refined.positions[i as usize]);
                let Some(nf) = (b - a).cross(c - a).try_normalize() else {
                    continue;
                };
                for (&i, g) in t.iter().zip(gs).filter(|&(_, g)| g != NONE) {
                    let g = g as usize;
                    cos_min[g] = cos_min[g].min(refined.normals[i as usize].dot(nf));
                }
            }
            (cos_min, own)
        })
        .collect();
    let (cos_min, own): (Vec<f64>, Vec<u32>) = (0..ng)
        .into_par_iter()
        .map(|g| {
            parts.iter().fold((1.0f64, NONE), |(c, o), (cm, ow)| {
                (c.min(cm[g]), if ow[g] == NONE { o } else { ow[g] })
            })
        })
        .unzip();
    drop(parts);
    let crease = CREASE_DEG.to_radians().cos();
    // Asked of gouged vertices only.
    let sharp = |i: usize| cos_min[slot[i] as usize] < crease || on_rim[i];
    // A smooth, oriented vertex read as a gouge: asked whether a design face lies nearer
    // to its entry point than the reading (below).
    let asks = |i: usize, s: f64| s < 0.0 && !sharp(i) && !unoriented[i];
    // Some design face nearer to `p` than `r`. Where the vertices to ask about outnumber
    // the design's faces four times (on sphere_on_plate's bull program 156,782 gouges a
    // micrometre deep on the plate, 20 per face), a grid answers the small radii and the
    // tree the rest; below that, building the grid costs about what it saves (callgrind,
    // sphere_on_plate ball, 2.7 per face: the build 28 M and its queries 22 M instructions
    // against the tree's 51 M).
    let asked = devs
        .par_iter()
        .enumerate()
        .filter(|&(i, d)| d.signed_mm.is_some_and(|s| asks(i, s)))
        .count();
    let grid = (asked >= 4 * design.len())
        .then(|| crate::deviation::TriangleGrid::new(design))
        .flatten();
    let near_design = |i: usize, p: DVec3, r: f64| {
        design
            .get(own[slot[i] as usize] as usize)
            .is_some_and(|t| crate::deviation::distance_to_triangle(p, t) < r)
            || grid
                .as_ref()
                .and_then(|g| g.any_within(p, r))
                .unwrap_or_else(|| part.any_within(p, r))
    };
    // Each vertex on its own: in parallel.
    // In pieces of at most 1024 vertices: the work lies on the creases and rims only, and
    // rayon's default split can leave most of it on one thread.
    devs.par_iter_mut()
        .enumerate()
        .with_max_len(1024)
        .for_each(|(i, d)| {
            let Some(s) = d.signed_mm.filter(|s| *s < 0.0) else {
                return;
            };
            // A smooth vertex whose entry point lies nearer to another part of the design than
            // to its own face sees a crease's glancing geometry too: its vector runs under an
            // edge within that distance.
            let entry = refined.positions[i] + s * refined.normals[i];
            if asks(i, s) && !near_design(i, entry, -s * (1.0 - 1e-6)) {
                return;
            }
            let first_order = s * m.facing[i].abs().min(1.0);
            let depth = match (exact, m.source[i]) {
                // Read at its start, the vector says only "at least this deep"; with the
                // material side unknown it says nothing: the vertex's depth inside the whole
                // cutter, the column included (there a lower bound).
                (Some((models, path)), Some(src)) if m.from_start[i] || unoriented[i] => {
                    measure::cutter_depth_inside(models, path, src, refined.positions[i])
                }
                (Some((models, path)), Some(src)) => {
                    measure::depth_inside(models, path, src, refined.positions[i])
                }
                _ => 0.0,
            };
            d.signed_mm = Some(if depth > 0.0 {
                -depth
            } else if unoriented[i] && exact.is_some() {
                // The vertex is not inside the volume: with the material side unknown, the
                // reading along the normal is not evidence of a gouge.
                0.0
            } else {
                first_order
            });
        });
}

/// Verifies `toolpath` (tool-tip poses) cut by `cutter` against `part`.
///
/// # Errors
/// [`VerifyError`] for impossible settings, a design surface too large to refine at the
/// requested resolution, or a toolpath with nothing to sweep.
pub fn verify(
    part: &Mesh,
    toolpath: &Toolpath,
    cutter: &Cutter,
    cfg: &VerifyConfig,
) -> Result<Verification, VerifyError> {
    verify_with_progress(part, toolpath, cutter, cfg, None)
}

/// The region the refinement must cover (see [`refine::Region`]): a box holding the end of
/// the cutter (up to `2R` along its axis, radius `R`) along the feed moves, and the vectors'
/// lengths `inside`/`outside` (mm); `None` without feed moves.
///
/// A translation sweeps its cylinder within the hull of its two ends, whose box is that of
/// their end discs (a disc of radius `R` about axis `k` spans `R·√(1 − k_i²)` along axis
/// `i`): nothing below the tips of a vertical tool. A move that turns the axis keeps every
/// point of the end within `√5·R` of its tip, which moves along a segment.
fn swept_region(
    toolpath: &Toolpath,
    cutter: &Cutter,
    inside: f64,
    outside: f64,
) -> Option<refine::Region> {
    let r = cutter.radius();
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for w in toolpath.moves.windows(2) {
        if w[1].kind == cam_core::MoveKind::Rapid {
            continue;
        }
        let (a, b) = (w[0].pose, w[1].pose);
        if a.axis == b.axis {
            let k = a.axis;
            let e = r * (DVec3::ONE - k * k).max(DVec3::ZERO).sqrt();
            for p in [a.tip, b.tip] {
                for q in [p, p + 2.0 * r * k] {
                    lo = lo.min(q - e);
                    hi = hi.max(q + e);
                }
            }
        } else {
            let e = DVec3::splat(5f64.sqrt() * r);
            for p in [a.tip, b.tip] {
                lo = lo.min(p - e);
                hi = hi.max(p + e);
            }
        }
    }
    if !(lo.is_finite() && hi.is_finite() && inside.is_finite() && outside.is_finite()) {
        return None;
    }
    // A relative margin for rounding.
    let grow = DVec3::splat(1e-9 * (1.0 + r + lo.abs().max(hi.abs()).max_element()));
    let (lo, hi) = (lo - grow, hi + grow);
    Some(refine::Region {
        bounds: [lo.x, lo.y, lo.z, hi.x, hi.y, hi.z],
        inside_mm: inside,
        outside_mm: outside,
    })
}

/// A stage of [`verify_with_progress`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Sweeping the toolpath (imprint curves, forward and back-gouge).
    Sweep,
    /// Refining the design surface.
    Refine,
    /// Growing the normal vectors and cutting them with the swept surface.
    Measure,
}

/// Progress callback: `(stage, done, total)`; `done == total` ends a stage. Called from the
/// calling thread between chunks of work.
pub type StageProgress<'a> = &'a (dyn Fn(Stage, usize, usize) + Sync);

/// [`verify`] reporting progress; the result is the same.
///
/// # Errors
/// As [`verify`].
pub fn verify_with_progress(
    part: &Mesh,
    toolpath: &Toolpath,
    cutter: &Cutter,
    cfg: &VerifyConfig,
    progress: Option<StageProgress<'_>>,
) -> Result<Verification, VerifyError> {
    let report_stage = |st: Stage, done: usize, total: usize| {
        if let Some(p) = progress {
            p(st, done, total);
        }
    };
    let e = cfg.resolution_mm;
    if !(e.is_finite() && e > 0.0) {
        return Err(VerifyError::Config(format!(
            "resolution {e} mm must be a positive number of mm"
        )));
    }
    let tol = cfg.tolerance_mm;
    if !(tol.is_finite() && tol > 0.0) {
        return Err(VerifyError::Config(format!(
            "tolerance {tol} mm must be a positive number of mm"
        )));
    }
    if tol > MAX_TOLERANCE_MM {
        return Err(VerifyError::Config(format!(
            "tolerance {tol} mm is above {MAX_TOLERANCE_MM} mm: the normal-vector check is for \
             finishing (its vectors reach 20 times the tolerance into the material)"
        )));
    }
    // The normal vectors' lengths set how far every search walks.
    let (li, lo) = (cfg.deviation.inside_mm, cfg.deviation.outside_mm);
    if !(li > 0.0 && lo > 0.0 && li <= MAX_VECTOR_MM && lo <= MAX_VECTOR_MM) {
        return Err(VerifyError::Config(format!(
            "normal vectors of {li} mm inside and {lo} mm outside must be positive and at \
             most {MAX_VECTOR_MM} mm"
        )));
    }
    let q = cfg.sweep.inserts;
    if q < 4 || !q.is_multiple_of(2) {
        return Err(VerifyError::Config(format!(
            "inserts {q} must be an even number ≥ 4"
        )));
    }
    let ms = cfg.sweep.max_step_mm;
    if !(ms.is_finite() && ms > 0.0) {
        return Err(VerifyError::Config(format!(
            "max step {ms} mm must be a positive number of mm"
        )));
    }
    // The imprint curves' memory: poses × points per curve, for both sweeps.
    let points = crate::model::pose_count(toolpath, cutter, &cfg.sweep)
        * (q / 2 + 1) as f64
        * if cfg.back_gouge { 2.0 } else { 1.0 };
    if points > MAX_IMPRINT_POINTS {
        return Err(VerifyError::Config(format!(
            "sweeping this path with {q} inserts at a max step of {ms} mm makes {points:.3e} \
             imprint points, more than the {MAX_IMPRINT_POINTS:.0e} that fit in memory; use a \
             larger max step or fewer inserts"
        )));
    }
    let mut timings = Timings::default();

    let t = Instant::now();
    report_stage(Stage::Sweep, 0, 1);
    if !SweepModel::sweeps_anything(toolpath, cutter, &cfg.sweep) {
        return Err(VerifyError::NothingSwept);
    }
    // The exact measurement of a program whose feed moves all keep their axis reads the
    // moves' volumes directly (`measure`): the forward imprint surface is then built only
    // when asked for, and holds the rotating moves (none) otherwise.
    let imprint_used =
        cfg.surface == SurfaceModel::Linear || !measure::keeps_axes(toolpath) || cfg.keep_swept;
    let swept = SweepModel::new(
        toolpath,
        cutter,
        &SweepConfig {
            rotating_only: !imprint_used,
            ..cfg.sweep
        },
    );
    let reverse = cfg.back_gouge.then(|| {
        SweepModel::new(
            toolpath,
            cutter,
            &SweepConfig {
                reverse: true,
                rotating_only: cfg.surface == SurfaceModel::Exact,
                ..cfg.sweep
            },
        )
    });
    timings.sweep_s = t.elapsed().as_secs_f64();
    report_stage(Stage::Sweep, 1, 1);
    report_stage(Stage::Refine, 0, 1);

    let t = Instant::now();
    let mut rcfg = RefineConfig::for_cutter(cutter, e);
    rcfg.max_vertices = cfg.max_vertices;
    // Only where a normal vector can meet the swept volume: elsewhere every vertex reads
    // "nothing swept" however finely the surface is refined (on pycam-textbox with a 40 mm
    // square of passes, the box's sides and bottom were most of 2.6 million vertices).
    if !cfg.refine_everywhere {
        rcfg.region = swept_region(
            toolpath,
            cutter,
            cfg.deviation.inside_mm,
            cfg.deviation.outside_mm,
        );
    }
    // One averaged normal per vertex, creases included: at a convex edge a face normal runs
    // along the neighbouring face (e.g. the top face's normal at a pocket rim runs down the
    // wall), where the swept surface of a pass along that face is tangent and any rounding
    // reads as a gouge. The bisector points into the material.
    rcfg.crease_angle_deg = 180.0;
    // The part's topology, its triangles' tree (for the vectors' material checks and the
    // depths at edges), the rapids' check and the moves' layout need neither the refinement
    // nor each other: they run beside it, on what its serial stretches leave of the threads.
    let mut models = vec![&swept];
    models.extend(reverse.as_ref().filter(|r| !r.pieces.is_empty()));
    // Every vector runs from a point of the part at most the longer of its lengths along a
    // unit normal: the moves' layout for the measurement needs only that box, and is laid
    // out beside the refinement too (the measurement lays out its own should a vector leave
    // the box, as rounding might have it).
    let reach = {
        let b = part.bounds();
        let l = cfg.deviation.inside_mm.max(cfg.deviation.outside_mm);
        let pad = l + 1e-9 * (1.0 + l + b.min.abs().max(b.max.abs()).max_element());
        (b.min - DVec3::splat(pad), b.max + DVec3::splat(pad))
    };
    let ((refined, layout), ((topology, unoriented_tris, rim), part_bvh, (rapids, rapids_s))) =
        rayon::join(
            || {
                rayon::join(
                    || refine::refine(part, &rcfg),
                    || measure::layout(&models, toolpath, cfg.surface, reach),
                )
            },
            || {
                let ((topo, bvh), rapids) = rayon::join(
                    || {
                        rayon::join(
                            || refine::design_topology(part),
                            || TriangleBvh::new(part.triangles()),
                        )
                    },
                    || {
                        let t = Instant::now();
                        let r = rapids::check_rapids(part, cutter, toolpath, tol);
                        (r, t.elapsed().as_secs_f64())
                    },
                );
                (topo, bvh, rapids)
            },
        );
    let refined = refined?;
    // Refined vertices on a face next to a misoriented or non-manifold edge.
    let mut unoriented = vec![false; refined.len()];
    // Walked only when some design face has such an edge.
    if unoriented_tris.contains(&true) {
        for (t, &src) in refined.triangles.iter().zip(&refined.face_source) {
            if unoriented_tris[src as usize] {
                for &i in t {
                    unoriented[i as usize] = true;
                }
            }
        }
    }
    timings.refine_s = t.elapsed().as_secs_f64();
    report_stage(Stage::Refine, 1, 1);

    let t = Instant::now();
    // Inner vector lengths clipped to the material (thin walls, skins open to the sky).
    let measure_progress = |done: usize, total: usize| report_stage(Stage::Measure, done, total);
    let mut inner = material::InnerLengths::default();
    let mut clip = |m: &measure::Measurement| {
        let (lengths, redo) = clip_to_material(&part_bvh, &refined, toolpath, cfg, &topology, m);
        inner = lengths;
        redo
    };
    let mut m = measure::measure_then(
        &refined,
        &layout,
        &cfg.deviation,
        &measure_progress,
        &mut clip,
    )?;
    let mut devs = std::mem::take(&mut m.deviations);
    let exact = (cfg.surface == SurfaceModel::Exact).then_some((models.as_slice(), toolpath));
    crease_depths(
        &refined,
        &mut devs,
        &m,
        exact,
        rim.as_deref(),
        &part_bvh,
        part.triangles(),
        &unoriented,
    );
    timings.measure_s = t.elapsed().as_secs_f64();

    let lines: Vec<Option<usize>> = toolpath.moves.iter().map(|m| m.line).collect();
    let mut extra = BTreeMap::new();
    extra.insert("inserts".to_string(), cfg.sweep.inserts as f64);
    extra.insert("max_step_mm".to_string(), cfg.sweep.max_step_mm);
    extra.insert(
        "swept_triangle_slots".to_string(),
        (0..swept.pieces.len())
            .map(|i| swept.slots(i))
            .sum::<usize>() as f64,
    );
    extra.insert("imprint_points".to_string(), swept.imprint_points as f64);
    extra.insert(
        "exact_surface".to_string(),
        if cfg.surface == SurfaceModel::Exact {
            1.0
        } else {
            0.0
        },
    );
    extra.insert("refined_vectors".to_string(), m.stats.refined as f64);
    extra.insert("exact_refinements".to_string(), m.stats.refinements as f64);
    extra.insert("crossed_vectors".to_string(), m.stats.crossed as f64);
    extra.insert("thin_material_vectors".to_string(), inner.thin as f64);
    extra.insert("open_above_vectors".to_string(), inner.open_above as f64);
    extra.insert("boundary_edges".to_string(), topology.boundary_edges as f64);
    extra.insert(
        "non_manifold_edges".to_string(),
        topology.non_manifold_edges as f64,
    );
    extra.insert(
        "misoriented_edges".to_string(),
        topology.misoriented_edges as f64,
    );
    extra.insert(
        "kept_linear_vectors".to_string(),
        m.stats.kept_linear as f64,
    );
    extra.insert("overflow_vectors".to_string(), m.stats.overflow as f64);
    extra.insert(
        "back_gouge".to_string(),
        if cfg.back_gouge { 1.0 } else { 0.0 },
    );
    let settings = MeasureSettings {
        resolution_mm: e,
        refine: rcfg,
        max_edge_used_mm: refined.max_edge_mm,
        deviation: cfg.deviation,
        extra,
    };
    let report = report::build_report(&devs, &lines, &ReportConfig::new(tol), Some(settings));
    timings.rapids_s = rapids_s;
    Ok(Verification {
        report,
        refined,
        deviations: devs,
        swept,
        stats: m.stats,
        timings,
        topology,
        inner,
        rapids,
    })
}
