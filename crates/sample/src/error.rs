//! Typed errors of `cam-sample`.

/// Why a sampling request cannot be carried out. Each variant says how it arises.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SampleError {
    /// A configuration value is NaN, infinite, zero or negative where a positive finite
    /// number is required (`plane_spacing_mm`, `arc_step_mm`), or a non-finite angle.
    #[error("invalid sampling configuration: {field} = {value}: {reason}")]
    InvalidConfig {
        /// The field name, e.g. `arc_step_mm`.
        field: &'static str,
        /// The value given.
        value: f64,
        /// What is required.
        reason: &'static str,
    },
    /// The part's extent over the plane spacing gives more section planes than the limit.
    #[error(
        "too many section planes: {planes} planes for the part's {extent_mm} mm extent across \
         the passes (limit {limit}); increase plane_spacing_mm"
    )]
    TooManyPlanes {
        /// Planes the request would need.
        planes: f64,
        /// Extent of the part across the passes (mm).
        extent_mm: f64,
        /// The limit ([`crate::MAX_POINTS`]).
        limit: usize,
    },
    /// The total arc length of the sections over the arc step gives more sample points than
    /// the limit.
    #[error(
        "too many sample points: about {estimated:.0} points (limit {limit}); increase \
         arc_step_mm or plane_spacing_mm"
    )]
    TooManyPoints {
        /// Upper estimate of the number of points the request would produce.
        estimated: f64,
        /// The limit ([`crate::MAX_POINTS`]).
        limit: usize,
    },
}
