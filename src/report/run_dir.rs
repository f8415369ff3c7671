//! A folder of outputs written as one unit: staged beside the target, swapped in when complete.
//!
//! A command that writes several files into `-o DIR` writes them into `.DIR.mtsim-new` (same
//! parent, so a rename moves it). Once all are written, the run records them in the folder's
//! manifest ([`Manifest`], `.mtsim-run.json`: names, sizes and hashes). Then the entries of
//! `DIR` that are not the earlier run's own (by the earlier manifest, never by their names:
//! the user's notes, a `shards/` folder, a file the earlier run wrote and the user edited, a
//! measured trace this run reads) are moved into the new folder, and it takes the place of
//! `DIR`: on Linux one `renameat2(RENAME_EXCHANGE)` swaps the two folders, elsewhere `DIR` is
//! renamed to `.DIR.mtsim-old` and the new folder renamed in. The old folder, which then holds
//! only the earlier run's unchanged files, is removed. A reader, or a crash at any instant,
//! sees the old complete run or the new complete run, never a mix. When an entry of the
//! user's has the name of one the run wrote, the run is refused (exit 2) and `DIR` is left as
//! it was. `-o LINK`, a symbolic link to a folder, writes into the folder it names: the link
//! stays.
//!
//! `.DIR.mtsim-lock` holds the writer's pid under an exclusive `flock` (`File::try_lock`):
//! a second run into `DIR` is refused while the first lives, and the OS releases the lock when
//! a run dies, however it dies. The run removes the lock file before it lets go of the lock;
//! a run that locked a file meanwhile removed finds the path no longer names its file (device
//! and inode differ) and starts over, so two runs never hold two files of one name. A crash
//! leaves the file, unlocked: the next run takes it. The run that next holds the lock cleans up
//! after a killed one ([`recover`]): the user's entries (those the staged manifest does not
//! list) go back from `.DIR.mtsim-new` into `DIR`, `.DIR.mtsim-old` goes back as `DIR` if
//! `DIR` is missing, and both are removed. SIGINT and SIGTERM do the same for the running
//! command, then end it as the signal would.

use std::fs::File;
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};

use std::collections::BTreeSet;

use super::manifest::{Manifest, MANIFEST_FILE};
use crate::error::{Error, Result};

/// An output folder being written; [`RunDir::commit`] puts it in place, dropping it without
/// committing removes what was written.
#[derive(Debug)]
pub struct RunDir {
    target: PathBuf,
    staging: PathBuf,
    /// The canonical paths of the files this run reads: never taken for the earlier run's.
    inputs: BTreeSet<PathBuf>,
    _lock: File,
    committed: bool,
}

/// `<parent>/.<name>.mtsim-<what>`.
fn sibling(target: &Path, what: &str) -> PathBuf {
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    target.with_file_name(format!(".{name}.mtsim-{what}"))
}

fn write_error(path: &Path) -> impl FnOnce(std::io::Error) -> Error + '_ {
    move |source| Error::Write {
        path: path.to_path_buf(),
        source,
    }
}

fn exists(path: &Path) -> bool {
    std::fs::symlink_metadata(path).is_ok()
}

/// Removes the file or folder at `path`, if any.
fn remove_any(path: &Path) -> Result<()> {
    let result = match std::fs::symlink_metadata(path) {
        Err(_) => return Ok(()),
        Ok(m) if m.is_dir() => std::fs::remove_dir_all(path),
        Ok(_) => std::fs::remove_file(path),
    };
    match result {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(write_error(path)(e)),
        _ => Ok(()),
    }
}

/// Moves back into `to` the user's entries that an interrupted commit had moved into the
/// staged folder `from`: those its manifest does not list. Without a manifest the commit had
/// not started moving, and every entry is the run's.
fn move_back_user_entries(from: &Path, to: &Path) -> Result<()> {
    let Some(staged) = Manifest::read(from) else {
        return Ok(());
    };
    let Ok(entries) = std::fs::read_dir(from) else {
        return Ok(());
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        if !staged.lists(&name.to_string_lossy()) && !exists(&to.join(&name)) {
            std::fs::rename(entry.path(), to.join(&name)).map_err(write_error(&entry.path()))?;
        }
    }
    Ok(())
}

/// What an interrupted run into `target` left, undone: the user's entries back from the
/// staging folder, the old run back in place if the swap stopped half way, then both
/// leftovers removed.
fn recover(target: &Path) -> Result<()> {
    let (staging, old) = (sibling(target, "new"), sibling(target, "old"));
    if exists(&old) && !exists(target) {
        std::fs::rename(&old, target).map_err(write_error(target))?;
    }
    if exists(target) {
        move_back_user_entries(&staging, target)?;
    }
    remove_any(&old)?;
    remove_any(&staging)
}

