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

use super::Interp;
use crate::axis::Axis;
use crate::block::Block;
use crate::canon::{Motion, Move};
use crate::code::{FeedRead, GCode};
use crate::lex::{LineError, LineResult};
use crate::units::MM_PER_INCH;

/// Chords an arc is cut into for the time integral.
const ARC_PIECES: usize = 2048;

/// Diameters below this (mm) are the spindle axis: no speed without a limit.
const AXIS_MM: f64 = 1e-9;

/// The refusal of a move at X 0 under G96 with no spindle speed limit.
const UNBOUNDED: &str = "feed per revolution under G96 (constant surface speed) on a move that reaches the spindle's axis (X 0) with no spindle speed limit: the spindle would turn endlessly fast; expected a limit first (`G50 S` on a Fanuc or Haas lathe, `G96 D` in LinuxCNC), or G97 S";

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
    fn minutes_per_rev(&self, d: f64, limit: Option<f64>) -> Option<f64> {
        self.rpm(d, limit).map(|n| 1.0 / n)
    }

    /// ∫ 1/n ds along a straight piece from work X `x0` to `x1`, `length` mm long:
    /// piecewise linear between X 0 and ±D_c, so exact by trapezoids there.
    fn straight_integral(&self, x0: f64, x1: f64, length: f64, limit: Option<f64>) -> Option<f64> {
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
fn x_along(mv: &Move, x_zero: f64) -> (Vec<f64>, f64) {
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

impl Interp {
    /// G96, G97 and the spindle speed limit in a block (phase 1, after F): sets the
    /// surface speed or the spindle speed from S. `G50 S` (Fanuc, Haas lathes) and `G92 S`
    /// alone (Fanuc mills) set the limit, not the speed; in LinuxCNC G96's D does.
    pub(super) fn spindle_mode(&mut self, b: &Block) -> LineResult<()> {
        let s = b.get('S');
        let table = self.dialect.table();
        let no_axis_word = !b
            .words
            .iter()
            .any(|w| Axis::from_letter(w.letter).is_some());
        let limit_block = b.has_g(|c| matches!(c, GCode::Control(500)))
            || (table.g92_s_limits_spindle
                && no_axis_word
                && b.has_g(|c| matches!(c, GCode::NonModal(crate::code::NonModal::G92))));
        if let (true, Some(s)) = (limit_block && table.macro_b, s) {
            self.spindle_limit_rpm = (s.value > 0.0).then_some(s.value);
            return Ok(());
        }
        let css_on = b.has_g(|c| matches!(c, GCode::Control(960)));
        let css_off = b.has_g(|c| matches!(c, GCode::Control(970)));
        if css_on {
            if let (false, Some(d)) = (table.macro_b, b.get('D')) {
                self.spindle_limit_rpm = (d.value > 0.0).then_some(d.value);
            }
            let v = s.map(|s| s.value).or(self.surface_speed.map(|c| {
                c.mm_per_min
                    / if self.inch {
                        12.0 * MM_PER_INCH
                    } else {
                        1000.0
                    }
            }));
            let Some(v) = v else {
                let w =
                    b.g.iter()
                        .find(|(c, _)| *c == GCode::Control(960))
                        .map(|(_, w)| w.span())
                        .unwrap_or(0..b.line.len());
                return Err(LineError::new(w, "G96 (constant surface speed) without S: expected the surface speed in S (m/min, ft/min under G20)", "no S"));
            };
            self.surface_speed = Some(SurfaceSpeed {
                mm_per_min: v * if self.inch {
                    12.0 * MM_PER_INCH
                } else {
                    1000.0
                },
                diameter_per_x: if table.macro_b { 1.0 } else { 2.0 },
            });
            return Ok(());
        }
        if css_off {
            if let (Some(css), None) = (self.surface_speed.take(), s) {
                // The spindle keeps the speed it turns at when G96 ends.
                let d = css.diameter_per_x * (self.pos[Axis::X] - self.offset[Axis::X]).abs();
                self.spindle_rpm = css.rpm(d, self.spindle_limit_rpm).unwrap_or(0.0);
            }
        }
        let unit = if self.inch {
            12.0 * MM_PER_INCH
        } else {
            1000.0
        };
        match (&mut self.surface_speed, s) {
            (Some(css), Some(s)) => css.mm_per_min = s.value * unit,
            (None, Some(s)) => self.spindle_rpm = s.value,
            (_, None) => {}
        }
        Ok(())
    }

    /// The per-minute feed of a feed move from `start` to `end` at f mm/rev under constant
    /// surface speed: the feed that takes the control's time (module doc). `Err` when the
    /// spindle speed is unbounded along it, or the machine is a Fanuc-family mill (whose
    /// surface-speed axis is a parameter mtsim does not model).
    pub(super) fn surface_speed_feed(
        &self,
        css: SurfaceSpeed,
        f: f64,
        mv: &Move,
    ) -> Result<f64, String> {
        if self.dialect.table().macro_b && !self.is_lathe() {
            return Err(format!("feed per revolution under G96 (constant surface speed) on a machine that is not a lathe: on a {} mill the axis the surface speed follows is a control parameter (Fanuc 3770) mtsim does not model; expected G97 S (a spindle speed in rev/min) or a feed per minute", self.dialect.name()));
        }
        let (xs, step) = x_along(mv, self.offset[Axis::X]);
        let length = step * (xs.len() - 1) as f64;
        if length == 0.0 {
            // A rotary axis alone: the speed at the diameter the tool stands at.
            let d = css.diameter_per_x * xs[0].abs();
            return css
                .rpm(d, self.spindle_limit_rpm)
                .map(|n| f * n)
                .ok_or_else(|| UNBOUNDED.to_string());
        }
        let mut minutes_per_mm_rev = 0.0;
        for w in xs.windows(2) {
            minutes_per_mm_rev += css
                .straight_integral(w[0], w[1], step, self.spindle_limit_rpm)
                .ok_or_else(|| UNBOUNDED.to_string())?;
        }
        Ok(length * f / minutes_per_mm_rev)
    }

    /// The feed mode needs a spindle speed: S under G95, or a surface speed under G96.
    pub(super) fn turns_per_minute_known(&self) -> bool {
        self.feed_mode != FeedRead::PerRevolution
            || self.spindle_rpm > 0.0
            || self.surface_speed.is_some()
    }
}
