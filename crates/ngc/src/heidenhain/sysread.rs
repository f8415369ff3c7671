//! `FN 18: SYSREAD Q = ID n NR m IDX k`: the system data CAM posts read, from the reader's
//! state. TNC 640 User's Manual for Klartext programming, "Q parameters", "FN 18: SYSREAD –
//! Read system data" (the table of IDs): ID 20 (active tool: NR1 its number, NR3 its axis),
//! ID 50 (the tool table: NR1 L, NR2 R, NR4 DL, NR5 DR, NR6 DR2 of tool IDX, the active
//! one without IDX), ID 240 (nominal position in the REF system, axis IDX 1-6 = X Y Z A B
//! C) and ID 270 (current position in the active coordinate system, axis IDX). Every other
//! ID or NR is refused, naming it and the manual's section, never read as 0.
//!
//! `FN 17: SYSWRITE ID50 NR m IDX k = v` (same manual, "FN 17: SYSWRITE – Write system
//! data") writes the tool table: a column that does not move the axes (NR 7 and up: tool
//! life, cutting data, tolerances, type …) is accepted with a notice; the geometry (NR1-6: L,
//! R, R2, DL, DR, DR2) marks the tool as changed, and a later `TOOL CALL` or `FN 18` of it
//! is refused, since mtsim's tool table stays as the run began.

use super::qparam::Qparams;
use super::state::Block;
use super::Reader;
use crate::axis::Axis;
use crate::lex::{LineError, LineResult};

/// The ID, NR and IDX numbers of `ID270 NR1 IDX3` or `IDXQ8` (a Q parameter holding a
/// whole number; NR and IDX absent: `None`).
fn numbers(text: &str, q: &Qparams) -> Option<(u32, Option<u32>, Option<u32>)> {
    let upper = text.to_ascii_uppercase();
    let after = |key: &str| -> Option<u32> {
        let word = upper.split_whitespace().find(|w| {
            let rest = &w[key.len().min(w.len())..];
            w.starts_with(key)
                && !rest.is_empty()
                && (rest.bytes().all(|c| c.is_ascii_digit()) || rest.starts_with('Q'))
        })?;
        let rest = &word[key.len()..];
        let v = match rest.parse::<u32>() {
            Ok(v) => f64::from(v),
            Err(_) => q.get_ref(rest, 0..0).ok()?,
        };
        (v >= 0.0 && v.fract() == 0.0 && v < 1e9).then_some(v as u32)
    };
    Some((after("ID")?, after("NR"), after("IDX")))
}

