//! Typed errors of `cam-core`. Each variant says how it arises.

use std::path::PathBuf;

/// Why a part file could not be turned into a [`crate::Mesh`].
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The file could not be opened or read.
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// The file name has no extension we read (`.obj`, `.stl`).
    #[error("{}: unknown part format '{ext}' (expected .obj or .stl)", path.display())]
    UnknownFormat {
        /// The file.
        path: PathBuf,
        /// The extension found (may be empty).
        ext: String,
    },
    /// A line (text formats) or record (binary STL) is malformed.
    #[error("{}{}: {message}", path.display(), location(*line, *triangle))]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number, for text formats, when it could be found.
        line: Option<usize>,
        /// 0-based triangle record, for binary STL.
        triangle: Option<usize>,
        /// What is wrong.
        message: String,
    },
    /// A coordinate is NaN or infinite.
    #[error("{}{}: coordinate is not a finite number ({value})", path.display(), location(*line, *triangle))]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// 1-based line number, for text formats.
        line: Option<usize>,
        /// 0-based triangle record, for binary STL.
        triangle: Option<usize>,
        /// The offending value as read.
        value: f64,
    },
    /// A coordinate lies beyond [`crate::mesh::MAX_COORD_MM`] of the origin (after scaling to
    /// mm): no machinable part is that large, and the planner's grids would not fit in memory.
    #[error(
        "{}{}: coordinate {value:e} mm is beyond ±{limit_mm:e} mm (1 km) of the origin; check the part's units and origin",
        path.display(),
        location(None, *triangle)
    )]
    OutOfRange {
        /// The file.
        path: PathBuf,
        /// 0-based triangle (in the order read).
        triangle: Option<usize>,
        /// The offending value in mm.
        value: f64,
        /// The limit (mm).
        limit_mm: f64,
    },
    /// The file holds no triangles at all.
    #[error("{}: the part has no triangles", path.display())]
    NoTriangles {
        /// The file.
        path: PathBuf,
    },
    /// Every triangle in the file is degenerate (zero area).
    #[error("{}: all {count} triangles are degenerate (zero area)", path.display())]
    AllDegenerate {
        /// The file.
        path: PathBuf,
        /// How many triangles were read.
        count: usize,
    },
}

fn location(line: Option<usize>, triangle: Option<usize>) -> String {
    match (line, triangle) {
        (Some(l), _) => format!(":{l}"),
        (None, Some(t)) => format!(": triangle {t}"),
        (None, None) => String::new(),
    }
}

impl MeshError {
    /// The 1-based line the error names, if any.
    pub fn line(&self) -> Option<usize> {
        match self {
            MeshError::Parse { line, .. } | MeshError::NonFinite { line, .. } => *line,
            _ => None,
        }
    }
}

/// Why a cutter specification such as `bull:10:2` was rejected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("invalid tool '{spec}': {message}")]
pub struct CutterSpecError {
    /// The specification as given.
    pub spec: String,
    /// What is wrong, with the expected form.
    pub message: String,
}
