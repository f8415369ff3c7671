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
            ".mtsim-run.json",
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
            ".mtsim-run.json",
            "sweep-center_y.csv",
            "sweep-center_y.parquet",
            "sweep-center_y.svg"
        ]
    );
}

/// Each file below `dir` whose top-level entry is not among `run`'s, with its length and a
/// checksum of its bytes (readable when an assertion fails): each must survive a run.
fn user_files(dir: &Path, run: &[&str]) -> BTreeMap<PathBuf, (usize, u64)> {
    contents(dir)
        .into_iter()
        .filter(|(p, _)| {
            let top = p.components().next().unwrap().as_os_str().to_string_lossy();
            !run.contains(&top.as_ref())
        })
        .map(|(p, bytes)| {
            let sum = bytes.iter().fold(0xcbf2_9ce4_8422_2325_u64, |h, b| {
                (h ^ *b as u64).wrapping_mul(0x100_0000_01b3)
            });
            (p, (bytes.len(), sum))
        })
        .collect()
}

/// What `simulate` (without `--html`) writes: the manifest and its five files.
const SIMULATE_FILES: [&str; 6] = [
    ".mtsim-run.json",
    "ballbar.svg",
    "check.json",
    "summary.json",
    "test.json",
    "trace.csv",
];

/// Issue 42's reproduction: names that look like mtsim's (`runs/`, `study-*`, `batch.*`)
/// are the user's when no manifest lists them, and a run goes beside them.
#[test]
fn files_named_like_outputs_but_not_listed_in_a_manifest_are_kept() {
    let dir = scratch("run-folders", "lookalikes");
    let out = dir.join("p");
    std::fs::create_dir_all(out.join("runs")).unwrap();
    std::fs::write(out.join("runs/k"), b"x").unwrap();
    std::fs::write(out.join("study-notes.txt"), b"x").unwrap();
    std::fs::write(out.join("batch.xlsx"), b"x").unwrap();
    std::fs::write(out.join("report.html"), b"<p>mine</p>").unwrap();
    let before = contents(&out);
    run_ok(&simulate_args(NEW, &out, false));
    run_ok(&simulate_args(OLD, &out, false));
    let after = contents(&out);
    for (path, bytes) in &before {
        assert_eq!(after.get(path), Some(bytes), "{} was lost", path.display());
    }
    let mut expected: Vec<&str> = SIMULATE_FILES.to_vec();
    expected.extend(["batch.xlsx", "report.html", "runs", "study-notes.txt"]);
    expected.sort();
    assert_eq!(names(&out), expected);
    // The run asked for a page: report.html is the user's, so it is refused, and nothing changes.
    let refused = mtsim(&simulate_args(NEW, &out, true));
    assert_eq!(refused.status.code(), Some(2));
    let err = String::from_utf8_lossy(&refused.stderr).replace(['\n', '│', ' '], "");
    assert!(
        err.contains("report.htmlisnotwrittenbyanearliermtsimrun"),
        "{err}"
    );
    assert_eq!(contents(&out), after, "the refused run touched nothing");
    assert_eq!(names(&dir), ["p"], "no lock or staging folder left");
}

/// `fit --measured DIR/trace.csv -o DIR`: the trace the fit reads stays, though the earlier
/// run's manifest lists it; the earlier run's other files go.
#[test]
fn a_fit_into_the_folder_of_its_measured_trace_keeps_the_trace() {
    let dir = scratch("run-folders", "fit");
    let out = dir.join("out");
    run_ok(&simulate_args(NEW, &out, false));
    let trace = std::fs::read(out.join("trace.csv")).unwrap();
    let measured = out.join("trace.csv");
    run_ok(&["fit", NEW, "--measured", s(&measured), "-o", s(&out)]);
    assert_eq!(std::fs::read(&measured).unwrap(), trace);
    let held = names(&out);
    assert!(held.contains(&"fit.json".to_string()), "{held:?}");
    assert!(!held.contains(&"summary.json".to_string()), "{held:?}");
}

/// A folder written by a run and then edited: the edited file is the user's.
#[test]
fn an_output_the_user_edited_is_theirs_and_a_run_that_would_replace_it_is_refused() {
    let dir = scratch("run-folders", "edited");
    let out = dir.join("out");
    run_ok(&simulate_args(NEW, &out, false));
    std::fs::write(out.join("ballbar.svg"), b"<svg>annotated</svg>").unwrap();
    let before = contents(&out);
    let refused = mtsim(&simulate_args(NEW, &out, false));
    assert_eq!(refused.status.code(), Some(2));
    assert_eq!(contents(&out), before);
    // Renamed out of the way, it is kept as the user's, and the run goes beside it.
    std::fs::rename(out.join("ballbar.svg"), out.join("ballbar-annotated.svg")).unwrap();
    run_ok(&simulate_args(NEW, &out, false));
    assert_eq!(
        std::fs::read(out.join("ballbar-annotated.svg")).unwrap(),
        b"<svg>annotated</svg>"
    );
}

