//! Exact upper envelope of a set of closed segments in the `(u, z)` plane.
//!
//! The envelope of the union `S` of the segments is `E(u) = max { z : (u, z) ∈ S }`, defined
//! where some segment covers `u`. It is computed by a sweep over the distinct endpoint
//! abscissae ("breakpoints"): between two consecutive breakpoints every segment that covers
//! the open interval spans it entirely and is a straight line there, so the envelope on that
//! interval is the upper envelope of a few lines, found by walking crossings (computed, not
//! sampled). At a breakpoint the envelope takes the left limit, the right limit and the
//! highest point of any segment (vertical ones included) at that `u`, which turns walls into
//! vertical jumps. Intervals that no segment spans are gaps and split the result into
//! separate [`Profile`]s.
//!
//! Cost: `O(k log k + Σ m_i²)` for `k` segments, where `m_i` is the number of segments
//! spanning elementary interval `i` (the number of surface sheets above each other there,
//! usually 2 for a closed part).

use crate::profile::Profile;

/// A closed segment `[(u, z), (u, z)]` in a section plane (mm).
pub type Seg = [(f64, f64); 2];

/// A non-vertical segment oriented by increasing `u`.
#[derive(Debug, Clone, Copy)]
struct Line {
    u0: f64,
    z0: f64,
    u1: f64,
    z1: f64,
    slope: f64,
}

impl Line {
    /// `z` at `u` in `[u0, u1]`, exact at both ends.
    fn z(&self, u: f64) -> f64 {
        if u == self.u0 {
            self.z0
        } else if u == self.u1 {
            self.z1
        } else {
            self.z0 + (self.z1 - self.z0) * ((u - self.u0) / (self.u1 - self.u0))
        }
    }
}

