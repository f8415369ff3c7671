//! **study::param** — `mtsim study`: the servo simulation over any scenario or machine key.
//! Inputs: a study file (base scenario, keys by dotted path, grid or random sampling).
//! Outputs: one row per point (G, F, H, B and spikes per axis, check verdict, status), its summary, plots and page.

pub mod evaluate;
pub mod page;
pub mod plots;
pub mod random;
pub mod spec;
pub mod stats;
pub mod table;

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::input::overrides::ScenarioTree;
use evaluate::Row;
use spec::{Sampling, StudyFile, StudySpec};
use stats::Share;

/// A study ready to run: its spec, the base scenario's tree, the machine's axes and points.
#[derive(Clone, Debug)]
pub struct Study {
    pub spec: StudySpec,
    pub tree: ScenarioTree,
    pub header: StudyHeader,
    pub points: Vec<Vec<f64>>,
}

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

impl Study {
    /// Loads the study file and its base scenario, makes the points, and checks that every
    /// key names a key of the scenario or its machine (with the first point's values).
    /// `samples` replaces a random study's `samples` (a smaller trial run of the same study).
    pub fn load(path: &Path, g_limit_um: Option<f64>, samples: Option<usize>) -> Result<Study> {
        let mut spec = StudySpec::load(path)?;
        if let Some(n) = samples {
            if !spec.random || !(1..=spec::MAX_POINTS).contains(&n) {
                return Err(crate::error::Error::usage(format!(
                    "--samples {n}: expected 1 to {} points of a random study (uniform, normal)",
                    spec::MAX_POINTS
                )));
            }
            spec.file.samples = Some(n);
        }
        let tree = ScenarioTree::read(&spec.scenario)?;
        let base = crate::input::scenario::Scenario::from_text(
            &tree.path,
            &toml::to_string(&tree.tree).unwrap_or_default(),
        )?;
        let points = spec.points();
        if let Some(first) = points.first() {
            // A bad path fails at every point: say so once, up front. A bad value is the
            // point's own failure, so only "names no key" errors stop the study here.
            // A key the trees do not hold whose first point fails is a bad path too.
            if let Err(e) = tree.load_with(&spec.keys(), first) {
                if matches!(e, crate::error::Error::Usage { .. }) {
                    return Err(e);
                }
                // An error that names the key is about its value: the point's own failure.
                let message = e.to_string();
                let names_it = |k: &crate::input::overrides::KeyPath| {
                    let path = k.to_string();
                    message.contains(path.strip_prefix("machine.").unwrap_or(&path))
                };
                if let Some((key, (depth, near))) = spec
                    .keys()
                    .iter()
                    .filter(|k| !names_it(k))
                    .find_map(|k| Some((k, tree.absent(k)?)))
                {
                    let prefix = crate::input::overrides::KeyPath {
                        steps: key.steps[..depth].to_vec(),
                    };
                    let near: Vec<String> = near
                        .iter()
                        .take(3)
                        .map(|n| match depth {
                            0 => format!("`{n}`"),
                            _ => format!("`{prefix}.{n}`"),
                        })
                        .collect();
                    return Err(crate::error::Error::usage(format!(
                        "study key `{key}` names no key of the scenario {} or its machine ({e}); nearest: {}",
                        tree.path.display(),
                        near.join(", ")
                    )));
                }
            }
        }
        let header = StudyHeader {
            keys: spec.keys().iter().map(ToString::to_string).collect(),
            axes: base
                .machine
                .axes()
                .iter()
                .map(ToString::to_string)
                .collect(),
            g_limit_um: g_limit_um.or(spec.file.g_limit_um),
            study: spec.file.clone(),
        };
        Ok(Study {
            spec,
            tree,
            header,
            points,
        })
    }

    /// The rows of the points `range` (0-based), run in parallel; `done` is told of each.
    pub fn run(&self, range: std::ops::Range<usize>, done: &(dyn Fn() + Sync)) -> Vec<Row> {
        evaluate::evaluate(
            &self.tree,
            &self.spec.keys(),
            &self.header.axes,
            &self.points,
            range,
            done,
        )
    }
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

/// The files of a study, in the order they are written.
pub const ROWS_CSV: &str = "rows.csv";
pub const ROWS_PARQUET: &str = "rows.parquet";
pub const SUMMARY_FILE: &str = "study.json";
pub const PAGE_FILE: &str = "study.html";

/// Writes rows.csv, rows.parquet, study.json, the plots and study.html into `dir` (the
/// staging folder of a run) from the rows alone, so that merged shards write the same bytes
/// as one whole run. Returns the summary.
pub fn write_outputs(dir: &Path, header: &StudyHeader, rows: &[Row]) -> Result<StudySummary> {
    use crate::report::write_atomic;
    write_atomic(
        &dir.join(ROWS_CSV),
        &table::to_csv(rows, &header.keys, &header.axes)?,
    )?;
    write_atomic(
        &dir.join(ROWS_PARQUET),
        &table::to_parquet(rows, &header.keys, &header.axes)?,
    )?;
    let summary = StudySummary::of(header, rows);
    let json = serde_json::to_string_pretty(&summary).expect("plain data serializes");
    write_atomic(&dir.join(SUMMARY_FILE), format!("{json}\n").as_bytes())?;
    let mut svgs: Vec<(String, String, String)> = Vec::new();
    let grids: Vec<Vec<f64>> = header
        .study
        .vary
        .iter()
        .filter_map(|v| match spec::sampling(v) {
            Ok(Sampling::Grid(values)) => Some(values),
            _ => None,
        })
        .collect();
    match (&header.keys[..], &grids[..]) {
        ([key], [_]) => svgs.push((
            "study-response.svg".into(),
            format!("Response: G and each axis's B against {key}"),
            plots::response(rows, key, &header.axes)?,
        )),
        ([a, b], [xs, ys]) => svgs.push((
            "study-heatmap.svg".into(),
            format!("G over {a} and {b}"),
            plots::heat_map(rows, [a, b], xs, ys)?,
        )),
        _ => {}
    }
    if let (Some(limit), Some(share)) = (summary.g_limit_um, &summary.g_below_limit) {
        svgs.push((
            "study-share.svg".into(),
            format!("Share of points with G below {limit} µm"),
            plots::share(rows, limit, share)?,
        ));
    }
    if !summary.sensitivity.is_empty() {
        let ranking: Vec<(String, f64)> = summary
            .sensitivity
            .iter()
            .map(|s| (s.key.clone(), s.spearman_g))
            .collect();
        svgs.push((
            "study-sensitivity.svg".into(),
            "Which keys G depends on most".into(),
            plots::sensitivity(&ranking)?,
        ));
    }
    for (name, _, svg) in &svgs {
        write_atomic(&dir.join(name), svg.as_bytes())?;
    }
    let page = page::render(&summary, rows, &svgs);
    write_atomic(&dir.join(PAGE_FILE), page.as_bytes())?;
    Ok(summary)
}
