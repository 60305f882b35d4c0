//! Reads a 3-axis G-code program (default: the bundled golden LinuxCNC program), prints a
//! summary, and posts it again for another control.
//!
//! ```text
//! cargo run -p cam-gcode --example repost -- [PROGRAM.ngc] [linuxcnc|grbl|fanuc]
//! ```

use cam_core::MoveKind;
use cam_gcode::{Post, PostJob, ReadConfig, post, read_gcode};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let input = args.next().unwrap_or_else(|| {
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../fixtures/golden/gcode/small_linuxcnc_mm.ngc"
        )
        .to_string()
    });
    let target: Post = args.next().as_deref().unwrap_or("grbl").parse()?;
    let tp = read_gcode(&input, &ReadConfig::default())?;
    let cut = tp.length_where(|k| k != MoveKind::Rapid);
    let rapid = tp.length_where(|k| k == MoveKind::Rapid);
    eprintln!(
        "{input}: {} moves, feed length {cut:.3} mm, rapid length {rapid:.3} mm",
        tp.moves.len()
    );
    let job = PostJob {
        part_name: input.clone(),
        ..PostJob::default()
    };
    post(&tp, &job, target, &mut std::io::stdout().lock())?;
    Ok(())
}
