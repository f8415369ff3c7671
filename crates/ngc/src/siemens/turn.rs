//! `G2/G3 X.. Y.. Z.. I.. J.. TURN=n`: a helix with `n` full turns before the arc to its
//! end point (Fundamentals, "Helical interpolation (G2/G3, TURN)"). The axis along the
//! plane's normal moves linearly with the angle turned over the whole helix; the canonical
//! moves are `n` full circles (each back to the start in the plane, rising by its share)
//! and then the arc to the end. TURN is read with the centre by I J K (not with CR=).

use super::words::{number, Coordinate, Words};
use super::Reader;
use crate::axis::Axis;
use crate::lex::{LineError, LineResult};

/// Most full turns one block may ask for.
const MAX_TURNS: f64 = 10_000.0;

impl Reader {
    /// `TURN=n` among the words (the cursor after `TURN`).
    pub(super) fn turn_word(
        &mut self,
        at: usize,
        sc: &mut super::expr::Scan,
        w: &mut Words,
    ) -> LineResult<()> {
        if !sc.eat(b'=') {
            return Err(sc.err(at, "expected `TURN=n` (full turns of a helix)", "TURN"));
        }
        let n = super::expr::expr(sc, &self.vars)?;
        if !(0.0..=MAX_TURNS).contains(&n) || n.fract() != 0.0 {
            return Err(sc.err(
                at,
                format!("TURN={n}: expected a whole number of full turns from 0 to {MAX_TURNS}"),
                "TURN",
            ));
        }
        w.turn = Some((n as u32, at..sc.at));
        Ok(())
    }

    /// The ISO blocks of a helix with full turns (see the module doc): the full circles
    /// are run here, the last arc is left in the block for `emit`.
    pub(super) fn turn_words(&mut self, w: &Words, line_no: usize) -> LineResult<()> {
        let Some((n, span)) = w.turn.clone() else {
            return Ok(());
        };
        let refuse = |m: &str| {
            Err(LineError::new(
                span.clone(),
                format!("{m} (Fundamentals, \"Helical interpolation (G2/G3, TURN)\")"),
                "TURN",
            ))
        };
        if !matches!(self.motion, 2 | 3) {
            return refuse("TURN= outside G2/G3: TURN gives the full turns of a helix");
        }
        if w.cr.is_some() || w.centres.iter().all(Option::is_none) {
            return refuse("TURN= without I J K (or with CR=): mtsim reads a helix's turns with its centre by I J K");
        }
        if w.axes[3..].iter().any(Option::is_some) {
            return refuse("TURN= with a rotary or other axis in the block: not supported");
        }
        let p = self.interp.program_position();
        let start = [p[Axis::X], p[Axis::Y], p[Axis::Z]];
        let here = self.frame.frame_point(start);
        let (plane, _, flip) = self.frame.arc_plane(self.normal).ok_or_else(|| {
            LineError::new(span.clone(), "a helix in a frame that tilts its plane off the work axes or stretches it unevenly", "arc in a tilted frame")
        })?;
        let (mut q, mut c) = (here, here);
        for k in 0..3 {
            q[k] = Coordinate::resolve(&w.axes[k], here[k], self.absolute);
            c[k] = Coordinate::resolve(&w.centres[k], here[k], false);
        }
        let (end, c) = (self.frame.work_point(q), self.frame.work_point(c));
        let clockwise = (self.motion == 2) != flip;
        let (u, v) = ((plane + 1) % 3, (plane + 2) % 3);
        let a0 = (start[v] - c[v]).atan2(start[u] - c[u]);
        let a1 = (end[v] - c[v]).atan2(end[u] - c[u]);
        let tau = std::f64::consts::TAU;
        let mut last = if clockwise { a0 - a1 } else { a1 - a0 }.rem_euclid(tau);
        if last < 1e-9 {
            last = tau;
        }
        let total = f64::from(n) * tau + last;
        let code = if clockwise { 2 } else { 3 };
        for k in 1..=n {
            let mut e = start;
            e[plane] = start[plane] + (end[plane] - start[plane]) * (f64::from(k) * tau / total);
            self.helix_block(code, plane, e, c, start, span.clone());
            self.run_iso(line_no)?;
        }
        self.helix_block(code, plane, end, c, start, span);
        Ok(())
    }

    /// One arc of the helix to `end` about `c` (in the plane, the start's in-plane point
    /// is the same for every turn).
    fn helix_block(
        &mut self,
        code: u8,
        plane: usize,
        end: [f64; 3],
        c: [f64; 3],
        start: [f64; 3],
        span: std::ops::Range<usize>,
    ) {
        self.push("G90", span.clone());
        self.interp_absolute = true;
        self.plane_code(plane, span.clone());
        self.push(&format!("G{code}"), span.clone());
        self.interp_motion = code;
        for (k, l) in ["X", "Y", "Z"].iter().enumerate() {
            self.push(&format!("{l}{}", number(end[k])), span.clone());
        }
        for (k, l) in ["I", "J", "K"].iter().enumerate() {
            if k != plane {
                self.push(&format!("{l}{}", number(c[k] - start[k])), span.clone());
            }
        }
    }
}
