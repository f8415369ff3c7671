//! Spindle-synchronised motion, G33 and G33.1 (LinuxCNC's G-code manual, "G33 Spindle
//! Synchronized Motion" and "G33.1 Rigid Tapping"; the canonical moves checked against
//! rs274 by the conformance test, tests/data/conformance/g33_*).
//!
//! A synchronised move advances its pitch `K` along its path per spindle revolution. mtsim
//! has no spindle model, so the move is a feed move at the speed it has when the spindle
//! turns at the programmed S:
//!
//! ```text
//! F = K · S        (mm/min; K in program units, converted to mm under G20)
//! ```
//!
//! - G33 X Z K: one synchronised move to the end point.
//! - G33.1 X Z K (rigid tapping): the move in, then the same move back out (the spindle
//!   reverses at the bottom); the tool ends where it started.
//!
//! Both need the spindle turning (M3 or M4 in effect; M5, M6 and the program end stop it).

use std::collections::VecDeque;

use super::Interp;
use crate::canon::{Feed, Motion, Move};
use crate::lex::{LineError, LineResult, Word};
use crate::AxisVec;

impl Interp {
    /// G33 (`code` 330) or G33.1 (331) from the current position to `target` (machine mm).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn spindle_sync<'l>(
        &mut self,
        line: &str,
        code: u32,
        get: &dyn Fn(char) -> Option<Word<'l>>,
        line_no: usize,
        queue: &mut VecDeque<Move>,
        at: std::ops::Range<usize>,
        target: AxisVec,
    ) -> LineResult<()> {
        let tapping = code == 331;
        let name = if tapping { "G33.1" } else { "G33" };
        if !self.spindle_turning {
            return Err(LineError::new(
                at,
                format!("spindle not turning in {name}: expected M3 or M4 before it"),
                "spindle stopped",
            )
            .help("start the spindle (S.. M3) after the last M5 or tool change"));
        }
        if self.spindle_rpm <= 0.0 {
            return Err(LineError::new(
                at,
                format!("{name} with the spindle speed zero: expected an S word above zero"),
                "no S",
            ));
        }
        let pitch = get('K').ok_or_else(|| {
            LineError::new(
                at.clone(),
                format!("{name} without K: expected the pitch K (distance per revolution) in every {name} block"),
                "no K",
            )
        })?;
        if !(pitch.value > 0.0) {
            return Err(LineError::new(
                pitch.span(),
                format!(
                    "`{}`: expected a pitch K greater than zero",
                    &line[pitch.span()]
                ),
                "pitch not positive",
            ));
        }
        let feed_mm_per_min = pitch.value * self.scale() * self.spindle_rpm;
        let feed = Feed::PerMinute(feed_mm_per_min);
        let start = self.pos;
        let path = self.path;
        self.emit_with_feed(queue, line_no, Motion::Linear, start, target, path, feed);
        if tapping {
            self.emit_with_feed(queue, line_no, Motion::Linear, target, start, path, feed);
        } else {
            self.pos = target;
        }
        Ok(())
    }
}
