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

/// A program path that names no program (a scenario file, an image): the message gives its
/// path, line and column, never its content, and says what to check. A real program that
/// fails on its first block keeps the reader's message and its line.
#[test]
fn a_program_path_that_names_no_program_is_named_without_its_content() {
    let dir = scratch("messages", "not-a-program");
    let image: Vec<u8> = [0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1a, b'\n']
        .into_iter()
        .chain((0..200u32).map(|i| (i * 37 % 251) as u8))
        .collect();
    std::fs::write(dir.join("image.nc"), &image).unwrap();
    std::fs::write(
        dir.join("other.toml"),
        "# SECRET-FIRST-LINE of some TOML\nkey = \"SECRET-SECOND-LINE\"\n",
    )
    .unwrap();
    for program in ["image.nc", "other.toml"] {
        write_scenario(
            &dir,
            &trt_ac(),
            &format!("[program]\nfile = \"{program}\"\n"),
        );
        let (code, err) = analyze_stderr(&dir);
        assert_eq!(code, Some(2), "{err}");
        assert!(err.contains(&format!("{program}:1:")), "{err}");
        assert!(err.contains("not an NC program"), "{err}");
        for quoted in ["SECRET", "PNG", "NAS", "key"] {
            assert!(!err.contains(quoted), "{program} quoted `{quoted}`: {err}");
        }
    }
}

#[test]
fn a_program_that_fails_on_its_first_block_is_quoted_with_the_readers_message() {
    let dir = scratch("messages", "first-block");
    std::fs::write(dir.join("p.nc"), "(a part)\nG01 X1.2.3 F100\nM30\n").unwrap();
    write_scenario(&dir, &trt_ac(), "[program]\nfile = \"p.nc\"\n");
    let (code, err) = analyze_stderr(&dir);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("p.nc:2:5:") && err.contains("G01 X1.2.3 F100"),
        "{err}"
    );
    assert!(!err.contains("not an NC program"), "{err}");
}
