//! `PATTERN DEF` and `CYCL CALL PAT`: the defined cycle at each point of a pattern (TNC 640
//! Klartext user's manual, "Pattern definition PATTERN DEF"; cycle manual, "Calling
//! cycles").
//!
//! The definition is kept as written (a row of a thousand holes is five numbers) and its
//! points made one at a time at the call. With the start or centre (x, y), rotation ROT
//! about it (deg), k = 0 … NUM − 1:
//!
//! ```text
//! POSn (X Y Z)                         the point (IX IY: from the point before)
//! ROWn (X Y D NUM ROT Z)               (x, y) + rot(ROT) (k D, 0)
//! PATn (X Y DX DY NUMX NUMY ROT Z)     (x, y) + rot(ROT) (i DX, j DY), row j by row
//! FRAMEn (…the same…)                  PAT's points on its border only
//! CIRCn (X Y D START NUM Z)            (x, y) + D/2 (cos a_k, sin a_k), a_k = START + k 360/NUM
//! PITCHCIRCn (X Y D START STEP NUM Z)  a_k = START + k STEP
//! ```
//!
//! Each point is called as `CYCL CALL POS X Y Z FMAX` (`cycle_pos`): Z, the pattern's
//! surface, is the same added shift of Q203, and between points the tool stays at the
//! height the cycle left it (its second set-up clearance) while it moves in the plane.
//! ROTX and ROTY (a sheared pattern) are refused.

use std::ops::Range;

use crate::lex::{LineError, LineResult};

use super::state::{unexpected, Block, Extras, Item, Reader};
use super::text::{split_word, value};
use super::{contour, cycle_pos};

/// The most points one `CYCL CALL PAT` may run: its moves are made in one step, so this
/// bounds the queue (a real pattern holds far fewer).
const MAX_POINTS: u64 = 10_000;

/// `PATTERN DEF …` (its elements on `~` lines joined into one block).
pub(super) fn define(r: &mut Reader, b: &Block) -> LineResult<()> {
    let text = b.text;
    let mut items = Vec::new();
    let mut last = [0.0; 3];
    let mut k = b.span(1).end;
    while let Some(open) = text[k..].find('(').map(|o| k + o) {
        let close = text[open..].find(')').map(|c| open + c).ok_or_else(|| {
            LineError::new(open..text.len(), "PATTERN DEF: `(` without `)`", "unclosed")
        })?;
        let name = text[k..open].trim();
        let kind = name
            .trim_end_matches(|c: char| c.is_ascii_digit())
            .to_ascii_uppercase();
        let span = k + (text[k..open].len() - text[k..open].trim_start().len())..close + 1;
        let v = values(r, &text[open + 1..close], open + 1)?;
        let get = |key: &str, default: Option<f64>| {
            v.iter()
                .find(|(n, _, _)| n == key)
                .map(|(_, x, _)| *x)
                .or(default)
                .ok_or_else(|| {
                    LineError::new(
                        span.clone(),
                        format!("PATTERN DEF {name}: expected {key}"),
                        "missing value",
                    )
                })
        };
        let count = |key: &str| -> LineResult<u32> {
            let n = get(key, None)?;
            if n < 1.0 || n.fract() != 0.0 || n as u64 > MAX_POINTS {
                return Err(LineError::new(
                    span.clone(),
                    format!("PATTERN DEF {name}: {key} {n}: expected a whole count of at least 1"),
                    "bad count",
                ));
            }
            Ok(n as u32)
        };
        let z = get("Z", Some(0.0))?;
        let item = match kind.as_str() {
            "POS" => {
                let inc = |key: &str, a: usize| -> LineResult<f64> {
                    match get(&format!("I{key}"), None) {
                        Ok(d) => Ok(last[a] + d),
                        Err(_) => get(key, Some(last[a])),
                    }
                };
                last = [inc("X", 0)?, inc("Y", 1)?, z];
                Item::Point(last)
            }
            "ROW" | "PAT" | "FRAME" => {
                if get("ROTX", Some(0.0))? != 0.0 || get("ROTY", Some(0.0))? != 0.0 {
                    return Err(LineError::new(span.clone(), format!("PATTERN DEF {name}: ROTX and ROTY (a sheared pattern) are not supported: expected ROTX+0 ROTY+0"), "sheared pattern"));
                }
                let row = kind == "ROW";
                let dx = get("DX", None).or_else(|_| get("D", None))?;
                let nx = count("NUMX").or_else(|_| count("NUM"))?;
                let (dy, ny) = if row { (0.0, 1) } else { (get("DY", None)?, count("NUMY")?) };
                if u64::from(nx) * u64::from(ny) > MAX_POINTS {
                    return Err(LineError::new(span.clone(), format!("PATTERN DEF {name}: more than {MAX_POINTS} points"), "too many points"));
                }
                Item::Grid {
                    at: [get("X", None)?, get("Y", None)?],
                    d: [dx, dy],
                    n: [nx, ny],
                    rot_deg: get("ROT", Some(0.0))?,
                    z,
                    border: kind == "FRAME",
                }
            }
            "CIRC" | "PITCHCIRC" => {
                let n = count("NUM")?;
                Item::Circle {
                    at: [get("X", None)?, get("Y", None)?],
                    diameter: get("D", None)?,
                    start_deg: get("START", Some(0.0))?,
                    step_deg: if kind == "CIRC" { 360.0 / f64::from(n) } else { get("STEP", None)? },
                    n,
                    z,
                }
            }
            _ => {
                return Err(LineError::new(
                    span.clone(),
                    format!("PATTERN DEF `{name}`: expected POS, ROW, PAT, FRAME, CIRC or PITCHCIRC with its number"),
                    "unknown pattern element",
                ))
            }
        };
        items.push(item);
        k = close + 1;
    }
    if items.is_empty() {
        return Err(LineError::new(
            b.spans(0, 1),
            "PATTERN DEF without elements: expected POS1 (X… Y… Z…), ROW1 (…), PAT1 (…), FRAME1 (…), CIRC1 (…) or PITCHCIRC1 (…)",
            "empty pattern",
        ));
    }
    r.pattern = items;
    Ok(())
}

