//! `mtsim check` on programs and side files that once crashed it or grew without end
//! (issue 26, items 2, 3 and 7): 20,000 nested `[` or `ABS[` exit 2 with file:line:column,
//! never an abort; a subroutine file that is `/dev/zero` is refused by name; a tool table,
//! parameter file or LinuxCNC INI that is not one is reported by file and line without
//! its text.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Output;

use common::{machine, mtsim_plain, scratch};

/// Writes `p.ngc` and `s.toml` (the three-axis machine, LinuxCNC dialect, `reader` lines
/// under `[reader]`) into a fresh folder; returns the scenario path.
fn setup(name: &str, program: &str, reader: &str) -> PathBuf {
    let dir = scratch("bounded", name);
    std::fs::write(dir.join("p.ngc"), program).unwrap();
    let path = dir.join("s.toml");
    std::fs::write(
        &path,
        format!(
            "machine = {:?}\n[program]\nfile = \"p.ngc\"\n[reader]\ndialect = \"linuxcnc\"\n{reader}",
            machine("vmc-3axis")
        ),
    )
    .unwrap();
    path
}

fn check(scenario: &Path) -> (Output, String) {
    let out = mtsim_plain(
        scenario.parent().unwrap(),
        &["check", scenario.to_str().unwrap()],
    );
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    (out, stderr)
}

