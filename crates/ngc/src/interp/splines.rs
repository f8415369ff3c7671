//! LinuxCNC splines: G5 (cubic), G5.1 (quadratic) and NURBS G5.2/G5.3 in the XY plane,
//! emitted as the lines and arcs of crate `spline`.

use std::collections::VecDeque;

use super::Interp;
use crate::axis::{Axis, AxisVec, Plane};
use crate::canon::{Motion, Move};
use crate::code::{FeedRead, MotionMode};
use crate::lex::{LineError, LineResult, Word};
use crate::spline;

impl Interp {
    /// Emits the pieces of a spline (program coordinates) as feed moves and arcs.
    pub(super) fn spline_pieces(
        &mut self,
        queue: &mut VecDeque<Move>,
        line_no: usize,
        pieces: &[spline::Piece],
    ) {
        let scale = self.scale();
        for piece in pieces {
            let start = self.pos;
            let mut end = start;
            let e = piece.end();
            let e = self.xy_to_machine([e[0] * scale, e[1] * scale]);
            end[Axis::X] = e[0];
            end[Axis::Y] = e[1];
            let motion = match *piece {
                spline::Piece::Line { .. } => Motion::Linear,
                spline::Piece::Arc { center, ccw, .. } => {
                    let c = self.xy_to_machine([center[0] * scale, center[1] * scale]);
                    Motion::Arc {
                        clockwise: !ccw,
                        plane: Plane::XY,
                        center_mm: [c[0], c[1], start[Axis::Z]],
                    }
                }
            };
            self.emit(queue, line_no, motion, start, end, self.path);
            self.pos = end;
        }
    }

