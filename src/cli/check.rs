//! `mtsim check`: limits and collisions; exit 1 on violations.

use std::path::Path;

use super::print_stdout;
use crate::check::limits::ViolationKind;
use crate::check::{check_observed, CheckOptions, CheckReport, CheckTiming, SceneQueries};
use crate::error::{Error, Result, EXIT_VIOLATIONS};

pub fn run(path: &Path, as_json: bool, options: CheckOptions, html: Option<&Path>) -> Result<i32> {
    if let Some(d) = options.near_miss_mm {
        if !(d.is_finite() && d >= 0.0) {
            return Err(Error::usage(format!(
                "--near-miss {d}: expected a clearance >= 0 mm"
            )));
        }
    }
    let scenario = super::load_scenario(path)?;
    for n in crate::program::scenario_warnings(&scenario)? {
        super::warn(&format!("{}:{}: {}", n.path.display(), n.line, n.message));
    }
    // Machine seconds checked against the run's least machine time (the planner's ramps
    // may take it past that, and the bar's length follows).
    let bar = super::progress_bar(0, "checking, s of machine time");
    let progress = |t_s: f64, least_s: f64| {
        bar.set_length(least_s.max(t_s).ceil() as u64);
        bar.set_position(t_s as u64);
    };
    let started = std::time::Instant::now();
    let report = check_observed(&scenario, &options, SceneQueries::Bounded, &progress)?;
    bar.finish_and_clear();
    for f in &report.feed_reductions {
        super::warn(&format!("feed held: {}", f.describe()));
    }
    super::detail(
        1,
        &format!(
            "checked {} samples in {:.3} s wall",
            report.samples,
            started.elapsed().as_secs_f64()
        ),
    );
    let code = if report.is_clean() {
        0
    } else {
        EXIT_VIOLATIONS
    };
    if let Some(file) = html {
        let page =
            crate::report::check_html::render_check_page(&path.display().to_string(), &report);
        crate::report::write_atomic(file, page.as_bytes())?;
    }
    let chain_events = crate::study::chain_events::chain_events(&scenario)?;
    if as_json {
        print_stdout(&format!(
            "{}\n",
            super::chain_events::json_with_chain_events(&report, chain_events.as_deref())
        ));
        return Ok(code);
    }
    let mut out = check_table(&report, &path.display().to_string());
    out.push_str(&super::chain_events::chain_events_text(
        chain_events.as_deref(),
    ));
    print_stdout(&out);
    Ok(code)
}

