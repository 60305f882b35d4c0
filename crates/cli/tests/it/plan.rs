//! `cam plan` end to end: tool choice, holder policies, outputs and bad input.

use crate::support::{cam, root, stderr, write};

fn pocket() -> String {
    root()
        .join("fixtures/parts/pocket.obj")
        .to_str()
        .unwrap()
        .to_string()
}

/// One ball:6 tool whose Ø20 holder sits 12 mm above the tip: too short for the 15 mm deep
/// pocket, whose rim (z = 30) it must clear while the tip is on the floor (z = 15).
const SHORT_TOOL: &str = r#"{ "units": "mm", "tools": [ {
  "id": "SHORT", "number": 7, "cutter": { "type": "ball", "diameter": 6 },
  "flute_length": 10, "shank_diameter": 6, "stick_out": 12, "stick_out_min": 10, "stick_out_max": 30,
  "holder": [ { "diameter": 20, "length": 20 } ] } ] }"#;

#[test]
fn holder_fail_policy_exits_1_and_writes_nothing() {
    let d = tempfile::tempdir().unwrap();
    let lib = write(d.path(), "lib.json", SHORT_TOOL);
    let out = d.path().join("p.ngc");
    let o = cam(&[
        "plan",
        &pocket(),
        "--tool-library",
        lib.to_str().unwrap(),
        "--tool",
        "SHORT",
        "--scallop",
        "0.1",
        "-o",
        out.to_str().unwrap(),
    ]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("collisions") && e.contains("line"), "{e}");
    // The holder must clear the rim at z = 30 with the tip on the floor at z = 15.
    assert!(
        e.contains("minimum collision-free stick-out 15.000 mm"),
        "{e}"
    );
    assert!(!out.exists());
}

#[test]
fn holder_report_and_avoid_policies_write_gcode() {
    let d = tempfile::tempdir().unwrap();
    let lib = write(d.path(), "lib.json", SHORT_TOOL);
    for policy in ["report", "avoid"] {
        let out = d.path().join(format!("{policy}.ngc"));
        let o = cam(&[
            "plan",
            &pocket(),
            "--tool-library",
            lib.to_str().unwrap(),
            "--tool",
            "SHORT",
            "--scallop",
            "0.1",
            "--holder",
            policy,
            "-o",
            out.to_str().unwrap(),
            "--json",
        ]);
        assert!(o.status.success(), "{policy}: {}", stderr(&o));
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let g = std::fs::read_to_string(&out).unwrap();
        assert!(
            g.contains("T7 M6") && g.contains("G43 H7"),
            "library tool number used"
        );
        match policy {
            "report" => {
                assert!(j["holder"]["collisions"].as_u64().unwrap() > 0, "{j}");
                let f = &j["holder"]["findings"][0];
                assert!(
                    f["line"].as_u64().unwrap() > 0 && f["depth_mm"].as_f64().unwrap() > 0.0,
                    "{f}"
                );
                // The Ø20 holder, its axis 3 mm from the wall (ball radius), reaches 10 - 3 = 7 mm in.
                assert_eq!(f["part"], "holder cylinder 0", "{f}");
                assert!((f["depth_mm"].as_f64().unwrap() - 7.0).abs() < 1e-6, "{f}");
            }
            _ => {
                assert_eq!(j["holder"]["collisions"], 0, "{j}");
                assert!(
                    j["holder"]["removed_cut_length_mm"].as_f64().unwrap() > 0.0,
                    "{j}"
                );
            }
        }
        assert!(
            (j["holder"]["min_stick_out_mm"].as_f64().unwrap() - 15.0).abs() < 1e-6,
            "{j}"
        );
    }
}

