//! The scenario a command runs, and its cone for the commands that need one.

use crate::error::{Error, Result};
use crate::input::program::{ConeTest, NcOptions};
use crate::input::scenario::Scenario;
use crate::program::test_of;

/// The cone of a scenario with a generated cone program, or an error naming `command`.
pub(crate) fn cone_of(scenario: &Scenario, command: &str) -> Result<(ConeTest, NcOptions)> {
    match test_of(scenario).generated_cone() {
        Some((cone, nc)) => Ok((*cone, *nc)),
        None => Err(Error::invalid(
            &scenario.path,
            format!("`mtsim {command}` needs a generated cone program ([program.cone])"),
        )
        .with_help("give the scenario a [program.cone] table instead of `file`")),
    }
}

/// Loads a scenario. A G-code file program is checked against the machine (motion
/// present, no move beyond the travel envelope) as its moves stream into the run
/// (`program::validate::checked`), not in a pass of its own; outputs are written only at
/// the end, so a bad move near the end still leaves none.
pub(crate) fn load_scenario(path: &std::path::Path) -> Result<Scenario> {
    Scenario::load(path)
}
