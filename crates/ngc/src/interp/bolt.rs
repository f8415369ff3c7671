//! Haas mill bolt-hole patterns: G70 (a full circle) and G71 (an arc) run the active canned
//! cycle at each hole, as the Haas mill operator's manual describes them ("G70 Bolt Hole
//! Circle", "G71 Bolt Hole Arc"). Hole k of L, about the centre c at radius I, from the
//! start angle J (degrees counter-clockwise from +X, the 3 o'clock position):
//!
//! ```text
//! a_k = J + k · 360/L      (G70)        a_k = J + k · K      (G71, K the spacing, ±)
//! p_k = c + I (cos a_k, sin a_k)        k = 0 … L−1
//! ```
//!
//! The centre is the block's X Y (absolute in G90, from the current position in G91), or
//! the current position. The cycle's own levels (R, Z, Q, P, G98/G99) are those it was
//! given; its hole at the centre is the cycle block's own, which a program leaves out with
//! L0 on that block. The same codes on a Haas lathe are the stock-removal and finishing
//! cycles, which take P and Q: a block with P or Q is refused as the lathe cycle.

use std::collections::VecDeque;

use super::Interp;
use crate::axis::Axis;
use crate::block::Block;
use crate::canon::Move;
use crate::code::{MotionMode, NonModal};
use crate::lex::{LineError, LineResult, Word};

/// Most holes a pattern may have (each hole is a handful of moves).
const MAX_HOLES: f64 = 100_000.0;

/// A G70 or G71 block with P or Q is the Haas lathe's finishing or stock-removal cycle
/// (its P Q the profile's first and last block): refused by that name, before its other
/// words (a lathe's U W) are read as axes.
pub(super) fn refuse_lathe_cycle(b: &Block) -> LineResult<()> {
    let Some((nm, w)) = b.nonmodal() else {
        return Ok(());
    };
    let lathe = match nm {
        NonModal::BoltCircle => "finishing cycle",
        NonModal::BoltArc => "O.D./I.D. stock removal cycle",
        _ => return Ok(()),
    };
    let Some(p) = b.get('P').or(b.get('Q')) else {
        return Ok(());
    };
    let code = &b.line[w.span()];
    Err(LineError::new(
        p.span(),
        format!("`{code}` with `{}`: on a Haas lathe {code} P Q is the {lathe}, which mtsim does not read (a mill's {code} is a bolt-hole pattern, with I J L)", &b.line[p.span()]),
        "lathe cycle",
    )
    .help("post the turning as G00/G01 moves"))
}

impl Interp {
    /// A G70 or G71 block (`nm`, its word `w`): the active canned cycle at every hole.
    pub(super) fn bolt_pattern(
        &mut self,
        b: &Block,
        nm: NonModal,
        w: Word,
        line_no: usize,
        queue: &mut VecDeque<Move>,
    ) -> LineResult<()> {
        let line = b.line;
        let code = &line[w.span()];
        let refuse = |at: std::ops::Range<usize>, what: String, label: &'static str| {
            Err(LineError::new(at, what, label))
        };
        let Some(MotionMode::Cycle(cycle)) = self.motion else {
            return refuse(w.span(), format!("`{code}` (bolt-hole pattern) with no canned cycle active: expected G73, G74, G76, G77 or G81-G89 in an earlier block, as the holes are that cycle's"), "no cycle");
        };
        if self.plane.axes().0 != Axis::X || self.plane.axes().1 != Axis::Y {
            return refuse(
                w.span(),
                format!("`{code}` outside the G17 plane: a bolt-hole pattern is read in XY"),
                "pattern plane",
            );
        }
        let word = |l: char, what: &str| {
            b.get(l).ok_or_else(|| {
                LineError::new(
                    w.span(),
                    format!("`{code}` without {l}: expected {what}"),
                    "pattern word",
                )
            })
        };
        let radius = word('I', "the radius I")?.value;
        let start_deg = b.get('J').map_or(0.0, |j| j.value);
        let count = word('L', "the number of holes L")?;
        if !(count.value >= 1.0 && count.value <= MAX_HOLES && count.value.fract() == 0.0) {
            return refuse(
                count.span(),
                format!(
                    "`{}`: expected a whole number of holes from 1 to {MAX_HOLES}",
                    &line[count.span()]
                ),
                "hole count",
            );
        }
        let step_deg = match nm {
            NonModal::BoltCircle => 360.0 / count.value,
            _ => word('K', "the angle between holes K")?.value,
        };
        let here = self.program_position();
        let centre = [Axis::X, Axis::Y].map(|a| match b.get(a.letter()) {
            Some(v) if self.absolute => v.value,
            Some(v) => here[a] + v.value,
            None => here[a],
        });
        for k in 0..count.value as u64 {
            let a = (start_deg + k as f64 * step_deg).to_radians();
            let hole = [centre[0] + radius * a.cos(), centre[1] + radius * a.sin()];
            let now = self.program_position();
            // The hole as the cycle's own X Y words: absolute, or from where the tool is.
            let value = |i: usize, a: Axis| match self.absolute {
                true => hole[i],
                false => hole[i] - now[a],
            };
            let (x, y) = (value(0, Axis::X), value(1, Axis::Y));
            let synthetic = |letter: char, value: f64| Word {
                letter,
                value,
                number: "",
                span: w.span,
            };
            let get = |l: char| match l {
                'X' => Some(synthetic('X', x)),
                'Y' => Some(synthetic('Y', y)),
                _ => None,
            };
            self.cycle(line, cycle, &get, line_no, queue, w.span())?;
        }
        Ok(())
    }
}
