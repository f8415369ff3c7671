//! The state of the ISO G-code family's reader, in a leaf of its own: the reader itself,
//! places in the loaded texts, the open loops, ifs and calls, and the o-word keywords. The
//! files of `reader/` add its behaviour: the streaming core (`stream.rs`), flow
//! (`flow.rs`), calls (`calls.rs`), remaps (`remap.rs`) and the language screen
//! (`language.rs`).

use std::collections::{HashMap, VecDeque};
use std::path::PathBuf;

use crate::budget::Budget;
use crate::canon::Move;
use crate::error::Error;
use crate::interp::Interp;
use crate::lex::{LineError, Word};
use crate::notice::Notice;
use crate::options::Dialect;
use crate::remap::Remap;
use crate::source::{quoted_at, syntax_error, Source};

pub(super) use crate::source::Cursor;

pub(super) struct Program {
    pub(super) path: PathBuf,
    pub(super) source: Source,
    /// `o<name> sub` → the line after it; built on the first call that needs it.
    pub(super) subs: Option<HashMap<String, Cursor>>,
}

/// An o-word or macro statement keyword.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kw {
    Sub,
    EndSub,
    Call,
    Return,
    If,
    ElseIf,
    Else,
    EndIf,
    While,
    EndWhile,
    Do,
    Repeat,
    EndRepeat,
    Break,
    Continue,
    /// A bare `O1234`: Fanuc program number.
    Number,
}

pub(super) const KEYWORDS: [(&str, Kw); 15] = [
    ("sub", Kw::Sub),
    ("endsub", Kw::EndSub),
    ("call", Kw::Call),
    ("return", Kw::Return),
    ("if", Kw::If),
    ("elseif", Kw::ElseIf),
    ("else", Kw::Else),
    ("endif", Kw::EndIf),
    ("while", Kw::While),
    ("endwhile", Kw::EndWhile),
    ("do", Kw::Do),
    ("repeat", Kw::Repeat),
    ("endrepeat", Kw::EndRepeat),
    ("break", Kw::Break),
    ("continue", Kw::Continue),
];

/// An o-word line: label, keyword, where the rest starts, span of the o-word.
pub(super) struct OLine {
    pub(super) label: String,
    pub(super) kw: Kw,
    pub(super) rest: usize,
    pub(super) span: std::ops::Range<usize>,
}

/// A Fanuc macro statement.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Macro {
    If,
    While,
    End,
    Goto,
}

#[derive(Clone, Debug)]
pub(super) enum LoopKind {
    While,
    Do,
    Repeat(u64),
    /// Fanuc WHILE [..] DO m.
    FanucDo,
}

#[derive(Clone, Debug)]
pub(super) struct Loop {
    pub(super) label: String,
    pub(super) kind: LoopKind,
    /// Where an iteration starts again: the `while` line for while loops, the line after
    /// `do` / `repeat` otherwise.
    pub(super) start: Cursor,
    /// The opening line and the span of its o-word or `WHILE`, for an unclosed loop.
    pub(super) head: (Cursor, std::ops::Range<usize>),
}

/// An open `o.. if`: its label, whether a branch was taken, and its opening line and span.
#[derive(Clone, Debug)]
pub(super) struct OpenIf {
    pub(super) label: String,
    pub(super) taken: bool,
    pub(super) head: (Cursor, std::ops::Range<usize>),
}

pub(super) struct Frame {
    pub(super) ret: Cursor,
    /// The calling line and the call's span: the construct a repeat is counted against.
    pub(super) site: (Cursor, std::ops::Range<usize>),
    pub(super) saved: Vec<f64>,
    pub(super) loops: usize,
    pub(super) ifs: usize,
    /// Fanuc M98 with L repeats left, and the subprogram start.
    pub(super) repeats: u64,
    pub(super) start: Cursor,
    /// LinuxCNC o-call or Fanuc G65: own locals.
    pub(super) locals: bool,
    /// M73: restore the modal state on return.
    pub(super) restore: Option<Box<crate::interp::Saved>>,
    /// The remap (index) this call executes, and the rest of its block to run on return.
    pub(super) remap: Option<usize>,
    pub(super) resume: Option<Resume>,
    /// The stdglue epilog to run on return (crate::stdglue).
    pub(super) epilog: Option<Box<Epilog>>,
}

/// A stdglue epilog waiting for its remap's subroutine to return.
pub(super) struct Epilog {
    pub(super) handler: crate::stdglue::Handler,
    pub(super) remap: usize,
    /// The subroutine used the built-in code (LinuxCNC `builtin_used`).
    pub(super) builtin_used: bool,
    /// The remapped block and code, for errors.
    pub(super) here: Cursor,
    pub(super) span: std::ops::Range<usize>,
}

/// The words of a block left to run after a remapped code's subroutine returns.
pub(super) struct Resume {
    pub(super) here: Cursor,
    /// The block's text (a streamed file keeps no text to slice).
    pub(super) line: String,
    /// Letter, value, the number's byte range in the line, the word's span.
    pub(super) words: Vec<(char, f64, std::ops::Range<usize>, (usize, usize))>,
}

/// Lathe stock removal (`lathe.rs`): the two-block format's depth and retract, and how the
/// last rough cycle returns.
#[derive(Clone, Debug, Default)]
pub(super) struct LatheState {
    pub(super) depth_mm: Option<f64>,
    pub(super) retract_mm: Option<f64>,
    /// The last G71/G72 was G72 (its return goes along Z first).
    pub(super) facing: bool,
    /// The warning that lathe codes are read with the mill's meanings was given.
    pub(super) warned: bool,
}

