//! Phase 0: the block's words checked against the modal state and the machine: G7/G8
//! (X as a diameter), the spindle selector `$`, axis words of axes the machine has, whole
//! numbers where a number is expected, and no word that no code uses.

use super::Interp;
use crate::axis::Axis;
use crate::block::{integer, letters, slot, Block};
use crate::code::{GCode, MotionMode, NonModal};
use crate::lex::{LineError, LineResult, Word};

impl Interp {
    /// Checks `b` and sets what its reading depends on (G7/G8 halves X from this block).
    pub(super) fn check_words(&mut self, b: &mut Block) -> LineResult<()> {
        // G7 (this block's or in effect): X words are diameters, everywhere X is read
        // (motion, G10, G92), as LinuxCNC halves them.
        for &(c, _) in b.g.iter() {
            if let GCode::Diameter(d) = c {
                self.diameter = d;
            }
        }
        b.halve_x = self.diameter;
        super::bolt::refuse_lathe_cycle(b)?;
        self.refuse_tool_vector(b)?;
        let line = b.line;
        if let Some(w) = b.spindle_select {
            if b.get('S').is_none() && !b.m.iter().any(|(c, _)| matches!(c, 3 | 4 | 5 | 19)) {
                return Err(LineError::new(
                    w.span(),
                    format!(
                        "`{}` with no spindle code: expected `$` only with M3, M4, M5, M19 or S",
                        &line[w.span()]
                    ),
                    "$ not used",
                ));
            }
        }
        self.check_machine_axes(b)?;
        // G41.1/G42.1 take the diameter itself in D, G96 the speed limit (rpm).
        let d_diameter = b.has_g(|c| matches!(c, GCode::CutterComp(3 | 4) | GCode::Control(960)));
        let integers: &[char] = if b.has_any(const { letters(&['N', 'T', 'H', 'D', 'L']) }) {
            &['N', 'T', 'H', 'D', 'L']
        } else {
            &[]
        };
        for &letter in integers {
            if letter == 'D' && d_diameter {
                continue;
            }
            if let Some(word) = b.get(letter) {
                integer(&word, line)?;
            }
        }
        if b.has_any(const { letters(&['P', 'Q', 'L', 'E', 'D']) }) {
            self.unused_words(line, &b.g, &b.m, &|l| b.get(l))?;
        }
        Ok(())
    }

    /// A word for an axis the machine has not is refused, never dropped.
    /// The axis a Fanuc-family lathe's incremental address moves: U is X and W is Z
    /// (G-code system A), on a lathe (a machine with X and Z but no Y, U or W); `None`
    /// otherwise (on a mill a U or W word for a missing axis stays an error).
    pub(super) fn lathe_increment(&self, a: Axis) -> Option<Axis> {
        let on = self.dialect.table().macro_b
            && !self.axes[a.index()]
            && !self.axes[Axis::Y.index()]
            && self.axes[Axis::X.index()]
            && self.axes[Axis::Z.index()];
        match a {
            Axis::U if on => Some(Axis::X),
            Axis::W if on => Some(Axis::Z),
            _ => None,
        }
    }

    pub(super) fn check_machine_axes(&self, b: &Block) -> LineResult<()> {
        let line = b.line;
        let missing_axes = Axis::ALL
            .iter()
            .filter(|a| !self.axes[a.index()])
            .fold(0, |m, a| m | 1 << slot(a.letter()));
        if !b.has_any(missing_axes) {
            return Ok(());
        }
        for a in Axis::ALL {
            if self.axes[a.index()] || self.lathe_increment(a).is_some() {
                continue;
            }
            if let Some(w) = b.get(a.letter()) {
                let has: Vec<String> = Axis::ALL
                    .iter()
                    .filter(|b| self.axes[b.index()])
                    .map(|b| b.letter().to_string())
                    .collect();
                return Err(LineError::new(w.span(), format!("`{}`: this machine has no {} axis (it has {})", &line[w.span()], a.letter(), has.join(" ")), "axis not on this machine")
                    .help(format!("run the program with a machine whose layout has a {} axis, or check the program is for this machine (a six-axis robot pose X Y Z A B C fits no machine mtsim models); a word for a missing axis is never dropped{}", a.letter(), if matches!(a, Axis::U | Axis::W) && self.dialect.table().macro_b { "; on a Fanuc or Haas lathe U and W are X and Z increments: run a lathe program with a lathe machine file (X and Z, no Y)" } else { "" })));
            }
        }
        Ok(())
    }

