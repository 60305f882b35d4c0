//! `cam plan`: mesh → finishing toolpath → G-code (and APT CL data), checked and verified.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use cam_core::{Mesh, MoveKind, Units};
use cam_gcode::{AptHeader, Post, PostJob};
use cam_holder::{AssemblyDefaults, CheckConfig, HolderPolicy, ToolAssembly, ToolLibrary};
use cam_plan::{Direction, Milling, PlanConfig};

use crate::exit::Findings;

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
    /// Tool library (JSON, see docs/tool-library.md); --tool then names a tool id.
    #[arg(long)]
    pub tool_library: Option<PathBuf>,
    /// What to do when the shank or holder collides with the part: fail (exit 1, no G-code),
    /// report (write G-code and print the collisions) or avoid (lift over colliding
    /// stretches and say what was left unmachined).
    #[arg(long, default_value = "fail")]
    pub holder: HolderPolicy,
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
    /// Cutting feed (mm/min); default the library tool's, else 1000.
    #[arg(long)]
    pub feed: Option<f64>,
    /// Plunge feed (mm/min); default the library tool's, else 300.
    #[arg(long)]
    pub plunge_feed: Option<f64>,
    /// Spindle speed (rev/min), clockwise (M3); default the library tool's, else 10000.
    #[arg(long)]
    pub rpm: Option<f64>,
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
    /// Skip the verification of the planned program.
    #[arg(long)]
    pub no_verify: bool,
    /// Verification settings (the gouge tolerance is --tolerance).
    #[command(flatten)]
    pub verify: crate::verify::VerifyOpts,
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

/// The tool: from the library (named or chosen by curvature and holder clearance), or a
/// spec with the default shank and holder.
fn choose_tool(
    a: &PlanArgs,
    mesh: &Mesh,
    base: &PlanConfig,
) -> Result<(ToolAssembly, Option<String>)> {
    let Some(lib_path) = &a.tool_library else {
        let cutter: cam_core::Cutter = match &a.tool {
            Some(spec) => spec.parse()?,
            None => cam_core::Cutter::ball(6.0)?,
        };
        return Ok((
            ToolAssembly::from_spec(cutter, &AssemblyDefaults::default()),
            None,
        ));
    };
    let lib = ToolLibrary::load(lib_path)?;
    if let Some(id) = &a.tool {
        let t = lib.get(id).with_context(|| {
            let ids: Vec<&str> = lib.tools.iter().map(|t| t.id.as_str()).collect();
            format!(
                "{}: no tool '{id}' (tools: {})",
                lib_path.display(),
                ids.join(", ")
            )
        })?;
        return Ok((t.clone(), None));
    }
    let curv = cam_holder::concave_curvature(mesh, &cam_holder::CurvatureConfig::default());
    // Judge each candidate on what the machine would run: its plan, posted and read back.
    let plan_for = |t: &ToolAssembly| -> Option<cam_core::Toolpath> {
        let cfg = PlanConfig {
            cutter: t.cutter,
            ..*base
        };
        let p = cam_plan::plan_part(mesh, &cfg, None).ok()?;
        let job = PostJob {
            safe_z_mm: p.safe_z_mm,
            ..PostJob::default()
        };
        let text = cam_gcode::post_to_string(&p.toolpath, &job, a.post).ok()?;
        reread(&text, a).ok()
    };
    let scfg = cam_holder::SelectConfig {
        check: holder_check(),
        ..cam_holder::SelectConfig::default()
    };
    let sel = cam_holder::select_tool(&lib, mesh, &curv, Some(&plan_for), &scfg)
        .map_err(|e| anyhow::anyhow!("{}: {e}", a.part.display()))?;
    let why = format!(
        "tool {} chosen from {} (smallest concave radius {}; {} larger tools passed over)",
        sel.tool_id,
        lib_path.display(),
        curv.min.map_or("none".to_string(), |m| format!(
            "{:.3} mm at ({:.2}, {:.2}, {:.2})",
            m.radius_mm, m.region.x, m.region.y, m.region.z
        )),
        sel.rejected.len()
    );
    Ok((sel.assembly, Some(why)))
}

