//! Tool library: JSON tool assemblies (cutter, shank, stick-out, stacked-cylinder holder,
//! feeds and speeds), their validation, and the default assembly for a bare cutter spec.
//!
//! The schema is documented in `docs/tool-library.md`; an example is
//! `fixtures/tools/library.json`. All lengths are converted to mm on load.

use std::path::{Path, PathBuf};

use cam_core::{Cutter, CutterKind, Units};
use serde::{Deserialize, Serialize};

/// One coaxial cylinder of a holder, stacked upward from the holder face.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HolderCylinder {
    /// Diameter (mm, or the library's unit in the file).
    pub diameter: f64,
    /// Length along the tool axis (mm, or the library's unit in the file).
    pub length: f64,
}

/// The cutter as written in a library file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CutterEntry {
    /// `ball`, `flat` or `bull`.
    #[serde(rename = "type")]
    pub kind: CutterKind,
    /// Diameter D.
    pub diameter: f64,
    /// Corner radius r: required for `bull`; if given for `ball` it must be D/2, for `flat` 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub corner_radius: Option<f64>,
}

/// One tool of a library file, as written (lengths in the file's unit).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToolEntry {
    /// Unique identifier used by `--tool ID`.
    pub id: String,
    /// Tool number for `T`/`M6` words, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub number: Option<u32>,
    /// Free text.
    #[serde(default)]
    pub name: String,
    /// The cutting end.
    pub cutter: CutterEntry,
    /// Cutting (flute) length from the tip.
    pub flute_length: f64,
    /// Diameter of the shank between the flute top and the holder face.
    pub shank_diameter: f64,
    /// Nominal stick-out: tip to holder face.
    pub stick_out: f64,
    /// Shortest stick-out the tool may be clamped at (default: the flute length).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stick_out_min: Option<f64>,
    /// Longest stick-out the tool may be clamped at (default: the nominal stick-out).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stick_out_max: Option<f64>,
    /// Holder cylinders from the holder face upward (at least one).
    pub holder: Vec<HolderCylinder>,
    /// Cutting feed (unit/min).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub feed_mm_per_min: Option<f64>,
    /// Plunge feed (unit/min).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plunge_feed_mm_per_min: Option<f64>,
    /// Spindle speed (rev/min).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rpm: Option<f64>,
}

/// A library file as written.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LibraryFile {
    /// Length unit of every size in the file (`mm` or `inch`); default mm.
    #[serde(default)]
    pub units: Units,
    /// The tools.
    pub tools: Vec<ToolEntry>,
}

/// Which part of a tool assembly (the non-cutting parts are checked for collisions).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum AssemblyPart {
    /// The shank from the flute top to the holder face.
    Shank,
    /// Holder cylinder `i` (0 = the one at the holder face).
    Holder(usize),
}

impl std::fmt::Display for AssemblyPart {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            AssemblyPart::Shank => f.write_str("shank"),
            AssemblyPart::Holder(i) => write!(f, "holder cylinder {i}"),
        }
    }
}

/// A non-cutting part as a cylinder coaxial with the tool, heights measured from the tip (mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PartCylinder {
    /// Which part.
    pub part: AssemblyPart,
    /// Radius (mm).
    pub radius_mm: f64,
    /// Bottom height above the tip (mm).
    pub z_min_mm: f64,
    /// Top height above the tip (mm); `f64::INFINITY` for the topmost holder cylinder, which
    /// stands for the spindle nose as well (see [`ToolAssembly::parts`]).
    pub z_max_mm: f64,
}

/// Feeds and speeds of a tool, in mm/min and rev/min.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Feeds {
    /// Cutting feed (mm/min).
    pub feed_mm_per_min: Option<f64>,
    /// Plunge feed (mm/min).
    pub plunge_feed_mm_per_min: Option<f64>,
    /// Spindle speed (rev/min).
    pub rpm: Option<f64>,
}

