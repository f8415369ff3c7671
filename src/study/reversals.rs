//! What each axis does: travel, peak speed and the angles (or lines) at which it reverses.
//!
//! Two sources:
//! - the exact cone path ([`analyse_cone`]): a reversal is a root of dq/dθ with a sign
//!   change, found by bracketing on a 0.5 deg grid and bisecting to 1e-12 rad; the peak
//!   speed is `max |dq/dθ| · dθ/dt` with `dθ/dt = F / r` (the ball moves at F on a circle of
//!   radius r);
//! - the blocks of an NC program ([`analyse_moves`]): block k's end is a turning point of
//!   an axis when its increment in block k and in the next block that moves it have opposite
//!   signs; speeds are implied by the F words, with block time `sqrt(Σ d²)/F` (G94, deg
//!   counted as mm) or `1/F` (G93).

use std::f64::consts::TAU;

use serde::Serialize;

use crate::error::Result;
use crate::input::machine::Machine;
use crate::input::program::{CircleTest, Direction};
use crate::input::scenario::Scenario;
use crate::measure::CircleFrame;
use crate::motion::sampling::{block_duration_s, position_in_block};
use crate::program::cone::{normalize_deg, ConePath};
use crate::program::{test_of, Motion, Move, TestProgram};
use crate::{Axis, AxisVec};

/// Reversals of different linear axes closer than this (deg) cannot be told apart in a trace.
pub const COINCIDENCE_WARNING_DEG: f64 = 2.0;

/// What one axis does over the program.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AxisMotion {
    #[serde(skip)]
    pub axis: Axis,
    /// Lowest position, mm or deg.
    pub min: f64,
    /// Highest position, mm or deg.
    pub max: f64,
    /// `max - min`, mm or deg.
    pub range: f64,
    /// Highest speed, mm/min or deg/min.
    pub peak_speed_per_min: f64,
    /// θ at which the axis reverses, deg in [0, 360), sorted. For a file program, the θ of
    /// the turning blocks' end points when the scenario gives the cone; otherwise empty.
    pub reversals_deg: Vec<f64>,
    /// For a file program: the source lines of the blocks whose end is a turning point.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reversal_lines: Option<Vec<usize>>,
    /// Reversals past the first [`MAX_LISTED_REVERSALS`] of the axis, counted, not listed
    /// (memory stays flat however long the program); absent when all are listed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reversals_not_listed: Option<u64>,
}

/// Reversals of one axis listed (lines and angles) before the rest are only counted.
pub const MAX_LISTED_REVERSALS: usize = 10_000;

/// The per-axis analysis of a program.
#[derive(Clone, Debug, PartialEq)]
pub struct Analysis {
    pub axes: Vec<AxisMotion>,
}

impl Analysis {
    pub fn axis(&self, axis: Axis) -> Option<&AxisMotion> {
        self.axes.iter().find(|a| a.axis == axis)
    }

    /// The smallest angular distance between reversals of two different linear axes, deg;
    /// `None` when fewer than two linear axes reverse.
    pub fn min_linear_separation_deg(&self) -> Option<f64> {
        self.closest_linear_reversals().map(|(d, _, _)| d)
    }

    /// The closest pair of reversals of different linear axes: (distance deg, (axis, θ), (axis, θ)).
    pub fn closest_linear_reversals(&self) -> Option<(f64, (Axis, f64), (Axis, f64))> {
        let linear: Vec<&AxisMotion> = self.axes.iter().filter(|a| !a.axis.is_rotary()).collect();
        let mut best: Option<(f64, (Axis, f64), (Axis, f64))> = None;
        for (i, a) in linear.iter().enumerate() {
            for b in &linear[i + 1..] {
                for &ta in &a.reversals_deg {
                    for &tb in &b.reversals_deg {
                        let d = angular_distance_deg(ta, tb);
                        if best.is_none_or(|(bd, _, _)| d < bd) {
                            best = Some((d, (a.axis, ta), (b.axis, tb)));
                        }
                    }
                }
            }
        }
        best
    }

