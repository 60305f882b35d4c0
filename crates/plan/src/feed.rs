//! Feed-forward marching along one pass: an exact, adaptively refined CL profile whose gaps
//! carry bounds on the CL surface between their samples, then the longest moves those bounds
//! prove to stay within the tolerance.
//!
//! A pass is the line `v = const` of the raster frame. Its profile is the exact tool-tip z at
//! sorted `u` positions (the caller's samples, constant arc length on the part), refined until
//! every gap between neighbouring samples is one of (see `docs/plan-math.md` §1):
//!
//! * **planar**: both samples rest on one plane, every triangle within the cutter's reach of
//!   the gap lies at most `rise` above it and coplanar facets carry the contact: the CL
//!   surface there is the plane's, raised by at most `rise / n.z`;
//! * **lemma** (ball and bull): the samples are at most `s` apart in 3-D, so any move through
//!   points no deeper than `g` below them penetrates the part by at most
//!   `r − sqrt((r − g)² − L²/4)` between them (`r` the corner radius); and the contact
//!   pieces of the two samples bound the CL surface's dip below their chord by `dip`;
//! * **sampled** (flat end mill, or surfaces without certificates): the exact z at the
//!   midpoint is within η/2 of the chord and the slope does not jump (a sampling argument,
//!   not a proof). A flat end mill on a surface that gives the exact rise of the CL surface
//!   above a move skips the midpoint for the gouge side: [`prove_moves`] proves each marched
//!   move instead;
//! * **break** (the cutter touches nothing in between) or **unresolved** (closer than
//!   [`MIN_DU_MM`] and not certified: a vertical CL wall).
//!
//! Marching (the seed's Algorithm 1 from its Eq. 1 estimate) then joins `L_i` to the farthest
//! `L_k` whose move the gap bounds prove: penetration ≤ τ and vertical excess ≤ τ.

use cam_core::DVec3;

use crate::{ClSample, ClSurface, frame::Raster};

/// Fraction η/τ reserved for the CL surface between samples on the sampled (heuristic) path:
/// gaps are refined until the fresh midpoint is within η/2 of the chord; moves are accepted
/// at `τ − η` at the samples and midpoints.
pub const LINEARITY_FRACTION: f64 = 0.2;

/// Share of τ the lemma's spacing term uses on its own: samples are refined to a 3-D spacing
/// `s` with `r − sqrt(r² − s²/4) = SPACING_FRACTION · τ`; the rest of τ is left for moves
/// spanning several samples.
pub const SPACING_FRACTION: f64 = 1.0;

/// Largest certified dip of the CL surface below a gap's chord, as a share of τ.
pub const DIP_FRACTION: f64 = 0.25;

/// Largest rise of material above a plane accepted for a planar gap, as a share of τ.
pub const RISE_FRACTION: f64 = 0.25;

/// On the sampled path, a gap whose two samples rest on one plane that the material within
/// reach rises above is split down to this share of the sample spacing before its midpoint
/// is trusted (on mount_rush a flat end mill's 1.03 mm gap hid a 0.3 mm shelf whose edge
/// drops 0.08 mm next to the midpoint: a 0.094 mm gouge).
pub const RAISED_PLANE_SPLIT: f64 = 0.125;

/// Gaps shorter than this (mm, along `u`) are not refined further.
pub const MIN_DU_MM: f64 = 1e-5;

/// Where the CL surface ends, located to this precision (mm, along `u`).
pub const EDGE_TOL_MM: f64 = 1e-5;

/// A triangle whose vertices are within this distance (mm) of a plane lies in it (the
/// drop-cutter's rule, `cam_offset::COPLANAR_MM`).
const COPLANAR_MM: f64 = 1e-9;

/// What is known about the CL surface between two neighbouring samples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Gap {
    /// The cutter touches nothing somewhere in between: never joined.
    Break,
    /// Not yet classified.
    Pending,
    /// Planar: material rises at most `rise` (mm, along the normal) above the samples'
    /// plane, whose normal has z component `nz`; coplanar facets carry the contact.
    Planar { rise: f64, nz: f64 },
    /// Certified by the samples: gouge by the lemma (ball/bull) or, with `mid`, by the
    /// midpoint test; excess by `dip` (certified, vertical mm) or the midpoint.
    Open { dip: Option<f64>, mid: Option<f64> },
    /// Closer than [`MIN_DU_MM`] and still not certified; `dz` is the z step (mm).
    Unresolved { dz: f64 },
}

