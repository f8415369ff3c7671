//! The cone-frustum test: geometry of the measured circle and the NC program generator.
//!
//! From `shared/spec/cone-frustum.md`. Inputs: half apex angle α, inclination β, base-circle
//! centre O (table frame, mm) and ball-bar length L (mm).
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

use std::f64::consts::TAU;
use std::fmt::Write as _;

use nalgebra::{Point3, Rotation3, Vector3};

use crate::axis::{Axis, AxisVec};
use crate::ballbar::CircleFrame;
use crate::kinematics::{Branch, Kinematics, ToolPose, C_START_REFERENCE_DEG};
use crate::machine::Machine;

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
        let (s, c) = theta_rad.sin_cos();
        let r = self.radius_mm();
        Point3::from(
            self.center_mm + self.frame_rotation() * Vector3::new(r * c, r * s, self.height_mm()),
        )
    }

    /// The cone apex, table frame, mm.
    pub fn apex(&self) -> Point3<f64> {
        let l = self.ballbar_length_mm / self.half_apex_deg.to_radians().sin();
        Point3::from(self.center_mm + self.frame_rotation() * Vector3::new(0.0, 0.0, l))
    }

    /// Tool tip and tool axis (toward the apex) at `theta_rad`.
    pub fn pose(&self, theta_rad: f64) -> ToolPose {
        let tip = self.point(theta_rad);
        ToolPose {
            tip,
            axis: (self.apex() - tip).normalize(),
        }
    }
}

/// The cone path on one machine: axis positions as functions of θ on one IK branch.
#[derive(Clone, Copy, Debug)]
pub struct ConePath {
    pub cone: ConeTest,
    pub kinematics: Kinematics,
    pub branch: Branch,
}

impl ConePath {
    /// Chooses the IK branch: the spec's (tilt >= 0) unless the machine's tilt limits
    /// exclude it and the other branch fits.
    pub fn new(cone: ConeTest, machine: &Machine) -> ConePath {
        let kinematics = machine.kinematics;
        let mut path = ConePath {
            cone,
            kinematics,
            branch: Branch::Primary,
        };
        if let Some(tilt) = kinematics.layout.tilt_axis() {
            let limits = machine.axis(tilt);
            let fits = |path: &ConePath| {
                (0..360).all(|k| {
                    limits.within_travel(path.axes_near((k as f64).to_radians(), 0.0)[tilt])
                })
            };
            if !fits(&path) {
                let other = ConePath {
                    branch: Branch::Secondary,
                    ..path
                };
                if fits(&other) {
                    path = other;
                }
            }
        }
        path
    }

    /// Axis positions at `theta_rad`, with C unwrapped nearest `reference_c_deg`.
    pub fn axes_near(&self, theta_rad: f64, reference_c_deg: f64) -> AxisVec {
        self.kinematics
            .inverse(&self.cone.pose(theta_rad), self.branch, reference_c_deg)
    }

    /// Axis positions at θ = 0, with C in the spec's atan2 range.
    pub fn start(&self) -> AxisVec {
        self.axes_near(0.0, C_START_REFERENCE_DEG)
    }