    /// The checks LinuxCNC makes of a spline (its messages quoted from rs274), shared by G5,
    /// G5.1 and G5.2.
    pub(super) fn spline_checks<'l>(
        &self,
        get: &dyn Fn(char) -> Option<Word<'l>>,
        at: &std::ops::Range<usize>,
    ) -> LineResult<()> {
        let err = |m: &str| Err(LineError::new(at.clone(), m.to_string(), "spline"));
        if self.comp.is_some() {
            return err("spline with cutter radius compensation on: expected G40 first (LinuxCNC: \"Cannot convert spline with cutter radius compensation\")");
        }
        if self.plane != Plane::XY {
            return err("spline outside G17: expected the XY plane (LinuxCNC: \"Splines must be in the XY plane\")");
        }
        if self.feed_mode == FeedRead::InverseTime {
            return err("spline in G93 (inverse time): not supported, expected G94");
        }
        if let Some(w) = ['Z', 'A', 'B', 'C'].into_iter().find_map(|l| get(l)) {
            return Err(LineError::new(w.span(), "axis word other than X Y in a spline block: expected X and Y only (LinuxCNC: \"Splines may not have motion in Z, A, B, or C\")", "not a spline axis"));
        }
        Ok(())
    }

    /// G5 (cubic) or G5.1 (quadratic) from `start` to `target` (machine coordinates).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn spline<'l>(
        &mut self,
        line: &str,
        code: u32,
        get: &dyn Fn(char) -> Option<Word<'l>>,
        line_no: usize,
        queue: &mut VecDeque<Move>,
        start: AxisVec,
        target: AxisVec,
        at: std::ops::Range<usize>,
    ) -> LineResult<()> {
        self.spline_checks(get, &at)?;
        let _ = line;
        let scale = self.scale();
        let prog = |p: AxisVec| {
            let q = self.xy_to_program([p[Axis::X], p[Axis::Y]]);
            [q[0] / scale, q[1] / scale]
        };
        let (s, e) = (prog(start), prog(target));
        let (i, j) = (get('I').map(|w| w.value), get('J').map(|w| w.value));
        let err = |m: &str| Err(LineError::new(at.clone(), m.to_string(), "spline"));
        let pieces = if code == 51 {
            let (Some(i), Some(j)) = (i, j) else {
                return err("G5.1 without I and J: expected both (LinuxCNC: \"Must specify both I and J with G5.1\")");
            };
            spline::pieces(&spline::quadratic(s, [i, j], e), 3)
        } else {
            let ij = match (i, j) {
                (Some(i), Some(j)) => [i, j],
                (None, None) => self.spline_ij,
                _ => return err("G5 with only one of I and J: expected both, or neither after a G5 (LinuxCNC: \"Must specify both I and J, or neither\")"),
            };
            let (Some(p), Some(q)) = (get('P').map(|w| w.value), get('Q').map(|w| w.value)) else {
                return err("G5 without P and Q: expected both (LinuxCNC: \"Must specify both P and Q with G5\")");
            };
            self.spline_ij = [-p, -q];
            spline::pieces(&spline::cubic(s, ij, e, [p, q]), 4)
        };
        self.spline_pieces(queue, line_no, &pieces);
        // The end is the programmed point exactly.
        self.pos = target;
        Ok(())
    }

    /// A G5.2 block (a control point) or a G5.3 block (the NURBS move). True when the
    /// block's axis words are used up.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn nurbs_block<'l>(
        &mut self,
        line: &str,
        get: &dyn Fn(char) -> Option<Word<'l>>,
        nurbs_end: Option<Word<'l>>,
        g52: Option<Word<'l>>,
        previous_motion: Option<MotionMode>,
        axis_words: &[(Axis, Word<'l>)],
        line_no: usize,
        queue: &mut VecDeque<Move>,
    ) -> LineResult<bool> {
        let at = nurbs_end
            .or(g52)
            .or(axis_words.first().map(|(_, w)| *w))
            .map_or(0..0, |w| w.span());
        let err = |m: &str| Err(LineError::new(at.clone(), m.to_string(), "NURBS"));
        if let Some(w) = nurbs_end {
            if previous_motion != Some(MotionMode::Spline(52)) {
                return err("G5.3 without G5.2 first: expected G5.2 control points before it (LinuxCNC: \"Cannot use G5.3 without G5.2 first\")");
            }
            if let Some((_, a)) = axis_words.first() {
                return Err(LineError::new(
                    a.span(),
                    format!("`{}` in a G5.3 block: expected G5.3 alone", &line[a.span()]),
                    "axis word with G5.3",
                ));
            }
            if self.nurbs.len() < self.nurbs_order {
                return Err(LineError::new(w.span(), format!("NURBS with {} control points: expected at least the order L = {} (LinuxCNC: \"You must specify a number of control points at least equal to the order\")", self.nurbs.len(), self.nurbs_order), "too few control points"));
            }
            let cps = std::mem::take(&mut self.nurbs);
            let pieces = spline::pieces(&cps, self.nurbs_order);
            self.spline_pieces(queue, line_no, &pieces);
            self.motion = None;
            return Ok(true);
        }
        if g52.is_none() && axis_words.is_empty() {
            return Ok(false);
        }
        self.spline_checks(get, &at)?;
        let (x, y) = (get('X'), get('Y'));
        if x.is_some() != y.is_some() {
            return err("G5.2 control point with only one of X and Y: expected both (LinuxCNC: \"You must specify both X and Y coordinates for Control Points\")");
        }
        let p = get('P').map(|w| w.value);
        if previous_motion != Some(MotionMode::Spline(52)) {
            self.nurbs.clear();
        }
        if x.is_none() && p.is_some_and(|p| p > 0.0) && !self.nurbs.is_empty() {
            return err("G5.2 with P and no X Y after the first control point (LinuxCNC: \"Can specify P without X and Y only for the first control point\")");
        }
        if x.is_some() && !p.is_some_and(|p| p > 0.0) {
            return err("G5.2 control point without a positive weight P: expected P > 0 (LinuxCNC: \"Must specify positive weight P for every Control Point\")");
        }
        if self.feed.is_none() {
            return err("NURBS with no feed programmed: expected an F word");
        }
        let scale = self.scale();
        if self.nurbs.is_empty() {
            let cur = self.program_position();
            self.nurbs.push(spline::ControlPoint {
                x: cur[Axis::X],
                y: cur[Axis::Y],
                w: if x.is_none() { p.unwrap_or(1.0) } else { 1.0 },
            });
            self.nurbs_order = 3;
        }
        if let Some(l) = get('L') {
            if l.value > 3.0 {
                self.nurbs_order = l.value.round() as usize;
            }
        }
        if x.is_some() {
            let t = self.target(axis_words, false);
            let q = self.xy_to_program([t[Axis::X], t[Axis::Y]]);
            self.nurbs.push(spline::ControlPoint {
                x: q[0] / scale,
                y: q[1] / scale,
                w: p.unwrap_or(1.0),
            });
        }
        if self.nurbs.len() > 10_000 {
            return err("more than 10000 NURBS control points: expected G5.3 before");
        }
        Ok(true)
    }
}
