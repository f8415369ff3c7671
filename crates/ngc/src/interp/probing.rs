//! Straight probes G38.2-G38.5 as rs274 standalone runs them (crate `probe`).

use std::collections::VecDeque;

use super::Interp;
use crate::axis::AxisVec;
use crate::canon::{Motion, Move};
use crate::probe;

impl Interp {
    /// A straight probe G38.2-G38.5 from `start` to `target` (machine coordinates) as
    /// rs274 standalone runs it: a feed move, the back-off, the probe parameters
    /// (`probe.rs`).
    pub(super) fn probe(
        &mut self,
        queue: &mut VecDeque<Move>,
        line_no: usize,
        code: u32,
        start: AxisVec,
        target: AxisVec,
    ) -> Result<(), &'static str> {
        if start == target {
            // G38.2/G38.4 must move to make contact; G38.3/G38.5 just do nothing.
            if code == 382 || code == 384 {
                return Err("G38.2/G38.4 to the start point: expected a probe move (LinuxCNC: \"Start point too close to probe point\")");
            }
        } else {
            self.emit(queue, line_no, Motion::Linear, start, target, self.path);
        }
        self.pos = target;
        let at_target = self.program_position();
        for (k, v) in probe::parameters(at_target).into_iter().enumerate() {
            self.params.numbered[probe::FIRST_PARAMETER + k] = v;
        }
        let back = probe::backoff(start, target);
        if back != target {
            self.emit(queue, line_no, Motion::Linear, target, back, self.path);
            self.pos = back;
        }
        Ok(())
    }
}
