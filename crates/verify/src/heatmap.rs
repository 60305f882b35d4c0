//! `--heatmap OUT.png`: a top view of the refined design surface coloured by signed
//! deviation (the colours of [`deviation_colour`]), with a colour scale bar and tick labels.
//!
//! The top view is rasterised with a z-buffer (the highest surface wins, as seen from +Z);
//! colours are interpolated from the vertex deviations. Labels use a built-in 5×7 bitmap font
//! drawn as rectangles with tiny-skia.

use std::path::Path;

use tiny_skia::{Color, Paint, Pixmap, Rect, Transform};

use crate::deviation::Deviation;
use crate::ply::deviation_colour;
use crate::refine::RefinedMesh;
use crate::report::OutputError;

/// Settings of the heat map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeatmapConfig {
    /// Size of the image's long side (px, default 1024); the other side follows the part's
    /// aspect ratio but is at least half the long side (room for the scale bar).
    pub long_side_px: u32,
    /// Tolerance (mm): the green band is ±tolerance.
    pub tolerance_mm: f64,
    /// The scale bar spans ±this (mm); default 4 × tolerance.
    pub range_mm: Option<f64>,
}

impl HeatmapConfig {
    /// Defaults (1024 px, ±4·tol scale) for a tolerance (mm).
    pub fn new(tolerance_mm: f64) -> Self {
        HeatmapConfig {
            long_side_px: 1024,
            tolerance_mm,
            range_mm: None,
        }
    }
}

/// The rendered image before encoding.
#[derive(Debug, Clone)]
pub struct Heatmap {
    /// The pixels (RGBA, opaque).
    pub pixmap: Pixmap,
}

impl Heatmap {
    /// Width (px).
    pub fn width(&self) -> u32 {
        self.pixmap.width()
    }
    /// Height (px).
    pub fn height(&self) -> u32 {
        self.pixmap.height()
    }
    /// The RGBA of pixel `(x, y)`.
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 4] {
        let i = 4 * (y as usize * self.pixmap.width() as usize + x as usize);
        let d = self.pixmap.data();
        [d[i], d[i + 1], d[i + 2], d[i + 3]]
    }
    /// Encodes as PNG into memory.
    ///
    /// # Errors
    /// The encoder's error as text.
    pub fn encode_png(&self) -> Result<Vec<u8>, String> {
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, self.width(), self.height());
            enc.set_color(png::ColorType::Rgba);
            enc.set_depth(png::BitDepth::Eight);
            let mut w = enc.write_header().map_err(|e| e.to_string())?;
            w.write_image_data(self.pixmap.data())
                .map_err(|e| e.to_string())?;
        }
        Ok(out)
    }
}

/// Where the map sits in the image: pixel = (m + (x − x0)·k, m + (y1 − y)·k).
#[derive(Debug, Clone, Copy)]
struct Frame {
    k: f64,
    x0: f64,
    y1: f64,
    m: f64,
}

/// Renders the heat map.
///
/// # Errors
/// A message when `devs.len() != refined.len()` or the size is below 64 px.
pub fn render(
    refined: &RefinedMesh,
    devs: &[Deviation],
    cfg: &HeatmapConfig,
) -> Result<Heatmap, String> {
    if devs.len() != refined.len() {
        return Err(format!(
            "{} deviations for {} vertices",
            devs.len(),
            refined.len()
        ));
    }
    let long = cfg.long_side_px;
    if !(64..=16384).contains(&long) {
        return Err(format!("image size {long} px outside 64..=16384"));
    }
    let lf = f64::from(long);
    let m = (lf / 64.0).round();
    let lw = (lf / 5.0).round();
    let (mut x0, mut y0, mut x1, mut y1) = (
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    );
    for p in &refined.positions {
        x0 = x0.min(p.x);
        y0 = y0.min(p.y);
        x1 = x1.max(p.x);
        y1 = y1.max(p.y);
    }
    let (w, h) = ((x1 - x0).max(1e-9), (y1 - y0).max(1e-9));
    let kw = (lf - lw - 3.0 * m) / w;
    let kh = (lf - 2.0 * m) / h;
    let hmin = (lf / 2.0).round() as u32;
    let (k, width, height) = if kw <= kh {
        (
            kw,
            long,
            ((kw * h + 2.0 * m).round() as u32).clamp(hmin, long),
        )
    } else {
        (
            kh,
            ((kh * w + lw + 3.0 * m).round() as u32).clamp(hmin, long),
            long,
        )
    };
    let mut pixmap = Pixmap::new(width, height).ok_or("cannot allocate image")?;
    pixmap.fill(Color::WHITE);
    let frame = Frame { k, x0, y1, m };
    raster(&mut pixmap, refined, devs, cfg.tolerance_mm, frame);
    let range = cfg
        .range_mm
        .unwrap_or(4.0 * cfg.tolerance_mm.abs())
        .max(1e-12);
    legend(
        &mut pixmap,
        cfg.tolerance_mm,
        range,
        lf,
        width as f64 - lw - m,
        m,
        lw,
    );
    Ok(Heatmap { pixmap })
}

