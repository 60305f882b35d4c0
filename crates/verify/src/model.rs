//! The swept surface as a compact model: imprint curves per pose plus a list of *pieces*
//! (the strip between two neighbouring curves, or a cap: the tool at one pose), from which
//! the triangles of [`crate::sweep::SweptSurface`] are generated on demand.
//!
//! The model is what the verifier keeps in memory: one curve of `Q/2 + 1` points per pose
//! instead of `Q` triangles per step and `Q·(1 + 2·rings)` per cap. Every triangle has a
//! *key* `(piece << 32) | local`, increasing in the order [`crate::sweep::sweep`] emits them,
//! so ties broken by key are ties broken by position in the triangle soup. Each strip also
//! remembers which toolpath move it belongs to and the parameters of its two poses on that
//! move (`u` in `[0, 1]`, tip and axis interpolated as in [`crate::sweep`]), which is what
//! the exact refinement of [`crate::exact`] works with.

use cam_core::{Cutter, DVec3, Move, MoveKind, Pose, Toolpath, Triangle};
use rayon::prelude::*;

use crate::imprint::{
    CurveInfo, CurveStatus, Half, ImprintConfig, Imprinter, Placement, PoseFrame, transport_frames,
};
use crate::sweep::{FacetKind, SweepConfig};

/// Where a strip lies on its toolpath move: the move index (into `Toolpath::moves`, the move
/// *ending* at that index) and the move parameters of the strip's first and second pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepParam {
    /// Index of the move in `Toolpath::moves`.
    pub mv: u32,
    /// Move parameter of the strip's first pose (0 = the move's start).
    pub u_from: f64,
    /// Move parameter of the strip's second pose.
    pub u_to: f64,
}

/// One piece of the swept surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Piece {
    /// Triangles between the curves of poses `frame` and `frame + 1`.
    Strip {
        /// Index of the first pose in [`SweepModel::frames`] (its curve has the same index).
        frame: u32,
        /// The move and the two poses' parameters on it.
        step: StepParam,
    },
    /// The tool's lower surface at pose `frame`.
    Cap {
        /// Index of the pose in [`SweepModel::frames`].
        frame: u32,
        /// The move the cap is attributed to.
        mv: u32,
    },
    /// A step the exact measurement searches directly (its move's exact volume), with no
    /// triangles: a step with no strip because the imprinted half flips between its poses
    /// (caps at both poses stand for it on the imprint surface), or a step along the tool
    /// axis, whose strip holds one half of the wall it sweeps.
    Gap {
        /// Index of the step's first pose in [`SweepModel::frames`].
        frame: u32,
        /// The move and the two poses' parameters on it.
        step: StepParam,
    },
}

impl Piece {
    /// The toolpath move this piece belongs to.
    pub fn source_move(&self) -> u32 {
        match *self {
            Piece::Strip { step, .. } | Piece::Gap { step, .. } => step.mv,
            Piece::Cap { mv, .. } => mv,
        }
    }
    /// Strip or cap (a gap, which has no triangles, counts as a strip).
    pub fn kind(&self) -> FacetKind {
        match self {
            Piece::Strip { .. } | Piece::Gap { .. } => FacetKind::Strip,
            Piece::Cap { .. } => FacetKind::Cap,
        }
    }
}

/// The swept surface of one sweep (forward or reverse) as imprint curves and pieces.
#[derive(Debug, Clone)]
pub struct SweepModel {
    cutter: Cutter,
    reverse: bool,
    inserts: usize,
    rings: usize,
    per_curve: usize,
    /// Pose frames, segment by segment (a break pose appears at the end of one segment and
    /// the start of the next).
    pub frames: Vec<PoseFrame>,
    /// Imprint curves: `per_curve` points for every frame, in frame order (mm).
    pub curves: Vec<DVec3>,
    /// Pieces in emission order.
    pub pieces: Vec<Piece>,
    /// Imprinted points (poses × points per curve), for statistics.
    pub imprint_points: usize,
    /// Per piece: an estimate (mm) of how far the true surface lies outside the strip's
    /// triangles (each edge's length times the turn of the tool normal along it over 8,
    /// the largest in the strip); 0 for caps and gaps.
    pub sag: Vec<f32>,
    /// Per frame: the angle (rad) the torus centre's direction of motion turns at that pose
    /// (0 at a segment's first and last pose, where caps stand).
    pub turn: Vec<f64>,
    /// `(cos, sin)` of the cap sector angles `2π·s/Q`, `s = 0 ..= Q`.
    sector_cs: Vec<(f64, f64)>,
    /// `(sin, cos)` of the cap ring profile angles `π/2 · g/rings`, `g = 0 ..= rings`.
    ring_sc: Vec<(f64, f64)>,
}

