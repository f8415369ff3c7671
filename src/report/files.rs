//! Writing outputs: complete or not at all.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// The summary a simulation leaves in its folder (with each ball-bar run's centring, which
/// a reader of `trace.csv` applies).
pub const SUMMARY_FILE: &str = "summary.json";

/// Writes `bytes` to `path` atomically: a temporary file beside it, then a rename, so a
/// reader never sees a partial file and a failure leaves no partial file behind.
///
/// Not synced to disk (no `fsync`), as the traces and the output folder's swap are not:
/// the promise is against a failed or killed run, not a power cut (docs/cli.md).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = temporary_path(path);
    let result = (|| {
        std::fs::File::create(&tmp)?.write_all(bytes)?;
        std::fs::rename(&tmp, path)
    })();
    result.map_err(|source| {
        let _ = std::fs::remove_file(&tmp);
        Error::Write {
            path: path.to_path_buf(),
            source,
        }
    })
}

/// `<path>.tmp`, in the same folder so that the rename stays on one file system.
pub fn temporary_path(path: &Path) -> PathBuf {
    let mut name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(".tmp");
    path.with_file_name(name)
}

/// Creates the folder `dir` and its parents, if missing.
pub fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|source| Error::Write {
        path: dir.to_path_buf(),
        source,
    })
}

/// Removes the temporary files a killed run left in `dir` (`<name>.tmp` and
/// `<stem>.csv.raw.tmp` for each of `outputs`), so that an interrupted run leaves nothing
/// behind once the next run into the same folder starts. Other files are not touched.
pub fn remove_stale_temporaries(dir: &Path, outputs: &[&str]) -> Result<()> {
    for name in outputs {
        let path = dir.join(name);
        let mut candidates = vec![temporary_path(&path)];
        if let Some(ext) = path.extension() {
            let mut raw = ext.to_os_string();
            raw.push(".raw.tmp");
            candidates.push(path.with_extension(raw));
        }
        for tmp in candidates {
            match std::fs::remove_file(&tmp) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                    return Err(Error::Write {
                        path: tmp,
                        source: e,
                    })
                }
                _ => {}
            }
        }
    }
    Ok(())
}