    /// Warnings for reversals of different linear axes within [`COINCIDENCE_WARNING_DEG`].
    pub fn warnings(&self) -> Vec<String> {
        let linear: Vec<&AxisMotion> = self.axes.iter().filter(|a| !a.axis.is_rotary()).collect();
        let mut out = Vec::new();
        for (i, a) in linear.iter().enumerate() {
            for b in &linear[i + 1..] {
                for &ta in &a.reversals_deg {
                    for &tb in &b.reversals_deg {
                        let d = angular_distance_deg(ta, tb);
                        if d < COINCIDENCE_WARNING_DEG {
                            out.push(format!(
                                "{} reverses at {ta:.2} deg and {} at {tb:.2} deg, {d:.2} deg apart: a spike there cannot be attributed to one axis",
                                a.axis, b.axis
                            ));
                        }
                    }
                }
            }
        }
        out
    }
}

/// |a - b| on the circle, deg in [0, 180].
pub fn angular_distance_deg(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(360.0);
    d.min(360.0 - d)
}

/// Grid on which dq/dθ is bracketed: 0.5 deg, offset by half a step so that roots at
/// multiples of 0.5 deg (0 and 180 deg by symmetry) fall inside an interval.
const GRID_STEPS: usize = 720;

/// Analyses the exact cone path at tool-ball feed `feed_mm_min`.
pub fn analyse_cone(path: &ConePath, feed_mm_min: f64) -> Analysis {
    let grid = derivative_grid(path);
    let theta_rate = feed_mm_min / path.cone.radius_mm(); // rad/min
                                                          // C is tracked continuously over one revolution for its range.
    let (mut c_min, mut c_max) = (f64::INFINITY, f64::NEG_INFINITY);
    for (_, q) in path.sampled(0.0, TAU, GRID_STEPS) {
        c_min = c_min.min(q[Axis::C]);
        c_max = c_max.max(q[Axis::C]);
    }
    let start = path.start();
    let axes = path
        .kinematics
        .layout
        .axes()
        .iter()
        .map(|&axis| {
            let reversals = reversal_roots(path, &grid, axis);
            let (min, max) = if axis == Axis::C {
                (c_min, c_max)
            } else {
                // Extremes of a smooth periodic function lie at its reversals; without any it is constant.
                reversals
                    .iter()
                    .map(|&t| path.axes_near(t, 0.0)[axis])
                    .chain(std::iter::once(start[axis]))
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                        (lo.min(v), hi.max(v))
                    })
            };
            let peak_rate = peak_abs_derivative(path, &grid, axis);
            AxisMotion {
                axis,
                min,
                max,
                range: max - min,
                peak_speed_per_min: peak_rate * theta_rate, // (mm or deg)/rad · rad/min
                reversals_deg: sorted_deg(&reversals),
                reversal_lines: None,
                reversals_not_listed: None,
            }
        })
        .collect();
    Analysis { axes }
}

/// Each axis's reversal angles on the exact cone path, deg, sorted: those of
/// [`analyse_cone`], without the ranges and peak speeds (what a ball-bar run needs).
fn cone_reversals_deg(path: &ConePath) -> Vec<(Axis, Vec<f64>)> {
    let grid = derivative_grid(path);
    path.kinematics
        .layout
        .axes()
        .iter()
        .map(|&axis| (axis, sorted_deg(&reversal_roots(path, &grid, axis))))
        .collect()
}

/// dq/dθ at the middle of each of the `GRID_STEPS` steps of a revolution (and one past).
fn derivative_grid(path: &ConePath) -> Vec<(f64, AxisVec)> {
    let step = TAU / GRID_STEPS as f64;
    (0..=GRID_STEPS)
        .map(|k| {
            let theta = (k as f64 + 0.5) * step;
            (theta, path.derivative(theta))
        })
        .collect()
}

