//! Imprint points against analytic truths: Chung's silhouette (paper Eq. 3), the torus, and
//! the degenerate cases.

use cam_core::{Cutter, DVec3, Pose};
use cam_verify::imprint::{
    CurveStatus, Difference, Half, ImprintConfig, Imprinter, Placement, Side, TorusTool,
    transport_frames,
};

fn cfg(q: usize, placement: Placement) -> ImprintConfig {
    ImprintConfig {
        inserts: q,
        placement,
        difference: Difference::Forward,
    }
}

/// Outgoing imprint curve of the straight 3-axis step `a → b` (tool tips, axis +Z).
fn curve3(
    cutter: &Cutter,
    c: &ImprintConfig,
    a: DVec3,
    b: DVec3,
    half: Half,
) -> (Vec<DVec3>, CurveStatus) {
    let frames = transport_frames(
        &[Pose::vertical(a), Pose::vertical(b)],
        cutter.corner_radius(),
    );
    let imp = Imprinter::new(cutter, c);
    let mut out = vec![DVec3::splat(f64::NAN); imp.points_per_curve()];
    let info = imp.curve(&frames[0], &frames[1], Side::Outgoing, half, &mut out);
    (out, info.status)
}

/// Paper §4.1: R = 1, r = 1 (bull:4:1), slope 0.2, Q = 40. Chung et al.'s Eq. 3 for a move
/// along +x rising with slope s, at a point (x, y) relative to the axis, t = √(x² + y²):
/// N·D ∝ √(t² − y²)·(t − R)/t − s·√(r² − (t − R)²) = 0 (front half, x ≥ 0).
#[test]
fn chung_silhouette_paper_case() {
    let cutter = Cutter::bull(4.0, 1.0).unwrap();
    let (big_r, r, s) = (1.0, 1.0, 0.2);
    let tool = TorusTool::from_cutter(&cutter);
    let dir = DVec3::new(1.0, 0.0, s).normalize();
    for placement in [Placement::Uniform, Placement::Adaptive] {
        let a = DVec3::new(3.0, -2.0, 1.0);
        let (pts, status) = curve3(
            &cutter,
            &cfg(40, placement),
            a,
            a + 0.7 * DVec3::new(1.0, 0.0, s),
            Half::Cutting,
        );
        assert_eq!(status, CurveStatus::Regular);
        assert_eq!(pts.len(), 21, "Q/2 + 1 points");
        let centre = a + r * DVec3::Z;
        let mut worst = (0.0f64, 0.0f64, 0.0f64);
        for m in &pts {
            let d = *m - centre;
            let (x, y) = (d.x, d.y);
            let t = x.hypot(y);
            assert!(x >= -1e-12, "{placement:?}: point behind the tool: {d}");
            assert!(
                d.z <= 1e-12,
                "{placement:?}: point above the torus equator: {d}"
            );
            let e3 = (t * t - y * y).max(0.0).sqrt() * (t - big_r) / t
                - s * (r * r - (t - big_r).powi(2)).max(0.0).sqrt();
            // The torus normal at m: from the insert centre on the ring towards m.
            let ring = centre + big_r * DVec3::new(x, y, 0.0) / t;
            let normal = (*m - ring).normalize();
            worst.0 = worst.0.max(e3.abs());
            worst.1 = worst.1.max(tool.torus_distance(centre, DVec3::Z, *m).abs());
            worst.2 = worst.2.max(normal.dot(dir).abs());
        }
        println!(
            "{placement:?}: Chung Eq.3 residual {:.2e}, torus distance {:.2e}, |n·D| {:.2e}",
            worst.0, worst.1, worst.2
        );
        assert!(
            worst.0 < 1e-9 && worst.1 < 1e-9 && worst.2 < 1e-9,
            "{placement:?}: {worst:?}"
        );
        // The demarcation points are the side points at ±90° from the motion, centre height.
        for (m, side) in [(pts[0], -1.0), (pts[20], 1.0)] {
            let d = m - centre;
            assert!(
                d.distance(DVec3::new(0.0, side * 2.0, 0.0)) < 1e-12,
                "demarcation {d}"
            );
        }
    }
}