/// A pass's exact profile: samples `(u, z_tip)` in increasing `u`, their certificates, and
/// the gap after each sample (`gaps[j]` lies between samples `j` and `j + 1`; the last is a
/// `Break`).
#[derive(Debug, Clone, Default)]
pub(crate) struct Profile {
    pub pts: Vec<(f64, f64)>,
    pub cert: Vec<ClSample>,
    pub gaps: Vec<Gap>,
    /// Drop-cutter samples this profile cost (including edge searches and midpoints).
    pub drops: usize,
}

/// Parameters of the profile refinement and the move check.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Check {
    /// τ (mm).
    pub tau: f64,
    /// Corner radius r (mm) for the lemma; 0 for a flat end mill (sampled path).
    pub corner: f64,
    /// Largest gap between samples (mm): 3-D for the lemma, along `u` for the sampled path.
    pub spacing: f64,
    /// Acceptance (mm) at samples and midpoints on the sampled path: τ − η.
    pub accept: f64,
    /// η (mm), the sampled path's linearity budget.
    pub eta: f64,
    /// Largest certified dip (mm) accepted for a gap.
    pub dip_budget: f64,
    /// Largest planar rise (mm) accepted for a gap.
    pub rise_budget: f64,
    /// Longest move (mm, 3-D).
    pub max_step: f64,
    /// Cutter radius (mm), the scale of the Eq. 1 estimate.
    pub radius: f64,
    /// Flat end mill on a surface that gives the exact rise of the CL surface above a move
    /// ([`ClSurface::chord_rise`]): the gouge side is proven by [`prove_moves`], so the
    /// profile is refined only for the excess side.
    pub exact_gouge: bool,
}

impl Check {
    /// The check for cutter corner radius `corner`, radius `radius`, tolerance `tau`, with
    /// `sampled_spacing` the sample spacing of the sampled path.
    pub fn new(tau: f64, corner: f64, radius: f64, sampled_spacing: f64, max_step: f64) -> Check {
        let eta = LINEARITY_FRACTION * tau;
        let spacing = if corner > 0.0 {
            let e = (SPACING_FRACTION * tau).min(corner);
            2.0 * (corner * corner - (corner - e) * (corner - e))
                .max(0.0)
                .sqrt()
        } else {
            sampled_spacing
        };
        Check {
            tau,
            corner,
            spacing,
            accept: tau - eta,
            eta,
            dip_budget: DIP_FRACTION * tau,
            rise_budget: RISE_FRACTION * tau,
            max_step,
            radius,
            exact_gouge: false,
        }
    }
}

/// Outcome of marching one pass.
#[derive(Debug, Clone, Default)]
pub(crate) struct Marched {
    /// Runs of CL points `(u, z)`, each joined by cut moves; runs are separated by gaps.
    pub runs: Vec<Vec<(f64, f64)>>,
    /// Largest bound (mm) over accepted moves: penetration (normal) or vertical excess.
    pub max_dev: f64,
    /// Joins across unresolved gaps (vertical CL walls).
    pub unresolved: usize,
    /// Largest z step (mm) at those joins.
    pub unresolved_dev: f64,
    /// Moves whose bound rests on the sampled (heuristic) path somewhere.
    pub sampled_moves: usize,
    /// Moves whose gouge side was sampled (flat end mills): `(u_a, u_b, excess_sampled)`,
    /// for [`prove_moves`].
    pub gouge_sampled: Vec<(f64, f64, bool)>,
}

fn xy(f: &Raster, u: f64, v: f64) -> (f64, f64) {
    f.to_xy(u, v)
}

fn sample_at(s: &dyn ClSurface, f: &Raster, u: f64, v: f64, hints: &[DVec3]) -> Option<ClSample> {
    let (x, y) = xy(f, u, v);
    s.sample(x, y, hints).filter(|c| c.z.is_finite())
}

fn hints_of(a: &ClSample, b: Option<&ClSample>) -> Vec<DVec3> {
    a.cc.into_iter().chain(b.and_then(|b| b.cc)).collect()
}

/// Bisects between `a` (hit) and `b` (miss) for the edge of the touched region; returns the
/// hit sample nearest the edge and the drops spent.
fn edge(
    s: &dyn ClSurface,
    f: &Raster,
    v: f64,
    a: (f64, ClSample),
    b: f64,
    drops: &mut usize,
) -> (f64, ClSample) {
    let (mut ua, mut ca) = a;
    let mut ub = b;
    while (ub - ua).abs() > EDGE_TOL_MM {
        let m = 0.5 * (ua + ub);
        *drops += 1;
        match sample_at(s, f, m, v, &hints_of(&ca, None)) {
            Some(c) => {
                ua = m;
                ca = c;
            }
            None => ub = m,
        }
    }
    (ua, ca)
}

