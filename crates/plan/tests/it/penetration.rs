//! Exact, independent penetration of a ball cutter along cut moves: the ball's depth into the
//! part is `R − distance(centre, part)`, and the distance from a point to a triangle is in
//! closed form (Ericson, *Real-Time Collision Detection*, §5.1.5). Nothing here uses the
//! planner's bounds or the drop-cutter.

use cam_core::{DVec3, MoveKind, Toolpath};

/// Squared distance from `p` to the triangle `abc`.
pub fn point_triangle_dist2(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return ap.length_squared();
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return bp.length_squared();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (p - (a + ab * v)).length_squared();
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return cp.length_squared();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (p - (a + ac * w)).length_squared();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (p - (b + (c - b) * w)).length_squared();
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    (p - (a + ab * v + ac * w)).length_squared()
}

/// Largest depth (mm) by which a ball of radius `r` penetrates the triangles `tris` while its
/// tip moves along the pass cut moves of `tp`, sampled every `step` mm along each move.
pub fn ball_penetration(tris: &[[DVec3; 3]], r: f64, tp: &Toolpath, step: f64) -> f64 {
    use rayon::prelude::*;
    let moves: Vec<(DVec3, DVec3)> = tp
        .moves
        .windows(2)
        .filter(|w| w[1].kind == MoveKind::Cut && w[1].pass.is_some())
        .map(|w| (w[0].pose.tip, w[1].pose.tip))
        .collect();
    moves
        .par_iter()
        .map(|&(a, b)| {
            let (ca, cb) = (a + DVec3::Z * r, b + DVec3::Z * r);
            let (lo, hi) = (ca.min(cb) - DVec3::splat(r), ca.max(cb) + DVec3::splat(r));
            let near: Vec<&[DVec3; 3]> = tris
                .iter()
                .filter(|t| {
                    let tl = t[0].min(t[1]).min(t[2]);
                    let th = t[0].max(t[1]).max(t[2]);
                    tl.cmple(hi).all() && th.cmpge(lo).all()
                })
                .collect();
            let n = (a.distance(b) / step).ceil().max(1.0) as usize;
            (0..=n)
                .map(|k| {
                    let c = ca.lerp(cb, k as f64 / n as f64);
                    let d2 = near
                        .iter()
                        .map(|t| point_triangle_dist2(c, t[0], t[1], t[2]))
                        .fold(f64::INFINITY, f64::min);
                    r - d2.sqrt().min(r)
                })
                .fold(0.0, f64::max)
        })
        .reduce(|| 0.0, f64::max)
}

#[test]
fn point_triangle_distance_cases() {
    let (a, b, c) = (DVec3::ZERO, DVec3::X * 2.0, DVec3::Y * 2.0);
    let d = |p: DVec3| point_triangle_dist2(p, a, b, c).sqrt();
    assert!((d(DVec3::new(0.5, 0.5, 3.0)) - 3.0).abs() < 1e-15); // face
    assert!((d(DVec3::new(-1.0, -1.0, 0.0)) - 2f64.sqrt()).abs() < 1e-15); // vertex
    assert!((d(DVec3::new(1.0, -2.0, 0.0)) - 2.0).abs() < 1e-15); // edge ab
    assert!((d(DVec3::new(2.0, 2.0, 0.0)) - 2f64.sqrt()).abs() < 1e-15); // edge bc
}
