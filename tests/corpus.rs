//! Real programs nobody on the project wrote: the sample programs that ship with LinuxCNC
//! (Debian package `linuxcnc-uspace`: /usr/share/linuxcnc/ncfiles and the examples under
//! /usr/share/doc/linuxcnc*). Issue 9's "Done when": every standalone program goes through
//! `analyze` and `check` with 0 panics, 0 hangs and 0 "clean" verdicts on input that was
//! not read; the fraction read is reported and held to a floor; where rs274 and mtsim both
//! read a program, their end points agree (tests/common/rs274.rs).
//!
//! Without the samples the test prints that it skipped and why; under `CI` it fails.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use common::{machine, rs274, scratch};

/// Fraction of standalone programs that `analyze` and `check` read, at least. The issue's
/// goal is 0.90; this is the figure reached so far (raise it as the reader grows).
const READ_FLOOR: f64 = 0.45;

/// Longest a single `analyze` or `check` may take before it counts as a hang.
const TIMEOUT: Duration = Duration::from_secs(30);

const NCFILES: &str = "/usr/share/linuxcnc/ncfiles";

/// Every `.ngc` and `.nc` file under the LinuxCNC sample folders, once (by real path).
fn sample_files() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, out);
            } else if p
                .extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| e.eq_ignore_ascii_case("ngc") || e.eq_ignore_ascii_case("nc"))
            {
                out.push(p);
            }
        }
    }
    let mut files = Vec::new();
    walk(Path::new(NCFILES), &mut files);
    if let Ok(docs) = std::fs::read_dir("/usr/share/doc") {
        for d in docs.flatten() {
            if d.file_name().to_string_lossy().starts_with("linuxcnc") {
                walk(&d.path().join("examples"), &mut files);
            }
        }
    }
    // The sample configurations link to the same folders: count each file once.
    let mut files: Vec<PathBuf> = files
        .into_iter()
        .filter_map(|p| std::fs::canonicalize(p).ok())
        .collect();
    files.sort();
    files.dedup();
    files
}

/// A subroutine file (LinuxCNC's convention: `name.ngc` holds `o<name> sub`) is not a
/// program of its own.
fn is_standalone(path: &Path, text: &str) -> bool {
    let stem = path
        .file_stem()
        .unwrap()
        .to_string_lossy()
        .to_ascii_lowercase();
    let squeezed: String = text
        .to_ascii_lowercase()
        .chars()
        .filter(|c| !c.is_whitespace())
        .collect();
    !squeezed.contains(&format!("o<{stem}>sub"))
}

/// LinuxCNC's metric sample tool table (lengths in mm), given to mtsim as it is and to
/// rs274 converted to inches (its machine units).
const TOOL_TABLE_MM: &str = "/usr/share/doc/linuxcnc/examples/sample-configs/sim/sim_mm.tbl";

/// The subroutine search path for `program`, as a LinuxCNC configuration's
/// `[RS274NGC]SUBROUTINE_PATH` would give it: the program's own folder, then every sample
/// folder that holds subroutine files, the ones nearest the program (longest common path)
/// first.
fn search_path(program: &Path, sub_dirs: &[PathBuf]) -> Vec<PathBuf> {
    let own = program.parent().unwrap().to_path_buf();
    let common = |d: &Path| {
        d.components()
            .zip(own.components())
            .take_while(|(a, b)| a == b)
            .count()
    };
    let mut dirs: Vec<&PathBuf> = sub_dirs.iter().filter(|d| **d != own).collect();
    dirs.sort_by(|a, b| common(b).cmp(&common(a)).then(a.cmp(b)));
    std::iter::once(own)
        .chain(dirs.into_iter().cloned())
        .collect()
}

/// Sample programs whose moves are known to differ from rs274's, with the reason; listed
/// here they are reported, not failed. A program that differs and is not listed fails.
const KNOWN_DIFFERENCES: &[(&str, &str)] = &[(
    "ncfiles/skeleton.ngc",
    "`T1 M06 G43 H1` in one block: rs274 keeps the program Z, so the next move without Z \
     moves the machine by the tool length; mtsim keeps the machine Z \
     (tests/data/conformance-pending/m6_g43_same_block.ngc)",
)];

fn known_difference(name: &str) -> Option<&'static str> {
    KNOWN_DIFFERENCES
        .iter()
        .find(|(suffix, _)| name.ends_with(suffix))
        .map(|(_, why)| *why)
}

/// The user M codes of LinuxCNC's table-rotary-tilting sample configurations
/// (`xyzac-trt.ini`: `REMAP = M428` switches to the tool-centre-point kinematics, M429 back
/// to identity, M430 to user kinematics), as a scenario would map them.
const USER_M_CODES: &str =
    "user_m_codes = { M428 = \"tcp-on\", M429 = \"tcp-off\", M430 = \"ignore\" }";

