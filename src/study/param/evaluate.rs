//! One point of a study: its scenario run through the servo simulation and `check`, and
//! the figures of its row.
//!
//! Points are handed over in groups ([`evaluate_group`]): points whose scenarios differ only
//! in drive, servo, friction, backlash or error keys share their program, so a group runs
//! its drives side by side on one interpolation pass (`study::lanes`), and its `check`, which
//! reads only the commanded motion, once.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::check::{check, CheckOptions};
use crate::error::Result;
use crate::input::overrides::{KeyPath, ScenarioTree, Step};
use crate::input::scenario::Scenario;
use crate::study::diagnose::{marks, AxisMark};
use crate::study::lanes::{run_ballbar_lanes_keyed, share_keys};
use crate::study::simulate::BallbarStudy;

/// One point's row: the varied values, the ball-bar figures, per axis the reversal value B
/// and the spike height, the check's violations, and the run's status.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// 1-based, in the order of the study's points.
    pub point: u64,
    pub values: Vec<f64>,
    /// Why the point could not be run; None when it ran.
    pub error: Option<String>,
    /// G, F max, F min, H, um.
    pub g_um: Option<f64>,
    pub f_max_um: Option<f64>,
    pub f_min_um: Option<f64>,
    pub h_um: Option<f64>,
    /// Per axis of the study's machine: its reversal value B as the ball bar sees it, from
    /// the run's lost-motion signature (`study::lost_motion`), um.
    pub b_um: Vec<Option<f64>>,
    /// Per axis: mean height of the spikes attributed to that axis alone, um.
    pub spike_um: Vec<Option<f64>>,
    /// Violations `check` found (travel, velocity, acceleration, collisions).
    pub violations: Option<u64>,
}

impl Row {
    fn failed(point: u64, values: &[f64], error: String) -> Row {
        Row {
            point,
            values: values.to_vec(),
            error: Some(error),
            g_um: None,
            f_max_um: None,
            f_min_um: None,
            h_um: None,
            b_um: Vec::new(),
            spike_um: Vec::new(),
            violations: None,
        }
    }

    /// `ok` or `error`.
    pub fn status(&self) -> &'static str {
        if self.error.is_some() {
            "error"
        } else {
            "ok"
        }
    }

    /// `clean`, `violations` or empty for a point that did not run.
    pub fn verdict(&self) -> &'static str {
        match self.violations {
            Some(0) => "clean",
            Some(_) => "violations",
            None => "",
        }
    }
}

/// Whether a key varies only what the drives do (a lane group's points share the program,
/// its planning and interpolation): a machine axis's `servo`, `drive` or `friction` keys, or
/// the machine's geometric errors.
pub fn is_drive_key(key: &KeyPath) -> bool {
    let names: Vec<&str> = key
        .steps
        .iter()
        .filter_map(|s| match s {
            Step::Key(k) => Some(k.as_str()),
            Step::Index(_) => None,
        })
        .collect();
    match names[..] {
        ["machine", "axes", _, section, ..] => ["servo", "drive", "friction"].contains(&section),
        ["machine", section, ..] => ["location_errors", "error_tables"].contains(&section),
        _ => false,
    }
}

/// The points of `indices` split into groups that differ only in drive keys, in order of
/// their first point.
pub fn groups(
    keys: &[KeyPath],
    points: &[Vec<f64>],
    indices: std::ops::Range<usize>,
) -> Vec<Vec<usize>> {
    let shared: Vec<usize> = (0..keys.len())
        .filter(|&k| !is_drive_key(&keys[k]))
        .collect();
    let mut index: std::collections::HashMap<Vec<u64>, usize> = Default::default();
    let mut out: Vec<Vec<usize>> = Vec::new();
    for i in indices {
        let id: Vec<u64> = shared.iter().map(|&k| points[i][k].to_bits()).collect();
        let g = *index.entry(id).or_insert_with(|| {
            out.push(Vec::new());
            out.len() - 1
        });
        out[g].push(i);
    }
    out
}

/// Points per thread run before their figures are taken: a full pass
/// ([`crate::study::lanes::POINTS_PER_PASS`]) each, so that a random study's drives fill
/// their lane groups and the pass's shared work spreads over 64 points (the 15/10 cone's
/// 128 points on 2 threads hold about 170 MB of traces; docs/performance.md).
const POINTS_PER_CHUNK_PER_THREAD: usize = 64;

/// The figures of one group of points, in its order: the ball-bar studies of
/// [`crate::study::lanes::run_ballbar_lanes`] (each equal to its point's single run), and
/// `check` once for each set of points with the same setpoints
/// ([`crate::study::lanes::share_key`]: `check` sees the commanded motion and the axis
/// limits, which the drive keys do not change). `done` is called once per point.
pub fn evaluate_group(scenarios: &[Scenario], done: &(dyn Fn() + Sync)) -> Vec<Result<Figures>> {
    // A failed check is not kept: each of its points runs it again and carries its error.
    let mut checked: std::collections::HashMap<String, u64> = Default::default();
    // A point's study holds its traces until its figures are taken, so the group runs in
    // chunks of a few passes per thread: memory stays that of a chunk, not of the group.
    let chunk = POINTS_PER_CHUNK_PER_THREAD * rayon::current_num_threads().max(1);
    let mut out = Vec::with_capacity(scenarios.len());
    for part in scenarios.chunks(chunk) {
        // The keys group the points into passes and their checks: made once for both.
        let keys = share_keys(part);
        let studies = run_ballbar_lanes_keyed(part, &keys, &|_| {});
        let violations: Vec<Result<u64>> = part
            .iter()
            .zip(keys)
            .map(|(scenario, key)| match checked.get(&key) {
                Some(&v) => Ok(v),
                None => check(scenario, &CheckOptions::default()).map(|r| {
                    let v = r.violations.len() as u64;
                    checked.insert(key, v);
                    v
                }),
            })
            .collect();
        // The figures (the spike analysis above all) on every core, not on this thread
        // alone while the pool waits.
        out.par_extend(part.par_iter().zip(studies).zip(violations).map(
            |((scenario, study), violations)| {
                let figures = study.and_then(|s| figures_from(scenario, &s, violations?));
                done();
                figures
            },
        ));
    }
    out
}

