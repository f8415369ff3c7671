//! `report.html`: one self-contained page per run folder, for people to open.
//!
//! Renders a [`RunFolder`] (what `simulate` wrote: the summary, `test.json`, `check.json`,
//! the trace, `ballbar.svg`, and `placement.svg` / `sweep-*.svg` when present) with its
//! [`Diagnosis`] into one HTML file with inline SVG and CSS: no network, no JavaScript.
//! Sections: test parameters (ISO 230-4, 5.2), the figures (G, F, H per direction and
//! bi-directional), the polar plot, deviation against θ, each axis's position, velocity and
//! following error against θ with its reversal angles (the paper's Figs. 5 and 11), the mark
//! table with attribution, the diagnoses, the limits and collision summary, and links to the
//! files beside it. The page depends only on its inputs (and the `date` given), so the same
//! run gives the same bytes. Nothing is computed here but the layout: the figures and marks
//! come from the ball bar, the findings from `study::diagnose`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::plot::{self, Chart, Mark as ChartMark, Marker, Series};
pub use super::run::CHECK_FILE;
use super::run::{
    file_names, svg_texts, AxisMarks, AxisReversal, Diagnosis, Finding, MachineReversal, Mark,
    RunFolder,
};
use super::trace::Trace;
use crate::check::CheckReport;
use crate::error::Result;
use crate::input::program::Direction;
use crate::measure::ballbar::EventKind;
use crate::measure::BallbarResult;
use crate::Axis;

/// The file a report is written to, in the run folder.
pub const REPORT_FILE: &str = "report.html";

/// A position plot whose range is below this (mm or deg) shows one value: ten times the
/// trace's rounding.
const POSITION_RESOLUTION: f64 = 1e-5;

/// Points per curve after decimation (per direction).
const BUCKETS: usize = 900;

pub use super::escape::esc;

/// An SVG document as an inline element: without the XML prolog, with a class and a
/// `data-plot` name (for tests), scaled to the page width.
pub fn inline_svg(svg: &str, name: &str) -> String {
    let start = svg.find("<svg").unwrap_or(0);
    let body = &svg[start..];
    let body = body.replacen(
        "<svg",
        &format!("<svg class=\"plot\" data-plot=\"{}\"", esc(name)),
        1,
    );
    // A viewBox so that the plot scales with the page.
    let with_box = match (attr(&body, "width"), attr(&body, "height")) {
        (Some(w), Some(h)) if !body[..body.find('>').unwrap_or(0)].contains("viewBox") => body
            .replacen(
                "<svg",
                &format!("<svg viewBox=\"0 0 {w} {h}\" preserveAspectRatio=\"xMinYMin meet\""),
                1,
            ),
        _ => body,
    };
    format!("<figure>{with_box}</figure>\n")
}

fn attr(svg: &str, name: &str) -> Option<String> {
    let head = &svg[..svg.find('>')?];
    let key = format!(" {name}=\"");
    let i = head.find(&key)? + key.len();
    let j = head[i..].find('"')? + i;
    Some(head[i..j].to_string())
}

fn fmt_opt(v: Option<f64>, digits: usize, unit: &str) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{x:.digits$} {unit}").trim_end().to_string(),
        _ => "–".to_string(),
    }
}

fn axis_unit(axis: Axis) -> (&'static str, &'static str, &'static str, f64) {
    // (position unit, velocity unit, following-error unit, following-error scale)
    if axis.is_rotary() {
        ("deg", "deg/min", "mdeg", 1e3)
    } else {
        ("mm", "mm/min", "µm", 1e3)
    }
}

fn direction_colour(direction: &str) -> plotters::style::RGBColor {
    if direction == "cw" {
        plot::CW
    } else {
        plot::CCW
    }
}

/// "ccw" or "cw".
fn direction_name(d: Direction) -> String {
    format!("{d:?}").to_lowercase()
}

fn kind_name(kind: EventKind) -> &'static str {
    match kind {
        EventKind::Spike => "spike",
        EventKind::Step => "step",
    }
}

