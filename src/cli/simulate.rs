//! `mtsim simulate`: the whole pipeline into the ball bar; trace, summary and plot files.

use std::path::Path;

use super::{print_stdout, spinner};
use crate::check::{check, CheckOptions};
use crate::error::{Result, EXIT_VIOLATIONS};
use crate::input::scenario::TraceFormat;
use crate::report::html::CHECK_FILE;
use crate::report::{write_atomic, RunDir};

pub fn run(
    path: &Path,
    out_dir: &Path,
    as_json: bool,
    (timing, with_budget): (bool, bool),
    html: bool,
    trace_format: Option<TraceFormat>,
) -> Result<i32> {
    let mut scenario = super::load_scenario(path)?;
    if let Some(format) = trace_format {
        scenario.simulate.trace_format = format;
    }
    // Everything goes into a staging folder, put in place of `out_dir` when complete.
    let run_dir = RunDir::begin(out_dir)?;
    let target = out_dir;
    let out_dir = run_dir.path();
    let bar = spinner("simulating");
    let summary =
        crate::study::simulate::simulate_with(&scenario, out_dir, timing, with_budget, &|t| {
            bar.set_message(format!("{t:.1} s of machine time"))
        })?;
    bar.finish_and_clear();
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
    // Travel, velocity, acceleration and collisions, as `check` finds them (commanded
    // positions at the planner's timing): written beside the trace for the report, and told on stderr.
    let checked = check(
        &scenario,
        &CheckOptions {
            dynamics: false,
            programmed: false,
            near_miss_mm: None,
        },
    )?;
    let json = serde_json::to_string_pretty(&checked).expect("plain data serializes");
    write_atomic(&out_dir.join(CHECK_FILE), format!("{json}\n").as_bytes())?;
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
    if let Some(rtf) = summary.realtime_factor {
        out.push_str(&format!(
            "real-time factor: {rtf:.0}x ({:.3} s wall)\n",
            summary.wall_time_s.unwrap_or(0.0)
        ));
    }
    match &summary.ballbar {
        None => out.push_str(
            "no measured circle: give the scenario a cone or circle to get ball-bar figures\n",
        ),
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
                    "{:>4} {:>6} {:>10} {:>10} {:>6} {:>5} {:>10}\n",
                    "run", "kind", "θ (deg)", "height (µm)", "axis", "conf.", "width (deg)"
                ));
                for e in &b.events {
                    out.push_str(&format!(
                        "{:>4} {:>6} {:>10.2} {:>10.2} {:>6} {:>5.2} {:>10.2}\n",
                        format!("{:?}", e.direction).to_lowercase(),
                        format!("{:?}", e.kind).to_lowercase(),
                        e.theta_deg,
                        e.height_um,
                        e.axis.map_or("?".to_string(), |a| a.to_string()),
                        e.confidence,
                        e.width_deg
                    ));
                }
            }
        }
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
