//! `--deviation OUT.ply`: the refined design surface with per-vertex colours and a
//! `deviation` property, as Fusion colours its deviation analysis: blue = excess beyond the
//! tolerance, green = within, red = gouge beyond the tolerance.

use std::io::{self, Write};
use std::path::Path;

use crate::deviation::Deviation;
use crate::refine::RefinedMesh;
use crate::report::OutputError;

/// PLY encoding.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlyFormat {
    /// `format ascii 1.0`.
    Ascii,
    /// `format binary_little_endian 1.0` (default; compact).
    BinaryLittleEndian,
}

fn lerp(a: [f64; 3], b: [f64; 3], t: f64) -> [u8; 3] {
    let t = t.clamp(0.0, 1.0);
    [0, 1, 2].map(|k| (a[k] + (b[k] - a[k]) * t).round().clamp(0.0, 255.0) as u8)
}

/// The colour (sRGB, 8 bit) of a signed deviation `signed_mm` at tolerance `tolerance_mm`.
///
/// Guarantees: a gouge beyond the tolerance is red-dominant (orange-red at −tol darkening to
/// deep red at −4·tol); a deviation within ±tol is green-dominant (yellow-green on the
/// gouge side, teal-green on the excess side); an excess beyond tol is blue-dominant (light
/// blue to deep blue at 4·tol); unmachined (`None`) is deep blue.
pub fn deviation_colour(signed_mm: Option<f64>, tolerance_mm: f64) -> [u8; 3] {
    let Some(v) = signed_mm else {
        return [0, 0, 110];
    };
    let tol = tolerance_mm.abs().max(f64::MIN_POSITIVE);
    let x = v / tol;
    if x.is_nan() {
        return [128, 128, 128];
    }
    if x < -1.0 {
        lerp([255.0, 110.0, 70.0], [150.0, 0.0, 0.0], (-x - 1.0) / 3.0)
    } else if x > 1.0 {
        lerp([90.0, 150.0, 255.0], [0.0, 0.0, 150.0], (x - 1.0) / 3.0)
    } else if x < 0.0 {
        lerp([0.0, 200.0, 0.0], [160.0, 220.0, 0.0], -x)
    } else {
        lerp([0.0, 200.0, 0.0], [0.0, 200.0, 160.0], x)
    }
}

/// Writes the PLY to any writer: vertices with `x y z nx ny nz` (float), `red green blue`
/// (uchar) and `deviation` (float, mm; NaN where unmachined), faces as `vertex_indices`.
///
/// # Errors
/// Any I/O error of `w`; `InvalidInput` if `devs.len() != refined.len()`.
pub fn write_ply_to(
    w: &mut dyn Write,
    refined: &RefinedMesh,
    devs: &[Deviation],
    tolerance_mm: f64,
    format: PlyFormat,
) -> io::Result<()> {
    if devs.len() != refined.len() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("{} deviations for {} vertices", devs.len(), refined.len()),
        ));
    }
    let fmt = match format {
        PlyFormat::Ascii => "ascii",
        PlyFormat::BinaryLittleEndian => "binary_little_endian",
    };
    write!(
        w,
        "ply\nformat {fmt} 1.0\ncomment cam verify: signed deviation (mm), tolerance {tolerance_mm} mm; \
         red = gouge, green = within, blue = excess\n\
         element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\n\
         property float deviation\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        refined.len(),
        refined.triangles.len()
    )?;
    for ((p, n), d) in refined.positions.iter().zip(&refined.normals).zip(devs) {
        let c = deviation_colour(d.signed_mm, tolerance_mm);
        let dev = d.signed_mm.map_or(f32::NAN, |v| v as f32);
        let f = [p.x, p.y, p.z, n.x, n.y, n.z].map(|v| v as f32);
        match format {
            PlyFormat::Ascii => writeln!(
                w,
                "{} {} {} {} {} {} {} {} {} {}",
                f[0], f[1], f[2], f[3], f[4], f[5], c[0], c[1], c[2], dev
            )?,
            PlyFormat::BinaryLittleEndian => {
                for v in f {
                    w.write_all(&v.to_le_bytes())?;
                }
                w.write_all(&c)?;
                w.write_all(&dev.to_le_bytes())?;
            }
        }
    }
    for t in &refined.triangles {
        match format {
            PlyFormat::Ascii => writeln!(w, "3 {} {} {}", t[0], t[1], t[2])?,
            PlyFormat::BinaryLittleEndian => {
                w.write_all(&[3u8])?;
                for &i in t {
                    w.write_all(&(i as i32).to_le_bytes())?;
                }
            }
        }
    }
    Ok(())
}

/// Writes the deviation PLY to `path` atomically.
///
/// # Errors
/// [`OutputError::Mismatch`] when there is not one deviation per vertex,
/// [`OutputError::Io`] when the file cannot be written.
pub fn write_deviation_ply(
    path: &Path,
    refined: &RefinedMesh,
    devs: &[Deviation],
    tolerance_mm: f64,
    format: PlyFormat,
) -> Result<(), OutputError> {
    if devs.len() != refined.len() {
        return Err(OutputError::Mismatch {
            path: path.to_path_buf(),
            message: format!("{} deviations for {} vertices", devs.len(), refined.len()),
        });
    }
    cam_core::io::write_atomic(path, |w| {
        write_ply_to(w, refined, devs, tolerance_mm, format)
    })
    .map_err(|source| OutputError::Io {
        path: path.to_path_buf(),
        source,
    })
}
