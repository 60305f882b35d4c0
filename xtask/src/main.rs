//! Developer chores for the `cam` workspace: reference data from OpenCAMLib, benchmarks
//! against it, and small analytic test parts.
//!
//! ```text
//! cargo xtask ocl-ref                      regenerate fixtures/ocl/ (OpenCAMLib CL grids)
//! cargo xtask bench dropcutter [--quick]   ours vs OpenCAMLib BatchDropCutter, points/s
//! cargo xtask bench mem                    load time and peak RSS for a 1M-triangle part
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
mod refs;

use std::path::PathBuf;

use anyhow::{Result, bail};

const USAGE: &str = "usage: cargo xtask <command>

commands:
  ocl-ref                     regenerate fixtures/ocl/ with OpenCAMLib (needs the shared tools)
  bench dropcutter [--quick]  drop-cutter points/s, ours vs OpenCAMLib (--quick: 1 run, not best of 3)
  bench mem                   load time and peak RSS for a generated 1M-triangle STL
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
        [mem::CHILD, path] => mem::child(path),
        ["gen-fixtures"] => parts::gen_fixtures(&repo_root().join("fixtures/parts")),
        ["help" | "--help" | "-h"] | [] => {
            print!("{USAGE}");
            Ok(())
        }
        _ => bail!("unknown command '{}'\n{USAGE}", args.join(" ")),
    }
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
