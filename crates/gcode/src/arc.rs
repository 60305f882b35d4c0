//! Circular and helical arcs (G2/G3) split into chords within a chordal tolerance.

use glam::DVec3;
use std::f64::consts::{PI, TAU};

/// The arc plane selected by G17, G18 or G19.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) enum Plane {
    /// G17: XY plane, arcs about +Z.
    #[default]
    Xy,
    /// G18: ZX plane, arcs about +Y (first axis Z, second X).
    Zx,
    /// G19: YZ plane, arcs about +X.
    Yz,
}

impl Plane {
    /// Indices (first in-plane axis, second in-plane axis, normal axis), right-handed.
    pub(crate) fn axes(self) -> (usize, usize, usize) {
        match self {
            Plane::Xy => (0, 1, 2),
            Plane::Zx => (2, 0, 1),
            Plane::Yz => (1, 2, 0),
        }
    }
}

/// An arc from `start` to `end` about the in-plane centre `centre` (first, second axis),
/// clockwise (G2) or counter-clockwise (G3) seen from the positive normal axis. The normal
/// axis moves linearly with the angle (helix).
#[derive(Debug, Clone, Copy)]
pub(crate) struct ArcSpec {
    pub start: DVec3,
    pub end: DVec3,
    pub centre: [f64; 2],
    pub plane: Plane,
    pub clockwise: bool,
}

impl ArcSpec {
    /// Radii from the centre to the start and to the end (in-plane, mm).
    pub(crate) fn radii(&self) -> (f64, f64) {
        let (a, b, _) = self.plane.axes();
        let r0 = (self.start[a] - self.centre[0]).hypot(self.start[b] - self.centre[1]);
        let r1 = (self.end[a] - self.centre[0]).hypot(self.end[b] - self.centre[1]);
        (r0, r1)
    }

    /// Signed sweep angle (rad): positive counter-clockwise. End = start in the plane means a
    /// full circle (±2π).
    pub(crate) fn sweep(&self) -> f64 {
        let (a, b, _) = self.plane.axes();
        let a0 = (self.start[b] - self.centre[1]).atan2(self.start[a] - self.centre[0]);
        let a1 = (self.end[b] - self.centre[1]).atan2(self.end[a] - self.centre[0]);
        let same = (self.end[a] - self.start[a]).hypot(self.end[b] - self.start[b]) <= 1e-12;
        if self.clockwise {
            let s = (a0 - a1).rem_euclid(TAU);
            -(if same || s == 0.0 { TAU } else { s })
        } else {
            let s = (a1 - a0).rem_euclid(TAU);
            if same || s == 0.0 { TAU } else { s }
        }
    }

    /// How many chords [`ArcSpec::chord_points`] returns (at least 1), as a float: huge or
    /// infinite where the radius is absurd for the tolerance.
    pub(crate) fn chord_count(&self, tolerance_mm: f64) -> f64 {
        let (r0, r1) = self.radii();
        let r = r0.max(r1);
        let dmax = if tolerance_mm >= r {
            PI
        } else {
            (2.0 * (1.0 - tolerance_mm / r).acos()).min(PI)
        };
        (self.sweep().abs() / dmax).ceil().max(1.0)
    }

    /// Chord end points (excluding `start`, ending exactly at `end`) such that no chord
    /// deviates from the arc by more than `tolerance_mm` (sagitta `r(1 - cos(δ/2))`).
    /// The radius is interpolated linearly from the start to the end radius (they agree
    /// within the reader's radius tolerance); the normal axis linearly with the angle.
    ///
    /// Callers bound [`ArcSpec::chord_count`] first: an absurd radius asks for more chords
    /// than memory holds.
    pub(crate) fn chord_points(&self, tolerance_mm: f64) -> Vec<DVec3> {
        let (a, b, n) = self.plane.axes();
        let (r0, r1) = self.radii();
        let sweep = self.sweep();
        let a0 = (self.start[b] - self.centre[1]).atan2(self.start[a] - self.centre[0]);
        let count = self.chord_count(tolerance_mm) as usize;
        let mut out = Vec::with_capacity(count);
        for i in 1..=count {
            if i == count {
                out.push(self.end);
                break;
            }
            let t = i as f64 / count as f64;
            let th = a0 + sweep * t;
            let ri = r0 + (r1 - r0) * t;
            let mut p = DVec3::ZERO;
            p[a] = self.centre[0] + ri * th.cos();
            p[b] = self.centre[1] + ri * th.sin();
            p[n] = self.start[n] + (self.end[n] - self.start[n]) * t;
            out.push(p);
        }
        out
    }
}

/// Centre of the arc of radius `|r|` from `s` to `e` (in-plane coordinates) in R form:
/// `r > 0` the short arc (≤ 180°), `r < 0` the long one. `None` when the chord is longer than
/// the diameter by more than `slack_mm`.
pub(crate) fn centre_from_radius(
    s: [f64; 2],
    e: [f64; 2],
    r: f64,
    clockwise: bool,
    slack_mm: f64,
) -> Option<[f64; 2]> {
    let (dx, dy) = (e[0] - s[0], e[1] - s[1]);
    let d = dx.hypot(dy);
    if d == 0.0 || d > 2.0 * r.abs() + slack_mm {
        return None;
    }
    let h = (r * r - d * d / 4.0).max(0.0).sqrt();
    let (ux, uy) = (dx / d, dy / d);
    let left = [-uy, ux];
    let m = [(s[0] + e[0]) / 2.0, (s[1] + e[1]) / 2.0];
    // Counter-clockwise short arc: centre on the left of start → end.
    let sign = if clockwise == (r > 0.0) { -1.0 } else { 1.0 };
    Some([m[0] + sign * h * left[0], m[1] + sign * h * left[1]])
}
