//! The Siemens Sinumerik 840D front end: part programs (`.MPF`) and subprograms (`.SPF`)
//! into the ISO blocks the shared interpreter runs, so every move leaves as the same
//! canonical [`Move`].
//!
//! Input: the program's text, streamed line by line (jumps and loops seek back to a byte
//! offset; subprograms are bounded side files); state: R parameters, `DEF` variables, the
//! control structures, the programmable frame and the modal call; output: canonical moves.
//!
//! ```text
//! Sinumerik block ─► block.rs: N, labels, statements (DEF, IF, WHILE, FOR, GOTOF, frames,
//!                    calls, cycles) and words (X=AC(..), CR=, R1=.., G700 ...)
//!                 ─► one or more ISO blocks in Fanuc's codes (frames and AC/IC resolved
//!                    to absolute targets) ─► crate `lex` ─► `Interp` ─► Move
//! ```
//!
//! Control structures nest at most [`MAX_STRUCTURES`] deep per program level, subprograms
//! at most `Options::max_call_depth`, and every executed block is counted against
//! `Options::max_blocks` (crate `budget`), so no program hangs the reader.
//!
//! A structure still open where its program's text ends, with no closing line after its
//! head, is an error at its opening line.

mod block;
mod boring;
mod cip;
mod contour;
mod corner;
mod cycles;
mod deep_hole;
mod emit;
mod expr;
mod fixed_point;
mod flow;
mod frame;
mod keywords;
mod machine_words;
mod macros;
mod orientation;
mod patterns;
mod plain;
mod polar;
mod repeat;
mod settable;
mod source;
mod state;
mod turn;
mod words;

use std::collections::VecDeque;
use std::path::{Path, PathBuf};

use crate::canon::Move;
use crate::error::{Error, Result, Syntax};
use crate::front_end::{FrontEnd, Input, Registration};
use crate::interp::{Interp, Stop};
use crate::lex::{lex_with, Lexed, LineError, LineResult, Word};
use crate::notice::Notice;
use crate::options::{Dialect, Options};

use expr::Vars;
use frame::ProgFrame;
use source::Source;
use state::Structure;

/// Deepest nesting of `IF`, `WHILE`, `FOR`, `REPEAT` and `LOOP` in one program level
/// (the control's own limit, Job planning "Program sequence control").
pub const MAX_STRUCTURES: usize = 16;

/// One program level: the main program or a called subprogram.
struct Level {
    source: Source,
    path: PathBuf,
    /// Byte offset and 1-based number of the next line.
    offset: usize,
    line: usize,
    /// Where the program starts, for a repeated call (`L10 P3`).
    start: (usize, usize),
    /// Runs left after this one.
    repeats: u64,
    structures: Vec<Structure>,
    /// For each open structure, its opening line (offset, number) and keyword's span.
    opened: Vec<(usize, usize, std::ops::Range<usize>)>,
    /// Program sections being repeated (`REPEAT label P=n`), innermost last.
    sections: Vec<state::Section>,
    /// `PROC` parameters to bind: the values the call passed.
    args: Vec<f64>,
}

