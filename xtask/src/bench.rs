//! `cargo xtask bench dropcutter`: our drop-cutter against OpenCAMLib's BatchDropCutter on the
//! same machine, grid and cutters.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use cam_core::{Cutter, Mesh, Units};
use cam_offset::{ClPoint, DropCutter, Grid};

use crate::ocl;

/// Benchmark settings.
pub struct BenchConfig {
    /// Runs per measurement; the best is reported.
    pub runs: usize,
    /// Grid step (mm).
    pub step_mm: f64,
}

/// The benchmark parts (in `$CAM_SHARED/fixtures/`).
pub const PARTS: [&str; 2] = ["ocl_mount_rush.stl", "ocl_sphere_on_plate.stl"];
/// The benchmark cutters.
pub const CUTTERS: [&str; 3] = ["ball:6", "flat:6", "bull:6:1.5"];
/// OpenMP threads for OpenCAMLib: all cores of the 2-core reference machine.
const OCL_THREADS: usize = 2;

/// Our side of one measurement.
#[derive(Debug, Clone, Copy)]
pub struct Ours {
    /// Seconds for `DropCutter::new`.
    pub build_s: f64,
    /// Seconds for `drop_grid`.
    pub drop_s: f64,
    /// Points dropped.
    pub points: usize,
}

/// Times `DropCutter::new` + `drop_grid` once; `Err` with the panic message while the
/// drop-cutter is not implemented.
pub fn time_ours(
    mesh: &Mesh,
    cutter: Cutter,
    grid: &Grid,
) -> std::result::Result<(Ours, Vec<ClPoint>), String> {
    let prev = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let r = catch_unwind(AssertUnwindSafe(|| {
        let t0 = Instant::now();
        let dc = DropCutter::new(mesh, cutter);
        let build_s = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let pts = dc.drop_grid(grid);
        let drop_s = t1.elapsed().as_secs_f64();
        (
            Ours {
                build_s,
                drop_s,
                points: pts.len(),
            },
            pts,
        )
    }));
    std::panic::set_hook(prev);
    r.map_err(|e| {
        e.downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| e.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "panic".into())
    })
}

fn best_load(path: &Path, runs: usize) -> Result<(Mesh, f64)> {
    let mut best = f64::INFINITY;
    let mut mesh = None;
    for _ in 0..runs.max(1) {
        let t = Instant::now();
        let m =
            Mesh::load(path, Units::Mm).with_context(|| format!("loading {}", path.display()))?;
        best = best.min(t.elapsed().as_secs_f64());
        mesh = Some(m);
    }
    Ok((mesh.expect("at least one run"), best))
}

fn fmt_rate(r: f64) -> String {
    if r >= 1e6 {
        format!("{:.2}M", r / 1e6)
    } else if r >= 1e4 {
        format!("{:.1}k", r / 1e3)
    } else {
        format!("{r:.0}")
    }
}

/// Max |Δz| (mm) between OpenCAMLib's CSV (`x,y,z`, 6 decimals, zig-zag rows) and our grid
/// points, over the points where OpenCAMLib's cutter rose above its start height `zmin`
/// (the mesh's min z) and ours touched; and the number of such points compared.
pub fn max_dz_vs_csv(csv: &str, grid: &Grid, ours: &[ClPoint], zmin: f64) -> Result<(f64, usize)> {
    let mut worst = 0.0f64;
    let mut n = 0;
    for (k, line) in csv.lines().skip(1).enumerate() {
        let bad = || anyhow::anyhow!("OpenCAMLib CSV line {}: '{line}'", k + 2);
        let v: Vec<f64> = line
            .split(',')
            .take(3)
            .map(|t| t.trim().parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| bad())?;
        let [x, y, z] = v[..] else { return Err(bad()) };
        let i = ((x - grid.x0) / grid.step).round();
        let j = ((y - grid.y0) / grid.step).round();
        if i < 0.0 || j < 0.0 || i as usize >= grid.nx || j as usize >= grid.ny {
            anyhow::bail!("OpenCAMLib point ({x}, {y}) is off our grid");
        }
        let p = ours[j as usize * grid.nx + i as usize];
        if (p.x - x).abs() > 1e-5 || (p.y - y).abs() > 1e-5 {
            anyhow::bail!(
                "OpenCAMLib point ({x}, {y}) matched ours at ({}, {})",
                p.x,
                p.y
            );
        }
        if let Some(zo) = p.z_tip
            && z > zmin + 1e-5
        {
            worst = worst.max((zo - z).abs());
            n += 1;
        }
    }
    Ok((worst, n))
}

