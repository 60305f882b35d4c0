//! Mesh and toolpath builders shared by the tests.

use cam_core::{Cutter, Mesh, Move, MoveKind, Pose, Toolpath, Triangle};
use cam_holder::{HolderCylinder, ToolAssembly};
use glam::DVec3;

/// Two triangles of the quad `a b c d` (counter-clockwise seen from the outside).
pub fn quad(out: &mut Vec<Triangle>, a: DVec3, b: DVec3, c: DVec3, d: DVec3) {
    out.push(Triangle::new(a, b, c));
    out.push(Triangle::new(a, c, d));
}

pub fn v(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

/// A square pocket: floor z = 0 over [-h, h]², walls up to `depth`, rim top at z = `depth`
/// out to ±`outer`. Normals point into the air.
pub fn pocket(h: f64, depth: f64, outer: f64) -> Mesh {
    let mut t = Vec::new();
    quad(
        &mut t,
        v(-h, -h, 0.0),
        v(h, -h, 0.0),
        v(h, h, 0.0),
        v(-h, h, 0.0),
    );
    // walls, facing inward
    quad(
        &mut t,
        v(h, -h, 0.0),
        v(h, -h, depth),
        v(h, h, depth),
        v(h, h, 0.0),
    ); // x = +h, normal -x
    quad(
        &mut t,
        v(-h, h, 0.0),
        v(-h, h, depth),
        v(-h, -h, depth),
        v(-h, -h, 0.0),
    ); // x = -h, normal +x
    quad(
        &mut t,
        v(h, h, 0.0),
        v(h, h, depth),
        v(-h, h, depth),
        v(-h, h, 0.0),
    ); // y = +h, normal -y
    quad(
        &mut t,
        v(-h, -h, 0.0),
        v(-h, -h, depth),
        v(h, -h, depth),
        v(h, -h, 0.0),
    ); // y = -h, normal +y
    // rim top (z = depth), four rectangles, normal +z
    let z = depth;
    quad(
        &mut t,
        v(h, -outer, z),
        v(outer, -outer, z),
        v(outer, outer, z),
        v(h, outer, z),
    );
    quad(
        &mut t,
        v(-outer, -outer, z),
        v(-h, -outer, z),
        v(-h, outer, z),
        v(-outer, outer, z),
    );
    quad(
        &mut t,
        v(-h, h, z),
        v(h, h, z),
        v(h, outer, z),
        v(-h, outer, z),
    );
    quad(
        &mut t,
        v(-h, -outer, z),
        v(h, -outer, z),
        v(h, -h, z),
        v(-h, -h, z),
    );
    Mesh::from_triangles(t, "<pocket>").unwrap()
}

/// A floor z = 0 over [-50, 50]² with a thin rib x ∈ [-w/2, w/2], y ∈ [-len/2, len/2] of
/// height `height` (the floor under the rib is left in place: a soup is fine).
pub fn rib(w: f64, len: f64, height: f64) -> Mesh {
    let mut t = Vec::new();
    quad(
        &mut t,
        v(-50.0, -50.0, 0.0),
        v(50.0, -50.0, 0.0),
        v(50.0, 50.0, 0.0),
        v(-50.0, 50.0, 0.0),
    );
    let (a, b, hgt) = (w / 2.0, len / 2.0, height);
    quad(
        &mut t,
        v(-a, -b, hgt),
        v(a, -b, hgt),
        v(a, b, hgt),
        v(-a, b, hgt),
    );
    quad(
        &mut t,
        v(a, -b, 0.0),
        v(a, b, 0.0),
        v(a, b, hgt),
        v(a, -b, hgt),
    );
    quad(
        &mut t,
        v(-a, b, 0.0),
        v(-a, -b, 0.0),
        v(-a, -b, hgt),
        v(-a, b, hgt),
    );
    quad(
        &mut t,
        v(a, b, 0.0),
        v(-a, b, 0.0),
        v(-a, b, hgt),
        v(a, b, hgt),
    );
    quad(
        &mut t,
        v(-a, -b, 0.0),
        v(a, -b, 0.0),
        v(a, -b, hgt),
        v(-a, -b, hgt),
    );
    Mesh::from_triangles(t, "<rib>").unwrap()
}

pub fn mv(kind: MoveKind, tip: DVec3) -> Move {
    Move {
        kind,
        pose: Pose::vertical(tip),
        feed_mm_per_min: None,
        line: None,
        pass: None,
    }
}

pub fn path(moves: &[(MoveKind, DVec3)]) -> Toolpath {
    let mut tp = Toolpath {
        moves: moves.iter().map(|&(k, p)| mv(k, p)).collect(),
    };
    for (i, m) in tp.moves.iter_mut().enumerate() {
        m.line = Some(10 + i);
    }
    tp
}

/// Ball Ø6 (flute 12), shank Ø6, holder Ø20×15 then Ø32×40, stick-out `so`.
pub fn ball6(so: f64) -> ToolAssembly {
    let cutter = Cutter::ball(6.0).unwrap().with_flute_length(12.0).unwrap();
    let mut a = ToolAssembly::from_spec(cutter, &Default::default());
    a.id = "T6".into();
    a.shank_diameter_mm = 6.0;
    a.stick_out_mm = so;
    a.stick_out_min_mm = 12.0;
    a.stick_out_max_mm = 60.0;
    a.holder = vec![
        HolderCylinder {
            diameter: 20.0,
            length: 15.0,
        },
        HolderCylinder {
            diameter: 32.0,
            length: 40.0,
        },
    ];
    a
}

/// Tiny deterministic generator (xorshift) for irregular tessellations.
pub struct Rng(pub u64);
impl Rng {
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}
