//! Reading TOML input files (machines, scenarios) with errors that point at the line.

use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;

use crate::error::{Error, Result};

/// Reads a whole text file: a regular file (after links) of at most
/// [`ngc::MAX_SIDE_FILE_BYTES`] ([`ngc::read_side_bytes`]), so that a device such as
/// `/dev/zero`, a FIFO or a huge file is refused before memory grows; invalid UTF-8 is an
/// error.
pub fn read_text(path: &Path) -> Result<String> {
    ngc::read_side_bytes(path)
        .and_then(|bytes| {
            String::from_utf8(bytes)
                .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e))
        })
        .map_err(|source| Error::Read {
            path: path.to_path_buf(),
            source,
        })
}

/// Deserializes `text` (the contents of `path`); a syntax or schema error names the line,
/// the column and, for an unknown key, the key.
pub fn parse<T: DeserializeOwned>(path: &Path, text: &str) -> Result<T> {
    toml::from_str(text).map_err(|e| toml_error(path, text, &e))
}

/// Converts a `toml` error into an [`Error`] at its span.
pub fn toml_error(path: &Path, text: &str, e: &toml::de::Error) -> Error {
    let message = e.message().trim().to_string();
    match e.span() {
        Some(span) => {
            let message = match key_of_value_at(text, span.start) {
                Some(key) => format!("`{key}`: {message}"),
                None => message,
            };
            Error::at(path, text, span, message, "here")
                .with_help("see docs/machine-format.md and docs/scenario-format.md for every key")
        }
        None => Error::invalid(path, message),
    }
}

/// The dotted key (`program.cone.center_mm`) whose value starts at byte `start`, when
/// `start` follows `key =` on its line; the table is the last `[header]` above it.
fn key_of_value_at(text: &str, start: usize) -> Option<String> {
    let before = text.get(..start)?;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    // A table where a value belongs: the span is its `[header]`.
    let line = text[line_start..].lines().next().unwrap_or("");
    let code = line.split('#').next().unwrap_or("").trim();
    if before[line_start..].trim().is_empty() && code.starts_with('[') && code.ends_with(']') {
        let header = code.trim_start_matches('[').trim_end_matches(']');
        return Some(header.trim().replace([' ', '"'], ""));
    }
    // The span is the value after `key =`, or (an unknown key) the key itself.
    let key = match before[line_start..].trim_end().strip_suffix('=') {
        Some(key) => key.trim(),
        None if before[line_start..].trim().is_empty() => line.split('=').next()?.trim(),
        None => return None,
    };
    let is_key_char = |c: char| c.is_ascii_alphanumeric() || "_-.\"".contains(c);
    if key.is_empty() || !key.chars().all(is_key_char) {
        return None;
    }
    let section = before[..line_start]
        .lines()
        .rev()
        .find_map(|line| {
            let header = line.trim().strip_prefix('[')?.trim_start_matches('[');
            Some(header[..header.find(']')?].trim().replace([' ', '"'], ""))
        })
        .unwrap_or_default();
    let key = key.replace('"', "");
    Some(if section.is_empty() {
        key
    } else {
        format!("{section}.{key}")
    })
}

/// Deserializes the machine table `merged` (a machine file with a scenario's
/// `[machine_overrides]` merged over it); an error, which the overrides made (the machine file
/// was read on its own first), points at its key under `[machine_overrides]` in the scenario.
pub fn parse_overridden<T: DeserializeOwned>(
    merged: &toml::Table,
    scenario_path: &Path,
    scenario_text: &str,
) -> Result<T> {
    let merged_text =
        toml::to_string(merged).map_err(|e| Error::invalid(scenario_path, e.to_string()))?;
    toml::from_str(&merged_text).map_err(|e: toml::de::Error| {
        let message = e.message().trim().to_string();
        let key = e
            .span()
            .and_then(|span| key_of_value_at(&merged_text, span.start));
        let Some(key) = key else {
            return Error::invalid(
                scenario_path,
                format!("[machine_overrides] does not fit the machine format: {message}"),
            );
        };
        let full = format!("{OVERRIDES}.{key}");
        let (section, leaf) = full.rsplit_once('.').unwrap_or(("", full.as_str()));
        let span = locate_key(scenario_text, section, leaf)
            .or_else(|| locate_key_header(scenario_text, &full));
        let message = format!("`{full}`: {message}");
        match span {
            Some(span) => Error::at(scenario_path, scenario_text, span, message, "here"),
            None => Error::invalid(scenario_path, message),
        }
    })
}

