//! Tool orientation by direction vector under `TRAORI`: `A3= B3= C3=`, the tool's
//! direction in the workpiece frame (Job planning, "Orientation programming: direction
//! vectors (A3, B3, C3)"; `ORIWKS`, the default, "orientation in the workpiece coordinate
//! system"). Components not written are 0, and the vector's length does not matter.
//!
//! ```text
//! t = (A3, B3, C3) / |(A3, B3, C3)|  ─►  the rotary positions that put the tool along t
//! ```
//!
//! The positions come from the interpreter's machine (`Interp::rotaries_for_direction`: on
//! a table-table machine the solution with the positive tilt, C next to its value; on a
//! kinematic chain the caller's inverse kinematics) and are written as the block's rotary
//! axis words, so the block runs as an `X Y Z A C` block under TCP. The control
//! interpolates the vector between blocks (ORIVECT, a great circle); mtsim interpolates the
//! axes (as ORIAXES), which gives the same end of every block (said in a notice).
//!
//! Refused: a vector without `TRAORI`, under `ORIMKS` (orientation in machine
//! coordinates), in a frame that turns, scales or mirrors, or beside rotary axis words.

use super::expr::Scan;
use super::words::{put, Coordinate, Mode, Words};
use super::Reader;
use crate::axis::Axis;
use crate::lex::{LineError, LineResult};

impl Reader {
    /// `A3=`, `B3=`, `C3=` (the cursor after the name): one component of the vector.
    pub(super) fn orientation_word(
        &mut self,
        name: &str,
        at: usize,
        sc: &mut Scan,
        w: &mut Words,
    ) -> LineResult<()> {
        let k = usize::from(name.as_bytes()[0] - b'A');
        let c = self.assigned(
            sc,
            at,
            "expected `A3=value` (a component of the tool's direction vector)",
            "orientation vector",
        )?;
        put(&mut w.orientation[k], c, sc, at)
    }

    /// The block's orientation vector, if it has one, as its rotary axis words.
    pub(super) fn orientation_to_axes(&mut self, w: &mut Words, line_no: usize) -> LineResult<()> {
        let Some(first) = w.orientation.iter().flatten().next() else {
            return Ok(());
        };
        let span = first.span.start
            ..w.orientation
                .iter()
                .flatten()
                .map(|c| c.span.end)
                .max()
                .unwrap_or(first.span.end);
        let refuse =
            |what: &str, label: &'static str| LineError::new(span.clone(), what.to_string(), label);
        if !self.tcp {
            return Err(refuse("A3= B3= C3= (the tool's direction vector) without TRAORI: the control orients the tool by a vector only under the orientation transformation", "orientation without TRAORI")
                .help("switch TRAORI on before the block"));
        }
        if self.ori_machine {
            return Err(refuse("A3= B3= C3= under ORIMKS (orientation in the machine coordinate system): mtsim reads the vector in the workpiece coordinate system only (ORIWKS)", "ORIMKS"));
        }
        if self.frame.matrix != crate::frame::IDENTITY {
            return Err(refuse("A3= B3= C3= in a programmable frame that turns, scales or mirrors (ROT, SCALE, MIRROR): mtsim reads the vector in the workpiece frame only", "orientation in a turned frame"));
        }
        if let Some(c) = w.axes[3..6].iter().flatten().next() {
            return Err(LineError::new(c.span.clone(), "a rotary axis word beside A3= B3= C3=: the block gives the tool's orientation twice", "axis word with orientation vector"));
        }
        let t = [0, 1, 2].map(|k| w.orientation[k].as_ref().map_or(0.0, |c| c.value));
        let q = self.interp.rotaries_for_direction(t).map_err(|why| {
            refuse(
                &format!("A3= B3= C3= ({}, {}, {}): {why}", t[0], t[1], t[2]),
                "orientation out of reach",
            )
        })?;
        let now = self.interp.machine_tip();
        for (k, axis) in [(3, Axis::A), (4, Axis::B), (5, Axis::C)] {
            if q[axis] != now[axis] {
                w.axes[k] = Some(Coordinate {
                    value: q[axis],
                    mode: Mode::Absolute,
                    raw: None,
                    span: span.clone(),
                });
            }
        }
        self.notice(
            line_no,
            "A3= B3= C3= (orientation vector): the block ends with the tool along the vector; between blocks mtsim interpolates the rotary axes (as ORIAXES), where ORIVECT turns the vector on a great circle".into(),
        );
        Ok(())
    }
}
