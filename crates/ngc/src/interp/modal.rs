//! Phases 1 and 5: the modal groups. Phase 1 sets the feed mode, the units F is read in,
//! F and S; phase 5 sets plane, units, cutter radius compensation, tool length (and TCP),
//! work system, path control, distance modes, retract mode, the G68.2 tilted plane with
//! G53.1, and G254.

use std::collections::VecDeque;

use super::Interp;
use crate::axis::{Axis, Plane};
use crate::block::Block;
use crate::canon::{Motion, Move, PathControl};
use crate::code::{FeedRead, GCode, NonModal};
use crate::comp;
use crate::frame;
use crate::lex::{LineError, LineResult, Word};

impl Interp {
    /// Phase 1: G20/G21 and G93/G94/G95, then F (in the units the dialect reads it in) and
    /// S.
    pub(super) fn feed_and_speed(&mut self, b: &mut Block) -> LineResult<()> {
        let line = b.line;
        let scale_before_units = self.scale();
        for &(c, _) in b.g.iter() {
            if let GCode::Units(inch) = c {
                self.inch = inch;
                self.units_stated = true;
            }
        }
        for &(c, _) in b.g.iter() {
            if let GCode::Feed(mode) = c {
                self.feed_mode_stated = true;
                if mode != self.feed_mode {
                    self.feed = None;
                }
                self.feed_mode = mode;
            }
        }
        if let Some(f) = b.get('F') {
            if f.value < 0.0 {
                return Err(LineError::new(
                    f.span(),
                    format!("`{}`: expected a feed of zero or more", &line[f.span()]),
                    "negative feed",
                ));
            }
            // F0 is accepted, as LinuxCNC does (a subroutine may restore a saved F of 0);
            // a feed move at F0 is then refused like one with no F at all.
            let units_scale = if self.dialect.table().feed_before_units {
                scale_before_units
            } else {
                self.scale()
            };
            self.feed = (f.value > 0.0).then(|| match self.feed_mode {
                FeedRead::InverseTime => f.value,
                _ => f.value * units_scale,
            });
            b.feed_word = Some(f);
        }
        if let Some(s) = b.get('S') {
            if s.value < 0.0 {
                return Err(LineError::new(
                    s.span(),
                    "negative spindle speed: expected S zero or more",
                    "negative",
                ));
            }
        }
        self.spindle_mode(b)?;
        Ok(())
    }

