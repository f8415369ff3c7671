//! The lathe stock-removal cycles of the Fanuc family, G71 (layers along Z) and G72 (layers
//! along X), type I, and the return of G70's finishing pass: this project's own design from
//! the behaviour the Fanuc 0i-TF operator's manual ("Stock removal in turning", "Stock
//! removal in facing", "Finishing cycle") and the Haas lathe operator's manual ("G71 O.D./I.D.
//! Stock Removal Cycle", "G72 End Face Stock Removal Cycle", "G70 Finishing Cycle") describe.
//!
//! In the cycle's own coordinates, `a` along the cut (Z for G71, X for G72) and `b` across it
//! (X for G71, Z for G72), with the start point A = (a_A, b_A) and the finishing profile
//! P0 … Pn (blocks N`ns` to N`nf`, shifted by the allowances Δu along X and Δw along Z):
//!
//! ```text
//!   s_b = sign(b_P0 − b_A)     the layers step from A toward the profile's first point
//!   s_a = sign(a_Pn − a_A)     the cuts run from A toward the profile's end
//!   b_k = b_A + k·s_b·Δd,  k = 1, 2, … while the profile reaches beyond b_k (in s_b)
//!   at level b_k, each stretch [a0, a1] where the profile lies beyond b_k:
//!     from P0's side: rapid to (a_A, b_k), feed to (a1, b_k)
//!     a pocket:       rapid out to b_A, over to a0, down to b_k − s_b·e, feed to (a0, b_k),
//!                     feed to (a1, b_k)
//!     then rapid 45° off by e to (a1 − s_a·e, b_k − s_b·e), and back along the level to
//!     a_A (out of a pocket first: to b_A, then to a_A)
//!   then: rapid to P0, the profile at the cycle's feed to Pn, rapid to b_A, then to a_A
//! ```
//!
//! X is a diameter on these lathes: the radial Δd and e count twice along X. A profile
//! monotone in both coordinates is type I; one that goes in and out across the cut (a
//! groove) is type II, roughed stretch by stretch as above. A profile that turns back along
//! the cut is refused.

use std::collections::VecDeque;

use super::Interp;
use crate::axis::{Axis, AxisVec};
use crate::canon::{Motion, Move};
use crate::lex::{LineError, LineResult};

/// A G71 or G72 cycle's numbers, in mm (the program's units and diameter already applied).
#[derive(Clone, Copy, Debug)]
pub(crate) struct StockRemoval {
    /// G72 (layers along X, cuts along X at successive Z) rather than G71.
    pub facing: bool,
    /// Depth of each layer Δd, > 0.
    pub depth_mm: f64,
    /// The 45° retract e after each layer, ≥ 0.
    pub retract_mm: f64,
    /// The finishing allowance along X (Δu, its sign the side) and along Z (Δw).
    pub allowance_mm: [f64; 2],
}

/// Tolerance of the monotone test and of a level meeting a vertex, mm.
const EPS_MM: f64 = 1e-9;

impl Interp {
    /// Where the tool is (the moves' coordinates).
    pub(crate) fn position(&self) -> AxisVec {
        self.pos
    }

