//! The state types the front end's files share, in a leaf of their own: the open control
//! structures, the sections being repeated, the variables a block assigns, a drilling
//! cycle's values.

use std::ops::Range;

/// The motion codes the front end keeps for CIP and CT (after G0-G3), modal as they are.
pub(super) const CIP: u8 = 5;
pub(super) const CT: u8 = 6;

/// An open control structure of a program level.
pub(super) enum Structure {
    If,
    /// The `WHILE` line (re-read at `ENDWHILE`).
    While {
        offset: usize,
        line: usize,
    },
    /// The first line of the body, the loop variable and its last value.
    For {
        offset: usize,
        line: usize,
        var: Var,
        end: f64,
    },
    Repeat {
        offset: usize,
        line: usize,
    },
    Loop {
        offset: usize,
        line: usize,
    },
}

/// A variable a block assigns: an R parameter or a `DEF` variable.
#[derive(Clone, Debug)]
pub(super) enum Var {
    R(usize),
    Named(String),
}

/// A drilling cycle's values, program units and s.
#[derive(Clone, Copy, Debug)]
pub(super) struct Cycle {
    pub retract: f64,
    /// RFP + SDIS.
    pub approach: f64,
    pub depth: f64,
    pub dwell_s: f64,
    /// The feed down to the depth (mm/min); `None`: the programmed F.
    pub feed_in: Option<f64>,
    /// Back up to RFP + SDIS at this feed (mm/min) before the rapid to RTP; `None`: the
    /// rapid from the depth.
    pub feed_out: Option<f64>,
}

/// A section being repeated.
pub(super) struct Section {
    /// Byte offset and 1-based number of its first line.
    pub(super) start: (usize, usize),
    /// The byte offset that ends a pass.
    pub(super) end: usize,
    /// Passes still to run after this one.
    pub(super) left: u64,
    /// Where the program goes on after the last pass: the line after the `REPEAT`.
    pub(super) back: (usize, usize),
    /// The `REPEAT` line (offset, number) and the statement's span.
    pub(super) site: (usize, usize, Range<usize>),
}
