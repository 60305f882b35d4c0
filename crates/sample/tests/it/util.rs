//! Mesh builders and the brute-force reference used by the tests.

use cam_core::{DVec3, Mesh, Triangle};
use cam_sample::{Profile, Sectioner};

/// A mesh from triangles given as `[x, y, z]` corners.
pub fn mesh(tris: &[[[f64; 3]; 3]]) -> Mesh {
    Mesh::from_triangles(
        tris.iter()
            .map(|t| Triangle::new(t[0].into(), t[1].into(), t[2].into()))
            .collect(),
        "<test>",
    )
    .expect("valid test mesh")
}

/// Regular grid height field over `[x0, x0+nx·h] × [y0, y0+ny·h]`, two triangles per cell
/// (diagonal from (i,j) to (i+1,j+1)); cells for which `keep(i, j)` is false are left out.
pub fn grid_mesh(
    (x0, y0): (f64, f64),
    (nx, ny): (usize, usize),
    h: f64,
    f: impl Fn(f64, f64) -> f64,
    keep: impl Fn(usize, usize) -> bool,
) -> Mesh {
    let p = |i: usize, j: usize| {
        let (x, y) = (x0 + i as f64 * h, y0 + j as f64 * h);
        [x, y, f(x, y)]
    };
    let mut t = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            if keep(i, j) {
                t.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
                t.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
            }
        }
    }
    mesh(&t)
}

/// The 12 triangles of the closed box `[lo, hi]`.
pub fn box_tris(lo: [f64; 3], hi: [f64; 3]) -> Vec<[[f64; 3]; 3]> {
    let c = |i: usize| {
        [
            if i & 1 == 0 { lo[0] } else { hi[0] },
            if i & 2 == 0 { lo[1] } else { hi[1] },
            if i & 4 == 0 { lo[2] } else { hi[2] },
        ]
    };
    // Faces as corner quads (indices into the 8 corners).
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mut t = Vec::new();
    for q in quads {
        t.push([c(q[0]), c(q[1]), c(q[2])]);
        t.push([c(q[0]), c(q[2]), c(q[3])]);
    }
    t
}

