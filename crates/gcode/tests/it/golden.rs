//! Golden G-code for the small path per post, in `fixtures/golden/gcode/`; rewritten only
//! with `UPDATE_GOLDEN=1`, compared within one unit of the last printed decimal.

use crate::post::job;
use crate::support::{compare_numbers_within_last_digit, small_path};
use cam_core::Units;
use cam_gcode::{Post, post_to_string};
use std::path::PathBuf;

fn golden_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/golden/gcode")
}

#[test]
fn golden_programs_per_post() {
    let update = std::env::var("UPDATE_GOLDEN").is_ok_and(|v| v == "1");
    let cases = [
        (Post::LinuxCnc, Units::Mm, "small_linuxcnc_mm.ngc"),
        (Post::LinuxCnc, Units::Inch, "small_linuxcnc_inch.ngc"),
        (Post::Grbl, Units::Mm, "small_grbl_mm.nc"),
        (Post::Fanuc, Units::Mm, "small_fanuc_mm.nc"),
    ];
    for (p, units, name) in cases {
        let got = post_to_string(&small_path(), &job(units), p).unwrap();
        let path = golden_dir().join(name);
        if update {
            std::fs::create_dir_all(golden_dir()).unwrap();
            std::fs::write(&path, &got).unwrap();
            continue;
        }
        let want = std::fs::read_to_string(&path).unwrap_or_else(|e| {
            panic!(
                "{}: {e} (run with UPDATE_GOLDEN=1 to create it)",
                path.display()
            )
        });
        if let Err(d) = compare_numbers_within_last_digit(&want, &got) {
            panic!("{} differs from the golden file: {d}", path.display());
        }
    }
}
