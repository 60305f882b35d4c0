//! Holder policies and the `avoid` rewrite: lift over colliding stretches of a toolpath.

use std::collections::BTreeSet;

use cam_core::{Move, MoveKind, Pose, Toolpath};
use glam::DVec3;
use serde::Serialize;

use crate::collide::Collision;

/// What to do when the holder or shank collides (the CLI's `--holder fail|report|avoid`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub enum HolderPolicy {
    /// Refuse the toolpath: report and write no G-code (the default).
    #[default]
    Fail,
    /// Keep the toolpath and report the collisions.
    Report,
    /// Lift over the colliding stretches with [`avoid`] and report what was left unmachined.
    Avoid,
}

impl std::str::FromStr for HolderPolicy {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "fail" => Ok(HolderPolicy::Fail),
            "report" => Ok(HolderPolicy::Report),
            "avoid" => Ok(HolderPolicy::Avoid),
            _ => Err(format!(
                "unknown holder policy '{s}' (expected fail, report or avoid)"
            )),
        }
    }
}

/// Settings of [`avoid`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AvoidConfig {
    /// Height (mm) of the tip for the rapid over a dropped stretch; must clear the part.
    pub safe_z_mm: f64,
    /// Path spacing (mm) used to estimate the unmachined area as dropped cut length × spacing.
    pub stepover_mm: f64,
}

/// One dropped stretch: moves `first_move..=last_move` of the input replaced by a lift.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Stretch {
    /// First replaced move (input index).
    pub first_move: usize,
    /// Last replaced move (input index).
    pub last_move: usize,
    /// Cutting length (mm, `Cut` and `Plunge` moves) dropped in this stretch.
    pub cut_length_mm: f64,
}

/// What [`avoid`] dropped.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct AvoidSummary {
    /// Total cutting length (mm) no longer machined.
    pub removed_cut_length_mm: f64,
    /// Estimate of the surface left unmachined (mm²): removed length × stepover.
    pub unmachined_area_mm2: f64,
    /// The stretches, in path order.
    pub stretches: Vec<Stretch>,
}

fn lift(kind: MoveKind, tip: DVec3, like: &Move) -> Move {
    Move {
        kind,
        pose: Pose::vertical(tip),
        feed_mm_per_min: None,
        line: None,
        pass: like.pass,
    }
}

/// Replaces every maximal run of consecutive colliding moves `i..=j` by: retract from the
/// tip at pose `i-1` straight up to `safe_z_mm`, rapid to above pose `j`, plunge to pose `j`.
///
/// Guarantee (when the collisions come from a check of the same path and assembly): the
/// poses lifted from and plunged to are collision-free, because the check includes both end
/// points of every move, so a colliding end pose would have put the neighbouring move into
/// the run. The vertical lifts themselves are clear on parts without overhangs; re-check
/// the result to be sure. A run at the start of the path begins with a rapid at safe Z, a
/// run at the end ends with the retract.
pub fn avoid(
    toolpath: &Toolpath,
    collisions: &[Collision],
    cfg: &AvoidConfig,
) -> (Toolpath, AvoidSummary) {
    let bad: BTreeSet<usize> = collisions.iter().map(|c| c.move_index).collect();
    let mv = &toolpath.moves;
    let mut out = Vec::with_capacity(mv.len() + 3 * bad.len());
    let mut sum = AvoidSummary::default();
    let mut i = 0;
    while i < mv.len() {
        if !bad.contains(&i) {
            out.push(mv[i]);
            i += 1;
            continue;
        }
        let mut j = i;
        while j + 1 < mv.len() && bad.contains(&(j + 1)) {
            j += 1;
        }
        let mut len = 0.0;
        for k in i..=j {
            if matches!(mv[k].kind, MoveKind::Cut | MoveKind::Plunge) && k > 0 {
                len += mv[k].pose.tip.distance(mv[k - 1].pose.tip);
            }
        }
        let up = |t: DVec3| DVec3::new(t.x, t.y, cfg.safe_z_mm.max(t.z));
        if i > 0 {
            out.push(lift(MoveKind::Retract, up(mv[i - 1].pose.tip), &mv[i]));
        }
        if j + 1 < mv.len() || i == 0 {
            out.push(lift(MoveKind::Rapid, up(mv[j].pose.tip), &mv[j]));
            let mut land = mv[j];
            land.kind = MoveKind::Plunge;
            if j + 1 < mv.len() {
                out.push(land);
            }
        }
        sum.removed_cut_length_mm += len;
        sum.stretches.push(Stretch {
            first_move: i,
            last_move: j,
            cut_length_mm: len,
        });
        i = j + 1;
    }
    sum.unmachined_area_mm2 = sum.removed_cut_length_mm * cfg.stepover_mm;
    (Toolpath { moves: out }, sum)
}
