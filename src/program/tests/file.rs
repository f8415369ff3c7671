//! A G-code program file: read as it streams and run as it was written (once, in the
//! direction it goes), measured on the cone the scenario gives beside it, if any.

use std::path::{Path, PathBuf};

use super::cone;
use super::interface::{BarSetup, Run, TestDescription, TestProgram};
use crate::error::Result;
use crate::input::program::{ConeTest, Direction, MeasuredLines};
use crate::input::scenario::Scenario;
use crate::kinematics::Kinematics;
use crate::program::{file, validate};

/// `[program] file`, with the cone's geometry when the scenario gives one.
pub struct File<'a> {
    pub path: &'a PathBuf,
    pub cone: Option<&'a ConeTest>,
}

/// The lines `[simulate] measure_lines` names, if any.
fn measured(scenario: &Scenario) -> Option<MeasuredLines> {
    scenario
        .simulate
        .measure_lines
        .map(|[first, last]| MeasuredLines { first, last })
}

impl TestProgram for File<'_> {
    fn table(&self) -> &'static str {
        "[program] file"
    }

    fn planned_directions(&self) -> Option<Vec<Direction>> {
        None
    }

    /// The file read as it streams, checked against the machine as it streams
    /// ([`validate::checked`]: no motion or an absurd move is bad input).
    fn run(
        &self,
        scenario: &Scenario,
        _direction: Direction,
        _lead_deg: f64,
    ) -> Result<Run<'static>> {
        Ok(Run {
            direction: Direction::Ccw,
            measured: measured(scenario),
            moves: validate::checked(
                self.path,
                &scenario.machine,
                scenario.simulate.tcp,
                file::read_moves(self.path, &scenario.reader)?,
            ),
        })
    }

    fn run_unchecked(&self, scenario: &Scenario, _direction: Direction) -> Result<Run<'static>> {
        Ok(Run {
            direction: Direction::Ccw,
            measured: measured(scenario),
            moves: file::read_file(self.path, &scenario.reader)?,
        })
    }

    fn warnings(&self, scenario: &Scenario) -> Result<Vec<ngc::Notice>> {
        file::warnings(self.path, &scenario.reader)
    }

    fn file(&self) -> Option<&Path> {
        Some(self.path)
    }

    fn bar(&self, _kinematics: &Kinematics) -> Option<BarSetup> {
        self.cone.map(cone::bar)
    }

    fn cone(&self) -> Option<&ConeTest> {
        self.cone
    }

    fn starts_unsettled(&self) -> bool {
        true
    }

    fn description(&self, _lead_deg: f64) -> TestDescription {
        let cone = self.cone;
        TestDescription {
            test: "G-code file".to_string(),
            geometry: cone.map_or("as programmed".to_string(), cone::geometry),
            radius_mm: cone.map(|c| c.radius_mm()),
            feed_mm_min: None,
            directions: vec!["ccw".to_string()],
            plane: cone.map_or("as programmed".to_string(), cone::plane),
            position_mm: cone.map(|c| [c.center_mm.x, c.center_mm.y, c.center_mm.z]),
            start_arc_deg: None,
            overshoot_arc_deg: None,
            program_file: Some(self.path.display().to_string()),
        }
    }

    fn title(&self, name: &str) -> String {
        format!("{name}: {}", self.path.display())
    }
}
