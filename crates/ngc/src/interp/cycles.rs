//! Canned cycles G73, G81-G83, G85, G86, G89 in the current plane: the moves of each hole
//! as LinuxCNC's G-code manual describes them (the retract to R or the initial level, the
//! pecks, the dwell), checked against rs274; and the Fanuc family's G74/G84 tapping, G76
//! fine boring, G87 back boring (Haas G77) and G88 boring with a manual retract (Haas G87
//! and G88) as the Fanuc 0i-MF operator's manual and the Haas mill manual describe them.

use std::collections::VecDeque;

use super::Interp;
use crate::axis::{Axis, AxisVec};
use crate::canon::{Motion, Move, PathControl};
use crate::lex::{LineError, LineResult, Word};
use crate::options::PECK_CLEARANCE_MM;
use crate::polar::Polar;

impl Interp {
    /// Canned cycle in the current plane, its moves as LinuxCNC's G-code manual describes
    /// them (checked against rs274).
    pub(super) fn cycle<'l>(
        &mut self,
        line: &str,
        code: u32,
        get: &dyn Fn(char) -> Option<Word<'l>>,
        line_no: usize,
        queue: &mut VecDeque<Move>,
        first: std::ops::Range<usize>,
    ) -> LineResult<()> {
        let (u, v, n) = self.plane.axes();
        let scale = self.scale();
        let at = first.clone();
        // The hole is placed by the plane's axes; another axis word would be lost.
        if let Some(w) = Axis::ALL
            .iter()
            .filter(|a| ![u, v, n].contains(a))
            .find_map(|a| get(a.letter()))
        {
            return Err(LineError::new(
                w.span(),
                format!(
                    "`{}` in a canned cycle: expected only {} {} {} (LinuxCNC: \"Cannot put an A in canned cycle\")",
                    &line[w.span()],
                    u.letter(),
                    v.letter(),
                    n.letter()
                ),
                "axis word in a cycle",
            ));
        }
        let back_bore = self.cycle_words(line, code, get, (u, v, n), scale)?;
        let r_prog = self.cycle_r.ok_or_else(|| {
            LineError::new(
                at.clone(),
                "canned cycle without R: expected the retract plane R",
                "no R",
            )
        })?;
        let z_prog = self.cycle_z.ok_or_else(|| {
            LineError::new(
                at.clone(),
                format!(
                    "canned cycle without {}: expected the hole bottom",
                    n.letter()
                ),
                "no bottom",
            )
        })?;
        // Repeats: LinuxCNC and Haas L; Fanuc K (Series 0i "Canned cycle": K, the number
        // of repeats, in G91 each at the next increment).
        let k = get('K').filter(|_| self.dialect.table().macro_b);
        let repeats = get('L').or(k).map_or(1, |l| l.value.round() as u64);
        let tlo = |a: Axis| {
            if a == Axis::Z {
                self.tool_length_mm
            } else {
                0.0
            }
        };
        // Everything in machine coordinates along n, and for u v.
        let old_n = *self.cycle_initial.get_or_insert(self.pos[n]);
        let (r, bottom, du, dv, pu, pv);
        if self.absolute {
            r = r_prog + self.offset[n] + tlo(n);
            bottom = z_prog + self.offset[n] + tlo(n);
            du = 0.0;
            dv = 0.0;
            pu = get(u.letter()).map_or(self.pos[u], |w| w.value * scale + self.offset[u] + tlo(u));
            pv = get(v.letter()).map_or(self.pos[v], |w| w.value * scale + self.offset[v] + tlo(v));
        } else {
            r = old_n + r_prog;
            bottom = r + z_prog;
            du = get(u.letter()).map_or(0.0, |w| w.value * scale);
            dv = get(v.letter()).map_or(0.0, |w| w.value * scale);
            pu = self.pos[u];
            pv = self.pos[v];
        }
        if back_bore {
            // R is the start below the bore, Z its top, the initial level above both.
            if r >= bottom || old_n < bottom {
                return Err(LineError::new(
                    at,
                    format!(
                        "back boring: expected R below {} (the bore's top) and the initial level above it",
                        n.letter()
                    ),
                    "back boring levels",
                ));
            }
        } else if r < bottom {
            return Err(LineError::new(
                at,
                format!(
                    "retract plane R below the hole bottom {}: expected R above it",
                    n.letter()
                ),
                "R below bottom",
            ));
        }
        let delta = self.cycle_q.unwrap_or(0.0);
        if matches!(code, 730 | 830) && delta <= 0.0 {
            return Err(LineError::new(
                at,
                "peck cycle without Q: expected the peck depth Q",
                "no Q",
            ));
        }
        let pecks = if matches!(code, 730 | 830) {
            ((r - bottom) / delta.max(1e-9)).min(1e9)
        } else {
            0.0
        };
        if (repeats as f64) * (pecks + 4.0) > 1e7 {
            return Err(LineError::new(at, "canned cycle would make more than 10^7 moves: expected a larger Q or fewer repeats", "too many moves"));
        }
        let holes = Holes {
            code,
            axes: (u, v, n),
            r,
            bottom,
            step: (du, dv),
            first: (pu, pv),
            delta,
            repeats,
            initial: old_n,
            back_bore,
        };
        self.holes(&holes, get, line_no, queue, at)
    }

    /// The sticky words of a canned cycle block (R, the hole bottom, Q, P, and a back
    /// bore's shift I J K), kept for the blocks after it; true for a back bore.
    fn cycle_words<'l>(
        &mut self,
        line: &str,
        code: u32,
        get: &dyn Fn(char) -> Option<Word<'l>>,
        (u, v, n): (Axis, Axis, Axis),
        scale: f64,
    ) -> LineResult<bool> {
        if let Some(r) = get('R') {
            self.cycle_r = Some(r.value * scale);
        }
        if let Some(z) = get(n.letter()) {
            self.cycle_z = Some(z.value * scale);
        }
        if let Some(q) = get('Q') {
            if q.value <= 0.0 {
                return Err(LineError::new(
                    q.span(),
                    "Q in a peck cycle: expected a peck depth greater than zero",
                    "Q not positive",
                ));
            }
            self.cycle_q = Some(q.value * scale);
        }
        if let Some(p) = get('P') {
            // In the dialect's dwell unit (Fanuc ms, LinuxCNC s), kept in seconds.
            self.cycle_p = Some(self.dwell_seconds(line, &p, Some(p), None)?);
        }
        let back_bore = self.is_back_bore(code);
        if back_bore {
            // The shift's I J (G17), K I (G18), J K (G19): incremental, along u and v.
            let letter = |a: Axis| match a {
                Axis::X => 'I',
                Axis::Y => 'J',
                _ => 'K',
            };
            let (i, j) = (get(letter(u)), get(letter(v)));
            if i.is_some() || j.is_some() {
                let value = |w: Option<Word>| w.map_or(0.0, |w| w.value * scale);
                self.cycle_shift = Some((value(i), value(j)));
            }
        }
        Ok(back_bore)
    }

    /// The moves of the holes of a canned cycle: approach, the cycle's own moves down and
    /// out, repeated `L` times (stepping by the increments under G91).
    fn holes<'l>(
        &mut self,
        h: &Holes,
        get: &dyn Fn(char) -> Option<Word<'l>>,
        line_no: usize,
        queue: &mut VecDeque<Move>,
        at: std::ops::Range<usize>,
    ) -> LineResult<()> {
        let Holes {
            axes: (u, v, n),
            r,
            step: (du, dv),
            first: (mut pu, mut pv),
            repeats,
            initial: old_n,
            ..
        } = *h;
        let scale = self.scale();
        let mut pen = Pen {
            cur: self.pos,
            axes: h.axes,
            line_no,
        };
        // As rs274 runs it: the first hole is approached at the current level (when
        // above R), the next ones at the clear level.
        let mut current = self.pos[n];
        let mut old = old_n;
        if old < r && !h.back_bore {
            pen.go(self, queue, Motion::Rapid, self.pos[u], self.pos[v], r);
            old = r;
            current = r;
        }
        let clear = if self.retract_r { r } else { old };
        let polar = Polar {
            radius: get('@').map(|w| w.value),
            angle_deg: get('^').map(|w| w.value),
        };
        for k in 0..repeats {
            pu += du;
            pv += dv;
            if !self.absolute && polar.is_some() {
                // G91 polar: each repeat turns (and moves out) about the work origin.
                let (ox, oy) = (self.offset[Axis::X], self.offset[Axis::Y]);
                let xy = polar
                    .cycle_step([(pu - ox) / scale, (pv - oy) / scale])
                    .map_err(|m| LineError::new(at.clone(), m, "polar coordinate"))?;
                pu = xy[0] * scale + ox;
                pv = xy[1] * scale + oy;
            }
            if h.back_bore {
                self.back_bore_hole(h, &mut pen, queue, pu, pv);
                continue;
            }
            if k == 0 && current > r {
                pen.go(self, queue, Motion::Rapid, pu, pv, current);
                pen.go(self, queue, Motion::Rapid, pu, pv, r);
            } else {
                pen.go(self, queue, Motion::Rapid, pu, pv, clear);
                if clear > r {
                    pen.go(self, queue, Motion::Rapid, pu, pv, r);
                }
            }
            self.down_and_out(h, &mut pen, queue, pu, pv, clear);
        }
        self.pos = pen.cur;
        Ok(())
    }

    /// A hole's own moves, from R down to the bottom and out to `clear` (the G98/G99
    /// level), at (pu, pv).
    fn down_and_out(
        &mut self,
        h: &Holes,
        pen: &mut Pen,
        queue: &mut VecDeque<Move>,
        pu: f64,
        pv: f64,
        clear: f64,
    ) {
        let (r, bottom, delta) = (h.r, h.bottom, h.delta);
        let dwell = self.cycle_p.unwrap_or(0.0);
        let peck_clearance = |given: Option<f64>| given.unwrap_or(PECK_CLEARANCE_MM);
        let control = self.control;
        match h.code {
            810 => {
                pen.go(self, queue, Motion::Linear, pu, pv, bottom);
                pen.go(self, queue, Motion::Rapid, pu, pv, clear);
            }
            820 | 860 => {
                pen.go(self, queue, Motion::Linear, pu, pv, bottom);
                pen.dwell(self, queue, dwell);
                pen.go(self, queue, Motion::Rapid, pu, pv, clear);
            }
            830 | 730 => {
                // G73 backs off by the retract; G83 rises to R (plus Haas Setting 52) and
                // comes back down to the clearance above the depth reached.
                let back = if h.code == 830 {
                    peck_clearance(control.g83_clearance_mm)
                } else {
                    peck_clearance(control.g73_retract_mm)
                };
                let mut depth = r - delta;
                while depth > bottom {
                    pen.go(self, queue, Motion::Linear, pu, pv, depth);
                    if h.code == 830 {
                        pen.go(
                            self,
                            queue,
                            Motion::Rapid,
                            pu,
                            pv,
                            r + control.g83_above_r_mm,
                        );
                    }
                    pen.go(self, queue, Motion::Rapid, pu, pv, depth + back);
                    depth -= delta;
                }
                pen.go(self, queue, Motion::Linear, pu, pv, bottom);
                pen.go(self, queue, Motion::Rapid, pu, pv, clear);
            }
            840 | 740 => {
                // Tapping (Fanuc family): feed in, dwell, the spindle reverses, feed
                // out to R; G98 then rapids to the initial level.
                pen.go(self, queue, Motion::Linear, pu, pv, bottom);
                if dwell > 0.0 {
                    pen.dwell(self, queue, dwell);
                }
                pen.go(self, queue, Motion::Linear, pu, pv, r);
                if clear != r {
                    pen.go(self, queue, Motion::Rapid, pu, pv, clear);
                }
            }
            760 => {
                // Fine boring (Fanuc family): feed in, dwell, the spindle stops
                // oriented, the tool shifts Q off the wall (+u, the builder's default
                // direction), rapids out and shifts back.
                pen.go(self, queue, Motion::Linear, pu, pv, bottom);
                if dwell > 0.0 {
                    pen.dwell(self, queue, dwell);
                }
                pen.go(self, queue, Motion::Rapid, pu + delta, pv, bottom);
                pen.go(self, queue, Motion::Rapid, pu + delta, pv, clear);
                pen.go(self, queue, Motion::Rapid, pu, pv, clear);
            }
            870 | 880 => {
                // Boring with a manual retract (Fanuc G88; Haas G87 without the dwell,
                // G88 with it): feed in, dwell, the spindle stops and the operator jogs
                // out. Simulated as a rapid straight back to the G98/G99 level (a notice
                // says so).
                pen.go(self, queue, Motion::Linear, pu, pv, bottom);
                if h.code == 880 {
                    pen.dwell(self, queue, dwell);
                }
                pen.go(self, queue, Motion::Rapid, pu, pv, clear);
            }
            850 => {
                pen.go(self, queue, Motion::Linear, pu, pv, bottom);
                pen.go(self, queue, Motion::Linear, pu, pv, r);
                if clear != r {
                    pen.go(self, queue, Motion::Rapid, pu, pv, clear);
                }
            }
            _ => {
                // G89
                pen.go(self, queue, Motion::Linear, pu, pv, bottom);
                pen.dwell(self, queue, dwell);
                // LinuxCNC feeds straight back to the clearance plane (checked with rs274).
                pen.go(self, queue, Motion::Linear, pu, pv, clear);
            }
        }
    }

    /// One hole of back boring (Fanuc G87, Haas G77) at (pu, pv): at the initial level the
    /// spindle stops oriented and the tool shifts off the wall by s (I J, else Q along +u,
    /// the builder's default direction), rapids down through the hole to R, shifts back,
    /// feeds up to the bore's top Z, dwells P, shifts off again, rapids up to the initial
    /// level and shifts back. It always returns to the initial level: R lies below the part.
    fn back_bore_hole(
        &mut self,
        h: &Holes,
        pen: &mut Pen,
        queue: &mut VecDeque<Move>,
        pu: f64,
        pv: f64,
    ) {
        let (low, top, initial) = (h.r, h.bottom, h.initial);
        let (su, sv) = self.cycle_shift.unwrap_or((h.delta, 0.0));
        let dwell = self.cycle_p.unwrap_or(0.0);
        pen.go(self, queue, Motion::Rapid, pu, pv, initial);
        pen.go(self, queue, Motion::Rapid, pu + su, pv + sv, initial);
        pen.go(self, queue, Motion::Rapid, pu + su, pv + sv, low);
        pen.go(self, queue, Motion::Rapid, pu, pv, low);
        pen.go(self, queue, Motion::Linear, pu, pv, top);
        if dwell > 0.0 {
            pen.dwell(self, queue, dwell);
        }
        pen.go(self, queue, Motion::Rapid, pu + su, pv + sv, top);
        pen.go(self, queue, Motion::Rapid, pu + su, pv + sv, initial);
        pen.go(self, queue, Motion::Rapid, pu, pv, initial);
    }
}

