//! Phases 4 and 6: the non-modal codes. Phase 4 is the dwell (G4); phase 6 the codes that
//! use the axis words for something other than a move: G10 (offsets and tool data),
//! G28/G30 (to a stored position, through the words' point), G28.1/G30.1 (store it), G92,
//! G52 and G92.1-G92.3 (axis offsets).

use std::collections::VecDeque;

use super::{coord_parameter, Interp};
use crate::axis::Axis;
use crate::block::Block;
use crate::canon::{Motion, Move};
use crate::code::{GCode, NonModal};
use crate::dialect::DwellUnit;
use crate::lex::{LineError, LineResult, Word};
use crate::options::{Tool, G28_PARAMETER, G30_PARAMETER};

impl Interp {
    /// Phase 4: G4 dwells where the tool is.
    pub(super) fn dwell(
        &mut self,
        b: &Block,
        line_no: usize,
        queue: &mut VecDeque<Move>,
    ) -> LineResult<()> {
        let Some((NonModal::Dwell, w)) = b.nonmodal() else {
            return Ok(());
        };
        let line = b.line;
        let x_is_time = self.dialect.table().dwell_x_seconds;
        let with_motion = b.has_g(|c| matches!(c, GCode::Motion(Some(_))));
        for letter in ['X', 'Y', 'Z', 'A', 'B', 'C', 'I', 'J', 'K', 'R'] {
            if (letter == 'X' && x_is_time) || with_motion {
                continue;
            }
            if let Some(aw) = b.get(letter) {
                return Err(LineError::new(
                    aw.span(),
                    format!(
                        "`{}` in a G04 block: expected only the dwell time",
                        &line[aw.span()]
                    ),
                    "not a dwell word",
                )
                .help("put the move in its own block"));
            }
        }
        let seconds = self.dwell_seconds(line, &w, b.get('P'), b.get('X'))?;
        self.emit(
            queue,
            line_no,
            Motion::Dwell { seconds },
            self.pos,
            self.pos,
            self.path,
        );
        Ok(())
    }

