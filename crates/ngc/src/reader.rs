//! The reader: a hand-written, streaming tokenizer and modal interpreter.
//!
//! Numbers are kept as exact f64 as written (`X0.1` is `0.1_f64`); inch input (G20) is
//! converted to mm. Every word is either understood or reported as an error with its line and
//! column: nothing is skipped silently. The supported dialect is documented in
//! `docs/gcode.md` of mtsim.
//!
//! ```text
//! source lines ─► lex (words, comments) ─► interpret (modal state) ─► Move
//! ```
//!
//! The reader holds one line at a time, so memory does not grow with the length of the
//! program. Only when it reports an error does it read the whole text again, to show the
//! offending line in context.

use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::ops::Range;
use std::path::{Path, PathBuf};

use crate::axis::{Axis, AxisVec, Plane};
use crate::canon::{FeedMode, Motion, Move, FULL_CIRCLE_TOLERANCE_MM};
use crate::error::{line_column, Error, Result, Syntax};

/// Millimetres per inch (exact by definition).
pub const MM_PER_INCH: f64 = 25.4;

/// Radii at the start and end of an arc may differ by at most this much, mm.
pub const ARC_RADIUS_TOLERANCE_MM: f64 = 1e-3;

/// The letters of the words the reader understands, for error messages.
const EXPECTED_WORDS: &str = "G M N O F S T X Y Z A B C I J K R P H";

/// A line source the reader can stream from, and read again in full when it must show an
/// error in context.
pub trait Source: BufRead {
    /// The whole text, or `None` when it cannot be read again.
    fn full_text(&self, path: &Path) -> Option<String>;
}

impl Source for BufReader<File> {
    fn full_text(&self, path: &Path) -> Option<String> {
        std::fs::read(path)
            .ok()
            .map(|bytes| String::from_utf8_lossy(&bytes).into_owned())
    }
}

/// A string read as a stream of lines.
#[derive(Clone, Debug)]
pub struct StrSource<'a> {
    text: &'a str,
    pos: usize,
}

impl Read for StrSource<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let rest = &self.text.as_bytes()[self.pos..];
        let n = rest.len().min(buf.len());
        buf[..n].copy_from_slice(&rest[..n]);
        self.pos += n;
        Ok(n)
    }
}

impl BufRead for StrSource<'_> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        Ok(&self.text.as_bytes()[self.pos..])
    }
    fn consume(&mut self, amt: usize) {
        self.pos = (self.pos + amt).min(self.text.len());
    }
}

impl Source for StrSource<'_> {
    fn full_text(&self, _path: &Path) -> Option<String> {
        Some(self.text.to_string())
    }
}

/// Streams the moves of a file; memory does not grow with file length.
///
/// `start` is the axis position before the program runs (mm, deg). Returns
/// [`Error::Read`] when the file cannot be opened.
pub fn read_file(path: &Path, start: AxisVec) -> Result<Moves<BufReader<File>>> {
    let file = File::open(path).map_err(|source| Error::Read {
        path: path.to_path_buf(),
        source,
    })?;
    Ok(Moves::new(path, BufReader::new(file), start))
}

/// Streams the moves of `text`, reported as the contents of `path`.
pub fn read_str<'a>(path: &'a Path, text: &'a str, start: AxisVec) -> Moves<StrSource<'a>> {
    Moves::new(path, StrSource { text, pos: 0 }, start)
}

/// The canonical moves of a program, in order. Yields `Err` at most once, then `None`; stops after
/// M02, M30 or a closing `%`.
pub struct Moves<R> {
    path: PathBuf,
    reader: R,
    bytes: Vec<u8>,
    /// 1-based number of the line last read.
    line_no: usize,
    /// Byte offset of the next line in the text.
    offset: usize,
    state: Modal,
    finished: bool,
}

impl<R: Source> Moves<R> {
    fn new(path: &Path, reader: R, start: AxisVec) -> Moves<R> {
        Moves {
            path: path.to_path_buf(),
            reader,
            bytes: Vec::new(),
            line_no: 0,
            offset: 0,
            state: Modal::new(start),
            finished: false,
        }
    }

    /// The error for `err` on the current line `line`, which starts at byte `line_start`.
    fn error(&self, line: &str, line_start: usize, err: LineError) -> Error {
        let found = self
            .reader
            .full_text(&self.path)
            .filter(|text| text.get(line_start..line_start + line.len()) == Some(line));
        // If the text changed under us, show the line alone at its own line number.
        let (text, start) = match found {
            Some(text) => (text, line_start),
            None => {
                let pad = self.line_no - 1;
                ("\n".repeat(pad) + line, pad)
            }
        };
        let span = start + err.span.start..start + err.span.end;
        let (line, column) = line_column(&text, span.start);
        Error::Syntax(Box::new(Syntax {
            path: self.path.clone(),
            line,
            column,
            message: err.message,
            label: err.label,
            help: err.help,
            text,
            span,
        }))
    }
}

