//! The normal-vector method: exact signed deviations against known swept surfaces.

use cam_core::{DVec3, Mesh, Triangle};
use cam_verify::deviation::{self, DeviationConfig, DeviationError, Facing};
use cam_verify::refine::{self, CapPolicy, RefineConfig, RefinedMesh};

fn refined(tris: Vec<Triangle>, s: f64) -> RefinedMesh {
    refined_with(tris, s, true)
}

/// As [`refined`]; `remesh: false` bisects only (a square's vertices stay on its dyadic grid).
fn refined_with(tris: Vec<Triangle>, s: f64, remesh: bool) -> RefinedMesh {
    let m = Mesh::from_triangles(tris, "<memory>").unwrap();
    let cfg = RefineConfig {
        max_edge_mm: s,
        crease_angle_deg: 30.0,
        max_vertices: None,
        on_cap: CapPolicy::Error,
        region: None,
        remesh,
    };
    refine::refine(&m, &cfg).unwrap()
}

/// The design: the square [0,10]² at z = 0, normal +Z, refined to edges ≤ 0.5 mm.
pub fn design_plane() -> RefinedMesh {
    let p = |x: f64, y: f64| DVec3::new(x, y, 0.0);
    refined(
        vec![
            Triangle::new(p(0., 0.), p(10., 0.), p(10., 10.)),
            Triangle::new(p(0., 0.), p(10., 10.), p(0., 10.)),
        ],
        0.5,
    )
}

/// A swept surface over [-1,11]² made of a fan around `apex` to the corners at height `z`,
/// oriented out of the tool volume above it (normals pointing down into the material).
fn fan(apex: DVec3, z: f64) -> Vec<Triangle> {
    let c =
        [(-1.0, -1.0), (11.0, -1.0), (11.0, 11.0), (-1.0, 11.0)].map(|(x, y)| DVec3::new(x, y, z));
    (0..4)
        .map(|k| Triangle::new(apex, c[(k + 1) % 4], c[k]))
        .collect()
}

/// Height of the fan surface above (x, y): an independent evaluation by plane equations.
fn fan_height(tris: &[Triangle], x: f64, y: f64) -> f64 {
    for t in tris {
        let [a, b, c] = t.v;
        let s = |p: DVec3, q: DVec3| (q.x - p.x) * (y - p.y) - (q.y - p.y) * (x - p.x);
        let (s0, s1, s2) = (s(a, b), s(b, c), s(c, a));
        if (s0 <= 0.0 && s1 <= 0.0 && s2 <= 0.0) || (s0 >= 0.0 && s1 >= 0.0 && s2 >= 0.0) {
            let n = t.cross();
            return a.z - (n.x * (x - a.x) + n.y * (y - a.y)) / n.z;
        }
    }
    panic!("({x}, {y}) outside the fan");
}

fn nearest(r: &RefinedMesh, x: f64, y: f64) -> DVec3 {
    *r.positions
        .iter()
        .min_by(|a, b| {
            a.distance(DVec3::new(x, y, 0.0))
                .total_cmp(&b.distance(DVec3::new(x, y, 0.0)))
        })
        .unwrap()
}

#[test]
fn plane_swept_at_known_height() {
    let r = design_plane();
    let sw = fan(DVec3::new(5.0, 5.0, 0.03), 0.03);
    let moves = [7, 8, 9, 10];
    let d = deviation::measure(&r, &sw, &moves, &DeviationConfig::default()).unwrap();
    assert_eq!(d.len(), r.len());
    assert!(r.len() > 400);
    for v in &d {
        let s = v.signed_mm.expect("every vertex is under the sweep");
        cam_core::assert_near!(s, 0.03, 1e-15);
        assert!(moves.contains(&v.source_move.unwrap()));
        assert_eq!(v.normal, DVec3::Z);
    }
}

