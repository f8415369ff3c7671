//! Everything `mtsim analyze` reports on a scenario's program: the reversal analysis, the
//! geometric errors' trace, the feed limits and the reader's notices.
//!
//! A file program is read once for the reversals, the feed limits and the notices: each move,
//! lent by the reader in place (no copy), is checked against the machine, then given to
//! [`MoveAnalysis`] and to the planner ([`FeedPlanner`]), and the notices are taken from the
//! same reader when it ends. Results and errors are those of the separate passes, in their
//! order (reversals, geometric trace, feed limits): the analysis reads on where the planner
//! stops, and its error comes first.

use crate::error::Result;
use crate::input::scenario::Scenario;
use crate::program::test_of;
use crate::program::{file, validate};
use crate::study::feed::{feed_limits, FeedPlanner, FeedReport};
use crate::study::geometry::{geometric_trace, GeometricTrace};
use crate::study::reversals::{analyse_scenario, Analysis, MoveAnalysis};

/// What `mtsim analyze` prints about a scenario's program.
#[derive(Clone, Debug)]
pub struct ProgramAnalysis {
    pub analysis: Analysis,
    /// The ball bar's trace of the programmed path with the geometric errors alone (None
    /// without location errors or rotary tables).
    pub geometric: Option<GeometricTrace>,
    pub feed: FeedReport,
    /// What the reader reported beside the moves of a file program (none for a generated one).
    pub notices: Vec<ngc::Notice>,
}

/// Analyses the scenario's program; see the module documentation.
pub fn analyse_program(scenario: &Scenario) -> Result<ProgramAnalysis> {
    let test = test_of(scenario);
    let Some(path) = test.file() else {
        return Ok(ProgramAnalysis {
            analysis: analyse_scenario(scenario)?,
            geometric: geometric_trace(scenario)?,
            feed: feed_limits(scenario)?,
            notices: Vec::new(),
        });
    };
    let machine = &scenario.machine;
    let mut reader = file::read_moves(path, &scenario.reader)?;
    // The checks `program::scenario_run` makes of a file, on each move in place.
    let mut checker = validate::move_checker(path, machine, scenario.simulate.tcp);
    let mut analysis = MoveAnalysis::new(machine, test.theta_frame(&machine.kinematics));
    let mut planner = FeedPlanner::new(scenario)?;
    // The planner stops at a block it cannot plan; the analysis reads on, and its error
    // (a bad read, a bad move) comes first.
    while let Some(m) = reader.next_ref() {
        let m = m?;
        checker.check(m)?;
        analysis.push(m)?;
        planner.push(m);
    }
    checker.end()?;
    let analysis = analysis.finish();
    let geometric = geometric_trace(scenario)?;
    let feed = planner.finish()?;
    // The reader has ended, so it holds every notice: the warnings and the codes accepted
    // with no effect on the motion.
    let notices = reader.notices().to_vec();
    Ok(ProgramAnalysis {
        analysis,
        geometric,
        feed,
        notices,
    })
}
