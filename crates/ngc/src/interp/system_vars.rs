//! Fanuc and Haas macro B system variables: the ones that read the modal state (`#4001`-
//! `#4120`, `#5001`-`#5046`), written before a line that reads parameters; the ones mtsim
//! does not model, refused when read; and the alarm `#3000`, which stops the program.
//!
//! Numbers and meanings: Fanuc Series 0i-MF operator's manual (B-64604EN), "Custom macro",
//! "System variables" (modal information #4001-#4130, position information #5001-#5108,
//! alarms #3000); the Haas mill operator's manual, "Macros", "System variables" (the same
//! numbers; #3026 the tool in the spindle).

use super::Interp;
use crate::axis::{Axis, Plane};
use crate::code::{FeedRead, MotionMode};
use crate::expr::Param;
use crate::lex::{LineError, LineResult};
use crate::options::Dialect;

/// What a macro B system variable is, for the numbers whose value mtsim does not give:
/// reading one is refused with this meaning, never read as 0.
pub(crate) fn unmodelled(n: usize) -> Option<&'static str> {
    Some(match n {
        1000..=1035 => "an interface input signal",
        1100..=1135 => "an interface output signal",
        1000..=1999 => "an interface signal",
        2000..=2999 => "a tool offset value (tool offset memory)",
        3000 => "the alarm (written, not read)",
        3001 | 3002 => "a clock",
        3003 | 3004 => "an automatic-operation control flag",
        3005 => "a setting",
        3006 => "the stop with message (written, not read)",
        3007 => "the mirror image state",
        3011 | 3012 => "the date or time",
        3901 | 3902 => "a parts count",
        3000..=3999 => "a system variable of the control",
        4001..=4022 | 4107 | 4109 | 4119 | 4120 => return None,
        4000..=4999 => "a modal value mtsim does not keep",
        5001..=5006 | 5021..=5026 | 5041..=5046 => return None,
        5081..=5088 => "a tool length offset value",
        5101..=5108 => "a servo position deviation",
        _ => return None,
    })
}

/// [`unmodelled`] on a Haas control, where `#3026` is the tool in the spindle.
pub(crate) fn unmodelled_haas(n: usize) -> Option<&'static str> {
    if n == 3026 {
        return None;
    }
    unmodelled(n)
}

impl Interp {
    /// Macro B dialects: reading a system variable of [`unmodelled`] is an error.
    pub(super) fn refuse_unmodelled_system_variables(&mut self) {
        if self.dialect.table().macro_b {
            self.params.unmodelled = Some(if self.dialect == Dialect::Haas {
                unmodelled_haas
            } else {
                unmodelled
            });
        }
    }

    /// The macro B modal and position variables, from the state now (program units).
    pub(super) fn refresh_macro_b(&mut self) {
        let p = self.program_position();
        let scale = self.scale();
        let group1 = match self.motion {
            Some(MotionMode::Cycle(_)) | None => self.interpolation,
            m => m,
        };
        let modal = [
            // #4001 group 1: G00-G03 (a code mtsim moves in another way reads its number).
            match group1 {
                // Fanuc's power-up group-1 mode is G00 (parameter 3402#0 = 0).
                Some(MotionMode::Rapid) | None => 0.0,
                Some(MotionMode::Linear) => 1.0,
                Some(MotionMode::Arc { clockwise: true }) => 2.0,
                Some(MotionMode::Arc { .. }) => 3.0,
                Some(
                    MotionMode::Cycle(c)
                    | MotionMode::SpindleSync(c)
                    | MotionMode::Probe(c)
                    | MotionMode::Spline(c),
                ) => c as f64 / 10.0,
            },
            match self.plane {
                Plane::XY => 17.0,
                Plane::ZX => 18.0,
                Plane::YZ => 19.0,
            },
            if self.absolute { 90.0 } else { 91.0 },
            // #4004 group 4: stored stroke check on (G22) is the power-up state.
            22.0,
            match self.feed_mode {
                FeedRead::InverseTime => 93.0,
                FeedRead::PerMinute => 94.0,
                FeedRead::PerRevolution => 95.0,
            },
            if self.inch { 20.0 } else { 21.0 },
            match &self.comp {
                None => 40.0,
                Some(c) if c.left => 41.0,
                Some(_) => 42.0,
            },
            if self.tcp {
                43.4
            } else if self.tool_length_mm != 0.0 {
                43.0
            } else {
                49.0
            },
            match self.motion {
                Some(MotionMode::Cycle(c)) => c as f64 / 10.0,
                _ => 80.0,
            },
            if self.retract_r { 99.0 } else { 98.0 },
            // #4011 group 11: scaling off (G50); #4012 group 12: macro modal call off (G67).
            50.0,
            67.0,
            // #4013 group 13: G97 (constant surface speed off), #4014 group 14: the work
            // system.
            97.0,
            match self.coord {
                1..=6 => 53.0 + self.coord as f64,
                7..=9 => 59.0 + (self.coord - 6) as f64 / 10.0,
                _ => 54.1,
            },
            // #4015 group 15: G64 cutting mode; #4016 group 16: G69 (rotation off).
            64.0,
            if self.tilt.is_some() { 68.2 } else { 69.0 },
            // #4017-#4022: G15 polar off, G40.1, G25, G160, G13.1, none.
            15.0,
            40.1,
            25.0,
            160.0,
            13.1,
            0.0,
        ];
        let tool = if self.tool_selected {
            self.next_tool
        } else {
            self.tool
        };
        let n = &mut self.params.numbered;
        for (k, v) in modal.iter().enumerate() {
            n[4001 + k] = *v;
        }
        n[4107] = self.d_register.map_or(0.0, f64::from);
        n[4109] = self.feed.unwrap_or(0.0);
        n[4119] = self.spindle_rpm;
        n[4120] = tool as f64;
        for a in Axis::LINEAR {
            let k = a.index();
            n[5001 + k] = p[a];
            n[5041 + k] = p[a];
            n[5021 + k] = self.pos[a] / scale;
        }
        for a in [Axis::A, Axis::B, Axis::C] {
            let k = a.index();
            n[5001 + k] = p[a];
            n[5041 + k] = p[a];
            n[5021 + k] = self.pos[a];
        }
        if self.dialect == Dialect::Haas {
            n[3026] = self.tool as f64;
        }
    }

    /// A macro B assignment to a system variable: `#3000 = n (text)` stops the program
    /// with alarm n and its text; the read-only modal and position variables refuse a
    /// write, as the control does ("write-protected variable").
    pub(crate) fn check_assign(&self, line: &str, p: &Param, v: f64) -> LineResult<()> {
        let Param::Numbered(n) = *p else {
            return Ok(());
        };
        if !self.dialect.table().macro_b {
            return Ok(());
        }
        let text = format!("{n}");
        let span = line
            .find(&text)
            .map_or(0..line.len(), |at| at.saturating_sub(1)..at + text.len());
        if n == 3000 {
            let message = line
                .find('(')
                .map(|open| line[open + 1..].trim_end().trim_end_matches(')').trim())
                .unwrap_or("");
            return Err(LineError::new(
                span,
                format!(
                    "`#3000 = {v}`: the program stops with alarm {} \"{message}\" (macro alarm)",
                    v.round()
                ),
                "macro alarm",
            ));
        }
        let read_only =
            matches!(n, 4001..=4130 | 5001..=5046) || (n == 3026 && self.dialect == Dialect::Haas);
        if read_only {
            return Err(LineError::new(
                span,
                format!("`#{n}` is a read-only system variable of the control (modal or position information): a program cannot set it"),
                "read-only system variable",
            ));
        }
        Ok(())
    }
}
