//! `cam-plan`: 3-axis finishing toolpaths on the exact CL (drop-cutter) surface with a
//! guaranteed feed-forward tolerance and a scallop-limited side step.
//!
//! The planner works on any [`ClSurface`] (the exact tool-tip height of the cutter resting on
//! the part); [`cam_offset::DropCutter`] is one. Passes are lines `v = const` of a raster frame
//! rotated by `angle_deg`; along each pass the exact CL profile is marched (the seed's
//! Algorithm 1 started from its Eq. 1, every move proven within τ); the side step (Eq. 2
//! re-derived, times `cos θ`, the seed's Algorithm 2 against the next pass) is the minimum
//! over the pass of the scallop-limited interval. The maths is in `docs/plan-math.md`.
//!
//! # Guarantees
//! - **Feed-forward (proven for ball and bull cutters).** Every cut move on a pass
//!   penetrates the part by at most τ (the cutter's depth into the material, normal to the
//!   part) and stays at most τ above the exact CL surface. Each pass's exact profile is refined
//!   until every gap between samples carries a bound: the lemma of `docs/plan-math.md` §1
//!   (penetration ≤ `r − sqrt((r − g)² − L²/4)` between points `L` apart and `g` below the CL
//!   surface, `r` the corner radius), the contact pieces' bound on the CL's dip below a chord,
//!   or a plane certificate over flat ground. The lemma needs only exact samples of a genuine
//!   CL surface; the dip and plane bounds need a [`ClSurface`] that certifies (the
//!   drop-cutter of a mesh does). Flat end mills (no corner radius) are proven move by move
//!   from the exact rise of the CL surface above the move ([`ClSurface::chord_rise`],
//!   vertical). Surfaces without these certificates fall back to midpoint tests for what
//!   the bounds cannot give (a sampling argument; such moves are counted in
//!   [`Plan::sampled_moves`]). Vertical walls of the CL
//!   surface that cannot be resolved above 1e-5 mm are counted in [`Plan::unresolved_joins`].
//! - **Side step.** The scallop forms in the plane perpendicular to the motion along the pass,
//!   where the cutter shows its outline seen along that motion ([`sidestep::Silhouette`]:
//!   its axial profile only on level motion). The interval after each pass is the minimum,
//!   over both passes' samples and points 1 mm apart, of the model's scallop-limited
//!   interval (the outline's exact step on a straight section, re-derived Eq. 2 with the
//!   resulting effective radius and the curvature through three passes, and the slope of the
//!   chord to the next pass: ε·cos θ, the seed's Algorithm 2 against the next pass's exact
//!   profile); where that curvature may be a crease of the CL surface the scallop is measured
//!   with drops between the passes. Flat and bull cutters are then verified in CL space at
//!   points every 2R along the pass (the cusp between the two passes against the best surface
//!   the cutter can leave, from the CL surface alone) and shrunk until that holds. The model
//!   is exact on planes (any slope, any cutter), for a ball on cylinders and for a bull on
//!   its corner; [`measure_scallop`] measures what is left against the part itself (3-D
//!   distance).
//! - **No plunges into the void.** Passes end where the cutter stops touching the part
//!   (located to 1e-5 mm) or at the boundary box; links follow the surface only when the same
//!   bounds prove them.
//!
//! The library never prints; progress goes to an optional callback.

mod config;
mod feed;
mod frame;
mod interval;
#[cfg(feature = "mesh")]
mod part;
mod plan;
mod scallop;
pub mod sidestep;

use cam_core::DVec3;

pub use config::{Direction, Milling, PlanConfig, PlanError};
pub use frame::Raster;
#[cfg(feature = "mesh")]
pub use part::{SectionSampler, plan_part};
pub use plan::{
    PassSampler, Plan, Progress, STEEP_FLOOR_FRACTION, UniformSampler, VERIFY_SLACK, plan,
};
pub use scallop::{ScallopProbe, ScallopReport, measure_scallop};

/// An exact sample of the CL surface, with what the surface can certify about its
/// neighbourhood.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClSample {
    /// Tool-tip z (mm).
    pub z: f64,
    /// A piece of the surface through this sample ([`ClSurface::piece_z`]): a lower bound of
    /// the CL surface everywhere, concave along straight lines, equal to `z` here. For a mesh,
    /// the triangle carrying the contact.
    pub piece: Option<u32>,
    /// The cutter-contact point on the part (mm), a pruning hint for nearby queries.
    pub cc: Option<DVec3>,
    /// The plane the cutter rests on here, if it rests on a facet: upward unit normal `n`
    /// and offset `d` of `{p : n·p = d}` (mm).
    pub plane: Option<(DVec3, f64)>,
}

impl ClSample {
    /// A sample with no certificate.
    pub fn bare(z: f64) -> ClSample {
        ClSample {
            z,
            piece: None,
            cc: None,
            plane: None,
        }
    }
}

/// What a surface proved about the CL surface along a segment over a plane (see
/// [`ClSurface::plane_bound`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneBound {
    /// Largest height (mm, along the plane normal) by which material within the cutter's
    /// reach rises above the plane.
    pub rise_mm: f64,
    /// Coplanar facets carry the contact along the whole segment.
    pub covered: bool,
}

