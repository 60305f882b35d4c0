//! Sectioning a mesh by vertical planes `v = const` of a raster frame.

use cam_core::Mesh;
use glam::DVec3;
use rayon::prelude::*;

use crate::envelope::{Seg, upper_envelope};
use crate::frame::RasterFrame;
use crate::profile::Profile;

/// A part prepared for sectioning by vertical planes `v = const` in one raster frame.
///
/// Construction transforms every vertex once into frame coordinates `(u, v, z)` and builds
/// a bucket index over `v`; a section then costs `O(t + 1)` for the `t` triangles whose `v`
/// extent contains the plane (plus the buckets' share of long triangles), not `O(n)`.
///
/// The intersection is that of the **closed** triangles with the plane, computed from the
/// same transformed vertices for every triangle: a vertex on the plane is itself a section
/// point, an edge in the plane is a section segment, a triangle in the plane contributes its
/// three edges (so its upper edge is on the envelope), a triangle perpendicular to the plane
/// gives a vertical segment. An edge crossing the plane is interpolated in a canonical
/// orientation (from its vertex below the plane to the one above), so the two triangles
/// sharing it produce bit-identical points and no spurious gap opens between them.
#[derive(Debug, Clone)]
pub struct Sectioner {
    frame: RasterFrame,
    /// Triangles in frame coordinates `(u, v, z)`.
    tris: Vec<[DVec3; 3]>,
    /// `(v_min, v_max)` per triangle.
    vext: Vec<(f64, f64)>,
    v_range: (f64, f64),
    u_range: (f64, f64),
    index: BucketIndex,
}

/// Buckets of equal width over `v`, each listing the triangles whose `v` extent meets it
/// (CSR layout).
#[derive(Debug, Clone)]
struct BucketIndex {
    v0: f64,
    inv_width: f64,
    count: usize,
    offsets: Vec<u32>,
    items: Vec<u32>,
}

impl BucketIndex {
    fn bucket(&self, v: f64) -> usize {
        let b = ((v - self.v0) * self.inv_width).floor();
        if b <= 0.0 {
            0
        } else {
            (b as usize).min(self.count - 1)
        }
    }

    fn build(vext: &[(f64, f64)], v_range: (f64, f64)) -> BucketIndex {
        let n = vext.len();
        let span = v_range.1 - v_range.0;
        // Bucket width ~ twice the median triangle extent, widened while long triangles
        // would make the index larger than 8 entries per triangle.
        let mut ext: Vec<f64> = vext.iter().map(|e| e.1 - e.0).collect();
        let mid = ext.len() / 2;
        let median = if ext.is_empty() {
            0.0
        } else {
            *ext.select_nth_unstable_by(mid, f64::total_cmp).1
        };
        let mut count: usize = if span > 0.0 && median > 0.0 {
            ((span / (2.0 * median)).ceil() as usize).clamp(1, 4 * n.max(1))
        } else if span > 0.0 {
            n.clamp(1, 1 << 20)
        } else {
            1
        };
        loop {
            let inv_width = if span > 0.0 { count as f64 / span } else { 0.0 };
            let probe = BucketIndex {
                v0: v_range.0,
                inv_width,
                count,
                offsets: Vec::new(),
                items: Vec::new(),
            };
            let total: usize = vext
                .iter()
                .map(|&(a, b)| probe.bucket(b) - probe.bucket(a) + 1)
                .sum();
            if total <= 8 * n + count || count == 1 {
                let mut offsets = vec![0u32; count + 1];
                for &(a, b) in vext {
                    for k in probe.bucket(a)..=probe.bucket(b) {
                        offsets[k + 1] += 1;
                    }
                }
                for k in 0..count {
                    offsets[k + 1] += offsets[k];
                }
                let mut fill = offsets.clone();
                let mut items = vec![0u32; total];
                for (i, &(a, b)) in vext.iter().enumerate() {
                    for k in probe.bucket(a)..=probe.bucket(b) {
                        items[fill[k] as usize] = i as u32;
                        fill[k] += 1;
                    }
                }
                return BucketIndex {
                    offsets,
                    items,
                    ..probe
                };
            }
            count = count.div_ceil(2);
        }
    }

    fn candidates(&self, v: f64) -> &[u32] {
        let k = self.bucket(v);
        &self.items[self.offsets[k] as usize..self.offsets[k + 1] as usize]
    }
}

