//! Whole-part sampling: parallel section planes, each resampled at constant arc length.

use cam_core::Mesh;
use glam::DVec3;
use rayon::prelude::*;

use crate::MAX_POINTS;
use crate::error::SampleError;
use crate::frame::RasterFrame;
use crate::profile::{CRACK_GAP_MM, Profile, bridge_gaps, resample_u};
use crate::section::Sectioner;

/// How to sample a part.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleConfig {
    /// Raster angle in degrees about +Z (0: passes along +X, planes normal to Y).
    pub angle_deg: f64,
    /// Distance between consecutive section planes (mm), > 0.
    pub plane_spacing_mm: f64,
    /// Arc length between consecutive samples along a section curve (mm), > 0.
    pub arc_step_mm: f64,
}

impl Default for SampleConfig {
    /// Raster along X, 1 mm between planes, 0.5 mm arc step.
    fn default() -> Self {
        SampleConfig {
            angle_deg: 0.0,
            plane_spacing_mm: 1.0,
            arc_step_mm: 0.5,
        }
    }
}

impl SampleConfig {
    /// Checks the configuration.
    ///
    /// # Errors
    /// [`SampleError::InvalidConfig`] for a non-finite angle or a spacing/step that is not a
    /// finite number > 0.
    pub fn validate(&self) -> Result<(), SampleError> {
        if !self.angle_deg.is_finite() {
            return Err(SampleError::InvalidConfig {
                field: "angle_deg",
                value: self.angle_deg,
                reason: "must be a finite number of degrees",
            });
        }
        for (field, value) in [
            ("plane_spacing_mm", self.plane_spacing_mm),
            ("arc_step_mm", self.arc_step_mm),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(SampleError::InvalidConfig {
                    field,
                    value,
                    reason: "must be a finite number > 0",
                });
            }
        }
        Ok(())
    }
}

/// The samples of one section plane.
#[derive(Debug, Clone, PartialEq)]
pub struct Section {
    /// The plane's `v` coordinate in the raster frame (mm).
    pub v: f64,
    /// One point list per connected piece of the top surface in this plane, in increasing
    /// `u`: world positions (mm) on the top surface. Empty when the plane misses the part
    /// or only touches it.
    pub segments: Vec<Vec<DVec3>>,
}

/// The plane positions `v_min + i·spacing` for `i = 0, 1, …` while `≤ v_max` (mm), computed
/// by multiplication (no accumulated drift).
///
/// # Errors
/// [`SampleError::InvalidConfig`] for a spacing that is not finite and > 0;
/// [`SampleError::TooManyPlanes`] beyond [`MAX_POINTS`] planes.
pub fn plane_positions(v_range: (f64, f64), spacing_mm: f64) -> Result<Vec<f64>, SampleError> {
    if !(spacing_mm.is_finite() && spacing_mm > 0.0) {
        return Err(SampleError::InvalidConfig {
            field: "plane_spacing_mm",
            value: spacing_mm,
            reason: "must be a finite number > 0",
        });
    }
    let extent = v_range.1 - v_range.0;
    let planes = (extent / spacing_mm).floor() + 1.0;
    if planes.is_nan() || planes > MAX_POINTS as f64 {
        return Err(SampleError::TooManyPlanes {
            planes,
            extent_mm: extent,
            limit: MAX_POINTS,
        });
    }
    let mut out: Vec<f64> = (0..planes as usize)
        .map(|i| v_range.0 + i as f64 * spacing_mm)
        .collect();
    while out.last().is_some_and(|&v| v > v_range.1) {
        out.pop();
    }
    Ok(out)
}

/// Samples a part: section planes `v = v_min, v_min + d, …` (`d = plane_spacing_mm`) across
/// the part in the raster frame of `angle_deg`, the top profile of each plane resampled at
/// constant arc length `arc_step_mm` ([`resample_u`]), returned as world points.
///
/// One [`Section`] per plane, in increasing `v`, planes that miss the part included with no
/// segments. Gaps narrower than [`CRACK_GAP_MM`] between a plane's profiles (mesh cracks)
/// are bridged ([`bridge_gaps`]); wider ones split the plane into several segments. The `z` of a sample is the top surface's height at its `u`
/// ([`Profile::z_at`]; the top of the wall at a vertical jump). Planes are processed in
/// parallel; the result does not depend on the number of threads.
///
/// # Errors
/// [`SampleError::InvalidConfig`] for a bad configuration, [`SampleError::TooManyPlanes`] /
/// [`SampleError::TooManyPoints`] when the request would exceed [`MAX_POINTS`] planes or
/// points (checked before any point is generated).
pub fn sample_part(mesh: &Mesh, cfg: &SampleConfig) -> Result<Vec<Section>, SampleError> {
    cfg.validate()?;
    let frame = RasterFrame::new(cfg.angle_deg);
    let sectioner = Sectioner::new(mesh, frame);
    let vs = plane_positions(sectioner.v_range(), cfg.plane_spacing_mm)?;
    let profiles: Vec<Vec<Profile>> = vs
        .par_iter()
        .map(|&v| bridge_gaps(sectioner.top_profile(v), CRACK_GAP_MM))
        .collect();
    // Each profile yields at most arc_length/step + 2 samples; summed in plane order.
    let mut estimate = 0.0;
    for ps in &profiles {
        for p in ps {
            estimate += p.arc_length() / cfg.arc_step_mm + 2.0;
        }
    }
    if estimate.is_nan() || estimate > MAX_POINTS as f64 {
        return Err(SampleError::TooManyPoints {
            estimated: estimate,
            limit: MAX_POINTS,
        });
    }
    let sections = vs
        .par_iter()
        .zip(profiles.par_iter())
        .map(|(&v, ps)| Section {
            v,
            segments: ps
                .iter()
                .map(|p| {
                    resample_u(p, cfg.arc_step_mm)
                        .into_iter()
                        .map(|u| {
                            let z = p.z_at(u).unwrap_or(f64::NAN);
                            frame.point_to_xyz(u, v, z)
                        })
                        .collect()
                })
                .collect(),
        })
        .collect();
    Ok(sections)
}
