//! The drop-cutter: a 2-D bucket index over the part's triangles for one cutter radius, and
//! the batch drivers.

use cam_core::{Cutter, Mesh};

use crate::{ClPoint, Contact, Grid};

/// A part prepared for dropping one cutter: triangles with precomputed data in an XY bucket
/// grid whose cells list every triangle within the cutter radius, sorted by descending top z
/// so a query stops as soon as no remaining triangle can raise the cutter.
///
/// # Performance
/// Building is O(triangles × cells each covers); a query touches one cell.
#[derive(Debug, Clone)]
pub struct DropCutter {
    cutter: Cutter,
}

impl DropCutter {
    /// Prepares `mesh` for dropping `cutter`.
    pub fn new(mesh: &Mesh, cutter: Cutter) -> DropCutter {
        let _ = mesh;
        DropCutter { cutter }
    }
    /// The cutter.
    pub fn cutter(&self) -> Cutter {
        self.cutter
    }
    /// Tool-tip z (mm) at `(x, y)`, or `None` if the cutter touches no triangle.
    pub fn drop(&self, x: f64, y: f64) -> Option<f64> {
        self.contact(x, y).map(|c| c.z_tip)
    }
    /// Like [`DropCutter::drop`] but also says where and how the cutter touches.
    pub fn contact(&self, x: f64, y: f64) -> Option<Contact> {
        let _ = (x, y);
        todo!()
    }
    /// Drops at every `(x, y)` in order, in parallel; identical for any thread count.
    pub fn drop_points(&self, xy: &[(f64, f64)]) -> Vec<ClPoint> {
        let _ = xy;
        todo!()
    }
    /// Drops over a grid, in parallel, row-major order.
    pub fn drop_grid(&self, grid: &Grid) -> Vec<ClPoint> {
        let _ = grid;
        todo!()
    }
}
