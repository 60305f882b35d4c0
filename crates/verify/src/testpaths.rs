//! Generated 5-axis toolpaths over analytic surfaces, for validating the swept surface:
//! a plane, a convex cylinder and a twisted blade (a helicoid strip), with lead and tilt
//! angles and a lead that oscillates along the pass so the tool axis keeps rotating.
//!
//! Each pose touches the surface at the pass point `S(u, v₀)`: the point of the cutter whose
//! outward normal is `−N` is placed on `S` (for a bull or ball cutter on its corner torus).

use cam_core::{Cutter, DVec3, Move, MoveKind, Pose, Toolpath, Triangle};

/// An analytic surface `S(u, v)` with unit normal `N` (pointing away from the material).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TestSurface {
    /// `S = (u, v, 0)`, `N = +Z`.
    Plane,
    /// A convex cylinder of radius `radius_mm` about the line `z = −radius_mm` along Y, top at
    /// `z = 0`; `u` is arc length around it.
    Cylinder {
        /// Radius (mm).
        radius_mm: f64,
    },
    /// A helicoid strip `S = (u, v cos βu, v sin βu)`, twisting `β` radians per mm about X.
    Blade {
        /// Twist β (rad/mm).
        twist_rad_per_mm: f64,
    },
}

impl TestSurface {
    /// Point (mm) and unit normal at `(u, v)`.
    pub fn eval(&self, u: f64, v: f64) -> (DVec3, DVec3) {
        match *self {
            TestSurface::Plane => (DVec3::new(u, v, 0.0), DVec3::Z),
            TestSurface::Cylinder { radius_mm: rc } => {
                let (s, c) = (u / rc).sin_cos();
                (DVec3::new(rc * s, v, rc * c - rc), DVec3::new(s, 0.0, c))
            }
            TestSurface::Blade {
                twist_rad_per_mm: b,
            } => {
                let (s, c) = (b * u).sin_cos();
                let n = DVec3::new(-v * b, -s, c).normalize();
                (DVec3::new(u, v * c, v * s), n)
            }
        }
    }
}

/// A pass along `u` at fixed `v`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PassSpec {
    /// The surface.
    pub surface: TestSurface,
    /// Fixed `v` of the pass (mm).
    pub v_mm: f64,
    /// First `u` (mm).
    pub u0_mm: f64,
    /// Number of poses.
    pub poses: usize,
    /// `u` step between poses (mm).
    pub step_mm: f64,
    /// Mean lead angle (degrees): the axis leans forward, in the feed direction.
    pub lead_deg: f64,
    /// Amplitude of the lead's oscillation along the pass (degrees).
    pub lead_wobble_deg: f64,
    /// Period of that oscillation (mm of `u`).
    pub wobble_period_mm: f64,
    /// Tilt angle (degrees): the axis leans sideways, about the feed direction.
    pub tilt_deg: f64,
}

/// The tool pose touching `S(u, v)` for a given lead and tilt (degrees).
pub fn pose_on(
    surface: &TestSurface,
    cutter: &Cutter,
    u: f64,
    v: f64,
    lead_deg: f64,
    tilt_deg: f64,
) -> Pose {
    let (p, n) = surface.eval(u, v);
    let (p1, _) = surface.eval(u + 1e-4, v);
    let (p0, _) = surface.eval(u - 1e-4, v);
    let d = p1 - p0;
    let f = (d - d.dot(n) * n).normalize();
    let side = n.cross(f);
    let (sl, cl) = lead_deg.to_radians().sin_cos();
    let (st, ct) = tilt_deg.to_radians().sin_cos();
    let k = (cl * ct * n + sl * f + cl * st * side).normalize();
    let (a, r) = (cutter.major_radius(), cutter.corner_radius());
    // Contact normal of the tool: w = −N on the insert û.
    let w = -n;
    let perp = w - w.dot(k) * k;
    let u_hat = if perp.length() > 1e-12 {
        perp.normalize()
    } else {
        crate::imprint::any_perpendicular(k)
    };
    let centre = p - r * w - a * u_hat;
    Pose {
        tip: centre - r * k,
        axis: k,
    }
}