impl<R: Source> Iterator for Moves<R> {
    type Item = Result<Move>;

    fn next(&mut self) -> Option<Result<Move>> {
        while !self.finished {
            self.bytes.clear();
            match self.reader.read_until(b'\n', &mut self.bytes) {
                Ok(0) => self.finished = true,
                Ok(_) => {
                    let raw = String::from_utf8_lossy(&self.bytes).into_owned();
                    let line_start = self.offset;
                    self.offset += raw.len();
                    self.line_no += 1;
                    let line = raw.trim_end_matches('\n').trim_end_matches('\r');
                    match self.state.line(line, self.line_no) {
                        Ok(Step::Nothing) => {}
                        Ok(Step::End) => self.finished = true,
                        Ok(Step::Block(block, end)) => {
                            self.finished = end;
                            return Some(Ok(block));
                        }
                        Err(err) => {
                            self.finished = true;
                            return Some(Err(self.error(line, line_start, err)));
                        }
                    }
                }
                Err(source) => {
                    self.finished = true;
                    return Some(Err(Error::Read {
                        path: self.path.clone(),
                        source,
                    }));
                }
            }
        }
        None
    }
}

/// An error on one line; `span` is a byte range in that line.
#[derive(Debug)]
struct LineError {
    span: Range<usize>,
    message: String,
    label: String,
    help: Option<String>,
}

impl LineError {
    fn new(span: Range<usize>, message: impl Into<String>, label: impl Into<String>) -> Self {
        LineError {
            span,
            message: message.into(),
            label: label.into(),
            help: None,
        }
    }

    fn help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(help.into());
        self
    }
}

type LineResult<T> = std::result::Result<T, LineError>;

/// One word: a letter and its number, as written.
#[derive(Clone, Copy, Debug)]
struct Word<'l> {
    /// Upper-case letter.
    letter: char,
    value: f64,
    /// The number as written.
    number: &'l str,
    /// Letter through number, bytes in the line.
    span: (usize, usize),
}

impl Word<'_> {
    fn span(&self) -> Range<usize> {
        self.span.0..self.span.1
    }
}

/// What a source line holds.
enum Lexed<'l> {
    /// Nothing but blanks and comments, or a deleted block.
    Nothing,
    /// A `%` line.
    Percent,
    Words(Vec<Word<'l>>),
}

fn is_blank(c: u8) -> bool {
    c == b' ' || c == b'\t'
}

/// The character at byte `i` of `line` and its byte range.
fn char_at(line: &str, i: usize) -> (char, Range<usize>) {
    let c = line[i..].chars().next().unwrap_or(' ');
    (c, i..i + c.len_utf8())
}

/// Splits a line into words, dropping comments.
fn lex(line: &str) -> LineResult<Lexed<'_>> {
    let bytes = line.as_bytes();
    let mut i = 0;
    while i < bytes.len() && is_blank(bytes[i]) {
        i += 1;
    }
    let percent = bytes.get(i) == Some(&b'%');
    if percent {
        i += 1;
    } else if bytes.get(i) == Some(&b'/') {
        // Block delete with the optional-block-skip switch on: the block is not executed.
        return Ok(Lexed::Nothing);
    }
    let mut words = Vec::new();
    while i < bytes.len() {
        let c = bytes[i];
        if is_blank(c) {
            i += 1;
        } else if c == b'(' {
            match line[i + 1..].find(')') {
                Some(close) => i += close + 2,
                None => {
                    return Err(LineError::new(
                        i..line.len(),
                        "unclosed comment: expected `)` before the end of the line",
                        "this comment is not closed",
                    )
                    .help("close the comment with `)` on the same line"))
                }
            }
        } else if c == b';' {
            break;
        } else if c == b'/' {
            return Err(LineError::new(
                i..i + 1,
                "block delete `/` in the middle of a block: expected it only at the start",
                "block delete here",
            )
            .help("move `/` to the start of the line to skip the whole block"));
        } else if c == b'%' {
            return Err(LineError::new(
                i..i + 1,
                "`%` inside a block: expected `%` alone on its own line",
                "unexpected `%`",
            ));
        } else if c == b'#' {
            let mut end = i + 1;
            while end < bytes.len() && bytes[end].is_ascii_digit() {
                end += 1;
            }
            return Err(LineError::new(
                i..end,
                format!(
                    "unsupported word `{}` (macro variables are not supported): expected one of {EXPECTED_WORDS}",
                    &line[i..end]
                ),
                "macro variable",
            )
            .help("write the values out as numbers (post-process the program without macros)"));
        } else if c.is_ascii_alphabetic() {
            words.push(lex_word(line, i)?);
            i = words.last().map_or(i + 1, |w: &Word| w.span.1);
        } else {
            let (ch, span) = char_at(line, i);
            return Err(LineError::new(
                span,
                format!(
                    "unexpected character `{}`: expected a word (one of {EXPECTED_WORDS} followed by a number), a comment `( )` or `;`",
                    ch.escape_debug()
                ),
                "unexpected character",
            ));
        }
    }
    if percent {
        if let Some(word) = words.first() {
            return Err(LineError::new(
                word.span(),
                "word on a `%` line: expected `%` alone on its line",
                "move this word to its own line",
            ));
        }
        return Ok(Lexed::Percent);
    }
    if words.is_empty() {
        Ok(Lexed::Nothing)
    } else {
        Ok(Lexed::Words(words))
    }
}

