//! Batch results are bit-for-bit identical for 1 and N threads.

use cam_core::Cutter;
use cam_offset::{DropCutter, Grid};

use crate::support::{mesh, uv_sphere};

#[test]
fn grid_identical_for_1_and_4_threads() {
    let m = mesh(uv_sphere(10.0, 24, 48));
    let dc = DropCutter::new(&m, Cutter::bull(6.0, 1.5).unwrap());
    let grid = Grid::covering(-14.0, 14.0, -14.0, 14.0, 0.37);
    let pts: Vec<(f64, f64)> = (0..grid.len()).map(|k| grid.xy(k)).collect();
    let run = |n: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap();
        pool.install(|| (dc.drop_grid(&grid), dc.drop_points(&pts)))
    };
    let (g1, p1) = run(1);
    let (g4, p4) = run(4);
    assert_eq!(g1, g4);
    assert_eq!(p1, p4);
    assert_eq!(g1, p1, "grid and point batches must agree");
    assert!(g1.iter().filter(|p| p.z_tip.is_some()).count() > 100);
    assert!(g1.iter().any(|p| p.z_tip.is_none()));
}
