//! Times a 0.5 mm grid drop on a part: `cargo run --release --example count -- PART SPEC`.
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let mesh = cam_core::Mesh::load(&a[1], cam_core::Units::Mm).unwrap();
    let c: cam_core::Cutter = a[2].parse().unwrap();
    let t = std::time::Instant::now();
    let dc = cam_offset::DropCutter::new(&mesh, c);
    let tb = t.elapsed().as_secs_f64();
    let b = mesh.bounds();
    let g = cam_offset::Grid::covering(b.min.x, b.max.x, b.min.y, b.max.y, 0.5);
    let t = std::time::Instant::now();
    let p = dc.drop_grid(&g);
    let el = t.elapsed().as_secs_f64();
    println!(
        "{} pts build {:.3}s {:.0} pts/s",
        p.len(),
        tb,
        p.len() as f64 / el
    );
}