/// One finding in words.
fn finding_text(finding: &Finding) -> String {
    match finding {
        Finding::NoCircle => "No measured circle: the run has no ball-bar figures.".to_string(),
        Finding::DominantSpot {
            direction,
            theta_deg: spot,
            g_um: g_run,
            g_without_um: g_rest,
        } => format!(
            "One spot dominates G ({} run): the deviation at θ = {spot:.1}° makes G = {g_run:.2} µm; \
             without ±5° around it G would be {g_rest:.2} µm. Look at that spot (a transient, \
             a reversal spike or a program artefact) before reading G as the machine's contouring error.",
            direction.to_uppercase()
        ),
        Finding::Elliptical {
            direction,
            amplitude_um: amp,
            long_axis_deg: dir,
        } => format!(
            "Elliptical shape ({} run): 2θ component {amp:.2} µm, long axis at {dir:.0}°. \
             In a planar test a long axis near 45° or 135° points to a servo gain mismatch \
             between the two axes, near 0° or 90° to a scale mismatch; on a cone it also \
             holds the rotary axes' share.",
            direction.to_uppercase()
        ),
        Finding::AxisMarks(g) => axis_marks_text(g),
        Finding::Unattributed {
            numbers,
            largest_um,
        } => format!(
            "Marks {} (up to {largest_um:.2} µm) sit where no axis reverses within 3°: look for \
             a block boundary, a feed change, a lost motion taken up before its reversal (inertia \
             against little friction), or the start and end of the measured revolution.",
            numbers_text(numbers)
        ),
        Finding::Hysteresis { h_um: h } => format!(
            "Hysteresis H = {h:.2} µm between the CW and CCW runs: lost motion that changes sign with \
             the direction (backlash, servo lag, friction)."
        ),
        Finding::RadiusOffset { direction, r0_um: r0 } => format!(
            "Mean radius {r0:+.2} µm off the bar length ({} run): servo lag shortens the \
             radius of a contoured circle (radial error ≈ −v²/(2 Kv² R) without feedforward); \
             a scale error changes it too.",
            direction.to_uppercase()
        ),
        Finding::BlockSawtooth => "The fine sawtooth with a period of one program block (strongest where the rotary axes \
             turn fastest, on the 15/10 cone between about 150° and 210°) is real, not an artefact of \
             the plot: without tool-centre-point control the axes move linearly in joint space between \
             block end points, and the tool tip sags off the cone between them. Its height falls with \
             the square of the block length (4× the segments: 1/16 of the sag); the same sag is the \
             cutter engagement depth `check` reports."
            .to_string(),
        Finding::Nothing => "Nothing stands out: no marks above noise.".to_string(),
    }
}

/// "#1, #3, #4".
fn numbers_text(numbers: &[usize]) -> String {
    let list: Vec<String> = numbers.iter().map(|n| format!("#{n}")).collect();
    list.join(", ")
}

/// A rotary axis letter (its lengths are in deg).
fn is_rotary_letter(axis: &str) -> bool {
    matches!(axis, "A" | "B" | "C")
}

/// What the machine file says about `axis`'s lost motion `m`, for a reversal step.
fn lost_motion_text(axis: &str, m: &MachineReversal) -> String {
    let (scale, unit, digits) = if is_rotary_letter(axis) {
        (1.0, "deg", 5)
    } else {
        (1e3, "µm", 2)
    };
    let v = |x: f64| format!("{:.digits$} {unit}", x * scale);
    if m.backlash > 0.0 {
        format!(
            "the machine file gives {axis} a backlash of {} (B = {} with the elastic part): \
             backlash compensation on {axis} removes the backlash part.",
            v(m.backlash),
            v(m.b)
        )
    } else if m.elastic > 0.0 {
        format!(
            "{axis}'s drive has no backlash: the step is friction's elastic lost motion, the \
             drive winding up by the friction at rest (2 Fc/k = {}). Backlash compensation does \
             not remove it; reversal (friction) compensation or a stiffer drive reduces it.",
            v(m.elastic)
        )
    } else {
        format!(
            "the machine file gives {axis} no lost motion (no backlash, no friction wind-up): \
             the step comes from elsewhere (a transient at the reversal, servo lag)."
        )
    }
}

/// The marks of one axis and kind in words: what the axis reversing there points to.
fn axis_marks_text(g: &AxisMarks) -> String {
    let marks = format!(
        "{} {}",
        if g.numbers.len() == 1 {
            "mark"
        } else {
            "marks"
        },
        numbers_text(&g.numbers)
    );
    let which = if g.axis.contains('/') {
        format!(
            "{} reversals ({} reverse too close together for the trace to tell them apart)",
            g.axis,
            g.axis.replace('/', " and ")
        )
    } else {
        format!("{} reversals", g.axis)
    };
    match g.kind {
        EventKind::Spike => format!(
            "Reversal spikes at {which}, {marks}, up to {:.2} µm: lost motion from friction \
             (stick-slip, the quadrant glitch) and servo lag. Friction compensation or more \
             velocity feedforward on {} reduces them.",
            g.largest_um,
            g.axis.replace('/', " or ")
        ),
        EventKind::Step => {
            let b = g
                .b_um
                .map_or(String::new(), |b| format!("; B from the trace {b:.2} µm"));
            let cause = if g.machine.is_empty() {
                format!(
                    "lost motion of {} (backlash or friction's elastic wind-up: this folder does \
                     not say which the machine has).",
                    g.axis
                )
            } else {
                let parts: Vec<String> = g
                    .machine
                    .iter()
                    .map(|(a, m)| lost_motion_text(a, m))
                    .collect();
                parts.join(" ")
            };
            format!(
                "Steps at {which}, {marks}, up to {:.2} µm{b}: {cause}",
                g.largest_um
            )
        }
    }
}

