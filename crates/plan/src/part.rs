//! Planning a mesh: constant-arc-length samples from `cam-sample`, the exact drop-cutter CL
//! surface from `cam-offset`, and the planner.

use cam_core::Mesh;
use cam_offset::DropCutter;
use cam_sample::{RasterFrame, Sectioner, resample_u};

use crate::{PassSampler, Plan, PlanConfig, PlanError, Progress, plan};

/// Samples passes from the part's sections: the pass at `v` spans the part's whole `u` extent
/// widened by the cutter radius (the drop-cutter decides where the cutter touches), with the
/// constant-arc-length samples of the top profile at `v` added, so steep stretches of the
/// part get denser profile points.
pub struct SectionSampler {
    sectioner: Sectioner,
    step_mm: f64,
    reach_mm: f64,
}

impl SectionSampler {
    /// Sections `mesh` in the raster frame of `angle_deg`; samples every `step_mm` of arc
    /// length; passes reach `reach_mm` beyond the part's `u` extent (the cutter radius).
    pub fn new(mesh: &Mesh, angle_deg: f64, step_mm: f64, reach_mm: f64) -> SectionSampler {
        SectionSampler {
            sectioner: Sectioner::new(mesh, RasterFrame::new(angle_deg)),
            step_mm,
            reach_mm,
        }
    }
}

impl PassSampler for SectionSampler {
    fn v_range(&self) -> Option<(f64, f64)> {
        let (a, b) = self.sectioner.v_range();
        (a <= b).then_some((a, b))
    }
    fn u_samples(&self, v: f64) -> Vec<f64> {
        let (a, b) = self.sectioner.u_range();
        if a.is_nan() || b.is_nan() || a > b {
            return Vec::new();
        }
        let mut us = vec![a - self.reach_mm];
        for prof in self.sectioner.top_profile(v) {
            us.extend(resample_u(&prof, self.step_mm));
        }
        us.push(b + self.reach_mm);
        us.retain(|u| u.is_finite());
        us.sort_by(f64::total_cmp);
        us
    }
}

/// Plans finishing passes over a mesh: sections and constant-arc-length samples at
/// [`PlanConfig::section_step_mm`], the exact drop-cutter CL surface, then [`plan`].
///
/// # Errors
/// As [`plan`].
pub fn plan_part(
    mesh: &Mesh,
    cfg: &PlanConfig,
    progress: Option<Progress<'_>>,
) -> Result<Plan, PlanError> {
    let step = cfg.section_step_mm()?;
    let dc = DropCutter::new(mesh, cfg.cutter);
    let sampler = SectionSampler::new(mesh, cfg.angle_deg, step, cfg.cutter.radius());
    plan(&dc, &sampler, cfg, progress)
}