/// An exclusive `flock` on the file `lock_path`, created if missing, that the path still names.
fn lock(target: &Path, lock_path: &Path) -> Result<File> {
    loop {
        let mut file = File::options()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(lock_path)
            .map_err(write_error(lock_path))?;
        match file.try_lock() {
            Ok(()) if names_file(lock_path, &file) => return Ok(file),
            Ok(()) => continue, // removed by the run that held it: lock the new file
            Err(std::fs::TryLockError::WouldBlock) => {
                let mut pid = String::new();
                let _ = file.read_to_string(&mut pid);
                // The holder writes its pid just after it locks: it may not be there yet.
                let pid = match pid.trim() {
                    "" => "not yet written",
                    pid => pid,
                };
                return Err(Error::usage(format!(
                    "{} is being written by another mtsim run (pid {pid}); wait for it or choose another -o",
                    target.display()
                )));
            }
            Err(std::fs::TryLockError::Error(source)) => {
                return Err(Error::Write {
                    path: lock_path.to_path_buf(),
                    source,
                })
            }
        }
    }
}

/// Whether `path` names the open `file` (same device and inode).
#[cfg(unix)]
fn names_file(path: &Path, file: &File) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (std::fs::metadata(path), file.metadata()) {
        (Ok(a), Ok(b)) => (a.dev(), a.ino()) == (b.dev(), b.ino()),
        _ => false,
    }
}

#[cfg(not(unix))]
fn names_file(path: &Path, _: &File) -> bool {
    path.exists()
}

/// The lock of an output folder that a command updates in place (`mtsim report` writing
/// `report.html` into a run folder): no run swaps the folder meanwhile. Taking it first
/// cleans up after a killed run, as [`RunDir::begin`] does; dropping it removes the lock file.
#[derive(Debug)]
pub struct FolderLock {
    target: PathBuf,
    _lock: File,
}

/// Locks `target` (`.DIR.mtsim-lock`) and writes this process's pid into the lock file.
fn lock_with_pid(target: &Path) -> Result<File> {
    let lock_path = sibling(target, "lock");
    let mut lock = lock(target, &lock_path)?;
    (|| {
        lock.set_len(0)?;
        lock.rewind()?;
        writeln!(lock, "{}", std::process::id())
    })()
    .map_err(write_error(&lock_path))?;
    Ok(lock)
}

impl FolderLock {
    /// Locks the existing folder `target`; fails (exit 2) while another live run holds it.
    pub fn take(target: &Path) -> Result<FolderLock> {
        let target = &through_links(target)?;
        let lock = FolderLock {
            target: target.to_path_buf(),
            _lock: lock_with_pid(target)?,
        };
        recover(target)?;
        Ok(lock)
    }

    /// Refuses (exit 2) to write the file `name` into the folder when one of the user's
    /// stands there: one that the folder's manifest does not list as it is now.
    pub fn may_write(&self, name: &str) -> Result<()> {
        let path = self.target.join(name);
        let earlier = Manifest::read(&self.target).unwrap_or_default();
        if !exists(&path) || earlier.owns(&self.target, name, &BTreeSet::new()) {
            return Ok(());
        }
        Err(Error::usage(format!(
            "{}: not written by an mtsim run (the folder's {MANIFEST_FILE} does not list it as it is now); nothing was changed: move it away or write the run again with --html",
            path.display()
        )))
    }

    /// Adds the file `name`, just written into the folder, to its manifest.
    pub fn record(&self, name: &str) -> Result<()> {
        let mut manifest = Manifest::read(&self.target).unwrap_or_default();
        let path = self.target.join(name);
        let record = super::manifest::record_of(&path).map_err(write_error(&path))?;
        manifest.mtsim_run = super::manifest::FORMAT;
        manifest.files.insert(name.to_string(), record);
        manifest.write(&self.target)
    }
}

impl Drop for FolderLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(sibling(&self.target, "lock"));
    }
}

/// The folder a chain of symbolic links at `target` ends in (`target` itself when it is no
/// link), so that a run writes through `-o LINK` and leaves the link in place.
fn through_links(target: &Path) -> Result<PathBuf> {
    let mut path = target.to_path_buf();
    // As many links as the kernel follows (ELOOP past 40).
    for _ in 0..40 {
        match std::fs::symlink_metadata(&path) {
            Ok(m) if m.file_type().is_symlink() => {
                let next = std::fs::read_link(&path).map_err(write_error(&path))?;
                path = match path.parent() {
                    Some(parent) if next.is_relative() => parent.join(next),
                    _ => next,
                };
            }
            _ => return Ok(path),
        }
    }
    Err(Error::usage(format!(
        "-o {}: a loop of symbolic links; name a folder",
        target.display()
    )))
}

