//! Phase 7, motion: the motion mode (G0-G3, G5.x, G33/G33.1, G38.x, the canned cycles;
//! G80 cancels), the axis words it moves to (polar words resolved), the checks every motion
//! shares (a feed in effect, G53, compensation, rotated and tilted frames), and the move of
//! each mode, dispatched to its file.

use std::collections::VecDeque;
use std::ops::Range;

use super::arcs::{turns, TiltedArc};
use super::Interp;
use crate::axis::{Axis, Plane};
use crate::block::{letters, slot, Block, Small};
use crate::canon::{Motion, Move};
use crate::code::{FeedRead, GCode, MotionMode, NonModal};
use crate::lex::{LineError, LineResult, Word};

impl Interp {
    /// The block's motion code becomes the motion mode (a G38.x needs its point); returns
    /// the mode before the block.
    pub(super) fn motion_mode(&mut self, b: &Block) -> LineResult<Option<MotionMode>> {
        let motion_code = b.motion_code();
        if let Some((Some(MotionMode::Probe(_)), w)) = motion_code {
            let any_axis = Axis::ALL.iter().any(|a| b.get(a.letter()).is_some());
            if !any_axis && b.get('@').is_none() && b.get('^').is_none() {
                return Err(LineError::new(
                    w.span(),
                    format!("`{}` without axis words: expected the probe point (LinuxCNC: \"All axes missing with motion code\")", &b.line[w.span()]),
                    "no probe point",
                ));
            }
        }
        let previous_motion = self.motion;
        if let Some((mm, _)) = motion_code {
            self.motion = mm;
            match mm {
                Some(MotionMode::Rapid | MotionMode::Linear | MotionMode::Arc { .. }) => {
                    self.interpolation = mm;
                }
                // Fanuc family: G80 leaves group 01's G00-G03 in effect.
                None if self.dialect.table().g80_keeps_motion => self.motion = self.interpolation,
                _ => {}
            }
            // The initial level of a row of cycles is kept until a motion that is not one.
            if !matches!(mm, Some(MotionMode::Cycle(_))) {
                self.cycle_initial = None;
            }
        }
        Ok(previous_motion)
    }

    /// The block's axis words in [`Axis::ALL`] order: polar words `@` `^` become X Y here,
    /// after the block's units and work system took effect (in a G91 canned cycle they step
    /// each repeat, see `cycle`); X is a diameter under G7; G4 X is a time, not an axis.
    pub(super) fn axis_words(&mut self, b: &mut Block) -> LineResult<()> {
        b.polar_word = if b.has_any(const { letters(&['@', '^']) }) {
            b.get('@').or(b.get('^'))
        } else {
            None
        };
        if let Some(pw) = b.polar_word {
            let mut xy = [None, None];
            let nonmodal = b.nonmodal();
            b.polar_cycle = self.polar_words(b.line, &pw, &|l| b.get(l), nonmodal, &mut xy)?;
            b.polar = Some(xy);
        }
        let dwell_x = self.dialect.table().dwell_x_seconds
            && matches!(b.nonmodal(), Some((NonModal::Dwell, _)));
        let mut axis: Small<(Axis, Word), 9> = Small::new();
        let increments = self.lathe_increments(b)?;
        for a in Axis::ALL {
            if let Some(w) = increments[a.index()] {
                axis.push_axis(a, &w, false);
                continue;
            }
            if self.lathe_increment(a).is_some() {
                continue;
            }
            let mut halve = false;
            let k = slot(a.letter());
            let w = match (a, &b.polar) {
                (Axis::X, Some([Some(x), _])) => x,
                (Axis::Y, Some([_, Some(y)])) => y,
                _ if b.present >> k & 1 == 1 => {
                    // X is a diameter under G7.
                    halve = b.halve_x && a == Axis::X;
                    b.at_slot(k)
                }
                _ => continue,
            };
            if !(dwell_x && a == Axis::X) {
                axis.push_axis(a, w, halve);
            }
        }
        b.axis = axis;
        Ok(())
    }

