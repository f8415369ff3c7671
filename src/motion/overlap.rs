//! Overlapped moves: LinuxCNC 2.9's rule at a corner between two straight moves when either
//! moves an axis besides X Y Z (a rotary axis), under G64, on a machine planned by LinuxCNC's
//! rules (`[control] max_feed_override` given). Such a corner gets no blend arc ([`blend`]):
//! the second move starts while the first still runs, and the two moves' axis velocities add
//! (parabolic-style blending).
//!
//! # The rule
//!
//! Each move is planned on its own, from rest to rest, and the second starts (`t_ov`, s into
//! the first) at the later of
//!
//! - where the first starts slowing down (the start of its last speed change), and
//! - where the first has `D = 2P / sin(θ/2)` of X Y Z travel left,
//!
//! with `P` the G64 tolerance (the machine's `[control] path_tolerance_mm` when the program
//! gives none; no bound from it when neither does) and `θ` the turn between the two moves'
//! X Y Z directions (no bound when either has no X Y Z travel or they do not turn). A move
//! that starts or ends in an overlap, like a program's last move, runs at half the
//! acceleration (and jerk) limits, so that the two moves' accelerations added stay within each
//! axis's limit. While both run the command is
//!
//! ```text
//! q(t) = q2(t − t_ov) + (q1(t) − q1(1))       (q1(1): the first move's end point)
//! ```
//!
//! Where the velocities added would pass an axis's velocity limit
//! (`|q1'_i v1(t) + q2'_i v2(t − t_ov)| > vmax_i` for some `t` of the overlap: a second move
//! that speeds an axis up faster than the first slows it down), mtsim starts the second move
//! later, at the earliest `t_ov` where they do not (LinuxCNC does not: on
//! `G1 X30 C60 F1200` then `G1 X60 C65` it reaches 25 mm/s on an X limited to 20). At most
//! two moves run at once: the overlap starts no earlier than the end of the one before, and
//! lasts no longer than the second move.
//!
//! # Where it comes from
//!
//! Measured on LinuxCNC 2.9 (black box, `tests/motion/linuxcnc_planner.rs`: its commanded
//! joints every 1 ms, each period's velocity split on the two moves' directions): on
//! `G64 P0.05` XC moves the second starts with 0.274, 0.130 and 0.148 mm of X Y Z left on the
//! first (`2P/sin(θ/2)` = 0.261, 0.123, 0.141 at 45°, 108° and 90°, one period's travel
//! below), after each has started slowing down; under G64 without P, and at P1, exactly where
//! the first starts slowing down; every move at half the acceleration limit of its slowest
//! axis (150 of 300 mm/s² and deg/s²), rapids too.

use super::{Active, Interpolator, Planned};
use crate::error::Result;
use crate::motion::profile::{reach, Profile};
use crate::program::{Move, PathControl};
use crate::AxisVec;

/// The X Y Z travel (mm) left on the first of two overlapping moves when the second may start
/// by the tolerance: `2P / sin(θ/2)`, with `θ` the turn between the moves' X Y Z directions
/// `first` and `second` (any length). Infinite (no bound) without a tolerance, when either
/// direction has no X Y Z part or when they do not turn.
pub fn tolerance_travel(first: [f64; 3], second: [f64; 3], tolerance_mm: Option<f64>) -> f64 {
    let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let (n1, n2) = (norm(first), norm(second));
    let Some(p) = tolerance_mm.filter(|p| p.is_finite() && *p >= 0.0) else {
        return f64::INFINITY;
    };
    if !(n1 > 1e-12 && n2 > 1e-12) {
        return f64::INFINITY;
    }
    // |u1 − u2| = 2 sin(θ/2) for unit vectors: no cancellation in an arccos.
    let chord = norm(std::array::from_fn(|i| first[i] / n1 - second[i] / n2));
    let half_sin = 0.5 * chord;
    if !(half_sin > 1e-12) {
        return f64::INFINITY;
    }
    2.0 * p / half_sin
}

/// X Y Z part of an axis vector.
fn xyz(v: AxisVec) -> [f64; 3] {
    [v.0[0], v.0[1], v.0[2]]
}