impl RunDir {
    /// Locks `target` for this run, cleans up after a killed run and creates the empty
    /// staging folder. Fails (exit 2) when another live run holds the lock or when `target`
    /// is not a folder. A `target` that is a symbolic link stands for the folder it names.
    pub fn begin(target: &Path) -> Result<RunDir> {
        if target.file_name().is_none() || target.as_os_str() == "." {
            return Err(Error::usage(format!(
                "-o {}: name the output folder (a run writes it whole, beside its parent's other entries)",
                target.display()
            )));
        }
        let target = &through_links(target)?;
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        super::create_dir(parent)?;
        let lock = lock_with_pid(target)?;
        // From here on, dropping `run_dir` undoes what was done and removes the lock file.
        let run_dir = RunDir {
            target: target.to_path_buf(),
            staging: sibling(target, "new"),
            inputs: BTreeSet::new(),
            _lock: lock,
            committed: false,
        };
        recover(target)?;
        if std::fs::metadata(target).is_ok_and(|m| !m.is_dir()) {
            return Err(Error::usage(format!(
                "-o {}: a file, not a folder",
                target.display()
            )));
        }
        // Watched before it exists: a signal from here on finds it to remove.
        signals::watch(target);
        super::create_dir(&run_dir.staging)?;
        Ok(run_dir)
    }

    /// Records the files this run reads (scenarios, measured traces, shards): whatever an
    /// earlier manifest says of them, they stay in the folder as the user's.
    pub fn reads<P: AsRef<Path>>(mut self, inputs: &[P]) -> RunDir {
        for input in inputs {
            if let Ok(path) = std::fs::canonicalize(input) {
                self.inputs.insert(path);
            }
        }
        self
    }

    /// The folder to write the run's files into.
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// The top-level entries of the target that are not the earlier run's own (by its
    /// manifest), to be kept; refused when one has the name of an entry this run wrote.
    fn users_entries(&self, staged: &Manifest) -> Result<Vec<std::ffi::OsString>> {
        let target = &self.target;
        let earlier = Manifest::read(target).unwrap_or_default();
        let entries = std::fs::read_dir(target).map_err(write_error(target))?;
        let (mut keep, mut clashes) = (Vec::new(), Vec::new());
        for entry in entries {
            let name = entry.map_err(write_error(target))?.file_name();
            let text = name.to_string_lossy();
            if earlier.owns(target, &text, &self.inputs) {
                continue;
            }
            if staged.lists(&text) {
                clashes.push(text.into_owned());
            } else {
                keep.push(name);
            }
        }
        if clashes.is_empty() {
            return Ok(keep);
        }
        Err(Error::usage(format!(
            "-o {}: {} {} not written by an earlier mtsim run (the folder's {MANIFEST_FILE} does not list {} as it is now), and this run writes the same {}; nothing was changed: move {} away or choose another -o",
            target.display(),
            clashes.join(", "),
            if clashes.len() == 1 { "is" } else { "are" },
            if clashes.len() == 1 { "it" } else { "them" },
            if clashes.len() == 1 { "name" } else { "names" },
            if clashes.len() == 1 { "it" } else { "them" },
        )))
    }

    /// Records what the run wrote in its manifest, then puts the written folder, with the
    /// user's entries of the old one, in place of the target and removes the old run's own
    /// files. Refused (exit 2, the target untouched) when an entry of the user's has the name
    /// of one the run wrote.
    pub fn commit(mut self) -> Result<()> {
        let staged = Manifest::of_folder(&self.staging)?;
        staged.write(&self.staging)?;
        let target = &self.target;
        if !exists(target) {
            std::fs::rename(&self.staging, target).map_err(write_error(target))?;
        } else {
            for name in self.users_entries(&staged)? {
                let (from, to) = (target.join(&name), self.staging.join(&name));
                std::fs::rename(&from, &to).map_err(write_error(&from))?;
            }
            if exchange(&self.staging, target).is_err() {
                let old = sibling(target, "old");
                std::fs::rename(target, &old).map_err(write_error(&old))?;
                std::fs::rename(&self.staging, target).map_err(write_error(target))?;
            }
        }
        // Now only the old run's own files are left beside it, to be removed. The target stays
        // watched until the lock file is gone (in `drop`): a signal meanwhile removes it too.
        self.committed = true;
        remove_any(&self.staging)?;
        remove_any(&sibling(target, "old"))
    }
}

impl Drop for RunDir {
    /// Cleans up an unfinished run; removes the lock file while the lock is still held.
    fn drop(&mut self) {
        if !self.committed {
            let _ = recover(&self.target);
        }
        let _ = std::fs::remove_file(sibling(&self.target, "lock"));
        signals::unwatch(&self.target);
    }
}