impl Sectioner {
    /// Prepares `mesh` for sectioning in `frame`: transforms the vertices to `(u, v, z)` and
    /// builds the index over `v`. `O(n)` time (the per-triangle work in parallel), `O(n)`
    /// memory: the index holds at most `8n` entries plus one per bucket.
    pub fn new(mesh: &Mesh, frame: RasterFrame) -> Sectioner {
        // Per-triangle work in parallel; the ranges are min/max folds, exact in any order.
        let tris: Vec<[DVec3; 3]> = mesh
            .triangles()
            .par_iter()
            .map(|t| t.v.map(|p| frame.point_to_uvz(p)))
            .collect();
        let vext: Vec<(f64, f64)> = tris
            .par_iter()
            .map(|t| {
                (
                    t[0].y.min(t[1].y).min(t[2].y),
                    t[0].y.max(t[1].y).max(t[2].y),
                )
            })
            .collect();
        let fold = |(a, b): (f64, f64), (c, d): (f64, f64)| (a.min(c), b.max(d));
        let empty = (f64::INFINITY, f64::NEG_INFINITY);
        let v_range = vext.par_iter().copied().reduce(|| empty, fold);
        let u_range = tris
            .par_iter()
            .map(|t| {
                (
                    t[0].x.min(t[1].x).min(t[2].x),
                    t[0].x.max(t[1].x).max(t[2].x),
                )
            })
            .reduce(|| empty, fold);
        let index = BucketIndex::build(&vext, v_range);
        Sectioner {
            frame,
            tris,
            vext,
            v_range,
            u_range,
            index,
        }
    }

    /// The raster frame the sections are taken in.
    pub fn frame(&self) -> RasterFrame {
        self.frame
    }

    /// The part's extent across the passes, `(v_min, v_max)` in mm.
    pub fn v_range(&self) -> (f64, f64) {
        self.v_range
    }

