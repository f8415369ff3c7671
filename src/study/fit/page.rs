//! fit.html: the fit on one self-contained page (inline SVG and CSS, no script): warnings,
//! each trace measured and fitted with its residual, the parameters with their uncertainty,
//! what the tests cannot separate, and the next test to run. Input: the report and fit.svg.

use std::fmt::Write as _;

use super::result::FitReport;
use crate::report::html::{esc, inline_svg, CSS};

/// The page's HTML text; depends only on its inputs (same fit, same bytes).
pub fn render(report: &FitReport, svg: &str) -> String {
    let mut h = format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <title>mtsim fit</title>\n<style>{CSS}</style>\n</head>\n<body>\n\
         <h1>mtsim fit: location errors of the {} machine</h1>\n",
        esc(&report.layout)
    );
    let placement = if report.placement_fitted {
        "fitted per trace (three translations)"
    } else {
        "taken as known (--placement-known)"
    };
    let _ = writeln!(
        h,
        "<p class=\"note\">Table-ball placement: {placement}. Residual RMS over all traces: {:.3} um.</p>",
        report.residual_rms_um
    );
    if !report.warnings.is_empty() || !report.cautions.is_empty() || !report.notes.is_empty() {
        h.push_str("<h2 id=\"warnings\">Warnings</h2>\n<ul class=\"warnings\">\n");
        for w in report
            .warnings
            .iter()
            .chain(&report.cautions)
            .chain(&report.notes)
        {
            let _ = writeln!(h, "<li>{}</li>", esc(w));
        }
        h.push_str("</ul>\n");
    }
    h.push_str(&traces_table(report));
    h.push_str("<h2 id=\"plots\">Measured, fitted and residual (um)</h2>\n");
    h.push_str(&inline_svg(svg, "fit"));
    h.push_str(&parameters_table(report));
    h.push_str("<h2 id=\"inseparable\">What these tests cannot separate</h2>\n");
    if report.unidentifiable.is_empty() {
        h.push_str("<p>Nothing: every parameter is separated.</p>\n");
    } else {
        h.push_str("<ul>\n");
        for n in &report.unidentifiable {
            let _ = writeln!(h, "<li>{}</li>", esc(&n.description));
        }
        h.push_str("</ul>\n");
    }
    h.push_str("<h2 id=\"next\">Next test</h2>\n");
    let next = report.suggestion.as_ref().map_or(
        "None needed: the tests separate every location error.".to_string(),
        |s| s.text.clone(),
    );
    let _ = writeln!(h, "<p>{}</p>", esc(&next));
    let _ = write!(
        h,
        "<h2 id=\"fragment\">Machine-file fragment</h2>\n<pre>{}</pre>\n\
         <p class=\"note\">Made by mtsim {}.</p>\n</body>\n</html>\n",
        esc(&report.fragment),
        env!("CARGO_PKG_VERSION")
    );
    h
}

/// One row per trace: the scenario, the residual against the noise, the bar offset.
fn traces_table(report: &FitReport) -> String {
    let mut h = String::from(
        "<h2 id=\"traces\">Traces</h2>\n<table class=\"traces\">\n<tr><th>scenario</th><th>measured</th>\
         <th>points</th><th>trace RMS (um)</th><th>residual RMS (um)</th><th>noise (um)</th>\
         <th>residual / noise</th><th>noise correlation</th><th>matched</th><th>bar offset (um)</th></tr>\n",
    );
    for t in &report.traces {
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{:.3}</td><td>{:.3}</td><td>{:.3}</td>\
             <td>{:.1}</td><td>{:.2}</td><td>{}</td><td>{}</td></tr>",
            esc(&t.scenario.display().to_string()),
            esc(&t.measured.display().to_string()),
            t.points,
            t.measured_rms_um,
            t.residual_rms_um,
            t.noise.noise_um,
            t.noise.ratio,
            t.noise.correlation,
            esc(&t.matched),
            t.bar_offset_um
                .map_or("not separable".to_string(), |b| format!("{b:+.3}"))
        );
    }
    h.push_str("</table>\n");
    h
}

/// One row per parameter: value, standard error (and the independent-sample one).
fn parameters_table(report: &FitReport) -> String {
    let mut h = String::from(
        "<h2 id=\"parameters\">Parameters</h2>\n<table class=\"parameters\">\n<tr><th>parameter</th>\
         <th>value</th><th>standard error</th><th>(independent samples)</th><th>unit</th>\
         <th>identifiable</th></tr>\n",
    );
    let v = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.3}"));
    for p in &report.parameters {
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(&p.name),
            v(p.value),
            v(p.standard_error),
            v(p.standard_error_white),
            esc(&p.unit),
            if p.identifiable { "yes" } else { "no" }
        );
    }
    h.push_str(
        "</table>\n<p class=\"note\">Standard error: the largest of the independent-sample one, the one \
         under the AR(1) model of the residual (correlated noise) and a block bootstrap along \
         theta, which holds when the residual is correlated.</p>\n",
    );
    h
}
