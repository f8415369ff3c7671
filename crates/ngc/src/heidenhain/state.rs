//! The front end's state and its words: the program files and calls, the path (position,
//! pole, tangent, held line), the frames and the defined cycle, and the interpreter words a
//! block emits; the block as tokens; the refusals that name a construct.

use std::collections::{HashMap, VecDeque};
use std::ops::Range;
use std::path::PathBuf;

use crate::axis::AxisVec;
use crate::canon::Move;
use crate::frame::Mat3;
use crate::interp::Interp;
use crate::lex::{LineError, LineResult, Word};
use crate::notice::Notice;
use crate::options::Tool;
use crate::source::Source;

use super::qparam::Qparams;
use super::text;

pub(super) use crate::source::Cursor;

pub(super) struct Program {
    pub(super) path: PathBuf,
    pub(super) source: Source,
    /// `LBL` name → the line after it; built on the first call or jump.
    pub(super) labels: Option<HashMap<String, Cursor>>,
}

/// A `CALL LBL` (or `CALL PGM`) being run.
pub(super) struct Frame {
    /// Where the program goes on after the call.
    pub(super) ret: Cursor,
    /// The `CALL LBL` line: reaching it again ends one pass of a section repeat.
    pub(super) call: Cursor,
    /// The call's span in its block: the construct a repeated pass is counted against.
    pub(super) call_span: Range<usize>,
    /// Where each pass starts.
    pub(super) target: Cursor,
    /// Passes still to run after this one.
    pub(super) repeats: u64,
    /// A called program file (ends at `END PGM`), not a label.
    pub(super) program: bool,
}

/// The Klartext front end's move stream.
pub(crate) struct Reader {
    pub(super) programs: Vec<Program>,
    pub(super) cursor: Cursor,
    pub(super) frames: Vec<Frame>,
    pub(super) interp: Interp,
    pub(super) queue: VecDeque<Move>,
    pub(super) notices: Vec<Notice>,
    pub(super) q: Qparams,
    pub(super) path: Contour,
    pub(super) frames_state: Frames,
    pub(super) cycle: Cycle,
    /// The last `PATTERN DEF`, as written (its points are made at `CYCL CALL PAT`).
    pub(super) pattern: Vec<Item>,
    pub(super) tools: Vec<Tool>,
    /// Tools whose geometry `FN 17: SYSWRITE ID50` changed: number and line (a later call
    /// or read of one is refused: the tool table is not changed during a run).
    pub(super) rewritten: Vec<(u32, usize)>,
    /// The machine's rotary table, for `PLANE … TURN`.
    pub(super) table: Option<crate::frame::RotaryTable>,
    /// Without a table: the rotaries a caller's inverse kinematics turns for `PLANE … TURN`
    /// (`Options::aligner`; empty when there is none).
    pub(super) chain_rotaries: Vec<crate::axis::Axis>,
    pub(super) search_path: Vec<PathBuf>,
    /// The current tool: number (0: none or named) and its `DL`, `DR`.
    pub(super) tool: (u32, f64, f64),
    pub(super) inch: bool,
    /// The spindle speed of the last `TOOL CALL … S`, rpm (cycle 207's feed).
    pub(super) spindle_rpm: f64,
    /// `M126`: rotary axes take the shorter way.
    pub(super) shortest: bool,
    /// `M89`: the cycle runs after every positioning.
    pub(super) modal_cycle: bool,
    pub(super) finished: bool,
    pub(super) flushed: bool,
    /// Executed blocks, against the option `max_blocks` (crate::budget).
    pub(super) budget: crate::budget::Budget,
    /// The construct that last repeated (a backward jump, a call, a repeated pass): where a
    /// spent budget is reported.
    pub(super) repeating: Option<(Cursor, Range<usize>)>,
    pub(super) max_call_depth: usize,
    /// The block being read (physical lines joined), and a file's line buffer.
    pub(super) text: String,
    pub(super) buf: String,
    pub(super) toks: Vec<Range<usize>>,
    /// Words to run, block by block: (end in `words`, line number, the block is a held one).
    pub(super) words: Vec<Word<'static>>,
    pub(super) ends: Vec<(usize, usize)>,
    pub(super) noticed: Vec<String>,
}

