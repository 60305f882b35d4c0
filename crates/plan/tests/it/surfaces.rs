//! Analytic parts and their exact CL (tool-tip) surfaces for ball, flat and bull cutters.

use cam_core::Cutter;
use cam_core::Toolpath;
use cam_plan::{ClSurface, PlanConfig};

/// A part with a known top surface and a known exact CL surface.
pub trait Analytic: ClSurface {
    /// Part top z (mm) at (x, y).
    fn part(&self, x: f64, y: f64) -> Option<f64>;
}

/// Plane z = m·y (a slope across passes along x).
pub struct Tilted {
    pub m: f64,
    pub cutter: Cutter,
}
impl ClSurface for Tilted {
    fn z_tip(&self, _x: f64, y: f64) -> Option<f64> {
        let (r, a, m) = (
            self.cutter.corner_radius(),
            self.cutter.major_radius(),
            self.m,
        );
        Some(m * y - r + m.abs() * a + r * (1.0 + m * m).sqrt())
    }
}
impl Analytic for Tilted {
    fn part(&self, _x: f64, y: f64) -> Option<f64> {
        Some(self.m * y)
    }
}

/// Plane z = mx·x + my·y, sloping along the passes (x) and across them (y). A torus cutter
/// rests on it at the corner point down the steepest slope g = |(mx, my)|, so the tip is
/// `a·g + r·(sqrt(1 + g²) − 1)` above the plane at the tip's XY; the contact lies
/// `a + r·g / sqrt(1 + g²)` from the axis up the slope.
pub struct Plane {
    pub mx: f64,
    pub my: f64,
    pub cutter: Cutter,
}
impl Plane {
    /// XY offset (mm) from the tip to the contact point.
    pub fn contact_offset(&self) -> (f64, f64) {
        let g = self.mx.hypot(self.my);
        if g == 0.0 {
            return (0.0, 0.0);
        }
        let d = self.cutter.major_radius() + self.cutter.corner_radius() * g / (1.0 + g * g).sqrt();
        (d * self.mx / g, d * self.my / g)
    }
}
impl ClSurface for Plane {
    fn z_tip(&self, x: f64, y: f64) -> Option<f64> {
        let (r, a) = (self.cutter.corner_radius(), self.cutter.major_radius());
        let g = self.mx.hypot(self.my);
        Some(self.mx * x + self.my * y + a * g + r * ((1.0 + g * g).sqrt() - 1.0))
    }
}
impl Analytic for Plane {
    fn part(&self, x: f64, y: f64) -> Option<f64> {
        Some(self.mx * x + self.my * y)
    }
}

/// Convex cylinder of radius `rho`, axis along x at z = 0 (top at z = rho).
pub struct Cylinder {
    pub rho: f64,
    pub cutter: Cutter,
}
impl ClSurface for Cylinder {
    fn z_tip(&self, _x: f64, y: f64) -> Option<f64> {
        let (r, a, rho) = (
            self.cutter.corner_radius(),
            self.cutter.major_radius(),
            self.rho,
        );
        if y.abs() <= a {
            return Some(rho);
        }
        let c = y.abs() - a;
        let q = (rho + r).powi(2) - c * c;
        (q >= 0.0).then(|| q.sqrt() - r)
    }
}
impl Analytic for Cylinder {
    fn part(&self, _x: f64, y: f64) -> Option<f64> {
        let q = self.rho * self.rho - y * y;
        (q >= 0.0).then(|| q.sqrt())
    }
}

/// Concave trough of radius `rho`, axis along x at z = rho (bottom at z = 0).
pub struct Trough {
    pub rho: f64,
    pub cutter: Cutter,
}
impl ClSurface for Trough {
    fn z_tip(&self, _x: f64, y: f64) -> Option<f64> {
        let (r, a, rho) = (
            self.cutter.corner_radius(),
            self.cutter.major_radius(),
            self.rho,
        );
        let mut best: Option<f64> = None;
        for c in [y - a, y + a] {
            let q = (rho - r).powi(2) - c * c;
            if q < 0.0 {
                return None;
            }
            let z = rho - q.sqrt() - r;
            best = Some(best.map_or(z, |b: f64| b.max(z)));
        }
        best
    }
}
impl Analytic for Trough {
    fn part(&self, _x: f64, y: f64) -> Option<f64> {
        let q = self.rho * self.rho - y * y;
        (q >= 0.0).then(|| self.rho - q.sqrt())
    }
}

/// Hemisphere of radius `rho` centred at the origin on the plane z = 0, ball cutter radius `r`;
/// optionally the part ends at |x| ≤ `edge` (cutter touches nothing beyond).
pub struct Dome {
    pub rho: f64,
    pub r: f64,
    pub edge: Option<f64>,
}
impl ClSurface for Dome {
    fn z_tip(&self, x: f64, y: f64) -> Option<f64> {
        if let Some(e) = self.edge
            && x.abs() > e
        {
            return None;
        }
        let q = (self.rho + self.r).powi(2) - x * x - y * y;
        Some(if q > 0.0 {
            (q.sqrt() - self.r).max(0.0)
        } else {
            0.0
        })
    }
}
impl Analytic for Dome {
    fn part(&self, x: f64, y: f64) -> Option<f64> {
        let q = self.rho * self.rho - x * x - y * y;
        Some(q.max(0.0).sqrt())
    }
}

/// Cylinder of radius `rho` with its axis along y (curved along passes along x), ball `r`.
pub struct CylinderAlong {
    pub rho: f64,
    pub r: f64,
}
impl ClSurface for CylinderAlong {
    fn z_tip(&self, x: f64, _y: f64) -> Option<f64> {
        let q = (self.rho + self.r).powi(2) - x * x;
        (q >= 0.0).then(|| q.sqrt() - self.r)
    }
}

/// The configuration used by most tests: τ = h = 0.01 mm, zig-zag, climb.
pub fn cfg(cutter: Cutter) -> PlanConfig {
    PlanConfig {
        cutter,
        tolerance_mm: 0.01,
        scallop_mm: 0.01,
        ..PlanConfig::default()
    }
}

/// Largest |z(move) − z_tip| over every cut move that belongs to a pass, sampled at `n`
/// points per move independently of the planner: (gouge = move below, excess = move above).
pub fn dense_deviation(s: &dyn ClSurface, tp: &Toolpath, n: usize) -> (f64, f64) {
    let (mut gouge, mut excess) = (0.0f64, 0.0f64);
    for w in tp.moves.windows(2) {
        if w[1].kind != cam_core::MoveKind::Cut || w[1].pass.is_none() {
            continue;
        }
        let (a, b) = (w[0].pose.tip, w[1].pose.tip);
        for k in 0..=n {
            let p = a.lerp(b, k as f64 / n as f64);
            let z = s.z_tip(p.x, p.y).expect("cut moves stay on the part");
            gouge = gouge.max(z - p.z);
            excess = excess.max(p.z - z);
        }
    }
    (gouge, excess)
}
