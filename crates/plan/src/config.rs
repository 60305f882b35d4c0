//! Planner configuration, options and errors.

use cam_core::{Cutter, CutterKind};

/// Order of passes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Direction {
    /// Alternate the feed direction from pass to pass, linking neighbouring pass ends.
    ZigZag,
    /// Every pass in the same direction; a retract, rapid and plunge between passes.
    OneWay,
}

/// Climb or conventional milling, for a clockwise (M3) spindle seen from above.
///
/// Passes are ordered by increasing `v` (the raster frame's side-step axis), so the material
/// still to be cut lies on the `+v` side of the current pass. `+v` is to the left of a feed
/// in `+u`; with a clockwise spindle the cutting edge on the tool's left moves with the feed,
/// so a `+u` pass is **climb** and a `−u` pass **conventional**. One-way passes all go the
/// chosen way; zig-zag starts with it (and alternates, so only half the passes can honour it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Milling {
    /// Passes along `+u`.
    Climb,
    /// Passes along `−u`.
    Conventional,
}

/// Everything the planner needs besides the CL surface. Lengths in mm, angles in degrees.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PlanConfig {
    /// The cutter (ball, flat or bull; axis +Z).
    pub cutter: Cutter,
    /// Feed-forward tolerance τ (mm): largest allowed vertical distance between a cut move
    /// and the exact CL surface, gouge or excess.
    pub tolerance_mm: f64,
    /// Largest scallop (cusp) height h (mm) left between neighbouring passes, measured normal
    /// to the surface in the section across the passes.
    pub scallop_mm: f64,
    /// Raster angle (degrees): passes run along `u = (cos a, sin a)`.
    pub angle_deg: f64,
    /// Safe height (mm) of the tool tip for rapids; `None` = 5 mm above the highest CL point.
    pub safe_z_mm: Option<f64>,
    /// Zig-zag or one-way.
    pub direction: Direction,
    /// Climb or conventional (see [`Milling`]).
    pub milling: Milling,
    /// Stock/boundary box `(xmin, xmax, ymin, ymax)` (mm) the tool tip must stay inside.
    pub boundary: Option<(f64, f64, f64, f64)>,
    /// Largest spacing (mm) of profile samples on the sampled path (flat end mills, CL
    /// surfaces without certificates; see `docs/plan-math.md` §1); `None` = half the cutter
    /// radius. At most the cutter diameter. Ball and bull cutters sample at the lemma's
    /// spacing instead.
    pub check_spacing_mm: Option<f64>,
    /// Longest cut move (mm); `None` = unlimited.
    pub max_step_mm: Option<f64>,
}

impl Default for PlanConfig {
    /// ball:6, τ = 0.01 mm, h = 0.01 mm, angle 0°, zig-zag climb, automatic safe Z.
    fn default() -> Self {
        PlanConfig {
            cutter: Cutter::ball(6.0).expect("valid cutter"),
            tolerance_mm: 0.01,
            scallop_mm: 0.01,
            angle_deg: 0.0,
            safe_z_mm: None,
            direction: Direction::ZigZag,
            milling: Milling::Climb,
            boundary: None,
            check_spacing_mm: None,
            max_step_mm: None,
        }
    }
}

