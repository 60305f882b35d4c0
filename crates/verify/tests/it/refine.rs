//! Refinement of the design surface: edge bound, surface preservation, conformity, normals.

use std::collections::HashMap;

use cam_core::{Cutter, DVec3, Mesh, Triangle};
use cam_verify::refine::{self, CapPolicy, RefineConfig, RefineError, RefinedMesh};

fn cfg(s: f64) -> RefineConfig {
    RefineConfig {
        max_edge_mm: s,
        crease_angle_deg: 30.0,
        max_vertices: None,
        on_cap: CapPolicy::Error,
        region: None,
        remesh: true,
    }
}

fn mesh(tris: Vec<Triangle>) -> Mesh {
    Mesh::from_triangles(tris, "<memory>").unwrap()
}

/// An axis-aligned box, outward normals.
pub fn cube(size: f64) -> Mesh {
    let p = |x: f64, y: f64, z: f64| DVec3::new(x, y, z) * size;
    let quads = [
        [p(0., 0., 0.), p(0., 1., 0.), p(1., 1., 0.), p(1., 0., 0.)], // -Z
        [p(0., 0., 1.), p(1., 0., 1.), p(1., 1., 1.), p(0., 1., 1.)], // +Z
        [p(0., 0., 0.), p(1., 0., 0.), p(1., 0., 1.), p(0., 0., 1.)], // -Y
        [p(0., 1., 0.), p(0., 1., 1.), p(1., 1., 1.), p(1., 1., 0.)], // +Y
        [p(0., 0., 0.), p(0., 0., 1.), p(0., 1., 1.), p(0., 1., 0.)], // -X
        [p(1., 0., 0.), p(1., 1., 0.), p(1., 1., 1.), p(1., 0., 1.)], // +X
    ];
    let mut t = Vec::new();
    for q in quads {
        t.push(Triangle::new(q[0], q[1], q[2]));
        t.push(Triangle::new(q[0], q[2], q[3]));
    }
    mesh(t)
}

fn edges_ok(r: &RefinedMesh, s: f64) -> f64 {
    let mut longest: f64 = 0.0;
    for t in &r.triangles {
        for k in 0..3 {
            let d = r.positions[t[k] as usize].distance(r.positions[t[(k + 1) % 3] as usize]);
            longest = longest.max(d);
        }
    }
    assert!(longest <= s * (1.0 + 1e-12), "edge {longest} > s = {s}");
    longest
}

/// Every refined face lies in its source triangle: on its plane and inside it.
fn on_source(r: &RefinedMesh, m: &Mesh) {
    let src = m.triangles();
    let mut area = vec![0.0; src.len()];
    for (t, &s) in r.triangles.iter().zip(&r.face_source) {
        let o = src[s as usize];
        let n = o.normal().unwrap();
        let [a, b, c] = o.v;
        for &vi in t {
            let p = r.positions[vi as usize];
            assert!(
                (p - a).dot(n).abs() <= 1e-12 * (1.0 + a.length()),
                "off plane by {}",
                (p - a).dot(n)
            );
            // Barycentric coordinates by sub-areas.
            let full = (b - a).cross(c - a).dot(n);
            let wa = (b - p).cross(c - p).dot(n) / full;
            let wb = (c - p).cross(a - p).dot(n) / full;
            let wc = (a - p).cross(b - p).dot(n) / full;
            assert!(
                wa >= -1e-12 && wb >= -1e-12 && wc >= -1e-12,
                "outside source: {wa} {wb} {wc}"
            );
        }
        let f = Triangle::new(
            r.positions[t[0] as usize],
            r.positions[t[1] as usize],
            r.positions[t[2] as usize],
        );
        // Orientation kept.
        assert!(f.cross().dot(n) > 0.0, "face flipped");
        area[s as usize] += f.area();
    }
    for (o, a) in src.iter().zip(area) {
        assert!(
            (a - o.area()).abs() <= 1e-9 * o.area(),
            "area {a} vs {}",
            o.area()
        );
    }
}

