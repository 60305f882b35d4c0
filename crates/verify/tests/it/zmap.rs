//! The independent z-map: analytic grooves, scallops and sloped moves for ball, bull and flat
//! cutters, a brute-force minimiser for arbitrary nodes, and the comparison with a part.

use cam_core::{Cutter, DVec3, Mesh, Move, MoveKind, Pose, Toolpath, Triangle};
use cam_verify::zmap::{self, DesignHeights, ZmapConfig, ZmapError, ZmapGrid};

fn path(points: &[(f64, f64, f64)]) -> Toolpath {
    path_kinds(
        &points
            .iter()
            .map(|&p| (p, MoveKind::Cut))
            .collect::<Vec<_>>(),
    )
}

fn path_kinds(points: &[((f64, f64, f64), MoveKind)]) -> Toolpath {
    Toolpath {
        moves: points
            .iter()
            .enumerate()
            .map(|(i, &((x, y, z), kind))| Move {
                kind,
                pose: Pose::vertical(DVec3::new(x, y, z)),
                feed_mm_per_min: None,
                line: Some(i + 1),
                pass: None,
            })
            .collect(),
    }
}

fn grid(x0: f64, y0: f64, x1: f64, y1: f64, res: f64) -> ZmapConfig {
    ZmapConfig::new(ZmapGrid::covering(x0, y0, x1, y1, res).unwrap())
}

/// Cross-section of the groove cut by a horizontal pass: the cutter profile itself.
fn profile(c: &Cutter, y: f64) -> Option<f64> {
    c.height_at(y.abs())
}

fn check_groove(c: &Cutter) {
    let tp = path(&[(-10.0, 0.0, 0.0), (10.0, 0.0, 0.0)]);
    let cfg = grid(-2.0, -6.0, 2.0, 6.0, 0.125);
    let z = zmap::machine(&tp, c, &cfg).unwrap();
    let g = z.grid;
    let mut cut = 0;
    for j in 0..g.ny {
        for i in 0..g.nx {
            let h = z.height(i, j);
            match profile(c, g.y(j)) {
                Some(want) => {
                    cam_core::assert_near!(h, want, 1e-9, "{c} at y = {}", g.y(j));
                    cut += 1;
                }
                None => assert_eq!(h, f64::INFINITY),
            }
        }
    }
    assert!(cut > 0);
}

#[test]
fn single_pass_grooves_are_the_cutter_profile() {
    for c in ["ball:6", "bull:10:2", "flat:10", "bull:8:1.5"] {
        check_groove(&c.parse().unwrap());
    }
}

#[test]
fn scallops_between_two_passes() {
    // Passes at y = 0 and y = w, linked at x = 10 (out of the checked region).
    let cases: [(&str, f64, f64); 3] = [
        // ball R = 3, w = 1.2: h = R − sqrt(R² − (w/2)²).
        ("ball:6", 1.2, 3.0 - (9.0f64 - 0.36).sqrt()),
        // bull R = 5, a = 3, r = 2, w = 7.6: h = r − sqrt(r² − (w/2 − a)²).
        ("bull:10:2", 7.6, 2.0 - (4.0f64 - 0.64).sqrt()),
        // flat: passes 10 apart leave nothing between their rims.
        ("flat:10", 9.0, 0.0),
    ];
    for (spec, w, h) in cases {
        let c: Cutter = spec.parse().unwrap();
        let tp = path(&[
            (-10.0, 0.0, 0.0),
            (10.0, 0.0, 0.0),
            (10.0, w, 0.0),
            (-10.0, w, 0.0),
        ]);
        // Rows at y = 0, w/8, …, w: w/2 is a node.
        let cfg = grid(-2.0, 0.0, 2.0, w, w / 8.0);
        let z = zmap::machine(&tp, &c, &cfg).unwrap();
        let g = z.grid;
        assert_eq!(g.ny, 9);
        for j in 0..g.ny {
            let y = g.y(j);
            let want = [profile(&c, y), profile(&c, y - w)]
                .into_iter()
                .flatten()
                .reduce(f64::min)
                .unwrap();
            for i in 0..g.nx {
                cam_core::assert_near!(z.height(i, j), want, 1e-9, "{spec} at y = {y}");
            }
        }
        for i in 0..g.nx {
            cam_core::assert_near!(z.height(i, 4), h, 1e-9, "{spec} scallop");
        }
    }
}