/// Angles in rad as deg in [0, 360), sorted.
fn sorted_deg(rad: &[f64]) -> Vec<f64> {
    let mut r: Vec<f64> = rad.iter().map(|t| normalize_deg(t.to_degrees())).collect();
    r.sort_by(f64::total_cmp);
    r
}

/// Roots of dq_axis/dθ with a sign change, rad.
fn reversal_roots(path: &ConePath, grid: &[(f64, AxisVec)], axis: Axis) -> Vec<f64> {
    let mut roots = Vec::new();
    for w in grid.windows(2) {
        let (t0, d0) = (w[0].0, w[0].1[axis]);
        let (t1, d1) = (w[1].0, w[1].1[axis]);
        if d0 == 0.0 || d0.signum() == d1.signum() {
            continue;
        }
        // A derivative that is zero to rounding everywhere (a constant axis) has no reversals.
        if d0.abs().max(d1.abs()) < 1e-9 {
            continue;
        }
        let (mut lo, mut hi, s_lo) = (t0, t1, d0.signum());
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            // lo and hi adjacent floats: mid is one of them, and neither moves any more (lo
            // keeps the sign s_lo, hi the other), so the remaining iterations change nothing.
            if mid == lo || mid == hi {
                break;
            }
            if path.derivative(mid)[axis].signum() == s_lo {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        roots.push(0.5 * (lo + hi));
    }
    roots
}

/// max |dq_axis/dθ|, refined by golden-section search around the best grid point.
fn peak_abs_derivative(path: &ConePath, grid: &[(f64, AxisVec)], axis: Axis) -> f64 {
    let step = TAU / GRID_STEPS as f64;
    let (best_theta, _) =
        grid.iter()
            .map(|(t, d)| (*t, d[axis].abs()))
            .fold(
                (0.0, f64::NEG_INFINITY),
                |acc, x| if x.1 > acc.1 { x } else { acc },
            );
    let f = |t: f64| path.derivative(t)[axis].abs();
    let (mut a, mut b) = (best_theta - step, best_theta + step);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut c, mut d) = (b - g * (b - a), a + g * (b - a));
    for _ in 0..60 {
        if f(c) > f(d) {
            b = d;
        } else {
            a = c;
        }
        c = b - g * (b - a);
        d = a + g * (b - a);
    }
    f(0.5 * (a + b)).max(grid.iter().map(|(_, d)| d[axis].abs()).fold(0.0, f64::max))
}

/// The reversal study of a scenario's program, run beside the pipeline: the exact path for
/// a generated cone, the closed form for a circle, the moves for any other program (a file,
/// read on its own).
pub fn analyse_scenario(scenario: &Scenario) -> Result<Analysis> {
    let test = test_of(scenario);
    let machine = &scenario.machine;
    if let Some((cone, nc)) = test.generated_cone() {
        let path = ConePath::new(*cone, machine);
        if is_smooth(&path) {
            return Ok(analyse_cone(&path, nc.feed_mm_min));
        }
    }
    if let Some(circle) = test.circle() {
        return Ok(analyse_circle(circle, machine.axes()));
    }
    analyse_moves(
        test.run(scenario, Direction::Ccw, 0.0)?.moves,
        machine,
        test.theta_frame(&machine.kinematics).as_ref(),
    )
}

/// Whether the reversal angles of `test` have a closed form here (a generated cone's exact
/// path, a circle's), or come from its moves.
pub fn has_closed_form(test: &dyn TestProgram) -> bool {
    test.generated_cone().is_some() || test.circle().is_some()
}

/// Each axis's reversal angles of a scenario's program, deg: those of [`analyse_scenario`],
/// for a generated cone without the ranges and peak speeds.
pub fn scenario_reversals_deg(scenario: &Scenario) -> Result<Vec<(Axis, Vec<f64>)>> {
    match test_of(scenario).generated_cone() {
        Some((cone, _)) if is_smooth(&ConePath::new(*cone, &scenario.machine)) => {
            Ok(cone_reversals_deg(&ConePath::new(*cone, &scenario.machine)))
        }
        _ => Ok(reversals_deg(analyse_scenario(scenario)?)),
    }
}

