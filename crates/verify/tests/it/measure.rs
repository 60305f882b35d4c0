//! The measurement against swept-surface models: the fast locator (tiles over a patch
//! hierarchy) against the straightforward reference (every triangle in one BVH, every cap
//! tested), thread independence, and the exact surface against the independent z-map.

use cam_core::{Cutter, DVec3, Mesh, Move, MoveKind, Pose, Toolpath, Units};
use cam_verify::deviation::DeviationConfig;
use cam_verify::measure::{
    Locator, Measurement, SurfaceModel, layout, measure_progress, measure_then, measure_with,
    measure_with_inner,
};
use cam_verify::model::SweepModel;
use cam_verify::refine::{self, RefineConfig, RefinedMesh};
use cam_verify::sweep::SweepConfig;
use cam_verify::testpaths::{PassSpec, TestSurface, normal_lines, pass};
use cam_verify::zmap::{self, ZmapConfig, ZmapGrid};

/// The dome fixture: a hemisphere of radius 20 on a 60 × 60 × 5 plate, top at z = 0.
fn dome() -> Mesh {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/parts");
    Mesh::load(root.join("dome.obj"), Units::Mm).expect("dome fixture")
}

/// Tip height of a ball of radius `r` dropped onto the dome at (x, y): the larger of resting
/// on the plate (0) and on the sphere (its centre on the sphere of radius 20 + r).
fn ball_tip_on_dome(x: f64, y: f64, r: f64) -> f64 {
    let d2 = x * x + y * y;
    let rr = 20.0 + r;
    if d2 < rr * rr {
        ((rr * rr - d2).sqrt() - r).max(0.0)
    } else {
        0.0
    }
}

/// A 3-axis zig-zag of a ball over the dome: passes along X every `step_y`, tips every 0.5 mm
/// (each exactly on the dome's exact drop surface), a rapid in and out.
fn dome_zigzag(r: f64, x: (f64, f64), y: (f64, f64), step_y: f64) -> Toolpath {
    let mv = |kind, p: DVec3| Move {
        kind,
        pose: Pose::vertical(p),
        feed_mm_per_min: Some(1000.0),
        line: None,
        pass: None,
    };
    let mut moves = Vec::new();
    let nx = ((x.1 - x.0) / 0.5).round() as usize;
    let ny = ((y.1 - y.0) / step_y).round() as usize;
    for j in 0..=ny {
        let yy = y.0 + j as f64 * step_y;
        for i in 0..=nx {
            let ii = if j % 2 == 0 { i } else { nx - i };
            let xx = x.0 + ii as f64 * 0.5;
            let p = DVec3::new(xx, yy, ball_tip_on_dome(xx, yy, r));
            let kind = if moves.is_empty() {
                MoveKind::Rapid
            } else {
                MoveKind::Cut
            };
            moves.push(mv(kind, p));
        }
    }
    Toolpath { moves }
}

fn refined_dome(e: f64, cutter: &Cutter) -> RefinedMesh {
    let mut rc = RefineConfig::for_cutter(cutter, e);
    rc.crease_angle_deg = 180.0;
    refine::refine(&dome(), &rc).expect("refine")
}

fn assert_same(a: &Measurement, b: &Measurement, what: &str) {
    assert_eq!(a.deviations.len(), b.deviations.len());
    let mut differ = 0;
    for (i, (x, y)) in a.deviations.iter().zip(&b.deviations).enumerate() {
        if x != y || a.facing[i] != b.facing[i] || a.source[i] != b.source[i] {
            differ += 1;
            if differ < 5 {
                eprintln!("{what}: vertex {i}: {x:?} vs {y:?}");
            }
        }
    }
    assert_eq!(differ, 0, "{what}: {differ} vertices differ");
    assert_eq!(a.stats, b.stats, "{what}");
}

