//! `cam verify` and the verification `cam plan` runs on what it planned.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use cam_core::{Cutter, Mesh, Toolpath, Units};
use cam_holder::ToolLibrary;
use cam_verify::{Verification, VerifyConfig};

use crate::exit::Findings;

/// Verification settings shared by `cam verify` and `cam plan`.
#[derive(clap::Args, Clone)]
pub struct VerifyOpts {
    /// Pseudo-inserts Q per cutter (even, ≥ 4).
    #[arg(long, default_value_t = 40)]
    pub inserts: usize,
    /// Longest step (mm) between swept poses; longer moves are subdivided (tip and axis
    /// interpolated linearly).
    #[arg(long, default_value_t = 0.5)]
    pub max_step: f64,
    /// Resolution e (mm) of the normal-vector method: the design surface is refined to edges
    /// of sqrt(6·r·e).
    #[arg(long, default_value_t = 0.005)]
    pub resolution: f64,
    /// Do not sweep the path in reverse (the other half of the tool). Programs of
    /// translations are read exactly either way; on rotating (5-axis) moves, and with
    /// `--surface linear`, the half the forward sweep does not imprint (back gouges, and
    /// under rotation also part of the cut) then goes unmeasured.
    #[arg(long)]
    pub no_back_gouge: bool,
    /// Swept surface measured against: `exact` refines every crossing of the imprint
    /// surface onto the exact swept volume; `linear` is the paper's piecewise-linear surface.
    #[arg(long, value_enum, default_value_t = Surface::Exact)]
    pub surface: Surface,
    /// Write the swept surface (.obj, .stl or .ply by extension).
    #[arg(long)]
    pub swept: Option<PathBuf>,
    /// Write the design surface coloured by deviation (.ply: blue excess, green within
    /// tolerance, red gouge).
    #[arg(long)]
    pub deviation: Option<PathBuf>,
    /// Write a top-view heat map of the deviation with a colour scale (.png).
    #[arg(long)]
    pub heatmap: Option<PathBuf>,
}

/// The swept surface a verification measures against.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Surface {
    /// Crossings refined onto the exact swept volume.
    Exact,
    /// The paper's triangles between imprint points.
    Linear,
}

/// Arguments of `cam verify`.
#[derive(clap::Args)]
pub struct VerifyArgs {
    /// The toolpath: G-code (.ngc, .nc, .gcode, .tap, ...) or APT CL data (.apt, .cl, .cls).
    pub toolpath: PathBuf,
    /// The design part (.obj or .stl).
    #[arg(long)]
    pub part: PathBuf,
    /// Cutter spec (ball:D, flat:D, bull:D:r in mm), or a tool id with --tool-library.
    #[arg(long)]
    pub tool: String,
    /// Tool library (JSON); --tool then names a tool id, and the tool's shank and holder
    /// are checked against the part along every move (3-axis paths): exit 1 on a collision.
    #[arg(long)]
    pub tool_library: Option<PathBuf>,
    /// Gouge tolerance (mm): exit 1 when a gouge is deeper.
    #[arg(long, default_value_t = 0.01)]
    pub tolerance: f64,
    /// Units of the part file.
    #[arg(long, default_value = "mm")]
    pub units: Units,
    /// Verification settings.
    #[command(flatten)]
    pub opts: VerifyOpts,
    /// Print the report as JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Reads a toolpath by extension: APT CL data or G-code.
fn read_toolpath(path: &Path) -> Result<Toolpath> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    Ok(match ext.as_str() {
        "apt" | "cl" | "cls" | "cldata" => cam_gcode::read_apt(path)?,
        _ => cam_gcode::read_gcode(path, &cam_gcode::ReadConfig::default())?,
    })
}

