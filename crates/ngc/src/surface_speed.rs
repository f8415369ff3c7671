//! Constant surface speed (G96 S, cancelled by G97) and the feed per revolution under it.
//!
//! Under G96 the S word is the surface speed v (m/min under G21, ft/min under G20) and the
//! control turns the spindle at `n = v / (π D)` rev/min for the diameter D of the tool's
//! position, clamped at the spindle speed limit (Fanuc and Haas lathes: `G50 S`; Fanuc
//! mills: `G92 S`; LinuxCNC: G96's own `D`). D is measured from the X zero of the work
//! system, the spindle's axis (Fanuc lathe operator's manual, "Constant surface speed
//! control": "set the work coordinate system so that the X coordinate of the centre of
//! rotation is zero"; LinuxCNC G-code manual, "G96, G97": X is the radius). On a Fanuc or
//! Haas lathe the X words are diameters (G-code system A's diameter programming), so
//! D = |X|; in LinuxCNC X is a radius (G7 halves the words), so D = 2 |X|.
//!
//! A feed per revolution f (G95, or G99 on a Fanuc-family lathe) then moves the tool at
//! f · n(D) mm/min, which changes along a move that changes X. mtsim's moves carry one
//! feed each, so such a move gets the feed that takes the same time as the control's:
//!
//! `t = ∫ ds / (f n(D(s))) = (1/f) ∫ max(1/n_max, π D(s) / v) ds`,  `F = L / t`.
//!
//! Along a straight move D(s) is linear in s away from the spindle axis, so the integrand
//! is piecewise linear between the points where the move crosses X 0 and the clamp
//! diameter `D_c = v / (π n_max)`: the trapezoid rule on those pieces is exact. An arc is
//! cut into [`ARC_PIECES`] equal angles, each integrated the same way (relative error below
//! 1e-6 for the arcs of a lathe profile). With no limit, a move that reaches D = 0 would
//! need an endless spindle speed: it is refused.

use std::f64::consts::PI;

use crate::axis::Axis;
use crate::canon::{Motion, Move};

/// Chords an arc is cut into for the time integral.
const ARC_PIECES: usize = 2048;

/// Diameters below this (mm) are the spindle axis: no speed without a limit.
const AXIS_MM: f64 = 1e-9;

/// The refusal of a move at X 0 under G96 with no spindle speed limit.
pub(crate) const UNBOUNDED: &str = "feed per revolution under G96 (constant surface speed) on a move that reaches the spindle's axis (X 0) with no spindle speed limit: the spindle would turn endlessly fast; expected a limit first (`G50 S` on a Fanuc or Haas lathe, `G96 D` in LinuxCNC), or G97 S";

/// Constant surface speed in effect: v, mm/min of surface per minute, and how a work X
/// coordinate turns into a diameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct SurfaceSpeed {
    pub mm_per_min: f64,
    /// D = `diameter_per_x` · |X| (1 where X words are diameters, 2 where they are radii).
    pub diameter_per_x: f64,
}

impl SurfaceSpeed {
    /// The spindle speed at diameter `d` mm, rev/min, clamped at `limit`; `None` when
    /// unbounded (on the axis with no limit).
    pub fn rpm(&self, d: f64, limit: Option<f64>) -> Option<f64> {
        let free = (d > AXIS_MM).then(|| self.mm_per_min / (PI * d));
        match (free, limit) {
            (Some(n), Some(max)) => Some(n.min(max)),
            (Some(n), None) => Some(n),
            (None, max) => max,
        }
    }

    /// Minutes per mm of path per (mm/rev) of feed at diameter `d`: 1 / n(D).
    pub fn minutes_per_rev(&self, d: f64, limit: Option<f64>) -> Option<f64> {
        self.rpm(d, limit).map(|n| 1.0 / n)
    }

    /// ∫ 1/n ds along a straight piece from work X `x0` to `x1`, `length` mm long:
    /// piecewise linear between X 0 and ±D_c, so exact by trapezoids there.
    pub fn straight_integral(
        &self,
        x0: f64,
        x1: f64,
        length: f64,
        limit: Option<f64>,
    ) -> Option<f64> {
        let mut cuts = vec![0.0, 1.0];
        let clamp_x = limit.map(|max| self.mm_per_min / (PI * max) / self.diameter_per_x);
        for level in [Some(0.0), clamp_x, clamp_x.map(|c| -c)]
            .into_iter()
            .flatten()
        {
            if (x1 - x0).abs() > 0.0 {
                let u = (level - x0) / (x1 - x0);
                if u > 0.0 && u < 1.0 {
                    cuts.push(u);
                }
            }
        }
        cuts.sort_by(f64::total_cmp);
        let at = |u: f64| {
            let d = self.diameter_per_x * (x0 + (x1 - x0) * u).abs();
            self.minutes_per_rev(d, limit)
        };
        let mut sum = 0.0;
        for w in cuts.windows(2) {
            sum += 0.5 * (at(w[0])? + at(w[1])?) * (w[1] - w[0]) * length;
        }
        Some(sum)
    }
}

/// The work X at each of `pieces + 1` equal steps along `mv`, and the path length of a step.
pub(crate) fn x_along(mv: &Move, x_zero: f64) -> (Vec<f64>, f64) {
    let Some(sweep) = mv.arc_sweep_rad() else {
        let d: f64 = [Axis::X, Axis::Y, Axis::Z]
            .iter()
            .map(|&a| (mv.end[a] - mv.start[a]).powi(2))
            .sum::<f64>()
            .sqrt();
        return (
            vec![mv.start[Axis::X] - x_zero, mv.end[Axis::X] - x_zero],
            d,
        );
    };
    let Motion::Arc {
        plane, center_mm, ..
    } = mv.motion
    else {
        unreachable!("a sweep is an arc's")
    };
    let (u, v, n) = plane.axes();
    let (su, sv) = (
        mv.start[u] - center_mm[u.index()],
        mv.start[v] - center_mm[v.index()],
    );
    let radius = su.hypot(sv);
    let start_angle = sv.atan2(su);
    let rise = mv.end[n] - mv.start[n];
    let step = (radius * sweep).hypot(rise).abs() / ARC_PIECES as f64;
    let xs = (0..=ARC_PIECES)
        .map(|k| {
            let a = start_angle + sweep * k as f64 / ARC_PIECES as f64;
            let x = match Axis::X {
                ax if ax == u => center_mm[u.index()] + radius * a.cos(),
                ax if ax == v => center_mm[v.index()] + radius * a.sin(),
                _ => mv.start[Axis::X] + rise * k as f64 / ARC_PIECES as f64,
            };
            x - x_zero
        })
        .collect();
    (xs, step)
}