#[test]
fn plan_defaults_write_a_program() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("p.ngc");
    let apt = d.path().join("p.apt");
    let o = cam(&[
        "plan",
        &pocket(),
        "--scallop",
        "0.1",
        "-o",
        out.to_str().unwrap(),
        "--cl-out",
        apt.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let g = std::fs::read_to_string(&out).unwrap();
    for want in [
        "(CL convention: tool tip)",
        "G21",
        "G90",
        "G17",
        "G94",
        "M3",
        "M30",
        "(tool: T1 ball:6)",
    ] {
        assert!(g.contains(want), "program lacks {want}");
    }
    assert!(std::fs::read_to_string(&apt).unwrap().contains("GOTO/"));
}

#[test]
fn plan_bad_values_exit_2() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("p.ngc");
    for args in [
        vec!["--tolerance", "0"],
        vec!["--scallop", "-1"],
        vec!["--scallop", "3"],
        // Below what a program's rounding can hold (1e-9 used to plan for days).
        vec!["--scallop", "0.000000001"],
        vec!["--tolerance", "0.000000000001"],
        vec!["--tool", "bull:6:4"],
        // Out of any machine's range (found probing: ball:1e300 panicked, safe Z 1e300
        // failed as an internal error, F1e300 was written).
        vec!["--tool", "ball:1e300"],
        vec!["--tool", "bull:6:0.000000001"],
        vec!["--safe-z", "1e300"],
        vec!["--feed", "1e300"],
        vec!["--rpm", "1e300"],
        // Above what the verification checks (1e300 made `cam verify` run for ever).
        vec!["--tolerance", "2"],
        vec!["--feed", "nan"],
        vec!["--stock", "1,0,0,1"],
        vec!["--tool-library", "/nonexistent.json"],
    ] {
        let part = pocket();
        let mut a = vec!["plan", part.as_str()];
        a.extend(args.iter().copied());
        a.extend(["-o", out.to_str().unwrap()]);
        let o = cam(&a);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        // A user error, named as such (safe Z 1e300 used to surface as an internal error).
        assert!(!stderr(&o).contains("internal"), "{args:?}: {}", stderr(&o));
        assert!(!out.exists());
    }
    let bad = write(
        d.path(),
        "lib.json",
        "{ \"units\": \"mm\", \"tools\": [ { \"id\": 3 } ] }",
    );
    let o = cam(&[
        "plan",
        &pocket(),
        "--tool-library",
        bad.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("lib.json"), "{}", stderr(&o));
}

fn fillet() -> String {
    root()
        .join("fixtures/parts/fillet.obj")
        .to_str()
        .unwrap()
        .to_string()
}

fn ball_lib(diameters: &[f64]) -> String {
    let tools: Vec<String> = diameters
        .iter()
        .enumerate()
        .map(|(i, d)| {
            format!(
                r#"{{ "id": "B{d}", "number": {n}, "cutter": {{ "type": "ball", "diameter": {d} }},
                 "flute_length": {f}, "shank_diameter": {d}, "stick_out": {s},
                 "holder": [ {{ "diameter": {h}, "length": 30 }} ] }}"#,
                n = i + 1,
                f = 2.0 * d,
                s = 4.0 * d + 10.0,
                h = 3.0 * d
            )
        })
        .collect();
    format!(r#"{{ "units": "mm", "tools": [ {} ] }}"#, tools.join(","))
}

