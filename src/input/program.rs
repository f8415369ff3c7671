//! What program a scenario runs: the cone-frustum test, the ISO 230-4 circle, and the
//! options of the program generator. Plain values with their closed-form geometry; the
//! generators that turn them into canonical moves are in `crate::program`.
//!
//! Cone geometry, from `docs/model.md` (α half apex angle, β inclination,
//! O base-circle centre in the table frame, L ball-bar length):
//!
//! ```text
//! cone frame:       table frame rotated by Ry(-β), origin at O (apex leans toward table -X)
//! measured circle:  r = L cos α,  h = L sin α
//! P(θ)  = O + Ry(-β) (r cos θ, r sin θ, h)          θ counter-clockwise seen from the apex
//! apex  = O + Ry(-β) (0, 0, L / sin α)
//! t(θ)  = unit(apex - P(θ))                          tool axis along the generatrix
//! ```
//!
//! The bar O→P is perpendicular to the generatrix: (P - O)·(apex - P) = L²... expanded,
//! r·(-r) + h·(L/sin α - h) = -L²cos²α + L² - L²sin²α = 0.

use nalgebra::{Point3, Rotation3, Vector3};
use serde::{Deserialize, Serialize};

use crate::kinematics::ToolPose;
use crate::{Axis, Plane};

/// The cone-frustum test geometry. Angles in deg, lengths in mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConeTest {
    /// Half apex angle α, deg, in (0, 90).
    pub half_apex_deg: f64,
    /// Inclination β of the cone axis from the table's Z, deg.
    pub inclination_deg: f64,
    /// Base-circle centre O in the table frame, mm.
    pub center_mm: Vector3<f64>,
    /// Ball-bar length L, mm.
    pub ballbar_length_mm: f64,
}

impl ConeTest {
    /// Radius of the measured circle, `r = L cos α`, mm.
    pub fn radius_mm(&self) -> f64 {
        self.ballbar_length_mm * self.half_apex_deg.to_radians().cos()
    }

    /// Height of the measured circle above the base plane, `h = L sin α`, mm.
    pub fn height_mm(&self) -> f64 {
        self.ballbar_length_mm * self.half_apex_deg.to_radians().sin()
    }

    /// Orientation of the cone frame in the table frame, `Ry(-β)`.
    pub fn frame_rotation(&self) -> Rotation3<f64> {
        Rotation3::from_axis_angle(&Vector3::y_axis(), -self.inclination_deg.to_radians())
    }

    /// P(θ): the tool-side ball centre (tool tip) at `theta_rad`, table frame, mm.
    pub fn point(&self, theta_rad: f64) -> Point3<f64> {
        self.poses().point(theta_rad)
    }

    /// The cone apex, table frame, mm.
    pub fn apex(&self) -> Point3<f64> {
        self.poses().apex
    }

    /// Tool tip and tool axis (toward the apex) at `theta_rad`.
    pub fn pose(&self, theta_rad: f64) -> ToolPose {
        self.poses().pose(theta_rad)
    }

    /// The constants of [`ConeTest::pose`], for a path that asks for many poses.
    pub fn poses(&self) -> ConePoses {
        let rotation = self.frame_rotation();
        let l = self.ballbar_length_mm / self.half_apex_deg.to_radians().sin();
        ConePoses {
            center_mm: self.center_mm,
            rotation,
            radius_mm: self.radius_mm(),
            height_mm: self.height_mm(),
            apex: Point3::from(self.center_mm + rotation * Vector3::new(0.0, 0.0, l)),
        }
    }
}

/// The poses of a cone-frustum test ([`ConeTest::poses`]): its frame, measured circle and
/// apex, so that a pose costs one `sin_cos`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConePoses {
    /// Base-circle centre O, table frame, mm.
    center_mm: Vector3<f64>,
    /// `Ry(-β)`.
    rotation: Rotation3<f64>,
    /// `r = L cos α` and `h = L sin α`, mm.
    radius_mm: f64,
    height_mm: f64,
    /// `O + Ry(-β) (0, 0, L / sin α)`, table frame, mm.
    pub apex: Point3<f64>,
}

impl ConePoses {
    /// `P(θ) = O + Ry(-β) (r cos θ, r sin θ, h)`, table frame, mm.
    pub fn point(&self, theta_rad: f64) -> Point3<f64> {
        let (s, c) = theta_rad.sin_cos();
        let r = self.radius_mm;
        Point3::from(self.center_mm + self.rotation * Vector3::new(r * c, r * s, self.height_mm))
    }

    /// Tool tip and tool axis (toward the apex) at `theta_rad`.
    pub fn pose(&self, theta_rad: f64) -> ToolPose {
        let tip = self.point(theta_rad);
        ToolPose {
            tip,
            axis: (self.apex - tip).normalize(),
        }
    }
}

/// Options of the NC program generator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NcOptions {
    /// Number of G01 blocks per revolution (the paper: 360).
    pub segments: usize,
    /// Feed of the tool ball relative to the table, mm/min.
    pub feed_mm_min: f64,
    /// Write inverse-time feed (G93, F = 1/block time in 1/min) instead of the mixed-unit F.
    pub inverse_time: bool,
    /// Write a tool-centre-point program (G43.4): X Y Z are the tool tip in the table frame and F is the tip feed.
    pub tcp: bool,
    /// Extra path before θ = 0 and after θ = 360 deg, deg, so a simulation can leave the
    /// measured revolution out of its start and stop transients.
    pub lead_deg: f64,
    /// Measure counter-clockwise (θ increasing) or clockwise.
    pub clockwise: bool,
}

/// Where the measured revolution sits in a generated program.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MeasuredLines {
    /// Source line of the first block of the measured revolution (θ leaving 0).
    pub first: usize,
    /// Source line of the last block of the measured revolution (θ arriving at 360 deg).
    pub last: usize,
}

/// A planar circle test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CircleTest {
    pub plane: Plane,
    /// Circle centre, machine coordinates, mm.
    pub center_mm: [f64; 3],
    /// Radius, mm.
    pub radius_mm: f64,
    /// Path feed, mm/min.
    pub feed_mm_min: f64,
}

impl CircleTest {
    /// The in-plane axes (u, v) and the normal axis, u→v counter-clockwise seen from +normal.
    pub fn axes(&self) -> (Axis, Axis, Axis) {
        self.plane.axes()
    }

    /// The point at `theta_deg`, machine coordinates, mm.
    pub fn point(&self, theta_deg: f64) -> [f64; 3] {
        let (u, v, _) = self.axes();
        let (s, c) = theta_deg.to_radians().sin_cos();
        let mut p = self.center_mm;
        p[u.index()] += self.radius_mm * c;
        p[v.index()] += self.radius_mm * s;
        p
    }
}

/// The direction of travel of a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Direction {
    /// Counter-clockwise: theta increases with time.
    Ccw,
    /// Clockwise: theta decreases with time.
    Cw,
}