    /// Axis positions at `n + 1` equally spaced θ from `theta0_rad` over `span_rad`, C kept
    /// continuous from the start value.
    pub fn sampled(
        &self,
        theta0_rad: f64,
        span_rad: f64,
        n: usize,
    ) -> impl Iterator<Item = (f64, AxisVec)> + '_ {
        let mut previous_c = self.axes_near(theta0_rad, C_START_REFERENCE_DEG)[Axis::C];
        (0..=n).map(move |k| {
            let theta = theta0_rad + span_rad * k as f64 / n as f64;
            let q = self.axes_near(theta, previous_c);
            previous_c = q[Axis::C];
            (theta, q)
        })
    }

    /// dq/dθ at `theta_rad` (mm/rad and deg/rad), by the fourth-order central difference
    /// `q' = (q(θ-2h) - 8q(θ-h) + 8q(θ+h) - q(θ+2h)) / 12h` with h = 1e-3 rad on the exact
    /// path (truncation ~h⁴q⁽⁵⁾/30 ≈ 1e-11, far below the 0.01 deg the analysis needs).
    pub fn derivative(&self, theta_rad: f64) -> AxisVec {
        const H: f64 = 1e-3;
        let c0 = self.axes_near(theta_rad, 0.0)[Axis::C];
        let q = |dt: f64| self.axes_near(theta_rad + dt, c0);
        (q(-2.0 * H) - q(-H) * 8.0 + q(H) * 8.0 - q(2.0 * H)) * (1.0 / (12.0 * H))
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

/// Writes the cone-frustum NC program (the paper's post-processor) and tells which lines
/// hold the measured revolution.
///
/// Each block moves the tool ball along one chord of the circle. Without TCP the F word is
/// the mixed-unit rate `sqrt(dX² + dY² + dZ² + dA² + dC²) / dt` with `dt = chord / F`; with
/// G93 it is `1 / dt`.
pub fn write_program(
    path: &ConePath,
    machine_name: &str,
    options: &NcOptions,
) -> (String, MeasuredLines) {
    let cone = &path.cone;
    let n = options.segments;
    let step = TAU / n as f64 * if options.clockwise { -1.0 } else { 1.0 };
    let lead_blocks = (options.lead_deg.to_radians() / step.abs()).ceil() as usize;
    let total = n + 2 * lead_blocks;
    let theta0 = -(lead_blocks as f64) * step;
    let axes = path.kinematics.layout.axes();

    let mut out = String::new();
    let mut line = 0usize;
    let mut emit = |out: &mut String, text: &str| {
        out.push_str(text);
        out.push('\n');
        line += 1;
        line
    };
    emit(&mut out, "%");
    emit(
        &mut out,
        "O1001 (MTSIM CONE-FRUSTUM TEST, NAS 979 / ISO 10791-7)",
    );
    emit(&mut out, &format!("(MACHINE: {})", sanitize(machine_name)));
    emit(
        &mut out,
        &format!(
            "(HALF APEX ANGLE {:.4} DEG, INCLINATION {:.4} DEG)",
            cone.half_apex_deg, cone.inclination_deg
        ),
    );
    emit(
        &mut out,
        &format!(
            "(BASE CENTRE XT {:.4} YT {:.4} ZT {:.4} MM, BALL BAR LENGTH {:.4} MM)",
            cone.center_mm.x, cone.center_mm.y, cone.center_mm.z, cone.ballbar_length_mm
        ),
    );
    emit(
        &mut out,
        &format!(
            "(CIRCLE RADIUS {:.4} MM, DIAMETER {:.4} MM, HEIGHT {:.4} MM)",
            cone.radius_mm(),
            2.0 * cone.radius_mm(),
            cone.height_mm()
        ),
    );
    let feed_kind = if options.tcp {
        "TOOL-TIP FEED WITH G43.4"
    } else if options.inverse_time {
        "INVERSE TIME G93"
    } else {
        "MIXED-UNIT F PER BLOCK"
    };
    emit(
        &mut out,
        &format!(
            "(SEGMENTS {n}, FEED {:.1} MM/MIN, {feed_kind}, {}, LEAD {:.1} DEG, {:?} BRANCH)",
            options.feed_mm_min,
            if options.clockwise { "CW" } else { "CCW" },
            options.lead_deg,
            path.branch
        ),
    );
    let modes = if options.inverse_time && !options.tcp {
        "G21 G90 G93 G17"
    } else {
        "G21 G90 G94 G17"
    };
    emit(&mut out, modes);

    let coords = |q: &AxisVec, tip: &Point3<f64>| -> String {
        let mut s = String::new();
        for &axis in axes {
            let v = if options.tcp && !axis.is_rotary() {
                tip[axis.index()]
            } else {
                q[axis]
            };
            let _ = write!(s, " {}{}", axis, fmt_num(v));
        }
        s
    };
    let mut samples = path.sampled(theta0, step * total as f64, total);
    let (theta_start, q_start) = samples.next().expect("at least one sample");
    let tip_start = cone.point(theta_start);
    if options.tcp {
        // Switch TCP on, then position tip and rotary axes in one rapid move.
        emit(&mut out, "G43.4 H1");
    }
    emit(&mut out, &format!("G00{}", coords(&q_start, &tip_start)));
    let mut first = 0;
    let mut last = 0;
    let (mut q_prev, mut tip_prev) = (q_start, tip_start);
    let chord = 2.0 * cone.radius_mm() * (step.abs() / 2.0).sin();
    let dt_min = chord / options.feed_mm_min;
    for (k, (theta, q)) in samples.enumerate() {
        let tip = cone.point(theta);
        let f = if options.tcp {
            options.feed_mm_min
        } else if options.inverse_time {
            1.0 / dt_min
        } else {
            (q - q_prev).mixed_norm() / dt_min
        };
        let l = emit(
            &mut out,
            &format!(
                "G01{} F{:.3} (THETA {:.3})",
                coords(&q, &tip),
                f,
                theta.to_degrees()
            ),
        );
        if k == lead_blocks {
            first = l;
        }
        if k + 1 == lead_blocks + n {
            last = l;
        }
        q_prev = q;
        tip_prev = tip;
    }
    let _ = tip_prev;
    if options.tcp {
        emit(&mut out, "G49");
    }
    emit(&mut out, "M30");
    emit(&mut out, "%");
    (out, MeasuredLines { first, last })
}

/// A number as an NC word value: 4 decimals (0.1 um, 0.0001 deg), no "-0".
fn fmt_num(v: f64) -> String {
    let s = format!("{v:.4}");
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        "0.0000".to_string()
    } else {
        s
    }
}

/// Parentheses end an NC comment, so they cannot appear inside one.
fn sanitize(text: &str) -> String {
    text.replace(['(', ')'], " ").to_uppercase()
}

impl ConeTest {
    /// The frame of the measured circle, for θ of a table-frame point.
    pub fn circle_frame(&self) -> CircleFrame {
        CircleFrame::cone(self.center_mm.into(), self.inclination_deg)
    }
}

/// An angle in deg brought into [0, 360); values within 1e-9 deg below 360 become 0.
pub fn normalize_deg(angle_deg: f64) -> f64 {
    let a = angle_deg.rem_euclid(360.0);
    if a > 360.0 - 1e-9 {
        0.0
    } else {
        a
    }
}