/// What one run gives a row.
#[derive(Clone, Debug, PartialEq)]
pub struct Figures {
    pub g_um: f64,
    pub f_max_um: f64,
    pub f_min_um: f64,
    pub h_um: Option<f64>,
    /// Per axis of the machine, in its order: the reversal value B from the run's
    /// lost-motion signature (`study::lost_motion::reversal_b`), um.
    pub b_um: Vec<(String, Option<f64>)>,
    pub spikes: Vec<AxisMark>,
    pub violations: u64,
}

/// One point's figures from its ball-bar study and its check's violation count.
fn figures_from(scenario: &Scenario, study: &BallbarStudy, violations: u64) -> Result<Figures> {
    let result = study.result()?.ok_or_else(|| {
        crate::error::Error::invalid(&scenario.path, "a study needs a measured circle: a cone, a circle or a file program with [program.cone]")
    })?;
    let (_, spikes) = marks(&result);
    let b_um = study
        .lost_motion_b
        .iter()
        .map(|r| (r.axis.clone(), r.b_um))
        .collect();
    Ok(Figures {
        g_um: result.circular_deviation_um,
        f_max_um: result.radial_max_um,
        f_min_um: result.radial_min_um,
        h_um: result.hysteresis_um,
        b_um,
        spikes,
        violations,
    })
}

/// The rows of the points `indices`: each scenario built from `tree` with its values, the
/// groups evaluated in parallel. A point that fails carries its error; the others run.
pub fn evaluate(
    tree: &ScenarioTree,
    keys: &[KeyPath],
    axes: &[String],
    points: &[Vec<f64>],
    indices: std::ops::Range<usize>,
    done: &(dyn Fn() + Sync),
) -> Vec<Row> {
    let groups = groups(keys, points, indices);
    let mut rows: Vec<Row> = groups
        .par_iter()
        .flat_map_iter(|group| {
            let built: Vec<(usize, Result<Scenario>)> = group
                .iter()
                .map(|&i| (i, tree.load_with(keys, &points[i])))
                .collect();
            let (ok, bad): (Vec<_>, Vec<_>) = built.into_iter().partition(|(_, s)| s.is_ok());
            let scenarios: Vec<Scenario> = ok
                .iter()
                .map(|(_, s)| s.as_ref().expect("ok").clone())
                .collect();
            let figures = evaluate_group(&scenarios, done);
            let mut rows: Vec<Row> = ok
                .iter()
                .zip(figures)
                .map(|((i, _), f)| row_of(*i, &points[*i], axes, f))
                .collect();
            for (i, s) in bad {
                done();
                let e = s.err().expect("partitioned");
                rows.push(Row::failed(i as u64 + 1, &points[i], message(&e)));
            }
            rows
        })
        .collect();
    rows.sort_by_key(|r| r.point);
    rows
}

fn row_of(i: usize, values: &[f64], axes: &[String], figures: Result<Figures>) -> Row {
    let f = match figures {
        Ok(f) => f,
        Err(e) => return Row::failed(i as u64 + 1, values, message(&e)),
    };
    let finite = |v: f64| v.is_finite().then_some(v);
    let mean_of = |marks: &[AxisMark], axis: &str| {
        let h: Vec<f64> = marks
            .iter()
            .filter(|m| m.axis == axis)
            .map(|m| m.height_um)
            .collect();
        (!h.is_empty()).then(|| h.iter().sum::<f64>() / h.len() as f64)
    };
    Row {
        point: i as u64 + 1,
        values: values.to_vec(),
        error: None,
        g_um: finite(f.g_um),
        f_max_um: finite(f.f_max_um),
        f_min_um: finite(f.f_min_um),
        h_um: f.h_um.and_then(finite),
        b_um: axes
            .iter()
            .map(|a| f.b_um.iter().find(|(x, _)| x == a).and_then(|(_, b)| *b))
            .collect(),
        spike_um: axes.iter().map(|a| mean_of(&f.spikes, a)).collect(),
        violations: Some(f.violations),
    }
}

/// An error as one line of a row: its message, with the study's `machine.` for the
/// scenario's `machine_overrides.`.
fn message(e: &crate::error::Error) -> String {
    use crate::error::Error;
    let text = match e {
        Error::AtSource(s) => s.message.clone(),
        Error::Located { message, .. } => message.clone(),
        other => other.to_string(),
    };
    text.replace("machine_overrides.", "machine.")
        .replace('\n', " ")
}
