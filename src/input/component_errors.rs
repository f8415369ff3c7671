//! `[component_errors]`: the ISO 230-1 component-error tables of the linear axes, one CSV
//! file per axis (the math in [`crate::kinematics::linear_errors`]).
//!
//! ```toml
//! [component_errors]
//! X = "errors/x-errors.csv"   # relative to the file that names it
//!
//! [axes.X]
//! reference_mm = [0.0, 0.0, 0.0]   # r_X, where the table was measured; default the origin
//! ```
//!
//! The file's first line is its header: `position_mm` and any of `EXX_um, EYX_um, EZX_um,
//! EAX_urad, EBX_urad, ECX_urad` (with the axis's letter for X), in any order; an absent
//! column is zero. Then one row per position, ascending; blank lines and text after `#` are
//! ignored.

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::Path;

use nalgebra::Vector3;

use crate::error::{Error, Result};
use crate::input::toml_text::{self, value_error};
use crate::kinematics::linear_errors::{ComponentErrors, ComponentTable};
use crate::kinematics::{Chain, Layout};
use crate::Axis;

/// Largest error accepted in a table, um or urad (1 mm, 1 mrad), as for location errors.
pub const MAX_COMPONENT_ERROR: f64 = 1000.0;

/// The six column names of axis `j` in table order: `EXJ_um` … `ECJ_urad`.
pub fn columns(j: Axis) -> [String; 6] {
    let names = ["EX", "EY", "EZ", "EA", "EB", "EC"];
    std::array::from_fn(|i| {
        let unit = if i < 3 { "um" } else { "urad" };
        format!("{}{j}_{unit}", names[i])
    })
}

/// Reads the tables of `[component_errors]` (`tables`: axis letter → file, relative to
/// `tables_dir`) of the machine file `path` (contents `text`) of `layout` whose nominal
/// chain is `chain`, with each axis's `reference_mm` (default the origin).
pub fn read(
    path: &Path,
    text: &str,
    layout: Layout,
    chain: Option<&Chain>,
    tables: &BTreeMap<String, String>,
    reference_mm: &BTreeMap<Axis, [f64; 3]>,
    tables_dir: &Path,
) -> Result<ComponentErrors> {
    let section = "component_errors";
    let mut out = ComponentErrors::default();
    for (name, file) in tables {
        let refuse = |message: String| Err(value_error(path, text, section, name, message));
        let axis = match name.chars().collect::<Vec<_>>().as_slice() {
            [c] => Axis::from_letter(*c),
            _ => None,
        };
        let Some(axis) = axis.filter(|a| matches!(a, Axis::X | Axis::Y | Axis::Z)) else {
            return refuse("component errors are given for the linear axes X, Y and Z".into());
        };
        if chain.and_then(|c| c.link(axis)).is_none() {
            return refuse(format!(
                "the {} layout has no {axis} axis in a kinematic chain; remove this key",
                layout.name()
            ));
        }
        let table_path = tables_dir.join(file);
        let table_text = toml_text::read_text(&table_path).map_err(|e| match e {
            Error::Read { source, .. } => value_error(
                path,
                text,
                section,
                name,
                format!("cannot read the table {}: {source}", table_path.display()),
            ),
            other => other,
        })?;
        let table = parse(&table_path, &table_text, axis)?;
        let reference = reference_mm.get(&axis).copied().unwrap_or([0.0; 3]);
        out = out.with(axis, table, Vector3::from(reference));
    }
    Ok(out)
}