/// The front end's view of the path.
pub(super) struct Contour {
    /// Program position X Y Z A B C (mm or inch, deg).
    pub(super) pos: [f64; 6],
    /// The pole `CC` (circle centre), in the plane of its two axes.
    pub(super) pole: Option<[f64; 2]>,
    /// The axes of the pole's plane, first and second (X Y, Z X or Y Z: the angle 0 lies
    /// on the first, DR+ turns from the first towards the second, as ISO's G17/G18/G19).
    pub(super) pole_plane: [usize; 2],
    /// Unit tangent at the end of the last contour element.
    pub(super) dir: Option<[f64; 2]>,
    /// The modal feed (`FMAX` leaves it).
    pub(super) feed: Option<f64>,
    /// The feed of `TOOL CALL … F` (`FAUTO`).
    pub(super) tool_feed: Option<f64>,
    /// Radius compensation: 0 `R0`, 1 `RL`, 2 `RR`.
    pub(super) comp: u8,
    pub(super) held: Option<Held>,
    pub(super) corner: Option<Corner>,
    /// An `APPR` waiting for the first contour element (its tangent).
    pub(super) appr: Option<Approach>,
    /// The last positioning was `FMAX` (`APPR` runs to its auxiliary point at rapid).
    pub(super) rapid: bool,
}

/// A straight feed line in the plane, not yet run.
#[derive(Clone, Copy)]
pub(super) struct Held {
    pub(super) start: [f64; 2],
    pub(super) end: [f64; 6],
    pub(super) feed: Option<f64>,
    pub(super) line: usize,
}

/// A `RND` (radius) or `CHF` (length) after a held line, waiting for the line after it.
pub(super) struct Corner {
    pub(super) held: Held,
    pub(super) round: bool,
    pub(super) size: f64,
    pub(super) feed: Option<f64>,
    pub(super) span: Range<usize>,
}

/// The words of a block besides its coordinates.
#[derive(Default)]
pub(super) struct Extras {
    pub(super) comp: Option<u8>,
    pub(super) feed: Option<f64>,
    pub(super) rapid: bool,
    /// M words passed to the interpreter.
    pub(super) m: Vec<(f64, Range<usize>)>,
    /// `M91`: the block's coordinates are machine coordinates.
    pub(super) m91: bool,
    /// `M140 MB`: retract by a distance, or to the top (`MB MAX`, `None`).
    pub(super) m140: Option<Option<f64>>,
    pub(super) m99: bool,
    pub(super) tcp: Option<bool>,
    pub(super) span: Range<usize>,
}

impl Extras {
    pub(super) fn plain(&self) -> bool {
        self.comp.is_none()
            && !self.rapid
            && self.m.is_empty()
            && !self.m91
            && self.m140.is_none()
            && !self.m99
            && self.tcp.is_none()
    }
}

impl Contour {
    pub(super) fn new(start: AxisVec) -> Contour {
        let mut c = Contour {
            pos: [0.0; 6],
            pole: None,
            pole_plane: [0, 1],
            dir: None,
            feed: None,
            tool_feed: None,
            comp: 0,
            held: None,
            corner: None,
            appr: None,
            rapid: false,
        };
        c.set_position(start);
        c
    }

    pub(super) fn set_position(&mut self, p: AxisVec) {
        use crate::axis::Axis;
        for (k, a) in [Axis::X, Axis::Y, Axis::Z, Axis::A, Axis::B, Axis::C]
            .iter()
            .enumerate()
        {
            self.pos[k] = p[*a];
        }
    }

    pub(super) fn set_z(&mut self, z: f64) {
        self.pos[2] = z;
    }

    pub(super) fn xy(&self) -> [f64; 2] {
        [self.pos[0], self.pos[1]]
    }
}

/// The active transformations.
#[derive(Default)]
pub(super) struct Frames {
    pub(super) datum: [f64; 3],
    /// The tool call's length delta `DL`.
    pub(super) dl: f64,
    pub(super) rot_deg: f64,
    pub(super) plane: Option<Mat3>,
    /// G68.2 is on in the interpreter.
    pub(super) tilted: bool,
    /// G52 is not zero in the interpreter.
    pub(super) shifted: bool,
    /// Cycles 8, 11 and 26: the map of the emitted words (`word_map`).
    pub(super) map: super::word_map::Map,
}

/// The cycle `CYCL DEF` defined last (its parameters are the Q parameters it set).
#[derive(Default)]
pub(super) struct Cycle {
    pub(super) number: Option<u32>,
    /// The line-by-line cycle's values in line order: cycle 1 PECKING's `1.1`-`1.5`
    /// (set-up clearance, depth, plunging depth, dwell (s), feed), cycle 2's `2.1`-`2.4`
    /// (set-up clearance, depth, dwell, feed), cycle 17's `17.1`-`17.3` (set-up clearance,
    /// depth, pitch).
    pub(super) pecking: [f64; 5],
    /// The Q parameters the last `CYCL DEF` of a 200-series cycle wrote (a cycle reads an
    /// optional parameter of its own, say Q439, only when its block wrote it, never a
    /// value another cycle left).
    pub(super) written: Vec<u32>,
}