/// Reads the word whose letter is at byte `start`. Blanks between the letter and the number
/// are allowed; the number is `[+-]digits[.digits]` with at least one digit.
fn lex_word(line: &str, start: usize) -> LineResult<Word<'_>> {
    let bytes = line.as_bytes();
    let letter = (bytes[start] as char).to_ascii_uppercase();
    let mut i = start + 1;
    while i < bytes.len() && is_blank(bytes[i]) {
        i += 1;
    }
    let number_start = i;
    while i < bytes.len() && matches!(bytes[i], b'0'..=b'9' | b'.' | b'+' | b'-') {
        i += 1;
    }
    let number = &line[number_start..i];
    let span = start..if number.is_empty() { start + 1 } else { i };
    let text = &line[span.clone()];
    if !"GMNOFSTXYZABCIJKRPH".contains(letter) {
        let why = match letter {
            'D' => " (cutter radius offsets are not supported)",
            'E' => " (thread leads and extruders are not supported)",
            'L' => " (repeat counts are not supported)",
            'Q' => " (canned-cycle parameters are not supported)",
            'U' | 'V' | 'W' => " (secondary and incremental axes U V W are not supported; use G91)",
            _ => "",
        };
        return Err(LineError::new(
            span,
            format!("unsupported word `{text}`{why}: expected one of {EXPECTED_WORDS}"),
            "unsupported word",
        )
        .help("docs/gcode.md lists the supported dialect; remove the word or post-process the program without it"));
    }
    if !is_decimal(number) {
        let what = if number.is_empty() && matches!(bytes.get(i), Some(b'[' | b'#')) {
            format!("`{letter}` is followed by an expression or macro variable (expressions and macro variables are not supported)")
        } else if number.is_empty() {
            format!("`{letter}` has no number")
        } else {
            format!("malformed number `{number}` in `{text}`")
        };
        return Err(LineError::new(
            span,
            format!("{what}: expected a decimal number after `{letter}`, such as `{letter}1.5` or `{letter}-2`"),
            "malformed word",
        )
        .help("write numbers as digits with at most one decimal point, e.g. `X-12.345`"));
    }
    let value: f64 = number.parse().map_err(|_| {
        LineError::new(
            span.clone(),
            format!("malformed number `{number}`: expected a decimal number"),
            "malformed number",
        )
    })?;
    if !value.is_finite() {
        return Err(LineError::new(
            span,
            format!("number `{number}` is too large: expected a finite value"),
            "too large",
        ));
    }
    Ok(Word {
        letter,
        value,
        number,
        span: (start, span.end),
    })
}

/// `[+-]? digits* ( . digits* )?` with at least one digit.
fn is_decimal(s: &str) -> bool {
    let s = s.strip_prefix(['+', '-']).unwrap_or(s);
    let (int, frac) = s.split_once('.').unwrap_or((s, ""));
    let digits = |p: &str| p.bytes().all(|b| b.is_ascii_digit());
    digits(int) && digits(frac) && int.len() + frac.len() > 0
}

/// A supported G code.
#[derive(Clone, Copy, Debug, PartialEq)]
enum GCode {
    Motion(MotionMode),
    Dwell,
    Plane(Plane),
    Absolute,
    Incremental,
    Feed(FeedMode),
    Inch,
    Millimetre,
    /// G40, G80, G54: accepted, cancel or select nothing we model.
    NoOp(Group),
    TcpOn,
    TcpOff,
}

