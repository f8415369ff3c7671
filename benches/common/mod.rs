//! What the benches share: the CPU time of this thread and of child processes, and the
//! project's root. Each bench uses a part of it.

#![allow(dead_code)]

use std::path::PathBuf;
use std::time::Instant;

/// The project's root folder (where `scenarios/` and `machines/` are).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// CPU time of the calling thread, s (`/proc/thread-self/schedstat`, ns on the CPU); falls
/// back to wall time where that file does not exist.
pub fn cpu_now() -> f64 {
    static START: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|t| t.split_whitespace().next()?.parse::<f64>().ok())
        .map(|ns| ns * 1e-9)
        .unwrap_or_else(|| START.get_or_init(Instant::now).elapsed().as_secs_f64())
}

/// CPU time (user + system) of this process's waited-for children, s (`getrusage`, to the
/// microsecond: `/proc/self/stat` counts 10 ms ticks, too coarse for one 40 ms run).
pub fn children_cpu_s() -> Option<f64> {
    #[cfg(unix)]
    {
        let mut usage = std::mem::MaybeUninit::<libc::rusage>::zeroed();
        // SAFETY: getrusage fills the struct it is handed, and returns 0 when it did.
        if unsafe { libc::getrusage(libc::RUSAGE_CHILDREN, usage.as_mut_ptr()) } != 0 {
            return None;
        }
        // SAFETY: filled above (and zeroed before: every field is an integer).
        let usage = unsafe { usage.assume_init() };
        let s = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
        Some(s(usage.ru_utime) + s(usage.ru_stime))
    }
    #[cfg(not(unix))]
    None
}

/// Median CPU time of one whole `mtsim` process with `args`, s, over `runs` runs (one run
/// slowed by a burst of other load on the host does not move it); its stdout is
/// discarded. None where the children's CPU time cannot be read.
#[allow(dead_code)] // not every bench runs whole processes
pub fn process_cpu_s(args: &[&std::ffi::OsStr], runs: usize) -> Option<f64> {
    median_cpu_s(runs, || {
        let status = std::process::Command::new(env!("CARGO_BIN_EXE_mtsim"))
            .args(args)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .status()
            .expect("mtsim runs");
        assert!(status.success(), "mtsim {args:?} failed");
    })
}

/// Median, over `runs` calls of `run`, of the CPU time of the child processes each call
/// waits for, s.
#[allow(dead_code)] // not every bench runs whole processes
pub fn median_cpu_s(runs: usize, mut run: impl FnMut()) -> Option<f64> {
    let mut times = Vec::with_capacity(runs);
    for _ in 0..runs.max(1) {
        let start = children_cpu_s()?;
        run();
        times.push(children_cpu_s()? - start);
    }
    times.sort_by(f64::total_cmp);
    Some(times[times.len() / 2])
}
