//! `mtsim cone`: writes the cone-frustum NC program of a scenario.

use std::path::Path;

use super::{cone_of, print_stdout};
use crate::error::{Error, Result};
use crate::input::scenario::Scenario;
use crate::program::cone::{write_program, ConePath};
use crate::report::write_atomic;

pub fn run(path: &Path, output: Option<&Path>, g93: bool, tcp: bool) -> Result<i32> {
    let scenario = Scenario::load(path)?;
    let (cone, mut nc) = cone_of(&scenario, "cone")?;
    nc.inverse_time |= g93;
    nc.tcp |= tcp;
    if nc.inverse_time && nc.tcp {
        // Both asked for, on the line or in the scenario: the TCP program feeds the tip in
        // mm/min (G94), so G93 would be dropped without a word.
        return Err(Error::usage(
            "--g93 with --tcp (or [program.cone] inverse_time with tcp): the G43.4 program feeds the tool tip in mm/min (G94) and writes no G93; choose one",
        ));
    }
    let cone_path = ConePath::new(cone, &scenario.machine).refusing_a_swing(path)?;
    let (text, _) = write_program(&cone_path, &scenario.machine.name, &nc);
    match output {
        Some(out) => {
            write_atomic(out, text.as_bytes())?;
            super::note(&format!("wrote {} ({} blocks)", out.display(), nc.segments));
        }
        None => print_stdout(&text),
    }
    Ok(0)
}
