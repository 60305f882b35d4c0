//! `cam verify`: gouges found and located, exit codes, outputs.

use crate::support::{SQUARE_OBJ, cam, stderr, write};

/// A ball:6 pass along y = 5 over the unit square at z = 1, tip at `z`.
fn pass_at(z: f64) -> String {
    format!("G21 G90 G17\nG0 Z5\nG0 X-2 Y5\nG1 Z{z} F100\nG1 X12 F500\nG0 Z5\nM30\n")
}

#[test]
fn tangent_pass_is_clean_and_outputs_are_written() {
    let d = tempfile::tempdir().unwrap();
    let part = write(d.path(), "sq.obj", SQUARE_OBJ);
    let ngc = write(d.path(), "p.ngc", &pass_at(1.0));
    let (ply, png, stl) = (
        d.path().join("dev.ply"),
        d.path().join("map.png"),
        d.path().join("swept.stl"),
    );
    let o = cam(&[
        "verify",
        ngc.to_str().unwrap(),
        "--part",
        part.to_str().unwrap(),
        "--tool",
        "ball:6",
        "--json",
        "--deviation",
        ply.to_str().unwrap(),
        "--heatmap",
        png.to_str().unwrap(),
        "--swept",
        stl.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    // The ball rests on the plane: no gouge; the groove's bottom is exact to the imprint
    // model's flat-bottom accuracy.
    assert!(j["max_gouge_mm"].as_f64().unwrap() < 1e-6, "{j}");
    assert!(j["measured"].as_u64().unwrap() > 100, "{j}");
    for p in [&ply, &png, &stl] {
        assert!(
            std::fs::metadata(p).unwrap().len() > 100,
            "{} not written",
            p.display()
        );
    }
}

#[test]
fn plunge_below_surface_is_a_located_gouge_exit_1() {
    let d = tempfile::tempdir().unwrap();
    let part = write(d.path(), "sq.obj", SQUARE_OBJ);
    let ngc = write(d.path(), "p.ngc", &pass_at(0.9));
    let o = cam(&[
        "verify",
        ngc.to_str().unwrap(),
        "--part",
        part.to_str().unwrap(),
        "--tool",
        "ball:6",
        "--json",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let g = j["max_gouge_mm"].as_f64().unwrap();
    // The tip runs 0.1 below the plane along y = 5: the deepest point is under the tip.
    assert!((g - 0.1).abs() < 1e-3, "max gouge {g}");
    let w = &j["worst_gouges"][0];
    assert!(
        (w["position"][1].as_f64().unwrap() - 5.0).abs() < 0.2,
        "{w}"
    );
    assert!(
        w["line"] == 4 || w["line"] == 5,
        "worst gouge names the cutting line: {w}"
    );
    assert!(
        stderr(&o).contains("exceeds the tolerance"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn bad_gcode_names_line_and_column_exit_2() {
    let d = tempfile::tempdir().unwrap();
    let part = write(d.path(), "sq.obj", SQUARE_OBJ);
    let ngc = write(d.path(), "bad.ngc", "G21 G90\nG0 Z5\nG1 X1 Q7 F100\n");
    let o = cam(&[
        "verify",
        ngc.to_str().unwrap(),
        "--part",
        part.to_str().unwrap(),
        "--tool",
        "ball:6",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("bad.ngc:3:"), "{}", stderr(&o));
    let apt = write(d.path(), "bad.apt", "GOTO/1,2,3,0,0,0\n");
    let o = cam(&[
        "verify",
        apt.to_str().unwrap(),
        "--part",
        part.to_str().unwrap(),
        "--tool",
        "ball:6",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("bad.apt:1"), "{}", stderr(&o));
}

/// `--surface linear` measures the paper's piecewise-linear surface, `exact` (the default)
/// the refined one: a ball 0.1 mm below the plane reads a 0.1 mm gouge on the exact surface
/// to rounding, and at most that on the linear one (its chords lie inside the tool).
#[test]
fn surface_flag_selects_linear_or_exact() {
    let d = tempfile::tempdir().unwrap();
    let part = write(d.path(), "sq.obj", SQUARE_OBJ);
    let ngc = write(d.path(), "p.ngc", &pass_at(0.9));
    let gouge = |surface: &str| {
        let o = cam(&[
            "verify",
            ngc.to_str().unwrap(),
            "--part",
            part.to_str().unwrap(),
            "--tool",
            "ball:6",
            "--surface",
            surface,
            "--json",
        ]);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(
            j["settings"]["extra"]["exact_surface"].as_f64(),
            Some(if surface == "exact" { 1.0 } else { 0.0 }),
            "{j}"
        );
        j["max_gouge_mm"].as_f64().unwrap()
    };
    let (exact, linear) = (gouge("exact"), gouge("linear"));
    assert!((exact - 0.1).abs() < 1e-9, "exact {exact}");
    assert!(linear <= exact + 1e-12 && linear > 0.09, "linear {linear}");
    let o = cam(&[
        "verify",
        ngc.to_str().unwrap(),
        "--part",
        part.to_str().unwrap(),
        "--tool",
        "ball:6",
        "--surface",
        "cubic",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}

/// An axis-aligned box `[x0, x1] × [0, 10] × [0, 5]` as OBJ, faces outward.
fn box_obj(x0: f64, x1: f64) -> String {
    let mut s = String::new();
    for x in [x0, x1] {
        for y in [0.0, 10.0] {
            for z in [0.0, 5.0] {
                s += &format!("v {x} {y} {z}\n");
            }
        }
    }
    let i = |a: usize, b: usize, c: usize| a * 4 + b * 2 + c + 1;
    let quads = [
        [(0, 0, 0), (0, 1, 0), (1, 1, 0), (1, 0, 0)],
        [(0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)],
        [(0, 0, 0), (0, 0, 1), (0, 1, 1), (0, 1, 0)],
        [(1, 0, 0), (1, 1, 0), (1, 1, 1), (1, 0, 1)],
        [(0, 0, 0), (1, 0, 0), (1, 0, 1), (0, 0, 1)],
        [(0, 1, 0), (0, 1, 1), (1, 1, 1), (1, 1, 0)],
    ];
    for q in quads {
        let [a, b, c, d] = q.map(|(x, y, z)| i(x, y, z));
        s += &format!("f {a} {b} {c}\nf {a} {c} {d}\n");
    }
    s
}

/// `cam verify NGC --part PART --tool TOOL --json EXTRA…`.
fn verify_json(
    ngc: &std::path::Path,
    part: &std::path::Path,
    tool: &str,
    extra: &[&str],
) -> std::process::Output {
    let mut a = vec![
        "verify",
        ngc.to_str().unwrap(),
        "--part",
        part.to_str().unwrap(),
        "--tool",
        tool,
        "--json",
    ];
    a.extend_from_slice(extra);
    cam(&a)
}

/// `cam verify NGC --part PART --tool TOOL --surface SURFACE --json`, which must exit 1 (a
/// gouge beyond the tolerance); its report.
fn verify_gouging(
    ngc: &std::path::Path,
    part: &std::path::Path,
    tool: &str,
    surface: &str,
) -> serde_json::Value {
    let o = verify_json(ngc, part, tool, &["--surface", surface]);
    assert_eq!(o.status.code(), Some(1), "{tool} {surface}: {}", stderr(&o));
    serde_json::from_slice(&o.stdout).unwrap()
}

/// A plunge whose side cuts 0.2 mm into a wall is a gouge whichever side the wall is on: a
/// move along the tool axis has no front half, both halves of its wall cut. (The verifier
/// used to model one half only, and passed this program on one side with no finding.) The
/// cutter above its corner also cuts the wall's top edge, from the plunge's bottom up
/// through the top face; the top face's vertices over the notch lie next to the wall, where
/// the reading is their depth inside the cutter (its side is at most 0.2 mm away).
#[test]
fn plunge_into_a_wall_is_a_gouge_on_either_side() {
    let d = tempfile::tempdir().unwrap();
    for (name, x0, x1, tool_x) in [("right", 0.0, 10.0, -2.8), ("left", -10.0, 0.0, 2.8)] {
        let part = write(d.path(), &format!("{name}.obj"), &box_obj(x0, x1));
        let ngc = write(
            d.path(),
            &format!("{name}.ngc"),
            &format!("G21 G90 G17\nG0 Z10\nG0 X{tool_x} Y5\nG0 Z3.5\nG1 Z2 F100\nG0 Z10\nM30\n"),
        );
        let j = verify_gouging(&ngc, &part, "flat:6", "exact");
        let g = j["max_gouge_mm"].as_f64().unwrap();
        assert!((g - 0.2).abs() < 1e-9, "{name}: max gouge {g}");
        let worst = j["worst_gouges"].as_array().unwrap();
        assert!(
            worst.iter().all(|w| w["line"] == 5),
            "{name}: the plunge's line"
        );
        // The wall itself, below the top face: 0.2 mm along its normal.
        let wall = worst
            .iter()
            .find(|w| w["position"][0].as_f64().unwrap().abs() < 1e-9)
            .unwrap_or_else(|| panic!("{name}: no gouge on the wall: {worst:?}"));
        let s = wall["signed_mm"].as_f64().unwrap();
        assert!((s + 0.2).abs() < 1e-9, "{name}: wall gouge {s}");
    }
}

/// A flat end mill run 2 mm deep across a box: its flat bottom is 1 mm below where the
/// vectors from the top face start, so only the cutter above its corner meets them. (The
/// verifier modelled the corner alone and passed this slot with no gouge and exit 0, on
/// either surface model.)
#[test]
fn slot_deeper_than_the_vectors_reach_is_a_gouge() {
    let d = tempfile::tempdir().unwrap();
    let part = write(d.path(), "box.obj", &box_obj(0.0, 10.0));
    let ngc = write(
        d.path(),
        "slot.ngc",
        "G21 G90 G17\nG0 Z10\nG0 X-5 Y5\nG1 Z3 F100\nG1 X15 F500\nG0 Z10\nM30\n",
    );
    for (tool, surface) in [
        ("flat:6", "exact"),
        ("bull:6:1.5", "exact"),
        ("ball:6", "exact"),
        ("flat:6", "linear"),
    ] {
        let j = verify_gouging(&ngc, &part, tool, surface);
        let g = j["max_gouge_mm"].as_f64().unwrap();
        assert!(g >= 1.0 - 1e-9, "{tool}: max gouge {g}");
        // The top face over the slot is among the worst gouges.
        let top = j["worst_gouges"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|w| (w["position"][2].as_f64().unwrap() - 5.0).abs() < 1e-9)
            .count();
        assert!(top > 0, "{tool}: no gouge on the top face: {j}");
    }
}

/// The vertices of a `--deviation` PLY: position and signed deviation (mm, NaN where
/// nothing was measured).
fn ply_deviations(path: &std::path::Path) -> Vec<([f32; 3], f32)> {
    let bytes = std::fs::read(path).unwrap();
    let end = b"end_header\n";
    let body = bytes.windows(end.len()).position(|w| w == end).unwrap() + end.len();
    let header = std::str::from_utf8(&bytes[..body]).unwrap();
    let n: usize = header
        .lines()
        .find_map(|l| l.strip_prefix("element vertex "))
        .unwrap()
        .parse()
        .unwrap();
    // x y z nx ny nz (f32), red green blue (u8), deviation (f32).
    let f = |at: usize| f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
    (0..n)
        .map(|i| {
            let at = body + i * 31;
            ([f(at), f(at + 4), f(at + 8)], f(at + 27))
        })
        .collect()
}

/// A cutter running beside a wall, 0.5 mm above the floor, with its side 0.1 mm into the
/// wall: every wall vertex along the straight run reads the cutter's outline at its
/// height, `a + sqrt(r² − (r − h)²)` below the torus centre and `R` above it, so the wall
/// is gouged 0.1 mm up to its top wherever the cutter above its corner is. (The verifier
/// imprinted the corner only: with a flat end mill it read nothing on the wall, max gouge
/// 0.0, and exited 0.)
#[test]
fn a_wall_cut_by_the_side_above_the_corner_is_a_gouge() {
    let d = tempfile::tempdir().unwrap();
    let part = write(d.path(), "box.obj", &box_obj(0.0, 10.0));
    let ngc = write(
        d.path(),
        "side.ngc",
        "G21 G90 G17\nG0 Z10\nG0 X-10 Y3\nG0 Z0.5\nG1 X-2.9 F500\nG1 Y7\nG1 X-10\nG0 Z10\nM30\n",
    );
    for (tool, a, r) in [
        ("flat:6", 3.0, 0.0),
        ("bull:6:1.5", 1.5, 1.5),
        ("ball:6", 0.0, 3.0),
    ] {
        let ply = d.path().join("dev.ply");
        let o = verify_json(&ngc, &part, tool, &["--deviation", ply.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(1), "{tool}: {}", stderr(&o));
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let g = j["max_gouge_mm"].as_f64().unwrap();
        assert!((g - 0.1).abs() < 1e-9, "{tool}: max gouge {g}");
        let (mut wall, mut gouged) = (0, 0);
        for ([x, y, z], dev) in ply_deviations(&ply) {
            // The wall along the straight run, off its edges (creases).
            if x != 0.0 || !(3.0..=7.0).contains(&y) || !(0.6..=4.9).contains(&z) {
                continue;
            }
            let h = f64::from(z) - 0.5;
            let outline = if h >= r {
                a + r
            } else {
                a + (r * r - (r - h) * (r - h)).sqrt()
            };
            let want = 2.9 - outline;
            assert!(
                (f64::from(dev) - want).abs() < 1e-5,
                "{tool}: wall at y {y} z {z} reads {dev}, the outline gives {want}"
            );
            wall += 1;
            gouged += usize::from(want < 0.0);
        }
        assert!(
            wall > 100 && gouged > 50,
            "{tool}: {wall} wall vertices, {gouged} gouged"
        );
    }
}

/// A rapid (G0) through the part is a crash: `cam verify` names its line and depth and
/// exits 1, though it removes no material in the deviation measurement. (It passed such a
/// program with max gouge 0.0 and exit 0.)
#[test]
fn a_rapid_through_the_part_fails_the_check() {
    let d = tempfile::tempdir().unwrap();
    let part = write(d.path(), "box.obj", &box_obj(0.0, 10.0));
    let ngc = write(
        d.path(),
        "rapid.ngc",
        "G21 G90 G17\nG0 Z10\nG0 X-5 Y5\nG0 Z3\nG0 X15\nG0 Z10\nG0 X-5 Y-5\nG1 Z5 F100\n\
         G1 X15 F500\nG0 Z10\nM30\n",
    );
    for tool in ["flat:6", "ball:6"] {
        let o = verify_json(&ngc, &part, tool, &[]);
        assert_eq!(o.status.code(), Some(1), "{tool}: {}", stderr(&o));
        assert!(stderr(&o).contains("line 5"), "{tool}: {}", stderr(&o));
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(
            j["max_gouge_mm"].as_f64(),
            Some(0.0),
            "{tool}: the feed moves are clean"
        );
        let r = &j["rapids"];
        // Six rapids: the first (from wherever the tool was) at the pose it reaches.
        assert_eq!(r["checked"], 6, "{tool}: {r}");
        let c = r["collisions"].as_array().unwrap();
        assert_eq!(c.len(), 1, "{tool}: {r}");
        assert_eq!(c[0]["line"], 5, "{tool}: {r}");
        assert!(
            (c[0]["depth_mm"].as_f64().unwrap() - 2.0).abs() < 1e-9,
            "{tool}: {r}"
        );
    }
}

/// A rapid with the tool axis tilted (3+2 positioning) through the part is a crash too:
/// `cam verify` checks it in the frame of its axis, names its line and depth (along the
/// axis, in closed form: a ball rests on the top face once its centre is `R` above it, a flat
/// end mill once its lowest rim point is on it) and exits 1. (It was counted unchecked.)
#[test]
fn a_tilted_rapid_through_the_part_fails_the_check() {
    let d = tempfile::tempdir().unwrap();
    let part = write(d.path(), "box.obj", &box_obj(0.0, 10.0));
    // Axis (0.6, 0, 0.8): down beside the box, through it 2 mm under its top (z = 5), then
    // a feed up clear of it.
    let k = "0.6,0,0.8";
    let apt = write(
        d.path(),
        "tilted.apt",
        &format!(
            "UNITS/MM\nRAPID\nGOTO/2,-10,20,{k}\nRAPID\nGOTO/2,-10,3,{k}\nRAPID\n\
             GOTO/2,20,3,{k}\nGOTO/2,20,20,{k}\n"
        ),
    );
    let (kx, kz, r) = (0.6, 0.8, 3.0);
    for (tool, want) in [
        // Centre at 3 + R·kz; it must rise along k until it is R above z = 5.
        ("ball:6", (r - (3.0 + r * kz - 5.0)) / kz),
        // The lowest rim point is R·kx below the tip; it must rise to z = 5.
        ("flat:6", (5.0 + r * kx - 3.0) / kz),
    ] {
        let o = verify_json(&apt, &part, tool, &[]);
        assert_eq!(o.status.code(), Some(1), "{tool}: {}", stderr(&o));
        assert!(stderr(&o).contains("line 7"), "{tool}: {}", stderr(&o));
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let rp = &j["rapids"];
        assert_eq!(
            (&rp["checked"], &rp["tilted"], &rp["unchecked"]),
            (&3.into(), &3.into(), &0.into()),
            "{tool}: {rp}"
        );
        let c = rp["collisions"].as_array().unwrap();
        assert_eq!(c.len(), 1, "{tool}: {rp}");
        let depth = c[0]["depth_mm"].as_f64().unwrap();
        assert!((depth - want).abs() < 1e-9, "{tool}: {depth} (want {want})");
    }
}

/// The twisted blade of the 5-axis tests (`cam_verify::testpaths`).
const BLADE: cam_verify::testpaths::TestSurface = cam_verify::testpaths::TestSurface::Blade {
    twist_rad_per_mm: 0.01,
};

/// A pass over [`BLADE`] at `v = 0`: 21 poses 1 mm apart from `u = 0`, lead 8° ± 3°, tilt 3°.
fn blade_pass_spec() -> cam_verify::testpaths::PassSpec {
    cam_verify::testpaths::PassSpec {
        surface: BLADE,
        v_mm: 0.0,
        u0_mm: 0.0,
        poses: 21,
        step_mm: 1.0,
        lead_deg: 8.0,
        lead_wobble_deg: 3.0,
        wobble_period_mm: 11.0,
        tilt_deg: 3.0,
    }
}

/// [`BLADE`] over u in [-4, 24], v in [-9, 8] as a shared-vertex grid of 40 × 24 cells, OBJ
/// text, counter-clockwise from +N.
fn blade_obj() -> String {
    let (nu, nv) = (40usize, 24usize);
    let mut obj = String::new();
    for j in 0..=nv {
        for i in 0..=nu {
            let (u, v) = (
                -4.0 + 28.0 * i as f64 / nu as f64,
                -9.0 + 17.0 * j as f64 / nv as f64,
            );
            let p = BLADE.eval(u, v).0;
            obj.push_str(&format!("v {:?} {:?} {:?}\n", p.x, p.y, p.z));
        }
    }
    let id = |i: usize, j: usize| j * (nu + 1) + i + 1;
    for j in 0..nv {
        for i in 0..nu {
            obj.push_str(&format!(
                "f {} {} {}\n",
                id(i, j),
                id(i + 1, j),
                id(i + 1, j + 1)
            ));
            obj.push_str(&format!(
                "f {} {} {}\n",
                id(i, j),
                id(i + 1, j + 1),
                id(i, j + 1)
            ));
        }
    }
    obj
}

/// APT CL text of `passes` (tool tips in mm, unit axes): each opened by a rapid.
fn apt_text(passes: &[Vec<cam_core::Pose>]) -> String {
    let mut apt = String::from("UNITS/MM\n");
    for poses in passes {
        for (k, p) in poses.iter().enumerate() {
            if k == 0 {
                apt.push_str("RAPID\n");
            }
            apt.push_str(&format!(
                "GOTO/{:.12},{:.12},{:.12},{:.15},{:.15},{:.15}\n",
                p.tip.x, p.tip.y, p.tip.z, p.axis.x, p.axis.y, p.axis.z
            ));
        }
    }
    apt
}

/// A 5-axis CL program from the CLI: three overlapping passes of a bull:10:2 over a twisted
/// blade (lead 8° ± 3°, tilt 3°, the middle pass run backwards, the axis turning at every
/// move), every pose pushed 0.03 mm into the blade along its normal, as APT `GOTO/x,y,z,i,j,k`
/// data. `cam verify` must fail it (exit 1) and every worst gouge and excess it reports must
/// equal, to 1e-6 mm, the first hit along the vertex's normal of an independent brute-force
/// envelope (the cutter 60 mm tall, 48 instances per move refined to 1e-9 mm, sphere-traced)
/// of the program
/// as read back. The deepest gouge lies within 0.01 mm of the push: vertices between the
/// passes see the tool curve away, and between two poses the interpolated tool dips a little
/// further (measured: 0.0314 mm for the 0.03 mm push).
#[test]
fn a_five_axis_cl_program_reads_the_envelope() {
    use cam_core::{Cutter, DVec3};
    use cam_verify::envelope::{BruteEnvelope, EnvelopeConfig};
    use cam_verify::testpaths::{PassSpec, pass};
    let d = tempfile::tempdir().unwrap();
    let cutter: Cutter = "bull:10:2".parse().unwrap();
    let surface = BLADE;
    let push = 0.03;
    let mut passes = Vec::new();
    for (i, v) in [-3.0, -0.5, 2.0].into_iter().enumerate() {
        let spec = PassSpec {
            v_mm: v,
            ..blade_pass_spec()
        };
        let mut poses: Vec<cam_core::Pose> = pass(&spec, &cutter)
            .moves
            .iter()
            .enumerate()
            .map(|(j, m)| {
                let (_, n) = surface.eval(j as f64 * spec.step_mm, v);
                cam_core::Pose {
                    tip: m.pose.tip - push * n,
                    axis: m.pose.axis,
                }
            })
            .collect();
        if i == 1 {
            poses.reverse();
        }
        passes.push(poses);
    }
    let apt_path = write(d.path(), "blade.apt", &apt_text(&passes));
    let obj_path = write(d.path(), "blade.obj", &blade_obj());
    let o = verify_json(&apt_path, &obj_path, "bull:10:2", &["--tolerance", "0.01"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let gouge = j["max_gouge_mm"].as_f64().unwrap();
    assert!(
        (gouge - push).abs() <= 0.01,
        "max gouge {gouge} for a push of {push}"
    );
    let tp = cam_gcode::read_apt(&apt_path).unwrap();
    let env = BruteEnvelope::new(
        &tp,
        &cutter,
        &EnvelopeConfig {
            instances_per_move: 48,
            // The whole cutter a vector can reach: its side 60 mm up (the verifier's is
            // unbounded).
            height_mm: Some(60.0),
            ..Default::default()
        },
    );
    let mut checked = 0;
    for key in ["worst_gouges", "worst_excess"] {
        for w in j[key].as_array().unwrap() {
            let f = |k: &str| {
                let a = w[k].as_array().unwrap();
                DVec3::new(
                    a[0].as_f64().unwrap(),
                    a[1].as_f64().unwrap(),
                    a[2].as_f64().unwrap(),
                )
            };
            let (p, n) = (f("position"), f("normal"));
            let reading = w["signed_mm"].as_f64().unwrap();
            let hit = env
                .first_hit(p - n, n, 6.0, 1e-9)
                .expect("the envelope is hit")
                - 1.0;
            assert!(
                (hit - reading).abs() <= 1e-6,
                "{key} at {p}: cam verify {reading}, envelope {hit}"
            );
            checked += 1;
        }
    }
    assert!(checked >= 10, "{checked}");
    assert_eq!(
        j["settings"]["extra"]["overflow_vectors"].as_f64(),
        Some(0.0)
    );
    // Two lines at the blade's edge cross the imprint surface where no move is entered (a
    // brute force over every move agrees); the miss is proven, not left at the linear value.
    assert_eq!(
        j["settings"]["extra"]["kept_linear_vectors"].as_f64(),
        Some(0.0)
    );
    assert_eq!(
        j["max_gouge_mm"].as_f64(),
        j["worst_gouges"][0]["signed_mm"].as_f64().map(|s| -s)
    );
}

/// A 5-axis program that runs the same short pass 70 times puts more crossings of the
/// imprint surface on the vectors under it than the locator keeps: the report counts them
/// (`overflow_vectors`) and the summary warns that those points are not proven exact.
#[test]
fn overflowing_crossings_are_reported_and_warned() {
    use cam_verify::testpaths::pass;
    let d = tempfile::tempdir().unwrap();
    let cutter: cam_core::Cutter = "bull:10:2".parse().unwrap();
    let spec = cam_verify::testpaths::PassSpec {
        poses: 6,
        ..blade_pass_spec()
    };
    let one: Vec<cam_core::Pose> = pass(&spec, &cutter).moves.iter().map(|m| m.pose).collect();
    let passes = vec![one; 70];
    let apt_path = write(d.path(), "repeat.apt", &apt_text(&passes));
    let obj_path = write(d.path(), "blade.obj", &blade_obj());
    let o = verify_json(&apt_path, &obj_path, "bull:10:2", &[]);
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let over = j["settings"]["extra"]["overflow_vectors"].as_f64().unwrap();
    let lin = j["settings"]["extra"]["kept_linear_vectors"]
        .as_f64()
        .unwrap();
    assert!(over > 0.0, "{over}");
    let args = [
        "verify",
        apt_path.to_str().unwrap(),
        "--part",
        obj_path.to_str().unwrap(),
        "--tool",
        "bull:10:2",
    ];
    let o = cam(&args);
    let text = stderr(&o);
    assert!(
        text.contains(&format!(
            "{} points are not proven exact and may read late ({over} with more crossings",
            over + lin
        )),
        "{text}"
    );
}
