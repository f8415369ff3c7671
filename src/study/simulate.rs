//! `mtsim simulate`: the whole pipeline into the virtual ball bar.
//!
//! For each direction: program (generated or file) → canonical moves → interpolator →
//! servo per axis (and its linear twin) → sinks: the ball bar ([`BallbarSink`]) and the
//! trace ([`TraceSink`]). The reversal study runs beside the pipeline, on the program alone;
//! its angles are what the marks in the trace are attributed to. Memory does not grow with
//! the program: moves and setpoints are consumed as they come, the ball bar keeps fixed θ
//! bins, and the trace goes to disk as it is made.

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::path::Path;
use std::rc::Rc;
use std::time::Instant;

use nalgebra::Point3;
use serde::Serialize;

use crate::check::of_run::RunCheck;
use crate::error::Result;
use crate::input::drive::si_per_unit;
use crate::input::lead_in::LeadIn;
use crate::input::program::{Direction, MeasuredLines};
use crate::input::scenario::{Scenario, TraceFormat};
use crate::measure::attribution::{sites_from_map, ReversalSite};
use crate::measure::ballbar::{analyse_events_at, BallbarResult};
use crate::measure::contour::{ContourGauge, ContourProfile};
use crate::measure::feed::{FeedMeter, FeedSeen, AT_FEED_TOLERANCE};
use crate::measure::measurement;
use crate::measure::settle::SettleGate;
use crate::measure::{BallbarSink, BarGeometry, CommandMaps};
use crate::motion::work;
use crate::motion::FeedReduction;
use crate::pipeline::{self, RunOptions, Sample, Sink, Timing};
use crate::program;
use crate::program::test_of;
use crate::report::create_dir;
use crate::report::trace::TraceSink;
use crate::study::budget::{self, BudgetDirection, BudgetPlan, BudgetRun, BudgetStepper};
use crate::study::contour_budget::ContourBudgetRuns;
use crate::study::reversals::{
    has_closed_form, reversals_deg, scenario_reversals_deg, MoveAnalysis,
};
use crate::{Axis, AxisVec};

/// What a simulation found.
#[derive(Clone, Debug, Serialize)]
pub struct SimulationSummary {
    /// Simulated machine time over all runs, s.
    pub sim_time_s: f64,
    /// Simulated seconds per wall-clock second (null with `--no-timing`).
    pub realtime_factor: Option<f64>,
    /// Wall-clock time of the simulation, s (null with `--no-timing`).
    pub wall_time_s: Option<f64>,
    /// Interpolation periods simulated.
    pub setpoints: u64,
    /// The ball-bar figures and events; null when the program has no measured circle.
    pub ballbar: Option<BallbarResult>,
    /// Each axis's reversal angles from the analysis, deg (what the spikes are attributed to).
    pub reversals_deg: std::collections::BTreeMap<String, Vec<f64>>,
    /// Every reversal with the bar's normalised sensitivity to its axis there (see
    /// `measure::attribution`); marks are attributed only where it is at least 0.05.
    pub reversal_sites: Vec<ReversalSite>,
    /// The directions run.
    pub directions: Vec<Direction>,
    /// Each axis's lost motion at a reversal (ISO 230-2 B, mm or deg) and its parts.
    pub reversal_values: std::collections::BTreeMap<String, crate::drive::ReversalValue>,
    /// Renishaw-style diagnostics from the trace; null without a measured circle.
    pub diagnostics: Option<crate::study::diagnose::Diagnostics>,
    /// Each axis's reversal value B from its lost-motion runs (`study::budget`); left out
    /// without a measured circle or a budget.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub reversal_b: Vec<crate::report::run::AxisReversal>,
    /// What makes G, by counterfactual runs (`study::budget`); left out without a measured
    /// circle or with `--no-budget`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error_budget: Option<crate::report::run::ErrorBudget>,
    /// What the user should know about the figures (a trimmed transient, one spot that
    /// dominates G, a feed held below the programmed one); left out when there is none.
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub warnings: Vec<String>,
    /// Feed blocks the planner ran below their F word, per axis and limit; left out when
    /// every block runs at its F.
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub feed_reductions: Vec<FeedReduction>,
    /// A circle test's lead-in: its arc and how long it took to reach speed and settle.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lead_in: Option<LeadIn>,
    /// What each registered measurement beside the ball bar read (`measure::measurement`),
    /// by name; left out when none applies.
    #[serde(skip_serializing_if = "BTreeMap::is_empty", default)]
    pub measurements: BTreeMap<String, serde_json::Value>,
    /// The pole passages of the program on a chain with two rotaries, each once with its
    /// line(s) and the inner rotary's move (`study::chain_events`); left out when the
    /// program passes none.
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub poles: Vec<String>,
}

/// Files a simulation writes into its output folder.
pub const TRACE_FILE: &str = TraceFormat::Csv.file_name();
/// The trace with `[simulate] trace_format = "parquet"` (one of the two is written).
pub const TRACE_PARQUET_FILE: &str = TraceFormat::Parquet.file_name();
pub const SUMMARY_FILE: &str = "summary.json";
pub const PLOT_FILE: &str = "ballbar.svg";

