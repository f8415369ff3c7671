//! Corner blending: the arc that replaces the corner between two straight blocks under G64.
//!
//! Two straight blocks meet at the corner `P` with unit directions `u1` (in) and `u2` (out),
//! in axis space (mm and deg, deg counted as mm as in the blocks' path length). They turn by
//! `θ = atan2(|u2 − (u1·u2) u1|, u1·u2)`. The blend is the circular arc of radius `R` tangent
//! to both lines, in their plane: it leaves the first line `d = R tan(θ/2)` before the corner
//! and joins the second `d` after it, and its middle passes the corner at
//!
//! ```text
//! deviation = R (1/cos(θ/2) − 1)
//! ```
//!
//! With `n = (u2 − (u1·u2) u1)/sin θ` (the inward normal at the arc's start `T1 = P − d u1`),
//! the arc at angle `φ ∈ [0, θ]` is `T1 + R sin φ u1 + R (1 − cos φ) n`; its length is `R θ`.
//!
//! The size is the largest that keeps the deviation within the programmed tolerance (G64 P),
//! the radius within what LinuxCNC lays for the feed ([`SpeedSizing::radius`], on a machine
//! whose `[control] max_feed_override` is set: the arc of [`arc_length_for_speed`], or for a
//! turn above 99° the arc that passes at that speed, from the limits of the corner's plane),
//! and takes at most half of either block (so that two blends never overlap, whatever the
//! order of the corners), and under LinuxCNC's rules passes at most a quarter of either
//! block from the corner:
//! `d = min(P tan(θ/2)/(1/cos(θ/2) − 1), R_speed tan(θ/2), L1/2, L2/2,
//!          min(L1, L2)/4 · tan(θ/2)/(1/cos(θ/2) − 1))`.
//! Without P (LinuxCNC's "G64 without P: the best speed possible, no matter how far from the
//! programmed point", its G-code reference) only the speed's radius and the halves bound it.
//! Speeds through the arc follow from the axis limits (`interpolation`): the centripetal term
//! `q'' v²` within [`NORMAL_SHARE`] of each axis's acceleration, the path acceleration within
//! [`TANGENTIAL_SHARE`], both measured on LinuxCNC.
//!
//! Not blended (the junction rule of `interpolation` applies): a corner that does not turn
//! (`θ` below 1e-9 rad: it needs nothing) or turns back (`θ` within 1e-6 rad of π: the arc
//! would have no size), and every corner next to an arc (but a line and a circle in its
//! plane: `arc_corner`), a tool-centre-point block, a rapid or a move of an axis
//! besides X Y Z (under LinuxCNC's rules straight ones are overlapped instead: `overlap`).

use crate::AxisVec;

/// A circular arc in axis space, as offsets from its start point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bend {
    /// `R u1`: the start tangent times the radius.
    pub along: AxisVec,
    /// `R n`: from the start toward the centre.
    pub inward: AxisVec,
    /// The angle turned, `θ`, rad.
    pub sweep_rad: f64,
}

impl Bend {
    /// The arc at `u ∈ [0, 1]` (angle `φ = θ u`) less its start: `R sin φ u1 + R (1 − cos φ) n`.
    #[inline]
    pub fn offset(&self, u: f64) -> AxisVec {
        let (sin, cos) = (self.sweep_rad * u).sin_cos();
        self.along * sin + self.inward * (1.0 - cos)
    }
}

/// The blend of one corner: how much of each block it takes, and its arc.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Corner {
    /// Taken from the end of the first block and from the start of the second, `d` (mm).
    pub trim: f64,
    /// The arc, from `P − d u1` to `P + d u2`.
    pub bend: Bend,
    /// Its length `R θ` (mm).
    pub length: f64,
    /// Its largest distance from the corner, `R (1/cos(θ/2) − 1)` (mm).
    pub deviation: f64,
}

/// Share of an axis's acceleration the centripetal term of a blend arc may use: `√(1 − ½²)`,
/// the rest of a vector budget whose tangential part is ½. Measured on LinuxCNC 2.9 (black
/// box, `tests/motion/linuxcnc_planner.rs`): a hexagon's 120° corners at G64 P0.05 and P0.01
/// pass at 9.162 and 4.095 mm/s, `v²/R` = 259.7 and 259.4 mm/s² on axes limited to 300.
pub const NORMAL_SHARE: f64 = 0.866_025_403_784_438_6;