/// The exact tool-tip height of the cutter resting on the part: the CL surface.
///
/// Only [`ClSurface::z_tip`] is required. Surfaces that can also certify their neighbourhood
/// (the drop-cutter of a mesh) let the planner prove its tolerance between samples instead of
/// testing it by sampling; see `docs/plan-math.md` §1.
pub trait ClSurface: Sync {
    /// Tool-tip z (mm) of the cutter (axis +Z) resting on the part at `(x, y)` (mm), `None`
    /// where the cutter touches nothing.
    fn z_tip(&self, x: f64, y: f64) -> Option<f64>;

    /// The exact sample at `(x, y)`; `hints` are contact points of nearby samples (they may
    /// speed the query up, never change it).
    fn sample(&self, x: f64, y: f64, hints: &[DVec3]) -> Option<ClSample> {
        let _ = hints;
        self.z_tip(x, y).map(ClSample::bare)
    }

    /// Exact samples at every point, in order (points along a line: neighbours may share
    /// work). Identical to [`ClSurface::sample`] point by point.
    fn samples(&self, xy: &[(f64, f64)]) -> Vec<Option<ClSample>> {
        use rayon::prelude::*;
        xy.par_iter()
            .map(|&(x, y)| self.sample(x, y, &[]))
            .collect()
    }

    /// The value (mm) at `(x, y)` of the piece `piece` of a sample ([`ClSample::piece`]),
    /// `None` where the piece does not reach.
    fn piece_z(&self, piece: u32, x: f64, y: f64) -> Option<f64> {
        let _ = (piece, x, y);
        None
    }

    /// For the cutter moving in XY from `a` to `b` over the plane `n·p = d`: the largest
    /// rise of material within reach above the plane and whether coplanar facets carry the
    /// contact; `None` if the rise exceeds `max_rise_mm` or the surface cannot tell.
    fn plane_bound(
        &self,
        a: (f64, f64),
        b: (f64, f64),
        n: DVec3,
        d: f64,
        max_rise_mm: f64,
    ) -> Option<PlaneBound> {
        let _ = (a, b, n, d, max_rise_mm);
        None
    }

    /// The largest height (mm, vertical) of the CL surface above the chord of the move from
    /// `(a, za)` to `(b, zb)` (XY mm, tool-tip z mm) and the fraction of the move where it is
    /// reached; heights at or below `limit_mm / 2` may be reported as `limit_mm / 2` (an
    /// upper bound is all a proof needs), and once a height above `limit_mm` is found it
    /// may stop with that one. `None` if the surface cannot tell.
    fn chord_rise(
        &self,
        a: (f64, f64),
        b: (f64, f64),
        za: f64,
        zb: f64,
        limit_mm: f64,
    ) -> Option<(f64, f64)> {
        let _ = (a, b, za, zb, limit_mm);
        None
    }
}

#[cfg(feature = "mesh")]
impl ClSurface for cam_offset::DropCutter {
    fn z_tip(&self, x: f64, y: f64) -> Option<f64> {
        self.drop(x, y)
    }

    fn sample(&self, x: f64, y: f64, hints: &[DVec3]) -> Option<ClSample> {
        self.contact_hinted(x, y, hints).map(|c| self.to_sample(c))
    }

    fn samples(&self, xy: &[(f64, f64)]) -> Vec<Option<ClSample>> {
        self.contact_points(xy)
            .into_iter()
            .map(|c| c.map(|c| self.to_sample(c)))
            .collect()
    }

    fn piece_z(&self, piece: u32, x: f64, y: f64) -> Option<f64> {
        self.triangle_drop(piece, x, y)
    }

    fn plane_bound(
        &self,
        a: (f64, f64),
        b: (f64, f64),
        n: DVec3,
        d: f64,
        max_rise_mm: f64,
    ) -> Option<PlaneBound> {
        self.plane_certificate(a, b, n, d, max_rise_mm)
            .map(|c| PlaneBound {
                rise_mm: c.rise_mm,
                covered: c.covered,
            })
    }

    fn chord_rise(
        &self,
        a: (f64, f64),
        b: (f64, f64),
        za: f64,
        zb: f64,
        limit_mm: f64,
    ) -> Option<(f64, f64)> {
        let r = cam_offset::DropCutter::chord_rise(self, a, b, za, zb, 0.5 * limit_mm, limit_mm);
        Some((r.rise_mm, r.at))
    }
}

#[cfg(feature = "mesh")]
trait ToSample {
    fn to_sample(&self, c: cam_offset::Contact) -> ClSample;
}

#[cfg(feature = "mesh")]
impl ToSample for cam_offset::DropCutter {
    fn to_sample(&self, c: cam_offset::Contact) -> ClSample {
        let plane = (c.kind == cam_offset::ContactKind::Facet)
            .then(|| self.triangle_normal(c.triangle))
            .flatten()
            .map(|n| (n, n.dot(c.cc)));
        ClSample {
            z: c.z_tip,
            piece: Some(c.triangle),
            cc: Some(c.cc),
            plane,
        }
    }
}

impl<F: Fn(f64, f64) -> Option<f64> + Sync> ClSurface for F {
    fn z_tip(&self, x: f64, y: f64) -> Option<f64> {
        self(x, y)
    }
}
