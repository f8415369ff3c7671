//! The planar circular test (ISO 230-4) program generator: G02/G03 with lead-in and lead-out
//! arcs, as canonical moves or text.
//!
//! The tool tip starts on the circle `lead_deg` before θ = 0, runs an arc into θ = 0, one
//! full circle (the measured revolution, one block), and an arc out of θ = 0. θ is measured
//! counter-clockwise from the plane's first axis (X in G17, Z in G18, Y in G19), seen from
//! the plane's positive normal; a clockwise run goes through θ decreasing.

use std::fmt::Write as _;

use crate::input::program::{CircleTest, MeasuredLines};
use crate::program::{Feed, Motion, Move};
use crate::{Axis, AxisVec, Plane};

/// Longest arc of a lead-in or lead-out block, deg: a longer lead is split into equal arcs.
pub const MAX_LEAD_ARC_DEG: f64 = 300.0;

/// The circle program as canonical moves: a G00 to the start `lead_deg` before θ = 0, the
/// lead-in arc, the measured full circle (one block) and the lead-out arc. Line numbers are
/// those of the text [`write_program`] writes.
#[derive(Clone, Debug)]
pub struct CircleProgram {
    circle: CircleTest,
    clockwise: bool,
    lead_deg: f64,
    /// The lead-in and lead-out as whole turns from θ = 0 to θ = 0, each one block like the
    /// measured one (`input::lead_in`, "Near the machine's limits").
    whole_turns: bool,
    header: [String; 4],
}

impl CircleProgram {
    pub fn new(circle: &CircleTest, clockwise: bool, lead_deg: f64) -> CircleProgram {
        let plane_code = match circle.plane {
            Plane::XY => "G17",
            Plane::ZX => "G18",
            Plane::YZ => "G19",
        };
        CircleProgram {
            circle: *circle,
            clockwise,
            lead_deg,
            whole_turns: false,
            header: [
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
            ],
        }
    }

    /// The same program with its lead-in and lead-out in whole turns of the measured circle:
    /// `lead_deg` rounded up to a multiple of 360 deg, each turn one block from θ = 0 to
    /// θ = 0, the measured one's twin.
    pub fn in_whole_turns(mut self) -> CircleProgram {
        self.whole_turns = true;
        self
    }

    /// Arcs of the lead-in (and of the lead-out): one per [`MAX_LEAD_ARC_DEG`] or part, or
    /// one per whole turn.
    fn lead_arcs(&self) -> usize {
        if self.whole_turns {
            (self.lead_deg / 360.0).ceil() as usize
        } else if self.lead_deg > 0.0 {
            (self.lead_deg / MAX_LEAD_ARC_DEG).ceil() as usize
        } else {
            0
        }
    }

    /// The line of the measured full-circle block.
    pub fn measured(&self) -> MeasuredLines {
        let line = self.header.len() + 2 + self.lead_arcs();
        MeasuredLines {
            first: line,
            last: line,
        }
    }

    /// The moves, in order.
    pub fn moves(&self) -> impl Iterator<Item = Move> {
        let c = self.circle;
        let sign = if self.clockwise { -1.0 } else { 1.0 };
        let at = |theta_deg: f64| {
            let p = c.point(theta_deg);
            AxisVec::xyzabc([p[0], p[1], p[2], 0.0, 0.0, 0.0])
        };
        let zero = at(0.0);
        let arc = Motion::Arc {
            clockwise: self.clockwise,
            plane: c.plane,
            center_mm: c.center_mm,
        };
        let n = self.lead_arcs();
        let ends = if self.whole_turns {
            // Every arc a whole turn from θ = 0 (an arc whose end is its start is one).
            let mut ends = vec![(Motion::Rapid, zero)];
            ends.extend(std::iter::repeat_n((arc, zero), 2 * n + 1));
            ends
        } else {
            // Equal arcs, each short of a full turn.
            let mut ends = vec![(Motion::Rapid, at(-sign * self.lead_deg))];
            let part = self.lead_deg / n.max(1) as f64;
            for k in (0..n).rev() {
                ends.push((arc, at(-sign * part * k as f64)));
            }
            ends.push((arc, zero));
            for k in 1..=n {
                ends.push((arc, at(sign * part * k as f64)));
            }
            ends
        };
        let first_line = self.header.len() + 1;
        let mut previous = AxisVec::ZERO;
        ends.into_iter().enumerate().map(move |(k, (motion, end))| {
            let mv = Move {
                line: first_line + k,
                motion,
                start: previous,
                end,
                feed: if motion == Motion::Rapid {
                    Feed::None
                } else {
                    Feed::PerMinute(c.feed_mm_min)
                },
                tcp: false,
                ..Move::default()
            };
            previous = end;
            mv
        })
    }
}

/// Writes the circle program as text; returns it and the line of the measured full-circle
/// block. Words are the [`CircleProgram`]'s moves rounded to 4 decimals.
pub fn write_program(
    circle: &CircleTest,
    clockwise: bool,
    lead_deg: f64,
) -> (String, MeasuredLines) {
    let program = CircleProgram::new(circle, clockwise, lead_deg);
    let measured = program.measured();
    let (u, v, _) = circle.axes();
    let mut text = program.header.join("\n");
    text.push('\n');
    for mv in program.moves() {
        let e = &mv.end;
        match mv.motion {
            Motion::Arc { center_mm, .. } => {
                let code = if clockwise { "G02" } else { "G03" };
                let _ = write!(
                    text,
                    "{code} X{:.4} Y{:.4} Z{:.4}",
                    e[Axis::X],
                    e[Axis::Y],
                    e[Axis::Z]
                );
                // I J K: the centre relative to the block's start point, in the plane's axes.
                for (axis, letter) in [(Axis::X, 'I'), (Axis::Y, 'J'), (Axis::Z, 'K')] {
                    if axis == u || axis == v {
                        let _ = write!(
                            text,
                            " {letter}{:.4}",
                            center_mm[axis.index()] - mv.start[axis]
                        );
                    }
                }
                let _ = write!(text, " F{:.3}", circle.feed_mm_min);
                if mv.line == measured.first {
                    text.push_str(" (MEASURED REVOLUTION)");
                }
            }
            _ => {
                let _ = write!(
                    text,
                    "G00 X{:.4} Y{:.4} Z{:.4}",
                    e[Axis::X],
                    e[Axis::Y],
                    e[Axis::Z]
                );
            }
        }
        text.push('\n');
    }
    text.push_str("M30\n%\n");
    (text, measured)
}