    /// Phase 5: the modal codes of the block, in the block's order, then G53.1 and the
    /// checks that span groups (TCP and a tilted frame; H only with a code that reads it).
    pub(super) fn modal_groups(
        &mut self,
        b: &Block,
        line_no: usize,
        queue: &mut VecDeque<Move>,
    ) -> LineResult<()> {
        if let (true, Some(d)) = (self.dialect.table().offset_words_alone, b.get('D')) {
            if !b.has_g(|c| matches!(c, GCode::CutterComp(3 | 4) | GCode::Control(960))) {
                self.d_register = Some(d.value.round() as u32);
            }
        }
        for &(c, w) in b.g.iter() {
            match c {
                GCode::Plane(p) => {
                    if self.rotation_2d.is_some() && p != self.plane {
                        return Err(LineError::new(w.span(), format!("`{}` while G68 rotates the coordinates: the plane may not change in a rotation", &b.line[w.span()]), "plane change under G68").help("cancel the rotation with G69 first"));
                    }
                    self.plane = p
                }
                GCode::Units(inch) => self.inch = inch,
                GCode::CutterComp(0) => {
                    self.comp_exit(queue)
                        .map_err(|m| LineError::new(w.span(), m, "cutter compensation"))?;
                }
                GCode::CutterComp(k) => self.cutter_comp_on(b, k, w)?,
                GCode::ToolLength(kind) => self.tool_length(b, kind, w)?,
                GCode::Tcp(on) => {
                    if on {
                        self.tcp = true;
                    } else {
                        self.tcp_cancel();
                    }
                    if let Some(h) = b.get('H') {
                        let t = self.tool_entry(h.value.round() as u32, &h)?;
                        self.tool_length_mm = t.length_mm;
                    }
                }
                GCode::Coord(n) => {
                    self.coord = n;
                    self.params.numbered[5220] = n as f64;
                    self.parameters_changed();
                }
                GCode::CoordExtended => self.coord_extended(b, w)?,
                GCode::Path(k) => {
                    self.path = match k {
                        0 => PathControl::ExactPath,
                        1 => PathControl::ExactStop,
                        _ => PathControl::Blend {
                            tolerance_mm: b.get('P').map(|p| p.value * self.scale()),
                            naive_cam_mm: b.get('Q').map(|q| q.value * self.scale()),
                        },
                    }
                }
                GCode::Distance(abs) => self.absolute = abs,
                GCode::ArcDistance(abs) => self.arc_absolute = abs,
                GCode::Retract(r) => self.retract_r = r,
                GCode::Control(1870) => {
                    // Haas G187: E is the corner rounding tolerance; without E, the
                    // control's default (no tolerance given).
                    self.path = PathControl::Blend {
                        tolerance_mm: b.get('E').map(|e| e.value * self.scale()),
                        naive_cam_mm: None,
                    };
                }
                GCode::Tilt(true) => self.tilt_on(b)?,
                GCode::Tilt(false) => {
                    self.tilt = None;
                    if self.rotation_2d.take().is_some() {
                        self.parameters_changed();
                    }
                }
                GCode::Rotate2d => self.rotate_on(b, w)?,
                GCode::Dwo(on) => {
                    if on && self.table.is_none() {
                        return Err(LineError::new(w.span(), "G254 on a machine without a rotary table: expected a table-table AC or BC machine", "no rotary table"));
                    }
                    self.dwo = on;
                }
                _ => {}
            }
        }
        if let Some((_, w)) = b.g.iter().find(|(c, _)| matches!(c, GCode::AlignRotary)) {
            self.align_rotary(b, *w, line_no, queue)?;
        }
        if self.tcp && self.frame().is_some() {
            let w = b.g.first().map_or(Word::EMPTY, |(_, w)| *w);
            return Err(LineError::new(
                w.span(),
                "tool-centre-point control with G68.2 or G254 active: expected one at a time",
                "TCP in a tilted frame",
            )
            .help(
                "cancel G68.2 with G69 (G254 with G255) before G43.4/G234, or TCP with G49 first",
            ));
        }
        if let Some(h) = b.get('H') {
            let alone = self.dialect.table().offset_words_alone
                && !b.has_g(|c| matches!(c, GCode::ToolLength(_) | GCode::Tcp(true)));
            if alone {
                // Fanuc family: H alone changes the length offset while G43/G44 is in
                // effect (the sign of the offset in effect kept), and is kept otherwise.
                let t = self.tool_entry(h.value.round() as u32, &h)?;
                if self.tool_length_mm != 0.0 {
                    self.tool_length_mm = t.length_mm.copysign(self.tool_length_mm);
                }
                return Ok(());
            }
            let used = b.has_g(|c| {
                matches!(c, GCode::ToolLength(_) | GCode::Tcp(true))
                    || matches!(c, GCode::NonModal(NonModal::G10))
            });
            if !used {
                return Err(LineError::new(
                    h.span(),
                    "`H` without G43: expected H only with G43, G43.2, G44 or a TCP code",
                    "H without G43",
                ));
            }
        }
        Ok(())
    }