/// The direct measurement `a` of a path of translations against the crossing-based
/// reference `b`: where both read a vertex, the readings and entry facings agree to 1e-9.
/// The reference finds entries through the imprint surface's triangles, and a line that
/// grazes a move's volume may cross none of them: where only `a` reads a vertex, its
/// reading must equal the brute force over every move's puck and column, and such
/// vertices must be few (at most 0.1 %). `b` never reads a vertex `a` does not.
fn assert_same_readings(
    a: &Measurement,
    b: &Measurement,
    r: &RefinedMesh,
    tp: &Toolpath,
    cutter: &Cutter,
    what: &str,
) {
    use cam_verify::exact::{Line, MoveGeometry, Puck};
    assert_eq!(a.deviations.len(), b.deviations.len());
    let cfg = DeviationConfig::default();
    let brute = |i: usize| {
        let line = Line {
            o: r.positions[i],
            n: r.normals[i],
            lo: -cfg.inside_mm,
            hi: cfg.outside_mm,
        };
        tp.moves
            .windows(2)
            .filter(|w| w[1].kind != MoveKind::Rapid)
            .flat_map(|w| {
                let g = MoveGeometry {
                    a: w[0].pose,
                    b: w[1].pose,
                    puck: Puck::of(cutter),
                };
                [g.translation_entry(&line), g.column_entry(&line, false)]
            })
            .flatten()
            .filter(|e| e.normal.dot(line.n) < 0.0)
            .map(|e| e.s)
            .fold(f64::INFINITY, f64::min)
    };
    let (mut differ, mut grazing) = (0, 0);
    for (i, (x, y)) in a.deviations.iter().zip(&b.deviations).enumerate() {
        let same = match (x.signed_mm, y.signed_mm) {
            (Some(p), Some(q)) => {
                (p - q).abs() <= 1e-9 && (a.facing[i] - b.facing[i]).abs() <= 1e-9
            }
            (None, None) => true,
            (Some(p), None) if (p - brute(i)).abs() <= 1e-9 => {
                grazing += 1;
                true
            }
            _ => false,
        };
        if !same {
            differ += 1;
            if differ < 5 {
                eprintln!(
                    "{what}: vertex {i}: {x:?} ({}) vs {y:?} ({})",
                    a.facing[i], b.facing[i]
                );
            }
        }
    }
    assert_eq!(differ, 0, "{what}: {differ} vertices differ");
    assert!(
        grazing * 1000 <= a.deviations.len(),
        "{what}: {grazing} vertices read by the direct search only"
    );
    eprintln!("{what}: {grazing} vertices read by the direct search only");
}

/// The fast locator finds exactly the crossings the reference finds (every triangle of the
/// swept surface in one BVH, every crossing collected, then selected; every cap tested), so
/// the measured deviations are bit-identical, on the linear and on the exact surface: a
/// 3-axis ball zig-zag over the dome (caps at the pass ends and the plate–dome corner) and a
/// 5-axis bull pass over the twisted blade with its back-gouge sweep.
#[test]
fn fast_locator_equals_reference() {
    let ball = Cutter::ball(6.0).unwrap();
    let tp = dome_zigzag(3.0, (-12.0, 12.0), (-6.0, 6.0), 1.2);
    let r = refined_dome(0.05, &ball);
    let fwd = SweepModel::new(&tp, &ball, &SweepConfig::default());
    let cfg = DeviationConfig::default();
    for surface in [SurfaceModel::Linear, SurfaceModel::Exact] {
        let fast = measure_with(&r, &[&fwd], &tp, &cfg, surface, Locator::Fast).unwrap();
        let refr = measure_with(&r, &[&fwd], &tp, &cfg, surface, Locator::Reference).unwrap();
        assert!(fast.stats.crossed > 1000, "{:?}", fast.stats);
        if surface == SurfaceModel::Linear {
            assert_same(&fast, &refr, &format!("dome zig-zag {surface:?}"));
        } else {
            // Every move translates: the fast measurement searches the moves' volumes
            // directly, without the imprint surface, and must read what the reference reads
            // through its crossings (a cap's reading comes from a move ending there).
            assert_same_readings(&fast, &refr, &r, &tp, &ball, "dome zig-zag Exact");
        }
    }

    let bull = Cutter::bull(38.0, 3.0).unwrap();
    let surface = TestSurface::Blade {
        twist_rad_per_mm: 0.004,
    };
    let spec = PassSpec {
        surface,
        v_mm: 20.0,
        u0_mm: 0.0,
        poses: 16,
        step_mm: 1.5,
        lead_deg: 8.0,
        lead_wobble_deg: 2.0,
        wobble_period_mm: 30.0,
        tilt_deg: 3.0,
    };
    let path = pass(&spec, &bull);
    let lines = normal_lines(&surface, (2.0, 20.0), (12.0, 28.0), 19, 17, 0.0);
    let r = RefinedMesh {
        positions: lines.iter().map(|l| l.0).collect(),
        normals: lines.iter().map(|l| l.1).collect(),
        triangles: Vec::new(),
        face_source: Vec::new(),
        max_edge_mm: 1.0,
    };
    let cfg5 = SweepConfig {
        max_step_mm: 0.25,
        ..SweepConfig::default()
    };
    let fwd = SweepModel::new(&path, &bull, &cfg5);
    let rev = SweepModel::new(
        &path,
        &bull,
        &SweepConfig {
            reverse: true,
            ..cfg5
        },
    );
    for surface in [SurfaceModel::Linear, SurfaceModel::Exact] {
        let models = [&fwd, &rev];
        let fast = measure_with(&r, &models, &path, &cfg, surface, Locator::Fast).unwrap();
        let refr = measure_with(&r, &models, &path, &cfg, surface, Locator::Reference).unwrap();
        assert!(fast.stats.crossed > 200, "{:?}", fast.stats);
        assert_same(&fast, &refr, &format!("5-axis blade {surface:?}"));
    }
}

