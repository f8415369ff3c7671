//! The report's words on what the figures mean: the warning on G when the tool did not run
//! at the programmed feed over the measured revolution, and a circle test's Ballbar figures
//! (servo mismatch, squareness, scale mismatch), each a number only when the data can
//! separate it and the reason otherwise. Plain text: the page escapes and places it.

use super::run::CircleFigures;
use crate::measure::feed::AT_FEED_TOLERANCE;
use crate::measure::BallbarResult;

/// The warning on G for a run off its feed; None at feed or without a nominal feed.
pub fn feed_warning(ballbar: &BallbarResult) -> Option<String> {
    let f = ballbar.feed.filter(|f| !f.at_feed)?;
    Some(format!(
        "⚠ G is not that of a circle at the programmed feed: over the measured revolution the tool \
         ran at {:.0} to {:.0} mm/min, more than {:.0} % off F. Lengthen the lead-in, or lower F to \
         what the machine holds on this path.",
        f.feed_min_mm_min,
        f.feed_max_mm_min,
        100.0 * AT_FEED_TOLERANCE
    ))
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

/// A circle test's Ballbar figures: (key, name, value or why not) per row.
pub fn circle_figure_rows(c: &CircleFigures) -> Vec<(&'static str, &'static str, String)> {
    let why = |field: &str| c.not_measured.get(field);
    vec![
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
    ]
}

/// The notes under the figures: the apparent scale mismatch taken out (when there is one),
/// and where the figures come from.
pub fn circle_figure_notes(c: &CircleFigures) -> Vec<String> {
    let mut notes = Vec::new();
    if let Some(s) = c.servo_scale_ppm.filter(|s| s.abs() >= 0.005) {
        notes.push(format!(
            "The scale mismatch is the cos 2θ term less {s:+.2} ppm, the apparent scale mismatch \
             the measured servo mismatch makes at this feed (first-order loops)."
        ));
    }
    notes.push(
        "From the trace's 2θ terms (docs/ballbar.md): a servo mismatch is the oval at 45° that \
         flips with the direction, squareness the one that does not, so both need a CCW and a CW \
         run."
            .to_string(),
    );
    notes
}
