//! Triangle meshes: the part as a triangle soup in mm, validated on load.

use std::path::{Path, PathBuf};

use glam::DVec3;

use crate::error::MeshError;
use crate::units::Units;

/// One triangle, vertices in mm, in the order the file gave them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Triangle {
    /// The three corners (mm).
    pub v: [DVec3; 3],
}

impl Triangle {
    /// Builds a triangle from its corners (mm).
    pub fn new(a: DVec3, b: DVec3, c: DVec3) -> Self {
        Triangle { v: [a, b, c] }
    }

    /// The non-normalised normal `(b - a) × (c - a)`; its length is twice the area (mm²).
    pub fn cross(&self) -> DVec3 {
        (self.v[1] - self.v[0]).cross(self.v[2] - self.v[0])
    }

    /// Unit normal by the right-hand rule, or `None` for a degenerate triangle.
    pub fn normal(&self) -> Option<DVec3> {
        let n = self.cross();
        let l = n.length();
        (l > 0.0 && l.is_finite()).then(|| n / l)
    }

    /// Area in mm².
    pub fn area(&self) -> f64 {
        0.5 * self.cross().length()
    }

    /// True when the triangle has (numerically) zero area: the sine of its largest angle's
    /// supplement is below 1e-12, or two corners coincide.
    pub fn is_degenerate(&self) -> bool {
        let [a, b, c] = self.v;
        let e2 = (b - a)
            .length_squared()
            .max((c - b).length_squared())
            .max((a - c).length_squared());
        if e2 == 0.0 {
            return true;
        }
        let cross = self.cross().length();
        cross <= 1e-12 * e2
    }

    /// Axis-aligned bounds of the triangle.
    pub fn aabb(&self) -> Aabb {
        let mut b = Aabb::empty();
        for p in self.v {
            b.grow(p);
        }
        b
    }
}

/// An axis-aligned box (mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: DVec3,
    /// Largest corner.
    pub max: DVec3,
}

impl Aabb {
    /// The empty box (min = +inf, max = -inf); growing it by a point gives that point.
    pub fn empty() -> Self {
        Aabb {
            min: DVec3::splat(f64::INFINITY),
            max: DVec3::splat(f64::NEG_INFINITY),
        }
    }
    /// Enlarges the box to contain `p`.
    pub fn grow(&mut self, p: DVec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }
    /// Size along each axis (mm).
    pub fn size(&self) -> DVec3 {
        self.max - self.min
    }
    /// True when the box contains no point.
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x
    }
}

/// What loading a part found besides its triangles.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct LoadStats {
    /// Triangles read from the file (after triangulating polygons).
    pub triangles_read: usize,
    /// Degenerate (zero-area) triangles dropped.
    pub degenerate_dropped: usize,
}

/// Largest distance (mm) of a part's coordinate from the origin along any axis: 1 km.
pub const MAX_COORD_MM: f64 = 1.0e6;

/// A validated part: a non-empty soup of finite, non-degenerate triangles in mm.
///
/// Guarantees: at least one triangle; every coordinate finite and within [`MAX_COORD_MM`];
/// no triangle degenerate in the sense of [`Triangle::is_degenerate`].
#[derive(Debug, Clone)]
pub struct Mesh {
    triangles: Vec<Triangle>,
    bounds: Aabb,
    stats: LoadStats,
    source: Option<PathBuf>,
}