/// The measurement is the same on 1 and on 2 threads, bit for bit.
#[test]
fn measurement_does_not_depend_on_threads() {
    let ball = Cutter::ball(6.0).unwrap();
    let tp = dome_zigzag(3.0, (-10.0, 10.0), (-4.0, 4.0), 1.0);
    let r = refined_dome(0.05, &ball);
    let fwd = SweepModel::new(&tp, &ball, &SweepConfig::default());
    let cfg = DeviationConfig::default();
    let run = |n: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
            .install(|| {
                measure_with(&r, &[&fwd], &tp, &cfg, SurfaceModel::Exact, Locator::Fast).unwrap()
            })
    };
    assert_same(&run(1), &run(2), "1 vs 2 threads");
}

/// Measuring again in the same pass (`measure_then`) reads what a second measurement of the
/// picked vertices alone reads, their inner lengths changed, and leaves the rest and the
/// counts as the first pass has them: for a ball (the runs), a bull (Newton's method, whose
/// last bits follow its seeds) and a flat end mill, the picks spread over the part.
#[test]
fn measuring_again_in_one_pass_equals_a_second_measurement() {
    for cutter in [
        Cutter::ball(6.0).unwrap(),
        Cutter::bull(6.0, 1.5).unwrap(),
        Cutter::flat(6.0).unwrap(),
    ] {
        let tp = dome_zigzag(3.0, (-10.0, 10.0), (-4.0, 4.0), 1.0);
        let r = refined_dome(0.05, &cutter);
        let fwd = SweepModel::new(&tp, &cutter, &SweepConfig::default());
        let cfg = DeviationConfig::default();
        // Every 7th vertex, from lengths between 0 and 2 mm.
        let picks: Vec<(usize, f64)> = (0..r.len())
            .step_by(7)
            .map(|i| (i, (i % 5) as f64 * 0.5))
            .collect();
        let mut seen = 0;
        let mut pick = |m: &Measurement| {
            seen = m.deviations.len();
            picks.clone()
        };
        let none = |_: usize, _: usize| {};
        // Laid out ahead for a box that holds every vector, and for one that holds none (the
        // measurement then lays out its own): the same readings.
        let b = dome().bounds();
        let pad = DVec3::splat(cfg.inside_mm.max(cfg.outside_mm) + 1e-6);
        let models = [&fwd];
        let whole = layout(
            &models,
            &tp,
            SurfaceModel::Exact,
            (b.min - pad, b.max + pad),
        );
        let small = layout(&models, &tp, SurfaceModel::Exact, (b.min, b.min));
        let both = measure_then(&r, &whole, &cfg, &none, &mut pick).unwrap();
        let mut pick_again = |_: &Measurement| picks.clone();
        let other = measure_then(&r, &small, &cfg, &none, &mut pick_again).unwrap();
        assert_same(&both, &other, "laid out ahead or not");
        assert_eq!(seen, r.len(), "the first pass is handed over whole");
        let first = measure_progress(&r, &[&fwd], &tp, &cfg, SurfaceModel::Exact, &none).unwrap();
        let sub = RefinedMesh {
            positions: picks.iter().map(|&(i, _)| r.positions[i]).collect(),
            normals: picks.iter().map(|&(i, _)| r.normals[i]).collect(),
            triangles: Vec::new(),
            face_source: Vec::new(),
            max_edge_mm: r.max_edge_mm,
        };
        let lens: Vec<f64> = picks.iter().map(|&(_, l)| l).collect();
        let again = measure_with_inner(
            &sub,
            &lens,
            &[&fwd],
            &tp,
            &cfg,
            SurfaceModel::Exact,
            Locator::Fast,
        )
        .unwrap();
        let mut expect = first.clone();
        for (k, &(i, _)) in picks.iter().enumerate() {
            expect.deviations[i] = again.deviations[k];
            expect.facing[i] = again.facing[k];
            expect.linear_mm[i] = again.linear_mm[k];
            expect.source[i] = again.source[k];
            expect.from_start[i] = again.from_start[k];
        }
        let changed = picks
            .iter()
            .enumerate()
            .filter(|&(k, &(i, _))| first.deviations[i] != again.deviations[k])
            .count();
        assert!(
            changed > 0,
            "{cutter:?}: some picked vertex reads otherwise"
        );
        assert_same(&both, &expect, &format!("{cutter:?}"));
        assert_eq!(both.from_start, expect.from_start);
        assert_eq!(both.linear_mm, expect.linear_mm);
        // A bad length is refused.
        let mut bad = |_: &Measurement| vec![(0, f64::NAN)];
        assert!(measure_then(&r, &whole, &cfg, &none, &mut bad).is_err());
    }
}

