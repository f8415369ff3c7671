//! **program** — stage 1: NC programs in, canonical moves out.
//! Inputs: a G-code file (read by the `ngc` crate) or a generated test (cone, circle) from `input`.
//! Outputs: a stream of canonical [`Move`]s, absolute axis positions in mm and deg, one block at a time.

pub mod circle;
pub mod cone;
pub mod file;
pub mod moves;
pub mod validate;

use crate::error::Result;
use crate::input::program::{Direction, MeasuredLines, NcOptions};
use crate::input::scenario::{Program, Scenario};

pub use moves::Moves;
pub use ngc::{FeedMode, Motion, Move, MoveKind, PathControl};

/// One program to run: its moves and the lines of its measured revolution.
pub struct Run<'a> {
    pub direction: Direction,
    pub moves: Moves<'a>,
    /// Lines whose samples the ball bar measures; `None`: every move after the first.
    pub measured: Option<MeasuredLines>,
}

/// The program a scenario runs in `direction`, with `lead_deg` of extra path before and after
/// the measured revolution of a generated test. Generators feed their moves straight in; a
/// file is read as it streams (and runs in the direction it was written), checked against
/// the machine as it streams ([`validate::checked`]: no motion or an absurd move is bad
/// input).
pub fn scenario_run(
    scenario: &Scenario,
    direction: Direction,
    lead_deg: f64,
) -> Result<Run<'static>> {
    let machine = &scenario.machine;
    let clockwise = direction == Direction::Cw;
    Ok(match &scenario.program {
        Program::Cone { cone, nc, .. } => {
            let path = cone::ConePath::new(*cone, machine);
            let options = NcOptions {
                lead_deg,
                clockwise,
                ..*nc
            };
            let program = cone::ConeProgram::new(&path, &machine.name, &options);
            Run {
                direction,
                measured: Some(program.measured()),
                moves: Box::new(program.moves().map(Ok)),
            }
        }
        Program::Circle { circle, .. } => {
            let mut program = circle::CircleProgram::new(circle, clockwise, lead_deg);
            // A lead of whole turns near the axes' limits (`input::lead_in`): only for the
            // lead it was sized as, not for a run without one.
            let lead = scenario.simulate.lead_in;
            if lead_deg > 0.0 && lead.is_some_and(|l| l.whole_turns && l.deg == lead_deg) {
                program = program.in_whole_turns();
            }
            Run {
                direction,
                measured: Some(program.measured()),
                moves: Box::new(program.moves().map(Ok)),
            }
        }
        Program::File { path, .. } => Run {
            direction: Direction::Ccw,
            measured: scenario
                .simulate
                .measure_lines
                .map(|[first, last]| MeasuredLines { first, last }),
            moves: validate::checked(
                path,
                machine,
                scenario.simulate.tcp,
                file::read_moves(path, &scenario.reader)?,
            ),
        },
    })
}

/// The reader's warnings about the scenario's program file ([`file::warnings`]); none for a
/// generated test.
pub fn scenario_warnings(scenario: &Scenario) -> Result<Vec<ngc::Notice>> {
    match &scenario.program {
        Program::File { path, .. } => file::warnings(path, &scenario.reader),
        _ => Ok(Vec::new()),
    }
}

/// The program a scenario runs, as [`scenario_run`], with a file's moves as the interpreter
/// gives them, unchecked against the machine (`mtsim blocks` prints them all).
pub fn scenario_run_unchecked(scenario: &Scenario, direction: Direction) -> Result<Run<'static>> {
    match &scenario.program {
        Program::File { path, .. } => Ok(Run {
            direction: Direction::Ccw,
            measured: scenario
                .simulate
                .measure_lines
                .map(|[first, last]| MeasuredLines { first, last }),
            moves: file::read_file(path, &scenario.reader)?,
        }),
        _ => scenario_run(scenario, direction, 0.0),
    }
}