#[test]
fn paper_edge_length() {
    // s = sqrt(6 r e): ball:6 (r = 3) at e = 0.005 gives sqrt(0.09) = 0.3.
    cam_core::assert_near!(
        refine::max_edge_for(&Cutter::ball(6.0).unwrap(), 0.005),
        0.3,
        1e-15
    );
    cam_core::assert_near!(
        refine::max_edge_for(&Cutter::bull(10.0, 2.0).unwrap(), 0.005),
        0.06f64.sqrt(),
        1e-15
    );
    // Flat: substitute r = R.
    cam_core::assert_near!(
        refine::max_edge_for(&Cutter::flat(10.0).unwrap(), 0.005),
        0.15f64.sqrt(),
        1e-15
    );
    let c = RefineConfig::for_cutter(&Cutter::ball(6.0).unwrap(), 0.005);
    cam_core::assert_near!(c.max_edge_mm, 0.3, 1e-15);
    assert_eq!(c.crease_angle_deg, 30.0);
}

#[test]
fn edges_bounded_and_surface_preserved() {
    let m = mesh(vec![
        Triangle::new(
            DVec3::new(0., 0., 0.),
            DVec3::new(7., 0.5, 1.),
            DVec3::new(2., 5., 2.),
        ),
        Triangle::new(
            DVec3::new(7., 0.5, 1.),
            DVec3::new(9., 6., -1.),
            DVec3::new(2., 5., 2.),
        ),
        // A sliver: long and thin.
        Triangle::new(
            DVec3::new(0., 0., 0.),
            DVec3::new(2., 5., 2.),
            DVec3::new(-8., 3., 0.1),
        ),
    ]);
    for s in [2.0, 0.37, 0.15] {
        let r = refine::refine(&m, &cfg(s)).unwrap();
        let longest = edges_ok(&r, s);
        assert!(
            longest > 0.4 * s,
            "over-refined: longest edge {longest} for s = {s}"
        );
        on_source(&r, &m);
        assert_eq!(r.max_edge_mm, s);
        assert_eq!(r.normals.len(), r.positions.len());
        for n in &r.normals {
            cam_core::assert_near!(n.length(), 1.0, 1e-12);
        }
    }
}