    /// Phase 6: the block's non-modal code, when it uses the axis words (all but G4, G53).
    pub(super) fn non_modal(
        &mut self,
        b: &mut Block,
        line_no: usize,
        queue: &mut VecDeque<Move>,
    ) -> LineResult<()> {
        // G43.1 takes its Z as the tool length, G68.2 its X Y Z as the origin, G68 its X Y
        // as the centre: not a move.
        b.axes_used = b.has_g(|c| {
            matches!(
                c,
                GCode::ToolLength(1) | GCode::Tilt(true) | GCode::Rotate2d
            )
        });
        let Some((nm, w)) = b.nonmodal() else {
            return Ok(());
        };
        let line = b.line;
        // Fanuc M series: G92 S alone clamps the spindle speed (constant surface speed).
        if nm == NonModal::G92
            && self.dialect.table().g92_s_limits_spindle
            && b.axis.is_empty()
            && b.get('S').is_some()
        {
            return Ok(());
        }
        if nm != NonModal::Dwell && nm != NonModal::G53 {
            b.axes_used = true;
            if let Some((Some(_), mw)) = b.motion_code() {
                if !b.axis.is_empty() {
                    return Err(LineError::new(mw.span(), format!("`{}` and `{}` both use the axis words: expected them in separate blocks", &line[w.span()], &line[mw.span()]), "axis words used twice"));
                }
            }
        }
        if self.comp.is_some()
            && matches!(
                nm,
                NonModal::G28 | NonModal::G30 | NonModal::G92 | NonModal::G52
            )
        {
            return Err(LineError::new(
                w.span(),
                format!(
                    "`{}` with cutter radius compensation on: expected G40 first",
                    &line[w.span()]
                ),
                "not with compensation",
            ));
        }
        if self.frame().is_some() && matches!(nm, NonModal::G92 | NonModal::G52 | NonModal::G10) {
            return Err(LineError::new(
                w.span(),
                format!(
                    "`{}` with G68.2 or G254 active: not supported",
                    &line[w.span()]
                ),
                "offset in a tilted frame",
            )
            .help("set offsets before G68.2 or G254"));
        }
        let b = &*b;
        let axis_words = &b.axis[..];
        match nm {
            NonModal::G10 => self.g10(line, &w, &|l| b.get(l), axis_words)?,
            NonModal::G28 | NonModal::G30 => {
                let base = if nm == NonModal::G28 {
                    G28_PARAMETER
                } else {
                    G30_PARAMETER
                } as usize;
                let k = usize::from(nm == NonModal::G30);
                if axis_words.is_empty() && !self.reference_all_without_axes() {
                    // No axis returns (a notice says so, `control_notices`).
                    return Ok(());
                }
                if let Some(setting) = &self.reference_missing[k] {
                    return Err(LineError::new(
                        w.span(),
                        format!(
                            "`{}` goes to the machine's reference position, which is not given: set {setting}",
                            ["G28", "G30"][k]
                        ),
                        "no reference position",
                    )
                    .help("the control's reference point is a machine setting (on most machines Z at the top of its travel); the reader never assumes zero"));
                }
                self.go_home(base, axis_words, line_no, queue);
            }
            NonModal::G28_1 | NonModal::G30_1 => {
                let base = if nm == NonModal::G28_1 {
                    G28_PARAMETER
                } else {
                    G30_PARAMETER
                } as usize;
                self.reference_missing[usize::from(nm == NonModal::G30_1)] = None;
                for a in Axis::ALL {
                    self.params.numbered[base + a.index()] = self.pos[a];
                }
            }
            NonModal::G92 | NonModal::G52 => self.axis_offsets(line, nm, w, axis_words)?,
            NonModal::G92_1 | NonModal::G92_2 => {
                let n = &mut self.params.numbered;
                if nm == NonModal::G92_1 {
                    for k in 0..9 {
                        n[5211 + k] = 0.0;
                    }
                }
                n[5210] = 0.0;
                self.parameters_changed();
            }
            NonModal::G92_3 => {
                self.params.numbered[5210] = 1.0;
                self.parameters_changed();
            }
            NonModal::BoltCircle | NonModal::BoltArc => {
                self.bolt_pattern(b, nm, w, line_no, queue)?
            }
            NonModal::Dwell | NonModal::G53 => {}
        }
        Ok(())
    }

    /// Whether G28/G30 without axis words send every axis home ([`ControlParameters`]).
    ///
    /// [`ControlParameters`]: crate::options::ControlParameters
    pub(super) fn reference_all_without_axes(&self) -> bool {
        self.control
            .reference_all_without_axes
            .unwrap_or(self.dialect.table().reference_all_without_axes)
    }

    /// G28/G30: a rapid through the axis words' point (when there are any) to the position
    /// stored at parameter `base` (of those axes; of all without axis words).
    pub(super) fn go_home(
        &mut self,
        base: usize,
        axis_words: &[(Axis, Word)],
        line_no: usize,
        queue: &mut VecDeque<Move>,
    ) {
        let start = self.pos;
        let via = self.target(axis_words, false);
        let mut home = via;
        if axis_words.is_empty() {
            for a in Axis::ALL {
                if self.axes[a.index()] {
                    home[a] = self.params.numbered[base + a.index()];
                }
            }
        } else {
            for (a, _) in axis_words {
                home[*a] = self.params.numbered[base + a.index()];
            }
        }
        if !axis_words.is_empty() {
            self.emit(queue, line_no, Motion::Rapid, start, via, self.path);
        }
        self.emit(queue, line_no, Motion::Rapid, via, home, self.path);
        self.pos = home;
    }