/// The exact profile of the pass at `v` over `[u_lo, u_hi]`, from the caller's `samples`
/// and a grid of spacing at most `initial`, refined until every gap is classified (see the
/// module docs). Edges of the touched region are located to [`EDGE_TOL_MM`].
pub(crate) fn profile(
    s: &dyn ClSurface,
    f: &Raster,
    v: f64,
    (u_lo, u_hi): (f64, f64),
    samples: &[f64],
    initial: f64,
    chk: &Check,
) -> Profile {
    let n = (((u_hi - u_lo) / initial).ceil() as usize).max(1);
    let mut us: Vec<f64> = (0..=n)
        .map(|k| u_lo + (u_hi - u_lo) * k as f64 / n as f64)
        .collect();
    us.extend(
        samples
            .iter()
            .copied()
            .filter(|u| u.is_finite() && *u > u_lo && *u < u_hi),
    );
    us.sort_by(f64::total_cmp);
    us.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    let pts_xy: Vec<(f64, f64)> = us.iter().map(|&u| xy(f, u, v)).collect();
    let zs = s.samples(&pts_xy);
    let mut p = Profile {
        drops: us.len(),
        ..Profile::default()
    };
    let mut drops = 0;
    for k in 0..us.len() {
        match zs[k].filter(|c| c.z.is_finite()) {
            Some(c) => {
                if k > 0 && zs[k - 1].is_none_or(|c| !c.z.is_finite()) {
                    let (eu, ec) = edge(s, f, v, (us[k], c), us[k - 1], &mut drops);
                    if let Some(g) = p.gaps.last_mut() {
                        *g = Gap::Break;
                    }
                    if eu < us[k] {
                        p.push(eu, ec, Gap::Pending);
                    }
                }
                p.push(us[k], c, Gap::Pending);
            }
            None => {
                if k > 0
                    && let Some(prev) = zs[k - 1].filter(|c| c.z.is_finite())
                {
                    let (eu, ec) = edge(s, f, v, (us[k - 1], prev), us[k], &mut drops);
                    if eu > us[k - 1] {
                        p.push(eu, ec, Gap::Pending);
                    }
                    if let Some(g) = p.gaps.last_mut() {
                        *g = Gap::Break;
                    }
                }
            }
        }
    }
    if let Some(g) = p.gaps.last_mut() {
        *g = Gap::Break;
    }
    p.drops += drops;
    refine(s, f, v, p, chk)
}

impl Profile {
    fn push(&mut self, u: f64, c: ClSample, gap: Gap) {
        self.pts.push((u, c.z));
        self.cert.push(c);
        self.gaps.push(gap);
    }
}

/// What a round decides for one pending gap.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Action {
    Done(Gap),
    /// Split at `u` (mm).
    Split(f64),
    /// Drop the midpoint, then test it (sampled path).
    Test,
    /// Drop the midpoint, then test only that the CL does not rise above the chord there
    /// (sampled path, the excess side certified by the contact pieces' dip, mm).
    TestUpper(f64),
}

/// The value (mm) of contact piece `piece` at `u` on the pass at `v` ([`ClSurface::piece_z`]).
fn piece_at(s: &dyn ClSurface, f: &Raster, v: f64, piece: u32, u: f64) -> Option<f64> {
    let (x, y) = xy(f, u, v);
    s.piece_z(piece, x, y)
}

/// Where the contact pieces of samples `a` and `b` cross between them (mm along `u`): at a
/// crease of the CL surface (two pieces meeting in a V) this is the crease, and a sample
/// there certifies both halves (each then has a piece equal to its end's z at both ends).
/// Found by bisection on the pieces alone (no drops); `None` without two distinct pieces
/// reaching across the gap.
fn crease_at(
    s: &dyn ClSurface,
    f: &Raster,
    v: f64,
    (ua, ca): (f64, &ClSample),
    (ub, cb): (f64, &ClSample),
) -> Option<f64> {
    let (pa, pb) = (ca.piece?, cb.piece?);
    if pa == pb {
        return None;
    }
    // g(u) = f_a(u) − f_b(u): > 0 at u_a (f_a = z_a ≥ f_b), < 0 at u_b.
    let g = |u: f64| Some(piece_at(s, f, v, pa, u)? - piece_at(s, f, v, pb, u)?);
    let (mut lo, mut hi) = (ua, ub);
    if !(g(lo)? > 0.0 && g(hi)? < 0.0) {
        return None;
    }
    for _ in 0..60 {
        let m = 0.5 * (lo + hi);
        match g(m) {
            Some(gm) if gm > 0.0 => lo = m,
            Some(_) => hi = m,
            None => return None,
        }
        if hi - lo <= 1e-12 * (1.0 + ua.abs()) {
            break;
        }
    }
    let m = 0.5 * (lo + hi);
    (m > ua && m < ub).then_some(m)
}

