//! The stud cycles 256 RECTANGULAR STUD and 257 CIRCULAR STUD: the blank around the stud
//! milled away from the outside in (TNC 640 cycle programming manual, "Cycles: pocket
//! milling, stud milling and slot milling", "Cycle 256", "Cycle 257").
//!
//! The manual's run: from the stud's centre to a start point beside the blank (256: 2 mm
//! to the right of the blank, Q437 = 0; 257: 2 mm outside it at the polar angle Q376),
//! FMAX to the set-up clearance s + Q200, at Q206 down to the first plunging depth Q202, a
//! semicircle tangent onto the contour, one revolution, a stepover of Q370 ρ inward and
//! another until the finished size plus the side allowance Q368 is reached, tangentially
//! off and back to the start point, the next plunging depth, down to Q201 + Q369; the end
//! at the clearance height over the start point ("the end position differs from the
//! starting position"). With Q215 0 and allowances, or 2: the finished wall per finishing
//! infeed Q338 (0: one, at Q201), then the floor (Q369 > 0, or Q215 = 2) at Q201, both at
//! F Q385 (0: Q207).
//!
//! Our path, with ρ the tool radius and e = ρ + allowance + d the tool centre's distance
//! outside the finished contour (257: a circle of radius Q223/2 + e; 256: the rectangle of
//! half sides Q218/2 + e, Q219/2 + e with corner radius Q220 + e, turned by Q224):
//!
//! ```text
//! S ─► semicircle (diameter S M, the other way round than the contour) ─► M ─► contour
//!   once round ─► M ─► semicircle on ─► S            (M: the contour's point on the line
//!                                                     from the centre to S)
//! d = (n − 1) k, …, k, 0 with k = Q370 ρ (at most 2ρ) and n = ⌈m / k⌉, m the widest
//! material beyond the allowance, (blank − finished)/2 − Q368
//! ```
//!
//! Outside the stud climb milling (Q351 +1, M3) runs clockwise, up-cut counter-clockwise.
//! Every point of a pass is at least e from the finished contour. Refused: an approach at a
//! corner (256 Q437 1-4, the manual's spiral), a chamfer (Q220 < 0), a blank not larger
//! than the stud, a negative starting angle Q376.

use crate::lex::{LineError, LineResult};

use super::cycle_moves::{
    arc, finishing_levels, levels, line, rapid_xy, rapid_z, rounded_rect, Geometry, MAX_PASSES,
};
use super::state::{Block, Reader};

/// The stud's finished outline about the centre `g.c`.
enum Outline {
    Circle {
        radius: f64,
        at_deg: f64,
    },
    Rect {
        a: f64,
        b: f64,
        corner: f64,
        rot_deg: f64,
    },
}

/// What a call of the stud cycle needs beyond `Geometry`.
struct Stud {
    outline: Outline,
    /// The start point S (X Y).
    start: [f64; 2],
    /// The number of passes at the roughing allowance, and the stepover.
    passes: u64,
    step: f64,
}

fn err<T>(b: &Block, message: String, label: &str) -> LineResult<T> {
    Err(LineError::new(b.span(0), message, label))
}

