//! Milling cutters: ball, flat and toroidal (bull-nose), and their one textual spec.
//!
//! Every cutter is a solid of revolution about its axis whose lower surface is a torus:
//! a flat disk of radius `a = R - r` (the imprint paper's *major* radius) rounded by a corner
//! of radius `r` (the *minor* radius), where `R = D/2`. A ball is `r = R` (`a = 0`), a flat
//! end mill `r = 0` (`a = R`). Above the corner the cutter is a cylinder of radius `R` up to
//! the flute length. Filled, the cutter is convex.

use std::fmt;
use std::str::FromStr;

use crate::error::CutterSpecError;

/// The cutter family.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CutterKind {
    /// Ball-end mill: corner radius = D/2.
    Ball,
    /// Flat end mill: corner radius 0.
    Flat,
    /// Toroidal (bull-nose) end mill: 0 < corner radius < D/2.
    Bull,
}

/// A milling cutter, dimensions in mm. Construct with [`Cutter::ball`], [`Cutter::flat`],
/// [`Cutter::bull`] or by parsing a spec (`ball:6`, `flat:10`, `bull:10:2`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Cutter {
    kind: CutterKind,
    diameter_mm: f64,
    corner_radius_mm: f64,
    flute_length_mm: f64,
}

/// Flute length given to a cutter when none is named: this many diameters.
pub const DEFAULT_FLUTE_DIAMETERS: f64 = 3.0;

/// Smallest cutter diameter (mm) accepted: below the finest micro end mills.
pub const MIN_DIAMETER_MM: f64 = 0.01;
/// Largest cutter diameter (mm) accepted: above any face mill a finishing pass would use.
pub const MAX_DIAMETER_MM: f64 = 1000.0;
/// Smallest bull-nose corner radius (mm) accepted; below it the cutter is a flat end mill.
pub const MIN_CORNER_RADIUS_MM: f64 = 0.001;

fn bad(spec: &str, message: impl Into<String>) -> CutterSpecError {
    CutterSpecError {
        spec: spec.to_string(),
        message: message.into(),
    }
}

impl Cutter {
    /// A ball-end mill of diameter `d` mm.
    ///
    /// # Errors
    /// If `d` is not finite and positive.
    pub fn ball(d: f64) -> Result<Cutter, CutterSpecError> {
        Self::new(CutterKind::Ball, d, d / 2.0, None)
    }
    /// A flat end mill of diameter `d` mm.
    ///
    /// # Errors
    /// If `d` is not finite and positive.
    pub fn flat(d: f64) -> Result<Cutter, CutterSpecError> {
        Self::new(CutterKind::Flat, d, 0.0, None)
    }
    /// A bull-nose mill of diameter `d` mm and corner radius `r` mm, `0 < r < d/2`.
    ///
    /// # Errors
    /// If `d` or `r` is not finite and positive, or `r >= d/2`.
    pub fn bull(d: f64, r: f64) -> Result<Cutter, CutterSpecError> {
        Self::new(CutterKind::Bull, d, r, None)
    }