/// Share of an axis's acceleration the path acceleration may use on a blend arc.
pub const TANGENTIAL_SHARE: f64 = 0.5;

/// The longest blend arc LinuxCNC 2.9 lays at a corner (measured, black box,
/// `tests/motion/linuxcnc_planner.rs`): `v_s² / (½ a)`, with `v_s` the programmed feed at the
/// control's highest feed override, held to the slowest velocity limit `v_max` of the axes
/// the corner's plane moves, and `a` their smallest acceleration limit (units/s, units/s²).
/// On xyzac-trt (20 mm/s, 300 mm/s², override 2): every G64 corner of XY lines at F600 and
/// above is an arc 2.667 mm long (90°: 703.2 um off, 60°: 394.0, 8.53°: 49.8), at F300 one
/// 0.667 mm long (90°: 175.8 um), whatever the lines' lengths (5 to 50 mm) and P5 alike.
pub fn arc_length_for_speed(feed: f64, max_feed_override: f64, v_max: f64, a: f64) -> f64 {
    let v = (feed * max_feed_override).min(v_max);
    v * v / (TANGENTIAL_SHARE * a)
}

/// The largest `|a cos φ + b sin φ|` for `φ ∈ [0, θ]` (θ ≤ π): `hypot(a, b)` when the peak
/// `φ0 = atan2(b, a)` (or `φ0 ± π`) falls inside, else the larger end.
fn peak_over_sweep(a: f64, b: f64, theta: f64) -> f64 {
    let phase = b.atan2(a).rem_euclid(std::f64::consts::PI);
    if phase <= theta {
        a.hypot(b)
    } else {
        a.abs().max((a * theta.cos() + b * theta.sin()).abs())
    }
}

impl Bend {
    /// Per axis, the largest first, second and third derivatives by path length over the
    /// arc, exact: with `s = R φ`, `dq/ds = cos φ u1 + sin φ n`,
    /// `d²q/ds² = (cos φ n − sin φ u1)/R`, `d³q/ds³ = −(cos φ u1 + sin φ n)/R²`.
    pub fn derivative_bounds(&self) -> ([f64; 9], [f64; 9], [f64; 9]) {
        let radius = self.along.mixed_norm();
        let (mut d1, mut d2, mut d3) = ([0.0; 9], [0.0; 9], [0.0; 9]);
        for i in 0..9 {
            let (u, n) = (self.along.0[i] / radius, self.inward.0[i] / radius);
            d1[i] = peak_over_sweep(u, n, self.sweep_rad);
            d2[i] = peak_over_sweep(n, -u, self.sweep_rad) / radius;
            d3[i] = d1[i] / (radius * radius);
        }
        (d1, d2, d3)
    }
}

/// How LinuxCNC 2.9 sizes a blend for speed (`[control] max_feed_override` given): the feed
/// the blend is laid for and the axes' limits, from which those of the blend's plane follow.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpeedSizing {
    /// The programmed feed (mm/s; infinite for a rapid) and the control's highest override.
    pub feed: f64,
    pub max_feed_override: f64,
    /// Each axis's velocity and acceleration limits (units/s, units/s²); `None`: absent.
    pub axes: [Option<(f64, f64)>; 9],
}

impl SpeedSizing {
    /// The velocity and acceleration limits of the plane spanned by `u1` and `n`
    /// (orthonormal): a direction `cos φ u1 + sin φ n` of that plane moves axis `i` by at
    /// most `w_i = sqrt(u1_i² + n_i²)` per unit, so the plane's limits are
    /// `min_i v_i / w_i` and `min_i a_i / w_i` over the axes it moves. For a plane of two
    /// axes (`w` = 1 on both) these are the slower axis's limits; for a plane tilted across
    /// three axes they are above every axis's own (measured: a corner between 3D rapids on
    /// 3axis-tutorial passes at 28.14 mm/s, axes at 25 mm/s, Y peaking at 25.00).
    pub fn plane_limits(&self, u1: AxisVec, n: AxisVec) -> (f64, f64) {
        let (mut v, mut a) = (f64::INFINITY, f64::INFINITY);
        for (i, limits) in self.axes.iter().enumerate() {
            let w = u1.0[i].hypot(n.0[i]);
            if let (Some((vi, ai)), true) = (limits, w > 1e-12) {
                v = v.min(vi / w);
                a = a.min(ai / w);
            }
        }
        (v, a)
    }

