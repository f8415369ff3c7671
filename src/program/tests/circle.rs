//! The circular test of ISO 230-4: the planar circle of `program/circle.rs`, programmed in
//! machine coordinates with any rotary axes at zero, run in the scenario's directions.

use nalgebra::{Point3, Vector3};

use super::frame::CircleFrame;
use super::interface::{direction_names, BarSetup, Run, TestDescription, TestProgram};
use crate::error::Result;
use crate::input::budget::Revolution;
use crate::input::program::{CircleTest, Direction};
use crate::input::scenario::Scenario;
use crate::kinematics::Kinematics;
use crate::program::circle::CircleProgram;

/// `[program.circle]`: the circle and the directions it runs.
pub struct Circle<'a> {
    pub circle: &'a CircleTest,
    pub directions: &'a [Direction],
}

impl TestProgram for Circle<'_> {
    fn table(&self) -> &'static str {
        "[program.circle]"
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
        let mut program = CircleProgram::new(self.circle, direction == Direction::Cw, lead_deg);
        // A lead of whole turns near the axes' limits (`input::lead_in`): only for the lead
        // it was sized as, not for a run without one.
        let lead = scenario.simulate.lead_in;
        if lead_deg > 0.0 && lead.is_some_and(|l| l.whole_turns && l.deg == lead_deg) {
            program = program.in_whole_turns();
        }
        Ok(Run {
            direction,
            measured: Some(program.measured()),
            moves: Box::new(program.moves().map(Ok)),
        })
    }

    fn revolution(&self) -> Option<Revolution> {
        Some(Revolution {
            radius_mm: self.circle.radius_mm,
            feed_mm_min: self.circle.feed_mm_min,
            table: self.table(),
        })
    }

    /// The bar's length is the radius; the table ball sits at the centre. On a general chain
    /// it sits where the centre's X Y Z put the tool ball (the gauge point, by the chain's
    /// forward kinematics, workpiece frame); on a named layout at the centre less the pivot.
    fn bar(&self, kinematics: &Kinematics) -> Option<BarSetup> {
        let circle = self.circle;
        let center_table = kinematics.tip_at_home_rotaries(circle.center_mm);
        Some(BarSetup {
            frame: CircleFrame::planar(center_table.into(), circle.plane),
            pivot_table_mm: Point3::from(center_table),
            length_mm: circle.radius_mm,
        })
    }

    /// `check` places θ's frame at the centre less the pivot on every machine, a general
    /// chain's too (where [`TestProgram::bar`] uses the chain's gauge point): kept as it was.
    fn theta_frame(&self, kinematics: &Kinematics) -> Option<CircleFrame> {
        let center = Vector3::from(self.circle.center_mm) - kinematics.pivot_mm;
        Some(CircleFrame::planar(center.into(), self.circle.plane))
    }

    fn description(&self, lead_deg: f64) -> TestDescription {
        let circle = self.circle;
        TestDescription {
            test: "circular test (ISO 230-4)".to_string(),
            geometry: format!("circle, radius {} mm", circle.radius_mm),
            radius_mm: Some(circle.radius_mm),
            feed_mm_min: Some(circle.feed_mm_min),
            directions: direction_names(self.directions),
            plane: format!("{:?}", circle.plane),
            position_mm: Some(circle.center_mm),
            start_arc_deg: Some(lead_deg),
            overshoot_arc_deg: Some(lead_deg),
            program_file: None,
        }
    }

    fn title(&self, name: &str) -> String {
        let circle = self.circle;
        format!(
            "{name}: circle r {} mm, F{} ({:?})",
            circle.radius_mm, circle.feed_mm_min, circle.plane
        )
    }

    fn circle(&self) -> Option<&CircleTest> {
        Some(self.circle)
    }
}
