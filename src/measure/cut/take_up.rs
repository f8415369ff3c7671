//! Each axis's lost motion along the cut, and the span over which a reversal takes it up.
//!
//! The run gives, at every sample, each axis's table position `x_a` and its linear twin's
//! `x̃_a` (the same drive without backlash, dry friction or pre-sliding, fed the same
//! setpoints; `pipeline::Sample::linear`). Their difference is the axis's lost motion at
//! that moment:
//!
//! ```text
//! δ_a = x_a − x̃_a ≈ −(B_a / 2) sgn(v_a)   away from a reversal (semi-closed loop)
//! ```
//!
//! with `B_a = b + 2 F_c / k` the ISO 230-2 reversal value (the gap, and the drive's wind-up
//! by the friction). Across a reversal δ_a swings by B_a while the motor crosses the gap and
//! the friction turns over: the *take-up*, 2-5° of θ on a realistic servo (finite Kv, dry
//! friction), which no fixed window can know. [`LostMotion`] keeps δ_a per grid column (by
//! the θ of the cutter's contact, where the cutter leaves its mark), and [`settled_windows`]
//! finds, on either side of a reversal, the nearest θ window over which δ_a has settled:
//! the surface's levels are read there, outside the whole take-up. An axis whose δ_a does
//! not change across its reversal (no backlash, no friction, a fully-closed loop without
//! wind-up) has no lost motion there and leaves no mark.

use crate::pipeline::Sample;
use crate::{Axis, AxisVec};

/// A reversal's lost motion below this (mm or deg) is none: no mark.
pub const LOST_MOTION_MIN: f64 = 1e-4;
/// δ_a has settled over a window where it varies by at most this fraction of its swing.
pub const SETTLED_FRACTION: f64 = 0.02;
/// The levels δ_a swings between are read this far either side of a reversal at most, deg
/// (less where the axis's next reversal is nearer: half the way to it).
pub const LEVEL_DEG: f64 = 45.0;
/// Columns averaged for each level.
const LEVEL_COLUMNS: i64 = 5;

/// Each axis's lost motion δ_a per grid column, mm or deg (NaN where no sample fell).
#[derive(Clone, Debug)]
pub struct LostMotion {
    axes: Vec<Axis>,
    columns: usize,
    step_deg: f64,
    /// `values[j * axes + k]`.
    values: Vec<f64>,
}

impl LostMotion {
    pub fn new(axes: &[Axis], columns: usize) -> LostMotion {
        LostMotion {
            axes: axes.to_vec(),
            columns,
            step_deg: 360.0 / columns as f64,
            values: vec![f64::NAN; columns * axes.len()],
        }
    }

    /// Sample `s`, whose cutter's contact is at θ `contact_rad`: its δ of every axis.
    #[inline]
    pub fn record(&mut self, contact_rad: f64, s: &Sample) {
        self.record_positions(contact_rad, &s.actual, &s.linear);
    }

    /// [`LostMotion::record`] of the `actual` and `linear` positions of a sample.
    #[inline]
    pub fn record_positions(&mut self, contact_rad: f64, actual: &AxisVec, linear: &AxisVec) {
        let j = (contact_rad.to_degrees() / self.step_deg).round() as i64;
        let j = j.rem_euclid(self.columns as i64) as usize;
        let n = self.axes.len();
        for (k, &a) in self.axes.iter().enumerate() {
            self.values[j * n + k] = actual[a] - linear[a];
        }
    }

    /// δ of `axis` at column `j` (any integer: the grid wraps), NaN where none fell or the
    /// axis is not kept.
    pub fn at(&self, axis: Axis, j: i64) -> f64 {
        match self.axes.iter().position(|&a| a == axis) {
            Some(k) => {
                let j = j.rem_euclid(self.columns as i64) as usize;
                self.values[j * self.axes.len() + k]
            }
            None => f64::NAN,
        }
    }

    /// Whether any sample was recorded.
    pub fn is_empty(&self) -> bool {
        self.values.iter().all(|v| v.is_nan())
    }
}

/// Where to read the surface's levels about one reversal, in columns along the cut's
/// direction of travel from the reversal's column: `before` and `after` each a window
/// `(from, to)`, `from < to`; and the lost motion's swing across it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TakeUp {
    pub before: (i64, i64),
    pub after: (i64, i64),
    /// δ after less δ before, mm or deg.
    pub swing: f64,
}

/// The swing of `axis`'s lost motion across its reversal at column `r`, the cut travelling
/// `sense` (+1 to higher θ, −1 lower): `Δ = δ(+H) − δ(−H)`, each the mean of
/// [`LEVEL_COLUMNS`] at `H = level_columns` columns from the reversal. None when |Δ| is
/// below [`LOST_MOTION_MIN`]: no lost motion there, no mark.
pub fn swing(lost: &LostMotion, axis: Axis, r: i64, sense: i64, level_columns: i64) -> Option<f64> {
    let level = |from: i64| -> f64 {
        let v: Vec<f64> = (from..from + LEVEL_COLUMNS)
            .map(|t| lost.at(axis, r + sense * t))
            .filter(|v| v.is_finite())
            .collect();
        if v.is_empty() {
            f64::NAN
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    };
    let swing = level(level_columns - LEVEL_COLUMNS + 1) - level(-level_columns);
    (swing.abs() >= LOST_MOTION_MIN).then_some(swing)
}

/// The take-up of `axis`'s reversal at column `r` whose lost motion swings by `swing`
/// ([`swing`]): on either side the nearest window of `window` columns, at least `gap` from
/// the reversal and within `level_columns`, over which δ, widened by `margin` columns toward
/// the reversal (the cutter's reach: its take-up positions cut that far), varies by at most
/// [`SETTLED_FRACTION`] of |Δ|. None when no settled window fits.
pub fn settled_windows(
    lost: &LostMotion,
    axis: Axis,
    (r, sense): (i64, i64),
    (level_columns, swing): (i64, f64),
    (gap, window, margin): (i64, i64, i64),
) -> Option<TakeUp> {
    let at = |t: i64| lost.at(axis, r + sense * t);
    let tolerance = SETTLED_FRACTION * swing.abs();
    // δ over columns `from..=to` varies by at most the tolerance (half of them at least
    // sampled).
    let settled = |from: i64, to: i64| -> bool {
        let v: Vec<f64> = (from..=to).map(at).filter(|v| v.is_finite()).collect();
        if 2 * v.len() < (to - from + 1) as usize {
            return false;
        }
        let (lo, hi) = v
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
                (lo.min(x), hi.max(x))
            });
        hi - lo <= tolerance
    };
    let after = (gap..=level_columns - window)
        .find(|&u| settled(u - margin, u + window))
        .map(|u| (u, u + window))?;
    let before = (gap..=level_columns - window)
        .find(|&u| settled(-u - window, -u + margin))
        .map(|u| (-u - window, -u))?;
    Some(TakeUp {
        before,
        after,
        swing,
    })
}