/// The ISO G-code family's front end (LinuxCNC, Fanuc, Haas): the canonical moves of a
/// program, in order. Yields `Err` at most once, then `None`; stops after M02, M30 or a
/// closing `%`.
pub(crate) struct IsoReader {
    pub(super) programs: Vec<Program>,
    pub(super) cursor: Cursor,
    pub(super) interp: Interp,
    pub(super) dialect: Dialect,
    pub(super) search_path: Vec<PathBuf>,
    pub(super) queue: VecDeque<Move>,
    /// The queue's first move was lent by `FrontEnd::next_ref`: it leaves at the next call.
    pub(super) lent: bool,
    pub(super) frames: Vec<Frame>,
    pub(super) loops: Vec<Loop>,
    pub(super) ifs: Vec<OpenIf>,
    /// Executed blocks, against the option `max_blocks` (crate::budget).
    pub(super) budget: Budget,
    /// The construct that last repeated (a backward jump, a call, a repeated pass): where a
    /// spent budget is reported.
    pub(super) repeating: Option<(Cursor, std::ops::Range<usize>)>,
    pub(super) max_call_depth: usize,
    pub(super) finished: bool,
    /// The interpreter's held moves have been released (or dropped after an error).
    pub(super) flushed: bool,
    pub(super) percent_seen: bool,
    pub(super) language_checked: bool,
    pub(super) notices: Vec<Notice>,
    /// The current line of a streamed file.
    pub(super) buf: String,
    /// The block's word buffer, kept empty between blocks (no allocation per block).
    pub(super) words: Vec<Word<'static>>,
    /// A read error of a streamed file, reported by the next step.
    pub(super) io_error: Option<std::io::Error>,
    pub(super) remaps: Vec<Remap>,
    /// A block's words to run before the next line (after a remap returned).
    pub(super) resume: Option<Resume>,
    pub(super) remaps_noticed: Vec<usize>,
    /// An error raised on return from a remap (a stdglue epilog), reported at the
    /// remapped block's code.
    pub(super) abort: Option<(Cursor, std::ops::Range<usize>, String)>,
    /// A stdglue epilog's commit, made before the rest of the remapped block runs.
    pub(super) commit: Option<crate::stdglue::Commit>,
    /// A remapped cycle that is the motion mode: blocks with axis words call it again.
    pub(super) modal_remap: Option<usize>,
    /// stdglue cycle_prolog's sticky words.
    pub(super) sticky: crate::stdglue::Sticky,
    /// Lathe stock removal: the depth and retract of the two-block G71/G72 format's first
    /// block, and the last rough cycle's start and direction (for G70's return).
    pub(super) lathe: LatheState,
    /// Dimension words without a decimal point are in the least input increment
    /// (crate::decimal_point), and whether the warning has been given.
    pub(super) whole_increments: bool,
    pub(super) whole_warned: bool,
    /// Fanuc G51.1 / Haas G101 mirror image and G51 scaling (crate::mirror_scale).
    pub(super) mirror_scale: crate::mirror_scale::MirrorScale,
    /// A G01 line with `,R` / `,C`, held until the next block's move (crate::corner).
    pub(super) corner: Option<crate::corner::Pending>,
    /// Fanuc and Haas G16 polar coordinates (crate::fanuc_polar).
    pub(super) fanuc_polar: crate::fanuc_polar::FanucPolar,
}

impl IsoReader {
    /// The line at `c`, and the cursor of the next line; `None` at the end of the text (or
    /// on a read error, kept in `io_error`). Inlined (docs/performance.md).
    #[inline(always)]
    pub(super) fn line_at(&mut self, c: Cursor) -> Option<(&str, Cursor)> {
        match self.programs[c.file].source.line(c.offset, &mut self.buf) {
            Ok(Some((line, len))) => Some((
                line,
                Cursor {
                    file: c.file,
                    offset: c.offset + len,
                    line: c.line + 1,
                },
            )),
            Ok(None) => None,
            Err(e) => {
                self.io_error = Some(std::io::Error::new(
                    e.kind(),
                    format!("line {}: {e}", c.line),
                ));
                None
            }
        }
    }

    /// The whole text of program `file` and the byte offset of 1-based `line` in it, for an
    /// error message; a streamed file is read again (only on this error path). If it cannot
    /// be, the text is `line_text` alone at its own line number.
    pub(super) fn error_text(&self, c: Cursor, line_text: &str) -> (String, usize) {
        let program = &self.programs[c.file];
        quoted_at(program.source.quoted(&program.path), c.line, line_text)
    }

    pub(super) fn error_at(&self, c: Cursor, err: LineError, line_text: &str) -> Error {
        let (text, start) = self.error_text(c, line_text);
        self.syntax_in(c.file, &text, start, err)
    }

    /// A syntax error at `err.span` of the line starting at byte `start` of `text`, the text
    /// of program `file`.
    pub(super) fn syntax_in(&self, file: usize, text: &str, start: usize, err: LineError) -> Error {
        syntax_error(&self.programs[file].path, text.to_string(), start, err)
    }

    /// The text of the line at `here`, `len` bytes long, just read by [`IsoReader::line_at`].
    pub(super) fn buf_line(&self, here: Cursor, len: usize) -> String {
        match &self.programs[here.file].source {
            Source::Text(text) => text[here.offset..here.offset + len].to_string(),
            Source::File(_) => self.buf.clone(),
        }
    }
}

impl Program {
    pub(super) fn is_empty(&self) -> bool {
        match &self.source {
            Source::Text(text) => text.is_empty(),
            Source::File(f) => f.len == 0,
        }
    }
}

pub(super) fn shift(mut e: LineError, by: usize) -> LineError {
    e.span = e.span.start + by..e.span.end + by;
    e
}

pub(super) fn kw_name(kw: Kw) -> &'static str {
    KEYWORDS
        .iter()
        .find(|(_, k)| *k == kw)
        .map_or("", |(n, _)| n)
}
