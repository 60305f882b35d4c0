//! The report's statistics, the PLY deviation file and the heat-map PNG.

use cam_core::{DVec3, Mesh, Triangle};
use cam_verify::deviation::Deviation;
use cam_verify::heatmap::{self, HeatmapConfig};
use cam_verify::ply::{self, PlyFormat};
use cam_verify::refine::{self, CapPolicy, RefineConfig, RefinedMesh};
use cam_verify::report::{self, Finding, ReportConfig};

/// 100 measured vertices on a line, signed = (i − 50)·1 µm·…, plus 3 unmachined.
fn synthetic() -> Vec<Deviation> {
    let mut d: Vec<Deviation> = (0..100)
        .map(|i| Deviation {
            position: DVec3::new(0.1 * i as f64, 0.0, 0.0),
            normal: DVec3::Z,
            signed_mm: Some((i as f64 - 50.0) * 0.001),
            source_move: Some(i as u32),
        })
        .collect();
    for k in 0..3 {
        d.push(Deviation {
            position: DVec3::new(0.0, 1.0 + k as f64, 0.0),
            normal: DVec3::Z,
            signed_mm: None,
            source_move: None,
        });
    }
    d
}

#[test]
fn statistics_bands_and_worst_locations() {
    let d = synthetic();
    // Move m comes from line 10 + m; move 0 has no line.
    let lines: Vec<Option<usize>> = (0..100).map(|m| (m > 0).then_some(10 + m)).collect();
    let cfg = ReportConfig::new(0.01);
    let r = report::build_report(&d, &lines, &cfg, None);
    assert_eq!((r.vertices, r.measured, r.unmachined), (103, 100, 3));
    cam_core::assert_near!(r.max_gouge_mm, 0.05, 1e-15);
    cam_core::assert_near!(r.max_excess_mm, 0.049, 1e-15);
    cam_core::assert_near!(r.mean_mm, -0.0005, 1e-15);
    // Nearest rank over the sorted values −0.050 … 0.049.
    cam_core::assert_near!(r.p50_mm, -0.001, 1e-15);
    cam_core::assert_near!(r.p95_mm, 0.044, 1e-15);
    cam_core::assert_near!(r.p99_mm, 0.048, 1e-15);
    cam_core::assert_near!(r.p01_mm, -0.05, 1e-15);
    // < −tol: i ≤ 39 (40); within: 40..=60 (21); > tol: 61..=99 (39).
    assert_eq!(
        (
            r.tolerance_counts.gouge,
            r.tolerance_counts.within,
            r.tolerance_counts.excess
        ),
        (40, 21, 39)
    );
    // Bands: edges −40, −20, −10, −5, 5, 10, 20, 40 µm.
    let counts: Vec<usize> = r.bands.iter().map(|b| b.count).collect();
    assert_eq!(counts, vec![10, 20, 10, 5, 10, 5, 10, 20, 10]);
    assert_eq!(counts.iter().sum::<usize>(), 100);
    assert_eq!((r.bands[0].lo_mm, r.bands[8].hi_mm), (None, None));
    // Worst gouges: deepest first, 1 mm apart (every 10th vertex), with their lines.
    let g: Vec<(f64, Option<usize>)> = r
        .worst_gouges
        .iter()
        .map(|w| (w.signed_mm, w.line))
        .collect();
    assert_eq!(g.len(), 5);
    cam_core::assert_near!(g[0].0, -0.05, 1e-15);
    assert_eq!(g[0].1, None); // move 0 has no line
    assert_eq!(g[1].1, Some(20)); // vertex 10, move 10
    assert!(r.worst_gouges.iter().all(|w| w.kind == Finding::Gouge));
    let e = &r.worst_excess;
    assert_eq!(e.len(), 5);
    cam_core::assert_near!(e[0].signed_mm, 0.049, 1e-15);
    assert_eq!((e[0].move_index, e[0].line), (Some(99), Some(109)));
    assert!(r.gouge_exceeds(0.01));
    assert!(!r.gouge_exceeds(0.05));
    let json = serde_json::to_value(&r).unwrap();
    assert_eq!(json["max_gouge_mm"].as_f64(), Some(r.max_gouge_mm));
    assert_eq!(json["config"]["tolerance_mm"].as_f64(), Some(0.01));
    assert_eq!(json["worst_excess"][0]["kind"], "excess");
    // Nothing measured: zeros, no panic.
    let empty = report::build_report(&d[100..], &[], &cfg, None);
    assert_eq!(
        (empty.max_gouge_mm, empty.max_excess_mm, empty.measured),
        (0.0, 0.0, 0)
    );
}

