//! The slot cycles 253 SLOT MILLING and 254 CIRCULAR SLOT: where the slot lies and the
//! path that clears it, for the pocket run of `milling` (levels Q202 down to Q201 + Q369,
//! side allowance Q368, wall and floor finishing). TNC 640 cycle programming manual,
//! "Cycles: pocket milling, stud milling and slot milling", "Cycle 253", "Cycle 254".
//!
//! A slot is a centre line from `from` to `to` (253: straight, Q218 − Q219 long; 254: an
//! arc of the pitch circle Q375 about its centre, Q248 degrees counter-clockwise from the
//! start angle Q376), and the band of half width Q219/2 about it with round ends. The tool
//! centre keeps `half` = Q219/2 − ρ from the centre line (ρ the tool radius). Our path
//! (the manual gives the order, not the path): the tool plunges at `from` (the centre of
//! the left slot arc, where the manual's plunge starts), runs the centre line there and
//! back, then the closed contours d = k, 2k, … up to `half` less the allowance (k = ρ, a
//! stepover of one tool radius; the slots have no Q370), each reached on a line out from
//! `from` and run counter-clockwise for climb milling (Q351 +1, M3), clockwise for up-cut,
//! and goes back to `from`:
//!
//! ```text
//!   contour d (straight):  from − d n ─► to − d n ─► arc about to ─► to + d n ─► from + d n
//!                          ─► arc about from ─► from − d n      (n the left normal)
//!   contour d (arc):       outer arc R + d from `from` to `to` ─► end arc about to ─►
//!                          inner arc R − d back ─► end arc about from
//! ```
//!
//! Every point of it is at most `half` from the centre line, so it stays inside the slot.
//! A slot as wide as the tool (`half` = 0) is the centre line alone.
//!
//! Read: 253 with Q367 0-4 (the call position is the slot's centre, its left end, the
//! centre of its left arc, of its right arc, its right end) and Q374 (the slot turned
//! about the call position); 254 with Q367 = 0 (the pitch circle's centre Q216, Q217),
//! repeated Q377 times, Q378 degrees apart. Refused: 254 with Q367 1-3 (the slot placed
//! from the tool position), Q218 < Q219, a slot narrower than the tool, a pitch circle
//! not wider than the slot.

use crate::lex::{LineError, LineResult};

use super::cycle_moves::{arc, line, Geometry, MAX_PASSES};
use super::state::{Block, Reader};

/// A slot's centre line and how far from it the tool centre may go.
pub(super) struct Slot {
    /// The centre line's ends (the centres of the slot's end arcs).
    from: [f64; 2],
    to: [f64; 2],
    /// The pitch circle's centre of a circular slot (its centre line runs counter-clockwise
    /// about it from `from` to `to`); None for a straight slot.
    pole: Option<[f64; 2]>,
    /// Q219/2 − ρ: the wall path's distance from the centre line.
    pub(super) half: f64,
    /// Climb milling: the contours counter-clockwise.
    ccw: bool,
}

fn err<T>(b: &Block, message: String, label: &str) -> LineResult<T> {
    Err(LineError::new(b.span(0), message, label))
}

/// Q219/2 − ρ, refused when the slot is narrower than the tool.
fn half_width(r: &Reader, b: &Block, g: &Geometry, n: u32) -> LineResult<f64> {
    let width = r.q.q(219);
    let half = width / 2.0 - g.rho;
    if half < -1e-9 {
        return err(b, format!("cycle {n}: slot width Q219 = {width} is narrower than the tool (Ø{}): expected Q219 ≥ the tool's diameter (TNC 640 cycle programming manual, \"Cycle {n}\")", 2.0 * g.rho), "slot narrower than the tool");
    }
    Ok(half.max(0.0))
}

