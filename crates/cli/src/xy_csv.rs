//! Reading XY point lists (`--points`): CSV with `x,y` per line, optional header, `#`
//! comments; extra columns are ignored.

use std::path::Path;

use anyhow::{Context, Result, bail};

/// Reads `(x, y)` pairs in mm (after scaling by `scale`); errors name file and line.
pub fn read_xy(path: &Path, scale: f64) -> Result<Vec<(f64, f64)>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read points file", path.display()))?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let l = line.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let mut f = l.split(',').map(str::trim);
        let (Some(xs), Some(ys)) = (f.next(), f.next()) else {
            bail!("{}:{}: expected 'x,y', found '{l}'", path.display(), i + 1);
        };
        match (xs.parse::<f64>(), ys.parse::<f64>()) {
            (Ok(x), Ok(y)) if x.is_finite() && y.is_finite() => out.push((x * scale, y * scale)),
            (Ok(x), Ok(y)) => bail!(
                "{}:{}: coordinate is not finite ({x}, {y})",
                path.display(),
                i + 1
            ),
            _ if out.is_empty() && xs.eq_ignore_ascii_case("x") => {} // header
            _ => bail!(
                "{}:{}: '{l}' is not a pair of numbers",
                path.display(),
                i + 1
            ),
        }
    }
    if out.is_empty() {
        bail!("{}: no points", path.display());
    }
    Ok(out)
}