    /// G92 (the current point becomes the words' program position) and G52 (a local
    /// offset by the words): both set the G92 offsets, parameters 5211-5219.
    pub(super) fn axis_offsets(
        &mut self,
        line: &str,
        nm: NonModal,
        w: Word,
        axis_words: &[(Axis, Word)],
    ) -> LineResult<()> {
        if self.rotation.is_some()
            && axis_words
                .iter()
                .any(|(a, _)| matches!(a, Axis::X | Axis::Y))
        {
            return Err(LineError::new(
                w.span(),
                format!(
                    "`{}` X Y in a rotated work system (G10 L2 R): not supported yet",
                    &line[w.span()]
                ),
                "rotated work system",
            ));
        }
        if axis_words.is_empty() {
            return Err(LineError::new(
                w.span(),
                format!(
                    "`{}` without axis words: expected at least one axis",
                    &line[w.span()]
                ),
                "no axes",
            ));
        }
        let scale = self.scale();
        let n = &mut self.params.numbered;
        if n[5210] == 0.0 {
            for k in 0..9 {
                n[5211 + k] = 0.0;
            }
        }
        for (a, wd) in axis_words {
            let v = wd.value * if a.is_rotary() { 1.0 } else { scale };
            let k = a.index();
            let g5x = n[coord_parameter(self.coord) + k];
            let tlo = if *a == Axis::Z {
                self.tool_length_mm
            } else {
                0.0
            };
            n[5211 + k] = if nm == NonModal::G52 {
                v
            } else {
                self.pos[*a] - g5x - tlo - v
            };
        }
        n[5210] = 1.0;
        self.parameters_changed();
        Ok(())
    }

    /// Dwell time: LinuxCNC P s; Fanuc P ms or X s; Haas P s with a decimal point, ms without.
    pub(super) fn dwell_seconds(
        &self,
        line: &str,
        g04: &Word,
        p: Option<Word>,
        x: Option<Word>,
    ) -> LineResult<f64> {
        let table = self.dialect.table();
        // Where X is an axis word (LinuxCNC), it is never a dwell time.
        let x = if table.dwell_x_seconds { x } else { None };
        let (seconds, w) = match (p, x) {
            (Some(p), None) => (dwell_p_seconds(table.dwell_p, &p), p),
            (None, Some(x)) => (x.value, x),
            (Some(_), Some(x)) => {
                return Err(LineError::new(
                    x.span(),
                    "G04 with both P and X: expected one dwell time",
                    "second dwell time",
                ));
            }
            (None, None) => {
                let help = if table.dwell_p == DwellUnit::Seconds {
                    "e.g. `G4 P0.5` dwells 0.5 s (LinuxCNC: P in seconds)"
                } else {
                    "e.g. `G04 P500` dwells 0.5 s"
                };
                return Err(LineError::new(
                    g04.span(),
                    format!("`{}` without a time: expected P", &line[g04.span()]),
                    "no dwell time",
                )
                .help(help));
            }
        };
        if seconds < 0.0 {
            return Err(LineError::new(
                w.span(),
                "negative dwell: expected a time of zero or more",
                "negative",
            ));
        }
        Ok(seconds)
    }