/// Runs the benchmark and prints the tables.
pub fn dropcutter(cfg: &BenchConfig) -> Result<()> {
    let py = ocl::python()?;
    let tmp = tempfile::tempdir()?;
    let threads = rayon::current_num_threads();
    println!(
        "drop-cutter benchmark: {} mm grid over each part's XY bounding box, best of {}; \
         OpenCAMLib {OCL_THREADS} OpenMP threads, ours {threads} rayon threads\n",
        cfg.step_mm, cfg.runs
    );
    let mut table = String::from(
        "| part | cutter | points | OCL pts/s | ours pts/s (drop) | ours build ms | ours pts/s (build+drop) | ratio (build+drop) | max abs dz mm (points) |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    let mut loads =
        String::from("| part | triangles | file MB | Mesh::load ms |\n| --- | --- | --- | --- |\n");
    let mut pending = None;
    for part in PARTS {
        let path = crate::shared_dir().join("fixtures").join(part);
        let (mesh, load_s) = best_load(&path, cfg.runs)?;
        let mb = std::fs::metadata(&path)?.len() as f64 / 1e6;
        loads.push_str(&format!(
            "| {part} | {} | {mb:.2} | {:.1} |\n",
            mesh.len(),
            load_s * 1e3
        ));
        let b = mesh.bounds();
        let grid = Grid::covering(b.min.x, b.max.x, b.min.y, b.max.y, cfg.step_mm);
        for spec in CUTTERS {
            let cutter: Cutter = spec.parse()?;
            let mut ocl_best: Option<ocl::BatchTiming> = None;
            for _ in 0..cfg.runs {
                let t = ocl::shared_batch(
                    &py,
                    &path,
                    &cutter,
                    cfg.step_mm,
                    OCL_THREADS,
                    &tmp.path().join("ocl.csv"),
                )?;
                if ocl_best.is_none_or(|b| t.points_per_s > b.points_per_s) {
                    ocl_best = Some(t);
                }
            }
            let o = ocl_best.expect("runs >= 1");
            if o.points != grid.len() {
                eprintln!(
                    "warning: {part} {spec}: OpenCAMLib dropped {} points, our grid has {}",
                    o.points,
                    grid.len()
                );
            }
            let mut ours: Option<Ours> = None;
            let mut agree = String::from("n/a");
            for run in 0..cfg.runs {
                match time_ours(&mesh, cutter, &grid) {
                    Ok((t, pts)) => {
                        if ours.is_none_or(|b| t.build_s + t.drop_s < b.build_s + b.drop_s) {
                            ours = Some(t);
                        }
                        if run == 0 {
                            let csv = std::fs::read_to_string(tmp.path().join("ocl.csv"))?;
                            let (dz, n) = max_dz_vs_csv(&csv, &grid, &pts, mesh.bounds().min.z)?;
                            agree = format!("{dz:.1e} ({n})");
                        }
                    }
                    Err(msg) => {
                        pending = Some(msg);
                        break;
                    }
                }
            }
            let cols = match ours {
                Some(t) => {
                    let total = t.points as f64 / (t.build_s + t.drop_s);
                    format!(
                        "{} | {:.1} | {} | {:.1}×",
                        fmt_rate(t.points as f64 / t.drop_s),
                        t.build_s * 1e3,
                        fmt_rate(total),
                        total / o.points_per_s
                    )
                }
                None => "n/a | n/a | n/a | n/a".into(),
            };
            let line = format!(
                "| {part} | {spec} | {} | {} | {cols} | {agree} |\n",
                grid.len(),
                fmt_rate(o.points_per_s)
            );
            eprint!("{line}");
            table.push_str(&line);
        }
    }
    println!("{table}");
    println!("Part loading (best of {}):\n\n{loads}", cfg.runs);
    println!(
        "OCL pts/s is what ../shared/tools/ocl/ocl_dropcutter.py prints: its wall time covers \
         BatchDropCutter setup (kd-tree), appending the points, run() and reading them back. \
         Ours: DropCutter::new (build) and drop_grid (drop); the ratio uses build+drop. \
         max abs dz: ours vs the z in OpenCAMLib's CSV (6 decimals, so resolution 5e-7 mm) \
         where both touch (OpenCAMLib above its start height, the part's min z)."
    );
    if let Some(msg) = pending {
        println!("\nours: not measured, the drop-cutter panicked: {msg}");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compares_zigzag_csv_by_grid_index() {
        let grid = Grid::covering(0.0, 1.0, 0.0, 1.0, 0.5);
        let ours: Vec<ClPoint> = (0..grid.len())
            .map(|k| {
                let (x, y) = grid.xy(k);
                ClPoint {
                    x,
                    y,
                    z_tip: (k != 4).then_some(x + y),
                }
            })
            .collect();
        // Zig-zag: the second row reversed; one point 3e-6 off, one a miss at zmin.
        let csv = "x,y,z\n0,0,0\n0.5,0,0.5\n1,0,1\n1,0.5,1.500003\n0.5,0.5,-1\n0,0.5,0.5\n\
                   0,1,1\n0.5,1,1.5\n1,1,2\n";
        let (dz, n) = max_dz_vs_csv(csv, &grid, &ours, -1.0).unwrap();
        assert!((dz - 3e-6).abs() < 1e-12, "{dz}");
        assert_eq!(n, 8);
        assert!(max_dz_vs_csv("x,y,z\n9,9,0\n", &grid, &ours, -1.0).is_err());
        assert!(max_dz_vs_csv("x,y,z\n0,zero,0\n", &grid, &ours, -1.0).is_err());
    }
}
