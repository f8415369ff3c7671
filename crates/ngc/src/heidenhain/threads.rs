//! The thread milling cycles 262 THREAD MILLING, 263 THREAD MILLING/COUNTERSINKING, 264
//! THREAD DRILLING/MILLING, 265 HELICAL THREAD DRILLING/MILLING and 267 OUTSIDE THREAD
//! MILLING as helices about the call position (TNC 640 cycle programming manual, "Cycles:
//! tapping / thread milling").
//!
//! The manual's rules: Q335 the nominal diameter, Q239 the pitch (+ right-hand, −
//! left-hand), Q201 the thread depth, Q351 climb (+1) or up-cut (−1), Q355 the threads
//! per step (0: one 360° helix to the thread depth, 1: one continuous helix over the
//! thread's length), Q253 the pre-positioning feed, Q207 the milling feed (Q512 the
//! approach feed, when given). The helix turns counter-clockwise inside a hole for climb
//! milling (M3), clockwise outside a stud; a right-hand thread rises when the helix turns
//! counter-clockwise, so the work direction is the manual's table:
//!
//! ```text
//!              inside (262, 263)        outside (267)
//!   right, +1  Z+ (from the depth up)   Z− (from the surface down)
//!   left,  −1  Z+                       Z−
//!   right, −1  Z−                       Z+
//!   left,  +1  Z−                       Z+
//! ```
//!
//! 263 and 264 mill one 360° helix (as Q355 = 0). 264 drills the hole first: at Q206 down
//! by the plunging depth Q202 at a time to the total hole depth Q356, FMAX up to s + Q200
//! after each infeed and down to Q258 above the depth reached (chip breaking, Q257 > 0,
//! refused). 265 drills from solid: always down from the surface, clockwise for a
//! right-hand thread.
//! The run: FMAX to s + Q200 (267: first beside the stud, 2 mm + ρ outside Q335), at Q253
//! to the starting plane (the lower or upper end of the thread, as the table says), a
//! semicircle onto the helix tangentially, the helix (r = Q335/2 ∓ ρ from the centre, ρ
//! the tool radius), a semicircle off it tangentially (inside: back to the centre;
//! outside: back out 2 mm + ρ beyond Q335), FMAX to s + Q200, then Q204.
//!
//! Our simplifications: the approach and departure semicircles are flat (the TNC's are
//! helical, with a compensating move of the tool axis). Refused, with their parameter
//! named: several offset helices (Q355 > 1), countersinking (263 Q356, and the
//! countersinking at front Q358 of 263, 265, 267), whose circle depends on the tool's
//! countersinking geometry mtsim's tool table does not carry.

use std::f64::consts::TAU;

use crate::lex::{LineError, LineResult};

use super::cycle_moves::{arc, line, rapid_xy, rapid_z, Geometry, MAX_PASSES};
use super::state::{Block, Reader};

fn err<T>(b: &Block, message: String, label: &str) -> LineResult<T> {
    Err(LineError::new(b.span(0), message, label))
}