/// The ball-bar runs of a scenario, without any file written.
#[derive(Clone, Debug)]
pub struct BallbarStudy {
    /// Each direction's trace.
    pub runs: Vec<crate::measure::BallbarRun>,
    /// Each direction's nonlinear signature (trace minus the linear twin's).
    pub signatures: Vec<crate::measure::BallbarRun>,
    /// Every axis reversal with the bar's sensitivity to that axis there.
    pub sites: Vec<ReversalSite>,
    /// Each axis's reversal angles from the analysis, deg.
    pub reversals: Vec<(Axis, Vec<f64>)>,
    /// Each machine axis's reversal value B from the signatures (`study::lost_motion`),
    /// in the machine's order; empty without a bar or command maps.
    pub lost_motion_b: Vec<crate::report::run::AxisReversal>,
    pub sim_time_s: f64,
    pub setpoints: u64,
    pub directions: Vec<Direction>,
    /// What the user should know about the figures (a trimmed start-up transient, a feed
    /// held below the programmed one).
    pub warnings: Vec<String>,
    /// Feed blocks run below their F word, per axis and limit (over all directions).
    pub feed_reductions: Vec<FeedReduction>,
    /// What each registered measurement beside the ball bar read, by name.
    pub measurements: BTreeMap<String, serde_json::Value>,
    /// Each run's tool speed along the measured circle, from the samples.
    pub feed: Vec<FeedMeter>,
    /// The measured circle's radius (mm) and programmed feed (mm/min) of a generated test;
    /// None for a file program.
    pub nominal_feed: Option<(f64, f64)>,
    /// A program without a measured circle: its contour error along the first run
    /// (`measure::contour`; its figures are `measurements.contour`).
    pub contour_profile: Option<ContourProfile>,
}

impl BallbarStudy {
    /// Figures from the trace; spikes and steps from the nonlinear signature, attributed
    /// to the axes the bar can see at each reversal. None without a measured circle.
    pub fn result(&self) -> Result<Option<BallbarResult>> {
        if self.runs.is_empty() {
            return Ok(None);
        }
        let mut result = analyse_events_at(&self.runs, &self.signatures, &self.sites)?;
        result.feed = self
            .nominal_feed
            .and_then(|(radius_mm, feed_mm_min)| FeedSeen::of(&self.feed, radius_mm, feed_mm_min));
        Ok(Some(result))
    }
}

/// The measured circle's radius (mm) and programmed feed (mm/min) of a generated test: what
/// the tool's speed over the measured revolution is held to. None for a file program.
pub(crate) fn nominal_feed(scenario: &Scenario) -> Option<(f64, f64)> {
    test_of(scenario)
        .revolution()
        .map(|r| (r.radius_mm, r.feed_mm_min))
}

/// The warning for G measured off the programmed feed; None at feed (or without one).
pub(crate) fn off_feed_warning(result: &BallbarResult, scenario: &Scenario) -> Option<String> {
    let seen = result.feed.filter(|f| !f.at_feed)?;
    let (_, feed) = nominal_feed(scenario)?;
    let (min, max) = (seen.feed_min_mm_min, seen.feed_max_mm_min);
    Some(if max <= feed * (1.0 + AT_FEED_TOLERANCE) {
        format!(
            "the tool did not reach the programmed F{feed} over the whole measured revolution: it \
             ran at {min:.0} to {max:.0} mm/min, so G is not that of a circle at F{feed}"
        )
    } else {
        format!(
            "the tool's speed along the measured circle varied from {min:.0} to {max:.0} mm/min \
             about the programmed F{feed} (more than {:.0} %), as a joint-space program's does \
             within its blocks, so G is not that of a circle at F{feed}",
            100.0 * AT_FEED_TOLERANCE
        )
    })
}

/// Runs every direction of the scenario through the pipeline into the virtual ball bar
/// (and into `trace`, when given). `progress` is told the simulated time now and then.
pub fn run_ballbar(
    scenario: &Scenario,
    trace: Option<&mut TraceSink>,
    progress: &dyn Fn(f64),
) -> Result<BallbarStudy> {
    run_ballbar_budget(scenario, (trace, None), None, progress).map(|(study, _)| study)
}