/// One call of cycle `n` (256 or 257) about `g.c`; `g.c` becomes where the tool ends.
pub(super) fn stud(r: &mut Reader, b: &Block, g: &mut Geometry, n: u32) -> LineResult<()> {
    let q = |k| r.q.q(k);
    // The later parameters (Q215, Q369, Q338, Q385, Q437, Q376) are 0 unless written.
    let opt = |k: u32| {
        if r.cycle.written.contains(&k) {
            r.q.q(k as usize)
        } else {
            0.0
        }
    };
    let op = opt(215);
    if op != 0.0 && op != 1.0 && op != 2.0 {
        return err(b, format!("cycle {n}: Q215 = {op}: expected 0 (roughing and finishing), 1 (roughing) or 2 (finishing)"), "bad Q215");
    }
    let (side, floor) = (q(368).max(0.0), opt(369).max(0.0));
    let (f_plunge, f_mill) = (q(206) * g.per, q(207) * g.per);
    let f_finish = if opt(385) > 0.0 {
        opt(385) * g.per
    } else {
        f_mill
    };
    if f_plunge <= 0.0 || f_mill <= 0.0 {
        return err(b, format!("cycle {n}: plunging feed Q206 = {f_plunge}, milling feed Q207 = {f_mill}: expected both positive"), "no feed");
    }
    // Outside the stud, climb milling runs clockwise.
    g.ccw = !g.ccw;
    let overlap = if q(370) > 0.0 { q(370) } else { 1.0 };
    let step = (overlap * g.rho).min(2.0 * g.rho);
    let unit = if r.inch { 25.4 } else { 1.0 };
    let clear = 2.0 / unit + g.rho;
    let (outline, margin, start) = if n == 256 {
        rectangle(r, b, g, opt(437), clear)?
    } else {
        circle(r, b, g, opt(376), clear)?
    };
    let (plunge, fin_infeed) = (q(202), opt(338));
    let material = margin - side;
    if material / step > MAX_PASSES {
        return err(
            b,
            format!("cycle {n}: path overlap Q370 = {overlap}: more than {MAX_PASSES} passes"),
            "bad Q370",
        );
    }
    let count = |m: f64| ((m - 1e-9) / step).ceil().max(1.0) as u64;
    let mut stud = Stud {
        outline,
        start,
        passes: count(material),
        step,
    };
    rapid_z(r, b, g.top);
    rapid_xy(r, b, start);
    if op != 2.0 {
        let Some(zs) = levels(g.s, g.bottom + floor, plunge) else {
            return err(b, format!("cycle {n}: plunging depth Q202 = {plunge}: expected a positive depth, at most {MAX_PASSES} levels"), "bad Q202");
        };
        for z in zs {
            line(r, b, [start[0], start[1], z], f_plunge);
            passes(r, b, g, &stud, z, g.rho + side, f_mill);
        }
    }
    if op == 2.0 || (op == 0.0 && (side > 0.0 || floor > 0.0)) {
        let zs = finishing_levels(b, g, n, fin_infeed)?;
        let roughing = stud.passes;
        stud.passes = 1;
        for z in zs {
            line(r, b, [start[0], start[1], z], f_plunge);
            passes(r, b, g, &stud, z, g.rho, f_finish);
        }
        if op == 2.0 || floor > 0.0 {
            stud.passes = roughing.max(count(margin));
            passes(r, b, g, &stud, g.bottom, g.rho, f_finish);
        }
    }
    g.c = start;
    Ok(())
}

/// Cycle 256's outline (Q218, Q219, Q220 about the centre the call position and Q367,
/// Q224 give), the widest blank margin m ((Q424 − Q218)/2 or (Q425 − Q219)/2) and the
/// start point `clear` (2 mm + ρ) right of Q218/2 + m (the blank's right side when its
/// margin in X is the wider).
fn rectangle(
    r: &Reader,
    b: &Block,
    g: &mut Geometry,
    q437: f64,
    clear: f64,
) -> LineResult<(Outline, f64, [f64; 2])> {
    let q = |k| r.q.q(k);
    let (len, wid, blank_len, blank_wid, corner, rot_deg) =
        (q(218), q(219), q(424), q(425), q(220), q(224));
    if q437 != 0.0 {
        return err(b, format!("cycle 256 with the approach position Q437 = {q437} (at a corner of the blank, then a spiral inward) is not supported (TNC 640 cycle programming manual, \"Cycle 256\", Q437): expected Q437 = 0 (beside the blank's right side)"), "approach position Q437");
    }
    if corner < 0.0 {
        return err(b, format!("cycle 256: Q220 = {corner} asks for chamfered corners, which mtsim does not read (TNC 640 cycle programming manual, \"Cycle 256\", Q220): expected a corner radius ≥ 0"), "chamfered stud");
    }
    if len <= 0.0 || wid <= 0.0 || corner > len.min(wid) / 2.0 {
        return err(b, format!("cycle 256: sides Q218 = {len}, Q219 = {wid}, corner radius Q220 = {corner}: expected positive sides and a radius at most half the shorter one"), "bad stud size");
    }
    if blank_len <= len || blank_wid <= wid {
        return err(b, format!("cycle 256: the blank Q424 × Q425 = {blank_len} × {blank_wid} is not larger than the stud Q218 × Q219 = {len} × {wid}: expected Q424 > Q218 and Q425 > Q219"), "blank not larger than the stud");
    }
    let at = match q(367) {
        p if p == 0.0 => [0.0, 0.0],
        p if p == 1.0 => [1.0, 1.0],
        p if p == 2.0 => [-1.0, 1.0],
        p if p == 3.0 => [-1.0, -1.0],
        p if p == 4.0 => [1.0, -1.0],
        p => {
            return err(
                b,
                format!(
                    "cycle 256: stud position Q367 = {p}: expected 0 (centre) or 1-4 (a corner)"
                ),
                "bad Q367",
            )
        }
    };
    let (s, c) = rot_deg.to_radians().sin_cos();
    let world = |o: [f64; 2], u: f64, v: f64| [o[0] + c * u - s * v, o[1] + s * u + c * v];
    g.c = world(g.c, at[0] * len / 2.0, at[1] * wid / 2.0);
    let margin = ((blank_len - len) / 2.0).max((blank_wid - wid) / 2.0);
    // Beside the blank's right side, or beside the widest pass when the blank's margin is
    // wider in Y (the approach semicircle must run from outside every pass).
    let start = world(g.c, len / 2.0 + margin + clear, 0.0);
    let outline = Outline::Rect {
        a: len / 2.0,
        b: wid / 2.0,
        corner,
        rot_deg,
    };
    Ok((outline, margin, start))
}

