//! Reading TOML input files (machines, scenarios) with errors that point at the line.

use std::ops::Range;
use std::path::Path;

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
    let key = before[line_start..].trim_end().strip_suffix('=')?.trim();
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

/// Byte range of `key = ...` inside the table `[section]` of a TOML text, found by a
/// line scan. `section` is the dotted header without brackets ("" for the top level).
/// Used to point value errors found after deserialization at their line.
pub fn locate_key(text: &str, section: &str, key: &str) -> Option<Range<usize>> {
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
    match locate_key(text, section, key) {
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
        assert_eq!(key_of_value_at(text, text.find("[program").unwrap()), None);
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
