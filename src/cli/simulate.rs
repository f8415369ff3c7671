//! `mtsim simulate`: the whole pipeline into the ball bar; trace, summary and plot files.

use std::path::Path;
use std::time::Instant;

use super::{print_stdout, spinner};
use crate::check::of_run::{self, RunCheck};
use crate::error::{Result, EXIT_VIOLATIONS};
use crate::input::scenario::TraceFormat;
use crate::report::html::CHECK_FILE;
use crate::report::{write_atomic, RunDir};
use crate::study::contour_budget::ContourBudget;

pub fn run(
    path: &Path,
    out_dir: &Path,
    as_json: bool,
    (timing, with_budget): (bool, bool),
    html: bool,
    (trace_format, cut): (Option<TraceFormat>, bool),
) -> Result<i32> {
    let started = Instant::now();
    let mut stages = Stages::default();
    let mut scenario = super::load_scenario(path)?;
    stages.read_s = started.elapsed().as_secs_f64();
    if let Some(format) = trace_format {
        scenario.simulate.trace_format = format;
    }
    // Everything goes into a staging folder, put in place of `out_dir` when complete.
    let run_dir = RunDir::begin(out_dir)?.reads(&[path]);
    let target = out_dir;
    let out_dir = run_dir.path();
    let bar = spinner("simulating");
    let progress = |t: f64| bar.set_message(format!("{t:.1} s of machine time"));
    let beside = |dir: &Path| crate::study::cut::cut_beside(&scenario, dir, with_budget, &progress);
    // Travel, velocity, acceleration and collisions of the run's own setpoints, checked as
    // they are made (`check.json`, for the report; no second plan of the program).
    let theta = of_run::theta_of(&scenario);
    let mut run_check = RunCheck::new(&scenario, &theta)?;
    let summary = crate::study::simulate::simulate_beside(
        &scenario,
        out_dir,
        (timing, with_budget),
        (
            cut.then_some(&beside as crate::study::simulate::BesideRun<'_>),
            Some(&mut run_check),
        ),
        &progress,
    )?;
    bar.finish_and_clear();
    stages.simulate_s = started.elapsed().as_secs_f64() - stages.read_s;
    for w in &summary.warnings {
        super::warn(w);
    }
    super::detail(
        1,
        &format!(
            "simulated {:.2} s of machine time in {} interpolation periods; wrote {}, {}, {}, {} and {}",
            summary.sim_time_s,
            summary.setpoints,
            scenario.simulate.trace_format.file_name(),
            crate::study::simulate::SUMMARY_FILE,
            crate::study::simulate::PLOT_FILE,
            crate::report::test_info::TEST_FILE,
            CHECK_FILE
        ),
    );
    // Written beside the trace for the report, and told on stderr.
    let checked = run_check.finish(summary.feed_reductions.clone());
    let json = serde_json::to_string_pretty(&checked).expect("plain data serializes");
    write_atomic(&out_dir.join(CHECK_FILE), format!("{json}\n").as_bytes())?;
    stages.check_s = started.elapsed().as_secs_f64() - stages.read_s - stages.simulate_s;
    super::detail(
        2,
        &super::check::check_table(&checked, &path.display().to_string()),
    );
    let code = if checked.is_clean() {
        0
    } else {
        super::warn(&format!(
            "the program does not fit the machine (exit code 1); `mtsim check` says:\n{}",
            super::check::check_table(&checked, &path.display().to_string())
        ));
        EXIT_VIOLATIONS
    };
    if html {
        super::report::write_page(out_dir, None)?;
    }
    run_dir.commit()?;
    let chain_events = crate::study::chain_events::chain_events(&scenario)?;
    let whole_s = started.elapsed().as_secs_f64();
    stages.files_s = whole_s - stages.read_s - stages.simulate_s - stages.check_s;
    super::detail(1, &stages.describe(whole_s));
    if as_json {
        print_stdout(&format!(
            "{}\n",
            super::chain_events::json_with_chain_events(&summary, chain_events.as_deref())
        ));
        return Ok(code);
    }
    let mut out = format!(
        "{}: {:.2} s of machine time ({} setpoints, {})\n",
        path.display(),
        summary.sim_time_s,
        summary.setpoints,
        summary
            .directions
            .iter()
            .map(|d| format!("{d:?}").to_lowercase())
            .collect::<Vec<_>>()
            .join(" + ")
    );
    out.push_str(&realtime_text(&summary, whole_s));
    match &summary.ballbar {
        None => out.push_str(&contour_text(&summary.measurements)?),
        Some(b) => {
            out.push_str(&format!(
                "ISO 230-4: circular deviation G = {:.2} µm, radial deviation F = {:+.2} / {:+.2} µm, hysteresis H = {}\n",
                b.circular_deviation_um,
                b.radial_max_um,
                b.radial_min_um,
                b.hysteresis_um.map_or("- (one direction)".to_string(), |h| format!("{h:.2} µm"))
            ));
            if b.events.is_empty() {
                out.push_str("no spikes or steps above noise\n");
            } else {
                out.push_str(&format!(
                    "{:>4} {:>6} {:>12} {:>10} {:>6} {:>5} {:>10}\n",
                    "run", "kind", "peak θ (deg)", "height (µm)", "axis", "conf.", "width (deg)"
                ));
                for e in &b.events {
                    out.push_str(&format!(
                        "{:>4} {:>6} {:>12.2} {:>10.2} {:>6} {:>5.2} {:>10.2}\n",
                        format!("{:?}", e.direction).to_lowercase(),
                        format!("{:?}", e.kind).to_lowercase(),
                        e.peak_deg,
                        e.height_um,
                        e.axis.map_or("?".to_string(), |a| a.to_string()),
                        e.confidence,
                        e.width_deg
                    ));
                }
            }
        }
    }
    if let Some(c) = summary.diagnostics.as_ref().and_then(|d| d.circle.as_ref()) {
        out.push_str(&circle_figures_text(c));
    }
    out.push_str(&super::chain_events::chain_events_text(
        chain_events.as_deref(),
    ));
    out.push_str(&format!(
        "wrote {}{}\n",
        target.display(),
        if html { " (report.html)" } else { "" }
    ));
    print_stdout(&out);
    Ok(code)
}

/// Wall time of each stage of a `simulate` command, s: what `-v` reports.
#[derive(Debug, Default)]
struct Stages {
    read_s: f64,
    simulate_s: f64,
    check_s: f64,
    files_s: f64,
}

impl Stages {
    fn describe(&self, whole_s: f64) -> String {
        format!(
            "stages (wall): read {:.3} s, simulation (interpolation, servo, ball bar, trace) {:.3} s, check {:.3} s, page, manifest and folder swap {:.3} s; whole run {whole_s:.3} s",
            self.read_s, self.simulate_s, self.check_s, self.files_s
        )
    }
}

/// A circle test's servo mismatch, squareness and scale mismatch, each a number only when
/// the data separates it, and why not otherwise.
fn circle_figures_text(c: &crate::study::diagnose::CircleDiagnostics) -> String {
    let figure = |value: f64, text: String, field: &str| {
        if value.is_finite() {
            text
        } else {
            format!(
                "not measured ({})",
                c.not_measured.get(field).map_or("", |w| w.as_str())
            )
        }
    };
    format!(
        "servo mismatch: {}\nsquareness: {}\nscale mismatch: {}\n",
        figure(
            c.servo_mismatch_ms,
            format!(
                "{:+.3} ms ({:.2} µm peak-to-peak)",
                c.servo_mismatch_ms, c.servo_mismatch_pp_um
            ),
            "servo_mismatch_ms"
        ),
        figure(
            c.squareness_urad,
            format!(
                "{:+.2} µrad ({:+.2} µm/m)",
                c.squareness_urad, c.squareness_um_per_m
            ),
            "squareness_urad"
        ),
        figure(
            c.scale_mismatch_ppm,
            format!("{:+.2} ppm", c.scale_mismatch_ppm),
            "scale_mismatch_ppm"
        ),
    )
}

/// The real-time factors, when timed: what the user waited for (the whole command, reading
/// and the check included) beside the simulation's own.
fn realtime_text(summary: &crate::study::simulate::SimulationSummary, whole_s: f64) -> String {
    let Some(rtf) = summary.realtime_factor else {
        return String::new();
    };
    format!(
        "real-time factor: {:.0}x for the whole run ({whole_s:.3} s wall: read, simulation, check, files); the simulation alone {rtf:.0}x ({:.3} s)\n",
        summary.sim_time_s / whole_s.max(1e-9),
        summary.wall_time_s.unwrap_or(0.0)
    )
}

/// What a program without a measured circle prints: its contour error and worst lines.
fn contour_text(
    measurements: &std::collections::BTreeMap<String, serde_json::Value>,
) -> Result<String> {
    let mut out = String::from(
        "no measured circle (no ball-bar figures): give the scenario a cone or circle for them\n",
    );
    if !measurements.contains_key("contour") {
        return Ok(out);
    }
    let f = crate::study::simulate::contour_figures(measurements)?;
    if f.samples == 0 {
        out.push_str("contour error: no feed move was measured\n");
        return Ok(out);
    }
    out.push_str(&format!(
        "contour error (actual tool tip to the programmed path): max {:.2} µm, RMS {:.2} µm over {} samples",
        f.max_um, f.rms_um, f.samples
    ));
    if f.max_tool_axis_error_urad > 0.0 {
        out.push_str(&format!(
            "; tool axis up to {:.1} µrad",
            f.max_tool_axis_error_urad
        ));
    }
    out.push('\n');
    let worst: Vec<String> = f
        .worst
        .iter()
        .take(5)
        .map(|w| {
            format!(
                "line {} ({:.2} µm at {:.3} s)",
                w.line, w.contour_um, w.time_s
            )
        })
        .collect();
    out.push_str(&format!("worst: {}\n", worst.join(", ")));
    let budget = measurements
        .get("contour")
        .and_then(|c| c.get("budget"))
        .and_then(|b| serde_json::from_value::<ContourBudget>(b.clone()).ok());
    if let Some(b) = budget {
        let mut rows: Vec<_> = b.rows.iter().filter(|r| r.share.abs() >= 0.005).collect();
        rows.sort_by(|x, y| y.share.total_cmp(&x.share));
        let parts: Vec<String> = rows
            .iter()
            .map(|r| {
                let axis = r
                    .axis
                    .as_deref()
                    .map_or(String::new(), |a| format!(" of {a}"));
                format!(
                    "{}{axis} {:.0} % (RMS {:.2} µm)",
                    crate::report::budget_table::mechanism_label(r.mechanism, r.axis.as_deref()),
                    100.0 * r.share,
                    r.rms_um
                )
            })
            .collect();
        out.push_str(&format!(
            "contour error budget (counterfactual runs): {}; the mechanisms together {:.0} %\n",
            parts.join(", "),
            // Rounded to whole percent, without a "-0".
            match 100.0 * b.interaction_share {
                v if v.abs() < 0.5 => 0.0,
                v => v,
            }
        ));
    }
    Ok(out)
}
