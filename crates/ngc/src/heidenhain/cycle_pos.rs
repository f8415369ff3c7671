//! `CYCL CALL POS X Y Z [F|FMAX] [M…]`: the defined cycle at a position given in the call
//! (TNC 640 cycle programming manual, "Calling cycles": "Calling a cycle with CYCL CALL
//! POS").
//!
//! The block names all three coordinates. The control reaches the position with its
//! positioning logic, without radius compensation, at the block's feed (FMAX when it gives
//! none): with the tool above the workpiece surface s it moves in the working plane first;
//! below it, first up the tool axis to the set-up clearance, then in the plane. The
//! tool-axis coordinate is, in the manual's words, an additional datum shift: for the
//! 200-series cycles the surface is s = Q203 + Z (the cycle then makes its own FMAX move
//! to s + Q200); the old cycles 1, 2 and 17, which start where the tool stands, start at
//! the position X Y Z.
//!
//! ```text
//! z > s:  (X, Y, z) ─► [(X, Y, Z) for 1, 2, 17] ─► the cycle
//! z ≤ s:  (x, y, s + Q200 | Z) ─► (X, Y, …) ─► the cycle
//! ```

use crate::lex::{LineError, LineResult};

use super::state::{self, Block, Extras, Reader};
use super::text::split_word;
use super::{approach, contour, cycles};

/// `CYCL CALL POS …`.
pub(super) fn call(r: &mut Reader, b: &Block) -> LineResult<()> {
    let mut at = r.path.pos;
    let mut given = 0u8;
    let mut e = Extras::default();
    let mut feed = None;
    for k in 3..b.toks.len() {
        if let Some(a) = approach::xyz_word(r, b, k, &mut at)? {
            given |= 1 << a;
            continue;
        }
        if !feed_or_m(r, b, k, &mut feed, &mut e)? {
            return Err(state::unexpected(
                b,
                k,
                "CYCL CALL POS",
                "X Y Z, F or FMAX, and M functions",
            ));
        }
    }
    if given != 7 {
        return Err(LineError::new(
            b.spans(0, 2),
            "CYCL CALL POS names all three coordinates: expected X, Y and Z",
            "coordinates",
        ));
    }
    call_at(r, b, [at[0], at[1], at[2]], feed)?;
    contour::run_extras(r, b, &e, None)
}

/// Token `k` of a cycle call as its feed (`F…`; `FMAX`, `F MAX`: rapid) or an M function;
/// false when it is neither.
pub(super) fn feed_or_m(
    r: &mut Reader,
    b: &Block,
    k: usize,
    feed: &mut Option<f64>,
    e: &mut Extras,
) -> LineResult<bool> {
    let (name, rest) = split_word(b.tok(k));
    match name.to_ascii_uppercase().as_str() {
        "FMAX" => *feed = None,
        "F" if b.is(k + 1, "MAX") => {}
        "MAX" if b.is(k - 1, "F") => *feed = None,
        "F" if !rest.is_empty() => *feed = Some(b.value(k, 1, &r.q)?),
        _ => return contour::m_word(r, b, k, e),
    }
    Ok(true)
}

/// The defined cycle at `at` (X Y, and Z the shift of the surface), reached at `feed`
/// (rapid when `None`).
pub(super) fn call_at(
    r: &mut Reader,
    b: &Block,
    at: [f64; 3],
    feed: Option<f64>,
) -> LineResult<()> {
    let Some(n) = r.cycle.number else {
        return cycles::call(r, b);
    };
    let old = matches!(n, 1 | 2 | 17);
    let shift = at[2];
    let surface = if old { shift } else { r.q.q(203) + shift };
    // The modal cycle (M89) must not run at the positioning moves.
    let modal = std::mem::replace(&mut r.modal_cycle, false);
    let saved_feed = r.path.feed;
    if feed.is_some() {
        r.path.feed = feed;
    }
    let g = if feed.is_some() { "1" } else { "0" };
    let mut p = r.path.pos;
    let positioned: LineResult<()> = (|| {
        if p[2] <= surface {
            p[2] = if old { shift } else { surface + r.q.q(200) };
            contour::motion(r, b, g, &p, 4, None, &Extras::default())?;
        }
        p[0] = at[0];
        p[1] = at[1];
        contour::motion(r, b, g, &p, 3, None, &Extras::default())?;
        if old && p[2] != shift {
            p[2] = shift;
            contour::motion(r, b, g, &p, 4, None, &Extras::default())?;
        }
        Ok(())
    })();
    r.modal_cycle = modal;
    r.path.feed = saved_feed;
    positioned?;
    r.path.pos = p;
    if old {
        return cycles::call(r, b);
    }
    let q203 = r.q.q(203);
    r.q.set_ref("Q203", surface, b.span(0))?;
    let run = cycles::call(r, b);
    r.q.set_ref("Q203", q203, b.span(0))?;
    run
}
