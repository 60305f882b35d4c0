//! Length units at the boundary of the toolkit (files and flags). Internally everything is mm.

use std::fmt;
use std::str::FromStr;

/// Length unit of an input file or an output program.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Units {
    /// Millimetres (the default and the internal unit).
    #[default]
    Mm,
    /// Inches (25.4 mm).
    Inch,
}

impl Units {
    /// Millimetres per unit: 1 for mm, 25.4 for inch.
    pub fn mm_per_unit(self) -> f64 {
        match self {
            Units::Mm => 1.0,
            Units::Inch => 25.4,
        }
    }
}

impl FromStr for Units {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "mm" | "millimetre" | "millimeter" => Ok(Units::Mm),
            "in" | "inch" | "inches" => Ok(Units::Inch),
            _ => Err(format!("unknown unit '{s}' (expected 'mm' or 'inch')")),
        }
    }
}

impl fmt::Display for Units {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Units::Mm => "mm",
            Units::Inch => "inch",
        })
    }
}