/// One call of thread milling cycle `n` about `g.c`; `g.c` becomes where the tool ends.
pub(super) fn thread(r: &mut Reader, b: &Block, g: &mut Geometry, n: u32) -> LineResult<()> {
    let q = |k| r.q.q(k);
    let section = format!("TNC 640 cycle programming manual, \"Cycle {n}\"");
    let (dia, pitch) = (q(335), q(239));
    if pitch == 0.0 {
        return err(b, format!("cycle {n}: thread pitch Q239 = 0: expected a pitch, + for a right-hand, − for a left-hand thread"), "no pitch");
    }
    // Countersinking (263 Q356) and countersinking at front (Q358) are not modelled.
    if n == 263 && q(356) != 0.0 {
        return err(b, format!("cycle 263 with the countersinking depth Q356 = {}: the countersinking circle depends on the tool's countersinking edge, which mtsim's tool table does not carry; not supported ({section}, Q356): expected Q356 = 0 (no countersinking), or the countersink as its own cycle", q(356)), "countersinking");
    }
    if n != 262 && q(358) != 0.0 {
        return err(b, format!("cycle {n} with countersinking at front Q358 = {}: not supported ({section}, Q358, Q359): expected Q358 = 0", q(358)), "countersinking at front");
    }
    let per_step = match n {
        262 | 267 => q(355),
        265 => 1.0,
        _ => 0.0,
    };
    if per_step != 0.0 && per_step != 1.0 {
        return err(b, format!("cycle {n} with threads per step Q355 = {per_step}: mtsim reads 0 (one 360° helix to the thread depth) and 1 (one continuous helix); several offset helices with an approach and departure each are not supported ({section}, Q355)"), "threads per step Q355");
    }
    let outside = n == 267;
    let radius = if outside {
        dia / 2.0 + g.rho
    } else {
        dia / 2.0 - g.rho
    };
    if radius <= 1e-9 {
        return err(b, format!("cycle {n}: nominal diameter Q335 = {dia} is not larger than the tool's diameter {}: expected Q335 > the tool's diameter", 2.0 * g.rho), "thread smaller than the tool");
    }
    let right = pitch > 0.0;
    // g.ccw: climb inside (counter-clockwise); outside climb is clockwise; 265 by the hand.
    let ccw = if n == 265 { !right } else { g.ccw != outside };
    let up = n != 265 && ccw == right;
    let p = pitch.abs();
    let (hi, lo) = if per_step == 0.0 {
        (g.bottom + p, g.bottom)
    } else {
        (g.s, g.bottom)
    };
    let (from, to) = if up { (lo, hi) } else { (hi, lo) };
    if (hi - lo) / p > MAX_PASSES {
        return err(
            b,
            format!(
                "cycle {n}: pitch Q239 = {pitch} over the depth Q201: more than {MAX_PASSES} turns"
            ),
            "bad Q239",
        );
    }
    let written = |k: u32| r.cycle.written.contains(&k);
    let (pre, mill) = (q(253) * g.per, q(207) * g.per);
    let approach = if written(512) && q(512) > 0.0 {
        q(512) * g.per
    } else {
        mill
    };
    if pre <= 0.0 || mill <= 0.0 {
        return err(b, format!("cycle {n}: pre-positioning feed Q253 = {pre}, milling feed Q207 = {mill}: expected both positive"), "no feed");
    }
    let c = g.c;
    let unit = if r.inch { 25.4 } else { 1.0 };
    let out = dia / 2.0 + g.rho + 2.0 / unit;
    rapid_z(r, b, g.top);
    if n == 264 {
        drill(r, b, g, &section)?;
    }
    let start = if outside { [c[0] + out, c[1]] } else { c };
    if outside {
        rapid_xy(r, b, start);
    }
    line(r, b, [start[0], start[1], from], pre);
    // On: a semicircle from the start to the helix (inside turning with the helix, outside
    // against it, so that it meets the helix tangentially).
    let on = [c[0] + radius, c[1]];
    let mid = [(start[0] + on[0]) / 2.0, (start[1] + on[1]) / 2.0];
    let turn = ccw != outside;
    arc(r, b, turn, [on[0], on[1], from], mid, approach);
    let end = helix(r, b, ccw, c, radius, [from, to], p, mill);
    let (sn, cs) = ((end[1] - c[1]) / radius, (end[0] - c[0]) / radius);
    let off = if outside {
        [c[0] + out * cs, c[1] + out * sn]
    } else {
        c
    };
    let mid = [(end[0] + off[0]) / 2.0, (end[1] + off[1]) / 2.0];
    arc(r, b, turn, [off[0], off[1], to], mid, approach);
    g.c = off;
    Ok(())
}

/// Cycle 264's hole: Q206 down by Q202 to s + Q356, FMAX to s + Q200 after each infeed
/// and back to Q258 above the depth reached.
fn drill(r: &mut Reader, b: &Block, g: &Geometry, section: &str) -> LineResult<()> {
    let q = |k| r.q.q(k);
    let (hole, plunge, stop, feed) = (q(356), q(202), q(258), q(206) * g.per);
    if q(257) != 0.0 {
        return err(b, format!("cycle 264 with chip breaking Q257 = {}: not supported ({section}, Q257, Q256): expected Q257 = 0", q(257)), "chip breaking");
    }
    if hole > q(201) || hole >= 0.0 {
        return err(b, format!("cycle 264: total hole depth Q356 = {hole} is not below the thread depth Q201 = {}: expected Q356 ≤ Q201 < 0", q(201)), "hole shallower than the thread");
    }
    if plunge <= 0.0 || feed <= 0.0 || -hole / plunge > MAX_PASSES {
        return err(b, format!("cycle 264: plunging depth Q202 = {plunge}, plunging feed Q206 = {feed}: expected both positive, at most {MAX_PASSES} infeeds"), "bad Q202");
    }
    let c = g.c;
    let bottom = g.s + hole;
    let mut reached = g.s;
    loop {
        let next = (reached - plunge).max(bottom);
        if reached < g.s {
            rapid_z(r, b, reached + stop);
        }
        line(r, b, [c[0], c[1], next], feed);
        if next <= bottom {
            return Ok(());
        }
        rapid_z(r, b, g.top);
        reached = next;
    }
}

/// The helix about `c` of radius `radius` from the angle 0 at Z `z[0]` to `z[1]`, `pitch`
/// per turn, counter-clockwise when `ccw`: the full turns, then the rest; where it ends.
fn helix(
    r: &mut Reader,
    b: &Block,
    ccw: bool,
    c: [f64; 2],
    radius: f64,
    z: [f64; 2],
    pitch: f64,
    f: f64,
) -> [f64; 2] {
    let turns = (z[1] - z[0]).abs() / pitch;
    let dir = (z[1] - z[0]).signum();
    let start = [c[0] + radius, c[1]];
    let full = (turns - 1e-9).floor().max(0.0) as u64;
    for k in 1..=full {
        let zk = z[0] + dir * k as f64 * pitch;
        arc(r, b, ccw, [start[0], start[1], zk], c, f);
    }
    let rest = (turns - full as f64) * TAU;
    if rest <= 1e-9 {
        return start;
    }
    let phi = if ccw { rest } else { -rest };
    let end = [c[0] + radius * phi.cos(), c[1] + radius * phi.sin()];
    arc(r, b, ccw, [end[0], end[1], z[1]], c, f);
    end
}
