//! Tool choice by curvature and by holder clearance.

use cam_core::{MoveKind, Toolpath, assert_near};
use cam_holder::{
    CurvatureConfig, Rejection, SelectConfig, SelectError, ToolAssembly, ToolLibrary,
    concave_curvature, select_tool,
};

use crate::common::{path, pocket, v};
use crate::curvature::fillet;

fn lib(tools: &[(&str, &str, f64)]) -> ToolLibrary {
    // (id, cutter json, stick_out_max)
    let body: Vec<String> = tools
        .iter()
        .map(|(id, cutter, max)| {
            format!(
                r#"{{ "id": "{id}", "cutter": {cutter}, "flute_length": 12, "shank_diameter": 6, "stick_out": 20, "stick_out_max": {max}, "holder": [ {{ "diameter": 20, "length": 15 }}, {{ "diameter": 32, "length": 40 }} ] }}"#
            )
        })
        .collect();
    ToolLibrary::from_json(
        &format!(r#"{{ "tools": [ {} ] }}"#, body.join(",")),
        "<sel>",
    )
    .unwrap()
}

#[test]
fn largest_fitting_cutter_is_chosen() {
    let mesh = fillet(6.0, 32, 0.3, true, 5);
    let curv = concave_curvature(&mesh, &CurvatureConfig::default());
    let library = lib(&[
        ("B3", r#"{ "type": "ball", "diameter": 3 }"#, 40.0),
        ("B10", r#"{ "type": "ball", "diameter": 10 }"#, 40.0),
        (
            "R10",
            r#"{ "type": "bull", "diameter": 10, "corner_radius": 2 }"#,
            40.0,
        ),
        ("B16", r#"{ "type": "ball", "diameter": 16 }"#, 40.0),
        ("F6", r#"{ "type": "flat", "diameter": 6 }"#, 40.0),
    ]);
    let s = select_tool(&library, &mesh, &curv, None, &SelectConfig::default()).unwrap();
    // Ball 16 (r = 8) does not fit the r = 6 fillet; ball 10 (r = 5) does and beats bull 10:2.
    assert_eq!(s.tool_id, "B10");
    assert_eq!(s.rejected.len(), 1);
    match &s.rejected[0] {
        (
            id,
            Rejection::TooLarge {
                radius_needed_mm,
                tool_radius_mm,
                ..
            },
        ) => {
            assert_eq!(id, "B16");
            assert_eq!(*tool_radius_mm, 8.0);
            assert!((radius_needed_mm - 6.0).abs() <= 0.12);
        }
        other => panic!("{other:?}"),
    }
    // A bull nose 16:4 (corner radius 4 ≤ 6) fits the floor fillet and is larger.
    let library = lib(&[
        ("B10", r#"{ "type": "ball", "diameter": 10 }"#, 40.0),
        (
            "R16",
            r#"{ "type": "bull", "diameter": 16, "corner_radius": 4 }"#,
            40.0,
        ),
    ]);
    assert_eq!(
        select_tool(&library, &mesh, &curv, None, &SelectConfig::default())
            .unwrap()
            .tool_id,
        "R16"
    );
}

#[test]
fn no_tool_fits_names_region_radius_and_closest() {
    let mesh = fillet(6.0, 24, 0.0, false, 1);
    let curv = concave_curvature(&mesh, &CurvatureConfig::default());
    let library = lib(&[
        ("B20", r#"{ "type": "ball", "diameter": 20 }"#, 40.0),
        ("B16", r#"{ "type": "ball", "diameter": 16 }"#, 40.0),
    ]);
    match select_tool(&library, &mesh, &curv, None, &SelectConfig::default()) {
        Err(SelectError::NoToolFits {
            region,
            radius_needed_mm,
            closest_tool_id,
        }) => {
            assert_eq!(closest_tool_id, "B16");
            assert_near!(radius_needed_mm, 6.0, 1e-9);
            let d = ((region.y - 6.0).powi(2) + (region.z - 6.0).powi(2)).sqrt();
            assert!((d - 6.0).abs() < 0.1, "region {region}");
        }
        other => panic!("{other:?}"),
    }
}

fn floor_line(t: &ToolAssembly) -> Option<Toolpath> {
    // Along the floor of the 40 × 40 pocket to 1 mm from the wall x = 20.
    let x = 20.0 - t.cutter.radius() - 1.0;
    Some(path(&[
        (MoveKind::Cut, v(0.0, 0.0, 0.0)),
        (MoveKind::Cut, v(x, 0.0, 0.0)),
    ]))
}

#[test]
fn holder_decides_between_fitting_tools() {
    let mesh = pocket(20.0, 25.0, 40.0);
    let curv = concave_curvature(&mesh, &CurvatureConfig::default());
    // Both fit (sharp edges only); B10 may stick out at most 22 but needs 25.
    let library = lib(&[
        ("B10", r#"{ "type": "ball", "diameter": 10 }"#, 22.0),
        ("B6", r#"{ "type": "ball", "diameter": 6 }"#, 40.0),
    ]);
    let s = select_tool(
        &library,
        &mesh,
        &curv,
        Some(&floor_line),
        &SelectConfig::default(),
    )
    .unwrap();
    assert_eq!(s.tool_id, "B6");
    match &s.rejected[0] {
        (
            id,
            Rejection::Collides {
                needed_stick_out_mm: Some(n),
                max_stick_out_mm,
                ..
            },
        ) => {
            assert_eq!(id, "B10");
            assert_near!(*n, 25.0, 1e-9);
            assert_eq!(*max_stick_out_mm, 22.0);
        }
        other => panic!("{other:?}"),
    }
    // Nominal 20 collides: minimum 25 plus the 1 mm margin.
    assert_near!(s.assembly.stick_out_mm, 26.0, 1e-9);
    assert_near!(s.stick_out.unwrap().min_mm.unwrap(), 25.0, 1e-9);
    let only_short = lib(&[("B10", r#"{ "type": "ball", "diameter": 10 }"#, 22.0)]);
    match select_tool(
        &only_short,
        &mesh,
        &curv,
        Some(&floor_line),
        &SelectConfig::default(),
    ) {
        Err(SelectError::NoAssemblyClears {
            closest_tool_id,
            needed_stick_out_mm: Some(n),
            ..
        }) => {
            assert_eq!(closest_tool_id, "B10");
            assert_near!(n, 25.0, 1e-9);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn tools_without_a_path_are_passed_over() {
    let mesh = pocket(20.0, 25.0, 40.0);
    let curv = concave_curvature(&mesh, &CurvatureConfig::default());
    let library = lib(&[
        ("B10", r#"{ "type": "ball", "diameter": 10 }"#, 40.0),
        ("B6", r#"{ "type": "ball", "diameter": 6 }"#, 40.0),
    ]);
    let only_small = |t: &ToolAssembly| {
        if t.cutter.diameter() < 8.0 {
            floor_line(t)
        } else {
            None
        }
    };
    let s = select_tool(
        &library,
        &mesh,
        &curv,
        Some(&only_small),
        &SelectConfig::default(),
    )
    .unwrap();
    assert_eq!(s.tool_id, "B6");
    assert_eq!(s.rejected, vec![("B10".to_string(), Rejection::NoToolpath)]);
    let none = |_: &ToolAssembly| None;
    assert_eq!(
        select_tool(
            &library,
            &mesh,
            &curv,
            Some(&none),
            &SelectConfig::default()
        ),
        Err(SelectError::NoToolpath)
    );
}