/// The largest magnitude any number of a machine or scenario file may have, in its key's
/// unit: 10⁹ mm is 1,000 km, 10⁹ mm/min 16.7 km/s; no machine key comes near it.
pub const MAX_MAGNITUDE: f64 = 1e9;

/// Integer keys that count samples, not a size: they may be raised past [`MAX_MAGNITUDE`]
/// (`trace_every = 1e12` keeps no row but the first: the trace switched off).
const COUNTS: [&str; 3] = ["max_samples", "max_trace_rows", "trace_every"];

/// Refuses a number in `text` (the contents of `path`) that no key can mean: NaN, an
/// infinity, or one larger than [`MAX_MAGNITUDE`] in size (a travel of 1e308 mm, a table of
/// 1e308 mm: values the checks that follow would turn into overflows). Run after the keys'
/// own checks, which give the more precise message where they have one.
pub fn check_numbers(path: &Path, text: &str) -> Result<()> {
    numbers_checked(path, text).map(drop)
}

/// [`check_numbers`], returning the tree it read.
pub fn numbers_checked(path: &Path, text: &str) -> Result<toml::Table> {
    let table: toml::Table = toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
    check_table(path, text, &table, &mut Vec::new())?;
    Ok(table)
}

/// [`check_numbers`] on a tree that has no text: the same refusals, with no line to point
/// at.
pub fn check_tree_numbers(path: &Path, table: &toml::Table) -> Result<()> {
    check_table(path, "", table, &mut Vec::new())
}

fn check_table(path: &Path, text: &str, table: &toml::Table, keys: &mut Vec<String>) -> Result<()> {
    for (key, value) in table {
        keys.push(key.clone());
        check_value(path, text, value, keys)?;
        keys.pop();
    }
    Ok(())
}

fn check_value(path: &Path, text: &str, value: &toml::Value, keys: &mut Vec<String>) -> Result<()> {
    let number = match value {
        toml::Value::Table(t) => return check_table(path, text, t, keys),
        toml::Value::Array(items) => {
            for item in items {
                check_value(path, text, item, keys)?;
            }
            return Ok(());
        }
        toml::Value::Float(f) => *f,
        toml::Value::Integer(i) if !COUNTS.contains(&keys.last().map_or("", String::as_str)) => {
            *i as f64
        }
        _ => return Ok(()),
    };
    if number.is_finite() && number.abs() <= MAX_MAGNITUDE {
        return Ok(());
    }
    let what = if number.is_nan() {
        "is not a number".to_string()
    } else {
        format!("{number:e} is beyond any machine")
    };
    let message = format!(
        "`{}`: {what}; expected a finite number of magnitude at most {MAX_MAGNITUDE:e} in the key's unit",
        keys.join(".")
    );
    // The key's line, or (a value inside an inline table or an array of tables) its
    // nearest enclosing key's.
    let span = (1..=keys.len()).rev().find_map(|n| {
        let (section, key) = (keys[..n - 1].join("."), &keys[n - 1]);
        locate_key(text, &section, key).or_else(|| locate_key_header(text, &keys[..n].join(".")))
    });
    Err(match span {
        Some(span) => Error::at(path, text, span, message, "this value"),
        None => Error::invalid(path, message),
    }
    .with_help("see docs/machine-format.md and docs/scenario-format.md for every key's range"))
}

/// The scenario table whose keys are a machine file's.
const OVERRIDES: &str = "machine_overrides";

