//! Regular XY grids of drop positions and the CL points they produce.

/// A regular XY grid, rows along X: point `(i, j)` is at `(x0 + i·step, y0 + j·step)`,
/// listed row by row (j outer, i inner). Units mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    /// X of the first column (mm).
    pub x0: f64,
    /// Y of the first row (mm).
    pub y0: f64,
    /// Spacing along X and Y (mm).
    pub step: f64,
    /// Points per row.
    pub nx: usize,
    /// Number of rows.
    pub ny: usize,
}

impl Grid {
    /// The grid covering `[xmin, xmax] × [ymin, ymax]` with spacing `step`, starting at the
    /// minimum corner; the last row/column is the last one not beyond the maximum (plus a
    /// 1e-9 mm allowance so an exact multiple is kept).
    pub fn covering(xmin: f64, xmax: f64, ymin: f64, ymax: f64, step: f64) -> Grid {
        let n = |lo: f64, hi: f64| ((hi - lo) / step + 1e-9).floor().max(0.0) as usize + 1;
        Grid {
            x0: xmin,
            y0: ymin,
            step,
            nx: n(xmin, xmax),
            ny: n(ymin, ymax),
        }
    }
    /// Number of points.
    pub fn len(&self) -> usize {
        self.nx * self.ny
    }
    /// True when the grid has no point.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// XY of point `k` in row-major order (mm).
    pub fn xy(&self, k: usize) -> (f64, f64) {
        let (j, i) = (k / self.nx, k % self.nx);
        (
            self.x0 + i as f64 * self.step,
            self.y0 + j as f64 * self.step,
        )
    }
}

/// One dropped position: tool-tip z (mm) or `None` where the cutter touches nothing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClPoint {
    /// X (mm).
    pub x: f64,
    /// Y (mm).
    pub y: f64,
    /// Tool-tip z (mm), `None` where the cutter misses the part.
    pub z_tip: Option<f64>,
}
