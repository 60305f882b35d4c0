//! Top-surface profiles in a section plane and their constant-arc-length resampling.

use crate::MAX_POINTS;
use crate::error::SampleError;

/// One connected piece of the top surface in a section plane: points `(u, z)` (mm) with
/// non-decreasing `u`.
///
/// Consecutive points are distinct. Two consecutive points with equal `u` are a vertical
/// jump (a wall); between points the profile is the straight segment joining them. A
/// profile spans a positive `u` interval (`first u < last u`).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Profile {
    /// The polyline vertices `(u, z)` in mm, `u` non-decreasing.
    pub points: Vec<(f64, f64)>,
}

impl Profile {
    /// `(first u, last u)` in mm, or `None` for an empty profile.
    pub fn u_range(&self) -> Option<(f64, f64)> {
        Some((self.points.first()?.0, self.points.last()?.0))
    }

    /// Length of the polyline in the section plane (mm), vertical jumps included.
    pub fn arc_length(&self) -> f64 {
        self.points.windows(2).map(|w| seg_len(w[0], w[1])).sum()
    }

    /// Height of the top surface at `u` (mm), or `None` outside the profile's `u` range.
    ///
    /// At a vertical jump the highest point at that `u` is returned (the top of the wall):
    /// the profile is the upper envelope of a closed set.
    pub fn z_at(&self, u: f64) -> Option<f64> {
        let (u0, u1) = self.u_range()?;
        if !(u >= u0 && u <= u1) {
            return None;
        }
        // First point with u_i >= u.
        let i = self.points.partition_point(|p| p.0 < u);
        let mut best = f64::NEG_INFINITY;
        let mut j = i;
        while j < self.points.len() && self.points[j].0 == u {
            best = best.max(self.points[j].1);
            j += 1;
        }
        if j > i {
            return Some(best);
        }
        // Strictly inside segment (i-1, i). (The guard only matters for hand-built profiles
        // whose u is not sorted.)
        if i == 0 || i >= self.points.len() {
            return None;
        }
        let (a, b) = (self.points[i - 1], self.points[i]);
        Some(lerp_z(a, b, u))
    }

    /// The 3-D arc length (mm) from the profile start to the first point at `u`
    /// (the bottom-most of a vertical jump at `u` is reached first when climbing, the
    /// top-most when descending: the first point along the curve).
    pub fn arc_length_at(&self, u: f64) -> Option<f64> {
        let (u0, u1) = self.u_range()?;
        if !(u >= u0 && u <= u1) {
            return None;
        }
        let mut acc = 0.0;
        for w in self.points.windows(2) {
            let (a, b) = (w[0], w[1]);
            if a.0 == u {
                return Some(acc);
            }
            if b.0 > u {
                let p = (u, lerp_z(a, b, u));
                return Some(acc + seg_len(a, p));
            }
            acc += seg_len(a, b);
        }
        Some(acc)
    }
}

/// Samples of [`resample_u`] closer than this in `u` (mm) are merged: far below any
/// machine resolution, far above the rounding of section coordinates.
pub const MERGE_U_MM: f64 = 1e-9;

/// Joins consecutive profiles (in increasing `u`, as [`crate::Sectioner::top_profile`]
/// returns them) whose gap in `u` is at most `max_gap_mm`: the straight segment from one's
/// last point to the next one's first point bridges the gap. Use it for mesh cracks (edges
/// that should be shared but are not, a fraction of a micron apart), not for real holes.
/// A negative or NaN `max_gap_mm` bridges nothing.
pub fn bridge_gaps(profiles: Vec<Profile>, max_gap_mm: f64) -> Vec<Profile> {
    let mut out: Vec<Profile> = Vec::with_capacity(profiles.len());
    for p in profiles {
        if let (Some(prev), Some(&first)) = (out.last_mut(), p.points.first())
            && let Some(&last) = prev.points.last()
            && first.0 - last.0 >= 0.0
            && first.0 - last.0 <= max_gap_mm
        {
            let skip = usize::from(first == last);
            prev.points.extend_from_slice(&p.points[skip..]);
            continue;
        }
        out.push(p);
    }
    out
}

