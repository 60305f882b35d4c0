//! `cam-offset`: the exact inverse tool offset (drop-cutter) CL surface.
//!
//! For an XY position, [`DropCutter::drop`] gives the lowest **tool-tip** z (mm) at which a
//! cutter with axis +Z touches the part without penetrating any triangle: the maximum over
//! all triangles of the vertex, edge and facet contact heights, each in closed form (the
//! torus–edge contact by a safeguarded Newton iteration converged to < 1e-12 mm).

mod certify;
mod chord;
mod contact;
mod grid;
mod index;

pub use certify::{COPLANAR_MM, PlaneCertificate};
pub use chord::ChordRise;
pub use contact::{Contact, ContactKind};
pub use grid::{ClPoint, Grid};
pub use index::DropCutter;