    /// A word no code of the block (or the modal motion) uses is an error, never dropped.
    pub(super) fn unused_words<'l>(
        &self,
        line: &str,
        g: &[(GCode, Word<'l>)],
        m: &[(u32, Word<'l>)],
        get: &dyn Fn(char) -> Option<Word<'l>>,
    ) -> LineResult<()> {
        // Most blocks have none of the words checked here: skip building the checks.
        if ['P', 'Q', 'L', 'E', 'D']
            .into_iter()
            .all(|l| get(l).is_none())
        {
            return Ok(());
        }
        let has_g = |f: &dyn Fn(&GCode) -> bool| g.iter().any(|(c, _)| f(c));
        let has_m = |codes: &[u32]| m.iter().any(|(c, _)| codes.contains(c));
        let motion = g
            .iter()
            .find_map(|(c, _)| match c {
                GCode::Motion(mm) => Some(*mm),
                _ => None,
            })
            .unwrap_or(self.motion);
        let cycle = matches!(motion, Some(MotionMode::Cycle(_)));
        let peck = matches!(motion, Some(MotionMode::Cycle(730 | 830)));
        let cubic = matches!(motion, Some(MotionMode::Spline(50)));
        let nurbs = matches!(motion, Some(MotionMode::Spline(52)));
        let dwell_cycle = matches!(
            motion,
            Some(MotionMode::Cycle(
                740 | 760 | 820 | 840 | 860 | 870 | 880 | 890
            ))
        );
        // G76/G87 (Haas G77) Q: the shift away from the bore wall.
        let shift_cycle = matches!(motion, Some(MotionMode::Cycle(760 | 770 | 870)));
        let table = self.dialect.table();
        // LinuxCNC G2/G3 P<turns>.
        let arc_turns =
            self.dialect.table().arc_turns && matches!(motion, Some(MotionMode::Arc { .. }));
        let g10 = has_g(&|c| matches!(c, GCode::NonModal(NonModal::G10)));
        // Haas G70/G71: L holes; P Q name the lathe's cycle, which the pattern refuses.
        let bolt =
            has_g(&|c| matches!(c, GCode::NonModal(NonModal::BoltCircle | NonModal::BoltArc)));
        // LinuxCNC passes P and Q to user M codes (M100-M199 programs, mapped codes).
        let user = m
            .iter()
            .any(|(c, _)| (100..=199).contains(c) || self.user_m.contains_key(c));
        let checks: [(char, bool, &str); 5] = [
            ('P', bolt || cubic || nurbs || has_g(&|c| matches!(c, GCode::NonModal(NonModal::Dwell) | GCode::Path(4) | GCode::CoordExtended | GCode::Control(80 | 1030 | 1870))) || g10 || dwell_cycle || has_m(&[19, 50, 51, 52, 53, 62, 63, 64, 65, 66, 97, 98, 99]) || user || arc_turns, "`P` with no code that uses it: expected P only with G02/G03 (turns), G04, G5, G5.2, G10, G64, G54.1, G82/G86/G89 (and G74/G76/G84/G87/G88 in the fanuc and haas dialects), M19, M50-M53, M62-M66, M98 or a user M code"),
            ('Q', bolt || has_g(&|c| matches!(c, GCode::Path(4) | GCode::Control(51))) || peck || shift_cycle || cubic || has_m(&[19, 61, 66, 67, 68]) || user, "`Q` with no code that uses it: expected Q only with G5, G64, G73/G83 (and G76/G87, Haas G77), M19, M61, M66-M68 or a user M code"),
            ('L', bolt || g10 || cycle || nurbs || has_m(&[66, 97, 98]) || has_g(&|c| matches!(c, GCode::CutterComp(3 | 4))), "`L` with no code that uses it: expected L only with G10, G5.2, a canned cycle, G41.1/G42.1, M66 or M98"),
            ('E', has_m(&[66, 67, 68]) || has_g(&|c| matches!(c, GCode::Control(1870))), "`E` with no code that uses it: expected E only with M66-M68 or G187"),
            ('D', table.offset_words_alone || has_g(&|c| matches!(c, GCode::CutterComp(1..=4) | GCode::Control(960))), "`D` with no code that uses it: expected D only with G41, G42, G41.1, G42.1 or G96 (in the fanuc and haas dialects, D also stands alone)"),
        ];
        for (letter, ok, message) in checks {
            if let Some(w) = get(letter) {
                if !ok {
                    return Err(
                        LineError::new(w.span(), message, format!("{letter} not used")).help(
                            format!("remove `{}` or add the code that uses it", &line[w.span()]),
                        ),
                    );
                }
            }
        }
        Ok(())
    }
}

impl Interp {
    /// Fanuc G43.5 programs the tool axis as a vector I J K in its blocks (tool-centre point
    /// type 2), which mtsim does not read: its I J K are refused by that meaning, not as arc
    /// words. G43.4, G49 and the TCP cancels end the mode.
    fn refuse_tool_vector(&mut self, b: &Block) -> LineResult<()> {
        for (c, w) in b.g.iter() {
            match c {
                GCode::Tcp(true) => self.tool_vector = (w.value - 43.5).abs() < 1e-9,
                GCode::Tcp(false) | GCode::ToolLength(_) => self.tool_vector = false,
                _ => {}
            }
        }
        if !self.tool_vector {
            return Ok(());
        }
        let arc = |m: Option<MotionMode>| matches!(m, Some(MotionMode::Arc { .. }));
        let motion = b.g.iter().find_map(|(c, _)| match c {
            GCode::Motion(m) => Some(*m),
            _ => None,
        });
        if arc(motion.unwrap_or(self.motion)) {
            return Ok(());
        }
        match ['I', 'J', 'K'].into_iter().find_map(|l| b.get(l)) {
            Some(w) => Err(LineError::new(
                w.span(),
                format!("`{}` under G43.5: Fanuc's tool-axis direction vector (I J K), which mtsim does not read", &b.line[w.span()]),
                "tool direction vector",
            )
            .help("post the tool direction as rotary-axis angles under G43.4")),
            None => Ok(()),
        }
    }
}
