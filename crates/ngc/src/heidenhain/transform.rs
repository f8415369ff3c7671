//! Cycle 8 MIRROR IMAGE, cycle 11 SCALING and cycle 26 AXIS-SPECIFIC SCALING, the cycles'
//! blocks; the map of the emitted words they set is `word_map`.
//!
//! HEIDENHAIN TNC 640 / iTNC 530 cycle programming manual, "Coordinate transformation
//! cycles": the transformations act about the current datum (cycle 7) in the order datum
//! shift, working plane (cycle 19, `PLANE`), mirror image, rotation (cycle 10), scaling.
//! A program point p is at
//!
//! ```text
//! w = d + P · M · Rz(rot) · S(p)          d datum, P plane, M mirror, S scaling
//! S(p)_a = s · (cc_a + f_a (p_a − cc_a))   s = cycle 11's SCL (about the datum),
//!                                           f, cc = cycle 26's factors and centre CCX CCY CCZ
//! M = diag(±1, ±1, 1)                       cycle 8's mirrored axes X, Y
//! ```
//!
//! M turns Rz(rot) the other way (`M Rz(rot) = Rz(−rot) M` when one axis of X Y is
//! mirrored), so the words are mapped by `M S` here and the interpreter's frame (G52 or
//! G68.2, `frames`) holds `d + P Rz(±rot)`. Where the map turns a plane over an arc runs
//! the other way (G2 ↔ G3: "if you mirror only one axis, the machining direction is
//! reversed") and the tool is on the other side (RL ↔ RR, G41.1 ↔ G42.1). Scaling acts on
//! all three axes (the TNC 640's; the iTNC 530's default) and so on the dimensions of
//! cycles; a CR radius, RND and CHF scale with the coordinates; the tool radius does not.
//! An arc in a plane whose two axes have different factors is refused ("axes sharing
//! coordinates for circular arcs must not be scaled by different factors"), as are the
//! spindle axis Z, rotary and parallel axes in cycle 8, and cycles 11 and 26 in effect
//! together (their combined order is not given).

use crate::lex::{LineError, LineResult};

use super::frames;
use super::state::{Block, Reader};
use super::text::{split_word, value};
use super::word_map::Map;

/// Before a change of the map: the words so far run under the old one; radius
/// compensation must be off.
fn begin(r: &mut Reader, b: &Block, n: u32) -> LineResult<()> {
    if r.path.comp != 0 {
        return Err(LineError::new(
            b.spans(0, 2),
            format!("cycle {n} with radius compensation RL/RR in effect: expected R0 before a coordinate transformation changes"),
            "compensation on",
        ));
    }
    r.sync_position(b)
}

/// After a change of the map: the frame again (cycle 10 turns the other way under a
/// mirror) and the program position under the new map.
fn end(r: &mut Reader, b: &Block, map: Map) -> LineResult<()> {
    r.frames_state.map = map;
    frames::apply(r, b)
}

/// `CYCL DEF 8.1 X Y` (the mirrored axes; none: the mirror image ends).
pub(super) fn mirror(r: &mut Reader, b: &Block) -> LineResult<()> {
    let mut axes = [false; 2];
    for k in 3..b.toks.len() {
        let t = b.tok(k).to_ascii_uppercase();
        // `X Y` or run together, `XY`.
        for c in t.chars() {
            match c {
                'X' => axes[0] = true,
                'Y' => axes[1] = true,
                'Z' => return Err(LineError::new(b.span(k), "`Z` in cycle 8: the spindle axis cannot be mirrored (TNC 640 cycle programming manual, \"Cycle 8\"): expected X, Y or both", "spindle axis mirrored")),
                'A' | 'B' | 'C' | 'U' | 'V' | 'W' => return Err(LineError::new(b.span(k), format!("`{c}` in cycle 8: mtsim mirrors the axes X and Y only (a mirrored rotary or parallel axis is not supported)"), "axis not mirrored")),
                _ => return Err(LineError::new(b.span(k), format!("`{t}` in cycle 8: expected the mirrored axes X, Y (none: the mirror image ends)"), "not an axis")),
            }
        }
    }
    begin(r, b, 8)?;
    let mut map = r.frames_state.map;
    map.mirror = axes;
    end(r, b, map)
}

