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
//! The size is the largest that keeps the deviation within the programmed tolerance (G64 P)
//! and takes at most half of either block (so that two blends never overlap, whatever the
//! order of the corners): `d = min(P tan(θ/2)/(1/cos(θ/2) − 1), L1/2, L2/2)`. Without P
//! (LinuxCNC's "G64 without P: the best speed possible, no matter how far from the
//! programmed point", its G-code reference) the arc is the smallest that keeps the blocks'
//! speed, `R = v²/a_n`. Speeds through the arc follow from the axis limits (`interpolation`):
//! the centripetal term `q'' v²` within [`NORMAL_SHARE`] of each axis's acceleration, the path
//! acceleration within [`TANGENTIAL_SHARE`], both measured on LinuxCNC.
//!
//! Not blended (the junction rule of `interpolation` applies): a corner that does not turn
//! (`θ` below 1e-9 rad: it needs nothing) or turns back (`θ` within 1e-6 rad of π: the arc
//! would have no size), and every corner next to an arc or a tool-centre-point block.

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

/// The blend at the corner between a straight block along `u1` (unit) and one along `u2`
/// (unit), each of which may give up to `half1` / `half2` (mm, half its length), with the
/// tolerance `tolerance_mm`. Without a tolerance the arc is the smallest that keeps `speed`
/// (the first block's cruise speed, path units/s, at which the arc is programmed) within `normal_limit` (per axis,
/// [`NORMAL_SHARE`] of its acceleration) and `jerk_limit` (per axis, the third of its jerk
/// the curved-block rule gives `q''' v³`; both infinite for an axis the machine does not
/// have): `R = max(v²/a_n, sqrt(v³/j_n))` with `a_n = min_i(normal_limit_i/max|q''_i| R)` and
/// `j_n = min_i(jerk_limit_i/max|q'_i|)`. `None` when the corner needs no blend or cannot have
/// one (see the module's doc).
pub fn corner(
    u1: AxisVec,
    u2: AxisVec,
    half1: f64,
    half2: f64,
    tolerance_mm: Option<f64>,
    speed: f64,
    (normal_limit, jerk_limit): (&[f64; 9], &[f64; 9]),
) -> Option<Corner> {
    let dot: f64 = (0..9).map(|i| u1.0[i] * u2.0[i]).sum();
    let across = u2 - u1 * dot;
    let sin = across.mixed_norm();
    let theta = sin.atan2(dot);
    if !(theta > 1e-9 && theta < std::f64::consts::PI - 1e-6) {
        return None;
    }
    let n = across * (1.0 / sin);
    let half_tan = (0.5 * theta).tan();
    // Deviation per unit radius: 1/cos(θ/2) − 1, written without cancellation.
    let half_cos = (0.5 * theta).cos();
    let per_radius = (1.0 - half_cos) / half_cos;
    let mut trim = half1.min(half2);
    match tolerance_mm {
        Some(tol) => trim = trim.min(tol.max(0.0) / per_radius * half_tan),
        None => {
            let least = |f: &dyn Fn(usize) -> f64| (0..9).map(f).fold(f64::INFINITY, f64::min);
            let normal = least(&|i| normal_limit[i] / peak_over_sweep(n.0[i], -u1.0[i], theta));
            let jerk = least(&|i| jerk_limit[i] / peak_over_sweep(u1.0[i], n.0[i], theta));
            // (A relative 1e-9 more, so that rounding leaves the arc at the blocks' speed.)
            let radius = (speed * speed / normal).max((speed.powi(3) / jerk).sqrt()) * (1.0 + 1e-9);
            trim = trim.min(radius * half_tan);
        }
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