impl<I: Iterator<Item = Result<Move>>> Interpolator<I> {
    /// Whether the corner between `prev` and `next` is overlapped (see the module's doc): if
    /// so, the path length (of `prev`) left on it when `next` may start by the tolerance.
    pub(super) fn overlap_travel(&self, prev: &Planned, next: &Planned) -> Option<f64> {
        let PathControl::Blend { tolerance_mm, .. } = prev.path_control else {
            return None;
        };
        let straight = |p: &Planned| p.length > 0.0 && p.path.is_straight() && !p.path.tcp;
        let rotary = |p: &Planned| (3..9).any(|i| p.path.delta.0[i] != 0.0);
        let rapid = |p: &Planned| p.programmed == f64::INFINITY;
        if self.control.max_feed_override.is_none()
            || !(straight(prev) && straight(next))
            || !(rotary(prev) || rotary(next))
            || rapid(prev) != rapid(next)
        {
            return None;
        }
        let tolerance = tolerance_mm.or(self.control.path_tolerance_mm);
        let (d1, d2) = (xyz(prev.path.delta), xyz(next.path.delta));
        let travel = tolerance_travel(d1, d2, tolerance);
        let along = (d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2]).sqrt();
        // Path length per X Y Z length on `prev` (none: no X Y Z travel, no bound).
        Some(if along > 1e-12 {
            travel * prev.length / along
        } else {
            f64::INFINITY
        })
    }

    /// Halves a block's acceleration and jerk limits for an overlap (once): half of what the
    /// axes allow (a rapid's share of them, `[control] rapid_acceleration_share`, set aside).
    pub(super) fn halve_for_overlap(&self, p: &mut Planned) {
        if p.halved {
            return;
        }
        let share = if p.programmed == f64::INFINITY {
            self.control.rapid_acceleration_share
        } else {
            1.0
        };
        p.accel = (0.5 * p.accel / share).min(p.accel);
        p.jerk *= 0.5;
        p.halved = true;
    }

    /// For the active block (the window's front) when the next one overlaps it: when the
    /// next starts (`handover`, s into the active block) and the next's profile (from rest,
    /// queued for its activation).
    pub(super) fn plan_handover(&mut self) {
        let (Some(active), Some(next)) = (self.active.as_ref(), self.window.get(1)) else {
            return;
        };
        let Some(travel) = next.overlap else {
            return;
        };
        let exit_max = self
            .window
            .get(2)
            .map_or(0.0, |n| n.entry_limit() / n.rho)
            .min(next.cap);
        let exit = reach(0.0, next.length, exit_max, next.accel, next.jerk);
        let profile = Profile::new(0.0, exit, next.cap, next.length, next.accel, next.jerk);
        let first = &active.profile;
        let by_tolerance = if travel < active.planned.length {
            first.time_at(active.planned.length - travel)
        } else {
            0.0
        };
        let mut earliest = (first.duration - profile.duration).max(0.0);
        if let Some(t) = &self.trailing {
            earliest = earliest.max(t.t0 + t.profile.duration - active.t0);
        }
        let start = first.down_start().max(by_tolerance).max(earliest);
        let u1 = active.planned.path.delta * (1.0 / active.planned.length);
        let u2 = next.path.delta * (1.0 / next.length);
        let fits = |t_ov: f64| self.velocities_fit(first, u1, &profile, u2, t_ov);
        let handover = if start >= first.duration || fits(start) {
            start.min(first.duration)
        } else {
            // The earliest start that fits: `fits` holds at the first move's end (no overlap).
            let early = crate::motion::profile::bisect(0.0, first.duration - start, |early| {
                fits(first.duration - early)
            });
            first.duration - early
        };
        let queued = (profile, exit);
        if let Some(a) = self.active.as_mut() {
            a.handover = handover;
        }
        self.queued = Some(queued);
    }

    /// Whether, with the second move (`second`, along `u2`) starting `t_ov` s into the first
    /// (`first`, along `u1`), every axis's two velocities added stay within its limit over the
    /// overlap: checked at both profiles' phase ends and 64 steps between.
    fn velocities_fit(
        &self,
        first: &Profile,
        u1: AxisVec,
        second: &Profile,
        u2: AxisVec,
        t_ov: f64,
    ) -> bool {
        let end = first.duration.min(t_ov + second.duration);
        if !(end > t_ov) {
            return true;
        }
        let phases = |p: &Profile| {
            [
                p.up.t1,
                p.up.t1 + p.up.t2,
                p.up.duration,
                p.down_start(),
                p.down_start() + p.down.t1,
                p.down_start() + p.down.t1 + p.down.t2,
            ]
        };
        let ends = phases(first)
            .into_iter()
            .chain(phases(second).into_iter().map(|t| t + t_ov));
        let steps = (0..=64).map(|k| t_ov + (end - t_ov) * k as f64 / 64.0);
        steps
            .chain(ends.filter(|t| (t_ov..=end).contains(t)))
            .all(|t| {
                let (v1, v2) = (first.speed(t), second.speed(t - t_ov));
                self.limits.iter().enumerate().all(|(i, l)| {
                    l.map_or(true, |l| {
                        (u1.0[i] * v1 + u2.0[i] * v2).abs() <= l.velocity * (1.0 + 1e-9)
                    })
                })
            })
    }
}

impl Active {
    /// What is left of this block at `t` (s) when it runs on beside the next (an overlap):
    /// `q(u(t)) − q(1)`, zero once it has ended.
    #[inline(always)]
    pub(super) fn left_at(&self, t: f64, kinematics: &crate::kinematics::Kinematics) -> AxisVec {
        if !(t < self.t0 + self.profile.duration) {
            return AxisVec::ZERO;
        }
        let p = &self.planned;
        let u = (self.profile.position(t - self.t0) / p.length).clamp(0.0, 1.0);
        p.path.at(u, kinematics) - p.path.at(1.0, kinematics)
    }
}