/// What happened to one program.
#[derive(Debug, Default)]
struct Outcome {
    name: String,
    analyze: Option<i32>,
    check: Option<i32>,
    panicked: bool,
    clean_unread: bool,
    /// Read to the end and refused by both commands only because nothing moves (exit 2,
    /// "the program has no motion": a tool-change or parameter demo).
    motion_free: bool,
    first_error: String,
    /// `Some(Ok(moves))` when rs274 and mtsim both read it and agree.
    compared: Option<Result<usize, String>>,
}

impl Outcome {
    fn read(&self) -> bool {
        (self.analyze == Some(0) && matches!(self.check, Some(0 | 1))) || self.motion_free
    }
    fn hung(&self) -> bool {
        self.analyze.is_none() || self.check.is_none()
    }
}

/// A diagnostic with miette's line wrapping and gutter removed.
fn unwrapped(err: &str) -> String {
    err.replace('│', " ")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}

fn mtsim(args: &[&str]) -> (Option<i32>, String, String) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_mtsim"));
    cmd.args(args).env("NO_COLOR", "1");
    rs274::run_timed(&mut cmd, TIMEOUT)
}

/// What every program needs: the folders of subroutine files, the tool tables (mm for
/// mtsim, inch for rs274) and rs274 itself when installed.
struct Setup {
    sub_dirs: Vec<PathBuf>,
    tools_mm: Option<PathBuf>,
    rs274: Option<(PathBuf, PathBuf)>,
}

fn run_one(path: &Path, k: usize, setup: &Setup) -> Outcome {
    let text = String::from_utf8_lossy(&std::fs::read(path).unwrap()).into_owned();
    let work = scratch("corpus", &k.to_string());
    let machine_path = machine(if rs274::uses_b_axis(&text) {
        "trt-bc"
    } else {
        "trt-ac"
    });
    let scenario = work.join("s.toml");
    let dirs = search_path(path, &setup.sub_dirs);
    let dir_list: Vec<String> = dirs
        .iter()
        .map(|d| format!("{:?}", d.display().to_string()))
        .collect();
    let tools = setup.tools_mm.as_ref().map_or(String::new(), |t| {
        format!("tool_table = {:?}\n", t.display().to_string())
    });
    std::fs::write(
        &scenario,
        format!(
            "machine = {machine_path:?}\n[program]\nfile = {:?}\n[reader]\ndialect = \"linuxcnc\"\n{tools}subroutine_path = [{}]\n{USER_M_CODES}\n[check]\ncollisions = false\n",
            path.display().to_string(),
            dir_list.join(", ")
        ),
    )
    .unwrap();
    let s = scenario.to_str().unwrap();
    let (analyze, _, a_err) = mtsim(&["analyze", s]);
    let (check, c_out, c_err) = mtsim(&["check", s]);
    let crashed =
        |code: Option<i32>, err: &str| err.contains("panicked") || matches!(code, Some(101 | -1));
    let mut o = Outcome {
        name: path.display().to_string(),
        analyze,
        check,
        panicked: crashed(analyze, &a_err) || crashed(check, &c_err),
        // A verdict of "clean" when either command could not read the program.
        clean_unread: c_out.contains("clean") && (analyze != Some(0) || check != Some(0)),
        motion_free: [(analyze, &a_err), (check, &c_err)]
            .iter()
            .all(|(code, err)| {
                *code == Some(2) && unwrapped(err).contains("the program has no motion")
            }),
        first_error: a_err
            .lines()
            .chain(c_err.lines())
            .find(|l| l.contains('×'))
            .unwrap_or("")
            .trim()
            .to_string(),
        compared: None,
    };
    if let (true, Some((rs274_bin, tools))) = (o.read(), &setup.rs274) {
        let run = rs274::run_with(rs274_bin, path, tools, &dirs, &work.join("rs"), TIMEOUT);
        if run.ok {
            let (code, csv, err) = mtsim(&["blocks", s, "--csv"]);
            o.compared = Some(match code {
                Some(0) => rs274::compare_moves(run.moves, rs274::parse_blocks_csv(&csv), true),
                _ => Err(format!("blocks failed: {err}")),
            });
        }
    }
    let _ = std::fs::remove_dir_all(&work);
    o
}

