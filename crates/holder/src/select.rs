//! Tool choice: the largest library tool that reaches every concave region of the part and
//! whose assembly is collision-free at some stick-out it allows.
//!
//! # Rules
//! - **Reach** (the paper's "tool radius below the smallest radius of curvature"): a tool
//!   reaches the part when its radius `D/2` is at most the smallest *wall* concave radius and
//!   its corner radius `r` at most the smallest *floor* concave radius (see
//!   [`crate::curvature`]), each with a relative tolerance `radius_tolerance_rel` for the
//!   estimate. A ball has `r = D/2`; a flat end mill (`r = 0`) reaches any floor fillet; a
//!   bull-nose lies between. Sharp concave edges are not required (no rounded tool reaches
//!   them; a flat end mill reaches a sharp floor/wall edge exactly).
//! - **Size order**: larger diameter first, then larger corner radius, then library order.
//! - **Holder**: when a toolpath per tool is supplied, the tool must have a collision-free
//!   stick-out in `[stick_out_min, stick_out_max]`; the chosen stick-out is the nominal one
//!   if it is clear, else the minimum plus `stick_out_margin_mm` (or plus 1e-6) within the
//!   range, verified by a full check.

use cam_core::{Mesh, Toolpath};
use glam::DVec3;
use serde::Serialize;

use crate::collide::{CheckConfig, HolderChecker};
use crate::curvature::Curvature;
use crate::library::{ToolAssembly, ToolLibrary};
use crate::stickout::{StickOut, min_stick_out_from};

/// Plans a toolpath for a candidate tool (`None`: it cannot be planned with that tool).
pub type PathFor<'a> = dyn Fn(&ToolAssembly) -> Option<Toolpath> + Sync + 'a;

/// Settings of [`select_tool`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelectConfig {
    /// The holder check settings.
    pub check: CheckConfig,
    /// Relative tolerance on the curvature estimate (default 0.02 = 2 %).
    pub radius_tolerance_rel: f64,
    /// Extra stick-out (mm) above the minimum when the nominal one collides (default 1).
    pub stick_out_margin_mm: f64,
}

impl Default for SelectConfig {
    fn default() -> Self {
        SelectConfig {
            check: CheckConfig::default(),
            radius_tolerance_rel: 0.02,
            stick_out_margin_mm: 1.0,
        }
    }
}

/// Why a tool was passed over.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub enum Rejection {
    /// The caller could not plan a toolpath with it.
    NoToolpath,
    /// The cutter is too large for a concave region.
    TooLarge {
        /// The radius the region allows (mm).
        radius_needed_mm: f64,
        /// The cutter's relevant radius (D/2 or corner radius, mm).
        tool_radius_mm: f64,
        /// Where (mm).
        region: DVec3,
    },
    /// No allowed stick-out is collision-free.
    Collides {
        /// The smallest free stick-out (mm), `None` if none.
        needed_stick_out_mm: Option<f64>,
        /// The longest the tool allows (mm).
        max_stick_out_mm: f64,
        /// Where the limiting contact is (tip, mm), if known.
        region: Option<DVec3>,
    },
}

/// The chosen tool.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Selection {
    /// Id of the chosen tool.
    pub tool_id: String,
    /// The assembly at the chosen stick-out.
    pub assembly: ToolAssembly,
    /// The minimum stick-out analysis, when a toolpath was checked.
    pub stick_out: Option<StickOut>,
    /// Larger tools passed over, and why, in size order.
    pub rejected: Vec<(String, Rejection)>,
}

/// Why no tool could be chosen.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SelectError {
    /// Every tool is too large for some concave region.
    #[error("no tool reaches the region at ({:.3}, {:.3}, {:.3}): it needs a radius ≤ {radius_needed_mm:.3} mm; closest tool: {closest_tool_id}", region.x, region.y, region.z)]
    NoToolFits {
        /// The region (mm) the closest tool fails at.
        region: DVec3,
        /// The radius (mm) that region allows.
        radius_needed_mm: f64,
        /// The tool that misses by the least ratio.
        closest_tool_id: String,
    },
    /// Tools fit the curvature but each assembly collides at every stick-out it allows.
    #[error("every fitting tool's holder collides; closest tool {closest_tool_id} needs stick-out {} but allows {max_stick_out_mm:.3} mm", needed_stick_out_mm.map_or("(none)".to_string(), |v| format!("{v:.3} mm")))]
    NoAssemblyClears {
        /// The fitting tool that needs the least extra stick-out.
        closest_tool_id: String,
        /// Its smallest free stick-out (mm), if any.
        needed_stick_out_mm: Option<f64>,
        /// Its longest allowed stick-out (mm).
        max_stick_out_mm: f64,
        /// Where its limiting contact is (tip, mm), if known.
        region: Option<DVec3>,
    },
    /// The library is empty.
    #[error("the tool library is empty")]
    EmptyLibrary,
    /// Every tool that fits the curvature had no toolpath (`path_for` gave `None`).
    #[error("no toolpath could be planned with any tool that fits the part")]
    NoToolpath,
}

