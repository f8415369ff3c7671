//! The measured circle's frame: what a test hands its measurements to give every table
//! point its angle θ on the circle.
//!
//! A frame holds an origin o and a rotation R whose columns are the frame's axes, both in the
//! table frame. A table point p has frame coordinates `v = Rᵀ (p − o)` and
//! `θ = atan2(v_y, v_x)` in [0, 360) deg: counter-clockwise from the frame's +X seen from its
//! +Z. The cone frame is `o = O`, `R = Ry(−β)`; a planar circle in G17/G18/G19 uses the
//! plane's two axes in G-code order (X→Y, Z→X, Y→Z).

use nalgebra::{Matrix3, Point3, Rotation3, Vector3};

use crate::input::program::ConeTest;
use crate::numeric::{sin_cos_deg, wrap_360};
use crate::Plane;

/// The measured circle's frame in the table frame: origin (mm) and orientation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CircleFrame {
    /// Origin, table frame, mm.
    pub origin_mm: Vector3<f64>,
    /// Frame axes as columns, in table coordinates.
    pub rotation: Rotation3<f64>,
}

impl CircleFrame {
    /// The cone frame: origin O = `center_mm` (table frame), rotated by `Ry(-inclination)`.
    pub fn cone(center_mm: [f64; 3], inclination_deg: f64) -> Self {
        CircleFrame {
            origin_mm: Vector3::from(center_mm),
            rotation: Rotation3::from_axis_angle(&Vector3::y_axis(), -inclination_deg.to_radians()),
        }
    }

    /// A circle in `plane` about `center_mm`; theta runs from the plane's first axis toward
    /// its second (XY: X→Y, ZX: Z→X, YZ: Y→Z), counter-clockwise seen from the normal.
    pub fn planar(center_mm: [f64; 3], plane: Plane) -> Self {
        let (x, y, z) = match plane {
            Plane::XY => (Vector3::x(), Vector3::y(), Vector3::z()),
            Plane::ZX => (Vector3::z(), Vector3::x(), Vector3::y()),
            Plane::YZ => (Vector3::y(), Vector3::z(), Vector3::x()),
        };
        CircleFrame {
            origin_mm: Vector3::from(center_mm),
            rotation: Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, y, z])),
        }
    }

    /// The measured circle of a cone-frustum test.
    pub fn of_cone(cone: &ConeTest) -> Self {
        CircleFrame::cone(cone.center_mm.into(), cone.inclination_deg)
    }

    /// Theta of a table-frame point, deg in [0, 360).
    pub fn theta_deg(&self, p_table: &Point3<f64>) -> f64 {
        let v = self.rotation.inverse() * (p_table.coords - self.origin_mm);
        wrap_360(v.y.atan2(v.x).to_degrees())
    }

    /// [`CircleFrame::theta_deg`] with `(sin θ, cos θ)` from the point's own coordinates in
    /// the circle's plane, `(y, x) / √(x² + y²)` (from `sin_cos_deg(wrap_360(θ))` where the point is on
    /// the circle's axis).
    #[inline]
    pub fn theta_deg_sin_cos(&self, p_table: &Point3<f64>) -> (f64, (f64, f64)) {
        let v = self.rotation.inverse() * (p_table.coords - self.origin_mm);
        let theta = wrap_360(v.y.atan2(v.x).to_degrees());
        let r = (v.x * v.x + v.y * v.y).sqrt();
        if r > 0.0 && r.is_finite() {
            let inv = 1.0 / r;
            (theta, (v.y * inv, v.x * inv))
        } else {
            (theta, sin_cos_deg(wrap_360(theta)))
        }
    }
}