/// Downhill the imprint sits on the back half (relative to the motion), mirrored.
#[test]
fn downhill_imprints_the_back_half() {
    let cutter = Cutter::bull(10.0, 2.0).unwrap();
    let tool = TorusTool::from_cutter(&cutter);
    let a = DVec3::ZERO;
    let step = DVec3::new(1.0, 0.5, -0.3);
    let (pts, _) = curve3(
        &cutter,
        &ImprintConfig::default(),
        a,
        a + step,
        Half::Cutting,
    );
    let centre = a + 2.0 * DVec3::Z;
    let h = DVec3::new(step.x, step.y, 0.0).normalize();
    for m in pts {
        let d = m - centre;
        assert!(d.dot(h) <= 1e-12, "not on the back half: {d}");
        assert!(tool.torus_distance(centre, DVec3::Z, m).abs() < 1e-12);
        let rho = DVec3::new(d.x, d.y, 0.0);
        let n = (m - (centre + 3.0 * rho.normalize())).normalize();
        assert!(n.dot(step.normalize()).abs() < 1e-12, "normal not ⟂ motion");
    }
}

/// Ball (a = 0): every imprint point is on the sphere, in the plane through the centre
/// perpendicular to the motion; horizontal motion is degenerate at the demarcation inserts and
/// the whole side profile (the lower great semicircle) is emitted.
#[test]
fn ball_horizontal_is_the_great_semicircle() {
    let cutter = Cutter::ball(6.0).unwrap();
    let a = DVec3::new(1.0, 2.0, 3.0);
    let (pts, status) = curve3(
        &cutter,
        &ImprintConfig::default(),
        a,
        a + DVec3::X,
        Half::Cutting,
    );
    assert_eq!(status, CurveStatus::Regular);
    let centre = a + 3.0 * DVec3::Z;
    let mut max_gap: f64 = 0.0;
    for w in pts.windows(2) {
        max_gap = max_gap.max(w[0].distance(w[1]));
    }
    for m in &pts {
        let d = *m - centre;
        assert!(d.x.abs() < 1e-12, "not in the plane ⟂ motion: {d}");
        assert!((d.length() - 3.0).abs() < 1e-12 && d.z <= 1e-12);
    }
    // The semicircle (length 3π) is covered: no gap longer than a tenth of it at Q = 40.
    assert!(max_gap < 0.1 * 3.0 * std::f64::consts::PI, "gap {max_gap}");
    assert!(
        pts.iter().any(|m| (m.z - a.z).abs() < 1e-12),
        "bottom point missing"
    );
}

/// Bull, horizontal motion: the degenerate case ΔT ∥ n at both demarcations; the curve is the
/// two side profiles (quarter circles in the plane ⟂ motion) joined by the bottom rim.
#[test]
fn bull_horizontal_emits_side_profiles() {
    let cutter = Cutter::bull(10.0, 2.0).unwrap();
    let tool = TorusTool::from_cutter(&cutter);
    let a = DVec3::ZERO;
    let (pts, _) = curve3(
        &cutter,
        &ImprintConfig::default(),
        a,
        a + DVec3::X,
        Half::Cutting,
    );
    let centre = a + 2.0 * DVec3::Z;
    let profile: Vec<&DVec3> = pts.iter().filter(|m| m.x.abs() < 1e-12).collect();
    for side in [-1.0, 1.0] {
        let heights: Vec<f64> = profile
            .iter()
            .filter(|m| m.y * side > 0.0)
            .map(|m| m.z)
            .collect();
        assert!(heights.len() >= 3, "side {side}: {heights:?}");
        assert!(
            heights.iter().any(|z| (z - 2.0).abs() < 1e-12),
            "side point missing"
        );
        assert!(
            heights.iter().any(|z| z.abs() < 1e-12),
            "bottom of the profile missing"
        );
    }
    for m in &pts {
        assert!(tool.torus_distance(centre, DVec3::Z, *m).abs() < 1e-12);
        if m.x.abs() >= 1e-12 {
            assert!(
                m.z.abs() < 1e-12,
                "front point off the flat bottom's rim: {m}"
            );
            assert!(m.x > 0.0);
        }
    }
}