/// Swaps the folders `a` and `b` in one step (Linux `renameat2(RENAME_EXCHANGE)`).
#[cfg(any(target_os = "linux", target_os = "android"))]
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    use rustix::fs::{renameat_with, RenameFlags, CWD};
    renameat_with(CWD, a, CWD, b, RenameFlags::EXCHANGE).map_err(std::io::Error::from)
}

#[cfg(not(any(target_os = "linux", target_os = "android")))]
fn exchange(_: &Path, _: &Path) -> std::io::Result<()> {
    Err(std::io::ErrorKind::Unsupported.into())
}

/// SIGINT and SIGTERM while a run writes: its target is recovered ([`recover`]), then the signal's
/// default action ends the process (so the exit status says which signal). The handler only
/// writes the signal number to a pipe (async-signal-safe); a thread reads it and cleans up.
#[cfg(unix)]
mod signals {
    use std::path::{Path, PathBuf};
    use std::sync::atomic::{AtomicI32, Ordering};
    use std::sync::{Mutex, Once};

    /// The targets being written.
    static TARGETS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
    static PIPE_WRITE: AtomicI32 = AtomicI32::new(-1);
    static INSTALL: Once = Once::new();

    extern "C" fn on_signal(signal: libc::c_int) {
        let byte = signal as u8;
        let fd = PIPE_WRITE.load(Ordering::Relaxed);
        // SAFETY: write(2) is async-signal-safe; the buffer is one live byte.
        unsafe { libc::write(fd, (&byte as *const u8).cast(), 1) };
    }

    /// Milliseconds the staging folder must stay gone before the process ends.
    const QUIET_MS: u32 = 20;

    /// [`super::recover`] of `target`, again whenever the run, which goes on writing until
    /// the process ends, creates its staging folder anew (a run that had not yet reached
    /// its first file creates the folder it writes into), until the folder has stayed gone
    /// for [`QUIET_MS`] (at most a second in all).
    fn recover_while_the_run_goes_on(target: &Path) {
        let staging = super::sibling(target, "new");
        let (mut quiet, mut waited) = (0, 0);
        while quiet < QUIET_MS && waited < 1000 {
            if super::exists(&staging) || waited == 0 {
                // A file the run is creating meanwhile can make one pass fail.
                for _ in 0..3 {
                    if super::recover(target).is_ok() {
                        break;
                    }
                }
                quiet = 0;
            } else {
                quiet += 1;
            }
            std::thread::sleep(std::time::Duration::from_millis(1));
            waited += 1;
        }
    }

    fn install() {
        let mut fds = [0 as libc::c_int; 2];
        // SAFETY: pipe(2) fills the two descriptors of the array it is given.
        if unsafe { libc::pipe(fds.as_mut_ptr()) } != 0 {
            return;
        }
        PIPE_WRITE.store(fds[1], Ordering::Relaxed);
        let read_fd = fds[0];
        let spawned = std::thread::Builder::new()
            .name("mtsim-signals".into())
            .spawn(move || {
                let mut byte = 0u8;
                // SAFETY: reads one byte into a live local from the pipe this thread owns.
                while unsafe { libc::read(read_fd, (&mut byte as *mut u8).cast(), 1) } != 1 {}
                let targets = TARGETS.lock().unwrap_or_else(|e| e.into_inner());
                for target in targets.iter() {
                    recover_while_the_run_goes_on(target);
                    let _ = std::fs::remove_file(super::sibling(target, "lock"));
                }
                // SAFETY: back to the default action, then the signal again: the process
                // ends as if it had not been caught.
                unsafe {
                    libc::signal(byte as libc::c_int, libc::SIG_DFL);
                    libc::raise(byte as libc::c_int);
                }
            });
        if spawned.is_err() {
            return;
        }
        for signal in [libc::SIGINT, libc::SIGTERM] {
            // SAFETY: the handler only loads an atomic and calls write(2).
            unsafe { libc::signal(signal, on_signal as *const () as libc::sighandler_t) };
        }
    }

    pub fn watch(target: &Path) {
        INSTALL.call_once(install);
        let mut targets = TARGETS.lock().unwrap_or_else(|e| e.into_inner());
        targets.push(target.to_path_buf());
    }

    pub fn unwatch(target: &Path) {
        let mut targets = TARGETS.lock().unwrap_or_else(|e| e.into_inner());
        targets.retain(|d| d != target);
    }
}

#[cfg(not(unix))]
mod signals {
    use std::path::Path;
    pub fn watch(_: &Path) {}
    pub fn unwatch(_: &Path) {}
}
