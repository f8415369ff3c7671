//! The state types the front end's files share, in a leaf of their own: the open control
//! structures, the sections being repeated, the variables a block assigns, a drilling
//! cycle's steps, a chamfer or rounding word and the line held for it.

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

/// The feed of a cycle's feed move, resolved when the cycle runs (an `MCALL` cycle runs
/// at the F in effect at each hole).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum CycleFeed {
    /// The F programmed before the call.
    Programmed,
    /// The programmed F times this factor (CYCLE83's FRF on its first stroke).
    Factor(f64),
    /// This feed, mm/min (CYCLE84's pitch × speed, CYCLE85's FFR and RFF).
    Rate(f64),
}

/// One step of a drilling cycle at the drilling position, in program units and s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum CycleStep {
    /// G0 (`feed` `None`) or G1 to `level` on the tool axis, `aside` off the drilling
    /// position along the plane's first and second axes (CYCLE86's lift-off).
    Move {
        level: f64,
        aside: [f64; 2],
        feed: Option<CycleFeed>,
    },
    /// A dwell, s.
    Dwell(f64),
    /// An M code the cycle outputs (M5 spindle stop, M0 program stop, M19 oriented
    /// spindle stop, M3/M4 the spindle on again).
    M(u8),
}

/// A drilling cycle: its steps from the drilling position, as its manual section lists
/// them.
#[derive(Clone, Debug)]
pub(super) struct Cycle {
    pub steps: Vec<CycleStep>,
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

/// A chamfer or rounding word: the kind and its value (program units).
#[derive(Clone, Debug)]
pub(super) struct CornerWord {
    pub kind: CornerKind,
    pub size: f64,
    pub span: std::ops::Range<usize>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum CornerKind {
    Rnd,
    Rndm,
    Chr,
    Chf,
}

impl CornerKind {
    pub(super) fn name(self) -> &'static str {
        match self {
            CornerKind::Rnd => "RND",
            CornerKind::Rndm => "RNDM",
            CornerKind::Chr => "CHR",
            CornerKind::Chf => "CHF",
        }
    }
}

/// A line held for the element at its end.
pub(super) struct Held {
    pub pending: crate::corner::Pending,
    /// CHF's length (the legs follow from the corner's angle once the next line is known).
    pub chamfer_length: Option<f64>,
    /// Set in the block that holds the line; the next block's moves join it.
    pub fresh: bool,
}
