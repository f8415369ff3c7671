//! Files hashed as they are written: the manifest's record of a large file (the trace)
//! without reading it back.
//!
//! [`Hashing`] wraps a writer and keeps the size and XXH64 of every byte that reached it;
//! [`note`] lists a finished file's record in this process, under its path, with the size
//! and modification time the file had then; [`known_record`] gives it back for as long as
//! the file still has them (any later write changes the size or the time, and the file is
//! then hashed again from its bytes by the manifest's `record_of`).

use std::collections::BTreeMap;
use std::io::{IoSlice, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::SystemTime;

use xxhash_rust::xxh64::Xxh64;

/// What was written to a file: its size and the XXH64 (seed 0) of its bytes (the manifest's
/// `FileRecord`, which this module does not import: the manifest imports it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Written {
    pub bytes: u64,
    pub xxh64: u64,
}

/// A writer that hashes (XXH64, seed 0) and counts the bytes it passes on.
pub struct Hashing<W> {
    inner: W,
    hash: Xxh64,
    bytes: u64,
}

impl<W> Hashing<W> {
    pub fn new(inner: W) -> Hashing<W> {
        Hashing {
            inner,
            hash: Xxh64::new(0),
            bytes: 0,
        }
    }

    /// The record of the bytes passed on so far.
    pub fn record(&self) -> Written {
        Written {
            bytes: self.bytes,
            xxh64: self.hash.digest(),
        }
    }

    pub fn get_ref(&self) -> &W {
        &self.inner
    }
}

impl<W: Write> Write for Hashing<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.hash.update(&buf[..n]);
        self.bytes += n as u64;
        Ok(n)
    }

    fn write_vectored(&mut self, bufs: &[IoSlice<'_>]) -> std::io::Result<usize> {
        let n = self.inner.write_vectored(bufs)?;
        // Only the first `n` bytes of the slices were taken.
        let mut left = n;
        for b in bufs {
            if left == 0 {
                break;
            }
            let take = left.min(b.len());
            self.hash.update(&b[..take]);
            left -= take;
        }
        self.bytes += n as u64;
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// A noted file: its record, and the size and modification time it had when noted.
struct Noted {
    record: Written,
    len: u64,
    modified: SystemTime,
}

static NOTED: Mutex<BTreeMap<PathBuf, Noted>> = Mutex::new(BTreeMap::new());

/// Notes `record` as that of the finished file at `path` (its bytes all written, renamed in
/// place). Nothing is noted when the file's size is not the record's.
pub fn note(path: &Path, record: Written) {
    let Ok(meta) = std::fs::metadata(path) else {
        return;
    };
    let (len, Ok(modified)) = (meta.len(), meta.modified()) else {
        return;
    };
    if len != record.bytes {
        return;
    }
    if let Ok(mut noted) = NOTED.lock() {
        noted.insert(
            path.to_path_buf(),
            Noted {
                record,
                len,
                modified,
            },
        );
    }
}

/// The record noted for the file at `path`, if it still has the size and modification
/// time it had when noted.
pub fn known_record(path: &Path) -> Option<Written> {
    let meta = std::fs::metadata(path).ok()?;
    let modified = meta.modified().ok()?;
    let noted = NOTED.lock().ok()?;
    let n = noted.get(path)?;
    (n.len == meta.len() && n.modified == modified).then_some(n.record)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_record_as_written_is_the_record_read_back_until_the_file_changes() {
        let dir = std::env::temp_dir().join(format!("mtsim-written-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.csv");
        let mut w = Hashing::new(std::fs::File::create(&path).unwrap());
        // Plain and vectored writes, an empty slice among them.
        w.write_all(b"abc").unwrap();
        let (a, b) = (vec![7u8; 100_000], vec![]);
        let mut slices = [IoSlice::new(&a), IoSlice::new(&b), IoSlice::new(b"\n")];
        let mut left = 100_001;
        let mut slices = &mut slices[..];
        while left > 0 {
            let n = w.write_vectored(slices).unwrap();
            left -= n;
            IoSlice::advance_slices(&mut slices, n);
        }
        w.flush().unwrap();
        let record = w.record();
        drop(w);
        // The file's bytes read back, hashed at once.
        let bytes = std::fs::read(&path).unwrap();
        let read = Written {
            bytes: bytes.len() as u64,
            xxh64: xxhash_rust::xxh64::xxh64(&bytes, 0),
        };
        assert_eq!(record, read);
        assert_eq!(read.bytes, 100_004);
        note(&path, record);
        assert_eq!(known_record(&path), Some(record));
        // Rewritten since: no longer known.
        std::thread::sleep(std::time::Duration::from_millis(20));
        std::fs::write(&path, vec![b'x'; 100_004]).unwrap();
        assert_eq!(known_record(&path), None);
        assert_eq!(known_record(&dir.join("other")), None);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
