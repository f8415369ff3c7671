//! The read-only system parameters (`#5420`-`#5428` positions, `#5400` tool, `#<_metric>`
//! ...), written before a line that reads parameters.

use super::Interp;
use crate::axis::{Axis, Plane};
use crate::code::{FeedRead, MotionMode};

impl Interp {
    /// Writes the read-only system parameters (positions, tool, work system) before a line
    /// that reads parameters.
    pub fn refresh_system_parameters(&mut self) {
        let p = self.program_position();
        let scale = self.scale();
        let diameter = self.tools.get(&self.tool).map_or(0.0, |t| t.diameter_mm);
        let n = &mut self.params.numbered;
        for a in Axis::ALL {
            n[5420 + a.index()] = p[a];
        }
        n[5400] = self.tool as f64;
        n[5403] = self.tool_length_mm / scale;
        n[5410] = diameter / scale;
        n[5220] = self.coord.min(9) as f64;
        let g = &mut self.params.globals;
        for a in Axis::ALL {
            g.insert(format!("_{}", a.letter().to_ascii_lowercase()), p[a]);
        }
        let t = |c: bool| if c { 1.0 } else { 0.0 };
        g.insert("_metric".into(), t(!self.inch));
        g.insert("_imperial".into(), t(self.inch));
        g.insert("_absolute".into(), t(self.absolute));
        g.insert("_incremental".into(), t(!self.absolute));
        g.insert("_current_tool".into(), self.tool as f64);
        g.insert("_selected_tool".into(), self.next_tool as f64);
        let pocket = |t: u32| self.pockets.get(&t).map_or(t as f64, |p| *p as f64);
        g.insert(
            "_current_pocket".into(),
            if self.tool == 0 {
                0.0
            } else {
                pocket(self.tool)
            },
        );
        g.insert(
            "_selected_pocket".into(),
            if self.tool_selected {
                pocket(self.next_tool)
            } else {
                -1.0
            },
        );
        g.insert(
            "_feed".into(),
            self.feed.unwrap_or(0.0)
                / if self.feed_mode == FeedRead::InverseTime {
                    1.0
                } else {
                    scale
                },
        );
        g.insert("_rpm".into(), self.spindle_rpm);
        g.insert("_lathe_diameter_mode".into(), t(self.diameter));
        g.insert("_lathe_radius_mode".into(), t(!self.diameter));
        g.insert("_spindle_on".into(), t(self.spindle_turning));
        g.insert(
            "_coord_system".into(),
            match self.coord {
                1..=6 => 530.0 + 10.0 * self.coord as f64,
                7..=9 => 584.0 + self.coord as f64,
                _ => 541.0,
            },
        );
        g.insert(
            "_plane".into(),
            match self.plane {
                Plane::XY => 170.0,
                Plane::ZX => 180.0,
                Plane::YZ => 190.0,
            },
        );
        g.insert(
            "_motion_mode".into(),
            match self.motion {
                Some(MotionMode::Rapid) => 0.0,
                Some(MotionMode::Linear) => 10.0,
                Some(MotionMode::Arc { clockwise: true }) => 20.0,
                Some(MotionMode::Arc { .. }) => 30.0,
                Some(MotionMode::Cycle(c) | MotionMode::SpindleSync(c) | MotionMode::Probe(c)) => {
                    c as f64
                }
                Some(MotionMode::Spline(c)) => c as f64,
                None => 800.0,
            },
        );
        g.insert("_task".into(), 0.0);
        if self.dialect.table().macro_b {
            self.refresh_macro_b();
        }
    }
}