/// Cycle 257's outline (Q223 about the call position), the blank margin (Q222 − Q223)/2
/// and the start point `clear` (2 mm + ρ) outside the blank at the polar angle Q376.
fn circle(
    r: &Reader,
    b: &Block,
    g: &Geometry,
    at_deg: f64,
    clear: f64,
) -> LineResult<(Outline, f64, [f64; 2])> {
    let (finished, blank) = (r.q.q(223), r.q.q(222));
    if finished <= 0.0 || blank <= finished {
        return err(b, format!("cycle 257: finished diameter Q223 = {finished}, blank diameter Q222 = {blank}: expected 0 < Q223 < Q222"), "blank not larger than the stud");
    }
    if !(0.0..360.0).contains(&at_deg) {
        return err(b, format!("cycle 257: starting angle Q376 = {at_deg}: expected 0 to 359 degrees (TNC 640 cycle programming manual, \"Cycle 257\", Q376)"), "bad Q376");
    }
    let (s, c) = at_deg.to_radians().sin_cos();
    let out = blank / 2.0 + clear;
    let start = [g.c[0] + out * c, g.c[1] + out * s];
    let outline = Outline::Circle {
        radius: finished / 2.0,
        at_deg,
    };
    Ok((outline, (blank - finished) / 2.0, start))
}

/// `stud.passes` passes at `z`, the last at `e` outside the finished contour, the others
/// `stud.step` further out each, every one from the start point and back there, at `f`.
fn passes(r: &mut Reader, b: &Block, g: &Geometry, stud: &Stud, z: f64, e: f64, f: f64) {
    let s = stud.start;
    for j in (0..stud.passes).rev() {
        let e = e + j as f64 * stud.step;
        let m = match stud.outline {
            Outline::Circle { radius, at_deg } => {
                let (sn, cs) = at_deg.to_radians().sin_cos();
                [g.c[0] + (radius + e) * cs, g.c[1] + (radius + e) * sn]
            }
            Outline::Rect { a, rot_deg, .. } => {
                let (sn, cs) = rot_deg.to_radians().sin_cos();
                [g.c[0] + (a + e) * cs, g.c[1] + (a + e) * sn]
            }
        };
        let mid = [(s[0] + m[0]) / 2.0, (s[1] + m[1]) / 2.0];
        // On to the contour tangentially: a semicircle turning the other way.
        arc(r, b, !g.ccw, [m[0], m[1], z], mid, f);
        match stud.outline {
            Outline::Circle { .. } => arc(r, b, g.ccw, [m[0], m[1], z], g.c, f),
            Outline::Rect {
                a,
                b: half_b,
                corner,
                rot_deg,
            } => {
                let (sn, cs) = rot_deg.to_radians().sin_cos();
                let world = |u: f64, v: f64| [g.c[0] + cs * u - sn * v, g.c[1] + sn * u + cs * v];
                rounded_rect(r, b, g, z, [a + e, half_b + e, corner + e], &world, f);
            }
        }
        arc(r, b, !g.ccw, [s[0], s[1], z], mid, f);
    }
}
