//! What the bar reads: the distance between its two balls, less its nominal length.

use nalgebra::Point3;

use crate::kinematics::Kinematics;
use crate::{Axis, AxisVec};

/// Ball-bar deviation `|p_tool - p_pivot| - L`, mm, both balls in the machine frame; the
/// table ball is moved by the actual chain (location errors included).
///
/// `q_actual`: actual axis positions (mm, deg); the tool tip is its (X, Y, Z).
/// `pivot_table_mm`: the table ball, table frame, mm. `length_mm`: nominal bar length L.
pub fn deviation_mm(
    kin: &Kinematics,
    q_actual: &AxisVec,
    pivot_table_mm: &Point3<f64>,
    length_mm: f64,
) -> f64 {
    if let Some(chain) = &kin.actual_chain() {
        // A general chain: the tool ball at the gauge point (tool length 0) carried by the
        // head, the table ball carried by the table (the kinematic-chains spec), both by the
        // actual chain (location errors included).
        let (tool, _) = chain.tool_in_machine(q_actual, 0.0);
        let pivot = chain.table_pose(q_actual) * pivot_table_mm;
        return (tool - pivot).norm() - length_mm;
    }
    let tool = Point3::new(q_actual[Axis::X], q_actual[Axis::Y], q_actual[Axis::Z]);
    let pivot = kin.actual_table_to_machine(q_actual, pivot_table_mm);
    (tool - pivot).norm() - length_mm
}
