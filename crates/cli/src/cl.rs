//! `cam cl`: CL points by exact drop-cutter.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use cam_core::{Cutter, Mesh, Units};
use cam_offset::{ClPoint, DropCutter, Grid};

/// Arguments of `cam cl`.
#[derive(clap::Args)]
pub struct ClArgs {
    /// The part: .obj or .stl (binary or ASCII).
    part: PathBuf,
    /// Cutter: ball:D, flat:D or bull:D:r (mm), optionally ',flute=L'.
    #[arg(long)]
    tool: Cutter,
    /// Grid spacing (mm) over the part's XY bounding box, rows along X.
    #[arg(long, conflicts_with = "points", required_unless_present = "points")]
    step: Option<f64>,
    /// CSV of x,y positions (part units) to drop at, in order.
    #[arg(long)]
    points: Option<PathBuf>,
    /// Output CSV: header x,y,z,hit; z = tool tip in mm; where hit = 0 the cutter touches
    /// nothing and z is the part's lowest z.
    #[arg(short, long)]
    output: PathBuf,
    /// Units of the part file and of --points.
    #[arg(long, default_value = "mm")]
    units: Units,
    /// Print a machine-readable summary on stdout.
    #[arg(long)]
    json: bool,
}

/// Runs `cam cl`.
pub fn run(a: ClArgs) -> Result<()> {
    let t0 = Instant::now();
    let mesh = Mesh::load(&a.part, a.units)?;
    let t_load = t0.elapsed().as_secs_f64();
    let b = mesh.bounds();
    let pts: Vec<(f64, f64)> = match (&a.points, a.step) {
        (Some(p), _) => crate::xy_csv::read_xy(p, a.units.mm_per_unit())?,
        (None, Some(step)) => {
            let step = step * a.units.mm_per_unit();
            if !(step.is_finite() && step > 0.0) {
                bail!("--step must be a positive number of mm, got {step}");
            }
            let g = Grid::covering(b.min.x, b.max.x, b.min.y, b.max.y, step);
            if g.len() > 200_000_000 {
                bail!(
                    "--step {step} gives {} points over the part; use a larger step",
                    g.len()
                );
            }
            (0..g.len()).map(|k| g.xy(k)).collect()
        }
        (None, None) => bail!("give --step MM or --points FILE"),
    };
    let t1 = Instant::now();
    let dc = DropCutter::new(&mesh, a.tool);
    let pb = crate::progress::bar(pts.len() as u64, "drop-cutter", a.json);
    let mut out: Vec<ClPoint> = Vec::with_capacity(pts.len());
    for chunk in pts.chunks(65_536) {
        out.extend(dc.drop_points(chunk));
        pb.inc(chunk.len() as u64);
    }
    pb.finish_and_clear();
    let t_drop = t1.elapsed().as_secs_f64();
    let zmin = b.min.z;
    cam_core::io::write_atomic(&a.output, |w| {
        writeln!(w, "x,y,z,hit")?;
        for p in &out {
            match p.z_tip {
                Some(z) => writeln!(w, "{},{},{},1", p.x, p.y, z)?,
                None => writeln!(w, "{},{},{},0", p.x, p.y, zmin)?,
            }
        }
        Ok(())
    })
    .with_context(|| format!("{}: cannot write", a.output.display()))?;
    let hits = out.iter().filter(|p| p.z_tip.is_some()).count();
    if a.json {
        let s = serde_json::json!({
            "part": a.part, "tool": a.tool.to_string(), "triangles": mesh.len(),
            "degenerate_dropped": mesh.stats().degenerate_dropped,
            "points": out.len(), "hits": hits, "output": a.output,
            "load_s": t_load, "drop_s": t_drop,
            "points_per_s": out.len() as f64 / t_drop.max(1e-9),
        });
        println!("{s}");
    } else {
        eprintln!(
            "cam cl: {} points ({} touch the part) with {} on {} triangles in {:.3} s -> {}",
            out.len(),
            hits,
            a.tool,
            mesh.len(),
            t_drop,
            a.output.display()
        );
    }
    Ok(())
}
