//! Errors, with source spans for input files, and the exit codes scripts rely on.
//!
//! Exit codes: 0 success, 1 checked and found violations, 2 bad input (missing file,
//! syntax, schema, value out of range), 3 a run that failed (the simulation diverged, or an
//! output could not be written).

use std::path::{Path, PathBuf};

use miette::{Diagnostic, NamedSource, SourceSpan};
use thiserror::Error;

pub use ngc::line_column;

/// Exit code for bad input.
pub const EXIT_BAD_INPUT: i32 = 2;
/// Exit code for a run that could not finish.
pub const EXIT_RUN_FAILED: i32 = 3;
/// Exit code for "checked and found violations".
pub const EXIT_VIOLATIONS: i32 = 1;

pub type Result<T, E = Error> = std::result::Result<T, E>;

#[derive(Debug, Error, Diagnostic)]
pub enum Error {
    /// An input file could not be read.
    #[error("cannot read {}", path.display())]
    #[diagnostic(
        code(mtsim::io),
        help("check the path; paths inside a scenario are relative to the scenario file")
    )]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },

    /// Bad input at a known place in a file: syntax, schema or value (boxed: every
    /// `Result` of the pipeline carries this enum, and its setpoints and samples are
    /// copied by value once per period).
    #[error(transparent)]
    #[diagnostic(transparent)]
    AtSource(Box<SourceError>),

    /// Bad input with no single place in a file, such as a missing key or a command-line value.
    #[error("{}: {message}", path.display())]
    #[diagnostic(code(mtsim::input))]
    Invalid {
        path: PathBuf,
        message: String,
        #[help]
        help: Option<String>,
    },

    /// Bad input at a known place in a file whose text is not shown: a file other than the
    /// scenario and the program (a machine file, an error table), which may be any file the
    /// user pointed at, so its lines are never quoted.
    #[error("{}:{line}:{column}: {message}", path.display())]
    #[diagnostic(code(mtsim::input))]
    Located {
        path: PathBuf,
        line: usize,
        column: usize,
        message: String,
        #[help]
        help: Option<String>,
    },

    /// A command-line argument out of range.
    #[error("{message}")]
    #[diagnostic(code(mtsim::usage))]
    Usage { message: String },

    /// The servo simulation became unstable.
    #[error("simulation diverged on axis {axis} at t = {time_s:.4} s: {reason}")]
    #[diagnostic(
        code(mtsim::diverged),
        help(
            "lower the gains, raise the servo substeps, or check the drive parameters of that axis"
        )
    )]
    Diverged {
        axis: crate::Axis,
        time_s: f64,
        reason: String,
    },

    /// An output file could not be written. Nothing partial is left behind.
    #[error("cannot write {}", path.display())]
    #[diagnostic(code(mtsim::write))]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

/// [`Error::AtSource`]: bad input at a known place in a file.
#[derive(Debug, Error, Diagnostic)]
#[error("{}:{line}:{column}: {message}", path.display())]
#[diagnostic(code(mtsim::input))]
pub struct SourceError {
    pub path: PathBuf,
    /// 1-based line.
    pub line: usize,
    /// 1-based column, in characters.
    pub column: usize,
    pub message: String,
    #[source_code]
    pub source_code: NamedSource<String>,
    #[label("{label}")]
    pub span: SourceSpan,
    pub label: String,
    #[help]
    pub help: Option<String>,
}