/// Certified dip (mm) of the CL surface below the chord of samples `a` and `b`: with the
/// concave contact pieces `f_a`, `f_b` (lower bounds of the surface, `f_a(u_a) = z_a`),
/// `chord − max(f_a, f_b)` is at most `G_a·G_b / (G_a + G_b)`, `G_a = z_b − f_a(u_b)`,
/// `G_b = z_a − f_b(u_a)`. `None` when a piece is unknown or out of reach at both ends.
fn dip_bound(
    s: &dyn ClSurface,
    f: &Raster,
    v: f64,
    (ua, ca): (f64, &ClSample),
    (ub, cb): (f64, &ClSample),
) -> Option<f64> {
    let (pa, pb) = (ca.piece?, cb.piece?);
    if pa == pb {
        return Some(0.0);
    }
    let ga = piece_at(s, f, v, pa, ub).map_or(f64::INFINITY, |z| cb.z - z);
    let gb = piece_at(s, f, v, pb, ua).map_or(f64::INFINITY, |z| ca.z - z);
    if ga <= 0.0 || gb <= 0.0 {
        return Some(0.0);
    }
    match (ga.is_finite(), gb.is_finite()) {
        (true, true) => Some(ga * gb / (ga + gb)),
        (true, false) => Some(ga),
        (false, true) => Some(gb),
        (false, false) => None,
    }
}

fn same_plane(a: Option<(DVec3, f64)>, b: Option<(DVec3, f64)>) -> Option<(DVec3, f64)> {
    let ((na, da), (nb, db)) = (a?, b?);
    ((na - nb).length() <= 1e-12 && (da - db).abs() <= COPLANAR_MM).then_some((na, da))
}

/// Classifies one pending gap (without its midpoint).
fn classify(s: &dyn ClSurface, f: &Raster, v: f64, p: &Profile, j: usize, chk: &Check) -> Action {
    let ((ua, za), (ub, zb)) = (p.pts[j], p.pts[j + 1]);
    let (ca, cb) = (&p.cert[j], &p.cert[j + 1]);
    let du = ub - ua;
    // Both samples on one plane, but material within reach rises above it: something (a
    // shelf, a step) lifts the CL surface between them that neither sample sees.
    let mut raised_plane = false;
    if let Some((n, d)) = same_plane(ca.plane, cb.plane) {
        match s.plane_bound(xy(f, ua, v), xy(f, ub, v), n, d, chk.rise_budget) {
            Some(b) if b.covered => {
                return Action::Done(Gap::Planar {
                    rise: b.rise_mm,
                    nz: n.z,
                });
            }
            _ => raised_plane = true,
        }
    }
    let tiny = du <= MIN_DU_MM;
    let mid = 0.5 * (ua + ub);
    if chk.corner > 0.0 {
        let l3 = (du * du + (zb - za) * (zb - za)).sqrt();
        if l3 > chk.spacing {
            return if tiny {
                Action::Done(Gap::Unresolved {
                    dz: (zb - za).abs(),
                })
            } else {
                Action::Split(mid)
            };
        }
        match dip_bound(s, f, v, (ua, ca), (ub, cb)) {
            Some(dip) if dip <= chk.dip_budget => Action::Done(Gap::Open {
                dip: Some(dip),
                mid: None,
            }),
            Some(_) if !tiny => {
                // Split where the pieces cross (a crease), unless that is too close to an
                // end to halve the gap's doubt.
                let at = crease_at(s, f, v, (ua, ca), (ub, cb))
                    .filter(|&u| u - ua > MIN_DU_MM && ub - u > MIN_DU_MM)
                    .unwrap_or(mid);
                Action::Split(at)
            }
            // No certificate for the excess: test the midpoint.
            _ if !tiny => Action::Test,
            _ => Action::Done(Gap::Open {
                dip: Some((zb - za).abs()),
                mid: None,
            }),
        }
    } else if tiny {
        if (zb - za).abs() <= chk.eta {
            Action::Done(Gap::Open {
                dip: None,
                mid: None,
            })
        } else {
            Action::Done(Gap::Unresolved {
                dz: (zb - za).abs(),
            })
        }
    } else if chk.exact_gouge {
        // The gouge side is proven move by move after marching; the excess side by the
        // contact pieces, else by the midpoint.
        match dip_bound(s, f, v, (ua, ca), (ub, cb)) {
            Some(dip) if dip <= chk.dip_budget => Action::Done(Gap::Open {
                dip: Some(dip),
                mid: None,
            }),
            Some(_) => Action::Split(
                crease_at(s, f, v, (ua, ca), (ub, cb))
                    .filter(|&u| u - ua > MIN_DU_MM && ub - u > MIN_DU_MM)
                    .unwrap_or(mid),
            ),
            None => Action::Test,
        }
    } else if du > chk.spacing || (raised_plane && du > RAISED_PLANE_SPLIT * chk.spacing) {
        // A flat end mill's CL section can step up over a shelf and drop off it again
        // within the gap, with both ends (and the midpoint, if the drop is near it) on the
        // plane: one midpoint does not see it, so such gaps are split further.
        Action::Split(mid)
    } else {
        // No corner radius: the excess side by the contact pieces where the surface
        // certifies them; the gouge side by the midpoint (a single ridge between the samples
        // deviates at most twice as much as the midpoint does).
        match dip_bound(s, f, v, (ua, ca), (ub, cb)) {
            Some(dip) if dip <= chk.dip_budget => Action::TestUpper(dip),
            Some(_) => Action::Split(
                crease_at(s, f, v, (ua, ca), (ub, cb))
                    .filter(|&u| u - ua > MIN_DU_MM && ub - u > MIN_DU_MM)
                    .unwrap_or(mid),
            ),
            None => Action::Test,
        }
    }
}

