//! `cargo xtask gen-fixtures`: small analytic test parts as OBJ text in `fixtures/parts/`.
//!
//! Every part is built as an indexed mesh with shared vertices, so the solids are watertight
//! by construction (tests below check every edge is used once in each direction), with
//! outward, counter-clockwise faces. Units mm. Coordinates are written with Rust's shortest
//! round-trip formatting, so reading a file back gives the generated doubles exactly.

use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Result, ensure};
use glam::DVec3;

/// An indexed triangle mesh.
#[derive(Debug, Clone, Default)]
pub struct IndexedMesh {
    /// Vertices (mm).
    pub v: Vec<DVec3>,
    /// Triangles as 0-based vertex indices, counter-clockwise seen from outside.
    pub f: Vec<[usize; 3]>,
}

impl IndexedMesh {
    fn vert(&mut self, p: DVec3) -> usize {
        self.v.push(DVec3::new(snap(p.x), snap(p.y), snap(p.z)));
        self.v.len() - 1
    }
    fn tri(&mut self, a: usize, b: usize, c: usize) {
        self.f.push([a, b, c]);
    }
    /// Quad a-b-c-d (counter-clockwise from outside) as triangles abc, acd.
    fn quad(&mut self, a: usize, b: usize, c: usize, d: usize) {
        self.tri(a, b, c);
        self.tri(a, c, d);
    }
    /// Signed volume (mm³), positive for a closed, outward-oriented surface.
    pub fn volume(&self) -> f64 {
        self.f
            .iter()
            .map(|t| self.v[t[0]].dot(self.v[t[1]].cross(self.v[t[2]])) / 6.0)
            .sum()
    }
    /// OBJ text with `header` lines as comments.
    pub fn to_obj(&self, header: &str) -> String {
        let mut s = String::new();
        for l in header.lines() {
            let _ = writeln!(s, "# {l}");
        }
        for p in &self.v {
            let _ = writeln!(s, "v {} {} {}", p.x, p.y, p.z);
        }
        for t in &self.f {
            let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
        }
        s
    }
}

/// Rounds away floating-point dust: values within 1e-12 mm of an integer become it.
fn snap(x: f64) -> f64 {
    let r = x.round();
    if (x - r).abs() < 1e-12 { r + 0.0 } else { x }
}

/// Tilt of `tilted_plane.obj` (degrees).
pub const TILT_DEG: f64 = 20.0;

/// `tilted_plane.obj`: z = x·tan 20° over [-30, 30]², a 6 × 6 grid of squares (72 triangles),
/// open surface, normals up.
pub fn tilted_plane() -> IndexedMesh {
    let mut m = IndexedMesh::default();
    let n = 6;
    let k = TILT_DEG.to_radians().tan();
    for j in 0..=n {
        for i in 0..=n {
            let x = -30.0 + 60.0 * i as f64 / n as f64;
            let y = -30.0 + 60.0 * j as f64 / n as f64;
            m.vert(DVec3::new(x, y, x * k));
        }
    }
    let id = |i: usize, j: usize| j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            m.quad(id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
        }
    }
    m
}

/// Dome parameters: hemisphere radius, plate half-width, plate thickness (mm), longitudes,
/// latitude bands.
pub const DOME: (f64, f64, f64, usize, usize) = (20.0, 30.0, 5.0, 96, 40);