/// The upper envelope of closed segments in `(u, z)`, as maximal connected profiles in
/// increasing `u`.
///
/// Segments may be vertical (equal `u`), overlap, repeat or cross. Non-finite segments and
/// zero-length ones are ignored. Pieces of zero `u` extent (an isolated point or a free
/// vertical segment) are not reported: a [`Profile`] always spans a positive `u` interval.
pub fn upper_envelope(segs: &[Seg]) -> Vec<Profile> {
    let mut lines: Vec<Line> = Vec::with_capacity(segs.len());
    // Vertical segments as (u, z_top).
    let mut verticals: Vec<(f64, f64)> = Vec::new();
    for s in segs {
        let [a, b] = *s;
        if !(a.0.is_finite() && a.1.is_finite() && b.0.is_finite() && b.1.is_finite()) {
            continue;
        }
        if a.0 == b.0 {
            if a.1 != b.1 {
                verticals.push((a.0, a.1.max(b.1)));
            }
            continue;
        }
        let (p, q) = if a.0 < b.0 { (a, b) } else { (b, a) };
        lines.push(Line {
            u0: p.0,
            z0: p.1,
            u1: q.0,
            z1: q.1,
            slope: (q.1 - p.1) / (q.0 - p.0),
        });
    }
    if lines.is_empty() {
        return Vec::new();
    }
    // Starts and ends as (key, index) pairs, sorted with a total order (deterministic).
    let keyed = |key: fn(&Line) -> f64| {
        let mut v: Vec<(f64, u32)> = lines
            .iter()
            .enumerate()
            .map(|(i, l)| (key(l), i as u32))
            .collect();
        v.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        v
    };
    let starts = keyed(|l| l.u0);
    let ends = keyed(|l| l.u1);
    verticals.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    // Breakpoints: the three sorted key lists merged, equal values once.
    let se = merge_dedup(starts.iter().map(|s| s.0), ends.iter().map(|e| e.0));
    let bps = if verticals.is_empty() {
        se
    } else {
        merge_dedup(se.into_iter(), verticals.iter().map(|v| v.0))
    };

    let mut out: Vec<Profile> = Vec::new();
    let mut cur: Vec<(f64, f64)> = Vec::new();
    let mut active: Vec<u32> = Vec::new();
    let (mut si, mut ei, mut vi) = (0usize, 0usize, 0usize);
    // The envelope's last line on the interval left of the current breakpoint.
    let mut left_top: Option<u32> = None;

    for (bi, &u) in bps.iter().enumerate() {
        // Left limit from the walk over the previous interval.
        let z_left = left_top.map(|t| lines[t as usize].z(u));
        // Update the active set to the interval right of u.
        while ei < ends.len() && ends[ei].0 <= u {
            let id = ends[ei].1;
            if let Some(pos) = active.iter().position(|&a| a == id) {
                active.swap_remove(pos);
            }
            ei += 1;
        }
        while si < starts.len() && starts[si].0 <= u {
            active.push(starts[si].1);
            si += 1;
        }
        let mut z_vert: Option<f64> = None;
        while vi < verticals.len() && verticals[vi].0 <= u {
            if verticals[vi].0 == u {
                z_vert = Some(z_vert.map_or(verticals[vi].1, |z: f64| z.max(verticals[vi].1)));
            }
            vi += 1;
        }
        let right = if active.is_empty() || bi + 1 == bps.len() {
            None
        } else {
            Some(top_at_start(&lines, &active, u))
        };
        let z_right = right.map(|t| lines[t as usize].z(u));
        let z_point = [z_left, z_right, z_vert]
            .into_iter()
            .flatten()
            .fold(f64::NEG_INFINITY, f64::max);

        match (left_top.zip(z_left), right.zip(z_right)) {
            (None, None) => {}
            (None, Some((_, zr))) => {
                push_pt(&mut cur, (u, z_point));
                push_pt(&mut cur, (u, zr));
            }
            (Some((_, zl)), None) => {
                push_pt(&mut cur, (u, zl));
                push_pt(&mut cur, (u, z_point));
                finish(&mut cur, &mut out);
            }
            (Some((lt, zl)), Some((rt, zr))) => {
                // Nothing happens at u when the same line (or two segments of one line: equal
                // slope and equal value at u) continues through it.
                let same_line = lt == rt || lines[lt as usize].slope == lines[rt as usize].slope;
                if !(same_line && zl == zr && z_point <= zl) {
                    push_pt(&mut cur, (u, zl));
                    push_pt(&mut cur, (u, z_point));
                    push_pt(&mut cur, (u, zr));
                }
            }
        }
        // Walk the interval (u, next breakpoint).
        left_top = right.map(|t| walk(&lines, &active, t, u, bps[bi + 1], &mut cur));
    }
    finish(&mut cur, &mut out);
    out
}

/// The line on top just right of `a`: highest at `a`, ties broken by larger slope, then by
/// lower index (deterministic).
fn top_at_start(lines: &[Line], active: &[u32], a: f64) -> u32 {
    let mut best = active[0];
    let mut bz = lines[best as usize].z(a);
    for &id in &active[1..] {
        let l = &lines[id as usize];
        let z = l.z(a);
        let b = &lines[best as usize];
        if z > bz || (z == bz && (l.slope > b.slope || (l.slope == b.slope && id < best))) {
            best = id;
            bz = z;
        }
    }
    best
}

/// Walks the upper envelope of the `active` lines over `(a, b)` starting on line `top`,
/// appending crossing points; returns the line on top just left of `b`.
fn walk(
    lines: &[Line],
    active: &[u32],
    mut top: u32,
    a: f64,
    b: f64,
    cur: &mut Vec<(f64, f64)>,
) -> u32 {
    if active.len() == 1 {
        return top;
    }
    let mut x = a;
    loop {
        let t = &lines[top as usize];
        let zt_a = t.z(a);
        let mut next: Option<(f64, u32)> = None;
        for &id in active {
            let l = &lines[id as usize];
            if id == top || l.slope <= t.slope {
                continue;
            }
            // Crossing of the two lines, referenced to the interval start for consistency.
            let uc = (a + (zt_a - l.z(a)) / (l.slope - t.slope)).max(x);
            if uc >= b {
                continue;
            }
            let better = match next {
                None => true,
                Some((bu, bid)) => {
                    let bl = &lines[bid as usize];
                    uc < bu
                        || (uc == bu && (l.slope > bl.slope || (l.slope == bl.slope && id < bid)))
                }
            };
            if better {
                next = Some((uc, id));
            }
        }
        match next {
            None => return top,
            Some((uc, id)) => {
                if uc > x {
                    push_pt(cur, (uc, t.z(uc)));
                }
                x = uc;
                top = id;
            }
        }
    }
}

