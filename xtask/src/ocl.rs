//! Running OpenCAMLib (the peer drop-cutter) through Python.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail};
use cam_core::{Cutter, CutterKind};

/// Directory of the shared OpenCAMLib scripts.
pub fn tools_dir() -> PathBuf {
    crate::shared_dir().join("tools/ocl")
}

/// A Python interpreter with `opencamlib`: `$CAM_OCL_PYTHON`, else the last line printed by
/// the shared `setup.sh` (which creates the venv on first use).
pub fn python() -> Result<PathBuf> {
    if let Some(p) = std::env::var_os("CAM_OCL_PYTHON") {
        return Ok(PathBuf::from(p));
    }
    let setup = tools_dir().join("setup.sh");
    let out = Command::new("bash")
        .arg(&setup)
        .output()
        .with_context(|| format!("running {}", setup.display()))?;
    if !out.status.success() {
        bail!(
            "{} failed ({}):\n{}",
            setup.display(),
            out.status,
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let stdout = String::from_utf8_lossy(&out.stdout);
    let py = stdout
        .lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .context("setup.sh printed nothing")?;
    Ok(PathBuf::from(py.trim()))
}

/// OpenCAMLib cutter flags (`--cutter ball -D 6`, ...) for one of our cutters.
pub fn cutter_args(c: &Cutter) -> Vec<String> {
    let mut v = vec!["--cutter".to_string()];
    match c.kind() {
        CutterKind::Ball => v.push("ball".into()),
        CutterKind::Flat => v.push("flat".into()),
        CutterKind::Bull => v.push("bull".into()),
    }
    v.push("-D".into());
    v.push(format!("{}", c.diameter()));
    if c.kind() == CutterKind::Bull {
        v.push("-r".into());
        v.push(format!("{}", c.corner_radius()));
    }
    v
}

/// Runs `cmd`, returning stdout; fails with its stderr when it fails.
pub fn run_capture(cmd: &mut Command) -> Result<String> {
    let out = cmd.output().with_context(|| format!("running {cmd:?}"))?;
    if !out.status.success() {
        bail!(
            "{cmd:?} failed ({}):\n{}",
            out.status,
            String::from_utf8_lossy(&out.stderr)
        );
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// The command line of xtask's own full-precision driver `xtask/ocl/ocl_grid.py`.
pub fn grid_command(py: &Path, part: &Path, cutter: &Cutter, step_mm: f64, out: &Path) -> Command {
    let mut cmd = Command::new(py);
    cmd.arg(crate::repo_root().join("xtask/ocl/ocl_grid.py"))
        .arg(part)
        .arg("--shared-ocl")
        .arg(tools_dir())
        .args(cutter_args(cutter))
        .arg("--step")
        .arg(format!("{step_mm}"))
        .arg("-o")
        .arg(out);
    cmd
}

/// What the shared `ocl_dropcutter.py` reported for one grid.
#[derive(Debug, Clone, Copy)]
pub struct BatchTiming {
    /// Points dropped.
    pub points: usize,
    /// Points per second as it printed them: points over the wall time of its drop phase
    /// (BatchDropCutter setup, appending the points, `run()`, reading the CL points back).
    pub points_per_s: f64,
}

/// Runs the shared `ocl_dropcutter.py` on `part` over a `step_mm` grid covering its XY
/// bounding box with `threads` OpenMP threads, writing its CSV to `out`.
pub fn shared_batch(
    py: &Path,
    part: &Path,
    cutter: &Cutter,
    step_mm: f64,
    threads: usize,
    out: &Path,
) -> Result<BatchTiming> {
    let mut cmd = Command::new(py);
    cmd.arg(tools_dir().join("ocl_dropcutter.py"))
        .arg(part)
        .args(cutter_args(cutter))
        .arg("--step")
        .arg(format!("{step_mm}"))
        .arg("--threads")
        .arg(threads.to_string())
        .arg("-o")
        .arg(out);
    let stdout = run_capture(&mut cmd)?;
    parse_batch_line(&stdout).with_context(|| format!("parsing the output of {cmd:?}:\n{stdout}"))
}

/// Parses `drop-cutter: N points in T s wall = P points/s; ...`.
pub fn parse_batch_line(stdout: &str) -> Result<BatchTiming> {
    let line = stdout
        .lines()
        .find(|l| l.starts_with("drop-cutter:"))
        .context("no 'drop-cutter:' line")?;
    let w: Vec<&str> = line.split_whitespace().collect();
    // drop-cutter: N points in T s wall = P points/s;
    let num = |i: usize| -> Result<f64> {
        let s = w.get(i).context("line too short")?;
        s.trim_end_matches(';')
            .parse::<f64>()
            .with_context(|| format!("'{s}' is not a number"))
    };
    if w.get(2) != Some(&"points") || w.get(9) != Some(&"points/s;") {
        bail!("unexpected layout: {line}");
    }
    num(4)?; // seconds: checked to be a number
    Ok(BatchTiming {
        points: num(1)? as usize,
        points_per_s: num(8)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_shared_scripts_summary() {
        let s = "mesh x.stl: 7570 triangles\ncutter ball D=6 L=50; grid\n\
                 drop-cutter: 23716 points in 2.345 s wall = 10113 points/s; 0 points without contact (z=zmin=0)\nwrote a.csv\n";
        let t = parse_batch_line(s).unwrap();
        assert_eq!(t.points, 23716);
        assert_eq!(t.points_per_s, 10113.0);
        assert!(parse_batch_line("drop-cutter: lots of points\n").is_err());
        assert!(parse_batch_line("nothing\n").is_err());
    }

    #[test]
    fn cutter_flags() {
        let c: Cutter = "bull:6:1.5".parse().unwrap();
        assert_eq!(
            cutter_args(&c),
            ["--cutter", "bull", "-D", "6", "-r", "1.5"]
        );
        let c: Cutter = "flat:6".parse().unwrap();
        assert_eq!(cutter_args(&c), ["--cutter", "flat", "-D", "6"]);
    }
}
