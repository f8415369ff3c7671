//! What the reader reports: a file it could not read, or a place in the program it does not
//! accept, with what it expected there.

use std::fmt;
use std::ops::Range;
use std::path::PathBuf;

pub type Result<T, E = Error> = std::result::Result<T, E>;

/// A reader error. Yielded at most once, after which the reader stops.
#[derive(Debug)]
pub enum Error {
    /// The program could not be opened or read.
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The program says something the reader does not accept, at a known place.
    Syntax(Box<Syntax>),
}

/// A place in a program that the reader does not accept.
#[derive(Clone, Debug, PartialEq)]
pub struct Syntax {
    pub path: PathBuf,
    /// 1-based line.
    pub line: usize,
    /// 1-based column, in characters.
    pub column: usize,
    /// What is wrong and what was expected.
    pub message: String,
    /// A short label for the offending span.
    pub label: String,
    /// What to do about it.
    pub help: Option<String>,
    /// The program text `span` points into: the whole file, or the offending line alone at
    /// its own line number when the file could not be read again.
    pub text: String,
    /// Byte range of the offending words in `text`.
    pub span: Range<usize>,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Read { path, .. } => write!(f, "cannot read {}", path.display()),
            Error::Syntax(s) => write!(
                f,
                "{}:{}:{}: {}",
                s.path.display(),
                s.line,
                s.column,
                s.message
            ),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Read { source, .. } => Some(source),
            Error::Syntax(_) => None,
        }
    }
}

/// 1-based line and character column of byte `offset` in `text`.
pub fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = before[line_start..].chars().count() + 1;
    (line, column)
}
