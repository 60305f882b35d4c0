//! `cargo xtask bench verify-one PART PROGRAM TOOL [--runs N]`: `cam_verify::verify` on one
//! program, in-process, `N` times in a row: the best and the median call with their stage
//! timings. For comparing two builds on one program: the CLI's wall time adds reading the
//! files and the first touch of every page, which the bench's repeated calls do not pay.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use cam_core::Cutter;

/// The part, the program, the tool spec and the number of calls.
#[derive(Debug, Clone, PartialEq)]
pub struct VerifyOne {
    pub part: PathBuf,
    pub program: PathBuf,
    pub tool: String,
    pub runs: usize,
}

/// Parses `PART PROGRAM TOOL [--runs N]` (N ≥ 1, default 7).
pub fn parse(rest: &[&str]) -> Result<VerifyOne> {
    let mut pos = Vec::new();
    let mut runs = 7;
    let mut it = rest.iter();
    while let Some(r) = it.next() {
        if *r == "--runs" {
            let n = it.next().context("--runs needs a count")?;
            runs = n
                .parse()
                .with_context(|| format!("--runs: '{n}' is not a count"))?;
            if runs == 0 {
                bail!("--runs must be at least 1");
            }
        } else {
            pos.push(*r);
        }
    }
    let [part, program, tool] = pos[..] else {
        bail!(
            "bench verify-one needs PART PROGRAM TOOL (got {} arguments)",
            pos.len()
        );
    };
    Ok(VerifyOne {
        part: part.into(),
        program: program.into(),
        tool: tool.to_string(),
        runs,
    })
}

/// Runs it and prints one line: best and median seconds, each with its refine and measure
/// stages.
pub fn run(cfg: &VerifyOne) -> Result<()> {
    let mesh = crate::planbench::load(&cfg.part)?;
    let path = read_program(&cfg.program)?;
    let cutter: Cutter = cfg
        .tool
        .parse()
        .map_err(|e| anyhow::anyhow!("tool '{}': {e}", cfg.tool))?;
    let vc = cam_verify::VerifyConfig::new(0.01);
    let mut rows = Vec::with_capacity(cfg.runs);
    for _ in 0..cfg.runs {
        let t = Instant::now();
        let v = cam_verify::verify(&mesh, &path, &cutter, &vc)?;
        rows.push((
            t.elapsed().as_secs_f64(),
            v.timings.refine_s,
            v.timings.measure_s,
        ));
    }
    rows.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (best, med) = (rows[0], rows[rows.len() / 2]);
    println!(
        "{} on {} ({}), {} calls, tolerance 0.01 mm: best {:.4} s (refine {:.4}, measure {:.4}), \
         median {:.4} s (refine {:.4}, measure {:.4})",
        cfg.program.display(),
        cfg.part.display(),
        cfg.tool,
        cfg.runs,
        best.0,
        best.1,
        best.2,
        med.0,
        med.1,
        med.2
    );
    Ok(())
}

fn read_program(path: &Path) -> Result<cam_core::Toolpath> {
    // The reader's message names the file, line and cause already.
    cam_gcode::read_gcode(path, &cam_gcode::ReadConfig::default())
        .map_err(|e| anyhow::anyhow!("{e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_positionals_and_runs() {
        let c = parse(&["p.stl", "g.ngc", "ball:6", "--runs", "3"]).unwrap();
        assert_eq!(
            c,
            VerifyOne {
                part: "p.stl".into(),
                program: "g.ngc".into(),
                tool: "ball:6".into(),
                runs: 3
            }
        );
        assert_eq!(parse(&["p.stl", "g.ngc", "ball:6"]).unwrap().runs, 7);
        assert!(parse(&["p.stl", "g.ngc"]).is_err());
        assert!(parse(&["p.stl", "g.ngc", "ball:6", "--runs", "0"]).is_err());
        assert!(parse(&["p.stl", "g.ngc", "ball:6", "--runs"]).is_err());
    }
}
