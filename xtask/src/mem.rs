//! `cargo xtask bench mem`: load time and peak memory for a 1M-triangle part.
//!
//! The parent writes a wavy height-field STL (708 × 708 squares, 1 002 528 triangles) into a
//! temporary directory, then re-runs this executable as a child ([`CHILD`]) that loads it,
//! builds the drop-cutter for `ball:6` and drops a 0.5 mm grid, reading its own peak resident
//! set (`VmHWM` in `/proc/self/status`) after each phase, so the parent's copy of the
//! triangles does not count.

use std::io::BufWriter;
use std::path::Path;
use std::process::Command;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use cam_core::{Cutter, DVec3, Mesh, Triangle, Units};
use cam_offset::Grid;

/// Hidden subcommand: the measured child.
pub const CHILD: &str = "__mem-child";
/// Squares per side of the height field.
pub const N: usize = 708;
/// Side of the square part (mm).
pub const SIDE_MM: f64 = 100.0;

/// The height-field surface z(x, y) (mm), smooth and wavy.
pub fn height(x: f64, y: f64) -> f64 {
    10.0 + 3.0 * (x / 5.0).sin() * (y / 7.0).cos() + 0.5 * (0.9 * x + 0.4 * y).sin()
}

/// The triangles of the `n × n` height field over `[-SIDE/2, SIDE/2]²`, 2 per square.
pub fn height_field(n: usize) -> Vec<Triangle> {
    let p = |i: usize, j: usize| {
        let x = -SIDE_MM / 2.0 + SIDE_MM * i as f64 / n as f64;
        let y = -SIDE_MM / 2.0 + SIDE_MM * j as f64 / n as f64;
        DVec3::new(x, y, height(x, y))
    };
    let mut t = Vec::with_capacity(2 * n * n);
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            t.push(Triangle::new(a, b, c));
            t.push(Triangle::new(a, c, d));
        }
    }
    t
}

/// Peak resident set size (VmHWM) of this process in MiB, if readable.
pub fn vm_hwm_mib() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

fn mib(v: Option<f64>) -> String {
    v.map_or("n/a".into(), |m| format!("{m:.1} MiB"))
}

/// The parent: generate, then measure in a child.
pub fn mem() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let path = dir.path().join("wavy_1m.stl");
    let t = Instant::now();
    let tris = height_field(N);
    {
        let f = std::fs::File::create(&path)?;
        let mut w = BufWriter::new(f);
        cam_core::io::stl::write_binary_stl(&mut w, &tris)?;
        std::io::Write::flush(&mut w)?;
    }
    let bytes = std::fs::metadata(&path)?.len();
    println!(
        "generated {} ({} triangles, {:.1} MB binary STL, {SIDE_MM}×{SIDE_MM} mm) in {:.2} s",
        path.display(),
        tris.len(),
        bytes as f64 / 1e6,
        t.elapsed().as_secs_f64()
    );
    drop(tris);
    let exe = std::env::current_exe()?;
    let status = Command::new(exe)
        .arg(CHILD)
        .arg(&path)
        .status()
        .context("running the child")?;
    if !status.success() {
        bail!("the measuring child failed ({status})");
    }
    Ok(())
}

/// The child: load, build, drop; print times and VmHWM after each phase.
pub fn child(path: &str) -> Result<()> {
    println!("| phase | time | peak RSS (VmHWM) after |\n| --- | --- | --- |");
    println!("| start | | {} |", mib(vm_hwm_mib()));
    let t = Instant::now();
    let mesh = Mesh::load(Path::new(path), Units::Mm)?;
    println!(
        "| Mesh::load ({} triangles) | {:.0} ms | {} |",
        mesh.len(),
        t.elapsed().as_secs_f64() * 1e3,
        mib(vm_hwm_mib())
    );
    let cutter: Cutter = "ball:6".parse()?;
    let b = mesh.bounds();
    let grid = Grid::covering(b.min.x, b.max.x, b.min.y, b.max.y, 0.5);
    let prev = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let r = std::panic::catch_unwind(|| {
        let t = Instant::now();
        let dc = cam_offset::DropCutter::new(&mesh, cutter);
        println!(
            "| DropCutter::new (ball:6) | {:.0} ms | {} |",
            t.elapsed().as_secs_f64() * 1e3,
            mib(vm_hwm_mib())
        );
        let t = Instant::now();
        let pts = dc.drop_grid(&grid);
        println!(
            "| drop_grid ({} points, 0.5 mm) | {:.0} ms | {} |",
            pts.len(),
            t.elapsed().as_secs_f64() * 1e3,
            mib(vm_hwm_mib())
        );
    });
    std::panic::set_hook(prev);
    if let Err(e) = r {
        let msg = e
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| e.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        println!("\ndrop-cutter not measured: it panicked ({msg})");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn height_field_size_and_heights() {
        let t = height_field(4);
        assert_eq!(t.len(), 32);
        assert_eq!(2 * N * N, 1_002_528);
        for tri in &t {
            for p in tri.v {
                assert_eq!(p.z, height(p.x, p.y));
            }
            // Upward-facing: the STL writer's normals point +z.
            assert!(tri.normal().unwrap().z > 0.0);
        }
    }
}
