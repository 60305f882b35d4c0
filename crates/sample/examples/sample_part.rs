//! Samples a part headless and prints a summary.
//!
//! ```text
//! cargo run --release -p cam-sample --example sample_part -- [PART] [SPACING_MM] [ARC_STEP_MM] [ANGLE_DEG]
//! ```
//! Defaults: `../shared/fixtures/ocl_mount_rush.stl`, 1 mm, 0.5 mm, 0°.

use std::process::ExitCode;
use std::time::Instant;

use cam_core::{Mesh, Units};
use cam_sample::{SampleConfig, sample_part};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let part = args.first().cloned().unwrap_or_else(|| {
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../../shared/fixtures/ocl_mount_rush.stl"
        )
        .to_string()
    });
    let num = |i: usize, d: f64| -> Result<f64, String> {
        args.get(i).map_or(Ok(d), |s| {
            s.parse::<f64>()
                .map_err(|e| format!("argument {}: '{s}': {e}", i + 1))
        })
    };
    let cfg = match (num(1, 1.0), num(2, 0.5), num(3, 0.0)) {
        (Ok(plane_spacing_mm), Ok(arc_step_mm), Ok(angle_deg)) => SampleConfig {
            angle_deg,
            plane_spacing_mm,
            arc_step_mm,
        },
        (a, b, c) => {
            for e in [a.err(), b.err(), c.err()].into_iter().flatten() {
                eprintln!("error: {e}");
            }
            return ExitCode::from(2);
        }
    };
    let t0 = Instant::now();
    let mesh = match Mesh::load(&part, Units::Mm) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let t_load = t0.elapsed();
    let t1 = Instant::now();
    let sections = match sample_part(&mesh, &cfg) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let t_sample = t1.elapsed();
    let segments: usize = sections.iter().map(|s| s.segments.len()).sum();
    let points: usize = sections
        .iter()
        .flat_map(|s| &s.segments)
        .map(|g| g.len())
        .sum();
    let b = mesh.bounds();
    println!("part        {part}");
    println!("triangles   {}", mesh.len());
    println!(
        "bounds mm   [{:.3}, {:.3}, {:.3}] .. [{:.3}, {:.3}, {:.3}]",
        b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z
    );
    println!(
        "config      angle {}°, plane spacing {} mm, arc step {} mm",
        cfg.angle_deg, cfg.plane_spacing_mm, cfg.arc_step_mm
    );
    println!("planes      {}", sections.len());
    println!("segments    {segments}");
    println!("points      {points}");
    println!("load        {:.1} ms", t_load.as_secs_f64() * 1e3);
    println!(
        "sample      {:.1} ms ({:.0} planes/s)",
        t_sample.as_secs_f64() * 1e3,
        sections.len() as f64 / t_sample.as_secs_f64()
    );
    if let Some(s) = sections.iter().find(|s| !s.segments.is_empty()) {
        let p = &s.segments[0];
        println!(
            "first plane v = {:.3}: {} points, first {:?}, last {:?}",
            s.v,
            p.len(),
            p[0],
            p[p.len() - 1]
        );
    }
    ExitCode::SUCCESS
}
