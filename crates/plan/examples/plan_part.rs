//! Plans a part headless and prints the summary as JSON (no toolpath), with the time taken,
//! the number of exact drops the planner made, and the time the drop-cutter alone needs for
//! as many drops as the plan has CL points.
//!
//! `cargo run --release -p cam-plan --example plan_part -- fixtures/parts/dome.obj ball:6 0.01 0.01`

use std::time::Instant;

use cam_core::{Mesh, MoveKind, Units};
use cam_offset::DropCutter;
use cam_plan::{PlanConfig, plan_part};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .get(1)
        .map_or("fixtures/parts/dome.obj", String::as_str);
    let cutter = args.get(2).map_or("ball:6", String::as_str).parse()?;
    let tolerance_mm = args.get(3).map_or(Ok(0.01), |s| s.parse())?;
    let scallop_mm = args.get(4).map_or(Ok(0.01), |s| s.parse())?;
    let mesh = Mesh::load(path, Units::Mm)?;
    let cfg = PlanConfig {
        cutter,
        tolerance_mm,
        scallop_mm,
        ..PlanConfig::default()
    };
    let t = Instant::now();
    let mut p = plan_part(&mesh, &cfg, None)?;
    let secs = t.elapsed().as_secs_f64();
    // The drop-cutter alone (index included) on as many points as the plan has CL points.
    let xy: Vec<(f64, f64)> = p
        .toolpath
        .moves
        .iter()
        .filter(|m| matches!(m.kind, MoveKind::Cut | MoveKind::Plunge))
        .map(|m| (m.pose.tip.x, m.pose.tip.y))
        .collect();
    let t = Instant::now();
    let dc = DropCutter::new(&mesh, cfg.cutter);
    let _ = dc.drop_points(&xy);
    let drop_secs = t.elapsed().as_secs_f64();
    let moves = p.toolpath.moves.len();
    p.toolpath.moves.clear();
    p.pass_v_mm.clear();
    println!("{}", serde_json::to_string_pretty(&p)?);
    println!(
        "{{\"part\": \"{path}\", \"cutter\": \"{}\", \"moves\": {moves}, \"cl_points\": {}, \"drops\": {}, \"drops_per_cl_point\": {:.2}, \"passes\": {}, \"pass_builds\": {}, \"seconds\": {secs:.3}, \"drop_seconds_for_cl_points\": {drop_secs:.4}, \"ratio\": {:.2}}}",
        cfg.cutter,
        xy.len(),
        p.drops,
        p.drops as f64 / xy.len() as f64,
        p.passes,
        p.pass_builds,
        secs / drop_secs
    );
    Ok(())
}