/// [`run_ballbar`] with the error budget's runs of `budget` beside it (`study::budget`):
/// each direction's, or why they failed; and `check`, when given, fed with every sample.
pub fn run_ballbar_budget(
    scenario: &Scenario,
    (mut trace, mut check): (Option<&mut TraceSink>, Option<&mut RunCheck<'_>>),
    budget: Option<&BudgetPlan>,
    progress: &dyn Fn(f64),
) -> Result<(BallbarStudy, BudgetRuns)> {
    let machine = &scenario.machine;
    let (along, analysis) = analyses(scenario)?;
    let geometry = bar_geometry(scenario);
    let mut budget_runs = Vec::new();
    let directions = directions_of(scenario);
    let mut measurements = measurement::for_scenario(scenario, &*test_of(scenario));
    let mut sinks = Vec::new();
    let mut sim_time_s = 0.0;
    let mut setpoints = 0u64;
    let mut warnings = Vec::new();
    let mut feed_reductions = Vec::new();
    let mut contour = None;
    for (k, &direction) in directions.iter().enumerate() {
        let mut run = program::scenario_run(scenario, direction, scenario.simulate.lead_deg)?;
        let mut ballbar = geometry.map(|g| ballbar_sink(g, direction, run.measured, k));
        // A program without a measured circle: its contour error, on the run's own moves.
        let mut gauge = (ballbar.is_none() && k == 0)
            .then(|| contour_gauge(scenario, &mut run.moves, sim_time_s));
        if let Some(along) = &along {
            run.moves = analysed_along(run.moves, along);
        }
        if let Some(c) = check.as_deref_mut() {
            run.moves = c.start_run(run.moves);
        }
        if let Some(t) = trace.as_deref_mut() {
            t.start_run(direction, run.measured);
        }
        for m in &mut measurements {
            m.start_run(direction, run.measured);
        }
        let options = run_options(scenario, sim_time_s)?;
        let budget_run = budget
            .filter(|_| ballbar.is_some() || gauge.is_some())
            .map(|plan| RefCell::new(plan.start(direction, options.timing)));
        // A part program's budget reads each run's positions through the contour gauge.
        let mut contour_runs = match (&gauge, &budget_run, budget) {
            (Some(_), Some(run), Some(plan)) => Some(ContourBudgetRuns::new(plan, run)),
            _ => None,
        };
        let stats = {
            let mut sinks: Vec<&mut dyn Sink> = Vec::with_capacity(1);
            // The ball bar and its trace, or (no measured circle) the contour gauge and the
            // program's trace: one of the two.
            let (mut measure, mut program_trace) = match (ballbar.as_mut(), gauge.as_mut()) {
                (Some(ballbar), _) => (
                    Some(BarAndTrace {
                        ballbar,
                        trace: trace.as_deref_mut(),
                        budget: budget_run.as_ref(),
                    }),
                    None,
                ),
                (None, Some(gauge)) => (
                    None,
                    Some(ProgramAndTrace {
                        gauge,
                        trace: trace.as_deref_mut(),
                        budget: contour_runs.as_mut(),
                    }),
                ),
                (None, None) => (None, None),
            };
            if let Some(m) = measure.as_mut() {
                sinks.push(m);
            }
            if let Some(p) = program_trace.as_mut() {
                sinks.push(p);
            }
            for m in &mut measurements {
                sinks.push(&mut **m);
            }
            // The budget's servos and the check take every setpoint, before any settle gate.
            let mut stepper = budget_run.as_ref().map(BudgetStepper);
            let mut front: Vec<&mut dyn Sink> = Vec::with_capacity(2);
            front.extend(stepper.as_mut().map(|s| s as &mut dyn Sink));
            front.extend(check.as_deref_mut().map(|c| c as &mut dyn Sink));
            let gate = Gate {
                scenario,
                measured: run.measured,
                geometry,
            };
            gate.run(run.moves, &options, sinks, front, &mut warnings, progress)?
        };
        if let Some(c) = check.as_deref_mut() {
            c.end_run()?;
        }
        let contour_sums = contour_runs.and_then(ContourBudgetRuns::finish);
        let finished = budget_run.map(|b| b.into_inner().finish());
        if let Some(gauge) = gauge {
            let budget = match (contour_sums, &finished) {
                (Some(sums), Some(Ok(direction))) => Some(sums.budget(direction.moved())),
                _ => None,
            };
            contour = Some((gauge.figures(), gauge.profile().clone(), budget));
        }
        budget_runs.extend(finished);
        // The run's rows go to the trace now that its centring is known.
        if let Some(t) = trace.as_deref_mut() {
            t.end_run(ballbar.as_ref().map(|b| b.run.centring()))?;
        }
        for m in &mut measurements {
            m.end_run()?;
        }
        sim_time_s = stats.end_time_s;
        setpoints += stats.samples;
        merge_reductions(&mut feed_reductions, stats.feed_reductions);
        sinks.extend(ballbar);
    }
    let shared = SharedRuns::new(
        machine,
        (along, analysis),
        directions,
        sim_time_s,
        setpoints,
        feed_reductions,
    );
    let maps = sinks.first_mut().and_then(|b| b.maps.take());
    let mut study = assemble(
        scenario,
        sinks,
        maps.as_ref(),
        warnings,
        &shared,
        (None, None),
    )?;
    for m in &measurements {
        study.measurements.insert(m.name().to_string(), m.finish()?);
    }
    if let Some((figures, profile, budget)) = contour {
        let mut json = serde_json::to_value(figures).expect("plain data serializes");
        if let (Some(budget), Some(map)) = (budget, json.as_object_mut()) {
            let budget = serde_json::to_value(budget).expect("plain data serializes");
            map.insert("budget".into(), budget);
        }
        study.measurements.insert("contour".into(), json);
        study.contour_profile = Some(profile);
    }
    let budget_runs = budget_runs.into_iter().collect();
    Ok((study, budget_runs))
}

/// The error budget's runs of every direction, or why one of them failed.
pub type BudgetRuns = std::result::Result<Vec<BudgetDirection>, String>;

/// The ball bar of a scenario's `k`-th run: with the maps of the bar's sensitivity and the
/// speeds for the first ([`assemble`] reads those), without for the others.
pub(crate) fn ballbar_sink(
    geometry: BarGeometry,
    direction: Direction,
    measured: Option<MeasuredLines>,
    k: usize,
) -> BallbarSink {
    let sink = BallbarSink::new(geometry, direction, measured);
    if k == 0 {
        sink
    } else {
        sink.without_maps()
    }
}

/// The directions a scenario runs: a test's, or counter-clockwise for a file program.
pub(crate) fn directions_of(scenario: &Scenario) -> Vec<Direction> {
    test_of(scenario).directions()
}

/// The reversal analysis of the scenario's program: to ride along the runs (a file
/// program), or done (a generated one, whose analysis has its own closed form).
/// Of a done analysis only each axis's reversal angles (deg) are kept.
#[allow(clippy::type_complexity)]
pub(crate) fn analyses(
    scenario: &Scenario,
) -> Result<(
    Option<Rc<RefCell<MoveAnalysis<'_>>>>,
    Option<Vec<(Axis, Vec<f64>)>>,
)> {
    let along = along_analysis(scenario);
    let done = match along {
        Some(_) => None,
        None => Some(scenario_reversals_deg(scenario)?),
    };
    Ok((along, done))
}

/// The reversal analysis of a file program, riding along its one run (the file is read
/// once for both); None for a generated program, whose analysis has its own closed form.
pub(crate) fn along_analysis(scenario: &Scenario) -> Option<Rc<RefCell<MoveAnalysis<'_>>>> {
    let test = test_of(scenario);
    if has_closed_form(&*test) {
        return None;
    }
    let frame = test.theta_frame(&scenario.machine.kinematics);
    Some(Rc::new(RefCell::new(MoveAnalysis::new(
        &scenario.machine,
        frame,
    ))))
}