/// Runs `cam plan`.
pub fn run(a: PlanArgs) -> Result<()> {
    let t0 = Instant::now();
    let mesh = Mesh::load(&a.part, a.units)?;
    let mut cfg = PlanConfig {
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
    // τ holds in the program as written: plan to τ less the post's rounding. Nor can a
    // scallop height below the rounding be held or checked (and the passes it asks for grow
    // as 1/√h: 1e-9 mm would plan for days).
    let rounding = cam_gcode::rounding_mm(a.gcode_units);
    for (flag, v) in [("--tolerance", a.tolerance), ("--scallop", a.scallop)] {
        if v <= 2.0 * rounding {
            anyhow::bail!(
                "{flag} {v} mm is below what a program in {} can hold: its coordinates are \
                 rounded by up to {rounding:.1e} mm; use at least {:.4} mm",
                a.gcode_units,
                2.0 * rounding
            );
        }
    }
    if !a.no_verify && a.tolerance > cam_verify::pipeline::MAX_TOLERANCE_MM {
        anyhow::bail!(
            "--tolerance {} mm is above the {} mm the verification checks (its vectors reach 20 \
             times the tolerance into the material); plan with --no-verify",
            a.tolerance,
            cam_verify::pipeline::MAX_TOLERANCE_MM
        );
    }
    cfg.tolerance_mm = a.tolerance - rounding;
    let (assembly, chosen) = choose_tool(&a, &mesh, &cfg)?;
    let cutter = assembly.cutter;
    cfg.cutter = cutter;
    cfg.validate()?;
    if let (Some(why), false) = (&chosen, a.json) {
        eprintln!("cam plan: {why}");
    }
    let feeds = &assembly.feeds;
    let feed = a.feed.or(feeds.feed_mm_per_min).unwrap_or(1000.0);
    let plunge_feed = a
        .plunge_feed
        .or(feeds.plunge_feed_mm_per_min)
        .unwrap_or(300.0);
    let rpm = a.rpm.or(feeds.rpm).unwrap_or(10000.0);
    // Upper limits far above any machine (1 km/min, a million rpm): beyond them a value is a
    // typo, and a post would print it with hundreds of digits.
    let from = |flag: Option<f64>, name: &'static str, field: &'static str| {
        if flag.is_some() { name } else { field }
    };
    for (name, v, most) in [
        (
            from(a.feed, "--feed", "the tool library's feed_mm_per_min"),
            feed,
            1.0e6,
        ),
        (
            from(
                a.plunge_feed,
                "--plunge-feed",
                "the tool library's plunge_feed_mm_per_min",
            ),
            plunge_feed,
            1.0e6,
        ),
        (from(a.rpm, "--rpm", "the tool library's rpm"), rpm, 1.0e6),
        ("--rapid-rate", a.rapid_rate, 1.0e6),
    ] {
        if !(v.is_finite() && v > 0.0) {
            bail!("{name} must be a positive number, got {v}");
        }
        if v > most {
            bail!("{name} {v:e} is above {most:e}");
        }
    }
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
        tool_number: assembly.number.unwrap_or(a.tool_number),
        tolerance_mm: a.tolerance,
        scallop_mm: a.scallop,
        feed_mm_per_min: feed,
        plunge_feed_mm_per_min: plunge_feed,
        rpm,
        spindle_cw: true,
        safe_z_mm: plan.safe_z_mm,
        units: a.gcode_units,
        ..PostJob::default()
    };
    let mut toolpath = plan.toolpath.clone();
    let mut program = cam_gcode::post_to_string(&toolpath, &job, a.post)?;
    // Check what the machine will run: the program read back, with its line numbers.
    let t1 = Instant::now();
    let mut readback = reread(&program, &a)?;
    let check = holder_check();
    let mut report = cam_holder::check_toolpath(&mesh, &assembly, &readback, &check);
    let first_report = report.clone();
    let stick = cam_holder::min_stick_out(&mesh, &assembly, &readback, &check);
    let mut avoided = None;
    if !report.is_clear() {
        match a.holder {
            HolderPolicy::Fail => {
                print_collisions(&report, &assembly);
                return Err(Findings(format!(
                    "{} holder/shank collisions (deepest {:.3} mm) with {} at stick-out {} mm; \
                     minimum collision-free stick-out {}; no G-code written (--holder report or avoid to override)",
                    report.collisions.len(),
                    report.max_depth_mm,
                    assembly.id,
                    assembly.stick_out_mm,
                    fmt_stick(&stick)
                ))
                .into());
            }
            HolderPolicy::Report => print_collisions(&report, &assembly),
            HolderPolicy::Avoid => {
                let side = plan
                    .pass_v_mm
                    .windows(2)
                    .map(|w| (w[1] - w[0]).abs())
                    .fold(0.0, f64::max);
                let (lifted, summary) = cam_holder::avoid(
                    &readback,
                    &report.collisions,
                    &cam_holder::AvoidConfig {
                        safe_z_mm: plan.safe_z_mm,
                        stepover_mm: side,
                    },
                );
                toolpath = lifted;
                program = cam_gcode::post_to_string(&toolpath, &job, a.post)?;
                readback = reread(&program, &a)?;
                report = cam_holder::check_toolpath(&mesh, &assembly, &readback, &check);
                if !report.is_clear() {
                    print_collisions(&report, &assembly);
                    return Err(Findings(
                        "collisions remain after lifting; no G-code written".into(),
                    )
                    .into());
                }
                if !a.json {
                    eprintln!(
                        "cam plan: lifted over {} colliding stretches: {:.1} mm of cut dropped, about {:.1} mm² left unmachined",
                        summary.stretches.len(),
                        summary.removed_cut_length_mm,
                        summary.unmachined_area_mm2
                    );
                }
                avoided = Some(summary);
            }
        }
    }
    let t_holder = t1.elapsed().as_secs_f64();
    cam_core::io::write_atomic(&a.output, |w| w.write_all(program.as_bytes()))
        .with_context(|| format!("{}: cannot write", a.output.display()))?;
    if let Some(cl) = &a.cl_out {
        let header = AptHeader {
            part_name: part_name.clone(),
            cutter: Some(cutter),
        };
        cam_core::io::write_atomic(cl, |w| cam_gcode::write_apt(w, &toolpath, &header))
            .with_context(|| format!("{}: cannot write", cl.display()))?;
    }
    let holder_json = serde_json::json!({
        "tool": assembly.id, "stick_out_mm": assembly.stick_out_mm,
        "collisions": report.collisions.len(), "max_depth_mm": report.max_depth_mm,
        "findings": findings_json(&first_report),
        "min_stick_out_mm": stick.min_mm, "policy": format!("{:?}", a.holder).to_lowercase(),
        "removed_cut_length_mm": avoided.as_ref().map(|s| s.removed_cut_length_mm),
        "unmachined_area_mm2": avoided.as_ref().map(|s| s.unmachined_area_mm2),
        "check_s": t_holder,
    });
    // Every plan certifies itself: verify the program as read back.
    let verification = if a.no_verify {
        None
    } else {
        Some(
            crate::verify::run_verification(
                &mesh,
                &readback,
                &cutter,
                a.tolerance,
                &a.verify,
                a.json,
            )
            .with_context(|| {
                format!(
                    "the program is written to {}, but verifying it could not run \
                     (--no-verify skips it)",
                    a.output.display()
                )
            })?,
        )
    };
    let tp = &toolpath;
    let plunge_len = tp.length_where(|k| matches!(k, MoveKind::Plunge | MoveKind::Retract));
    let cut_len = tp.length_where(|k| k == MoveKind::Cut);
    let rapid_len = tp.length_where(|k| k == MoveKind::Rapid);
    let cycle_min = cut_len / feed + plunge_len / plunge_feed + rapid_len / a.rapid_rate;
    let summary = serde_json::json!({
        "part": a.part, "output": a.output, "tool": cutter.to_string(), "post": a.post.name(),
        "tolerance_mm": a.tolerance, "scallop_mm": a.scallop,
        "passes": plan.passes, "cl_points": plan.cl_points, "moves": tp.moves.len(),
        "cut_length_mm": cut_len, "rapid_length_mm": rapid_len,
        "plunge_retract_length_mm": plunge_len,
        "estimated_cycle_time_min": cycle_min,
        "max_chord_deviation_mm": plan.max_chord_deviation_mm,
        "planned_tolerance_mm": cfg.tolerance_mm, "rounding_mm": rounding,
        "sampled_moves": plan.sampled_moves,
        "predicted_max_scallop_mm": plan.predicted_max_scallop_mm,
        "steep_limited_points": plan.steep_limited_points,
        "floor_limited_passes": plan.floor_limited_passes,
        "unresolved_joins": plan.unresolved_joins,
        "drops": plan.drops,
        "safe_z_mm": plan.safe_z_mm,
        "plan_s": t_plan, "holder": holder_json,
        "verify": verification.as_ref().map(|v| serde_json::json!({
            "max_gouge_mm": v.report.max_gouge_mm, "max_excess_mm": v.report.max_excess_mm,
            "mean_mm": v.report.mean_mm, "p95_mm": v.report.p95_mm, "points": v.report.measured,
            "unmachined": v.report.unmachined, "within_tolerance": v.report.tolerance_counts.within,
            "worst_gouge": v.report.worst_gouges.first(), "timings": v.timings,
            "rapids": v.rapids,
        })),
    });
    if a.json {
        println!("{summary}");
    } else {
        eprintln!(
            "cam plan: {} passes, {} CL points, cut {:.0} mm, rapid {:.0} mm, ~{:.1} min; \
             penetration and excess ≤ {:.4} mm (τ {}{}), scallop ≤ {:.4} mm predicted (h {}{}); \
             holder: {} collisions, minimum stick-out {} -> {}",
            plan.passes,
            plan.cl_points,
            cut_len,
            rapid_len,
            cycle_min,
            plan.max_chord_deviation_mm + rounding,
            a.tolerance,
            if plan.sampled_moves > 0 {
                format!(", {} moves checked by sampling", plan.sampled_moves)
            } else {
                ", proven".to_string()
            },
            plan.predicted_max_scallop_mm,
            a.scallop,
            if plan.floor_limited_passes > 0 {
                format!(
                    ", above h after {} passes at the step floor: steep walls or rows tangent \
                     to a concave crease",
                    plan.floor_limited_passes
                )
            } else {
                String::new()
            },
            report.collisions.len(),
            fmt_stick(&stick),
            a.output.display()
        );
        if let Some(v) = &verification {
            eprintln!("cam {}", crate::verify::summary_line(v, a.tolerance));
            let warnings = [
                crate::verify::topology_warning(v),
                crate::verify::rapids_warning(v),
                crate::verify::exactness_warning(v),
            ];
            for w in warnings.into_iter().flatten() {
                eprintln!("cam plan: {w}");
            }
        }
    }
    match &verification {
        Some(v) => crate::verify::verdict(v, a.tolerance),
        None => Ok(()),
    }
}

