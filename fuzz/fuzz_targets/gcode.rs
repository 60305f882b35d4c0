#![no_main]
//! parse_gcode must return Ok or a typed GcodeError, never panic, hang or blow the stack.
use cam_gcode::{ReadConfig, parse_gcode};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    // Default config: unknown start, block delete on.
    let _ = parse_gcode(text, &ReadConfig::default());
    // Known start at the origin, block delete off (rs274-like).
    let cfg = ReadConfig {
        initial_position_mm: Some(glam::DVec3::ZERO),
        block_delete: false,
        ..ReadConfig::default()
    };
    let _ = parse_gcode(text, &cfg);
    // Inch program: same text under G20.
    let inch = format!("G20\n{text}");
    let _ = parse_gcode(&inch, &cfg);
});
