//! `cam plan`: mesh → finishing toolpath → G-code (and APT CL data), checked and verified.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use cam_core::{Mesh, MoveKind, Units};
use cam_gcode::{AptHeader, Post, PostJob};
use cam_plan::{Direction, Milling, PlanConfig};

/// Arguments of `cam plan`. Every length flag is in mm (feeds in mm/min) whatever the part's
/// or the program's units.
#[derive(clap::Args)]
pub struct PlanArgs {
    /// The part: .obj or .stl.
    pub part: PathBuf,
    /// Output G-code program (written atomically).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Cutter spec (ball:D, flat:D, bull:D:r in mm), or a tool id with --tool-library.
    /// Default: ball:6, or with a library the largest tool that fits the part.
    #[arg(long)]
    pub tool: Option<String>,
    /// Feed-forward tolerance τ (mm): largest distance of a cut move from the exact CL surface.
    #[arg(long, default_value_t = 0.01)]
    pub tolerance: f64,
    /// Largest scallop height h (mm) left between passes.
    #[arg(long, default_value_t = 0.01)]
    pub scallop: f64,
    /// Raster angle (degrees from +X) of the passes.
    #[arg(long, default_value_t = 0.0)]
    pub angle: f64,
    /// Post-processor.
    #[arg(long, default_value = "linuxcnc")]
    pub post: Post,
    /// Cutting feed (mm/min).
    #[arg(long, default_value_t = 1000.0)]
    pub feed: f64,
    /// Plunge feed (mm/min).
    #[arg(long, default_value_t = 300.0)]
    pub plunge_feed: f64,
    /// Spindle speed (rev/min), clockwise (M3).
    #[arg(long, default_value_t = 10000.0)]
    pub rpm: f64,
    /// Safe Z of the tool tip for rapids (mm); default 5 mm above the highest CL point.
    #[arg(long)]
    pub safe_z: Option<f64>,
    /// Stock/boundary box the tool tip stays inside: xmin,xmax,ymin,ymax (mm).
    #[arg(long, value_parser = parse_box)]
    pub stock: Option<(f64, f64, f64, f64)>,
    /// Pass order.
    #[arg(long, value_enum, default_value_t = DirectionArg::Zigzag)]
    pub direction: DirectionArg,
    /// Climb or conventional milling (clockwise spindle).
    #[arg(long, value_enum, default_value_t = MillingArg::Climb)]
    pub milling: MillingArg,
    /// Units of the part file.
    #[arg(long, default_value = "mm")]
    pub units: Units,
    /// Units of the G-code program (G21 mm or G20 inch).
    #[arg(long, default_value = "mm")]
    pub gcode_units: Units,
    /// Tool number for the tool change (T/H words).
    #[arg(long, default_value_t = 1)]
    pub tool_number: u32,
    /// Also write APT-style CL data (GOTO/x,y,z,i,j,k; tool tip, mm) to this file.
    #[arg(long)]
    pub cl_out: Option<PathBuf>,
    /// Rapid rate (mm/min) used only for the cycle-time estimate.
    #[arg(long, default_value_t = 5000.0)]
    pub rapid_rate: f64,
    /// Print a machine-readable summary on stdout.
    #[arg(long)]
    pub json: bool,
}

/// `--direction`.
#[derive(Clone, Copy, clap::ValueEnum)]
pub enum DirectionArg {
    /// Alternate directions, linking pass ends.
    Zigzag,
    /// All passes the same way, retracting between them.
    Oneway,
}

/// `--milling`.
#[derive(Clone, Copy, clap::ValueEnum)]
pub enum MillingArg {
    /// Climb milling.
    Climb,
    /// Conventional milling.
    Conventional,
}

fn parse_box(s: &str) -> Result<(f64, f64, f64, f64), String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| {
            t.trim()
                .parse::<f64>()
                .map_err(|_| format!("'{t}' is not a number"))
        })
        .collect::<Result<_, _>>()?;
    match v[..] {
        [a, b, c, d] if v.iter().all(|x| x.is_finite()) && a < b && c < d => Ok((a, b, c, d)),
        _ => Err("expected xmin,xmax,ymin,ymax with xmin < xmax and ymin < ymax".into()),
    }
}