/// `-o LINK`: the run writes into the folder the link names; the link stays a link, and the
/// user's files in its folder stay.
#[test]
fn an_output_through_a_symbolic_link_writes_through_it_and_keeps_it() {
    let dir = scratch("run-folders", "link");
    let real = dir.join("real");
    std::fs::create_dir_all(&real).unwrap();
    std::fs::write(real.join("mine.txt"), b"mine").unwrap();
    let link = dir.join("link");
    std::os::unix::fs::symlink("real", &link).unwrap();
    run_ok(&simulate_args(NEW, &link, false));
    run_ok(&simulate_args(OLD, &link, false));
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    assert_eq!(std::fs::read_link(&link).unwrap(), Path::new("real"));
    assert_eq!(std::fs::read(real.join("mine.txt")).unwrap(), b"mine");
    assert!(real.join("summary.json").is_file());
    assert_eq!(names(&dir), ["link", "real"]);
}

/// `mtsim report` adds its page to the folder's manifest, so the next run replaces it.
#[test]
fn a_page_written_by_report_is_the_runs_and_a_rerun_with_html_replaces_it() {
    let dir = scratch("run-folders", "report-manifest");
    let out = dir.join("out");
    run_ok(&simulate_args(NEW, &out, false));
    run_ok(&["report", s(&out)]);
    let manifest = std::fs::read_to_string(out.join(".mtsim-run.json")).unwrap();
    assert!(manifest.contains("\"report.html\""), "{manifest}");
    run_ok(&simulate_args(OLD, &out, true));
    run_ok(&simulate_args(NEW, &out, false));
    assert!(
        !out.join("report.html").exists(),
        "the earlier run's page goes with it"
    );
}

/// A user's tree drawn at random: names like mtsim's outputs and not, files and folders.
fn random_tree(rng: &mut Rng, root: &Path) -> usize {
    const NAMES: [&str; 12] = [
        "trace.csv.bak",
        "runs",
        "study-notes.txt",
        "batch.xlsx",
        "placement.md",
        "sweep-old",
        "fit.toml",
        "notes",
        ".hidden",
        "report.htm",
        "shards",
        "summary.json.orig",
    ];
    let mut made = 0;
    for name in NAMES {
        if rng.unit() < 0.5 {
            continue;
        }
        let path = root.join(name);
        if rng.unit() < 0.5 {
            std::fs::create_dir_all(path.join("inner")).unwrap();
            std::fs::write(path.join("inner/trace.csv"), name.as_bytes()).unwrap();
        } else {
            std::fs::write(&path, name.as_bytes()).unwrap();
        }
        made += 1;
    }
    made
}

/// The property of issue 42: over random user trees, every entry the run did not write
/// survives a run, a rerun and a killed run (after the next run has cleaned up).
#[test]
fn every_entry_not_in_the_manifest_survives_runs_reruns_and_killed_runs() {
    let dir = scratch("run-folders", "property");
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    let cases = if std::env::var_os("MTSIM_LONG_FAULTS").is_some() {
        40
    } else {
        8
    };
    let mut users = 0;
    for case in 0..cases {
        let out = dir.join(format!("case{case}"));
        std::fs::create_dir_all(&out).unwrap();
        users += random_tree(&mut rng, &out);
        let mine = user_files(&out, &[]);
        let check = |when: &str| {
            let held = user_files(&out, &SIMULATE_FILES);
            assert_eq!(held, mine, "case {case}, after {when}");
        };
        run_ok(&simulate_args(OLD, &out, false));
        check("a run");
        run_ok(&simulate_args(NEW, &out, false));
        check("a rerun");
        let mut child = spawn(&simulate_args(OLD, &out, false));
        std::thread::sleep(Duration::from_millis((rng.unit() * 400.0) as u64));
        let _ = child.kill();
        child.wait().unwrap();
        // Killed while it moved them, the user's entries are in the folder or in the staged
        // one beside it, never gone; the next run puts them back.
        let staging = dir.join(format!(".case{case}.mtsim-new"));
        let mut held = user_files(&out, &SIMULATE_FILES);
        if staging.is_dir() {
            // The staged folder also holds the run's own files, finished or not.
            let staged = user_files(&staging, &[]);
            held.extend(staged.into_iter().filter(|(p, _)| mine.contains_key(p)));
        }
        assert_eq!(held, mine, "case {case}, just after a killed run");
        run_ok(&simulate_args(NEW, &out, false));
        check("a killed run and the next");
    }
    assert!(users > 0, "the trees held some of the user's entries");
}