/// Gaps narrower than this (mm) between consecutive profiles of a plane are treated as
/// mesh cracks and bridged by [`crate::sample_part`] (see [`bridge_gaps`]): one micron, far
/// below any machine resolution, far above f64 rounding of section coordinates.
pub const CRACK_GAP_MM: f64 = 1e-6;

/// Euclidean length of the segment between two `(u, z)` points.
pub(crate) fn seg_len(a: (f64, f64), b: (f64, f64)) -> f64 {
    let (du, dz) = (b.0 - a.0, b.1 - a.1);
    (du * du + dz * dz).sqrt()
}

/// `z` on segment `a`–`b` at `u` (`a.0 <= u <= b.0`, `a.0 < b.0`), exact at the ends.
fn lerp_z(a: (f64, f64), b: (f64, f64), u: f64) -> f64 {
    if u == a.0 {
        a.1
    } else if u == b.0 {
        b.1
    } else {
        a.1 + (b.1 - a.1) * ((u - a.0) / (b.0 - a.0))
    }
}

/// Resamples a profile at constant arc length `step_mm` along the curve in the section
/// plane (vertical jumps included) and returns the `u` positions (mm).
///
/// Guarantees: strictly increasing; the first and last `u` of the profile are included;
/// arc positions `0, s, 2s, …` (`s = step_mm`) that fall on a vertical jump give that jump's
/// `u` once (duplicates merged); a `u` within [`MERGE_U_MM`] of the previous one is merged
/// into it (walls that rounding left a few ulp off vertical, e.g. in rotated frames, give
/// one `u`, not a cluster), and one within [`MERGE_U_MM`] before the end gives way to the
/// end; a final arc position closer than `1e-9·s` to the profile's end is merged into the end.
/// Between consecutive samples the arc length of the curve, vertical jumps not counted, is
/// at most `s` (up to rounding and the merge distance). On a straight stretch of slope angle θ consecutive samples are
/// `s·cos θ` apart in `u`, so steep stretches get denser `u`.
///
/// Degenerate input never panics: an empty profile gives an empty vector, a one-point
/// profile its `u`; a `step_mm` that is not finite and positive, or that would give more than
/// [`MAX_POINTS`] samples, gives only the first and last `u` (use [`try_resample_u`] to get
/// an error instead).
pub fn resample_u(profile: &Profile, step_mm: f64) -> Vec<f64> {
    match try_resample_u(profile, step_mm) {
        Ok(u) => u,
        Err(_) => {
            let mut out = Vec::new();
            if let Some((u0, u1)) = profile.u_range() {
                out.push(u0);
                if u1 > u0 {
                    out.push(u1);
                }
            }
            out
        }
    }
}