/// On the exact surface, vertical vectors from the dome's top surface at z-map nodes read
/// exactly the machined height the independent z-map computes there (closed form for a
/// ball). Like with like: both are the lowest point of the swept volume on the vertical
/// through the node (the z-map sweeps every move; the path has no rapid over the part). The
/// paper's linear surface reads up to the chord sag `r(1 − cos π/Q)` higher, and over the
/// dome's crest, where the imprinted half flips and only the caps at the two poses stand for
/// a step, up to that step's bulge `r − √(r² − (0.25 mm)²)` more.
#[test]
fn exact_surface_equals_zmap_on_vertical_lines() {
    let ball = Cutter::ball(6.0).unwrap();
    let tp = dome_zigzag(3.0, (-14.0, 14.0), (-8.0, 8.0), 1.1);
    let grid = ZmapGrid::covering(-10.0, -5.0, 10.0, 5.0, 0.1).unwrap();
    let zm = zmap::machine(&tp, &ball, &ZmapConfig::new(grid)).unwrap();
    let design = zmap::DesignHeights::new(&dome());
    let mut positions = Vec::new();
    let mut nodes = Vec::new();
    for j in 0..grid.ny {
        for i in 0..grid.nx {
            let (x, y) = (grid.x(i), grid.y(j));
            let z = design.top(x, y).expect("dome below").0;
            positions.push(DVec3::new(x, y, z));
            nodes.push((i, j));
        }
    }
    let n = positions.len();
    let r = RefinedMesh {
        positions,
        normals: vec![DVec3::Z; n],
        triangles: Vec::new(),
        face_source: Vec::new(),
        max_edge_mm: 0.1,
    };
    let fwd = SweepModel::new(&tp, &ball, &SweepConfig::default());
    let cfg = DeviationConfig::default();
    let sag = 3.0 * (1.0 - (std::f64::consts::PI / 40.0).cos());
    let bulge = 3.0 - (9.0f64 - 0.25 * 0.25).sqrt();
    for (surface, tol) in [
        (SurfaceModel::Exact, 1e-9),
        (SurfaceModel::Linear, sag + bulge),
    ] {
        let m = measure_with(&r, &[&fwd], &tp, &cfg, surface, Locator::Fast).unwrap();
        let (mut worst, mut below) = (0.0f64, 0.0f64);
        for (d, &(i, j)) in m.deviations.iter().zip(&nodes) {
            let z = d.position.z + d.signed_mm.expect("every node is under the passes");
            let diff = z - zm.height(i, j);
            worst = worst.max(diff.abs());
            below = below.min(diff);
        }
        println!("{surface:?}: |imprint − z-map| max {:.3e} mm", worst);
        assert!(worst <= tol, "{surface:?}: {worst} > {tol}");
        // The linear surface never lies below the true one (its points are on it, its chords
        // inside the tool).
        assert!(below >= -1e-9, "{surface:?}: {below} below the z-map");
        if surface == SurfaceModel::Linear {
            assert!(
                worst > 0.3 * sag,
                "linear surface suspiciously exact: {worst}"
            );
        }
    }
}

/// A plunge and a retract move along the tool axis: no demarcation picks a half of the wall
/// they sweep, and both halves are real (nothing above or beside the tool covers either), so
/// a line coming at the wall from any side enters it where the cylinder of radius R is.
#[test]
fn plunge_walls_are_entered_from_every_side() {
    use cam_verify::measure::first_entries;
    let mv = |kind, z: f64| Move {
        kind,
        pose: Pose::vertical(DVec3::new(0.0, 0.0, z)),
        feed_mm_per_min: Some(500.0),
        line: None,
        pass: None,
    };
    let tp = Toolpath {
        moves: vec![
            mv(MoveKind::Rapid, 10.0),
            mv(MoveKind::Plunge, 0.0),
            mv(MoveKind::Retract, 10.0),
        ],
    };
    for spec in ["flat:6", "bull:6:1.5", "ball:6"] {
        let cutter: Cutter = spec.parse().unwrap();
        let model = SweepModel::new(&tp, &cutter, &SweepConfig::default());
        // Horizontal lines towards the axis from 4 mm out, at heights where the swept wall
        // is the cylinder of radius 3 for every cutter, from 16 directions.
        let mut lines = Vec::new();
        for k in 0..16 {
            let a = k as f64 * std::f64::consts::TAU / 16.0 + 0.1;
            let d = DVec3::new(a.cos(), a.sin(), 0.0);
            for z in [4.0, 6.0, 8.0] {
                lines.push((4.0 * d + DVec3::new(0.0, 0.0, z), -d));
            }
        }
        let got = first_entries(&[&model], &tp, &lines, 3.0, SurfaceModel::Exact);
        for (l, s) in lines.iter().zip(&got) {
            let s = s.unwrap_or_else(|| panic!("{spec}: line from {:?} enters nothing", l.0));
            assert!(
                (s - 1.0).abs() <= 1e-9,
                "{spec}: line from {:?} enters at {s}",
                l.0
            );
        }
    }
}