/// Largest move of a rotary between two points of the 0.5-deg grid on a smooth cone path,
/// deg: a 15-deg cone 5 deg from the pole turns C by about 1.5 deg there.
const SMOOTH_STEP_DEG: f64 = 5.0;

/// Whether the exact analysis of [`analyse_cone`] holds for `path`: every axis a smooth
/// function of θ (extremes at the roots of dq/dθ, speeds from it). Not so where the path
/// passes the pole (its rotaries interpolated across the pole's zone, or on the other
/// branch after it) or turns a rotary by more than [`SMOOTH_STEP_DEG`] between grid points
/// (the pole passed just outside its tolerance, a swing): then the written program is
/// analysed, block by block ([`analyse_moves`]).
pub fn is_smooth(path: &ConePath) -> bool {
    if path.passage.is_some() {
        return false;
    }
    let mut previous: Option<AxisVec> = None;
    path.sampled(0.0, TAU, GRID_STEPS).all(|(_, q)| {
        let smooth = previous.is_none_or(|p| {
            [Axis::A, Axis::B, Axis::C]
                .iter()
                .all(|&a| (q[a] - p[a]).abs() <= SMOOTH_STEP_DEG)
        });
        previous = Some(q);
        smooth && q.0.iter().all(|v| v.is_finite())
    })
}

/// Each axis's reversal angles of an analysis, deg.
pub fn reversals_deg(analysis: Analysis) -> Vec<(Axis, Vec<f64>)> {
    analysis
        .axes
        .into_iter()
        .map(|a| (a.axis, a.reversals_deg))
        .collect()
}

/// Analyses the moves of an NC program. `frame`, when given, supplies θ for the turning
/// points (the θ of the tool tip at the block's end on the measured circle).
pub fn analyse_moves(
    blocks: impl Iterator<Item = Result<Move>>,
    machine: &Machine,
    frame: Option<&CircleFrame>,
) -> Result<Analysis> {
    let mut analysis = MoveAnalysis::new(machine, frame.copied());
    for block in blocks {
        analysis.push(&block?)?;
    }
    Ok(analysis.finish())
}

/// [`analyse_moves`] one move at a time, so that it can ride along another pass over the
/// same moves (`simulate` of a file program reads the file once for both).
pub struct MoveAnalysis<'m> {
    machine: &'m Machine,
    frame: Option<CircleFrame>,
    acc: Vec<BlockAxisState>,
    /// The position before the program is unknown, so the first block's start is not part
    /// of the program: it counts for neither the ranges nor the speeds nor the reversals.
    first: bool,
}

impl<'m> MoveAnalysis<'m> {
    pub fn new(machine: &'m Machine, frame: Option<CircleFrame>) -> Self {
        MoveAnalysis {
            machine,
            frame,
            acc: machine
                .axes()
                .iter()
                .map(|_| BlockAxisState::default())
                .collect(),
            first: true,
        }
    }

    /// The next move of the program.
    pub fn push(&mut self, block: &Move) -> Result<()> {
        let machine = self.machine;
        if block.tcp {
            let kin = &machine.kinematics;
            let start = machine_coordinates(kin, block, block.start);
            let end = machine_coordinates(kin, block, block.end);
            return self.push_in_machine_axes(block, &start, &end);
        }
        // Out of TCP the block's axes are the machine's: no copy of them.
        self.push_in_machine_axes(block, &block.start, &block.end)
    }

