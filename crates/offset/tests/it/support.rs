//! Mesh builders and a deterministic RNG for the tests.

use cam_core::{Cutter, DVec3, Mesh, Triangle};

pub fn mesh(tris: Vec<Triangle>) -> Mesh {
    Mesh::from_triangles(tris, "<test>").expect("valid test mesh")
}

pub fn cutters() -> Vec<Cutter> {
    vec![
        Cutter::ball(6.0).unwrap(),
        Cutter::flat(6.0).unwrap(),
        Cutter::bull(6.0, 1.5).unwrap(),
        Cutter::bull(10.0, 1.0).unwrap(),
    ]
}

/// A square [-h, h]² as two triangles of the plane z = f(x, y) (f affine).
pub fn square(h: f64, f: impl Fn(f64, f64) -> f64) -> Vec<Triangle> {
    let p = |x: f64, y: f64| DVec3::new(x, y, f(x, y));
    vec![
        Triangle::new(p(-h, -h), p(h, -h), p(h, h)),
        Triangle::new(p(-h, -h), p(h, h), p(-h, h)),
    ]
}

/// SplitMix64: small, deterministic, good enough for test data.
pub struct Rng(pub u64);
impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A UV sphere of radius `rho` centred at the origin, vertices on the sphere.
pub fn uv_sphere(rho: f64, n_lat: usize, n_lon: usize) -> Vec<Triangle> {
    use std::f64::consts::{PI, TAU};
    let p = |i: usize, j: usize| {
        let th = PI * i as f64 / n_lat as f64;
        let ph = TAU * j as f64 / n_lon as f64 + 0.1234;
        DVec3::new(
            rho * th.sin() * ph.cos(),
            rho * th.sin() * ph.sin(),
            rho * th.cos(),
        )
    };
    let mut t = Vec::new();
    for i in 0..n_lat {
        for j in 0..n_lon {
            let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            if i != 0 {
                t.push(Triangle::new(a, b, d));
            }
            if i + 1 != n_lat {
                t.push(Triangle::new(b, c, d));
            }
        }
    }
    t
}
