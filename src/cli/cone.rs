//! `mtsim cone`: writes the cone-frustum NC program of a scenario.

use std::path::Path;

use super::{cone_of, print_stdout};
use crate::error::Result;
use crate::input::scenario::Scenario;
use crate::program::cone::{write_program, ConePath};
use crate::report::write_atomic;

pub fn run(path: &Path, output: Option<&Path>, g93: bool, tcp: bool) -> Result<i32> {
    let scenario = Scenario::load(path)?;
    let (cone, mut nc) = cone_of(&scenario, "cone")?;
    nc.inverse_time |= g93;
    nc.tcp |= tcp;
    let cone_path = ConePath::new(cone, &scenario.machine);
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