fn check_fan(apex_dz: f64) {
    let r = design_plane();
    let p = nearest(&r, 3.3, 4.1);
    let sw = fan(DVec3::new(p.x, p.y, apex_dz), 0.03);
    let moves = [0, 1, 2, 3];
    let d = deviation::measure(&r, &sw, &moves, &DeviationConfig::default()).unwrap();
    for v in &d {
        let want = fan_height(&sw, v.position.x, v.position.y);
        cam_core::assert_near!(v.signed_mm.unwrap(), want, 1e-12, "at {:?}", v.position);
    }
    let (extreme, at) = if apex_dz < 0.0 {
        let w = d
            .iter()
            .min_by(|a, b| a.signed_mm.unwrap().total_cmp(&b.signed_mm.unwrap()))
            .unwrap();
        (w.signed_mm.unwrap(), w.position)
    } else {
        let w = d
            .iter()
            .max_by(|a, b| a.signed_mm.unwrap().total_cmp(&b.signed_mm.unwrap()))
            .unwrap();
        (w.signed_mm.unwrap(), w.position)
    };
    cam_core::assert_near!(extreme, apex_dz, 1e-15);
    assert_eq!(at, p);
}

#[test]
fn gouge_found_with_depth_and_location() {
    check_fan(-0.05);
}

#[test]
fn excess_found_with_height_and_location() {
    check_fan(0.2);
}

/// A vertical wall x = 0 (normal +X) with two sweeps in front of it: the back of a
/// neighbouring pass at x = 0.5 (normal +X, an exit for the wall's vectors) and the real cut
/// at x = 2 (normal −X).
#[test]
fn back_facing_crossings_are_ignored() {
    let p = |y: f64, z: f64| DVec3::new(0.0, y, z);
    let wall = refined(
        vec![
            Triangle::new(p(0., 0.), p(10., 0.), p(10., 10.)),
            Triangle::new(p(0., 0.), p(10., 10.), p(0., 10.)),
        ],
        1.0,
    );
    assert!(wall.normals.iter().all(|n| *n == DVec3::X));
    let sheet = |x: f64, out: f64| {
        let q = |y: f64, z: f64| DVec3::new(x, y, z);
        let (a, b, c, d) = (q(-1., -1.), q(11., -1.), q(11., 11.), q(-1., 11.));
        let t = [Triangle::new(a, b, c), Triangle::new(a, c, d)];
        if t[0].normal().unwrap().x * out > 0.0 {
            t.to_vec()
        } else {
            t.iter()
                .map(|t| Triangle::new(t.v[0], t.v[2], t.v[1]))
                .collect()
        }
    };
    let mut sw = sheet(0.5, 1.0);
    sw.extend(sheet(2.0, -1.0));
    let moves = [1, 1, 2, 2];
    let d = deviation::measure(&wall, &sw, &moves, &DeviationConfig::default()).unwrap();
    for v in &d {
        cam_core::assert_near!(v.signed_mm.unwrap(), 2.0, 1e-14);
        assert_eq!(v.source_move, Some(2));
    }
    let any = DeviationConfig {
        facing: Facing::Any,
        ..Default::default()
    };
    let d = deviation::measure(&wall, &sw, &moves, &any).unwrap();
    assert!(
        d.iter()
            .all(|v| (v.signed_mm.unwrap() - 0.5).abs() < 1e-14 && v.source_move == Some(1))
    );
    // Only the back sheet: nothing enters, unmachined.
    let d = deviation::measure(&wall, &sw[..2], &moves[..2], &DeviationConfig::default()).unwrap();
    assert!(
        d.iter()
            .all(|v| v.signed_mm.is_none() && v.source_move.is_none())
    );
}

#[test]
fn vector_span_limits() {
    let r = design_plane();
    // A gouge of 1.5 mm lies beyond L_in = 1: not seen; with L_in = 2 it is.
    let sw = fan(DVec3::new(5.0, 5.0, -1.5), -1.5);
    let m = [0; 4];
    let d = deviation::measure(&r, &sw, &m, &DeviationConfig::default()).unwrap();
    assert!(d.iter().all(|v| v.signed_mm.is_none()));
    let deep = DeviationConfig {
        inside_mm: 2.0,
        ..Default::default()
    };
    let d = deviation::measure(&r, &sw, &m, &deep).unwrap();
    assert!(d.iter().all(|v| (v.signed_mm.unwrap() + 1.5).abs() < 1e-14));
    // Excess beyond L_out = 5: unmachined.
    let sw = fan(DVec3::new(5.0, 5.0, 6.0), 6.0);
    let d = deviation::measure(&r, &sw, &m, &DeviationConfig::default()).unwrap();
    assert!(d.iter().all(|v| v.signed_mm.is_none()));
    assert_eq!(DeviationConfig::for_tolerance(0.1).inside_mm, 2.0);
}

