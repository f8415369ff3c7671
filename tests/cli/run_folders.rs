//! A run folder is one unit (src/report/run_dir.rs): `kill -9` at random times into a folder
//! holding an earlier run leaves the old run or the new one, whole; a rerun leaves nothing of
//! the old one; a second run into a folder in use is refused; SIGINT and SIGTERM leave no
//! temporary files; `mtsim report` takes the same lock. `MTSIM_LONG_FAULTS=1` runs 100 kill times instead of 10.

use crate::common;

use std::collections::BTreeMap;
use std::os::unix::process::ExitStatusExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use common::{mtsim, scratch};

const OLD: &str = "scenarios/circle-iso230-4.toml";
const NEW: &str = "scenarios/cone-15-10.toml";

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn simulate_args<'a>(scenario: &'a str, out: &'a Path, html: bool) -> Vec<&'a str> {
    let mut args = vec!["simulate", scenario, "-o", s(out), "--no-timing"];
    if html {
        args.push("--html");
    }
    args
}

fn run_ok(args: &[&str]) {
    let out = mtsim(args);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn spawn(args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_mtsim"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("the binary starts")
}

/// Every file of folder `dir` (recursively) with its bytes.
fn contents(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.insert(
                    p.strip_prefix(dir).unwrap().to_path_buf(),
                    std::fs::read(&p).unwrap(),
                );
            }
        }
    }
    out
}

/// The names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut n: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    n.sort();
    n
}

/// xorshift64*: the kill times, reproducible from the seed.
struct Rng(u64);

