//! Where a run writes its files: the caller's output folder (each file written atomically;
//! not the command line's swap of the whole folder, whose SIGINT handler would end a
//! Python session on Ctrl-C), or a private temporary folder removed afterwards.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

pub enum Scratch {
    Output(PathBuf),
    Temporary(TempDir),
}

/// A folder removed with everything in it when dropped.
pub struct TempDir(PathBuf);

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

static NEXT: AtomicU64 = AtomicU64::new(0);

impl Scratch {
    pub fn begin(output: Option<&Path>) -> mtsim::Result<Scratch> {
        Ok(match output {
            Some(dir) => {
                mtsim::report::create_dir(dir)?;
                Scratch::Output(dir.to_path_buf())
            }
            None => {
                let n = NEXT.fetch_add(1, Ordering::Relaxed);
                let dir = std::env::temp_dir().join(format!("mtsim-py-{}-{n}", std::process::id()));
                mtsim::report::create_dir(&dir)?;
                Scratch::Temporary(TempDir(dir))
            }
        })
    }

    pub fn path(&self) -> &Path {
        match self {
            Scratch::Output(dir) => dir,
            Scratch::Temporary(dir) => &dir.0,
        }
    }
}
