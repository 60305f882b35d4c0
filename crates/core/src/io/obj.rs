//! Wavefront OBJ reading through `tobj` (f64, polygons triangulated). `tobj` reports no line
//! numbers, so on failure this module scans the text to name the offending line.

use std::path::Path;

use glam::DVec3;

use crate::error::MeshError;
use crate::mesh::Triangle;

/// Reads the triangles of every object in an OBJ file (mm as written; no unit scaling).
///
/// Material libraries are not opened. Points and lines are ignored.
///
/// # Errors
/// [`MeshError::Io`], [`MeshError::Parse`] with the line when it can be located,
/// [`MeshError::NonFinite`] with the line of the vertex.
pub fn read_obj(path: &Path) -> Result<Vec<Triangle>, MeshError> {
    let bytes = std::fs::read(path).map_err(|e| MeshError::Io {
        path: path.to_path_buf(),
        source: e,
    })?;
    parse_obj(&bytes, path)
}

/// Parses OBJ text already in memory; `path` labels errors.
///
/// # Errors
/// As [`read_obj`].
pub fn parse_obj(bytes: &[u8], path: &Path) -> Result<Vec<Triangle>, MeshError> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let mut reader = std::io::BufReader::new(bytes);
    let (models, _materials) =
        tobj::load_obj_buf(&mut reader, &opts, |_| Err(tobj::LoadError::OpenFileFailed))
            .map_err(|e| locate(bytes, path, e))?;
    let text = String::from_utf8_lossy(bytes);
    let mut tris = Vec::new();
    for m in &models {
        let pos = &m.mesh.positions;
        if let Some(k) = pos.iter().position(|c| !c.is_finite()) {
            let line = nth_statement_line(&text, "v", k / 3);
            return Err(MeshError::NonFinite {
                path: path.to_path_buf(),
                line,
                triangle: None,
                value: pos[k],
            });
        }
        let p = |i: u32| {
            let i = i as usize * 3;
            DVec3::new(pos[i], pos[i + 1], pos[i + 2])
        };
        for f in m.mesh.indices.chunks_exact(3) {
            tris.push(Triangle::new(p(f[0]), p(f[1]), p(f[2])));
        }
    }
    Ok(tris)
}

/// 1-based line number of the `n`-th (0-based) statement with keyword `kw`.
fn nth_statement_line(text: &str, kw: &str, n: usize) -> Option<usize> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| l.split_whitespace().next() == Some(kw))
        .nth(n)
        .map(|(i, _)| i + 1)
}

/// Turns a `tobj` error into a [`MeshError::Parse`], finding the line by re-scanning.
fn locate(bytes: &[u8], path: &Path, e: tobj::LoadError) -> MeshError {
    use tobj::LoadError as L;
    let text = String::from_utf8_lossy(bytes);
    let nverts = text
        .lines()
        .filter(|l| l.split_whitespace().next() == Some("v"))
        .count();
    let bad_floats = |kw: &str, n: usize| {
        text.lines().enumerate().find_map(|(i, l)| {
            let mut it = l.split_whitespace();
            if it.next() != Some(kw) {
                return None;
            }
            let vals: Vec<&str> = it.collect();
            let ok = vals.len() >= n && vals.iter().all(|v| v.parse::<f64>().is_ok());
            (!ok).then(|| (i + 1, format!("malformed '{kw}' statement: '{}'", l.trim())))
        })
    };
    let found = match e {
        L::PositionParseError => bad_floats("v", 3),
        L::NormalParseError => bad_floats("vn", 3),
        L::TexcoordParseError => bad_floats("vt", 1),
        L::FaceParseError
        | L::InvalidPolygon
        | L::FaceVertexOutOfBounds
        | L::FaceTexCoordOutOfBounds
        | L::FaceNormalOutOfBounds => bad_face(&text, nverts),
        _ => None,
    };
    let (line, message) = match found {
        Some((l, m)) => (Some(l), m),
        None => (None, format!("malformed OBJ: {e}")),
    };
    MeshError::Parse {
        path: path.to_path_buf(),
        line,
        triangle: None,
        message,
    }
}

/// Finds the first face statement with fewer than 3 corners or a bad vertex index.
fn bad_face(text: &str, nverts: usize) -> Option<(usize, String)> {
    let mut seen_v = 0usize;
    for (i, l) in text.lines().enumerate() {
        let mut it = l.split_whitespace();
        match it.next() {
            Some("v") => seen_v += 1,
            Some("f") => {
                let corners: Vec<&str> = it.collect();
                if corners.len() < 3 {
                    return Some((
                        i + 1,
                        format!("face with {} corners: '{}'", corners.len(), l.trim()),
                    ));
                }
                for c in corners {
                    let idx = c.split('/').next().unwrap_or("");
                    match idx.parse::<i64>() {
                        Ok(0) | Err(_) => {
                            return Some((i + 1, format!("bad vertex index '{c}' in face")));
                        }
                        Ok(k) if k > nverts as i64 || (k < 0 && -k > seen_v as i64) => {
                            return Some((
                                i + 1,
                                format!(
                                    "vertex index {k} out of range (file has {nverts} vertices)"
                                ),
                            ));
                        }
                        Ok(_) => {}
                    }
                }
            }
            _ => {}
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<Vec<Triangle>, MeshError> {
        parse_obj(s.as_bytes(), Path::new("t.obj"))
    }

    #[test]
    fn quad_is_triangulated() {
        let t = parse("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n").unwrap();
        assert_eq!(t.len(), 2);
        assert_eq!(t[0].v[1], DVec3::new(1.0, 0.0, 0.0));
    }

    #[test]
    fn bad_vertex_names_line() {
        let e = parse("# c\nv 0 0 0\nv 1 x 0\nv 0 1 0\nf 1 2 3\n").unwrap_err();
        assert_eq!(e.line(), Some(3), "{e}");
        assert!(e.to_string().contains("t.obj:3"), "{e}");
    }

    #[test]
    fn nan_vertex_names_line() {
        let e = parse("v 0 0 0\nv 1 0 0\n\nv 0 nan 0\nf 1 2 3\n").unwrap_err();
        assert!(
            matches!(e, MeshError::NonFinite { line: Some(4), .. }),
            "{e}"
        );
    }

    #[test]
    fn out_of_range_face_names_line() {
        let e = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n").unwrap_err();
        assert_eq!(e.line(), Some(5), "{e}");
    }
}
