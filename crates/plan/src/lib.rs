//! `cam-plan`: 3-axis finishing toolpaths on the exact CL (drop-cutter) surface with a
//! guaranteed feed-forward tolerance and a scallop-limited side step.
//!
//! The planner works on any [`ClSurface`] (the exact tool-tip height of the cutter resting on
//! the part); [`cam_offset::DropCutter`] is one. Passes are lines `v = const` of a raster frame
//! rotated by `angle_deg`; along each pass the exact CL profile is marched (the seed's
//! Algorithm 1 started from its Eq. 1, then every move checked exactly); the side step
//! (Eq. 2 re-derived, times `cos θ`) is the minimum over the pass of the scallop-limited
//! interval. The maths is in `docs/plan-math.md`.
//!
//! # Guarantees (measured, not estimated)
//! - **Feed-forward.** Each pass's exact CL profile (samples merged with a grid of spacing
//!   `c`) is refined until every neighbour pair passes a midpoint test (exact z at the
//!   midpoint within η/2 of the chord, η = 0.2·τ) and a crease test (length × slope change
//!   to the neighbouring pairs ≤ η); a move is accepted only if it is within `τ − η` of the
//!   exact CL z (vertical distance, gouge and excess alike) at every profile point and tested
//!   midpoint it spans. Between those points the CL surface then differs from the profile
//!   polyline by about η at most when each pair holds one crease or slowly varying curvature,
//!   so every move is within τ. This is a sampling argument, not a proof for arbitrary
//!   surfaces. Pairs that cannot be resolved above 1e-5 mm (vertical jumps or tangents of the
//!   CL surface) are counted in [`Plan::unresolved_joins`]. The tests check every move
//!   densely and independently (0.01 mm or 400 samples per move).
//! - **Side step.** The scallop forms in the plane perpendicular to the motion along the pass,
//!   where the cutter shows its outline seen along that motion ([`sidestep::Silhouette`]:
//!   its axial profile only on level motion). The interval after each pass is the minimum,
//!   over the pass's CL points and profile points 1 mm apart, of the model's
//!   scallop-limited interval (the outline's exact step on a straight section, re-derived
//!   Eq. 2 with the resulting effective radius and the CL section's curvature, and the slope
//!   of the chord to the next pass: ε·cos θ). It is then verified in CL space at points every
//!   2R along the pass (the cusp between the two passes against the best surface the cutter
//!   can leave, computed from the CL surface alone in that plane) and shrunk until that
//!   verification reports ≤ h(1 + 1e-3). The model is exact on planes (any slope, any
//!   cutter), for a ball on cylinders and for a bull on its corner; [`measure_scallop`]
//!   measures what is left against the part itself (3-D distance).
//! - **No plunges into the void.** Passes end where the cutter stops touching the part
//!   (located to 1e-5 mm) or at the boundary box; links follow the surface only when checked.
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

pub use config::{Direction, Milling, PlanConfig, PlanError};
pub use frame::Raster;
#[cfg(feature = "mesh")]
pub use part::{SectionSampler, plan_part};
pub use plan::{
    PassSampler, Plan, Progress, STEEP_FLOOR_FRACTION, UniformSampler, VERIFY_SLACK, plan,
};
pub use scallop::{ScallopProbe, ScallopReport, measure_scallop};

/// The exact tool-tip height of the cutter resting on the part: the CL surface.
pub trait ClSurface: Sync {
    /// Tool-tip z (mm) of the cutter (axis +Z) resting on the part at `(x, y)` (mm), `None`
    /// where the cutter touches nothing.
    fn z_tip(&self, x: f64, y: f64) -> Option<f64>;
}

#[cfg(feature = "mesh")]
impl ClSurface for cam_offset::DropCutter {
    fn z_tip(&self, x: f64, y: f64) -> Option<f64> {
        self.drop(x, y)
    }
}

impl<F: Fn(f64, f64) -> Option<f64> + Sync> ClSurface for F {
    fn z_tip(&self, x: f64, y: f64) -> Option<f64> {
        self(x, y)
    }
}
