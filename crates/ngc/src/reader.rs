//! The reader: program text, control flow (o-words, M98/M99, GOTO, WHILE), and the stream
//! of canonical moves. The modal interpreter itself is in `interp.rs`.
//!
//! ```text
//! text ─► line ─► o-word / macro statement? ─► flow (jump, call, loop)
//!                └► lex (words, assignments) ─► interp (modal state) ─► Move queue
//! ```
//!
//! A program file is streamed line by line through a fixed buffer: jumps (loops, calls,
//! GOTO) seek back to a byte offset, as LinuxCNC re-reads its file by offset, and the
//! subroutine index keeps offsets, not text. Subroutine files are streamed the same way.
//! Moves are streamed, never collected, so memory grows neither with the file nor with the
//! moves. A line longer than [`MAX_LINE_BYTES`] is a read error, and only regular files
//! are read (a device such as `/dev/zero`, a FIFO or a folder is refused).

use std::collections::{HashMap, VecDeque};
use std::io::Read;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use crate::axis::AxisVec;
use crate::budget::Budget;
use crate::canon::Move;
use crate::error::{Error, Result};
use crate::expr::{Eval, Param};
use crate::interp::{Interp, Stop};
use crate::lex::{is_blank, lex, lex_with, Lexed, LineError, LineResult, Word};
use crate::notice::Notice;
use crate::options::{Dialect, Options};
use crate::remap::Remap;
use crate::source::{quoted_at, syntax_error, FileLines, Source, FILE_BUFFER_BYTES};

/// Streams the moves of a file with default options, from `start`.
pub fn read_file(path: &Path, start: AxisVec) -> Result<Moves> {
    read_file_with(
        path,
        &Options {
            start,
            ..Options::default()
        },
    )
}

/// Streams the moves of `text`, reported as the contents of `path`, with default options.
pub fn read_str(path: &Path, text: &str, start: AxisVec) -> Moves {
    read_str_with(
        path,
        text,
        &Options {
            start,
            ..Options::default()
        },
    )
}

/// Streams the moves of the file at `path`, reading it line by line (memory does not grow
/// with the file).
pub fn read_file_with(path: &Path, options: &Options) -> Result<Moves> {
    let read_error = |source| Error::Read {
        path: path.to_path_buf(),
        source,
    };
    if options.dialect == Dialect::Siemens {
        let front = crate::siemens::Reader::new(path, None, options).map_err(read_error)?;
        return Ok(Moves::siemens(path, front, options));
    }
    let source = Source::File(FileLines::open(path).map_err(read_error)?);
    Ok(Moves::new(path, source, options))
}

/// Streams the moves of `text`, reported as the contents of `path`.
pub fn read_str_with(path: &Path, text: &str, options: &Options) -> Moves {
    if options.dialect == Dialect::Siemens {
        let front = crate::siemens::Reader::new(path, Some(text), options)
            .expect("a text source opens no file");
        return Moves::siemens(path, front, options);
    }
    Moves::new(path, Source::Text(text.into()), options)
}

/// A place in one of the loaded program texts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Cursor {
    file: usize,
    /// Byte offset of the line start.
    offset: usize,
    /// 1-based line number of the line at `offset`.
    line: usize,
}

struct Program {
    path: PathBuf,
    source: Source,
    /// `o<name> sub` → the line after it; built on the first call that needs it.
    subs: Option<HashMap<String, Cursor>>,
}

/// An o-word or macro statement keyword.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kw {
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

const KEYWORDS: [(&str, Kw); 15] = [
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
struct OLine {
    label: String,
    kw: Kw,
    rest: usize,
    span: std::ops::Range<usize>,
}

/// Skips blanks and an `N<digits>` word; returns the index after them.
fn after_line_number(b: &[u8]) -> usize {
    let mut i = 0;
    while i < b.len() && is_blank(b[i]) {
        i += 1;
    }
    if i < b.len() && (b[i] == b'N' || b[i] == b'n') {
        let mut k = i + 1;
        while k < b.len() && (b[k].is_ascii_digit() || b[k] == b'.') {
            k += 1;
        }
        if k > i + 1 {
            i = k;
            while i < b.len() && is_blank(b[i]) {
                i += 1;
            }
        }
    }
    i
}

/// Reads an o-word line header, if the line is one.
fn oline(line: &str) -> LineResult<Option<OLine>> {
    let b = line.as_bytes();
    let i = after_line_number(b);
    if !matches!(b.get(i), Some(b'o' | b'O')) {
        return Ok(None);
    }
    let start = i;
    let mut k = i + 1;
    while k < b.len() && is_blank(b[k]) {
        k += 1;
    }
    let label = if b.get(k) == Some(&b'<') {
        let Some(close) = line[k..].find('>') else {
            return Err(LineError::new(
                start..line.len(),
                "unclosed o-word name: expected `>` after `o<name`",
                "no `>`",
            ));
        };
        let name: String = line[k + 1..k + close]
            .chars()
            .filter(|c| !c.is_whitespace())
            .map(|c| c.to_ascii_lowercase())
            .collect();
        k += close + 1;
        name
    } else {
        let d = k;
        while k < b.len() && b[k].is_ascii_digit() {
            k += 1;
        }
        if d == k && b.get(k).is_some_and(u8::is_ascii_alphabetic) {
            // `OFinal ToolPath`: a program name where the number would be (a CAM post's
            // header), read as a Fanuc program number line; the rest of the line is its name.
            let end = line[k..].find(['(', ';']).map_or(line.len(), |e| k + e);
            return Ok(Some(OLine {
                label: line[k..end].trim().to_ascii_lowercase(),
                kw: Kw::Number,
                rest: line.len(),
                span: start..end,
            }));
        }
        if d == k {
            return Err(LineError::new(
                start..k.max(start + 1),
                "o-word without a label: expected `o<number>` or `o<name>`",
                "no label",
            ));
        }
        line[d..k].trim_start_matches('0').to_string()
    };
    while k < b.len() && is_blank(b[k]) {
        k += 1;
    }
    let ks = k;
    while k < b.len() && b[k].is_ascii_alphabetic() {
        k += 1;
    }
    let word = line[ks..k].to_ascii_lowercase();
    let kw = if word.is_empty() {
        Kw::Number
    } else {
        match KEYWORDS.iter().find(|(w, _)| *w == word) {
            Some(&(_, kw)) => kw,
            None => {
                return Err(LineError::new(
                    ks..k,
                    format!("unknown o-word keyword `{}`: expected one of sub endsub call return if elseif else endif while endwhile do repeat endrepeat break continue", &line[ks..k]),
                    "unknown keyword",
                ))
            }
        }
    };
    Ok(Some(OLine {
        label,
        kw,
        rest: k,
        span: start..k,
    }))
}

/// A Fanuc macro statement.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Macro {
    If,
    While,
    End,
    Goto,
}

fn macro_line(line: &str) -> Option<(Macro, usize, usize)> {
    let b = line.as_bytes();
    let i = after_line_number(b);
    let mut k = i;
    while k < b.len() && b[k].is_ascii_alphabetic() {
        k += 1;
    }
    if k - i < 2 {
        // A word letter and its number (`G1`): the common case, no keyword.
        return None;
    }
    let word = &line[i..k];
    let m = [
        ("IF", Macro::If),
        ("WHILE", Macro::While),
        ("END", Macro::End),
        ("GOTO", Macro::Goto),
    ]
    .into_iter()
    .find(|(w, _)| word.eq_ignore_ascii_case(w))?
    .1;
    Some((m, i, k))
}

#[derive(Clone, Debug)]
enum LoopKind {
    While,
    Do,
    Repeat(u64),
    /// Fanuc WHILE [..] DO m.
    FanucDo,
}

#[derive(Clone, Debug)]
struct Loop {
    label: String,
    kind: LoopKind,
    /// Where an iteration starts again: the `while` line for while loops, the line after
    /// `do` / `repeat` otherwise.
    start: Cursor,
    /// The opening line and the span of its o-word or `WHILE`, for an unclosed loop.
    head: (Cursor, std::ops::Range<usize>),
}