/// A level move seen from the side: a horizontal line at height `z` above the tip meets the
/// cutter's outline, `a + sqrt(r² − (r − z)²)` from the axis below the torus centre and
/// `R` above it, up the flutes and the shank without limit. (The sweep imprints the
/// corner only; the verifier used to see nothing of the cutter above its corner, and
/// passed a flat end mill that cut 0.1 mm into a wall with its side.)
#[test]
fn the_side_above_the_corner_is_entered() {
    use cam_verify::measure::first_entries;
    let mv = |kind, y: f64| Move {
        kind,
        pose: Pose::vertical(DVec3::new(0.0, y, 0.0)),
        feed_mm_per_min: Some(500.0),
        line: None,
        pass: None,
    };
    let tp = Toolpath {
        moves: vec![mv(MoveKind::Rapid, 0.0), mv(MoveKind::Cut, 10.0)],
    };
    for spec in ["flat:6", "bull:6:1.5", "ball:6"] {
        let cutter: Cutter = spec.parse().unwrap();
        let (a, r) = (cutter.major_radius(), cutter.corner_radius());
        let model = SweepModel::new(&tp, &cutter, &SweepConfig::default());
        let heights: Vec<f64> = (1..=40).map(|i| 0.25 * i as f64).chain([50.0]).collect();
        // From both sides, across the move's middle.
        let mut lines = Vec::new();
        for &z in &heights {
            for d in [DVec3::X, -DVec3::X] {
                lines.push((5.0 * d + DVec3::new(0.0, 5.0, z), -d));
            }
        }
        let got = first_entries(&[&model], &tp, &lines, 5.0, SurfaceModel::Exact);
        for ((o, _), s) in lines.iter().zip(&got) {
            let z = o.z;
            let reach = if z >= r {
                a + r
            } else {
                a + (r * r - (r - z) * (r - z)).sqrt()
            };
            let s = s.unwrap_or_else(|| panic!("{spec}: the line at {o:?} enters nothing"));
            assert!(
                (s - (5.0 - reach)).abs() <= 1e-9,
                "{spec}: the line at {o:?} enters at {s}, the outline is {reach} from the axis"
            );
        }
    }
}

/// A gouging 3-axis program over the dome with everything a real one has: passes both ways
/// 0.05 mm below a ball's drop surface (so every cutter cuts into the part), each entered by
/// a plunge from above and left by a retract, the passes joined by rapids.
fn dome_program_with_plunges() -> Toolpath {
    let mv = |kind, x: f64, y: f64, z: f64| Move {
        kind,
        pose: Pose::vertical(DVec3::new(x, y, z)),
        feed_mm_per_min: Some(1000.0),
        line: None,
        pass: None,
    };
    let mut moves = vec![mv(MoveKind::Rapid, -12.0, -6.0, 30.0)];
    for (j, y) in [-6.0, -4.5, -3.0, -1.5, 0.0, 1.5, 3.0]
        .into_iter()
        .enumerate()
    {
        let xs: Vec<f64> = (0..=48).map(|i| -12.0 + 0.5 * i as f64).collect();
        let xs: Vec<f64> = if j % 2 == 0 {
            xs
        } else {
            xs.into_iter().rev().collect()
        };
        let z = |x: f64| ball_tip_on_dome(x, y, 3.0) - 0.05;
        moves.push(mv(MoveKind::Rapid, xs[0], y, 30.0));
        moves.push(mv(MoveKind::Plunge, xs[0], y, z(xs[0])));
        for &x in &xs[1..] {
            moves.push(mv(MoveKind::Cut, x, y, z(x)));
        }
        let last = *xs.last().unwrap();
        moves.push(mv(MoveKind::Retract, last, y, 30.0));
    }
    Toolpath { moves }
}

/// Checks the first entries [`cam_verify::measure::first_entries`] reads along `lines`
/// (origin and unit direction, searched over 0..4 mm) for the cutter `spec` on `tp` against
/// the brute force: the least entry, facing against the line, into the puck or the column
/// (`base` as in `MoveGeometry::column_entry`) of every feed move, one by one. Returns the
/// brute-force entries (`∞` where the line enters nothing).
fn entries_equal_brute_force(
    tp: &Toolpath,
    spec: &str,
    lines: &[(DVec3, DVec3)],
    base: bool,
) -> Vec<f64> {
    use cam_verify::exact::{Line, MoveGeometry, Puck};
    let cutter: Cutter = spec.parse().unwrap();
    let model = SweepModel::new(tp, &cutter, &SweepConfig::default());
    let got = cam_verify::measure::first_entries(&[&model], tp, lines, 4.0, SurfaceModel::Exact);
    let puck = Puck::of(&cutter);
    let moves: Vec<MoveGeometry> = tp
        .moves
        .windows(2)
        .filter(|w| w[1].kind != MoveKind::Rapid)
        .map(|w| MoveGeometry {
            a: w[0].pose,
            b: w[1].pose,
            puck,
        })
        .collect();
    let mut out = Vec::with_capacity(lines.len());
    for (&(o, n), got) in lines.iter().zip(&got) {
        let line = Line {
            o,
            n,
            lo: 0.0,
            hi: 4.0,
        };
        let least = |f: &dyn Fn(&MoveGeometry) -> Option<cam_verify::exact::Entry>| {
            moves
                .iter()
                .filter_map(f)
                .filter(|e| e.normal.dot(n) < 0.0)
                .map(|e| e.s)
                .fold(f64::INFINITY, f64::min)
        };
        let pucks = least(&|g| g.translation_entry(&line));
        let columns = least(&|g| g.column_entry(&line, base));
        let brute = pucks.min(columns);
        let got = got.unwrap_or(f64::INFINITY);
        if brute.is_infinite() {
            assert!(
                got.is_infinite(),
                "{spec}: {o:?}: read {got}, nothing there"
            );
        } else {
            assert!(
                (got - brute).abs() <= 1e-9,
                "{spec}: {o:?}: read {got}, brute force {brute} (pucks {pucks}, columns {columns})"
            );
        }
        out.push(brute);
    }
    out
}

