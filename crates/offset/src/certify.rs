//! Certificates about the CL surface between exact samples, for planners that must bound
//! the CL surface along a straight move without dropping the cutter everywhere on it.
//!
//! * [`DropCutter::triangle_drop`]: the drop onto one triangle alone. It is a **lower bound**
//!   of the CL surface everywhere, and along any straight line it is a **concave** function
//!   (the triangle's Minkowski sum with the reflected cutter is convex), so the pieces of
//!   two neighbouring samples bound how far the CL surface can dip between them.
//! * [`DropCutter::plane_certificate`]: along a segment whose samples rest on one plane,
//!   how far any triangle within reach rises above that plane (an **upper bound** of the
//!   CL surface) and whether coplanar facets carry the contact all the way (a lower bound).

use cam_core::DVec3;

use crate::contact;
use crate::index::DropCutter;

/// What [`DropCutter::plane_certificate`] proved about the CL surface along a segment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneCertificate {
    /// Largest height (mm, along the plane's normal) by which any triangle within the
    /// cutter's reach of the segment rises above the plane; 0 if none does. The CL surface
    /// along the segment is at most `rise_mm / n.z` above the plane's CL (vertically).
    pub rise_mm: f64,
    /// The contact track (where the cutter resting on the plane would touch it) lies on
    /// coplanar triangles (within [`COPLANAR_MM`]) the whole way, so the CL surface is at
    /// least the plane's CL minus `COPLANAR_MM / n.z` along the segment.
    pub covered: bool,
}

/// A triangle whose vertices are all within this distance (mm) of a plane counts as lying
/// in it.
pub const COPLANAR_MM: f64 = 1e-9;

impl DropCutter {
    /// Tool-tip z (mm) of the cutter at `(x, y)` resting on the mesh triangle `triangle`
    /// alone (its vertices, edges and face), `None` if the triangle is out of reach or the
    /// index is out of range. A lower bound of [`DropCutter::drop`] everywhere, equal to it
    /// where this triangle carries the contact, and concave along every straight line.
    pub fn triangle_drop(&self, triangle: u32, x: f64, y: f64) -> Option<f64> {
        let slot = *self.slot_of.get(triangle as usize)? as usize;
        let t = &self.tris[slot];
        let pf = &self.pf;
        let mut best = f64::NEG_INFINITY;
        for &p in &t.v {
            if let Some((z, _)) = contact::vertex(pf, x, y, p) {
                best = best.max(z);
            }
        }
        if t.n.z > 1e-12
            && let Some((z, _)) = contact::facet(pf, x, y, &t.v, t.n)
        {
            best = best.max(z);
        }
        for k in 0..3 {
            if let Some((z, _)) = contact::edge(pf, x, y, t.v[k], t.v[(k + 1) % 3], best) {
                best = best.max(z);
            }
        }
        best.is_finite().then_some(best)
    }

    /// The upward unit normal of mesh triangle `triangle` (as the drop-cutter uses it).
    pub fn triangle_normal(&self, triangle: u32) -> Option<DVec3> {
        let slot = *self.slot_of.get(triangle as usize)? as usize;
        Some(self.tris[slot].n)
    }