    /// [`MoveAnalysis::push`] with the block's start and end in machine axes.
    fn push_in_machine_axes(&mut self, block: &Move, start: &AxisVec, end: &AxisVec) -> Result<()> {
        let (machine, frame, acc) = (self.machine, self.frame.as_ref(), &mut self.acc);
        let axes = machine.axes();
        let kin = &machine.kinematics;
        if std::mem::take(&mut self.first) {
            for (s, &axis) in acc.iter_mut().zip(axes) {
                s.extend(end[axis]);
            }
            return Ok(());
        }
        // Only feed moves carry an F that implies speeds; their time is the programmed one.
        let seconds = match block.motion {
            Motion::Linear | Motion::Arc { .. } => Some(block_duration_s(block, machine)?),
            _ => None,
        };
        // Arcs and G43.4 moves are not straight in machine axes: follow them at 1/32 steps,
        // so that an axis turning inside a block is found too.
        let steps = if matches!(block.motion, Motion::Arc { .. }) || block.tcp {
            32
        } else {
            1
        };
        let step_s = seconds.filter(|t| *t > 0.0).map(|t| t / steps as f64);
        let follow = |acc: &mut [BlockAxisState], previous: &AxisVec, q: &AxisVec| {
            for (s, &axis) in acc.iter_mut().zip(axes) {
                let x = q[axis];
                let d = x - previous[axis];
                s.extend(x);
                if let Some(t) = step_s {
                    s.peak_speed = s.peak_speed.max(d.abs() / t * 60.0);
                }
                // The turning point's position is kept only to give its θ.
                if let Some(turn) = s.push_increment(d, x, block.line, frame.map(|_| q)) {
                    let theta = frame.map(|f| f.theta_deg(&kin.forward(&turn.1).tip));
                    if s.turns.len() < MAX_LISTED_REVERSALS {
                        s.turns.push((turn.0, theta));
                    } else {
                        s.not_listed += 1;
                    }
                }
            }
        };
        if steps == 1 {
            // A straight block, one step from its start: no copy of either end (most blocks).
            follow(acc, start, end);
            return Ok(());
        }
        let mut previous = *start;
        for k in 1..=steps {
            let inside;
            let q = if k == steps {
                end
            } else {
                inside = position_in_block(block, machine, k as f64 / steps as f64);
                &inside
            };
            follow(acc, &previous, q);
            previous = *q;
        }
        Ok(())
    }

    /// The analysis of the moves pushed so far.
    pub fn finish(self) -> Analysis {
        let axes = self.machine.axes();
        let axes = axes
            .iter()
            .zip(self.acc)
            .map(|(&axis, s)| {
                let mut reversals_deg: Vec<f64> = s.turns.iter().filter_map(|(_, t)| *t).collect();
                reversals_deg.sort_by(f64::total_cmp);
                AxisMotion {
                    axis,
                    min: s.min,
                    max: s.max,
                    range: s.max - s.min,
                    peak_speed_per_min: s.peak_speed,
                    reversals_deg,
                    reversal_lines: Some(s.turns.iter().map(|(l, _)| *l).collect()),
                    reversals_not_listed: (s.not_listed > 0).then_some(s.not_listed),
                }
            })
            .collect();
        Analysis { axes }
    }
}

/// A turn counts once the axis has come back this far from its extreme, mm or deg: smaller
/// wiggles (a G43.4 block near a reversal, the NC program's 0.1 um rounding) are not
/// reversals. With no deadband this is the block rule: block k's end is a turning point when
/// the increments of block k and of the next block that moves the axis have opposite signs.
pub const REVERSAL_DEADBAND: f64 = 1e-3;

/// Running state of one axis over the blocks.
#[derive(Debug)]
struct BlockAxisState {
    min: f64,
    max: f64,
    peak_speed: f64,
    /// Direction of travel (+1 or -1) and the extreme reached in it: value, line, position.
    travel: Option<(f64, f64, usize, AxisVec)>,
    turns: Vec<(usize, Option<f64>)>,
    /// Turns past [`MAX_LISTED_REVERSALS`].
    not_listed: u64,
}

impl Default for BlockAxisState {
    fn default() -> Self {
        BlockAxisState {
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
            peak_speed: 0.0,
            travel: None,
            turns: Vec::new(),
            not_listed: 0,
        }
    }
}

impl BlockAxisState {
    fn extend(&mut self, v: f64) {
        self.min = self.min.min(v);
        self.max = self.max.max(v);
    }