#[test]
fn input_errors() {
    let r = design_plane();
    let sw = fan(DVec3::new(5.0, 5.0, 0.0), 0.0);
    assert!(matches!(
        deviation::measure(&r, &sw, &[0, 1], &DeviationConfig::default()),
        Err(DeviationError::LengthMismatch {
            triangles: 4,
            moves: 2
        })
    ));
    let bad = DeviationConfig {
        inside_mm: -1.0,
        ..Default::default()
    };
    assert!(matches!(
        deviation::measure(&r, &sw, &[0; 4], &bad),
        Err(DeviationError::BadLength { .. })
    ));
}

/// Deterministic pseudo-random numbers in [0, 1).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Brute force: every triangle, plane intersection then same-side inside tests.
fn brute(
    p: DVec3,
    n: DVec3,
    tris: &[Triangle],
    moves: &[u32],
    lin: f64,
    lout: f64,
) -> (Option<f64>, Option<u32>) {
    let mut best: Option<(f64, u32)> = None;
    for (t, &m) in tris.iter().zip(moves) {
        let nt = t.normal().unwrap();
        if nt.dot(n) >= 0.0 {
            continue;
        }
        let s = (t.v[0] - p).dot(nt) / n.dot(nt);
        if s < -lin || s > lout {
            continue;
        }
        let x = p + s * n;
        let inside = (0..3).all(|k| (t.v[(k + 1) % 3] - t.v[k]).cross(x - t.v[k]).dot(nt) >= 0.0);
        if inside && best.is_none_or(|(b, _)| s < b) {
            best = Some((s, m));
        }
    }
    (best.map(|b| b.0), best.map(|b| b.1))
}

#[test]
fn bvh_agrees_with_brute_force() {
    let mut g = Lcg(42);
    // A bumpy design surface: a tilted, folded strip.
    let q = |x: f64, y: f64| DVec3::new(x, y, 0.3 * x + 0.5 * (y - 2.0).abs());
    let r = refined(
        vec![
            Triangle::new(q(0., 0.), q(6., 0.), q(6., 2.)),
            Triangle::new(q(0., 0.), q(6., 2.), q(0., 2.)),
            Triangle::new(q(0., 2.), q(6., 2.), q(6., 4.)),
            Triangle::new(q(0., 2.), q(6., 4.), q(0., 4.)),
        ],
        0.4,
    );
    let mut sw = Vec::new();
    for _ in 0..600 {
        let c = DVec3::new(
            g.next() * 7.0 - 0.5,
            g.next() * 5.0 - 0.5,
            g.next() * 4.0 - 1.0,
        );
        let e = |g: &mut Lcg| DVec3::new(g.next() - 0.5, g.next() - 0.5, g.next() - 0.5) * 1.5;
        let t = Triangle::new(c, c + e(&mut g), c + e(&mut g));
        if !t.is_degenerate() {
            sw.push(t);
        }
    }
    let moves: Vec<u32> = (0..sw.len() as u32).collect();
    let cfg = DeviationConfig::default();
    let d = deviation::measure(&r, &sw, &moves, &cfg).unwrap();
    let mut hits = 0;
    for v in &d {
        let (s, m) = brute(
            v.position,
            v.normal,
            &sw,
            &moves,
            cfg.inside_mm,
            cfg.outside_mm,
        );
        match (v.signed_mm, s) {
            (Some(a), Some(b)) => {
                cam_core::assert_near!(a, b, 1e-9);
                assert_eq!(v.source_move, m);
                hits += 1;
            }
            (None, None) => {}
            other => panic!("BVH {other:?} at {:?}", v.position),
        }
    }
    assert!(hits > d.len() / 4, "only {hits} of {} vectors hit", d.len());
    // Same result on one thread.
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let d1 = one.install(|| deviation::measure(&r, &sw, &moves, &cfg).unwrap());
    assert_eq!(d, d1);
}

