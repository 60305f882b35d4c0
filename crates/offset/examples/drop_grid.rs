//! Drops a cutter over a 0.5 mm grid on a part and prints the timing: how to embed
//! `cam-offset` headless.
//!
//! `cargo run --release -p cam-offset --example drop_grid -- PART.stl bull:6:1.5`

use cam_core::{Cutter, Mesh, Units};
use cam_offset::{DropCutter, Grid};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let part = args
        .get(1)
        .map_or("../shared/fixtures/ocl_mount_rush.stl", String::as_str);
    let cutter: Cutter = args.get(2).map_or("ball:6", String::as_str).parse()?;
    let mesh = Mesh::load(part, Units::Mm)?;
    let t = std::time::Instant::now();
    let dc = DropCutter::new(&mesh, cutter);
    let build = t.elapsed().as_secs_f64();
    let b = mesh.bounds();
    let grid = Grid::covering(b.min.x, b.max.x, b.min.y, b.max.y, 0.5);
    let t = std::time::Instant::now();
    let cl = dc.drop_grid(&grid);
    let drop = t.elapsed().as_secs_f64();
    let hits = cl.iter().filter(|p| p.z_tip.is_some()).count();
    println!(
        "{part}: {} triangles, {cutter}: {} points ({hits} touch) in {drop:.3} s = {:.0} points/s; index {build:.3} s",
        mesh.len(),
        cl.len(),
        cl.len() as f64 / drop
    );
    Ok(())
}