    /// The largest blend radius LinuxCNC lays for speed at a turn of `theta` (rad) in the
    /// plane of `u1`, `n`: with the plane's limits `v_max`, `a` and `v_s = min(F · override,
    /// v_max)`,
    ///
    /// ```text
    /// R_speed = max( ℓmax / θ,  v_s² / (√3/2 · a) ),   ℓmax = v_s² / (½ a)
    /// ```
    ///
    /// the arc of [`arc_length_for_speed`], or, where the turn exceeds `√3` rad (99.2°) and
    /// that arc would be tighter, the one that passes at `v_s` with its centripetal term at
    /// [`NORMAL_SHARE`] of `a` (measured: 102° and 146° turns between rapids, 570.9 and
    /// 2662.9 um off; same-way line-arc blends, docs/interpolation.md).
    pub fn radius(&self, theta: f64, u1: AxisVec, n: AxisVec) -> f64 {
        let (v_max, a) = self.plane_limits(u1, n);
        let v = (self.feed * self.max_feed_override).min(v_max);
        let length = arc_length_for_speed(self.feed, self.max_feed_override, v_max, a);
        (length / theta).max(v * v / (NORMAL_SHARE * a))
    }
}

/// The turn from `u1` to `u2` (unit): its angle `θ` and the unit normal `n` toward `u2`,
/// `None` where it does not turn (θ below 1e-9 rad) or turns back (within 1e-6 rad of π).
pub fn turn(u1: AxisVec, u2: AxisVec) -> Option<(f64, AxisVec)> {
    let dot: f64 = (0..9).map(|i| u1.0[i] * u2.0[i]).sum();
    let across = u2 - u1 * dot;
    let sin = across.mixed_norm();
    let theta = sin.atan2(dot);
    if !(theta > 1e-9 && theta < std::f64::consts::PI - 1e-6) {
        return None;
    }
    Some((theta, across * (1.0 / sin)))
}

/// The blend at the corner between a straight block along `u1` (unit) and one along `u2`
/// (unit), each of which may give up to `half1` / `half2` (mm, half its length), with the
/// tolerance `tolerance_mm` (none: no bound from it) and LinuxCNC's bound for speed
/// ([`SpeedSizing::radius`]; none: no bound from it). `None` when the corner needs no
/// blend or cannot have one (see the module's doc), or when nothing bounds it.
pub fn corner(
    u1: AxisVec,
    u2: AxisVec,
    half1: f64,
    half2: f64,
    tolerance_mm: Option<f64>,
    speed: Option<&SpeedSizing>,
) -> Option<Corner> {
    let (theta, n) = turn(u1, u2)?;
    let half_tan = (0.5 * theta).tan();
    // Deviation per unit radius: 1/cos(θ/2) − 1, written without cancellation.
    let half_cos = (0.5 * theta).cos();
    let per_radius = (1.0 - half_cos) / half_cos;
    let mut trim = half1.min(half2);
    if let Some(tol) = tolerance_mm {
        trim = trim.min(tol.max(0.0) / per_radius * half_tan);
    }
    if let Some(speed) = speed {
        trim = trim.min(speed.radius(theta, u1, n).max(0.0) * half_tan);
        // LinuxCNC's: the deviation at most a quarter of either block, `R (1/cos(θ/2) − 1)
        // ≤ L/4`; it binds before the halves past `θ = 4 atan(½)` (106.3°).
        trim = trim.min(0.5 * half1.min(half2) / per_radius * half_tan);
    }
    if !trim.is_finite() {
        return None;
    }
    if !(trim > 1e-9) {
        return None;
    }
    let radius = trim / half_tan;
    Some(Corner {
        trim,
        bend: Bend {
            along: u1 * radius,
            inward: n * radius,
            sweep_rad: theta,
        },
        length: radius * theta,
        deviation: radius * per_radius,
    })
}