/// UV sphere of radius `r` centred at `c`, vertices on the sphere; `nlat` (even) rings.
pub fn sphere_mesh(c: [f64; 3], r: f64, nlat: usize, nlon: usize) -> Mesh {
    let p = |i: usize, j: usize| {
        let th = std::f64::consts::PI * i as f64 / nlat as f64; // polar angle
        let ph = 2.0 * std::f64::consts::PI * j as f64 / nlon as f64;
        [
            c[0] + r * th.sin() * ph.cos(),
            c[1] + r * th.sin() * ph.sin(),
            c[2] + r * th.cos(),
        ]
    };
    let mut t = Vec::new();
    for i in 0..nlat {
        for j in 0..nlon {
            let (a, b, cc, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            if i > 0 {
                t.push([a, b, d]);
            }
            if i + 1 < nlat {
                t.push([b, cc, d]);
            }
        }
    }
    mesh(&t)
}

fn orient(a: (f64, f64), b: (f64, f64), p: (f64, f64)) -> f64 {
    (b.0 - a.0) * (p.1 - a.1) - (b.1 - a.1) * (p.0 - a.0)
}

/// Brute force: the highest point of any closed triangle (frame coordinates `(u, v, z)`) on
/// the vertical line through `(u, v)`, by a barycentric ray test on every triangle.
/// Points within 1e-14 (in barycentric weight) of a triangle count as inside.
/// Triangles lying in the plane `v` exactly contribute their highest point at `u`; other
/// vertical triangles (which meet a vertical line in at most a measure-zero set of `u`) are
/// ignored.
pub fn brute_z(tris: &[[DVec3; 3]], u: f64, v: f64) -> Option<f64> {
    let mut best: Option<f64> = None;
    let q = (u, v);
    for t in tris {
        let (a, b, c) = ((t[0].x, t[0].y), (t[1].x, t[1].y), (t[2].x, t[2].y));
        let area = orient(a, b, c);
        let z = if area != 0.0 {
            let w0 = orient(b, c, q) / area;
            let w1 = orient(c, a, q) / area;
            let w2 = orient(a, b, q) / area;
            // Closed triangles, with a 1e-14 slack on the barycentric weights so that points
            // on edges and vertices (computed in rotated frames with rounding) count as in.
            if w0 < -1e-14 || w1 < -1e-14 || w2 < -1e-14 {
                continue;
            }
            w0 * t[0].z + w1 * t[1].z + w2 * t[2].z
        } else if t[0].y == v && t[1].y == v && t[2].y == v {
            // In the plane: highest crossing of the vertical line u with the three edges.
            let mut zt: Option<f64> = None;
            for k in 0..3 {
                let (p0, p1) = (t[k], t[(k + 1) % 3]);
                let (lo, hi) = (p0.x.min(p1.x), p0.x.max(p1.x));
                if u < lo || u > hi {
                    continue;
                }
                let z = if p0.x == p1.x {
                    p0.z.max(p1.z)
                } else {
                    p0.z + (p1.z - p0.z) * (u - p0.x) / (p1.x - p0.x)
                };
                zt = Some(zt.map_or(z, |w: f64| w.max(z)));
            }
            match zt {
                Some(z) => z,
                None => continue,
            }
        } else {
            continue;
        };
        best = Some(best.map_or(z, |w: f64| w.max(z)));
    }
    best
}

/// The profile value at `u` from a set of profiles (`None` in a gap).
pub fn profiles_z(ps: &[Profile], u: f64) -> Option<f64> {
    ps.iter().find_map(|p| p.z_at(u))
}

/// What a comparison against the brute force measured.
#[derive(Debug, Default, Clone)]
pub struct Agreement {
    /// Samples compared.
    pub samples: usize,
    /// Samples where both found the surface.
    pub both: usize,
    /// Largest |Δz| where both found it (mm).
    pub max_dz: f64,
    /// Samples where exactly one of them found the surface, farther than 1e-9 mm from any
    /// profile end.
    pub coverage_mismatch: usize,
    /// Samples within 1e-9 mm of a profile end where exactly one of them found the surface
    /// (the brute force's inside test is not exact on triangle edges).
    pub boundary_mismatch: usize,
    /// Samples where only the brute force found the surface, at an isolated point (nothing
    /// 1e-9 mm to either side): the plane touches the part there, and profiles of zero
    /// length are documented as dropped.
    pub isolated_touch: usize,
    /// The first few mismatches: `(u, profile z, brute z)`.
    pub mismatches: Vec<(f64, Option<f64>, Option<f64>)>,
}

/// Compares the top profile of plane `v` with the brute force at the given `u`.
pub fn compare(s: &Sectioner, v: f64, us: &[f64]) -> Agreement {
    let ps = s.top_profile(v);
    let mut a = Agreement::default();
    for &u in us {
        a.samples += 1;
        match (profiles_z(&ps, u), brute_z(s.triangles_uvz(), u, v)) {
            (Some(z1), Some(z2)) => {
                a.both += 1;
                a.max_dz = a.max_dz.max((z1 - z2).abs());
            }
            (None, None) => {}
            (z1, z2) => {
                let near_end = ps.iter().any(|p| {
                    let (u0, u1) = p.u_range().expect("non-empty");
                    (u - u0).abs() <= 1e-9 || (u - u1).abs() <= 1e-9
                });
                if near_end {
                    a.boundary_mismatch += 1;
                    continue;
                }
                let tris = s.triangles_uvz();
                if z1.is_none()
                    && brute_z(tris, u - 1e-9, v).is_none()
                    && brute_z(tris, u + 1e-9, v).is_none()
                {
                    a.isolated_touch += 1;
                    continue;
                }
                a.coverage_mismatch += 1;
                if a.mismatches.len() < 5 {
                    a.mismatches.push((u, z1, z2));
                }
            }
        }
    }
    a
}

/// Profile invariants: u non-decreasing, consecutive points distinct, positive u extent,
/// finite values.
pub fn check_profile(p: &Profile) {
    assert!(p.points.len() >= 2, "profile with fewer than 2 points");
    for w in p.points.windows(2) {
        assert!(w[0].0 <= w[1].0, "u decreases: {:?}", w);
        assert!(w[0] != w[1], "duplicate point {:?}", w[0]);
    }
    assert!(p.points[0].0 < p.points[p.points.len() - 1].0);
    assert!(p.points.iter().all(|q| q.0.is_finite() && q.1.is_finite()));
}

/// Deterministic pseudo-random numbers in [0, 1) (SplitMix64).
pub struct Rng(pub u64);

impl Rng {
    /// Next value in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [a, b).
    pub fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next_f64()
    }
}