/// `moves` with every move also handed to the analysis `along`.
pub(crate) fn analysed_along<'a>(
    moves: crate::program::Moves<'a>,
    along: &Rc<RefCell<MoveAnalysis<'a>>>,
) -> crate::program::Moves<'a> {
    let along = Rc::clone(along);
    // The move is looked at where it lies in the result, not moved out and back in (two
    // copies of a large move fewer: docs/performance.md "Session 27: the fine file below 1.5").
    Box::new(moves.map(move |m| {
        if let Ok(m) = &m {
            along.borrow_mut().push(m)?;
        }
        m
    }))
}

/// The pipeline's options for one direction of a ball-bar run starting at `start_time_s`.
pub(crate) fn run_options(scenario: &Scenario, start_time_s: f64) -> Result<RunOptions> {
    Ok(RunOptions {
        timing: Timing::Planned {
            twins: true,
            settle: false,
        },
        force_tcp: scenario.simulate.tcp,
        start_time_s,
        program_path: scenario.path.clone(),
        max_samples: work::check_up_front(scenario, scenario.simulate.lead_deg)?,
    })
}

/// A file program measured from its first feed block: the start-up transient (the rapid
/// still settling) is kept out of the measured revolution.
pub(crate) fn gates_transient(scenario: &Scenario) -> bool {
    test_of(scenario).starts_unsettled() && scenario.simulate.measure_lines.is_none()
}

/// What the settle gate left out, as a warning; None when it left nothing out.
pub(crate) fn transient_warning(gate: &SettleGate<'_>) -> Option<String> {
    (gate.skipped_samples > 0).then(|| {
        format!(
            "the file program has no measure_lines: the first {:.2} deg of the measured revolution \
             ({} samples, the start-up transient) were left out until the axes settled; \
             set [simulate] measure_lines to measure chosen blocks instead",
            gate.skipped_deg, gate.skipped_samples
        )
    })
}

/// Adds a direction's feed reductions: each direction runs the same blocks, so a
/// reduction is listed once.
pub(crate) fn merge_reductions(all: &mut Vec<FeedReduction>, new: Vec<FeedReduction>) {
    for r in new {
        if !all
            .iter()
            .any(|f: &FeedReduction| (f.axis, f.limit) == (r.axis, r.limit))
        {
            all.push(r);
        }
    }
}

/// What the runs of one program share, whatever the drives.
pub(crate) struct SharedRuns {
    pub reversals: Vec<(Axis, Vec<f64>)>,
    pub sim_time_s: f64,
    pub setpoints: u64,
    pub directions: Vec<Direction>,
    pub feed_reductions: Vec<FeedReduction>,
}

