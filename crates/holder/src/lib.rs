//! `cam-holder`: tool assemblies (cutter, shank, stacked-cylinder holder), an exact
//! collision check of the non-cutting parts along every move of a 3-axis toolpath, the
//! minimum stick-out, holder policies, the part's smallest concave radius and tool choice.
//!
//! Builds on the CyberCut paper's stacked-cylinder model (Eq. 3a–c) but checks the whole
//! swept volume of every straight move exactly against the part's triangles instead of
//! sample points at CL points. Conventions of `cam-core`: mm, tool tip, axis +Z.
//!
//! - [`library`] — JSON tool library (`docs/tool-library.md`), [`ToolAssembly`].
//! - [`collide`] — [`check_toolpath`] → [`CollisionReport`].
//! - [`stickout`] — [`min_stick_out`].
//! - [`avoid`](mod@avoid) — [`HolderPolicy`], [`avoid()`].
//! - [`curvature`] — [`concave_curvature`].
//! - [`select`] — [`select_tool`].

pub mod avoid;
pub mod collide;
pub mod curvature;
mod geom;
pub mod library;
pub mod select;
pub mod stickout;

pub use avoid::{AvoidConfig, AvoidSummary, HolderPolicy, Stretch, avoid};
pub use collide::{CheckConfig, Collision, CollisionReport, HolderChecker, check_toolpath};
pub use curvature::{ConcaveMin, Curvature, CurvatureConfig, SharpEdge, concave_curvature};
pub use library::{
    AssemblyDefaults, AssemblyPart, CutterEntry, Feeds, HolderCylinder, LibraryError, LibraryFile,
    PartCylinder, ToolAssembly, ToolEntry, ToolLibrary,
};
pub use select::{PathFor, Rejection, SelectConfig, SelectError, Selection, select_tool};
pub use stickout::{StickOut, min_stick_out, min_stick_out_from};
