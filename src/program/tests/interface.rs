//! The trait every test implements, and what it answers in.

use std::path::Path;

use nalgebra::Point3;

use crate::error::Result;
use crate::input::budget::Revolution;
use crate::input::program::{CircleTest, ConeTest, Direction, MeasuredLines, NcOptions};
use crate::input::scenario::Scenario;
use crate::kinematics::Kinematics;
use crate::program::Moves;

use super::frame::CircleFrame;

/// One program to run: its moves and the lines of its measured revolution.
pub struct Run<'a> {
    pub direction: Direction,
    pub moves: Moves<'a>,
    /// Lines whose samples the ball bar measures; `None`: every move after the first.
    pub measured: Option<MeasuredLines>,
}

/// The ball bar a test is measured with, before `[ballbar] pivot_mm` moves its table ball.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BarSetup {
    /// The measured circle, for θ.
    pub frame: CircleFrame,
    /// Table-side ball, table frame, mm.
    pub pivot_table_mm: Point3<f64>,
    /// Nominal bar length L, mm.
    pub length_mm: f64,
}

/// What the report's test parameters (`test.json`) say of a test.
#[derive(Clone, Debug, PartialEq)]
pub struct TestDescription {
    /// The test's name and standard.
    pub test: String,
    pub geometry: String,
    pub radius_mm: Option<f64>,
    pub feed_mm_min: Option<f64>,
    /// The directions run, lower case.
    pub directions: Vec<String>,
    pub plane: String,
    pub position_mm: Option<[f64; 3]>,
    pub start_arc_deg: Option<f64>,
    pub overshoot_arc_deg: Option<f64>,
    pub program_file: Option<String>,
}

/// A test program: everything the house asks of what a scenario runs.
///
/// The cut cone of issue 40 is the cone's program with another measurement (its `bar` stays,
/// the cut surface is a `measure::Measurement` beside it); an ISO 10791-6 rotary-axis ball-bar
/// test (a C-axis or A-axis circle with X Y following) is a new file here: its `run` writes the
/// simultaneous moves, its `bar` puts the table ball on the rotary table and the frame in the
/// table's plane, its `revolution` is the tool ball's circle about the table ball, and it has
/// no generated cone or ISO 230-4 circle.
pub trait TestProgram {
    /// The scenario table that gives it, for messages: `[program.cone]`.
    fn table(&self) -> &'static str;

    /// The directions a generated test runs, as the scenario plans them; `None` for a program
    /// that runs as it was written.
    fn planned_directions(&self) -> Option<Vec<Direction>>;

    /// The directions `simulate` runs: the planned ones, or counter-clockwise once.
    fn directions(&self) -> Vec<Direction> {
        self.planned_directions()
            .unwrap_or_else(|| vec![Direction::Ccw])
    }

    /// The program run in `direction`, with `lead_deg` of extra path before and after the
    /// measured revolution of a generated test (a file runs as written), checked against the
    /// machine as it streams.
    fn run(&self, scenario: &Scenario, direction: Direction, lead_deg: f64)
        -> Result<Run<'static>>;

    /// [`TestProgram::run`] without lead and with a file's moves as the interpreter gives
    /// them, unchecked (`mtsim blocks` prints them all).
    fn run_unchecked(&self, scenario: &Scenario, direction: Direction) -> Result<Run<'static>> {
        self.run(scenario, direction, 0.0)
    }

    /// The reader's warnings about the program; none for a generated test.
    fn warnings(&self, _scenario: &Scenario) -> Result<Vec<ngc::Notice>> {
        Ok(Vec::new())
    }

    /// The program file it reads, if any.
    fn file(&self) -> Option<&Path> {
        None
    }

    /// The measured revolution in closed form, for the sample and trace budgets before a run;
    /// `None` when it is known only while the program runs.
    fn revolution(&self) -> Option<Revolution> {
        None
    }

    /// The ball bar it is measured with; `None` without a measured circle.
    fn bar(&self, kinematics: &Kinematics) -> Option<BarSetup>;

    /// The frame that gives θ to `check`'s reports: the bar's.
    fn theta_frame(&self, kinematics: &Kinematics) -> Option<CircleFrame> {
        self.bar(kinematics).map(|b| b.frame)
    }

    /// Whether the measured revolution starts with the program's start-up transient (no lead
    /// in), so that a settle gate keeps it out unless the scenario names measured lines.
    fn starts_unsettled(&self) -> bool {
        false
    }

    /// What the report says of it; `lead_deg` the lead-in and lead-out arcs of a generated test.
    fn description(&self, lead_deg: f64) -> TestDescription;

    /// The title of its plots, after the scenario's `name`.
    fn title(&self, name: &str) -> String;

    /// The generated cone-frustum program: its geometry and NC options.
    fn generated_cone(&self) -> Option<(&ConeTest, &NcOptions)> {
        None
    }

    /// The cone-frustum geometry the test is measured on: the generated cone's, or the one a
    /// file program's scenario gives beside it (the cut surface, `measure::cut`).
    fn cone(&self) -> Option<&ConeTest> {
        self.generated_cone().map(|(cone, _)| cone)
    }

    /// The ISO 230-4 circle, for the circle's own diagnostics.
    fn circle(&self) -> Option<&CircleTest> {
        None
    }
}

/// The directions as the report writes them.
pub(super) fn direction_names(directions: &[Direction]) -> Vec<String> {
    directions
        .iter()
        .map(|d| format!("{d:?}").to_lowercase())
        .collect()
}