fn row(out: &mut String, key: &str, value: &str) {
    let _ = writeln!(out, "<tr><th>{}</th><td>{}</td></tr>", esc(key), esc(value));
}

fn test_table(folder: &RunFolder, date: Option<&str>) -> String {
    let mut out = String::from("<table class=\"params\">\n");
    match &folder.test {
        Some(t) => {
            row(
                &mut out,
                "Machine",
                &format!("{} ({})", t.machine, t.kinematics),
            );
            if !t.chain_geometry.is_empty() {
                row(&mut out, "Chain", &t.chain_geometry.join("; "));
            }
            row(&mut out, "Machine file", &t.machine_file);
            row(&mut out, "Test", &t.test);
            row(&mut out, "Scenario", &t.scenario);
            if let Some(p) = &t.program_file {
                row(&mut out, "Program file", p);
            }
            row(&mut out, "Geometry", &t.geometry);
            row(&mut out, "Radius", &fmt_opt(t.radius_mm, 3, "mm"));
            row(&mut out, "Feed", &fmt_opt(t.feed_mm_min, 0, "mm/min"));
            row(
                &mut out,
                "Direction",
                &t.directions.join(", ").to_uppercase(),
            );
            row(&mut out, "Plane", &t.plane);
            row(
                &mut out,
                "Position (centre)",
                &t.position_mm.map_or("as programmed".to_string(), |p| {
                    format!("X {} Y {} Z {} mm", p[0], p[1], p[2])
                }),
            );
            row(
                &mut out,
                "Start arc / overshoot arc",
                &match (t.start_arc_deg, t.overshoot_arc_deg) {
                    (Some(s), Some(o)) => format!("{s}° / {o}°"),
                    _ => match t.measure_lines {
                        Some([a, b]) => format!("as programmed; measured lines {a}..{b}"),
                        None => "as programmed".to_string(),
                    },
                },
            );
            for c in &t.compensation {
                row(&mut out, "Compensation", c);
            }
            row(
                &mut out,
                "Interpolation",
                if t.tcp {
                    "tool-centre-point control"
                } else {
                    "joint space between blocks"
                },
            );
            row(
                &mut out,
                "Sample period",
                &format!(
                    "{} ms (trace: every {} sample{})",
                    t.sample_period_ms,
                    t.trace_every,
                    if t.trace_every == 1 { "" } else { "s" }
                ),
            );
            let date = date
                .map(str::to_string)
                .or_else(|| t.date.clone())
                .unwrap_or_else(|| {
                    "not recorded (simulate --no-timing; report --date)".to_string()
                });
            row(&mut out, "Date", &date);
            row(&mut out, "mtsim version", &t.mtsim_version);
            row(&mut out, "Scenario hash (XXH64)", &t.scenario_hash);
        }
        None => {
            row(
                &mut out,
                "Test parameters",
                "not recorded: this folder has no test.json (made before mtsim wrote it)",
            );
            if let Some(d) = date {
                row(&mut out, "Date", d);
            }
        }
    }
    let s = &folder.summary;
    row(
        &mut out,
        "Machine time",
        &format!(
            "{} ({} interpolation periods)",
            fmt_opt(Some(s.sim_time_s), 2, "s"),
            s.setpoints
        ),
    );
    out.push_str("</table>\n");
    out
}

