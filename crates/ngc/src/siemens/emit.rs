//! The collected words of a block written as ISO blocks and run (see `words.rs` for the
//! frame arithmetic), then the block's return, call or modal cycle.

use super::words::{number, Coordinate, Mode, Words};
use super::Reader;
use crate::axis::Axis;
use crate::interp::Stop;
use crate::lex::{LineError, LineResult};

impl Reader {
    /// Runs the collected block; `Ok(false)` when the program ends. `G53`, `G153` and
    /// `SUPA` suppress the settable and programmable frames for their block (Fundamentals,
    /// "Settable zero offset (G54 to G57, G505 to G599, G53, G500, SUPA, G153)"): the
    /// block's coordinates are machine coordinates, not turned or shifted by the frames.
    pub(super) fn emit(&mut self, w: Words, up: &str, line_no: usize) -> LineResult<bool> {
        if w.other.iter().any(|(t, _)| t == "G53") && !self.frame.is_identity() {
            let frame = std::mem::take(&mut self.frame);
            let result = self.emit_block(w, up, line_no);
            self.frame = frame;
            return result;
        }
        self.emit_block(w, up, line_no)
    }

    fn emit_block(&mut self, mut w: Words, up: &str, line_no: usize) -> LineResult<bool> {
        for iso in std::mem::take(&mut w.before) {
            self.iso.push_str(&iso);
            self.run_iso(line_no)?;
        }
        self.orientation_to_axes(&mut w, line_no)?;
        if self.polar(&mut w)? {
            return Ok(true);
        }
        self.contour_words(&mut w)?;
        if let Some(m) = w.motion {
            self.motion = m;
        }
        let moves = w.has_motion_words();
        if let Some(span) = w.dwell.clone() {
            let Some((f, _)) = w.feed.take() else {
                return Err(LineError::new(
                    span,
                    "G4 without F: expected `G4 F<seconds>` in a block of its own",
                    "dwell without time",
                ));
            };
            self.push(&format!("G4 X{}", number(f)), span);
        }
        let computed = moves
            && (!self.frame.is_identity()
                || self.motion == super::state::CIP
                || self.motion == super::state::CT
                || w.turn.is_some()
                || w.axes
                    .iter()
                    .chain(&w.centres)
                    .flatten()
                    .any(|c| c.mode != Mode::Modal));
        let other = std::mem::take(&mut w.other);
        for (k, (text, span)) in other.iter().enumerate() {
            // `G94 FNORM` names one code twice.
            if !other[..k].iter().any(|(t, _)| t == text) {
                self.push(text, span.clone());
            }
        }
        if let Some((f, span)) = w.feed.clone() {
            let f = if self.feed_in_mm {
                f / crate::units::MM_PER_INCH
            } else {
                f
            };
            self.push(&format!("F{}", number(f)), span);
        }
        if !moves {
            self.plane_code(self.normal, 0..0);
        } else {
            if computed {
                self.computed_words(&w, line_no)?;
            } else {
                self.written_words(&w, up);
            }
        }
        let stop = if self.iso.is_empty() {
            Stop::None
        } else {
            self.run_iso(line_no)?
        };
        if matches!(stop, Stop::End) {
            return Ok(false);
        }
        let corner = w.corner.take();
        if corner.is_some() || (self.rounding_modal.is_some() && moves) || self.held.is_some() {
            if let Some(c) = corner.as_ref().filter(|_| self.modal_call.is_some()) {
                return Err(LineError::new(c.span.clone(), "a chamfer or rounding under a modal cycle call (MCALL): not read by mtsim; expected MCALL alone before the contour", "chamfer or rounding"));
            }
            self.corner_after_block(corner, moves, line_no)?;
        }
        self.approach_fixed_point(&mut w, line_no)?;
        for iso in std::mem::take(&mut w.after) {
            self.iso.push_str(&iso);
            self.run_iso(line_no)?;
        }
        if moves && self.modal_call.is_some() && w.axes.iter().any(Option::is_some) {
            self.run_cycle(None, line_no)?;
        }
        if let Some((name, args, span)) = w.call.take() {
            let repeats = w.repeats.unwrap_or(1);
            self.call(&name, args, repeats, span)?;
        }
        if w.ret {
            return self.end_of_level();
        }
        Ok(true)
    }

    /// Appends `text` (one or more ISO words) to the block, noting its source span.
    pub(super) fn push(&mut self, text: &str, span: std::ops::Range<usize>) {
        if !self.iso.is_empty() {
            self.iso.push(' ');
        }
        self.spans.push((self.iso.len(), span));
        self.iso.push_str(text);
    }