impl Mesh {
    /// Builds a mesh from triangles in mm, dropping degenerate ones.
    ///
    /// # Errors
    /// [`MeshError::NonFinite`] if any coordinate is NaN or infinite, [`MeshError::OutOfRange`]
    /// if one lies beyond [`MAX_COORD_MM`] of the origin, [`MeshError::NoTriangles`]
    /// for an empty list, [`MeshError::AllDegenerate`] if nothing is left after dropping.
    /// `path` only labels the errors (use `"<memory>"` for generated meshes).
    pub fn from_triangles(
        triangles: Vec<Triangle>,
        path: impl AsRef<Path>,
    ) -> Result<Mesh, MeshError> {
        let path = path.as_ref();
        let read = triangles.len();
        if read == 0 {
            return Err(MeshError::NoTriangles {
                path: path.to_path_buf(),
            });
        }
        for (i, t) in triangles.iter().enumerate() {
            for p in t.v {
                for c in p.to_array() {
                    if !c.is_finite() {
                        return Err(MeshError::NonFinite {
                            path: path.to_path_buf(),
                            line: None,
                            triangle: Some(i),
                            value: c,
                        });
                    }
                    if c.abs() > MAX_COORD_MM {
                        return Err(MeshError::OutOfRange {
                            path: path.to_path_buf(),
                            triangle: Some(i),
                            value: c,
                            limit_mm: MAX_COORD_MM,
                        });
                    }
                }
            }
        }
        let kept: Vec<Triangle> = triangles
            .into_iter()
            .filter(|t| !t.is_degenerate())
            .collect();
        if kept.is_empty() {
            return Err(MeshError::AllDegenerate {
                path: path.to_path_buf(),
                count: read,
            });
        }
        let mut bounds = Aabb::empty();
        for t in &kept {
            for p in t.v {
                bounds.grow(p);
            }
        }
        let stats = LoadStats {
            triangles_read: read,
            degenerate_dropped: read - kept.len(),
        };
        Ok(Mesh {
            triangles: kept,
            bounds,
            stats,
            source: Some(path.to_path_buf()),
        })
    }

    /// Loads an `.obj` or `.stl` part (binary or ASCII STL), scaling `units` to mm.
    ///
    /// # Errors
    /// Any [`MeshError`]: unreadable file, unknown extension, malformed line (with its line
    /// number for text formats), non-finite coordinates, no triangles, only degenerate ones.
    pub fn load(path: impl AsRef<Path>, units: Units) -> Result<Mesh, MeshError> {
        let path = path.as_ref();
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .unwrap_or_default();
        let mut tris = match ext.as_str() {
            "obj" => crate::io::obj::read_obj(path)?,
            "stl" => crate::io::stl::read_stl(path)?,
            _ => {
                return Err(MeshError::UnknownFormat {
                    path: path.to_path_buf(),
                    ext,
                });
            }
        };
        let k = units.mm_per_unit();
        if k != 1.0 {
            for t in &mut tris {
                for p in &mut t.v {
                    *p *= k;
                }
            }
        }
        Mesh::from_triangles(tris, path)
    }

    /// The triangles (mm).
    pub fn triangles(&self) -> &[Triangle] {
        &self.triangles
    }
    /// Bounds of all triangles (mm).
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }
    /// What loading found (triangles read, degenerate ones dropped).
    pub fn stats(&self) -> LoadStats {
        self.stats
    }
    /// The file the mesh came from, if any.
    pub fn source(&self) -> Option<&Path> {
        self.source.as_deref()
    }
    /// Number of triangles kept.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }
    /// Always false: a [`Mesh`] holds at least one triangle.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A coordinate beyond 1 km (a part read in the wrong units, or a corrupt file found by
    /// fuzzing) is a typed error naming the triangle, not a part whose grids exhaust memory;
    /// one at the limit is a part.
    #[test]
    fn coordinates_beyond_a_kilometre_are_errors() {
        let tri = |x: f64| {
            vec![Triangle::new(
                DVec3::ZERO,
                DVec3::new(x, 0.0, 0.0),
                DVec3::new(0.0, 1.0, 0.0),
            )]
        };
        assert!(Mesh::from_triangles(tri(MAX_COORD_MM), "<memory>").is_ok());
        for x in [1.0e12, -2.0e6, 1.0e40] {
            match Mesh::from_triangles(tri(x), "<memory>") {
                Err(MeshError::OutOfRange {
                    triangle, value, ..
                }) => {
                    assert_eq!((triangle, value), (Some(0), x));
                }
                other => panic!("{x}: {other:?}"),
            }
        }
    }
}
