//! Imprint points of a toroidal cutter: the pseudo-insert method of Roth, Bedi, Ismail and
//! Mann, *Surface swept by a toroidal cutter during 5-axis machining* (CAD 2000), Eq. 2.
//!
//! # Tool model
//! Every [`Cutter`] is a solid of revolution whose lower surface is a flat disk of radius
//! `a` (the paper's major radius R, [`Cutter::major_radius`]) rounded by a corner of radius
//! `r` (the paper's minor radius r, [`Cutter::corner_radius`]), continued upward by a cylinder
//! of radius `a + r`. Poses are given by the tool tip and the unit axis `k`; the torus centre
//! (the centre of the ring of corner-circle centres) is `T = tip + r·k`.
//!
//! # Pseudo-inserts
//! A pseudo-insert is the cutter's profile in a half-plane through the axis at angle `φ` in
//! a per-pose frame `(e1, e2, k)`: radial direction `u = cos φ e1 + sin φ e2`, insert centre
//! `T_q = T + a·u`, insert normal `n = k × u`. The frames are carried from pose to pose by the
//! minimal rotation taking one axis to the next (a rotation-minimising, parallel-transport
//! frame, [`transport_frames`]), so an insert at angle `φ` is the *same material section* of
//! the non-spinning tool body at both poses and `ΔT_q = T_{p+1,q} − T_{p,q}` is its motion.
//!
//! # Imprint point (Eq. 2) and the cutting solution
//! `m = T_q + r·w`, `w = ±(ΔT × n)/|ΔT × n|`: the two points of the insert circle whose
//! surface normal `w` is perpendicular to `ΔT`. Of `±` we keep the one on the *lower-outer
//! quarter* of the circle, the only part of the torus that is cutter surface (the inner half is
//! covered by the flat bottom, the upper-outer quarter by the cylinder): the sign with
//! `w·(u − k) ≥ 0`. If that solution still leaves the quarter it is clamped to its end: above
//! the equator to the side point `w = u` (the silhouette continues up the cylinder), inside the
//! ring to the disk rim `w = −k` (the silhouette continues across the flat bottom), except for
//! a ball (`a = 0`) where the inner half of one insert is the outer half of the opposite one and
//! the torus point is kept.
//!
//! # Demarcation and the cutting half
//! With `ΔC` the motion of the torus centre and `h` its part perpendicular to `k`, the two
//! demarcation inserts lie at ±90° from the direction `σ·ĥ`. For a translation exactly the
//! half centred on `sign(ΔC·k)·ĥ` has its Eq. 2 solutions on the lower-outer quarter: for a
//! tool tilted forward (the paper's assumption) or moving uphill that is the front half, for a
//! 3-axis move downhill the back half. Under rotation the middle insert's own motion decides:
//! `σ = +1` if the insert at `+ĥ` does not move down relative to the tool or the one at `−ĥ`
//! moves up, else `−1`. The demarcation inserts are placed exactly at those angles; the inserts
//! turn with the demarcation from pose to pose (each insert's `ΔT` is still that of the same
//! material section, through the transported frames), which keeps the `Q/2 + 1` points of
//! neighbouring curves in correspondence from the demarcation on, as §3.3 asks.
//! [`Half::Complement`] takes the other half, used for back-gouge sweeps, which run the path
//! backwards: the half opposite to the one the forward sweep takes at the same pose (its
//! choice made on the negated motion), so that together they cover the whole tool also
//! where, under rotation, `σ` would come out the same both ways.
//!
//! # Insert placement and motion direction (beyond the paper, both switchable)
//! Near a demarcation the imprint curve climbs from the bottom of the insert to its side point
//! within an angle of about `s'` radians, `s' = |ΔT·k|/|ΔT − (ΔT·k)k|` of the middle insert;
//! for a near-horizontal motion that is much less than the uniform spacing `2π/Q` and the chord
//! between the last two inserts cuts deep into the tool. [`Placement::Adaptive`] places the
//! `Q/2 + 1` inserts where they equidistribute the chord error of the translation imprint
//! curve of slope `s'` (tables precomputed per cutter); [`Placement::Uniform`] is the paper's.
//! Every point is still an Eq. 2 imprint point of a pseudo-insert.
//! [`Difference::Central`] takes each insert's motion as `T_{p+1} − T_{p−1}` at interior
//! poses (the tangent at `p` to second order); [`Difference::Forward`] is the paper's
//! `T_{p+1} − T_p` (the direction at `p + ½`), first order.
//!
//! # Degenerate cases
//! - `ΔT ∥ n` (`|ΔT × n| ≤ 1e-12·|ΔT|`): the whole side profile of the insert cuts (a motion
//!   perpendicular to the axis, at the demarcation). With adaptive placement the horizontal
//!   curve puts several inserts on each demarcation profile, at prescribed profile angles from
//!   the side point down to the bottom (including the corner where the profile meets the
//!   bottom rim), so the profile quarter circle is emitted; with uniform placement the
//!   demarcation insert emits its side point. An interior insert with this degeneracy emits
//!   its bottom point.
//! - No motion (`ΔT = 0` for the centre and no rotation): [`Imprinter::curve`] returns
//!   [`CurveStatus::NoMotion`] and writes nothing; the sweep drops such poses and joins the
//!   neighbours.
//! - Reversal of direction: the demarcation follows the motion at every pose, so a reversal
//!   gives a new demarcation (the other half, [`CurveInfo::front`] flips); the sweep breaks the
//!   surface there and caps it.
//! - Motion along the axis (`h = 0`): no demarcation exists; the half centred on `e1` is
//!   emitted (every insert's imprint is its side point) and [`CurveStatus::Axial`] is returned.
//!   The other half of a plunge's wall is not emitted (the caps close the bottom); the sweep
//!   marks such steps for the exact measurement, which searches their move directly, both
//!   halves (the linear surface and the exported sweep hold the emitted half only).
//! - Flat end mill (`r = 0`): every imprint point is the rim point `T_q`; the flat bottom is
//!   the ruled surface between rim half-circles of neighbouring poses (see `sweep`).
//!
//! # Limits
//! Only the corner torus is imprinted. Where a rotating tool's characteristic curve leaves the
//! corner (onto the cylinder above it, or across the flat bottom) the point is clamped to the
//! end of the quarter; such points lie inside the true envelope (measured up to ~0.25 mm on
//! the sides of the tool in `tests/it/five_axis.rs`). They are on the groove walls, not on
//! the first hits along the design normals.
//!
//! # Performance
//! Per interior insert: two frame combinations, one cross product, one square root, no
//! allocation; the per-pose constants (rotated frames) are computed once per curve.