/// A scaling factor: 0.000001 to 99.999999 (the TNC's input range).
fn factor(v: f64, span: std::ops::Range<usize>, n: u32) -> LineResult<f64> {
    if (0.000_001..100.0).contains(&v) {
        return Ok(v);
    }
    Err(LineError::new(
        span,
        format!("cycle {n}: scaling factor {v}: expected 0.000001 to 99.999999"),
        "bad scaling factor",
    ))
}

/// `CYCL DEF 11.1 SCL 0.75` (SCL 1 ends the scaling).
pub(super) fn scaling(r: &mut Reader, b: &Block) -> LineResult<()> {
    let mut scl = None;
    let mut k = 3;
    while k < b.toks.len() {
        let (name, rest) = split_word(b.tok(k));
        let (text, span) = match (name.to_ascii_uppercase().as_str(), rest) {
            ("SCL", "") => {
                k += 1;
                (b.tok(k), b.span(k))
            }
            ("SCL", rest) => (rest, b.span(k)),
            _ => {
                return Err(LineError::new(
                    b.span(k),
                    format!("`{}` in cycle 11: expected SCL and the factor", b.tok(k)),
                    "not SCL",
                ))
            }
        };
        scl = Some(factor(value(text, &r.q, span.clone())?, span, 11)?);
        k += 1;
    }
    let Some(scl) = scl else {
        return Err(LineError::new(
            b.spans(0, 2),
            "CYCL DEF 11.1 without SCL: expected `CYCL DEF 11.1 SCL 0.75`",
            "no factor",
        ));
    };
    let mut map = r.frames_state.map;
    if scl != 1.0 && map.factor != [1.0; 3] {
        return Err(both(b));
    }
    begin(r, b, 11)?;
    map.scl = scl;
    end(r, b, map)
}

fn both(b: &Block) -> LineError {
    LineError::new(b.spans(0, 2), "cycles 11 SCALING and 26 AXIS-SPECIFIC SCALING together: mtsim does not combine them (their order is not given); expected one reset (SCL 1, or factors 1) before the other", "two scalings")
}

/// `CYCL DEF 26.1 X1.4 Y0.6 CCX+15 CCY+20` (factor 1 ends an axis's scaling).
pub(super) fn axis_scaling(r: &mut Reader, b: &Block) -> LineResult<()> {
    let mut map = r.frames_state.map;
    let mut pending: Option<usize> = None;
    for k in 3..b.toks.len() {
        let t = b.tok(k);
        let (name, rest) = split_word(t);
        let name = name.to_ascii_uppercase();
        let axis = |s: &str| ["X", "Y", "Z"].iter().position(|a| *a == s);
        let (target, text) = match (name.as_str(), pending.take()) {
            ("", Some(a)) => (a, t),
            (n, None) if axis(n).is_some() && rest.is_empty() => {
                pending = axis(n);
                continue;
            }
            (n, None) if axis(n).is_some() => (axis(n).unwrap_or(0), rest),
            (n, None) if n.len() == 3 && n.starts_with("CC") && axis(&n[2..]).is_some() => {
                (3 + axis(&n[2..]).unwrap_or(0), rest)
            }
            _ => {
                return Err(LineError::new(
                    b.span(k),
                    format!(
                        "`{t}` in cycle 26: expected the factors X Y Z and the centre CCX CCY CCZ"
                    ),
                    "unexpected word",
                ))
            }
        };
        let v = value(text, &r.q, b.span(k))?;
        if target < 3 {
            map.factor[target] = factor(v, b.span(k), 26)?;
        } else {
            map.centre[target - 3] = v;
        }
    }
    if let Some(a) = pending {
        return Err(LineError::new(
            b.span(b.toks.len().saturating_sub(1)),
            format!(
                "cycle 26: the axis {} without its factor",
                ["X", "Y", "Z"][a]
            ),
            "no factor",
        ));
    }
    if map.factor != [1.0; 3] && map.scl != 1.0 {
        return Err(both(b));
    }
    begin(r, b, 26)?;
    end(r, b, map)
}
