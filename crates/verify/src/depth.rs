//! Depth of a point inside the volume a 3-axis cutter sweeps along a toolpath, by direct
//! search over the moves: an independent check of a planned program (it shares no code
//! with the imprint sweep, the locator or the exact refinement), used by the planner's
//! tests and `cargo xtask plan-report` where a vertical z-map depth over-states the
//! penetration (the cutter's surface is steep there).

use cam_core::{Cutter, CutterKind, DVec3, Toolpath};

/// The moves of a 3-axis toolpath bucketed by XY cells, for the depth of points inside the
/// volume the cutter sweeps along them (every move, rapids included).
#[derive(Debug, Clone)]
pub struct SweptDepth {
    cutter: Cutter,
    moves: Vec<(DVec3, DVec3)>,
    cell: f64,
    x0: f64,
    y0: f64,
    nx: usize,
    ny: usize,
    buckets: Vec<Vec<u32>>,
}

impl SweptDepth {
    /// Indexes the moves of `tp` (tool tips, axis +Z) for `cutter`.
    pub fn new(tp: &Toolpath, cutter: &Cutter) -> SweptDepth {
        let reach = cutter.radius();
        let moves: Vec<(DVec3, DVec3)> = tp
            .moves
            .windows(2)
            .map(|w| (w[0].pose.tip, w[1].pose.tip))
            .collect();
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for &(a, b) in &moves {
            lo = lo.min(a).min(b);
            hi = hi.max(a).max(b);
        }
        let cell = reach.max(1.0);
        let (x0, y0) = (lo.x - reach, lo.y - reach);
        let nx = (((hi.x + reach - x0) / cell).ceil() as usize).max(1);
        let ny = (((hi.y + reach - y0) / cell).ceil() as usize).max(1);
        let mut buckets = vec![Vec::new(); nx * ny];
        let ci = |v: f64, o: f64, n: usize| (((v - o) / cell).floor().max(0.0) as usize).min(n - 1);
        for (k, &(a, b)) in moves.iter().enumerate() {
            let (l, h) = (a.min(b), a.max(b));
            for j in ci(l.y - reach, y0, ny)..=ci(h.y + reach, y0, ny) {
                for i in ci(l.x - reach, x0, nx)..=ci(h.x + reach, x0, nx) {
                    buckets[j * nx + i].push(k as u32);
                }
            }
        }
        SweptDepth {
            cutter: *cutter,
            moves,
            cell,
            x0,
            y0,
            nx,
            ny,
            buckets,
        }
    }

    /// Depth (mm) of `p` in the volume a flat end mill of radius `rr` sweeps along the moves,
    /// at least the exact depth: the largest over the moves of the depth in each move's convex
    /// swept volume, each the least `max(a·u, b·u) + rr·|u_xy| − p·u` over unit directions `u`
    /// with `u_z ≤ 0` (a grid of directions, then a local refinement about the best one).
    fn flat_depth(&self, p: DVec3) -> f64 {
        let rr = self.cutter.radius();
        let i = (((p.x - self.x0) / self.cell).floor().max(0.0) as usize).min(self.nx - 1);
        let j = (((p.y - self.y0) / self.cell).floor().max(0.0) as usize).min(self.ny - 1);
        let dir = |az: f64, el: f64| {
            let (se, ce) = el.sin_cos();
            DVec3::new(ce * az.cos(), ce * az.sin(), -se)
        };
        let mut depth = f64::NEG_INFINITY;
        for &k in &self.buckets[j * self.nx + i] {
            let (a, b) = self.moves[k as usize];
            // Only a move whose flat bottom passes below p at p's XY contains it: the bottom
            // is at the tip's z wherever the tip is within rr of p in XY.
            let d = b.truncate() - a.truncate();
            let w = p.truncate() - a.truncate();
            let dd = d.length_squared();
            let (t0, t1) = if dd < 1e-24 {
                if w.length_squared() > rr * rr {
                    continue;
                }
                (0.0, 1.0)
            } else {
                let tc = w.dot(d) / dd;
                let perp2 = (w - d * tc).length_squared();
                if perp2 > rr * rr {
                    continue;
                }
                let half = ((rr * rr - perp2) / dd).sqrt();
                ((tc - half).max(0.0), (tc + half).min(1.0))
            };
            if t0 > t1 || a.z + (b.z - a.z) * t0 >= p.z && a.z + (b.z - a.z) * t1 >= p.z {
                continue;
            }
            let f = |az: f64, el: f64| {
                let u = dir(az, el.clamp(0.0, std::f64::consts::FRAC_PI_2));
                a.dot(u).max(b.dot(u)) + rr * (u.x * u.x + u.y * u.y).sqrt() - p.dot(u)
            };
            // Grid, then a pattern search (axis and diagonal steps, which follow the ridge
            // where the two end points' planes meet) from each of the best few grid
            // directions: the function is convex in u ∈ R³ but not on the sphere.
            const NA: usize = 180;
            const NE: usize = 45;
            let mut grid: Vec<(f64, f64, f64)> = Vec::with_capacity(NA * (NE + 1));
            for ia in 0..NA {
                for ie in 0..=NE {
                    let (az, el) = (
                        ia as f64 * std::f64::consts::TAU / NA as f64,
                        ie as f64 * std::f64::consts::FRAC_PI_2 / NE as f64,
                    );
                    grid.push((f(az, el), az, el));
                }
            }
            grid.sort_by(|x, y| x.0.total_cmp(&y.0));
            let mut best = f64::INFINITY;
            for &(v0, az0, el0) in grid.iter().take(4) {
                let (mut v, mut az, mut el) = (v0, az0, el0);
                let mut step = std::f64::consts::TAU / NA as f64;
                while step > 1e-9 {
                    let mut moved = false;
                    for (da, de) in [
                        (1.0, 0.0),
                        (-1.0, 0.0),
                        (0.0, 1.0),
                        (0.0, -1.0),
                        (1.0, 1.0),
                        (1.0, -1.0),
                        (-1.0, 1.0),
                        (-1.0, -1.0),
                    ] {
                        let e = (el + de * step).clamp(0.0, std::f64::consts::FRAC_PI_2);
                        let w = f(az + da * step, e);
                        if w < v {
                            (v, az, el) = (w, az + da * step, e);
                            moved = true;
                        }
                    }
                    if !moved {
                        step *= 0.5;
                    }
                }
                best = best.min(v);
            }
            depth = depth.max(best);
        }
        depth
    }