/// Runs `cam verify`.
pub fn run(a: VerifyArgs) -> Result<()> {
    let mesh = Mesh::load(&a.part, a.units)?;
    // With a library the whole assembly is known: its shank and holder are checked too.
    let assembly = match &a.tool_library {
        Some(lib) => {
            let l = ToolLibrary::load(lib)?;
            Some(
                l.get(&a.tool)
                    .with_context(|| format!("{}: no tool '{}'", lib.display(), a.tool))?
                    .clone(),
            )
        }
        None => None,
    };
    let cutter: Cutter = match &assembly {
        Some(t) => t.cutter,
        None => a.tool.parse()?,
    };
    let path = read_toolpath(&a.toolpath)?;
    let v = run_verification(&mesh, &path, &cutter, a.tolerance, &a.opts, a.json)?;
    // The holder check is exact for 3-axis moves (cam_holder); a 5-axis path is not checked.
    let holder = assembly.as_ref().map(|asm| {
        let rep = cam_verify::material::is_three_axis(&path)
            .then(|| cam_holder::check_toolpath(&mesh, asm, &path, &crate::plan::holder_check()));
        (asm, rep)
    });
    let mut report = serde_json::to_value(&v.report)?;
    report["toolpath"] = serde_json::json!(a.toolpath);
    report["part"] = serde_json::json!(a.part);
    report["tool"] = serde_json::json!(cutter.to_string());
    report["timings"] = serde_json::to_value(v.timings)?;
    report["rapids"] = serde_json::to_value(&v.rapids)?;
    report["holder"] = match &holder {
        None => serde_json::Value::Null,
        Some((asm, rep)) => serde_json::json!({
            "tool": asm.id, "stick_out_mm": asm.stick_out_mm, "checked": rep.is_some(),
            "collisions": rep.as_ref().map(|r| r.collisions.len()),
            "max_depth_mm": rep.as_ref().map(|r| r.max_depth_mm),
            "findings": rep.as_ref().map(crate::plan::findings_json),
        }),
    };
    if a.json {
        println!("{report}");
    } else {
        eprintln!("cam {}", summary_line(&v, a.tolerance));
        match &holder {
            None => eprintln!(
                "cam verify: shank and holder not checked (give the tool with --tool-library)"
            ),
            Some((asm, None)) => eprintln!(
                "cam verify: warning: shank and holder of {} not checked: the path is not 3-axis",
                asm.id
            ),
            Some((asm, Some(r))) if r.is_clear() => eprintln!(
                "cam verify: shank and holder of {} (stick-out {} mm) clear of the part",
                asm.id, asm.stick_out_mm
            ),
            Some((asm, Some(r))) => crate::plan::print_collisions(r, asm),
        }
        for w in [
            topology_warning(&v),
            rapids_warning(&v),
            exactness_warning(&v),
        ]
        .into_iter()
        .flatten()
        {
            eprintln!("cam verify: {w}");
        }
    }
    verdict(&v, a.tolerance)?;
    if let Some((asm, Some(r))) = &holder
        && let Some(deepest) = r
            .collisions
            .iter()
            .max_by(|p, q| p.depth_mm.total_cmp(&q.depth_mm))
    {
        return Err(Findings(format!(
            "{} shank/holder collisions with {} at stick-out {} mm; the deepest {:.3} mm ({}){}",
            r.collisions.len(),
            asm.id,
            asm.stick_out_mm,
            deepest.depth_mm,
            deepest.part,
            deepest
                .line
                .map_or(String::new(), |l| format!(", toolpath line {l}"))
        ))
        .into());
    }
    Ok(())
}

/// Runs the verification and writes the optional outputs.
pub fn run_verification(
    mesh: &Mesh,
    path: &Toolpath,
    cutter: &Cutter,
    tolerance: f64,
    o: &VerifyOpts,
    quiet: bool,
) -> Result<Verification> {
    let mut cfg = VerifyConfig::new(tolerance);
    cfg.sweep.inserts = o.inserts;
    cfg.sweep.max_step_mm = o.max_step;
    cfg.resolution_mm = o.resolution;
    cfg.back_gouge = !o.no_back_gouge;
    cfg.keep_swept = o.swept.is_some();
    cfg.surface = match o.surface {
        Surface::Exact => cam_verify::measure::SurfaceModel::Exact,
        Surface::Linear => cam_verify::measure::SurfaceModel::Linear,
    };
    if !(tolerance.is_finite() && tolerance > 0.0) {
        bail!("--tolerance must be a positive number of mm, got {tolerance}");
    }
    let pb = crate::progress::bar(1, "sweeping", quiet);
    pb.enable_steady_tick(std::time::Duration::from_millis(200));
    let report = |st: cam_verify::Stage, done: usize, total: usize| {
        pb.set_message(match st {
            cam_verify::Stage::Sweep => "sweeping",
            cam_verify::Stage::Refine => "refining",
            cam_verify::Stage::Measure => "measuring",
        });
        pb.set_length(total as u64);
        pb.set_position(done as u64);
    };
    let v = cam_verify::verify_with_progress(mesh, path, cutter, &cfg, Some(&report))?;
    pb.finish_and_clear();
    if let Some(p) = &o.swept {
        let ext = p
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        cam_core::io::write_atomic(p, |w| match ext.as_str() {
            "obj" => cam_verify::sweep::write_obj(&v.swept_surface(), w),
            "ply" => cam_verify::sweep::write_ply(&v.swept_surface(), w),
            _ => cam_verify::sweep::write_stl(&v.swept_surface(), w),
        })
        .with_context(|| format!("{}: cannot write", p.display()))?;
    }
    if let Some(p) = &o.deviation {
        cam_verify::ply::write_deviation_ply(
            p,
            &v.refined,
            &v.deviations,
            tolerance,
            cam_verify::ply::PlyFormat::BinaryLittleEndian,
        )?;
    }
    if let Some(p) = &o.heatmap {
        cam_verify::heatmap::write_heatmap(
            p,
            &v.refined,
            &v.deviations,
            &cam_verify::heatmap::HeatmapConfig::new(tolerance),
        )?;
    }
    Ok(v)
}

