//! The poses of a named layout's cradle and table at one sample, on the actual chain
//! (location errors included), for the collision scene: the lines of the tilting and the
//! table axis taken once, each turn built from its quaternion directly.
//!
//! ```text
//! T(θ) x = r x r⁻¹ + (p − r p r⁻¹),   r = (cos θ/2, sin θ/2 · d)     (line through p along d)
//! cradle = T_tilt(s q_tilt) · home,   table = T_tilt(s q_tilt) · T_table(s q_table) · home
//! ```
//!
//! with `home` the translation to the pivot and `s` the sign of a positive turn
//! ([`super::Layout::table_turn_sign`]): `Kinematics::actual_cradle_pose` and
//! `Kinematics::actual_table_pose`, sharing the tilt, with the half angle's sine and
//! cosine reduced exactly in degrees.

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};

use super::location::AxisLine;
use crate::numeric::sin_cos_deg;
use crate::AxisVec;

/// The actual lines (location errors included) of the tilting axis and of the table axis,
/// with their indices into the axis vector, and the sign of a positive turn.
#[derive(Clone, Copy, Debug)]
pub struct CradleTablePoses {
    axes: Option<((usize, AxisLine), (usize, AxisLine))>,
    sign: f64,
    pivot: Vector3<f64>,
}

impl CradleTablePoses {
    /// The poses of a cradle tilting about `tilt` carrying a table turning about `table`
    /// (each: its index into the axis vector and its actual line), `sign` the sign of a
    /// positive turn; with `None`, cradle and table sit at the pivot (`pivot_mm`).
    pub fn new(
        axes: Option<((usize, AxisLine), (usize, AxisLine))>,
        sign: f64,
        pivot_mm: Vector3<f64>,
    ) -> CradleTablePoses {
        CradleTablePoses {
            axes,
            sign,
            pivot: pivot_mm,
        }
    }

    /// `T(θ)` of [`AxisLine::turn`], built from the quaternion directly:
    /// `r = (cos θ/2, sin θ/2 · d)`, the half angle's sine and cosine reduced exactly in
    /// degrees ([`sin_cos_deg`]).
    fn turn(line: &AxisLine, angle_deg: f64) -> Isometry3<f64> {
        let (s, c) = sin_cos_deg(0.5 * angle_deg);
        let r = UnitQuaternion::new_unchecked(Quaternion::from_parts(
            c,
            line.direction.into_inner() * s,
        ));
        Isometry3::from_parts(Translation3::from(line.point_mm - r * line.point_mm), r)
    }

    /// The cradle and the table poses at `q` (`Kinematics::actual_cradle_pose` and
    /// `Kinematics::actual_table_pose`, sharing the tilt).
    pub fn poses(&self, q: &AxisVec) -> (Isometry3<f64>, Isometry3<f64>) {
        let home = Isometry3::from_parts(Translation3::from(self.pivot), Default::default());
        match &self.axes {
            Some(((tilt, tilt_line), (table, table_line))) => {
                let t = CradleTablePoses::turn(tilt_line, self.sign * q.0[*tilt]);
                let c = CradleTablePoses::turn(table_line, self.sign * q.0[*table]);
                (t * home, t * c * home)
            }
            None => (home, home),
        }
    }
}