    /// The roughing moves of `cycle` about the finishing `profile` (its moves as the
    /// interpreter reads blocks N`ns`-N`nf` from the current position), queued at
    /// `line_no`; the tool ends at the start point.
    pub(crate) fn stock_removal(
        &mut self,
        cycle: &StockRemoval,
        profile: &[Move],
        line_no: usize,
        queue: &mut VecDeque<Move>,
        span: std::ops::Range<usize>,
    ) -> LineResult<()> {
        let (ax_a, ax_b) = if cycle.facing {
            (Axis::X, Axis::Z)
        } else {
            (Axis::Z, Axis::X)
        };
        let refuse =
            |m: String| -> LineResult<()> { Err(LineError::new(span.clone(), m, "stock removal")) };
        let start = self.pos;
        let shift = |p: AxisVec| {
            let mut q = p;
            q[Axis::X] += cycle.allowance_mm[0];
            q[Axis::Z] += cycle.allowance_mm[1];
            q
        };
        let path: Vec<Move> = profile
            .iter()
            .filter(|m| !matches!(m.motion, Motion::Dwell { .. }))
            .map(|m| Move {
                start: shift(m.start),
                end: shift(m.end),
                motion: match m.motion {
                    Motion::Arc {
                        clockwise,
                        plane,
                        center_mm: c,
                    } => Motion::Arc {
                        clockwise,
                        plane,
                        center_mm: [
                            c[0] + cycle.allowance_mm[0],
                            c[1],
                            c[2] + cycle.allowance_mm[1],
                        ],
                    },
                    other => other,
                },
                ..*m
            })
            .collect();
        let (Some(first), Some(last)) = (path.first(), path.last()) else {
            return refuse(
                "the profile blocks N(P) to N(Q) make no move: expected the finishing shape".into(),
            );
        };
        let (a_start, b_start) = (start[ax_a], start[ax_b]);
        let p0 = first.end;
        let pn = last.end;
        let s_b = (p0[ax_b] - b_start).signum();
        let s_a = (pn[ax_a] - a_start).signum();
        if (p0[ax_b] - b_start).abs() < EPS_MM || (pn[ax_a] - a_start).abs() < EPS_MM {
            return refuse(format!(
                "the profile's first block must move {} toward the part and its end lie along {} from the start point (type I)",
                ax_b.letter(),
                ax_a.letter()
            ));
        }
        let points = polyline(&path, ax_a, ax_b);
        if points.windows(2).any(|w| (w[1].0 - w[0].0) * s_a < -EPS_MM) {
            return refuse(format!(
                "the profile turns back along {}, which neither type I nor type II roughs: expected {} to keep its direction from N(P) to N(Q)",
                ax_a.letter(),
                ax_a.letter()
            ));
        }
        let go = |interp: &mut Interp, queue: &mut VecDeque<Move>, motion: Motion, to: AxisVec| {
            let from = interp.pos;
            if from != to {
                interp.emit(queue, line_no, motion, from, to, interp.path);
                interp.pos = to;
            }
        };
        let frame = Frame { start, ax_a, ax_b };
        // Radial lengths along X are doubled: X is a diameter.
        let x_units = |v: f64, axis: Axis| if axis == Axis::X { 2.0 * v } else { v };
        let step = x_units(cycle.depth_mm, ax_b);
        let back = (
            x_units(cycle.retract_mm, ax_a),
            x_units(cycle.retract_mm, ax_b),
        );
        let deepest = points
            .iter()
            .map(|p| p.1 * s_b)
            .fold(f64::NEG_INFINITY, f64::max);
        let mut k = 1.0;
        loop {
            let b = b_start + k * s_b * step;
            if deepest - b * s_b <= EPS_MM {
                break;
            }
            for (n, (a0, a1)) in cut_intervals(&points, b, s_b).into_iter().enumerate() {
                let from_start_side = n == 0 && (a0 - points[0].0).abs() < EPS_MM;
                if from_start_side {
                    // Along the level from the start point's side.
                    go(self, queue, Motion::Rapid, frame.at(a_start, b));
                } else {
                    // Into a pocket: out to the start's level, over its edge, and down.
                    go(
                        self,
                        queue,
                        Motion::Rapid,
                        frame.at(self.pos[ax_a], b_start),
                    );
                    go(self, queue, Motion::Rapid, frame.at(a0, b_start));
                    go(self, queue, Motion::Rapid, frame.at(a0, b - s_b * back.1));
                    go(self, queue, Motion::Linear, frame.at(a0, b));
                }
                go(self, queue, Motion::Linear, frame.at(a1, b));
                let off = frame.at(a1 - s_a * back.0, b - s_b * back.1);
                go(self, queue, Motion::Rapid, off);
                if !from_start_side {
                    // Out of the pocket before going back over the part.
                    go(self, queue, Motion::Rapid, frame.at(off[ax_a], b_start));
                    go(self, queue, Motion::Rapid, frame.at(a_start, b_start));
                } else {
                    go(
                        self,
                        queue,
                        Motion::Rapid,
                        frame.at(a_start, b - s_b * back.1),
                    );
                }
            }
            k += 1.0;
        }
        // The profile itself, shifted by the allowances, at the cycle's feed.
        go(self, queue, Motion::Rapid, p0);
        for m in &path[1..] {
            let motion = if m.motion == Motion::Rapid {
                Motion::Linear
            } else {
                m.motion
            };
            go(self, queue, motion, m.end);
        }
        self.return_to_start(start, ax_b, line_no, queue);
        Ok(())
    }

