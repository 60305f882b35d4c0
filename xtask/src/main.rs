//! Developer chores for the `cam` workspace: reference data from OpenCAMLib, benchmarks
//! against it, and small analytic test parts.
//!
//! ```text
//! cargo xtask ocl-ref                      regenerate fixtures/ocl/ (OpenCAMLib CL grids)
//! cargo xtask bench dropcutter [--quick]   ours vs OpenCAMLib BatchDropCutter, points/s
//! cargo xtask bench mem                    load time and peak RSS for a 1M-triangle part
//! cargo xtask bench plan [--quick] [--cutter SPEC]...    plan vs drop-cutter time, holder share
//! cargo xtask bench verify [--quick] [--cutter SPEC]...  imprint points/s, verify vs plan time
//! cargo xtask bench verify-one PART PROGRAM TOOL [--runs N]  one program's verify, in-process
//! cargo xtask plan-report [--quick] [--cutter SPEC]... [--part PATH]...  what planned programs leave, measured
//! cargo xtask gen-fixtures                 write fixtures/parts/*.obj
//! ```
//!
//! Environment: `CAM_SHARED` (default `<repo>/../shared`) locates the shared peer tools and
//! test meshes; `CAM_OCL_PYTHON` names a Python with OpenCAMLib (default: the one printed by
//! `$CAM_SHARED/tools/ocl/setup.sh`).

mod bench;
mod mem;
mod ocl;
mod parts;
mod planbench;
mod planreport;
mod refs;
mod verifybench;
mod verifyone;

use std::path::PathBuf;

use anyhow::{Result, bail};

const USAGE: &str = "usage: cargo xtask <command>

commands:
  ocl-ref                     regenerate fixtures/ocl/ with OpenCAMLib (needs the shared tools)
  bench dropcutter [--quick]  drop-cutter points/s, ours vs OpenCAMLib (--quick: 1 run, not best of 3)
  bench mem                   load time and peak RSS for a generated 1M-triangle STL
  bench plan [--quick] [--cutter SPEC]...    plan_part time vs drop-cutter time for its CL
                                             points, holder check (--quick: 1 run)
  bench verify [--quick] [--cutter SPEC]...  imprint points/s; verify time vs plan time
                                             (--quick: 1 run, ball:6 unless --cutter)
  bench verify-one PART PROGRAM TOOL [--runs N]
                                             verify one G-code program N times in-process
                                             (default 7): best and median with the refine
                                             and measure stages
  plan-report [--quick] [--cutter SPEC]... [--part PATH]...
                                             plan, post, read back and z-map dome.obj and
                                             sphere_on_plate (or the given parts): gouge
                                             (exact) and scallop at reachable points
                                             (--quick: 0.1 mm grid, else 0.05)
  gen-fixtures                write the analytic test parts into fixtures/parts/
";

fn main() {
    if let Err(e) = run(std::env::args().skip(1).collect()) {
        eprintln!("error: {e:#}");
        std::process::exit(2);
    }
}