#[test]
fn sloped_moves_match_closed_forms() {
    // Move from (−10, 0, −2) to (10, 0, 2): slope m = 0.2, z_line(x) = m·x.
    let m: f64 = 0.2;
    let tp = path(&[(-10.0, 0.0, -2.0), (10.0, 0.0, 2.0)]);
    let cfg = grid(-3.0, -6.0, 3.0, 6.0, 0.25);
    let k = (1.0 + m * m).sqrt();
    // Ball R: m·x + R − sqrt(1+m²)·sqrt(R² − y²).
    let ball: Cutter = "ball:6".parse().unwrap();
    let z = zmap::machine(&tp, &ball, &cfg).unwrap();
    // Flat R: m·x − m·sqrt(R² − y²) (the trailing rim).
    let flat: Cutter = "flat:10".parse().unwrap();
    let zf = zmap::machine(&tp, &flat, &cfg).unwrap();
    // Bull on the centre line (y = 0): m·x − m·a + r − r·sqrt(1+m²).
    let bull: Cutter = "bull:10:2".parse().unwrap();
    let zb = zmap::machine(&tp, &bull, &cfg).unwrap();
    let g = z.grid;
    for j in 0..g.ny {
        let y = g.y(j);
        for i in 0..g.nx {
            let x = g.x(i);
            if y.abs() <= 3.0 {
                cam_core::assert_near!(
                    z.height(i, j),
                    m * x + 3.0 - k * (9.0 - y * y).sqrt(),
                    1e-9,
                    "ball ({x}, {y})"
                );
            }
            if y.abs() <= 5.0 {
                cam_core::assert_near!(
                    zf.height(i, j),
                    m * x - m * (25.0 - y * y).sqrt(),
                    1e-9,
                    "flat ({x}, {y})"
                );
            }
            if y == 0.0 {
                cam_core::assert_near!(
                    zb.height(i, j),
                    m * x - m * 3.0 + 2.0 - 2.0 * k,
                    1e-9,
                    "bull ({x}, 0)"
                );
            }
        }
    }
}

/// Independent minimiser: the reach interval from the quadratic |q − p(t)|² = R², then a
/// golden-section search on f(t) built from `Cutter::height_at` (f is convex there).
fn brute_min(c: &Cutter, q: (f64, f64), a: DVec3, b: DVec3) -> Option<f64> {
    let rr = c.radius();
    let f = |t: f64| {
        let p = a + t * (b - a);
        let d = ((q.0 - p.x).powi(2) + (q.1 - p.y).powi(2)).sqrt().min(rr);
        p.z + c.height_at(d).unwrap()
    };
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let (wx, wy) = (a.x - q.0, a.y - q.1);
    let qa = dx * dx + dy * dy;
    let qb = 2.0 * (dx * wx + dy * wy);
    let qc = wx * wx + wy * wy - rr * rr;
    let disc = qb * qb - 4.0 * qa * qc;
    if disc < 0.0 {
        return None;
    }
    let lo = ((-qb - disc.sqrt()) / (2.0 * qa)).max(0.0);
    let hi = ((-qb + disc.sqrt()) / (2.0 * qa)).min(1.0);
    if lo > hi {
        return None;
    }
    let (mut l, mut h) = (lo, hi);
    let g = (5f64.sqrt() - 1.0) / 2.0;
    for _ in 0..200 {
        let m1 = h - g * (h - l);
        let m2 = l + g * (h - l);
        if f(m1) <= f(m2) { h = m2 } else { l = m1 }
    }
    Some(f(0.5 * (l + h)).min(f(lo)).min(f(hi)))
}

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

