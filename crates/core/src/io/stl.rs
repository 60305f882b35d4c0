//! STL reading, binary and ASCII, written here rather than through `stl_io` so that errors
//! name the line (ASCII) or triangle record (binary) and a 1M-triangle binary file loads in a
//! single pass without building an indexed mesh.

use std::path::Path;

use glam::DVec3;

use crate::error::MeshError;
use crate::mesh::Triangle;

/// Reads an STL file, binary or ASCII (detected from size and content).
///
/// # Errors
/// [`MeshError::Io`], [`MeshError::Parse`] (line for ASCII, triangle record for binary),
/// [`MeshError::NonFinite`].
pub fn read_stl(path: &Path) -> Result<Vec<Triangle>, MeshError> {
    let bytes = std::fs::read(path).map_err(|e| MeshError::Io {
        path: path.to_path_buf(),
        source: e,
    })?;
    parse_stl(&bytes, path)
}

/// Parses STL bytes already in memory; `path` labels errors.
///
/// # Errors
/// As [`read_stl`].
pub fn parse_stl(bytes: &[u8], path: &Path) -> Result<Vec<Triangle>, MeshError> {
    if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        if bytes.len() as u64 == 84 + 50 * n as u64 {
            return parse_binary(bytes, n, path);
        }
    }
    let head = bytes
        .iter()
        .skip_while(|b| b.is_ascii_whitespace())
        .take(5)
        .copied();
    if head.eq(b"solid".iter().copied()) {
        return parse_ascii(bytes, path);
    }
    let message = if bytes.len() < 84 {
        format!(
            "file too short for binary STL ({} bytes) and not ASCII STL",
            bytes.len()
        )
    } else {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
        format!(
            "binary STL header announces {n} triangles ({} bytes) but the file has {} bytes",
            84 + 50 * n,
            bytes.len()
        )
    };
    Err(MeshError::Parse {
        path: path.to_path_buf(),
        line: None,
        triangle: None,
        message,
    })
}

fn parse_binary(bytes: &[u8], n: usize, path: &Path) -> Result<Vec<Triangle>, MeshError> {
    let mut tris = Vec::with_capacity(n);
    for (i, rec) in bytes[84..].chunks_exact(50).enumerate() {
        let f = |o: usize| f32::from_le_bytes([rec[o], rec[o + 1], rec[o + 2], rec[o + 3]]) as f64;
        let mut v = [DVec3::ZERO; 3];
        for (k, p) in v.iter_mut().enumerate() {
            let o = 12 + 12 * k;
            *p = DVec3::new(f(o), f(o + 4), f(o + 8));
            if let Some(&c) = p.to_array().iter().find(|c| !c.is_finite()) {
                return Err(MeshError::NonFinite {
                    path: path.to_path_buf(),
                    line: None,
                    triangle: Some(i),
                    value: c,
                });
            }
        }
        tris.push(Triangle { v });
    }
    Ok(tris)
}

fn parse_ascii(bytes: &[u8], path: &Path) -> Result<Vec<Triangle>, MeshError> {
    let err = |line: usize, message: String| MeshError::Parse {
        path: path.to_path_buf(),
        line: Some(line),
        triangle: None,
        message,
    };
    let text = std::str::from_utf8(bytes).map_err(|e| {
        err(
            line_of_offset(bytes, e.valid_up_to()),
            "ASCII STL is not valid UTF-8".into(),
        )
    })?;
    let mut tris = Vec::new();
    let mut verts: Vec<DVec3> = Vec::with_capacity(3);
    // Expected next keyword, to reject statements out of order.
    #[derive(PartialEq, Clone, Copy, Debug)]
    enum St {
        Solid,
        Facet,
        Loop,
        Vertex,
        EndFacet,
    }
    let mut st = St::Solid;
    for (i, line) in text.lines().enumerate() {
        let ln = i + 1;
        let mut it = line.split_ascii_whitespace();
        let Some(kw) = it.next() else { continue };
        match (kw, st) {
            ("solid", St::Solid) => st = St::Facet,
            ("facet", St::Facet) => {
                if it.next() != Some("normal") {
                    return Err(err(ln, "expected 'facet normal nx ny nz'".into()));
                }
                st = St::Loop;
            }
            ("endsolid", St::Facet) => st = St::Solid,
            ("outer", St::Loop) => st = St::Vertex,
            ("vertex", St::Vertex) => {
                let mut c = [0.0f64; 3];
                for (k, slot) in c.iter_mut().enumerate() {
                    let tok = it.next().ok_or_else(|| {
                        err(ln, format!("vertex has {k} coordinates, expected 3"))
                    })?;
                    *slot = tok
                        .parse::<f64>()
                        .map_err(|_| err(ln, format!("'{tok}' is not a number")))?;
                    if !slot.is_finite() {
                        return Err(MeshError::NonFinite {
                            path: path.to_path_buf(),
                            line: Some(ln),
                            triangle: None,
                            value: *slot,
                        });
                    }
                }
                if verts.len() == 3 {
                    return Err(err(ln, "facet has more than 3 vertices".into()));
                }
                verts.push(DVec3::from_array(c));
            }
            ("endloop", St::Vertex) => {
                if verts.len() != 3 {
                    return Err(err(
                        ln,
                        format!("facet has {} vertices, expected 3", verts.len()),
                    ));
                }
                tris.push(Triangle::new(verts[0], verts[1], verts[2]));
                verts.clear();
                st = St::EndFacet;
            }
            ("endfacet", St::EndFacet) => st = St::Facet,
            (kw, st) => {
                let expected = match st {
                    St::Solid => "'solid'",
                    St::Facet => "'facet' or 'endsolid'",
                    St::Loop => "'outer loop'",
                    St::Vertex => "'vertex' or 'endloop'",
                    St::EndFacet => "'endfacet'",
                };
                return Err(err(ln, format!("unexpected '{kw}', expected {expected}")));
            }
        }
    }
    if st != St::Solid && st != St::Facet {
        let last = text.lines().count().max(1);
        return Err(err(last, "file ends inside a facet".into()));
    }
    Ok(tris)
}