impl SharedRuns {
    /// After the runs in `directions` on `machine`: each axis's reversal angles (deg) from
    /// the program's analysis, `done` before the runs or finished now from the one that
    /// rode `along` them ([`analyses`]), and the runs' tallies.
    pub(crate) fn new<'m>(
        machine: &'m crate::input::Machine,
        (along, done): (
            Option<Rc<RefCell<MoveAnalysis<'m>>>>,
            Option<Vec<(Axis, Vec<f64>)>>,
        ),
        directions: Vec<Direction>,
        sim_time_s: f64,
        setpoints: u64,
        feed_reductions: Vec<FeedReduction>,
    ) -> SharedRuns {
        let reversals = done.or_else(|| {
            let along = along?;
            let rode =
                std::mem::replace(&mut *along.borrow_mut(), MoveAnalysis::new(machine, None));
            Some(reversals_deg(rode.finish()))
        });
        SharedRuns {
            reversals: reversals.unwrap_or_default(),
            sim_time_s,
            setpoints,
            directions,
            feed_reductions,
        }
    }
}

/// A scenario's study from its ball bars (one per direction), the first run's command maps
/// (the reversal sites' poses and speeds) and what its runs share.
pub(crate) fn assemble(
    scenario: &Scenario,
    ballbars: Vec<BallbarSink>,
    maps: Option<&CommandMaps>,
    warnings: Vec<String>,
    shared: &SharedRuns,
    (regressors, shared_sites): (
        Option<&crate::study::lost_motion::SharedRegressors>,
        Option<&crate::measure::attribution::SharedSites>,
    ),
) -> Result<BallbarStudy> {
    let machine = &scenario.machine;
    let geometry = bar_geometry(scenario);
    let (mut runs, mut signatures, mut feed) = (Vec::new(), Vec::new(), Vec::new());
    for b in ballbars {
        runs.push(b.run);
        signatures.push(b.signature);
        feed.push(b.feed);
    }
    let reversals = shared.reversals.clone();
    // The bar's sensitivity is a property of the nominal pose at θ: the first run's map.
    // Each axis's Stribeck velocity bounds its slow zone about a reversal (a cascade axis
    // with dry friction; otherwise the zone is the reversal itself).
    let drives = machine
        .axes()
        .iter()
        .map(|&a| machine.drive(a))
        .collect::<Vec<_>>();
    let stribeck = |a: Axis| -> f64 {
        match drives.iter().find(|d| d.axis == a) {
            // m/s or rad/s to the commanded speeds' mm/s or deg/s.
            Some(d) if d.has_dry_friction() => d.stribeck_m_or_rad_per_s / si_per_unit(a),
            _ => 0.0,
        }
    };
    let sites = match (maps, geometry) {
        (Some(maps), Some(g)) => {
            let sensitivity = |q: &AxisVec| g.sensitivity_at(q);
            let speed = (&maps.speed, &stribeck as &dyn Fn(Axis) -> f64);
            let (commanded, length) = (&maps.commanded, g.length_mm);
            match shared_sites {
                Some(shared) => shared.get(&reversals, commanded, &sensitivity, length, speed),
                None => sites_from_map(&reversals, commanded, &sensitivity, length, Some(speed)),
            }
        }
        _ => ReversalSite::unweighted(&reversals),
    };
    let lost_motion_b = match (maps, geometry) {
        (Some(maps), Some(g)) => {
            let (bar, r) = ((maps, &g), regressors);
            crate::study::lost_motion::reversal_b(&signatures, bar, &drives, &sites, r)?
        }
        _ => Vec::new(),
    };
    Ok(BallbarStudy {
        runs,
        signatures,
        sites,
        reversals,
        lost_motion_b,
        sim_time_s: shared.sim_time_s,
        setpoints: shared.setpoints,
        directions: shared.directions.clone(),
        warnings: warnings
            .into_iter()
            .chain(shared.feed_reductions.iter().map(FeedReduction::describe))
            .collect(),
        feed_reductions: shared.feed_reductions.clone(),
        measurements: BTreeMap::new(),
        feed,
        nominal_feed: nominal_feed(scenario),
        contour_profile: None,
    })
}

/// Runs the scenario and writes `trace.csv`, `summary.json` and `ballbar.svg` to `out_dir`,
/// with the error budget. `progress` is told the simulated time, s, now and then.
pub fn simulate(
    scenario: &Scenario,
    out_dir: &Path,
    timing: bool,
    progress: &dyn Fn(f64),
) -> Result<SimulationSummary> {
    simulate_with(scenario, out_dir, timing, true, progress)
}

/// [`simulate`], with the error budget (`study::budget`) or without it (`--no-budget`:
/// no `error_budget`, no B per axis).
pub fn simulate_with(
    scenario: &Scenario,
    out_dir: &Path,
    timing: bool,
    with_budget: bool,
    progress: &dyn Fn(f64),
) -> Result<SimulationSummary> {
    simulate_beside(
        scenario,
        out_dir,
        (timing, with_budget),
        (None, None),
        progress,
    )
}