/// Cycle 253: the slot about the call position (Q367, Q374); `g.c` becomes its start.
pub(super) fn straight(r: &mut Reader, b: &Block, g: &mut Geometry) -> LineResult<Slot> {
    let q = |k| r.q.q(k);
    let (length, width, rot) = (q(218), q(219), q(374));
    let half = half_width(r, b, g, 253)?;
    if length < width {
        return err(b, format!("cycle 253: slot length Q218 = {length} is shorter than its width Q219 = {width}: expected Q218 ≥ Q219 (the length is measured over the round ends)"), "slot shorter than wide");
    }
    // The centre line is ±h along the slot's axis from its centre.
    let h = (length - width) / 2.0;
    let shift = match q(367) {
        p if p == 0.0 => 0.0,
        p if p == 1.0 => length / 2.0,
        p if p == 2.0 => h,
        p if p == 3.0 => -h,
        p if p == 4.0 => -length / 2.0,
        p => return err(b, format!("cycle 253: slot position Q367 = {p}: expected 0 (the call position is the slot's centre), 1 (its left end), 2 (the centre of its left arc), 3 (of its right arc) or 4 (its right end)"), "bad Q367"),
    };
    let (s, c) = rot.to_radians().sin_cos();
    let along = |u: f64| [g.c[0] + c * u, g.c[1] + s * u];
    let (from, to) = (along(shift - h), along(shift + h));
    g.c = from;
    Ok(Slot {
        from,
        to,
        pole: None,
        half,
        ccw: g.ccw,
    })
}

/// Cycle 254's number of slots, Q377 (0: one).
pub(super) fn repetitions(r: &Reader, b: &Block) -> LineResult<u32> {
    let n = r.q.q(377);
    if n == 0.0 {
        return Ok(1);
    }
    if n < 1.0 || n.fract() != 0.0 || n > MAX_PASSES {
        return err(
            b,
            format!("cycle 254: number of repetitions Q377 = {n}: expected a whole number from 1 to {MAX_PASSES}"),
            "bad Q377",
        );
    }
    Ok(n as u32)
}

/// Cycle 254's slot `k` (0 the first): on the pitch circle Q375 about (Q216, Q217), from
/// the angle Q376 + k Q378 over Q248 degrees counter-clockwise; `g.c` becomes its start.
pub(super) fn circular(r: &mut Reader, b: &Block, g: &mut Geometry, k: u32) -> LineResult<Slot> {
    let q = |k| r.q.q(k);
    let half = half_width(r, b, g, 254)?;
    if q(367) != 0.0 {
        return err(b, format!("cycle 254 with Q367 = {} (the slot placed from the tool position: the pitch circle's centre worked out from the starting angle) is not supported (TNC 640 cycle programming manual, \"Cycle 254\", Q367): expected Q367 = 0 and the pitch circle's centre in Q216, Q217", q(367)), "slot reference Q367");
    }
    let (radius, sweep) = (q(375) / 2.0, q(248));
    if radius <= q(219) / 2.0 {
        return err(b, format!("cycle 254: pitch circle diameter Q375 = {} is not wider than the slot Q219 = {}: expected Q375 > Q219", q(375), q(219)), "pitch circle too small");
    }
    if !(sweep > 0.0 && sweep <= 360.0) {
        return err(
            b,
            format!("cycle 254: angular length Q248 = {sweep}: expected more than 0 and at most 360 degrees"),
            "bad Q248",
        );
    }
    let pole = [q(216), q(217)];
    let start = q(376) + f64::from(k) * q(378);
    let at = |deg: f64| {
        let (s, c) = deg.to_radians().sin_cos();
        [pole[0] + radius * c, pole[1] + radius * s]
    };
    let (from, to) = (at(start), at(start + sweep));
    g.c = from;
    Ok(Slot {
        from,
        to,
        pole: Some(pole),
        half,
        ccw: g.ccw,
    })
}

/// One element of a closed contour: to `end`, on a line or an arc about a centre.
#[derive(Clone, Copy)]
struct Step {
    end: [f64; 2],
    centre: Option<[f64; 2]>,
    ccw: bool,
}

