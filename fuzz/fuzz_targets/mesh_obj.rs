#![no_main]
//! OBJ loading (cam_core::io::obj::parse_obj + Mesh::load's scaling and validation).
use cam_core::Units;
use libfuzzer_sys::fuzz_target;
use std::path::Path;

#[path = "mesh_common.rs"]
mod mesh_common;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.obj");
    mesh_common::load_like(cam_core::io::obj::parse_obj, data, path, Units::Mm);
    mesh_common::load_like(cam_core::io::obj::parse_obj, data, path, Units::Inch);
});