    /// General constructor; `flute_mm = None` gives [`DEFAULT_FLUTE_DIAMETERS`] × D.
    ///
    /// # Errors
    /// On non-finite or non-positive sizes, a diameter outside [`MIN_DIAMETER_MM`] to
    /// [`MAX_DIAMETER_MM`], a corner radius outside the family's range (a bull's at least
    /// [`MIN_CORNER_RADIUS_MM`]), or a flute length shorter than the corner radius.
    pub fn new(
        kind: CutterKind,
        diameter_mm: f64,
        corner_radius_mm: f64,
        flute_mm: Option<f64>,
    ) -> Result<Cutter, CutterSpecError> {
        let c = Cutter {
            kind,
            diameter_mm,
            corner_radius_mm,
            flute_length_mm: flute_mm.unwrap_or(DEFAULT_FLUTE_DIAMETERS * diameter_mm),
        };
        let spec = c.to_string();
        if !(diameter_mm.is_finite() && diameter_mm > 0.0) {
            return Err(bad(&spec, "diameter must be a positive number of mm"));
        }
        if !(MIN_DIAMETER_MM..=MAX_DIAMETER_MM).contains(&diameter_mm) {
            return Err(bad(
                &spec,
                format!(
                    "diameter {diameter_mm:e} mm is outside {MIN_DIAMETER_MM}–{MAX_DIAMETER_MM} mm"
                ),
            ));
        }
        match kind {
            CutterKind::Bull => {
                if !(corner_radius_mm.is_finite() && corner_radius_mm > 0.0) {
                    return Err(bad(&spec, "corner radius must be a positive number of mm"));
                }
                if corner_radius_mm < MIN_CORNER_RADIUS_MM {
                    return Err(bad(
                        &spec,
                        format!(
                            "corner radius {corner_radius_mm:e} mm is below {MIN_CORNER_RADIUS_MM} mm \
                             (use flat:{diameter_mm})"
                        ),
                    ));
                }
                if corner_radius_mm >= diameter_mm / 2.0 {
                    return Err(bad(
                        &spec,
                        format!(
                            "corner radius {corner_radius_mm} must be below D/2 = {} (use ball:{diameter_mm})",
                            diameter_mm / 2.0
                        ),
                    ));
                }
            }
            CutterKind::Ball => debug_assert!(corner_radius_mm == diameter_mm / 2.0),
            CutterKind::Flat => debug_assert!(corner_radius_mm == 0.0),
        }
        if !(c.flute_length_mm.is_finite() && c.flute_length_mm >= corner_radius_mm) {
            return Err(bad(
                &spec,
                "flute length must be a number of mm at least the corner radius",
            ));
        }
        Ok(c)
    }

    /// Returns this cutter with another flute length (mm).
    ///
    /// # Errors
    /// As [`Cutter::new`].
    pub fn with_flute_length(self, flute_mm: f64) -> Result<Cutter, CutterSpecError> {
        Self::new(
            self.kind,
            self.diameter_mm,
            self.corner_radius_mm,
            Some(flute_mm),
        )
    }

    /// The family.
    pub fn kind(&self) -> CutterKind {
        self.kind
    }
    /// Diameter D (mm).
    pub fn diameter(&self) -> f64 {
        self.diameter_mm
    }
    /// Radius R = D/2 (mm).
    pub fn radius(&self) -> f64 {
        self.diameter_mm / 2.0
    }
    /// Corner (minor) radius r (mm): R for a ball, 0 for a flat end mill.
    pub fn corner_radius(&self) -> f64 {
        self.corner_radius_mm
    }
    /// Major radius a = R - r (mm): the radius of the circle of corner centres.
    pub fn major_radius(&self) -> f64 {
        self.radius() - self.corner_radius_mm
    }
    /// Flute (cutting) length measured up from the tip (mm).
    pub fn flute_length(&self) -> f64 {
        self.flute_length_mm
    }

    /// Height (mm) of the cutter's lower surface above the tip at radial distance `d` mm from
    /// the axis, or `None` when `d > R`. Exact: 0 on the flat, `r - sqrt(r² - (d - a)²)` on
    /// the corner.
    pub fn height_at(&self, d: f64) -> Option<f64> {
        let rr = self.radius();
        if d > rr {
            return None;
        }
        let a = self.major_radius();
        if d <= a {
            return Some(0.0);
        }
        let r = self.corner_radius_mm;
        let t = d - a;
        Some(r - (r * r - t * t).max(0.0).sqrt())
    }
}

impl fmt::Display for Cutter {
    /// The spec form: `ball:6`, `flat:10`, `bull:10:2` (flute length not shown).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.kind {
            CutterKind::Ball => write!(f, "ball:{}", self.diameter_mm),
            CutterKind::Flat => write!(f, "flat:{}", self.diameter_mm),
            CutterKind::Bull => write!(f, "bull:{}:{}", self.diameter_mm, self.corner_radius_mm),
        }
    }
}

