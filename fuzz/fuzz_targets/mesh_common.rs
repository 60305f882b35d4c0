// Shared by the mesh targets: what Mesh::load does after reading the file (scale + validate),
// then a DropCutter built on the result and one drop.
use cam_core::{Mesh, MeshError, Triangle, Units};
use std::path::Path;

pub fn load_like(
    parse: fn(&[u8], &Path) -> Result<Vec<Triangle>, MeshError>,
    data: &[u8],
    path: &Path,
    units: Units,
) {
    let Ok(mut tris) = parse(data, path) else {
        return;
    };
    let k = units.mm_per_unit();
    if k != 1.0 {
        for t in &mut tris {
            for p in &mut t.v {
                *p *= k;
            }
        }
    }
    let Ok(mesh) = Mesh::from_triangles(tris, path) else {
        return;
    };
    let _ = mesh.bounds();
    let _ = mesh.stats();
    // The index must stay bounded for any part the validation accepts (within 1 km).
    let dc = cam_offset::DropCutter::new(&mesh, "ball:6".parse().unwrap());
    let _ = dc.drop(0.0, 0.0);
}
