//! Real programs from public repositories (CAM posts and shop programs, five-axis ones among
//! them), kept outside the project in `shared/corpus` (its `manifest.tsv` names each one's
//! source, licence and control). Issue 28: every Fanuc, Haas and LinuxCNC program there goes
//! through `analyze` and `check` with 0 panics, 0 hangs and 0 "clean" verdicts on input that
//! was not read; each one is read, or refused for a reason listed in [`REFUSED`]: a real
//! fault of the program, or a documented, named gap of mtsim.
//!
//! Without the corpus the test prints that it skipped and why; under `CI` it fails.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use crate::common::rs274;
use crate::common::scratch;

/// Longest one `analyze` or `check` may take before it counts as a hang.
const TIMEOUT: Duration = Duration::from_secs(60);

/// Why a program is refused.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Why {
    /// The program is at fault: a real control (or rs274) refuses it too.
    /// (No documented gap of mtsim remains among these programs.)
    Fault,
}

/// The programs not read: file name, why, and a piece of the error each must give.
const REFUSED: &[(&str, Why, &str)] = &[
    // A grbl post's `K0` on a G17 arc: rs274 refuses it too.
    ("fc_grbl_ecc33.nc", Why::Fault, "`K0.000` is not in"),
    // M451 is grblHAL's TCP switch, no LinuxCNC code (rs274: unknown M code).
    (
        "grblhal_rtcp_5ax_ac.nc",
        Why::Fault,
        "unsupported code `M451`",
    ),
    // Not text: the file in the repository is binary.
    ("haas_mc_o78238.nc", Why::Fault, "unexpected character"),
    // Heidenhain conversational listed as Fanuc, read as Klartext: a circle around CC
    // from a start the operator sets by hand (the program reads it with FN 18). Its twin
    // hdh_profile.h (`APPR LT` … `DEP LT`) reads.
    ("hdh_cirstud.h", Why::Fault, "is on CC"),
    // The subroutine files these programs call are not in their repository's folder.
    (
        "lcnc_lagun_HEMA-P017.ngc",
        Why::Fault,
        "subroutine `drill_man` not found",
    ),
    ("lcnc_lagun_HEMA-P048.ngc", Why::Fault, "not found"),
    ("lcnc_lagun_HEMS-0002.ngc", Why::Fault, "not found"),
    ("lcnc_lagun_HEQJ-P001.ngc", Why::Fault, "not found"),
    // `o<drill_man> [..]` without `call`: rs274 refuses it too.
    (
        "lcnc_lagun_HEQJ-W002.ngc",
        Why::Fault,
        "o-word without a keyword",
    ),
    // `GOO` (letters O for zeros): a typo no control reads.
    ("mill_lduran_steps.nc", Why::Fault, "`G` has no number"),
];

/// The programs whose source says they are in inches but never state G20: the test runs
/// them with `[reader] start_units = "inch"`, as the control they ran on was set up.
fn starts_in_inch(units: &str) -> bool {
    units.starts_with("inch") && units.contains("no G20")
}

/// `shared/corpus`, found walking up from the package folder.
fn corpus_dir() -> Option<PathBuf> {
    let mut dir = Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf();
    loop {
        let c = dir.join("shared/corpus");
        if c.join("manifest.tsv").is_file() {
            return Some(c);
        }
        if !dir.pop() {
            return None;
        }
    }
}

fn mtsim(args: &[&str]) -> (Option<i32>, String, String) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_mtsim"));
    cmd.args(args).env("NO_COLOR", "1");
    rs274::run_timed(&mut cmd, TIMEOUT)
}

fn one_line(err: &str) -> String {
    err.replace('│', " ")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}