impl FromStr for Cutter {
    type Err = CutterSpecError;

    /// Parses `ball:D`, `flat:D`, `bull:D:r` (mm), each optionally followed by `,flute=L`.
    fn from_str(spec: &str) -> Result<Cutter, CutterSpecError> {
        const FORM: &str = "expected ball:D, flat:D or bull:D:r in mm, optionally ',flute=L'";
        let (main, flute) = match spec.split_once(',') {
            Some((m, rest)) => {
                let v = rest
                    .trim()
                    .strip_prefix("flute=")
                    .ok_or_else(|| bad(spec, format!("unknown option '{rest}'; {FORM}")))?;
                let l: f64 = v
                    .parse()
                    .map_err(|_| bad(spec, format!("'{v}' is not a number")))?;
                (m, Some(l))
            }
            None => (spec, None),
        };
        let parts: Vec<&str> = main.trim().split(':').collect();
        let num = |s: &str| -> Result<f64, CutterSpecError> {
            s.trim()
                .parse::<f64>()
                .map_err(|_| bad(spec, format!("'{s}' is not a number; {FORM}")))
        };
        let kind = parts[0].trim().to_ascii_lowercase();
        let c = match (kind.as_str(), parts.len()) {
            ("ball", 2) => {
                let d = num(parts[1])?;
                Cutter::new(CutterKind::Ball, d, d / 2.0, flute)
            }
            ("flat", 2) => Cutter::new(CutterKind::Flat, num(parts[1])?, 0.0, flute),
            ("bull", 3) => Cutter::new(CutterKind::Bull, num(parts[1])?, num(parts[2])?, flute),
            ("ball" | "flat" | "bull", _) => {
                Err(bad(spec, format!("wrong number of fields; {FORM}")))
            }
            _ => Err(bad(
                spec,
                format!("unknown cutter type '{}'; {FORM}", parts[0]),
            )),
        }?;
        Ok(c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_specs() {
        let b: Cutter = "bull:10:2".parse().unwrap();
        assert_eq!(
            (b.radius(), b.corner_radius(), b.major_radius()),
            (5.0, 2.0, 3.0)
        );
        assert_eq!(b.to_string(), "bull:10:2");
        let s: Cutter = "ball:6,flute=20".parse().unwrap();
        assert_eq!((s.corner_radius(), s.flute_length()), (3.0, 20.0));
        let f: Cutter = "flat:10".parse().unwrap();
        assert_eq!((f.major_radius(), f.flute_length()), (5.0, 30.0));
    }

    #[test]
    fn reject_bad_specs() {
        for s in [
            "ball",
            "ball:-1",
            "ball:nan",
            "bull:10:5",
            "bull:10:0",
            "cone:3",
            "flat:3:1",
            "ball:6,foo=1",
            "ball:inf",
            // Out of range (ball:1e300 used to panic downstream).
            "ball:1e300",
            "flat:1001",
            "ball:0.009",
            "bull:6:0.0009",
        ] {
            assert!(s.parse::<Cutter>().is_err(), "{s} accepted");
        }
        for s in ["ball:0.01", "flat:1000", "bull:6:0.001"] {
            assert!(s.parse::<Cutter>().is_ok(), "{s} rejected");
        }
    }

    #[test]
    fn profile_heights() {
        let b = Cutter::ball(6.0).unwrap();
        assert_eq!(b.height_at(0.0), Some(0.0));
        assert!((b.height_at(3.0).unwrap() - 3.0).abs() < 1e-15);
        assert_eq!(b.height_at(3.0001), None);
        let t = Cutter::bull(10.0, 2.0).unwrap();
        assert_eq!(t.height_at(3.0), Some(0.0));
        assert!((t.height_at(5.0).unwrap() - 2.0).abs() < 1e-15);
        let f = Cutter::flat(10.0).unwrap();
        assert_eq!(f.height_at(5.0), Some(0.0));
    }
}