/// `dome.obj`: a hemisphere of radius 20 centred at the origin on the top (z = 0) of a
/// 60 × 60 × 5 plate (z from -5 to 0); UV sphere with 96 longitudes and 40 latitude bands,
/// vertices exactly on the sphere. Watertight.
pub fn dome() -> IndexedMesh {
    let (r, h, t, nl, nb) = DOME;
    let mut m = IndexedMesh::default();
    let theta = |k: usize| 2.0 * PI * k as f64 / nl as f64;
    // Sphere rings: ring 0 is the equator at z = 0.
    let mut rings = Vec::new();
    for b in 0..nb {
        let phi = 0.5 * PI * b as f64 / nb as f64;
        let ring: Vec<usize> = (0..nl)
            .map(|k| {
                let th = theta(k);
                m.vert(DVec3::new(
                    r * phi.cos() * th.cos(),
                    r * phi.cos() * th.sin(),
                    r * phi.sin(),
                ))
            })
            .collect();
        rings.push(ring);
    }
    let pole = m.vert(DVec3::new(0.0, 0.0, r));
    for b in 0..nb - 1 {
        for k in 0..nl {
            let k1 = (k + 1) % nl;
            m.quad(rings[b][k], rings[b][k1], rings[b + 1][k1], rings[b + 1][k]);
        }
    }
    for k in 0..nl {
        m.tri(rings[nb - 1][k], rings[nb - 1][(k + 1) % nl], pole);
    }
    // Plate: the square boundary point on each longitude's ray, top (z = 0) and bottom.
    let square = |k: usize| {
        let (s, c) = theta(k).sin_cos();
        let q = c.abs().max(s.abs());
        (h * c / q, h * s / q)
    };
    let top: Vec<usize> = (0..nl)
        .map(|k| {
            let (x, y) = square(k);
            m.vert(DVec3::new(x, y, 0.0))
        })
        .collect();
    let bot: Vec<usize> = (0..nl)
        .map(|k| {
            let (x, y) = square(k);
            m.vert(DVec3::new(x, y, -t))
        })
        .collect();
    let centre = m.vert(DVec3::new(0.0, 0.0, -t));
    for k in 0..nl {
        let k1 = (k + 1) % nl;
        m.quad(rings[0][k], top[k], top[k1], rings[0][k1]);
        m.quad(bot[k], bot[k1], top[k1], top[k]);
        m.tri(centre, bot[k1], bot[k]);
    }
    m
}

/// Pocket parameters: block side, block height, pocket side, pocket depth (mm).
pub const POCKET: (f64, f64, f64, f64) = (80.0, 30.0, 40.0, 15.0);

/// `pocket.obj`: an 80 × 80 × 30 block (x, y in [-40, 40], z in [0, 30]) with a centred
/// 40 × 40 square pocket 15 deep (walls at x, y = ±20, flat floor at z = 15). 28 triangles,
/// watertight.
pub fn pocket() -> IndexedMesh {
    let (side, height, ps, depth) = POCKET;
    let (a, b) = (side / 2.0, ps / 2.0);
    let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    let mut m = IndexedMesh::default();
    let mut ring = |half: f64, z: f64| -> Vec<usize> {
        corners
            .iter()
            .map(|&(sx, sy)| m.vert(DVec3::new(sx * half, sy * half, z)))
            .collect()
    };
    let o = ring(a, height);
    let i = ring(b, height);
    let fl = ring(b, height - depth);
    let bo = ring(a, 0.0);
    for k in 0..4 {
        let k1 = (k + 1) % 4;
        m.quad(o[k], o[k1], i[k1], i[k]); // top annulus
        m.quad(fl[k], i[k], i[k1], fl[k1]); // pocket wall, facing the pocket
        m.quad(bo[k], bo[k1], o[k1], o[k]); // outer side
    }
    m.quad(fl[0], fl[1], fl[2], fl[3]);
    m.quad(bo[0], bo[3], bo[2], bo[1]);
    m
}

/// Fillet parameters: radius, length along X, arc segments (mm, mm, count).
pub const FILLET: (f64, f64, usize) = (6.0, 40.0, 64);

/// The (y, z) profile of `fillet.obj`, counter-clockwise seen from +X.
pub fn fillet_profile() -> Vec<(f64, f64)> {
    let (r, _, n) = FILLET;
    let mut p = vec![(-10.0, -5.0), (30.0, -5.0), (30.0, 0.0)];
    for s in 0..=n {
        let phi = 1.5 * PI - 0.5 * PI * s as f64 / n as f64;
        p.push((snap(r + r * phi.cos()), snap(r + r * phi.sin())));
    }
    p.push((0.0, 30.0));
    p.push((-10.0, 30.0));
    p
}