#[test]
fn linuxcnc_sample_programs_never_panic_hang_or_pass_unread() {
    if !Path::new(NCFILES).is_dir() {
        if std::env::var_os("CI").is_some() {
            panic!("{NCFILES} is missing but CI is set: install linuxcnc-uspace");
        }
        eprintln!("SKIPPED corpus: the LinuxCNC sample programs ({NCFILES}, package linuxcnc-uspace) are not installed");
        return;
    }
    let (programs, subs): (Vec<PathBuf>, Vec<PathBuf>) =
        sample_files().into_iter().partition(|p| {
            let text = String::from_utf8_lossy(&std::fs::read(p).unwrap()).into_owned();
            is_standalone(p, &text)
        });
    let mut sub_dirs: Vec<PathBuf> = subs
        .iter()
        .map(|p| p.parent().unwrap().to_path_buf())
        .collect();
    sub_dirs.sort();
    sub_dirs.dedup();
    assert!(
        programs.len() >= 90,
        "only {} standalone programs found",
        programs.len()
    );
    // LinuxCNC's metric sample tool table for mtsim, its inch copy for rs274.
    let tools_mm = Path::new(TOOL_TABLE_MM)
        .is_file()
        .then(|| PathBuf::from(TOOL_TABLE_MM));
    let rs = rs274::require("corpus (end-point comparison)").map(|b| {
        let work = scratch("corpus", "tools");
        let tools = work.join("tool-inch.tbl");
        let mm = tools_mm
            .as_ref()
            .map_or(String::new(), |t| std::fs::read_to_string(t).unwrap());
        std::fs::write(&tools, rs274::tool_table_to_inch(&mm)).unwrap();
        (b, tools)
    });
    let setup = Setup {
        sub_dirs,
        tools_mm,
        rs274: rs,
    };

    let started = Instant::now();
    let next = Mutex::new(0usize);
    let outcomes = Mutex::new(Vec::new());
    std::thread::scope(|scope| {
        for _ in 0..2 {
            scope.spawn(|| loop {
                let k = {
                    let mut n = next.lock().unwrap();
                    *n += 1;
                    *n - 1
                };
                let Some(p) = programs.get(k) else { break };
                let o = run_one(p, k, &setup);
                outcomes.lock().unwrap().push(o);
            });
        }
    });
    let mut outcomes = outcomes.into_inner().unwrap();
    outcomes.sort_by(|a, b| a.name.cmp(&b.name));

    let n = outcomes.len();
    let read: Vec<_> = outcomes.iter().filter(|o| o.read()).collect();
    let panics: Vec<_> = outcomes
        .iter()
        .filter(|o| o.panicked)
        .map(|o| &o.name)
        .collect();
    let hangs: Vec<_> = outcomes
        .iter()
        .filter(|o| o.hung())
        .map(|o| &o.name)
        .collect();
    let clean_unread: Vec<_> = outcomes
        .iter()
        .filter(|o| o.clean_unread)
        .map(|o| &o.name)
        .collect();
    let compared: Vec<_> = outcomes
        .iter()
        .filter_map(|o| o.compared.as_ref().map(|c| (&o.name, c)))
        .collect();
    let disagree: Vec<String> = compared
        .iter()
        .filter_map(|(name, c)| c.as_ref().err().map(|e| format!("{name}: {e}")))
        .collect();
    let (known, unknown): (Vec<&String>, Vec<&String>) = disagree
        .iter()
        .partition(|d| known_difference(d.split(':').next().unwrap_or("")).is_some());
    for d in &known {
        let name = d.split(':').next().unwrap_or("");
        eprintln!(
            "known difference: {d}\n  why: {}",
            known_difference(name).unwrap_or("")
        );
    }
    let fraction = read.len() as f64 / n as f64;
    eprintln!(
        "corpus: {} standalone LinuxCNC sample programs in {:.1} s: {} read by analyze and check ({:.1} %), \
         {} panics, {} hangs, {} 'clean' on unread input; rs274 and mtsim both read {}, agree on {} ({} known differences)",
        n,
        started.elapsed().as_secs_f64(),
        read.len(),
        100.0 * fraction,
        panics.len(),
        hangs.len(),
        clean_unread.len(),
        compared.len(),
        compared.len() - disagree.len(),
        known.len()
    );
    for o in &outcomes {
        eprintln!(
            "  {:<5} {}  {}",
            if o.read() { "read" } else { "no" },
            o.name,
            o.first_error
        );
    }
    assert!(panics.is_empty(), "panics: {panics:?}");
    assert!(hangs.is_empty(), "hangs (over {TIMEOUT:?}): {hangs:?}");
    assert!(
        clean_unread.is_empty(),
        "'clean' on unread input: {clean_unread:?}"
    );
    assert!(
        unknown.is_empty(),
        "end points differ from rs274:\n{}",
        unknown
            .iter()
            .map(|s| s.as_str())
            .collect::<Vec<_>>()
            .join("\n")
    );
    assert!(
        fraction >= READ_FLOOR,
        "read {:.1} % of the programs, below the floor of {:.1} %",
        100.0 * fraction,
        100.0 * READ_FLOOR
    );
}
