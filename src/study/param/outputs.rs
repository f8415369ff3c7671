//! The files of a study: rows.csv, rows.parquet, study.json, the plots and study.html,
//! written from the rows alone.

use std::path::Path;

use crate::error::Result;
use crate::study::param::evaluate::Row;
use crate::study::param::spec::{self, Sampling};
use crate::study::param::summary::{StudyHeader, StudySummary};
use crate::study::param::{page, plots, table};

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