    /// G41/G42 (`k` 1, 2: D the tool number) or G41.1/G42.1 (3, 4: D the diameter, L the
    /// lathe tool orientation).
    pub(super) fn cutter_comp_on(&mut self, b: &Block, k: u32, w: Word) -> LineResult<()> {
        let line = b.line;
        if self.comp.is_some() {
            return Err(LineError::new(
                w.span(),
                "cutter radius compensation turned on while it is on: expected G40 first",
                "compensation already on",
            ));
        }
        if self.plane == Plane::YZ {
            return Err(LineError::new(
                w.span(),
                "cutter radius compensation in G19: expected the XY plane (G17) or, for a lathe, the ZX plane (G18)",
                "not G17 or G18",
            ));
        }
        if self.frame().is_some() {
            return Err(LineError::new(
                w.span(),
                "cutter radius compensation with G68.2 or G254 active: not supported",
                "compensation in a tilted frame",
            ));
        }
        let d = b.get('D');
        let mut orientation = 0;
        if let (true, Some(l)) = (k >= 3, b.get('L')) {
            if self.plane != Plane::ZX {
                return Err(LineError::new(l.span(), format!("`{}` with L (lathe tool orientation) but the plane is not G18: expected G18", &line[w.span()]), "not G18"));
            }
            if !(0.0..=9.0).contains(&l.value) || l.value.fract() != 0.0 {
                return Err(LineError::new(
                    l.span(),
                    "lathe tool orientation out of range: expected L0 to L9",
                    "not 0-9",
                ));
            }
            orientation = l.value as u32;
        }
        let diameter = if k >= 3 {
            let d = d.ok_or_else(|| {
                LineError::new(
                    w.span(),
                    format!("`{}` without D: expected D<diameter>", &line[w.span()]),
                    "no D",
                )
            })?;
            d.value * self.scale()
        } else {
            let n = d.map_or(self.d_register.unwrap_or(self.tool), |d| {
                d.value.round() as u32
            });
            orientation = self.orientations.get(&n).copied().unwrap_or(0);
            if self.plane != Plane::ZX && !matches!(orientation, 0 | 9) {
                return Err(LineError::new(w.span(), format!("`{}` with a lathe tool (orientation {orientation}) but the plane is not G18: expected G18", &line[w.span()]), "not G18"));
            }
            self.tool_entry(n, &d.unwrap_or(w))?.diameter_mm
        };
        // A negative diameter puts the tool on the other side (LinuxCNC).
        let left = (k % 2 == 1) != (diameter < 0.0);
        self.comp = Some(comp::Comp::new(
            left,
            diameter.abs() / 2.0,
            orientation,
            self.plane,
            self.pos,
            self.comp_out.unwrap_or(self.pos),
            self.scale(),
        ));
        Ok(())
    }

    /// G43 (`kind` 0), G43.1 (1), G43.2 (2), G44 (4), G49 (9).
    pub(super) fn tool_length(&mut self, b: &Block, kind: u32, w: Word) -> LineResult<()> {
        let line = b.line;
        let h = b.get('H');
        match kind {
            0 | 4 => {
                let n = h.map_or(self.tool, |h| h.value.round() as u32);
                let t = self.tool_entry(n, &h.unwrap_or(w))?;
                self.tool_length_mm = if kind == 4 { -t.length_mm } else { t.length_mm };
            }
            1 => {
                // LinuxCNC offsets any axis by its word; mtsim applies a tool
                // length along Z only, so another axis word is refused, not dropped.
                if let Some(o) = Axis::ALL
                    .iter()
                    .filter(|a| **a != Axis::Z)
                    .find_map(|a| b.get(a.letter()))
                {
                    return Err(LineError::new(
                        o.span(),
                        format!("`{}` in a G43.1 block: expected only Z (mtsim applies the tool length offset along Z only)", &line[o.span()]),
                        "offset not along Z",
                    ));
                }
                let z = b.get('Z').ok_or_else(|| {
                    LineError::new(
                        w.span(),
                        "G43.1 without Z: expected `G43.1 Z<length>`",
                        "no Z",
                    )
                })?;
                self.tool_length_mm = z.value * self.scale();
            }
            2 => {
                let h = h.ok_or_else(|| {
                    LineError::new(
                        w.span(),
                        "G43.2 without H: expected `G43.2 H<tool>`",
                        "no H",
                    )
                })?;
                let t = self.tool_entry(h.value.round() as u32, &h)?;
                self.tool_length_mm += t.length_mm;
            }
            _ => {
                if self.dialect.table().g49_cancels_tcp {
                    self.tcp_cancel();
                }
                self.tool_length_mm = 0.0;
            }
        }
        Ok(())
    }

