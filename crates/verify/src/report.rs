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
/// The index in ascending order of the nearest-rank `p`-th percentile of `n > 0` values.
fn rank_of(n: usize, p: f64) -> usize {
    let rank = ((p / 100.0) * n as f64).ceil().max(1.0) as usize;
    rank.min(n) - 1
}

/// The least value, the 1st, 50th, 95th and 99th nearest-rank percentiles and the
/// greatest of `values` (0 each when empty), by selection instead of a sort: each is the
/// value the sorted order puts at its rank (equal under `total_cmp` means bit-identical).
fn order_statistics(mut values: Vec<f64>) -> [f64; 6] {
    let n = values.len();
    if n == 0 {
        return [0.0; 6];
    }
    let ranks = [
        0,
        rank_of(n, 1.0),
        rank_of(n, 50.0),
        rank_of(n, 95.0),
        rank_of(n, 99.0),
        n - 1,
    ];
    let mut out = [0.0; 6];
    // Ascending ranks: each selection works on what lies above the previous one.
    let mut from = 0;
    for (o, &r) in out.iter_mut().zip(&ranks) {
        if r < from {
            // The same rank as the previous one.
            *o = values[r];
            continue;
        }
        let (_, &mut v, _) = values[from..].select_nth_unstable_by(r - from, f64::total_cmp);
        *o = v;
        from = r + 1;
    }
    out
}

/// An integer that orders as `x` does under `f64::total_cmp` (its own definition).
fn total_key(x: f64) -> i64 {
    let b = x.to_bits() as i64;
    b ^ (((b >> 63) as u64) >> 1) as i64
}