/// `fillet.obj`: an L-shaped solid extruded along X from 0 to 40: a floor (top z = 0 for
/// y ≥ 6, slab down to z = -5, out to y = 30) and a wall (face y = 0 for z ≥ 6, 10 thick, up
/// to z = 30), joined by a concave quarter-cylinder fillet of radius 6 with axis
/// (y, z) = (6, 6) along X, 64 segments along the arc (vertices exactly on the cylinder).
/// Watertight; the fillet is its only concave feature.
pub fn fillet() -> IndexedMesh {
    let (_, len, _) = FILLET;
    let prof = fillet_profile();
    let n = prof.len();
    let mut m = IndexedMesh::default();
    let a: Vec<usize> = prof
        .iter()
        .map(|&(y, z)| m.vert(DVec3::new(0.0, y, z)))
        .collect();
    let b: Vec<usize> = prof
        .iter()
        .map(|&(y, z)| m.vert(DVec3::new(len, y, z)))
        .collect();
    for k in 0..n {
        let k1 = (k + 1) % n;
        m.quad(a[k], a[k1], b[k1], b[k]);
    }
    // The profile is star-shaped about its first vertex: fan caps.
    for k in 1..n - 1 {
        m.tri(b[0], b[k], b[k + 1]);
        m.tri(a[0], a[k + 1], a[k]);
    }
    m
}

/// Every part: file name, mesh, one-line description.
pub fn all() -> Vec<(&'static str, IndexedMesh, &'static str)> {
    vec![
        (
            "tilted_plane.obj",
            tilted_plane(),
            "plane z = x*tan(20 deg) over x, y in [-30, 30]; 6x6 squares; open surface",
        ),
        (
            "dome.obj",
            dome(),
            "hemisphere r = 20 at the origin on a 60x60x5 plate (z in [-5, 0]); 96 longitudes x 40 latitude bands; watertight",
        ),
        (
            "pocket.obj",
            pocket(),
            "80x80x30 block (x, y in [-40, 40], z in [0, 30]) with a centred 40x40 pocket 15 deep (floor z = 15); watertight",
        ),
        (
            "fillet.obj",
            fillet(),
            "L-shaped solid along x in [0, 40]: floor z = 0 (y >= 6), wall y = 0 (z >= 6), concave fillet r = 6 about (y, z) = (6, 6), 64 arc segments; watertight",
        ),
    ]
}

const README: &str = "# Analytic test parts

Written by `cargo xtask gen-fixtures` (xtask/src/parts.rs; do not edit by hand). OBJ text,
units mm, triangles counter-clockwise seen from outside (outward normals), vertices shared, so
the solids are watertight (each edge used once in each direction; checked by xtask's tests,
as are the volumes below). Coordinates are printed with Rust's shortest round-trip format:
parsing them gives the generated doubles exactly; values within 1e-12 of an integer were
snapped to it.

| file | triangles | vertices | what | volume mm³ |
| --- | --- | --- | --- | --- |
";

const NOTES: &str = "
## Analytic facts

- `tilted_plane.obj`: z = x·tan 20°, x, y ∈ [-30, 30], unit normal (−sin 20°, 0, cos 20°).
  Vertices on a 10 mm grid, so every interior vertex and edge lies in the plane. Away from
  the boundary (≥ R from it) a cutter's tip z at (x, y) is x·tan 20° plus: ball R:
  R·(1/cos 20° − 1); flat R: R·tan 20°; bull (R, r): (R − r)·tan 20° + r·(1/cos 20° − 1)
  (OpenCAMLib agrees to 1e-15 mm for ball:6, flat:6, bull:6:1.5).