    /// Certificate for the cutter moving in XY from `a` to `b` over the plane
    /// `{p : n·p = d}` (`n` a unit normal with `n.z > 0`, mm): every triangle that can come
    /// within the cutter radius of the segment is examined. Returns `None` as soon as one
    /// rises more than `max_rise_mm` above the plane (along `n`), else the largest rise and
    /// whether coplanar triangles carry the contact track (see [`PlaneCertificate`]).
    ///
    /// Exact: the cutter at any point of the segment can only touch material within its
    /// radius, all of which lies below the plane shifted by the rise.
    pub fn plane_certificate(
        &self,
        a: (f64, f64),
        b: (f64, f64),
        n: DVec3,
        d: f64,
        max_rise_mm: f64,
    ) -> Option<PlaneCertificate> {
        if !(n.z > 1e-12 && n.is_finite() && d.is_finite()) {
            return None;
        }
        let pf = &self.pf;
        let big_r = pf.big_r;
        // Where the cutter resting on the plane touches it, relative to the tip (XY).
        let nxy = (n.x * n.x + n.y * n.y).sqrt();
        let (ox, oy) = if nxy <= 1e-15 {
            (0.0, 0.0)
        } else {
            let k = pf.a / nxy + pf.r;
            (-k * n.x, -k * n.y)
        };
        let (ca, cb) = ((a.0 + ox, a.1 + oy), (b.0 + ox, b.1 + oy));
        let (x0, x1) = (a.0.min(b.0), a.0.max(b.0));
        let (y0, y1) = (a.1.min(b.1), a.1.max(b.1));
        let mut rise = 0.0f64;
        let mut cover: Vec<(f64, f64)> = Vec::new();
        let reach_box = (x0 - big_r, y0 - big_r, x1 + big_r, y1 + big_r);
        let seg = (b.0 - a.0, b.1 - a.1);
        let seg_len2 = seg.0 * seg.0 + seg.1 * seg.1;
        for (c, (rx0, ry0, rx1, ry1)) in self.cells_on_segment(a, b) {
            // Lowest the plane gets over the cell grown by R: a triangle whose top is
            // below it lies under the plane (and is not coplanar).
            let gx = [rx0 - big_r, rx1 + big_r];
            let gy = [ry0 - big_r, ry1 + big_r];
            let mut plane_lo = f64::INFINITY;
            for &x in &gx {
                for &y in &gy {
                    plane_lo = plane_lo.min((d - n.x * x - n.y * y) / n.z);
                }
            }
            let slots = &self.items[self.start[c] as usize..self.start[c + 1] as usize];
            for &s in slots {
                let t = &self.tris[s as usize];
                if t.top < plane_lo - COPLANAR_MM {
                    break;
                }
                // Quick reject: bounding boxes more than R apart.
                if t.lo[0] > reach_box.2
                    || t.hi[0] < reach_box.0
                    || t.lo[1] > reach_box.3
                    || t.hi[1] < reach_box.1
                {
                    continue;
                }
                let h = t.v.map(|p| n.dot(p) - d);
                let hmax = h[0].max(h[1]).max(h[2]);
                if hmax <= COPLANAR_MM {
                    let hmin = h[0].min(h[1]).min(h[2]);
                    if hmin >= -COPLANAR_MM
                        && let Some(iv) = clip_segment_triangle(ca, cb, &t.v)
                    {
                        cover.push(iv);
                    }
                    continue; // at or below the plane: cannot raise the cutter
                }
                // Rises above the plane: does it come within reach of the segment?
                let dx = seg_rect_dist2(a, b, (t.lo[0], t.lo[1], t.hi[0], t.hi[1]));
                if dx > big_r * big_r {
                    continue;
                }
                if hmax > max_rise_mm {
                    return None;
                }
                rise = rise.max(hmax);
            }
        }
        let covered = if seg_len2 == 0.0 {
            cover.iter().any(|&(lo, hi)| lo <= 0.0 && hi >= 0.0)
        } else {
            cover.sort_by(|p, q| p.0.total_cmp(&q.0));
            let mut reach = 0.0f64;
            let mut ok = false;
            for &(lo, hi) in &cover {
                if lo > reach + 1e-12 {
                    break;
                }
                reach = reach.max(hi);
                if reach >= 1.0 - 1e-12 {
                    ok = true;
                    break;
                }
            }
            ok
        };
        Some(PlaneCertificate {
            rise_mm: rise.max(0.0),
            covered,
        })
    }
}

impl DropCutter {
    /// The index cells the XY segment `a → b` passes through, with their rectangles
    /// `(x0, y0, x1, y1)` (mm): each lists every triangle within the cutter radius of it.
    pub(crate) fn cells_on_segment(
        &self,
        a: (f64, f64),
        b: (f64, f64),
    ) -> Vec<(usize, (f64, f64, f64, f64))> {
        let ci = |v: f64, o: f64, n: usize| {
            (((v - o) / self.cell).floor().max(0.0) as usize).min(n.saturating_sub(1))
        };
        let (i0, i1) = (
            ci(a.0.min(b.0), self.ox, self.nx),
            ci(a.0.max(b.0), self.ox, self.nx),
        );
        let (j0, j1) = (
            ci(a.1.min(b.1), self.oy, self.ny),
            ci(a.1.max(b.1), self.oy, self.ny),
        );
        let mut out = Vec::new();
        for j in j0..=j1 {
            for i in i0..=i1 {
                let (rx0, ry0) = (
                    self.ox + i as f64 * self.cell,
                    self.oy + j as f64 * self.cell,
                );
                let rect = (rx0, ry0, rx0 + self.cell, ry0 + self.cell);
                if seg_rect_dist2(a, b, rect) == 0.0 {
                    out.push((j * self.nx + i, rect));
                }
            }
        }
        out
    }
}