    /// TCP off (G49 on the Fanuc family, M129 / `FUNCTION RESET TCPM`, `TRAFOOF`): every
    /// control's manual has the current point become where the axes are (Fanuc: the
    /// absolute coordinates are updated to the axes' positions, Heidenhain and Sinumerik:
    /// the display shows the axes' positions without the transformation), so the next
    /// block moves only the axes it programs. With the rotaries turned that point is not
    /// the tip's: `pos ← K(pos, L)`, the machine's TCP transform
    /// ([`crate::Options::tcp_axes`]), taken with the tool length still in effect.
    pub(super) fn tcp_cancel(&mut self) {
        if !self.tcp {
            return;
        }
        self.tcp = false;
        if let Some(k) = &self.tcp_axes {
            self.pos = (k.0)(&self.pos, self.tool_length_mm);
        }
    }

    /// G54.1 P / G154 P: extended work offsets P1-P99.
    pub(super) fn coord_extended(&mut self, b: &Block, w: Word) -> LineResult<()> {
        let p = b.get('P').ok_or_else(|| {
            LineError::new(
                w.span(),
                "extended work offset without P: expected `P1` to `P99`",
                "no P",
            )
        })?;
        let n = p.value.round();
        if !(1.0..=99.0).contains(&n) {
            return Err(LineError::new(
                p.span(),
                "extended work offset number: expected P1 to P99",
                "out of range",
            ));
        }
        self.coord = 9 + n as u32;
        self.parameters_changed();
        Ok(())
    }

    /// G68 X Y R (Fanuc and Haas): the program's X Y turn by R degrees (counter-clockwise
    /// seen from +Z) about the centre (X, Y), given absolute in the work system, the current
    /// position where a word is left out:
    ///
    /// ```text
    /// machine X Y = offset + c + Rot(R) (p − c)
    /// ```
    ///
    /// R is absolute (Fanuc parameter 5400 bit RIN at its default 0); an incremental
    /// move turns its increment by R (the manual: about the tool position of the G68
    /// block until the first absolute move, which is the same map). Only the G17 plane is
    /// read; G69 cancels.
    pub(super) fn rotate_on(&mut self, b: &Block, w: Word) -> LineResult<()> {
        let line = b.line;
        let refuse = |at: std::ops::Range<usize>, what: String, label: &str| {
            Err(LineError::new(at, what, label))
        };
        if let Some((_, mw)) =
            b.g.iter()
                .find(|(c, _)| matches!(c, GCode::Motion(Some(_))))
        {
            return refuse(mw.span(), format!("`{}` in a G68 block: expected G68 in a block of its own (its X Y are the centre of rotation)", &line[mw.span()]), "motion with G68");
        }
        if let Some(x) = ['I', 'J', 'K'].into_iter().find_map(|l| b.get(l)) {
            return refuse(x.span(), format!("`{}` in a G68 block: G68 with I J K is Fanuc's three-dimensional coordinate conversion, which mtsim does not read (G68.2 is)", &line[x.span()]), "3-D coordinate conversion");
        }
        if self.plane != Plane::XY {
            return refuse(
                w.span(),
                "G68 outside the G17 plane: only a rotation in XY (G17) is read".to_string(),
                "rotation plane",
            );
        }
        if self.tilt.is_some() || self.dwo || self.rotation.is_some() {
            return refuse(w.span(), "G68 with a tilted plane, a dynamic work offset or a rotation already active: expected G69 (or G255, G10 L2 R0) first".to_string(), "rotation on a rotation");
        }
        if let Some(x) = ['Z', 'A', 'B', 'C', 'U', 'V', 'W']
            .into_iter()
            .find_map(|l| b.get(l))
        {
            return refuse(
                x.span(),
                format!(
                    "`{}` in a G68 block: in G17 the centre is X Y",
                    &line[x.span()]
                ),
                "not a G68 word",
            );
        }
        let Some(r) = b.get('R') else {
            return refuse(w.span(), "G68 without R: the angle then comes from the control's parameter 5410, which a program does not carry".to_string(), "no angle").map_err(|e: LineError| e.help("write the angle as R, in degrees"));
        };
        let here = self.program_position();
        let scale = self.scale();
        let centre = |l: char, a: Axis| b.get(l).map_or(here[a], |w| w.value) * scale;
        self.rotation_2d = Some((r.value, [centre('X', Axis::X), centre('Y', Axis::Y)]));
        self.parameters_changed();
        Ok(())
    }

