//! What the command line prints besides its results: warnings, notes and detail on stderr
//! (quiet with `--quiet`, more with `-v`), progress bars and spinners on a terminal, and
//! results on stdout.

use std::io::{IsTerminal, Write};

/// `--quiet` and `-v`, for the whole process ([`set_flags`]).
static QUIET: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);
static VERBOSE: std::sync::atomic::AtomicU8 = std::sync::atomic::AtomicU8::new(0);

/// Whether `--quiet` was given.
pub(crate) fn quiet() -> bool {
    QUIET.load(std::sync::atomic::Ordering::Relaxed)
}

/// The `-v` count.
pub(crate) fn verbosity() -> u8 {
    VERBOSE.load(std::sync::atomic::Ordering::Relaxed)
}

/// A warning on stderr, unless `--quiet`.
pub(crate) fn warn(text: &str) {
    if !quiet() {
        eprintln!("warning: {text}");
    }
}

/// A note on stderr (which files were written), unless `--quiet`.
pub(crate) fn note(text: &str) {
    if !quiet() {
        eprintln!("{text}");
    }
}

/// Detail on stderr with `-v` (level 1) or `-vv` (level 2).
pub(crate) fn detail(level: u8, text: &str) {
    if verbosity() >= level && !quiet() {
        eprintln!("{text}");
    }
}

/// Sets `--quiet` and the `-v` count for the whole process.
pub(crate) fn set_flags(quiet: bool, verbose: u8) {
    QUIET.store(quiet, std::sync::atomic::Ordering::Relaxed);
    VERBOSE.store(verbose, std::sync::atomic::Ordering::Relaxed);
}

/// A progress bar on stderr when it is a terminal; hidden otherwise (scripts, CI).
pub fn progress_bar(len: u64, what: &str) -> indicatif::ProgressBar {
    if quiet() || !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len);
    if let Ok(style) = indicatif::ProgressStyle::with_template(&format!(
        "{what} {{bar:40}} {{pos}}/{{len}} {{eta}}"
    )) {
        bar.set_style(style);
    }
    bar
}

/// Prints to stdout; a closed pipe (`| head`) ends quietly instead of panicking.
pub(crate) fn print_stdout(text: &str) {
    let mut out = std::io::stdout().lock();
    let _ = out.write_all(text.as_bytes()).and_then(|_| out.flush());
}

/// A spinner on stderr when it is a terminal; hidden otherwise.
pub(crate) fn spinner(what: &str) -> indicatif::ProgressBar {
    if quiet() || !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new_spinner();
    bar.set_prefix(what.to_string());
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{spinner} {prefix}: {msg} [{elapsed}]")
    {
        bar.set_style(style);
    }
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    bar
}