    /// A Fanuc-family lathe's U and W words (incremental X and Z, [`Interp::lathe_increment`])
    /// as the X and Z words they stand for: `X = x + U` under G90, `X = U` under G91, with x
    /// the program position; an error beside an X (Z) word of the same block.
    fn lathe_increments<'l>(&self, b: &Block<'l>) -> LineResult<[Option<Word<'l>>; 9]> {
        let mut out = [None; 9];
        for inc in [Axis::U, Axis::W] {
            let (Some(axis), Some(w)) = (self.lathe_increment(inc), b.get(inc.letter())) else {
                continue;
            };
            if let Some(x) = b.get(axis.letter()) {
                return Err(LineError::new(
                    x.span(),
                    format!(
                        "`{}` beside `{}` (its increment on a lathe): expected one of them",
                        &b.line[x.span()],
                        &b.line[w.span()]
                    ),
                    "both",
                ));
            }
            let value = if self.absolute {
                self.program_position()[axis] + w.value
            } else {
                w.value
            };
            out[axis.index()] = Some(Word {
                letter: axis.letter(),
                value,
                number: "",
                ..w
            });
        }
        Ok(out)
    }

    /// Phase 7: NURBS control points, then the move of the motion mode when the block has
    /// axis (or arc, or polar cycle) words no other code used.
    pub(super) fn motion(
        &mut self,
        b: &mut Block,
        previous_motion: Option<MotionMode>,
        line_no: usize,
        queue: &mut VecDeque<Move>,
    ) -> LineResult<()> {
        let mut arc_buf = [Word::EMPTY; 4];
        let mut n_arc = 0;
        // M19 R is the spindle orientation angle, not an arc radius.
        let m19 = b.has_m(19);
        let arc_letters: &[char] = if b.has_any(const { letters(&['I', 'J', 'K', 'R']) }) {
            &['I', 'J', 'K', 'R']
        } else {
            &[]
        };
        for &l in arc_letters {
            if l == 'R' && m19 {
                continue;
            }
            if let Some(w) = b.get(l) {
                arc_buf[n_arc] = w;
                n_arc += 1;
            }
        }
        let arc_words = &arc_buf[..n_arc];
        // NURBS: G5.2 blocks collect control points, G5.3 moves along them.
        let nurbs_end =
            b.g.iter()
                .find(|(c, _)| matches!(c, GCode::NurbsEnd))
                .map(|(_, w)| *w);
        if nurbs_end.is_some() || self.motion == Some(MotionMode::Spline(52)) {
            let g52 = b.motion_code().map(|(_, w)| w);
            let bb = &*b;
            if self.nurbs_block(
                bb.line,
                &|l| bb.get(l),
                nurbs_end,
                g52,
                previous_motion,
                &bb.axis,
                line_no,
                queue,
            )? {
                b.axes_used = true;
            }
        }
        let moves = !b.axis.is_empty()
            || b.polar_cycle
            || (!arc_words.is_empty() && !matches!(self.motion, Some(MotionMode::Cycle(_))));
        if b.axes_used || !moves {
            return Ok(());
        }
        let mut first = b.polar_word.map_or(usize::MAX..usize::MAX, |w| w.span());
        for w in b.axis.iter().map(|(_, w)| w).chain(arc_words.iter()) {
            if w.span.0 < first.start {
                first = w.span();
            }
        }
        let (mode, at) = self.motion_checks(b, arc_words, first.clone())?;
        self.move_in_mode(b, mode, at, first, line_no, queue)
    }

    /// The checks every move makes before its mode's own: returns the mode and the span
    /// errors point at (the motion code, else the first axis word).
    pub(super) fn motion_checks(
        &mut self,
        b: &Block,
        arc_words: &[Word],
        first: Range<usize>,
    ) -> LineResult<(MotionMode, Range<usize>)> {
        let line = b.line;
        let g53 = matches!(b.nonmodal(), Some((NonModal::G53, _)));
        let Some(mode) = self.motion else {
            return Err(LineError::new(first, "axis word with no motion mode: expected G00, G01, G02 or G03 in this or an earlier block", "no motion mode"));
        };
        if !matches!(mode, MotionMode::Arc { .. }) {
            if let Some(w) = arc_words.iter().find(|w| {
                !(matches!(mode, MotionMode::Cycle(_)) && w.letter == 'R')
                    // Fanuc and Haas: a canned cycle's K is its repeat count.
                    && !(matches!(mode, MotionMode::Cycle(_)) && w.letter == 'K' && self.dialect.table().macro_b)
                    // Back boring's shift I J (K).
                    && !(matches!(mode, MotionMode::Cycle(c) if self.is_back_bore(c)))
                    && !(matches!(mode, MotionMode::SpindleSync(_)) && w.letter == 'K')
                    && !(matches!(mode, MotionMode::Spline(_)) && matches!(w.letter, 'I' | 'J'))
            }) {
                return Err(LineError::new(
                    w.span(),
                    format!(
                        "`{}` outside an arc: expected I J K R only with G02 or G03",
                        &line[w.span()]
                    ),
                    "not an arc",
                ));
            }
        }
        if g53 && !matches!(mode, MotionMode::Rapid | MotionMode::Linear) {
            return Err(LineError::new(
                first,
                "G53 with an arc or cycle: expected G53 only with G00 or G01",
                "G53 motion",
            ));
        }
        if g53 && !self.absolute && !self.dialect.table().g53_absolute_in_g91 {
            return Err(LineError::new(
                first,
                "G53 in G91: expected G53 only in absolute mode (G90)",
                "G53 incremental",
            ));
        }
        let at = b
            .motion_code()
            .map(|(_, w)| w.span())
            .unwrap_or(first.clone());
        if let MotionMode::Probe(_) = mode {
            // The probe's own checks, in LinuxCNC's order.
            let refuse = if self.feed_mode == FeedRead::InverseTime {
                Some("probe move in G93 (inverse time): expected G94 (LinuxCNC: \"Cannot probe with zero feed rate\")")
            } else if self.comp.is_some() {
                Some("probe move with cutter radius compensation on: expected G40 first (LinuxCNC: \"Cannot probe with cutter radius comp on\")")
            } else {
                None
            };
            if let Some(m) = refuse {
                return Err(LineError::new(at, m, "not a probe"));
            }
        }
        if !matches!(mode, MotionMode::Rapid | MotionMode::SpindleSync(_)) {
            self.feed_in_effect(b, at.clone())?;
        }
        self.frame_checks(mode, g53, at.clone())?;
        Ok((mode, at))
    }

    /// A feed move needs a feed: F in this block under G93, S under G95, F > 0 otherwise.
    pub(super) fn feed_in_effect(&self, b: &Block, at: Range<usize>) -> LineResult<()> {
        match self.feed_mode {
            FeedRead::InverseTime if b.feed_word.is_none() => {
                Err(LineError::new(at, "feed move in G93 (inverse time) without F: expected an F word in every G01/G02/G03 block", "no F in this block").help("add F = 1 / (block time in minutes) to this block"))
            }
            FeedRead::PerRevolution if !self.turns_per_minute_known() => {
                Err(LineError::new(at, "feed per revolution (G95; G99 on a Fanuc or Haas lathe) with the spindle speed zero: expected an S word", "no S"))
            }
            _ if self.feed.is_none() || self.feed == Some(0.0) => {
                Err(LineError::new(at, "feed move with no feed programmed (or F0): expected a positive F word (mm/min) in this or an earlier block", "no F in effect").help("add F, e.g. `F1000` for 1000 mm/min"))
            }
            _ => Ok(()),
        }
    }

    /// What a mode may not do under compensation, after G40, in a rotated work system or a
    /// tilted frame.
    pub(super) fn frame_checks(
        &mut self,
        mode: MotionMode,
        g53: bool,
        at: Range<usize>,
    ) -> LineResult<()> {
        if self.comp.as_ref().is_some_and(|c| {
            g53 || matches!(mode, MotionMode::Cycle(_) | MotionMode::SpindleSync(_))
                || self.plane != c.plane
        }) {
            return Err(LineError::new(at, "G53, a canned cycle or a change of plane with cutter radius compensation on: expected G40 first", "not with compensation"));
        }
        match mode {
            MotionMode::Arc { .. } if self.arc_not_allowed => {
                return Err(LineError::new(at, "the move just after exiting cutter compensation mode must be straight, not an arc: expected a G00 or G01 move after G40", "arc after G40"));
            }
            MotionMode::Rapid | MotionMode::Linear => self.arc_not_allowed = false,
            _ => {}
        }
        if self.rotation.is_some()
            && !g53
            && (matches!(mode, MotionMode::Cycle(_) | MotionMode::SpindleSync(_))
                || (matches!(mode, MotionMode::Arc { .. }) && self.plane != Plane::XY))
        {
            return Err(LineError::new(
                at,
                "canned cycle, or arc outside G17, in a rotated work system (G68, or G10 L2 R): not supported yet",
                "rotated work system",
            )
            .help("cancel the rotation first (G69, or G10 L2 P0 R0)"));
        }
        if self.frame().is_some()
            && matches!(mode, MotionMode::Cycle(_) | MotionMode::SpindleSync(_))
        {
            return Err(LineError::new(
                at,
                "canned cycle with G68.2 or G254 active: not supported yet",
                "cycle in a tilted frame",
            )
            .help("post the holes as G00/G01 moves"));
        }
        Ok(())
    }

    /// The move of `mode`, to the block's axis words.
    pub(super) fn move_in_mode(
        &mut self,
        b: &Block,
        mode: MotionMode,
        at: Range<usize>,
        first: Range<usize>,
        line_no: usize,
        queue: &mut VecDeque<Move>,
    ) -> LineResult<()> {
        let line = b.line;
        let g53 = matches!(b.nonmodal(), Some((NonModal::G53, _)));
        let get = |l: char| b.get(l);
        let start = self.pos;
        match mode {
            MotionMode::Cycle(code) => self.cycle(line, code, &get, line_no, queue, first),
            MotionMode::SpindleSync(code) => {
                let target = self.target(&b.axis, g53);
                self.spindle_sync(line, code, &get, line_no, queue, at, target)
            }
            MotionMode::Spline(code) => {
                let target = self.target(&b.axis, g53);
                self.spline(line, code, &get, line_no, queue, start, target, at)
            }
            MotionMode::Probe(code) => {
                let target = self.target(&b.axis, g53);
                self.probe(queue, line_no, code, start, target)
                    .map_err(|m| LineError::new(at, m, "probe move"))
            }
            MotionMode::Rapid | MotionMode::Linear | MotionMode::Arc { .. } => {
                self.straight_or_arc(b, mode, g53, at, line_no, queue)
            }
        }
    }

    /// G0, G1, or G2/G3 (of several turns with LinuxCNC's P), straight or through the
    /// cutter compensation queue.
    pub(super) fn straight_or_arc(
        &mut self,
        b: &Block,
        mode: MotionMode,
        g53: bool,
        at: Range<usize>,
        line_no: usize,
        queue: &mut VecDeque<Move>,
    ) -> LineResult<()> {
        let line = b.line;
        let get = |l: char| b.get(l);
        let start = self.pos;
        let target = self.target(&b.axis, g53);
        let motion = match mode {
            MotionMode::Linear => Motion::Linear,
            MotionMode::Arc { clockwise } if self.frame().is_some() => {
                match self.tilted_arc(line, &get, b.words, clockwise, target, at.clone())? {
                    TiltedArc::Canonical(m) => m,
                    TiltedArc::Chords(points) => {
                        let mut from = start;
                        for p in points.into_iter().chain(std::iter::once(target)) {
                            self.emit(queue, line_no, Motion::Linear, from, p, self.path);
                            from = p;
                        }
                        self.pos = target;
                        return Ok(());
                    }
                }
            }
            MotionMode::Arc { clockwise } => {
                let center_mm = self.arc_center(line, &get, b.words, clockwise, start, target)?;
                Motion::Arc {
                    clockwise,
                    plane: self.plane,
                    center_mm,
                }
            }
            _ => Motion::Rapid,
        };
        let turns = match motion {
            Motion::Arc { .. } => match get('P') {
                Some(p) => turns(line, &p, self.feed_mode)?,
                None => 1,
            },
            _ => 1,
        };
        if self.comp.is_some() && turns > 1 {
            return Err(LineError::new(
                at,
                "an arc of several turns (P) under cutter radius compensation: not supported",
                "turns with compensation",
            ));
        }
        if self.frame().is_some() && turns > 1 {
            return Err(LineError::new(
                at,
                "an arc of several turns (P) with G68.2 or G254 active: not supported",
                "turns in a tilted frame",
            ));
        }
        if self.comp.is_some() {
            self.comp_element(queue, line_no, motion, start, target)
                .map_err(|m| LineError::new(at, m, "cutter compensation"))?;
        } else {
            let mut from = start;
            // The intermediate full turns' ends, only for several turns.
            let ends = if turns > 1 {
                crate::turns::full_turn_ends(motion, start, target, turns)
            } else {
                Vec::new()
            };
            for end in ends {
                self.emit(queue, line_no, motion, from, end, self.path);
                from = end;
            }
            self.emit(queue, line_no, motion, from, target, self.path);
        }
        self.pos = target;
        Ok(())
    }

    /// The block when it is a plain move: at most one `G0`/`G1` (written `0`, `00`, `1` or
    /// `01`), axis words of this machine's axes, at most one of each, and `F`, in a plain
    /// modal state (no cutter compensation, tilted or rotated frame, or diameter mode; a
    /// modal G0 or G1 when the block has no G word). It is interpreted as
    /// [`Interp::block`] would, step for step (feed, motion mode, target, move), without the
    /// checks and lookups of every other feature: most blocks of most programs. Returns
    /// false, having changed nothing, for any other block, and for one the general path
    /// would refuse (a negative F, a feed move with no feed), which then reports the error.
    pub(super) fn plain_move(
        &mut self,
        words: &[Word],
        line_no: usize,
        queue: &mut VecDeque<Move>,
    ) -> bool {
        if self.comp.is_some()
            || self.surface_speed.is_some()
            || self.lathe_cycle.is_some()
            || (!self.feed_mode_stated && self.is_lathe())
            || self.diameter
            || self.rotation.is_some()
            || self.tilt.is_some()
            || self.dwo
            || !self.units_stated
        {
            return false;
        }
        const NONE: u8 = u8::MAX;
        let mut axis_at = [NONE; 9];
        let (mut g, mut f) = (None, None);
        for (k, w) in words.iter().enumerate() {
            let axis = match w.letter {
                'G' if g.is_none() => {
                    g = Some(match w.number {
                        "1" | "01" => MotionMode::Linear,
                        "0" | "00" => MotionMode::Rapid,
                        _ => return false,
                    });
                    continue;
                }
                'F' if f.is_none() => {
                    f = Some(w);
                    continue;
                }
                'X' => Axis::X,
                'Y' => Axis::Y,
                'Z' => Axis::Z,
                'A' => Axis::A,
                'B' => Axis::B,
                'C' => Axis::C,
                _ => return false,
            };
            if axis_at[axis.index()] != NONE || !self.axes[axis.index()] {
                return false;
            }
            axis_at[axis.index()] = k as u8;
        }
        let mode = match (g, self.motion) {
            (Some(mode), _) => mode,
            (None, Some(mode @ (MotionMode::Rapid | MotionMode::Linear))) => mode,
            _ => return false,
        };
        if axis_at == [NONE; 9] {
            return false;
        }
        let feed = match f {
            Some(f) if f.value < 0.0 => return false,
            // (No G20/G21 here: the scale before and after the block's units is the same.)
            Some(f) => (f.value > 0.0).then(|| match self.feed_mode {
                FeedRead::InverseTime => f.value,
                _ => f.value * self.scale(),
            }),
            None => self.feed,
        };
        if mode == MotionMode::Linear {
            let refused = match self.feed_mode {
                FeedRead::InverseTime if f.is_none() => true,
                FeedRead::PerRevolution if self.spindle_rpm == 0.0 => true,
                _ => feed.is_none() || feed == Some(0.0),
            };
            if refused {
                return false;
            }
        }
        if f.is_some() {
            self.feed = feed;
        }
        if g.is_some() {
            self.motion = Some(mode);
            self.cycle_initial = None;
        }
        self.arc_not_allowed = false;
        let mut axis_words: Small<(Axis, Word), 9> = Small::new();
        for a in Axis::ALL {
            if let Some(w) = words.get(axis_at[a.index()] as usize) {
                axis_words.push_axis(a, w, false);
            }
        }
        let start = self.pos;
        let target = self.target(&axis_words, false);
        let motion = match mode {
            MotionMode::Linear => Motion::Linear,
            _ => Motion::Rapid,
        };
        self.emit(queue, line_no, motion, start, target, self.path);
        self.pos = target;
        true
    }
}
