//! `cam-gcode`: toolpath input and output.
//!
//! - [`parse_gcode`] / [`read_gcode`]: 3-axis G-code (RS274/NGC subset) → [`Toolpath`] in mm,
//!   tool tip, axis +Z, arcs split into chords within a chordal tolerance.
//! - [`parse_apt`] / [`read_apt`] and [`write_apt`]: APT-style CL data with tool axis
//!   (`GOTO/x,y,z,i,j,k`) for 5-axis paths.
//! - [`post()`]: posts a 3-axis toolpath for LinuxCNC, Grbl or Fanuc, refusing rapids below
//!   the safe Z.
//! - [`rs274`]: test support that runs LinuxCNC's interpreter on a program and reads its
//!   canonical motions.
//!
//! Every reader error names the 1-based line and column ([`GcodeError`]). The library never
//! prints and never panics on input.
//!
//! [`Toolpath`]: cam_core::Toolpath

mod apt;
mod arc;
mod error;
mod format;
mod post;
mod reader;
pub mod rs274;
mod words;

pub use apt::{AptHeader, parse_apt, read_apt, write_apt};
pub use error::{GcodeError, PostError, ReadError};
pub use post::{Post, PostJob, post, post_to_string, rounding_mm};
pub use reader::{ReadConfig, parse_gcode, read_gcode};
