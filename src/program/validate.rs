//! A G-code file checked against the machine as it streams, before a bad move is sampled.
//!
//! Two kinds of program cannot be simulated or checked meaningfully, and are bad input
//! (exit code 2, with file:line:column):
//! - a program without motion: empty, comments only, or moves that go nowhere;
//! - a move longer than the machine's travel envelope on some axis, `|end − start| >
//!   max − min` (for a continuous rotary axis, more than [`MAX_ROTARY_TURNS`] turns), or a
//!   target that is not a finite number. Sampled at 1 ms, `G01 X1e308` would take longer
//!   than the universe is old; it is refused before the first sample.
//!
//! - a move under tool-centre-point control on a machine whose rotaries have no modelled
//!   chain (xyzabc).
//!
//! A target outside the travel but within the envelope's length is not bad input: it is
//! a travel violation, which `check` and `simulate` report with exit code 1.

use std::path::{Path, PathBuf};

use super::file::read_moves;
use super::moves::Moves;
use super::{Motion, Move};
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
/// `machine` (see the module doc): the whole file, as [`checked`] streams it.
pub fn validate_file(path: &Path, machine: &Machine, options: &ngc::Options) -> Result<()> {
    for m in checked(path, machine, false, read_moves(path, options)?) {
        m?;
    }
    Ok(())
}

/// The moves of the G-code file at `path`, checked against `machine` as they stream (see
/// the module doc): the first move that fails is an error in place of the move, and a
/// stream that ends without motion ends with an error. Nothing is collected; the file's
/// text is read again only to show an error. `moves` is the reader itself (its errors
/// converted here) or any stream of moves: with the reader, the moves pass through one
/// boxed layer instead of two, one copy of each fewer. With `written_for_tcp` (`[simulate]
/// tcp = true`) every feed move must run under tool-centre-point control (G43.4, G234, M128,
/// TRAORI: the canonical `tcp` flag): a joint-space one is refused where it stands.
pub fn checked<I, E>(
    path: &Path,
    machine: &Machine,
    written_for_tcp: bool,
    moves: I,
) -> Moves<'static>
where
    I: Iterator<Item = std::result::Result<Move, E>> + 'static,
    E: Into<Error>,
{
    Box::new(Checked {
        checker: move_checker(path, machine, written_for_tcp),
        moves,
        done: false,
    })
}

/// The checks of [`checked`] on moves given one at a time by reference (no copy of a move):
/// [`MoveChecker::check`] each, then [`MoveChecker::end`] when the program ends.
pub fn move_checker(path: &Path, machine: &Machine, written_for_tcp: bool) -> MoveChecker {
    let limits = machine
        .axes()
        .iter()
        .map(|&axis| {
            let config = machine.axis(axis);
            let envelope = if config.continuous {
                360.0 * MAX_ROTARY_TURNS
            } else {
                config.max - config.min
            };
            (axis, envelope, config.min, config.max)
        })
        .collect();
    MoveChecker {
        path: path.to_path_buf(),
        no_tcp: machine
            .kinematics
            .layout
            .tool_pose_unmodelled()
            .map(|why| (machine.kinematics.layout.name(), why)),
        limits,
        written_for_tcp,
        moving: false,
    }
}

/// The stream of [`checked`].
pub struct Checked<I> {
    checker: MoveChecker,
    moves: I,
    done: bool,
}

/// The checks of [`checked`], one move at a time ([`move_checker`]).
pub struct MoveChecker {
    path: PathBuf,
    /// The machine cannot give tool-centre-point control (xyzabc: no modelled chain; U V W
    /// layouts): its layout's name and why.
    no_tcp: Option<(&'static str, &'static str)>,
    /// Per machine axis: envelope (mm or deg), travel min and max.
    limits: Vec<(Axis, f64, f64, f64)>,
    /// Every feed move must carry the `tcp` flag (`[simulate] tcp = true`).
    written_for_tcp: bool,
    moving: bool,
}

impl MoveChecker {
    /// The file's text, for an error message.
    fn text(&self) -> String {
        std::fs::read(&self.path)
            .map(|b| String::from_utf8_lossy(&b).into_owned())
            .unwrap_or_default()
    }

    /// An error pointing at the whole source line of `m`.
    fn line_error(&self, m: &Move, message: String, label: &str) -> Error {
        let text = self.text();
        let span = line_span(&text, m.line);
        Error::at(&self.path, &text, span, message, label)
    }