#[test]
fn fanuc_haas_and_linuxcnc_programs_of_the_corpus_read_or_are_refused_for_a_listed_reason() {
    let Some(corpus) = corpus_dir() else {
        if std::env::var_os("CI").is_some() {
            panic!("shared/corpus is missing but CI is set");
        }
        eprintln!("SKIPPED shared corpus: no shared/corpus/manifest.tsv above the package");
        return;
    };
    let manifest = std::fs::read_to_string(corpus.join("manifest.tsv")).unwrap();
    let machines = Path::new(env!("CARGO_MANIFEST_DIR")).join("machines");
    let work = scratch("shared-corpus", "run");
    let (mut read, mut faults, mut gaps) = (0, 0, 0);
    let mut failures = Vec::new();
    for row in manifest.lines().skip(1) {
        let f: Vec<&str> = row.split('\t').collect();
        let (name, dialect, five, units) = (f[0], f[1], f[6], f[7]);
        if !matches!(dialect, "fanuc" | "haas" | "linuxcnc") {
            continue;
        }
        // The UMC-750 is a B-C trunnion; the other five-axis programs are A-C.
        let machine = match (name.starts_with("haas_umc"), five) {
            (true, _) => "trt-bc.toml",
            (false, "yes") => "trt-ac.toml",
            _ => "vmc-3axis.toml",
        };
        let start = if starts_in_inch(units) {
            "start_units = \"inch\"\n"
        } else {
            ""
        };
        let scenario = work.join(format!("{name}.toml"));
        std::fs::write(
            &scenario,
            format!(
                "machine = {:?}\n[program]\nfile = {:?}\n[reader]\ndialect = \"{dialect}\"\n{start}[check]\ncollisions = false\n",
                machines.join(machine).display().to_string(),
                corpus.join("programs").join(name).display().to_string(),
            ),
        )
        .unwrap();
        let s = scenario.to_str().unwrap();
        let (analyze, _, a_err) = mtsim(&["analyze", s]);
        let (check, c_out, c_err) = mtsim(&["check", s]);
        let panicked = |code: Option<i32>, err: &str| err.contains("panicked") || code == Some(101);
        if panicked(analyze, &a_err) || panicked(check, &c_err) {
            failures.push(format!("{name}: panicked"));
            continue;
        }
        if analyze.is_none() || check.is_none() {
            failures.push(format!("{name}: no answer within {TIMEOUT:?}"));
            continue;
        }
        let is_read = analyze == Some(0) && matches!(check, Some(0 | 1));
        if !is_read && c_out.contains("clean") {
            failures.push(format!("{name}: 'clean' on input that was not read"));
        }
        let listed = REFUSED.iter().find(|(n, _, _)| *n == name);
        match (is_read, listed) {
            (true, None) => read += 1,
            (true, Some(_)) => failures.push(format!("{name}: read now, remove it from REFUSED")),
            (false, Some((_, why, expect))) => {
                let err = one_line(&format!("{a_err} {c_err}"));
                if !err.contains(expect) {
                    failures.push(format!("{name}: refused, but not for `{expect}`: {err}"));
                } else if *why == Why::Fault {
                    faults += 1;
                } else {
                    gaps += 1;
                }
            }
            (false, None) => failures.push(format!(
                "{name}: refused and not listed: {}",
                one_line(&a_err)
            )),
        }
    }
    let _ = std::fs::remove_dir_all(&work);
    eprintln!(
        "shared corpus (Fanuc, Haas, LinuxCNC): {read} read, {faults} refused for a fault of the program, {gaps} refused for a documented gap"
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(read >= 11, "only {read} programs read");
}

/// Runs `args` on a scenario in a scratch folder: the program `program`, the three-axis
/// machine with `machine_extra` appended and `[reader]` keys `reader`.
fn run_units_case(
    name: &str,
    program: &str,
    machine_extra: &str,
    reader: &str,
    args: &[&str],
) -> (Option<i32>, String, String) {
    let dir = scratch("units", name);
    let machine = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/vmc-3axis.toml"),
    )
    .unwrap();
    std::fs::write(dir.join("m.toml"), format!("{machine}\n{machine_extra}")).unwrap();
    std::fs::write(dir.join("p.nc"), program).unwrap();
    let s = dir.join("s.toml");
    std::fs::write(
        &s,
        format!("machine = \"m.toml\"\n[program]\nfile = \"p.nc\"\n[reader]\n{reader}[check]\ncollisions = false\n"),
    )
    .unwrap();
    let mut full: Vec<&str> = args.to_vec();
    full.push(s.to_str().unwrap());
    let out = mtsim(&full);
    let _ = std::fs::remove_dir_all(&dir);
    out
}

#[test]
fn the_start_units_come_from_the_machine_or_scenario_and_a_guess_is_never_silent() {
    // No G20/G21: read in mm, with a warning on stderr and in the JSON.
    let program = "G90 G0 X4 Y2\nG1 X5 F10\nM30\n";
    let (code, out, err) = run_units_case("mm", program, "", "", &["analyze", "--json"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(err.contains("moves before it states its units"), "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["axes"]["X"]["max"], 5.0);
    assert!(v["warnings"][0].as_str().unwrap().contains("read in mm"));
    // `check` gives the same warning (its reader stops at the first move, which carries it).
    let (_, _, err) = run_units_case("mm-check", program, "", "", &["check"]);
    assert!(err.contains("moves before it states its units"), "{err}");
    assert!(
        err.contains(":1:"),
        "the warning names the program line: {err}"
    );
    // The machine starts in inch: X 5 in = 127 mm; the warning names the machine file.
    let (_, out, err) = run_units_case(
        "machine-inch",
        program,
        "[start]\nunits = \"inch\"\n",
        "",
        &["analyze", "--json"],
    );
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["axes"]["X"]["max"], 127.0, "{err}");
    assert!(err.contains("the machine file's [start] units"), "{err}");
    // The scenario's start_units overrides the machine file.
    let (_, out, _) = run_units_case(
        "scenario-mm",
        program,
        "[start]\nunits = \"inch\"\n",
        "start_units = \"mm\"\n",
        &["analyze", "--json"],
    );
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["axes"]["X"]["max"], 5.0);
    // A program in mm stated as inches: X 500 in = 12,700 mm is longer than the whole
    // travel, and 500 mm would fit: the error says so.
    let (code, _, err) = run_units_case("too-long", "G20\nG0 X500\nM30\n", "", "", &["check"]);
    assert_eq!(code, Some(2));
    let err = one_line(&err);
    assert!(
        err.contains("read as mm instead of inches it would be 500 mm and fit"),
        "{err}"
    );
}
