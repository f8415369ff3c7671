//! One budget of executed blocks per run, shared by every front end, so that no program
//! runs forever: a block counts each time the flow comes back to it, through a loop or
//! jump, or inside a subprogram, macro call or repeated section. The main program's first
//! pass is free: a block of the main program that lies past every one executed before (the
//! flow reading on) costs nothing, so a straight program runs however long its file is, and
//! only repetition draws on the budget.
//!
//! ```text
//! used = Σ over executed blocks of [not a first pass through the main program]
//! used > max_blocks  ─► error at the repeating construct (file:line:col), naming the option
//! ```
//!
//! A repeat count is checked before it runs: every pass of a repeated subprogram or section
//! executes at least one block (its return, its last line or its closing keyword), so
//! `passes > max_blocks − used` cannot fit and is refused at once, before any pass. That
//! keeps a huge count such as `M98 P1000 L99999999` from running for minutes before the
//! budget stops it.

use std::ops::Range;

use crate::lex::LineError;

/// Executed blocks counted against the reader option `max_blocks`.
#[derive(Clone, Debug)]
pub(crate) struct Budget {
    max: u64,
    used: u64,
    /// The main program's byte offset from which a block is read for the first time.
    fresh_from: usize,
}

impl Budget {
    pub(crate) fn new(max_blocks: u64) -> Budget {
        Budget {
            max: max_blocks,
            used: 0,
            fresh_from: 0,
        }
    }

    /// Counts the block at byte `offset` of the main program (`main`) or of a called file:
    /// free when it is the main program's first pass over it (past every block executed
    /// before), one block otherwise. False once the budget is spent.
    #[inline(always)]
    pub(crate) fn spend_at(&mut self, main: bool, offset: usize) -> bool {
        if main && offset >= self.fresh_from {
            self.fresh_from = offset + 1;
            return true;
        }
        self.spend()
    }

    /// Counts one executed block; false once the budget is spent.
    #[inline(always)]
    pub(crate) fn spend(&mut self) -> bool {
        self.used += 1;
        self.used <= self.max
    }

    /// Blocks still allowed.
    pub(crate) fn left(&self) -> u64 {
        self.max.saturating_sub(self.used)
    }

    /// Refuses `passes` more passes of a repeated construct (at `span`, described as
    /// `what`) when even one block each would overrun the budget.
    pub(crate) fn check_passes(
        &self,
        passes: u64,
        what: &str,
        span: Range<usize>,
    ) -> Result<(), LineError> {
        if passes > self.left() {
            return Err(LineError::new(
                span,
                format!(
                    "{what} asks for {passes} passes, each at least one block, but only {} of the {} blocks a run may execute (reader option max_blocks) are left: expected a bounded repeat count",
                    self.left(),
                    self.max
                ),
                "repeat count over the block budget",
            )
            .help(HELP));
        }
        Ok(())
    }

    /// The error when the budget is spent, at the repeating construct `span`.
    pub(crate) fn spent(&self, span: Range<usize>) -> LineError {
        LineError::new(
            span,
            format!(
                "more than {} blocks executed (reader option max_blocks): this repeat, loop, call or jump keeps the program from ending (an endless loop, or a repeat count too large)",
                self.max
            ),
            "block budget spent",
        )
        .help(HELP)
    }
}

const HELP: &str =
    "the limit is the reader option max_blocks (docs/gcode.md), executed blocks per run";
