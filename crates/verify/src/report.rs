//! The verification report: statistics of the signed deviations, counts per tolerance band
//! and the worst locations with their toolpath lines. Serialisable for `--json`.

use std::collections::BTreeMap;
use std::path::PathBuf;

use rayon::prelude::*;

use crate::deviation::{Deviation, DeviationConfig};
use crate::refine::RefineConfig;

/// Settings of the report.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ReportConfig {
    /// Machining tolerance (mm): a gouge deeper than this fails the check.
    pub tolerance_mm: f64,
    /// How many worst gouges and worst excess locations to list (default 10).
    pub worst_n: usize,
    /// Two listed locations of the same kind are at least this far apart (mm, default 1), so
    /// the list names distinct places rather than neighbouring vertices of one.
    pub worst_separation_mm: f64,
    /// Band edges as multiples of the tolerance, ascending (default −4, −2, −1, −½, ½, 1, 2, 4).
    pub band_edges_tol: Vec<f64>,
}

impl ReportConfig {
    /// Defaults for a tolerance (mm).
    pub fn new(tolerance_mm: f64) -> Self {
        ReportConfig {
            tolerance_mm,
            worst_n: 10,
            worst_separation_mm: 1.0,
            band_edges_tol: vec![-4.0, -2.0, -1.0, -0.5, 0.5, 1.0, 2.0, 4.0],
        }
    }
}

/// The settings that produced a measurement, echoed in the report.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MeasureSettings {
    /// Resolution `e` of the normal-vector method (mm).
    pub resolution_mm: f64,
    /// The refinement settings.
    pub refine: RefineConfig,
    /// Longest edge actually used (mm).
    pub max_edge_used_mm: f64,
    /// The vector settings.
    pub deviation: DeviationConfig,
    /// Other named numbers (inserts, max step, …) the caller wants recorded.
    pub extra: BTreeMap<String, f64>,
}

/// A count of vertices whose signed deviation lies in `[lo_mm, hi_mm)`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Band {
    /// Lower bound (mm), `-inf` for the first band (serialised as null).
    pub lo_mm: Option<f64>,
    /// Upper bound (mm), `+inf` for the last band (serialised as null).
    pub hi_mm: Option<f64>,
    /// Vertices in the band.
    pub count: usize,
}

/// The coarse classification against the tolerance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct ToleranceCounts {
    /// Signed deviation below −tolerance (gouge).
    pub gouge: usize,
    /// Within [−tolerance, +tolerance].
    pub within: usize,
    /// Above +tolerance (excess), unmachined vertices not included.
    pub excess: usize,
}

/// Gouge or excess.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Finding {
    /// Below the design surface.
    Gouge,
    /// Material left.
    Excess,
}

/// One of the worst locations.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct WorstLocation {
    /// Gouge or excess.
    pub kind: Finding,
    /// The design-surface vertex (mm).
    pub position: [f64; 3],
    /// Its unit normal.
    pub normal: [f64; 3],
    /// Signed deviation (mm).
    pub signed_mm: f64,
    /// Index of the toolpath move responsible.
    pub move_index: Option<u32>,
    /// That move's line in the toolpath file (1-based), when known.
    pub line: Option<usize>,
}

/// The verification report.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct VerifyReport {
    /// The toolpath file, when there is one.
    pub toolpath: Option<PathBuf>,
    /// The part file, when there is one.
    pub part: Option<PathBuf>,
    /// Report settings.
    pub config: ReportConfig,
    /// Measurement settings, when the caller gave them.
    pub settings: Option<MeasureSettings>,
    /// Refined design vertices checked.
    pub vertices: usize,
    /// Vertices with a measured deviation.
    pub measured: usize,
    /// Vertices no swept surface reached (excess ≥ `L_out`).
    pub unmachined: usize,
    /// Deepest gouge, `max(0, −min signed)` (mm, ≥ 0).
    pub max_gouge_mm: f64,
    /// Largest measured excess, `max(0, max signed)` (mm, ≥ 0; unmachined not included).
    pub max_excess_mm: f64,
    /// Mean signed deviation over measured vertices (mm).
    pub mean_mm: f64,
    /// Median signed deviation (mm; nearest rank).
    pub p50_mm: f64,
    /// 95th percentile (mm; nearest rank).
    pub p95_mm: f64,
    /// 99th percentile (mm; nearest rank).
    pub p99_mm: f64,
    /// 1st percentile (mm; nearest rank): the gouge side.
    pub p01_mm: f64,
    /// Counts against ± tolerance.
    pub tolerance_counts: ToleranceCounts,
    /// Finer bands.
    pub bands: Vec<Band>,
    /// Worst gouges, deepest first (only signed < 0).
    pub worst_gouges: Vec<WorstLocation>,
    /// Worst excess, largest first (only signed > 0).
    pub worst_excess: Vec<WorstLocation>,
}

