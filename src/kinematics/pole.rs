//! The pole of a chain with two rotaries, and how near a tool direction is to it.
//!
//! Of the two rotaries, the one nearest the workpiece in the chain workpiece → tool (the
//! table's last rotary, or the head's first when the table has none) is the *inner* rotary.
//! In the workpiece frame its line keeps its home direction d (the bodies between it and the
//! workpiece do not turn). Where the tool direction t_w lies along that line the inner rotary
//! does not change the tool direction: it is free, and nearby it must turn fast for a small
//! change of t_w (the kinematic-chains spec, "Poles, as controls handle them"). The angle
//! from the pole is
//!
//! ```text
//! δ = atan2(|d × t_w|, |d · t_w|)          (either sense of the line)
//! ```
//!
//! Within `pole_tolerance_deg` of it (machine file `[kinematics]`, default
//! [`DEFAULT_POLE_TOLERANCE_DEG`]) the inner rotary holds and the tool direction may deviate
//! by at most that angle.

use nalgebra::Vector3;

use super::chain::{Chain, Side};
use crate::Axis;

/// The pole tolerance when the machine file gives none, deg (Siemens TRAORI's pole limit
/// is of this order).
pub const DEFAULT_POLE_TOLERANCE_DEG: f64 = 0.1;

/// Largest pole tolerance the machine file may give, deg: beyond it the tool direction
/// would deviate visibly from the program's.
pub const MAX_POLE_TOLERANCE_DEG: f64 = 5.0;

/// The pole of a chain with two rotaries.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pole {
    /// The rotary left free at the pole (nearest the workpiece).
    pub inner: Axis,
    /// The other rotary.
    pub outer: Axis,
    /// The inner rotary's line in the workpiece frame (unit).
    pub direction: Vector3<f64>,
}

impl Pole {
    /// The pole of `chain`; `None` unless it has exactly two rotaries.
    pub fn of(chain: &Chain) -> Option<Pole> {
        let rotaries: Vec<_> = chain.rotaries().map(|(s, l)| (s, *l)).collect();
        let [(s1, l1), (s2, l2)] = rotaries.as_slice() else {
            return None;
        };
        // Workpiece → tool: the table from the workpiece inward, then the head outward.
        let (inner, outer) = match (s1, s2) {
            (Side::Table, Side::Table) => (l2, l1),
            _ => (l1, l2),
        };
        Some(Pole {
            inner: inner.axis,
            outer: outer.axis,
            direction: inner.direction,
        })
    }

    /// The angle δ (deg) of tool direction `axis_w` (workpiece frame) from the pole.
    pub fn angle_deg(&self, axis_w: &Vector3<f64>) -> f64 {
        let t = axis_w.normalize();
        self.direction
            .cross(&t)
            .norm()
            .atan2(self.direction.dot(&t).abs())
            .to_degrees()
    }
}