/// Squared XY distance from the segment `a → b` to the rectangle `(x0, y0, x1, y1)`;
/// 0 if they meet.
pub(crate) fn seg_rect_dist2(a: (f64, f64), b: (f64, f64), r: (f64, f64, f64, f64)) -> f64 {
    let inside = |p: (f64, f64)| p.0 >= r.0 && p.0 <= r.2 && p.1 >= r.1 && p.1 <= r.3;
    if inside(a) || inside(b) {
        return 0.0;
    }
    // Clip the segment against the rectangle (Liang–Barsky): any overlap means 0.
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    let mut hit = true;
    for (p, q) in [
        (-dx, a.0 - r.0),
        (dx, r.2 - a.0),
        (-dy, a.1 - r.1),
        (dy, r.3 - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                hit = false;
                break;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    if hit && t0 <= t1 {
        return 0.0;
    }
    // Disjoint: the distance is attained at a segment end point or a rectangle corner.
    let pr = |p: (f64, f64)| {
        let qx = p.0.clamp(r.0, r.2);
        let qy = p.1.clamp(r.1, r.3);
        (p.0 - qx).powi(2) + (p.1 - qy).powi(2)
    };
    let ps = |p: (f64, f64)| {
        let l2 = dx * dx + dy * dy;
        let t = if l2 > 0.0 {
            (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (p.0 - a.0 - t * dx).powi(2) + (p.1 - a.1 - t * dy).powi(2)
    };
    let mut best = pr(a).min(pr(b));
    for c in [(r.0, r.1), (r.2, r.1), (r.0, r.3), (r.2, r.3)] {
        best = best.min(ps(c));
    }
    best
}

/// The parameter interval `[t0, t1] ⊂ [0, 1]` of the XY segment `a → b` inside the XY
/// projection of a triangle (edges included), `None` if they do not meet.
fn clip_segment_triangle(a: (f64, f64), b: (f64, f64), v: &[DVec3; 3]) -> Option<(f64, f64)> {
    // Orientation of the projected triangle.
    let area = (v[1].x - v[0].x) * (v[2].y - v[0].y) - (v[1].y - v[0].y) * (v[2].x - v[0].x);
    if area == 0.0 {
        return None;
    }
    let sgn = area.signum();
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..3 {
        let (p, q) = (v[k], v[(k + 1) % 3]);
        // Inside: sgn · cross(q − p, x − p) ≥ 0, linear in t.
        let f = |x: (f64, f64)| sgn * ((q.x - p.x) * (x.1 - p.y) - (q.y - p.y) * (x.0 - p.x));
        let (fa, fb) = (f(a), f(b));
        if fa < 0.0 && fb < 0.0 {
            return None;
        }
        if fa < 0.0 {
            t0 = t0.max(fa / (fa - fb));
        } else if fb < 0.0 {
            t1 = t1.min(fa / (fa - fb));
        }
    }
    (t0 <= t1).then_some((t0, t1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clip_and_distance() {
        let v = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0),
        ];
        let (t0, t1) = clip_segment_triangle((-1.0, 0.5), (3.0, 0.5), &v).unwrap();
        assert!(
            (t0 - 0.25).abs() < 1e-12 && (t1 - 0.625).abs() < 1e-12,
            "{t0} {t1}"
        );
        assert!(clip_segment_triangle((-1.0, 3.0), (3.0, 3.0), &v).is_none());
        assert_eq!(
            seg_rect_dist2((-1.0, 0.5), (3.0, 0.5), (0.0, 0.0, 1.0, 1.0)),
            0.0
        );
        let d = seg_rect_dist2((-1.0, 3.0), (3.0, 3.0), (0.0, 0.0, 1.0, 1.0));
        assert!((d - 4.0).abs() < 1e-12, "{d}");
    }
}