/// A validated tool assembly, all lengths in mm.
///
/// Guarantees: every size finite and positive; `flute ≤ stick_out_min ≤ stick_out ≤
/// stick_out_max`; at least one holder cylinder.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ToolAssembly {
    /// Identifier (`--tool ID`); the spec (`ball:6`) for a default assembly.
    pub id: String,
    /// Tool number, if any.
    pub number: Option<u32>,
    /// Free text.
    pub name: String,
    /// The cutter, with its flute length.
    pub cutter: Cutter,
    /// Shank diameter (mm).
    pub shank_diameter_mm: f64,
    /// Stick-out: tip to holder face (mm).
    pub stick_out_mm: f64,
    /// Shortest allowed stick-out (mm).
    pub stick_out_min_mm: f64,
    /// Longest allowed stick-out (mm).
    pub stick_out_max_mm: f64,
    /// Holder cylinders from the holder face upward, in mm.
    pub holder: Vec<HolderCylinder>,
    /// Feeds and speeds.
    pub feeds: Feeds,
}

/// Defaults for an assembly built from a bare cutter spec (`--tool ball:6`).
///
/// The default approximates an ER collet chuck: a collet nut of diameter
/// `max(nut_diameters·D, nut_min_mm)` and length `nut_length_mm`, then a body of diameter
/// `max(body_diameters·D, body_min_mm)` and length `body_length_mm`. The shank diameter is D,
/// the stick-out `stick_out_diameters·D` (at least the flute length), allowed up to
/// `stick_out_max_diameters·D`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AssemblyDefaults {
    /// Stick-out in cutter diameters (default 4).
    pub stick_out_diameters: f64,
    /// Longest allowed stick-out in cutter diameters (default 8).
    pub stick_out_max_diameters: f64,
    /// Collet-nut diameter in cutter diameters (default 3).
    pub nut_diameters: f64,
    /// Smallest collet-nut diameter (mm, default 20).
    pub nut_min_mm: f64,
    /// Collet-nut length (mm, default 20).
    pub nut_length_mm: f64,
    /// Chuck-body diameter in cutter diameters (default 5).
    pub body_diameters: f64,
    /// Smallest chuck-body diameter (mm, default 40).
    pub body_min_mm: f64,
    /// Chuck-body length (mm, default 40).
    pub body_length_mm: f64,
}

impl Default for AssemblyDefaults {
    fn default() -> Self {
        AssemblyDefaults {
            stick_out_diameters: 4.0,
            stick_out_max_diameters: 8.0,
            nut_diameters: 3.0,
            nut_min_mm: 20.0,
            nut_length_mm: 20.0,
            body_diameters: 5.0,
            body_min_mm: 40.0,
            body_length_mm: 40.0,
        }
    }
}

/// Why a tool library could not be loaded or a tool is invalid.
#[derive(Debug, thiserror::Error)]
pub enum LibraryError {
    /// The file could not be read.
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// The file is not valid JSON for the schema (line and column 1-based).
    #[error("{}:{line}:{column}: {message}", path.display())]
    Json {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What serde_json says is wrong.
        message: String,
    },
    /// A tool's field has an impossible value.
    #[error("{}: tool '{tool}': {field}: {message}", path.display())]
    Invalid {
        /// The file (`<memory>` for in-memory entries).
        path: PathBuf,
        /// The tool id.
        tool: String,
        /// The field, as named in the file (`stick_out`, `holder[1].diameter`, ...).
        field: String,
        /// What is wrong.
        message: String,
    },
    /// Two tools share an id.
    #[error("{}: tool id '{tool}' appears more than once", path.display())]
    DuplicateId {
        /// The file.
        path: PathBuf,
        /// The repeated id.
        tool: String,
    },
    /// The library holds no tools.
    #[error("{}: the library has no tools", path.display())]
    Empty {
        /// The file.
        path: PathBuf,
    },
}

/// A validated tool library (mm).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ToolLibrary {
    /// The tools in file order.
    pub tools: Vec<ToolAssembly>,
}