#[test]
fn merge_keeps_the_lower() {
    let r = design_plane();
    let a = deviation::measure(
        &r,
        &fan(DVec3::new(2.0, 2.0, -0.02), 0.03),
        &[0; 4],
        &DeviationConfig::default(),
    )
    .unwrap();
    let b = deviation::measure(
        &r,
        &fan(DVec3::new(8.0, 8.0, -0.04), 0.03),
        &[1; 4],
        &DeviationConfig::default(),
    )
    .unwrap();
    let m = deviation::merge_lowest(&a, &b);
    for ((x, y), z) in a.iter().zip(&b).zip(&m) {
        assert_eq!(
            z.signed_mm.unwrap(),
            x.signed_mm.unwrap().min(y.signed_mm.unwrap())
        );
    }
}

/// End to end against the independent z-map: ball passes along a plane of slope m, the
/// design plane under them. Sweeping a shape along a straight line gives a surface invariant
/// along the line, so on a plane parallel to the passes the normal deviation equals the
/// vertical one times the normal's z component, exactly. The imprint sweep is polyhedral:
/// its cross-section is a polygon through Q/2 + 1 points of the ball's profile, so it may lie
/// up to the chord sag R·(1 − cos(π/Q)) above the true envelope, and never below it.
#[test]
fn imprint_sweep_agrees_with_zmap_within_chord_sag() {
    use cam_core::{Cutter, Move, MoveKind, Pose, Toolpath};
    use cam_verify::{sweep, zmap};
    let m = 0.2;
    let cutter: Cutter = "ball:6".parse().unwrap();
    let z = |x: f64| m * (x - 4.0);
    let p = |x: f64, y: f64| DVec3::new(x, y, z(x));
    // Bisected only: the vertices stay on the z-map's 0.25 mm grid.
    let r = refined_with(
        vec![
            Triangle::new(p(0., 0.), p(8., 0.), p(8., 8.)),
            Triangle::new(p(0., 0.), p(8., 8.), p(0., 8.)),
        ],
        0.5,
        false,
    );
    let mut moves = Vec::new();
    for k in 0..=13 {
        let y = -4.0 + 1.2 * k as f64;
        let (xa, xb) = if k % 2 == 0 {
            (-4.0, 12.0)
        } else {
            (12.0, -4.0)
        };
        for i in 0..=32 {
            let x = xa + (xb - xa) * i as f64 / 32.0;
            moves.push(Move {
                kind: MoveKind::Cut,
                pose: Pose::vertical(DVec3::new(x, y, z(x))),
                feed_mm_per_min: None,
                line: None,
                pass: None,
            });
        }
    }
    let tp = Toolpath { moves };
    let g = zmap::ZmapGrid::covering(0.0, 0.0, 8.0, 8.0, 0.25).unwrap();
    let zm = zmap::machine(&tp, &cutter, &zmap::ZmapConfig::new(g)).unwrap();
    let nz = 1.0 / (1.0 + m * m).sqrt();
    for q in [40usize, 80] {
        let sw = sweep::sweep(
            &tp,
            &cutter,
            &sweep::SweepConfig {
                inserts: q,
                ..Default::default()
            },
        );
        let d = deviation::measure_swept(&r, &sw, &DeviationConfig::default()).unwrap();
        let sag = 3.0 * (1.0 - (std::f64::consts::PI / q as f64).cos());
        let mut worst: f64 = 0.0;
        for v in &d {
            // Refined vertices of this square lie on the 0.25 mm grid.
            let (i, j) = (
                (v.position.x / 0.25).round() as usize,
                (v.position.y / 0.25).round() as usize,
            );
            cam_core::assert_near!(g.x(i), v.position.x, 1e-12);
            cam_core::assert_near!(g.y(j), v.position.y, 1e-12);
            let truth = (zm.height(i, j) - z(v.position.x)) * nz;
            let diff = v.signed_mm.expect("covered") - truth;
            assert!(
                diff >= -1e-9 && diff <= sag + 1e-9,
                "Q = {q}: sweep − z-map = {diff} at {:?}, sag {sag}",
                v.position
            );
            worst = worst.max(diff);
        }
        assert!(
            worst > 0.5 * sag,
            "Q = {q}: worst {worst} far below the sag {sag}?"
        );
    }
}

