//! `cam cl`: CL points, and bad input handled with exit code 2 and nothing written.

use crate::support::{SQUARE_OBJ, cam, stderr, write};

#[test]
fn grid_on_square_writes_csv() {
    let d = tempfile::tempdir().unwrap();
    let part = write(d.path(), "sq.obj", SQUARE_OBJ);
    let out = d.path().join("cl.csv");
    let o = cam(&[
        "cl",
        part.to_str().unwrap(),
        "--tool",
        "bull:4:1",
        "--step",
        "2.5",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&out).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("x,y,z,hit"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 25, "5x5 grid over the 10x10 square");
    assert_eq!((rows[1][0], rows[1][1]), (2.5, 0.0), "rows along X");
    for r in &rows {
        assert_eq!((r[2], r[3]), (1.0, 1.0));
    }
}

#[test]
fn points_file_and_misses() {
    let d = tempfile::tempdir().unwrap();
    let part = write(d.path(), "sq.obj", SQUARE_OBJ);
    let pts = write(d.path(), "xy.csv", "x,y\n5,5\n# far away\n100,100\n");
    let out = d.path().join("cl.csv");
    let o = cam(&[
        "cl",
        part.to_str().unwrap(),
        "--tool",
        "ball:6",
        "--points",
        pts.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&out).unwrap();
    assert_eq!(text, "x,y,z,hit\n5,5,1,1\n100,100,1,0\n");
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["points"], 2);
    assert_eq!(j["hits"], 1);
}

#[test]
fn inch_part_is_scaled() {
    let d = tempfile::tempdir().unwrap();
    let part = write(d.path(), "sq.obj", SQUARE_OBJ);
    let pts = write(d.path(), "xy.csv", "5,5\n");
    let out = d.path().join("cl.csv");
    let o = cam(&[
        "cl",
        part.to_str().unwrap(),
        "--units",
        "inch",
        "--tool",
        "flat:6",
        "--points",
        pts.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read_to_string(&out).unwrap(),
        "x,y,z,hit\n127,127,25.4,1\n"
    );
}

/// Each bad input: exit code 2, a message with the expected fragments, no output file.
#[test]
fn bad_input_exit_2_and_nothing_written() {
    let d = tempfile::tempdir().unwrap();
    let p = |n: &str, t: &str| write(d.path(), n, t).to_str().unwrap().to_string();
    let square = p("ok.obj", SQUARE_OBJ);
    let cases: Vec<(Vec<String>, Vec<&str>)> = vec![
        (
            vec!["missing.obj".into()],
            vec!["missing.obj", "cannot read"],
        ),
        (
            vec![p("part.step", "x")],
            vec!["part.step", "unknown part format"],
        ),
        (
            vec![p("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 oops\nf 1 2 3\n")],
            vec!["bad.obj:3", "malformed"],
        ),
        (
            vec![p("nan.obj", "v 0 0 0\nv 1 0 0\nv 0 1 nan\nf 1 2 3\n")],
            vec!["nan.obj:3", "not a finite number"],
        ),
        (
            vec![p("empty.obj", "# nothing\n")],
            vec!["empty.obj", "no triangles"],
        ),
        (
            vec![p("degen.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n")],
            vec!["degen.obj", "degenerate"],
        ),
        (
            vec![p(
                "bad.stl",
                "solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0\n",
            )],
            vec!["bad.stl:5", "coordinates"],
        ),
        (
            vec![p("short.stl", "garbage")],
            vec!["short.stl", "too short"],
        ),
        (
            vec![p("face.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n")],
            vec!["face.obj:4", "out of range"],
        ),
    ];
    for (args, want) in cases {
        let out = d.path().join("out.csv");
        let mut a: Vec<&str> = vec!["cl"];
        a.extend(args.iter().map(String::as_str));
        a.extend([
            "--tool",
            "ball:6",
            "--step",
            "1",
            "-o",
            out.to_str().unwrap(),
        ]);
        let o = cam(&a);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
        for w in want {
            assert!(e.contains(w), "{args:?}: message '{e}' lacks '{w}'");
        }
        assert!(!out.exists(), "{args:?}: output written despite error");
    }
    // Impossible tool and step values.
    for (tool, step, want) in [
        ("bull:6:3", "1", "corner radius"),
        ("ball:-2", "1", "diameter"),
        ("ball:6", "0", "--step"),
        ("ball:6", "nan", "--step"),
    ] {
        let out = d.path().join("out.csv");
        let o = cam(&[
            "cl",
            &square,
            "--tool",
            tool,
            "--step",
            step,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(2), "{tool} {step}: {}", stderr(&o));
        assert!(stderr(&o).contains(want), "{tool} {step}: {}", stderr(&o));
        assert!(!out.exists());
    }
}

#[test]
fn bad_points_file_names_line() {
    let d = tempfile::tempdir().unwrap();
    let part = write(d.path(), "sq.obj", SQUARE_OBJ);
    let pts = write(d.path(), "xy.csv", "x,y\n1,2\n3;4\n");
    let out = d.path().join("cl.csv");
    let o = cam(&[
        "cl",
        part.to_str().unwrap(),
        "--tool",
        "ball:6",
        "--points",
        pts.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("xy.csv:3"), "{}", stderr(&o));
    assert!(!out.exists());
}

#[test]
fn degenerate_triangles_are_dropped_and_counted() {
    let d = tempfile::tempdir().unwrap();
    let part = write(
        d.path(),
        "p.obj",
        &format!("{SQUARE_OBJ}v 0 0 0\nv 1 1 1\nv 2 2 2\nf 5 6 7\n"),
    );
    let out = d.path().join("cl.csv");
    let o = cam(&[
        "cl",
        part.to_str().unwrap(),
        "--tool",
        "ball:6",
        "--step",
        "5",
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["degenerate_dropped"], 1);
    assert_eq!(j["triangles"], 2);
}