use std::f64::consts::{FRAC_PI_2, PI};

use cam_core::{Cutter, DVec3, Pose};

/// The torus model of a cutter (mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TorusTool {
    /// Major radius `a = D/2 − r` (the paper's R), mm.
    pub major_mm: f64,
    /// Minor (corner) radius `r` (the paper's r), mm.
    pub minor_mm: f64,
}

impl TorusTool {
    /// The torus of a cutter: `a = major_radius()`, `r = corner_radius()`.
    pub fn from_cutter(cutter: &Cutter) -> TorusTool {
        TorusTool {
            major_mm: cutter.major_radius(),
            minor_mm: cutter.corner_radius(),
        }
    }

    /// Signed distance (mm) from the torus surface `|(ρ − a, z)| = r` to `p`, in the tool frame
    /// with the torus centre at `centre` and unit axis `axis` (negative inside the ring).
    pub fn torus_distance(&self, centre: DVec3, axis: DVec3, p: DVec3) -> f64 {
        let d = p - centre;
        let z = d.dot(axis);
        let rho = (d - z * axis).length();
        (rho - self.major_mm).hypot(z) - self.minor_mm
    }
}

/// A pose's frame: torus centre, unit axis `k` and unit `e1`, `e2 = k × e1`, `e1 ⟂ k`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseFrame {
    /// Torus centre `tip + r·k` (mm).
    pub centre: DVec3,
    /// Unit tool axis (tip → spindle).
    pub axis: DVec3,
    /// First unit direction perpendicular to the axis.
    pub e1: DVec3,
    /// `axis × e1`.
    pub e2: DVec3,
}

