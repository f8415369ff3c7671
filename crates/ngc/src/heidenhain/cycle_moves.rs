//! The moves the milling cycles (`milling`, `slots`, `studs`, `threads`) are made of: G0
//! along the tool axis and in the plane, G1, G2/G3 (full circles and helices), a rounded
//! rectangle, the levels of a roughing, and the geometry of one cycle call.

use super::state::{Block, Reader};
use crate::lex::{LineError, LineResult};

/// The most circles, levels or helix turns one cycle call may make (its moves are made in
/// one step): a real cycle makes far fewer.
pub(super) const MAX_PASSES: f64 = 10_000.0;

/// One call of a milling cycle: where, the heights, the tool radius, the direction and the
/// feeds' unit.
pub(super) struct Geometry {
    /// The centre X Y (the position at the call); where the tool ends.
    pub(super) c: [f64; 2],
    /// Surface, set-up clearance, depth and 2nd set-up clearance, as Z.
    pub(super) s: f64,
    pub(super) top: f64,
    pub(super) bottom: f64,
    pub(super) second: f64,
    pub(super) rho: f64,
    pub(super) ccw: bool,
    /// The feeds' unit as Q439 gives it: mm/min × this (S for a feed per revolution).
    pub(super) per: f64,
}

/// The depths of a cycle's finishing passes: from the surface to the bottom, Q338
/// (`fin_infeed`) apart, or all at once where Q338 is 0; cycle `n` named when they are too
/// many.
pub(super) fn finishing_levels(
    b: &Block,
    g: &Geometry,
    n: u32,
    fin_infeed: f64,
) -> LineResult<Vec<f64>> {
    let by = if fin_infeed > 0.0 {
        fin_infeed
    } else {
        g.s - g.bottom
    };
    levels(g.s, g.bottom, by).ok_or_else(|| {
        LineError::new(
            b.span(0),
            format!("cycle {n}: finishing infeed Q338 = {by}: at most {MAX_PASSES} levels"),
            "bad Q338",
        )
    })
}

/// The levels from `from` down to `to`, `by` apart (the last at `to`); None for a step
/// that is not positive or more than `MAX_PASSES` levels.
pub(super) fn levels(from: f64, to: f64, by: f64) -> Option<Vec<f64>> {
    if by <= 0.0 || (from - to) / by > MAX_PASSES {
        return None;
    }
    // Counted, not stepped until reached: far from 0, z - by may round to z.
    let n = ((from - to) / by - 1e-9).ceil().max(0.0) as u64;
    Some(
        (1..=n)
            .map(|i| {
                if i == n {
                    to
                } else {
                    (from - i as f64 * by).max(to)
                }
            })
            .collect(),
    )
}

/// One rounded rectangle of half sides `s[0]`, `s[1]` and corner radius `s[2]` at `z`,
/// from the middle of its +X side around (counter-clockwise when `g.ccw`) and back there,
/// reached on a line from where the tool is; `world` maps the pocket's (u, v) to X Y.
pub(super) fn rounded_rect(
    r: &mut Reader,
    b: &Block,
    g: &Geometry,
    z: f64,
    s: [f64; 3],
    world: &dyn Fn(f64, f64) -> [f64; 2],
    f: f64,
) {
    let [a, hb, rc] = s;
    // Clockwise: the same path mirrored in v.
    let m = if g.ccw { 1.0 } else { -1.0 };
    let to = |r: &mut Reader, u: f64, v: f64| {
        let p = world(u, m * v);
        let here = r.path.pos;
        if (p[0] - here[0]).hypot(p[1] - here[1]) > 1e-9 || (z - here[2]).abs() > 1e-9 {
            line(r, b, [p[0], p[1], z], f);
        }
    };
    let round = |r: &mut Reader, u: f64, v: f64, cu: f64, cv: f64| {
        if rc > 1e-9 {
            let p = world(u, m * v);
            arc(r, b, g.ccw, [p[0], p[1], z], world(cu, m * cv), f);
        }
    };
    to(r, a, 0.0);
    for (su, sv) in [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)] {
        // Along the side to the corner's arc, then the arc (quarter turn) about its centre.
        let (cu, cv) = (su * (a - rc), sv * (hb - rc));
        if su * sv > 0.0 {
            to(r, su * a, cv);
            round(r, cu, sv * hb, cu, cv);
        } else {
            to(r, cu, sv * hb);
            round(r, su * a, cv, cu, cv);
        }
    }
    to(r, a, 0.0);
}

pub(super) fn rapid_z(r: &mut Reader, b: &Block, z: f64) {
    let span = b.span(0);
    r.gword("0", span.clone());
    r.word('Z', z, span);
    r.end_block(b.line);
    r.path.set_z(z);
}

/// G0 in the plane to `xy`.
pub(super) fn rapid_xy(r: &mut Reader, b: &Block, xy: [f64; 2]) {
    let span = b.span(0);
    r.gword("0", span.clone());
    r.word('X', xy[0], span.clone());
    r.word('Y', xy[1], span);
    r.end_block(b.line);
    r.path.pos[0] = xy[0];
    r.path.pos[1] = xy[1];
}

/// G1 to `p` at `f`.
pub(super) fn line(r: &mut Reader, b: &Block, p: [f64; 3], f: f64) {
    let span = b.span(0);
    r.gword("1", span.clone());
    for (l, v) in ['X', 'Y', 'Z'].into_iter().zip(p) {
        r.word(l, v, span.clone());
    }
    r.word('F', f, span);
    r.end_block(b.line);
    r.path.pos[..3].copy_from_slice(&p);
}

/// G3 (`ccw`) or G2 from where the tool is to `p` about the centre `c` (X Y), at `f`; end
/// on the start: a full circle.
pub(super) fn arc(r: &mut Reader, b: &Block, ccw: bool, p: [f64; 3], c: [f64; 2], f: f64) {
    let span = b.span(0);
    let from = r.path.xy();
    r.gword(if ccw { "3" } else { "2" }, span.clone());
    for (l, v) in ['X', 'Y', 'Z'].into_iter().zip(p) {
        r.word(l, v, span.clone());
    }
    r.word('I', c[0] - from[0], span.clone());
    r.word('J', c[1] - from[1], span.clone());
    r.word('F', f, span);
    r.end_block(b.line);
    r.path.pos[..3].copy_from_slice(&p);
}