fn figures_table(ballbar: Option<&BallbarResult>) -> String {
    let Some(b) = ballbar else {
        return "<p>No measured circle: no ball-bar figures.</p>\n".to_string();
    };
    let mut out = String::from(
        "<table class=\"figures\">\n<tr><th>run</th><th>G circular deviation (µm)</th>\
         <th>F max (µm)</th><th>F min (µm)</th><th>H hysteresis (µm)</th><th>centre offset a, b (µm)</th>\
         <th>mean radius error (µm)</th><th>noise (µm)</th><th>samples</th></tr>\n",
    );
    let f = |v: f64, d: usize| fmt_opt(Some(v), d, "");
    for r in &b.runs {
        let _ = writeln!(
            out,
            "<tr><td>{}</td><td class=\"figure\" data-figure=\"G-{0}\">{}</td><td>{}</td><td>{}</td><td>–</td>\
             <td>{}, {}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(&direction_name(r.direction).to_uppercase()),
            f(r.circular_deviation_um, 2),
            f(r.radial_max_um, 2),
            f(r.radial_min_um, 2),
            f(r.centring.a_um, 2),
            f(r.centring.b_um, 2),
            f(r.centring.r0_um, 2),
            f(r.noise_um, 3),
            r.samples,
        );
    }
    let _ = writeln!(
        out,
        "<tr class=\"total\"><td>bi-directional</td><td class=\"figure\" data-figure=\"G\">{}</td>\
         <td class=\"figure\" data-figure=\"F-max\">{}</td><td class=\"figure\" data-figure=\"F-min\">{}</td>\
         <td class=\"figure\" data-figure=\"H\">{}</td><td></td><td></td><td></td><td></td></tr>",
        f(b.circular_deviation_um, 2),
        f(b.radial_max_um, 2),
        f(b.radial_min_um, 2),
        b.hysteresis_um
            .map_or("– (one direction)".to_string(), |h| f(h, 2)),
    );
    out.push_str("</table>\n");
    out
}

fn marks_table(marks: &[Mark]) -> String {
    if marks.is_empty() {
        return "<p>No spikes or steps above noise.</p>\n".to_string();
    }
    let mut out = String::from(
        "<table class=\"marks\">\n<tr><th>#</th><th>kind</th><th>run</th><th>peak θ (deg)</th>\
         <th>start θ (deg)</th><th>extent (deg)</th><th>height (µm)</th><th>width (deg)</th><th>axis</th>\
         <th>candidates</th><th>confidence</th><th>attribution</th></tr>\n",
    );
    for m in marks {
        let e = &m.event;
        let attribution = match (e.axis, m.reversal) {
            (Some(a), Some((t, d))) => format!("{a} reverses at {t:.2}° ({d:.2}° from the start)"),
            (Some(a), None) => format!("axis {a}"),
            (None, _) => "none: no axis reverses within 3°".to_string(),
        };
        let candidates = if e.ambiguous {
            format!("{} (cannot be told apart)", e.candidates)
        } else {
            e.candidates.to_string()
        };
        let _ = writeln!(
            out,
            "<tr data-mark=\"{}\"><td>{}</td><td>{}</td><td>{}</td><td class=\"peak\">{:.2}</td><td>{:.2}</td>\
             <td>{:.2}</td><td>{:+.2}</td><td>{:.2}</td><td>{}</td><td class=\"candidates\">{}</td>\
             <td>{:.2}</td><td>{}</td></tr>",
            m.number,
            m.number,
            kind_name(e.kind),
            esc(&direction_name(e.direction).to_uppercase()),
            e.peak_deg,
            e.theta_deg,
            e.extent_deg,
            e.height_um,
            e.width_deg,
            esc(&e.axis.map_or("?".to_string(), |a| a.to_string())),
            esc(&candidates),
            e.confidence,
            esc(&attribution)
        );
    }
    out.push_str("</table>\n");
    out
}

/// The summary a ball-bar user reads first: G, F, H, what each mechanism adds to G per
/// axis (ranked) and each axis's reversal value B.
fn summary_section(folder: &RunFolder) -> String {
    let s = &folder.summary;
    let Some(b) = &s.ballbar else {
        return "<p>No measured circle: no ball-bar figures.</p>\n".to_string();
    };
    let mut out = format!(
        "<p class=\"summary\">G <b data-summary=\"G\">{:.2}</b> µm · F max <b data-summary=\"F-max\">{:+.2}</b> µm · \
         F min <b data-summary=\"F-min\">{:+.2}</b> µm · H <b data-summary=\"H\">{}</b></p>\n",
        b.circular_deviation_um,
        b.radial_max_um,
        b.radial_min_um,
        b.hysteresis_um
            .map_or("– (one direction)".to_string(), |h| format!("{h:.2} µm")),
    );
    for pole in &s.poles {
        // The pole is named before the figures are read (a swing there makes G).
        let _ = writeln!(
            out,
            "<p class=\"warning\" data-warning=\"pole\">Pole passed: {}</p>",
            esc(pole)
        );
    }
    if let Some(w) = super::circle_figures::feed_warning(b) {
        let _ = writeln!(
            out,
            "<p class=\"warning\" data-warning=\"feed\" style=\"color:#b00\">{}</p>",
            esc(&w)
        );
    }
    out.push_str(&super::budget_table::budget_section(
        s.error_budget.as_ref(),
    ));
    out.push_str(&reversal_b_table(&s.reversal_b, &s.reversal_values));
    out
}

