#![no_main]
//! parse_apt must return Ok or a typed GcodeError, never panic.
use cam_gcode::parse_apt;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let _ = parse_apt(text);
    let inch = format!("UNITS/INCHES\n{text}");
    let _ = parse_apt(&inch);
});
