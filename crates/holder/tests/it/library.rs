//! Tool library loading and validation.

use std::path::PathBuf;

use cam_core::{Cutter, CutterKind};
use cam_holder::{AssemblyDefaults, AssemblyPart, LibraryError, ToolAssembly, ToolLibrary};

fn fixture() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/tools/library.json")
}

#[test]
fn example_library_loads() {
    let lib = ToolLibrary::load(fixture()).unwrap();
    assert_eq!(lib.tools.len(), 6);
    let t4 = lib.get("T4").unwrap();
    assert_eq!(t4.cutter.kind(), CutterKind::Bull);
    assert_eq!(
        (
            t4.cutter.diameter(),
            t4.cutter.corner_radius(),
            t4.cutter.flute_length()
        ),
        (10.0, 2.0, 22.0)
    );
    assert_eq!(t4.stick_out_mm, 40.0);
    assert_eq!(t4.feeds.rpm, Some(9000.0));
    let parts = lib.get("T5").unwrap().parts();
    let desc: Vec<(AssemblyPart, f64, f64, f64)> = parts
        .iter()
        .map(|p| (p.part, p.radius_mm, p.z_min_mm, p.z_max_mm))
        .collect();
    assert_eq!(
        desc,
        vec![
            (AssemblyPart::Shank, 3.0, 13.0, 25.0),
            (AssemblyPart::Holder(0), 6.0, 25.0, 55.0),
            (AssemblyPart::Holder(1), 13.5, 55.0, 75.0),
            (AssemblyPart::Holder(2), 20.0, 75.0, f64::INFINITY),
        ]
    );
}

fn one_tool(body: &str) -> Result<ToolLibrary, LibraryError> {
    let json = format!(r#"{{ "units": "mm", "tools": [ {{ "id": "X1", {body} }} ] }}"#);
    ToolLibrary::from_json(&json, "lib.json")
}

const GOOD: &str = r#""cutter": { "type": "ball", "diameter": 6 }, "flute_length": 18, "shank_diameter": 6, "stick_out": 30, "holder": [ { "diameter": 20, "length": 15 } ]"#;

fn field_of(e: LibraryError) -> (String, String) {
    match e {
        LibraryError::Invalid { tool, field, .. } => (tool, field),
        other => panic!("expected Invalid, got {other}"),
    }
}

#[test]
fn invalid_values_name_tool_and_field() {
    assert!(one_tool(GOOD).is_ok());
    let cases = [
        (
            GOOD.replace("\"diameter\": 6 }", "\"diameter\": -6 }"),
            "cutter.diameter",
        ),
        (
            GOOD.replace("\"stick_out\": 30", "\"stick_out\": 10"),
            "stick_out",
        ),
        (
            GOOD.replace("\"shank_diameter\": 6", "\"shank_diameter\": 0"),
            "shank_diameter",
        ),
        (
            GOOD.replace("\"length\": 15", "\"length\": -1"),
            "holder[0].length",
        ),
        (
            GOOD.replace("[ { \"diameter\": 20, \"length\": 15 } ]", "[]"),
            "holder",
        ),
        (
            GOOD.replace("\"type\": \"ball\"", "\"type\": \"bull\""),
            "cutter.corner_radius",
        ),
        (
            GOOD.replace(
                "\"diameter\": 6 }",
                "\"diameter\": 6, \"corner_radius\": 1 }",
            ),
            "cutter.corner_radius",
        ),
        (format!("{GOOD}, \"stick_out_max\": 25"), "stick_out"),
        (format!("{GOOD}, \"stick_out_min\": 12"), "stick_out_min"),
        (format!("{GOOD}, \"rpm\": -5"), "rpm"),
    ];
    for (body, field) in cases {
        let e = one_tool(&body).expect_err(&body);
        let msg = e.to_string();
        assert_eq!(field_of(e), ("X1".to_string(), field.to_string()), "{msg}");
        assert!(msg.starts_with("lib.json: tool 'X1': "), "{msg}");
    }
}

#[test]
fn bad_json_names_line_and_column() {
    let e = ToolLibrary::from_json("{\n  \"tools\": [\n    { \"id\": 3 }\n  ]\n}", "t.json")
        .unwrap_err();
    match e {
        LibraryError::Json { line, column, .. } => assert_eq!((line, column), (3, 13)),
        other => panic!("{other}"),
    }
    let dup = format!(r#"{{ "tools": [ {{ "id": "A", {GOOD} }}, {{ "id": "A", {GOOD} }} ] }}"#);
    assert!(matches!(
        ToolLibrary::from_json(&dup, "d.json"),
        Err(LibraryError::DuplicateId { .. })
    ));
    assert!(matches!(
        ToolLibrary::from_json(r#"{ "tools": [] }"#, "e.json"),
        Err(LibraryError::Empty { .. })
    ));
}

#[test]
fn inch_library_is_converted() {
    let json = r#"{ "units": "inch", "tools": [ { "id": "I", "cutter": { "type": "flat", "diameter": 0.25 }, "flute_length": 0.75, "shank_diameter": 0.25, "stick_out": 1, "holder": [ { "diameter": 1, "length": 1 } ], "feed_mm_per_min": 10 } ] }"#;
    let lib = ToolLibrary::from_json(json, "i.json").unwrap();
    let t = &lib.tools[0];
    assert_eq!(
        (t.cutter.diameter(), t.stick_out_mm, t.holder[0].diameter),
        (6.35, 25.4, 25.4)
    );
    assert_eq!(t.feeds.feed_mm_per_min, Some(254.0));
}

#[test]
fn default_assembly_for_a_spec() {
    let c: Cutter = "ball:6".parse().unwrap();
    let a = ToolAssembly::from_spec(c, &AssemblyDefaults::default());
    assert_eq!(a.id, "ball:6");
    assert_eq!(
        (
            a.shank_diameter_mm,
            a.stick_out_mm,
            a.stick_out_min_mm,
            a.stick_out_max_mm
        ),
        (6.0, 24.0, 18.0, 48.0)
    );
    assert_eq!(a.holder.len(), 2);
    assert_eq!(
        (
            a.holder[0].diameter,
            a.holder[0].length,
            a.holder[1].diameter,
            a.holder[1].length
        ),
        (20.0, 20.0, 40.0, 40.0)
    );
    let big = ToolAssembly::from_spec("flat:12".parse().unwrap(), &AssemblyDefaults::default());
    assert_eq!(
        (
            big.holder[0].diameter,
            big.holder[1].diameter,
            big.stick_out_mm
        ),
        (36.0, 60.0, 48.0)
    );
}