/// A run of poses joined by feed steps; `steps[i]` is the step `i → i+1`.
#[derive(Debug, Clone, Default)]
struct Stretch {
    poses: Vec<Pose>,
    steps: Vec<StepParam>,
}

/// The pose at parameter `t` of the straight move `a → b`: tip linear, axis linear and
/// renormalised (the axis of `a` if the interpolated axis vanishes).
pub fn interpolate(a: &Pose, b: &Pose, t: f64) -> Pose {
    let axis = a.axis.lerp(b.axis, t);
    let l = axis.length();
    Pose {
        tip: a.tip.lerp(b.tip, t),
        axis: if l > 1e-12 { axis / l } else { a.axis },
    }
}

/// Length (mm) that decides a move's subdivision: tip displacement plus the rim's
/// displacement from the axis rotation.
fn move_length(a: &Pose, b: &Pose, cutter: &Cutter) -> f64 {
    a.tip.distance(b.tip) + a.axis.distance(b.axis) * cutter.radius()
}

/// The longest step (mm) between swept poses: `cfg.max_step_mm`, or unlimited when it is
/// not a positive number.
fn max_step(cfg: &SweepConfig) -> f64 {
    if cfg.max_step_mm.is_finite() && cfg.max_step_mm > 0.0 {
        cfg.max_step_mm
    } else {
        f64::INFINITY
    }
}

/// The steps a move of `len` mm is swept in: at most `max_step` mm each, 1 to 1e6.
fn subdivisions(len: f64, max_step: f64) -> usize {
    if len.is_finite() && max_step.is_finite() {
        ((len / max_step).ceil() as usize).clamp(1, 1_000_000)
    } else {
        1
    }
}

/// Whether the sweep skips the move from `a` to `b` (a rapid, or a translation when only
/// rotating moves are swept).
fn skipped(a: &Move, b: &Move, cfg: &SweepConfig) -> bool {
    b.kind == MoveKind::Rapid || (cfg.rotating_only && a.pose.axis == b.pose.axis)
}

/// How many poses [`SweepModel::new`] sweeps along `path` (each feed move subdivided as it
/// does), computed without building them: callers bound the model's memory with it.
pub fn pose_count(path: &Toolpath, cutter: &Cutter, cfg: &SweepConfig) -> f64 {
    let step = max_step(cfg);
    path.moves
        .windows(2)
        .filter(|w| !skipped(&w[0], &w[1], cfg))
        .map(|w| subdivisions(move_length(&w[0].pose, &w[1].pose, cutter), step) as f64)
        .sum()
}