/// A circle test's servo mismatch, squareness and scale (`data-circle` cells), each a
/// number or why not, and the notes under them.
fn circle_figures_table(c: &super::run::CircleFigures) -> String {
    let mut out =
        String::from("<table class=\"circle-figures\">\n<tr><th>figure</th><th>value</th></tr>\n");
    for (key, name, value) in super::circle_figures::circle_figure_rows(c) {
        let _ = writeln!(
            out,
            "<tr><td>{}</td><td data-circle=\"{key}\">{}</td></tr>",
            esc(name),
            esc(&value)
        );
    }
    out.push_str("</table>\n");
    for note in super::circle_figures::circle_figure_notes(c) {
        let _ = writeln!(out, "<p class=\"note\">{}</p>", esc(&note));
    }
    out
}

/// Each axis's reversal value B from the trace, beside the machine file's.
fn reversal_b_table(
    reversal_b: &[AxisReversal],
    machine: &std::collections::BTreeMap<String, MachineReversal>,
) -> String {
    if reversal_b.is_empty() {
        return String::new();
    }
    let mut out = String::from(
        "<table class=\"reversal-b\">\n<tr><th>axis</th><th>B from the trace (µm)</th>\
         <th>step at the bar (µm)</th><th>reversals measured</th><th>machine file: backlash + elastic = B</th></tr>\n",
    );
    for r in reversal_b {
        let (scale, unit, digits) = if is_rotary_letter(&r.axis) {
            (1.0, "deg", 5)
        } else {
            (1e3, "µm", 2)
        };
        let machine_b = machine.get(&r.axis).map_or("–".to_string(), |m| {
            format!(
                "{:.digits$} + {:.digits$} = {:.digits$} {unit}",
                m.backlash * scale,
                m.elastic * scale,
                m.b * scale
            )
        });
        let _ = writeln!(
            out,
            "<tr><td>{}</td><td class=\"figure\" data-b=\"{}\">{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(&r.axis),
            esc(&r.axis),
            r.b_um.map_or("– (the bar does not see its reversals)".to_string(), |b| format!("{b:.2}")),
            r.step_um.map_or("–".to_string(), |s| format!("{s:.2}")),
            r.reversals,
            machine_b
        );
    }
    out.push_str(
        "</table>\n<p class=\"note\">B (ISO 230-2 reversal value) from the trace: the lost motion the \
         axis's own backlash and friction runs make on the bar, fitted with how much the bar sees the \
         axis where it moves; along the axis for a linear axis, of arc at the bar's length for a rotary \
         one; 0 for an axis without backlash and dry friction. Step at the bar: that lost motion's \
         peak-to-valley on the bar.</p>\n",
    );
    out
}

pub(crate) fn check_section(check: &CheckReport) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "<p>{} samples, {}.</p>",
        check.samples,
        esc(check.timing.describe())
    );
    out.push_str(
        "<table class=\"limits\">\n<tr><th>axis</th><th>used</th><th>travel</th><th>margin</th>\
         <th>peak velocity / limit</th><th>peak acceleration / limit</th></tr>\n",
    );
    for (name, u) in &check.axes {
        let (unit, vunit, aunit) = if u.axis.is_rotary() {
            ("deg", "deg/min", "deg/s²")
        } else {
            ("mm", "mm/min", "mm/s²")
        };
        let f = |v: f64, d: usize| fmt_opt(Some(v), d, "");
        let _ = writeln!(
            out,
            "<tr><td>{}</td><td>{} … {} {unit}</td><td>{} … {} {unit}</td><td>{}</td><td>{} / {} {vunit}</td>\
             <td>{} / {} {aunit}</td></tr>",
            esc(name),
            f(u.min, 3),
            f(u.max, 3),
            f(u.limit_min, 3),
            f(u.limit_max, 3),
            u.margin
                .map_or("continuous".to_string(), |m| fmt_opt(Some(m), 3, unit)),
            f(u.peak_velocity_per_min, 0),
            f(u.velocity_limit_per_min, 0),
            f(u.peak_acceleration_per_s2, 0),
            f(u.acceleration_limit_per_s2, 0),
        );
    }
    out.push_str("</table>\n<ul>\n");
    if let (Some(c), Some([a, b])) = (check.min_clearance_mm, &check.min_clearance_bodies) {
        let _ = writeln!(
            out,
            "<li>Smallest clearance: {c:.3} mm ({} / {}).</li>",
            esc(a),
            esc(b)
        );
    }
    let collided = check
        .violations
        .iter()
        .any(|v| v.kind == crate::check::limits::ViolationKind::Collision);
    if let (true, Some(t)) = (collided, check.collision_depth_tolerance) {
        let _ = writeln!(
            out,
            "<li>Collision depths: each is a sample's, and no sample of the collision is deeper \
             by more than {} mm + {} % of it ([scene] depth_tolerance_mm, \
             depth_tolerance_relative).</li>",
            t.mm,
            100.0 * t.relative
        );
    }
    for e in &check.engagement {
        let _ = writeln!(
            out,
            "<li>Cutting: {} in {}, deepest {:.4} mm. Expected, not a collision: the cone-frustum test \
             cuts the cone; between block end points the joint-space interpolation lets the tip sag \
             into the nominal surface, by an amount that falls with the square of the block length.</li>",
            esc(&e.bodies[0]),
            esc(&e.bodies[1]),
            e.max_depth_mm
        );
    }
    if check.violations.is_empty() {
        out.push_str("<li>Clean: no violations and no near misses.</li>\n");
    }
    for x in &check.violations {
        let what = match (&x.axis, &x.bodies) {
            (Some(a), _) => a.to_string(),
            (None, Some(b)) => b.join(" / "),
            (None, None) => String::new(),
        };
        let _ = writeln!(
            out,
            "<li class=\"violation\">{} {}: line {}, t {:.3}…{:.3} s, worst {:.3}{}</li>",
            x.kind.name(),
            esc(&what),
            x.line,
            x.time_start_s,
            x.time_end_s,
            x.worst,
            x.limit.map_or(String::new(), |l| format!(", limit {l:.3}")),
        );
    }
    out.push_str("</ul>\n");
    out
}