#[test]
fn cube_stays_conforming_with_crease_normals() {
    let m = cube(10.0);
    let r = refine::refine(&m, &cfg(1.3)).unwrap();
    edges_ok(&r, 1.3);
    on_source(&r, &m);
    // Conforming and closed: every edge (by position) is used by exactly two faces, once in
    // each direction.
    let key = |p: DVec3| [p.x, p.y, p.z].map(|c| (c * 1e6).round() as i64);
    let mut uses: HashMap<([i64; 3], [i64; 3]), i32> = HashMap::new();
    for t in &r.triangles {
        for k in 0..3 {
            let (a, b) = (
                key(r.positions[t[k] as usize]),
                key(r.positions[t[(k + 1) % 3] as usize]),
            );
            *uses.entry((a, b)).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &uses {
        assert_eq!(n, 1, "directed edge used {n} times");
        assert_eq!(
            uses.get(&(b, a)),
            Some(&1),
            "edge {a:?}-{b:?} has no twin: T-junction or hole"
        );
    }
    // Crease normals: every face's corners carry exactly the face's normal.
    for (t, &s) in r.triangles.iter().zip(&r.face_source) {
        let n = m.triangles()[s as usize].normal().unwrap();
        for &v in t {
            assert_eq!(r.normals[v as usize], n);
        }
    }
    // The 8 corners appear 3 times each (one per face group); edge vertices twice.
    let mut copies: HashMap<[i64; 3], usize> = HashMap::new();
    for p in &r.positions {
        *copies.entry(key(*p)).or_default() += 1;
    }
    assert_eq!(copies.get(&key(DVec3::ZERO)), Some(&3));
    assert_eq!(copies.get(&key(DVec3::new(10., 10., 10.))), Some(&3));
    assert_eq!(copies.get(&key(DVec3::new(5., 0., 0.))), Some(&2));
}

#[test]
fn smooth_normals_on_a_faceted_cylinder() {
    // 64 facets, dihedral 5.6° < 30°: one smooth group; normals on the facet lines are radial.
    let (rad, segs, hgt) = (5.0, 64, 4.0);
    let at = |k: usize, z: f64| {
        // k % segs: the seam must repeat the first column bit for bit to be welded.
        let a = std::f64::consts::TAU * (k % segs) as f64 / segs as f64;
        DVec3::new(rad * a.cos(), rad * a.sin(), z)
    };
    let mut t = Vec::new();
    for k in 0..segs {
        let (a0, a1, b0, b1) = (at(k, 0.0), at(k + 1, 0.0), at(k, hgt), at(k + 1, hgt));
        t.push(Triangle::new(a0, a1, b1));
        t.push(Triangle::new(a0, b1, b0));
    }
    let m = mesh(t);
    let r = refine::refine(&m, &cfg(0.3)).unwrap();
    edges_ok(&r, 0.3);
    on_source(&r, &m);
    let mut on_line = 0;
    for (p, n) in r.positions.iter().zip(&r.normals) {
        let ang =
            p.y.atan2(p.x).rem_euclid(std::f64::consts::TAU) / std::f64::consts::TAU * segs as f64;
        if (ang - ang.round()).abs() < 1e-9 {
            on_line += 1;
            let radial = DVec3::new(p.x, p.y, 0.0).normalize();
            assert!(
                (*n - radial).length() < 1e-9,
                "normal {n:?} at {p:?} not radial"
            );
        } else {
            // Inside a facet: the facet normal, perpendicular to the facet's mid-radial.
            let k = ang.floor();
            let mid = std::f64::consts::TAU * (k + 0.5) / segs as f64;
            let fnorm = DVec3::new(mid.cos(), mid.sin(), 0.0);
            assert!(
                (*n - fnorm).length() < 1e-9,
                "normal {n:?} at {p:?} not the facet's"
            );
        }
    }
    assert!(
        on_line >= segs * 14,
        "only {on_line} vertices on facet lines"
    );
    // No duplicates: smooth, so every position occurs once.
    let mut seen = std::collections::HashSet::new();
    for p in &r.positions {
        assert!(
            seen.insert([p.x, p.y, p.z].map(f64::to_bits)),
            "duplicated vertex at {p:?}"
        );
    }
}

#[test]
fn deterministic() {
    let m = cube(7.0);
    let a = refine::refine(&m, &cfg(0.9)).unwrap();
    let b = refine::refine(&m, &cfg(0.9)).unwrap();
    assert_eq!(a, b);
}

/// Refining `m` under `capped` (whose cap it exceeds) fails with `TooManyVertices` naming
/// the cap; with `CapPolicy::Coarsen` it succeeds. Returns the suggested edge length and the
/// coarsened mesh.
fn errs_then_coarsens(m: &Mesh, capped: RefineConfig) -> (f64, RefinedMesh) {
    let suggested = match refine::refine(m, &capped) {
        Err(RefineError::TooManyVertices {
            cap,
            suggested_max_edge_mm,
            ..
        }) => {
            assert_eq!(Some(cap), capped.max_vertices);
            suggested_max_edge_mm
        }
        other => panic!("expected TooManyVertices, got {:?}", other.map(|r| r.len())),
    };
    let coarse = refine::refine(
        m,
        &RefineConfig {
            on_cap: CapPolicy::Coarsen,
            ..capped
        },
    )
    .unwrap();
    (suggested, coarse)
}

#[test]
fn vertex_cap_errors_or_coarsens() {
    let m = cube(10.0);
    let capped = RefineConfig {
        max_vertices: Some(2000),
        ..cfg(0.2)
    };
    let (suggested, coarse) = errs_then_coarsens(&m, capped);
    assert!(suggested > 0.2);
    assert!(coarse.max_edge_mm > 0.2);
    // A cap below the design's own 8 vertices fails even when coarsening.
    let tiny = RefineConfig {
        max_vertices: Some(5),
        on_cap: CapPolicy::Coarsen,
        ..cfg(0.2)
    };
    assert!(matches!(
        refine::refine(&m, &tiny),
        Err(RefineError::TooManyVertices { cap: 5, .. })
    ));
    edges_ok(&coarse, coarse.max_edge_mm);
    // The cap counts welded vertices before crease duplication (≤ 3 copies here).
    assert!(coarse.len() <= 3 * 2000);
    assert!(matches!(
        refine::refine(&m, &cfg(0.0)),
        Err(RefineError::BadEdgeLength { .. })
    ));
    assert!(matches!(
        refine::refine(&m, &cfg(f64::NAN)),
        Err(RefineError::BadEdgeLength { .. })
    ));
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(24))]
    /// Any non-degenerate pair of triangles sharing an edge, any edge length: edges bounded,
    /// faces inside their source triangles, areas kept, the shared edge conforming.
    #[test]
    fn refinement_invariants(c in proptest::collection::vec(-5.0f64..5.0, 12), s in 0.3f64..3.0) {
        let p = |i: usize| DVec3::new(c[3 * i], c[3 * i + 1], c[3 * i + 2]);
        let tris = vec![Triangle::new(p(0), p(1), p(2)), Triangle::new(p(0), p(3), p(1))];
        proptest::prop_assume!(tris.iter().all(|t| !t.is_degenerate() && t.area() > 0.5));
        let m = mesh(tris);
        let r = refine::refine(&m, &cfg(s)).unwrap();
        edges_ok(&r, s);
        on_source(&r, &m);
        // Vertices on the shared edge p0–p1: the same set seen from both faces.
        let on_edge = |f: u32| {
            let mut v: Vec<[u64; 3]> = r.triangles.iter().zip(&r.face_source)
                .filter(|(_, src)| **src == f)
                .flat_map(|(t, _)| t.iter().map(|&i| r.positions[i as usize]))
                .filter(|q| (*q - p(0)).cross(p(1) - p(0)).length() <= 1e-9 * (p(1) - p(0)).length())
                .map(|q| [q.x, q.y, q.z].map(f64::to_bits))
                .collect();
            v.sort();
            v.dedup();
            v
        };
        proptest::prop_assert_eq!(on_edge(0), on_edge(1));
    }
}

