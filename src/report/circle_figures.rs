//! The report's words on what the figures mean: the warning on G when the tool did not run
//! at the programmed feed over the measured revolution, and a circle test's Ballbar figures
//! (servo mismatch, squareness, scale mismatch), each a number only when the data can
//! separate it and the reason otherwise.

use std::fmt::Write as _;

use super::html::esc;
use super::run::CircleFigures;
use crate::measure::feed::AT_FEED_TOLERANCE;
use crate::measure::BallbarResult;

/// The warning on G for a run off its feed; empty at feed or without a nominal feed.
pub fn feed_warning(ballbar: &BallbarResult) -> String {
    match ballbar.feed {
        Some(f) if !f.at_feed => format!(
            "<p class=\"warning\" data-warning=\"feed\" style=\"color:#b00\">⚠ G is not that of a circle at the programmed \
             feed: over the measured revolution the tool ran at {:.0} to {:.0} mm/min, more than {:.0} % \
             off F. Lengthen the lead-in, or lower F to what the machine holds on this path.</p>\n",
            f.feed_min_mm_min,
            f.feed_max_mm_min,
            100.0 * AT_FEED_TOLERANCE
        ),
        _ => String::new(),
    }
}

/// One figure: its value with `digits` decimals and `unit`, or "not measured" and why.
fn figure(value: Option<f64>, digits: usize, unit: &str, why: Option<&String>) -> String {
    match value {
        Some(v) => format!("{v:+.digits$} {unit}"),
        None => format!(
            "not measured: {}",
            why.map_or("not in this folder", |w| w.as_str())
        ),
    }
}

/// A circle test's Ballbar figures as a table.
pub fn circle_figures_table(c: &CircleFigures) -> String {
    let why = |field: &str| c.not_measured.get(field);
    let rows = [
        (
            "servo-mismatch",
            "servo mismatch T_u − T_v",
            figure(c.servo_mismatch_ms, 3, "ms", why("servo_mismatch_ms")),
        ),
        (
            "servo-mismatch-pp",
            "its oval, peak-to-peak",
            figure(c.servo_mismatch_pp_um, 2, "µm", why("servo_mismatch_pp_um"))
                .trim_start_matches('+')
                .to_string(),
        ),
        (
            "squareness",
            "squareness",
            match c.squareness_urad {
                Some(v) => format!("{v:+.2} µrad ({v:+.2} µm/m)"),
                None => figure(None, 0, "", why("squareness_urad")),
            },
        ),
        (
            "scale-mismatch",
            "scale mismatch ε_u − ε_v",
            figure(c.scale_mismatch_ppm, 2, "ppm", why("scale_mismatch_ppm")),
        ),
    ];
    let mut out = String::from("<table class=\"circle-figures\">\n<tr><th>figure</th><th>value</th></tr>\n");
    for (key, name, value) in rows {
        let _ = writeln!(
            out,
            "<tr><td>{}</td><td data-circle=\"{key}\">{}</td></tr>",
            esc(name),
            esc(&value)
        );
    }
    out.push_str("</table>\n");
    if let Some(s) = c.servo_scale_ppm.filter(|s| s.abs() >= 0.005) {
        let _ = writeln!(
            out,
            "<p class=\"note\">The scale mismatch is the cos 2θ term less {s:+.2} ppm, the apparent \
             scale mismatch the measured servo mismatch makes at this feed (first-order loops).</p>"
        );
    }
    out.push_str(
        "<p class=\"note\">From the trace's 2θ terms (docs/ballbar.md): a servo mismatch is the oval \
         at 45° that flips with the direction, squareness the one that does not, so both need a CCW and \
         a CW run.</p>\n",
    );
    out
}