fn line_of_offset(bytes: &[u8], off: usize) -> usize {
    bytes[..off].iter().filter(|&&b| b == b'\n').count() + 1
}

/// Writes triangles as binary STL (f32 coordinates, zero normals recomputed from winding).
///
/// # Errors
/// Any I/O error of `w`.
pub fn write_binary_stl(w: &mut dyn std::io::Write, tris: &[Triangle]) -> std::io::Result<()> {
    let mut header = [0u8; 80];
    header[..14].copy_from_slice(b"cam binary STL");
    w.write_all(&header)?;
    w.write_all(&(tris.len() as u32).to_le_bytes())?;
    for t in tris {
        let n = t.normal().unwrap_or(DVec3::ZERO);
        for p in std::iter::once(n).chain(t.v) {
            for c in p.to_array() {
                w.write_all(&(c as f32).to_le_bytes())?;
            }
        }
        w.write_all(&[0, 0])?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const ASCII: &str = "solid t\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 1 0\n  endloop\n endfacet\nendsolid t\n";

    #[test]
    fn ascii_roundtrip() {
        let t = parse_stl(ASCII.as_bytes(), Path::new("a.stl")).unwrap();
        assert_eq!(t.len(), 1);
        assert_eq!(t[0].v[1], DVec3::X);
    }

    #[test]
    fn ascii_bad_number_names_line() {
        let s = ASCII.replace("vertex 1 0 0", "vertex 1 zz 0");
        let e = parse_stl(s.as_bytes(), Path::new("a.stl")).unwrap_err();
        assert_eq!(e.line(), Some(5), "{e}");
        assert!(e.to_string().starts_with("a.stl:5:"), "{e}");
    }

    #[test]
    fn ascii_nan_names_line() {
        let s = ASCII.replace("vertex 0 1 0", "vertex 0 NaN 0");
        let e = parse_stl(s.as_bytes(), Path::new("a.stl")).unwrap_err();
        assert!(
            matches!(e, MeshError::NonFinite { line: Some(6), .. }),
            "{e}"
        );
    }

    #[test]
    fn binary_roundtrip_and_truncation() {
        let tri = Triangle::new(DVec3::ZERO, DVec3::X, DVec3::Y);
        let mut buf = Vec::new();
        write_binary_stl(&mut buf, &[tri, tri]).unwrap();
        let t = parse_stl(&buf, Path::new("b.stl")).unwrap();
        assert_eq!(t, vec![tri, tri]);
        let e = parse_stl(&buf[..buf.len() - 7], Path::new("b.stl")).unwrap_err();
        assert!(e.to_string().contains("announces 2 triangles"), "{e}");
    }

    #[test]
    fn binary_nan_names_record() {
        let tri = Triangle::new(DVec3::ZERO, DVec3::X, DVec3::new(0.0, f64::NAN, 0.0));
        let mut buf = Vec::new();
        write_binary_stl(
            &mut buf,
            &[Triangle::new(DVec3::ZERO, DVec3::X, DVec3::Y), tri],
        )
        .unwrap();
        let e = parse_stl(&buf, Path::new("b.stl")).unwrap_err();
        assert!(
            matches!(
                e,
                MeshError::NonFinite {
                    triangle: Some(1),
                    ..
                }
            ),
            "{e}"
        );
    }
}
