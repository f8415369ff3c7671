//! **program** — stage 1: NC programs in, canonical moves out.
//! Inputs: a G-code file (read by the `ngc` crate) or a generated test (cone, circle) from `input`, each a [`TestProgram`] of `tests/`.
//! Outputs: a stream of canonical [`Move`]s, absolute axis positions in mm and deg, one block at a time.

pub mod circle;
pub mod cone;
pub mod cone_pole;
pub mod file;
pub mod moves;
pub mod tests;
pub mod validate;

use crate::error::Result;
use crate::input::program::Direction;
use crate::input::scenario::Scenario;

pub use moves::Moves;
pub use ngc::{Feed, FeedMode, Motion, Move, MoveKind, PathControl};
pub use tests::{test_of, Run, TestProgram};

/// The program a scenario runs in `direction`, with `lead_deg` of extra path before and after
/// the measured revolution of a generated test ([`TestProgram::run`]). Generators feed their
/// moves straight in; a file is read as it streams (and runs in the direction it was written),
/// checked against the machine as it streams ([`validate::checked`]: no motion or an absurd
/// move is bad input).
pub fn scenario_run(
    scenario: &Scenario,
    direction: Direction,
    lead_deg: f64,
) -> Result<Run<'static>> {
    test_of(scenario).run(scenario, direction, lead_deg)
}

/// The reader's warnings about the scenario's program file ([`file::warnings`]); none for a
/// generated test.
pub fn scenario_warnings(scenario: &Scenario) -> Result<Vec<ngc::Notice>> {
    test_of(scenario).warnings(scenario)
}

/// The program a scenario runs, as [`scenario_run`], with a file's moves as the interpreter
/// gives them, unchecked against the machine (`mtsim blocks` prints them all).
pub fn scenario_run_unchecked(scenario: &Scenario, direction: Direction) -> Result<Run<'static>> {
    test_of(scenario).run_unchecked(scenario, direction)
}
