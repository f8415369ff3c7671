//! A study point's reversal value B per axis from its trace alone, for `mtsim study`'s
//! `B_<axis>_um` columns. `simulate` no longer uses it: its B comes from the error budget's
//! lost-motion runs (`study::budget`), which a study's shared passes do not run.
//!
//! # B per axis (ISO 230-2 reversal value, as the bar sees it)
//!
//! At each reversal θr of axis a where the bar sees a (normalised sensitivity `s >= 0.5`,
//! see `measure::attribution`), the centred trace is fitted by a straight line on each side,
//! over `[θr − 20°, θr − 8°]` before and `[θr + 8°, θr + 20°]` after (in the direction of
//! travel), and both lines are taken to θr: the step is `after(θr) − before(θr)`. The gap
//! skips the take-up of the lost motion (with friction off, inertia can take up a backlash
//! gap several degrees before the reversal); the lines cancel a smooth shape (lag, scale,
//! the other axis's lost motion, which is linear in θ there). Then
//!
//! ```text
//! B_a = mean over runs and reversals of |step| / s
//! ```
//!
//! µm along a linear axis (s is the cosine between bar and axis), µm of arc at the bar's
//! length for a rotary one. A reversal of another axis inside the windows adds its step too.

use crate::input::program::Direction;
use crate::measure::attribution::ReversalSite;
use crate::measure::ballbar::{BIN_DEG, N_BINS};
use crate::measure::BallbarRun;
use crate::report::run::AxisReversal;

/// The bar must see an axis at least this much (normalised sensitivity) for its step to
/// count towards B.
pub const B_SENSITIVITY_MIN: f64 = 0.5;
/// The fit windows on each side of a reversal: from, to (deg from θr).
pub const STEP_WINDOW_DEG: (f64, f64) = (8.0, 20.0);

/// The line through `(x, y)` taken to x = 0; None with fewer than 2 points.
fn line_at_zero(points: &[(f64, f64)]) -> Option<f64> {
    let n = points.len() as f64;
    if points.len() < 2 {
        return None;
    }
    let (mx, my) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), p| (a + p.0 / n, b + p.1 / n));
    let (sxy, sxx) = points.iter().fold((0.0, 0.0), |(a, b), p| {
        (a + (p.0 - mx) * (p.1 - my), b + (p.0 - mx).powi(2))
    });
    let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    Some(my - slope * mx)
}

/// The step of the binned trace `dev` (bins of [`BIN_DEG`]) across `theta_r`, in the
/// direction of travel of `direction`, µm.
pub fn step_across(dev: &[f64], theta_r: f64, direction: Direction) -> Option<f64> {
    let side = |sign: f64| line_at_zero(&window_points(dev, theta_r, sign));
    let (after, before) = match direction {
        Direction::Ccw => (side(1.0)?, side(-1.0)?),
        Direction::Cw => (side(-1.0)?, side(1.0)?),
    };
    Some(after - before)
}

/// The finite bins of `dev` whose offset `x = θ − θr` (wrapped to [−180°, 180°)) lies in
/// `sign · x ∈ [near, far]` of [`STEP_WINDOW_DEG`], as `(x, value)` in bin order.
///
/// Over a full revolution only the bins `i ≈ (θr + x)/BIN_DEG − ½ (mod N_BINS)` can be in
/// the window, so only those (two bins of margin each side) are tested, each by the same
/// test as a scan of every bin would apply: the same points, in the same order.
fn window_points(dev: &[f64], theta_r: f64, sign: f64) -> Vec<(f64, f64)> {
    let (near, far) = STEP_WINDOW_DEG;
    let offset = |i: usize| {
        let t = (i as f64 + 0.5) * BIN_DEG;
        (t - theta_r + 180.0).rem_euclid(360.0) - 180.0
    };
    let in_window = |i: &usize| {
        let x = offset(*i);
        dev[*i].is_finite() && sign * x >= near && sign * x <= far
    };
    if dev.len() != N_BINS || !(theta_r.abs() <= 720.0) {
        let all = (0..dev.len()).filter(in_window);
        return all.map(|i| (offset(i), dev[i])).collect();
    }
    let (lo, hi) = if sign > 0.0 {
        (theta_r + near, theta_r + far)
    } else {
        (theta_r - far, theta_r - near)
    };
    let first = (lo / BIN_DEG - 0.5).floor() as i64 - 2;
    let last = (hi / BIN_DEG - 0.5).ceil() as i64 + 2;
    let mut bins: Vec<usize> = (first..=last)
        .map(|k| k.rem_euclid(N_BINS as i64) as usize)
        .collect();
    bins.sort_unstable();
    bins.dedup();
    bins.retain(in_window);
    bins.into_iter().map(|i| (offset(i), dev[i])).collect()
}

