//! The spindle's mode and speed in the modal state: G96/G97, S as a surface speed or a
//! spindle speed, the speed limit (G50 S, G92 S, G96 D), and the per-minute feed of a
//! per-revolution move under constant surface speed (the math: crate `surface_speed`).

use super::Interp;
use crate::axis::Axis;
use crate::block::Block;
use crate::canon::Move;
use crate::code::{FeedRead, GCode};
use crate::lex::{LineError, LineResult};
use crate::surface_speed::{x_along, SurfaceSpeed, UNBOUNDED};
use crate::units::MM_PER_INCH;

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
