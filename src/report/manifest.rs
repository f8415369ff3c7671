//! The record of what a run wrote into its output folder: `.mtsim-run.json`.
//!
//! A run's output folder may hold the user's own files beside the run's: notes, a measured
//! trace, a spreadsheet called `batch.xlsx`. Which entries a rerun may replace is never
//! guessed from a name. The run that writes a folder lists, in the manifest, every file it
//! wrote (relative path, size and XXH64 of the bytes) and every folder it made. The next run
//! into that folder treats an entry as the earlier run's own only when
//!
//! ```text
//! owned(file)   = listed(file) ∧ size and XXH64 unchanged ∧ file is no input of this run
//! owned(folder) = listed(folder) ∧ every entry below it is owned (files and folders alike)
//! ```
//!
//! Everything else is the user's and stays where it is, including a file the earlier run
//! wrote and the user has since edited, and an output the user now feeds back in (a measured
//! trace given to `fit`). A folder without a manifest, or with one that does not parse, holds
//! only the user's entries.
//!
//! Format (`serde_json`, keys sorted, no time stamps or absolute paths, so two runs with the
//! same outputs write the same manifest byte for byte):
//!
//! ```json
//! {"mtsim_run": 1,
//!  "files": {"runs/a/summary.json": {"bytes": 812, "xxh64": "5f0c…"}, …},
//!  "folders": ["runs", "runs/a"]}
//! ```

use std::collections::{BTreeMap, BTreeSet};
use std::io::Read;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// The manifest's file name, in the output folder itself.
pub const MANIFEST_FILE: &str = ".mtsim-run.json";
/// The format's version, the value of `mtsim_run`.
pub const FORMAT: u32 = 1;

/// One file a run wrote: its size and the XXH64 (seed 0) of its bytes, 16 hex digits.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct FileRecord {
    pub bytes: u64,
    pub xxh64: String,
}

/// The files (relative paths with `/`) and folders a run wrote into its output folder.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Manifest {
    pub mtsim_run: u32,
    pub files: BTreeMap<String, FileRecord>,
    pub folders: BTreeSet<String>,
}

fn read_error(path: &Path) -> impl FnOnce(std::io::Error) -> Error + '_ {
    move |source| Error::Write {
        path: path.to_path_buf(),
        source,
    }
}

/// The size and XXH64 of the file at `path`, read in 64 KiB pieces (memory stays flat
/// whatever the trace's length).
pub fn record_of(path: &Path) -> std::io::Result<FileRecord> {
    let mut file = std::fs::File::open(path)?;
    let mut hash = xxhash_rust::xxh64::Xxh64::new(0);
    let mut buf = vec![0u8; 64 * 1024];
    let mut bytes = 0u64;
    loop {
        match file.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => {
                hash.update(&buf[..n]);
                bytes += n as u64;
            }
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        }
    }
    Ok(FileRecord {
        bytes,
        xxh64: format!("{:016x}", hash.digest()),
    })
}

/// `rel` joined to `name` with `/` (the manifest's separator on every system).
fn join_rel(rel: &str, name: &str) -> String {
    if rel.is_empty() {
        name.to_string()
    } else {
        format!("{rel}/{name}")
    }
}

impl Manifest {
    /// The manifest of everything in folder `dir` (the staged run), the manifest file itself
    /// left out. Entries that are neither files nor folders (a run writes none) are refused.
    pub fn of_folder(dir: &Path) -> Result<Manifest> {
        let mut manifest = Manifest {
            mtsim_run: FORMAT,
            ..Manifest::default()
        };
        // Folders still to list, as (path, relative name): an explicit stack, so the depth of
        // the tree never becomes the depth of the call stack.
        let mut stack = vec![(dir.to_path_buf(), String::new())];
        while let Some((folder, rel)) = stack.pop() {
            for entry in std::fs::read_dir(&folder).map_err(read_error(&folder))? {
                let entry = entry.map_err(read_error(&folder))?;
                let name = entry.file_name().to_string_lossy().into_owned();
                if rel.is_empty() && name == MANIFEST_FILE {
                    continue;
                }
                let path = entry.path();
                let rel_name = join_rel(&rel, &name);
                let kind = entry.file_type().map_err(read_error(&path))?;
                if kind.is_dir() {
                    manifest.folders.insert(rel_name.clone());
                    stack.push((path, rel_name));
                } else if kind.is_file() {
                    // A file hashed as it was written (the trace) is not read back.
                    let record = match super::written::known_record(&path) {
                        Some(w) => FileRecord {
                            bytes: w.bytes,
                            xxh64: format!("{:016x}", w.xxh64),
                        },
                        None => record_of(&path).map_err(read_error(&path))?,
                    };
                    manifest.files.insert(rel_name, record);
                } else {
                    return Err(Error::Write {
                        path,
                        source: std::io::Error::other("a run writes only files and folders"),
                    });
                }
            }
        }
        Ok(manifest)
    }

