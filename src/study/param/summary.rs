//! What identifies a study (its header, equal in all its shards) and `study.json`: the
//! counts, the share of points below the G limit, and the keys G depends on most.

use serde::{Deserialize, Serialize};

use crate::study::param::evaluate::Row;
use crate::study::param::spec::StudyFile;
use crate::study::param::stats::{self, Share};

/// What identifies a study (equal in all its shards) and what its summary needs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StudyHeader {
    pub study: StudyFile,
    /// The varied keys, as dotted paths.
    pub keys: Vec<String>,
    /// The machine's axes, by letter.
    pub axes: Vec<String>,
    /// The G limit of the share, um (the study file's or `--g-limit-um`).
    pub g_limit_um: Option<f64>,
}

/// One key's rank correlation with G.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sensitivity {
    pub key: String,
    /// Spearman's ρ of the key's values with G over the points that ran.
    pub spearman_g: f64,
}

/// `study.json`: the study, its counts and, for a random study, the share below the limit
/// and the keys G depends on most.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StudySummary {
    pub format: String,
    pub study: StudyFile,
    /// `grid` or `random`.
    pub kind: String,
    pub keys: Vec<String>,
    pub axes: Vec<String>,
    pub points: u64,
    /// Points that ran, and that failed.
    pub ok: u64,
    pub failed: u64,
    /// Points that ran without a `check` violation.
    pub clean: u64,
    pub g_min_um: Option<f64>,
    pub g_max_um: Option<f64>,
    pub g_limit_um: Option<f64>,
    /// Points that ran with G below the limit, with the Wilson 95 % interval.
    pub g_below_limit: Option<Share>,
    /// Random study: the keys by |ρ|, largest first.
    pub sensitivity: Vec<Sensitivity>,
}

/// Format tag of `study.json`.
pub const FORMAT: &str = "mtsim-study/1";

impl StudySummary {
    pub fn of(header: &StudyHeader, rows: &[Row]) -> StudySummary {
        let ran: Vec<&Row> = rows.iter().filter(|r| r.error.is_none()).collect();
        let g: Vec<f64> = ran.iter().filter_map(|r| r.g_um).collect();
        let random = header
            .study
            .vary
            .iter()
            .any(|v| v.uniform.is_some() || v.normal.is_some());
        let g_below_limit = header.g_limit_um.and_then(|limit| {
            let hits = g.iter().filter(|&&x| x < limit).count() as u64;
            stats::wilson(hits, g.len() as u64, stats::Z95)
        });
        let mut sensitivity: Vec<Sensitivity> = Vec::new();
        if random {
            let with_g: Vec<&&Row> = ran.iter().filter(|r| r.g_um.is_some()).collect();
            let gs: Vec<f64> = with_g.iter().filter_map(|r| r.g_um).collect();
            for (k, key) in header.keys.iter().enumerate() {
                let xs: Vec<f64> = with_g.iter().map(|r| r.values[k]).collect();
                if let Some(rho) = stats::spearman(&xs, &gs) {
                    sensitivity.push(Sensitivity {
                        key: key.clone(),
                        spearman_g: rho,
                    });
                }
            }
            sensitivity.sort_by(|a, b| b.spearman_g.abs().total_cmp(&a.spearman_g.abs()));
        }
        StudySummary {
            format: FORMAT.to_string(),
            study: header.study.clone(),
            kind: if random { "random" } else { "grid" }.to_string(),
            keys: header.keys.clone(),
            axes: header.axes.clone(),
            points: rows.len() as u64,
            ok: ran.len() as u64,
            failed: (rows.len() - ran.len()) as u64,
            clean: ran.iter().filter(|r| r.violations == Some(0)).count() as u64,
            g_min_um: g.iter().copied().reduce(f64::min),
            g_max_um: g.iter().copied().reduce(f64::max),
            g_limit_um: header.g_limit_um,
            g_below_limit,
            sensitivity,
        }
    }
}
