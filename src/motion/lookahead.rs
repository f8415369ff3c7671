//! The look-ahead window's planning ([`Interpolator`]'s): each appended block's junction
//! limit, and the backward passes that raise the blocks' entry limits from the end of the
//! window (the rules: the parent module's documentation and docs/interpolation.md,
//! "Look-ahead").
//!
//! A block appended since the last pass assumes a stop at its own end: its entry limit is
//! `reach(0, L, min(junction cap, V))` ([`Planned::rest_entry`]). The pass takes the larger
//! of that and the limit from the next block's entry `v`, `reach(v, L, ..)`; where
//! [`rest_reach_below`] shows `v` above the limit from rest, the larger is the latter, to the
//! bit, and the limit from rest is not computed.

use super::{pass_batch, Interpolator, JunctionEnd, Planned};
use crate::error::Result;
use crate::motion::profile::{reach, rest_reach_below};
use crate::program::{Move, PathControl};
use crate::AxisVec;

impl Planned {
    /// Largest entry speed from which the block can stop at its own end (what a block not
    /// yet passed assumes): `reach(0, L, min(entry cap, cap))`.
    pub(super) fn rest_entry(&self) -> f64 {
        if self.length == 0.0 {
            return 0.0;
        }
        reach(
            0.0,
            self.length,
            self.entry_cap.min(self.cap),
            self.accel,
            self.jerk,
        )
    }

    /// Largest entry speed from which the rest of the window is feasible: `entry_max`, or
    /// the stop at its own end for a block appended since the last backward pass.
    pub(super) fn entry_limit(&self) -> f64 {
        if self.rest_entry_due {
            self.rest_entry()
        } else {
            self.entry_max
        }
    }
}

impl<I: Iterator<Item = Result<Move>>> Interpolator<I> {
    /// The junction limit of the block just appended to the window (its back), with `dq/ds`
    /// at its start and end, computed in place; then the backward pass when one is due.
    pub(super) fn finish_push(&mut self, tangent_start: AxisVec, tangent_end: AxisVec) {
        let Some(p) = self.window.back_mut() else {
            return;
        };
        let dwell = p.length == 0.0;
        let curved = !p.path.is_straight();
        if let (Some(prev), false) = (self.last_end, dwell) {
            if !prev.dwell {
                let share = if curved || prev.curved { 0.5 } else { 1.0 }
                    * self.options.corner_acceleration_share;
                // Into and out of a blend held below its feed the path speed is continuous
                // (a speed ratio would make the step at its far end as large as the drop).
                let slow = p.path.bend.is_some() && p.cap < p.programmed * (1.0 - 1e-9);
                let smooth = prev.slow_bend || slow;
                // Under LinuxCNC's rules the path speed is continuous at every junction
                // (measured: X10 at F600 then X20 at F1200 passes X10 at 10.16 mm/s).
                let linuxcnc = self.control.max_feed_override.is_some();
                let rho = if smooth || linuxcnc {
                    1.0
                } else {
                    p.cap / prev.cap
                };
                let mut mu = prev.cap;
                for (i, l) in self.limits.iter().enumerate() {
                    let Some(l) = l else { continue };
                    let jump = (rho * tangent_start.0[i] - prev.tangent.0[i]).abs();
                    let allowed = share * l.acceleration * self.period_s;
                    if jump * mu > allowed {
                        mu = allowed / jump;
                    }
                }
                match prev.path {
                    // G61.1: every move ends at rest.
                    PathControl::ExactStop => mu = 0.0,
                    // G61: stop at every corner that is not collinear.
                    PathControl::ExactPath => {
                        let unit = |t: AxisVec| t * (1.0 / t.mixed_norm().max(f64::MIN_POSITIVE));
                        if (unit(tangent_start) - unit(prev.tangent)).mixed_norm() > 1e-9 {
                            mu = 0.0;
                        }
                    }
                    // G64 P: the fine-interpolated command cuts the corner by at most
                    // (T/4) |Δw| (Δw: the XYZ velocity jump); keep that within P.
                    PathControl::Blend {
                        tolerance_mm: Some(tol),
                        ..
                    } if tol.is_finite() && tol >= 0.0 => {
                        let jump = tangent_start * rho - prev.tangent;
                        let xyz_jump =
                            (jump.0[0].powi(2) + jump.0[1].powi(2) + jump.0[2].powi(2)).sqrt();
                        let allowed = 4.0 * tol / self.period_s;
                        if xyz_jump * mu > allowed {
                            mu = allowed / xyz_jump;
                        }
                    }
                    PathControl::Blend { .. } => {}
                }
                // LinuxCNC's planner (`[control] max_feed_override` given) stops between a
                // rapid and a feed move (measured: 0.06 and 0.13 mm/s there, blend.rs).
                let rapid = p.programmed == f64::INFINITY;
                if self.control.max_feed_override.is_some() && prev.rapid != rapid {
                    mu = 0.0;
                }
                // Under its rules a corner next to an arc that is not blended (an arc curving
                // the same way as the turn, a reversal: arc_corner) stops: the junction rule's
                // step beside the arc's acceleration would exceed the axis's limit.
                // (The turn only then: two norms and a difference of the tangents.)
                let unit = |t: AxisVec| t * (1.0 / t.mixed_norm().max(f64::MIN_POSITIVE));
                let turns = || (unit(tangent_start) - unit(prev.tangent)).mixed_norm() > 1e-6;
                if self.control.max_feed_override.is_some() && (curved || prev.curved) && turns() {
                    mu = 0.0;
                }
                if p.overlap.is_some() {
                    mu = 0.0;
                }
                p.rho = rho;
                p.entry_cap = rho * mu;
            }
        }
        self.last_end = Some(JunctionEnd {
            tangent: tangent_end,
            cap: p.cap,
            dwell,
            curved,
            slow_bend: p.path.bend.is_some() && p.cap < p.programmed * (1.0 - 1e-9),
            path: p.path_control,
            rapid: p.programmed == f64::INFINITY,
        });
        // Its limit from a stop at its own end ([`Planned::rest_entry`]) is left to the
        // backward pass, which often finds it cannot matter.
        p.entry_max = 0.0;
        p.rest_entry_due = !dwell;
        self.unpassed += 1;
        if self.unpassed >= pass_batch(&self.options) {
            self.backward_pass();
        }
    }