/// Modal groups (Fanuc numbering in the docs); two codes of one group may not share a block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Group {
    /// G00 G01 G02 G03, and the one-shot G04 which cannot share a block with them.
    Motion,
    Plane,
    Distance,
    FeedMode,
    Units,
    CutterComp,
    ToolLength,
    CannedCycle,
    WorkOffset,
}

impl GCode {
    fn group(self) -> Group {
        match self {
            GCode::Motion(_) | GCode::Dwell => Group::Motion,
            GCode::Plane(_) => Group::Plane,
            GCode::Absolute | GCode::Incremental => Group::Distance,
            GCode::Feed(_) => Group::FeedMode,
            GCode::Inch | GCode::Millimetre => Group::Units,
            GCode::TcpOn | GCode::TcpOff => Group::ToolLength,
            GCode::NoOp(group) => group,
        }
    }

    /// The code for word `G<number>`, or an error saying why it is not supported.
    fn parse(word: &Word, line: &str) -> LineResult<GCode> {
        let text = &line[word.span()];
        let tenths = word.value * 10.0;
        let code = tenths.round();
        let unsupported = |why: &str, help: &str| {
            let error = LineError::new(
                word.span(),
                format!("unsupported code `{text}`{why}"),
                "unsupported G code",
            );
            if help.is_empty() {
                error.help("supported: G00 G01 G02 G03 G04 G17 G18 G19 G20 G21 G40 G43.4 G49 G54 G80 G90 G91 G93 G94")
            } else {
                error.help(help)
            }
        };
        if word.number.starts_with(['+', '-']) || (tenths - code).abs() > 1e-6 || code > 9999.0 {
            return Err(unsupported("", ""));
        }
        let code = match code as u32 {
            0 => GCode::Motion(MotionMode::Rapid),
            10 => GCode::Motion(MotionMode::Linear),
            20 => GCode::Motion(MotionMode::Arc { clockwise: true }),
            30 => GCode::Motion(MotionMode::Arc { clockwise: false }),
            40 => GCode::Dwell,
            170 => GCode::Plane(Plane::XY),
            180 => GCode::Plane(Plane::ZX),
            190 => GCode::Plane(Plane::YZ),
            200 => GCode::Inch,
            210 => GCode::Millimetre,
            400 => GCode::NoOp(Group::CutterComp),
            434 => GCode::TcpOn,
            490 => GCode::TcpOff,
            540 => GCode::NoOp(Group::WorkOffset),
            800 => GCode::NoOp(Group::CannedCycle),
            900 => GCode::Absolute,
            910 => GCode::Incremental,
            930 => GCode::Feed(FeedMode::InverseTime),
            940 => GCode::Feed(FeedMode::PerMinute),
            280 | 281 | 290 | 300 => {
                return Err(unsupported(
                    " (reference-point return is not supported)",
                    "move to the reference point with an explicit G00 or G01 block",
                ))
            }
            410 | 420 => {
                return Err(unsupported(
                    " (cutter radius compensation is not supported)",
                    "post-process the program with the tool radius applied; G40 (cancel) is accepted",
                ))
            }
            430 | 440 => {
                return Err(unsupported(
                    " (tool length offsets are not supported)",
                    "use G43.4 for tool-centre-point control; the tool length comes from the machine file",
                ))
            }
            520 => {
                return Err(unsupported(
                    " (local coordinate systems are not supported)",
                    "write positions in the work coordinate system G54, taken as machine zero",
                ))
            }
            550..=590 => {
                return Err(unsupported(
                    " (only work offset G54 is supported, and it is taken as zero)",
                    "write positions in G54",
                ))
            }
            680..=689 | 690 => {
                return Err(unsupported(
                    " (coordinate rotation and tilted working planes are not supported)",
                    "post-process the program to machine axis positions",
                ))
            }
            730 | 740 | 760 | 810..=890 => {
                return Err(unsupported(
                    " (canned cycles are not supported)",
                    "expand the cycle into G00/G01 moves; G80 (cancel) is accepted",
                ))
            }
            920 => {
                return Err(unsupported(
                    " (coordinate system setting is not supported)",
                    "give the start position to the reader instead",
                ))
            }
            _ => return Err(unsupported("", "")),
        };
        Ok(code)
    }
}

/// Modal motion mode (group 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum MotionMode {
    Rapid,
    Linear,
    Arc { clockwise: bool },
}

