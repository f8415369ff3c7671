//! The cone-frustum test (NAS 979, ISO 10791-7; measured with a ball bar as ISO 10791-6 does):
//! the generated five-axis program of `program/cone.rs`, run in the scenario's directions.

use nalgebra::Point3;

use super::frame::CircleFrame;
use super::interface::{direction_names, BarSetup, Run, TestDescription, TestProgram};
use crate::error::Result;
use crate::input::budget::Revolution;
use crate::input::program::{ConeTest, Direction, NcOptions};
use crate::input::scenario::Scenario;
use crate::kinematics::Kinematics;
use crate::program::cone::{ConePath, ConeProgram};

/// `[program.cone]`: the cone's geometry, its NC options and the directions it runs.
pub struct Cone<'a> {
    pub cone: &'a ConeTest,
    pub nc: &'a NcOptions,
    pub directions: &'a [Direction],
}

/// The description of a cone's geometry, for a generated cone and a file that cuts one.
pub(super) fn geometry(c: &ConeTest) -> String {
    format!(
        "cone frustum, half apex {} deg, inclination {} deg, ball bar {} mm (circle radius {:.3} mm)",
        c.half_apex_deg,
        c.inclination_deg,
        c.ballbar_length_mm,
        c.radius_mm()
    )
}

/// The plane of a cone's measured circle, as the report says it.
pub(super) fn plane(c: &ConeTest) -> String {
    format!(
        "circle plane inclined {} deg about the table X axis",
        c.inclination_deg
    )
}

/// The ball bar of a cone: the measured circle's frame, the table ball at the base centre O,
/// the bar's length L.
pub(super) fn bar(c: &ConeTest) -> BarSetup {
    BarSetup {
        frame: CircleFrame::of_cone(c),
        pivot_table_mm: Point3::from(c.center_mm),
        length_mm: c.ballbar_length_mm,
    }
}

impl TestProgram for Cone<'_> {
    fn table(&self) -> &'static str {
        "[program.cone]"
    }

    fn planned_directions(&self) -> Option<Vec<Direction>> {
        Some(self.directions.to_vec())
    }

    fn run(
        &self,
        scenario: &Scenario,
        direction: Direction,
        lead_deg: f64,
    ) -> Result<Run<'static>> {
        let machine = &scenario.machine;
        let path = ConePath::new(*self.cone, machine).refusing_a_swing(&scenario.path)?;
        let options = NcOptions {
            lead_deg,
            clockwise: direction == Direction::Cw,
            ..*self.nc
        };
        let program = ConeProgram::new(&path, &machine.name, &options);
        Ok(Run {
            direction,
            measured: Some(program.measured()),
            moves: Box::new(program.moves().map(Ok)),
        })
    }

    fn revolution(&self) -> Option<Revolution> {
        Some(Revolution {
            radius_mm: self.cone.radius_mm(),
            feed_mm_min: self.nc.feed_mm_min,
            table: self.table(),
        })
    }

    fn bar(&self, _kinematics: &Kinematics) -> Option<BarSetup> {
        Some(bar(self.cone))
    }

    fn description(&self, lead_deg: f64) -> TestDescription {
        let cone = self.cone;
        TestDescription {
            test: "cone frustum (ISO 10791-6 ball-bar version of NAS 979)".to_string(),
            geometry: geometry(cone),
            radius_mm: Some(cone.radius_mm()),
            feed_mm_min: Some(self.nc.feed_mm_min),
            directions: direction_names(self.directions),
            plane: plane(cone),
            position_mm: Some([cone.center_mm.x, cone.center_mm.y, cone.center_mm.z]),
            start_arc_deg: Some(lead_deg),
            overshoot_arc_deg: Some(lead_deg),
            program_file: None,
        }
    }

    fn title(&self, name: &str) -> String {
        let cone = self.cone;
        format!(
            "{name}: cone {}/{} deg, O ({}, {}, {}) mm, L {} mm, F{}",
            cone.half_apex_deg,
            cone.inclination_deg,
            cone.center_mm.x,
            cone.center_mm.y,
            cone.center_mm.z,
            cone.ballbar_length_mm,
            self.nc.feed_mm_min
        )
    }

    fn generated_cone(&self) -> Option<(&ConeTest, &NcOptions)> {
        Some((self.cone, self.nc))
    }
}