/// [`simulate_with`], with a measurement made `beside` the run (`simulate --cut`), its
/// document under `measurements` and its files in `out_dir`, and `check` fed with the run's
/// samples ([`RunCheck`]), when given.
pub fn simulate_beside(
    scenario: &Scenario,
    out_dir: &Path,
    (timing, with_budget): (bool, bool),
    (beside, check): (Option<BesideRun<'_>>, Option<&mut RunCheck<'_>>),
    progress: &dyn Fn(f64),
) -> Result<SimulationSummary> {
    create_dir(out_dir)?;
    // What a killed run into this folder left behind.
    crate::report::files::remove_stale_temporaries(
        out_dir,
        &[
            TRACE_FILE,
            TRACE_PARQUET_FILE,
            SUMMARY_FILE,
            PLOT_FILE,
            crate::report::test_info::TEST_FILE,
            crate::report::html::CHECK_FILE,
            crate::report::html::REPORT_FILE,
            crate::report::contour::CONTOUR_FILE,
            crate::report::contour::CONTOUR_PLOT_FILE,
            crate::report::cut::CUT_JSON,
            crate::report::cut::SURFACE_CSV,
            crate::report::cut::SURFACE_PARQUET,
            crate::report::cut_html::CUT_HTML,
            crate::report::cut_plots::SURFACE_SVG,
            crate::report::cut_plots::ROUNDNESS_SVG,
            crate::report::cut_tip::TIP_SVG,
        ],
    )?;
    work::check_trace_up_front(scenario, scenario.simulate.lead_deg)?;
    let format = scenario.simulate.trace_format;
    let mut trace = TraceSink::create(
        &out_dir.join(format.file_name()),
        scenario.machine.axes(),
        bar_geometry(scenario),
        scenario.simulate.trace_every as u64,
        format,
        scenario.simulate.max_trace_rows,
    )?;
    let started = Instant::now();
    // The ball bar's budget; a part program's, of its contour error, without a bar.
    let plan = match (bar_geometry(scenario), with_budget) {
        (Some(g), true) => Some(BudgetPlan::new(scenario, g)?),
        (None, true) => Some(BudgetPlan::for_positions(scenario)?),
        (_, false) => None,
    };
    let (study, budget_runs) =
        run_ballbar_budget(scenario, (Some(&mut trace), check), plan.as_ref(), progress)?;
    let ballbar = study.result()?;
    let (runs, reversals) = (&study.runs, &study.reversals);
    let mut warnings = study.warnings.clone();
    warnings.extend(ballbar.as_ref().and_then(|b| off_feed_warning(b, scenario)));
    let test = test_of(scenario);
    let circle = test.circle();
    let diagnostics = ballbar
        .as_ref()
        .map(|b| crate::study::diagnose::diagnose(b, runs, circle))
        .transpose()?;
    let machine_reversals = reversal_values(&scenario.machine)?;
    let (error_budget, reversal_b) = match (&ballbar, &plan, budget_runs) {
        (Some(b), Some(plan), Ok(directions)) if directions.len() == runs.len() => {
            let (budget, rb) = budget::assemble(plan, &directions, runs, b, &study.sites)?;
            (Some(budget), rb)
        }
        (Some(_), Some(_), Err(why)) => {
            warnings.push(format!("no error budget: one of its runs failed ({why})"));
            (None, Vec::new())
        }
        _ => (None, Vec::new()),
    };
    trace.finish()?;
    // The other format's trace of an earlier run would be read for this one's.
    let other = match format {
        TraceFormat::Csv => TRACE_PARQUET_FILE,
        TraceFormat::Parquet => TRACE_FILE,
    };
    match std::fs::remove_file(out_dir.join(other)) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            return Err(crate::error::Error::Write {
                path: out_dir.join(other),
                source: e,
            })
        }
        _ => {}
    }
    write_contour_plot(scenario, &study, out_dir)?;
    let mut measurements = study.measurements.clone();
    if let Some(beside) = beside {
        let made = beside(out_dir)?;
        warnings.extend(made.warnings);
        measurements.extend(made.json.map(|j| (made.name, j)));
    }
    if let Some(result) = &ballbar {
        let title = plot_title(scenario);
        crate::report::polar::write_polar_svg(
            &out_dir.join(PLOT_FILE),
            runs,
            reversals,
            result,
            &title,
        )?;
    }
    warnings.extend(dominant_spots(runs)?);
    let wall = started.elapsed().as_secs_f64();
    let sim_time_s = study.sim_time_s;
    let summary = SimulationSummary {
        sim_time_s,
        realtime_factor: timing.then(|| sim_time_s / wall.max(1e-9)),
        wall_time_s: timing.then_some(wall),
        setpoints: study.setpoints,
        ballbar,
        reversals_deg: reversals
            .iter()
            .map(|(a, r)| (a.to_string(), r.clone()))
            .collect(),
        reversal_sites: study.sites.clone(),
        directions: study.directions.clone(),
        reversal_values: machine_reversals,
        diagnostics,
        reversal_b,
        error_budget,
        warnings,
        feed_reductions: study.feed_reductions.clone(),
        lead_in: scenario.simulate.lead_in.map(|lead| LeadIn {
            reached_mm_min: study.nominal_feed.and_then(|(radius_mm, _)| {
                crate::measure::feed::start_mm_min(&study.feed, radius_mm)
            }),
            ..lead
        }),
        measurements,
        poles: pole_passages(scenario)?,
    };
    let json = serde_json::to_string_pretty(&summary).expect("plain data serializes");
    crate::report::write_atomic(&out_dir.join(SUMMARY_FILE), format!("{json}\n").as_bytes())?;
    // The test parameters (ISO 230-4) for the report; the date only with timing, so that
    // `--no-timing` runs stay byte-identical.
    let test = crate::report::test_info::TestParameters::of(
        scenario,
        timing.then(crate::report::test_info::today_utc),
    )?;
    let json = serde_json::to_string_pretty(&test).expect("plain data serializes");
    crate::report::write_atomic(
        &out_dir.join(crate::report::test_info::TEST_FILE),
        format!("{json}\n").as_bytes(),
    )?;
    Ok(summary)
}