/// The text report of `mtsim check`.
pub fn check_table(report: &CheckReport, name: &str) -> String {
    let mut out = format!(
        "{name}: {} samples, {:.2} s of machine time, {}{}\n",
        report.samples,
        report.sim_time_s,
        report.timing.describe(),
        report
            .scene_queries
            .map_or(String::new(), |q| format!(", {q} geometric queries"))
    );
    out.push_str(&format!(
        "{:<4} {:<4} {:>21} {:>21} {:>11} {:>27} {:>23} {:>25}\n",
        "axis",
        "unit",
        "used",
        "travel",
        "margin",
        "peak/limit velocity (/min)",
        "peak/limit accel. (/s²)",
        "peak/limit jerk (/s³)"
    ));
    for (axis, u) in &report.axes {
        let unit = if "ABC".contains(axis.as_str()) {
            "deg"
        } else {
            "mm"
        };
        out.push_str(&format!(
            "{axis:<4} {unit:<4} {:>9.3}..{:<9.3} {:>9.3}..{:<9.3} {:>11} {:>15.0}/{:<11.0} {:>11.0}/{:<11.0} {:>12.0}/{:<12.0}\n",
            u.min,
            u.max,
            u.limit_min,
            u.limit_max,
            u.margin.map_or("continuous".to_string(), |m| format!("{m:.3}")),
            u.peak_velocity_per_min,
            u.velocity_limit_per_min,
            u.peak_acceleration_per_s2,
            u.acceleration_limit_per_s2,
            u.peak_jerk_per_s3,
            u.jerk_limit_per_s3,
        ));
    }
    out.push_str(match report.timing {
        CheckTiming::Programmed => {
            "accelerations and jerks: within blocks only (at programmed timing a junction is a velocity step)\n"
        }
        _ => {
            "jerk: reported, not checked (the planner bounds a junction's velocity step by the acceleration over one period)\n"
        }
    });
    for f in &report.feed_reductions {
        out.push_str(&format!("feed held: {}\n", f.describe()));
    }
    if let Some(why) = &report.scene_stand_in {
        out.push_str(&format!("note: {why}\n"));
    }
    if let (Some(c), Some(b)) = (report.min_clearance_mm, &report.min_clearance_bodies) {
        out.push_str(&format!(
            "smallest clearance: {c:.3} mm ({} / {})\n",
            b[0], b[1]
        ));
    }
    let collided = report
        .violations
        .iter()
        .any(|v| v.kind == ViolationKind::Collision);
    if let (true, Some(t)) = (collided, report.collision_depth_tolerance) {
        out.push_str(&format!(
            "collision depths: each is a sample's, and no sample of the collision is deeper \
             by more than {} mm + {} % of it ([scene] depth_tolerance_mm, \
             depth_tolerance_relative)\n",
            t.mm,
            100.0 * t.relative
        ));
    }
    for e in &report.engagement {
        out.push_str(&format!(
            "cutting: {} in {}, deepest {:.4} mm (expected, not a violation: the test cuts the \
             workpiece; without tool-centre-point control the tip sags into the nominal surface \
             between block end points, by an amount that falls with the square of the block length)\n",
            e.bodies[0], e.bodies[1], e.max_depth_mm
        ));
    }
    if report.violations.is_empty() && report.samples == 0 {
        // Nothing was checked: say so rather than "clean".
        out.push_str("nothing checked: the program has no moves\n");
        return out;
    }
    if report.violations.is_empty() {
        out.push_str("clean: no violations\n");
        return out;
    }
    out.push_str(&format!("{} violation(s):\n", report.violations.len()));
    let mut unit_named = false;
    for v in &report.violations {
        let what = match (&v.axis, &v.bodies) {
            (Some(a), _) => a.to_string(),
            (_, Some(b)) => format!("{} / {}", b[0], b[1]),
            _ => String::new(),
        };
        let time = if v.time_end_s > v.time_start_s {
            format!("t {:.3}..{:.3} s", v.time_start_s, v.time_end_s)
        } else {
            format!("t {:.3} s (one sample)", v.time_start_s)
        };
        let whole_run = v.time_start_s <= 0.0 && v.time_end_s >= report.sim_time_s;
        let span = match (v.theta_start_deg, v.theta_end_deg) {
            _ if whole_run => format!("the whole run, {time}"),
            (Some(a), Some(b)) if v.time_end_s > v.time_start_s => {
                format!("θ {a:.2}..{b:.2} deg, {time}")
            }
            (Some(a), _) => format!("θ {a:.2} deg, {time}"),
            _ => time,
        };
        let worst = match v.kind {
            ViolationKind::Collision => format!("penetration {:.3} mm", v.worst),
            ViolationKind::NearMiss => format!(
                "clearance {:.3} mm (threshold {:.1})",
                v.worst,
                v.limit.unwrap_or(0.0)
            ),
            _ => {
                let limit = v.limit.unwrap_or(f64::NAN);
                format!(
                    "worst {:.3}, limit {:.3}, excess {:.3}",
                    v.worst,
                    limit,
                    (v.worst - limit).abs()
                )
            }
        };
        out.push_str(&format!(
            "  {:<12} {:<28} {span}, line {}: {worst}\n",
            format!("{:?}", v.kind).to_lowercase(),
            what,
            v.line
        ));
        // Named once, under the first travel violation (every one carries it in JSON).
        if let Some(note) = v.other_unit.as_ref().filter(|_| !unit_named) {
            out.push_str(&format!("               {note}\n"));
            unit_named = true;
        }
    }
    out
}