/// The `NAME value` words between a pattern element's brackets (starting at byte `at`).
fn values(r: &Reader, inner: &str, at: usize) -> LineResult<Vec<(String, f64, Range<usize>)>> {
    let mut out = Vec::new();
    let mut k = 0;
    for word in inner.split_whitespace() {
        let start = k + inner[k..].find(word).unwrap_or(0);
        k = start + word.len();
        let span = at + start..at + k;
        let (name, rest) = split_word(word);
        out.push((
            name.to_ascii_uppercase(),
            value(rest, &r.q, span.clone())?,
            span,
        ));
    }
    Ok(out)
}

/// How many points `item` gives.
fn count_of(item: &Item) -> u64 {
    match *item {
        Item::Point(_) => 1,
        Item::Grid { n, border, .. } => {
            let (nx, ny) = (u64::from(n[0]), u64::from(n[1]));
            if border && ny > 2 {
                2 * nx + (ny - 2) * nx.min(2)
            } else {
                nx * ny
            }
        }
        Item::Circle { n, .. } => u64::from(n),
    }
}

/// Point `k` of `item`, and whether there is one.
fn point(item: &Item, k: u64) -> Option<[f64; 3]> {
    match *item {
        Item::Point(p) => (k == 0).then_some(p),
        Item::Grid {
            at,
            d,
            n,
            rot_deg,
            z,
            border,
        } => {
            let (nx, ny) = (u64::from(n[0]), u64::from(n[1]));
            let mut seen = 0;
            // Row by row; a frame keeps the first and last row and column.
            for j in 0..ny {
                let on_edge_row = j == 0 || j + 1 == ny;
                let in_row = if border && !on_edge_row {
                    nx.min(2)
                } else {
                    nx
                };
                if k < seen + in_row {
                    let idx = k - seen;
                    let i = if in_row < nx && idx == 1 { nx - 1 } else { idx };
                    let (s, c) = rot_deg.to_radians().sin_cos();
                    let (u, v) = (i as f64 * d[0], j as f64 * d[1]);
                    return Some([at[0] + u * c - v * s, at[1] + u * s + v * c, z]);
                }
                seen += in_row;
            }
            None
        }
        Item::Circle {
            at,
            diameter,
            start_deg,
            step_deg,
            n,
            z,
        } => (k < u64::from(n)).then(|| {
            let a = (start_deg + k as f64 * step_deg).to_radians();
            [
                at[0] + diameter / 2.0 * a.cos(),
                at[1] + diameter / 2.0 * a.sin(),
                z,
            ]
        }),
    }
}

/// `CYCL CALL PAT [F] [M…]`: the cycle at every point of the pattern.
pub(super) fn call(r: &mut Reader, b: &Block) -> LineResult<()> {
    if r.pattern.is_empty() {
        return Err(LineError::new(
            b.spans(0, 2),
            "CYCL CALL PAT with no PATTERN DEF before it",
            "no pattern",
        ));
    }
    let mut feed = None;
    let mut e = Extras::default();
    for k in 3..b.toks.len() {
        if !cycle_pos::feed_or_m(r, b, k, &mut feed, &mut e)? {
            return Err(unexpected(
                b,
                k,
                "CYCL CALL PAT",
                "F or FMAX, and M functions",
            ));
        }
    }
    let items = r.pattern.clone();
    let mut total = 0;
    for item in &items {
        total += count_of(item);
    }
    if total > MAX_POINTS {
        return Err(LineError::new(b.spans(0, 2), format!("CYCL CALL PAT: the pattern has {total} points, more than the {MAX_POINTS} mtsim runs in one call"), "too many points"));
    }
    for item in &items {
        let mut k = 0;
        while let Some(p) = point(item, k) {
            cycle_pos::call_at(r, b, p, feed)?;
            k += 1;
        }
    }
    contour::run_extras(r, b, &e, None)
}