/// A 10 × 5 mm plane refined to 1 mm; deviations by x: gouge for x < 3, excess for x > 7,
/// within otherwise, and unmachined at one vertex.
fn coloured() -> (RefinedMesh, Vec<Deviation>) {
    let p = |x: f64, y: f64| DVec3::new(x, y, 0.0);
    let m = Mesh::from_triangles(
        vec![
            Triangle::new(p(0., 0.), p(10., 0.), p(10., 5.)),
            Triangle::new(p(0., 0.), p(10., 5.), p(0., 5.)),
        ],
        "<memory>",
    )
    .unwrap();
    let r = refine::refine(
        &m,
        &RefineConfig {
            max_edge_mm: 1.0,
            crease_angle_deg: 30.0,
            max_vertices: None,
            on_cap: CapPolicy::Error,
            region: None,
            remesh: true,
        },
    )
    .unwrap();
    let d: Vec<Deviation> = r
        .positions
        .iter()
        .zip(&r.normals)
        .enumerate()
        .map(|(i, (&position, &normal))| {
            let v = if position.x < 3.0 {
                -0.05
            } else if position.x > 7.0 {
                0.03
            } else {
                0.002
            };
            Deviation {
                position,
                normal,
                signed_mm: (i != 0).then_some(v),
                source_move: Some(0),
            }
        })
        .collect();
    (r, d)
}

/// A tiny PLY reader for what `ply.rs` writes: returns (x, y, z, r, g, b, deviation) per
/// vertex and the faces.
#[allow(clippy::type_complexity)]
fn read_ply(bytes: &[u8]) -> (Vec<([f32; 6], [u8; 3], f32)>, Vec<[i32; 3]>) {
    let end = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    let header = std::str::from_utf8(&bytes[..end]).unwrap();
    let count = |name: &str| -> usize {
        header
            .lines()
            .find_map(|l| l.strip_prefix(&format!("element {name} ")))
            .unwrap()
            .parse()
            .unwrap()
    };
    let (nv, nf) = (count("vertex"), count("face"));
    let props: Vec<&str> = header
        .lines()
        .filter_map(|l| l.strip_prefix("property "))
        .collect();
    assert_eq!(
        props[..10],
        [
            "float x",
            "float y",
            "float z",
            "float nx",
            "float ny",
            "float nz",
            "uchar red",
            "uchar green",
            "uchar blue",
            "float deviation"
        ]
    );
    let mut verts = Vec::new();
    let mut faces = Vec::new();
    if header.contains("format ascii 1.0") {
        let body = std::str::from_utf8(&bytes[end..]).unwrap();
        let mut lines = body.lines();
        for _ in 0..nv {
            let f: Vec<&str> = lines.next().unwrap().split(' ').collect();
            assert_eq!(f.len(), 10);
            let xyz: [f32; 6] = std::array::from_fn(|k| f[k].parse().unwrap());
            let c: [u8; 3] = std::array::from_fn(|k| f[6 + k].parse().unwrap());
            verts.push((xyz, c, f[9].parse().unwrap()));
        }
        for _ in 0..nf {
            let f: Vec<i32> = lines
                .next()
                .unwrap()
                .split(' ')
                .map(|s| s.parse().unwrap())
                .collect();
            assert_eq!(f[0], 3);
            faces.push([f[1], f[2], f[3]]);
        }
        assert!(lines.next().is_none());
    } else {
        assert!(header.contains("format binary_little_endian 1.0"));
        let mut b = &bytes[end..];
        let f32le = |b: &mut &[u8]| {
            let v = f32::from_le_bytes(b[..4].try_into().unwrap());
            *b = &b[4..];
            v
        };
        for _ in 0..nv {
            let xyz: [f32; 6] = std::array::from_fn(|_| f32le(&mut b));
            let c = [b[0], b[1], b[2]];
            b = &b[3..];
            verts.push((xyz, c, f32le(&mut b)));
        }
        for _ in 0..nf {
            assert_eq!(b[0], 3);
            let idx: [i32; 3] = std::array::from_fn(|k| {
                i32::from_le_bytes(b[1 + 4 * k..5 + 4 * k].try_into().unwrap())
            });
            b = &b[13..];
            faces.push(idx);
        }
        assert!(b.is_empty());
    }
    (verts, faces)
}

fn dominant(c: [u8; 3]) -> usize {
    (0..3).max_by_key(|&k| c[k]).unwrap()
}