fn run(args: Vec<String>) -> Result<()> {
    let a: Vec<&str> = args.iter().map(String::as_str).collect();
    match a.as_slice() {
        ["ocl-ref"] => refs::ocl_ref(),
        ["bench", "dropcutter", rest @ ..] => {
            let mut quick = false;
            for r in rest {
                match *r {
                    "--quick" => quick = true,
                    other => bail!("unknown option '{other}' for bench dropcutter\n{USAGE}"),
                }
            }
            bench::dropcutter(&bench::BenchConfig {
                runs: if quick { 1 } else { 3 },
                step_mm: 0.5,
            })
        }
        ["bench", "mem"] => mem::mem(),
        ["bench", "plan", rest @ ..] => {
            let (quick, cutters) = bench_flags("plan", rest)?;
            let mut cfg = planbench::PlanBenchConfig::new(if quick { 1 } else { 3 });
            if !cutters.is_empty() {
                cfg.cutters = cutters;
            }
            planbench::plan(&cfg)
        }
        ["bench", "verify", rest @ ..] => {
            let (quick, cutters) = bench_flags("verify", rest)?;
            let mut plan = planbench::PlanBenchConfig::new(if quick { 1 } else { 3 });
            if quick {
                plan.cutters = vec!["ball:6".into()];
            }
            if !cutters.is_empty() {
                plan.cutters = cutters;
            }
            verifybench::verify_bench(&verifybench::VerifyBenchConfig {
                plan,
                imprint_poses: 100_000,
                imprint_min_s: if quick { 0.2 } else { 1.0 },
            })
        }
        ["bench", "verify-one", rest @ ..] => verifyone::run(&verifyone::parse(rest)?),
        [mem::CHILD, path] => mem::child(path),
        ["plan-report", rest @ ..] => {
            // `--part PATH` (repeatable) replaces the default parts.
            let mut parts = Vec::new();
            let mut others = Vec::new();
            let mut it = rest.iter();
            while let Some(r) = it.next() {
                if *r == "--part" {
                    match it.next() {
                        Some(p) => parts.push(std::path::PathBuf::from(p)),
                        None => bail!("--part needs a path\n{USAGE}"),
                    }
                } else {
                    others.push(*r);
                }
            }
            let (quick, mut cutters) = bench_flags("plan-report", &others)?;
            if cutters.is_empty() {
                cutters = planbench::CUTTERS.iter().map(|s| s.to_string()).collect();
            }
            if parts.is_empty() {
                parts = planbench::default_parts()[..2].to_vec();
            }
            planreport::plan_report(&parts, &cutters, if quick { 0.1 } else { 0.05 })
        }
        ["gen-fixtures"] => parts::gen_fixtures(&repo_root().join("fixtures/parts")),
        ["help" | "--help" | "-h"] | [] => {
            print!("{USAGE}");
            Ok(())
        }
        _ => bail!("unknown command '{}'\n{USAGE}", args.join(" ")),
    }
}

/// The options of `bench plan` / `bench verify`: `--quick` and any `--cutter SPEC`.
fn bench_flags(bench: &str, rest: &[&str]) -> Result<(bool, Vec<String>)> {
    let mut quick = false;
    let mut cutters = Vec::new();
    let mut it = rest.iter();
    while let Some(r) = it.next() {
        match *r {
            "--quick" => quick = true,
            "--cutter" => match it.next() {
                Some(spec) => cutters.push(spec.to_string()),
                None => bail!("--cutter needs a spec (e.g. ball:6)\n{USAGE}"),
            },
            other => bail!("unknown option '{other}' for bench {bench}\n{USAGE}"),
        }
    }
    Ok((quick, cutters))
}

/// The machine's load averages (1, 5, 15 min) as `uptime` prints them, for the tables.
pub(crate) fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg").map_or_else(
        |_| "load average: n/a".to_string(),
        |s| {
            let v: Vec<&str> = s.split_whitespace().take(3).collect();
            format!("load average: {}", v.join(", "))
        },
    )
}

/// The workspace root (the parent of this crate's directory).
pub(crate) fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask has a parent")
        .to_path_buf()
}

/// The shared directory with peer tools and test meshes.
pub(crate) fn shared_dir() -> PathBuf {
    std::env::var_os("CAM_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| repo_root().join("../shared"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bench_flags_parse_quick_and_cutters() {
        assert_eq!(bench_flags("plan", &[]).unwrap(), (false, vec![]));
        assert_eq!(
            bench_flags(
                "verify",
                &["--cutter", "flat:6", "--quick", "--cutter", "ball:3"]
            )
            .unwrap(),
            (true, vec!["flat:6".to_string(), "ball:3".to_string()])
        );
        assert!(bench_flags("plan", &["--cutter"]).is_err());
        assert!(bench_flags("plan", &["--fast"]).is_err());
    }
}
