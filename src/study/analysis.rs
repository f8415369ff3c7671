//! Everything `mtsim analyze` reports on a scenario's program: the reversal analysis, the
//! geometric errors' trace, the feed limits and the reader's notices.
//!
//! A file program is read once for the reversals, the feed limits and the notices: its moves
//! go to [`MoveAnalysis`] on their way to the planner, and the notices are taken from the
//! same reader when it ends. Results and errors are those of the separate passes, in their
//! order (reversals, geometric trace, feed limits): the analysis reads on where the planner
//! stops, and its error comes first.

use crate::error::{Error, Result};
use crate::input::scenario::{Program, Scenario};
use crate::measure::CircleFrame;
use crate::program::validate::{self, Checked};
use crate::program::{file, Move};
use crate::study::feed::{feed_limits, plan_feed, FeedReport};
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
    let Program::File { path, cone } = &scenario.program else {
        return Ok(ProgramAnalysis {
            analysis: analyse_scenario(scenario)?,
            geometric: geometric_trace(scenario)?,
            feed: feed_limits(scenario)?,
            notices: Vec::new(),
        });
    };
    let machine = &scenario.machine;
    let reader = file::read_moves(path, &scenario.reader)?;
    // The stream `program::scenario_run` gives for a file, as both passes read it.
    let moves = validate::checked_unboxed(path, machine, scenario.simulate.tcp, reader);
    let mut tee = Analysed {
        moves,
        analysis: MoveAnalysis::new(machine, cone.map(|c| CircleFrame::of_cone(&c))),
        failed: None,
    };
    let feed = plan_feed(&mut tee, scenario);
    // Where the planner stopped early (a block it cannot plan), the analysis reads on.
    tee.by_ref().for_each(drop);
    if let Some(e) = tee.failed {
        return Err(e);
    }
    let analysis = tee.analysis.finish();
    let geometric = geometric_trace(scenario)?;
    let feed = feed?;
    // The reader has ended (the analysis read it to its end), so it holds every notice:
    // the warnings and the codes accepted with no effect on the motion.
    let notices = tee.moves.inner().notices().to_vec();
    Ok(ProgramAnalysis {
        analysis,
        geometric,
        feed,
        notices,
    })
}

/// The moves of a file program, each given to the reversal analysis on its way; a failed
/// read or analysis ends the stream and is kept in `failed`.
struct Analysed<'m> {
    moves: Checked<ngc::Moves>,
    analysis: MoveAnalysis<'m>,
    failed: Option<Error>,
}

impl Iterator for Analysed<'_> {
    type Item = Result<Move>;

    fn next(&mut self) -> Option<Result<Move>> {
        if self.failed.is_some() {
            return None;
        }
        match self.moves.next()? {
            Ok(m) => match self.analysis.push(&m) {
                Ok(()) => Some(Ok(m)),
                Err(e) => {
                    self.failed = Some(e);
                    None
                }
            },
            Err(e) => {
                self.failed = Some(e);
                None
            }
        }
    }
}
