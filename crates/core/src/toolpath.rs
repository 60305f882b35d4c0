//! Toolpaths: ordered tool poses joined by straight moves, 3- or 5-axis.
//!
//! A [`Pose`] is the **tool tip** (mm) and the unit tool axis (tip → spindle). A
//! [`Toolpath`] is a sequence of [`Move`]s; move *i* goes in a straight line (tip and axis
//! linearly interpolated) from the pose of move *i-1* to its own pose.

use glam::DVec3;

/// Tool tip position (mm) and unit tool axis pointing from the tip to the spindle.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Pose {
    /// Tool tip: the lowest point of the cutter on its axis (mm).
    pub tip: DVec3,
    /// Unit tool axis, tip → spindle (+Z for 3-axis work).
    pub axis: DVec3,
}

impl Pose {
    /// A 3-axis pose: tool tip at `tip` (mm), axis +Z.
    pub fn vertical(tip: DVec3) -> Pose {
        Pose {
            tip,
            axis: DVec3::Z,
        }
    }
}

/// How the machine gets to a move's pose.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum MoveKind {
    /// Positioning at rapid rate (G0); must not touch the part.
    Rapid,
    /// Cutting feed (G1 at the cutting feed).
    Cut,
    /// Descent into material or onto the surface (G1 at the plunge feed).
    Plunge,
    /// Leaving the surface at cutting feed before a rapid.
    Retract,
}

/// One straight move to `pose`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Move {
    /// Rapid, cut, plunge or retract.
    pub kind: MoveKind,
    /// Where the move ends.
    pub pose: Pose,
    /// Programmed feed (mm/min) for feed moves, if known.
    pub feed_mm_per_min: Option<f64>,
    /// The source line (1-based) this move came from, when read from a file.
    pub line: Option<usize>,
    /// Index of the finishing pass this move belongs to, if any.
    pub pass: Option<usize>,
}

/// A whole toolpath: moves in order. The first move's start is its own pose.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Toolpath {
    /// The moves in machine order.
    pub moves: Vec<Move>,
}

impl Toolpath {
    /// Total length (mm) of the tip path over moves whose kind satisfies `keep`.
    pub fn length_where(&self, keep: impl Fn(MoveKind) -> bool) -> f64 {
        self.moves
            .windows(2)
            .filter(|w| keep(w[1].kind))
            .map(|w| w[1].pose.tip.distance(w[0].pose.tip))
            .sum::<f64>()
            + 0.0 // an empty sum of f64 is -0.0
    }
}
