//! Program and machine coordinates: the work offset, G92, the G10 L2 R rotation, the
//! G68.2/G254 frame and the tool length between a word's value and a machine position.

use super::Interp;
use crate::axis::{Axis, AxisVec};
use crate::frame::{self, Frame};
use crate::lex::Word;
use crate::units::MM_PER_INCH;

impl Interp {
    pub(crate) fn scale(&self) -> f64 {
        if self.inch {
            MM_PER_INCH
        } else {
            1.0
        }
    }

    /// Program position (current work system, current units).
    pub(crate) fn program_position(&self) -> AxisVec {
        let mut p = self.pos - self.offset;
        p[Axis::Z] -= self.tool_length_mm;
        if self.rotation.is_some() {
            let xy = self.xy_to_program([self.pos[Axis::X], self.pos[Axis::Y]]);
            p[Axis::X] = xy[0];
            p[Axis::Y] = xy[1];
        }
        if let Some(f) = self.frame() {
            let pp = f.to_program(self.tip(), &self.offset, &self.pos);
            for a in Axis::LINEAR {
                p[a] = pp[a.index()];
            }
        }
        for a in Axis::ALL {
            if !a.is_rotary() {
                p[a] /= self.scale();
            }
        }
        p
    }

    /// Program X Y (mm) to machine X Y: `rot(p + g92, R) + g5x` (the G92 offset turns with
    /// the work system in LinuxCNC, measured with rs274), or `p + offset` without a
    /// rotation.
    pub(super) fn xy_to_machine(&self, p: [f64; 2]) -> [f64; 2] {
        match self.rotation {
            None => [p[0] + self.offset[Axis::X], p[1] + self.offset[Axis::Y]],
            Some((r, g5x, g92)) => {
                let q = rotate_deg([p[0] + g92[0], p[1] + g92[1]], r);
                [q[0] + g5x[0], q[1] + g5x[1]]
            }
        }
    }

    /// Machine X Y (mm) to program X Y (mm): the inverse of [`Interp::xy_to_machine`].
    pub(super) fn xy_to_program(&self, m: [f64; 2]) -> [f64; 2] {
        match self.rotation {
            None => [m[0] - self.offset[Axis::X], m[1] - self.offset[Axis::Y]],
            Some((r, g5x, g92)) => {
                let q = rotate_deg([m[0] - g5x[0], m[1] - g5x[1]], -r);
                [q[0] - g92[0], q[1] - g92[1]]
            }
        }
    }

    /// A program X Y increment (mm) as a machine increment.
    pub(super) fn xy_increment(&self, v: [f64; 2]) -> [f64; 2] {
        match self.rotation {
            None => v,
            Some((r, ..)) => rotate_deg(v, r),
        }
    }

    /// A tilted plane (G68.2) or table-following offset (G254) is active.
    pub(crate) fn framed(&self) -> bool {
        self.tilt.is_some() || self.dwo
    }

    /// Tool-centre-point control (G43.4, G234, and the front ends' M128, `FUNCTION TCPM`,
    /// `TRAORI`) is on: X Y Z are the tool tip in the workpiece frame.
    pub(crate) fn tcp_active(&self) -> bool {
        self.tcp
    }

    /// The axis positions with the rotaries turned so that the tool lies along the unit
    /// direction `t` of the workpiece frame (Heidenhain `LN … TX TY TZ`, Sinumerik
    /// `A3= B3= C3=`), the other axes as they are; or why it cannot be reached. On a
    /// table-table machine this is [`RotaryTable::align`](crate::frame::RotaryTable::align)
    /// (the solution with a positive tilt, C next to its current value), on a kinematic chain
    /// the caller's [`ToolAligner`](crate::frame::ToolAligner).
    pub(crate) fn rotaries_for_direction(&self, t: [f64; 3]) -> Result<AxisVec, String> {
        let n = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
        if !(n > 1e-9) || !n.is_finite() {
            return Err("the tool direction is the zero vector".into());
        }
        let t = t.map(|c| c / n);
        if let Some(table) = self.table {
            let (tilt, c) = table.align(t, self.pos[Axis::C]);
            let mut q = self.pos;
            q[table.tilt] = tilt;
            q[Axis::C] = c;
            return Ok(q);
        }
        match &self.aligner {
            Some(aligner) => (aligner.0)(t, &self.pos),
            None => Err("the machine has no rotary axes mtsim can turn to a direction (a table-table AC or BC machine, or a kinematic chain with two rotaries)".into()),
        }
    }

    /// The program-to-machine map while G68.2 or G254 is active.
    pub(crate) fn frame(&self) -> Option<Frame> {
        if self.tilt.is_none() && !self.dwo {
            return None;
        }
        let (origin_mm, rotation) = self.tilt.unwrap_or(([0.0; 3], frame::IDENTITY));
        Some(Frame {
            origin_mm,
            rotation,
            table: self.table,
        })
    }

