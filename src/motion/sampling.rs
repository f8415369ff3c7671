//! Sampling a program at its programmed timing, for the limits and collision checks.
//!
//! Each block takes the time its words ask for: `sqrt(Σ d²)/F` in G94 (deg counted as mm,
//! the controller without tool-centre-point control), the tool-tip chord over F in G43.4,
//! `1/F` in G93, `max |d|/v_max` for G00, the arc length over F for G02/G03, P or X for G04.
//! No feed planning: what the program demands is what is checked. Samples fall every
//! `period_s` on one global clock, so the stream is uniform across block boundaries.
//! Memory is O(1): one block at a time.

use crate::error::{Error, Result};
use crate::input::machine::Machine;
use crate::program::{Feed, Motion, Move};
use crate::{Axis, AxisVec};

use crate::motion::interpolation::Setpoint;

/// Programmed duration of a block, s.
pub fn block_duration_s(block: &Move, machine: &Machine) -> Result<f64> {
    let bad_feed = || {
        Error::invalid(
            &machine.path,
            format!(
                "line {}: the block has no usable F word (need F > 0)",
                block.line
            ),
        )
    };
    let minutes = match block.motion {
        Motion::Dwell { seconds } => return Ok(seconds.max(0.0)),
        Motion::Rapid => {
            let d = block.end - block.start;
            return Ok(machine
                .axes()
                .iter()
                .map(|&a| d[a].abs() / (machine.axis(a).max_velocity / 60.0))
                .fold(0.0, f64::max));
        }
        Motion::Linear | Motion::Arc { .. } => match block.feed {
            Feed::InverseTime(f) if f.is_finite() && f > 0.0 => 1.0 / f,
            Feed::PerMinute(f) if f.is_finite() && f > 0.0 => feed_length(block) / f,
            _ => return Err(bad_feed()),
        },
    };
    Ok(minutes * 60.0)
}

/// The length a G94 F word is divided by, mm (deg counted as mm).
fn feed_length(block: &Move) -> f64 {
    match block.motion {
        Motion::Arc {
            plane, center_mm, ..
        } => {
            let (u, v, w) = plane.axes();
            let r = (block.start[u] - center_mm[u.index()])
                .hypot(block.start[v] - center_mm[v.index()]);
            let sweep = block.arc_sweep_rad().unwrap_or(0.0).abs();
            (r * sweep).hypot(block.end[w] - block.start[w])
        }
        _ if block.tcp => {
            let d = block.end - block.start;
            let tip = (d[Axis::X].powi(2) + d[Axis::Y].powi(2) + d[Axis::Z].powi(2)).sqrt();
            // A pure rotary move under TCP falls back to the mixed-unit rule.
            if tip > 0.0 {
                tip
            } else {
                d.mixed_norm()
            }
        }
        _ => (block.end - block.start).mixed_norm(),
    }
}

/// Commanded machine axis positions at fraction `f` in [0, 1] of `block`.
#[inline]
pub fn position_in_block(block: &Move, machine: &Machine, f: f64) -> AxisVec {
    let q = block.start + (block.end - block.start) * f;
    // The straight line in machine axes stays inline (it runs on every sample of most
    // programs); an arc or a TCP move takes its own function.
    match block.motion {
        Motion::Arc { .. } => on_arc(block, q, f),
        _ if block.tcp => under_tcp(block, machine, q),
        _ => q,
    }
}

/// [`position_in_block`] into `q`, the straight line in machine axes lane by lane (the
/// same arithmetic as `start + (end - start) * f`).
#[inline(always)]
fn position_in_block_into(block: &Move, machine: &Machine, f: f64, q: &mut AxisVec) {
    match block.motion {
        Motion::Arc { .. } => *q = position_in_block(block, machine, f),
        _ if block.tcp => *q = position_in_block(block, machine, f),
        _ => {
            let (a, b) = (&block.start.0, &block.end.0);
            for i in 0..a.len() {
                q.0[i] = a[i] + (b[i] - a[i]) * f;
            }
        }
    }
}

/// [`position_in_block`] on an arc: `q` the straight-line interpolation, whose arc-plane
/// coordinates are replaced by the point on the arc.
#[inline(never)]
fn on_arc(block: &Move, mut q: AxisVec, f: f64) -> AxisVec {
    let Motion::Arc {
        plane, center_mm, ..
    } = block.motion
    else {
        return q;
    };
    let (u, v, _) = plane.axes();
    let (cu, cv) = (center_mm[u.index()], center_mm[v.index()]);
    let r = (block.start[u] - cu).hypot(block.start[v] - cv);
    let a0 = (block.start[v] - cv).atan2(block.start[u] - cu);
    // The reader's signed sweep: negative for G02, ±2π for a full circle.
    let a = a0 + block.arc_sweep_rad().unwrap_or(0.0) * f;
    q[u] = cu + r * a.cos();
    q[v] = cv + r * a.sin();
    q
}