/// Asserts exit 2 (not an abort or a signal) and `expected` on stderr.
fn assert_refused(out: &Output, stderr: &str, expected: &str) {
    assert_eq!(out.status.code(), Some(2), "stderr: {stderr}");
    assert!(
        stderr.contains(expected),
        "expected `{expected}` in: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// `G1 X<open × n>1<close × n>` on line 2.
fn nested(open: &str, close: &str, n: usize) -> String {
    format!(
        "G21 G90\nG1 X{}1{} F100\nM2\n",
        open.repeat(n),
        close.repeat(n)
    )
}

#[test]
fn twenty_thousand_nested_brackets_or_functions_exit_2_with_the_column() {
    let limit = ngc::MAX_NESTING;
    // The column where level `limit + 1` opens: after `G1 X` and `limit` levels' openings
    // (`[ABS[` is two levels, of 1 and 4 characters).
    let after = |levels_text: usize| "G1 X".len() + 1 + levels_text;
    for (name, open, close, column) in [
        ("brackets", "[", "]", after(limit)),
        ("abs", "ABS[", "]", after(4 * limit)),
        ("mixed", "[ABS[", "]]", after(5 * limit / 2)),
    ] {
        let s = setup(name, &nested(open, close, 20_000), "");
        let (out, stderr) = check(&s);
        assert_refused(&out, &stderr, &format!("p.ngc:2:{column}"));
        // The message is wrapped to the terminal width: its words, not its lines.
        let words: Vec<&str> = stderr.split_whitespace().filter(|w| *w != "│").collect();
        assert!(
            words
                .join(" ")
                .contains(&format!("nested deeper than {limit} levels")),
            "{stderr}"
        );
    }
}

#[test]
fn nesting_at_the_limit_runs() {
    let s = setup("limit", &nested("[", "]", ngc::MAX_NESTING), "");
    let (out, stderr) = check(&s);
    assert!(matches!(out.status.code(), Some(0 | 1)), "{stderr}");
    assert!(!stderr.contains("nested deeper"), "{stderr}");
}

#[cfg(unix)]
#[test]
fn a_subroutine_file_linked_to_dev_zero_is_refused_by_name() {
    let s = setup(
        "zero",
        "G21 G90\no<zero> call\nM2\n",
        "subroutine_path = [\".\"]\n",
    );
    std::os::unix::fs::symlink("/dev/zero", s.parent().unwrap().join("zero.ngc")).unwrap();
    let (out, stderr) = check(&s);
    assert_refused(&out, &stderr, "p.ngc:2:1");
    assert!(stderr.contains("zero.ngc"), "{stderr}");
    assert!(stderr.contains("not a regular file"), "{stderr}");
}

#[test]
fn a_tool_table_that_is_not_one_is_named_without_its_text() {
    let s = setup(
        "shadow",
        "G21 G90\nG1 X1 F100\nM2\n",
        "tool_table = \"shadow\"\n",
    );
    std::fs::write(
        s.parent().unwrap().join("shadow"),
        "root:$6$secretsecret:19000:0:99999:7:::\n",
    )
    .unwrap();
    let (out, stderr) = check(&s);
    assert_refused(&out, &stderr, "shadow");
    assert!(stderr.contains("line 1"), "{stderr}");
    assert!(!stderr.contains("secretsecret"), "{stderr}");
    assert!(!String::from_utf8_lossy(&out.stdout).contains("secretsecret"));
}

#[test]
fn a_parameter_file_or_ini_that_is_not_one_is_named_without_its_text() {
    for (key, file) in [("var_file", "params"), ("linuxcnc_ini", "cfg.ini")] {
        let s = setup(
            key,
            "G21 G90\nG1 X1 F100\nM2\n",
            &format!("{key} = {file:?}\n"),
        );
        std::fs::write(
            s.parent().unwrap().join(file),
            "root:$6$secretsecret:19000:0:99999:7:::\n",
        )
        .unwrap();
        let (out, stderr) = check(&s);
        assert_refused(&out, &stderr, file);
        assert!(!stderr.contains("secretsecret"), "{key}: {stderr}");
    }
}

/// The Heidenhain and Sinumerik front ends' expressions (issue 42 item 3): a formula of
/// 20,000 nested brackets, functions or signs is refused with exit 2 at its line, naming
/// the nesting, never a stack overflow (exit 134). The ISO family's are above.
#[test]
fn twenty_thousand_nested_heidenhain_and_sinumerik_expressions_exit_2_at_their_line() {
    let n = 20_000;
    let heidenhain = |expr: String| {
        format!(
            "0 BEGIN PGM DEEP MM\n1 Q1 = {expr}\n2 L X+0 Y+0 Z+0 R0 FMAX\n3 L X+Q1 F100\n4 END PGM DEEP MM\n"
        )
    };
    let sinumerik =
        |expr: String| format!("N10 G0 X0 Y0 Z0\nN20 R1={expr}\nN30 G1 X=R1 F100\nM30\n");
    let cases = [
        (
            "hh-brackets",
            "heidenhain",
            heidenhain(format!("{}1{}", "(".repeat(n), ")".repeat(n))),
        ),
        (
            "hh-sqrt",
            "heidenhain",
            heidenhain(format!("{}1{}", "SQRT (".repeat(n), ")".repeat(n))),
        ),
        (
            "hh-signs",
            "heidenhain",
            heidenhain(format!("{}1", "-".repeat(n))),
        ),
        (
            "sie-brackets",
            "siemens",
            sinumerik(format!("{}1{}", "(".repeat(n), ")".repeat(n))),
        ),
        (
            "sie-sin",
            "siemens",
            sinumerik(format!("{}1{}", "SIN(".repeat(n), ")".repeat(n))),
        ),
        (
            "sie-signs",
            "siemens",
            sinumerik(format!("{}1", "-".repeat(n))),
        ),
    ];
    for (name, dialect, program) in cases {
        let dir = scratch("bounded", name);
        std::fs::write(dir.join("p.txt"), program).unwrap();
        let path = dir.join("s.toml");
        std::fs::write(
            &path,
            format!(
                "machine = {:?}\n[program]\nfile = \"p.txt\"\n[reader]\ndialect = \"{dialect}\"\n",
                machine("vmc-3axis")
            ),
        )
        .unwrap();
        let (out, stderr) = check(&path);
        assert_refused(&out, &stderr, "p.txt:2:");
        assert!(stderr.contains("nested"), "{name}: {stderr}");
    }
}