impl Rng {
    fn unit(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[test]
fn a_run_killed_at_random_times_leaves_the_old_run_or_the_new_one_whole() {
    let dir = scratch("run-folders", "kill");
    // The two complete runs the folder may hold, made apart.
    let (old_ref, new_ref) = (dir.join("old"), dir.join("new"));
    run_ok(&simulate_args(OLD, &old_ref, true));
    let started = Instant::now();
    run_ok(&simulate_args(NEW, &new_ref, true));
    let span = started.elapsed().mul_f64(1.3);
    let (old, new) = (contents(&old_ref), contents(&new_ref));
    assert_ne!(
        old.get(Path::new("summary.json")),
        new.get(Path::new("summary.json"))
    );
    let kills = if std::env::var_os("MTSIM_LONG_FAULTS").is_some() {
        100
    } else {
        10
    };
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let out = dir.join("out");
    let (mut saw_old, mut saw_new) = (0, 0);
    for i in 0..kills {
        run_ok(&simulate_args(OLD, &out, true));
        let delay = span.mul_f64(rng.unit());
        let mut child = spawn(&simulate_args(NEW, &out, true));
        std::thread::sleep(delay);
        let _ = child.kill(); // SIGKILL
        child.wait().unwrap();
        let held = contents(&out);
        if held == old {
            saw_old += 1;
        } else if held == new {
            saw_new += 1;
        } else {
            panic!(
                "kill {i} after {delay:?}: the folder holds neither run whole: {:?}",
                held.keys().collect::<Vec<_>>()
            );
        }
    }
    assert_eq!(saw_old + saw_new, kills);
    eprintln!("{kills} kills: {saw_old} left the old run, {saw_new} the new one");
    // The next run cleans up what the killed one left beside the folder.
    run_ok(&simulate_args(NEW, &out, true));
    assert_eq!(contents(&out), new);
    assert_eq!(names(&dir), ["new", "old", "out"]);
}

#[test]
fn a_rerun_leaves_no_file_of_the_earlier_run_and_keeps_the_users_files() {
    let dir = scratch("run-folders", "rerun");
    let out = dir.join("out");
    run_ok(&simulate_args(NEW, &out, true));
    std::fs::write(out.join("notes.txt"), b"mine").unwrap();
    std::fs::create_dir(out.join("shards")).unwrap();
    std::fs::write(out.join("shards").join("a.json"), b"{}").unwrap();
    run_ok(&simulate_args(NEW, &out, false));
    assert_eq!(
        names(&out),
        [
            "ballbar.svg",
            "check.json",
            "notes.txt",
            "shards",
            "summary.json",
            "test.json",
            "trace.csv"
        ]
    );
    assert_eq!(std::fs::read(out.join("notes.txt")).unwrap(), b"mine");
    assert_eq!(std::fs::read(out.join("shards/a.json")).unwrap(), b"{}");
}

#[test]
fn a_second_run_into_a_folder_in_use_is_refused_and_a_dead_runs_lock_is_not() {
    let dir = scratch("run-folders", "lock");
    let out = dir.join("out");
    run_ok(&simulate_args(OLD, &out, false));
    let before = contents(&out);
    // The lock a live run holds: flock on .out.mtsim-lock, with its pid inside.
    let lock_path = dir.join(".out.mtsim-lock");
    let lock = std::fs::File::create(&lock_path).unwrap();
    lock.try_lock().unwrap();
    std::fs::write(&lock_path, b"4242\n").unwrap();
    let refused = mtsim(&simulate_args(NEW, &out, false));
    assert_eq!(refused.status.code(), Some(2));
    let err = String::from_utf8_lossy(&refused.stderr).replace(['\n', '│', ' '], "");
    assert!(
        err.contains(&format!(
            "{}isbeingwrittenbyanothermtsimrun(pid4242);waitforitorchooseanother-o",
            s(&out).replace(' ', "")
        )),
        "{err}"
    );
    assert_eq!(contents(&out), before, "the refused run touched nothing");
    // A run that died holds no flock: the pid left in the file does not block the next one.
    drop(lock);
    run_ok(&simulate_args(NEW, &out, false));
    assert_ne!(contents(&out), before);
    assert!(!lock_path.exists(), "a finished run removes its lock file");
}

/// `mtsim report` writes into a finished run folder: it takes the folder's lock, so it is
/// refused while a run writes there and leaves no lock file when done.
#[test]
fn report_into_a_folder_in_use_is_refused_and_otherwise_leaves_no_lock() {
    let dir = scratch("run-folders", "report-lock");
    let out = dir.join("out");
    run_ok(&simulate_args(NEW, &out, false));
    let lock_path = dir.join(".out.mtsim-lock");
    let lock = std::fs::File::create(&lock_path).unwrap();
    lock.try_lock().unwrap();
    std::fs::write(&lock_path, b"4343\n").unwrap();
    let refused = mtsim(&["report", s(&out)]);
    assert_eq!(refused.status.code(), Some(2));
    let err = String::from_utf8_lossy(&refused.stderr).replace(['\n', '│', ' '], "");
    assert!(
        err.contains("isbeingwrittenbyanothermtsimrun(pid4343)"),
        "{err}"
    );
    assert!(!out.join("report.html").exists());
    drop(lock);
    run_ok(&["report", s(&out)]);
    assert!(out.join("report.html").exists());
    assert_eq!(names(&dir), ["out"], "no lock file left");
    let missing = mtsim(&["report", s(&dir.join("missing"))]);
    assert_eq!(missing.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("not a folder"));
}

/// Sends `signal` to `child` once its staging folder exists, and checks that the old run
/// is left whole and nothing temporary remains.
fn interrupted(signal: &str, signal_number: i32) {
    let dir = scratch("run-folders", signal);
    let out = dir.join("out");
    run_ok(&simulate_args(OLD, &out, true));
    let before = contents(&out);
    let mut child = spawn(&simulate_args(NEW, &out, true));
    let staging = dir.join(".out.mtsim-new");
    let waited = Instant::now();
    while !staging.exists() && waited.elapsed() < Duration::from_secs(20) {
        std::thread::sleep(Duration::from_millis(1));
    }
    let status = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    // The signal comes within milliseconds of the start of a run of about half a second.
    let status = child.wait().unwrap();
    assert_eq!(status.signal(), Some(signal_number), "{status:?}");
    assert_eq!(names(&dir), ["out"]);
    assert_eq!(contents(&out), before);
}

#[test]
fn sigint_and_sigterm_leave_the_old_run_and_no_temporary_files() {
    interrupted("-INT", 2);
    interrupted("-TERM", 15);
}

#[test]
fn an_output_that_is_a_file_is_refused_and_left_alone() {
    let dir = scratch("run-folders", "file");
    let out = dir.join("out");
    std::fs::write(&out, b"mine").unwrap();
    let refused = mtsim(&simulate_args(NEW, &out, false));
    assert_eq!(refused.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("a file, not a folder"));
    assert_eq!(std::fs::read(&out).unwrap(), b"mine");
    assert_eq!(names(&dir), ["out"], "no lock file or staging folder left");
}

#[test]
fn a_sweep_into_the_folder_of_another_sweep_leaves_only_its_own_files() {
    let dir = scratch("run-folders", "sweep");
    let out = dir.join("out");
    let sweep = |param: &str| {
        run_ok(&[
            "sweep",
            NEW,
            "--vary",
            param,
            "--from",
            "-10",
            "--to",
            "0",
            "--step",
            "5",
            "-o",
            s(&out),
        ])
    };
    sweep("center_x");
    sweep("center_y");
    assert_eq!(
        names(&out),
        [
            "sweep-center_y.csv",
            "sweep-center_y.parquet",
            "sweep-center_y.svg"
        ]
    );
}