#[test]
fn library_without_tool_picks_the_largest_that_fits_the_fillet() {
    // fillet.obj: a concave fillet of radius 6. A ball of radius 5 fits, 8 does not.
    let d = tempfile::tempdir().unwrap();
    let lib = write(d.path(), "lib.json", &ball_lib(&[4.0, 10.0, 16.0]));
    let out = d.path().join("f.ngc");
    let o = cam(&[
        "plan",
        &fillet(),
        "--tool-library",
        lib.to_str().unwrap(),
        "--scallop",
        "0.2",
        "--no-verify",
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["tool"], "ball:10", "{j}");
    assert!(std::fs::read_to_string(&out).unwrap().contains("T2 M6"));
}

#[test]
fn no_tool_fits_exit_2_names_region_radius_and_closest_tool() {
    let d = tempfile::tempdir().unwrap();
    let lib = write(d.path(), "lib.json", &ball_lib(&[16.0, 20.0]));
    let out = d.path().join("f.ngc");
    let o = cam(&[
        "plan",
        &fillet(),
        "--tool-library",
        lib.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("B16"), "closest tool named: {e}");
    assert!(e.contains('6'), "radius named: {e}");
    assert!(!out.exists());
}

/// `cam plan` verifies what it planned, and on an open part that verification must agree
/// with the planner's guarantee: the tilted plane is an open sheet, and balls and bulls
/// hang over its rim at the pass ends. Along the rim vertices' normals the tool reads up to
/// 0.0146 mm (the face's plane continued past the rim), so there the verifier reports the
/// vertex's depth in the swept volume, which the planner bounds by τ.
#[test]
fn plan_verifies_an_open_part_within_tolerance() {
    let part = root().join("fixtures/parts/tilted_plane.obj");
    let d = tempfile::tempdir().unwrap();
    for tool in ["ball:6", "bull:6:1.5"] {
        let out = d.path().join("p.ngc");
        let o = cam(&[
            "plan",
            part.to_str().unwrap(),
            "--tool",
            tool,
            "--scallop",
            "0.05",
            "--tolerance",
            "0.01",
            "--json",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(0), "{tool}: {}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
        let g = v["verify"]["max_gouge_mm"].as_f64().expect("max_gouge_mm");
        assert!(g <= 0.01, "{tool}: verified gouge {g}");
    }
}

/// τ is held in the program as written: the planner works to τ less the post's rounding
/// (reported in the JSON), and a τ the program's decimals cannot hold is refused.
#[test]
fn plan_tolerance_leaves_room_for_the_programs_rounding() {
    let part = root().join("fixtures/parts/tilted_plane.obj");
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("p.ngc");
    for (units, rounding) in [
        ("mm", 3f64.sqrt() * 5e-5),
        ("inch", 3f64.sqrt() * 5e-6 * 25.4),
    ] {
        let o = cam(&[
            "plan",
            part.to_str().unwrap(),
            "--tool",
            "flat:6",
            "--tolerance",
            "0.01",
            "--gcode-units",
            units,
            "--no-verify",
            "--json",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(0), "{units}: {}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
        let planned = v["planned_tolerance_mm"]
            .as_f64()
            .expect("planned_tolerance_mm");
        assert!(
            (planned - (0.01 - rounding)).abs() < 1e-12,
            "{units}: {planned}"
        );
        assert!(v["max_chord_deviation_mm"].as_f64().unwrap() <= planned + 1e-12);
    }
    let o = cam(&[
        "plan",
        part.to_str().unwrap(),
        "--tolerance",
        "0.0003",
        "--gcode-units",
        "inch",
        "-o",
        out.to_str().unwrap(),
    ]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains("--tolerance 0.0003") && e.contains("inch"),
        "{e}"
    );
}

/// `cam verify` with the tool from a library checks its shank and holder too: the program
/// `--holder report` wrote for the short tool fails with the holder's 7 mm collision, the
/// same tool 16 mm out (the minimum is 15) passes, and a bare spec says it did not check.
#[test]
fn verify_checks_the_holder_of_a_library_tool() {
    let d = tempfile::tempdir().unwrap();
    let lib = write(d.path(), "lib.json", SHORT_TOOL);
    let long = write(
        d.path(),
        "long.json",
        &SHORT_TOOL.replace("\"stick_out\": 12", "\"stick_out\": 16"),
    );
    let out = d.path().join("p.ngc");
    let o = cam(&[
        "plan",
        &pocket(),
        "--tool-library",
        lib.to_str().unwrap(),
        "--tool",
        "SHORT",
        "--scallop",
        "0.1",
        "--holder",
        "report",
        "--no-verify",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let verify = |tool: &[&str]| {
        let part = pocket();
        let mut a = vec![
            "verify",
            out.to_str().unwrap(),
            "--part",
            part.as_str(),
            "--json",
        ];
        a.extend_from_slice(tool);
        cam(&a)
    };
    let o = verify(&["--tool-library", lib.to_str().unwrap(), "--tool", "SHORT"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("shank/holder collisions"),
        "{}",
        stderr(&o)
    );
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let h = &j["holder"];
    assert!(
        h["checked"] == true && h["collisions"].as_u64().unwrap() > 0,
        "{h}"
    );
    assert!(
        (h["max_depth_mm"].as_f64().unwrap() - 7.0).abs() < 1e-6,
        "{h}"
    );
    assert_eq!(h["findings"][0]["part"], "holder cylinder 0", "{h}");
    assert!(h["findings"][0]["line"].as_u64().unwrap() > 0, "{h}");

    let o = verify(&["--tool-library", long.to_str().unwrap(), "--tool", "SHORT"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["holder"]["collisions"], 0, "{}", j["holder"]);

    let o = verify(&["--tool", "ball:6"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(j["holder"].is_null(), "{}", j["holder"]);
}