/// The exact measurement against brute force: the first entry of each line into the whole
/// cutter swept along every feed move of the program, its puck and its column (the cutter
/// above its corner) tested one by one. Along the dome's normals, from 1 mm inside to 3 mm
/// outside, for a ball, a bull and a flat end mill: every reading, gouge or material left,
/// equals the brute force, those deeper than the line reaches and those where the nearest
/// part of the tool is its side above the corner included.
#[test]
fn exact_entries_equal_brute_force_over_every_move() {
    let tp = dome_program_with_plunges();
    // Normals of the hemisphere (radius 20 about the origin) and of the plate around it.
    let mut lines = Vec::new();
    for i in 0..60 {
        for j in 0..30 {
            let (x, y) = (
                -11.0 + 22.0 * i as f64 / 59.0,
                -7.0 + 11.0 * j as f64 / 29.0,
            );
            let d2 = x * x + y * y;
            let (p, n) = if d2 < 400.0 {
                let p = DVec3::new(x, y, (400.0 - d2).sqrt());
                (p, p / 20.0)
            } else {
                (DVec3::new(x, y, 0.0), DVec3::Z)
            };
            lines.push((p - 1.0 * n, n));
        }
    }
    for spec in ["ball:6", "bull:6:1.5", "flat:6"] {
        let brute = entries_equal_brute_force(&tp, spec, &lines, true);
        let gouges = brute.iter().filter(|&&b| b < 1.0).count();
        let starts = brute.iter().filter(|&&b| b == 0.0).count();
        println!(
            "{spec}: {} lines, all exact: {gouges} gouges ({starts} starting inside the \
             cutter)",
            lines.len()
        );
        assert!(gouges > 100, "{spec}: the program gouges: {gouges}");
        if spec == "flat:6" {
            // A flat end mill at a ball's tips sinks more than 1 mm into the dome's flanks.
            assert!(starts > 100, "{spec}: {starts} lines start in the cutter");
        }
    }
}

/// A flat end mill's level passes at the height of a vertex on a part's edge (the tool
/// resting on the face the vertex bounds): the vertex is on the bottom of the second pass,
/// and its vector, along the edge's averaged normal, reads 0. (The line's lowest crossing
/// is on the first pass's edge, whose exact volume it only grazes: refuted. The second
/// pass's crossing lay 2.5e-16 mm above it, and a flat sheet's window is 0, so it was
/// skipped as unable to reach below the lowest crossing; the reading fell to the side of
/// the link beyond, 1.39 mm away. Found on ocl_sphere_on_plate's planned program, whose
/// moves these are.)
#[test]
fn a_flat_bottom_through_the_vertex_reads_zero() {
    let mv = |kind, x: f64, y: f64| Move {
        kind,
        pose: Pose::vertical(DVec3::new(x, y, 14.9359)),
        feed_mm_per_min: Some(1000.0),
        line: None,
        pass: None,
    };
    let tp = Toolpath {
        moves: vec![
            mv(MoveKind::Rapid, -3.0, 60.3374),
            mv(MoveKind::Cut, 79.4923, 60.3374),
            mv(MoveKind::Cut, 79.4923, 65.5648),
            mv(MoveKind::Cut, -3.0, 65.5648),
            mv(MoveKind::Cut, -3.0, 71.2648),
        ],
    };
    let cutter: Cutter = "flat:6".parse().unwrap();
    let model = SweepModel::new(&tp, &cutter, &SweepConfig::default());
    let sub = RefinedMesh {
        positions: vec![DVec3::new(0.0, 63.345185937500005, 14.9359)],
        normals: vec![DVec3::new(-1.0, 0.0, 1.0).normalize()],
        triangles: Vec::new(),
        face_source: Vec::new(),
        max_edge_mm: 0.1,
    };
    let cfg = DeviationConfig::default();
    for loc in [Locator::Fast, Locator::Reference] {
        let m = measure_with(&sub, &[&model], &tp, &cfg, SurfaceModel::Exact, loc).unwrap();
        let s = m.deviations[0].signed_mm.unwrap();
        assert!(s.abs() < 1e-9, "{loc:?}: read {s}");
    }
}

/// The dense program of `fixtures/verify/mount_rush_bull_dense.ngc` and the design vertex
/// (position, unit normal) it was cut about.
fn dense_program() -> (Toolpath, DVec3, DVec3) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/verify");
    let tp = cam_gcode::read_gcode(
        root.join("mount_rush_bull_dense.ngc"),
        &cam_gcode::ReadConfig::default(),
    )
    .unwrap();
    let o = DVec3::new(-25.489606857299805, -2.1983015537261963, 1.3206899166107178);
    let n = DVec3::new(0.6608251943731915, -0.2218887422182684, 0.7169905498389979).normalize();
    (tp, o, n)
}