    /// Machine position of the tool tip (the tool length offset taken off Z), mm and deg.
    pub(crate) fn machine_tip(&self) -> AxisVec {
        let mut p = self.pos;
        p[Axis::Z] -= self.tool_length_mm;
        p
    }

    /// Machine X Y Z of the controlled point without the tool length offset, mm.
    pub(super) fn tip(&self) -> [f64; 3] {
        [
            self.pos[Axis::X],
            self.pos[Axis::Y],
            self.pos[Axis::Z] - self.tool_length_mm,
        ]
    }

    /// The machine target of axis words (program coordinates, or machine with G53).
    pub(super) fn target(&self, axis_words: &[(Axis, Word)], g53: bool) -> AxisVec {
        if let (Some(f), false) = (self.frame(), g53) {
            if !self.dwo && axis_words.iter().all(|(a, _)| a.is_rotary()) {
                // A tilted plane without TCP (G68.2, CYCL DEF 19, PLANE): a block of
                // rotary words alone turns those axes and no other (Fanuc G68.2 and
                // Heidenhain's tilted plane position only the programmed axes; the plane
                // is not followed without TCP).
                let mut target = self.pos;
                for &(a, w) in axis_words {
                    target[a] = if self.absolute {
                        w.value + self.offset[a]
                    } else {
                        self.pos[a] + w.value
                    };
                }
                return target;
            }
            // Program X Y Z in the feature / table-fixed frame; rotary (and U V W) words as
            // usual.
            let mut p = f.to_program(self.tip(), &self.offset, &self.pos);
            let mut target = self.pos;
            for &(a, w) in axis_words {
                if a.is_rotary() || a.is_secondary() {
                    let v = if a.is_rotary() {
                        w.value
                    } else {
                        w.value * self.scale()
                    };
                    target[a] = if self.absolute {
                        v + self.offset[a]
                    } else {
                        self.pos[a] + v
                    };
                } else {
                    let v = w.value * self.scale();
                    let k = a.index();
                    p[k] = if self.absolute { v } else { p[k] + v };
                }
            }
            let m = f.to_machine(p, &self.offset, &target);
            for a in Axis::LINEAR {
                target[a] = m[a.index()];
            }
            target[Axis::Z] += self.tool_length_mm;
            return target;
        }
        let mut target = self.pos;
        if let (Some(_), false) = (self.rotation, g53) {
            // A rotated work system (G10 L2 R): X Y words in the rotated frame.
            let scale = self.scale();
            let word = |l: Axis| {
                axis_words
                    .iter()
                    .find(|(a, _)| *a == l)
                    .map(|(_, w)| w.value * scale)
            };
            let (x, y) = (word(Axis::X), word(Axis::Y));
            if x.is_some() || y.is_some() {
                let xy = if self.absolute {
                    let p = self.xy_to_program([self.pos[Axis::X], self.pos[Axis::Y]]);
                    self.xy_to_machine([x.unwrap_or(p[0]), y.unwrap_or(p[1])])
                } else {
                    let d = self.xy_increment([x.unwrap_or(0.0), y.unwrap_or(0.0)]);
                    [self.pos[Axis::X] + d[0], self.pos[Axis::Y] + d[1]]
                };
                target[Axis::X] = xy[0];
                target[Axis::Y] = xy[1];
            }
        }
        // Axis by axis with constant indices, so `target` stays in registers
        // (docs/performance.md). The words are in `Axis::ALL` order, as the block collects
        // them.
        debug_assert!(axis_words
            .windows(2)
            .all(|p| p[0].0.index() < p[1].0.index()));
        let mut words = axis_words.iter().peekable();
        for a in Axis::ALL {
            let Some(&(_, w)) = words.next_if(|(b, _)| *b == a) else {
                continue;
            };
            if self.rotation.is_some() && !g53 && matches!(a, Axis::X | Axis::Y) {
                continue;
            }
            let v = if a.is_rotary() {
                w.value
            } else {
                w.value * self.scale()
            };
            target[a] = if g53 {
                v
            } else if self.absolute {
                v + self.offset[a]
                    + if a == Axis::Z {
                        self.tool_length_mm
                    } else {
                        0.0
                    }
            } else {
                self.pos[a] + v
            };
        }
        target
    }
}

/// M-code groups (LinuxCNC's modal groups 4, 6, 7, 8, 9, 10); two of one group may not
/// share a block.
/// `v` turned counter-clockwise by `deg` about the origin.
fn rotate_deg(v: [f64; 2], deg: f64) -> [f64; 2] {
    let (s, c) = deg.to_radians().sin_cos();
    [v[0] * c - v[1] * s, v[0] * s + v[1] * c]
}