/// Parses the CSV `text` (the contents of `path`) of axis `j`'s table.
pub fn parse(path: &Path, text: &str, j: Axis) -> Result<ComponentTable> {
    let names = columns(j);
    let expected = format!("position_mm and any of {}", names.join(", "));
    let mut lines = text_lines(text);
    let Some((header_start, header)) = lines.next() else {
        return Err(Error::at(
            path,
            text,
            0..0,
            format!("an empty table; its first line is the header: {expected}"),
            "here",
        ));
    };
    // Which of the six each column fills (None: the position).
    let mut slots: Vec<Option<usize>> = Vec::new();
    for (span, word) in fields(header_start, header) {
        let slot = if word == "position_mm" {
            None
        } else {
            match names.iter().position(|n| n == word) {
                Some(i) => Some(i),
                None => {
                    return Err(Error::at(
                        path,
                        text,
                        span,
                        format!("unknown column `{word}`; expected {expected}"),
                        "unknown column",
                    ))
                }
            }
        };
        if slots.contains(&slot) {
            return Err(Error::at(
                path,
                text,
                span,
                format!("column `{word}` appears twice"),
                "again",
            ));
        }
        slots.push(slot);
    }
    if !slots.contains(&None) {
        let span = header_start..header_start + header.len();
        return Err(Error::at(
            path,
            text,
            span,
            format!("the header has no `position_mm`; expected {expected}"),
            "header",
        ));
    }
    let mut rows: Vec<(f64, [f64; 6])> = Vec::new();
    for (start, line) in lines {
        let row = row_of(path, text, start, line, &slots)?;
        if let Some(last) = rows.last() {
            if row.0 <= last.0 {
                let span = start..start + line.len();
                let message = format!("positions must ascend: {} follows {}", row.0, last.0);
                return Err(Error::at(path, text, span, message, "here"));
            }
        }
        rows.push(row);
    }
    if rows.is_empty() {
        let span = header_start..header_start + header.len();
        return Err(Error::at(
            path,
            text,
            span,
            "a table needs at least one row after its header",
            "header only",
        ));
    }
    Ok(ComponentTable::new(rows))
}

/// One data row: its position and the six errors (absent columns zero).
fn row_of(
    path: &Path,
    text: &str,
    start: usize,
    line: &str,
    slots: &[Option<usize>],
) -> Result<(f64, [f64; 6])> {
    let cells = fields(start, line);
    if cells.len() != slots.len() {
        let span = start..start + line.len();
        let message = format!(
            "a row has {} values, one per header column; got {}",
            slots.len(),
            cells.len()
        );
        return Err(Error::at(path, text, span, message, "this row"));
    }
    let (mut position, mut errors) = (0.0, [0.0; 6]);
    for ((span, word), slot) in cells.into_iter().zip(slots) {
        let limit = if slot.is_some() {
            MAX_COMPONENT_ERROR
        } else {
            f64::INFINITY
        };
        let value = match word.parse::<f64>() {
            Ok(v) if v.is_finite() && v.abs() <= limit => v,
            _ => {
                let message = match slot {
                    Some(_) => format!(
                        "expected a finite number within ±{MAX_COMPONENT_ERROR} (um or urad)"
                    ),
                    None => "expected a finite position, mm".to_string(),
                };
                return Err(Error::at(path, text, span, message, "this value"));
            }
        };
        match slot {
            Some(i) => errors[*i] = value,
            None => position = value,
        }
    }
    Ok((position, errors))
}

/// The non-blank lines of `text` with their byte offsets, comments (after `#`) removed.
fn text_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    let mut offset = 0;
    text.split_inclusive('\n').filter_map(move |line| {
        let start = offset;
        offset += line.len();
        let body = line.split('#').next().unwrap_or("").trim_end();
        (!body.trim().is_empty()).then_some((start, body))
    })
}

/// The comma-separated fields of a line starting at byte `start`: their spans and
/// trimmed texts.
fn fields(start: usize, line: &str) -> Vec<(Range<usize>, &str)> {
    let mut out = Vec::new();
    let mut at = start;
    for cell in line.split(',') {
        let lead = cell.len() - cell.trim_start().len();
        let word = cell.trim();
        out.push((at + lead..at + lead + word.len(), word));
        at += cell.len() + 1;
    }
    out
}
