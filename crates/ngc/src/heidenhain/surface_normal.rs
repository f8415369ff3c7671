//! `LN`: a straight line with the surface normal and, under TCP, the tool's direction, as
//! CAM posts write five-axis and 3D-compensated paths for the TNC.
//!
//! HEIDENHAIN TNC 640 Klartext programming manual, "Three-dimensional tool compensation":
//! `LN X Y Z NX NY NZ [TX TY TZ]`, the end point, the unit normal of the surface at it, and
//! the tool's direction. The control moves the tool's reference point to X Y Z offset by
//! the tool's delta values along the normal:
//!
//! ```text
//! end = P + DR · N            (N = (NX, NY, NZ)/|N|, DR the delta radius of the tool)
//! ```
//!
//! so with `DR = 0` (a tool of its nominal size) the block is `L X Y Z`. `TX TY TZ` act
//! under `M128` / `FUNCTION TCPM` only ("tool orientation with M128"): the rotary axes
//! turn so that the tool lies along T = (TX, TY, TZ)/|T| in the workpiece frame, with the
//! tool tip held on the path, as an `L X Y Z A C` under TCP. On a table-table machine the
//! rotary solution is that of `PLANE … TURN SEQ+` (the positive tilt, C next to its
//! current value).
//!
//! Refused, each named: a delta radius (3D radius compensation is not simulated), `RL`/`RR`
//! (an `LN` block has none), the tool direction without TCP, and the tool direction in a
//! tilted working plane.

use crate::axis::Axis;
use crate::lex::{LineError, LineResult};

use super::contour::{extra, motion, release};
use super::state::{Block, Extras, Reader};
use super::text::split_word;

/// The vector words of an `LN` block: letter pair and slot (N 0-2, T 3-5).
const VECTOR_WORDS: [&str; 6] = ["NX", "NY", "NZ", "TX", "TY", "TZ"];

/// `LN X.. Y.. Z.. NX.. NY.. NZ.. [TX.. TY.. TZ..] [R0] [F..|FMAX] [M..]`.
pub(super) fn ln(r: &mut Reader, b: &Block) -> LineResult<()> {
    let mut target = r.path.pos;
    let mut mask = 0u8;
    let mut vectors: [Option<f64>; 6] = [None; 6];
    let mut e = Extras::default();
    for k in 1..b.toks.len() {
        let (name, rest) = split_word(b.tok(k));
        let upper = name.to_ascii_uppercase();
        let (inc, axis) = match upper.strip_prefix('I') {
            Some(a) if a.len() == 1 => (true, a),
            _ => (false, upper.as_str()),
        };
        if let Some(i) = ["X", "Y", "Z"].iter().position(|l| *l == axis) {
            if !rest.is_empty() {
                let v = b.value(k, name.len(), &r.q)?;
                target[i] = if inc { target[i] + v } else { v };
                mask |= 1 << i;
                continue;
            }
        }
        if let Some(i) = VECTOR_WORDS.iter().position(|w| *w == upper) {
            if !rest.is_empty() {
                vectors[i] = Some(b.value(k, name.len(), &r.q)?);
                continue;
            }
        }
        if matches!(axis, "A" | "B" | "C") && !rest.is_empty() {
            return Err(LineError::new(
                b.span(k),
                format!("`{}` in an LN block: the rotary axes of an LN block come from its tool direction TX TY TZ (under M128 or FUNCTION TCPM), not from axis words", b.tok(k)),
                "rotary axis in LN",
            )
            .help("write the rotary positions in an L block, or give TX TY TZ"));
        }
        if !extra(r, b, k, &mut e)? {
            return Err(super::state::unexpected(
                b,
                k,
                "an LN block",
                "X Y Z (I for incremental), NX NY NZ, TX TY TZ, R0, F, FMAX or M functions",
            ));
        }
    }
    if matches!(e.comp, Some(1 | 2)) {
        return Err(LineError::new(b.span(0), "RL or RR in an LN block: an LN block is compensated in 3D along its normal, not in the plane (KP \"Three-dimensional tool compensation\")", "radius compensation in LN"));
    }
    let normal = vector(b, &vectors[..3], "normal NX NY NZ")?;
    if r.tool.2 != 0.0 && normal.is_some() {
        return Err(LineError::new(
            b.span(0),
            format!("LN with the tool's delta radius DR {:+}: the 3D radius compensation along the surface normal is not simulated", r.tool.2),
            "3D tool compensation",
        )
        .help("call the tool with DR+0 (the CAM system then gives the path of the tool as it is)"));
    }
    if let Some(t) = vector(b, &vectors[3..], "tool direction TX TY TZ")? {
        turn_to(r, b, t, &e, &mut target, &mut mask)?;
    }
    release(r, b)?;
    if let Some(f) = e.feed {
        r.path.feed = Some(f);
    }
    r.path.rapid = e.rapid;
    let g = if e.rapid { "0" } else { "1" };
    motion(r, b, g, &target, mask, None, &e)?;
    r.path.pos = target;
    r.path.dir = None;
    if e.m91 || e.m140.is_some() || e.tcp.is_some() {
        r.sync_position(b)?;
    }
    Ok(())
}

/// The unit vector of three optional components, `None` when none is given.
fn vector(b: &Block, c: &[Option<f64>], what: &str) -> LineResult<Option<[f64; 3]>> {
    if c.iter().all(Option::is_none) {
        return Ok(None);
    }
    let v = [0, 1, 2].map(|k| c[k].unwrap_or(0.0));
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if !(n > 1e-9) {
        return Err(LineError::new(
            b.span(0),
            format!("LN with the {what} zero: expected a vector of non-zero length"),
            "zero vector",
        ));
    }
    Ok(Some(v.map(|x| x / n)))
}

/// The rotary axes of `target` turned so the tool lies along `t` (under TCP only).
fn turn_to(
    r: &mut Reader,
    b: &Block,
    t: [f64; 3],
    e: &Extras,
    target: &mut [f64; 6],
    mask: &mut u8,
) -> LineResult<()> {
    let tcp = match e.tcp {
        Some(on) => on,
        None => r.interp.tcp_active(),
    };
    if !tcp {
        return Err(LineError::new(
            b.span(0),
            "LN with the tool direction TX TY TZ but no TCP: the TNC turns the tool to TX TY TZ only under M128 or FUNCTION TCPM (KP \"Three-dimensional tool compensation\")",
            "tool direction without TCP",
        )
        .help("switch TCP on with M128 or FUNCTION TCPM before the LN blocks"));
    }
    if r.frames_state.plane.is_some() || r.frames_state.rot_deg != 0.0 {
        return Err(LineError::new(
            b.span(0),
            "LN with the tool direction TX TY TZ in a tilted or rotated working plane: mtsim takes the tool direction in the workpiece frame only",
            "tool direction in a tilted plane",
        )
        .help("reset the plane (PLANE RESET STAY) before the LN blocks"));
    }
    let q = r.interp.rotaries_for_direction(t).map_err(|why| {
        LineError::new(
            b.span(0),
            format!(
                "LN tool direction ({:.6}, {:.6}, {:.6}): {why}",
                t[0], t[1], t[2]
            ),
            "tool direction out of reach",
        )
    })?;
    let rotaries = match r.table {
        Some(table) => vec![table.tilt, Axis::C],
        None => r.chain_rotaries.clone(),
    };
    for axis in rotaries {
        if let Some(slot) = [Axis::A, Axis::B, Axis::C].iter().position(|a| *a == axis) {
            target[3 + slot] = q[axis];
            *mask |= 1 << (3 + slot);
        }
    }
    Ok(())
}