    /// The rapid back to a cycle's start point: off the part across the cut first
    /// (`across`), then along it.
    pub(crate) fn return_to_start(
        &mut self,
        start: AxisVec,
        across: Axis,
        line_no: usize,
        queue: &mut VecDeque<Move>,
    ) {
        let mut off = self.pos;
        off[across] = start[across];
        for to in [off, start] {
            let from = self.pos;
            if from != to {
                self.emit(queue, line_no, Motion::Rapid, from, to, self.path);
                self.pos = to;
            }
        }
    }
}

/// A cycle's own coordinates: `a` along the cut, `b` across it, about the start point.
struct Frame {
    start: AxisVec,
    ax_a: Axis,
    ax_b: Axis,
}

impl Frame {
    /// The axis positions at (a, b), the other axes at the start point's.
    fn at(&self, a: f64, b: f64) -> AxisVec {
        let mut q = self.start;
        q[self.ax_a] = a;
        q[self.ax_b] = b;
        q
    }
}

/// The stretches of `a` where level `b` lies in material: where the profile `points` lies
/// beyond it in the direction `s_b` the layers step in, in the order of the cut.
fn cut_intervals(points: &[(f64, f64)], b: f64, s_b: f64) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::new();
    for w in points.windows(2) {
        let ((a0, b0), (a1, b1)) = (w[0], w[1]);
        // > 0: the surface lies beyond the level, which is in material there.
        let (d0, d1) = ((b0 - b) * s_b, (b1 - b) * s_b);
        if d0 <= EPS_MM && d1 <= EPS_MM {
            continue;
        }
        let cross = a0 + (a1 - a0) * d0 / (d0 - d1);
        let from = if d0 < 0.0 { cross } else { a0 };
        let to = if d1 < 0.0 { cross } else { a1 };
        match out.last_mut() {
            Some(last) if (last.1 - from).abs() < EPS_MM => last.1 = to,
            _ => out.push((from, to)),
        }
    }
    out.retain(|(a0, a1)| (a1 - a0).abs() > EPS_MM);
    out
}

/// The shifted profile as (a, b) points, its arcs cut into chords of at most 1°.
fn polyline(path: &[Move], ax_a: Axis, ax_b: Axis) -> Vec<(f64, f64)> {
    let mut points = vec![(path[0].end[ax_a], path[0].end[ax_b])];
    for m in &path[1..] {
        if let Motion::Arc {
            clockwise,
            center_mm: c,
            ..
        } = m.motion
        {
            // In the ZX plane (G18): u = Z, v = X.
            let (cu, cv) = (c[2], c[0]);
            let (su, sv) = (m.start[Axis::Z] - cu, m.start[Axis::X] - cv);
            let (eu, ev) = (m.end[Axis::Z] - cu, m.end[Axis::X] - cv);
            let r = su.hypot(sv);
            let (t0, mut t1) = (sv.atan2(su), ev.atan2(eu));
            // Seen from +Y (G18's normal) Z turns toward X counter-clockwise (Z × X = Y),
            // so the angle atan2(X, Z) grows along a G3 and falls along a G2.
            let ccw = !clockwise;
            if ccw && t1 <= t0 {
                t1 += std::f64::consts::TAU;
            }
            if !ccw && t1 >= t0 {
                t1 -= std::f64::consts::TAU;
            }
            let n = ((t1 - t0).abs().to_degrees().ceil() as usize).max(1);
            for i in 1..=n {
                let t = t0 + (t1 - t0) * i as f64 / n as f64;
                let (z, x) = (cu + r * t.cos(), cv + r * t.sin());
                points.push(if ax_a == Axis::Z { (z, x) } else { (x, z) });
            }
        } else {
            points.push((m.end[ax_a], m.end[ax_b]));
        }
    }
    points
}