/// An open `o.. if`: its label, whether a branch was taken, and its opening line and span.
#[derive(Clone, Debug)]
struct OpenIf {
    label: String,
    taken: bool,
    head: (Cursor, std::ops::Range<usize>),
}

struct Frame {
    ret: Cursor,
    /// The calling line and the call's span: the construct a repeat is counted against.
    site: (Cursor, std::ops::Range<usize>),
    saved: Vec<f64>,
    loops: usize,
    ifs: usize,
    /// Fanuc M98 with L repeats left, and the subprogram start.
    repeats: u64,
    start: Cursor,
    /// LinuxCNC o-call or Fanuc G65: own locals.
    locals: bool,
    /// M73: restore the modal state on return.
    restore: Option<Box<crate::interp::Saved>>,
    /// The remap (index) this call executes, and the rest of its block to run on return.
    remap: Option<usize>,
    resume: Option<Resume>,
    /// The stdglue epilog to run on return (crate::stdglue).
    epilog: Option<Box<Epilog>>,
}

/// A stdglue epilog waiting for its remap's subroutine to return.
struct Epilog {
    handler: crate::stdglue::Handler,
    remap: usize,
    /// The subroutine used the built-in code (LinuxCNC `builtin_used`).
    builtin_used: bool,
    /// The remapped block and code, for errors.
    here: Cursor,
    span: std::ops::Range<usize>,
}

/// The words of a block left to run after a remapped code's subroutine returns.
struct Resume {
    here: Cursor,
    /// The block's text (a streamed file keeps no text to slice).
    line: String,
    /// Letter, value, the number's byte range in the line, the word's span.
    words: Vec<(char, f64, std::ops::Range<usize>, (usize, usize))>,
}

/// The canonical moves of a program, in order. Yields `Err` at most once, then `None`; stops
/// after M02, M30 or a closing `%`.
pub struct Moves {
    programs: Vec<Program>,
    cursor: Cursor,
    interp: Interp,
    dialect: Dialect,
    search_path: Vec<PathBuf>,
    queue: VecDeque<Move>,
    /// The queue's first move was lent by [`Moves::next_ref`]: it leaves at the next call.
    lent: bool,
    frames: Vec<Frame>,
    loops: Vec<Loop>,
    ifs: Vec<OpenIf>,
    /// Executed blocks, against the option `max_blocks` (crate::budget).
    budget: Budget,
    /// The construct that last repeated (a backward jump, a call, a repeated pass): where a
    /// spent budget is reported.
    repeating: Option<(Cursor, std::ops::Range<usize>)>,
    max_call_depth: usize,
    finished: bool,
    /// The interpreter's held moves have been released (or dropped after an error).
    flushed: bool,
    percent_seen: bool,
    language_checked: bool,
    notices: Vec<Notice>,
    /// The current line of a streamed file.
    buf: String,
    /// A HEIDENHAIN Klartext program's own front end (crate `dialect::heidenhain`), which
    /// then yields every move.
    klartext: Option<Box<crate::heidenhain::Reader>>,
    /// The block's word buffer, kept empty between blocks (no allocation per block).
    words: Vec<Word<'static>>,
    /// A read error of a streamed file, reported by the next step.
    io_error: Option<std::io::Error>,
    remaps: Vec<Remap>,
    /// A block's words to run before the next line (after a remap returned).
    resume: Option<Resume>,
    remaps_noticed: Vec<usize>,
    /// An error raised on return from a remap (a stdglue epilog), reported at the
    /// remapped block's code.
    abort: Option<(Cursor, std::ops::Range<usize>, String)>,
    /// A stdglue epilog's commit, made before the rest of the remapped block runs.
    commit: Option<crate::stdglue::Commit>,
    /// A remapped cycle that is the motion mode: blocks with axis words call it again.
    modal_remap: Option<usize>,
    /// stdglue cycle_prolog's sticky words.
    sticky: crate::stdglue::Sticky,
    /// The Siemens Sinumerik front end, which reads the program instead (crate `siemens`).
    siemens: Option<Box<crate::siemens::Reader>>,
}

impl Moves {
    fn new(path: &Path, source: Source, options: &Options) -> Moves {
        let mut moves = Moves::g_code(path, source, options);
        // A Klartext program goes to its own front end, whatever the dialect named.
        if options.dialect == Dialect::Heidenhain || moves.first_line_heidenhain() {
            let source = std::mem::replace(&mut moves.programs[0].source, Source::Text("".into()));
            let options = Options {
                dialect: Dialect::Heidenhain,
                ..options.clone()
            };
            moves.klartext = Some(Box::new(crate::heidenhain::Reader::new(
                path, source, &options,
            )));
        }
        moves
    }

    fn g_code(path: &Path, source: Source, options: &Options) -> Moves {
        Moves {
            programs: vec![Program {
                path: path.to_path_buf(),
                source,
                subs: None,
            }],
            cursor: Cursor {
                file: 0,
                offset: 0,
                line: 1,
            },
            interp: Interp::new(options),
            dialect: options.dialect,
            search_path: options.search_path.clone(),
            queue: VecDeque::new(),
            lent: false,
            frames: Vec::new(),
            loops: Vec::new(),
            ifs: Vec::new(),
            budget: Budget::new(options.max_blocks),
            repeating: None,
            max_call_depth: options.max_call_depth,
            finished: false,
            flushed: false,
            percent_seen: false,
            language_checked: false,
            notices: Vec::new(),
            buf: String::new(),
            klartext: None,
            words: Vec::new(),
            io_error: None,
            remaps: options.remaps.clone(),
            resume: None,
            remaps_noticed: Vec::new(),
            abort: None,
            commit: None,
            modal_remap: None,
            sticky: Default::default(),
            siemens: None,
        }
    }

    /// The moves of a Sinumerik program, read by its own front end.
    fn siemens(path: &Path, front: crate::siemens::Reader, options: &Options) -> Moves {
        let mut moves = Moves::new(path, Source::Text("".into()), options);
        moves.siemens = Some(Box::new(front));
        moves
    }

    /// What was accepted without being simulated (user M codes, at most one notice per
    /// code), so far.
    pub fn notices(&self) -> &[Notice] {
        if let Some(k) = &self.klartext {
            return k.notices();
        }
        if let Some(front) = &self.siemens {
            return front.notices();
        }
        &self.notices
    }

