//! What the benches share: the CPU time of child processes.

/// CPU time (user + system) of this process's waited-for children, s (`/proc/self/stat`
/// fields 16 and 17, in clock ticks of 1/100 s).
pub fn children_cpu_s() -> Option<f64> {
    let t = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name, which is in parentheses and may hold blanks.
    let fields: Vec<&str> = t.rsplit_once(')')?.1.split_whitespace().collect();
    let ticks = |k: usize| fields.get(k - 3)?.parse::<f64>().ok();
    Some((ticks(16)? + ticks(17)?) / 100.0)
}

/// Mean CPU time of one whole `mtsim` process with `args`, s, over `runs` runs (the
/// children's clock counts 10 ms ticks, so many short runs are summed); its stdout is
/// discarded. None where /proc is missing.
#[allow(dead_code)] // not every bench runs whole processes
pub fn process_cpu_s(args: &[&std::ffi::OsStr], runs: usize) -> Option<f64> {
    let start = children_cpu_s()?;
    for _ in 0..runs {
        let status = std::process::Command::new(env!("CARGO_BIN_EXE_mtsim"))
            .args(args)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .status()
            .expect("mtsim runs");
        assert!(status.success(), "mtsim {args:?} failed");
    }
    Some((children_cpu_s()? - start) / runs as f64)
}