/// The moves of a Sinumerik program, in order (see the module doc).
pub(crate) struct Reader {
    interp: Interp,
    levels: Vec<Level>,
    vars: Vars,
    queue: VecDeque<Move>,
    notices: Vec<Notice>,
    /// The frame programmed points go through: the active settable frame's rotation,
    /// scale and mirror, then the programmable frame `prog` (settable.rs).
    frame: ProgFrame,
    prog: ProgFrame,
    /// Settable frames the program wrote (`$P_UIFR[n]`), and the active one's matrix.
    settable: [Option<frame::Components>; frame::SETTABLE],
    settable_matrix: crate::frame::Mat3,
    /// The pole of polar coordinates (frame coordinates) and the modal AP=, RP= (polar.rs).
    pole: [f64; 3],
    /// The direction the last move left its end point in (machine X Y Z), for CT.
    tangent: Option<[f64; 3]>,
    polar_values: [f64; 2],
    /// `DEFINE name AS text` macros, in order of definition (macro.rs).
    macros: Vec<(String, String)>,
    /// G90 as the Siemens program has it, and as the interpreter was last given.
    absolute: bool,
    interp_absolute: bool,
    /// The motion code (0-3) as programmed, and as the interpreter was last given.
    motion: u8,
    interp_motion: u8,
    /// A D number other than D0 is active (tool length compensation).
    d_active: bool,
    tool: u32,
    /// Tools called by name (`T="DRILL 8.5"`): numbered 1001, 1002 ... in order of call.
    tool_names: Vec<String>,
    tcp: bool,
    /// `ORIMKS`: orientation in the machine coordinate system (`ORIWKS`, the default: in
    /// the workpiece's).
    ori_machine: bool,
    /// G60 (exact stop) in effect; G64 otherwise.
    exact_stop: bool,
    /// CYCLE832's tolerance (mm), which the continuous-path modes G64/G641-G645 blend
    /// within (the planner's G64 P); `None`: the machine's default.
    path_tolerance_mm: Option<f64>,
    /// G70: inch geometry with the feed in mm/min.
    feed_in_mm: bool,
    /// The active plane's normal axis: 0 X (G19), 1 Y (G18), 2 Z (G17).
    normal: usize,
    /// The plane's normal as the interpreter was last given (a frame may stand an arc up).
    interp_normal: usize,
    /// Byte offset and number of the line being run.
    line_start: (usize, usize),
    /// `MCALL CYCLE8x(..)`: the cycle called after each positioning block.
    modal_call: Option<state::Cycle>,
    /// A G1 line held for the chamfer or rounding at its end (corner.rs).
    held: Option<state::Held>,
    /// `RNDM=r`: the modal rounding radius, program units.
    rounding_modal: Option<f64>,
    search_path: Vec<PathBuf>,
    user_m: Vec<u32>,
    max_depth: usize,
    /// Executed blocks, against the option `max_blocks` (crate::budget).
    budget: crate::budget::Budget,
    /// The construct that last repeated (a backward jump, a repeated call or section): its
    /// level, line (offset, number) and span, where a spent budget is reported.
    repeating: Option<(usize, (usize, usize, std::ops::Range<usize>))>,
    /// The ISO block being built, and for each of its words the span of the Sinumerik
    /// words it came from: (start in `iso`, span in the source line).
    iso: String,
    spans: Vec<(usize, std::ops::Range<usize>)>,
    /// The current line, as read and upper-cased.
    line: String,
    upper: String,
    words: Vec<Word<'static>>,
    finished: bool,
    noticed: Vec<String>,
}

impl Reader {
    /// The reader of `text` (`None`: stream the file at `path`).
    pub fn new(path: &Path, text: Option<&str>, options: &Options) -> std::io::Result<Reader> {
        let source = match text {
            Some(t) => Source::Text(t.into()),
            None => Source::open(path)?,
        };
        let iso_options = Options {
            dialect: Dialect::Fanuc,
            ..options.clone()
        };
        let mut search_path = options.search_path.clone();
        if let Some(dir) = path.parent() {
            search_path.push(dir.to_path_buf());
        }
        Ok(Reader {
            interp: Interp::new(&iso_options),
            levels: vec![Level {
                source,
                path: path.to_path_buf(),
                offset: 0,
                line: 1,
                start: (0, 1),
                repeats: 0,
                structures: Vec::new(),
                opened: Vec::new(),
                sections: Vec::new(),
                args: Vec::new(),
            }],
            vars: Vars {
                system: options.system_variables.clone(),
                ..Vars::new()
            },
            queue: VecDeque::new(),
            notices: Vec::new(),
            frame: ProgFrame::default(),
            prog: ProgFrame::default(),
            settable: [None; frame::SETTABLE],
            settable_matrix: crate::frame::IDENTITY,
            macros: Vec::new(),
            pole: [0.0; 3],
            tangent: None,
            polar_values: [0.0; 2],
            absolute: true,
            interp_absolute: true,
            motion: u8::MAX,
            interp_motion: u8::MAX,
            d_active: false,
            tool: 0,
            tool_names: Vec::new(),
            tcp: options.tcp,
            ori_machine: false,
            normal: 2,
            interp_normal: 2,
            feed_in_mm: false,
            exact_stop: false,
            path_tolerance_mm: None,
            line_start: (0, 1),
            modal_call: None,
            held: None,
            rounding_modal: None,
            search_path,
            user_m: options.user_m.keys().copied().collect(),
            max_depth: options.max_call_depth,
            budget: crate::budget::Budget::new(options.max_blocks),
            repeating: None,
            iso: String::new(),
            spans: Vec::new(),
            line: String::new(),
            upper: String::new(),
            words: Vec::new(),
            finished: false,
            noticed: Vec::new(),
        })
    }

