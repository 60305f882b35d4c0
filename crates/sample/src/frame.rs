//! The raster frame: horizontal coordinates `u` (along the passes) and `v` (across them).

use glam::DVec3;

/// Raster frame: `u` runs along the passes, `v` across them, both in mm, Z unchanged.
///
/// The frame is the XY plane rotated about +Z by `angle_deg`: with `angle_deg = 0` the passes
/// run along +X, `u = x`, `v = y`, and the section planes `v = const` have their normal
/// along Y. For angles that are whole multiples of 90° the sine and cosine are taken exactly
/// (0, ±1), so axis-aligned frames transform coordinates without rounding.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RasterFrame {
    angle_deg: f64,
    cos: f64,
    sin: f64,
}

impl RasterFrame {
    /// The frame rotated by `angle_deg` degrees about +Z (counter-clockwise seen from above).
    ///
    /// A non-finite angle is stored as given; its transforms then yield NaN (the
    /// [`crate::sample_part`] entry point rejects such angles with a [`crate::SampleError`]).
    pub fn new(angle_deg: f64) -> RasterFrame {
        let (sin, cos) = exact_sin_cos(angle_deg);
        RasterFrame {
            angle_deg,
            cos,
            sin,
        }
    }

    /// The rotation angle in degrees, as given to [`RasterFrame::new`].
    pub fn angle_deg(&self) -> f64 {
        self.angle_deg
    }

    /// Frame coordinates `(u, v)` (mm) to world `(x, y)` (mm).
    pub fn to_xy(&self, u: f64, v: f64) -> (f64, f64) {
        (u * self.cos - v * self.sin, u * self.sin + v * self.cos)
    }

    /// World `(x, y)` (mm) to frame coordinates `(u, v)` (mm).
    pub fn to_uv(&self, x: f64, y: f64) -> (f64, f64) {
        (x * self.cos + y * self.sin, -x * self.sin + y * self.cos)
    }

    /// Unit horizontal direction of increasing `u` (along the passes).
    pub fn u_dir(&self) -> DVec3 {
        DVec3::new(self.cos, self.sin, 0.0)
    }

    /// Unit horizontal direction of increasing `v` (across the passes; the section planes'
    /// normal).
    pub fn v_dir(&self) -> DVec3 {
        DVec3::new(-self.sin, self.cos, 0.0)
    }

    /// A world point (mm) in frame coordinates `(u, v, z)`.
    pub fn point_to_uvz(&self, p: DVec3) -> DVec3 {
        let (u, v) = self.to_uv(p.x, p.y);
        DVec3::new(u, v, p.z)
    }

    /// A frame point `(u, v, z)` (mm) in world coordinates.
    pub fn point_to_xyz(&self, u: f64, v: f64, z: f64) -> DVec3 {
        let (x, y) = self.to_xy(u, v);
        DVec3::new(x, y, z)
    }
}

impl Default for RasterFrame {
    /// The unrotated frame (`angle_deg = 0`).
    fn default() -> Self {
        RasterFrame::new(0.0)
    }
}

/// `(sin, cos)` of an angle in degrees, exact for whole multiples of 90°.
fn exact_sin_cos(angle_deg: f64) -> (f64, f64) {
    if angle_deg.is_finite() {
        let r = angle_deg.rem_euclid(360.0);
        if r == 0.0 {
            return (0.0, 1.0);
        } else if r == 90.0 {
            return (1.0, 0.0);
        } else if r == 180.0 {
            return (0.0, -1.0);
        } else if r == 270.0 {
            return (-1.0, 0.0);
        }
    }
    angle_deg.to_radians().sin_cos()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_axes() {
        for a in [0.0, 17.0, 90.0, -90.0, 135.0, 180.0, 270.0, 400.0] {
            let f = RasterFrame::new(a);
            let (u, v) = f.to_uv(3.25, -7.5);
            let (x, y) = f.to_xy(u, v);
            assert!(
                (x - 3.25).abs() < 1e-12 && (y + 7.5).abs() < 1e-12,
                "angle {a}"
            );
            assert!((f.u_dir().length() - 1.0).abs() < 1e-15);
            assert!(f.u_dir().dot(f.v_dir()).abs() < 1e-15);
            // u_dir is the world direction of +u.
            let (x1, y1) = f.to_xy(1.0, 0.0);
            assert!((x1 - f.u_dir().x).abs() < 1e-15 && (y1 - f.u_dir().y).abs() < 1e-15);
            let (x2, y2) = f.to_xy(0.0, 1.0);
            assert!((x2 - f.v_dir().x).abs() < 1e-15 && (y2 - f.v_dir().y).abs() < 1e-15);
        }
    }

    #[test]
    fn axis_aligned_frames_are_exact() {
        let f = RasterFrame::new(0.0);
        assert_eq!(f.to_uv(0.1, 0.7), (0.1, 0.7));
        let f = RasterFrame::new(90.0);
        // Passes along +Y; v = -x.
        assert_eq!(f.to_uv(0.1, 0.7), (0.7, -0.1));
        assert_eq!(f.to_xy(0.7, -0.1), (0.1, 0.7));
        assert_eq!(f.u_dir(), DVec3::Y);
    }
}
