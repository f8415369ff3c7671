//! A cone path through the pole, as a control takes it (the kinematic-chains spec, "Poles,
//! as controls handle them").
//!
//! The tool direction of the cone turns on a circle of directions; where that circle passes
//! within `pole_tolerance_deg` (δ_tol) of the chain's pole ([`Pole`]), the path is in the
//! pole's zone, θ ∈ [θ_in, θ_out] (each revolution), the angle δ(θ) from the pole below δ_tol.
//!
//! - **Through the pole on the other branch.** Each IK branch has the outer rotary on one
//!   side of zero; a tool direction that crosses the pole on one branch would make the inner
//!   rotary swing 180° (its azimuth turns over), while the other branch continues with the
//!   inner rotary where it is and the outer rotary through zero. So at θ_out the path goes
//!   on the other branch (`flip`), when the travel limits allow it.
//! - **Inside the zone** the rotaries move linearly in θ from their values at θ_in (on the
//!   branch before) to those at θ_out (on the branch after):
//!   `q_r(θ) = q_r(θ_in) + s (q_r(θ_out) − q_r(θ_in))`, `s = (θ − θ_in)/(θ_out − θ_in)`; the
//!   linear axes place the tool tip exactly on the path ([`Kinematics::with_tip_at`]). On
//!   the other branch the inner rotary's two end values differ only by the curvature of the
//!   path of directions (it holds), and the tool direction deviates from the cone's by at
//!   most about δ_tol (both are within δ_tol of the pole).
//! - Without the other branch (`flip` false) the inner rotary swings about 180° inside the
//!   zone: [`PolePassage::swing_deg`], which the cone generator refuses to write (a swing
//!   of a joint-space program between two block ends is a straight line of the linear axes).
//!
//! The cone's circle of directions passes one point (the pole) at most once a revolution, so
//! one zone per revolution: the one about the smallest δ.

use std::f64::consts::TAU;

use crate::input::program::ConePoses;
use crate::kinematics::{Branch, Kinematics, Pole};
use crate::AxisVec;

/// Grid on which the smallest angle from the pole is looked for, steps per revolution
/// (0.1 deg of θ; a zone of δ_tol = 0.1 deg spans about 0.4 deg of θ on a 15-deg cone).
const GRID: usize = 3600;

/// Where a cone path passes the pole, θ in rad.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PolePassage {
    /// The pole passed.
    pub pole: Pole,
    /// Entry into the zone, rad in [0, 2π).
    pub theta_in: f64,
    /// Exit from it, rad (> `theta_in`, less than a turn later).
    pub theta_out: f64,
    /// θ of the smallest angle from the pole, rad.
    pub theta_pole: f64,
    /// The smallest angle from the pole, deg.
    pub angle_deg: f64,
    /// Whether the path goes on the other branch after the zone.
    pub flip: bool,
}

