//! A G-code file checked against the machine before anything is sampled.
//!
//! Two kinds of program cannot be simulated or checked meaningfully, and are bad input
//! (exit code 2, with file:line:column):
//! - a program without motion: empty, comments only, or moves that go nowhere;
//! - a move longer than the machine's travel envelope on some axis, `|end − start| >
//!   max − min` (for a continuous rotary axis, more than [`MAX_ROTARY_TURNS`] turns), or a
//!   target that is not a finite number. Sampled at 1 ms, `G01 X1e308` would take longer
//!   than the universe is old; it is refused before the first sample.
//!
//! A target outside the travel but within the envelope's length is not bad input: it is
//! a travel violation, which `check` and `simulate` report with exit code 1.

use std::path::Path;

use super::file::read_file;
use crate::error::{Error, Result};
use crate::input::machine::Machine;
use crate::Axis;

/// Most turns one move of a continuous rotary axis may make.
pub const MAX_ROTARY_TURNS: f64 = 1000.0;

/// Byte range of the word of `axis` on 1-based `line` of `text` (the whole line when the
/// word is not written there, e.g. a modal value).
fn word_span(text: &str, line: usize, axis: Axis) -> std::ops::Range<usize> {
    let start = text
        .split_inclusive('\n')
        .take(line.saturating_sub(1))
        .map(str::len)
        .sum::<usize>();
    let line_text = text[start..].lines().next().unwrap_or("");
    let letter = axis.to_string().chars().next().unwrap_or('X');
    let bytes = line_text.as_bytes();
    for (i, c) in line_text.char_indices() {
        let next = bytes.get(i + 1).copied().unwrap_or(b' ');
        if c.eq_ignore_ascii_case(&letter)
            && (next.is_ascii_digit() || next == b'-' || next == b'+' || next == b'.')
        {
            let len = line_text[i..]
                .find(|ch: char| ch.is_whitespace() || ch == '(' || ch == ';')
                .unwrap_or(line_text.len() - i);
            return start + i..start + i + len;
        }
    }
    start..start + line_text.len()
}

/// Checks the G-code file at `path`, read with the scenario's reader `options`, against
/// `machine` (see the module doc).
pub fn validate_file(path: &Path, machine: &Machine, options: &ngc::Options) -> Result<()> {
    let text = std::fs::read_to_string(path).map_err(|source| Error::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let mut moving = false;
    for m in read_file(path, options)? {
        let m = m?;
        for &axis in machine.axes() {
            let (from, to) = (m.start[axis], m.end[axis]);
            let config = machine.axis(axis);
            let unit = if axis.is_rotary() { "deg" } else { "mm" };
            let span = word_span(&text, m.line, axis);
            if !to.is_finite() {
                return Err(Error::at(
                    path,
                    &text,
                    span,
                    format!("{axis} is not a finite number"),
                    "not finite",
                ));
            }
            let length = (to - from).abs();
            let envelope = if config.continuous {
                360.0 * MAX_ROTARY_TURNS
            } else {
                config.max - config.min
            };
            if length > envelope {
                return Err(Error::at(
                    path,
                    &text,
                    span,
                    format!(
                        "this move takes {axis} {} {unit} (from {} to {}), longer than the machine's \
                         whole {axis} travel of {} {unit} ({} .. {})",
                        fmt_len(length),
                        fmt_len(from),
                        fmt_len(to),
                        envelope,
                        config.min,
                        config.max
                    ),
                    "beyond the travel envelope",
                )
                .with_help(format!(
                    "expected {axis} within {} .. {} {unit}; check the units (G20 inch / G21 mm) and the digits",
                    config.min, config.max
                )));
            }
            if length > 1e-9 {
                moving = true;
            }
        }
    }
    if !moving {
        let last = text.trim_end().len();
        return Err(Error::at(
            path,
            &text,
            0..last.min(text.find('\n').unwrap_or(last)),
            "the program has no motion: no G00, G01, G02 or G03 move changes an axis position",
            "no motion in this program",
        )
        .with_help(
            "give the scenario a program with moves, or a [program.cone] / [program.circle] table",
        ));
    }
    Ok(())
}

/// A length without hundreds of digits: 500, 1.0e308.
fn fmt_len(v: f64) -> String {
    if v.abs() < 1e9 {
        format!("{v}")
    } else {
        format!("{v:.1e}")
    }
}