    /// The manifest of folder `dir`, or None when it has none or it does not parse (then
    /// nothing in the folder is taken for a run's).
    pub fn read(dir: &Path) -> Option<Manifest> {
        let text = std::fs::read(dir.join(MANIFEST_FILE)).ok()?;
        serde_json::from_slice::<Manifest>(&text)
            .ok()
            .filter(|m| m.mtsim_run == FORMAT)
    }

    /// Writes the manifest into `dir` (temporary file, then rename).
    pub fn write(&self, dir: &Path) -> Result<()> {
        let mut text = serde_json::to_string_pretty(self).map_err(|e| Error::Write {
            path: dir.join(MANIFEST_FILE),
            source: std::io::Error::other(e),
        })?;
        text.push('\n');
        super::write_atomic(&dir.join(MANIFEST_FILE), text.as_bytes())
    }

    /// Whether the top-level entry `name` of `dir` (the folder this manifest describes) is
    /// entirely the run's own: see the module's rule. `inputs` are the canonical paths of
    /// the files the current run reads; none of them is ever the run's.
    pub fn owns(&self, dir: &Path, name: &str, inputs: &BTreeSet<PathBuf>) -> bool {
        if name == MANIFEST_FILE {
            return true;
        }
        let mut stack = vec![(dir.join(name), name.to_string())];
        while let Some((path, rel)) = stack.pop() {
            let Ok(meta) = std::fs::symlink_metadata(&path) else {
                return false;
            };
            if meta.is_file() {
                let unchanged = self.files.get(&rel).is_some_and(|listed| {
                    listed.bytes == meta.len() && record_of(&path).is_ok_and(|r| &r == listed)
                });
                let input = std::fs::canonicalize(&path).is_ok_and(|p| inputs.contains(&p));
                if !unchanged || input {
                    return false;
                }
            } else if meta.is_dir() && self.folders.contains(&rel) {
                let Ok(entries) = std::fs::read_dir(&path) else {
                    return false;
                };
                for entry in entries {
                    let Ok(entry) = entry else { return false };
                    let child = entry.file_name().to_string_lossy().into_owned();
                    stack.push((entry.path(), join_rel(&rel, &child)));
                }
            } else {
                // A link, a device, or a folder the run did not make.
                return false;
            }
        }
        true
    }

    /// Whether the top-level `name` is one this run wrote (a listed file or a folder it made).
    pub fn lists(&self, name: &str) -> bool {
        name == MANIFEST_FILE || self.files.contains_key(name) || self.folders.contains(name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("mtsim-manifest-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn the_record_is_the_size_and_the_xxh64_of_the_bytes() {
        let dir = scratch("record");
        std::fs::write(dir.join("a"), b"abc").unwrap();
        // XXH64("abc", seed 0), from the reference implementation's test vectors.
        assert_eq!(
            record_of(&dir.join("a")).unwrap(),
            FileRecord {
                bytes: 3,
                xxh64: "44bc2cf5ad770999".into()
            }
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn an_edited_file_an_input_and_a_folder_with_a_stranger_are_not_owned() {
        let dir = scratch("owns");
        std::fs::create_dir_all(dir.join("runs/a")).unwrap();
        std::fs::write(dir.join("runs/a/s.json"), b"{}").unwrap();
        std::fs::write(dir.join("trace.csv"), b"t,x\n").unwrap();
        std::fs::write(dir.join("summary.json"), b"{}").unwrap();
        let manifest = Manifest::of_folder(&dir).unwrap();
        assert_eq!(
            manifest.folders.iter().collect::<Vec<_>>(),
            ["runs", "runs/a"]
        );
        let none = BTreeSet::new();
        for name in ["runs", "trace.csv", "summary.json", MANIFEST_FILE] {
            assert!(manifest.owns(&dir, name, &none), "{name}");
        }
        // The trace fed back in as an input is the user's.
        let inputs = BTreeSet::from([std::fs::canonicalize(dir.join("trace.csv")).unwrap()]);
        assert!(!manifest.owns(&dir, "trace.csv", &inputs));
        // Edited since: the user's.
        std::fs::write(dir.join("summary.json"), b"{ }").unwrap();
        assert!(!manifest.owns(&dir, "summary.json", &none));
        // A file the user put inside a run's folder makes the folder the user's.
        std::fs::write(dir.join("runs/k"), b"x").unwrap();
        assert!(!manifest.owns(&dir, "runs", &none));
        // A name not listed at all.
        std::fs::write(dir.join("batch.xlsx"), b"x").unwrap();
        assert!(!manifest.owns(&dir, "batch.xlsx", &none));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_manifest_reads_back_as_written_and_a_foreign_one_as_none() {
        let dir = scratch("read");
        std::fs::write(dir.join("x"), b"1").unwrap();
        let manifest = Manifest::of_folder(&dir).unwrap();
        manifest.write(&dir).unwrap();
        assert_eq!(Manifest::read(&dir), Some(manifest));
        std::fs::write(dir.join(MANIFEST_FILE), b"{\"files\": 3}").unwrap();
        assert_eq!(Manifest::read(&dir), None);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