/// Flat end mill (r = 0): every imprint point is a rim point of the flat bottom, on the front
/// half-circle.
#[test]
fn flat_imprint_is_the_front_rim() {
    let cutter = Cutter::flat(8.0).unwrap();
    let a = DVec3::new(0.0, 0.0, 1.0);
    for step in [DVec3::new(1.0, 0.0, 0.0), DVec3::new(1.0, 1.0, 0.4)] {
        let (pts, _) = curve3(
            &cutter,
            &ImprintConfig::default(),
            a,
            a + step,
            Half::Cutting,
        );
        let h = DVec3::new(step.x, step.y, 0.0).normalize();
        for m in &pts {
            let d = *m - a;
            assert!(d.z.abs() < 1e-12 && (d.length() - 4.0).abs() < 1e-12, "{d}");
            assert!(d.dot(h) >= -1e-12);
        }
    }
}

/// No motion: nothing is written.
#[test]
fn no_motion_writes_nothing() {
    let cutter = Cutter::bull(10.0, 2.0).unwrap();
    let (pts, status) = curve3(
        &cutter,
        &ImprintConfig::default(),
        DVec3::ONE,
        DVec3::ONE,
        Half::Cutting,
    );
    assert_eq!(status, CurveStatus::NoMotion);
    assert!(pts.iter().all(|p| p.x.is_nan()));
}

/// Reversal: the demarcation follows the motion, the imprinted half flips.
#[test]
fn reversal_flips_the_half() {
    let cutter = Cutter::bull(10.0, 2.0).unwrap();
    let a = DVec3::ZERO;
    let (fwd, _) = curve3(
        &cutter,
        &ImprintConfig::default(),
        a,
        a + DVec3::new(1.0, 0.0, 0.1),
        Half::Cutting,
    );
    let (back, _) = curve3(
        &cutter,
        &ImprintConfig::default(),
        a,
        a - DVec3::new(1.0, 0.0, -0.1),
        Half::Cutting,
    );
    assert!(fwd.iter().all(|m| m.x >= -1e-12) && fwd.iter().any(|m| m.x > 1.0));
    assert!(back.iter().all(|m| m.x <= 1e-12) && back.iter().any(|m| m.x < -1.0));
}

/// The complement half of an uphill bull move lies on the back half, on the flat bottom's rim
/// (its Eq. 2 solutions fall inside the ring, covered by the flat bottom).
#[test]
fn complement_half_is_the_heel() {
    let cutter = Cutter::bull(10.0, 2.0).unwrap();
    let a = DVec3::ZERO;
    let (pts, _) = curve3(
        &cutter,
        &ImprintConfig::default(),
        a,
        a + DVec3::new(1.0, 0.0, 0.2),
        Half::Complement,
    );
    for m in &pts[1..pts.len() - 1] {
        assert!(m.x <= 1e-12, "{m}");
    }
    assert!(pts.iter().filter(|m| m.z.abs() < 1e-12).count() >= pts.len() / 2);
}

/// Transported frames stay orthonormal and rotate minimally: for an axis turning about a fixed
/// direction w, e1's component along w is preserved.
#[test]
fn transported_frames_are_rotation_minimising() {
    let poses: Vec<Pose> = (0..50)
        .map(|i| {
            let ang = 0.02 * i as f64;
            Pose {
                tip: DVec3::new(i as f64, 0.0, 0.0),
                axis: DVec3::new(ang.sin(), 0.0, ang.cos()),
            }
        })
        .collect();
    let frames = transport_frames(&poses, 2.0);
    let w0 = frames[0].e1.dot(DVec3::Y);
    for f in &frames {
        assert!((f.e1.length() - 1.0).abs() < 1e-12 && f.e1.dot(f.axis).abs() < 1e-12);
        assert!((f.e2 - f.axis.cross(f.e1)).length() < 1e-12);
        assert!((f.e1.dot(DVec3::Y) - w0).abs() < 1e-12);
    }
}
