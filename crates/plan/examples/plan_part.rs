//! Plans a part headless and prints the summary as JSON (no toolpath), with the time taken,
//! the number of exact drops the planner made, and the time the drop-cutter alone needs for
//! as many drops as the plan has CL points.
//!
//! `cargo run --release -p cam-plan --example plan_part -- fixtures/parts/dome.obj ball:6 0.01 0.01`

use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use cam_core::{Mesh, Units};
use cam_offset::DropCutter;
use cam_plan::{ClSurface, PlanConfig, SectionSampler, plan};

/// Counts the drops the planner asks for.
struct Counting<'a>(&'a DropCutter, AtomicUsize);

impl ClSurface for Counting<'_> {
    fn z_tip(&self, x: f64, y: f64) -> Option<f64> {
        self.1.fetch_add(1, Ordering::Relaxed);
        self.0.drop(x, y)
    }
}

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
    let (c, _) = cfg.validate()?;
    let dc = DropCutter::new(&mesh, cfg.cutter);
    let counting = Counting(&dc, AtomicUsize::new(0));
    let sampler = SectionSampler::new(&mesh, cfg.angle_deg, c, cfg.cutter.radius());
    let mut p = plan(&counting, &sampler, &cfg, None)?;
    let secs = t.elapsed().as_secs_f64();
    // The drop-cutter alone on as many points as the plan has CL points.
    let xy: Vec<(f64, f64)> = p
        .toolpath
        .moves
        .iter()
        .filter(|m| m.pass.is_some())
        .map(|m| (m.pose.tip.x, m.pose.tip.y))
        .collect();
    let t = Instant::now();
    let _ = dc.drop_points(&xy);
    let drop_secs = t.elapsed().as_secs_f64();
    let moves = p.toolpath.moves.len();
    p.toolpath.moves.clear();
    p.pass_v_mm.clear();
    println!("{}", serde_json::to_string_pretty(&p)?);
    println!(
        "{{\"part\": \"{path}\", \"cutter\": \"{}\", \"moves\": {moves}, \"drops\": {}, \"seconds\": {secs:.3}, \"drop_seconds_for_cl_points\": {drop_secs:.4}}}",
        cfg.cutter,
        counting.1.load(Ordering::Relaxed)
    );
    Ok(())
}