/// A supported M code's group; two of one group may not share a block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum MGroup {
    /// M00 M01 (ignored) and M02 M30 (end of program).
    Stop {
        end: bool,
    },
    Spindle,
    ToolChange,
    Coolant,
}

impl MGroup {
    fn same(self, other: MGroup) -> bool {
        std::mem::discriminant(&self) == std::mem::discriminant(&other)
    }

    fn parse(word: &Word, line: &str) -> LineResult<MGroup> {
        let text = &line[word.span()];
        let code = integer(word, line)?;
        Ok(match code {
            0 | 1 => MGroup::Stop { end: false },
            2 | 30 => MGroup::Stop { end: true },
            3..=5 => MGroup::Spindle,
            6 => MGroup::ToolChange,
            8 | 9 => MGroup::Coolant,
            98 | 99 => {
                return Err(LineError::new(
                    word.span(),
                    format!("unsupported code `{text}` (subprogram calls are not supported)"),
                    "subprogram call",
                )
                .help("expand the subprogram into the main program"))
            }
            _ => {
                return Err(LineError::new(
                    word.span(),
                    format!("unsupported code `{text}`"),
                    "unsupported M code",
                )
                .help("supported: M00 M01 M02 M03 M04 M05 M06 M08 M09 M30"))
            }
        })
    }
}

/// The value of `word` as a non-negative integer.
fn integer(word: &Word, line: &str) -> LineResult<u64> {
    let digits = word.number.strip_prefix('+').unwrap_or(word.number);
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return Err(LineError::new(
            word.span(),
            format!(
                "`{}`: expected a whole number after `{}`",
                &line[word.span()],
                word.letter
            ),
            "expected a whole number",
        ));
    }
    Ok(word.value as u64)
}

/// What one line produced.
enum Step {
    Nothing,
    /// A block, and whether the program ends after it.
    Block(Move, bool),
    /// End of program with no motion on this line.
    End,
}

/// The modal state of the controller between blocks.
#[derive(Clone, Debug)]
struct Modal {
    position: AxisVec,
    motion: Option<MotionMode>,
    plane: Plane,
    absolute: bool,
    feed_mode: FeedMode,
    inch: bool,
    /// Last F programmed in the current feed mode (mm/min or 1/min).
    feed: Option<f64>,
    tcp: bool,
    percent_seen: bool,
}