    pub fn notices(&self) -> &[Notice] {
        &self.notices
    }

    fn level(&mut self) -> &mut Level {
        self.levels.last_mut().expect("the main program level")
    }

    /// Reads and runs the next line; `Ok(false)` at the end of the program.
    fn step(&mut self) -> Result<bool> {
        self.section_end();
        let mut line = std::mem::take(&mut self.line);
        let main = self.levels.len() == 1;
        let level = self.levels.last_mut().expect("the main program level");
        let n = level
            .source
            .line(level.offset, &mut line)
            .map_err(|e| Error::Read {
                path: level.path.clone(),
                source: std::io::Error::new(e.kind(), format!("line {}: {e}", level.line)),
            })?;
        if n == 0 {
            self.line = line;
            if let Some(e) = self.unclosed() {
                return Err(e);
            }
            // The end of a file ends its level as M17 (or the program as M30).
            return self.end_of_level().map_err(|e| self.syntax(e));
        }
        let line_no = level.line;
        if !self.budget.spend_at(main, level.offset) {
            self.line = line;
            let depth = self.levels.len() - 1;
            let (offset, line_no) = (self.levels[depth].offset, self.levels[depth].line);
            let (depth, (offset, line_no, span)) = self
                .repeating
                .clone()
                .unwrap_or((depth, (offset, line_no, 0..0)));
            let err = self.budget.spent(span);
            return Err(self.error_on_line(depth, offset, line_no, err));
        }
        self.line_start = (level.offset, level.line);
        level.offset += n;
        level.line += 1;
        if let Some(result) = self.plain(&line, line_no) {
            self.line = line;
            return result.map_err(|e| self.syntax_at(e, line_no));
        }
        let mut upper = std::mem::take(&mut self.upper);
        upper.clear();
        upper.push_str(&line);
        upper.make_ascii_uppercase();
        if let Some(expanded) = self.expand(&upper) {
            // The block as read: errors quote the expanded text.
            line.clone_from(&expanded);
            upper = expanded;
        }
        let result = self.block(&upper, line_no);
        self.upper = upper;
        self.line = line;
        let go_on = result.map_err(|e| self.syntax_at(e, line_no))?;
        Ok(go_on)
    }

    /// The current level ends: return to the caller (or run the subprogram again), or
    /// end the program.
    fn end_of_level(&mut self) -> LineResult<bool> {
        let level = self.level();
        if level.repeats > 0 {
            level.repeats -= 1;
            (level.offset, level.line) = level.start;
            level.structures.clear();
            level.opened.clear();
            level.sections.clear();
            return Ok(true);
        }
        if self.levels.len() == 1 {
            return Ok(false);
        }
        self.levels.pop();
        self.vars.levels.pop();
        Ok(true)
    }

    /// Runs the ISO block in `self.iso` through the interpreter.
    fn run_iso(&mut self, line_no: usize) -> LineResult<Stop> {
        let iso = std::mem::take(&mut self.iso);
        let result = self
            .run_text(&iso, line_no)
            .map_err(|e| self.source_span(e));
        self.iso = iso;
        self.iso.clear();
        self.spans.clear();
        result
    }