    /// Records a move of `d` to `x` (at `q`, in a block of `line`); returns the line and
    /// position of a turning point once the axis has come back past the deadband.
    /// `q` is kept with the extreme when given (for the turn's θ); the origin otherwise.
    fn push_increment(
        &mut self,
        d: f64,
        x: f64,
        line: usize,
        q: Option<&AxisVec>,
    ) -> Option<(usize, AxisVec)> {
        if d == 0.0 {
            return None;
        }
        // By reference: the position is copied only where it changes (most blocks).
        let Some((direction, extreme, ext_line, ext_q)) = &mut self.travel else {
            self.travel = Some((d.signum(), x, line, q.copied().unwrap_or(AxisVec::ZERO)));
            return None;
        };
        if (x - *extreme) * *direction > 0.0 {
            (*extreme, *ext_line) = (x, line);
            if let Some(q) = q {
                *ext_q = *q;
            }
            None
        } else if (*extreme - x).abs() > REVERSAL_DEADBAND {
            let turn = (*ext_line, *ext_q);
            (*direction, *extreme, *ext_line) = (-*direction, x, line);
            if let Some(q) = q {
                *ext_q = *q;
            }
            Some(turn)
        } else {
            None
        }
    }
}

/// In TCP mode a block's X Y Z are the tool tip in the table frame; machine axes follow by kinematics.
fn machine_coordinates(kin: &crate::kinematics::Kinematics, block: &Move, q: AxisVec) -> AxisVec {
    if !block.tcp {
        return q;
    }
    if !kin.has_closed_form() {
        return kin.tcp_axes(&q, block.tool_length_mm);
    }
    let tip = nalgebra::Point3::new(q[Axis::X], q[Axis::Y], q[Axis::Z]);
    let m = kin.table_to_machine(&q, &tip);
    let mut out = q;
    out[Axis::X] = m.x;
    out[Axis::Y] = m.y;
    out[Axis::Z] = m.z;
    out
}

/// The exact analysis of a planar circle of radius r at feed F: the plane's first axis u
/// (at r cos θ) reverses at 0 and 180 deg, the second v (at r sin θ) at 90 and 270 deg; both
/// span the centre ± r and peak at F. Other axes stand still.
pub fn analyse_circle(circle: &CircleTest, axes: &[Axis]) -> Analysis {
    let (u, v, _) = circle.plane.axes();
    let axes = axes
        .iter()
        .map(|&axis| {
            let c = circle.center_mm.get(axis.index()).copied().unwrap_or(0.0);
            let (reversals_deg, r, speed) = if axis == u {
                (vec![0.0, 180.0], circle.radius_mm, circle.feed_mm_min)
            } else if axis == v {
                (vec![90.0, 270.0], circle.radius_mm, circle.feed_mm_min)
            } else {
                (Vec::new(), 0.0, 0.0)
            };
            AxisMotion {
                axis,
                min: c - r,
                max: c + r,
                range: 2.0 * r,
                peak_speed_per_min: speed,
                reversals_deg,
                reversal_lines: None,
                reversals_not_listed: None,
            }
        })
        .collect();
    Analysis { axes }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cones_reversal_angles_alone_are_those_of_its_analysis() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        for name in ["cone-15-10", "cone-45-30", "cone-15-10-offset"] {
            let scenario = Scenario::load(&root.join(format!("scenarios/{name}.toml"))).unwrap();
            let full = reversals_deg(analyse_scenario(&scenario).unwrap());
            let alone = scenario_reversals_deg(&scenario).unwrap();
            assert!(
                full.iter().any(|(_, r)| !r.is_empty()),
                "{name} has reversals"
            );
            let bits = |r: &[(Axis, Vec<f64>)]| -> Vec<(Axis, Vec<u64>)> {
                r.iter()
                    .map(|(a, d)| (*a, d.iter().map(|v| v.to_bits()).collect()))
                    .collect()
            };
            assert_eq!(bits(&full), bits(&alone), "{name}");
        }
    }
}
