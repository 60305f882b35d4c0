//! Typed errors of `cam-gcode`. Each variant says how it arises.

use std::path::PathBuf;

/// A syntax or semantic error in a G-code program or an APT CL file, located at a 1-based
/// line and column (columns count characters, the first is 1).
///
/// Arises for anything the readers do not support or cannot interpret: an unknown G or M
/// code, an unsupported word letter, a malformed number, two codes of one modal group on a
/// line (e.g. two motion codes), an arc whose radius is inconsistent, an unknown APT word, a
/// zero tool axis.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}{line}:{col}: {message}", path.as_ref().map(|p| format!("{}:", p.display())).unwrap_or_default())]
pub struct GcodeError {
    /// The file, when the text came from one ([`crate::read_gcode`], [`crate::read_apt`]).
    pub path: Option<PathBuf>,
    /// 1-based line number.
    pub line: usize,
    /// 1-based column (in characters) of the offending word or character.
    pub col: usize,
    /// What is wrong.
    pub message: String,
}

impl GcodeError {
    /// An error at `line`:`col` with no path.
    pub(crate) fn new(line: usize, col: usize, message: impl Into<String>) -> GcodeError {
        GcodeError {
            path: None,
            line,
            col,
            message: message.into(),
        }
    }
}

/// Why a toolpath file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file could not be opened or read (or is not UTF-8).
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// The text is malformed; the error carries the path, line and column.
    #[error(transparent)]
    Parse(#[from] GcodeError),
}

/// Why a toolpath could not be posted as G-code. Nothing is written when one of the
/// input checks fails: the whole toolpath is validated before the first byte is written.
#[derive(Debug, thiserror::Error)]
pub enum PostError {
    /// Writing the program failed.
    #[error("cannot write G-code: {0}")]
    Io(#[from] std::io::Error),
    /// A rapid (G0) would run below the safe Z: its end is below `safe_z_mm`, or it starts
    /// below and is not a pure upward retract. Rapids are only emitted at or above safe Z.
    #[error(
        "move {move_index}{}: rapid below the safe Z ({z_mm:.4} mm < safe Z {safe_z_mm:.4} mm)",
        line.map(|l| format!(" (line {l})")).unwrap_or_default()
    )]
    RapidBelowSafeZ {
        /// 0-based index of the move in the toolpath.
        move_index: usize,
        /// The source line of the move, if it came from a file.
        line: Option<usize>,
        /// The lowest tool-tip Z of the rapid (mm).
        z_mm: f64,
        /// The job's safe Z (mm).
        safe_z_mm: f64,
    },
    /// A move's tool axis is not +Z: 3-axis posts cannot express it.
    #[error(
        "move {move_index}: tool axis {axis:?} is not +Z; the 3-axis posts need a vertical tool"
    )]
    NotThreeAxis {
        /// 0-based index of the move.
        move_index: usize,
        /// The axis found.
        axis: [f64; 3],
    },
    /// A move's tip is NaN or infinite.
    #[error("move {move_index}: tool tip is not finite")]
    NonFinite {
        /// 0-based index of the move.
        move_index: usize,
    },
    /// A job parameter is out of range (e.g. a feed that is not positive).
    #[error("invalid post job: {0}")]
    InvalidJob(String),
}