- `dome.obj`: hemisphere centre (0, 0, 0), radius 20, on the plate top z = 0 (plate
  x, y ∈ [-30, 30], z ∈ [-5, 0]). UV sphere: 96 longitudes (every 3.75°), 40 latitude bands
  (every 2.25°), pole vertex at (0, 0, 20); every sphere vertex is exactly on the sphere
  (to rounding). Chordal (tessellation) error of the sphere: ≤ 20·(1 − cos(1.875°)) ≈
  0.0107 mm across longitudes, ≤ 20·(1 − cos(1.125°)) ≈ 0.0039 mm across latitudes, so a
  ball of radius R dropped on the dome reads at most ~0.011 mm below the exact sphere
  (tip z = sqrt((20 + R)² − ρ²) − R at distance ρ from the axis, within the cap; OpenCAMLib,
  ball:6 at four points: 0 to −0.0064 mm).
  Volume: plate 18000 + hemisphere (exact 16755.16; the polyhedron is slightly less).
- `pocket.obj`: block x, y ∈ [-40, 40], z ∈ [0, 30]; pocket x, y ∈ [-20, 20], floor
  z = 15, vertical walls; top rim z = 30. A flat cutter of radius R ≤ 20 at the pocket
  centre rests on the floor (tip z = 15), over the rim at z = 30; a ball of radius R at
  x = 20 − d inside the wall x = 20 (0 < d < R ≤ 15, |y| ≤ 20 − R) rests on the rim
  edge at tip z = 30 − R + sqrt(R² − d²).
  Volume 80·80·30 − 40·40·15 = 168000 exactly.
- `fillet.obj`: extruded along x ∈ [0, 40]. Profile (y, z): slab y ∈ [-10, 30],
  z ∈ [-5, 0]; wall y ∈ [-10, 0], z ∈ [-5, 30]; fillet: quarter circle of radius 6 about
  (y, z) = (6, 6) from (6, 0) to (0, 6), 64 segments (vertices on the circle). The only
  concave feature is the fillet, radius 6. A ball of radius R < 6 dropped at
  R < y ≤ 6 (0 < x < 40, away from the ends) rests on the arc at tip
  z = 6 − sqrt((6 − R)² − (y − 6)²) − R, up to the tessellation (chordal error of the arc
  6·(1 − cos(0.703°)) ≈ 4.5e-4 mm; measured with OpenCAMLib for D = 4, 6, 8: ≤ 6e-4 mm
  for y ≥ R + 1, ≤ 5e-3 mm at y = R + 0.01 where the contact is on the steep part by the
  wall). For y ≤ R the disc reaches the wall's top face (z = 30) and the cutter rests there.
  Volume 40·(200 + 300 + (36 − area under the tessellated arc)) ≈ 40·(536 − 9π).
";