    /// The part's extent along the passes, `(u_min, u_max)` in mm.
    pub fn u_range(&self) -> (f64, f64) {
        self.u_range
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    /// Always false: a [`Mesh`] has at least one triangle.
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// The triangles in frame coordinates `(u, v, z)` (mm), in mesh order.
    pub fn triangles_uvz(&self) -> &[[DVec3; 3]] {
        &self.tris
    }

    /// The raw section of the part by the plane `v` (mm): one closed `(u, z)` segment per
    /// triangle meeting the plane in a segment (three for a triangle lying in the plane), in
    /// mesh order. Triangles touching the plane in a single point contribute nothing.
    pub fn section_segments(&self, v: f64) -> Vec<Seg> {
        let mut out = Vec::new();
        if !(v >= self.v_range.0 && v <= self.v_range.1) {
            return out;
        }
        let cand = self.index.candidates(v);
        // Bucket lists are in ascending triangle order, so the output is in mesh order.
        for &i in cand {
            let (a, b) = self.vext[i as usize];
            if a <= v && v <= b {
                triangle_section(&self.tris[i as usize], v, &mut out);
            }
        }
        out
    }

    /// The top surface in the plane `v` (mm): the upper envelope `z(u)` of the section as
    /// profiles of points `(u, z)` in increasing `u`, one per maximal covered `u` interval
    /// (the profile splits where the plane leaves the part). Vertical walls are vertical
    /// jumps inside a profile (two consecutive points with equal `u`). Exact up to f64
    /// rounding of the plane–edge crossings and segment–segment crossings; see
    /// [`crate::upper_envelope`]. Empty outside [`Sectioner::v_range`] or for NaN.
    pub fn top_profile(&self, v: f64) -> Vec<Profile> {
        upper_envelope(&self.section_segments(v))
    }

    /// [`Sectioner::top_profile`] for each plane of `vs`, in parallel; the result is in the
    /// order of `vs` and independent of the number of threads.
    pub fn top_profiles(&self, vs: &[f64]) -> Vec<Vec<Profile>> {
        vs.par_iter().map(|&v| self.top_profile(v)).collect()
    }
}

/// Appends the section of the closed triangle `t` (frame coordinates) with the plane `v = c`.
fn triangle_section(t: &[DVec3; 3], c: f64, out: &mut Vec<Seg>) {
    let d = [t[0].y - c, t[1].y - c, t[2].y - c];
    // Exact signs: the subtraction of two f64 is zero iff they are equal, and its sign is
    // exact (Sterbenz / correctly rounded subtraction never flips a sign).
    let s = d.map(|x| {
        if x > 0.0 {
            1i8
        } else if x < 0.0 {
            -1
        } else {
            0
        }
    });
    if s == [0, 0, 0] {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            out.push([(a.x, a.z), (b.x, b.z)]);
        }
        return;
    }
    if (s[0] > 0 && s[1] > 0 && s[2] > 0) || (s[0] < 0 && s[1] < 0 && s[2] < 0) {
        return;
    }
    let mut pts: [(f64, f64); 2] = [(0.0, 0.0); 2];
    let mut n = 0;
    for k in 0..3 {
        if s[k] == 0 {
            if n < 2 {
                pts[n] = (t[k].x, t[k].z);
            }
            n += 1;
        }
    }
    for k in 0..3 {
        let j = (k + 1) % 3;
        if s[k] * s[j] < 0 {
            // Canonical orientation: from the vertex below the plane to the one above.
            let (lo, hi, dl, dh) = if s[k] < 0 {
                (t[k], t[j], d[k], d[j])
            } else {
                (t[j], t[k], d[j], d[k])
            };
            let f = dl / (dl - dh); // in (0, 1)
            let p = (lo.x + (hi.x - lo.x) * f, lo.z + (hi.z - lo.z) * f);
            if n < 2 {
                pts[n] = p;
            }
            n += 1;
        }
    }
    if n == 2 && pts[0] != pts[1] {
        out.push(pts);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> [DVec3; 3] {
        [DVec3::from(a), DVec3::from(b), DVec3::from(c)]
    }

    #[test]
    fn bucket_index_finds_exactly_the_crossing_triangles() {
        // Many tiny triangles plus long ones spanning everything: the index must widen its
        // buckets to stay within 8 entries per triangle and still find every triangle.
        let mut vext: Vec<(f64, f64)> = Vec::new();
        let mut x = 0.123_f64;
        for i in 0..2000 {
            x = (x * 997.0 + 0.31).fract();
            let v = x * 1000.0;
            vext.push((v, v + 0.001 * (i % 3) as f64));
            if i % 20 == 0 {
                vext.push((-0.5 * x, 1000.0 + x));
            }
        }
        let range = vext
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |r, e| {
                (r.0.min(e.0), r.1.max(e.1))
            });
        let idx = BucketIndex::build(&vext, range);
        assert!(
            idx.items.len() <= 8 * vext.len() + idx.count,
            "{} entries",
            idx.items.len()
        );
        assert!(idx.count > 1);
        let mut probes: Vec<f64> = vext.iter().flat_map(|e| [e.0, e.1]).collect();
        probes.extend((0..500).map(|k| range.0 + (range.1 - range.0) * k as f64 / 499.0));
        for v in probes {
            let got: Vec<u32> = idx
                .candidates(v)
                .iter()
                .copied()
                .filter(|&i| vext[i as usize].0 <= v && v <= vext[i as usize].1)
                .collect();
            let want: Vec<u32> = (0..vext.len() as u32)
                .filter(|&i| vext[i as usize].0 <= v && v <= vext[i as usize].1)
                .collect();
            assert_eq!(got, want, "v = {v}");
        }
    }

    #[test]
    fn section_cases() {
        let mut out = Vec::new();
        // Crossing.
        triangle_section(
            &tri([0.0, -1.0, 0.0], [2.0, 1.0, 2.0], [0.0, 1.0, 0.0]),
            0.0,
            &mut out,
        );
        assert_eq!(out.len(), 1);
        // Vertex on plane, others on one side: nothing.
        out.clear();
        triangle_section(
            &tri([0.0, 0.0, 0.0], [2.0, 1.0, 2.0], [0.0, 1.0, 0.0]),
            0.0,
            &mut out,
        );
        assert!(out.is_empty());
        // Edge in plane.
        triangle_section(
            &tri([0.0, 0.0, 0.0], [2.0, 0.0, 2.0], [0.0, 1.0, 0.0]),
            0.0,
            &mut out,
        );
        assert_eq!(out, vec![[(0.0, 0.0), (2.0, 2.0)]]);
        // Coplanar: three edges.
        out.clear();
        triangle_section(
            &tri([0.0, 0.0, 0.0], [2.0, 0.0, 2.0], [0.0, 0.0, 1.0]),
            0.0,
            &mut out,
        );
        assert_eq!(out.len(), 3);
        // Perpendicular wall: vertical segment.
        out.clear();
        triangle_section(
            &tri([1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [1.0, 0.0, 5.0]),
            0.5,
            &mut out,
        );
        assert_eq!(out.len(), 1);
        assert_eq!(out[0][0].0, 1.0);
        assert_eq!(out[0][1].0, 1.0);
    }
}