/// With a region, only faces meeting it (and the neighbours conforming bisection pulls in)
/// are refined: a 10 mm cube refined near its top face only keeps edges ≤ s there, stays
/// conforming (every edge shared by exactly two faces) and on its sources, and has far fewer
/// vertices than the whole cube refined.
#[test]
fn region_refines_only_where_asked_and_stays_conforming() {
    let m = cube(10.0);
    let s = 0.5;
    let full = refine::refine(&m, &cfg(s)).unwrap();
    let b = m.bounds();
    let top = b.max.z;
    let region = [
        b.min.x - 1.0,
        b.min.y - 1.0,
        top - 0.1,
        b.max.x + 1.0,
        b.max.y + 1.0,
        top + 1.0,
    ];
    let part = refine::refine(
        &m,
        &RefineConfig {
            region: Some(refine::Region {
                bounds: region,
                inside_mm: 0.0,
                outside_mm: 0.0,
            }),
            ..cfg(s)
        },
    )
    .unwrap();
    on_source(&part, &m);
    // Faces meeting the region: edges ≤ s.
    for t in &part.triangles {
        let p = t.map(|i| part.positions[i as usize]);
        if p.iter().any(|q| q.z >= top - 0.1) {
            for k in 0..3 {
                let d = p[k].distance(p[(k + 1) % 3]);
                assert!(d <= s * (1.0 + 1e-12), "edge {d} in the region");
            }
        }
    }
    // Conforming: every undirected edge (by position) is used by exactly two faces.
    let key = |a: cam_core::DVec3, b: cam_core::DVec3| {
        let (a, b) = (
            a.to_array().map(f64::to_bits),
            b.to_array().map(f64::to_bits),
        );
        if a <= b { (a, b) } else { (b, a) }
    };
    let mut count = std::collections::HashMap::new();
    for t in &part.triangles {
        let p = t.map(|i| part.positions[i as usize]);
        for k in 0..3 {
            *count.entry(key(p[k], p[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    assert!(count.values().all(|&c| c == 2), "not conforming");
    let (nf, np) = (full.positions.len(), part.positions.len());
    eprintln!("region refinement: {np} vertices against {nf} for the whole cube");
    assert!(np * 3 < nf, "{np} vs {nf}");
}

/// Remeshing into near-equilateral faces keeps every guarantee of the refinement (edges ≤ s,
/// faces inside their sources with their orientation and area, closed meshes conforming)
/// with far fewer vertices than bisection alone: measured 0.49×, 0.22× and 0.49× on the
/// dome, fillet and pocket at s = 0.5 (0.44×, 0.17× and 0.33× at a ball:6's 0.3). The bound
/// fails the remesh before its lattice ran along each face's longest edge (0.60×, 0.24×,
/// 0.55×).
#[test]
fn remeshing_keeps_the_guarantees_with_far_fewer_vertices() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/parts");
    let s = 0.5;
    for name in ["dome.obj", "fillet.obj", "pocket.obj"] {
        let m = Mesh::load(root.join(name), cam_core::Units::Mm).unwrap();
        let bisected = refine::refine(
            &m,
            &RefineConfig {
                remesh: false,
                ..cfg(s)
            },
        )
        .unwrap();
        let r = refine::refine(&m, &cfg(s)).unwrap();
        edges_ok(&r, s);
        on_source(&r, &m);
        // Conforming: the parts are closed, so every undirected edge (by position: creases
        // duplicate vertices) has two faces.
        let key = |i: u32| r.positions[i as usize].to_array().map(f64::to_bits);
        let mut uses: HashMap<_, u32> = HashMap::new();
        for t in &r.triangles {
            for k in 0..3 {
                let (a, b) = (key(t[k]), key(t[(k + 1) % 3]));
                *uses.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        assert!(uses.values().all(|&n| n == 2), "{name}: not conforming");
        let ratio = r.positions.len() as f64 / bisected.positions.len() as f64;
        eprintln!(
            "{name}: {} vertices remeshed, {} bisected ({ratio:.2}×)",
            r.positions.len(),
            bisected.positions.len()
        );
        assert!(ratio < 0.53, "{name}: {ratio}");
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]
    /// Thin and needle-like faces (one corner within `1e-6`–`1` mm of the opposite edge's
    /// line) next to a regular one: the remesh either triangulates them or fans them, and
    /// the refinement keeps its guarantees (edges ≤ s, faces inside their sources with their
    /// orientation and area, the shared edge conforming) without a panic.
    #[test]
    fn thin_faces_keep_the_guarantees(
        len in 1.0f64..20.0,
        along in -0.5f64..1.5,
        lift in -6.0f64..0.0,
        s in 0.2f64..2.0,
    ) {
        let h = 10f64.powf(lift);
        let (a, b) = (DVec3::new(0.0, 0.0, 0.0), DVec3::new(len, 0.0, 0.3));
        let c = DVec3::new(along * len, h, 0.1);
        let d = DVec3::new(0.3 * len, -3.0, -0.2);
        let tris = vec![Triangle::new(a, b, c), Triangle::new(a, d, b)];
        proptest::prop_assume!(tris.iter().all(|t| !t.is_degenerate()));
        let m = mesh(tris);
        let r = refine::refine(&m, &cfg(s)).unwrap();
        edges_ok(&r, s);
        on_source(&r, &m);
    }
}

/// A face of a square metre at s = 0.05 mm would hold some 5e8 lattice points: the remesh
/// counts them against the vertex cap before building any, so refining fails with a clear
/// error (or coarsens) instead of exhausting memory.
#[test]
fn a_huge_face_meets_the_cap_before_any_memory_is_spent() {
    let p = |x: f64, y: f64| DVec3::new(x, y, 0.0);
    let m = mesh(vec![
        Triangle::new(p(0.0, 0.0), p(1000.0, 0.0), p(1000.0, 1000.0)),
        Triangle::new(p(0.0, 0.0), p(1000.0, 1000.0), p(0.0, 1000.0)),
    ]);
    let capped = RefineConfig {
        max_vertices: Some(2_000_000),
        ..cfg(0.05)
    };
    let (_, coarse) = errs_then_coarsens(&m, capped);
    assert!(coarse.len() <= 2_000_000 && coarse.max_edge_mm > 0.05 * 10.0);
    edges_ok(&coarse, coarse.max_edge_mm);
}