/// Writes every part and `README.md` into `dir`.
pub fn gen_fixtures(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir)?;
    let mut readme = String::from(README);
    for (name, mesh, what) in all() {
        let text = mesh.to_obj(&format!(
            "{name}: {what}\nunits mm; generated by `cargo xtask gen-fixtures` (xtask/src/parts.rs)"
        ));
        ensure!(text.len() < 1_000_000, "{name} is {} bytes", text.len());
        std::fs::write(dir.join(name), &text)?;
        let volume = if name == "tilted_plane.obj" {
            "open".to_string()
        } else {
            format!("{:.3}", mesh.volume())
        };
        let _ = writeln!(
            readme,
            "| {name} | {} | {} | {what} | {volume} |",
            mesh.f.len(),
            mesh.v.len()
        );
        println!(
            "{}: {} triangles, {} bytes",
            dir.join(name).display(),
            mesh.f.len(),
            text.len()
        );
    }
    readme.push_str(NOTES);
    std::fs::write(dir.join("README.md"), readme)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use super::*;

    /// Number of times each directed edge is used.
    fn edges(m: &IndexedMesh) -> HashMap<(usize, usize), usize> {
        let mut e = HashMap::new();
        for t in &m.f {
            for k in 0..3 {
                *e.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        e
    }

    fn assert_closed_oriented(name: &str, m: &IndexedMesh) {
        let e = edges(m);
        for (&(a, b), &n) in &e {
            assert_eq!(n, 1, "{name}: edge {a}->{b} used {n} times");
            assert_eq!(
                e.get(&(b, a)),
                Some(&1),
                "{name}: edge {a}->{b} has no twin"
            );
        }
        // No duplicate vertices (which would hide an open seam).
        let mut seen = HashMap::new();
        for (i, p) in m.v.iter().enumerate() {
            let key = (p.x.to_bits(), p.y.to_bits(), p.z.to_bits());
            if let Some(j) = seen.insert(key, i) {
                panic!("{name}: vertices {j} and {i} coincide at {p}");
            }
        }
    }

    fn no_degenerate(name: &str, m: &IndexedMesh) {
        for t in &m.f {
            let tri = cam_core::Triangle::new(m.v[t[0]], m.v[t[1]], m.v[t[2]]);
            assert!(!tri.is_degenerate(), "{name}: degenerate {t:?}");
        }
    }

    #[test]
    fn solids_are_watertight_and_outward() {
        for (name, m, _) in all() {
            no_degenerate(name, &m);
            if name == "tilted_plane.obj" {
                continue;
            }
            assert_closed_oriented(name, &m);
            assert!(m.volume() > 0.0, "{name}: inward-facing");
        }
    }

    #[test]
    fn volumes_match_the_geometry() {
        assert_eq!(pocket().volume(), 168000.0);
        let (r, h, t, _, _) = DOME;
        let v = dome().volume();
        let plate = 4.0 * h * h * t;
        let hemi = 2.0 / 3.0 * PI * r * r * r;
        // Inscribed polyhedron: below the hemisphere, by less than 0.2 %.
        assert!(
            v < plate + hemi && v > plate + hemi * 0.998,
            "dome volume {v}"
        );
        // Fillet: profile area by the shoelace formula, times the length.
        let p = fillet_profile();
        let area: f64 = (0..p.len())
            .map(|k| {
                let (a, b) = (p[k], p[(k + 1) % p.len()]);
                a.0 * b.1 - b.0 * a.1
            })
            .sum::<f64>()
            / 2.0;
        let (fr, len, _) = FILLET;
        assert!((fillet().volume() - area * len).abs() < 1e-9 * area * len);
        let exact = 200.0 + 300.0 + fr * fr * (1.0 - PI / 4.0);
        assert!(
            area > exact && area < exact + 0.01,
            "fillet profile area {area} vs {exact}"
        );
    }

    #[test]
    fn vertices_lie_on_the_analytic_surfaces() {
        let k = TILT_DEG.to_radians().tan();
        for p in tilted_plane().v {
            assert!((p.z - p.x * k).abs() < 1e-14, "{p}");
        }
        let (r, ..) = DOME;
        let on_sphere = dome()
            .v
            .iter()
            .filter(|p| (p.length() - r).abs() < 1e-12)
            .count();
        assert_eq!(on_sphere, 96 * 40 + 1);
        let (fr, ..) = FILLET;
        let on_arc = fillet()
            .v
            .iter()
            .filter(|p| ((p.y - fr).hypot(p.z - fr) - fr).abs() < 1e-12)
            .count();
        assert_eq!(on_arc, 2 * 65);
        assert_eq!(dome().f.len(), 8064);
        assert_eq!(fillet().f.len(), 276);
        assert_eq!(pocket().f.len(), 28);
    }

    #[test]
    fn obj_text_reads_back_exactly() {
        for (name, m, _) in all() {
            let text = m.to_obj("test");
            let tris = cam_core::io::obj::parse_obj(text.as_bytes(), Path::new(name)).unwrap();
            assert_eq!(tris.len(), m.f.len(), "{name}");
            for (t, f) in tris.iter().zip(&m.f) {
                assert_eq!(t.v, [m.v[f[0]], m.v[f[1]], m.v[f[2]]], "{name}");
            }
            assert!(text.len() < 1_000_000);
            assert_eq!(text, m.to_obj("test"), "{name}: not deterministic");
        }
    }
}
