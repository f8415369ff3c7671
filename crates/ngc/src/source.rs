//! Program text as lines: a program in memory or a file streamed through a fixed buffer,
//! read a line at a byte offset (so jumps seek back); and the error that quotes a place in
//! it. Both front ends (the G-code reader and the Klartext one) read through it.

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::rc::Rc;

use crate::byte_words::{below_first, bytes_equal, first_byte, load, HIGHS};
use crate::error::{line_column, Error, Syntax};
use crate::lex::LineError;

/// Read buffer of a streamed program file, bytes.
pub(crate) const FILE_BUFFER_BYTES: usize = 64 * 1024;

/// Longest line of a program or subroutine file, bytes (1 MiB): no G-code line comes near
/// it, and a file without newlines (`/dev/zero`, a binary) stops here instead of growing
/// the line buffer without end.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// Largest program file whose whole text an error message quotes, bytes (64 MiB); beyond
/// it the message quotes the offending line alone.
const MAX_QUOTED_FILE_BYTES: u64 = 64 << 20;

/// A place in one of a front end's loaded program texts: which text, the byte offset of a
/// line's start, and that line's 1-based number.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Cursor {
    pub(crate) file: usize,
    /// Byte offset of the line start.
    pub(crate) offset: usize,
    /// 1-based line number of the line at `offset`.
    pub(crate) line: usize,
}

/// The text of a program: in memory (a string), or a file (the program, a subroutine file)
/// read line by line at byte offsets.
pub(crate) enum Source {
    Text(Rc<str>),
    File(FileLines),
}

impl Source {
    /// The line at byte `offset` (without its `\n` or `\r\n`, a file's line read into
    /// `buf`) and the bytes it takes; `None` at the end of the text.
    #[inline(always)]
    pub(crate) fn line<'a>(
        &'a mut self,
        offset: usize,
        buf: &'a mut String,
    ) -> std::io::Result<Option<(&'a str, usize)>> {
        Ok(match self {
            Source::Text(text) => {
                if offset >= text.len() {
                    return Ok(None);
                }
                let rest = &text[offset..];
                let (raw, len) = match newline(rest.as_bytes()) {
                    Some(n) => (&rest[..n], n + 1),
                    None => (rest, rest.len()),
                };
                Some((raw.strip_suffix('\r').unwrap_or(raw), len))
            }
            Source::File(f) => match f.read_line(offset, buf)? {
                0 => None,
                len => Some((buf.as_str(), len)),
            },
        })
    }

    /// The whole text, for an error message (a file is read again, up to
    /// `MAX_QUOTED_FILE_BYTES`); `None` when it cannot be.
    pub(crate) fn quoted(&self, path: &Path) -> Option<String> {
        match self {
            Source::Text(text) => Some(text.to_string()),
            Source::File(f) => {
                let bytes = (f.len <= MAX_QUOTED_FILE_BYTES)
                    .then(|| std::fs::read(path).ok())
                    .flatten()?;
                Some(match String::from_utf8(bytes) {
                    Ok(t) => t,
                    Err(e) => String::from_utf8_lossy(e.as_bytes()).into_owned(),
                })
            }
        }
    }
}

/// A program file read through a buffer; `pos` is the byte offset of the next unread byte.
pub(crate) struct FileLines {
    reader: BufReader<std::fs::File>,
    pos: u64,
    pub(crate) len: u64,
}

impl FileLines {
    /// Opens the regular file at `path` for streaming (see [`crate::side_file::open_regular`]).
    pub(crate) fn open(path: &Path) -> std::io::Result<FileLines> {
        let file = crate::side_file::open_regular(path)?;
        let len = file.metadata()?.len();
        Ok(FileLines {
            reader: BufReader::with_capacity(FILE_BUFFER_BYTES, file),
            pos: 0,
            len,
        })
    }

    /// Reads the line at byte `offset` into `buf` (without its `\n` or `\r\n`; invalid
    /// UTF-8 replaced); returns the bytes it takes in the file, 0 at the end.
    fn read_line(&mut self, offset: usize, buf: &mut String) -> std::io::Result<usize> {
        let offset = offset as u64;
        if offset != self.pos {
            // Within the buffer when jumping back a little (a loop), a real seek otherwise.
            self.reader.seek_relative(offset as i64 - self.pos as i64)?;
            self.pos = offset;
        }
        // The line is read into `buf`'s own bytes, in place (docs/performance.md).
        // SAFETY: `buf` holds UTF-8 again before this returns: on an error it is emptied,
        // and the bytes read are checked (or replaced) below.
        let bytes = unsafe { buf.as_mut_vec() };
        bytes.clear();
        let (mut n, mut ascii) = (0, true);
        loop {
            let available = match self.reader.fill_buf() {
                Ok(available) => available,
                Err(e) => {
                    bytes.clear();
                    return Err(e);
                }
            };
            if available.is_empty() {
                break;
            }
            let (found, ascii_before) = newline_ascii(available);
            ascii &= ascii_before;
            let (take, end) = match found {
                Some(k) => (k + 1, true),
                None => (available.len(), false),
            };
            if n + take > MAX_LINE_BYTES + 2 {
                bytes.clear();
                return Err(std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    format!("a line longer than {MAX_LINE_BYTES} bytes: expected G-code lines"),
                ));
            }
            bytes.extend_from_slice(&available[..take]);
            self.reader.consume(take);
            n += take;
            if end {
                break;
            }
        }
        self.pos += n as u64;
        if bytes.last() == Some(&b'\n') {
            bytes.pop();
            if bytes.last() == Some(&b'\r') {
                bytes.pop();
            }
        }
        // ASCII is UTF-8; a G-code line nearly always is, found in the newline's search.
        if !ascii && std::str::from_utf8(bytes).is_err() {
            let valid = String::from_utf8_lossy(bytes).into_owned();
            *buf = valid;
        }
        Ok(n)
    }
}

