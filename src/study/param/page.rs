//! `study.html`: the study's parameters, counts, plots and rows on one self-contained page
//! (inline SVG and CSS, no script), in the look of the run report.

use std::fmt::Write;

use crate::report::html::{esc, inline_svg, CSS};
use crate::study::param::evaluate::Row;
use crate::study::param::summary::StudySummary;
use crate::study::param::table::columns;

/// Rows listed on the page; the rest are in rows.csv.
pub const PAGE_ROWS: usize = 1000;

/// The page of a study with its `rows` and plots `(file, title, svg)`.
pub fn render(summary: &StudySummary, rows: &[Row], svgs: &[(String, String, String)]) -> String {
    let title = format!("mtsim study: {} {} points", summary.kind, summary.points);
    let mut h = format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <title>{0}</title>\n<style>{CSS}</style>\n</head>\n<body>\n<h1>{0}</h1>\n",
        esc(&title)
    );
    h.push_str("<h2>Study</h2>\n<table class=\"params\">\n");
    let mut param = |k: &str, v: String| {
        let _ = writeln!(h, "<tr><th>{}</th><td>{}</td></tr>", esc(k), esc(&v));
    };
    param("base scenario", summary.study.scenario.clone());
    if let Some(seed) = summary.study.seed {
        param("seed", seed.to_string());
    }
    for v in &summary.study.vary {
        let how = serde_json::to_value(v)
            .ok()
            .and_then(|j| j.as_object().cloned())
            .map(|o| {
                o.iter()
                    .filter(|(k, _)| *k != "key")
                    .map(|(k, v)| format!("{k} = {v}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            })
            .unwrap_or_default();
        param(&v.key, how);
    }
    param(
        "points",
        format!(
            "{} ({} ran, {} failed; {} clean, {} with check violations)",
            summary.points,
            summary.ok,
            summary.failed,
            summary.clean,
            summary.ok - summary.clean
        ),
    );
    if let (Some(lo), Some(hi)) = (summary.g_min_um, summary.g_max_um) {
        param("G range", format!("{lo:.3} to {hi:.3} µm"));
    }
    if let (Some(limit), Some(s)) = (summary.g_limit_um, &summary.g_below_limit) {
        param(
            &format!("G < {limit} µm"),
            format!(
                "{} of {} points: {:.2} % (Wilson 95 % interval {:.2} to {:.2} %)",
                s.hits,
                s.points,
                100.0 * s.share,
                100.0 * s.low,
                100.0 * s.high
            ),
        );
    }
    h.push_str("</table>\n");
    if !summary.sensitivity.is_empty() {
        h.push_str("<h2>Which keys G depends on most</h2>\n<p class=\"note\">Spearman's rank correlation ρ of each key with G over the points that ran: +1, G rises with the key; −1, G falls; near 0, G does not follow the key monotonically.</p>\n<table class=\"figures\">\n<tr><th>key</th><th>ρ</th></tr>\n");
        for s in &summary.sensitivity {
            let _ = writeln!(
                h,
                "<tr><td>{}</td><td>{:+.3}</td></tr>",
                esc(&s.key),
                s.spearman_g
            );
        }
        h.push_str("</table>\n");
    }
    for (file, title, svg) in svgs {
        let _ = writeln!(h, "<h2>{}</h2>", esc(title));
        h.push_str(&inline_svg(svg, file.trim_end_matches(".svg")));
    }
    rows_table(&mut h, summary, rows);
    h.push_str("<h2 id=\"files\">Files</h2>\n<ul class=\"files\">\n");
    for f in ["rows.csv", "rows.parquet", "study.json"]
        .into_iter()
        .chain(svgs.iter().map(|(f, _, _)| f.as_str()))
    {
        let _ = writeln!(h, "<li><a href=\"{0}\">{0}</a></li>", esc(f));
    }
    let _ = write!(
        h,
        "</ul>\n<p class=\"note\">Made by mtsim {}.</p>\n</body>\n</html>\n",
        env!("CARGO_PKG_VERSION")
    );
    h
}

fn rows_table(h: &mut String, summary: &StudySummary, rows: &[Row]) {
    let _ = writeln!(h, "<h2>Rows</h2>");
    if rows.len() > PAGE_ROWS {
        let _ = writeln!(
            h,
            "<p class=\"note\">The first {PAGE_ROWS} of {} points; all are in rows.csv.</p>",
            rows.len()
        );
    }
    h.push_str("<div class=\"wide\"><table class=\"figures\">\n<tr>");
    for c in columns(&summary.keys, &summary.axes) {
        let _ = write!(h, "<th>{}</th>", esc(&c));
    }
    h.push_str("</tr>\n");
    let f = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.4}"));
    for r in rows.iter().take(PAGE_ROWS) {
        let mut cells = vec![r.point.to_string()];
        cells.extend(r.values.iter().map(|v| format!("{v}")));
        cells.push(r.status().into());
        cells.push(r.error.clone().unwrap_or_default());
        cells.extend([r.g_um, r.f_max_um, r.f_min_um, r.h_um].map(f));
        cells.push(r.verdict().into());
        cells.push(r.violations.map_or(String::new(), |v| v.to_string()));
        for per_axis in [&r.b_um, &r.spike_um] {
            cells.extend((0..summary.axes.len()).map(|a| f(per_axis.get(a).copied().flatten())));
        }
        h.push_str("<tr>");
        for c in cells {
            let _ = write!(h, "<td>{}</td>", esc(&c));
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</table></div>\n");
}