    /// Raises the entry limits that the blocks appended since the last pass allow, from the
    /// end of the window back. It stops at the first block whose limit rises by less than a
    /// relative 1e-12 (including one already at its own cap, which cannot rise) once it is
    /// past the new blocks: every limit
    /// is feasible at all times (a block not yet passed assumes a stop at its own end), so a
    /// pass left early is only conservative. Cost: at most the window per pass, one pass per
    /// [`pass_batch`] blocks, so O(1) amortised per block.
    pub(super) fn backward_pass(&mut self) {
        // The new blocks and the one before them (which assumed a stop at its end) are
        // always recomputed; earlier ones only while the limits keep rising.
        let fresh_from = self.window.len().saturating_sub(self.unpassed + 1);
        self.unpassed = 0;
        // The last block stops at its own end. The blocks walked back in one sweep of the
        // window, each next block's two numbers carried over (not indexed again).
        let len = self.window.len();
        let mut blocks = self.window.iter_mut().rev();
        let Some(last) = blocks.next() else {
            return;
        };
        last.entry_max = last.entry_limit();
        last.rest_entry_due = false;
        let (mut next_entry_max, mut next_rho) = (last.entry_max, last.rho);
        for (k, b) in (0..len - 1).rev().zip(blocks) {
            let exit = next_entry_max / next_rho;
            let v = exit.min(b.cap);
            let entry = if b.length == 0.0 {
                0.0
            } else {
                reach(v, b.length, b.entry_cap.min(b.cap), b.accel, b.jerk)
            };
            if b.rest_entry_due {
                b.rest_entry_due = false;
                b.entry_max = if k >= fresh_from && rest_reach_below(v, b.length, b.accel, b.jerk) {
                    // `entry ≥ v > rest_entry`: the max below is `entry`, bit for bit.
                    0.0
                } else {
                    b.rest_entry()
                };
            }
            if entry <= b.entry_max * (1.0 + 1e-12) && k < fresh_from {
                break;
            }
            b.entry_max = entry.max(b.entry_max);
            (next_entry_max, next_rho) = (b.entry_max, b.rho);
        }
    }
}