impl ToolLibrary {
    /// Reads and validates a library file.
    ///
    /// # Errors
    /// [`LibraryError`] naming the file, and the line/column (bad JSON) or the tool id and
    /// field (bad value).
    pub fn load(path: impl AsRef<Path>) -> Result<ToolLibrary, LibraryError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| LibraryError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_json(&text, path)
    }

    /// Parses and validates library JSON; `path` only labels errors.
    ///
    /// # Errors
    /// As [`ToolLibrary::load`].
    pub fn from_json(text: &str, path: impl AsRef<Path>) -> Result<ToolLibrary, LibraryError> {
        let path = path.as_ref();
        let file: LibraryFile = serde_json::from_str(text).map_err(|e| LibraryError::Json {
            path: path.to_path_buf(),
            line: e.line(),
            column: e.column(),
            message: e.to_string(),
        })?;
        Self::from_file(&file, path)
    }

    /// Validates a parsed library; `path` only labels errors.
    ///
    /// # Errors
    /// As [`ToolLibrary::load`].
    pub fn from_file(
        file: &LibraryFile,
        path: impl AsRef<Path>,
    ) -> Result<ToolLibrary, LibraryError> {
        let path = path.as_ref();
        if file.tools.is_empty() {
            return Err(LibraryError::Empty {
                path: path.to_path_buf(),
            });
        }
        let mut tools = Vec::with_capacity(file.tools.len());
        for e in &file.tools {
            if tools.iter().any(|t: &ToolAssembly| t.id == e.id) {
                return Err(LibraryError::DuplicateId {
                    path: path.to_path_buf(),
                    tool: e.id.clone(),
                });
            }
            tools.push(ToolAssembly::from_entry(e, file.units, path)?);
        }
        Ok(ToolLibrary { tools })
    }

    /// The tool with this id, if any.
    pub fn get(&self, id: &str) -> Option<&ToolAssembly> {
        self.tools.iter().find(|t| t.id == id)
    }
}

fn positive(v: f64) -> bool {
    v.is_finite() && v > 0.0
}

impl ToolAssembly {
    /// Validates one library entry, scaling `units` to mm.
    ///
    /// # Errors
    /// [`LibraryError::Invalid`] naming `e.id` and the field.
    pub fn from_entry(
        e: &ToolEntry,
        units: Units,
        path: &Path,
    ) -> Result<ToolAssembly, LibraryError> {
        let k = units.mm_per_unit();
        let err = |field: &str, message: String| LibraryError::Invalid {
            path: path.to_path_buf(),
            tool: e.id.clone(),
            field: field.to_string(),
            message,
        };
        let need_pos = |field: &str, v: f64| -> Result<f64, LibraryError> {
            if positive(v) {
                Ok(v * k)
            } else {
                Err(err(field, format!("must be a positive number, got {v}")))
            }
        };
        if e.id.trim().is_empty() {
            return Err(err("id", "must not be empty".into()));
        }
        let d = need_pos("cutter.diameter", e.cutter.diameter)?;
        let flute = need_pos("flute_length", e.flute_length)?;
        let r = match (e.cutter.kind, e.cutter.corner_radius) {
            (CutterKind::Bull, None) => {
                return Err(err(
                    "cutter.corner_radius",
                    "required for a bull-nose cutter".into(),
                ));
            }
            (CutterKind::Bull, Some(r)) => need_pos("cutter.corner_radius", r)?,
            (CutterKind::Ball, Some(r)) if (r * k - d / 2.0).abs() > 1e-9 * d => {
                return Err(err(
                    "cutter.corner_radius",
                    format!(
                        "a ball cutter's corner radius is D/2 = {}, got {r}",
                        e.cutter.diameter / 2.0
                    ),
                ));
            }
            (CutterKind::Flat, Some(r)) if r != 0.0 => {
                return Err(err(
                    "cutter.corner_radius",
                    format!("a flat cutter's corner radius is 0, got {r}"),
                ));
            }
            (CutterKind::Ball, _) => d / 2.0,
            (CutterKind::Flat, _) => 0.0,
        };
        let cutter =
            Cutter::new(e.cutter.kind, d, r, Some(flute)).map_err(|c| err("cutter", c.message))?;
        let shank = need_pos("shank_diameter", e.shank_diameter)?;
        let so = need_pos("stick_out", e.stick_out)?;
        if so < flute {
            return Err(err(
                "stick_out",
                format!(
                    "stick-out {} is shorter than the flute length {}",
                    e.stick_out, e.flute_length
                ),
            ));
        }
        let so_min = match e.stick_out_min {
            Some(v) => need_pos("stick_out_min", v)?,
            None => flute,
        };
        let so_max = match e.stick_out_max {
            Some(v) => need_pos("stick_out_max", v)?,
            None => so,
        };
        if so_min < flute {
            return Err(err(
                "stick_out_min",
                format!(
                    "{} is shorter than the flute length {}",
                    so_min / k,
                    e.flute_length
                ),
            ));
        }
        if !(so_min <= so && so <= so_max) {
            return Err(err(
                "stick_out",
                format!(
                    "need stick_out_min ≤ stick_out ≤ stick_out_max, got {} ≤ {} ≤ {}",
                    so_min / k,
                    e.stick_out,
                    so_max / k
                ),
            ));
        }
        if e.holder.is_empty() {
            return Err(err("holder", "needs at least one cylinder".into()));
        }
        let mut holder = Vec::with_capacity(e.holder.len());
        for (i, c) in e.holder.iter().enumerate() {
            holder.push(HolderCylinder {
                diameter: need_pos(&format!("holder[{i}].diameter"), c.diameter)?,
                length: need_pos(&format!("holder[{i}].length"), c.length)?,
            });
        }
        let opt_pos =
            |field: &str, v: Option<f64>, scale: f64| -> Result<Option<f64>, LibraryError> {
                match v {
                    None => Ok(None),
                    Some(x) if positive(x) => Ok(Some(x * scale)),
                    Some(x) => Err(err(field, format!("must be a positive number, got {x}"))),
                }
            };
        let feeds = Feeds {
            feed_mm_per_min: opt_pos("feed_mm_per_min", e.feed_mm_per_min, k)?,
            plunge_feed_mm_per_min: opt_pos("plunge_feed_mm_per_min", e.plunge_feed_mm_per_min, k)?,
            rpm: opt_pos("rpm", e.rpm, 1.0)?,
        };
        Ok(ToolAssembly {
            id: e.id.clone(),
            number: e.number,
            name: e.name.clone(),
            cutter,
            shank_diameter_mm: shank,
            stick_out_mm: so,
            stick_out_min_mm: so_min,
            stick_out_max_mm: so_max,
            holder,
            feeds,
        })
    }