    /// The motion code the block needs, when the interpreter's differs or `always`.
    fn motion_code(&mut self, always: bool, mirrored: bool, span: std::ops::Range<usize>) {
        let mut m = self.motion;
        if mirrored && matches!(m, 2 | 3) {
            m = 5 - m;
        }
        if m <= 3 && (always || m != self.interp_motion) {
            self.push(&format!("G{m}"), span);
            self.interp_motion = m;
        }
    }

    /// The plane code for normal axis `k`, when the interpreter's plane differs.
    pub(super) fn plane_code(&mut self, k: usize, span: std::ops::Range<usize>) {
        if k != self.interp_normal {
            self.push(["G19", "G18", "G17"][k], span);
            self.interp_normal = k;
        }
    }

    /// The words as written, in the program's distance mode.
    fn written_words(&mut self, w: &Words, up: &str) {
        let span = first_span(w);
        if self.interp_absolute != self.absolute {
            self.push(if self.absolute { "G90" } else { "G91" }, span.clone());
            self.interp_absolute = self.absolute;
        }
        self.plane_code(self.normal, span.clone());
        self.motion_code(false, false, span);
        let letters = b"XYZABCUVWIJK";
        for (k, c) in w.axes.iter().chain(&w.centres).enumerate() {
            if let Some(c) = c {
                let text = match &c.raw {
                    Some(r) => up[r.clone()].to_string(),
                    None => number(c.value),
                };
                self.push(&format!("{}{text}", letters[k] as char), c.span.clone());
            }
        }
        if let Some((r, span)) = w.cr.clone() {
            self.push(&format!("R{}", number(r)), span);
        }
    }

    /// The words resolved through the frame and AC/IC to absolute work targets.
    fn computed_words(&mut self, w: &Words, line_no: usize) -> LineResult<()> {
        let span = first_span(w);
        if self.motion == super::state::CIP {
            return self.cip_words(w, span);
        }
        if self.motion == super::state::CT {
            return self.ct_words(w, span);
        }
        if w.turn.is_some() {
            return self.turn_words(w, line_no);
        }
        let p = self.interp.program_position();
        let work = [p[Axis::X], p[Axis::Y], p[Axis::Z]];
        let here = self.frame.frame_point(work);
        let arc = matches!(self.motion, 2 | 3);
        let (plane, scale, flip) = if arc {
            self.frame.arc_plane(self.normal).ok_or_else(|| {
                LineError::new(span.clone(), "an arc in a frame that tilts its plane off the work axes or stretches it unevenly: expected rotations in steps of 90 deg off the plane, and a uniform scale", "arc in a tilted frame")
                    .help("post the arc as lines, or program it without the frame")
            })?
        } else {
            (self.normal, 1.0, false)
        };
        self.push("G90", span.clone());
        self.interp_absolute = true;
        self.plane_code(plane, span.clone());
        self.motion_code(true, flip, span.clone());
        if w.axes[..3].iter().any(Option::is_some) {
            let mut q = here;
            for k in 0..3 {
                q[k] = Coordinate::resolve(&w.axes[k], here[k], self.absolute);
            }
            let t = self.frame.work_point(q);
            for (k, l) in ["X", "Y", "Z"].iter().enumerate() {
                self.push(&format!("{l}{}", number(t[k])), span.clone());
            }
        }
        for (k, axis) in Axis::ALL.iter().enumerate().skip(3) {
            if w.axes[k].is_some() {
                let v = Coordinate::resolve(&w.axes[k], p[*axis], self.absolute);
                self.push(&format!("{}{}", axis.letter(), number(v)), span.clone());
            }
        }
        if w.centres.iter().any(Option::is_some) {
            // Centres are incremental from the start unless AC().
            let mut c = here;
            for k in 0..3 {
                c[k] = Coordinate::resolve(&w.centres[k], here[k], false);
            }
            let c = self.frame.work_point(c);
            for (k, l) in ["I", "J", "K"].iter().enumerate() {
                if k != plane {
                    self.push(&format!("{l}{}", number(c[k] - work[k])), span.clone());
                }
            }
        }
        if let Some((r, span)) = w.cr.clone() {
            self.push(&format!("R{}", number(r * scale)), span);
        }
        Ok(())
    }
}

fn first_span(w: &Words) -> std::ops::Range<usize> {
    w.axes
        .iter()
        .chain(&w.centres)
        .flatten()
        .map(|c| c.span.clone())
        .next()
        .or_else(|| w.cr.as_ref().map(|c| c.1.clone()))
        .unwrap_or(0..0)
}