/// Each axis's B from the centred traces of `runs` at the reversal `sites`.
pub fn reversal_b(
    runs: &[BallbarRun],
    sites: &[ReversalSite],
    axes: &[crate::Axis],
) -> crate::error::Result<Vec<AxisReversal>> {
    let traces: Vec<(Direction, Vec<f64>)> = runs
        .iter()
        .map(|r| Ok((r.direction(), r.trace_um(true)?)))
        .collect::<crate::error::Result<_>>()?;
    Ok(axes
        .iter()
        .map(|&axis| {
            let (mut b, mut step, mut n) = (0.0, 0.0, 0usize);
            for site in sites.iter().filter(|s| s.axis == axis) {
                let s = site.sensitivity.unwrap_or(1.0);
                if s < B_SENSITIVITY_MIN {
                    continue;
                }
                for (direction, dev) in &traces {
                    if let Some(h) = step_across(dev, site.theta_deg, *direction) {
                        b += h.abs() / s;
                        step += h.abs();
                        n += 1;
                    }
                }
            }
            let mean = |v: f64| (n > 0).then(|| v / n as f64);
            AxisReversal {
                axis: axis.to_string(),
                b_um: mean(b),
                step_um: mean(step),
                reversals: n,
            }
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A step of 10 µm at 180° on a slope: the lines on each side give 10 µm, whatever
    /// the slope, and the sign follows the direction of travel.
    #[test]
    fn a_step_on_a_slope_is_its_height() {
        let n = (360.0 / BIN_DEG).round() as usize;
        let dev: Vec<f64> = (0..n)
            .map(|i| {
                let t = (i as f64 + 0.5) * BIN_DEG;
                0.03 * t + if t > 176.0 { 10.0 } else { 0.0 }
            })
            .collect();
        let ccw = step_across(&dev, 180.0, Direction::Ccw).unwrap();
        let cw = step_across(&dev, 180.0, Direction::Cw).unwrap();
        assert!((ccw - 10.0).abs() < 1e-9, "{ccw}");
        assert!((cw + 10.0).abs() < 1e-9, "{cw}");
        // No step at 90°: the slope alone gives 0.
        assert!(step_across(&dev, 90.0, Direction::Ccw).unwrap().abs() < 1e-9);
    }

    /// The windows near 0°/360° wrap: a reversal at 3° takes its "before" window from
    /// [343°, 355°], and the points are those a scan of every bin finds, in bin order.
    #[test]
    fn windows_wrap_and_hold_every_bin_in_them() {
        let dev: Vec<f64> = (0..N_BINS)
            .map(|i| {
                if i % 97 == 0 {
                    f64::NAN
                } else {
                    (i as f64 * 0.37).sin()
                }
            })
            .collect();
        for theta_r in [0.0, 3.0, 7.99, 180.0, 340.0, 352.5, 359.99, 360.0, -5.0] {
            for sign in [1.0, -1.0] {
                let scanned: Vec<(f64, f64)> = (0..N_BINS)
                    .filter(|&i| dev[i].is_finite())
                    .filter_map(|i| {
                        let t = (i as f64 + 0.5) * BIN_DEG;
                        let x = (t - theta_r + 180.0).rem_euclid(360.0) - 180.0;
                        (sign * x >= 8.0 && sign * x <= 20.0).then_some((x, dev[i]))
                    })
                    .collect();
                // 12° of 0.05° bins, less the NaN bins among them.
                assert!((236..=241).contains(&scanned.len()), "{}", scanned.len());
                assert_eq!(
                    window_points(&dev, theta_r, sign),
                    scanned,
                    "{theta_r} {sign}"
                );
            }
        }
    }
}