/// The first `want` of the items `i < n` with a key (`key(i)`) in ascending `(key, i)`
/// order that `keep` accepts (it sees them in that order, and is told which it kept): a
/// block of the least items after those seen at a time, doubling from `block`, each
/// gathered in one parallel pass without listing the rest. The order is the full sort's.
fn take_in_order(
    n: usize,
    key: impl Fn(usize) -> Option<f64> + Sync,
    want: usize,
    block: usize,
    mut keep: impl FnMut(usize) -> bool,
) -> usize {
    use std::collections::BinaryHeap;
    // Candidates `(key, index)`, all distinct.
    let (mut after, mut block, mut kept) = (None::<(i64, usize)>, block.max(1), 0);
    while kept < want {
        // Max-heaps of at most `block`: the greatest kept on top, to be replaced.
        let least = (0..n)
            .into_par_iter()
            .filter_map(|i| {
                key(i)
                    .map(|k| (total_key(k), i))
                    .filter(|c| after.is_none_or(|a| *c > a))
            })
            .fold(BinaryHeap::new, |mut h, c| {
                if h.len() < block {
                    h.push(c);
                } else if h.peek().is_some_and(|top| c < *top) {
                    h.pop();
                    h.push(c);
                }
                h
            })
            .reduce(BinaryHeap::new, |mut a, b| {
                for c in b {
                    a.push(c);
                    if a.len() > block {
                        a.pop();
                    }
                }
                a
            })
            .into_sorted_vec();
        for &c in &least {
            if kept >= want {
                break;
            }
            kept += usize::from(keep(c.1));
            after = Some(c);
        }
        if least.len() < block {
            break;
        }
        block *= 2;
    }
    kept
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
    // The values in vertex order (sums run in that order), and their summary beside the
    // worst locations.
    let values: Vec<f64> = devs.par_iter().filter_map(|d| d.signed_mm).collect();
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
        // Worst first (ties by vertex), each at least the separation from those before.
        let key = |i: usize| match (kind, devs[i].signed_mm) {
            (Finding::Gouge, Some(v)) if v < 0.0 => Some(v),
            (Finding::Excess, Some(v)) if v > 0.0 => Some(-v),
            _ => None,
        };
        let mut out: Vec<WorstLocation> = Vec::new();
        let sep2 = cfg.worst_separation_mm * cfg.worst_separation_mm;
        take_in_order(devs.len(), key, cfg.worst_n, 64, |i| {
            let p = devs[i].position;
            let apart = out
                .iter()
                .all(|w| glam::DVec3::from_array(w.position).distance_squared(p) >= sep2);
            if apart {
                out.push(locate(&devs[i], kind));
            }
            apart
        });
        out
    };
    let ((measured, mean, counts, bands, stats), (worst_gouges, worst_excess)) = rayon::join(
        || {
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
            (measured, mean, counts, bands, order_statistics(values))
        },
        || rayon::join(|| worst(Finding::Gouge), || worst(Finding::Excess)),
    );
    let [least, p01, p50, p95, p99, greatest] = stats;
    VerifyReport {
        toolpath: None,
        part: None,
        config: cfg.clone(),
        settings,
        vertices: devs.len(),
        measured,
        unmachined: devs.len() - measured,
        max_gouge_mm: (-least).max(0.0),
        max_excess_mm: greatest.max(0.0),
        mean_mm: mean,
        p50_mm: p50,
        p95_mm: p95,
        p99_mm: p99,
        p01_mm: p01,
        tolerance_counts: counts,
        bands,
        worst_gouges,
        worst_excess,
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

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The nearest-rank percentile of sorted values: the reference.
    fn percentile(sorted: &[f64], p: f64) -> f64 {
        if sorted.is_empty() {
            return 0.0;
        }
        sorted[rank_of(sorted.len(), p)]
    }

    fn values() -> impl Strategy<Value = Vec<f64>> {
        // Few distinct values as well as many: ties at the ranks.
        prop_oneof![
            proptest::collection::vec(-5.0..5.0f64, 0..400),
            proptest::collection::vec((-3i32..3).prop_map(|k| f64::from(k) * 0.25), 0..400),
        ]
    }

    proptest! {
        /// Selection gives what the full sort puts at each rank.
        #[test]
        fn order_statistics_equal_the_sorted_ranks(v in values()) {
            let mut sorted = v.clone();
            sorted.sort_unstable_by(f64::total_cmp);
            let want = if sorted.is_empty() {
                [0.0; 6]
            } else {
                [
                    sorted[0],
                    percentile(&sorted, 1.0),
                    percentile(&sorted, 50.0),
                    percentile(&sorted, 95.0),
                    percentile(&sorted, 99.0),
                    sorted[sorted.len() - 1],
                ]
            };
            prop_assert_eq!(order_statistics(v), want);
        }

        /// The items `take_in_order` shows `keep`, and what it keeps, are those of a scan
        /// of the fully sorted pairs, for a `keep` that depends on what it kept before
        /// (as the worst locations' separation does). Some items have no key, and some
        /// zeros are negative (`total_cmp` puts −0 before +0).
        #[test]
        fn take_in_order_scans_as_the_full_sort(
            v in values(), want in 0usize..30, gap in 1usize..50, block in 1usize..70,
        ) {
            let key = |i: usize| match i % 7 {
                3 => None,
                5 if v[i] == 0.0 => Some(-0.0),
                _ => Some(v[i]),
            };
            let mut sorted: Vec<(f64, usize)> =
                (0..v.len()).filter_map(|i| key(i).map(|k| (k, i))).collect();
            sorted.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let keep_far = |kept: &mut Vec<usize>, i: usize| {
                let far = kept.iter().all(|&k: &usize| k.abs_diff(i) >= gap);
                if far {
                    kept.push(i);
                }
                far
            };
            let mut reference = Vec::new();
            for &(_, i) in &sorted {
                if reference.len() >= want {
                    break;
                }
                keep_far(&mut reference, i);
            }
            let mut got = Vec::new();
            // Small first blocks: several rounds.
            let n = take_in_order(v.len(), key, want, block, |i| keep_far(&mut got, i));
            prop_assert_eq!(n, got.len());
            prop_assert_eq!(got, reference);
        }
    }
}