/// The stretches of consecutive feed moves, subdivided.
fn stretches(path: &Toolpath, cutter: &Cutter, cfg: &SweepConfig) -> Vec<Stretch> {
    let max_step = max_step(cfg);
    let mut out = Vec::new();
    let mut cur = Stretch::default();
    // The move and parameter of the last pose kept in `cur`.
    let mut last_param: Option<(u32, f64)> = None;
    for (i, w) in path.moves.windows(2).enumerate() {
        let idx = (i + 1) as u32;
        let (a, b) = (&w[0].pose, &w[1].pose);
        if skipped(&w[0], &w[1], cfg) {
            if cur.poses.len() >= 2 {
                out.push(std::mem::take(&mut cur));
            }
            cur = Stretch::default();
            last_param = None;
            continue;
        }
        let n = subdivisions(move_length(a, b, cutter), max_step);
        if cur.poses.is_empty() {
            cur.poses.push(*a);
        }
        for s in 1..=n {
            let u = s as f64 / n as f64;
            let p = interpolate(a, b, u);
            let last = cur.poses.last().copied().unwrap_or(p);
            if p.tip.distance(last.tip) <= 1e-12 && p.axis.distance(last.axis) <= 1e-12 {
                continue;
            }
            let u_from = match last_param {
                Some((m, v)) if m == idx => v,
                _ => 0.0,
            };
            cur.poses.push(p);
            cur.steps.push(StepParam {
                mv: idx,
                u_from,
                u_to: u,
            });
            last_param = Some((idx, u));
        }
    }
    if cur.poses.len() >= 2 {
        out.push(cur);
    }
    if cfg.reverse {
        out.reverse();
        for s in &mut out {
            s.poses.reverse();
            s.steps.reverse();
            for st in &mut s.steps {
                std::mem::swap(&mut st.u_from, &mut st.u_to);
            }
        }
    }
    out
}

/// Whether the step between two pose frames moves along the (unchanged) tool axis: its
/// centre's motion has no part across the axis beyond rounding.
fn axial_step(a: &PoseFrame, b: &PoseFrame) -> bool {
    let d = b.centre - a.centre;
    let h = d - d.dot(a.axis) * a.axis;
    a.axis == b.axis && d != DVec3::ZERO && h.length() <= 1e-9 * d.length()
}

/// Pose indices where a stretch breaks (first and last included).
fn breaks(frames: &[PoseFrame], sharp_turn_deg: f64) -> Vec<usize> {
    let cos_limit = sharp_turn_deg.to_radians().cos();
    let mut out = vec![0];
    let dir = |i: usize| {
        let d = frames[i + 1].centre - frames[i].centre;
        let l = d.length();
        (l > 1e-12).then(|| d / l)
    };
    for p in 1..frames.len() - 1 {
        if let (Some(a), Some(b)) = (dir(p - 1), dir(p))
            && a.dot(b) < cos_limit
        {
            out.push(p);
        }
    }
    out.push(frames.len() - 1);
    out
}

/// A segment of a stretch between breaks: its frames and steps.
struct Segment {
    frames: Vec<PoseFrame>,
    steps: Vec<StepParam>,
    first: bool,
}

impl SweepModel {
    /// Whether sweeping `cutter` along `toolpath` with `cfg` gives any piece: some run of
    /// feed moves (rotating ones only, with `cfg.rotating_only`) moves the tool. Cheap: no
    /// imprint curve is computed.
    pub fn sweeps_anything(toolpath: &Toolpath, cutter: &Cutter, cfg: &SweepConfig) -> bool {
        // `stretches` is not empty, decided without building it: a run of feed moves
        // holds two poses once one of its subdivided poses differs from its first (the
        // only one kept until then).
        let max_step = max_step(cfg);
        let mut first: Option<Pose> = None;
        for w in toolpath.moves.windows(2) {
            if skipped(&w[0], &w[1], cfg) {
                first = None;
                continue;
            }
            let (a, b) = (&w[0].pose, &w[1].pose);
            let f = *first.get_or_insert(*a);
            let n = subdivisions(move_length(a, b, cutter), max_step);
            for s in 1..=n {
                let p = interpolate(a, b, s as f64 / n as f64);
                if !(p.tip.distance(f.tip) <= 1e-12 && p.axis.distance(f.axis) <= 1e-12) {
                    return true;
                }
            }
        }
        false
    }