    /// G68.2 X Y Z I J K: the tilted work plane's origin and Euler angles (Z-X-Z).
    pub(super) fn tilt_on(&mut self, b: &Block) -> LineResult<()> {
        let line = b.line;
        if self.rotation_2d.is_some() {
            return Err(LineError::new(
                0..line.len(),
                "G68.2 while G68 rotates the coordinates: expected G69 first",
                "tilt on a rotation",
            ));
        }
        if let Some((_, mw)) =
            b.g.iter()
                .find(|(c, _)| matches!(c, GCode::Motion(Some(_))))
        {
            return Err(LineError::new(mw.span(), format!("`{}` in a G68.2 block: expected G68.2 in a block of its own (its X Y Z are the plane's origin)", &line[mw.span()]), "motion with G68.2").help("move in the next block"));
        }
        for letter in ['A', 'B', 'C', 'R'] {
            if let Some(x) = b.get(letter) {
                return Err(LineError::new(x.span(), format!("`{}` in a G68.2 block: expected only X Y Z (origin) and I J K (Euler angles)", &line[x.span()]), "not a G68.2 word"));
            }
        }
        let v = |l: char| b.get(l).map_or(0.0, |w| w.value);
        let scale = self.scale();
        let origin = [v('X') * scale, v('Y') * scale, v('Z') * scale];
        self.tilt = Some((origin, frame::euler_zxz(v('I'), v('J'), v('K'))));
        Ok(())
    }

    /// G53.1: the rotary axes turn the table so the tool axis is normal to the tilted plane.
    pub(super) fn align_rotary(
        &mut self,
        b: &Block,
        w: Word,
        line_no: usize,
        queue: &mut VecDeque<Move>,
    ) -> LineResult<()> {
        if let (Some((_, rf)), None, Some(aligner)) = (self.tilt, self.table, &self.aligner) {
            // A kinematic chain: the caller's inverse kinematics turns the rotaries; the
            // move runs under tool-centre-point control, so the tool tip holds its place.
            let end = (aligner.0)([rf[0][2], rf[1][2], rf[2][2]], &self.pos).map_err(|why| {
                LineError::new(
                    w.span(),
                    format!("G53.1: the tilted plane's normal cannot be the tool direction: {why}"),
                    "tool direction out of reach",
                )
            })?;
            let start = self.pos;
            self.emit(queue, line_no, Motion::Rapid, start, end, self.path);
            self.pos = end;
            return Ok(());
        }
        let (Some((_, rf)), Some(table)) = (self.tilt, self.table) else {
            return Err(LineError::new(
                w.span(),
                if self.tilt.is_none() {
                    "G53.1 with no tilted plane: expected G68.2 in this or an earlier block"
                } else {
                    "G53.1 on a machine without a rotary table: expected a table-table AC or BC machine, or a kinematic chain with two rotaries"
                },
                "nothing to align",
            ));
        };
        if !b.g.iter().any(|(c, _)| *c == GCode::Tilt(true)) {
            if let Some(a) = Axis::ALL.iter().find_map(|a| b.get(a.letter())) {
                return Err(LineError::new(
                    a.span(),
                    "axis word in a G53.1 block: expected G53.1 alone",
                    "axis word with G53.1",
                )
                .help("move in the next block"));
            }
        }
        let (tilt, c) = table.align([rf[0][2], rf[1][2], rf[2][2]], self.pos[Axis::C]);
        let start = self.pos;
        let mut end = start;
        end[table.tilt] = tilt;
        end[Axis::C] = c;
        self.emit(queue, line_no, Motion::Rapid, start, end, self.path);
        self.pos = end;
        Ok(())
    }
}
