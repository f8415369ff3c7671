//! Does a measured trace belong to its scenario? Before fitting, each trace is compared with
//! the scenario's simulated revolution: its directions, its commanded axis positions at the
//! same θ (the angles and the radius of the test), and the duration of the revolution (the
//! feed). Inputs: the trace, its simulated runs. Output: `Ok`, or an error naming what differs.

use super::measured::{MeasuredPoint, MeasuredTrace};
use super::model::{Recorded, Run};
use super::noise::direction_name;
use super::result::TraceFit;
use crate::error::{Error, Result};
use crate::input::scenario::Scenario;
use crate::program::test_of;
use crate::Axis;

/// Largest commanded difference accepted: mm for linear axes, deg for rotary ones.
pub const COMMANDED_TOLERANCE: f64 = 0.01;
/// Largest relative difference of the revolution's duration accepted (beyond the trace's
/// own sampling interval, twice).
pub const DURATION_TOLERANCE: f64 = 0.02;

/// Refuses a trace whose directions, duration or commanded positions differ from the
/// scenario's (`runs`: this trace's runs, simulated), naming every difference: another feed
/// also moves the commanded corners (the planner's blending) by a few um.
pub fn check(
    scenario: &Scenario,
    trace: &MeasuredTrace,
    runs: &[&Run],
    measured: &[MeasuredPoint],
) -> Result<()> {
    let refuse = |what: String| {
        Err(Error::invalid(
            &trace.path,
            format!(
                "this trace does not belong to the scenario {}: {what}",
                scenario.path.display()
            ),
        )
        .with_help("give each scenario the trace measured with it, in the same order"))
    };
    let planned = test_of(scenario).planned_directions();
    for run in runs {
        if let Some(dirs) = &planned {
            if !dirs.contains(&run.direction) {
                return refuse(format!(
                    "the trace holds {} points, the scenario runs only {}",
                    direction_name(run.direction),
                    dirs.iter()
                        .map(|d| direction_name(*d))
                        .collect::<Vec<_>>()
                        .join(" and ")
                ));
            }
        }
        let rows: Vec<&MeasuredPoint> = run.rows.iter().map(|&i| &measured[i]).collect();
        let differences: Vec<String> = [
            duration_difference(&rows, &run.samples),
            commanded_difference(trace, &rows, &run.samples),
        ]
        .into_iter()
        .flatten()
        .collect();
        if !differences.is_empty() {
            return refuse(format!(
                "{} ({})",
                differences.join("; "),
                direction_name(run.direction)
            ));
        }
    }
    Ok(())
}

/// The sample nearest in θ (circular).
fn nearest<'a>(by_theta: &[&'a Recorded], theta: f64) -> &'a Recorded {
    let t = theta.rem_euclid(360.0);
    let i = by_theta.partition_point(|s| s.theta_deg.rem_euclid(360.0) < t);
    let n = by_theta.len();
    let dist = |s: &Recorded| {
        let d = (s.theta_deg - t).rem_euclid(360.0);
        d.min(360.0 - d)
    };
    [by_theta[i % n], by_theta[(i + n - 1) % n]]
        .into_iter()
        .min_by(|a, b| dist(a).total_cmp(&dist(b)))
        .expect("two candidates")
}

/// The largest commanded difference beyond tolerance, described; None when all agree.
fn commanded_difference(
    trace: &MeasuredTrace,
    rows: &[&MeasuredPoint],
    samples: &[Recorded],
) -> Option<String> {
    if trace.commanded_axes.is_empty() || samples.is_empty() {
        return None;
    }
    let mut by_theta: Vec<&Recorded> = samples.iter().collect();
    by_theta.sort_by(|a, b| {
        a.theta_deg
            .rem_euclid(360.0)
            .total_cmp(&b.theta_deg.rem_euclid(360.0))
    });
    let mut worst: Option<(f64, Axis, f64, f64, f64)> = None;
    for p in rows {
        let s = nearest(&by_theta, p.theta_deg);
        for &axis in &trace.commanded_axes {
            let (m, c) = (p.commanded[axis], s.commanded[axis]);
            let d = if axis.is_rotary() {
                let d = (m - c).rem_euclid(360.0);
                d.min(360.0 - d)
            } else {
                (m - c).abs()
            };
            if d > COMMANDED_TOLERANCE && worst.is_none_or(|w| d > w.0) {
                worst = Some((d, axis, p.theta_deg, m, c));
            }
        }
    }
    worst.map(|(d, axis, theta, m, c)| {
        let u = axis.unit();
        format!(
            "commanded {axis} differs by up to {d:.3} {u} (at theta {theta:.2} deg: {m:.4} {u} \
             in the trace, {c:.4} {u} in the scenario), so the test's angles or radius differ"
        )
    })
}

/// The revolution's duration against the scenario's, described when it differs.
fn duration_difference(rows: &[&MeasuredPoint], samples: &[Recorded]) -> Option<String> {
    let mut times: Vec<f64> = rows.iter().filter_map(|p| p.time_s).collect();
    if times.len() < 3 || samples.len() < 2 {
        return None;
    }
    times.sort_by(f64::total_cmp);
    let span = times[times.len() - 1] - times[0];
    let mut steps: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    steps.sort_by(f64::total_cmp);
    let dt = steps[steps.len() / 2];
    let (t0, t1) = samples.iter().fold((f64::MAX, f64::MIN), |(a, b), s| {
        (a.min(s.time_s), b.max(s.time_s))
    });
    let expected = t1 - t0;
    ((span - expected).abs() > 2.0 * dt + DURATION_TOLERANCE * expected).then(|| {
        format!(
            "the revolution lasts {span:.3} s in the trace and {expected:.3} s in the scenario, \
             so the feed differs (by a factor {:.3})",
            expected / span.max(f64::MIN_POSITIVE)
        )
    })
}

/// After the fit, the traces without commanded columns: a note for each (they were matched
/// to their scenario only weakly), and a refusal of one whose fitted bar offset exceeds its
/// own radius change (the peak-to-valley of its deviation): a constant larger than all the
/// trace varies by is no bar-length error but a trace of another test (another bar, another
/// radius, another reference).
pub fn weak_matches(
    inputs: &[(Scenario, MeasuredTrace)],
    traces: &[TraceFit],
) -> Result<Vec<String>> {
    let mut notes = Vec::new();
    for ((scenario, trace), fit) in inputs.iter().zip(traces) {
        if !trace.commanded_axes.is_empty() {
            continue;
        }
        let offset = fit.bar_offset_basic_um;
        if offset.abs() > fit.radius_change_um {
            return Err(Error::invalid(
                &trace.path,
                format!(
                    "this trace does not belong to the scenario {}: the fit needs a bar offset \
                     of {offset:+.3} um, more than the trace's own radius change ({:.3} um \
                     peak-to-valley); a trace of another test (another bar length, radius or \
                     reference) looks like this",
                    scenario.path.display(),
                    fit.radius_change_um
                ),
            )
            .with_help(
                "give each scenario the trace measured with it; mtsim's trace.csv carries the \
                 commanded columns that match it for sure",
            ));
        }
        notes.push(format!(
            "{}: no commanded axis columns (X_cmd_mm ...), so it is matched to {} only weakly: \
             by its directions{}, and by its fitted bar offset ({offset:+.3} um) against its own \
             radius change ({:.3} um); a trace of another test at the same feed would pass",
            trace.path.display(),
            scenario.path.display(),
            if trace.points.iter().any(|p| p.time_s.is_some()) {
                " and the revolution's duration"
            } else {
                ""
            },
            fit.radius_change_um
        ));
    }
    Ok(notes)
}