/// Runs `cam plan`.
pub fn run(a: PlanArgs) -> Result<()> {
    for (name, v) in [
        ("--feed", a.feed),
        ("--plunge-feed", a.plunge_feed),
        ("--rpm", a.rpm),
        ("--rapid-rate", a.rapid_rate),
    ] {
        if !(v.is_finite() && v > 0.0) {
            bail!("{name} must be a positive number, got {v}");
        }
    }
    let t0 = Instant::now();
    let mesh = Mesh::load(&a.part, a.units)?;
    let cutter = match &a.tool {
        Some(spec) => spec.parse()?,
        None => cam_core::Cutter::ball(6.0)?,
    };
    let cfg = PlanConfig {
        cutter,
        tolerance_mm: a.tolerance,
        scallop_mm: a.scallop,
        angle_deg: a.angle,
        safe_z_mm: a.safe_z,
        direction: match a.direction {
            DirectionArg::Zigzag => Direction::ZigZag,
            DirectionArg::Oneway => Direction::OneWay,
        },
        milling: match a.milling {
            MillingArg::Climb => Milling::Climb,
            MillingArg::Conventional => Milling::Conventional,
        },
        boundary: a.stock,
        ..PlanConfig::default()
    };
    cfg.validate()?;
    let pb = crate::progress::bar(0, "planning", a.json);
    let progress = |done: usize, total: usize| {
        pb.set_length(total as u64);
        pb.set_position(done as u64);
    };
    let plan = cam_plan::plan_part(&mesh, &cfg, Some(&progress))
        .with_context(|| format!("{}: cannot plan", a.part.display()))?;
    pb.finish_and_clear();
    let t_plan = t0.elapsed().as_secs_f64();

    let part_name = a
        .part
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or("part")
        .to_string();
    let job = PostJob {
        part_name: part_name.clone(),
        tool_spec: cutter.to_string(),
        tool_number: a.tool_number,
        tolerance_mm: a.tolerance,
        scallop_mm: a.scallop,
        feed_mm_per_min: a.feed,
        plunge_feed_mm_per_min: a.plunge_feed,
        rpm: a.rpm,
        spindle_cw: true,
        safe_z_mm: plan.safe_z_mm,
        units: a.gcode_units,
        ..PostJob::default()
    };
    let program = cam_gcode::post_to_string(&plan.toolpath, &job, a.post)?;
    cam_core::io::write_atomic(&a.output, |w| w.write_all(program.as_bytes()))
        .with_context(|| format!("{}: cannot write", a.output.display()))?;
    if let Some(cl) = &a.cl_out {
        let header = AptHeader {
            part_name: part_name.clone(),
            cutter: Some(cutter),
        };
        cam_core::io::write_atomic(cl, |w| cam_gcode::write_apt(w, &plan.toolpath, &header))
            .with_context(|| format!("{}: cannot write", cl.display()))?;
    }

    let tp = &plan.toolpath;
    let plunge_len = tp.length_where(|k| matches!(k, MoveKind::Plunge | MoveKind::Retract));
    let cycle_min = plan.cut_length_mm / a.feed
        + plunge_len / a.plunge_feed
        + plan.rapid_length_mm / a.rapid_rate;
    let summary = serde_json::json!({
        "part": a.part, "output": a.output, "tool": cutter.to_string(), "post": a.post.name(),
        "tolerance_mm": a.tolerance, "scallop_mm": a.scallop,
        "passes": plan.passes, "cl_points": plan.cl_points, "moves": tp.moves.len(),
        "cut_length_mm": plan.cut_length_mm, "rapid_length_mm": plan.rapid_length_mm,
        "plunge_retract_length_mm": plan.plunge_retract_length_mm,
        "estimated_cycle_time_min": cycle_min,
        "max_chord_deviation_mm": plan.max_chord_deviation_mm,
        "predicted_max_scallop_mm": plan.predicted_max_scallop_mm,
        "unresolved_joins": plan.unresolved_joins,
        "safe_z_mm": plan.safe_z_mm,
        "plan_s": t_plan,
    });
    if a.json {
        println!("{summary}");
    } else {
        eprintln!(
            "cam plan: {} passes, {} CL points, cut {:.0} mm, rapid {:.0} mm, ~{:.1} min; \
             chordal deviation ≤ {:.4} mm (τ {}), scallop ≤ {:.4} mm (h {}) -> {}",
            plan.passes,
            plan.cl_points,
            plan.cut_length_mm,
            plan.rapid_length_mm,
            cycle_min,
            plan.max_chord_deviation_mm,
            a.tolerance,
            plan.predicted_max_scallop_mm,
            a.scallop,
            a.output.display()
        );
    }
    Ok(())
}