/// A dense program read exactly: the feed moves of a bull-nose plan of mount_rush within
/// 3 mm (in XY) of one design vertex, 2038 moves. Before the direct search of translation
/// programs, the crossing locator overflowed on this vector (too many crossings within its
/// window) and read −0.009746 mm from move 1353; the brute force over every move's puck and
/// column says −0.010022 mm, from move 1476: a gouge deeper than τ = 0.01 along the normal,
/// missed. The measurement must read the brute force.
#[test]
fn a_dense_program_is_read_exactly() {
    use cam_verify::exact::{Line, MoveGeometry, Puck};
    let (tp, o, n) = dense_program();
    let bull = Cutter::bull(6.0, 1.5).unwrap();
    let cfg = DeviationConfig::default();
    let line = Line {
        o,
        n,
        lo: -cfg.inside_mm,
        hi: cfg.outside_mm,
    };
    let (mut brute, mut from) = (f64::INFINITY, 0);
    for (i, w) in tp.moves.windows(2).enumerate() {
        if w[1].kind == MoveKind::Rapid {
            continue;
        }
        let g = MoveGeometry {
            a: w[0].pose,
            b: w[1].pose,
            puck: Puck::of(&bull),
        };
        for e in [g.translation_entry(&line), g.column_entry(&line, false)]
            .into_iter()
            .flatten()
        {
            if e.normal.dot(n) < 0.0 && e.s < brute {
                (brute, from) = (e.s, i + 1);
            }
        }
    }
    assert!(
        brute < -0.01,
        "the brute force reads {brute} from move {from}"
    );
    let r = RefinedMesh {
        positions: vec![o],
        normals: vec![n],
        triangles: Vec::new(),
        face_source: Vec::new(),
        max_edge_mm: 0.1,
    };
    let model = SweepModel::new(&tp, &bull, &SweepConfig::default());
    let m = measure_with(&r, &[&model], &tp, &cfg, SurfaceModel::Exact, Locator::Fast).unwrap();
    let got = m.deviations[0].signed_mm.unwrap();
    assert!(
        (got - brute).abs() <= 1e-9,
        "read {got}, the brute force {brute} (move {from})"
    );
    assert_eq!(m.deviations[0].source_move, Some(from as u32));
}

/// Many vectors in that dense program, read as a group and against the brute force: 169
/// parallel lines about the same vertex, 0.25 mm apart across the normal, for a ball, a bull
/// and a flat end mill. Neighbours enter the move that cut the one before, so they are read
/// in groups: some groups' boxes reach few enough moves to search them as a list, the
/// others search the trees. Every reading must equal the least entry over every move's puck
/// and column.
#[test]
fn a_dense_program_is_read_exactly_in_groups() {
    let (tp, o, n) = dense_program();
    let u = n.any_orthonormal_vector();
    let w = n.cross(u);
    let mut lines = Vec::new();
    for i in -6..=6 {
        for j in -6..=6 {
            let p = o + 0.25 * (i as f64 * u + j as f64 * w);
            lines.push((p - 1.0 * n, n));
        }
    }
    for spec in ["ball:6", "bull:6:1.5", "flat:6"] {
        let brute = entries_equal_brute_force(&tp, spec, &lines, false);
        let read = brute.iter().filter(|b| b.is_finite()).count();
        println!("{spec}: {read} of {} lines read, all exact", lines.len());
        assert!(read > 150, "{spec}: only {read} lines enter the cutter");
    }
}

/// The entry of `line` into each feed move's puck (`MoveGeometry::translation_entry`), with
/// the move's index, in move order.
fn feed_entries(
    tp: &Toolpath,
    cutter: &Cutter,
    line: &cam_verify::exact::Line,
) -> Vec<(f64, usize)> {
    use cam_verify::exact::{MoveGeometry, Puck};
    (1..tp.moves.len())
        .filter(|&k| tp.moves[k].kind != MoveKind::Rapid)
        .filter_map(|k| {
            let g = MoveGeometry {
                a: tp.moves[k - 1].pose,
                b: tp.moves[k].pose,
                puck: Puck::of(cutter),
            };
            g.translation_entry(line).map(|e| (e.s, k))
        })
        .collect()
}

/// Measures vertices at `positions` with the normal `n` against `cutter` on `tp` and checks
/// each reading and its source move against `expected`, in order.
fn reads_as(
    tp: &Toolpath,
    cutter: &Cutter,
    cfg: &DeviationConfig,
    positions: Vec<DVec3>,
    n: DVec3,
    expected: &[(f64, u32)],
) {
    let r = RefinedMesh {
        normals: vec![n; positions.len()],
        positions,
        triangles: Vec::new(),
        face_source: Vec::new(),
        max_edge_mm: 0.1,
    };
    let model = SweepModel::new(tp, cutter, &SweepConfig::default());
    let m = measure_with(&r, &[&model], tp, cfg, SurfaceModel::Exact, Locator::Fast).unwrap();
    assert_eq!(m.deviations.len(), expected.len());
    for (k, (d, &(s, mv))) in m.deviations.iter().zip(expected).enumerate() {
        assert_eq!(d.signed_mm, Some(s), "vector {k}: {d:?}");
        assert_eq!(d.source_move, Some(mv), "vector {k}");
    }
}