/// One line for the terminal.
/// A warning when the design mesh's faces disagree on orientation or share edges three
/// ways: there the normal-vector method cannot tell the material side, and vectors that
/// start in the air read as gouges of up to `L_in`.
pub fn topology_warning(v: &Verification) -> Option<String> {
    let t = v.topology;
    (t.misoriented_edges > 0 || t.non_manifold_edges > 0).then(|| {
        format!(
            "warning: the part has {} edges where neighbouring faces disagree on orientation \
             and {} edges shared by more than two faces; next to them the material side is \
             unknown, so deviations there are the depth of the surface inside the swept \
             volume, and a gouge whose vector faces the wrong way can be missed (vectors \
             reach {} mm into the part)",
            t.misoriented_edges,
            t.non_manifold_edges,
            v.report
                .settings
                .as_ref()
                .map_or(f64::NAN, |s| s.deviation.inside_mm),
        )
    })
}

/// One line: max gouge and excess, points within tolerance, unmachined, time.
pub fn summary_line(v: &Verification, tol: f64) -> String {
    let r = &v.report;
    let worst = r.worst_gouges.first().map_or(String::new(), |w| {
        format!(
            " (worst at ({:.3}, {:.3}, {:.3}){})",
            w.position[0],
            w.position[1],
            w.position[2],
            w.line.map_or(String::new(), |l| format!(", line {l}"))
        )
    });
    let rp = &v.rapids;
    let rapids = if rp.collisions.is_empty() {
        let s = if rp.checked == 1 { "" } else { "s" };
        format!("{} rapid{s} clear of the part", rp.checked)
    } else {
        format!(
            "{} of {} rapids run into the part (up to {:.4} mm)",
            rp.collisions.len(),
            rp.checked,
            rp.max_depth_mm
        )
    };
    format!(
        "verify: max gouge {:.4} mm{worst}, max excess {:.4} mm, {} of {} measured points within \
         ±{tol} mm; {} points beyond the cutter's reach (over {} mm of material, or faces the \
         path never approaches such as a part's sides and bottom); {rapids}; {:.1} s",
        r.max_gouge_mm,
        r.max_excess_mm,
        r.tolerance_counts.within,
        r.measured,
        r.unmachined,
        r.settings
            .as_ref()
            .map_or(f64::NAN, |s| s.deviation.outside_mm),
        v.timings.sweep_s + v.timings.refine_s + v.timings.measure_s
    )
}

/// A warning when some readings are not proven exact: a vector whose list of crossings of
/// the imprint surface overflowed (the deepest may be among those dropped), or whose
/// crossings could not be refined onto the exact volume (the linear value stands).
pub fn exactness_warning(v: &Verification) -> Option<String> {
    let (over, lin) = (v.stats.overflow, v.stats.kept_linear);
    (over + lin > 0).then(|| {
        format!(
            "warning: {} points are not proven exact and may read late ({over} with more \
             crossings than kept, {lin} on the linear surface where no crossing refined)",
            over + lin
        )
    })
}

/// A warning when some rapids could not be checked (the axis turns between their ends:
/// the tool's motion then depends on the machine's kinematics).
pub fn rapids_warning(v: &Verification) -> Option<String> {
    (v.rapids.unchecked > 0).then(|| {
        format!(
            "warning: {} rapids that turn the tool axis were not checked against the part",
            v.rapids.unchecked
        )
    })
}

/// Exit 1 when a gouge exceeds the tolerance or a rapid runs into the part deeper than it.
pub fn verdict(v: &Verification, tol: f64) -> Result<()> {
    if let Some(c) = v
        .rapids
        .collisions
        .iter()
        .max_by(|p, q| p.depth_mm.total_cmp(&q.depth_mm))
    {
        let n = v.rapids.collisions.len();
        return Err(Findings(format!(
            "{} into the part; the deepest, {:.4} mm (along the tool axis) below where the tool \
             would rest on it, at ({:.3}, {:.3}, {:.3}){}",
            if n == 1 {
                "a rapid move runs".to_string()
            } else {
                format!("{n} rapid moves run")
            },
            c.depth_mm,
            c.tip[0],
            c.tip[1],
            c.tip[2],
            c.line
                .map_or(String::new(), |l| format!(", toolpath line {l}"))
        ))
        .into());
    }
    if v.report.gouge_exceeds(tol) {
        let w = v.report.worst_gouges.first();
        return Err(Findings(format!(
            "gouge of {:.4} mm exceeds the tolerance {tol} mm{}",
            v.report.max_gouge_mm,
            w.map_or(String::new(), |w| format!(
                " at ({:.3}, {:.3}, {:.3}){}",
                w.position[0],
                w.position[1],
                w.position[2],
                w.line
                    .map_or(String::new(), |l| format!(", toolpath line {l}"))
            ))
        ))
        .into());
    }
    Ok(())
}
