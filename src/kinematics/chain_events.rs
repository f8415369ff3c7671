//! Poles and solution switches along a path of machine poses on a chain with two rotaries.
//!
//! At a block end q the tool direction is `t_w` (forward kinematics); the inverse
//! kinematics of that direction has two rotary solutions (`chain_inverse::solutions`), or a
//! family at a pole, where t_w lies along the line of the inner rotary ([`Pole`]) and that
//! rotary is free. So:
//!
//! - **pole passage**: block ends in a row within the chain's pole tolerance of the pole
//!   (angle δ < `pole_tolerance_deg`), reported once for the passage with its first and
//!   last line (`PathEvent::Pole`, `swing_deg` = the inner rotary's move from the block end
//!   before the passage to the one after it: about 180° for a path that crosses the pole
//!   on one branch, C swinging round; about 0 on the other branch, C holding). A change of
//!   branch across the passage belongs to it (the outer rotary passes zero) and is no switch.
//! - **switch**: two block ends in a row, neither at the pole, lie on different branches
//!   (the solution whose rotaries are q's, each compared modulo 360°): the block passed
//!   through a singular pose (the rim of the reach) from one solution to the other
//!   (`PathEvent::Switch`).

use super::chain::{Chain, ToolPose};
use super::chain_inverse::{solutions, PathEvent};
use super::pole::Pole;
use crate::{Axis, AxisVec};

/// Two rotaries agree when they differ by a whole number of turns within this, deg.
const SAME_DEG: f64 = 1e-6;

/// A pole passage under way: its first and last line, and the inner rotary's value before it.
#[derive(Clone, Copy, Debug)]
struct Passage {
    first_line: usize,
    last_line: usize,
    before: f64,
}

/// Watches the block ends of a path for [`PathEvent`]s.
#[derive(Clone, Debug)]
pub struct PoleWatch {
    chain: Chain,
    pole: Pole,
    tolerance_deg: f64,
    /// The previous block end: its joints and branch (`None` at a pole).
    previous: Option<(AxisVec, Option<usize>)>,
    /// The passage the previous block end is in.
    passage: Option<Passage>,
    pub events: Vec<PathEvent>,
}

impl PoleWatch {
    /// A watcher for `chain` with pole tolerance `tolerance_deg`; `None` unless it has
    /// exactly two rotaries (one rotary has no second solution; more are refused by the
    /// inverse kinematics).
    pub fn new(chain: &Chain, tolerance_deg: f64) -> Option<PoleWatch> {
        Some(PoleWatch {
            chain: *chain,
            pole: Pole::of(chain)?,
            tolerance_deg,
            previous: None,
            passage: None,
            events: Vec::new(),
        })
    }

    /// The next block end: machine axis positions `q` reached by source line `line`.
    pub fn push(&mut self, line: usize, q: &AxisVec) {
        let inner = self.pole.inner;
        let (tip, axis) = self.chain.tool_in_workpiece(q, 0.0);
        // The exact pole (the free axis of the solutions) or within the tolerance of it.
        let all = solutions(&self.chain, &ToolPose { tip, axis }, 0.0, q);
        let exact = all
            .as_ref()
            .is_ok_and(|all| all.iter().any(|s| s.free_axis.is_some()));
        if exact || self.pole.angle_deg(&axis) < self.tolerance_deg {
            let before = self.previous.map_or(q[inner], |(p, _)| p[inner]);
            let passage = self.passage.get_or_insert(Passage {
                first_line: line,
                last_line: line,
                before,
            });
            passage.last_line = line;
            self.previous = Some((*q, None));
            return;
        }
        let branch = all.ok().and_then(|all| {
            all.iter()
                .find(|s| self.same_rotaries(&s.joints, q))
                .map(|s| s.branch)
        });
        if let Some(p) = self.passage.take() {
            self.events.push(passage_event(p, inner, q[inner]));
        } else if let Some((_, Some(before))) = self.previous {
            if let Some(now) = branch.filter(|b| *b != before) {
                self.events.push(PathEvent::Switch {
                    line,
                    from: before,
                    to: now,
                });
            }
        }
        self.previous = Some((*q, branch));
    }

    /// The events, a passage at the last block end included (its swing up to that end).
    pub fn finish(mut self) -> Vec<PathEvent> {
        if let Some(p) = self.passage.take() {
            let last = self.previous.map_or(p.before, |(q, _)| q[self.pole.inner]);
            self.events.push(passage_event(p, self.pole.inner, last));
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

/// The event of passage `p` of the pole of `axis`, which stands at `after` past it.
fn passage_event(p: Passage, axis: Axis, after: f64) -> PathEvent {
    PathEvent::Pole {
        line: p.first_line,
        last_line: p.last_line,
        axis,
        swing_deg: after - p.before,
    }
}

/// What `event` means on `chain`, for the terminal:
/// "line 42: pole of B (tool along C): C swings 180.000 deg in one block".
pub fn describe(event: &PathEvent, chain: &Chain) -> String {
    match event {
        PathEvent::Pole {
            line,
            last_line,
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
            } else if line == last_line {
                format!("{axis} swings {swing_deg:.3} deg in one block")
            } else {
                format!("{axis} turns {swing_deg:.3} deg across the passage")
            };
            if line == last_line {
                format!("line {line}: pole of {other} (tool along {axis}): {what}")
            } else {
                format!("lines {line}..{last_line}: pole of {other} (tool along {axis}): {what}")
            }
        }
        PathEvent::Switch { line, from, to } => format!(
            "line {line}: the rotaries switch from solution {from} to solution {to} (the block passes a singular pose)"
        ),
    }
}
