//! Property tests: random triangle soups against the brute force; resampling invariants.

use cam_core::{Mesh, Triangle};
use cam_sample::{MERGE_U_MM, Profile, RasterFrame, Sectioner, resample_u, upper_envelope};
use proptest::prelude::*;

use crate::util::{check_profile, compare};

fn soup() -> impl Strategy<Value = Vec<[[f64; 3]; 3]>> {
    prop::collection::vec(
        prop::array::uniform3(prop::array::uniform3(-10.0f64..10.0)),
        1..25,
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, .. ProptestConfig::default() })]

    /// The exact envelope of random (overlapping, crossing) triangles equals the brute force
    /// at random u, for random planes and frames.
    #[test]
    fn soup_matches_brute_force(tris in soup(), angle in 0.0f64..360.0, t in 0.0f64..1.0, us in prop::collection::vec(0.0f64..1.0, 50)) {
        let tris: Vec<Triangle> = tris.iter().map(|t| Triangle::new(t[0].into(), t[1].into(), t[2].into())).collect();
        let Ok(mesh) = Mesh::from_triangles(tris, "<prop>") else { return Ok(()) };
        let s = Sectioner::new(&mesh, RasterFrame::new(angle));
        let (v0, v1) = s.v_range();
        let v = v0 + (v1 - v0) * t;
        for p in s.top_profile(v) {
            check_profile(&p);
        }
        let (u0, u1) = s.u_range();
        let us: Vec<f64> = us.iter().map(|f| u0 + (u1 - u0) * f).collect();
        let a = compare(&s, v, &us);
        prop_assert_eq!(a.coverage_mismatch, 0, "{:?}", a);
        prop_assert!(a.max_dz <= 1e-9, "{:?}", a);
    }

    /// Envelope of random (u, z) segments, vertical ones included, against sampling each
    /// segment's value at u.
    #[test]
    fn segments_envelope(segs in prop::collection::vec(((-5.0f64..5.0, -5.0f64..5.0), (-5.0f64..5.0, -5.0f64..5.0), any::<bool>()), 1..30), us in prop::collection::vec(-5.0f64..5.0, 60)) {
        let segs: Vec<[(f64, f64); 2]> = segs.iter().map(|&(a, b, vert)| if vert { [a, (a.0, b.1)] } else { [a, b] }).collect();
        let env = upper_envelope(&segs);
        for p in &env {
            check_profile(p);
        }
        for w in env.windows(2) {
            prop_assert!(w[0].points.last().unwrap().0 < w[1].points[0].0, "profiles overlap");
        }
        for u in us {
            let mut best: Option<f64> = None;
            let mut spans = false;
            for s in &segs {
                let [(ua, za), (ub, zb)] = *s;
                let (lo, hi) = (ua.min(ub), ua.max(ub));
                if ua != ub && u > lo && u < hi {
                    spans = true;
                    let z = za + (zb - za) * (u - ua) / (ub - ua);
                    best = Some(best.map_or(z, |b: f64| b.max(z)));
                }
            }
            let got = env.iter().find_map(|p| p.z_at(u));
            if spans {
                let (b, g) = (best.unwrap(), got.expect("covered u inside a profile"));
                prop_assert!((b - g).abs() <= 1e-9, "u {}: brute {} envelope {}", u, b, g);
            }
        }
    }

    /// Resampling: strictly increasing, ends included, arc between samples ≤ step, and one
    /// sample per step on profiles without walls.
    #[test]
    fn resample_invariants(zs in prop::collection::vec(-3.0f64..3.0, 2..20), dus in prop::collection::vec(0.01f64..3.0, 19), step in 0.05f64..2.0) {
        let mut u = 0.0;
        let mut pts = Vec::new();
        for (i, z) in zs.iter().enumerate() {
            pts.push((u, *z));
            u += dus[i % dus.len()];
        }
        let p = Profile { points: pts };
        let out = resample_u(&p, step);
        let (a, b) = p.u_range().unwrap();
        prop_assert_eq!(out[0], a);
        prop_assert_eq!(*out.last().unwrap(), b);
        // A sample's u is exact to its rounding, a few ulps of |u|, and on a segment of
        // slope dz/du that moves its arc length sqrt(1 + slope²) times as much (a slope of
        // 300 turns 4e-15 mm of u into 1.3e-12 mm of arc).
        let stretch = p
            .points
            .windows(2)
            .map(|w| (1.0 + ((w[1].1 - w[0].1) / (w[1].0 - w[0].0)).powi(2)).sqrt())
            .fold(1.0f64, f64::max);
        let rounding = 8.0 * f64::EPSILON * (1.0 + b.abs()) * stretch;
        for w in out.windows(2) {
            prop_assert!(w[1] > w[0] + MERGE_U_MM);
            let d = p.arc_length_at(w[1]).unwrap() - p.arc_length_at(w[0]).unwrap();
            prop_assert!(
                d <= step * (1.0 + 1e-12) + rounding,
                "arc {} > step {} (rounding {:e})", d, step, rounding
            );
        }
        // All but the last gap are exactly one step of arc.
        for w in out.windows(2).take(out.len().saturating_sub(2)) {
            let d = p.arc_length_at(w[1]).unwrap() - p.arc_length_at(w[0]).unwrap();
            prop_assert!((d - step).abs() <= 1e-9, "arc {} != step {}", d, step);
        }
    }
}