    /// Runs the ISO block `text` through the interpreter (errors at spans of `text`).
    fn run_text(&mut self, text: &str, line_no: usize) -> LineResult<Stop> {
        let words = std::mem::take(&mut self.words);
        let level = self.levels.last().expect("the main program level");
        match lex_with(text, &self.interp.params, true, reuse(words))? {
            Lexed::Words { words, .. } => {
                let r = self.interp.block(
                    text,
                    &words,
                    line_no,
                    &mut self.queue,
                    &mut self.notices,
                    &level.path,
                );
                self.words = reuse(words);
                if let Some(t) = self.queue.back().and_then(frame::end_tangent) {
                    self.tangent = Some(t);
                }
                r
            }
            _ => Ok(Stop::None),
        }
    }

    /// An error in the ISO block, moved onto the Sinumerik words it came from.
    fn source_span(&self, mut e: LineError) -> LineError {
        let from = self
            .spans
            .iter()
            .rev()
            .find(|(at, _)| *at <= e.span.start)
            .map(|(_, span)| span.clone());
        e.span = from.unwrap_or(0..self.line.len());
        e
    }

    /// Notes once per text that `what` was accepted and not simulated.
    fn notice(&mut self, line: usize, what: String) {
        if self.noticed.len() < 100 && !self.noticed.contains(&what) {
            self.noticed.push(what.clone());
            let path = self
                .levels
                .last()
                .map(|l| l.path.clone())
                .unwrap_or_default();
            self.notices.push(Notice {
                path,
                line,
                message: what,
                warning: false,
            });
        }
    }

    /// The error `e` on line `line` (the current line): the text quoted is the line alone
    /// at its own line number, as the G-code reader quotes a file it cannot read again.
    fn syntax_at(&self, e: LineError, line: usize) -> Error {
        let mut text = "\n".repeat(line.saturating_sub(1));
        let start = text.len();
        text.push_str(&self.line);
        let mut span = (start + e.span.start).min(text.len())..(start + e.span.end).min(text.len());
        while !text.is_char_boundary(span.start) {
            span.start -= 1;
        }
        while !text.is_char_boundary(span.end) {
            span.end += 1;
        }
        let column = text[start..span.start].chars().count() + 1;
        let path = self
            .levels
            .last()
            .map(|l| l.path.clone())
            .unwrap_or_default();
        Error::Syntax(Box::new(Syntax {
            path,
            line,
            column,
            message: e.message,
            label: e.label,
            help: e.help,
            text,
            span,
        }))
    }

    /// The error `e` on the line at byte `offset` (number `line`) of program level `depth`.
    fn error_on_line(&mut self, depth: usize, offset: usize, line: usize, e: LineError) -> Error {
        let mut text = String::new();
        let mut path = None;
        if let Some(level) = self.levels.get_mut(depth) {
            if level.source.line(offset, &mut text).is_err() {
                text.clear();
            }
            path = Some(level.path.clone());
        }
        let current = std::mem::replace(&mut self.line, text);
        let mut err = self.syntax_at(e, line);
        self.line = current;
        if let (Error::Syntax(s), Some(path)) = (&mut err, path) {
            // The quoted program is the level's own.
            s.path = path;
        }
        err
    }

    /// At the end of a level's text: the innermost structure opened in it with no closing
    /// line after its head, as an error at its opening line. (A loop left by a jump has its
    /// closing line and is not reported.)
    fn unclosed(&mut self) -> Option<Error> {
        let depth = self.levels.len() - 1;
        let opened = self.levels[depth].opened.clone();
        for (offset, line, span) in opened.into_iter().rev() {
            if !self.closed_after(offset) {
                let err = LineError::new(
                    span,
                    "this structure is never closed: expected its ENDIF, ENDWHILE, ENDFOR, UNTIL or ENDLOOP before the end of the program",
                    "unclosed structure",
                );
                self.finished = true;
                return Some(self.error_on_line(depth, offset, line, err));
            }
        }
        None
    }