impl Slot {
    /// The unit vector from `from` along which the contours start (right of a straight
    /// slot's direction, outward on a circular slot's pitch circle).
    fn out(&self) -> [f64; 2] {
        match self.pole {
            Some(p) => unit([self.from[0] - p[0], self.from[1] - p[1]]),
            None => {
                let t = unit([self.to[0] - self.from[0], self.to[1] - self.from[1]]);
                if t == [0.0, 0.0] {
                    [0.0, -1.0]
                } else {
                    [t[1], -t[0]]
                }
            }
        }
    }

    /// The contour at distance `d` from the centre line, counter-clockwise from
    /// `from + d out`.
    fn contour(&self, d: f64) -> Vec<Step> {
        let o = self.out();
        let (from, to) = (self.from, self.to);
        let plus = |p: [f64; 2], v: [f64; 2], k: f64| [p[0] + k * v[0], p[1] + k * v[1]];
        let o_end = match self.pole {
            Some(p) => unit([to[0] - p[0], to[1] - p[1]]),
            None => o,
        };
        let step = |end, centre, ccw| Step { end, centre, ccw };
        vec![
            step(plus(to, o_end, d), self.pole, true),
            step(plus(to, o_end, -d), Some(to), true),
            step(plus(from, o, -d), self.pole, false),
            step(plus(from, o, d), Some(from), true),
        ]
    }

    /// The clearing at `z` out to `max` from the centre line, `step` apart, at `f`: the
    /// centre line there and back, then the contours, then back to `from`.
    pub(super) fn rings(&self, r: &mut Reader, b: &Block, z: f64, max: f64, step: f64, f: f64) {
        let run = |r: &mut Reader, s: Step| {
            let p = [s.end[0], s.end[1], z];
            let here = r.path.pos;
            match s.centre {
                Some(c) => arc(r, b, s.ccw, p, c, f),
                None if (p[0] - here[0]).hypot(p[1] - here[1]) > 1e-9 => line(r, b, p, f),
                None => {}
            }
        };
        let (from, to) = (self.from, self.to);
        run(
            r,
            Step {
                end: from,
                centre: None,
                ccw: true,
            },
        );
        // The centre line, but not before a finishing pass (the wall alone: step ≥ max).
        let along = (to[0] - from[0]).hypot(to[1] - from[1]) > 1e-9 || self.pole.is_some();
        if along && (step < max || max <= 1e-9) {
            run(
                r,
                Step {
                    end: to,
                    centre: self.pole,
                    ccw: true,
                },
            );
            run(
                r,
                Step {
                    end: from,
                    centre: self.pole,
                    ccw: false,
                },
            );
        }
        let max = max.max(0.0);
        let count = if max <= 1e-9 {
            0
        } else if step <= 0.0 {
            1
        } else {
            ((max - 1e-9) / step).ceil().max(1.0) as u64
        };
        let o = self.out();
        for i in 1..=count {
            let d = if i == count { max } else { i as f64 * step };
            run(
                r,
                Step {
                    end: [from[0] + d * o[0], from[1] + d * o[1]],
                    centre: None,
                    ccw: true,
                },
            );
            let steps = self.contour(d);
            if self.ccw {
                for s in steps {
                    run(r, s);
                }
            } else {
                // The same contour backwards: each element from its end to its start.
                let start = [from[0] + d * o[0], from[1] + d * o[1]];
                let ends: Vec<[f64; 2]> = std::iter::once(start)
                    .chain(steps.iter().map(|s| s.end))
                    .collect();
                for (k, s) in steps.iter().enumerate().rev() {
                    run(
                        r,
                        Step {
                            end: ends[k],
                            centre: s.centre,
                            ccw: !s.ccw,
                        },
                    );
                }
            }
        }
        run(
            r,
            Step {
                end: from,
                centre: None,
                ccw: true,
            },
        );
    }
}

fn unit(v: [f64; 2]) -> [f64; 2] {
    let n = v[0].hypot(v[1]);
    if n > 0.0 {
        [v[0] / n, v[1] / n]
    } else {
        [0.0, 0.0]
    }
}
