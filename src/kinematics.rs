//! Forward and inverse kinematics of the supported machine layouts.
//!
//! Frames: the machine frame M, in which the tool tip sits at (X, Y, Z) and the tool axis
//! is +Z (vertical spindle), and the table frame T fixed to the rotary table. T's origin is
//! the pivot, where the rotary axes cross; its Z axis is the C axis; at zero rotary angles
//! it is parallel to M. The pivot sits at `pivot_mm` in machine coordinates.
//!
//! A point p fixed to the table appears in the machine frame at
//!
//! ```text
//! m = pivot + R(q) p,   R = Rx(A) Rz(C)  (trt-ac)   or   R = Ry(B) Rz(C)  (trt-bc)
//! ```
//!
//! Inverse kinematics, for a tool tip p and unit tool axis t = (i, j, k) in the table frame
//! (t points from the tip toward the spindle): the tilt must carry t onto +Z, and a rotation
//! about Z keeps k, so `tilt = ±acos(k)`. Then C turns t's horizontal part, at angle
//! `atan2(j, i)`, onto the direction the tilt needs: +Y for A (so `C = atan2(i, j)`, the
//! spec's formula) and -X for B. The primary branch has tilt >= 0; the secondary branch has
//! tilt <= 0 and C + 180 deg. C is unwrapped to stay continuous with the previous value,
//! and kept when i = j = 0, where it is free.

use nalgebra::{Matrix3, Point3, Rotation3, Vector3};
use serde::{Deserialize, Serialize};

use crate::{Axis, AxisVec};

/// The layout of a machine.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Layout {
    /// Three linear axes, vertical spindle.
    #[serde(rename = "xyz")]
    Xyz,
    /// Tilting rotary table: A tilts about X, C turns the table about its own Z.
    #[serde(rename = "trt-ac")]
    TrtAc,
    /// Tilting rotary table: B tilts about Y, C turns the table about its own Z.
    #[serde(rename = "trt-bc")]
    TrtBc,
}

impl Layout {
    /// The axes a machine of this layout has, in order.
    pub fn axes(self) -> &'static [Axis] {
        match self {
            Layout::Xyz => &[Axis::X, Axis::Y, Axis::Z],
            Layout::TrtAc => &[Axis::X, Axis::Y, Axis::Z, Axis::A, Axis::C],
            Layout::TrtBc => &[Axis::X, Axis::Y, Axis::Z, Axis::B, Axis::C],
        }
    }

    /// The tilting axis, if any.
    pub fn tilt_axis(self) -> Option<Axis> {
        match self {
            Layout::Xyz => None,
            Layout::TrtAc => Some(Axis::A),
            Layout::TrtBc => Some(Axis::B),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Layout::Xyz => "xyz",
            Layout::TrtAc => "trt-ac",
            Layout::TrtBc => "trt-bc",
        }
    }
}

/// Which of the two inverse-kinematics solutions to take.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Branch {
    /// Tilt >= 0 (the spec's branch).
    #[default]
    Primary,
    /// Tilt <= 0 and C + 180 deg.
    Secondary,
}

/// Tool tip and tool axis in the table frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToolPose {
    /// Tool tip, mm, table frame.
    pub tip: Point3<f64>,
    /// Unit tool axis, from the tip toward the spindle, table frame.
    pub axis: Vector3<f64>,
}

/// The kinematic chain of a machine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kinematics {
    pub layout: Layout,
    /// Machine coordinates of the pivot (table-frame origin), mm.
    pub pivot_mm: Vector3<f64>,
}

/// Below this horizontal length of the tool axis, C is free and kept.
const C_FREE_EPS: f64 = 1e-12;

impl Kinematics {
    pub fn new(layout: Layout, pivot_mm: Vector3<f64>) -> Kinematics {
        Kinematics { layout, pivot_mm }
    }

    /// R(q): rotates table-frame vectors into the machine frame.
    pub fn table_rotation(&self, q: &AxisVec) -> Rotation3<f64> {
        // Written out with one sin_cos per angle (the ball bar reads it three times a sample):
        // Rx(A) Rz(C) and Ry(B) Rz(C).
        let (sc, cc) = q[Axis::C].to_radians().sin_cos();
        let m = match self.layout {
            Layout::Xyz => return Rotation3::identity(),
            Layout::TrtAc => {
                let (sa, ca) = q[Axis::A].to_radians().sin_cos();
                Matrix3::new(cc, -sc, 0.0, ca * sc, ca * cc, -sa, sa * sc, sa * cc, ca)
            }
            Layout::TrtBc => {
                let (sb, cb) = q[Axis::B].to_radians().sin_cos();
                Matrix3::new(cb * cc, -cb * sc, sb, sc, cc, 0.0, -sb * cc, sb * sc, cb)
            }
        };
        Rotation3::from_matrix_unchecked(m)
    }

    /// Machine coordinates of a table-frame point at axis positions `q`.
    pub fn table_to_machine(&self, q: &AxisVec, p: &Point3<f64>) -> Point3<f64> {
        Point3::from(self.pivot_mm + self.table_rotation(q) * p.coords)
    }

    /// Forward kinematics: axis positions → tool tip and tool axis in the table frame.
    pub fn forward(&self, q: &AxisVec) -> ToolPose {
        let r_inv = self.table_rotation(q).inverse();
        let tip_m = Vector3::new(q[Axis::X], q[Axis::Y], q[Axis::Z]);
        ToolPose {
            tip: Point3::from(r_inv * (tip_m - self.pivot_mm)),
            axis: r_inv * Vector3::z(),
        }
    }

    /// Inverse kinematics on `branch`, with C unwrapped near `previous_c_deg` (and kept
    /// there when the tool axis is along the table's Z). `axis` need not be normalized.
    pub fn inverse(&self, pose: &ToolPose, branch: Branch, previous_c_deg: f64) -> AxisVec {
        let mut q = AxisVec::ZERO;
        if let Some(tilt_axis) = self.layout.tilt_axis() {
            let t = pose.axis.normalize();
            let tilt = t.z.clamp(-1.0, 1.0).acos().to_degrees();
            // Direction (angle about Z) that t's horizontal part must be turned to by C.
            let target = match self.layout {
                Layout::TrtAc => 90.0,
                _ => 180.0,
            };
            let (tilt, target) = match branch {
                Branch::Primary => (tilt, target),
                Branch::Secondary => (-tilt, target + 180.0),
            };
            let horizontal = t.x.hypot(t.y);
            let c = if horizontal < C_FREE_EPS {
                previous_c_deg
            } else {
                unwrap_near(target - t.y.atan2(t.x).to_degrees(), previous_c_deg)
            };
            q[tilt_axis] = tilt;
            q[Axis::C] = c;
        }
        let m = self.table_to_machine(&q, &pose.tip);
        q[Axis::X] = m.x;
        q[Axis::Y] = m.y;
        q[Axis::Z] = m.z;
        q
    }
}

/// `angle_deg` plus the multiple of 360 that brings it nearest to `reference_deg`.
pub fn unwrap_near(angle_deg: f64, reference_deg: f64) -> f64 {
    angle_deg + 360.0 * ((reference_deg - angle_deg) / 360.0).round()
}

/// The first C value of a path: the spec's `atan2` range (-180, 180].
pub const C_START_REFERENCE_DEG: f64 = 0.0;
