//! Closed-form contact heights of a cutter (axis +Z) with a vertex, an edge and a facet.

use glam::DVec3;

/// Which feature of a triangle the cutter rests on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum ContactKind {
    /// A triangle corner.
    Vertex,
    /// The interior of a triangle edge.
    Edge,
    /// The interior of a triangle face.
    Facet,
}

/// Where a dropped cutter comes to rest.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// Tool-tip z (mm).
    pub z_tip: f64,
    /// The cutter-contact (CC) point on the part (mm).
    pub cc: DVec3,
    /// Vertex, edge or facet contact.
    pub kind: ContactKind,
    /// Index of the triangle touched, in [`cam_core::Mesh::triangles`].
    pub triangle: u32,
}
