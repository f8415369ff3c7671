//! A batch: many scenarios (or programs) run as one study, one row per scenario with the
//! figures of `analyze`, `check` and, optionally, `simulate`.
//!
//! A scenario that cannot be read or run does not stop the batch: its row carries the
//! error. Rows are independent, so a batch is split by [`crate::study::shard`] like a sweep.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::check::limits::ViolationKind;
use crate::check::{check, CheckOptions};
use crate::error::{Error, Result};
use crate::input::scenario::Scenario;
use crate::study::reversals::analyse_scenario;
use crate::study::simulate::simulate;

/// One scenario's figures. Missing figures (an error, no scene, no simulation, no measured
/// circle) are null.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BatchRow {
    /// The scenario file, as listed.
    pub scenario: String,
    /// Why the scenario could not be run.
    pub error: Option<String>,
    /// analyze: reversals over all axes, and the closest reversals of two linear axes, deg.
    pub reversals: Option<u64>,
    pub min_linear_separation_deg: Option<f64>,
    /// check: samples, machine time (s), violations by kind.
    pub samples: Option<u64>,
    pub sim_time_s: Option<f64>,
    pub violations: Option<u64>,
    pub travel: Option<u64>,
    pub velocity: Option<u64>,
    pub acceleration: Option<u64>,
    pub collisions: Option<u64>,
    pub near_misses: Option<u64>,
    /// Smallest travel margin of a non-continuous axis, mm or deg, and that axis.
    pub min_margin: Option<f64>,
    pub min_margin_axis: Option<String>,
    /// Smallest clearance between bodies that must not touch, mm.
    pub min_clearance_mm: Option<f64>,
    /// Largest cutter engagement depth, mm.
    pub max_engagement_mm: Option<f64>,
    /// simulate: ball-bar G, F max, F min, H (um) and the number of spikes and steps.
    pub circular_deviation_um: Option<f64>,
    pub radial_max_um: Option<f64>,
    pub radial_min_um: Option<f64>,
    pub hysteresis_um: Option<f64>,
    pub ballbar_events: Option<u64>,
}

impl BatchRow {
    fn empty(scenario: &str) -> BatchRow {
        BatchRow {
            scenario: scenario.to_string(),
            error: None,
            reversals: None,
            min_linear_separation_deg: None,
            samples: None,
            sim_time_s: None,
            violations: None,
            travel: None,
            velocity: None,
            acceleration: None,
            collisions: None,
            near_misses: None,
            min_margin: None,
            min_margin_axis: None,
            min_clearance_mm: None,
            max_engagement_mm: None,
            circular_deviation_um: None,
            radial_max_um: None,
            radial_min_um: None,
            hysteresis_um: None,
            ballbar_events: None,
        }
    }

    /// Whether the scenario ran and fits the machine.
    pub fn is_clean(&self) -> bool {
        self.error.is_none() && self.violations == Some(0)
    }
}

/// Runs one scenario: analyze and check; with `simulate_dir`, simulate too, writing its
/// files there (without wall-clock figures, so they are reproducible).
pub fn run_scenario(listed: &str, path: &Path, simulate_dir: Option<&Path>) -> BatchRow {
    let mut row = BatchRow::empty(listed);
    if let Err(e) = fill(&mut row, path, simulate_dir) {
        row.error = Some(e.to_string());
    }
    row
}

fn fill(row: &mut BatchRow, path: &Path, simulate_dir: Option<&Path>) -> Result<()> {
    let scenario = Scenario::load(path)?;
    let analysis = analyse_scenario(&scenario)?;
    row.reversals = Some(
        analysis
            .axes
            .iter()
            .map(|a| a.reversals_deg.len() as u64)
            .sum(),
    );
    row.min_linear_separation_deg = analysis.min_linear_separation_deg();
    let report = check(&scenario, &CheckOptions::default())?;
    let count = |k: ViolationKind| report.violations.iter().filter(|v| v.kind == k).count() as u64;
    row.samples = Some(report.samples);
    row.sim_time_s = Some(report.sim_time_s);
    row.violations = Some(report.violations.len() as u64);
    row.travel = Some(count(ViolationKind::Travel));
    row.velocity = Some(count(ViolationKind::Velocity));
    row.acceleration = Some(count(ViolationKind::Acceleration));
    row.collisions = Some(count(ViolationKind::Collision));
    row.near_misses = Some(count(ViolationKind::NearMiss));
    for (axis, usage) in &report.axes {
        if let Some(m) = usage.margin {
            if row.min_margin.is_none_or(|b| m < b) {
                row.min_margin = Some(m);
                row.min_margin_axis = Some(axis.clone());
            }
        }
    }
    row.min_clearance_mm = report.min_clearance_mm;
    row.max_engagement_mm = report
        .engagement
        .iter()
        .map(|e| e.max_depth_mm)
        .reduce(f64::max);
    if let Some(dir) = simulate_dir {
        let summary = simulate(&scenario, dir, false, &|_| {})?;
        if let Some(b) = summary.ballbar {
            row.circular_deviation_um = Some(b.circular_deviation_um);
            row.radial_max_um = Some(b.radial_max_um);
            row.radial_min_um = Some(b.radial_min_um);
            row.hysteresis_um = b.hysteresis_um;
            row.ballbar_events = Some(b.events.len() as u64);
        }
    }
    Ok(())
}

