//! A Sinumerik program's text, read one line at a byte offset: the main program streamed
//! from its file through a fixed buffer, a subprogram read whole as a bounded side file.

use std::io::{BufRead, BufReader, Read, Seek, SeekFrom};
use std::path::Path;
use std::rc::Rc;

use crate::side_file::MAX_LINE_BYTES;

/// Read buffer of a streamed program file, bytes.
const BUFFER_BYTES: usize = 64 * 1024;

/// The text of one program level.
pub(super) enum Source {
    Text(Rc<str>),
    File {
        reader: BufReader<std::fs::File>,
        /// Byte offset of the next unread byte.
        pos: u64,
        /// The line's bytes, the allocation kept from line to line.
        bytes: Vec<u8>,
    },
}

impl Source {
    /// The regular file at `path`, streamed.
    pub fn open(path: &Path) -> std::io::Result<Source> {
        let file = crate::side_file::open_regular(path)?;
        Ok(Source::File {
            reader: BufReader::with_capacity(BUFFER_BYTES, file),
            pos: 0,
            bytes: Vec::new(),
        })
    }

    /// Reads the line at byte `offset` into `buf` (without its line end; invalid UTF-8
    /// replaced); returns the bytes it takes, 0 at the end of the text.
    pub fn line(&mut self, offset: usize, buf: &mut String) -> std::io::Result<usize> {
        buf.clear();
        match self {
            Source::Text(text) => {
                let rest = text.get(offset..).unwrap_or("");
                let (line, len) = match rest.find('\n') {
                    Some(n) => (&rest[..n], n + 1),
                    None => (rest, rest.len()),
                };
                buf.push_str(line.strip_suffix('\r').unwrap_or(line));
                Ok(len)
            }
            Source::File { reader, pos, bytes } => {
                if offset as u64 != *pos {
                    // Within the buffer for a short jump back (a loop), a seek otherwise.
                    let by = offset as i64 - *pos as i64;
                    if reader.seek_relative(by).is_err() {
                        reader.seek(SeekFrom::Start(offset as u64))?;
                    }
                    *pos = offset as u64;
                }
                bytes.clear();
                let n = reader
                    .by_ref()
                    .take(MAX_LINE_BYTES as u64 + 2)
                    .read_until(b'\n', bytes)?;
                if n > MAX_LINE_BYTES + 1 {
                    return Err(std::io::Error::new(
                        std::io::ErrorKind::InvalidData,
                        format!("a line longer than {MAX_LINE_BYTES} bytes: expected NC blocks"),
                    ));
                }
                *pos += n as u64;
                while matches!(bytes.last(), Some(b'\n' | b'\r')) {
                    bytes.pop();
                }
                match std::str::from_utf8(bytes) {
                    Ok(text) => buf.push_str(text),
                    Err(_) => buf.push_str(&String::from_utf8_lossy(bytes)),
                }
                Ok(n)
            }
        }
    }
}
