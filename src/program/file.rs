//! G-code files, read by the `ngc` interpreter crate, as a stream of canonical moves.
//!
//! The reader starts from all axes at zero: the machine position before a program runs is
//! not known, so the first move only brings the machine to the program's start.

use std::path::Path;

use super::Moves;
use crate::error::{Error, Result};
use crate::{Axis, AxisVec};

/// Streams the moves of the file at `path`; memory does not grow with its length.
pub fn read_file(path: &Path) -> Result<Moves<'static>> {
    let moves = ngc::read_file(path, AxisVec::ZERO)?;
    Ok(Box::new(moves.map(|m| m.map_err(Into::into))))
}

/// Streams the moves of the file at `path` as `options` say (dialect, tools, parameters,
/// subroutine path), for a machine with `options.axes`: a move of any other axis is an
/// error at its line (a word for an axis the machine lacks is never dropped, nor is a
/// move an offset makes on it).
pub fn read_file_with(path: &Path, options: &ngc::Options) -> Result<Moves<'static>> {
    let moves = ngc::read_file_with(path, options)?.map(|m| m.map_err(Error::from));
    let axes = options.axes.clone();
    let path = path.to_path_buf();
    let mut failed = false;
    Ok(Box::new(moves.map_while(move |m| {
        if failed {
            return None;
        }
        let m = match m {
            Ok(m) => m,
            Err(e) => {
                failed = true;
                return Some(Err(e));
            }
        };
        let missing = Axis::ALL
            .into_iter()
            .find(|&a| !axes.contains(&a) && (m.start[a] != 0.0 || m.end[a] != 0.0));
        match missing {
            None => Some(Ok(m)),
            Some(axis) => {
                failed = true;
                Some(Err(missing_axis(&path, m.line, axis, &axes)))
            }
        }
    })))
}

/// The error for a move of `axis` on line `line` of `path`, pointing at the axis word.
fn missing_axis(path: &Path, line: usize, axis: Axis, axes: &[Axis]) -> Error {
    let have: String = axes.iter().map(|a| a.letter()).collect();
    let message = format!(
        "the program moves axis {axis}, which the machine does not have: expected only the axes {have}"
    );
    let text = std::fs::read(path)
        .map(|b| String::from_utf8_lossy(&b).into_owned())
        .unwrap_or_default();
    // Byte range of the line, and of the axis word in it (outside comments), if found.
    let start: usize = text
        .split_inclusive('\n')
        .take(line - 1)
        .map(str::len)
        .sum();
    let body = text[start.min(text.len())..].lines().next().unwrap_or("");
    let span = word_of(body, axis.letter()).map_or(start..start + body.len(), |r| {
        start + r.start..start + r.end
    });
    Error::at(path, &text, span, message, format!("axis {axis}"))
        .with_help("use a machine with this axis, or post-process the program for this machine")
}

/// The byte range of the first word with `letter` in `line`, outside comments.
fn word_of(line: &str, letter: char) -> Option<std::ops::Range<usize>> {
    let mut depth = 0;
    for (i, c) in line.char_indices() {
        match c {
            '(' => depth += 1,
            ')' => depth = (depth - 1).max(0),
            ';' if depth == 0 => return None,
            c if depth == 0 && c.eq_ignore_ascii_case(&letter) => {
                let end = line[i + 1..]
                    .find(|c: char| !(c.is_ascii_digit() || "+-. \t".contains(c)))
                    .map_or(line.len(), |k| i + 1 + k);
                return Some(i..line[..end].trim_end().len().max(i + 1));
            }
            _ => {}
        }
    }
    None
}

/// Streams the moves of `text`, reported as the contents of `path`.
pub fn read_str<'a>(path: &'a Path, text: &'a str) -> Moves<'a> {
    Box::new(ngc::read_str(path, text, AxisVec::ZERO).map(|m| m.map_err(Into::into)))
}