/// Vectors that start inside the cutter, in the dense program: each starts 0.5 mm below
/// the ball's centre at the middle of one of its feed moves, where the balls of many moves
/// before and after it overlap. Every one reads its start, and its source is the
/// lowest-numbered move whose volume holds that start (the tie rule of
/// `measure::take_least`), found by trying every move in order: a search that stops
/// looking once the start is held must still look at every lower-numbered move.
#[test]
fn a_start_inside_many_moves_names_the_lowest_numbered() {
    use cam_verify::exact::Line;
    let (tp, _, _) = dense_program();
    let ball = Cutter::ball(6.0).unwrap();
    let cfg = DeviationConfig::default();
    let n = DVec3::new(0.3, -0.2, 0.9).normalize();
    let feeds: Vec<usize> = (1..tp.moves.len())
        .filter(|&i| tp.moves[i].kind != MoveKind::Rapid)
        .collect();
    let (mut positions, mut expected) = (Vec::new(), Vec::new());
    let mut held_by_many = 0;
    for &i in feeds.iter().step_by(37) {
        let (a, b) = (tp.moves[i - 1].pose.tip, tp.moves[i].pose.tip);
        let start = 0.5 * (a + b) + DVec3::new(0.0, 0.0, 3.0 - 0.5);
        let line = Line {
            o: start,
            n,
            lo: 0.0,
            hi: 4.0,
        };
        let holders: Vec<usize> = feed_entries(&tp, &ball, &line)
            .into_iter()
            .filter(|e| e.0 == 0.0)
            .map(|e| e.1)
            .collect();
        assert!(holders.contains(&i), "move {i} holds its own start");
        held_by_many += usize::from(holders.len() > 10);
        positions.push(start + cfg.inside_mm * n);
        expected.push((-cfg.inside_mm, holders[0] as u32));
    }
    assert!(
        held_by_many * 2 > positions.len(),
        "most starts lie in many moves' volumes: {held_by_many} of {}",
        positions.len()
    );
    reads_as(&tp, &ball, &cfg, positions, n, &expected);
}

/// A bull's vectors rising through a floor its level passes share: lines up +Z from below
/// the plane the tool's flat bottom rests on, under a zig-zag of level passes 1 mm apart
/// with steps of 0.5 mm, so each line meets the bottoms of some twenty moves at the same
/// height. Each reads that height, from the lowest-numbered of those moves: a search
/// that turns away moves whose slab it enters no earlier than the best entry must still
/// try every lower-numbered one.
#[test]
fn a_floor_shared_by_many_moves_names_the_lowest_numbered() {
    use cam_verify::exact::Line;
    let bull = Cutter::bull(6.0, 1.5).unwrap();
    let mv = |kind, x: f64, y: f64, z: f64| Move {
        kind,
        pose: Pose::vertical(DVec3::new(x, y, z)),
        feed_mm_per_min: Some(1000.0),
        line: None,
        pass: None,
    };
    let mut moves = vec![mv(MoveKind::Rapid, -10.0, -5.0, 10.0)];
    moves.push(mv(MoveKind::Plunge, -10.0, -5.0, 0.0));
    for j in 0..=10 {
        let y = -5.0 + j as f64;
        let xs: Vec<f64> = (0..=40).map(|i| -10.0 + 0.5 * i as f64).collect();
        let xs: Vec<f64> = if j % 2 == 0 {
            xs
        } else {
            xs.into_iter().rev().collect()
        };
        for &x in &xs {
            moves.push(mv(MoveKind::Cut, x, y, 0.0));
        }
    }
    let tp = Toolpath { moves };
    let cfg = DeviationConfig::default();
    let n = DVec3::Z;
    let (mut positions, mut expected) = (Vec::new(), Vec::new());
    for i in 0..12 {
        for j in 0..8 {
            let p = DVec3::new(-7.3 + 1.21 * i as f64, -3.9 + 0.93 * j as f64, 0.0);
            let line = Line {
                o: p - cfg.inside_mm * n,
                n,
                lo: 0.0,
                hi: cfg.inside_mm + cfg.outside_mm,
            };
            let entries = feed_entries(&tp, &bull, &line);
            let least = entries.iter().map(|e| e.0).fold(f64::INFINITY, f64::min);
            let ties: Vec<usize> = entries
                .iter()
                .filter(|e| e.0 == least)
                .map(|e| e.1)
                .collect();
            assert!(
                ties.len() > 10,
                "{p:?}: {} moves meet the floor there",
                ties.len()
            );
            positions.push(p);
            expected.push((least - cfg.inside_mm, ties[0] as u32));
        }
    }
    reads_as(&tp, &bull, &cfg, positions, n, &expected);
}