/// Deviation against θ, both directions, with the numbered marks.
fn deviation_chart(marks: &[Mark], trace: &Trace) -> Result<String> {
    let mut chart = Chart::new(
        "Deviation from the nominal circle, centred (least squares), against θ",
        "θ (deg)",
        "deviation (µm)",
        1100,
        360,
    );
    chart.x_range = Some((0.0, 360.0));
    chart.x_tick = Some(30.0);
    for run in &trace.runs {
        let points = sorted_by_theta(&run.theta_deg, &run.deviation_centred_um, 1.0);
        chart.series.push(Series {
            label: format!("{} run", run.direction.to_uppercase()),
            colour: direction_colour(&run.direction),
            points: plot::decimate_min_max(&points, BUCKETS),
            dots: false,
        });
    }
    for m in marks {
        chart.marks.push(ChartMark {
            x: m.event.peak_deg.rem_euclid(360.0),
            y: m.trace_um.unwrap_or(0.0),
            label: m.number.to_string(),
            colour: m.event.axis.map_or(plot::INK, plot::axis_colour),
        });
    }
    chart.to_svg()
}

/// (θ, y) pairs, θ wrapped into [0, 360), sorted by θ, with a gap (NaN) where θ jumps.
fn sorted_by_theta(theta: &[f64], y: &[f64], scale: f64) -> Vec<(f64, f64)> {
    let mut p: Vec<(f64, f64)> = theta
        .iter()
        .zip(y)
        .filter(|(t, v)| t.is_finite() && v.is_finite())
        .map(|(t, v)| (t.rem_euclid(360.0), v * scale))
        .collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out = Vec::with_capacity(p.len());
    for (i, q) in p.iter().enumerate() {
        if i > 0 && q.0 - p[i - 1].0 > 5.0 {
            out.push((f64::NAN, f64::NAN));
        }
        out.push(*q);
    }
    out
}

/// Position, velocity and following error of each axis against θ (the paper's Figs. 5, 11).
fn axis_charts(folder: &RunFolder, trace: &Trace) -> Result<Vec<(String, String)>> {
    let revs = &folder.summary.reversals_deg;
    let mut out = Vec::new();
    for (k, &axis) in trace.axes.iter().enumerate() {
        let (pu, vu, fu, fscale) = axis_unit(axis);
        let quantities: [(&str, String, String); 3] = [
            (
                "position",
                format!("{axis} position ({pu})"),
                format!("{axis} actual position"),
            ),
            (
                "velocity",
                format!("{axis} velocity ({vu})"),
                format!("{axis} velocity"),
            ),
            (
                "following-error",
                format!("{axis} following error ({fu})"),
                format!("{axis} following error (commanded − actual)"),
            ),
        ];
        for (q, (name, y_label, title)) in quantities.iter().enumerate() {
            let mut chart = Chart::new(title, "θ (deg)", y_label, 540, 300);
            chart.x_range = Some((0.0, 360.0));
            chart.x_tick = Some(60.0);
            if q == 0 {
                // Positions: the trace rounds to 1e-6 mm or deg; a few of those is flat.
                chart.y_resolution = POSITION_RESOLUTION;
            }
            for run in &trace.runs {
                let y: Vec<f64> = match q {
                    0 => run.actual[k].clone(),
                    1 => run.velocity_per_min(k),
                    _ => run.following_error[k].iter().map(|v| v * fscale).collect(),
                };
                let points = sorted_by_theta(&run.theta_deg, &y, 1.0);
                chart.series.push(Series {
                    label: run.direction.to_uppercase(),
                    colour: direction_colour(&run.direction),
                    points: plot::decimate_min_max(&points, BUCKETS / 2),
                    dots: false,
                });
            }
            for t in revs.get(&axis.to_string()).into_iter().flatten() {
                chart.markers.push(Marker {
                    x: t.rem_euclid(360.0),
                    label: format!("{axis} rev. {:.1}°", t.rem_euclid(360.0)),
                    colour: plot::axis_colour(axis),
                });
            }
            out.push((format!("{axis}-{name}"), chart.to_svg()?));
        }
    }
    Ok(out)
}