/// [`resample_u`] with input checks.
///
/// # Errors
/// [`SampleError::InvalidConfig`] when `step_mm` is not a finite positive number;
/// [`SampleError::TooManyPoints`] when the profile's arc length over `step_mm` exceeds
/// [`MAX_POINTS`].
pub fn try_resample_u(profile: &Profile, step_mm: f64) -> Result<Vec<f64>, SampleError> {
    if !(step_mm.is_finite() && step_mm > 0.0) {
        return Err(SampleError::InvalidConfig {
            field: "arc_step_mm",
            value: step_mm,
            reason: "must be a finite number > 0",
        });
    }
    let pts = &profile.points;
    if pts.is_empty() {
        return Ok(Vec::new());
    }
    let total = profile.arc_length();
    let estimate = total / step_mm + 2.0;
    if estimate.is_nan() || estimate > MAX_POINTS as f64 {
        return Err(SampleError::TooManyPoints {
            estimated: estimate,
            limit: MAX_POINTS,
        });
    }
    let mut out = Vec::with_capacity(estimate as usize);
    out.push(pts[0].0);
    let mut last = pts[0].0;
    // Arc position k·s, computed by multiplication (no drift), walked against the running
    // length of the polyline.
    let end_guard = total - 1e-9 * step_mm;
    let mut k: u64 = 1;
    let mut acc = 0.0;
    for w in pts.windows(2) {
        let (a, b) = (w[0], w[1]);
        let len = seg_len(a, b);
        let next = acc + len;
        loop {
            let s = k as f64 * step_mm;
            if s >= next || s >= end_guard {
                break;
            }
            // s in [acc, next): on this segment.
            let t = (s - acc) / len;
            let u = if a.0 == b.0 {
                a.0
            } else {
                (a.0 + (b.0 - a.0) * t).clamp(a.0, b.0)
            };
            if u > last + MERGE_U_MM {
                out.push(u);
                last = u;
            }
            k += 1;
        }
        acc = next;
    }
    // The end is always included; a sample within MERGE_U_MM before it gives way to it.
    let end = pts[pts.len() - 1].0;
    if end > last {
        if end > last + MERGE_U_MM || out.len() == 1 {
            out.push(end);
        } else {
            let n = out.len();
            out[n - 1] = end;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn z_at_and_jump() {
        let p = Profile {
            points: vec![(0.0, 0.0), (1.0, 0.0), (1.0, 2.0), (3.0, 2.0)],
        };
        assert_eq!(p.z_at(0.5), Some(0.0));
        assert_eq!(p.z_at(1.0), Some(2.0));
        assert_eq!(p.z_at(2.0), Some(2.0));
        assert_eq!(p.z_at(3.5), None);
        assert_eq!(p.arc_length(), 5.0);
        assert_eq!(p.arc_length_at(1.0), Some(1.0));
        assert_eq!(p.arc_length_at(2.0), Some(4.0));
    }

    #[test]
    fn bridge_only_narrow_gaps() {
        let ps = vec![
            Profile {
                points: vec![(0.0, 0.0), (1.0, 1.0)],
            },
            Profile {
                points: vec![(1.0 + 5e-7, 1.0), (2.0, 0.0)],
            },
            Profile {
                points: vec![(2.5, 0.0), (3.0, 0.0)],
            },
            Profile {
                points: vec![(3.0, 0.5), (4.0, 0.0)],
            },
        ];
        let b = bridge_gaps(ps.clone(), CRACK_GAP_MM);
        assert_eq!(b.len(), 2);
        assert_eq!(
            b[0].points,
            vec![(0.0, 0.0), (1.0, 1.0), (1.0 + 5e-7, 1.0), (2.0, 0.0)]
        );
        assert_eq!(
            b[1].points,
            vec![(2.5, 0.0), (3.0, 0.0), (3.0, 0.5), (4.0, 0.0)]
        );
        assert_eq!(bridge_gaps(ps.clone(), -1.0), ps);
        assert_eq!(bridge_gaps(ps.clone(), f64::NAN), ps);
    }

    #[test]
    fn resample_flat_and_jump() {
        let p = Profile {
            points: vec![(0.0, 0.0), (1.0, 0.0), (1.0, 2.0), (3.0, 2.0)],
        };
        // Arc positions 0, .5, 1 (u=1), 1.5, 2, 2.5, 3 (all u=1), 3.5 (u=1.5), 4, 4.5, 5.
        assert_eq!(resample_u(&p, 0.5), vec![0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0]);
        assert_eq!(resample_u(&p, 10.0), vec![0.0, 3.0]);
        assert_eq!(resample_u(&p, 0.0), vec![0.0, 3.0]);
        assert_eq!(resample_u(&p, f64::NAN), vec![0.0, 3.0]);
        assert!(try_resample_u(&p, -1.0).is_err());
        assert!(try_resample_u(&p, 1e-12).is_err());
        assert!(resample_u(&Profile::default(), 1.0).is_empty());
    }
}