/// [`position_in_block`] under TCP: X Y Z of `q` are the tool tip in the table frame,
/// moving on the straight line; they become the machine's.
#[inline(never)]
fn under_tcp(block: &Move, machine: &Machine, q: AxisVec) -> AxisVec {
    machine.kinematics.tcp_axes(&q, block.tool_length_mm)
}

/// Streams [`Setpoint`]s every `period_s` through a block stream at programmed timing; the
/// last sample is the program's end point at its end time.
pub struct NominalSampler<'m, I> {
    blocks: I,
    machine: &'m Machine,
    period_s: f64,
    /// The block being sampled, its start time and duration, s.
    current: Option<(Move, f64, f64)>,
    block_index: u64,
    /// Index of the next sample on the clock.
    k: u64,
    done: bool,
}

impl<'m, I: Iterator<Item = Result<Move>>> NominalSampler<'m, I> {
    pub fn new(blocks: I, machine: &'m Machine, period_s: f64) -> Self {
        NominalSampler {
            blocks,
            machine,
            period_s,
            current: None,
            block_index: 0,
            k: 0,
            done: false,
        }
    }

    #[inline]
    fn sample(&self, block: &Move, time_s: f64, f: f64) -> Setpoint {
        Setpoint {
            time_s,
            line: block.line,
            block_index: self.block_index - 1,
            q: position_in_block(block, self.machine, f),
        }
    }
}

impl<I: Iterator<Item = Result<Move>>> Iterator for NominalSampler<'_, I> {
    type Item = Result<Setpoint>;

    fn next(&mut self) -> Option<Result<Setpoint>> {
        let mut q = AxisVec::ZERO;
        match self.next_into(&mut q) {
            Ok(Some(at)) => Some(Ok(Setpoint {
                time_s: at.time_s,
                q,
                line: at.line,
                block_index: at.block_index,
            })),
            Ok(None) => None,
            Err(e) => Some(Err(e)),
        }
    }
}

impl<I: Iterator<Item = Result<Move>>> NominalSampler<'_, I> {
    /// [`Iterator::next`] with the positions written into `q` (mm, deg): the sample's time
    /// and place, or `None` at the end. The sample within the current block is inline, where
    /// the caller keeps its positions (and compiled as the caller is: see
    /// `pipeline::run_programmed`), and is written straight into them (a setpoint returned
    /// in an `Option<Result<_>>` is copied through the stack); the block change is out of
    /// line.
    #[inline(always)]
    pub fn next_into(&mut self, q: &mut AxisVec) -> Result<Option<SampleAt>> {
        if let (false, Some((block, start_s, duration_s))) = (self.done, &self.current) {
            let t = self.k as f64 * self.period_s;
            if let Some(f) = fraction_of_block(t, *start_s, *duration_s) {
                self.k += 1;
                position_in_block_into(block, self.machine, f, q);
                return Ok(Some(SampleAt {
                    time_s: t,
                    line: block.line,
                    block_index: self.block_index - 1,
                }));
            }
        }
        match self.next_after_block() {
            Some(Ok(s)) => {
                *q = s.q;
                Ok(Some(SampleAt {
                    time_s: s.time_s,
                    line: s.line,
                    block_index: s.block_index,
                }))
            }
            Some(Err(e)) => Err(e),
            None => Ok(None),
        }
    }
}

/// The fraction `f = (t - t₀) / T` in `[0, 1]` of the block that starts at `t₀ =
/// start_s` and lasts `T = duration_s` reached at time `t` (s), or `None` once `t` is past
/// its end (a block of no duration is all at its end, `f = 1`).
#[inline(always)]
fn fraction_of_block(t: f64, start_s: f64, duration_s: f64) -> Option<f64> {
    if !(t <= start_s + duration_s) {
        return None;
    }
    let f = if duration_s > 0.0 {
        (t - start_s) / duration_s
    } else {
        1.0
    };
    Some(f.clamp(0.0, 1.0))
}

/// When and where a sample of [`NominalSampler::next_into`] is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleAt {
    /// s from the program's start.
    pub time_s: f64,
    /// Source line and 0-based index of the block.
    pub line: usize,
    pub block_index: u64,
}

