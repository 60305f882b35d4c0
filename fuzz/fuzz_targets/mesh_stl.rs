#![no_main]
//! STL loading, ASCII and binary (cam_core::io::stl::parse_stl + Mesh::load's scaling and
//! validation). Also feeds a copy whose binary header count is fixed up to match the length,
//! so that mutations reach the binary parser.
use cam_core::Units;
use libfuzzer_sys::fuzz_target;
use std::path::Path;

#[path = "mesh_common.rs"]
mod mesh_common;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.stl");
    let parse = cam_core::io::stl::parse_stl;
    mesh_common::load_like(parse, data, path, Units::Mm);
    mesh_common::load_like(parse, data, path, Units::Inch);
    if data.len() >= 84 {
        let n = (data.len() - 84) / 50;
        let mut bin = data[..84 + 50 * n].to_vec();
        bin[80..84].copy_from_slice(&(n as u32).to_le_bytes());
        mesh_common::load_like(parse, &bin, path, Units::Mm);
    }
});
