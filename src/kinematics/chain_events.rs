//! Poles and solution switches along a path of machine poses on a chain with two rotaries.
//!
//! At a block end q the tool direction is `t_w` (forward kinematics); the inverse
//! kinematics of that direction has two rotary solutions (`chain_inverse::solutions`), or a
//! family at a pole, where t_w lies along the line of the rotary nearer the bed (on a
//! fork head or a nutating head over C: the tool along C) and that rotary is free. So:
//!
//! - **pole**: a block ends at a pole. The free rotary may take any value there; whatever
//!   the next block programs for it is the swing the machine makes with the tool standing
//!   on the pole (`PathEvent::Pole`, `swing_deg` = the next block's move of the free axis:
//!   180° for a path that crosses the pole straight, C swinging round in one block).
//! - **switch**: two block ends in a row lie on different branches (the solution whose
//!   rotaries are q's, each compared modulo 360°): the block passed through a singular pose
//!   (a pole or the rim of the reach) from one solution to the other (`PathEvent::Switch`).

use super::chain::{Chain, ToolPose};
use super::chain_inverse::{solutions, PathEvent};
use crate::{Axis, AxisVec};

/// Two rotaries agree when they differ by a whole number of turns within this, deg.
const SAME_DEG: f64 = 1e-6;

/// Watches the block ends of a path for [`PathEvent`]s.
#[derive(Clone, Debug)]
pub struct PoleWatch {
    chain: Chain,
    /// The previous block end: its line, joints and branch (`None` at a pole).
    previous: Option<(usize, AxisVec, Option<usize>)>,
    /// A pole met at the previous block end: its line, the free axis and its value there.
    pending: Option<(usize, Axis, f64)>,
    pub events: Vec<PathEvent>,
}

impl PoleWatch {
    /// A watcher for `chain`; `None` unless it has exactly two rotaries (one rotary has no
    /// second solution; more are refused by the inverse kinematics).
    pub fn new(chain: &Chain) -> Option<PoleWatch> {
        (chain.rotaries().count() == 2).then(|| PoleWatch {
            chain: *chain,
            previous: None,
            pending: None,
            events: Vec::new(),
        })
    }

    /// The next block end: machine axis positions `q` reached by source line `line`.
    pub fn push(&mut self, line: usize, q: &AxisVec) {
        if let Some((pole_line, axis, at)) = self.pending.take() {
            self.events.push(PathEvent::Pole {
                line: pole_line,
                axis,
                swing_deg: q[axis] - at,
            });
        }
        let (tip, axis) = self.chain.tool_in_workpiece(q, 0.0);
        let branch = match solutions(&self.chain, &ToolPose { tip, axis }, 0.0, q) {
            Ok(all) => {
                if let Some(free) = all.iter().find_map(|s| s.free_axis) {
                    self.pending = Some((line, free, q[free]));
                    None
                } else {
                    all.iter()
                        .find(|s| self.same_rotaries(&s.joints, q))
                        .map(|s| s.branch)
                }
            }
            Err(_) => None,
        };
        if let Some((_, _, Some(before))) = self.previous {
            if let Some(now) = branch.filter(|b| *b != before) {
                self.events.push(PathEvent::Switch {
                    line,
                    from: before,
                    to: now,
                });
            }
        }
        self.previous = Some((line, *q, branch));
    }

    /// The events, a pole at the last block end included (its swing 0: nothing follows).
    pub fn finish(mut self) -> Vec<PathEvent> {
        if let Some((line, axis, _)) = self.pending.take() {
            self.events.push(PathEvent::Pole {
                line,
                axis,
                swing_deg: 0.0,
            });
        }
        self.events
    }

    fn same_rotaries(&self, a: &AxisVec, b: &AxisVec) -> bool {
        self.chain.rotaries().all(|(_, l)| {
            let d = (a[l.axis] - b[l.axis]).rem_euclid(360.0);
            d.min(360.0 - d) < SAME_DEG
        })
    }
}

/// What `event` means on `chain`, for the terminal:
/// "line 42: pole of B (tool along C): C swings 180.000 deg in one block".
pub fn describe(event: &PathEvent, chain: &Chain) -> String {
    match event {
        PathEvent::Pole {
            line,
            axis,
            swing_deg,
        } => {
            let other = chain
                .rotaries()
                .map(|(_, l)| l.axis)
                .find(|a| a != axis)
                .unwrap_or(*axis);
            let what = if swing_deg.abs() < SAME_DEG {
                format!("{axis} holds")
            } else {
                format!("{axis} swings {swing_deg:.3} deg in one block")
            };
            format!("line {line}: pole of {other} (tool along {axis}): {what}")
        }
        PathEvent::Switch { line, from, to } => format!(
            "line {line}: the rotaries switch from solution {from} to solution {to} (the block passes a singular pose)"
        ),
    }
}