/// Where a canned cycle's tool is, and the moves that take it on: each along the plane's
/// axes `(u, v, n)` only, exact path, on the cycle's line.
struct Pen {
    cur: AxisVec,
    axes: (Axis, Axis, Axis),
    line_no: usize,
}

impl Pen {
    /// A move of `motion` to (pu, pv, pn).
    fn go(
        &mut self,
        me: &mut Interp,
        queue: &mut VecDeque<Move>,
        motion: Motion,
        pu: f64,
        pv: f64,
        pn: f64,
    ) {
        let (u, v, n) = self.axes;
        let mut t = self.cur;
        t[u] = pu;
        t[v] = pv;
        t[n] = pn;
        me.emit(
            queue,
            self.line_no,
            motion,
            self.cur,
            t,
            PathControl::ExactPath,
        );
        self.cur = t;
    }

    /// A dwell of `seconds` where the tool stands (G82, G86, G88, G89 at the bottom).
    fn dwell(&mut self, me: &mut Interp, queue: &mut VecDeque<Move>, seconds: f64) {
        let at = self.cur;
        me.emit(
            queue,
            self.line_no,
            Motion::Dwell { seconds },
            at,
            at,
            PathControl::ExactPath,
        );
    }
}

/// A canned cycle's geometry along the plane's axes `(u, v, n)`, machine mm: the R plane,
/// the hole bottom, the first hole (and the step between holes under G91), the peck depth.
#[derive(Clone, Copy)]
struct Holes {
    code: u32,
    axes: (Axis, Axis, Axis),
    r: f64,
    bottom: f64,
    step: (f64, f64),
    first: (f64, f64),
    delta: f64,
    repeats: u64,
    /// The initial level along n of this row of cycles.
    initial: f64,
    /// Back boring (Fanuc G87, Haas G77): R below the bore, `bottom` its top.
    back_bore: bool,
}

impl Interp {
    /// Whether cycle `code` is back boring: Haas G77, and G87 where the dialect says so
    /// (Fanuc; on Haas G87 bores with a manual retract).
    pub(super) fn is_back_bore(&self, code: u32) -> bool {
        code == 770 || (code == 870 && self.dialect.table().g87_back_bore)
    }
}