/// Holder contacts shallower than this (mm) are rubbing, not collisions: where the cutter's
/// side is tangent to a face, a shank as wide as the cutter is tangent too, and pass ends
/// are located to 1e-5 mm, so "depths" of micrometres and below are noise.
const HOLDER_CONTACT_MM: f64 = 1e-3;

/// The holder check `cam plan` and `cam verify` run: contacts above [`HOLDER_CONTACT_MM`].
pub(crate) fn holder_check() -> CheckConfig {
    CheckConfig {
        min_depth_mm: HOLDER_CONTACT_MM,
        ..CheckConfig::default()
    }
}

/// Reads a posted program back (the moves the machine will run, with their lines).
fn reread(program: &str, a: &PlanArgs) -> Result<cam_core::Toolpath> {
    cam_gcode::parse_gcode(program, &cam_gcode::ReadConfig::default()).map_err(|e| {
        anyhow::anyhow!(
            "internal: the {} post wrote a program our reader rejects: {e}",
            a.post.name()
        )
    })
}

fn fmt_stick(s: &cam_holder::StickOut) -> String {
    match s.min_mm {
        Some(m) => format!("{m:.3} mm"),
        None => "none (the shank itself collides)".into(),
    }
}

/// The first 1000 collisions of a holder check, for `--json` (`cam plan` and `cam verify`).
pub(crate) fn findings_json(r: &cam_holder::CollisionReport) -> Vec<serde_json::Value> {
    r.collisions
        .iter()
        .take(1000)
        .map(|c| {
            serde_json::json!({
                "line": c.line, "pass": c.pass,
                "position_mm": [c.position.x, c.position.y, c.position.z],
                "part": c.part.to_string(), "depth_mm": c.depth_mm,
            })
        })
        .collect()
}

/// Prints the collision report (first 20 findings) on stderr.
pub(crate) fn print_collisions(r: &cam_holder::CollisionReport, asm: &ToolAssembly) {
    eprintln!(
        "holder/shank collisions with {} (stick-out {} mm):",
        asm.id, asm.stick_out_mm
    );
    for c in r.collisions.iter().take(20) {
        eprintln!(
            "  line {:>6}  pass {:>4}  at ({:.3}, {:.3}, {:.3})  {}  depth {:.3} mm",
            c.line.map_or("-".into(), |l| l.to_string()),
            c.pass.map_or("-".into(), |p| p.to_string()),
            c.position.x,
            c.position.y,
            c.position.z,
            c.part,
            c.depth_mm
        );
    }
    if r.collisions.len() > 20 {
        eprintln!("  ... and {} more", r.collisions.len() - 20);
    }
}