impl PolePassage {
    /// The zone of the cone `poses` about the pole of `kinematics` (within its
    /// `pole_tolerance_deg`); `None` when the path keeps farther (or the chain has no pole).
    pub fn find(poses: &ConePoses, kinematics: &Kinematics) -> Option<PolePassage> {
        let pole = kinematics.pole()?;
        let tol = kinematics.pole_tolerance_deg;
        let delta = |theta: f64| pole.angle_deg(&poses.pose(theta).axis);
        let step = TAU / GRID as f64;
        let (k_min, d_min) = (0..GRID)
            .map(|k| (k, delta(k as f64 * step)))
            .fold((0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
        // The grid's step moves the direction by far less than a degree: a zone below δ_tol
        // has a grid point within a step of its bottom.
        if d_min > tol + 1.0 {
            return None;
        }
        let theta_pole = golden_min(
            &delta,
            (k_min as f64 - 1.0) * step,
            (k_min as f64 + 1.0) * step,
        );
        let angle_deg = delta(theta_pole);
        if angle_deg >= tol {
            return None;
        }
        let edge = |dir: f64| {
            // Step out until δ ≥ δ_tol, then bisect to the crossing.
            let mut far = theta_pole;
            while delta(far) < tol {
                far += dir * step;
            }
            let (mut inside, mut outside) = (theta_pole, far);
            for _ in 0..60 {
                let mid = 0.5 * (inside + outside);
                if delta(mid) < tol {
                    inside = mid;
                } else {
                    outside = mid;
                }
            }
            outside
        };
        let (lo, hi) = (edge(-1.0), edge(1.0));
        let shift = lo.div_euclid(TAU) * TAU;
        Some(PolePassage {
            pole,
            theta_in: lo - shift,
            theta_out: hi - shift,
            theta_pole: theta_pole - shift,
            angle_deg,
            flip: true,
        })
    }

    /// The branch at θ of a path that starts (θ = 0) on `start`: flipped once per exit from
    /// the zone passed since θ = 0 (counted backward for θ < 0), when `flip`.
    pub fn branch_at(&self, theta_rad: f64, start: Branch) -> Branch {
        if !self.flip {
            return start;
        }
        let exits = |t: f64| ((t - self.theta_out) / TAU).floor() as i64;
        if (exits(theta_rad) - exits(0.0)).rem_euclid(2) == 0 {
            start
        } else {
            other(start)
        }
    }

    /// The zone θ lies in, as its (θ_in, θ_out) of that revolution; `None` outside.
    pub fn zone_of(&self, theta_rad: f64) -> Option<(f64, f64)> {
        let k = ((theta_rad - self.theta_in) / TAU).floor();
        let (a, b) = (self.theta_in + k * TAU, self.theta_out + k * TAU);
        (theta_rad >= a && theta_rad < b).then_some((a, b))
    }

    /// Axis positions at θ inside the zone (θ_in, θ_out): the rotaries interpolated between
    /// their values at the zone's ends (`at(θ, branch, previous)` gives a pose on a branch),
    /// the tip placed on the path at θ by the linear axes.
    pub fn axes_in_zone(
        &self,
        kinematics: &Kinematics,
        poses: &ConePoses,
        (theta_in, theta_out): (f64, f64),
        theta_rad: f64,
        at: &dyn Fn(f64, Branch, &AxisVec) -> AxisVec,
        start: Branch,
        previous: &AxisVec,
    ) -> AxisVec {
        let before = self.branch_at(theta_in, start);
        let after = self.branch_at(theta_out, start);
        let q_in = at(theta_in, before, previous);
        let q_out = at(theta_out, after, &q_in);
        let s = (theta_rad - theta_in) / (theta_out - theta_in);
        let mut q = q_in;
        for axis in [self.pole.inner, self.pole.outer] {
            q[axis] = q_in[axis] + s * (q_out[axis] - q_in[axis]);
        }
        kinematics.with_tip_at(&poses.pose(theta_rad).tip, &q)
    }

    /// The inner rotary's move across the zone, deg: about 0 on the other branch, about
    /// 180 on the same one.
    pub fn swing_deg(&self, at: &dyn Fn(f64, Branch, &AxisVec) -> AxisVec, start: Branch) -> f64 {
        let q_in = at(
            self.theta_in,
            self.branch_at(self.theta_in, start),
            &AxisVec::ZERO,
        );
        let q_out = at(self.theta_out, self.branch_at(self.theta_out, start), &q_in);
        q_out[self.pole.inner] - q_in[self.pole.inner]
    }
}

/// The other IK branch.
pub fn other(branch: Branch) -> Branch {
    match branch {
        Branch::Primary => Branch::Secondary,
        Branch::Secondary => Branch::Primary,
    }
}

/// The minimum of `f` on [a, b] by golden-section search (60 steps: to rounding).
fn golden_min(f: &dyn Fn(f64) -> f64, mut a: f64, mut b: f64) -> f64 {
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..80 {
        let (c, d) = (b - g * (b - a), a + g * (b - a));
        if f(c) < f(d) {
            b = d;
        } else {
            a = c;
        }
    }
    0.5 * (a + b)
}
