//! The scenario argument of every function: a path to a scenario file, or a dict of the
//! file's tables whose `machine` is a path or a dict of the machine file's tables.

use std::path::{Path, PathBuf};

use mtsim::input::Scenario;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::Texts;
use crate::to_toml::dict_to_toml;

/// The name a dict scenario's errors carry; its relative paths resolve from the
/// current folder.
pub const DICT_SCENARIO: &str = "<scenario dict>";
/// The name a dict machine's errors carry.
pub const DICT_MACHINE: &str = "<machine dict>";

/// A scenario as read from Python: plain data, so that it loads with the GIL released.
pub enum ScenarioInput {
    File(PathBuf),
    Dict {
        text: String,
        /// The machine's TOML text when the dict gave its tables.
        machine: Option<String>,
    },
}

impl ScenarioInput {
    pub fn from_py(value: &Bound<'_, PyAny>) -> PyResult<ScenarioInput> {
        let Ok(dict) = value.cast::<PyDict>() else {
            return Ok(ScenarioInput::File(value.extract::<PathBuf>()?));
        };
        let dict = dict.copy()?;
        let machine = match dict.get_item("machine")? {
            Some(m) if m.is_instance_of::<PyDict>() => {
                let text = dict_to_toml(&m, "machine")?;
                dict.set_item("machine", DICT_MACHINE)?;
                Some(text)
            }
            _ => None,
        };
        Ok(ScenarioInput::Dict {
            text: dict_to_toml(dict.as_any(), "scenario")?,
            machine,
        })
    }

    /// Reads and checks the scenario as `Scenario::load` reads a file.
    pub fn load(&self) -> mtsim::Result<Scenario> {
        match self {
            ScenarioInput::File(path) => Scenario::load(path),
            ScenarioInput::Dict { text, machine } => Scenario::from_toml(
                Path::new(DICT_SCENARIO),
                text,
                machine.as_deref().map(|m| (Path::new(DICT_MACHINE), m)),
            ),
        }
    }

    /// The texts made from dicts, by the names their errors carry.
    pub fn texts(&self) -> Texts {
        match self {
            ScenarioInput::File(_) => Vec::new(),
            ScenarioInput::Dict { text, machine } => std::iter::once((DICT_SCENARIO, text))
                .chain(machine.iter().map(|m| (DICT_MACHINE, m)))
                .map(|(p, t)| (PathBuf::from(p), t.clone()))
                .collect(),
        }
    }
}
