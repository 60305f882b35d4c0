//! The raster frame: passes run along `u`, side steps go along `v`.

/// Raster frame rotated by `angle_deg` about +Z: `u = (cos a, sin a)`, `v = (−sin a, cos a)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Raster {
    c: f64,
    s: f64,
}

impl Raster {
    /// The frame for a raster angle in degrees.
    pub fn new(angle_deg: f64) -> Raster {
        let (s, c) = angle_deg.to_radians().sin_cos();
        Raster { c, s }
    }
    /// XY (mm) of frame coordinates `(u, v)` (mm).
    pub fn to_xy(&self, u: f64, v: f64) -> (f64, f64) {
        (u * self.c - v * self.s, u * self.s + v * self.c)
    }
    /// Frame coordinates `(u, v)` (mm) of XY (mm).
    pub fn to_uv(&self, x: f64, y: f64) -> (f64, f64) {
        (x * self.c + y * self.s, -x * self.s + y * self.c)
    }
    /// The `u`-interval (mm) of the pass at `v` inside the box `(xmin, xmax, ymin, ymax)`.
    pub fn clip(&self, v: f64, b: (f64, f64, f64, f64)) -> Option<(f64, f64)> {
        // Point on the line: p(u) = u·U + v·V; clip against each slab.
        let (px, py) = self.to_xy(0.0, v);
        let (dx, dy) = (self.c, self.s);
        let mut lo = f64::NEG_INFINITY;
        let mut hi = f64::INFINITY;
        for (p, d, mn, mx) in [(px, dx, b.0, b.1), (py, dy, b.2, b.3)] {
            if d.abs() < 1e-15 {
                if p < mn || p > mx {
                    return None;
                }
            } else {
                let (t0, t1) = ((mn - p) / d, (mx - p) / d);
                lo = lo.max(t0.min(t1));
                hi = hi.min(t0.max(t1));
            }
        }
        (lo <= hi).then_some((lo, hi))
    }
    /// The `v`-range (mm) covered by the box.
    pub fn v_range_of(&self, b: (f64, f64, f64, f64)) -> (f64, f64) {
        let vs = [(b.0, b.2), (b.0, b.3), (b.1, b.2), (b.1, b.3)].map(|(x, y)| self.to_uv(x, y).1);
        vs.iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, z), &v| {
                (a.min(v), z.max(v))
            })
    }
}