/// A parsed block: its text and tokens.
pub(super) struct Block<'a> {
    pub(super) text: &'a str,
    pub(super) toks: &'a [Range<usize>],
    pub(super) line: usize,
}

impl Block<'_> {
    pub(super) fn tok(&self, k: usize) -> &str {
        self.toks.get(k).map_or("", |r| &self.text[r.clone()])
    }

    pub(super) fn span(&self, k: usize) -> Range<usize> {
        self.toks
            .get(k)
            .or(self.toks.last())
            .cloned()
            .unwrap_or(0..0)
    }

    /// From token `a` through token `b`.
    pub(super) fn spans(&self, a: usize, b: usize) -> Range<usize> {
        self.span(a).start..self.span(b).end
    }

    /// The value of token `k` after its `skip` letters: a plain decimal read in place (the
    /// G-code lexer's reader looks past the token's end, so it is given the whole block),
    /// else as [`text::value`] reads it.
    pub(super) fn value(&self, k: usize, skip: usize, q: &Qparams) -> LineResult<f64> {
        let span = self.span(k);
        if let (end, Some(v)) = crate::lex::scan_number(self.text.as_bytes(), span.start + skip) {
            if end == span.end {
                return Ok(v);
            }
        }
        text::value(&self.text[span.start + skip..span.end], q, span)
    }

    pub(super) fn is(&self, k: usize, word: &str) -> bool {
        self.tok(k).eq_ignore_ascii_case(word)
    }
}

/// The construct at token `k` (and the next, for two-word constructs) is not supported.
pub(super) fn refusal(b: &Block, k: usize) -> LineError {
    let name = construct_name(b, k);
    LineError::new(
        b.span(k).start..b.span((k + 1).min(b.toks.len().saturating_sub(1))).end,
        format!("the Heidenhain construct `{name}` is not supported by mtsim"),
        "Heidenhain construct not supported",
    )
    .help("docs/gcode.md lists the Heidenhain (Klartext) constructs mtsim reads")
}

/// The name a refusal gives: two words for `TCH PROBE`, `APPR LT`, `PATTERN DEF`, ….
fn construct_name(b: &Block, k: usize) -> String {
    let first = b.tok(k).to_ascii_uppercase();
    let two = [
        "TCH", "APPR", "DEP", "PATTERN", "SEL", "FUNCTION", "DECLARE", "SQL", "TRANS", "CALL",
        "TOOL", "END", "BLK", "FN", "CYCL",
    ];
    if two.contains(&first.as_str()) && k + 1 < b.toks.len() {
        format!("{} {}", first, b.tok(k + 1).to_ascii_uppercase())
    } else {
        first
    }
}

/// An unexpected word in a known construct.
pub(super) fn unexpected(b: &Block, k: usize, what: &str, expected: &str) -> LineError {
    LineError::new(
        b.span(k),
        format!("`{}` in {what}: expected {expected}", b.tok(k)),
        "unexpected word",
    )
}

/// The four paths, approach or departure.
#[derive(Clone, Copy, PartialEq, Debug)]
pub(super) enum Kind {
    /// Straight line, tangential.
    Lt,
    /// Straight line, normal.
    Ln,
    /// Circular arc, tangential.
    Ct,
    /// Straight line and arc, tangential to both.
    Lct,
}

/// An `APPR` read, waiting for the first contour element that gives its tangent.
pub(super) struct Approach {
    pub(super) kind: Kind,
    /// P_S, the position before the block.
    pub(super) start: [f64; 6],
    /// P_A (Z as the block gives it).
    pub(super) end: [f64; 6],
    pub(super) z_given: bool,
    pub(super) len: f64,
    pub(super) radius: f64,
    pub(super) cca_deg: f64,
    pub(super) comp: u8,
    pub(super) feed: Option<f64>,
    /// The block before `APPR` was `FMAX`: P_S → P_H at rapid.
    pub(super) rapid: bool,
    pub(super) m: Vec<(f64, std::ops::Range<usize>)>,
    pub(super) line: usize,
}

/// One element of a pattern definition.
#[derive(Clone, Copy, Debug)]
pub(super) enum Item {
    Point([f64; 3]),
    /// Start, spacing (x, y), counts (x, y), rotation (deg), surface; border only.
    Grid {
        at: [f64; 2],
        d: [f64; 2],
        n: [u32; 2],
        rot_deg: f64,
        z: f64,
        border: bool,
    },
    /// Centre, diameter, first angle, step (deg), count, surface.
    Circle {
        at: [f64; 2],
        diameter: f64,
        start_deg: f64,
        step_deg: f64,
        n: u32,
        z: f64,
    },
}