/// The sampled path's tests on gap `j` with its midpoint z `zm`: the midpoint within η/2 of
/// the chord, and no slope jump to a joinable neighbour larger than η over the gap.
fn midpoint_ok(p: &Profile, j: usize, zm: f64, chk: &Check) -> bool {
    let ((ua, za), (ub, zb)) = (p.pts[j], p.pts[j + 1]);
    if (0.5 * (za + zb) - zm).abs() > chk.eta / 2.0 {
        return false;
    }
    // A crease of the CL section near the gap shows as a slope jump even when a curved
    // stretch makes the midpoint fit by cancellation.
    let slope = |k: usize| (p.pts[k + 1].1 - p.pts[k].1) / (p.pts[k + 1].0 - p.pts[k].0);
    let sj = slope(j);
    let joinable = |k: usize| !matches!(p.gaps[k], Gap::Break);
    let left = if j > 0 && joinable(j - 1) {
        (sj - slope(j - 1)).abs()
    } else {
        0.0
    };
    let right = if j + 2 < p.pts.len() && joinable(j + 1) {
        (slope(j + 1) - sj).abs()
    } else {
        0.0
    };
    (ub - ua) * left.max(right) <= chk.eta
}

/// Refines a profile until every gap is classified.
fn refine(s: &dyn ClSurface, f: &Raster, v: f64, mut p: Profile, chk: &Check) -> Profile {
    use rayon::prelude::*;
    loop {
        let pending: Vec<usize> = (0..p.gaps.len())
            .filter(|&j| p.gaps[j] == Gap::Pending)
            .collect();
        if pending.is_empty() {
            break;
        }
        let actions: Vec<Action> = pending
            .par_iter()
            .map(|&j| classify(s, f, v, &p, j, chk))
            .collect();
        // Midpoints to drop: splits and tests.
        let want: Vec<usize> = pending
            .iter()
            .zip(&actions)
            .filter(|(_, a)| !matches!(a, Action::Done(_)))
            .map(|(&j, _)| j)
            .collect();
        let at: Vec<f64> = pending
            .iter()
            .zip(&actions)
            .filter_map(|(&j, a)| match *a {
                Action::Done(_) => None,
                Action::Split(u) => Some(u),
                Action::Test | Action::TestUpper(_) => Some(0.5 * (p.pts[j].0 + p.pts[j + 1].0)),
            })
            .collect();
        let mids: Vec<Option<ClSample>> = want
            .par_iter()
            .zip(&at)
            .map(|(&j, &um)| sample_at(s, f, um, v, &hints_of(&p.cert[j], Some(&p.cert[j + 1]))))
            .collect();
        p.drops += want.len();
        // Decide, then rebuild with the inserted samples.
        // Gap index, split point, sample there.
        let mut insert: Vec<(usize, f64, Option<ClSample>)> = Vec::new();
        let mut wi = 0;
        for (&j, a) in pending.iter().zip(&actions) {
            match *a {
                Action::Done(g) => p.gaps[j] = g,
                Action::Split(u) => {
                    insert.push((j, u, mids[wi]));
                    wi += 1;
                }
                Action::Test => {
                    let m = mids[wi];
                    wi += 1;
                    match m {
                        Some(c) if midpoint_ok(&p, j, c.z, chk) => {
                            p.gaps[j] = Gap::Open {
                                dip: None,
                                mid: Some(c.z),
                            }
                        }
                        _ => insert.push((j, at[wi - 1], m)),
                    }
                }
                Action::TestUpper(dip) => {
                    let m = mids[wi];
                    wi += 1;
                    let ((_, za), (_, zb)) = (p.pts[j], p.pts[j + 1]);
                    let lerp = 0.5 * (za + zb);
                    // Vertical, as the move check (`move_bound`, sampled path).
                    match m {
                        Some(c) if c.z - lerp <= chk.eta / 2.0 => {
                            p.gaps[j] = Gap::Open {
                                dip: Some(dip),
                                mid: Some(c.z),
                            }
                        }
                        _ => insert.push((j, at[wi - 1], m)),
                    }
                }
            }
        }
        if insert.is_empty() {
            continue;
        }
        let old = std::mem::take(&mut p);
        let n = old.pts.len();
        let mut next = Profile {
            drops: old.drops,
            ..Profile::default()
        };
        let mut ii = 0;
        let mut drops = 0;
        for j in 0..n {
            next.push(old.pts[j].0, old.cert[j], old.gaps[j]);
            if ii < insert.len() && insert[ii].0 == j {
                let (um, m) = (insert[ii].1, insert[ii].2);
                ii += 1;
                let (ua, ub) = (old.pts[j].0, old.pts[j + 1].0);
                match m {
                    Some(c) => {
                        // Both halves pending.
                        if let Some(g) = next.gaps.last_mut() {
                            *g = Gap::Pending;
                        }
                        next.push(um, c, Gap::Pending);
                    }
                    None => {
                        // The cutter leaves the part in between: cut at both edges.
                        let (e0u, e0) = edge(s, f, v, (ua, old.cert[j]), um, &mut drops);
                        let (e1u, e1) = edge(s, f, v, (ub, old.cert[j + 1]), um, &mut drops);
                        if let Some(g) = next.gaps.last_mut() {
                            *g = if e0u > ua { Gap::Pending } else { Gap::Break };
                        }
                        if e0u > ua {
                            next.push(e0u, e0, Gap::Break);
                        }
                        if e1u < ub {
                            next.push(e1u, e1, Gap::Pending);
                        }
                    }
                }
            }
        }
        next.drops += drops;
        p = next;
    }
    p
}