/// One spot that makes most of G (a transient, a spike) is worth a word: a warning per run
/// where one does.
fn dominant_spots(runs: &[crate::measure::BallbarRun]) -> Result<Vec<String>> {
    let mut warnings = Vec::new();
    for run in runs {
        let dev = run.trace_um(true)?;
        let theta: Vec<f64> = (0..dev.len())
            .map(|i| (i as f64 + 0.5) * crate::measure::ballbar::BIN_DEG)
            .collect();
        if let Some((g, rest, spot)) = crate::study::diagnose::dominant_spot(&theta, &dev) {
            warnings.push(format!(
                "one spot dominates G in the {} run: G = {g:.2} µm, {:.2} µm without ±5° around θ = {spot:.1}°",
                format!("{:?}", run.direction()).to_uppercase(),
                rest
            ));
        }
    }
    Ok(warnings)
}

/// A measurement made beside the run by a path of its own (`simulate --cut`: the cut,
/// `study::cut::cut_beside`): its name under `measurements`, its document (None: nothing
/// to measure) and what the user should know.
pub struct Beside {
    pub name: String,
    pub json: Option<serde_json::Value>,
    pub warnings: Vec<String>,
}

/// Makes a [`Beside`] measurement, its files written into the run's folder (given).
pub type BesideRun<'a> = &'a dyn Fn(&Path) -> Result<Beside>;

/// The ball bar, the trace of its readings and the error budget's runs, as one sink: the
/// bar reads each sample once, and the budget takes the samples the bar takes.
struct BarAndTrace<'a, 'p> {
    ballbar: &'a mut BallbarSink,
    trace: Option<&'a mut TraceSink>,
    budget: Option<&'a RefCell<BudgetRun<'p>>>,
}

impl Sink for BarAndTrace<'_, '_> {
    fn push(&mut self, s: &Sample) -> Result<()> {
        let reading = self.ballbar.take(s);
        if let (Some(r), Some(budget)) = (&reading, self.budget) {
            budget.borrow_mut().record(s, r);
        }
        match (reading, self.trace.as_deref_mut()) {
            (Some(r), Some(trace)) => trace.push_reading(s, &r),
            _ => Ok(()),
        }
    }
}

/// `contour.svg` of a program without a measured circle (nothing for one with a circle).
fn write_contour_plot(scenario: &Scenario, study: &BallbarStudy, out_dir: &Path) -> Result<()> {
    let Some(profile) = &study.contour_profile else {
        return Ok(());
    };
    let figures = contour_figures(&study.measurements)?;
    let svg = crate::report::contour::render_contour_svg(profile, &figures, &plot_title(scenario))?;
    crate::report::write_atomic(
        &out_dir.join(crate::report::contour::CONTOUR_PLOT_FILE),
        svg.as_bytes(),
    )
}

/// The contour error's figures of a program without a measured circle, from the
/// measurements of its run (`measurements.contour`); empty figures where there is none.
pub fn contour_figures(
    measurements: &BTreeMap<String, serde_json::Value>,
) -> Result<crate::measure::contour::ContourFigures> {
    match measurements.get("contour") {
        Some(v) => serde_json::from_value(v.clone())
            .map_err(|e| crate::error::Error::usage(format!("contour figures: {e}"))),
        None => Ok(Default::default()),
    }
}

/// The contour gauge of a program without a measured circle, on its run starting at machine
/// time `start_s`: the run's `moves` become one side of a tee ([`program::moves::tee`]), the
/// gauge reads the other in step with the samples.
fn contour_gauge<'s>(
    scenario: &'s Scenario,
    moves: &mut program::Moves<'s>,
    start_s: f64,
) -> ContourGauge<'s> {
    let (run, gauge) = program::moves::tee(std::mem::replace(moves, Box::new(std::iter::empty())));
    *moves = run;
    ContourGauge::new(&scenario.machine, gauge, scenario.simulate.tcp, start_s)
}