impl PoseFrame {
    /// The tool tip of this frame for a tool of corner radius `r_mm`.
    pub fn tip(&self, r_mm: f64) -> DVec3 {
        self.centre - r_mm * self.axis
    }
}

/// A unit vector perpendicular to unit `k`, chosen deterministically.
pub fn any_perpendicular(k: DVec3) -> DVec3 {
    let reference = if k.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    (reference - reference.dot(k) * k).normalize()
}

/// Rotates `v` by the minimal rotation taking unit `k0` to unit `k1` (Rodrigues with
/// `w = k0 × k1`); for opposite axes, reflects through the plane perpendicular to `k0`.
pub fn minimal_rotation(v: DVec3, k0: DVec3, k1: DVec3) -> DVec3 {
    let c = k0.dot(k1);
    if c > -1.0 + 1e-12 {
        let w = k0.cross(k1);
        v * c + w.cross(v) + w * (w.dot(v) / (1.0 + c))
    } else {
        v - 2.0 * v.dot(k0) * k0
    }
}

/// Frames for consecutive poses of one stretch, `e1` carried by minimal rotations
/// (rotation-minimising frame). `r_mm` is the corner radius (torus centre = tip + r·k).
/// Axes must be unit vectors.
pub fn transport_frames(poses: &[Pose], r_mm: f64) -> Vec<PoseFrame> {
    let mut out = Vec::with_capacity(poses.len());
    let mut prev: Option<(DVec3, DVec3)> = None;
    for pose in poses {
        let k = pose.axis;
        let e1 = match prev {
            None => any_perpendicular(k),
            Some((k0, e0)) => {
                let e = minimal_rotation(e0, k0, k);
                let e = e - e.dot(k) * k;
                let l = e.length();
                if l > 1e-9 {
                    e / l
                } else {
                    any_perpendicular(k)
                }
            }
        };
        out.push(PoseFrame {
            centre: pose.tip + r_mm * k,
            axis: k,
            e1,
            e2: k.cross(e1),
        });
        prev = Some((k, e1));
    }
    out
}

/// Which pose of a step the imprint curve is evaluated on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// On the first pose of the step (the curve the paper uses at every pose).
    Outgoing,
    /// On the second pose of the step (the last curve of a stretch).
    Incoming,
}

/// Which half of the tool, between the demarcation inserts, is imprinted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Half {
    /// The half centred on `σ·h` whose Eq. 2 solutions lie on the cutting quarter.
    Cutting,
    /// For a sweep of the path backwards (back gouges): the half opposite to the one
    /// [`Half::Cutting`] takes at the same pose of the forward path.
    Complement,
}

/// What [`Imprinter::curve`] found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CurveStatus {
    /// A regular curve was written.
    Regular,
    /// The centre moved along the axis only: no demarcation exists; the half about `e1` was
    /// written.
    Axial,
    /// Nothing moves: nothing was written.
    NoMotion,
}

/// Where the imprint points of one curve are taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Placement {
    /// The paper's method: inserts at the uniform angles `2πj/Q`, `j = 0 ..= Q/2`, from the
    /// demarcation on.
    Uniform,
    /// Beyond the paper: the `Q/2 + 1` inserts are placed, per pose, where they equidistribute
    /// the chord (sagitta) error along the imprint curve of the translation that has the pose's
    /// slope `s' = |ΔC·k|/|h|`: density `sqrt(r·dθ² + ρ·(sin θ + 0.1)·dφ²)` (the tool's normal
    /// curvature along the curve, `θ` the profile angle from the bottom, `ρ = a + r sin θ`).
    /// Where the imprint climbs the corner near a demarcation inserts crowd there; on a
    /// horizontal motion several sit on the demarcation profile itself (the degenerate case).
    Adaptive,
}

/// What [`Imprinter::curve`] found, with the direction the imprinted half is centred on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurveInfo {
    /// Regular, axial or no motion.
    pub status: CurveStatus,
    /// Unit direction (⟂ axis) at the middle of the imprinted half; zero on `NoMotion`.
    pub front: DVec3,
}