impl Error {
    /// The process exit code for this error.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Diverged { .. } | Error::Write { .. } => EXIT_RUN_FAILED,
            _ => EXIT_BAD_INPUT,
        }
    }

    /// An error at byte range `span` of `text`, the contents of `path`.
    pub fn at(
        path: &Path,
        text: &str,
        span: std::ops::Range<usize>,
        message: impl Into<String>,
        label: impl Into<String>,
    ) -> Error {
        let start = span.start.min(text.len());
        let end = span.end.clamp(start, text.len());
        let (line, column) = line_column(text, start);
        Error::AtSource(Box::new(SourceError {
            path: path.to_path_buf(),
            line,
            column,
            message: message.into(),
            source_code: NamedSource::new(path.display().to_string(), text.to_string()),
            span: (start, end - start).into(),
            label: label.into(),
            help: None,
        }))
    }

    /// The same error without the file's text, unless the file is `shown` (the scenario):
    /// the place and the message stay, the quoted line goes.
    pub fn without_source_unless(self, shown: Option<&Path>) -> Error {
        match self {
            Error::AtSource(e) if Some(e.path.as_path()) != shown => Error::Located {
                path: e.path,
                line: e.line,
                column: e.column,
                message: e.message,
                help: e.help,
            },
            other => other,
        }
    }

    /// Adds a hint that says what to do.
    pub fn with_help(mut self, text: impl Into<String>) -> Error {
        match &mut self {
            Error::AtSource(e) => e.help = Some(text.into()),
            Error::Invalid { help, .. } | Error::Located { help, .. } => *help = Some(text.into()),
            _ => {}
        }
        self
    }

    pub fn invalid(path: &Path, message: impl Into<String>) -> Error {
        Error::Invalid {
            path: path.to_path_buf(),
            message: message.into(),
            help: None,
        }
    }

    pub fn usage(message: impl Into<String>) -> Error {
        Error::Usage {
            message: message.into(),
        }
    }
}

/// Extensions of files that are no NC program whatever they hold: data, pages, images,
/// documents and source code a scenario may name by mistake.
const NOT_PROGRAM_EXTENSIONS: [&str; 22] = [
    "toml", "json", "csv", "parquet", "svg", "html", "htm", "xml", "png", "jpg", "jpeg", "gif",
    "pdf", "zip", "gz", "md", "yaml", "yml", "py", "rs", "xlsx", "docx",
];

/// Whether the file `path` with text `text` is no program at all, judged where its reader
/// stopped (byte `at`): the offending line holds control characters or bytes that were not
/// UTF-8 (an image, an archive), or nothing before that line was read as a block and the
/// file's extension names another kind of file (a scenario or machine file named as the
/// program). Such a file is named by its path, line and column only: its content is not the
/// user's G-code to quote. A real program that fails on its first block (a Sinumerik system
/// variable, say) keeps the reader's message, which names the construct.
fn not_a_program(path: &Path, text: &str, at: usize) -> bool {
    let at = at.min(text.len());
    let line_start = text[..at].rfind('\n').map_or(0, |i| i + 1);
    let line_end = text[at..].find('\n').map_or(text.len(), |i| at + i);
    let line = &text[line_start..line_end];
    let garbled = line
        .chars()
        .any(|c| c == '\u{fffd}' || (c.is_control() && c != '\t' && c != '\r'));
    let other_kind = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| NOT_PROGRAM_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()));
    let words_before = text[..line_start].lines().any(|l| {
        let mut depth = 0;
        for c in l.chars() {
            match c {
                '(' => depth += 1,
                ')' if depth > 0 => depth -= 1,
                ';' if depth == 0 => return false,
                c if depth == 0 && !c.is_whitespace() && c != '%' => return true,
                _ => {}
            }
        }
        false
    });
    garbled || (other_kind && !words_before)
}

/// A G-code reader error becomes a diagnostic that shows the line with its caret (or, for a
/// file that is no program at all, only its place: [`not_a_program`]).
impl From<ngc::Error> for Error {
    fn from(e: ngc::Error) -> Error {
        match e {
            ngc::Error::Read { path, source } => Error::Read { path, source },
            // Neither the text nor the reader's message, which names the offending word.
            ngc::Error::Syntax(s) if not_a_program(&s.path, &s.text, s.span.start) => {
                Error::Located {
                    path: s.path,
                    line: s.line,
                    column: s.column,
                    message: format!(
                        "not an NC program: it does not read as one from its first block ({})",
                        s.label
                    ),
                    help: Some(
                        "check the scenario's [program] file: it names this file as the program"
                            .into(),
                    ),
                }
            }
            ngc::Error::Syntax(s) => {
                let error = Error::at(&s.path, &s.text, s.span, s.message, s.label);
                match s.help {
                    Some(help) => error.with_help(help),
                    None => error,
                }
            }
        }
    }
}
