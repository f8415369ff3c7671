//! mtsim's errors → the Python exceptions of `mtsim.errors`, with the place in the input
//! (file, line, column, dotted key) as attributes and the command line's message.

use std::path::{Path, PathBuf};

use mtsim::error::{Error, EXIT_RUN_FAILED};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Texts the caller made (a dict rendered as TOML): their errors' keys are found in them
/// rather than in a file on disk.
pub type Texts = Vec<(PathBuf, String)>;

/// The Python exception for `e`: `InputError` for bad input (exit code 2), `RunError`
/// for a run that failed (3).
pub fn to_py_err(e: &Error, texts: &Texts) -> PyErr {
    Python::attach(|py| match exception(py, e, texts) {
        Ok(err) => err,
        Err(failed) => failed,
    })
}

fn exception(py: Python<'_>, e: &Error, texts: &Texts) -> PyResult<PyErr> {
    let code = e.exit_code();
    let class = if code == EXIT_RUN_FAILED {
        "RunError"
    } else {
        "InputError"
    };
    let (file, line, column, help) = place(e);
    let key = match (&file, line) {
        (Some(f), Some(l)) => text_of(f, texts).and_then(|t| key_at(&t, l)),
        _ => None,
    };
    let kwargs = PyDict::new(py);
    kwargs.set_item("file", file.map(|f| f.display().to_string()))?;
    kwargs.set_item("line", line)?;
    kwargs.set_item("column", column)?;
    kwargs.set_item("key", key)?;
    kwargs.set_item("help", help)?;
    kwargs.set_item("exit_code", code)?;
    let cls = py.import("mtsim.errors")?.getattr(class)?;
    let instance = cls.call((e.to_string(),), Some(&kwargs))?;
    Ok(PyErr::from_value(instance))
}

/// An error that is no mtsim error (a panic caught at the boundary): `MtsimError`.
pub fn internal(message: String) -> PyErr {
    Python::attach(|py| {
        let made = py
            .import("mtsim.errors")
            .and_then(|m| m.getattr("MtsimError"))
            .and_then(|cls| cls.call1((message.clone(),)));
        match made {
            Ok(instance) => PyErr::from_value(instance),
            Err(failed) => failed,
        }
    })
}

type Place = (
    Option<PathBuf>,
    Option<usize>,
    Option<usize>,
    Option<String>,
);

/// File, 1-based line and column, and the hint of an error, where it has them.
fn place(e: &Error) -> Place {
    match e {
        Error::AtSource(s) => (
            Some(s.path.clone()),
            Some(s.line),
            Some(s.column),
            s.help.clone(),
        ),
        Error::Located {
            path,
            line,
            column,
            help,
            ..
        } => (Some(path.clone()), Some(*line), Some(*column), help.clone()),
        Error::Invalid { path, help, .. } => (Some(path.clone()), None, None, help.clone()),
        Error::Read { path, .. } | Error::Write { path, .. } => {
            (Some(path.clone()), None, None, None)
        }
        Error::Usage { .. } | Error::Diverged { .. } => (None, None, None, None),
    }
}

fn text_of(file: &Path, texts: &Texts) -> Option<String> {
    match texts.iter().find(|(p, _)| p == file) {
        Some((_, t)) => Some(t.clone()),
        None => std::fs::read_to_string(file).ok(),
    }
}

/// The dotted key that line `line` (1-based) of TOML `text` sets: the last table header
/// above it joined with the key before `=` (`simulate.trace_every`), or the header itself
/// on a header line. None on a blank or comment line.
pub fn key_at(text: &str, line: usize) -> Option<String> {
    let mut table = String::new();
    for (i, raw) in text.lines().enumerate() {
        let l = raw.trim();
        let header = l
            .strip_prefix("[[")
            .and_then(|h| h.split("]]").next())
            .or_else(|| l.strip_prefix('[').and_then(|h| h.split(']').next()));
        if let Some(h) = header {
            table = unquote_dotted(h);
            if i + 1 == line {
                return Some(table);
            }
            continue;
        }
        if i + 1 == line {
            let (key, _) = l.split_once('=')?;
            let key = unquote_dotted(key);
            return Some(if table.is_empty() {
                key
            } else {
                format!("{table}.{key}")
            });
        }
    }
    None
}

/// `a."b c".d` → `a.b c.d`: the dotted key without quotes and spaces about the dots.
fn unquote_dotted(key: &str) -> String {
    key.split('.')
        .map(|p| p.trim().trim_matches('"').trim_matches('\''))
        .collect::<Vec<_>>()
        .join(".")
}