/// Merges two ascending sequences into one ascending vector, equal values once.
fn merge_dedup(a: impl Iterator<Item = f64>, b: impl Iterator<Item = f64>) -> Vec<f64> {
    let (mut a, mut b) = (a.peekable(), b.peekable());
    let mut out: Vec<f64> = Vec::with_capacity(a.size_hint().0 + b.size_hint().0);
    loop {
        let x = match (a.peek(), b.peek()) {
            (Some(&x), Some(&y)) => {
                if x.total_cmp(&y).is_le() {
                    a.next();
                    x
                } else {
                    b.next();
                    y
                }
            }
            (Some(&x), None) => {
                a.next();
                x
            }
            (None, Some(&y)) => {
                b.next();
                y
            }
            (None, None) => return out,
        };
        if out.last() != Some(&x) {
            out.push(x);
        }
    }
}

fn push_pt(cur: &mut Vec<(f64, f64)>, p: (f64, f64)) {
    if cur.last() != Some(&p) {
        cur.push(p);
    }
}

fn finish(cur: &mut Vec<(f64, f64)>, out: &mut Vec<Profile>) {
    if cur.len() >= 2 && cur[0].0 < cur[cur.len() - 1].0 {
        out.push(Profile {
            points: std::mem::take(cur),
        });
    } else {
        cur.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_crossing_segments() {
        // z = u and z = 2 - u on [0, 2]: the envelope is a V with its low point at u = 1.
        let e = upper_envelope(&[[(0.0, 0.0), (2.0, 2.0)], [(0.0, 2.0), (2.0, 0.0)]]);
        assert_eq!(e.len(), 1);
        assert_eq!(e[0].points, vec![(0.0, 2.0), (1.0, 1.0), (2.0, 2.0)]);
    }

    #[test]
    fn gap_and_wall() {
        let e = upper_envelope(&[
            [(0.0, 0.0), (1.0, 0.0)],
            [(1.0, 0.0), (1.0, 3.0)],
            [(1.0, 3.0), (2.0, 3.0)],
            [(5.0, 1.0), (6.0, 1.0)],
            [(5.0, 0.0), (6.0, 0.0)],
            [(8.0, 0.0), (8.0, 4.0)],
        ]);
        assert_eq!(e.len(), 2);
        assert_eq!(
            e[0].points,
            vec![(0.0, 0.0), (1.0, 0.0), (1.0, 3.0), (2.0, 3.0)]
        );
        assert_eq!(e[1].points, vec![(5.0, 1.0), (6.0, 1.0)]);
    }

    #[test]
    fn spike_from_free_vertical_inside() {
        let e = upper_envelope(&[[(0.0, 0.0), (2.0, 0.0)], [(1.0, -1.0), (1.0, 5.0)]]);
        assert_eq!(
            e[0].points,
            vec![(0.0, 0.0), (1.0, 0.0), (1.0, 5.0), (1.0, 0.0), (2.0, 0.0)]
        );
    }

    #[test]
    fn many_lines_one_interval() {
        // Tangent lines of z = u^2 at several points, all over [-3, 3]: envelope touches each.
        let ts = [-2.0, -1.0, 0.0, 1.0, 2.0];
        let segs: Vec<Seg> = ts
            .iter()
            .map(|&t: &f64| {
                let f = |u: f64| 2.0 * t * u - t * t;
                [(-3.0, f(-3.0)), (3.0, f(3.0))]
            })
            .collect();
        let e = upper_envelope(&segs);
        assert_eq!(e.len(), 1);
        let us: Vec<f64> = e[0].points.iter().map(|p| p.0).collect();
        assert_eq!(us, vec![-3.0, -1.5, -0.5, 0.5, 1.5, 3.0]);
    }
}