/// Column names of [`to_csv`] and [`to_parquet`], in order.
pub const COLUMNS: [&str; 21] = [
    "scenario",
    "error",
    "reversals",
    "min_linear_separation_deg",
    "samples",
    "sim_time_s",
    "violations",
    "travel",
    "velocity",
    "acceleration",
    "collisions",
    "near_misses",
    "min_margin",
    "min_margin_axis",
    "min_clearance_mm",
    "max_engagement_mm",
    "circular_deviation_um",
    "radial_max_um",
    "radial_min_um",
    "hysteresis_um",
    "ballbar_events",
];

/// One CSV line per scenario; floats in their shortest exact decimal form, null as empty.
pub fn to_csv(rows: &[BatchRow]) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let err = |e: csv::Error| Error::usage(format!("cannot format the CSV: {e}"));
    w.write_record(COLUMNS).map_err(err)?;
    let f = |v: Option<f64>| v.map(|v| v.to_string()).unwrap_or_default();
    let u = |v: Option<u64>| v.map(|v| v.to_string()).unwrap_or_default();
    for r in rows {
        w.write_record([
            r.scenario.clone(),
            r.error.clone().unwrap_or_default(),
            u(r.reversals),
            f(r.min_linear_separation_deg),
            u(r.samples),
            f(r.sim_time_s),
            u(r.violations),
            u(r.travel),
            u(r.velocity),
            u(r.acceleration),
            u(r.collisions),
            u(r.near_misses),
            f(r.min_margin),
            r.min_margin_axis.clone().unwrap_or_default(),
            f(r.min_clearance_mm),
            f(r.max_engagement_mm),
            f(r.circular_deviation_um),
            f(r.radial_max_um),
            f(r.radial_min_um),
            f(r.hysteresis_um),
            u(r.ballbar_events),
        ])
        .map_err(err)?;
    }
    w.into_inner()
        .map_err(|e| Error::usage(format!("cannot format the CSV: {e}")))
}

/// The same table as Parquet, with nulls for missing figures.
pub fn to_parquet(rows: &[BatchRow]) -> Result<Vec<u8>> {
    use crate::report::parquet::{Column, Table};
    let f = |g: &dyn Fn(&BatchRow) -> Option<f64>| Column::F64(rows.iter().map(g).collect());
    let u = |g: &dyn Fn(&BatchRow) -> Option<u64>| Column::U64(rows.iter().map(g).collect());
    let s = |g: &dyn Fn(&BatchRow) -> Option<String>| Column::Str(rows.iter().map(g).collect());
    let columns = [
        s(&|r| Some(r.scenario.clone())),
        s(&|r| r.error.clone()),
        u(&|r| r.reversals),
        f(&|r| r.min_linear_separation_deg),
        u(&|r| r.samples),
        f(&|r| r.sim_time_s),
        u(&|r| r.violations),
        u(&|r| r.travel),
        u(&|r| r.velocity),
        u(&|r| r.acceleration),
        u(&|r| r.collisions),
        u(&|r| r.near_misses),
        f(&|r| r.min_margin),
        s(&|r| r.min_margin_axis.clone()),
        f(&|r| r.min_clearance_mm),
        f(&|r| r.max_engagement_mm),
        f(&|r| r.circular_deviation_um),
        f(&|r| r.radial_max_um),
        f(&|r| r.radial_min_um),
        f(&|r| r.hysteresis_um),
        u(&|r| r.ballbar_events),
    ];
    let mut table = Table::new();
    for (name, column) in COLUMNS.iter().zip(columns) {
        table = table.with(name, column);
    }
    table.to_parquet()
}