fn len3(a: (f64, f64), b: (f64, f64)) -> f64 {
    ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt()
}

/// Which sides of a move's bound rest on the sampled path.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Sampled {
    /// The gouge side (CL above the move).
    pub gouge: bool,
    /// The excess side (move above the CL).
    pub excess: bool,
}

/// The bound a move `i → k` gets from the gaps it spans: `Some((bound, sampled))` where
/// `bound` is the largest penetration (normal, mm) or vertical excess (mm) it proves and
/// `sampled` says which sides used the sampled path; `None` if the move fails.
pub(crate) fn move_bound(p: &Profile, i: usize, k: usize, chk: &Check) -> Option<(f64, Sampled)> {
    let (ua, za) = p.pts[i];
    let (ub, zb) = p.pts[k];
    let du = ub - ua;
    if len3(p.pts[i], p.pts[k]) > chk.max_step && k > i + 1 {
        return None;
    }
    let slope = (zb - za) / du;
    let chord = |u: f64| za + slope * (u - ua);
    let stretch = (1.0 + slope * slope).sqrt();
    let r = chk.corner;
    let mut worst = 0.0f64;
    let mut sampled = Sampled::default();
    for j in i..k {
        let ((u0, z0), (u1, z1)) = (p.pts[j], p.pts[j + 1]);
        let (d0, d1) = (z0 - chord(u0), z1 - chord(u1)); // + : CL above the move (gouge side)
        let up = d0.max(d1).max(0.0);
        let down = (-d0).max(-d1).max(0.0);
        match p.gaps[j] {
            Gap::Break | Gap::Pending => return None,
            Gap::Unresolved { .. } => {
                if k != i + 1 {
                    return None;
                }
            }
            Gap::Planar { rise, nz } => {
                let pen = up * nz + rise;
                let exc = down + COPLANAR_MM / nz;
                if pen > chk.tau || exc > chk.tau {
                    return None;
                }
                worst = worst.max(pen).max(exc);
            }
            Gap::Open { dip, mid } => {
                let mid_dev = mid.map(|zm| zm - chord(0.5 * (u0 + u1)));
                // Gouge side.
                if r > 0.0 {
                    let l = (u1 - u0) * stretch;
                    let q = (r - up) * (r - up) - l * l / 4.0;
                    if up >= r || q < 0.0 {
                        return None;
                    }
                    let pen = r - q.sqrt();
                    if pen > chk.tau {
                        return None;
                    }
                    worst = worst.max(pen);
                } else {
                    // Sampled path (flat end mill): the move's depth below the CL at the
                    // samples and the midpoint, vertical. Lowered by δ from touching, the
                    // cutter penetrates at most δ, and a flat end mill can penetrate that
                    // much even on a steep move: its bottom may rest on level material
                    // near the rim while the CL climbs (on mount_rush a 67° move 0.0146 mm
                    // low cut 0.0125 mm into a level patch; normal to the move, 0.0057).
                    sampled.gouge = true;
                    let g = up.max(mid_dev.unwrap_or(0.0));
                    if g > chk.accept {
                        return None;
                    }
                    worst = worst.max(g);
                }
                // Excess side.
                match dip {
                    Some(dip) => {
                        let exc = down + dip;
                        if exc > chk.tau {
                            return None;
                        }
                        worst = worst.max(exc);
                    }
                    None => {
                        sampled.excess = true;
                        let e = down.max(mid_dev.map_or(0.0, |m| -m));
                        if e > chk.accept {
                            return None;
                        }
                        worst = worst.max(e);
                    }
                }
            }
        }
    }
    Some((worst, sampled))
}

