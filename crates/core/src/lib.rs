//! `cam-core`: the shared vocabulary of the cam toolkit.
//!
//! # Conventions (hold in every crate)
//! - Lengths are **millimetres** in `f64`; positions are [`glam::DVec3`] in mm, Z up.
//!   Inch input is converted once at the boundary ([`Units`]).
//! - A cutter-location (CL) point is the **tool tip**: the lowest point of the cutter on its
//!   axis, the point G-code programs. A name says `centre` where the cutter centre is meant
//!   (for a ball or bull-nose cutter the centre of the corner circle lies `corner_radius` above
//!   the tip).
//! - The tool axis points from the tip towards the spindle (+Z for 3-axis work).
//! - Libraries return typed errors; only the CLI prints.

pub mod cutter;
pub mod error;
pub mod io;
pub mod mesh;
pub mod testing;
pub mod toolpath;
pub mod units;

pub use cutter::{Cutter, CutterKind};
pub use error::{CutterSpecError, MeshError};
pub use mesh::{Aabb, LoadStats, Mesh, Triangle};
pub use toolpath::{Move, MoveKind, Pose, Toolpath};
pub use units::Units;

/// Re-export of the vector type used for every position and direction.
pub use glam::DVec3;