    fn syntax(&self, e: LineError) -> Error {
        let line = self.levels.last().map_or(1, |l| l.line.saturating_sub(1));
        self.syntax_at(e, line)
    }

    /// After a line ran: the line held for a chamfer or rounding joins the first move a
    /// later line made; a program that ends with one held is refused.
    fn join_after_step(&mut self, go_on: bool) -> Result<bool> {
        if let Some(h) = self.held.as_mut() {
            if h.fresh {
                h.fresh = false;
            } else if let Err(m) = self.join_held() {
                return Err(self.syntax(LineError::new(
                    0..self.line.len(),
                    m,
                    "chamfer or rounding",
                )));
            }
        }
        if !go_on {
            if let Some(h) = self.held.take() {
                let m = format!(
                    "{}: the program ends before the next line; expected a G1 line after it",
                    h.pending.name()
                );
                return Err(self.syntax(LineError::new(
                    0..self.line.len(),
                    m,
                    "chamfer or rounding",
                )));
            }
        }
        Ok(go_on)
    }

    /// The next move, or the error that ends the program.
    pub fn next_move(&mut self) -> Option<Result<Move>> {
        loop {
            if let Some(m) = self.queue.pop_front() {
                return Some(Ok(m));
            }
            if self.finished {
                return None;
            }
            match self.step().and_then(|go_on| self.join_after_step(go_on)) {
                Ok(true) => {}
                Ok(false) => {
                    self.finished = true;
                    self.interp.finish(&mut self.queue);
                }
                Err(e) => {
                    self.finished = true;
                    self.held = None;
                    self.queue.clear();
                    self.interp.discard();
                    return Some(Err(e));
                }
            }
        }
    }
}

/// The Sinumerik front end's entry in `reader::FRONT_ENDS`: it reads a program of the
/// `siemens` dialect, and any program that is a Sinumerik part program or subprogram by its
/// file name or first line ([`is_sinumerik_program`]), whatever the dialect named (a
/// program in memory as its text, a file streamed its own way).
pub(crate) const FRONT_END: Registration = Registration {
    dialect: |d| d == Dialect::Siemens,
    first_line: Some(is_sinumerik_program),
    open: |path, input, options| {
        let text = match &input {
            Input::Source(crate::source::Source::Text(text)) => Some(&**text),
            _ => None,
        };
        Ok(Box::new(Reader::new(path, text, options)?))
    },
};

/// A Sinumerik main program or subprogram: the file's extension is the control's `MPF` or
/// `SPF` (any case), or its first line is the control's file header `%_N_<name>_MPF` /
/// `_SPF` (as the control writes it on export, also behind `;`). Sinumerik 840D sl
/// "Fundamentals", "File and program management: program memory" (the `_N_…_MPF` names).
fn is_sinumerik_program(path: &Path, first_line: &str) -> bool {
    let by_name = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("mpf") || e.eq_ignore_ascii_case("spf"));
    let header = first_line
        .trim_start_matches(['\u{feff}', ' ', '\t', ';'])
        .trim_start();
    let by_header = header.len() > 4
        && header.as_bytes()[..4].eq_ignore_ascii_case(b"%_N_")
        && header
            .split_whitespace()
            .next()
            .and_then(|h| h.get(h.len().saturating_sub(4)..))
            .is_some_and(|end| {
                end.eq_ignore_ascii_case("_MPF") || end.eq_ignore_ascii_case("_SPF")
            });
    by_name || by_header
}

impl FrontEnd for Reader {
    fn next_move(&mut self) -> Option<Result<Move>> {
        Reader::next_move(self)
    }

    fn notices(&self) -> &[Notice] {
        Reader::notices(self)
    }
}

/// An emptied vector of words, its allocation kept, for words that borrow another line.
fn reuse<'a, 'b>(mut words: Vec<Word<'a>>) -> Vec<Word<'b>> {
    words.clear();
    words.into_iter().map(|_| Word::EMPTY).collect()
}