/// Eq. 1 of the seed: δ = 2·sqrt(2τ|ρ| − τ²) with ρ the CL section's radius of curvature
/// at `i`, estimated through the profile points about `λ/2` and `λ` of arc ahead
/// (λ = 2·sqrt(2Rτ), the step for a CL radius R).
fn eq1_step(pts: &[(f64, f64)], i: usize, end: usize, chk: &Check) -> f64 {
    let lam = 2.0 * (2.0 * chk.radius * chk.tau).sqrt();
    let mut acc = 0.0;
    let (mut j1, mut j2) = (None, None);
    for j in i + 1..=end {
        acc += len3(pts[j - 1], pts[j]);
        if j1.is_none() && acc >= lam / 2.0 {
            j1 = Some(j);
        } else if j1.is_some() && acc >= lam {
            j2 = Some(j);
            break;
        }
    }
    let rho = match (j1, j2) {
        (Some(a), Some(b)) => crate::sidestep::signed_radius(pts[i], pts[a], pts[b]).abs(),
        _ => f64::INFINITY,
    };
    if rho.is_infinite() {
        chk.max_step
    } else if rho <= chk.tau {
        0.0
    } else {
        2.0 * (2.0 * chk.tau * rho - chk.tau * chk.tau).sqrt()
    }
}