    /// Builds the model of the sweep of `cutter` along the feed moves of `toolpath`
    /// (see [`crate::sweep`] for what sweeps and where the surface breaks). Curves are
    /// computed in parallel; the result does not depend on the number of threads.
    pub fn new(toolpath: &Toolpath, cutter: &Cutter, cfg: &SweepConfig) -> SweepModel {
        let sts = stretches(toolpath, cutter, cfg);
        // The adaptive placement's tables take milliseconds to build: not for a sweep with
        // nothing to imprint (a program of translations when only rotating moves are
        // swept), whose inserts and points per curve do not depend on the placement.
        let imp = Imprinter::new(
            cutter,
            &ImprintConfig {
                inserts: cfg.inserts,
                placement: if sts.is_empty() {
                    Placement::Uniform
                } else {
                    cfg.placement
                },
                difference: cfg.difference,
            },
        );
        let q = imp.inserts();
        let l = imp.points_per_curve();
        let half = if cfg.reverse {
            Half::Complement
        } else {
            Half::Cutting
        };
        let r = cutter.corner_radius();
        let segments: Vec<Segment> = sts
            .into_par_iter()
            .map(|st| {
                let frames = transport_frames(&st.poses, r);
                let cuts = breaks(&frames, cfg.sharp_turn_deg);
                cuts.windows(2)
                    .enumerate()
                    .map(|(si, w)| Segment {
                        frames: frames[w[0]..=w[1]].to_vec(),
                        steps: st.steps[w[0]..w[1]].to_vec(),
                        first: si == 0,
                    })
                    .collect::<Vec<_>>()
            })
            .collect::<Vec<_>>()
            .into_iter()
            .flatten()
            .collect();
        let total: usize = segments.iter().map(|s| s.frames.len()).sum();
        let mut curves = vec![DVec3::ZERO; total * l];
        let mut slices = Vec::with_capacity(segments.len());
        let mut rest = curves.as_mut_slice();
        for s in &segments {
            let (head, tail) = rest.split_at_mut(s.frames.len() * l);
            slices.push(head);
            rest = tail;
        }
        let infos: Vec<Vec<CurveInfo>> = segments
            .par_iter()
            .zip(slices.into_par_iter())
            .map(|(s, out)| imp.curves(&s.frames, half, out))
            .collect();
        let cos_limit = cfg.sharp_turn_deg.to_radians().cos();
        let mut pieces = Vec::new();
        let mut frames = Vec::with_capacity(total);
        let mut turn = Vec::with_capacity(total);
        for (seg, info) in segments.into_iter().zip(&infos) {
            let base = frames.len() as u32;
            let n = seg.frames.len();
            if seg.first {
                pieces.push(Piece::Cap {
                    frame: base,
                    mv: seg.steps[0].mv,
                });
            }
            for p in 0..n - 1 {
                let (i0, i1) = (&info[p], &info[p + 1]);
                if i0.status == CurveStatus::NoMotion || i1.status == CurveStatus::NoMotion {
                    continue;
                }
                let mv = seg.steps[p].mv;
                if i0.front.dot(i1.front) < cos_limit {
                    // The imprinted half flips between these poses (a reversal relative to
                    // the tool): no strip; cap both poses.
                    pieces.push(Piece::Cap {
                        frame: base + p as u32,
                        mv,
                    });
                    pieces.push(Piece::Cap {
                        frame: base + p as u32 + 1,
                        mv,
                    });
                    pieces.push(Piece::Gap {
                        frame: base + p as u32,
                        step: seg.steps[p],
                    });
                    continue;
                }
                pieces.push(Piece::Strip {
                    frame: base + p as u32,
                    step: seg.steps[p],
                });
                if axial_step(&seg.frames[p], &seg.frames[p + 1]) {
                    // Motion along the axis (a plunge or a retract): no demarcation picks a
                    // half, the strip holds one half of the wall, so the exact measurement
                    // also searches the step's move directly, both halves.
                    pieces.push(Piece::Gap {
                        frame: base + p as u32,
                        step: seg.steps[p],
                    });
                }
            }
            pieces.push(Piece::Cap {
                frame: base + n as u32 - 1,
                mv: seg.steps[n - 2].mv,
            });
            turn.push(0.0);
            for w in seg.frames.windows(3) {
                let (a, b) = (w[1].centre - w[0].centre, w[2].centre - w[1].centre);
                turn.push(a.angle_between(b).min(std::f64::consts::PI));
            }
            if n > 1 {
                turn.push(0.0);
            }
            frames.extend(seg.frames);
        }
        let sag: Vec<f32> = pieces
            .par_iter()
            .map(|p| match *p {
                Piece::Strip { frame, .. } => {
                    let motion = frames[frame as usize + 1].centre - frames[frame as usize].centre;
                    let normals = |f: u32| -> Vec<(DVec3, DVec3)> {
                        let fr = &frames[f as usize];
                        curves[f as usize * l..(f as usize + 1) * l]
                            .iter()
                            .map(|&m| (m, surface_normal(cutter, fr, m, motion)))
                            .collect()
                    };
                    let (c0, c1) = (normals(frame), normals(frame + 1));
                    let edge = |(p, n): (DVec3, DVec3), (q, m): (DVec3, DVec3)| {
                        p.distance(q) * n.distance(m)
                    };
                    let mut worst: f64 = 0.0;
                    for j in 0..l {
                        worst = worst.max(edge(c0[j], c1[j]));
                        if j + 1 < l {
                            worst = worst
                                .max(edge(c0[j], c0[j + 1]))
                                .max(edge(c1[j], c1[j + 1]))
                                .max(edge(c0[j], c1[j + 1]));
                        }
                    }
                    // Chord of the normals for the angle (× 1.1 covers the arc), over 8.
                    (worst * 1.1 / 8.0) as f32
                }
                _ => 0.0,
            })
            .collect();
        let rings = (q / 4).max(2);
        let step = 2.0 * std::f64::consts::PI / q as f64;
        let sector_cs = (0..=q)
            .map(|s| {
                let phi = s as f64 * step;
                (phi.cos(), phi.sin())
            })
            .collect();
        let ring_sc = (0..=rings)
            .map(|g| {
                let theta = std::f64::consts::FRAC_PI_2 * g as f64 / rings as f64;
                (theta.sin(), theta.cos())
            })
            .collect();
        SweepModel {
            cutter: *cutter,
            reverse: cfg.reverse,
            inserts: q,
            rings,
            sector_cs,
            ring_sc,
            per_curve: l,
            imprint_points: total * l,
            sag,
            turn,
            frames,
            curves,
            pieces,
        }
    }

