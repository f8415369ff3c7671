//! The Siemens Sinumerik programs of the shared corpus (`shared/corpus/manifest.tsv`,
//! dialect `siemens`: CAM posts and DMG/shop programs, some five-axis) through `analyze`
//! and `check` with `dialect = "siemens"`: each is read, or refused with the construct
//! named (file, line and column, exit code 2), or a move its machine cannot make named;
//! 0 panics, 0 hangs.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use common::{machine, rs274, scratch};

/// Longest a single `analyze` or `check` may take before it counts as a hang.
const TIMEOUT: Duration = Duration::from_secs(60);

/// Programs read through to the end, at least (CAM_TEST.MPF, and DM_MILL.SPF, which moves
/// nothing; raise it as the reader grows).
const READ_FLOOR: usize = 2;

/// The corpus folder: `shared/corpus` in a folder above the checkout.
fn corpus() -> Option<PathBuf> {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .ancestors()
        .map(|d| d.join("shared/corpus"))
        .find(|d| d.join("manifest.tsv").is_file())
}

fn mtsim(args: &[&str]) -> (Option<i32>, String, String) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_mtsim"));
    cmd.args(args).env("NO_COLOR", "1");
    rs274::run_timed(&mut cmd, TIMEOUT)
}

#[test]
fn siemens_corpus_programs_are_read_or_refused_by_name_without_panics_or_hangs() {
    let Some(dir) = corpus() else {
        assert!(
            std::env::var_os("CI").is_none(),
            "the corpus (shared/corpus) is missing"
        );
        eprintln!(
            "SKIPPED siemens corpus: no shared/corpus above {}",
            env!("CARGO_MANIFEST_DIR")
        );
        return;
    };
    let manifest = std::fs::read_to_string(dir.join("manifest.tsv")).unwrap();
    let names: Vec<&str> = manifest
        .lines()
        .skip(1)
        .filter_map(|l| {
            let f: Vec<&str> = l.split('\t').collect();
            (f.get(1) == Some(&"siemens")).then_some(f[0])
        })
        .collect();
    assert!(
        names.len() >= 10,
        "expected the corpus's Siemens programs, found {}",
        names.len()
    );
    let work = scratch("siemens-corpus", "all");
    let (mut read, mut rightly, mut report) = (0, 0, Vec::new());
    for (k, name) in names.iter().enumerate() {
        let path = dir.join("programs").join(name);
        let text = String::from_utf8_lossy(&std::fs::read(&path).unwrap()).into_owned();
        let m = machine(if rs274::uses_b_axis(&text) {
            "trt-bc"
        } else {
            "trt-ac"
        });
        let scenario = work.join(format!("{k}.toml"));
        std::fs::write(
            &scenario,
            format!(
                "machine = {m:?}\n[program]\nfile = {:?}\n[reader]\ndialect = \"siemens\"\n[check]\ncollisions = false\n",
                path.display().to_string()
            ),
        )
        .unwrap();
        let s = scenario.to_str().unwrap();
        let (analyze, _, a_err) = mtsim(&["analyze", s]);
        let (check, _, c_err) = mtsim(&["check", s]);
        for (what, code, err) in [("analyze", analyze, &a_err), ("check", check, &c_err)] {
            assert!(code.is_some(), "{name}: {what} hung (over {TIMEOUT:?})");
            assert!(
                !err.contains("panicked") && code != Some(101),
                "{name}: {what} panicked: {err}"
            );
        }
        if analyze == Some(0) && matches!(check, Some(0 | 1)) {
            read += 1;
            report.push(format!("{name}: read"));
            continue;
        }
        // Read to its end, with no move (a machine maker's cycle that only sets modes):
        // `analyze` says there is nothing to analyse.
        let a_flat = a_err
            .replace('│', " ")
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
        if analyze == Some(2) && a_flat.contains("the program has no motion") {
            read += 1;
            report.push(format!("{name}: read, no motion"));
            continue;
        }
        // Refused: exit code 2, the program's file and line named with what is not read
        // (a construct in backquotes, or a move the machine cannot make).
        let err = a_err.replace('│', " ");
        assert_eq!(
            analyze,
            Some(2),
            "{name}: analyze exit code {analyze:?}: {a_err}"
        );
        let placed = err.contains(&format!("{name}:"));
        assert!(
            placed && (err.contains('`') || err.contains("travel")),
            "{name}: the refusal names no construct: {a_err}"
        );
        let first = err
            .lines()
            .find(|l| l.contains('×'))
            .unwrap_or("")
            .trim()
            .to_string();
        // Refused rightly: for a file, a global user variable's definition file or a value
        // of the control that is not given, or a move beyond the machine's travel.
        let flat = err.split_whitespace().collect::<Vec<_>>().join(" ");
        if [
            "nor a subprogram it finds",
            "not given",
            "gives it",
            "travel",
        ]
        .iter()
        .any(|why| flat.contains(why))
        {
            rightly += 1;
        }
        report.push(format!("{name}: refused: {first}"));
    }
    let _ = std::fs::remove_dir_all(&work);
    eprintln!(
        "siemens corpus: {read} of {} read, the others refused by name:\n{}",
        names.len(),
        report.join("\n")
    );
    assert!(
        read >= READ_FLOOR,
        "only {read} Siemens programs read, floor {READ_FLOOR}"
    );
    // Every program of the corpus is read or refused for what is not given (issue 41:
    // 5 subprograms, 4 global user data files, 3 values of the control, 1 travel).
    assert_eq!(
        read + rightly,
        names.len(),
        "{read} read and {rightly} refused for what is not given, of {}",
        names.len()
    );
}