/// How one run of a scenario reaches its sinks: for a file program measured from where it
/// settles ([`gates_transient`]), through the settle gate (θ from the bar's `geometry`).
pub(crate) struct Gate<'s> {
    pub scenario: &'s Scenario,
    pub measured: Option<MeasuredLines>,
    pub geometry: Option<BarGeometry>,
}

impl Gate<'_> {
    /// Runs `moves` with `options` into `sinks`, the `front` sinks (the error budget's
    /// stepper, whose servos take every setpoint, the run's check) before any gate; the
    /// gate's warning goes to `warnings`.
    pub(crate) fn run<'a>(
        &self,
        moves: crate::program::Moves<'_>,
        options: &RunOptions,
        mut sinks: Vec<&'a mut dyn Sink>,
        mut front: Vec<&mut dyn Sink>,
        warnings: &mut Vec<String>,
        progress: &dyn Fn(f64),
    ) -> Result<crate::pipeline::RunStats> {
        let machine = &self.scenario.machine;
        let gated = self
            .geometry
            .filter(|_| gates_transient(self.scenario) && !sinks.is_empty());
        let Some(g) = gated else {
            let mut all: Vec<&mut dyn Sink> = Vec::with_capacity(sinks.len() + front.len());
            for s in front.iter_mut() {
                all.push(&mut **s);
            }
            for s in sinks.iter_mut() {
                all.push(&mut **s);
            }
            return pipeline::run(moves, machine, options, &mut all, progress);
        };
        let mut gate = SettleGate::new(
            sinks,
            self.measured,
            Box::new(move |s| g.read_commanded(&s.commanded).theta_deg),
        );
        let stats = {
            let mut outer: Vec<&mut dyn Sink> = Vec::with_capacity(front.len() + 1);
            for s in front.iter_mut() {
                outer.push(&mut **s);
            }
            outer.push(&mut gate);
            pipeline::run(moves, machine, options, &mut outer, progress)?
        };
        warnings.extend(transient_warning(&gate));
        Ok(stats)
    }
}

/// A program without a measured circle: its contour error, and its trace rows with it.
struct ProgramAndTrace<'a, 'g, 'b, 'p> {
    gauge: &'a mut ContourGauge<'g>,
    trace: Option<&'a mut TraceSink>,
    /// The error budget's runs, each read at the full run's feed samples.
    budget: Option<&'a mut ContourBudgetRuns<'b, 'p>>,
}

impl Sink for ProgramAndTrace<'_, '_, '_, '_> {
    fn push(&mut self, s: &Sample) -> Result<()> {
        let reading = self.gauge.read(s)?;
        if let (Some(r), Some(budget)) = (&reading, self.budget.as_deref_mut()) {
            budget.record(self.gauge, s, &r.error_mm);
        }
        match self.trace.as_deref_mut() {
            Some(trace) => trace.push_program(s, reading.as_ref()),
            None => Ok(()),
        }
    }
}

/// Each axis's reversal value from its drive configuration, by axis letter.
pub fn reversal_values(
    machine: &crate::input::Machine,
) -> Result<std::collections::BTreeMap<String, crate::drive::ReversalValue>> {
    machine
        .axes()
        .iter()
        .map(|&a| {
            let servo = crate::drive::AxisServo::new(
                &machine.drive(a),
                machine.interpolation_period_s,
                0.0,
            )?;
            Ok((a.to_string(), servo.reversal_value()))
        })
        .collect()
}

/// The virtual ball bar of a scenario: the cone's or circle's measured circle, the table
/// ball at its centre (or where `[ballbar] pivot_mm` puts it); none for a file program
/// without a cone.
pub fn bar_geometry(scenario: &Scenario) -> Option<BarGeometry> {
    let kinematics = scenario.machine.kinematics;
    let pivot_override = scenario.ballbar_pivot_mm.map(Point3::from);
    test_of(scenario).bar(&kinematics).map(|bar| BarGeometry {
        kinematics,
        frame: bar.frame,
        pivot_table_mm: pivot_override.unwrap_or(bar.pivot_table_mm),
        length_mm: bar.length_mm,
    })
}

fn plot_title(scenario: &Scenario) -> String {
    let name = scenario
        .path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    test_of(scenario).title(&name)
}

/// The messages of the program's pole passages ([`crate::study::chain_events`]), for the
/// summary and the report.
fn pole_passages(scenario: &Scenario) -> Result<Vec<String>> {
    let events = crate::study::chain_events::chain_events(scenario)?.unwrap_or_default();
    Ok(events
        .into_iter()
        .filter(|e| {
            matches!(
                e.event,
                crate::kinematics::chain_inverse::PathEvent::Pole { .. }
            )
        })
        .map(|e| e.message)
        .collect())
}