    /// The cutter swept.
    pub fn cutter(&self) -> &Cutter {
        &self.cutter
    }
    /// True for a reverse (back-gouge) sweep.
    pub fn is_reverse(&self) -> bool {
        self.reverse
    }
    /// Points per imprint curve, `Q/2 + 1`.
    pub fn per_curve(&self) -> usize {
        self.per_curve
    }
    /// Pseudo-inserts Q (also the number of cap sectors).
    pub fn inserts(&self) -> usize {
        self.inserts
    }
    /// Profile segments of a cap's corner.
    pub fn rings(&self) -> usize {
        self.rings
    }

    /// The imprint curve of frame `f`.
    pub fn curve(&self, f: u32) -> &[DVec3] {
        let l = self.per_curve;
        &self.curves[f as usize * l..(f as usize + 1) * l]
    }

    /// The point inside the tool that orients the triangles of frame `f` (away from it).
    fn inside(&self, f: u32) -> DVec3 {
        let fr = &self.frames[f as usize];
        fr.centre + self.cutter.radius() * fr.axis
    }

    /// Number of local triangle slots of piece `i` (some may be degenerate and skipped).
    pub fn slots(&self, i: usize) -> usize {
        match self.pieces[i] {
            Piece::Strip { .. } => 2 * (self.per_curve - 1),
            Piece::Cap { .. } => self.inserts * self.cap_per_sector(),
            Piece::Gap { .. } => 0,
        }
    }

    fn cap_per_sector(&self) -> usize {
        let fan = usize::from(self.cutter.major_radius() > 0.0);
        let ring = if self.cutter.corner_radius() > 0.0 {
            2 * self.rings
        } else {
            0
        };
        fan + ring
    }

    /// Point of cap ring `ring` at sector boundary `sector` (angle `2π·sector/Q`) of frame `f`.
    pub fn cap_point(&self, f: &PoseFrame, sector: usize, ring: usize) -> DVec3 {
        let (a, r) = (self.cutter.major_radius(), self.cutter.corner_radius());
        let (c, s) = self.sector_cs[sector];
        let u = c * f.e1 + s * f.e2;
        let (ts, tc) = self.ring_sc[ring];
        f.centre + a * u + r * (ts * u - tc * f.axis)
    }