/// Byte range of `key = ...` inside the table `[section]` of a TOML text, found by a
/// line scan. `section` is the dotted header without brackets ("" for the top level).
/// Used to point value errors found after deserialization at their line. A machine key
/// not found is looked for under the scenario's `[machine_overrides]` too.
pub fn locate_key(text: &str, section: &str, key: &str) -> Option<Range<usize>> {
    locate_key_in(text, section, key).or_else(|| {
        let overridden = match section {
            "" => OVERRIDES.to_string(),
            s if s.starts_with(OVERRIDES) => return None,
            s => format!("{OVERRIDES}.{s}"),
        };
        locate_key_in(text, &overridden, key)
    })
}

fn locate_key_in(text: &str, section: &str, key: &str) -> Option<Range<usize>> {
    let mut current = String::new();
    let mut offset = 0;
    for line in text.split_inclusive('\n') {
        let trimmed = line.trim_start();
        let indent = line.len() - trimmed.len();
        if let Some(header) = trimmed.strip_prefix('[') {
            let header = header.trim_start_matches('[');
            if let Some(end) = header.find(']') {
                current = header[..end].trim().replace([' ', '"'], "");
            }
        } else if current == section {
            if let Some(rest) = trimmed.strip_prefix(key) {
                if rest.trim_start().starts_with('=') {
                    let start = offset + indent;
                    let end = offset + line.trim_end().len();
                    return Some(start..end);
                }
            }
        }
        offset += line.len();
    }
    None
}

/// An error about the value of `key` in `[section]`, pointing at its line when it can be found.
pub fn value_error(path: &Path, text: &str, section: &str, key: &str, message: String) -> Error {
    let full_key = if section.is_empty() {
        key.to_string()
    } else {
        format!("{section}.{key}")
    };
    // A key inside an inline table (`hal_pins = { "a.b" = 1.0 }`) is pointed at by the
    // table's own key.
    let enclosing = || {
        let (parent, table) = section.rsplit_once('.').unwrap_or(("", section));
        locate_key(text, parent, table).or_else(|| locate_key_header(text, section))
    };
    match locate_key(text, section, key).or_else(enclosing) {
        Some(span) => Error::at(
            path,
            text,
            span,
            format!("`{full_key}`: {message}"),
            "this value",
        ),
        None => Error::invalid(path, format!("`{full_key}`: {message}")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locate_key_finds_the_key_in_its_section_only() {
        let text = "min = 1\n[axes.X]\nmin = -5\n[axes.Y]\n  min = 7\n";
        let r = locate_key(text, "axes.Y", "min").unwrap();
        assert_eq!(&text[r], "min = 7");
        let r = locate_key(text, "", "min").unwrap();
        assert_eq!(&text[r], "min = 1");
        assert!(locate_key(text, "axes.Z", "min").is_none());
    }

    #[test]
    fn a_value_error_names_its_table_and_key() {
        let text = "a = 1\n[program.cone]\nx = 2\ncenter_mm = [0, 0, 200, 5]\n";
        let start = text.find("[0,").unwrap();
        assert_eq!(
            key_of_value_at(text, start).as_deref(),
            Some("program.cone.center_mm")
        );
        assert_eq!(key_of_value_at(text, 4).as_deref(), Some("a"));
        // A table where a value belongs is named by its header.
        assert_eq!(
            key_of_value_at(text, text.find("[program").unwrap()).as_deref(),
            Some("program.cone")
        );
    }
}

/// Byte range of the header line `[section]`, found by a line scan.
pub fn locate_key_header(text: &str, section: &str) -> Option<Range<usize>> {
    let mut offset = 0;
    for line in text.split_inclusive('\n') {
        let trimmed = line.trim();
        if let Some(inner) = trimmed.strip_prefix('[').and_then(|s| s.split(']').next()) {
            if inner.trim().replace([' ', '"'], "") == section {
                let start = offset + (line.len() - line.trim_start().len());
                return Some(start..start + trimmed.len());
            }
        }
        offset += line.len();
    }
    None
}

/// `relative` as named in the input file at `scenario`: from that file's folder, unless it
/// is absolute.
pub fn resolve(scenario: &Path, relative: &str) -> PathBuf {
    let p = Path::new(relative);
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        scenario.parent().unwrap_or(Path::new(".")).join(p)
    }
}