    /// G10 L1/L10 (tool length and radius), L2/L20 (work offsets; L2 R rotates the work
    /// system where the dialect has rotations).
    pub(super) fn g10<'l>(
        &mut self,
        line: &str,
        w: &Word,
        get: &dyn Fn(char) -> Option<Word<'l>>,
        axis_words: &[(Axis, Word)],
    ) -> LineResult<()> {
        let l = get('L').ok_or_else(|| {
            LineError::new(
                w.span(),
                "G10 without L: expected L1, L2, L10 or L20",
                "no L",
            )
        })?;
        let p = get('P').ok_or_else(|| {
            LineError::new(
                w.span(),
                "G10 without P: expected the work system (L2/L20) or tool (L1/L10) number",
                "no P",
            )
        })?;
        let pn = p.value.round();
        if p.value < 0.0 || (p.value - pn).abs() > 1e-4 {
            return Err(LineError::new(
                p.span(),
                "expected a whole P of zero or more",
                "bad P",
            ));
        }
        if self.dialect.table().macro_b {
            return self.g10_fanuc(line, get, axis_words, l, p);
        }
        let scale = self.scale();
        let value = |a: Axis, wd: &Word| {
            if a.is_rotary() {
                wd.value
            } else {
                wd.value * scale
            }
        };
        match l.value.round() as u32 {
            2 | 20 => {
                if pn > 9.0 {
                    return Err(LineError::new(
                        p.span(),
                        "work system number: expected P0 (active) to P9 (G59.3)",
                        "out of range",
                    ));
                }
                let coord = if pn == 0.0 { self.coord } else { pn as u32 };
                let base = coord_parameter(coord);
                if let Some(r) = get('R') {
                    let rotations = self.dialect.table().rotated_work_systems;
                    if r.value != 0.0 && (!rotations || l.value.round() as u32 != 2) {
                        return Err(LineError::new(
                            r.span(),
                            "rotated work systems: expected R only with G10 L2 in the linuxcnc dialect",
                            "rotation",
                        ));
                    }
                    if rotations && coord <= 9 {
                        self.params.numbered[base + 9] = r.value;
                    }
                }
                if l.value.round() as u32 == 20
                    && self.params.numbered[base + 9] != 0.0
                    && axis_words
                        .iter()
                        .any(|(a, _)| matches!(a, Axis::X | Axis::Y))
                {
                    return Err(LineError::new(
                        l.span(),
                        "G10 L20 X Y on a rotated work system: not supported, expected G10 L2",
                        "rotation",
                    ));
                }
                let g92_on = self.params.numbered[5210] != 0.0;
                for (a, wd) in axis_words {
                    let k = a.index();
                    let v = value(*a, wd);
                    self.params.numbered[base + k] = if l.value.round() as u32 == 2 {
                        v
                    } else {
                        let g92 = if g92_on {
                            self.params.numbered[5211 + k]
                        } else {
                            0.0
                        };
                        let tlo = if *a == Axis::Z {
                            self.tool_length_mm
                        } else {
                            0.0
                        };
                        self.pos[*a] - g92 - tlo - v
                    };
                }
                self.parameters_changed();
            }
            1 | 10 => {
                // A tool has a length along Z and a diameter: an offset along another axis
                // (LinuxCNC's lathe X, or U V W) is refused rather than dropped.
                if let Some((_, o)) = axis_words.iter().find(|(a, _)| *a != Axis::Z) {
                    return Err(LineError::new(
                        o.span(),
                        format!("`{}` in a G10 L1/L10 block: expected only Z (the tool length) and R (the radius); mtsim's tools have no offset along other axes", &line[o.span()]),
                        "tool offset not along Z",
                    ));
                }
                let n = pn as u32;
                let mut tool = self.tools.get(&n).copied().unwrap_or(Tool {
                    number: n,
                    length_mm: 0.0,
                    diameter_mm: 0.0,
                });
                if let Some(z) = get('Z') {
                    tool.length_mm = if l.value.round() as u32 == 1 {
                        z.value * scale
                    } else {
                        self.pos[Axis::Z] - self.offset[Axis::Z] - z.value * scale
                    };
                }
                if let Some(r) = get('R') {
                    tool.diameter_mm = 2.0 * r.value * scale;
                }
                self.tools.insert(n, tool);
                let _ = line;
            }
            _ => {
                return Err(LineError::new(
                    l.span(),
                    "unsupported G10 L: expected L1, L2, L10 or L20",
                    "unsupported L",
                ))
            }
        }
        Ok(())
    }
}

/// A dwell's P word in seconds, in the dialect's unit (G4, and the cycles G82 G86 G89:
/// the Fanuc Series 0i operator's manual gives both in ms).
pub(super) fn dwell_p_seconds(unit: DwellUnit, p: &Word) -> f64 {
    match unit {
        DwellUnit::Seconds => p.value,
        DwellUnit::Milliseconds => p.value / 1000.0,
        DwellUnit::MillisecondsUnlessDecimal if p.number.contains('.') => p.value,
        DwellUnit::MillisecondsUnlessDecimal => p.value / 1000.0,
    }
}