/// Renders and writes the heat map PNG to `path` atomically.
///
/// # Errors
/// [`OutputError::Mismatch`] on unusable inputs, [`OutputError::Encode`],
/// [`OutputError::Io`].
pub fn write_heatmap(
    path: &Path,
    refined: &RefinedMesh,
    devs: &[Deviation],
    cfg: &HeatmapConfig,
) -> Result<(), OutputError> {
    let hm = render(refined, devs, cfg).map_err(|message| OutputError::Mismatch {
        path: path.to_path_buf(),
        message,
    })?;
    let bytes = hm.encode_png().map_err(|message| OutputError::Encode {
        path: path.to_path_buf(),
        message,
    })?;
    cam_core::io::write_atomic(path, |w| w.write_all(&bytes)).map_err(|source| OutputError::Io {
        path: path.to_path_buf(),
        source,
    })
}

fn raster(pm: &mut Pixmap, refined: &RefinedMesh, devs: &[Deviation], tol: f64, f: Frame) {
    let (wpx, hpx) = (pm.width() as usize, pm.height() as usize);
    let mut zbuf = vec![f64::NEG_INFINITY; wpx * hpx];
    let data = pm.data_mut();
    let to_px = |p: glam::DVec3| (f.m + (p.x - f.x0) * f.k, f.m + (f.y1 - p.y) * f.k);
    for t in &refined.triangles {
        let v = t.map(|i| refined.positions[i as usize]);
        let s = t.map(|i| devs[i as usize].signed_mm);
        let q = v.map(to_px);
        let det = (q[1].0 - q[0].0) * (q[2].1 - q[0].1) - (q[2].0 - q[0].0) * (q[1].1 - q[0].1);
        if det == 0.0 {
            continue;
        }
        let (minx, maxx) = (
            q[0].0.min(q[1].0).min(q[2].0),
            q[0].0.max(q[1].0).max(q[2].0),
        );
        let (miny, maxy) = (
            q[0].1.min(q[1].1).min(q[2].1),
            q[0].1.max(q[1].1).max(q[2].1),
        );
        let ix0 = (minx - 0.5).ceil().max(0.0) as usize;
        let iy0 = (miny - 0.5).ceil().max(0.0) as usize;
        let ix1 = ((maxx - 0.5).floor().min(wpx as f64 - 1.0)).max(-1.0);
        let iy1 = ((maxy - 0.5).floor().min(hpx as f64 - 1.0)).max(-1.0);
        if ix1 < 0.0 || iy1 < 0.0 {
            continue;
        }
        for py in iy0..=iy1 as usize {
            for px in ix0..=ix1 as usize {
                let (cx, cy) = (px as f64 + 0.5, py as f64 + 0.5);
                let w1 =
                    ((cx - q[0].0) * (q[2].1 - q[0].1) - (q[2].0 - q[0].0) * (cy - q[0].1)) / det;
                let w2 =
                    ((q[1].0 - q[0].0) * (cy - q[0].1) - (cx - q[0].0) * (q[1].1 - q[0].1)) / det;
                let w0 = 1.0 - w1 - w2;
                if w0 < -1e-9 || w1 < -1e-9 || w2 < -1e-9 {
                    continue;
                }
                let z = w0 * v[0].z + w1 * v[1].z + w2 * v[2].z;
                let k = py * wpx + px;
                if z <= zbuf[k] {
                    continue;
                }
                zbuf[k] = z;
                let dev = match s {
                    [Some(a), Some(b), Some(c)] => Some(w0 * a + w1 * b + w2 * c),
                    _ => {
                        // Mixed measured/unmachined: the nearest corner's value.
                        let ws = [w0, w1, w2];
                        let j = (0..3).max_by(|&a, &b| ws[a].total_cmp(&ws[b])).unwrap_or(0);
                        s[j]
                    }
                };
                let c = deviation_colour(dev, tol);
                data[4 * k..4 * k + 4].copy_from_slice(&[c[0], c[1], c[2], 255]);
            }
        }
    }
}