    /// Checks the next move of the program: an error where it is bad input.
    pub fn check(&mut self, m: &Move) -> Result<()> {
        if let (Some((layout, why)), true) = (self.no_tcp, m.tcp) {
            let message = format!(
                "this move runs under tool-centre-point control (TCP), which this machine \
                 ({layout} layout) cannot give: {why}"
            );
            return Err(self
                .line_error(m, message, "TCP on")
                .with_help("leave TCP off on this machine (no G43.4, no `tcp-on` user M code)"));
        }
        if self.written_for_tcp && !m.tcp && matches!(m.motion, Motion::Linear | Motion::Arc { .. })
        {
            let message = "[simulate] tcp = true applies only to programs written for \
                           tool-centre-point control, but this feed move runs in joint space (no \
                           G43.4, G234, M128 or TRAORI active): tcp would read its machine X Y Z \
                           as tool-tip positions and run another motion";
            return Err(self
                .line_error(m, message.to_string(), "joint-space move")
                .with_help(
                    "remove `tcp = true` from [simulate] for a joint-space program, or switch \
                     TCP on before the first feed move",
                ));
        }
        for &(axis, envelope, min, max) in &self.limits {
            let (from, to) = (m.start[axis], m.end[axis]);
            let length = (to - from).abs();
            if to.is_finite() && length <= envelope {
                if length > 1e-9 {
                    self.moving = true;
                }
                continue;
            }
            let text = self.text();
            let span = word_span(&text, m.line, axis);
            if !to.is_finite() {
                return Err(Error::at(
                    &self.path,
                    &text,
                    span,
                    format!("{axis} is not a finite number"),
                    "not finite",
                ));
            }
            let unit = if axis.is_rotary() { "deg" } else { "mm" };
            // A program in mm read as inches is 25.4 times too large.
            let other_unit = if !axis.is_rotary() && length / ngc::MM_PER_INCH <= envelope {
                format!(
                    "; read as mm instead of inches it would be {} mm and fit: check the units \
                     the program is in (G21) or the control starts in ([reader] start_units)",
                    fmt_len(length / ngc::MM_PER_INCH)
                )
            } else {
                String::new()
            };
            return Err(Error::at(
                &self.path,
                &text,
                span,
                format!(
                    "this move takes {axis} {} {unit} (from {} to {}), longer than the machine's \
                     whole {axis} travel of {} {unit} ({} .. {}){other_unit}",
                    fmt_len(length),
                    fmt_len(from),
                    fmt_len(to),
                    envelope,
                    min,
                    max
                ),
                "beyond the travel envelope",
            )
            .with_help(format!(
                "expected {axis} within {min} .. {max} {unit}; check the units (G20 inch / G21 mm) and the digits"
            )));
        }
        Ok(())
    }

    /// The program has ended: an error when none of its moves changed an axis position.
    pub fn end(&self) -> Result<()> {
        if self.moving {
            Ok(())
        } else {
            Err(self.no_motion())
        }
    }

    fn no_motion(&self) -> Error {
        let text = self.text();
        let last = text.trim_end().len();
        Error::at(
            &self.path,
            &text,
            0..last.min(text.find('\n').unwrap_or(last)),
            "the program has no motion: no G00, G01, G02 or G03 move changes an axis position",
            "no motion in this program",
        )
        .with_help(
            "give the scenario a program with moves, or a [program.cone] / [program.circle] table",
        )
    }
}

impl<I, E> Iterator for Checked<I>
where
    I: Iterator<Item = std::result::Result<Move, E>>,
    E: Into<Error>,
{
    type Item = Result<Move>;

    fn next(&mut self) -> Option<Result<Move>> {
        if self.done {
            return None;
        }
        let item = match self.moves.next() {
            Some(Ok(m)) => self.checker.check(&m).map(|()| m),
            Some(Err(e)) => Err(e.into()),
            None => match self.checker.end() {
                Ok(()) => {
                    self.done = true;
                    return None;
                }
                Err(e) => Err(e),
            },
        };
        self.done = item.is_err();
        Some(item)
    }
}

/// The byte range of source line `line` (1-based) of `text`, without its line break.
fn line_span(text: &str, line: usize) -> std::ops::Range<usize> {
    let start = text
        .split_inclusive('\n')
        .take(line.saturating_sub(1))
        .map(str::len)
        .sum::<usize>();
    start..start + text[start..].lines().next().unwrap_or("").len()
}

/// A length without hundreds of digits: 500, 1.0e308.
fn fmt_len(v: f64) -> String {
    if v.abs() < 1e9 {
        format!("{v}")
    } else {
        format!("{v:.1e}")
    }
}
