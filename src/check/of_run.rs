//! The check of a run's own setpoints: `simulate`'s `check.json` without planning the
//! program a second time.
//!
//! [`RunCheck`] is a sink fed during `simulate`'s run, beside the ball bar and the trace.
//! It takes each sample's commanded position (the interpolator's setpoint, with each axis's
//! position error for its direction of motion, as [`crate::check::check`] takes it) into the
//! same limits monitor and collision scene as `mtsim check`, so that travel, velocity,
//! acceleration and jerk are the finite differences
//! `v_k = (q_k - q_{k-1}) / Δt`, `a_k = (v_k - v_{k-1}) / Δt`, `j_k = (a_k - a_{k-1}) / Δt`
//! of the setpoints the run itself commanded: every direction, the lead-in and lead-out arcs.
//!
//! Each run begins where the reader assumes the machine is (zero), which is fictional: the
//! path of a run's first move, from there to the program's start, is not checked. Its last
//! sample (the program's start within a period, which must lie within reach like every other
//! point) is the first one checked, for travel and collisions; velocity, acceleration and
//! jerk are differenced from the second move's first sample on (`check` replaces that move
//! with a standstill at its end). Each run is differenced on its own clock: no velocity
//! across the seam between two runs ([`Monitors::restart`]).
//!
//! What differs from `mtsim check` alone: that check plans each direction's revolution
//! without lead arcs from time 0, while this one checks the samples the run took, on the
//! run's clock (`"timing": "run"`); `docs/check.md` says which figures agree.

use crate::check::limits::LimitsMonitor;
use crate::check::run::{
    note_tool_changes, report_of, scene_sink, CheckOptions, CheckReport, CheckTiming, Monitors,
    SceneQueries, ToolChanges,
};
use crate::error::Result;
use crate::input::scenario::Scenario;
use crate::kinematics::error_table::PositionErrors;
use crate::motion::FeedReduction;
use crate::pipeline::{RunStats, Sample, Sink};
use crate::program::{test_of, Moves};
use crate::AxisVec;

/// θ of a commanded position on the scenario's measured circle, if it has one.
pub type ThetaOf = Box<dyn Fn(&AxisVec) -> Option<f64> + Send + Sync>;

/// The θ function a [`RunCheck`] names violations by (the measured circle's angle).
pub fn theta_of(scenario: &Scenario) -> ThetaOf {
    let kin = scenario.machine.kinematics;
    let frame = test_of(scenario).theta_frame(&kin);
    Box::new(move |q: &AxisVec| frame.map(|f| f.theta_deg(&kin.forward(q).tip)))
}

/// Where a run stands in its first move, whose path is not checked.
#[derive(Clone, Copy, Debug)]
enum Start {
    /// No sample of the run yet.
    Before,
    /// In the first move (its block index), its latest sample held until the move ends.
    InFirst(u64),
    /// Past it: every sample is checked.
    Past,
}

/// The limits monitor and the collision scene fed with a run's setpoints as they are made.
pub struct RunCheck<'a> {
    scenario: &'a Scenario,
    monitors: Monitors<'a>,
    changes: ToolChanges,
    errors: PositionErrors,
    start: Start,
    /// The first move's latest sample (as the pipeline gave it).
    held: Option<Sample>,
    /// What the monitors are given: the sample with `actual` the commanded position plus
    /// its position errors.
    checked: Sample,
    samples: u64,
    end_time_s: f64,
}

impl<'a> RunCheck<'a> {
    /// A check of `scenario`'s runs, violations named by `theta` ([`theta_of`]).
    pub fn new(scenario: &'a Scenario, theta: &'a ThetaOf) -> Result<RunCheck<'a>> {
        let changes = ToolChanges::default();
        let options = CheckOptions::default();
        let scene = scene_sink(
            scenario,
            &options,
            SceneQueries::Bounded,
            changes.clone(),
            theta_of(scenario),
        )?;
        let theta: &'a dyn Fn(&AxisVec) -> Option<f64> = &**theta;
        let checked = Sample::blank(0.0);
        Ok(RunCheck {
            scenario,
            monitors: Monitors {
                limits: LimitsMonitor::new(&scenario.machine, theta),
                scene,
            },
            changes,
            errors: scenario.machine.geometry.position_errors(),
            start: Start::Before,
            held: None,
            checked,
            samples: 0,
            end_time_s: 0.0,
        })
    }

    /// The moves of the next run, watched for tool changes (for the scene's tool); call
    /// once per run, before its first sample.
    pub fn start_run<'m>(&mut self, moves: Moves<'m>) -> Moves<'m> {
        self.monitors.restart();
        // The axes' directions of motion are known afresh from the run's first checked sample.
        self.errors = self.scenario.machine.geometry.position_errors();
        self.start = Start::Before;
        self.held = None;
        if self.monitors.scene.is_some() {
            self.changes.borrow_mut().clear();
            note_tool_changes(moves, self.changes.clone())
        } else {
            moves
        }
    }

    /// Ends a run: one that never left its first move has that move's last sample checked.
    pub fn end_run(&mut self) -> Result<()> {
        match self.held.take() {
            Some(held) => self.check(&held),
            None => Ok(()),
        }
    }

    /// The report, as `check` writes it, of every sample checked, with the runs'
    /// `feed_reductions` (blocks the planner ran below their F word).
    pub fn finish(self, feed_reductions: Vec<FeedReduction>) -> CheckReport {
        let stats = RunStats {
            samples: self.samples,
            end_time_s: self.end_time_s,
            feed_reductions,
        };
        let mut report = report_of(self.scenario, self.monitors, &stats);
        report.timing = CheckTiming::Run;
        report
    }

    /// Hands `s` to the monitors, its position errors applied.
    #[inline]
    fn check(&mut self, s: &Sample) -> Result<()> {
        let c = &mut self.checked;
        c.index = self.samples;
        c.time_s = s.time_s;
        c.line = s.line;
        c.block_index = s.block_index;
        c.commanded = s.commanded;
        c.actual = s.commanded;
        if !self.errors.is_empty() {
            self.errors.apply_in_place(&mut c.actual);
        }
        c.linear = c.actual;
        self.samples += 1;
        self.end_time_s = s.time_s;
        self.monitors.push(&self.checked)
    }
}

impl Sink for RunCheck<'_> {
    #[inline]
    fn push(&mut self, s: &Sample) -> Result<()> {
        match self.start {
            Start::Past => self.check(s),
            Start::Before => {
                self.start = Start::InFirst(s.block_index);
                self.held = Some(*s);
                Ok(())
            }
            Start::InFirst(first) if s.block_index == first => {
                self.held = Some(*s);
                Ok(())
            }
            Start::InFirst(_) => {
                self.start = Start::Past;
                if let Some(held) = self.held.take() {
                    self.check(&held)?;
                }
                // The held sample's successor is a period on, mostly past the first move's
                // end: its difference would be the tail of that move's deceleration (without
                // the acceleration before it, a jerk of a/T). Differences start in the
                // second move.
                self.monitors.limits.difference_afresh();
                self.check(s)
            }
        }
    }
}
