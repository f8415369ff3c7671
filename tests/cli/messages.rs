//! The error messages users see, pinned as insta snapshots: `file:line:column: message`,
//! the source line with its label, and the help text.

use crate::common;

use std::path::Path;

use common::{mtsim_plain, scratch, trt_ac, write_scenario};

/// Runs `mtsim analyze s.toml` in `dir` as a user would from their own folder (a relative path,
/// so that the message and where it wraps do not depend on where the temporary folder lives),
/// as plain text. Returns the exit code and stderr with `dir` replaced by `[SCRATCH]` and ANSI escapes removed.
fn analyze_stderr(dir: &Path) -> (Option<i32>, String) {
    let out = mtsim_plain(dir, &["analyze", "s.toml"]);
    let err = String::from_utf8(out.stderr).expect("stderr is UTF-8");
    let err = strip_ansi(&err).replace(&dir.display().to_string(), "[SCRATCH]");
    (out.status.code(), err)
}

/// Removes ANSI CSI (`ESC [ ... letter`) and OSC (`ESC ] ... ESC \` or BEL) sequences.
fn strip_ansi(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let mut chars = s.chars().peekable();
    while let Some(c) = chars.next() {
        if c != '\u{1b}' {
            out.push(c);
            continue;
        }
        match chars.next() {
            Some('[') => {
                for c in chars.by_ref() {
                    if c.is_ascii_alphabetic() {
                        break;
                    }
                }
            }
            Some(']') => {
                while let Some(c) = chars.next() {
                    if c == '\u{7}' || (c == '\u{1b}' && chars.next_if_eq(&'\\').is_some()) {
                        break;
                    }
                }
            }
            _ => {}
        }
    }
    out
}

#[test]
fn a_malformed_number_in_a_program_names_file_line_and_column_with_help() {
    let dir = scratch("messages", "malformed");
    std::fs::write(
        dir.join("p.nc"),
        "G21 G90 G94\nG00 X0 Y0 Z100 A0 C0\nG01 X1.2.3 F100\nM30\n",
    )
    .unwrap();
    write_scenario(&dir, &trt_ac(), "[program]\nfile = \"p.nc\"\n");
    let (code, err) = analyze_stderr(&dir);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("p.nc:3:5:"), "{err}");
    assert!(
        err.contains("G01 X1.2.3 F100") && err.contains("help:"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    insta::assert_snapshot!(err);
}