pub const CSS: &str = "body{font-family:sans-serif;color:#1e1e1e;max-width:1180px;margin:1.5em auto;padding:0 1em;line-height:1.4}\
h1{font-size:1.5em}h2{font-size:1.2em;border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:2em}\
table{border-collapse:collapse;margin:.5em 0}th,td{border:1px solid #ddd;padding:.25em .6em;text-align:left;vertical-align:top}\
table.params th{background:#f5f5f5;width:16em}table.figures td,table.marks td,table.limits td,table.budget td,table.reversal-b td{text-align:right}.summary{font-size:1.15em}\
tr.total{font-weight:bold}figure{margin:.5em 0}svg.plot{width:100%;height:auto;display:block}\
.axes{display:grid;grid-template-columns:repeat(3,1fr);gap:.5em}.axes figure{margin:0}\
li.violation{color:#b00}.note{color:#555;font-size:.95em}\
div.wide{overflow-x:auto;max-width:100%}pre{white-space:pre-wrap;overflow-wrap:anywhere;background:#f7f7f7;padding:.5em}";

/// The HTML text of the report of `folder` with its `diagnosis`; `date` (YYYY-MM-DD)
/// overrides the recorded one.
pub fn render(folder: &RunFolder, diagnosis: &Diagnosis, date: Option<&str>) -> Result<String> {
    let name = folder
        .test
        .as_ref()
        .map(|t| t.scenario.clone())
        .unwrap_or_else(|| folder.dir.display().to_string());
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <title>mtsim report: {}</title>\n<style>{CSS}</style>\n</head>\n<body>\n\
         <h1>mtsim report: {0}</h1>\n",
        esc(&name)
    );
    h.push_str("<h2 id=\"summary\">Summary</h2>\n");
    h.push_str(&summary_section(folder));
    h.push_str("<h2 id=\"test\">Test parameters (ISO 230-4)</h2>\n");
    h.push_str(&test_table(folder, date));
    h.push_str("<h2 id=\"figures\">Figures (ISO 230-4)</h2>\n");
    h.push_str(&figures_table(folder.summary.ballbar.as_ref()));
    h.push_str(
        "<p class=\"note\">G: circular deviation, the radial band of the centred trace. F: radial deviation, \
         the largest and smallest radius against the nominal. H: circular hysteresis between the CW and \
         CCW runs, about the common centre. Centring: least-squares centre offset a (cos θ), b (sin θ) \
         and mean radius error r0, removed before the figures.</p>\n",
    );
    if let Some(c) = folder
        .summary
        .diagnostics
        .as_ref()
        .and_then(|d| d.circle.as_ref())
    {
        h.push_str("<h2 id=\"circle-figures\">Servo mismatch, squareness, scale</h2>\n");
        h.push_str(&circle_figures_table(c));
    }
    if let Some((_, svg)) = folder.svgs.iter().find(|(n, _)| n == "ballbar.svg") {
        h.push_str("<h2 id=\"polar\">Polar plot</h2>\n");
        h.push_str(&inline_svg(svg, "polar"));
    }
    if let Some(trace) = folder.trace.as_ref().filter(|t| !t.runs.is_empty()) {
        h.push_str("<h2 id=\"linear\">Deviation against θ</h2>\n");
        h.push_str(&inline_svg(
            &deviation_chart(&diagnosis.marks, trace)?,
            "deviation",
        ));
        h.push_str(
            "<h2 id=\"axes\">Axis position, velocity and following error against θ</h2>\n\
             <p class=\"note\">One row per axis, as in the paper's Figs. 5 and 11; the vertical lines are \
             the axis's reversal angles from the program. Velocity: central difference of the actual \
             position over the trace's time.</p>\n",
        );
        for (i, (name, svg)) in axis_charts(folder, trace)?.iter().enumerate() {
            if i % 3 == 0 {
                h.push_str("<div class=\"axes\">\n");
            }
            h.push_str(&inline_svg(svg, name));
            if i % 3 == 2 {
                h.push_str("</div>\n");
            }
        }
    }
    h.push_str("<h2 id=\"marks\">Marks</h2>\n");
    h.push_str(&marks_table(&diagnosis.marks));
    if let Some(cut) = &folder.cut {
        let cut: super::cut::CutJson = serde_json::from_value(cut.clone()).map_err(|e| {
            crate::error::Error::invalid(
                &folder.dir.join(super::cut::CUT_JSON),
                format!("unexpected contents: {e}"),
            )
        })?;
        h.push_str(&super::cut_html::run_section(
            &cut.figures,
            cut.budget.as_ref(),
        ));
    }
    h.push_str("<h2 id=\"diagnoses\">Diagnoses</h2>\n<ul class=\"diagnoses\">\n");
    for finding in &diagnosis.findings {
        let _ = writeln!(h, "<li>{}</li>", esc(&finding_text(finding)));
    }
    h.push_str("</ul>\n");
    h.push_str("<h2 id=\"check\">Limits and collisions</h2>\n");
    match &folder.check {
        Some(c) => h.push_str(&check_section(c)),
        None => h.push_str("<p>Not checked: the folder has no check.json.</p>\n"),
    }
    for (file, svg) in folder.svgs.iter().filter(|(n, _)| n != "ballbar.svg") {
        let _ = writeln!(h, "<h2>{}</h2>", esc(file));
        h.push_str(&inline_svg(svg, file.trim_end_matches(".svg")));
    }
    h.push_str("<h2 id=\"files\">Files</h2>\n<ul class=\"files\">\n");
    for f in &folder.files {
        let _ = writeln!(h, "<li><a href=\"{0}\">{0}</a></li>", esc(f));
    }
    h.push_str("</ul>\n<p class=\"note\">Made by mtsim ");
    h.push_str(env!("CARGO_PKG_VERSION"));
    h.push_str(".</p>\n</body>\n</html>\n");
    Ok(h)
}

