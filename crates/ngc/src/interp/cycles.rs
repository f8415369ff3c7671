//! Canned cycles G73, G81-G83, G85, G86, G89 in the current plane: the moves of each hole
//! as LinuxCNC's G-code manual describes them (the retract to R or the initial level, the
//! pecks, the dwell), checked against rs274.

use std::collections::VecDeque;

use super::Interp;
use crate::axis::{Axis, AxisVec};
use crate::canon::{Motion, Move, PathControl};
use crate::lex::{LineError, LineResult, Word};
use crate::polar::Polar;
use crate::units::MM_PER_INCH;

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
            self.cycle_p = Some(super::non_modal::dwell_p_seconds(
                self.dialect.table().dwell_p,
                &p,
            ));
        }
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
        let repeats = get('L').map_or(1, |l| l.value.round() as u64);
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
        if r < bottom {
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
        };
        self.holes(&holes, get, line_no, queue, at)
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
            code,
            axes: (u, v, n),
            r,
            bottom,
            step: (du, dv),
            first: (mut pu, mut pv),
            delta,
            repeats,
            initial: old_n,
        } = *h;
        let scale = self.scale();
        let dwell = self.cycle_p.unwrap_or(0.0);
        let rapid_delta = 0.010 * MM_PER_INCH; // LinuxCNC's G73/G83 clearance, 0.010 in.
        let exact = PathControl::ExactPath;
        let mut cur = self.pos;
        let go = |me: &mut Interp,
                  queue: &mut VecDeque<Move>,
                  cur: &mut AxisVec,
                  motion: Motion,
                  pu: f64,
                  pv: f64,
                  pn: f64| {
            let mut t = *cur;
            t[u] = pu;
            t[v] = pv;
            t[n] = pn;
            me.emit(queue, line_no, motion, *cur, t, exact);
            *cur = t;
        };
        // The dwell at the hole bottom (G82, G86, G89): P seconds where the tool stands.
        let dwell_at = |me: &mut Interp, queue: &mut VecDeque<Move>, at: AxisVec| {
            me.emit(
                queue,
                line_no,
                Motion::Dwell { seconds: dwell },
                at,
                at,
                exact,
            );
        };
        // As rs274 runs it: the first hole is approached at the current level (when
        // above R), the next ones at the clear level.
        let mut current = self.pos[n];
        let mut old = old_n;
        if old < r {
            go(
                self,
                queue,
                &mut cur,
                Motion::Rapid,
                self.pos[u],
                self.pos[v],
                r,
            );
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
            if k == 0 && current > r {
                go(self, queue, &mut cur, Motion::Rapid, pu, pv, current);
                go(self, queue, &mut cur, Motion::Rapid, pu, pv, r);
            } else {
                go(self, queue, &mut cur, Motion::Rapid, pu, pv, clear);
                if clear > r {
                    go(self, queue, &mut cur, Motion::Rapid, pu, pv, r);
                }
            }
            match code {
                810 => {
                    go(self, queue, &mut cur, Motion::Linear, pu, pv, bottom);
                    go(self, queue, &mut cur, Motion::Rapid, pu, pv, clear);
                }
                820 | 860 => {
                    go(self, queue, &mut cur, Motion::Linear, pu, pv, bottom);
                    dwell_at(self, queue, cur);
                    go(self, queue, &mut cur, Motion::Rapid, pu, pv, clear);
                }
                830 | 730 => {
                    let mut depth = r - delta;
                    while depth > bottom {
                        go(self, queue, &mut cur, Motion::Linear, pu, pv, depth);
                        if code == 830 {
                            go(self, queue, &mut cur, Motion::Rapid, pu, pv, r);
                        }
                        go(
                            self,
                            queue,
                            &mut cur,
                            Motion::Rapid,
                            pu,
                            pv,
                            depth + rapid_delta,
                        );
                        depth -= delta;
                    }
                    go(self, queue, &mut cur, Motion::Linear, pu, pv, bottom);
                    go(self, queue, &mut cur, Motion::Rapid, pu, pv, clear);
                }
                850 => {
                    go(self, queue, &mut cur, Motion::Linear, pu, pv, bottom);
                    go(self, queue, &mut cur, Motion::Linear, pu, pv, r);
                    if clear != r {
                        go(self, queue, &mut cur, Motion::Rapid, pu, pv, clear);
                    }
                }
                _ => {
                    // G89
                    go(self, queue, &mut cur, Motion::Linear, pu, pv, bottom);
                    dwell_at(self, queue, cur);
                    // LinuxCNC feeds straight back to the clearance plane (checked with rs274).
                    go(self, queue, &mut cur, Motion::Linear, pu, pv, clear);
                }
            }
        }
        self.pos = cur;
        Ok(())
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
}
