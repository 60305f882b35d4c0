//! Drop-cutter against a brute-force reference on random meshes.
//!
//! The reference samples the contact problem densely: every sampled pair (a point of the
//! cutter's lower surface above a point of a triangle, or a sampled point of an edge under
//! the cutter) is a real constraint, so the reference is a LOWER bound of the exact height:
//! `exact >= brute - 1e-9` must hold sharply (otherwise the cutter would penetrate). The
//! sampling error above the reference is bounded a priori: contacts on facets and edges of
//! ball and bull cutters are stationary points (error second order in the sample spacing),
//! flat-cutter edge contacts sit at the rim (first order: edge spacing × slope).

use cam_core::{Cutter, DVec3, Triangle};
use cam_offset::DropCutter;

use crate::support::{Rng, cutters, mesh};

const EDGE_STEP: f64 = 2e-4; // mm between sampled edge points
const N_ANG: usize = 720;
const N_RAD: usize = 240;

fn ray_z(t: &Triangle, x: f64, y: f64) -> Option<f64> {
    let [a, b, c] = t.v;
    let det = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
    if det.abs() < 1e-14 {
        return None;
    }
    let l1 = ((x - a.x) * (c.y - a.y) - (c.x - a.x) * (y - a.y)) / det;
    let l2 = ((b.x - a.x) * (y - a.y) - (x - a.x) * (b.y - a.y)) / det;
    (l1 >= 0.0 && l2 >= 0.0 && l1 + l2 <= 1.0).then_some(a.z + l1 * (b.z - a.z) + l2 * (c.z - a.z))
}

fn brute(tris: &[Triangle], c: &Cutter, x: f64, y: f64) -> Option<f64> {
    let big_r = c.radius();
    let mut best: Option<f64> = None;
    let mut put = |z: f64| best = Some(best.map_or(z, |b: f64| b.max(z)));
    let point = |p: DVec3| {
        let d = ((p.x - x).powi(2) + (p.y - y).powi(2)).sqrt();
        c.height_at(d).map(|h| p.z - h)
    };
    for t in tris {
        for k in 0..3 {
            let (p, q) = (t.v[k], t.v[(k + 1) % 3]);
            let n = ((q - p).length() / EDGE_STEP).ceil() as usize;
            for i in 0..=n {
                if let Some(z) = point(p + (q - p) * (i as f64 / n as f64)) {
                    put(z);
                }
            }
        }
        for i in 0..=N_RAD {
            let rho = big_r * i as f64 / N_RAD as f64;
            let h = c.height_at(rho).unwrap();
            let n_ang = if i == 0 { 1 } else { N_ANG };
            for j in 0..n_ang {
                let ang = std::f64::consts::TAU * j as f64 / N_ANG as f64;
                if let Some(z) = ray_z(t, x + rho * ang.cos(), y + rho * ang.sin()) {
                    put(z - h);
                }
            }
        }
    }
    best
}

fn random_mesh(rng: &mut Rng, n: usize) -> (Vec<Triangle>, f64) {
    let mut tris = Vec::new();
    let mut max_slope: f64 = 0.0;
    while tris.len() < n {
        let c = DVec3::new(
            rng.range(-5.0, 5.0),
            rng.range(-5.0, 5.0),
            rng.range(0.0, 2.0),
        );
        let mut p = || {
            c + DVec3::new(
                rng.range(-3.0, 3.0),
                rng.range(-3.0, 3.0),
                rng.range(-1.5, 1.5),
            )
        };
        let t = Triangle::new(p(), p(), p());
        if t.is_degenerate() || t.area() < 0.5 {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (t.v[k], t.v[(k + 1) % 3]);
            let xy = ((b.x - a.x).powi(2) + (b.y - a.y).powi(2)).sqrt();
            if xy > 0.3 {
                max_slope = max_slope.max((b.z - a.z).abs() / xy);
            } else {
                max_slope = f64::INFINITY; // steep edge: tolerance bound not applicable
            }
        }
        if max_slope.is_infinite() {
            max_slope = 0.0;
            tris.clear();
            continue;
        }
        tris.push(t);
    }
    (tris, max_slope)
}

#[test]
fn random_meshes_against_brute_force() {
    let mut rng = Rng(2026);
    let mut worst_gap: f64 = 0.0;
    let mut checked = 0;
    for round in 0..3 {
        let (tris, max_slope) = random_mesh(&mut rng, 4);
        let m = mesh(tris.clone());
        for c in cutters() {
            let dc = DropCutter::new(&m, c);
            // Second-order sampling error of stationary contacts is far below this; the
            // first-order term is a flat cutter's rim on an edge.
            let tol = EDGE_STEP * max_slope + 2e-5;
            for _ in 0..6 {
                let (x, y) = (rng.range(-7.0, 7.0), rng.range(-7.0, 7.0));
                let exact = dc.drop(x, y);
                let reference = brute(&tris, &c, x, y);
                match (exact, reference) {
                    (None, None) => {}
                    (Some(e), Some(b)) => {
                        assert!(
                            e >= b - 1e-9,
                            "round {round} {c} at {x},{y}: exact {e} below brute {b}: penetration"
                        );
                        assert!(
                            e - b <= tol,
                            "round {round} {c} at {x},{y}: exact {e} above brute {b} by {} > {tol}",
                            e - b
                        );
                        worst_gap = worst_gap.max(e - b);
                        checked += 1;
                    }
                    (e, b) => panic!("round {round} {c} at {x},{y}: exact {e:?} vs brute {b:?}"),
                }
            }
        }
    }
    assert!(checked > 40, "too few contacts checked: {checked}");
    eprintln!("brute force: {checked} contacts, max exact - brute = {worst_gap:.3e} mm");
}