/// The words of a block, sorted by kind.
#[derive(Default)]
struct Parsed<'l> {
    g: Vec<(GCode, Word<'l>)>,
    m: Vec<(MGroup, Word<'l>)>,
    /// Single words by letter index ('A' = 0).
    single: [Option<Word<'l>>; 26],
}

impl<'l> Parsed<'l> {
    fn get(&self, letter: char) -> Option<Word<'l>> {
        self.single[(letter as u8 - b'A') as usize]
    }

    fn motion_code(&self) -> Option<(GCode, Word<'l>)> {
        self.g
            .iter()
            .copied()
            .find(|(code, _)| code.group() == Group::Motion)
    }
}

impl Modal {
    fn new(start: AxisVec) -> Modal {
        Modal {
            position: start,
            motion: None,
            plane: Plane::XY,
            absolute: true,
            feed_mode: FeedMode::PerMinute,
            inch: false,
            feed: None,
            tcp: false,
            percent_seen: false,
        }
    }

    /// Reads one source line (without its line terminator).
    fn line(&mut self, line: &str, line_no: usize) -> LineResult<Step> {
        match lex(line)? {
            Lexed::Nothing => Ok(Step::Nothing),
            Lexed::Percent if self.percent_seen => Ok(Step::End),
            Lexed::Percent => {
                self.percent_seen = true;
                Ok(Step::Nothing)
            }
            Lexed::Words(words) => self.block(line, &words, line_no),
        }
    }

    fn sort<'l>(line: &str, words: &[Word<'l>]) -> LineResult<Parsed<'l>> {
        let mut parsed = Parsed::default();
        for word in words {
            match word.letter {
                'G' => {
                    let code = GCode::parse(word, line)?;
                    if let Some((_, other)) =
                        parsed.g.iter().find(|(c, _)| c.group() == code.group())
                    {
                        return Err(LineError::new(
                            word.span(),
                            format!(
                                "`{}` and `{}` are in the same modal group: expected at most one per block",
                                &line[other.span()],
                                &line[word.span()]
                            ),
                            "second code of the group",
                        )
                        .help("split them into two blocks"));
                    }
                    parsed.g.push((code, *word));
                }
                'M' => {
                    let group = MGroup::parse(word, line)?;
                    if let Some((_, other)) = parsed.m.iter().find(|(g, _)| g.same(group)) {
                        return Err(LineError::new(
                            word.span(),
                            format!(
                                "`{}` and `{}` are in the same group: expected at most one per block",
                                &line[other.span()],
                                &line[word.span()]
                            ),
                            "second code of the group",
                        ));
                    }
                    parsed.m.push((group, *word));
                }
                letter => {
                    let slot = &mut parsed.single[(letter as u8 - b'A') as usize];
                    if let Some(first) = slot {
                        return Err(LineError::new(
                            word.span(),
                            format!(
                                "repeated `{letter}` word (first `{}`): expected each of {EXPECTED_WORDS} at most once per block, apart from G and M",
                                &line[first.span()]
                            ),
                            "repeated word",
                        ));
                    }
                    *slot = Some(*word);
                }
            }
        }
        Ok(parsed)
    }

    /// Interprets the words of one block.
    fn block(&mut self, line: &str, words: &[Word], line_no: usize) -> LineResult<Step> {
        let p = Self::sort(line, words)?;
        for letter in ['N', 'O', 'T', 'H'] {
            if let Some(word) = p.get(letter) {
                integer(&word, line)?;
            }
        }
        if let Some(s) = p.get('S') {
            if s.value < 0.0 {
                return Err(LineError::new(
                    s.span(),
                    "negative spindle speed: expected S zero or more",
                    "negative",
                ));
            }
        }

        // Modal settings take effect before the block's motion.
        let mut motion_code = None;
        let mut dwell = None;
        let mut tcp_on = false;
        for &(code, word) in &p.g {
            match code {
                GCode::Motion(mode) => motion_code = Some(mode),
                GCode::Dwell => dwell = Some(word),
                GCode::Plane(plane) => self.plane = plane,
                GCode::Absolute => self.absolute = true,
                GCode::Incremental => self.absolute = false,
                GCode::Feed(mode) => {
                    if mode != self.feed_mode {
                        // An F of the other mode means nothing here: it must be given again.
                        self.feed = None;
                    }
                    self.feed_mode = mode;
                }
                GCode::Inch => self.inch = true,
                GCode::Millimetre => self.inch = false,
                GCode::TcpOn => {
                    self.tcp = true;
                    tcp_on = true;
                }
                GCode::TcpOff => self.tcp = false,
                GCode::NoOp(_) => {}
            }
        }
        if let Some(mode) = motion_code {
            self.motion = Some(mode);
        }
        if let Some(h) = p.get('H') {
            if !tcp_on {
                return Err(LineError::new(
                    h.span(),
                    "`H` without G43.4: expected H only in a G43.4 block",
                    "H without G43.4",
                ));
            }
        }
        let scale = if self.inch { MM_PER_INCH } else { 1.0 };
        let mut feed_word = None;
        if let Some(f) = p.get('F') {
            if f.value <= 0.0 {
                return Err(LineError::new(
                    f.span(),
                    format!("`{}`: expected a feed greater than zero", &line[f.span()]),
                    "feed not positive",
                ));
            }
            let feed = match self.feed_mode {
                FeedMode::PerMinute => f.value * scale,
                FeedMode::InverseTime => f.value,
            };
            self.feed = Some(feed);
            feed_word = Some(f);
        }
        let end = p.m.iter().any(|(g, _)| *g == MGroup::Stop { end: true });

        if let Some(g04) = dwell {
            let block = self.dwell(line, &p, g04, line_no)?;
            return Ok(Step::Block(block, end));
        }
        if let Some(p_word) = p.get('P') {
            return Err(LineError::new(
                p_word.span(),
                "`P` outside a G04 block: expected P only as the dwell time of G04",
                "P without G04",
            ));
        }

        let axis_words: Vec<(Axis, Word)> = Axis::ALL
            .iter()
            .filter_map(|&axis| p.get(axis.letter()).map(|w| (axis, w)))
            .collect();
        let arc_words: Vec<Word> = ['I', 'J', 'K', 'R']
            .iter()
            .filter_map(|&l| p.get(l))
            .collect();
        if axis_words.is_empty() && arc_words.is_empty() {
            return Ok(if end { Step::End } else { Step::Nothing });
        }
        let first = axis_words
            .iter()
            .map(|(_, w)| *w)
            .chain(arc_words.iter().copied())
            .min_by_key(|w| w.span.0)
            .map_or(0..0, |w| w.span());
        let Some(mode) = self.motion else {
            return Err(LineError::new(
                first,
                "axis word with no motion mode: expected G00, G01, G02 or G03 in this or an earlier block",
                "no motion mode",
            ));
        };
        if !matches!(mode, MotionMode::Arc { .. }) {
            if let Some(w) = arc_words.first() {
                return Err(LineError::new(
                    w.span(),
                    format!(
                        "`{}` outside an arc: expected I J K R only with G02 or G03",
                        &line[w.span()]
                    ),
                    "not an arc",
                ));
            }
        }

        let start = self.position;
        let mut target = start;
        for &(axis, w) in &axis_words {
            let value = if axis.is_rotary() {
                w.value
            } else {
                w.value * scale
            };
            target[axis] = if self.absolute {
                value
            } else {
                start[axis] + value
            };
        }

        let motion = match mode {
            MotionMode::Rapid => Motion::Rapid,
            MotionMode::Linear => Motion::Linear,
            MotionMode::Arc { clockwise } => {
                let center_mm = self.arc_center(line, &p, clockwise, start, target, scale)?;
                Motion::Arc {
                    clockwise,
                    plane: self.plane,
                    center_mm,
                }
            }
        };
        if mode != MotionMode::Rapid {
            let at = p.motion_code().map_or(first, |(_, w)| w.span());
            match self.feed_mode {
                FeedMode::InverseTime if feed_word.is_none() => {
                    return Err(LineError::new(
                        at,
                        "feed move in G93 (inverse time) without F: expected an F word in every G01/G02/G03 block",
                        "no F in this block",
                    )
                    .help("add F = 1 / (block time in minutes) to this block"));
                }
                FeedMode::PerMinute if self.feed.is_none() => {
                    return Err(LineError::new(
                        at,
                        "feed move with no feed programmed: expected an F word (mm/min) in this or an earlier G94 block",
                        "no F in effect",
                    )
                    .help("add F, e.g. `F1000` for 1000 mm/min"));
                }
                _ => {}
            }
        }
        self.position = target;
        Ok(Step::Block(
            Move {
                line: line_no,
                motion,
                start,
                end: target,
                feed: self.feed,
                feed_mode: self.feed_mode,
                tcp: self.tcp,
                ..Move::default()
            },
            end,
        ))
    }

    /// A G04 block: P in ms (Fanuc) or X in s.
    fn dwell(&self, line: &str, p: &Parsed, g04: Word, line_no: usize) -> LineResult<Move> {
        for letter in ['Y', 'Z', 'A', 'B', 'C', 'I', 'J', 'K', 'R'] {
            if let Some(w) = p.get(letter) {
                return Err(LineError::new(
                    w.span(),
                    format!(
                        "`{}` in a G04 block: expected only P (ms) or X (s) with G04",
                        &line[w.span()]
                    ),
                    "not a dwell word",
                )
                .help("put the move in its own block"));
            }
        }
        let seconds = match (p.get('P'), p.get('X')) {
            (Some(ms), None) => (ms.value / 1000.0, ms),
            (None, Some(s)) => (s.value, s),
            (Some(_), Some(x)) => {
                return Err(LineError::new(
                    x.span(),
                    "G04 with both P and X: expected one dwell time, P (ms) or X (s)",
                    "second dwell time",
                ))
            }
            (None, None) => {
                return Err(LineError::new(
                    g04.span(),
                    "G04 without a time: expected P (ms) or X (s)",
                    "no dwell time",
                )
                .help("e.g. `G04 P500` dwells 0.5 s"))
            }
        };
        let (seconds, word) = seconds;
        if seconds < 0.0 {
            return Err(LineError::new(
                word.span(),
                "negative dwell: expected a time of zero or more",
                "negative",
            ));
        }
        Ok(Move {
            line: line_no,
            motion: Motion::Dwell { seconds },
            start: self.position,
            end: self.position,
            feed: self.feed,
            feed_mode: self.feed_mode,
            tcp: self.tcp,
            ..Move::default()
        })
    }

    /// The absolute arc centre `[X, Y, Z]`, mm, from I J K (incremental from the start) or R,
    /// checked so that the start and end radii agree.
    ///
    /// For R, with chord length d from s to e and midpoint m, the centre lies at distance
    /// `h = sqrt(R² - (d/2)²)` from m along the chord's normal; it is on the left of the
    /// direction of travel for a counter-clockwise short arc and for a clockwise long arc.
    fn arc_center(
        &self,
        line: &str,
        p: &Parsed,
        clockwise: bool,
        start: AxisVec,
        end: AxisVec,
        scale: f64,
    ) -> LineResult<[f64; 3]> {
        let (u, v, n) = self.plane.axes();
        let offset_letter = |axis: Axis| match axis {
            Axis::X => 'I',
            Axis::Y => 'J',
            _ => 'K',
        };
        let block_span =
            p.g.iter()
                .map(|(_, w)| *w)
                .chain(p.single.iter().flatten().copied())
                .fold(None, |acc: Option<(usize, usize)>, w| {
                    Some(acc.map_or(w.span, |(a, b)| (a.min(w.span.0), b.max(w.span.1))))
                })
                .map_or(0..line.len(), |(a, b)| a..b);
        if let Some(w) = p.get(offset_letter(n)) {
            return Err(LineError::new(
                w.span(),
                format!(
                    "`{}` is not in the arc plane {}: expected {} and {}",
                    &line[w.span()],
                    self.plane.g_code(),
                    offset_letter(u),
                    offset_letter(v)
                ),
                "off-plane centre offset",
            )
            .help("select the plane of the arc with G17, G18 or G19"));
        }
        let (su, sv) = (start[u], start[v]);
        let (eu, ev) = (end[u], end[v]);
        let mut center = [start[Axis::X], start[Axis::Y], start[Axis::Z]];
        let offsets = (p.get(offset_letter(u)), p.get(offset_letter(v)));
        match (p.get('R'), offsets) {
            (Some(r), (Some(w), _) | (_, Some(w))) => {
                let first = if r.span.0 < w.span.0 { w } else { r };
                Err(LineError::new(
                    first.span(),
                    "arc with both R and I J K: expected either the radius R or the centre offsets I J K",
                    "second arc definition",
                ))
            }
            (None, (None, None)) => Err(LineError::new(
                block_span,
                format!(
                    "arc without a centre: expected {} {} (centre offsets from the start) or R (radius)",
                    offset_letter(u),
                    offset_letter(v)
                ),
                "no centre",
            )),
            (None, (i, j)) => {
                let cu = su + i.map_or(0.0, |w| w.value * scale);
                let cv = sv + j.map_or(0.0, |w| w.value * scale);
                let r_start = (su - cu).hypot(sv - cv);
                let r_end = (eu - cu).hypot(ev - cv);
                if r_start == 0.0 {
                    return Err(LineError::new(
                        block_span,
                        "arc of radius zero: expected centre offsets that are not all zero",
                        "zero radius",
                    ));
                }
                if (r_start - r_end).abs() > ARC_RADIUS_TOLERANCE_MM {
                    return Err(LineError::new(
                        block_span,
                        format!(
                            "arc radius at the start is {r_start:.6} mm but at the end {r_end:.6} mm: expected them to agree within {ARC_RADIUS_TOLERANCE_MM} mm"
                        ),
                        "inconsistent arc",
                    )
                    .help("I J K are incremental from the start point; check them and the end point"));
                }
                center[u.index()] = cu;
                center[v.index()] = cv;
                Ok(center)
            }
            (Some(r), (None, None)) => {
                let radius = r.value * scale;
                let (du, dv) = (eu - su, ev - sv);
                let chord = du.hypot(dv);
                if chord < FULL_CIRCLE_TOLERANCE_MM {
                    return Err(LineError::new(
                        r.span(),
                        "R arc whose end is its start: expected an end point away from the start (R cannot describe a full circle)",
                        "R arc with no chord",
                    )
                    .help("program a full circle with I J K"));
                }
                if radius == 0.0 {
                    return Err(LineError::new(
                        r.span(),
                        "arc of radius zero: expected R other than zero",
                        "zero radius",
                    ));
                }
                let half = chord / 2.0;
                let h2 = radius * radius - half * half;
                if h2 < 0.0 && half - radius.abs() > ARC_RADIUS_TOLERANCE_MM {
                    return Err(LineError::new(
                        r.span(),
                        format!(
                            "radius {:.6} mm is shorter than half the chord, {half:.6} mm: expected |R| of at least half the distance from start to end",
                            radius.abs()
                        ),
                        "radius too small",
                    ));
                }
                let h = h2.max(0.0).sqrt();
                let long = radius < 0.0;
                let left = !clockwise != long;
                let side = if left { h } else { -h };
                // Left normal of the chord direction (du, dv) is (-dv, du).
                center[u.index()] = su + du / 2.0 - side * dv / chord;
                center[v.index()] = sv + dv / 2.0 + side * du / chord;
                Ok(center)
            }
        }
    }
}