/// Number and placement of the pseudo-inserts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ImprintConfig {
    /// Pseudo-inserts Q around the tool (rounded up to an even number ≥ 4); each imprint curve
    /// has `Q/2 + 1` points. Default 40.
    pub inserts: usize,
    /// Where the inserts of the imprinted half sit. Default [`Placement::Adaptive`].
    pub placement: Placement,
    /// How [`Imprinter::curves`] takes each insert's motion `ΔT`. Default
    /// [`Difference::Central`].
    pub difference: Difference,
}

/// The motion direction used at a pose by [`Imprinter::curves`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Difference {
    /// The paper's: `ΔT = T_{p+1} − T_p` (the direction at `p + ½`; first-order accurate).
    Forward,
    /// `ΔT = T_{p+1} − T_{p−1}` at interior poses (second-order accurate direction at `p`);
    /// forward / backward at the ends of a run.
    Central,
}

impl Default for ImprintConfig {
    fn default() -> Self {
        ImprintConfig {
            inserts: 40,
            placement: Placement::Adaptive,
            difference: Difference::Central,
        }
    }
}

/// Slopes `s'` of the placement tables: table 0 is `s' = 0`, tables `1 ..= N` are
/// log-spaced from `10^S_LOG_MIN` to `10^S_LOG_MAX`.
const S_LOG_MIN: f64 = -4.0;
const S_LOG_MAX: f64 = 3.0;
const S_TABLES: usize = 141;

/// Computes imprint curves for one cutter; holds the insert placement tables.
#[derive(Debug, Clone)]
pub struct Imprinter {
    tool: TorusTool,
    q: usize,
    placement: Placement,
    difference: Difference,
    /// Per slope table: `(δ, θ)` of each of the `Q/2 + 1` points: insert angle from the
    /// first demarcation and the profile angle used where Eq. 2 is degenerate.
    tables: Vec<Vec<(f64, f64)>>,
}

/// One evaluated insert: the imprint point, the insert centre and radial direction, and the
/// normal's components along `u` and `−k` (`None` when Eq. 2 is degenerate).
struct InsertPoint {
    m: DVec3,
    t: DVec3,
    u: DVec3,
    w: Option<(f64, f64)>,
}

/// Per-curve constants.
struct CurveFrame<'a> {
    e: &'a PoseFrame,
    g1: DVec3,
    g2: DVec3,
    c_a: DVec3,
    g1a: DVec3,
    g2a: DVec3,
    c_b: DVec3,
    g1b: DVec3,
    g2b: DVec3,
}