#[test]
fn arbitrary_moves_match_brute_force() {
    let mut g = Lcg(7);
    for spec in ["ball:6", "bull:10:2", "flat:8", "bull:6:0.5"] {
        let c: Cutter = spec.parse().unwrap();
        for _ in 0..12 {
            let a = DVec3::new(
                g.next() * 8.0 - 4.0,
                g.next() * 8.0 - 4.0,
                g.next() * 4.0 - 2.0,
            );
            let b = a + DVec3::new(
                g.next() * 8.0 - 4.0,
                g.next() * 8.0 - 4.0,
                g.next() * 6.0 - 3.0,
            );
            let tp = path(&[(a.x, a.y, a.z), (b.x, b.y, b.z)]);
            let cfg = grid(-8.0, -8.0, 8.0, 8.0, 1.0);
            let z = zmap::machine(&tp, &c, &cfg).unwrap();
            let gr = z.grid;
            for j in 0..gr.ny {
                for i in 0..gr.nx {
                    let want = brute_min(&c, (gr.x(i), gr.y(j)), a, b).unwrap_or(f64::INFINITY);
                    let got = z.height(i, j);
                    if want.is_finite() || got.is_finite() {
                        cam_core::assert_near!(
                            got,
                            want,
                            1e-9,
                            "{spec} {a:?}->{b:?} node ({}, {})",
                            gr.x(i),
                            gr.y(j)
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn vertical_moves_rapids_and_stock() {
    let ball: Cutter = "ball:6".parse().unwrap();
    // Plunge from z = 5 to −1 at the origin: the ball's bottom at −1.
    let tp = path_kinds(&[
        ((0.0, 0.0, 5.0), MoveKind::Rapid),
        ((0.0, 0.0, -1.0), MoveKind::Plunge),
    ]);
    let cfg = grid(-4.0, -4.0, 4.0, 4.0, 1.0);
    let z = zmap::machine(&tp, &ball, &cfg).unwrap();
    let g = z.grid;
    cam_core::assert_near!(z.height(4 + 1, 4), -1.0 + 3.0 - 8f64.sqrt(), 1e-12);
    cam_core::assert_near!(z.height(4, 4), -1.0, 1e-12);
    assert_eq!(z.lowered_by[4 * g.nx + 4], Some(1));
    // A rapid through the material is swept too.
    let tp = path_kinds(&[
        ((-5.0, 0.0, 1.0), MoveKind::Rapid),
        ((5.0, 0.0, -0.5), MoveKind::Rapid),
    ]);
    let z = zmap::machine(&tp, &ball, &cfg).unwrap();
    assert!(z.height(4, 4) < 0.3);
    // Stock top at 0: moves above it do not lower anything.
    let tp = path(&[(-5.0, 0.0, 0.5), (5.0, 0.0, 0.5)]);
    let z = zmap::machine(
        &tp,
        &ball,
        &ZmapConfig {
            stock_top_mm: 0.0,
            ..cfg
        },
    )
    .unwrap();
    assert!(z.heights.iter().all(|&h| h == 0.0) && z.lowered_by.iter().all(Option::is_none));
    // 5-axis input is refused.
    let mut tp = path(&[(0.0, 0.0, 0.0)]);
    tp.moves[0].pose.axis = DVec3::new(0.0, 0.6, 0.8);
    assert!(matches!(
        zmap::machine(&tp, &ball, &cfg),
        Err(ZmapError::NotVertical { index: 0, .. })
    ));
    assert!(ZmapGrid::covering(0.0, 0.0, 1.0, 1.0, 0.0).is_err());
}

fn plane(z: impl Fn(f64, f64) -> f64, x0: f64, x1: f64) -> Mesh {
    let p = |x: f64, y: f64| DVec3::new(x, y, z(x, y));
    Mesh::from_triangles(
        vec![
            Triangle::new(p(x0, x0), p(x1, x0), p(x1, x1)),
            Triangle::new(p(x0, x0), p(x1, x1), p(x0, x1)),
        ],
        "<memory>",
    )
    .unwrap()
}

#[test]
fn design_heights_are_exact() {
    let m = plane(|x, y| 0.3 * x + 0.1 * y + 1.0, -5.0, 5.0);
    let dh = DesignHeights::new(&m);
    for k in 0..=40 {
        let (x, y) = (-5.0 + 0.25 * k as f64, 5.0 - 0.21 * k as f64);
        cam_core::assert_near!(dh.top(x, y).unwrap().0, 0.3 * x + 0.1 * y + 1.0, 1e-12);
    }
    assert!(dh.top(5.5, 0.0).is_none());
    // Two layers: the top one wins.
    let mut t = m.triangles().to_vec();
    t.extend(plane(|_, _| 7.0, -1.0, 1.0).triangles());
    let dh = DesignHeights::new(&Mesh::from_triangles(t, "<memory>").unwrap());
    assert_eq!(dh.top(0.5, -0.5).unwrap().0, 7.0);
}

#[test]
fn comparison_finds_scallop_and_gouge() {
    let part = plane(|_, _| 0.0, -5.0, 5.0);
    let ball: Cutter = "ball:6".parse().unwrap();
    // Zig-zag passes at y = −6..6 step 1 at z = 0, then a plunge to −0.1 at (1, 1).
    let mut pts = Vec::new();
    for k in 0..=12 {
        let y = -6.0 + k as f64;
        let (xa, xb) = if k % 2 == 0 { (-9.0, 9.0) } else { (9.0, -9.0) };
        pts.push((xa, y, 0.0));
        pts.push((xb, y, 0.0));
    }
    pts.extend([
        (9.0, 6.0, 5.0),
        (1.0, 1.0, 5.0),
        (1.0, 1.0, -0.1),
        (1.0, 1.0, 5.0),
    ]);
    let tp = path(&pts);
    let cfg = grid(-6.0, -6.0, 6.0, 6.0, 0.25);
    let z = zmap::machine(&tp, &ball, &cfg).unwrap();
    let c = zmap::compare_with_part(&z, &part);
    assert_eq!(c.nodes.len(), 41 * 41);
    assert_eq!(c.unmachined, 0);
    cam_core::assert_near!(c.max_gouge_mm, 0.1, 1e-12);
    let g = c.max_gouge_at.unwrap();
    assert_eq!((z.grid.x(g.i as usize), z.grid.y(g.j as usize)), (1.0, 1.0));
    assert_eq!(g.source_move as usize, pts.len() - 2);
    cam_core::assert_near!(c.max_excess_mm, 3.0 - (9.0f64 - 0.25).sqrt(), 1e-9);
    let e = c.max_excess_at.unwrap();
    cam_core::assert_near!(z.grid.y(e.j as usize).rem_euclid(1.0), 0.5, 1e-12);
    // Same result on one thread.
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let z1 = one.install(|| zmap::machine(&tp, &ball, &cfg).unwrap());
    assert_eq!(z, z1);
}

/// The z-map at arbitrary points gives the grid's values at its nodes, bit for bit, and the
/// same lowering moves.
#[test]
fn heights_at_points_equal_the_grid() {
    let mut g = Lcg(11);
    let mut pts = Vec::new();
    for _ in 0..40 {
        pts.push((
            g.next() * 16.0 - 8.0,
            g.next() * 16.0 - 8.0,
            g.next() * 4.0 - 2.0,
        ));
    }
    let tp = path(&pts);
    for spec in ["ball:6", "bull:10:2", "flat:8"] {
        let c: Cutter = spec.parse().unwrap();
        let cfg = grid(-10.0, -10.0, 10.0, 10.0, 0.5);
        let z = zmap::machine(&tp, &c, &cfg).unwrap();
        let gr = z.grid;
        let nodes: Vec<(f64, f64)> = (0..gr.ny)
            .flat_map(|j| (0..gr.nx).map(move |i| (gr.x(i), gr.y(j))))
            .collect();
        let at = zmap::heights_at(&tp, &c, &nodes).unwrap();
        for (k, h) in at.iter().enumerate() {
            match (h, z.lowered_by[k]) {
                (Some((hz, mv)), Some(lm)) => {
                    assert_eq!(*hz, z.heights[k], "{spec} node {k}");
                    assert_eq!(*mv, lm, "{spec} node {k}");
                }
                (None, None) => {}
                other => panic!("{spec} node {k}: {other:?}"),
            }
        }
    }
}
