//! The planar circular test (ISO 230-4): a G02/G03 program with lead-in and lead-out arcs.
//!
//! The tool tip starts on the circle `lead_deg` before θ = 0, runs an arc into θ = 0, one
//! full circle (the measured revolution, one block), and an arc out of θ = 0. θ is measured
//! counter-clockwise from the plane's first axis (X in G17, Z in G18, Y in G19), seen from
//! the plane's positive normal; a clockwise run goes through θ decreasing.

use std::fmt::Write as _;

use crate::axis::Axis;
use crate::cone::MeasuredLines;
use crate::gcode::Plane;

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

/// Writes the circle program; returns it and the line of the measured full-circle block.
pub fn write_program(
    circle: &CircleTest,
    clockwise: bool,
    lead_deg: f64,
) -> (String, MeasuredLines) {
    let (u, v, _) = circle.axes();
    let plane_code = match circle.plane {
        Plane::XY => "G17",
        Plane::ZX => "G18",
        Plane::YZ => "G19",
    };
    let sign = if clockwise { -1.0 } else { 1.0 };
    let arc = if clockwise { "G02" } else { "G03" };
    let start = circle.point(-sign * lead_deg);
    let fmt = |p: &[f64; 3]| format!("X{:.4} Y{:.4} Z{:.4}", p[0], p[1], p[2]);
    // I J K: the centre relative to the block's start point, in the plane's axes.
    let ijk = |from: &[f64; 3]| {
        let mut s = String::new();
        for (axis, letter) in [(Axis::X, 'I'), (Axis::Y, 'J'), (Axis::Z, 'K')] {
            if axis == u || axis == v {
                let _ = write!(
                    s,
                    " {letter}{:.4}",
                    circle.center_mm[axis.index()] - from[axis.index()]
                );
            }
        }
        s
    };
    let mut lines = vec![
        "%".to_string(),
        "O2001 (MTSIM CIRCULAR TEST, ISO 230-4)".to_string(),
        format!(
            "(CENTRE {:.4} {:.4} {:.4} MM, RADIUS {:.4} MM, FEED {:.1} MM/MIN, {}, LEAD {:.1} DEG)",
            circle.center_mm[0],
            circle.center_mm[1],
            circle.center_mm[2],
            circle.radius_mm,
            circle.feed_mm_min,
            if clockwise { "CW" } else { "CCW" },
            lead_deg
        ),
        format!("G21 G90 G94 {plane_code}"),
        format!("G00 {}", fmt(&start)),
    ];
    let zero = circle.point(0.0);
    if lead_deg > 0.0 {
        lines.push(format!(
            "{arc} {}{} F{:.3}",
            fmt(&zero),
            ijk(&start),
            circle.feed_mm_min
        ));
    }
    lines.push(format!(
        "{arc} {}{} F{:.3} (MEASURED REVOLUTION)",
        fmt(&zero),
        ijk(&zero),
        circle.feed_mm_min
    ));
    let measured = lines.len();
    if lead_deg > 0.0 {
        let end = circle.point(sign * lead_deg);
        lines.push(format!(
            "{arc} {}{} F{:.3}",
            fmt(&end),
            ijk(&zero),
            circle.feed_mm_min
        ));
    }
    lines.push("M30".into());
    lines.push("%".into());
    let mut text = lines.join("\n");
    text.push('\n');
    (
        text,
        MeasuredLines {
            first: measured,
            last: measured,
        },
    )
}