impl<I: Iterator<Item = Result<Move>>> NominalSampler<'_, I> {
    /// [`Iterator::next`] where the current block has ended (or none has begun): the next
    /// block's first sample, or the program's end point.
    #[inline(never)]
    fn next_after_block(&mut self) -> Option<Result<Setpoint>> {
        if self.done {
            return None;
        }
        let t = self.k as f64 * self.period_s;
        loop {
            if let Some((block, start_s, duration_s)) = &self.current {
                if let Some(f) = fraction_of_block(t, *start_s, *duration_s) {
                    self.k += 1;
                    return Some(Ok(self.sample(block, t, f)));
                }
            }
            let start_s = self.current.as_ref().map_or(0.0, |(_, s, d)| s + d);
            match self.blocks.next() {
                Some(Ok(block)) => match block_duration_s(&block, self.machine) {
                    Ok(d) => {
                        self.current = Some((block, start_s, d));
                        self.block_index += 1;
                    }
                    Err(e) => {
                        self.done = true;
                        return Some(Err(e));
                    }
                },
                Some(Err(e)) => {
                    self.done = true;
                    return Some(Err(e));
                }
                None => {
                    self.done = true;
                    let (block, s, d) = self.current.as_ref()?;
                    let last_sampled = (self.k as f64 - 1.0) * self.period_s;
                    return (self.k == 0 || last_sampled < s + d)
                        .then(|| Ok(self.sample(block, s + d, 1.0)));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(n: usize, start: [f64; 3], end: [f64; 3], feed_mm_per_min: f64) -> Move {
        let v = |p: [f64; 3]| AxisVec::xyzabc([p[0], p[1], p[2], 0.0, 0.0, 0.0]);
        Move {
            line: n,
            motion: Motion::Linear,
            start: v(start),
            end: v(end),
            feed: Feed::PerMinute(feed_mm_per_min),
            ..Move::default()
        }
    }

    /// Two G1 blocks at their programmed feed, sampled on one global grid `t = k p`: 10 mm
    /// along X at F700 (T₁ = 6/7 s) then 5 mm along Y at F300 (T₂ = 1 s). Each sample is
    /// at `start + (end - start) (t - t₀) / T` of the block holding `t`, with a last sample
    /// at the end point `T₁ + T₂`, which is off the grid. `next` and `next_into` agree.
    #[test]
    fn samples_lie_on_the_global_grid_along_each_block_and_end_at_the_end_point() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/vmc-3axis.toml");
        let machine = Machine::load(&path).unwrap();
        let p = machine.interpolation_period_s;
        assert_eq!(p, 1e-3);
        let blocks = [
            line(7, [0.0; 3], [10.0, 0.0, 0.0], 700.0),
            line(8, [10.0, 0.0, 0.0], [10.0, 5.0, 0.0], 300.0),
        ];
        let (t1, t2) = (6.0 / 7.0, 1.0);
        let expected = |t: f64| -> (usize, u64, [f64; 2]) {
            if t <= t1 {
                (7, 0, [10.0 * t / t1, 0.0])
            } else {
                (8, 1, [10.0, 5.0 * (t - t1) / t2])
            }
        };
        let setpoints: Vec<Setpoint> =
            NominalSampler::new(blocks.clone().into_iter().map(Ok), &machine, p)
                .map(|s| s.unwrap())
                .collect();
        // 0, p, ..., 1857 p on the grid (1.857 s <= T₁ + T₂ = 1.857142... s), then the end.
        assert_eq!(setpoints.len(), 1858 + 1);
        for (k, s) in setpoints.iter().enumerate() {
            let t = if k < 1858 { k as f64 * p } else { t1 + t2 };
            let (line, block, [x, y]) = expected(t);
            assert!(
                (s.time_s - t).abs() < 1e-12,
                "sample {k}: t = {} s, expected {t} s",
                s.time_s
            );
            assert_eq!(
                (s.line, s.block_index),
                (line, block),
                "sample {k} at {t} s"
            );
            assert!(
                (s.q[Axis::X] - x).abs() < 1e-9 && (s.q[Axis::Y] - y).abs() < 1e-9,
                "sample {k} at {t} s: ({}, {}), expected ({x}, {y})",
                s.q[Axis::X],
                s.q[Axis::Y]
            );
        }
        let mut sampler = NominalSampler::new(blocks.into_iter().map(Ok), &machine, p);
        let mut q = AxisVec::ZERO;
        for s in &setpoints {
            let at = sampler
                .next_into(&mut q)
                .unwrap()
                .expect("as many samples as next");
            assert_eq!(
                (at.time_s, at.line, at.block_index, q),
                (s.time_s, s.line, s.block_index, s.q)
            );
        }
        assert_eq!(sampler.next_into(&mut q).unwrap(), None);
    }
}
