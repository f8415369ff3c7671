//! Queueing canonical moves: straight, or through the cutter radius compensation queue
//! (G41/G42 to G40), with the feed of the modal state.

use std::collections::VecDeque;

use super::Interp;
use crate::axis::AxisVec;
use crate::canon::{Feed, Motion, Move, PathControl};
use crate::code::FeedRead;

impl Interp {
    /// Tool-centre-point control for the next move: G43.4 and the like, or a tilted plane
    /// on a kinematic chain (whose program X Y Z are the tool tip, [`crate::ToolAligner`]).
    fn tcp_now(&self) -> bool {
        self.tcp || (self.aligner.is_some() && self.tilt.is_some())
    }

    pub(super) fn emit(
        &mut self,
        queue: &mut VecDeque<Move>,
        line: usize,
        motion: Motion,
        start: AxisVec,
        end: AxisVec,
        path: PathControl,
    ) {
        let feed = self.feed_of(&motion, &start, &end);
        self.emit_with_feed(queue, line, motion, start, end, path, feed);
    }

    /// [`Interp::emit`] with the feed given (spindle-synchronised moves: pitch × S).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn emit_with_feed(
        &mut self,
        queue: &mut VecDeque<Move>,
        line: usize,
        motion: Motion,
        start: AxisVec,
        end: AxisVec,
        path: PathControl,
        feed: Feed,
    ) {
        if self.comp.is_none() && self.comp_out.is_none() {
            // Built in place in the queue (docs/performance.md).
            queue.push_back(Move {
                line,
                motion,
                start,
                end,
                feed,
                tcp: self.tcp_now(),
                tool: self.tool,
                tool_length_mm: self.tool_length_mm,
                path,
            });
            return;
        }
        let mut mv = Move {
            line,
            motion,
            start,
            end,
            feed,
            tcp: self.tcp_now(),
            tool: self.tool,
            tool_length_mm: self.tool_length_mm,
            path,
        };
        if let Some(c) = &mut self.comp {
            // A dwell under compensation waits behind the queued moves; any other move
            // made here runs as programmed after them.
            if matches!(motion, Motion::Dwell { .. }) {
                c.dwell(mv, queue);
            } else {
                c.pass(mv, queue);
            }
            return;
        }
        if let Some(p) = self.comp_out {
            // The first move after G40 starts where the compensated path ended.
            mv.start = p;
            if matches!(motion, Motion::Dwell { .. }) {
                mv.end = p;
            } else {
                self.comp_out = None;
            }
        }
        queue.push_back(mv);
    }

    /// The feed of a move of `motion`, resolved once here: none for a rapid or a dwell;
    /// for a feed move the F in effect as the feed mode reads it (G95: F × S, mm/min; under
    /// G96 the feed of the same time, crate `surface_speed`). The modal checks
    /// ([`Interp::feed_in_effect`]) have refused a feed move without one.
    pub(super) fn feed_of(&mut self, motion: &Motion, start: &AxisVec, end: &AxisVec) -> Feed {
        if matches!(motion, Motion::Rapid | Motion::Dwell { .. }) {
            return Feed::None;
        }
        match (self.feed_mode, self.feed, self.surface_speed) {
            (FeedRead::PerRevolution, Some(f), Some(css)) => {
                let mv = Move {
                    motion: *motion,
                    start: *start,
                    end: *end,
                    ..Move::default()
                };
                match self.surface_speed_feed(css, f, &mv) {
                    Ok(feed) => return Feed::PerMinute(feed),
                    Err(fault) => {
                        self.surface_speed_fault.get_or_insert(fault);
                        return Feed::PerMinute(f);
                    }
                }
            }
            _ => {}
        }
        match (self.feed_mode, self.feed) {
            (_, None) => Feed::None,
            (FeedRead::PerMinute, Some(f)) => Feed::PerMinute(f),
            (FeedRead::PerRevolution, Some(f)) => Feed::PerMinute(f * self.spindle_rpm),
            (FeedRead::InverseTime, Some(f)) => Feed::InverseTime(f),
        }
    }

    /// G40: the queued moves end at the compensated point, where the next move starts.
    pub(super) fn comp_exit(&mut self, queue: &mut VecDeque<Move>) -> Result<(), String> {
        let Some(mut c) = self.comp.take() else {
            return Ok(());
        };
        let was_on = c.radius > 0.0 && c.started();
        let out = c.off(queue)?;
        if was_on {
            self.arc_not_allowed = true;
        }
        self.comp_out = (out != self.pos).then_some(out);
        Ok(())
    }

    /// A move under cutter radius compensation, as programmed from `start` to `target`.
    pub(super) fn comp_element(
        &mut self,
        queue: &mut VecDeque<Move>,
        line_no: usize,
        motion: Motion,
        start: AxisVec,
        target: AxisVec,
    ) -> Result<(), String> {
        let feed = self.feed_of(&motion, &start, &target);
        let mv = Move {
            line: line_no,
            motion,
            start,
            end: target,
            feed,
            tcp: self.tcp_now(),
            tool: self.tool,
            tool_length_mm: self.tool_length_mm,
            path: self.path,
        };
        let c = self.comp.as_mut().expect("compensation on");
        if c.radius == 0.0 {
            // LinuxCNC compensates nothing for a tool of radius zero.
            c.pass(mv, queue);
            return Ok(());
        }
        match motion {
            Motion::Arc { .. } => c.arc(mv, queue),
            _ => c.straight(mv, queue),
        }
    }
}