/// The page of a `sweep` output folder: its plots and links.
pub fn render_study(dir: &Path, svgs: &[(String, String)], files: &[String]) -> String {
    let mut h = format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <title>mtsim study: {0}</title>\n<style>{CSS}</style>\n</head>\n<body>\n\
         <h1>mtsim study: {0}</h1>\n",
        esc(&dir.display().to_string())
    );
    for (name, svg) in svgs {
        let title = if name == "placement.svg" {
            "Placement map: where the test fits".to_string()
        } else {
            format!("Reversal angles: {}", name.trim_end_matches(".svg"))
        };
        let _ = writeln!(h, "<h2>{}</h2>", esc(&title));
        h.push_str(&inline_svg(svg, name.trim_end_matches(".svg")));
    }
    h.push_str("<h2 id=\"files\">Files</h2>\n<ul class=\"files\">\n");
    for f in files {
        let _ = writeln!(h, "<li><a href=\"{0}\">{0}</a></li>", esc(f));
    }
    let _ = write!(
        h,
        "</ul>\n<p class=\"note\">Made by mtsim {}.</p>\n</body>\n</html>\n",
        env!("CARGO_PKG_VERSION")
    );
    h
}

/// Writes the page of a `sweep` output folder (its plots and links) to `dir/report.html`
/// and returns its path; None when `dir` holds no `placement.svg` or `sweep-*.svg`.
pub fn write_study_page(dir: &Path) -> Result<Option<PathBuf>> {
    let files = file_names(dir, &[".csv", ".json", ".svg"]).unwrap_or_default();
    let svgs = svg_texts(dir, &files, &|n| {
        n == "placement.svg" || (n.starts_with("sweep-") && n.ends_with(".svg"))
    });
    if svgs.is_empty() {
        return Ok(None);
    }
    let path = dir.join(REPORT_FILE);
    super::write_atomic(&path, render_study(dir, &svgs, &files).as_bytes())?;
    Ok(Some(path))
}

/// Writes the page of the run folder `folder` with its `diagnosis` to `report.html` there,
/// atomically, and returns its path.
pub fn write_run_page(
    folder: &RunFolder,
    diagnosis: &Diagnosis,
    date: Option<&str>,
) -> Result<PathBuf> {
    let path = folder.dir.join(REPORT_FILE);
    super::write_atomic(&path, render(folder, diagnosis, date)?.as_bytes())?;
    Ok(path)
}