/// The index of the first `\n` in `bytes`, 8 bytes at a time ([`crate::byte_words`]; see
/// docs/performance.md for `memchr`).
#[inline]
pub(crate) fn newline(bytes: &[u8]) -> Option<usize> {
    let mut chunks = bytes.chunks_exact(8);
    let mut i = 0;
    for chunk in &mut chunks {
        let found = bytes_equal(load(chunk), b'\n');
        if found != 0 {
            return Some(i + first_byte(found));
        }
        i += 8;
    }
    chunks
        .remainder()
        .iter()
        .position(|&b| b == b'\n')
        .map(|k| i + k)
}

/// [`newline`], and whether the bytes before the `\n` (all of them, without one) are
/// ASCII: their high bits, read from the same words (exact, no borrow).
#[inline]
pub(crate) fn newline_ascii(bytes: &[u8]) -> (Option<usize>, bool) {
    let mut chunks = bytes.chunks_exact(8);
    let (mut i, mut high) = (0, 0u64);
    for chunk in &mut chunks {
        let w = load(chunk);
        let found = bytes_equal(w, b'\n');
        if found != 0 {
            let before = high | below_first(w & HIGHS, found);
            return (Some(i + first_byte(found)), before == 0);
        }
        high |= w & HIGHS;
        i += 8;
    }
    for (k, &b) in chunks.remainder().iter().enumerate() {
        if b == b'\n' {
            return (Some(i + k), high == 0);
        }
        high |= (b & 0x80) as u64;
    }
    (None, high == 0)
}

/// A syntax error at `err.span` of the line starting at byte `start` of `text`, the text of
/// the program at `path`.
pub(crate) fn syntax_error(path: &Path, text: String, start: usize, err: LineError) -> Error {
    let mut span = start + err.span.start..start + err.span.end;
    span.end = span.end.min(text.len());
    span.start = span.start.min(span.end);
    // Keep the span on character boundaries (a label may end inside `é`).
    while !text.is_char_boundary(span.start) {
        span.start -= 1;
    }
    while !text.is_char_boundary(span.end) {
        span.end += 1;
    }
    let (line, column) = line_column(&text, span.start);
    Error::Syntax(Box::new(Syntax {
        path: path.to_path_buf(),
        line,
        column,
        message: err.message,
        label: err.label,
        help: err.help,
        text,
        span,
    }))
}

/// The text quoted by an error at 1-based `line` (`text`, the whole program, when it could
/// be read) and the byte offset of that line in it; without the program, `line_text` alone
/// at its own line number.
pub(crate) fn quoted_at(text: Option<String>, line: usize, line_text: &str) -> (String, usize) {
    match text {
        Some(text) => {
            let start = if line <= 1 {
                0
            } else {
                text.bytes()
                    .enumerate()
                    .filter(|&(_, b)| b == b'\n')
                    .nth(line - 2)
                    .map_or(text.len(), |(i, _)| i + 1)
            };
            (text, start)
        }
        None => {
            let mut text = "\n".repeat(line.saturating_sub(1));
            let start = text.len();
            text.push_str(line_text);
            (text, start)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::newline_ascii;

    /// The first `\n` of every short text of a `\n`, a byte above 0x7f and filler (bytes
    /// next to them), and whether all before it are ASCII, as a byte loop finds them.
    #[test]
    fn a_line_ends_at_its_first_newline_with_its_ascii_test_before_it() {
        let filler = [b'\x0b', b'\x09', b'X', b'\x7f', b'0'];
        for len in 0..=20 {
            for a in 0..len.max(1) {
                for b in 0..len.max(1) {
                    for (ca, cb) in [(b'\n', 0x80), (0x80, b'\n'), (b'\n', b'\n'), (0xff, 0xc3)] {
                        let mut text: Vec<u8> = (0..len).map(|k| filler[k % 5]).collect();
                        if len > 0 {
                            text[a] = ca;
                            text[b] = cb;
                        }
                        let end = text.iter().position(|&c| c == b'\n');
                        let ascii = text[..end.unwrap_or(len)].is_ascii();
                        assert_eq!(newline_ascii(&text), (end, ascii), "{text:?}");
                    }
                }
            }
        }
    }
}