    /// The default assembly for a bare cutter (`--tool ball:6`), see [`AssemblyDefaults`].
    /// For ball:6 with the defaults: shank Ø6, stick-out 24 (18 … 48), holder Ø20×20 then
    /// Ø40×40.
    pub fn from_spec(cutter: Cutter, defaults: &AssemblyDefaults) -> ToolAssembly {
        let d = cutter.diameter();
        let flute = cutter.flute_length();
        let so = (defaults.stick_out_diameters * d).max(flute);
        let so_max = (defaults.stick_out_max_diameters * d).max(so);
        ToolAssembly {
            id: cutter.to_string(),
            number: None,
            name: format!("{cutter} (default ER-collet assembly)"),
            cutter,
            shank_diameter_mm: d,
            stick_out_mm: so,
            stick_out_min_mm: flute,
            stick_out_max_mm: so_max,
            holder: vec![
                HolderCylinder {
                    diameter: (defaults.nut_diameters * d).max(defaults.nut_min_mm),
                    length: defaults.nut_length_mm,
                },
                HolderCylinder {
                    diameter: (defaults.body_diameters * d).max(defaults.body_min_mm),
                    length: defaults.body_length_mm,
                },
            ],
            feeds: Feeds::default(),
        }
    }

    /// This assembly clamped at another stick-out (mm); the allowed range is unchanged.
    pub fn with_stick_out(&self, stick_out_mm: f64) -> ToolAssembly {
        ToolAssembly {
            stick_out_mm,
            ..self.clone()
        }
    }

    /// The non-cutting parts as coaxial cylinders, heights from the tip (mm), bottom to top:
    /// the shank `[flute, stick_out]` (omitted when the stick-out equals the flute length)
    /// and holder cylinder *i* `[stick_out + Σ_{k<i} L_k, stick_out + Σ_{k≤i} L_k]`.
    ///
    /// The topmost holder cylinder is extended upward without end: it stands for the spindle
    /// nose above the holder, so nothing can pass over the holder.
    pub fn parts(&self) -> Vec<PartCylinder> {
        let mut v = Vec::with_capacity(self.holder.len() + 1);
        let flute = self.cutter.flute_length();
        if self.stick_out_mm > flute {
            v.push(PartCylinder {
                part: AssemblyPart::Shank,
                radius_mm: self.shank_diameter_mm / 2.0,
                z_min_mm: flute,
                z_max_mm: self.stick_out_mm,
            });
        }
        let mut z = self.stick_out_mm;
        let n = self.holder.len();
        for (i, c) in self.holder.iter().enumerate() {
            let top = if i + 1 == n {
                f64::INFINITY
            } else {
                z + c.length
            };
            v.push(PartCylinder {
                part: AssemblyPart::Holder(i),
                radius_mm: c.diameter / 2.0,
                z_min_mm: z,
                z_max_mm: top,
            });
            z += c.length;
        }
        v
    }
}