/// `(excess ratio, rejection)` of a tool against the curvature; ratio ≤ 1 + tol fits.
fn reach(t: &ToolAssembly, c: &Curvature) -> (f64, Option<Rejection>) {
    let mut worst = (0.0f64, None);
    let checks = [
        (c.min_wall, t.cutter.radius()),
        (c.min_floor, t.cutter.corner_radius()),
    ];
    for (m, tool_r) in checks {
        if let Some(m) = m {
            let ratio = if m.radius_mm > 0.0 {
                tool_r / m.radius_mm
            } else {
                f64::INFINITY
            };
            if ratio > worst.0 {
                worst = (
                    ratio,
                    Some(Rejection::TooLarge {
                        radius_needed_mm: m.radius_mm,
                        tool_radius_mm: tool_r,
                        region: m.region,
                    }),
                );
            }
        }
    }
    worst
}

/// Picks the largest tool of `library` that reaches every concave region of `curvature` and,
/// when `path_for` is given, whose assembly has a collision-free stick-out on the toolpath
/// `path_for(tool)` planned for it (`None`: no path could be planned with that tool, which
/// is then passed over). See the module docs for the rules.
///
/// # Errors
/// [`SelectError::NoToolFits`] naming the region, the radius it needs and the closest tool;
/// [`SelectError::NoAssemblyClears`] when all fitting tools' holders collide.
pub fn select_tool(
    library: &ToolLibrary,
    mesh: &Mesh,
    curvature: &Curvature,
    path_for: Option<&PathFor<'_>>,
    cfg: &SelectConfig,
) -> Result<Selection, SelectError> {
    if library.tools.is_empty() {
        return Err(SelectError::EmptyLibrary);
    }
    let mut order: Vec<&ToolAssembly> = library.tools.iter().collect();
    order.sort_by(|a, b| {
        b.cutter.diameter().total_cmp(&a.cutter.diameter()).then(
            b.cutter
                .corner_radius()
                .total_cmp(&a.cutter.corner_radius()),
        )
    });
    let checker = path_for.map(|_| HolderChecker::new(mesh));
    let mut rejected = Vec::new();
    let mut closest_fit: Option<(f64, &ToolAssembly, Rejection)> = None;
    let mut closest_collide: Option<(f64, &ToolAssembly, Rejection)> = None;
    for t in order {
        let (ratio, why) = reach(t, curvature);
        if ratio > 1.0 + cfg.radius_tolerance_rel {
            let why = why.expect("ratio > 1 has a reason");
            if closest_fit.as_ref().is_none_or(|(r, _, _)| ratio < *r) {
                closest_fit = Some((ratio, t, why.clone()));
            }
            rejected.push((t.id.clone(), why));
            continue;
        }
        let (Some(f), Some(ch)) = (path_for, checker.as_ref()) else {
            return Ok(Selection {
                tool_id: t.id.clone(),
                assembly: t.clone(),
                stick_out: None,
                rejected,
            });
        };
        let Some(path) = f(t) else {
            rejected.push((t.id.clone(), Rejection::NoToolpath));
            continue;
        };
        let so = min_stick_out_from(ch, t, &path, &cfg.check, t.stick_out_min_mm);
        let mut chosen = None;
        if let Some(s) = so.min_mm {
            let base = if so.limiting.is_some() {
                s
            } else {
                s.max(t.stick_out_min_mm)
            };
            let mut cands = vec![t.stick_out_mm, base + cfg.stick_out_margin_mm, base + 1e-6];
            if so.limiting.is_none() {
                cands.push(base);
            }
            for c in cands {
                if c >= s
                    && c <= t.stick_out_max_mm
                    && ch.check(&t.with_stick_out(c), &path, &cfg.check).is_clear()
                {
                    chosen = Some(c);
                    break;
                }
            }
        }
        match chosen {
            Some(c) => {
                return Ok(Selection {
                    tool_id: t.id.clone(),
                    assembly: t.with_stick_out(c),
                    stick_out: Some(so),
                    rejected,
                });
            }
            None => {
                let need = so.min_mm;
                let why = Rejection::Collides {
                    needed_stick_out_mm: need,
                    max_stick_out_mm: t.stick_out_max_mm,
                    region: so.limiting.map(|l| l.1),
                };
                let excess = need.map_or(f64::INFINITY, |n| n - t.stick_out_max_mm);
                if closest_collide.as_ref().is_none_or(|(e, _, _)| excess < *e) {
                    closest_collide = Some((excess, t, why.clone()));
                }
                rejected.push((t.id.clone(), why));
            }
        }
    }
    if let Some((
        _,
        t,
        Rejection::Collides {
            needed_stick_out_mm,
            max_stick_out_mm,
            region,
        },
    )) = closest_collide
    {
        return Err(SelectError::NoAssemblyClears {
            closest_tool_id: t.id.clone(),
            needed_stick_out_mm,
            max_stick_out_mm,
            region,
        });
    }
    match closest_fit {
        Some((
            _,
            t,
            Rejection::TooLarge {
                radius_needed_mm,
                region,
                ..
            },
        )) => Err(SelectError::NoToolFits {
            region,
            radius_needed_mm,
            closest_tool_id: t.id.clone(),
        }),
        _ => Err(SelectError::NoToolpath),
    }
}