    /// Number of triangle slots per cap sector (fan triangle, then two per ring).
    pub fn cap_slots_per_sector(&self) -> usize {
        self.cap_per_sector()
    }

    /// The pose frame of piece `i`: a strip's first pose or a cap's pose.
    pub fn piece_frame(&self, i: usize) -> u32 {
        match self.pieces[i] {
            Piece::Strip { frame, .. } | Piece::Cap { frame, .. } | Piece::Gap { frame, .. } => {
                frame
            }
        }
    }

    /// The oriented triangle in slot `local` of piece `i` (see [`SweepModel::triangle`]).
    pub fn slot_triangle(&self, i: usize, local: usize) -> Option<Triangle> {
        self.triangle(i, local)
    }

    /// The unoriented corners of local triangle `local` of piece `i`, before the degenerate
    /// test and orientation.
    fn raw_triangle(&self, i: usize, local: usize) -> [DVec3; 3] {
        match self.pieces[i] {
            Piece::Strip { frame, .. } | Piece::Gap { frame, .. } => {
                let (c0, c1) = (self.curve(frame), self.curve(frame + 1));
                let j = local / 2;
                let (a, b, c, d) = (c0[j], c0[j + 1], c1[j + 1], c1[j]);
                if local.is_multiple_of(2) {
                    [a, b, c]
                } else {
                    [a, c, d]
                }
            }
            Piece::Cap { frame, .. } => {
                let f = &self.frames[frame as usize];
                let per = self.cap_per_sector();
                let (s, mut k) = (local / per, local % per);
                let tip = f.tip(self.cutter.corner_radius());
                if self.cutter.major_radius() > 0.0 {
                    if k == 0 {
                        return [tip, self.cap_point(f, s, 0), self.cap_point(f, s + 1, 0)];
                    }
                    k -= 1;
                }
                let g = k / 2;
                let q = [
                    self.cap_point(f, s, g),
                    self.cap_point(f, s + 1, g),
                    self.cap_point(f, s + 1, g + 1),
                    self.cap_point(f, s, g + 1),
                ];
                if k % 2 == 0 {
                    [q[0], q[1], q[2]]
                } else {
                    [q[0], q[2], q[3]]
                }
            }
        }
    }

    /// Triangle `local` of piece `i`, oriented away from the tool, or `None` when degenerate
    /// (exactly the triangle [`crate::sweep::sweep`] emits for that slot).
    pub fn triangle(&self, i: usize, local: usize) -> Option<Triangle> {
        if local >= self.slots(i) {
            return None;
        }
        let t = self.raw_triangle(i, local);
        orient(t, self.inside(self.piece_frame(i)))
    }

    /// Calls `f(key, triangle)` for every triangle of piece `i`, in emission order.
    pub fn for_each_triangle(&self, i: usize, mut f: impl FnMut(u64, Triangle)) {
        match self.pieces[i] {
            Piece::Strip { frame, .. } => {
                let (c0, c1) = (self.curve(frame), self.curve(frame + 1));
                let inside = self.inside(frame);
                for j in 0..self.per_curve - 1 {
                    let (a, b, c, d) = (c0[j], c0[j + 1], c1[j + 1], c1[j]);
                    if let Some(t) = orient([a, b, c], inside) {
                        f(key(i, 2 * j), t);
                    }
                    if let Some(t) = orient([a, c, d], inside) {
                        f(key(i, 2 * j + 1), t);
                    }
                }
            }
            Piece::Cap { .. } => {
                for local in 0..self.slots(i) {
                    if let Some(t) = self.triangle(i, local) {
                        f(key(i, local), t);
                    }
                }
            }
            Piece::Gap { .. } => {}
        }
    }
}