/// Marches a refined profile (see the module docs).
pub(crate) fn march(p: &Profile, chk: &Check) -> Marched {
    let pts = &p.pts;
    let mut out = Marched::default();
    if pts.is_empty() {
        return out;
    }
    let mut run = vec![pts[0]];
    let mut i = 0;
    while i + 1 < pts.len() {
        if p.gaps[i] == Gap::Break {
            if run.len() >= 2 {
                out.runs.push(std::mem::take(&mut run));
            } else {
                run.clear();
            }
            i += 1;
            run.push(pts[i]);
            continue;
        }
        // Last index reachable without crossing a break.
        let end = (i..pts.len())
            .find(|&j| p.gaps[j] == Gap::Break)
            .unwrap_or(pts.len() - 1);
        let ok = |k: usize| move_bound(p, i, k, chk).is_some();
        // Initial guess from Eq. 1, then gallop up / bisect down to a locally longest move.
        let delta = eq1_step(pts, i, end, chk);
        let mut acc = 0.0;
        let mut k0 = end;
        for j in i + 1..=end {
            acc += len3(pts[j - 1], pts[j]);
            if acc >= delta {
                k0 = j;
                break;
            }
        }
        let k0 = k0.max(i + 1);
        let (mut lo, mut hi) = if ok(k0) {
            let mut lo = k0;
            let mut step = 1;
            loop {
                let cand = (lo + step).min(end);
                if cand == lo {
                    break (lo, lo + 1);
                }
                if ok(cand) {
                    lo = cand;
                    step *= 2;
                } else {
                    break (lo, cand);
                }
            }
        } else {
            (i + 1, k0)
        };
        while hi > lo + 1 && hi <= end {
            let mid = (lo + hi) / 2;
            if ok(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        match move_bound(p, i, lo, chk) {
            Some((b, sampled)) => {
                out.max_dev = out.max_dev.max(b);
                out.sampled_moves += usize::from(sampled.gouge || sampled.excess);
                if sampled.gouge {
                    out.gouge_sampled
                        .push((pts[i].0, pts[lo].0, sampled.excess));
                }
            }
            None => {
                // A single gap that its own bounds do not prove (unresolved wall, or a
                // lemma gap too steep to fit): joined and counted.
                out.unresolved += 1;
                out.unresolved_dev = out.unresolved_dev.max((pts[lo].1 - pts[i].1).abs());
            }
        }
        if let Gap::Unresolved { dz } = p.gaps[i]
            && lo == i + 1
        {
            out.unresolved += 1;
            out.unresolved_dev = out.unresolved_dev.max(dz);
        }
        i = lo;
        run.push(pts[i]);
    }
    if run.len() >= 2 {
        out.runs.push(run);
    }
    out
}

/// Rounds of [`prove_moves`] before it leaves the remaining moves on the sampled path.
const PROOF_ROUNDS: usize = 40;

/// Proves the gouge side of the moves a flat end mill's march accepted by sampling: the
/// exact height of the CL surface above each move's chord ([`ClSurface::chord_rise`],
/// vertical, the flat's gouge measure) must be at most τ. Where it is not, the exact sample
/// at the highest point goes into the profile and the pass is marched again. Moves whose
/// excess side is certified too are then proven; the rest stay counted as sampled. Surfaces
/// that cannot tell leave the march as it was. Should the rounds run out with a move still
/// rising above τ, its rise goes into the pass's bound ([`Marched::max_dev`]), so the plan
/// reports it rather than hiding it among the sampled moves.
pub(crate) fn prove_moves(
    s: &dyn ClSurface,
    f: &Raster,
    v: f64,
    p: &mut Profile,
    mut m: Marched,
    chk: &Check,
) -> Marched {
    use rayon::prelude::*;
    if m.gouge_sampled.is_empty() {
        return m;
    }
    let key = |ua: f64, ub: f64| (ua.to_bits(), ub.to_bits());
    let mut proven: std::collections::HashMap<(u64, u64), f64> = Default::default();
    // Moves found to rise above τ (kept only if the rounds run out before they are split).
    let mut failed: std::collections::HashMap<(u64, u64), f64> = Default::default();
    let z_of = |p: &Profile, u: f64| {
        let j = p.pts.partition_point(|q| q.0 < u);
        p.pts.get(j).filter(|q| q.0 == u).map(|q| q.1)
    };
    for _ in 0..PROOF_ROUNDS {
        let todo: Vec<(f64, f64, f64, f64)> = m
            .gouge_sampled
            .iter()
            .filter(|mv| !proven.contains_key(&key(mv.0, mv.1)))
            .filter_map(|&(ua, ub, _)| Some((ua, z_of(p, ua)?, ub, z_of(p, ub)?)))
            .collect();
        if todo.is_empty() {
            break;
        }
        let rises: Vec<Option<(f64, f64)>> = todo
            .par_iter()
            .map(|&(ua, za, ub, zb)| s.chord_rise(xy(f, ua, v), xy(f, ub, v), za, zb, chk.tau))
            .collect();
        let mut split: Vec<f64> = Vec::new();
        for (&(ua, _, ub, _), r) in todo.iter().zip(rises) {
            match r {
                None => return m,
                Some((rise, _)) if rise <= chk.tau => {
                    proven.insert(key(ua, ub), rise.max(0.0));
                }
                Some((rise, at)) => {
                    failed.insert(key(ua, ub), rise);
                    split.push(ua + at * (ub - ua));
                }
            }
        }
        if split.is_empty() {
            break;
        }
        // The exact samples where the moves rose above τ, then the pass again.
        let samples: Vec<Option<ClSample>> = split
            .par_iter()
            .map(|&u| sample_at(s, f, u, v, &[]))
            .collect();
        p.drops += split.len();
        let mut inserted = false;
        for (&u, c) in split.iter().zip(samples) {
            let Some(c) = c else { continue };
            let j = p.pts.partition_point(|q| q.0 < u);
            if j == 0 || j >= p.pts.len() || p.pts[j].0 == u {
                continue;
            }
            p.pts.insert(j, (u, c.z));
            p.cert.insert(j, c);
            p.gaps[j - 1] = Gap::Pending;
            p.gaps.insert(j, Gap::Pending);
            inserted = true;
        }
        if !inserted {
            break;
        }
        *p = refine(s, f, v, std::mem::take(p), chk);
        m = march(p, chk);
    }
    // Recount with the proofs; a move still known to rise above τ reports that rise.
    for &(ua, ub, excess_sampled) in &m.gouge_sampled {
        if let Some(&rise) = proven.get(&key(ua, ub)) {
            m.max_dev = m.max_dev.max(rise);
            if !excess_sampled {
                m.sampled_moves -= 1;
            }
        } else if let Some(&rise) = failed.get(&key(ua, ub)) {
            m.max_dev = m.max_dev.max(rise);
        }
    }
    m
}