/// Runs `FN 18: SYSREAD Q… = ID … NR … [IDX …]`; `rest` is the text after `FN 18:`, at byte
/// `at` of the block.
pub(super) fn read(r: &mut Reader, b: &Block, rest: &str, at: usize) -> LineResult<()> {
    let upper = rest.to_ascii_uppercase();
    let manual = "TNC 640 User's Manual, \"FN 18: SYSREAD\"";
    let eq = rest.find('=');
    let (Some(eq), true) = (eq, upper.trim_start().starts_with("SYSREAD")) else {
        return Err(LineError::new(
            at..b.text.len(),
            "FN 18: expected `FN 18: SYSREAD Q1 = ID… NR… IDX…`",
            "bad FN 18",
        ));
    };
    let target = rest[..eq].trim()["SYSREAD".len()..].trim().to_string();
    let span = at + eq + 1..b.text.len();
    let Some((id, nr, idx)) = numbers(&rest[eq + 1..], &r.q) else {
        return Err(LineError::new(
            span,
            "FN 18: expected `ID` and a number after `=`",
            "no ID",
        ));
    };
    let refuse = |what: &str| {
        LineError::new(
            span.clone(),
            format!("`FN 18: SYSREAD` ID{id} NR{} ({what}) is not modelled by mtsim ({manual}), so the program is not read", nr.unwrap_or(0)),
            "system datum not modelled",
        )
        .help("mtsim reads ID20 NR1/NR3, ID50 NR1/2/4/5/6, ID240 NR1 and ID270 NR1")
    };
    let scale = if r.inch {
        crate::units::MM_PER_INCH
    } else {
        1.0
    };
    let axis = |k: Option<u32>| -> LineResult<Axis> {
        match k {
            Some(k @ 1..=6) => Ok(Axis::XYZABC[k as usize - 1]),
            _ => Err(refuse("an axis index other than IDX1-6 (X Y Z A B C)")),
        }
    };
    if let Some(&(tool, line)) = r
        .rewritten
        .iter()
        .find(|(t, _)| id == 50 && *t == idx.unwrap_or(r.tool.0))
    {
        return Err(LineError::new(span, format!("`FN 18: SYSREAD` ID50 reads tool {tool}, whose geometry FN 17 changed at line {line}: mtsim's tool table stays as the run began"), "tool table changed"));
    }
    let value = match (id, nr.unwrap_or(1)) {
        (20, 1) => r.tool.0 as f64,
        // Tool axis: 2 = Z, the only one mtsim reads (TOOL CALL … Z).
        (20, 3) => 2.0,
        (50, n @ (1 | 2 | 4 | 5 | 6)) => {
            let number = idx.unwrap_or(r.tool.0);
            let t = r.tools.iter().find(|t| t.number == number);
            if t.is_none() && !r.tools.is_empty() {
                return Err(LineError::new(
                    span,
                    format!("`FN 18: SYSREAD` ID50 reads tool {number}, which the tool table does not have"),
                    "no such tool",
                ));
            }
            let (length, radius) = t.map_or((0.0, 0.0), |t| (t.length_mm, t.diameter_mm / 2.0));
            // mtsim's tool table holds the values in effect: its deltas are 0, except
            // the TOOL CALL's DL and DR for the active tool.
            let active = number == r.tool.0;
            match n {
                1 => length / scale,
                2 => radius / scale,
                4 if active => r.tool.1,
                5 if active => r.tool.2,
                _ => 0.0,
            }
        }
        (240, 1) => {
            r.sync_position(b)?;
            let a = axis(idx)?;
            let m = r.interp.machine_tip();
            if a.is_rotary() {
                m[a]
            } else {
                m[a] / scale
            }
        }
        (270, 1) => {
            r.sync_position(b)?;
            r.program_position()[axis(idx)?]
        }
        (20, _) => return Err(refuse("active tool data other than its number and axis")),
        (50, _) => return Err(refuse("tool table data other than L, R, DL, DR and DR2")),
        _ => return Err(refuse("system data mtsim does not keep")),
    };
    r.q.set_ref(&target, value, at..at + eq)
}

/// Runs `FN 17: SYSWRITE ID50 NR… IDX… = value`; `rest` is the text after `FN 17:`.
pub(super) fn write(r: &mut Reader, b: &Block, rest: &str, at: usize) -> LineResult<()> {
    let upper = rest.to_ascii_uppercase();
    let eq = rest.find('=');
    let (Some(eq), true) = (eq, upper.trim_start().starts_with("SYSWRITE")) else {
        return Err(LineError::new(
            at..b.text.len(),
            "FN 17: expected `FN 17: SYSWRITE ID… NR… IDX… = value`",
            "bad FN 17",
        ));
    };
    let span = at..at + eq;
    let numbers = numbers(&rest["SYSWRITE".len().min(eq)..eq], &r.q);
    let value_span = at + eq + 1..b.text.len();
    super::text::value(rest[eq + 1..].trim(), &r.q, value_span)?;
    match numbers {
        Some((50, Some(nr), idx)) => {
            let tool = idx.unwrap_or(r.tool.0);
            if nr <= 6 {
                r.rewritten.push((tool, b.line));
            } else {
                r.note(b, &format!("`FN 17: SYSWRITE` ID50 NR{nr} (a tool table column that does not move the axes) of tool {tool} accepted and not kept"));
            }
            Ok(())
        }
        _ => Err(LineError::new(span, "`FN 17: SYSWRITE` of data other than the tool table (ID50 NR…) is not supported (TNC 640 User's Manual, \"FN 17: SYSWRITE\")", "system datum not modelled")),
    }
}

/// Refuses a `TOOL CALL` of a tool whose geometry `FN 17` changed.
pub(super) fn unchanged(r: &Reader, tool: u32, span: std::ops::Range<usize>) -> LineResult<()> {
    match r.rewritten.iter().find(|(t, _)| *t == tool) {
        Some((_, line)) => Err(LineError::new(span, format!("`TOOL CALL {tool}`: FN 17 changed this tool's geometry at line {line}; mtsim's tool table stays as the run began"), "tool table changed")),
        None => Ok(()),
    }
}