/// Input the planner cannot work with.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlanError {
    /// τ not a positive finite number.
    #[error("tolerance {0} mm must be a positive number of mm")]
    Tolerance(f64),
    /// h not a positive finite number.
    #[error("scallop height {0} mm must be a positive number of mm")]
    Scallop(f64),
    /// h too large for the cutter: no side step leaves a cusp that low... or high.
    #[error("scallop height {h} mm must be below the cutter's corner radius {r} mm for {cutter}")]
    ScallopTooLarge {
        /// Requested scallop (mm).
        h: f64,
        /// Corner radius limiting it (mm).
        r: f64,
        /// Cutter spec.
        cutter: String,
    },
    /// Angle not finite.
    #[error("raster angle {0} degrees is not a finite number")]
    Angle(f64),
    /// Safe Z not finite, beyond 1 km ([`cam_core::mesh::MAX_COORD_MM`]), or below the top
    /// of the toolpath.
    #[error("safe Z {safe_z} mm must be a number above the highest CL point {top} mm")]
    SafeZ {
        /// Requested safe Z (mm).
        safe_z: f64,
        /// Highest tool-tip z planned (mm).
        top: f64,
    },
    /// Boundary box empty or not finite.
    #[error("boundary box {0:?} must be finite with xmin < xmax and ymin < ymax")]
    Boundary((f64, f64, f64, f64)),
    /// Check spacing not positive, or so coarse that no tolerance is left for the chords.
    #[error("check spacing {0} mm must be positive and at most the cutter diameter")]
    CheckSpacing(f64),
    /// Maximum step not positive.
    #[error("maximum step {0} mm must be a positive number of mm")]
    MaxStep(f64),
    /// The cutter touches the part nowhere in the planned region.
    #[error("the cutter touches the part nowhere inside the planned region")]
    NothingToCut,
}

impl PlanConfig {
    /// The spacing (mm) of the first samples along a pass: constant arc length on the part's
    /// sections (the seed's discretisation) and a grid of the same spacing. Refinement only
    /// ever adds samples, so starting coarse costs nothing where a profile needs detail and
    /// saves drops where it is planar: the cutter radius, or four times the finest sample
    /// spacing if that is larger.
    ///
    /// # Errors
    /// As [`PlanConfig::validate`].
    pub fn section_step_mm(&self) -> Result<f64, PlanError> {
        let (c, _) = self.validate()?;
        let chk = crate::feed::Check::new(
            self.tolerance_mm,
            self.cutter.corner_radius(),
            self.cutter.radius(),
            c,
            f64::INFINITY,
        );
        Ok(self.cutter.radius().max(4.0 * chk.spacing))
    }

    /// Checks every value; returns the check spacing (mm) and the acceptance threshold (mm)
    /// for deviations at profile points, `0.8·τ`.
    ///
    /// # Errors
    /// On any value named in [`PlanError`].
    pub fn validate(&self) -> Result<(f64, f64), PlanError> {
        let tau = self.tolerance_mm;
        if !(tau.is_finite() && tau > 0.0) {
            return Err(PlanError::Tolerance(tau));
        }
        let h = self.scallop_mm;
        if !(h.is_finite() && h > 0.0) {
            return Err(PlanError::Scallop(h));
        }
        let limit = match self.cutter.kind() {
            CutterKind::Flat => self.cutter.radius(),
            _ => self.cutter.corner_radius(),
        };
        if h >= limit {
            return Err(PlanError::ScallopTooLarge {
                h,
                r: limit,
                cutter: self.cutter.to_string(),
            });
        }
        if !self.angle_deg.is_finite() {
            return Err(PlanError::Angle(self.angle_deg));
        }
        if let Some(z) = self.safe_z_mm
            && (!z.is_finite() || z.abs() > cam_core::mesh::MAX_COORD_MM)
        {
            return Err(PlanError::SafeZ {
                safe_z: z,
                top: f64::NAN,
            });
        }
        if let Some(b) = self.boundary
            && !(b.0.is_finite()
                && b.1.is_finite()
                && b.2.is_finite()
                && b.3.is_finite()
                && b.0 < b.1
                && b.2 < b.3)
        {
            return Err(PlanError::Boundary(b));
        }
        if let Some(m) = self.max_step_mm
            && !(m.is_finite() && m > 0.0)
        {
            return Err(PlanError::MaxStep(m));
        }
        let rr = self.cutter.radius();
        let c = self.check_spacing_mm.unwrap_or(0.5 * rr);
        let accept = (1.0 - crate::feed::LINEARITY_FRACTION) * tau;
        if !(c.is_finite() && c > 0.0 && c <= 2.0 * rr) {
            return Err(PlanError::CheckSpacing(c));
        }
        Ok((c, accept))
    }
}