/// `TriangleBvh::any_within` and `TriangleGrid::any_within` against `nearest_within`: the
/// same answer for points at, just inside and just outside the nearest distance, on and
/// beside a tessellated plane (whose coplanar faces `any_within` passes over by their plane)
/// and a tilted fan.
#[test]
fn any_within_answers_as_nearest_within() {
    use cam_verify::deviation::TriangleBvh;
    let mut rng = Lcg(0x9e37_79b9_7f4a_7c15);
    // A 10 x 10 mm plate in 200 faces at z = 0, and a fan leaning over it.
    let mut tris = Vec::new();
    for i in 0..10 {
        for j in 0..10 {
            let (x, y) = (i as f64, j as f64);
            let q = |dx: f64, dy: f64| DVec3::new(x + dx, y + dy, 0.0);
            tris.push(Triangle::new(q(0.0, 0.0), q(1.0, 0.0), q(1.0, 1.0)));
            tris.push(Triangle::new(q(0.0, 0.0), q(1.0, 1.0), q(0.0, 1.0)));
        }
    }
    tris.extend(fan(DVec3::new(5.0, 5.0, 3.0), 0.5));
    let bvh = TriangleBvh::new(&tris);
    let grid = cam_verify::deviation::TriangleGrid::new(&tris).expect("a grid for 204 faces");
    let (mut checked, mut by_grid) = (0, 0);
    for k in 0..3000 {
        let p = DVec3::new(
            12.0 * rng.next() - 1.0,
            12.0 * rng.next() - 1.0,
            // Most a hair under or over the plate, as a gouge's entry point lies.
            if k % 3 == 0 {
                4.0 * rng.next() - 1.0
            } else {
                (rng.next() - 0.5) * 10f64.powf(-6.0 * rng.next())
            },
        );
        let d = bvh.nearest_within(p, 100.0).expect("within 100 mm");
        for r in [
            d,
            d * (1.0 + 1e-12),
            d * (1.0 - 1e-12),
            d * 1.5,
            d * 0.5,
            p.z.abs() * (1.0 - 1e-6),
        ] {
            let want = bvh.nearest_within(p, r).is_some();
            assert_eq!(bvh.any_within(p, r), want, "{p} r = {r} (nearest {d})");
            if let Some(g) = grid.any_within(p, r) {
                assert_eq!(g, want, "grid: {p} r = {r} (nearest {d})");
                by_grid += 1;
            }
            checked += usize::from(want);
        }
    }
    assert!(checked > 3000, "too few points within r: {checked}");
    assert!(by_grid > 9000, "too few answered by the grid: {by_grid}");
}

/// `TriangleBvh::nearest_within` against a dense sampling of each triangle: never farther
/// than the nearest sample, never nearer than it minus the sampling step.
#[test]
fn nearest_within_matches_sampled_distances() {
    use cam_verify::deviation::TriangleBvh;
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut rnd = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64 * 10.0 - 5.0
    };
    let tris: Vec<cam_core::Triangle> = (0..40)
        .map(|_| {
            let a = cam_core::DVec3::new(rnd(), rnd(), rnd());
            cam_core::Triangle::new(
                a,
                a + 0.4 * cam_core::DVec3::new(rnd(), rnd(), rnd()),
                a + 0.4 * cam_core::DVec3::new(rnd(), rnd(), rnd()),
            )
        })
        .collect();
    let bvh = TriangleBvh::new(&tris);
    let n = 120;
    for _ in 0..60 {
        let p = cam_core::DVec3::new(rnd(), rnd(), rnd());
        let (mut sampled, mut step) = (f64::INFINITY, 0.0f64);
        for t in &tris {
            let [a, b, c] = t.v;
            step = step.max((b - a).length().max((c - a).length()) / n as f64);
            for i in 0..=n {
                for j in 0..=n - i {
                    let q = a + (b - a) * (i as f64 / n as f64) + (c - a) * (j as f64 / n as f64);
                    sampled = sampled.min(p.distance(q));
                }
            }
        }
        let d = bvh.nearest_within(p, 100.0).expect("within 100 mm");
        assert!(d <= sampled + 1e-12, "{p}: {d} > sampled {sampled}");
        assert!(
            d >= sampled - 1.5 * step,
            "{p}: {d} < sampled {sampled} − step"
        );
        assert_eq!(
            bvh.nearest_within(p, d),
            None,
            "strictly nearer than itself"
        );
        assert!(bvh.nearest_within(p, d * (1.0 + 1e-9) + 1e-12).is_some());
    }
}