/// The placement of `m` points for slope `s` (see [`Placement::Adaptive`]).
fn placement_table(a: f64, r: f64, s: f64, m: usize) -> Vec<(f64, f64)> {
    const F: usize = 256;
    let mut half: Vec<(f64, f64)> = Vec::with_capacity(2 * F + 2);
    if s == 0.0 {
        for i in 0..=F {
            half.push((0.0, FRAC_PI_2 * (1.0 - i as f64 / F as f64)));
        }
        for i in 1..=F {
            half.push((FRAC_PI_2 * i as f64 / F as f64, 0.0));
        }
    } else {
        let theta_min = s.atan();
        for i in 0..=F {
            let th = FRAC_PI_2 - (FRAC_PI_2 - theta_min) * i as f64 / F as f64;
            half.push(((s * th.cos() / th.sin()).min(1.0).asin(), th));
        }
        for i in 1..=F {
            let d = FRAC_PI_2 * i as f64 / F as f64;
            half.push((d, (s / d.sin()).atan()));
        }
        half.sort_by(|x, y| x.0.total_cmp(&y.0).then(y.1.total_cmp(&x.1)));
    }
    let mut curve = half.clone();
    curve.extend(half.iter().rev().map(|&(d, th)| (PI - d, th)));
    let mut cum = vec![0.0];
    for w in curve.windows(2) {
        let (dd, dt) = (w[1].0 - w[0].0, w[1].1 - w[0].1);
        let th = 0.5 * (w[0].1 + w[1].1);
        let rho = a + r * th.sin();
        let g = (r * dt * dt + rho * (th.sin() + 0.1) * dd * dd).sqrt();
        cum.push(cum.last().copied().unwrap_or(0.0) + g);
    }
    let total = cum.last().copied().unwrap_or(0.0);
    let mut out = Vec::with_capacity(m);
    let mut seg = 0;
    for j in 0..m {
        let target = total * j as f64 / (m - 1) as f64;
        while seg + 2 < cum.len() && cum[seg + 1] < target {
            seg += 1;
        }
        let span = cum[seg + 1] - cum[seg];
        let f = if span > 0.0 {
            ((target - cum[seg]) / span).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (p, q) = (curve[seg], curve[seg + 1]);
        out.push((p.0 + f * (q.0 - p.0), p.1 + f * (q.1 - p.1)));
    }
    out[0] = (0.0, FRAC_PI_2);
    out[m - 1] = (PI, FRAC_PI_2);
    if s == 0.0 && m > 4 {
        // The horizontal curve has corners where the side profiles meet the bottom rim
        // (fine point F); put a point exactly on each so no chord cuts across them.
        let j = ((cum[F] / total.max(1e-300)) * (m - 1) as f64).round() as usize;
        let j = j.clamp(1, m / 2 - 1);
        out[j] = (0.0, 0.0);
        out[m - 1 - j] = (PI, 0.0);
    }
    out
}

impl Imprinter {
    /// An imprinter for `cutter` with `cfg.inserts` pseudo-inserts (rounded up to even ≥ 4).
    pub fn new(cutter: &Cutter, cfg: &ImprintConfig) -> Imprinter {
        let q = cfg.inserts.max(4).next_multiple_of(2);
        let m = q / 2 + 1;
        let (a, r) = (cutter.major_radius(), cutter.corner_radius());
        let tables = match cfg.placement {
            Placement::Uniform => {
                vec![
                    (0..m)
                        .map(|j| (2.0 * PI * j as f64 / q as f64, 0.0))
                        .collect(),
                ]
            }
            Placement::Adaptive => (0..S_TABLES)
                .map(|i| {
                    let s = if i == 0 {
                        0.0
                    } else {
                        let x = (i - 1) as f64 / (S_TABLES - 2) as f64;
                        10f64.powf(S_LOG_MIN + (S_LOG_MAX - S_LOG_MIN) * x)
                    };
                    placement_table(a, r, s, m)
                })
                .collect(),
        };
        Imprinter {
            tool: TorusTool::from_cutter(cutter),
            q,
            placement: cfg.placement,
            difference: cfg.difference,
            tables,
        }
    }

    /// The torus model.
    pub fn tool(&self) -> TorusTool {
        self.tool
    }
    /// Q (even, ≥ 4).
    pub fn inserts(&self) -> usize {
        self.q
    }
    /// Points per imprint curve: `Q/2 + 1`.
    pub fn points_per_curve(&self) -> usize {
        self.q / 2 + 1
    }

    #[inline(always)]
    fn eval(&self, cf: &CurveFrame<'_>, c: f64, s: f64) -> InsertPoint {
        let TorusTool {
            major_mm: a,
            minor_mm: r,
        } = self.tool;
        let k = cf.e.axis;
        let u = c * cf.g1 + s * cf.g2;
        let ua = c * cf.g1a + s * cf.g2a;
        let ub = c * cf.g1b + s * cf.g2b;
        let t = cf.e.centre + a * u;
        let dt = (cf.c_b + a * ub) - (cf.c_a + a * ua);
        let n = k.cross(u);
        let x = dt.cross(n);
        let xx = x.length_squared();
        if xx.is_nan() || xx <= 1e-24 * dt.length_squared() {
            return InsertPoint {
                m: t - r * k,
                t,
                u,
                w: None,
            };
        }
        let mut w = x * (1.0 / xx.sqrt());
        let (mut wu, mut wk) = (w.dot(u), -w.dot(k));
        if wu + wk < 0.0 {
            w = -w;
            wu = -wu;
            wk = -wk;
        }
        if wk < 0.0 {
            w = u;
            (wu, wk) = (1.0, 0.0);
        } else if wu < 0.0 && a > 0.0 {
            w = -k;
            (wu, wk) = (0.0, 1.0);
        }
        InsertPoint {
            m: t + r * w,
            t,
            u,
            w: Some((wu, wk)),
        }
    }

    /// The imprint curve of the step `from → to`, evaluated on `from` ([`Side::Outgoing`]) or on
    /// `to` ([`Side::Incoming`]), for the chosen `half`, written to `out` (length
    /// [`Imprinter::points_per_curve`]; extra entries are left alone, missing ones make it
    /// write fewer). Points run from the demarcation at `σh × k` through `σh` to the other
    /// demarcation. Returns what it found; on [`CurveStatus::NoMotion`] nothing is written.
    pub fn curve(
        &self,
        from: &PoseFrame,
        to: &PoseFrame,
        side: Side,
        half: Half,
        out: &mut [DVec3],
    ) -> CurveInfo {
        let at = match side {
            Side::Outgoing => from,
            Side::Incoming => to,
        };
        self.curve_at(at, from, to, half, out)
    }

    /// The imprint curve on the pose `at` for the motion `from → to` (each insert's
    /// `ΔT = T_to − T_from`, the inserts corresponding through the transported frames):
    /// [`Imprinter::curve`] with `at` = `from` or `to`, or a central difference with `from`,
    /// `to` the poses before and after `at`.
    pub fn curve_at(
        &self,
        at: &PoseFrame,
        from: &PoseFrame,
        to: &PoseFrame,
        half: Half,
        out: &mut [DVec3],
    ) -> CurveInfo {
        let e = at;
        let k = e.axis;
        let dc = to.centre - from.centre;
        let rotation = (to.axis - from.axis).length() * self.tool.major_mm;
        let dcl = dc.length();
        if dcl <= 1e-12 && rotation <= 1e-12 {
            return CurveInfo {
                status: CurveStatus::NoMotion,
                front: DVec3::ZERO,
            };
        }
        let along = dc.dot(k);
        let h = dc - along * k;
        let hn = h.length();
        let axial = hn.is_nan() || hn <= 1e-9 * dcl.max(rotation);
        // Motion of the insert centred on direction `d` (unit, ⟂ k): ΔT_d.
        let a = self.tool.major_mm;
        let insert_motion = |d: DVec3| {
            let (p, q) = (d.dot(e.e1), d.dot(e.e2));
            (to.centre + a * (p * to.e1 + q * to.e2))
                - (from.centre + a * (p * from.e1 + q * from.e2))
        };
        let slope_of = |dt: DVec3| {
            let v = dt.dot(k);
            (v, v.abs() / (dt - v * k).length().max(1e-300))
        };
        let (front, slope) = if axial {
            let front = if half == Half::Complement {
                -e.e1
            } else {
                e.e1
            };
            (front, f64::INFINITY)
        } else {
            // σ: the half whose middle insert moves up (relative to the tool) along with its
            // forward motion; for a translation sign(ΔC·k); under rotation the middle insert's
            // own ΔT decides.
            let f = h / hn;
            let (vf, sf) = slope_of(insert_motion(f));
            let (vb, sb) = slope_of(insert_motion(-f));
            let eps = 1e-12 * dcl.max(rotation);
            let cutting = |vf: f64, vb: f64| vf >= -eps || vb > eps;
            // The complement (a back-gouge sweep, which takes the path backwards and so sees
            // every motion negated) is the other half of the one the forward sweep imprints:
            // the forward choice is made with the inserts' roles swapped and their motions
            // negated. (Taking the complement of this sweep's own choice is the same for a
            // translation, but under rotation, with the insert at +ĥ rising and the one at −ĥ
            // sinking, both sweeps would imprint the +ĥ half and leave the other uncovered.)
            let plus = match half {
                Half::Cutting => cutting(vf, vb),
                Half::Complement => cutting(-vb, -vf),
            };
            if plus { (f, sf) } else { (-f, sb) }
        };
        let g1 = front.cross(k);
        let g2 = front;
        let (alpha, beta) = (g1.dot(e.e1), g1.dot(e.e2));
        let g1a = alpha * from.e1 + beta * from.e2;
        let g2a = from.axis.cross(g1a);
        let g1b = alpha * to.e1 + beta * to.e2;
        let g2b = to.axis.cross(g1b);
        let cf = CurveFrame {
            e,
            g1,
            g2,
            c_a: from.centre,
            g1a,
            g2a,
            c_b: to.centre,
            g1b,
            g2b,
        };

        let r = self.tool.minor_mm;
        let m = self.points_per_curve();
        let len = m.min(out.len());
        match self.placement {
            Placement::Uniform => {
                for (j, &(delta, _)) in self.tables[0].iter().enumerate().take(len) {
                    let (s, c) = delta.sin_cos();
                    let ip = self.eval(&cf, c, s);
                    out[j] = match ip.w {
                        Some(_) => ip.m,
                        // ΔT ∥ n: the whole profile cuts; one point per insert: the side point
                        // at a demarcation, the bottom elsewhere.
                        None if j == 0 || j + 1 == m => ip.t + r * ip.u,
                        None => ip.m,
                    };
                }
            }
            Placement::Adaptive => {
                let (t0, t1, f, flat) = if slope < 10f64.powf(S_LOG_MIN) {
                    (0, 0, 0.0, true)
                } else {
                    let x = ((slope.log10() - S_LOG_MIN) / (S_LOG_MAX - S_LOG_MIN)).clamp(0.0, 1.0)
                        * (S_TABLES - 2) as f64;
                    let i = (x.floor() as usize).min(S_TABLES - 3);
                    (i + 1, i + 2, x - i as f64, false)
                };
                let (ta, tb) = (&self.tables[t0], &self.tables[t1]);
                for j in 0..len {
                    let (delta, theta) = if flat {
                        ta[j]
                    } else {
                        (
                            ta[j].0 + f * (tb[j].0 - ta[j].0),
                            ta[j].1 + f * (tb[j].1 - ta[j].1),
                        )
                    };
                    let (s, c) = delta.sin_cos();
                    let ip = self.eval(&cf, c, s);
                    let on_profile = flat && (delta == 0.0 || delta == PI);
                    out[j] = match ip.w {
                        Some(_) if !on_profile => ip.m,
                        _ => ip.t + r * (theta.sin() * ip.u - theta.cos() * k),
                    };
                }
            }
        }
        let status = if axial {
            CurveStatus::Axial
        } else {
            CurveStatus::Regular
        };
        CurveInfo { status, front }
    }

    /// Imprint curves of consecutive poses, one per pose, in parallel (rayon), written to
    /// `out` (`frames.len() × points_per_curve()` points): pose `p < P−1` gets the outgoing
    /// curve of step `p → p+1`, the last pose the incoming curve of the last step. Poses whose
    /// step does not move get the neighbouring curve's status `NoMotion` and untouched output.
    /// Results do not depend on the number of threads.
    pub fn curves(&self, frames: &[PoseFrame], half: Half, out: &mut [DVec3]) -> Vec<CurveInfo> {
        let central = self.difference == Difference::Central;
        use rayon::prelude::*;
        let l = self.points_per_curve();
        let np = frames.len();
        if np < 2 {
            return vec![
                CurveInfo {
                    status: CurveStatus::NoMotion,
                    front: DVec3::ZERO
                };
                np
            ];
        }
        out.par_chunks_mut(l)
            .take(np)
            .with_min_len(256)
            .enumerate()
            .map(|(p, chunk)| {
                if central && p > 0 && p + 1 < np {
                    self.curve_at(&frames[p], &frames[p - 1], &frames[p + 1], half, chunk)
                } else if p + 1 < np {
                    self.curve(&frames[p], &frames[p + 1], Side::Outgoing, half, chunk)
                } else {
                    self.curve(&frames[p - 1], &frames[p], Side::Incoming, half, chunk)
                }
            })
            .collect()
    }
}