/// Unit normal of the swept surface at imprint point `m` of pose frame `f` moving along
/// `motion`: the tool's normal there (the envelope is tangent to the tool at its imprint
/// points); for a flat end mill, whose imprint points lie on the rim (an edge), the normal
/// of the surface the rim sweeps, `rim tangent × motion`, facing away from the tool.
fn surface_normal(cutter: &Cutter, f: &PoseFrame, m: DVec3, motion: DVec3) -> DVec3 {
    let (a, r) = (cutter.major_radius(), cutter.corner_radius());
    let y = m - f.centre;
    let h = y - y.dot(f.axis) * f.axis;
    let uh = h.try_normalize().unwrap_or(f.e1);
    if r > 0.0 {
        ((y - a * uh) / r).try_normalize().unwrap_or(-f.axis)
    } else {
        let n = f
            .axis
            .cross(uh)
            .cross(motion)
            .try_normalize()
            .unwrap_or(-f.axis);
        if n.dot(f.axis) > 0.0 { -n } else { n }
    }
}

/// The key of local triangle `local` of piece `piece`.
pub fn key(piece: usize, local: usize) -> u64 {
    ((piece as u64) << 32) | local as u64
}

/// The piece and local index of a key.
pub fn unkey(k: u64) -> (usize, usize) {
    ((k >> 32) as usize, (k & 0xffff_ffff) as usize)
}

/// The triangle `t` oriented away from `inside`, or `None` if degenerate.
fn orient(t: [DVec3; 3], inside: DVec3) -> Option<Triangle> {
    let mut tri = Triangle::new(t[0], t[1], t[2]);
    if tri.is_degenerate() {
        return None;
    }
    let centroid = (t[0] + t[1] + t[2]) / 3.0;
    if tri.cross().dot(centroid - inside) < 0.0 {
        tri.v.swap(1, 2);
    }
    Some(tri)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `sweeps_anything` decides as building the stretches does, on programs that sweep
    /// nothing (no moves, rapids only, feeds that do not move the tool or move it by less
    /// than the 1e-12 mm a pose must differ by, translations when only rotating moves
    /// count) and on ones that sweep something late in the program or only by turning.
    #[test]
    fn sweeps_anything_decides_as_the_stretches() {
        let at = |kind, x: f64, axis: DVec3| Move {
            kind,
            pose: Pose {
                tip: DVec3::new(x, 0.0, 0.0),
                axis,
            },
            feed_mm_per_min: Some(100.0),
            line: None,
            pass: None,
        };
        let (z, tilted) = (DVec3::Z, DVec3::new(0.1, 0.0, 1.0).normalize());
        let (cut, rapid) = (MoveKind::Cut, MoveKind::Rapid);
        let programs: Vec<Vec<Move>> = vec![
            vec![],
            vec![at(rapid, 0.0, z)],
            vec![at(rapid, 0.0, z), at(rapid, 5.0, z)],
            vec![at(rapid, 0.0, z), at(cut, 0.0, z), at(cut, 0.0, z)],
            vec![at(rapid, 0.0, z), at(cut, 1e-13, z), at(cut, 2e-13, z)],
            vec![
                at(rapid, 0.0, z),
                at(cut, 0.0, z),
                at(rapid, 3.0, z),
                at(cut, 3.0, z),
            ],
            vec![at(rapid, 0.0, z), at(cut, 0.0, z), at(cut, 3.0, z)],
            vec![
                at(rapid, 0.0, z),
                at(cut, 1e-13, z),
                at(rapid, 3.0, z),
                at(cut, 4.0, z),
            ],
            vec![at(rapid, 0.0, z), at(cut, 0.0, tilted)],
            vec![at(rapid, 0.0, z), at(cut, 2.0, z), at(cut, 2.0, tilted)],
        ];
        let cutter = Cutter::bull(6.0, 1.0).unwrap();
        let mut yes = 0;
        for (i, moves) in programs.into_iter().enumerate() {
            let tp = Toolpath { moves };
            for rotating_only in [false, true] {
                let cfg = SweepConfig {
                    rotating_only,
                    ..SweepConfig::default()
                };
                let built = !stretches(&tp, &cutter, &cfg).is_empty();
                assert_eq!(
                    SweepModel::sweeps_anything(&tp, &cutter, &cfg),
                    built,
                    "program {i}, rotating only: {rotating_only}"
                );
                yes += usize::from(built);
            }
        }
        assert!(yes >= 5, "only {yes} programs sweep something");
    }
}