impl VerifyReport {
    /// True when some gouge is deeper than `tolerance_mm`.
    pub fn gouge_exceeds(&self, tolerance_mm: f64) -> bool {
        self.max_gouge_mm > tolerance_mm
    }
}

/// Nearest-rank percentile of sorted values (`p` in 0..=100).
fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let rank = ((p / 100.0) * sorted.len() as f64).ceil().max(1.0) as usize;
    sorted[rank.min(sorted.len()) - 1]
}

/// Builds the report from per-vertex deviations. `move_lines[m]` is the source line of
/// move `m` (pass `&[]` when unknown). Deterministic: sums and sorts run in vertex order.
pub fn build_report(
    devs: &[Deviation],
    move_lines: &[Option<usize>],
    cfg: &ReportConfig,
    settings: Option<MeasureSettings>,
) -> VerifyReport {
    let tol = cfg.tolerance_mm;
    let values: Vec<f64> = devs.iter().filter_map(|d| d.signed_mm).collect();
    let mut sorted = values.clone();
    // Equal under `total_cmp` means bit-identical: any sort gives the same order.
    sorted.par_sort_unstable_by(f64::total_cmp);
    let measured = values.len();
    let mean = if measured > 0 {
        values.iter().sum::<f64>() / measured as f64
    } else {
        0.0
    };
    let mut counts = ToleranceCounts {
        gouge: 0,
        within: 0,
        excess: 0,
    };
    for &v in &values {
        if v < -tol {
            counts.gouge += 1;
        } else if v > tol {
            counts.excess += 1;
        } else {
            counts.within += 1;
        }
    }
    let edges: Vec<f64> = cfg.band_edges_tol.iter().map(|k| k * tol).collect();
    let mut bands: Vec<Band> = (0..=edges.len())
        .map(|b| Band {
            lo_mm: (b > 0).then(|| edges[b - 1]),
            hi_mm: edges.get(b).copied(),
            count: 0,
        })
        .collect();
    for &v in &values {
        let b = edges.partition_point(|&e| e <= v);
        bands[b].count += 1;
    }
    let locate = |d: &Deviation, kind: Finding| WorstLocation {
        kind,
        position: d.position.to_array(),
        normal: d.normal.to_array(),
        signed_mm: d.signed_mm.unwrap_or(f64::NAN),
        move_index: d.source_move,
        line: d
            .source_move
            .and_then(|m| move_lines.get(m as usize).copied().flatten()),
    };
    let worst = |kind: Finding| {
        let mut idx: Vec<usize> = devs
            .iter()
            .enumerate()
            .filter(|(_, d)| match (kind, d.signed_mm) {
                (Finding::Gouge, Some(v)) => v < 0.0,
                (Finding::Excess, Some(v)) => v > 0.0,
                _ => false,
            })
            .map(|(i, _)| i)
            .collect();
        let key = |i: &usize| {
            let v = devs[*i].signed_mm.unwrap_or(0.0);
            if kind == Finding::Gouge { v } else { -v }
        };
        idx.par_sort_unstable_by(|a, b| key(a).total_cmp(&key(b)).then(a.cmp(b)));
        let mut out: Vec<WorstLocation> = Vec::new();
        let sep2 = cfg.worst_separation_mm * cfg.worst_separation_mm;
        for i in idx {
            if out.len() >= cfg.worst_n {
                break;
            }
            let p = devs[i].position;
            if out
                .iter()
                .any(|w| glam::DVec3::from_array(w.position).distance_squared(p) < sep2)
            {
                continue;
            }
            out.push(locate(&devs[i], kind));
        }
        out
    };
    VerifyReport {
        toolpath: None,
        part: None,
        config: cfg.clone(),
        settings,
        vertices: devs.len(),
        measured,
        unmachined: devs.len() - measured,
        max_gouge_mm: sorted.first().map_or(0.0, |&v| (-v).max(0.0)),
        max_excess_mm: sorted.last().map_or(0.0, |&v| v.max(0.0)),
        mean_mm: mean,
        p50_mm: percentile(&sorted, 50.0),
        p95_mm: percentile(&sorted, 95.0),
        p99_mm: percentile(&sorted, 99.0),
        p01_mm: percentile(&sorted, 1.0),
        tolerance_counts: counts,
        bands,
        worst_gouges: worst(Finding::Gouge),
        worst_excess: worst(Finding::Excess),
    }
}

/// Why an output file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// Creating or writing the file failed.
    #[error("{}: cannot write: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// The inputs do not fit together (e.g. one deviation per vertex expected).
    #[error("{}: {message}", path.display())]
    Mismatch {
        /// The file that was to be written.
        path: PathBuf,
        /// What does not fit.
        message: String,
    },
    /// The image could not be encoded.
    #[error("{}: cannot encode image: {message}", path.display())]
    Encode {
        /// The file.
        path: PathBuf,
        /// The encoder's message.
        message: String,
    },
}