/// The pass as a toolpath: a rapid to the first pose, then one `Cut` per further pose.
pub fn pass(spec: &PassSpec, cutter: &Cutter) -> Toolpath {
    let moves = (0..spec.poses)
        .map(|i| {
            let du = i as f64 * spec.step_mm;
            let lead = spec.lead_deg
                + spec.lead_wobble_deg
                    * (2.0 * std::f64::consts::PI * du / spec.wobble_period_mm).sin();
            let pose = pose_on(
                &spec.surface,
                cutter,
                spec.u0_mm + du,
                spec.v_mm,
                lead,
                spec.tilt_deg,
            );
            Move {
                kind: if i == 0 {
                    MoveKind::Rapid
                } else {
                    MoveKind::Cut
                },
                pose,
                feed_mm_per_min: None,
                line: None,
                pass: Some(0),
            }
        })
        .collect();
    Toolpath { moves }
}

/// A zig-zag of `passes` passes like `spec` at `v = spec.v_mm + i·stepover_mm`, every
/// other one run backwards, each opened by a rapid to its first pose (pass `i` numbered
/// `i`): a multi-pass 5-axis program whose neighbouring passes overlap when the stepover is
/// below the cutter's diameter.
pub fn zigzag(spec: &PassSpec, passes: usize, stepover_mm: f64, cutter: &Cutter) -> Toolpath {
    let mut moves = Vec::new();
    for i in 0..passes {
        let one = PassSpec {
            v_mm: spec.v_mm + i as f64 * stepover_mm,
            ..*spec
        };
        let mut p = pass(&one, cutter).moves;
        if i % 2 == 1 {
            p.reverse();
        }
        for (j, m) in p.iter_mut().enumerate() {
            m.kind = if j == 0 {
                MoveKind::Rapid
            } else {
                MoveKind::Cut
            };
            m.pass = Some(i);
        }
        moves.extend(p);
    }
    Toolpath { moves }
}

/// The surface over `u_range × v_range` (mm) as `nu × nv` grid cells of two triangles
/// each, counter-clockwise seen from `+N` (an open sheet: the design surface of the
/// generated programs).
pub fn surface_triangles(
    surface: &TestSurface,
    u_range: (f64, f64),
    v_range: (f64, f64),
    nu: usize,
    nv: usize,
) -> Vec<Triangle> {
    let (nu, nv) = (nu.max(1), nv.max(1));
    let at = |i: usize, j: usize| {
        let u = u_range.0 + (u_range.1 - u_range.0) * i as f64 / nu as f64;
        let v = v_range.0 + (v_range.1 - v_range.0) * j as f64 / nv as f64;
        surface.eval(u, v).0
    };
    let mut out = Vec::with_capacity(2 * nu * nv);
    for j in 0..nv {
        for i in 0..nu {
            let (p00, p10, p11, p01) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            out.push(Triangle::new(p00, p10, p11));
            out.push(Triangle::new(p00, p11, p01));
        }
    }
    out
}

/// A two-pose 3-axis path: rapid to `a`, cut to `b` (tool tips, axis +Z).
pub fn straight(a: DVec3, b: DVec3) -> Toolpath {
    let mk = |kind, tip| Move {
        kind,
        pose: Pose::vertical(tip),
        feed_mm_per_min: None,
        line: None,
        pass: None,
    };
    Toolpath {
        moves: vec![mk(MoveKind::Rapid, a), mk(MoveKind::Cut, b)],
    }
}

/// Lines for [`crate::envelope::line_error`]: from `depth_mm` below `S(u, v)` along `+N`, for
/// `nu × nv` points with `u` evenly in `u_range` and `v` evenly in `v_range` (mm).
pub fn normal_lines(
    surface: &TestSurface,
    u_range: (f64, f64),
    v_range: (f64, f64),
    nu: usize,
    nv: usize,
    depth_mm: f64,
) -> Vec<(DVec3, DVec3)> {
    let lerp =
        |r: (f64, f64), i: usize, n: usize| r.0 + (r.1 - r.0) * i as f64 / (n.max(2) - 1) as f64;
    let mut out = Vec::with_capacity(nu * nv);
    for i in 0..nu {
        for j in 0..nv {
            let (p, n) = surface.eval(lerp(u_range, i, nu), lerp(v_range, j, nv));
            out.push((p - depth_mm * n, n));
        }
    }
    out
}