#[test]
fn ply_round_trips_with_colours() {
    let (r, d) = coloured();
    let dir = tempfile::tempdir().unwrap();
    for fmt in [PlyFormat::Ascii, PlyFormat::BinaryLittleEndian] {
        let path = dir.path().join(format!("{fmt:?}.ply"));
        ply::write_deviation_ply(&path, &r, &d, 0.01, fmt).unwrap();
        let (verts, faces) = read_ply(&std::fs::read(&path).unwrap());
        assert_eq!(verts.len(), r.len());
        assert_eq!(
            faces,
            r.triangles
                .iter()
                .map(|t| t.map(|i| i as i32))
                .collect::<Vec<_>>()
        );
        let (mut red, mut green, mut blue) = (0, 0, 0);
        for ((xyz, c, dev), (p, dv)) in verts.iter().zip(r.positions.iter().zip(&d)) {
            assert_eq!(xyz[..3], [p.x as f32, p.y as f32, p.z as f32]);
            match dv.signed_mm {
                None => {
                    assert!(dev.is_nan());
                    assert_eq!(dominant(*c), 2);
                }
                Some(v) => {
                    assert_eq!(*dev, v as f32);
                    let want = if v < -0.01 {
                        0
                    } else if v > 0.01 {
                        2
                    } else {
                        1
                    };
                    assert_eq!(dominant(*c), want, "colour {c:?} for {v}");
                    *[&mut red, &mut green, &mut blue][want] += 1;
                }
            }
        }
        assert!(red > 10 && green > 10 && blue > 10, "{red} {green} {blue}");
    }
    assert!(
        ply::write_deviation_ply(
            &dir.path().join("x.ply"),
            &r,
            &d[1..],
            0.01,
            PlyFormat::Ascii
        )
        .is_err()
    );
}

#[test]
fn colour_scale() {
    use cam_verify::ply::deviation_colour as c;
    for v in [-1.0, -0.05, -0.0101] {
        assert_eq!(dominant(c(Some(v), 0.01)), 0, "{v}");
    }
    for v in [-0.01, -0.005, 0.0, 0.005, 0.01] {
        assert_eq!(dominant(c(Some(v), 0.01)), 1, "{v}");
    }
    for v in [0.0101, 0.05, 1.0] {
        assert_eq!(dominant(c(Some(v), 0.01)), 2, "{v}");
    }
    assert_eq!(dominant(c(None, 0.01)), 2);
}

#[test]
fn heatmap_png_decodes_with_expected_size() {
    let (r, d) = coloured();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("heat.png");
    let cfg = HeatmapConfig {
        long_side_px: 512,
        ..HeatmapConfig::new(0.01)
    };
    heatmap::write_heatmap(&path, &r, &d, &cfg).unwrap();
    let dec = png::Decoder::new(std::fs::File::open(&path).unwrap());
    let mut rd = dec.read_info().unwrap();
    let mut buf = vec![0; rd.output_buffer_size()];
    let info = rd.next_frame(&mut buf).unwrap();
    // Landscape 10 × 5 part: the long side is the width; height at least half of it.
    assert_eq!((info.width, info.height), (512, 256));
    let px = |x: u32, y: u32| {
        let i = 4 * (y * info.width + x) as usize;
        [buf[i], buf[i + 1], buf[i + 2]]
    };
    // Layout: margin 8 px, 38.6 px/mm, y up. (1.5, 2.5) is gouge, (5, 2.5) within, (8.5, 2.5) excess.
    let at = |x: f64, y: f64| px((8.0 + x * 38.6) as u32, (8.0 + (5.0 - y) * 38.6) as u32);
    assert_eq!(dominant(at(1.5, 2.5)), 0, "{:?}", at(1.5, 2.5));
    assert_eq!(dominant(at(5.0, 2.5)), 1, "{:?}", at(5.0, 2.5));
    assert_eq!(dominant(at(8.5, 2.5)), 2, "{:?}", at(8.5, 2.5));
    // The scale bar and its labels put black pixels in the right-hand panel.
    let dark = (400..512)
        .flat_map(|x| (0..256).map(move |y| (x, y)))
        .filter(|&(x, y)| px(x, y) == [0, 0, 0])
        .count();
    assert!(dark > 100, "{dark} label pixels");
    // Portrait and default size: the height is the long side.
    let rot: Vec<Deviation> = d
        .iter()
        .map(|v| Deviation {
            position: DVec3::new(v.position.y, v.position.x, 0.0),
            ..*v
        })
        .collect();
    let mut rr = r.clone();
    rr.positions = rot.iter().map(|v| v.position).collect();
    let hm = heatmap::render(&rr, &rot, &HeatmapConfig::new(0.01)).unwrap();
    assert_eq!(hm.height(), 1024);
    assert!(hm.width() >= 512 && hm.width() <= 1024);
}