fn fill(pm: &mut Pixmap, x: f64, y: f64, w: f64, h: f64, rgb: [u8; 3]) {
    if let Some(r) = Rect::from_xywh(x as f32, y as f32, w as f32, h as f32) {
        let mut p = Paint::default();
        p.set_color_rgba8(rgb[0], rgb[1], rgb[2], 255);
        p.anti_alias = false;
        pm.fill_rect(r, &p, Transform::identity(), None);
    }
}

/// The scale bar: gouge (bottom, red) to excess (top, blue), ticks at 0, ±tol, ±2·tol, ±range.
fn legend(pm: &mut Pixmap, tol: f64, range: f64, long: f64, x: f64, m: f64, lw: f64) {
    let hpx = f64::from(pm.height());
    let scale = (long / 512.0).round().max(1.0);
    let top = m + 12.0 * scale;
    let bar_h = hpx - top - m - 4.0 * scale;
    let bar_w = (lw * 0.22).round();
    let steps = bar_h.round().max(1.0) as usize;
    for i in 0..steps {
        let v = range - 2.0 * range * (i as f64 + 0.5) / steps as f64;
        fill(
            pm,
            x,
            top + i as f64,
            bar_w,
            1.0,
            deviation_colour(Some(v), tol),
        );
    }
    text(pm, x, m, scale, "mm");
    let decimals = if tol > 0.0 {
        ((-tol.log10()).ceil() as i32 + 1).clamp(0, 4) as usize
    } else {
        3
    };
    let mut ticks = vec![-range, 0.0, range];
    for k in [1.0, 2.0] {
        if k * tol < range * 0.999 {
            ticks.extend([-k * tol, k * tol]);
        }
    }
    for v in ticks {
        let y = top + (range - v) / (2.0 * range) * bar_h;
        fill(
            pm,
            x + bar_w,
            y - scale / 2.0,
            3.0 * scale,
            scale.max(1.0),
            [0, 0, 0],
        );
        let label = format!("{:.*}", decimals, v);
        let label = if v > 0.0 { format!("+{label}") } else { label };
        text(pm, x + bar_w + 5.0 * scale, y - 3.5 * scale, scale, &label);
    }
}

/// 5×7 glyphs, one row per byte, bit 4 = leftmost column.
fn glyph(c: char) -> Option<[u8; 7]> {
    Some(match c {
        '0' => [0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E],
        '1' => [0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E],
        '2' => [0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F],
        '3' => [0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E],
        '4' => [0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02],
        '5' => [0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E],
        '6' => [0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E],
        '7' => [0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08],
        '8' => [0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E],
        '9' => [0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C],
        '-' => [0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00],
        '+' => [0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00],
        '.' => [0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C],
        'm' => [0x00, 0x00, 0x1A, 0x15, 0x15, 0x11, 0x11],
        _ => return None,
    })
}

fn text(pm: &mut Pixmap, x: f64, y: f64, scale: f64, s: &str) {
    for (n, c) in s.chars().enumerate() {
        let Some(g) = glyph(c) else { continue };
        let gx = x + n as f64 * 6.0 * scale;
        for (row, bits) in g.iter().enumerate() {
            for col in 0..5 {
                if bits & (0x10 >> col) != 0 {
                    fill(
                        pm,
                        gx + col as f64 * scale,
                        y + row as f64 * scale,
                        scale,
                        scale,
                        [0, 0, 0],
                    );
                }
            }
        }
    }
}