    /// The line at `c`, and the cursor of the next line; `None` at the end of the text (or
    /// on a read error, kept in `io_error`). Inlined (docs/performance.md).
    #[inline(always)]
    fn line_at(&mut self, c: Cursor) -> Option<(&str, Cursor)> {
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
    fn error_text(&self, c: Cursor, line_text: &str) -> (String, usize) {
        let program = &self.programs[c.file];
        quoted_at(program.source.quoted(&program.path), c.line, line_text)
    }

    fn error_at(&self, c: Cursor, err: LineError, line_text: &str) -> Error {
        let (text, start) = self.error_text(c, line_text);
        self.syntax_in(c.file, &text, start, err)
    }

    /// A syntax error at `err.span` of the line starting at byte `start` of `text`, the text
    /// of program `file`.
    fn syntax_in(&self, file: usize, text: &str, start: usize, err: LineError) -> Error {
        syntax_error(&self.programs[file].path, text.to_string(), start, err)
    }

    /// A backward jump from the line at `here`: the construct a spent budget names (the
    /// blocks themselves are counted as they run, in [`Moves::step`]).
    fn backward(&mut self, here: Cursor, span: std::ops::Range<usize>) {
        self.repeating = Some((here, span));
    }

    /// Moves the cursor forward from the line after `from` to the first o-word line with
    /// `label` and a keyword in `kws`; the cursor is left on that line.
    fn skip_to(
        &mut self,
        from: Cursor,
        label: &str,
        kws: &[Kw],
        span: std::ops::Range<usize>,
    ) -> LineResult<()> {
        let mut c = match self.line_at(from) {
            Some((_, next)) => next,
            None => from,
        };
        while let Some((line, next)) = self.line_at(c) {
            if let Ok(Some(o)) = oline(line) {
                if o.label == label && kws.contains(&o.kw) {
                    self.cursor = c;
                    return Ok(());
                }
            }
            c = next;
        }
        Err(LineError::new(
            span,
            format!(
                "no matching `o{label} {}` after this line: expected the block to be closed",
                kw_name(kws[kws.len() - 1])
            ),
            "unclosed block",
        ))
    }

    /// Same for Fanuc `END m`.
    fn skip_to_end(
        &mut self,
        from: Cursor,
        m: &str,
        span: std::ops::Range<usize>,
    ) -> LineResult<()> {
        let mut c = match self.line_at(from) {
            Some((_, next)) => next,
            None => from,
        };
        while let Some((line, next)) = self.line_at(c) {
            if let Some((Macro::End, _, k)) = macro_line(line) {
                if line[k..].trim().trim_start_matches('0') == m {
                    self.cursor = c;
                    return Ok(());
                }
            }
            c = next;
        }
        Err(LineError::new(
            span,
            format!("no `END {m}` after this WHILE: expected the loop to be closed"),
            "unclosed loop",
        ))
    }

    /// The file subroutine index of program `file`.
    fn subs(&mut self, file: usize) -> &HashMap<String, Cursor> {
        if self.programs[file].subs.is_none() {
            let mut map = HashMap::new();
            let mut c = Cursor {
                file,
                offset: 0,
                line: 1,
            };
            let fanuc = self.dialect.table().macro_b;
            while let Some((line, next)) = self.line_at(c) {
                if let Ok(Some(o)) = oline(line) {
                    if o.kw == Kw::Sub || (fanuc && o.kw == Kw::Number) {
                        map.entry(o.label).or_insert(next);
                    }
                }
                c = next;
            }
            self.programs[file].subs = Some(map);
        }
        self.programs[file].subs.as_ref().expect("built above")
    }

    /// Where subroutine `label` starts in program `file`, if it is there; a file that could
    /// not be read to its end while indexing it is an error at the call's `span`.
    fn sub_in(
        &mut self,
        file: usize,
        label: &str,
        span: &std::ops::Range<usize>,
    ) -> LineResult<Option<Cursor>> {
        let found = self.subs(file).get(label).copied();
        match self.io_error.take() {
            Some(e) => Err(LineError::new(
                span.clone(),
                format!(
                    "subroutine file {}: {e}",
                    self.programs[file].path.display()
                ),
                "unreadable subroutine file",
            )),
            None => Ok(found),
        }
    }

    /// Where subroutine `label` starts: this file, a loaded file, or a file on the search
    /// path (`label.ngc`, or for Fanuc `O<label>.nc`), loaded once.
    fn find_sub(&mut self, label: &str, span: std::ops::Range<usize>) -> LineResult<Cursor> {
        let here = self.cursor.file;
        for file in std::iter::once(here).chain(0..self.programs.len()) {
            if let Some(c) = self.sub_in(file, label, &span)? {
                return Ok(c);
            }
        }
        let names = if self.dialect.table().macro_b {
            vec![
                format!("O{label}.nc"),
                format!("o{label}.nc"),
                format!("O{label:0>4}.nc"),
                format!("{label}.nc"),
            ]
        } else {
            vec![format!("{label}.ngc")]
        };
        for dir in self.search_path.clone() {
            for name in &names {
                let path = dir.join(name);
                if !path.exists() {
                    continue;
                }
                let lines = FileLines::open(&path).map_err(|e| {
                    LineError::new(
                        span.clone(),
                        format!("subroutine file {}: {e}", path.display()),
                        "unreadable subroutine file",
                    )
                })?;
                self.programs.push(Program {
                    path,
                    source: Source::File(lines),
                    subs: None,
                });
                let file = self.programs.len() - 1;
                if let Some(c) = self.sub_in(file, label, &span)? {
                    return Ok(c);
                }
                if self.dialect.table().macro_b {
                    // A Fanuc program file without its own O line starts at its top.
                    return Ok(Cursor {
                        file,
                        offset: 0,
                        line: 1,
                    });
                }
            }
        }
        Err(LineError::new(
            span,
            format!("subroutine `{label}` not found: expected it defined in this file or in a file on the subroutine search path"),
            "unknown subroutine",
        )
        .help("set the scenario's subroutine search path, or define the subroutine in the program"))
    }

    #[allow(clippy::too_many_arguments)]
    fn call(
        &mut self,
        label: &str,
        args: &[f64],
        locals: bool,
        repeats: u64,
        here: Cursor,
        next: Cursor,
        span: std::ops::Range<usize>,
    ) -> LineResult<()> {
        // Every pass runs at least its return: a count the budget cannot hold is refused
        // before the first pass.
        self.budget
            .check_passes(repeats, "this subprogram call", span.clone())?;
        let site = (here, span.clone());
        self.repeating = Some(site.clone());
        if self.frames.len() >= self.max_call_depth {
            return Err(LineError::new(
                span,
                format!("subroutines nested deeper than {}: expected the calls to return (endless recursion?)", self.max_call_depth),
                "call depth limit",
            ));
        }
        let start = match label.strip_prefix('N') {
            // Haas M97: a local subprogram at a sequence number of this program.
            Some(n) => self.sequence_line(self.cursor.file, n).ok_or_else(|| {
                LineError::new(
                    span,
                    format!("M97 P{n}: no block with sequence number N{n} in this program"),
                    "unknown sequence number",
                )
                .help("M97 calls a local subprogram that starts at N<n> of the same program")
            })?,
            None => self.find_sub(label, span)?,
        };
        let nlocal = if self.dialect.table().macro_b { 33 } else { 30 };
        let saved = if locals {
            let p = &mut self.interp.params;
            let saved = p.numbered[1..=nlocal].to_vec();
            for k in 1..=nlocal {
                p.numbered[k] = args.get(k - 1).copied().unwrap_or(0.0);
            }
            p.locals.push(HashMap::new());
            saved
        } else {
            Vec::new()
        };
        self.frames.push(Frame {
            ret: next,
            site,
            saved,
            loops: self.loops.len(),
            ifs: self.ifs.len(),
            repeats: repeats.saturating_sub(1),
            start,
            locals,
            restore: None,
            remap: None,
            resume: None,
            epilog: None,
        });
        self.cursor = start;
        Ok(())
    }

    /// Returns from the current subroutine; false in the main program.
    fn ret(&mut self, value: Option<f64>) -> bool {
        let Some(frame) = self.frames.last_mut() else {
            return false;
        };
        if frame.repeats > 0 {
            frame.repeats -= 1;
            self.repeating = Some(frame.site.clone());
            self.cursor = frame.start;
            self.loops.truncate(frame.loops);
            self.ifs.truncate(frame.ifs);
            return true;
        }
        let frame = self.frames.pop().expect("checked");
        if let Some(e) = &frame.epilog {
            // The epilog reads the subroutine's parameters before they go.
            let p = &self.interp.params;
            let locals = p.locals.last();
            let remap = &self.remaps[e.remap];
            let result = crate::stdglue::epilog(
                e.handler,
                remap.code,
                remap.ngc.as_deref().unwrap_or(""),
                value,
                e.builtin_used,
                &|k| locals.and_then(|l| l.get(k).copied()),
                &|n| p.numbered.get(n).copied().unwrap_or(0.0),
            );
            match result {
                Ok(crate::stdglue::Commit::KeepMotion) => self.modal_remap = Some(e.remap),
                Ok(c) => self.commit = Some(c),
                Err(m) => {
                    self.abort = Some((
                        e.here,
                        e.span.clone(),
                        format!("{m} (stdglue {}, {})", e.handler.name(), remap.origin),
                    ))
                }
            }
        }
        if frame.locals {
            let p = &mut self.interp.params;
            for (k, v) in frame.saved.iter().enumerate() {
                p.numbered[k + 1] = *v;
            }
            p.locals.pop();
        }
        if let Some(saved) = frame.restore {
            self.interp.restore(&saved);
        }
        self.resume = frame.resume;
        self.loops.truncate(frame.loops);
        self.ifs.truncate(frame.ifs);
        let p = &mut self.interp.params;
        p.set(
            &Param::Named("_value_returned".into()),
            if value.is_some() { 1.0 } else { 0.0 },
        );
        if let Some(v) = value {
            p.set(&Param::Named("_value".into()), v);
        }
        self.cursor = frame.ret;
        true
    }

    fn eval_bracket(&mut self, line: &str, at: usize) -> LineResult<(f64, usize)> {
        self.interp.refresh_system_parameters();
        let mut e = Eval::new(line, at, &self.interp.params, self.dialect.table().macro_b);
        e.skip_blanks();
        if line.as_bytes().get(e.i) != Some(&b'[') {
            let end = (e.i + 1).min(line.len());
            return Err(LineError::new(
                e.i.min(end)..end,
                "expected `[condition]`",
                "expected `[`",
            ));
        }
        let v = e.value()?;
        Ok((v, e.i))
    }

    /// Executes an o-word line at `here` (cursor already past it, at `next`).
    fn o_word(&mut self, line: &str, o: OLine, here: Cursor, next: Cursor) -> LineResult<bool> {
        let label = o.label.clone();
        match o.kw {
            Kw::Number => {
                if !self.dialect.table().macro_b {
                    return Err(LineError::new(o.span, "o-word without a keyword: expected `o<label> sub`, `call`, `if`, `while` ...", "no keyword")
                        .help("LinuxCNC o-words need a keyword; for Fanuc programs set dialect = \"fanuc\""));
                }
                // Fanuc program number: nothing to do.
            }
            Kw::Sub => {
                // A definition met in the flow: skip over it.
                self.skip_to(here, &label, &[Kw::EndSub], o.span)?;
                let (_, after) = self.line_at(self.cursor).expect("found");
                self.cursor = after;
            }
            Kw::EndSub | Kw::Return => {
                let value = self.optional_value(line, o.rest)?;
                if !self.ret(value) {
                    return Err(LineError::new(
                        o.span.clone(),
                        format!(
                            "`{}` outside a subroutine: expected it only in a called subroutine",
                            &line[o.span.clone()]
                        ),
                        "not in a subroutine",
                    ));
                }
            }
            Kw::Call => self.o_call(line, &o, &label, here, next)?,
            Kw::If => {
                let (c, _) = self.eval_bracket(line, o.rest)?;
                self.ifs.push(OpenIf {
                    label: label.clone(),
                    taken: c != 0.0,
                    head: (here, o.span.clone()),
                });
                if c == 0.0 {
                    self.skip_to(here, &label, &[Kw::ElseIf, Kw::Else, Kw::EndIf], o.span)?;
                }
            }
            Kw::ElseIf | Kw::Else => self.o_else(line, &o, &label, here)?,
            Kw::EndIf => match self.ifs.last() {
                Some(open) if open.label == label => {
                    self.ifs.pop();
                }
                _ => {
                    return Err(LineError::new(
                        o.span,
                        "`endif` without a matching `if`",
                        "no if",
                    ))
                }
            },
            Kw::While => self.o_while(line, &o, label, here)?,
            Kw::EndWhile => match self.loops.last() {
                Some(l) if l.label == label => {
                    let start = l.start;
                    self.backward(here, o.span);
                    self.cursor = start;
                }
                _ => {
                    return Err(LineError::new(
                        o.span,
                        "`endwhile` without a matching `while`",
                        "no while",
                    ))
                }
            },
            Kw::Do => self.loops.push(Loop {
                label,
                kind: LoopKind::Do,
                start: next,
                head: (here, o.span),
            }),
            Kw::Repeat => {
                let (n, _) = self.eval_bracket(line, o.rest)?;
                let n = if n.is_finite() && n > 0.0 {
                    n.round() as u64
                } else {
                    0
                };
                // Every pass runs at least its `endrepeat` line.
                self.budget.check_passes(
                    n.saturating_sub(1),
                    "this o-word repeat",
                    o.span.clone(),
                )?;
                if n == 0 {
                    self.skip_to(here, &label, &[Kw::EndRepeat], o.span)?;
                    let (_, after) = self.line_at(self.cursor).expect("found");
                    self.cursor = after;
                } else {
                    self.loops.push(Loop {
                        label,
                        kind: LoopKind::Repeat(n - 1),
                        start: next,
                        head: (here, o.span),
                    });
                }
            }
            Kw::EndRepeat => match self.loops.last_mut() {
                Some(Loop {
                    label: l,
                    kind: LoopKind::Repeat(left),
                    start,
                    ..
                }) if *l == label => {
                    if *left > 0 {
                        *left -= 1;
                        let start = *start;
                        self.backward(here, o.span);
                        self.cursor = start;
                    } else {
                        self.loops.pop();
                    }
                }
                _ => {
                    return Err(LineError::new(
                        o.span,
                        "`endrepeat` without a matching `repeat`",
                        "no repeat",
                    ))
                }
            },
            Kw::Break | Kw::Continue => self.o_break(line, &o, &label, here)?,
        }
        Ok(false)
    }

    /// `o<label> call [args]`: the subroutine called with its arguments.
    fn o_call(
        &mut self,
        line: &str,
        o: &OLine,
        label: &str,
        here: Cursor,
        next: Cursor,
    ) -> LineResult<()> {
        self.interp.refresh_system_parameters();
        let mut args = Vec::new();
        let mut e = Eval::new(line, o.rest, &self.interp.params, false);
        loop {
            e.skip_blanks();
            match line.as_bytes().get(e.i) {
                Some(b'[') => args.push(e.value()?),
                Some(b'(') | Some(b';') | None => break,
                _ => {
                    return Err(LineError::new(
                        e.i..e.i + 1,
                        "expected `[argument]` after `call`",
                        "expected `[`",
                    ));
                }
            }
        }
        if args.len() > 30 {
            return Err(LineError::new(
                o.span.clone(),
                "more than 30 arguments: expected at most 30",
                "too many arguments",
            ));
        }
        self.call(label, &args, true, 1, here, next, o.span.clone())?;
        Ok(())
    }

    /// `o.. elseif [cond]` / `o.. else`: taken when no branch of the `if` was.
    fn o_else(&mut self, line: &str, o: &OLine, label: &str, here: Cursor) -> LineResult<()> {
        let Some(OpenIf {
            label: l, taken, ..
        }) = self.ifs.last().cloned()
        else {
            return Err(LineError::new(
                o.span.clone(),
                "`else` without `if`: expected a matching `o.. if`",
                "no if",
            ));
        };
        if l != label {
            return Err(LineError::new(
                o.span.clone(),
                format!("`o{label}` does not match the open `o{l} if`"),
                "label mismatch",
            ));
        }
        if taken {
            self.skip_to(here, &label, &[Kw::EndIf], o.span.clone())?;
        } else if o.kw == Kw::Else {
            self.ifs.last_mut().expect("checked").taken = true;
        } else {
            let (c, _) = self.eval_bracket(line, o.rest)?;
            if c != 0.0 {
                self.ifs.last_mut().expect("checked").taken = true;
            } else {
                self.skip_to(
                    here,
                    &label,
                    &[Kw::ElseIf, Kw::Else, Kw::EndIf],
                    o.span.clone(),
                )?;
            }
        }
        Ok(())
    }

    /// `o.. while [cond]`: the loop's head, or the tail of an `o.. do` loop.
    fn o_while(&mut self, line: &str, o: &OLine, label: String, here: Cursor) -> LineResult<()> {
        let top_do = matches!(self.loops.last(), Some(Loop { label: l, kind: LoopKind::Do, .. }) if *l == label);
        let (c, _) = self.eval_bracket(line, o.rest)?;
        if top_do {
            if c != 0.0 {
                self.backward(here, o.span.clone());
                self.cursor = self.loops.last().expect("checked").start;
            } else {
                self.loops.pop();
            }
        } else if c != 0.0 {
            let again = matches!(self.loops.last(), Some(Loop { label: l, kind: LoopKind::While, .. }) if *l == label);
            if !again {
                self.loops.push(Loop {
                    label,
                    kind: LoopKind::While,
                    start: here,
                    head: (here, o.span.clone()),
                });
            }
        } else {
            if matches!(self.loops.last(), Some(l) if l.label == label) {
                self.loops.pop();
            }
            self.skip_to(here, &label, &[Kw::EndWhile], o.span.clone())?;
            let (_, after) = self.line_at(self.cursor).expect("found");
            self.cursor = after;
        }
        Ok(())
    }

    /// `o.. break` / `o.. continue`: out of, or to the end of, the loop `label`.
    fn o_break(&mut self, line: &str, o: &OLine, label: &str, here: Cursor) -> LineResult<()> {
        let Some(l) = self.loops.iter().rev().find(|l| l.label == label).cloned() else {
            return Err(LineError::new(
                o.span.clone(),
                format!("`{}` outside loop `o{label}`", &line[o.span.clone()]),
                "not in this loop",
            ));
        };
        let end = match l.kind {
            LoopKind::While => Kw::EndWhile,
            LoopKind::Do => Kw::While,
            _ => Kw::EndRepeat,
        };
        self.skip_to(here, &label, &[end], o.span.clone())?;
        if o.kw == Kw::Break {
            while let Some(top) = self.loops.pop() {
                if top.label == label {
                    break;
                }
            }
            let (_, after) = self.line_at(self.cursor).expect("found");
            self.cursor = after;
        }
        Ok(())
    }

    fn optional_value(&mut self, line: &str, at: usize) -> LineResult<Option<f64>> {
        let b = line.as_bytes();
        let mut i = at;
        while i < b.len() && is_blank(b[i]) {
            i += 1;
        }
        if b.get(i) == Some(&b'[') {
            Ok(Some(self.eval_bracket(line, i)?.0))
        } else {
            Ok(None)
        }
    }

    /// A Fanuc macro statement line.
    fn macro_statement(
        &mut self,
        line: &str,
        m: Macro,
        at: usize,
        rest: usize,
        here: Cursor,
        next: Cursor,
    ) -> LineResult<()> {
        let span = at..rest;
        let number_after = |s: &str| -> LineResult<String> {
            let t = s.trim();
            if t.is_empty() || !t.bytes().all(|b| b.is_ascii_digit()) {
                return Err(LineError::new(
                    span.clone(),
                    format!("`{}`: expected a number after it", &line[span.clone()]),
                    "expected a number",
                ));
            }
            let t = t.trim_start_matches('0');
            Ok(if t.is_empty() { "0".into() } else { t.into() })
        };
        match m {
            Macro::Goto => {
                let n = number_after(&line[rest..])?;
                self.goto(&n, here, span)
            }
            Macro::If => {
                let (c, after) = self.eval_bracket(line, rest)?;
                let tail = line[after..].trim_start();
                let upper = tail.to_ascii_uppercase();
                if let Some(target) = upper.strip_prefix("GOTO") {
                    if c != 0.0 {
                        let n = number_after(target)?;
                        return self.goto(&n, here, span);
                    }
                    Ok(())
                } else if upper.starts_with("THEN") {
                    if c != 0.0 {
                        let off = line.len() - tail.len() + 4;
                        let stmt = &line[off..];
                        match lex(stmt, &self.interp.params, true).map_err(|e| shift(e, off))? {
                            Lexed::Words { words, assigns } if words.is_empty() => {
                                for (p, v) in assigns {
                                    self.interp.params.set(&p, v);
                                }
                                self.interp.parameters_changed();
                            }
                            Lexed::Nothing => {}
                            _ => {
                                return Err(LineError::new(
                                    off..line.len(),
                                    "expected an assignment `#n = value` after THEN",
                                    "not an assignment",
                                ))
                            }
                        }
                    }
                    Ok(())
                } else {
                    Err(LineError::new(
                        after..line.len(),
                        "expected `GOTO n` or `THEN #n = value` after `IF [condition]`",
                        "expected GOTO or THEN",
                    ))
                }
            }
            Macro::While => {
                let (c, after) = self.eval_bracket(line, rest)?;
                let tail = line[after..].trim_start();
                let Some(m) = tail
                    .to_ascii_uppercase()
                    .strip_prefix("DO")
                    .map(|s| s.trim().trim_start_matches('0').to_string())
                else {
                    return Err(LineError::new(
                        after..line.len(),
                        "expected `DO m` after `WHILE [condition]`",
                        "expected DO",
                    ));
                };
                let again = matches!(self.loops.last(), Some(l) if l.label == m && l.start == here);
                if c != 0.0 {
                    if !again {
                        self.loops.push(Loop {
                            label: m,
                            kind: LoopKind::FanucDo,
                            start: here,
                            head: (here, span.clone()),
                        });
                    }
                } else {
                    if again {
                        self.loops.pop();
                    }
                    self.skip_to_end(here, &m, span)?;
                    let (_, after) = self.line_at(self.cursor).expect("found");
                    self.cursor = after;
                }
                let _ = next;
                Ok(())
            }
            Macro::End => {
                let m = number_after(&line[rest..])?;
                match self.loops.last() {
                    Some(l) if l.label == m => {
                        let start = l.start;
                        self.backward(here, span);
                        self.cursor = start;
                        Ok(())
                    }
                    _ => Err(LineError::new(
                        span,
                        format!("`END {m}` without a matching `WHILE [..] DO {m}`"),
                        "no WHILE",
                    )),
                }
            }
        }
    }

    /// Fanuc GOTO n: the line with sequence number N n in the current program.
    fn goto(&mut self, n: &str, here: Cursor, span: std::ops::Range<usize>) -> LineResult<()> {
        match self.sequence_line(here.file, n) {
            Some(c) => {
                if c.offset <= here.offset {
                    self.backward(here, span);
                }
                self.cursor = c;
                Ok(())
            }
            None => Err(LineError::new(
                span,
                format!("GOTO {n}: no block with sequence number N{n} in this program"),
                "unknown target",
            )),
        }
    }

    /// The first line of `file` that starts with sequence number N`n` (leading zeros
    /// ignored).
    fn sequence_line(&mut self, file: usize, n: &str) -> Option<Cursor> {
        let mut c = Cursor {
            file,
            offset: 0,
            line: 1,
        };
        while let Some((line, next)) = self.line_at(c) {
            let b = line.as_bytes();
            let mut i = 0;
            while i < b.len() && is_blank(b[i]) {
                i += 1;
            }
            if matches!(b.get(i), Some(b'N' | b'n')) {
                let d = i + 1;
                let mut k = d;
                while k < b.len() && b[k].is_ascii_digit() {
                    k += 1;
                }
                let t = line[d..k].trim_start_matches('0');
                if k > d && (t == n || (t.is_empty() && n == "0")) {
                    return Some(c);
                }
            }
            c = next;
        }
        None
    }

    /// Refuses a program written in another control's language: Siemens Sinumerik
    /// (`TRAORI`, `CYCLE800`), before any move (a Heidenhain program never gets here: it is
    /// read by its own front end, see [`Moves::new`]). The Siemens front end will plug in
    /// the same way (crate `dialect`'s module doc).
    fn foreign_language(&mut self) -> Option<Error> {
        // A cheap screen first, so that a streamed file is read whole only when it fails.
        let suspect = match &self.programs[0].source {
            Source::Text(text) => may_be_foreign(text.as_bytes()),
            Source::File(_) => file_may_be_foreign(&self.programs[0].path).unwrap_or(false),
        };
        if !suspect {
            return None;
        }
        let text: Rc<str> = match &self.programs[0].source {
            Source::Text(text) => Rc::clone(text),
            Source::File(_) => {
                let bytes = std::fs::read(&self.programs[0].path).ok()?;
                String::from_utf8_lossy(&bytes).into()
            }
        };
        let text = &text;
        // The first Siemens word in the file.
        let first = SIEMENS_TOKENS
            .iter()
            .filter_map(|&t| text.find(t).map(|k| (k, t)))
            .min();
        if let Some((k, token)) = first {
            let line_start = text[..k].rfind('\n').map_or(0, |n| n + 1);
            let line_no = text[..line_start].matches('\n').count() + 1;
            let c = Cursor {
                file: 0,
                offset: line_start,
                line: line_no,
            };
            let col = k - line_start;
            return Some(self.syntax_in(c.file, text, c.offset, LineError::new(col..col + token.len(), format!("`{token}` is Siemens Sinumerik: this program is in the Siemens language, expected G-code in the RS274/NGC, Fanuc or Haas language"), "Siemens Sinumerik").help("set dialect = \"siemens\" in the scenario's [reader] to read it with the Sinumerik front end")));
        }
        None
    }

    /// The text of the line at `here`, `len` bytes long, just read by [`Moves::line_at`].
    fn buf_line(&self, here: Cursor, len: usize) -> String {
        match &self.programs[here.file].source {
            Source::Text(text) => text[here.offset..here.offset + len].to_string(),
            Source::File(_) => self.buf.clone(),
        }
    }

    /// At the end of a text: the innermost `if`, loop or `WHILE` opened in it that has no
    /// closing line anywhere after its head, as an error at its opening line. (A loop left
    /// by a jump, as Fanuc allows, has its closing line and is not reported.)
    fn unclosed(&mut self) -> Option<Error> {
        let (loops_from, ifs_from) = self.frames.last().map_or((0, 0), |f| (f.loops, f.ifs));
        let mut open: Vec<(Cursor, std::ops::Range<usize>, String, Vec<Kw>)> = Vec::new();
        for l in &self.loops[loops_from.min(self.loops.len())..] {
            let ends = match l.kind {
                LoopKind::While => vec![Kw::EndWhile],
                LoopKind::Do => vec![Kw::While],
                LoopKind::Repeat(_) => vec![Kw::EndRepeat],
                LoopKind::FanucDo => Vec::new(),
            };
            open.push((l.head.0, l.head.1.clone(), l.label.clone(), ends));
        }
        for i in &self.ifs[ifs_from.min(self.ifs.len())..] {
            open.push((i.head.0, i.head.1.clone(), i.label.clone(), vec![Kw::EndIf]));
        }
        // Innermost first: the one opened last.
        open.sort_by_key(|(c, ..)| std::cmp::Reverse((c.file, c.offset)));
        let cursor = self.cursor;
        for (head, span, label, ends) in open {
            let closed = if ends.is_empty() {
                self.skip_to_end(head, &label, span.clone()).is_ok()
            } else {
                self.skip_to(head, &label, &ends, span.clone()).is_ok()
            };
            self.cursor = cursor;
            if self.io_error.take().is_some() || closed {
                continue;
            }
            let closing = if ends.is_empty() {
                format!("END {label}")
            } else {
                format!("o{label} {}", kw_name(ends[0]))
            };
            let err = LineError::new(
                span,
                format!("this structure is never closed: expected `{closing}` before the end of the program"),
                "unclosed structure",
            );
            return Some(self.error_at(head, err, ""));
        }
        None
    }

    /// Fanuc family: text before the program's first `%` line (within its first 64 lines)
    /// is the tape leader, which the control skips (a CAM system's listing header).
    fn skip_leader(&mut self) {
        let mut c = self.cursor;
        let mut text_before = false;
        // A first line that starts like G-code (or `%`, a comment, a block delete) has no
        // leader before it: nothing is read ahead.
        while let Some((line, next)) = self.line_at(c) {
            let t = line.trim_start_matches(['\u{feff}', ' ', '\t']);
            if let Some(first) = t.chars().next() {
                if "%OoNnGgMmTtXxYyZzFfSs(;#/".contains(first) {
                    return;
                }
                break;
            }
            c = next;
        }
        for _ in 0..64 {
            let Some((line, next)) = self.line_at(c) else {
                return;
            };
            let t = line.trim();
            if t == "%" {
                if text_before {
                    self.cursor = c;
                }
                return;
            }
            text_before |= !t.is_empty();
            c = next;
        }
    }

    /// The first line with more than blanks opens a Heidenhain Klartext program (`BEGIN
    /// PGM`, with or without a block number).
    fn first_line_heidenhain(&mut self) -> bool {
        let mut c = Cursor {
            file: 0,
            offset: 0,
            line: 1,
        };
        while let Some((line, next)) = self.line_at(c) {
            if !line.trim().is_empty() {
                return crate::heidenhain::opens_program(line);
            }
            c = next;
        }
        false
    }

    /// Reads on until a move is queued, the program ends, or an error.
    fn step(&mut self) -> Result<()> {
        if !self.language_checked {
            self.language_checked = true;
            if let Some(e) = self.foreign_language() {
                self.finished = true;
                return Err(e);
            }
            if self.dialect.table().leader_before_percent {
                self.skip_leader();
            }
        }
        if let Some((here, span, message)) = self.abort.take() {
            self.finished = true;
            return Err(self.error_at(here, LineError::new(span, message, "remap epilog"), ""));
        }
        if let Some(c) = self.commit.take() {
            self.interp.glue_commit(&c);
        }
        if let Some(r) = self.resume.take() {
            let line = r.line.as_str();
            let words: Vec<Word> = r
                .words
                .iter()
                .map(|(letter, value, number, span)| Word {
                    letter: *letter,
                    value: *value,
                    number: &line[number.clone()],
                    span: *span,
                })
                .collect();
            let next = self.cursor;
            // The rest of the block may hold further remapped codes (`S300 M3 F50` with S
            // and F remapped: F, then S, then M3).
            let split = if self.remaps.is_empty() {
                Ok(None)
            } else {
                let busy: Vec<usize> = self.frames.iter().filter_map(|f| f.remap).collect();
                crate::remap::split(&self.remaps, &words, line, &busy, self.modal_remap)
            };
            let result = split.and_then(|s| match s {
                Some(s) => self.run_remap(line, &words, s, r.here, next),
                None => self.run_block(line, &words, r.here, next),
            });
            return result.map_err(|e| {
                self.finished = true;
                self.error_at(r.here, e, line)
            });
        }
        let here = self.cursor;
        let Some((line, next)) = self.line_at(here) else {
            if let Some(e) = self.io_error.take() {
                self.finished = true;
                return Err(Error::Read {
                    path: self.programs[here.file].path.clone(),
                    source: e,
                });
            }
            if let Some(e) = self.unclosed() {
                self.finished = true;
                return Err(e);
            }
            if let Some(f) = self.frames.last() {
                if self.programs[f.start.file].is_empty() || f.start.file != 0 {
                    // A Fanuc subprogram file without M99 returns at its end.
                    if self.dialect.table().macro_b && self.ret(None) {
                        return Ok(());
                    }
                }
            }
            self.finished = true;
            return Ok(());
        };
        let len = line.len();
        if !self.budget.spend() {
            self.finished = true;
            let (at, span) = self.repeating.clone().unwrap_or((here, 0..len));
            let line = if at == here {
                self.buf_line(here, len)
            } else {
                String::new()
            };
            return Err(self.error_at(at, self.budget.spent(span), &line));
        }
        // Own the line while the interpreter changes state: share the text (a reference
        // count, no copy), or take the file's line buffer (given back below).
        let owner = match &self.programs[here.file].source {
            Source::Text(text) => LineOwner::Shared(Rc::clone(text)),
            Source::File(_) => LineOwner::Buffer(std::mem::take(&mut self.buf)),
        };
        let line = match &owner {
            LineOwner::Shared(text) => &text[here.offset..here.offset + len],
            LineOwner::Buffer(buf) => buf.as_str(),
        };
        // Field by field (docs/performance.md); the file is the same.
        self.cursor.offset = next.offset;
        self.cursor.line = next.line;
        let result = self.line(line, here, next).map_err(|e| {
            self.finished = true;
            self.error_at(here, e, line)
        });
        if let LineOwner::Buffer(buf) = owner {
            self.buf = buf;
        }
        if result.is_ok() {
            if let Some(e) = self.io_error.take() {
                self.finished = true;
                return Err(Error::Read {
                    path: self.programs[here.file].path.clone(),
                    source: e,
                });
            }
        }
        result?;
        Ok(())
    }

    fn line(&mut self, line: &str, here: Cursor, next: Cursor) -> LineResult<()> {
        let b = line.as_bytes();
        let first = after_line_number(b);
        match b.get(first) {
            Some(b'o' | b'O') => {
                if let Some(o) = oline(line)? {
                    self.o_word(line, o, here, next)?;
                    return Ok(());
                }
            }
            Some(b'/') => return Ok(()),
            Some(c) if self.dialect.table().macro_b && c.is_ascii_alphabetic() => {
                if let Some((m, at, rest)) = macro_line(line) {
                    return self.macro_statement(line, m, at, rest, here, next);
                }
            }
            _ => {}
        }
        if has_hash_or_bracket(b) {
            self.interp.refresh_system_parameters();
        }
        let words = reuse(std::mem::take(&mut self.words));
        let lexed = lex_with(
            line,
            &self.interp.params,
            self.dialect.table().macro_b,
            words,
        )?;
        match lexed {
            Lexed::Nothing => Ok(()),
            Lexed::Percent => {
                if self.percent_seen {
                    self.finished = true;
                } else {
                    self.percent_seen = true;
                }
                Ok(())
            }
            Lexed::Words { words, assigns } => {
                if !assigns.is_empty() {
                    for (p, v) in &assigns {
                        self.interp.params.set(p, *v);
                    }
                    self.interp.parameters_changed();
                }
                if words.is_empty() {
                    self.words = reuse(words);
                    return Ok(());
                }
                let remap = if self.remaps.is_empty() {
                    None
                } else {
                    let busy: Vec<usize> = self.frames.iter().filter_map(|f| f.remap).collect();
                    if !busy.is_empty() && crate::remap::uses_builtin(&self.remaps, &words, &busy) {
                        if let Some(e) = self
                            .frames
                            .iter_mut()
                            .rev()
                            .find(|f| f.remap.is_some())
                            .and_then(|f| f.epilog.as_mut())
                        {
                            e.builtin_used = true;
                        }
                    }
                    if self.modal_remap.is_some() && crate::remap::sets_motion(&words) {
                        self.modal_remap = None;
                    }
                    crate::remap::split(&self.remaps, &words, line, &busy, self.modal_remap)?
                };
                let result = match remap {
                    Some(s) => self.run_remap(line, &words, s, here, next),
                    None => self.run_block(line, &words, here, next),
                };
                self.words = reuse(words);
                // Not `result`: that copied the whole (large) result on every block.
                result?;
                Ok(())
            }
        }
    }

    /// Runs a block with a remapped code: the words before it, the handler, and (on return,
    /// or at once for an accepted Python handler) the words after it.
    fn run_remap(
        &mut self,
        line: &str,
        words: &[Word],
        s: crate::remap::Split,
        here: Cursor,
        next: Cursor,
    ) -> LineResult<()> {
        let remap = self.remaps[s.remap].clone();
        let name = if s.explicit {
            line[s.span.clone()].to_string()
        } else {
            format!(
                "{} (the modal cycle, called again by axis words)",
                remap.code
            )
        };
        // Python prolog/epilog handlers: LinuxCNC's stdglue ones are emulated
        // (crate::stdglue); others cannot be run.
        let unknown = [&remap.prolog, &remap.epilog]
            .into_iter()
            .flatten()
            .find(|name| crate::stdglue::Handler::named(name).is_none())
            .map(|name| format!("the Python handler `{name}` is not one of LinuxCNC's stdglue.py handlers mtsim emulates ({})", crate::stdglue::NAMES));
        if let Some(why) = unknown.as_ref().or(remap.handlers_refused.as_ref()) {
            return Err(LineError::new(s.span.clone(), format!("`{name}` is remapped ({}) with Python prolog/epilog handlers around its subroutine: {why}; mtsim runs no Python, and such handlers set the parameters the subroutine reads", remap.origin), "Python remap")
                .help("remap the code with LinuxCNC's stdglue handlers or without prolog= and epilog=, or remove it from the program"));
        }
        let glue = |h: &Option<String>| h.as_deref().and_then(crate::stdglue::Handler::named);
        let (prolog, epilog) = (glue(&remap.prolog), glue(&remap.epilog));
        let pick = |idx: &[usize]| idx.iter().map(|&k| words[k]).collect::<Vec<_>>();
        let before = pick(&s.before);
        if !before.is_empty() {
            self.run_block(line, &before, here, next)?;
        }
        let after = pick(&s.after);
        let Some(label) = &remap.ngc else {
            if let Some(why) = &remap.python_motion {
                return Err(LineError::new(s.span.clone(), format!("`{name}` is remapped ({}) to the Python function `{}`: {why}; mtsim runs no Python", remap.origin, remap.python.as_deref().unwrap_or("")), "Python remap")
                    .help("remap it to an o-word subroutine (ngc=), or remove it from the program"));
            }
            if !self.remaps_noticed.contains(&s.remap) {
                self.remaps_noticed.push(s.remap);
                self.notices.push(Notice { path: self.programs[here.file].path.clone(), line: here.line, message: format!("{} is remapped ({}) to the Python function `{}`, which does not move the machine: accepted and not run", remap.code, remap.origin, remap.python.as_deref().unwrap_or("")), warning: false });
            }
            if remap.python_keeps_motion {
                self.modal_remap = Some(s.remap);
            }
            return if after.is_empty() {
                Ok(())
            } else {
                self.run_block(line, &after, here, next)
            };
        };
        let positional: Vec<f64> = if remap.positional() {
            remap
                .letters()
                .map(|(l, _)| s.args.iter().find(|a| a.0 == l).map_or(0.0, |a| a.1))
                .collect()
        } else {
            Vec::new()
        };
        let set = match prolog {
            None => Vec::new(),
            Some(h) => {
                let change = if h == crate::stdglue::Handler::ChangeProlog {
                    self.interp.tool_change_parameters()
                } else {
                    None
                };
                let interp = &self.interp;
                let call = crate::stdglue::Call {
                    code: remap.code,
                    value: s.value,
                    q: s.q,
                    words: &s.args,
                    explicit: s.explicit,
                    cycle_typeerror: remap.cycle_prolog_typeerror,
                };
                crate::stdglue::prolog(
                    h,
                    &call,
                    s.remap,
                    interp.glue_view(),
                    &mut self.sticky,
                    &|n| interp.glue_pocket(n),
                    &|n| interp.params.numbered.get(n).copied().unwrap_or(0.0),
                    change,
                )
                .map_err(|m| {
                    LineError::new(
                        s.span.clone(),
                        format!("`{name}`: {m} (stdglue {}, {})", h.name(), remap.origin),
                        "remap prolog",
                    )
                })?
            }
        };
        self.call(label, &positional, true, 1, here, next, s.span.clone())?;
        if !remap.positional() {
            if let Some(locals) = self.interp.params.locals.last_mut() {
                for (letter, v) in &s.args {
                    locals.insert(letter.to_ascii_lowercase().to_string(), *v);
                }
            }
        }
        if let Some(locals) = self.interp.params.locals.last_mut() {
            for (k, v) in set {
                locals.insert(k, v);
            }
        }
        let base = line.as_ptr() as usize;
        let frame = self.frames.last_mut().expect("just called");
        frame.remap = Some(s.remap);
        frame.epilog = epilog.map(|handler| {
            Box::new(Epilog {
                handler,
                remap: s.remap,
                builtin_used: false,
                here,
                span: s.span.clone(),
            })
        });
        if !after.is_empty() {
            frame.resume = Some(Resume {
                here,
                line: line.to_string(),
                words: after
                    .iter()
                    .map(|w| {
                        let at = if w.number.is_empty() {
                            0
                        } else {
                            w.number.as_ptr() as usize - base
                        };
                        (w.letter, w.value, at..at + w.number.len(), w.span)
                    })
                    .collect(),
            });
        }
        Ok(())
    }

    /// Interprets one block's words and follows its stop (end, call, return).
    fn run_block(
        &mut self,
        line: &str,
        words: &[Word],
        here: Cursor,
        next: Cursor,
    ) -> LineResult<()> {
        let stop = self.interp.block(
            line,
            words,
            here.line,
            &mut self.queue,
            &mut self.notices,
            &self.programs[here.file].path,
        )?;
        match stop {
            Stop::None => {}
            Stop::End => self.finished = true,
            Stop::Call {
                label,
                repeats,
                args,
                locals,
                span,
            } => {
                self.call(&label, &args, locals, repeats, here, next, span)?;
            }
            Stop::Return { span } => {
                if !self.ret(None) {
                    if self.dialect.table().macro_b {
                        // M99 in the main program: end (a real control would restart it).
                        self.finished = true;
                    } else {
                        return Err(LineError::new(
                            span,
                            "M99 outside a subprogram",
                            "no subprogram",
                        ));
                    }
                }
            }
            Stop::SaveForReturn(saved) => {
                if let Some(f) = self.frames.last_mut() {
                    f.restore = Some(saved);
                }
            }
        }
        Ok(())
    }
}

/// An emptied vector of words, its allocation kept, for words that borrow another line.
/// (Collecting a vector's own `into_iter` into the same layout reuses its allocation.)
fn reuse<'a, 'b>(mut words: Vec<Word<'a>>) -> Vec<Word<'b>> {
    words.clear();
    words.into_iter().map(|_| Word::EMPTY).collect()
}

/// The line being interpreted, owned apart from the reader's state.
enum LineOwner {
    Shared(Rc<str>),
    Buffer(String),
}

impl Program {
    fn is_empty(&self) -> bool {
        match &self.source {
            Source::Text(text) => text.is_empty(),
            Source::File(f) => f.len == 0,
        }
    }
}

fn has_hash_or_bracket(bytes: &[u8]) -> bool {
    const ONES: u64 = 0x0101_0101_0101_0101;
    const HIGHS: u64 = 0x8080_8080_8080_8080;
    let zero = |v: u64| v.wrapping_sub(ONES) & !v & HIGHS;
    let mut chunks = bytes.chunks_exact(8);
    for chunk in &mut chunks {
        let mut word = [0u8; 8];
        word.copy_from_slice(chunk);
        let w = u64::from_le_bytes(word);
        if zero(w ^ (ONES * b'#' as u64)) | zero(w ^ (ONES * b'[' as u64)) != 0 {
            return true;
        }
    }
    chunks.remainder().iter().any(|&c| c == b'#' || c == b'[')
}

/// Siemens Sinumerik words [`foreign_language`](Moves::foreign_language) refuses.
const SIEMENS_TOKENS: [&str; 5] = ["TRAORI", "traori", "Traori", "CYCLE800", "cycle800"];

/// True when `bytes` may hold a Siemens token. Every token begins with `tra` or `cyc` in
/// one case or the other, so the screen folds each run of 64 start positions, branch free
/// (vectorised), for those three letters (case folded: `b | 0x20`), and looks closer only
/// where one begins. Letters alone (a `T` or `C` word, a comment) do not stop it: a
/// five-axis program has a `C` on nearly every line.
fn may_be_foreign(bytes: &[u8]) -> bool {
    const SHORTEST: usize = 6;
    if bytes.len() < SHORTEST {
        return false;
    }
    // Start positions `0..starts` have the two bytes after them.
    let starts = bytes.len() - 2;
    let mut k = 0;
    while k < starts {
        let end = (k + 64).min(starts);
        let (first, second, third) = (
            &bytes[k..end],
            &bytes[k + 1..end + 1],
            &bytes[k + 2..end + 2],
        );
        let hit = first
            .iter()
            .zip(second)
            .zip(third)
            .fold(false, |hit, ((&x, &y), &z)| {
                let (x, y, z) = (x | 0x20, y | 0x20, z | 0x20);
                hit | ((x == b't') & (y == b'r') & (z == b'a'))
                    | ((x == b'c') & (y == b'y') & (z == b'c'))
            });
        if hit
            && (k..end).any(|i| {
                SIEMENS_TOKENS
                    .iter()
                    .any(|t| bytes[i..].starts_with(t.as_bytes()))
            })
        {
            return true;
        }
        k = end;
    }
    false
}

/// [`may_be_foreign`] over a file, read in fixed chunks that overlap by a token's length.
fn file_may_be_foreign(path: &Path) -> std::io::Result<bool> {
    const KEEP: usize = 7;
    let mut file = std::fs::File::open(path)?;
    let mut buf = vec![0u8; FILE_BUFFER_BYTES + KEEP];
    let mut kept = 0;
    loop {
        let n = file.read(&mut buf[kept..])?;
        if n == 0 {
            return Ok(false);
        }
        let end = kept + n;
        if may_be_foreign(&buf[..end]) {
            return Ok(true);
        }
        let keep = KEEP.min(end);
        buf.copy_within(end - keep..end, 0);
        kept = keep;
    }
}

fn shift(mut e: LineError, by: usize) -> LineError {
    e.span = e.span.start + by..e.span.end + by;
    e
}

fn kw_name(kw: Kw) -> &'static str {
    KEYWORDS
        .iter()
        .find(|(_, k)| *k == kw)
        .map_or("", |(n, _)| n)
}

impl Moves {
    /// The next move, lent in place: as [`Iterator::next`], without moving the (large) move
    /// out of the reader's queue; it leaves the queue at the next call of either.
    pub fn next_ref(&mut self) -> Option<Result<&Move>> {
        if std::mem::take(&mut self.lent) {
            self.queue.pop_front();
        }
        if self.siemens.is_some() || self.klartext.is_some() {
            // The other front ends hand out moves by value: one is held here to be lent.
            match self.next()? {
                Ok(m) => self.queue.push_back(m),
                Err(e) => return Some(Err(e)),
            }
        } else if let Err(e) = self.fill_queue() {
            return Some(Err(e));
        }
        self.lent = true;
        self.queue.front().map(Ok)
    }