    /// Depth (mm) of `p` inside the swept volume; negative outside (`−∞` beyond every
    /// move's reach). Ball and bull: exact, `r` minus the distance from `p` to the swept
    /// core (the ring of corner centres), convex along each move, so ternary search
    /// converges to it. Flat end mill: the support-function search of `flat_depth`, at
    /// least the exact depth, to its convergence.
    pub fn depth(&self, p: DVec3) -> f64 {
        if self.cutter.kind() == CutterKind::Flat {
            return self.flat_depth(p);
        }
        let (a, r) = (self.cutter.major_radius(), self.cutter.corner_radius());
        let i = (((p.x - self.x0) / self.cell).floor().max(0.0) as usize).min(self.nx - 1);
        let j = (((p.y - self.y0) / self.cell).floor().max(0.0) as usize).min(self.ny - 1);
        let dist = |tip: DVec3| {
            let q = p - (tip + DVec3::Z * r);
            let rad = (q.x * q.x + q.y * q.y).sqrt();
            ((rad - a).max(0.0).powi(2) + q.z * q.z).sqrt()
        };
        let mut depth = f64::NEG_INFINITY;
        for &k in &self.buckets[j * self.nx + i] {
            let (s, e) = self.moves[k as usize];
            let (mut t0, mut t1) = (0.0f64, 1.0f64);
            for _ in 0..100 {
                let m1 = t0 + (t1 - t0) / 3.0;
                let m2 = t1 - (t1 - t0) / 3.0;
                if dist(s.lerp(e, m1)) <= dist(s.lerp(e, m2)) {
                    t1 = m2;
                } else {
                    t0 = m1;
                }
            }
            let d = dist(s.lerp(e, 0.5 * (t0 + t1))).min(dist(s)).min(dist(e));
            depth = depth.max(r - d);
        }
        depth
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cam_core::{Move, MoveKind, Pose};

    fn path(tips: &[DVec3]) -> Toolpath {
        Toolpath {
            moves: tips
                .iter()
                .map(|&t| Move {
                    kind: MoveKind::Cut,
                    pose: Pose::vertical(t),
                    feed_mm_per_min: None,
                    line: None,
                    pass: None,
                })
                .collect(),
        }
    }

    /// A ball along a sloped line: the swept volume is a capsule of radius R about the
    /// centres' segment, so the depth is R minus the distance to that segment.
    #[test]
    fn ball_depth_is_the_capsule_depth() {
        let (a, b) = (DVec3::new(0.0, 0.0, 0.0), DVec3::new(10.0, 0.0, 2.0));
        let d = SweptDepth::new(&path(&[a, b]), &"ball:6".parse().unwrap());
        let (ca, cb) = (a + 3.0 * DVec3::Z, b + 3.0 * DVec3::Z);
        for p in [
            DVec3::new(5.0, 1.0, 1.0),
            DVec3::new(5.0, -2.5, 2.9),
            DVec3::new(-1.0, 0.5, 1.0),
            DVec3::new(11.5, 0.0, 4.0),
            DVec3::new(5.0, 2.9, 0.0),
        ] {
            let t = ((p - ca).dot(cb - ca) / (cb - ca).length_squared()).clamp(0.0, 1.0);
            let want = 3.0 - p.distance(ca.lerp(cb, t));
            assert!(
                (d.depth(p) - want).abs() < 1e-9,
                "{p}: {} vs {want}",
                d.depth(p)
            );
        }
    }

    /// A flat end mill along a level line: the swept volume is the slab-sided box-with-round-
    /// ends above the tip's z; a point inside it is as deep as its distance to the nearest
    /// side (bottom, flank or round end).
    #[test]
    fn flat_depth_is_the_nearest_side() {
        let d = SweptDepth::new(
            &path(&[DVec3::ZERO, DVec3::new(10.0, 0.0, 0.0)]),
            &"flat:6".parse().unwrap(),
        );
        // Bottom nearest: 0.2 above it, 2 from the flank.
        assert!((d.depth(DVec3::new(5.0, 1.0, 0.2)) - 0.2).abs() < 1e-6);
        // Flank nearest: 0.3 inside it, 1 above the bottom.
        assert!((d.depth(DVec3::new(5.0, 2.7, 1.0)) - 0.3).abs() < 1e-6);
        // Round end nearest: 0.5 inside the disc at the end, 2 above the bottom.
        assert!((d.depth(DVec3::new(12.5, 0.0, 2.0)) - 0.5).abs() < 1e-6);
        // Outside: below the bottom.
        assert!(d.depth(DVec3::new(5.0, 0.0, -0.1)) < 0.0);
    }
}
