//! Files the reader opens besides text it is given: the program and subroutine files it
//! streams, and the side files (tool table, parameter file, LinuxCNC INI) it reads whole.
//! Only regular files are opened, and a side file only up to [`MAX_SIDE_FILE_BYTES`].

use std::io::{Error, ErrorKind, Read};
use std::path::Path;

/// Longest line of a program or subroutine file, bytes (1 MiB): no G-code line comes near
/// it, and a file without newlines (`/dev/zero`, a binary) stops here instead of growing
/// the line buffer without end.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// Largest side file read, bytes (64 MiB): a tool table, parameter file or INI of a real
/// machine is a few kB.
pub const MAX_SIDE_FILE_BYTES: u64 = 64 << 20;

/// Opens the regular file at `path` (after following links). Any other kind of file is
/// refused before it is opened: a device such as `/dev/zero` never ends, and opening a
/// FIFO waits for a writer.
pub fn open_regular(path: &Path) -> std::io::Result<std::fs::File> {
    if !std::fs::metadata(path)?.is_file() {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            "not a regular file (a device, FIFO or folder)",
        ));
    }
    std::fs::File::open(path)
}

/// The bytes of the side file at `path`; a file that is not regular or is larger than
/// [`MAX_SIDE_FILE_BYTES`] is refused before its content is read.
pub fn read_side_bytes(path: &Path) -> std::io::Result<Vec<u8>> {
    let file = open_regular(path)?;
    let too_large = || {
        Error::new(
            ErrorKind::InvalidData,
            format!("larger than {} MiB", MAX_SIDE_FILE_BYTES >> 20),
        )
    };
    if file.metadata()?.len() > MAX_SIDE_FILE_BYTES {
        return Err(too_large());
    }
    // The limit holds even for a file that grows while it is read.
    let mut bytes = Vec::new();
    file.take(MAX_SIDE_FILE_BYTES + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > MAX_SIDE_FILE_BYTES {
        return Err(too_large());
    }
    Ok(bytes)
}

/// The text of the side file at `path` ([`read_side_bytes`]), invalid UTF-8 replaced.
pub fn read_side_file(path: &Path) -> std::io::Result<String> {
    Ok(match String::from_utf8(read_side_bytes(path)?) {
        Ok(text) => text,
        Err(e) => String::from_utf8_lossy(e.as_bytes()).into_owned(),
    })
}