    /// Reads on until a move is queued (`Ok` with an empty queue: the program has ended).
    /// After an error the queue is empty and the reader done.
    fn fill_queue(&mut self) -> Result<()> {
        while self.queue.is_empty() {
            if self.finished {
                if self.flushed {
                    return Ok(());
                }
                // A compensated element still held ends as at G40.
                self.flushed = true;
                self.interp.finish(&mut self.queue);
                continue;
            }
            if let Err(e) = self.step() {
                self.queue.clear();
                self.interp.discard();
                self.flushed = true;
                return Err(e);
            }
        }
        Ok(())
    }
}

impl Iterator for Moves {
    type Item = Result<Move>;

    fn next(&mut self) -> Option<Result<Move>> {
        if std::mem::take(&mut self.lent) {
            self.queue.pop_front();
        }
        if let Some(front) = &mut self.siemens {
            return front.next_move();
        }
        if let Some(k) = &mut self.klartext {
            return k.next();
        }
        if let Err(e) = self.fill_queue() {
            return Some(Err(e));
        }
        self.queue.pop_front().map(Ok)
    }
}

#[cfg(test)]
mod tests {
    use super::{has_hash_or_bracket, may_be_foreign, SIEMENS_TOKENS};

    /// Every Siemens token at every offset (across the 64-position runs) of five-axis lines
    /// is found; the same lines without one, full of `T`, `C`, `tra`- and `cyc`-words that
    /// are not tokens, are not.
    #[test]
    fn the_siemens_screen_finds_every_token_at_every_offset_and_nothing_else() {
        let clean = "G01 X0.0072 C-90.0061 F559.386 (THETA 0.010 CENTRE TRACE CYCLE 80)\nT1 M6\n";
        let clean = clean.repeat(3);
        assert!(!may_be_foreign(clean.as_bytes()));
        for token in SIEMENS_TOKENS {
            for at in 0..=clean.len() {
                let mut text = clean.clone();
                text.insert_str(at, token);
                assert!(may_be_foreign(text.as_bytes()), "{token} at {at}");
                // A token cut short is not one.
                let mut text = clean.clone();
                text.insert_str(at, &token[..token.len() - 1]);
                text.insert(at + token.len() - 1, ' ');
                assert!(
                    !may_be_foreign(text.as_bytes()),
                    "{token} cut short at {at}"
                );
            }
        }
        for short in ["", "T", "TRAOR", "cycle8"] {
            assert!(!may_be_foreign(short.as_bytes()), "{short:?}");
        }
    }

    #[test]
    fn a_hash_or_bracket_is_found_at_every_place_of_every_short_line() {
        // Bytes next to `#` (0x23) and `[` (0x5b), and ones whose difference from them
        // borrows across bytes in the 8-byte test.
        let filler = b"G1X-0.5\"$ZZ\\\x01\xff";
        for len in 0..=24 {
            let line: Vec<u8> = (0..len).map(|k| filler[k % filler.len()]).collect();
            assert!(!has_hash_or_bracket(&line), "{len}: none in {line:?}");
            for at in 0..len {
                for c in [b'#', b'['] {
                    let mut with = line.clone();
                    with[at] = c;
                    assert!(has_hash_or_bracket(&with), "{} at {at} of {len}", c as char);
                }
            }
        }
    }
}
