//! The modal interpreter: one block of words into canonical moves in machine coordinates.
//!
//! Machine position = program position + work offset (G54-G59.3, G54.1 Pn) + G92/G52
//! offset + tool length offset (G43, on Z). The offsets live in LinuxCNC's numbered
//! parameters (5211-5219 G92, 5221+20(n-1) work system n, 5161/5181 G28/G30), so `.var`
//! files, G10 and `#5221 = ...` all act on the same numbers.

use std::collections::{HashMap, VecDeque};
use std::path::Path;

use crate::axis::{Axis, AxisVec, Plane};
use crate::canon::{FeedMode, Motion, Move, PathControl, FULL_CIRCLE_TOLERANCE_MM};
use crate::comp;
use crate::expr::{Param, Params};
use crate::frame::{self, Frame, Mat3, RotaryTable};
use crate::lex::{LineError, LineResult, Word, EXPECTED_WORDS};
use crate::options::{Dialect, Options, Tool, UserM, G28_PARAMETER, G30_PARAMETER};
use crate::reader::{Notice, ARC_RADIUS_TOLERANCE_MM, FANUC_ARC_RADIUS_TOLERANCE_MM, MM_PER_INCH};

/// What the reader must do after a block.
pub enum Stop {
    None,
    End,
    /// M98 P (Fanuc subprogram, shared locals) or G65 P (macro call, own locals).
    Call {
        label: String,
        repeats: u64,
        args: Vec<f64>,
        locals: bool,
        span: std::ops::Range<usize>,
    },
    /// M99.
    Return {
        span: std::ops::Range<usize>,
    },
    /// M73: restore this state when the subroutine returns.
    SaveForReturn(Box<Saved>),
}

/// Modal state saved by M70/M73.
#[derive(Clone, Debug)]
pub struct Saved {
    motion: Option<MotionMode>,
    plane: Plane,
    absolute: bool,
    arc_absolute: bool,
    feed_mode: FeedRead,
    inch: bool,
    feed: Option<f64>,
    spindle_rpm: f64,
    path: PathControl,
    retract_r: bool,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum MotionMode {
    Rapid,
    Linear,
    Arc {
        clockwise: bool,
    },
    /// Canned cycle G73, G81-G89: the code ×10.
    Cycle(u32),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum FeedRead {
    PerMinute,
    InverseTime,
    PerRevolution,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum NonModal {
    Dwell,
    G10,
    G28,
    G28_1,
    G30,
    G30_1,
    G52,
    G53,
    G92,
    G92_1,
    G92_2,
    G92_3,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum GCode {
    Motion(Option<MotionMode>),
    NonModal(NonModal),
    Plane(Plane),
    Distance(bool),
    ArcDistance(bool),
    Feed(FeedRead),
    Units(bool),
    CutterComp(u32),
    /// G43 (0), G43.1 (1), G43.2 (2), G44 (4), G49 (9), TCP on/off.
    ToolLength(u32),
    Tcp(bool),
    Coord(u32),
    /// G54.1 P / G154 P: extended offsets.
    CoordExtended,
    Path(u32),
    Retract(bool),
    /// Fanuc G05.1 (AI contour control, Q) and G08 (look-ahead, P); Haas G103 (block
    /// look-ahead, P): accepted, no effect on the canonical moves. Haas G187 (P accuracy
    /// level, E corner tolerance) sets the blending tolerance.
    Control(u32),
    /// Fanuc G68.2 (true, tilted work plane) and G69 (false, cancel).
    Tilt(bool),
    /// Fanuc G53.1: rotary axes to the tilted plane.
    AlignRotary,
    /// Haas G254 (true, dynamic work offset) and G255 (false).
    Dwo(bool),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Group {
    Control,
    Tilt,
    AlignRotary,
    Dwo,
    Motion,
    NonModal,
    Plane,
    Distance,
    ArcDistance,
    Feed,
    Units,
    CutterComp,
    ToolLength,
    Coord,
    Path,
    Retract,
}

impl GCode {
    fn group(self) -> Group {
        match self {
            GCode::Motion(_) => Group::Motion,
            // G4 cannot share a block with a motion code: P and X would be ambiguous.
            GCode::NonModal(NonModal::Dwell) => Group::Motion,
            GCode::NonModal(_) => Group::NonModal,
            GCode::Plane(_) => Group::Plane,
            GCode::Distance(_) => Group::Distance,
            GCode::ArcDistance(_) => Group::ArcDistance,
            GCode::Feed(_) => Group::Feed,
            GCode::Units(_) => Group::Units,
            GCode::CutterComp(_) => Group::CutterComp,
            GCode::ToolLength(_) | GCode::Tcp(_) => Group::ToolLength,
            GCode::Coord(_) | GCode::CoordExtended => Group::Coord,
            GCode::Path(_) => Group::Path,
            GCode::Retract(_) => Group::Retract,
            GCode::Control(_) => Group::Control,
            GCode::Tilt(_) => Group::Tilt,
            GCode::AlignRotary => Group::AlignRotary,
            GCode::Dwo(_) => Group::Dwo,
        }
    }

    // Inlined: the large result read back from memory after a call stalled every block.
    #[inline(always)]
    fn parse(word: &Word, line: &str, dialect: Dialect) -> LineResult<GCode> {
        let text = &line[word.span()];
        let tenths = word.value * 10.0;
        // `round` without the call to libm: the same code for every value accepted below.
        let code = if tenths >= 0.0 {
            (tenths + 0.5) as i64 as f64
        } else {
            tenths.round()
        };
        let unsupported = |why: &str, help: &str| {
            LineError::new(
                word.span(),
                format!("unsupported code `{text}`{why}"),
                "unsupported G code",
            )
            .help(if help.is_empty() {
                "docs/gcode.md lists every supported G code"
            } else {
                help
            })
        };
        if word.number.starts_with(['+', '-'])
            || word.value < 0.0
            || (tenths - code).abs() > 1e-6
            || code > 99999.0
        {
            return Err(unsupported("", ""));
        }
        let fanuc = dialect.is_fanuc_family();
        use MotionMode::*;
        Ok(match code as u32 {
            0 => GCode::Motion(Some(Rapid)),
            10 => GCode::Motion(Some(Linear)),
            20 => GCode::Motion(Some(Arc { clockwise: true })),
            30 => GCode::Motion(Some(Arc { clockwise: false })),
            40 => GCode::NonModal(NonModal::Dwell),
            100 => GCode::NonModal(NonModal::G10),
            170 => GCode::Plane(Plane::XY),
            180 => GCode::Plane(Plane::ZX),
            190 => GCode::Plane(Plane::YZ),
            200 => GCode::Units(true),
            210 => GCode::Units(false),
            280 => GCode::NonModal(NonModal::G28),
            281 => GCode::NonModal(NonModal::G28_1),
            300 => GCode::NonModal(NonModal::G30),
            301 => GCode::NonModal(NonModal::G30_1),
            400 => GCode::CutterComp(0),
            410 => GCode::CutterComp(1),
            420 => GCode::CutterComp(2),
            411 if !fanuc => GCode::CutterComp(3),
            421 if !fanuc => GCode::CutterComp(4),
            430 => GCode::ToolLength(0),
            431 if !fanuc => GCode::ToolLength(1),
            432 if !fanuc => GCode::ToolLength(2),
            434 | 435 if fanuc => GCode::Tcp(true),
            2340 if dialect == Dialect::Haas => GCode::Tcp(true),
            440 if fanuc => GCode::ToolLength(4),
            490 => GCode::ToolLength(9),
            520 => GCode::NonModal(NonModal::G52),
            530 => GCode::NonModal(NonModal::G53),
            540..=590 if code as u32 % 10 == 0 => GCode::Coord((code as u32 - 530) / 10),
            591..=593 if !fanuc => GCode::Coord(code as u32 - 591 + 7),
            541 => GCode::CoordExtended,
            1540 if dialect == Dialect::Haas => GCode::CoordExtended,
            610 => GCode::Path(0),
            611 => GCode::Path(1),
            640 => GCode::Path(4),
            730 => GCode::Motion(Some(Cycle(730))),
            800 => GCode::Motion(None),
            810 | 820 | 830 | 850 | 860 | 890 => GCode::Motion(Some(Cycle(code as u32))),
            900 => GCode::Distance(true),
            910 => GCode::Distance(false),
            901 => GCode::ArcDistance(true),
            911 => GCode::ArcDistance(false),
            920 => GCode::NonModal(NonModal::G92),
            921 => GCode::NonModal(NonModal::G92_1),
            922 => GCode::NonModal(NonModal::G92_2),
            923 => GCode::NonModal(NonModal::G92_3),
            930 => GCode::Feed(FeedRead::InverseTime),
            940 => GCode::Feed(FeedRead::PerMinute),
            950 => GCode::Feed(FeedRead::PerRevolution),
            51 | 80 if fanuc => GCode::Control(code as u32),
            1030 | 1870 if dialect == Dialect::Haas => GCode::Control(code as u32),
            682 if fanuc => GCode::Tilt(true),
            690 if fanuc => GCode::Tilt(false),
            531 if fanuc => GCode::AlignRotary,
            2540 if dialect == Dialect::Haas => GCode::Dwo(true),
            2550 if dialect == Dialect::Haas => GCode::Dwo(false),
            980 => GCode::Retract(false),
            990 => GCode::Retract(true),
            434 | 435 => return Err(unsupported(" (LinuxCNC has no G43.4; TCP is switched by the scenario option or a user M code such as M428)", "map the TCP M codes in the scenario (user_m_codes)")),
            2340 => return Err(unsupported(" (G234 is Haas TCP)", "set dialect = \"haas\"")),
            682 | 690 | 531 => return Err(unsupported(" (G68.2, G53.1 and G69 are Fanuc and Haas codes)", "set dialect = \"fanuc\" or \"haas\"")),
            2540 | 2550 => return Err(unsupported(" (G254/G255 are Haas dynamic work offsets)", "set dialect = \"haas\"")),
            680..=689 => return Err(unsupported(" (2D coordinate rotation G68 and other G68.x are not supported; G68.2 is)", "post-process the program without G68")),
            760 | 840 | 870 | 880 => return Err(unsupported(" (this canned cycle is not supported; G73 G81 G82 G83 G85 G86 G89 are)", "")),
            _ => return Err(unsupported("", "")),
        })
    }
}

/// The modal state of the controller between blocks.
pub struct Interp {
    pub params: Params,
    dialect: Dialect,
    axes: [bool; 6],
    /// Machine position of the controlled point, mm and deg.
    pos: AxisVec,
    motion: Option<MotionMode>,
    plane: Plane,
    absolute: bool,
    arc_absolute: bool,
    feed_mode: FeedRead,
    inch: bool,
    /// F as programmed (program units per minute or per revolution, or 1/min).
    feed: Option<f64>,
    spindle_rpm: f64,
    tcp: bool,
    tools: HashMap<u32, Tool>,
    table_given: bool,
    tool: u32,
    next_tool: u32,
    tool_length_mm: f64,
    /// Active work system: 1 = G54 ... 9 = G59.3, 10+ = G54.1 P1...
    coord: u32,
    /// Work offset + G92, machine minus program (before the tool length), cached.
    offset: AxisVec,
    path: PathControl,
    retract_r: bool,
    cycle_r: Option<f64>,
    cycle_z: Option<f64>,
    cycle_q: Option<f64>,
    cycle_p: Option<f64>,
    user_m: HashMap<u32, UserM>,
    noticed: Vec<u32>,
    saved: Option<Box<Saved>>,
    /// G68.2 feature frame: origin in work coordinates (mm) and rotation `R_f`.
    tilt: Option<([f64; 3], Mat3)>,
    /// Haas G254: the work offset follows the rotary table.
    dwo: bool,
    table: Option<RotaryTable>,
    /// Cutter radius compensation: tool on the left (G41), radius mm.
    comp: Option<(bool, f64)>,
    /// The compensated element waiting for the next one.
    held: Option<comp::Held>,
    /// Compensated X Y of the last move when it differs from `pos` (after G40).
    comp_actual: Option<[f64; 2]>,
}

/// Parameter of extended work offset P n (G54.1 Pn, G154 Pn), axis X.
fn extended_parameter(n: u32) -> usize {
    // LinuxCNC has none; stored above its range, 7001 + 20 (n - 1).
    7001 + 20 * (n as usize - 1)
}

fn coord_parameter(coord: u32) -> usize {
    if coord <= 9 {
        5201 + 20 * coord as usize
    } else {
        extended_parameter(coord - 9)
    }
}

impl Interp {
    pub fn new(o: &Options) -> Interp {
        let mut params = Params::new();
        for &(n, v) in &o.parameters {
            params.set(&Param::Numbered(n as usize), v);
        }
        params.numbered[5220] = 1.0;
        let mut axes = [false; 6];
        for a in &o.axes {
            axes[a.index()] = true;
        }
        let mut i = Interp {
            params,
            dialect: o.dialect,
            axes,
            pos: o.start,
            motion: None,
            plane: Plane::XY,
            absolute: true,
            arc_absolute: false,
            feed_mode: FeedRead::PerMinute,
            inch: false,
            feed: None,
            spindle_rpm: 0.0,
            tcp: o.tcp,
            tools: o.tools.iter().map(|t| (t.number, *t)).collect(),
            table_given: !o.tools.is_empty(),
            tool: 0,
            next_tool: 0,
            tool_length_mm: 0.0,
            coord: 1,
            offset: AxisVec::ZERO,
            path: PathControl::BLEND,
            retract_r: false,
            cycle_r: None,
            cycle_z: None,
            cycle_q: None,
            cycle_p: None,
            user_m: o.user_m.clone(),
            noticed: Vec::new(),
            saved: None,
            tilt: None,
            dwo: false,
            table: o.table,
            comp: None,
            held: None,
            comp_actual: None,
        };
        i.parameters_changed();
        i
    }

    /// Recomputes the cached offsets after parameters changed.
    pub fn parameters_changed(&mut self) {
        let base = coord_parameter(self.coord);
        let g92_on = self.params.numbered[5210] != 0.0;
        for a in Axis::ALL {
            let k = a.index();
            let g92 = if g92_on {
                self.params.numbered[5211 + k]
            } else {
                0.0
            };
            self.offset[a] = self.params.numbered.get(base + k).copied().unwrap_or(0.0) + g92;
        }
    }

    fn scale(&self) -> f64 {
        if self.inch {
            MM_PER_INCH
        } else {
            1.0
        }
    }

    /// Program position (current work system, current units).
    fn program_position(&self) -> AxisVec {
        let mut p = self.pos - self.offset;
        p[Axis::Z] -= self.tool_length_mm;
        if let Some(f) = self.frame() {
            let pp = f.to_program(self.tip(), &self.offset, &self.pos);
            for a in Axis::LINEAR {
                p[a] = pp[a.index()];
            }
        }
        for a in Axis::LINEAR {
            p[a] /= self.scale();
        }
        p
    }

    /// The program-to-machine map while G68.2 or G254 is active.
    fn frame(&self) -> Option<Frame> {
        if self.tilt.is_none() && !self.dwo {
            return None;
        }
        let (origin_mm, rotation) = self.tilt.unwrap_or(([0.0; 3], frame::IDENTITY));
        Some(Frame {
            origin_mm,
            rotation,
            table: self.table,
        })
    }

    /// Machine X Y Z of the controlled point without the tool length offset, mm.
    fn tip(&self) -> [f64; 3] {
        [
            self.pos[Axis::X],
            self.pos[Axis::Y],
            self.pos[Axis::Z] - self.tool_length_mm,
        ]
    }

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
                Some(MotionMode::Cycle(c)) => c as f64,
                None => 800.0,
            },
        );
        g.insert("_task".into(), 0.0);
    }

    pub fn restore(&mut self, s: &Saved) {
        self.motion = s.motion;
        self.plane = s.plane;
        self.absolute = s.absolute;
        self.arc_absolute = s.arc_absolute;
        self.feed_mode = s.feed_mode;
        self.inch = s.inch;
        self.feed = s.feed;
        self.spindle_rpm = s.spindle_rpm;
        self.path = s.path;
        self.retract_r = s.retract_r;
    }

    fn save(&self) -> Saved {
        Saved {
            motion: self.motion,
            plane: self.plane,
            absolute: self.absolute,
            arc_absolute: self.arc_absolute,
            feed_mode: self.feed_mode,
            inch: self.inch,
            feed: self.feed,
            spindle_rpm: self.spindle_rpm,
            path: self.path,
            retract_r: self.retract_r,
        }
    }

    fn tool_entry(&self, n: u32, w: &Word) -> LineResult<Tool> {
        match self.tools.get(&n) {
            Some(t) => Ok(*t),
            None if !self.table_given || n == 0 => Ok(Tool {
                number: n,
                length_mm: 0.0,
                diameter_mm: 0.0,
            }),
            None => Err(LineError::new(
                w.span(),
                format!("tool {n} is not in the tool table: expected one of its tools"),
                "unknown tool",
            )
            .help("add the tool to the scenario's tool table")),
        }
    }

    fn emit(
        &mut self,
        queue: &mut VecDeque<Move>,
        line: usize,
        motion: Motion,
        mut start: AxisVec,
        mut end: AxisVec,
        path: PathControl,
    ) {
        let (feed, feed_mode) = self.feed_out();
        if let Some(h) = &mut self.held {
            // Waits with the held element (a plunge or a dwell under compensation).
            h.after.push(Move {
                line,
                motion,
                start,
                end,
                feed,
                feed_mode,
                tcp: self.tcp,
                tool: self.tool,
                tool_length_mm: self.tool_length_mm,
                path,
            });
            return;
        }
        if let Some(xy) = self.comp_actual {
            start[Axis::X] = xy[0];
            start[Axis::Y] = xy[1];
            if end[Axis::X] == self.pos[Axis::X] && end[Axis::Y] == self.pos[Axis::Y] {
                // Not moving in X Y: stays at the compensated point.
                end[Axis::X] = xy[0];
                end[Axis::Y] = xy[1];
            } else {
                self.comp_actual = None;
            }
        }
        queue.push_back(Move {
            line,
            motion,
            start,
            end,
            feed,
            feed_mode,
            tcp: self.tcp,
            tool: self.tool,
            tool_length_mm: self.tool_length_mm,
            path,
        });
    }

    fn feed_out(&self) -> (Option<f64>, FeedMode) {
        match self.feed_mode {
            FeedRead::PerMinute => (self.feed, FeedMode::PerMinute),
            FeedRead::PerRevolution => {
                (self.feed.map(|f| f * self.spindle_rpm), FeedMode::PerMinute)
            }
            FeedRead::InverseTime => (self.feed, FeedMode::InverseTime),
        }
    }

    /// Interprets the words of one block, queueing its moves.
    pub fn block(
        &mut self,
        line: &str,
        words: &[Word],
        line_no: usize,
        queue: &mut VecDeque<Move>,
        notices: &mut Vec<Notice>,
        path: &Path,
    ) -> LineResult<Stop> {
        let dialect = self.dialect;
        if dialect.is_fanuc_family() {
            if let Some(g65) = words.iter().find(|w| w.letter == 'G' && w.value == 65.0) {
                return self.g65(line, words, *g65);
            }
        }
        let mut g: Small<(GCode, Word), 16> = Small::new();
        let mut m: Small<(u32, Word), 16> = Small::new();
        if words.len() > 64 {
            let w = words[64];
            return Err(LineError::new(
                w.span(),
                "more than 64 words in a block: expected a shorter block",
                "too many words",
            ));
        }
        // Per letter, the index in `words` of its word (`NONE`: not in this block).
        const NONE: u8 = u8::MAX;
        let mut single = [NONE; 26];
        for (k, word) in words.iter().enumerate() {
            match word.letter {
                'G' => {
                    let code = GCode::parse(word, line, dialect)?;
                    // LinuxCNC accepts G80 beside G00/G01 (`G80 G0 Z10`): the cancel is implied.
                    let g80 = GCode::Motion(None);
                    if code == g80 && g.iter().any(|(c, _)| matches!(c, GCode::Motion(Some(_)))) {
                        continue;
                    }
                    if let Some(k) = g.iter().position(|(c, _)| *c == g80) {
                        if matches!(code, GCode::Motion(Some(_))) {
                            g.remove(k);
                        }
                    }
                    // LinuxCNC: G4 is non-modal (group 0) and may share a block with G0-G3.
                    let dwell_pair = |a: GCode, b: GCode| {
                        dialect == Dialect::Linuxcnc
                            && (a == GCode::NonModal(NonModal::Dwell))
                                != (b == GCode::NonModal(NonModal::Dwell))
                    };
                    if let Some((_, other)) = g
                        .iter()
                        .find(|(c, _)| c.group() == code.group() && !dwell_pair(*c, code))
                    {
                        return Err(LineError::new(word.span(), format!("`{}` and `{}` are in the same modal group: expected at most one per block", &line[other.span()], &line[word.span()]), "second code of the group").help("split them into two blocks"));
                    }
                    if !g.push((code, *word)) {
                        return Err(LineError::new(
                            word.span(),
                            "more than 16 G codes in a block: expected at most one per modal group",
                            "too many G codes",
                        ));
                    }
                }
                'M' => {
                    let code = integer(word, line)? as u32;
                    let grp = m_group(code);
                    if let Some((_, other)) =
                        m.iter().find(|(c, _)| grp.is_some() && m_group(*c) == grp)
                    {
                        return Err(LineError::new(word.span(), format!("`{}` and `{}` are in the same group: expected at most one per block", &line[other.span()], &line[word.span()]), "second code of the group"));
                    }
                    if !m.push((code, *word)) {
                        return Err(LineError::new(
                            word.span(),
                            "more than 16 M codes in a block: expected fewer",
                            "too many M codes",
                        ));
                    }
                }
                'O' => {
                    return Err(LineError::new(
                        word.span(),
                        "`O` inside a block: expected an o-word only at the start of a line",
                        "misplaced O",
                    ));
                }
                letter => {
                    let slot = &mut single[(letter as u8 - b'A') as usize];
                    if let Some(first) = words.get(*slot as usize) {
                        return Err(LineError::new(word.span(), format!("repeated `{letter}` word (first `{}`): expected each of {EXPECTED_WORDS} at most once per block, apart from G and M", &line[first.span()]), "repeated word"));
                    }
                    *slot = k as u8;
                }
            }
        }
        let get = |l: char| {
            words
                .get(single[(l as u8 - b'A') as usize] as usize)
                .copied()
        };
        for a in Axis::ALL {
            if let Some(w) = get(a.letter()) {
                if !self.axes[a.index()] {
                    return Err(LineError::new(w.span(), format!("`{}`: this machine has no {} axis", &line[w.span()], a.letter()), "axis not on this machine")
                        .help("check the program is for this machine; a word for a missing axis is never dropped"));
                }
            }
        }
        for letter in ['N', 'T', 'H', 'D', 'L'] {
            if let Some(word) = get(letter) {
                integer(&word, line)?;
            }
        }
        let nonmodal = g.iter().find_map(|(c, w)| match c {
            GCode::NonModal(n) => Some((*n, *w)),
            _ => None,
        });
        self.unused_words(line, &g, &m, &get)?;
        let mut stop = Stop::None;

        // 1. Units, feed mode, F, S. LinuxCNC sets F before G20/G21 (its order of
        // execution), so there `G20 F60` from metric is 60 mm/min; the Fanuc family reads
        // F in the block's new units.
        let scale_before_units = self.scale();
        for &(c, _) in g.iter() {
            if let GCode::Units(inch) = c {
                self.inch = inch;
            }
        }
        for &(c, _) in g.iter() {
            if let GCode::Feed(mode) = c {
                if mode != self.feed_mode {
                    self.feed = None;
                }
                self.feed_mode = mode;
            }
        }
        let mut feed_word = None;
        if let Some(f) = get('F') {
            if f.value <= 0.0 {
                return Err(LineError::new(
                    f.span(),
                    format!("`{}`: expected a feed greater than zero", &line[f.span()]),
                    "feed not positive",
                ));
            }
            self.feed = Some(match self.feed_mode {
                FeedRead::InverseTime => f.value,
                _ if self.dialect == Dialect::Linuxcnc => f.value * scale_before_units,
                _ => f.value * self.scale(),
            });
            feed_word = Some(f);
        }
        if let Some(s) = get('S') {
            if s.value < 0.0 {
                return Err(LineError::new(
                    s.span(),
                    "negative spindle speed: expected S zero or more",
                    "negative",
                ));
            }
            self.spindle_rpm = s.value;
        }
        // 2. Tool select and change.
        if let Some(t) = get('T') {
            let n = t.value.round() as u32;
            self.tool_entry(n, &t)?;
            self.next_tool = n;
        }
        let mut tcp_m = None;
        for &(code, w) in m.iter() {
            match code {
                6 => self.tool = self.next_tool,
                61 => {
                    let Some(q) = get('Q') else {
                        return Err(LineError::new(
                            w.span(),
                            "M61 without Q: expected `M61 Q<tool>`",
                            "no Q",
                        ));
                    };
                    let n = q.value.round() as u32;
                    self.tool_entry(n, &q)?;
                    self.tool = n;
                    self.next_tool = n;
                }
                0
                | 1
                | 2
                | 30
                | 60
                | 3
                | 4
                | 5
                | 19
                | 7
                | 8
                | 9
                | 48..=53
                | 62..=68
                | 70..=73
                | 98
                | 99 => {}
                code => match self.user_m.get(&code) {
                    Some(UserM::TcpOn) => tcp_m = Some(true),
                    Some(UserM::TcpOff) => tcp_m = Some(false),
                    Some(UserM::Ignore) => {}
                    None if (100..=199).contains(&code) => {
                        if !self.noticed.contains(&code) && self.noticed.len() < 100 {
                            self.noticed.push(code);
                            notices.push(Notice { path: path.to_path_buf(), line: line_no, message: format!("user code M{code} accepted and ignored (map it in the scenario's user_m_codes to give it an effect)") });
                        }
                    }
                    None => {
                        return Err(LineError::new(w.span(), format!("unsupported code `{}`", &line[w.span()]), "unsupported M code")
                            .help("supported: M0-M9 M19 M30 M48-M53 M60-M68 M70-M73 M98 M99 and user M100-M199; map others in the scenario's user_m_codes"));
                    }
                },
            }
        }
        if let Some(on) = tcp_m {
            self.tcp = on;
        }
        // 3. M70-M73: modal state.
        for &(code, w) in m.iter() {
            match code {
                70 => self.saved = Some(Box::new(self.save())),
                71 => self.saved = None,
                72 => match self.saved.clone() {
                    Some(s) => self.restore(&s),
                    None => {
                        return Err(LineError::new(
                            w.span(),
                            "M72 with no state saved: expected an M70 before it",
                            "nothing saved",
                        ))
                    }
                },
                73 => stop = Stop::SaveForReturn(Box::new(self.save())),
                _ => {}
            }
        }
        // 4. Dwell.
        if let Some((NonModal::Dwell, w)) = nonmodal {
            let x_is_time = if dialect.is_fanuc_family() { "" } else { "X" };
            let with_motion = g.iter().any(|(c, _)| matches!(c, GCode::Motion(Some(_))));
            for letter in ['X', 'Y', 'Z', 'A', 'B', 'C', 'I', 'J', 'K', 'R'] {
                if (letter == 'X' && x_is_time.is_empty()) || with_motion {
                    continue;
                }
                if let Some(aw) = get(letter) {
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
            let seconds = self.dwell_seconds(line, &w, get('P'), get('X'))?;
            self.emit(
                queue,
                line_no,
                Motion::Dwell { seconds },
                self.pos,
                self.pos,
                self.path,
            );
        }
        // 5. Plane, units, tool length, coordinate system, path control, distance, retract.
        let mut tcp_on = false;
        for &(c, w) in g.iter() {
            match c {
                GCode::Plane(p) => self.plane = p,
                GCode::Units(inch) => self.inch = inch,
                GCode::CutterComp(0) => {
                    self.comp = None;
                    self.comp_exit(queue);
                }
                GCode::CutterComp(k) => {
                    if self.comp.is_some() {
                        return Err(LineError::new(w.span(), "cutter radius compensation turned on while it is on: expected G40 first", "compensation already on"));
                    }
                    if self.plane != Plane::XY {
                        return Err(LineError::new(
                            w.span(),
                            "cutter radius compensation outside G17: expected the XY plane (G17)",
                            "not G17",
                        ));
                    }
                    if self.frame().is_some() {
                        return Err(LineError::new(
                            w.span(),
                            "cutter radius compensation with G68.2 or G254 active: not supported",
                            "compensation in a tilted frame",
                        ));
                    }
                    let d = get('D');
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
                        let n = d.map_or(self.tool, |d| d.value.round() as u32);
                        self.tool_entry(n, &d.unwrap_or(w))?.diameter_mm
                    };
                    if diameter < 0.0 {
                        return Err(LineError::new(
                            w.span(),
                            "negative cutter diameter: expected D of zero or more",
                            "negative",
                        ));
                    }
                    self.comp = Some((k % 2 == 1, diameter / 2.0));
                }
                GCode::ToolLength(kind) => {
                    let h = get('H');
                    match kind {
                        0 | 4 => {
                            let n = h.map_or(self.tool, |h| h.value.round() as u32);
                            let t = self.tool_entry(n, &h.unwrap_or(w))?;
                            self.tool_length_mm =
                                if kind == 4 { -t.length_mm } else { t.length_mm };
                        }
                        1 => {
                            let z = get('Z').ok_or_else(|| {
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
                            self.tool_length_mm = 0.0;
                            if self.dialect.is_fanuc_family() {
                                // G49 also cancels G43.4/G43.5/G234.
                                self.tcp = false;
                            }
                        }
                    }
                }
                GCode::Tcp(on) => {
                    self.tcp = on;
                    tcp_on = on;
                    if let Some(h) = get('H') {
                        let t = self.tool_entry(h.value.round() as u32, &h)?;
                        self.tool_length_mm = t.length_mm;
                    }
                }
                GCode::Coord(n) => {
                    self.coord = n;
                    self.params.numbered[5220] = n as f64;
                    self.parameters_changed();
                }
                GCode::CoordExtended => {
                    let p = get('P').ok_or_else(|| {
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
                }
                GCode::Path(k) => {
                    self.path = match k {
                        0 => PathControl::ExactPath,
                        1 => PathControl::ExactStop,
                        _ => PathControl::Blend {
                            tolerance_mm: get('P').map(|p| p.value * self.scale()),
                            naive_cam_mm: get('Q').map(|q| q.value * self.scale()),
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
                        tolerance_mm: get('E').map(|e| e.value * self.scale()),
                        naive_cam_mm: None,
                    };
                }
                GCode::Tilt(true) => {
                    if let Some((_, mw)) =
                        g.iter().find(|(c, _)| matches!(c, GCode::Motion(Some(_))))
                    {
                        return Err(LineError::new(mw.span(), format!("`{}` in a G68.2 block: expected G68.2 in a block of its own (its X Y Z are the plane's origin)", &line[mw.span()]), "motion with G68.2").help("move in the next block"));
                    }
                    for letter in ['A', 'B', 'C', 'R'] {
                        if let Some(x) = get(letter) {
                            return Err(LineError::new(x.span(), format!("`{}` in a G68.2 block: expected only X Y Z (origin) and I J K (Euler angles)", &line[x.span()]), "not a G68.2 word"));
                        }
                    }
                    let v = |l: char| get(l).map_or(0.0, |w| w.value);
                    let scale = self.scale();
                    let origin = [v('X') * scale, v('Y') * scale, v('Z') * scale];
                    self.tilt = Some((origin, frame::euler_zxz(v('I'), v('J'), v('K'))));
                }
                GCode::Tilt(false) => self.tilt = None,
                GCode::Dwo(on) => {
                    if on && self.table.is_none() {
                        return Err(LineError::new(w.span(), "G254 on a machine without a rotary table: expected a table-table AC or BC machine", "no rotary table"));
                    }
                    self.dwo = on;
                }
                _ => {}
            }
        }
        if let Some((_, w)) = g.iter().find(|(c, _)| *c == GCode::AlignRotary) {
            let (Some((_, rf)), Some(table)) = (self.tilt, self.table) else {
                return Err(LineError::new(
                    w.span(),
                    if self.tilt.is_none() {
                        "G53.1 with no tilted plane: expected G68.2 in this or an earlier block"
                    } else {
                        "G53.1 on a machine without a rotary table: expected a table-table AC or BC machine"
                    },
                    "nothing to align",
                ));
            };
            if !g.iter().any(|(c, _)| *c == GCode::Tilt(true)) {
                if let Some(a) = Axis::ALL.iter().find_map(|a| get(a.letter())) {
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
        }
        if self.tcp && self.frame().is_some() {
            let w = g.first().map_or(Word::EMPTY, |(_, w)| *w);
            return Err(LineError::new(
                w.span(),
                "tool-centre-point control with G68.2 or G254 active: expected one at a time",
                "TCP in a tilted frame",
            )
            .help(
                "cancel G68.2 with G69 (G254 with G255) before G43.4/G234, or TCP with G49 first",
            ));
        }
        if let Some(h) = get('H') {
            let used = g.iter().any(|(c, _)| {
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
        let _ = tcp_on;
        let motion_code = g.iter().find_map(|(c, w)| match c {
            GCode::Motion(mm) => Some((*mm, *w)),
            _ => None,
        });
        if let Some((mm, _)) = motion_code {
            if mm != self.motion || !matches!(mm, Some(MotionMode::Cycle(_))) {
                // A new cycle forgets nothing LinuxCNC keeps; G80 ends the cycle.
            }
            self.motion = mm;
        }
        let dwell_x = dialect.is_fanuc_family() && matches!(nonmodal, Some((NonModal::Dwell, _)));
        // Fixed buffers, no allocation per block.
        let mut axis_buf: Small<(Axis, Word), 6> = Small::new();
        for a in Axis::ALL {
            if let Some(w) = get(a.letter()) {
                if !(dwell_x && a == Axis::X) {
                    axis_buf.push((a, w));
                }
            }
        }
        let axis_words = &axis_buf[..];
        // 6. Non-modal codes that use axis words.
        // G43.1 takes its Z as the tool length, not as a move.
        let mut axes_used = g
            .iter()
            .any(|(c, _)| *c == GCode::ToolLength(1) || *c == GCode::Tilt(true));
        if let Some((nm, w)) = nonmodal {
            if nm != NonModal::Dwell && nm != NonModal::G53 {
                axes_used = true;
                if let Some((Some(_), mw)) = motion_code {
                    if !axis_words.is_empty() {
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
            if self.frame().is_some() && matches!(nm, NonModal::G92 | NonModal::G52 | NonModal::G10)
            {
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
            match nm {
                NonModal::G10 => self.g10(line, &w, &get, &axis_words)?,
                NonModal::G28 | NonModal::G30 => {
                    let base = if nm == NonModal::G28 {
                        G28_PARAMETER
                    } else {
                        G30_PARAMETER
                    } as usize;
                    let start = self.pos;
                    let via = self.target(&axis_words, false);
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
                NonModal::G28_1 | NonModal::G30_1 => {
                    let base = if nm == NonModal::G28_1 {
                        G28_PARAMETER
                    } else {
                        G30_PARAMETER
                    } as usize;
                    for a in Axis::ALL {
                        self.params.numbered[base + a.index()] = self.pos[a];
                    }
                }
                NonModal::G92 | NonModal::G52 => {
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
                }
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
                NonModal::Dwell | NonModal::G53 => {}
            }
        }
        // 7. Motion.
        let mut arc_buf = [Word::EMPTY; 4];
        let mut n_arc = 0;
        for l in ['I', 'J', 'K', 'R'] {
            if let Some(w) = get(l) {
                arc_buf[n_arc] = w;
                n_arc += 1;
            }
        }
        let arc_words = &arc_buf[..n_arc];
        let g53 = matches!(nonmodal, Some((NonModal::G53, _)));
        if !axes_used
            && (!axis_words.is_empty()
                || (!arc_words.is_empty() && !matches!(self.motion, Some(MotionMode::Cycle(_)))))
        {
            let mut first = usize::MAX..usize::MAX;
            for w in axis_words.iter().map(|(_, w)| w).chain(arc_words.iter()) {
                if w.span.0 < first.start {
                    first = w.span();
                }
            }
            let Some(mode) = self.motion else {
                return Err(LineError::new(first, "axis word with no motion mode: expected G00, G01, G02 or G03 in this or an earlier block", "no motion mode"));
            };
            if !matches!(mode, MotionMode::Arc { .. }) {
                if let Some(w) = arc_words
                    .iter()
                    .find(|w| !(matches!(mode, MotionMode::Cycle(_)) && w.letter == 'R'))
                {
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
            if g53 && !self.absolute {
                return Err(LineError::new(
                    first,
                    "G53 in G91: expected G53 only in absolute mode (G90)",
                    "G53 incremental",
                ));
            }
            let at = motion_code
                .and_then(|(_, w)| Some(w.span()))
                .unwrap_or(first.clone());
            if mode != MotionMode::Rapid {
                match self.feed_mode {
                    FeedRead::InverseTime if feed_word.is_none() => {
                        return Err(LineError::new(at, "feed move in G93 (inverse time) without F: expected an F word in every G01/G02/G03 block", "no F in this block").help("add F = 1 / (block time in minutes) to this block"));
                    }
                    FeedRead::PerRevolution if self.spindle_rpm == 0.0 => {
                        return Err(LineError::new(at, "feed per revolution (G95) with the spindle speed zero: expected an S word", "no S"));
                    }
                    _ if self.feed.is_none() || self.feed == Some(0.0) => {
                        return Err(LineError::new(at, "feed move with no feed programmed: expected an F word (mm/min) in this or an earlier block", "no F in effect").help("add F, e.g. `F1000` for 1000 mm/min"));
                    }
                    _ => {}
                }
            }
            let start = self.pos;
            if self.comp.is_some()
                && (g53 || matches!(mode, MotionMode::Cycle(_)) || self.plane != Plane::XY)
            {
                return Err(LineError::new(at, "G53, a canned cycle or a plane other than G17 with cutter radius compensation on: expected G40 first", "not with compensation"));
            }
            if self.frame().is_some() && matches!(mode, MotionMode::Cycle(_)) {
                return Err(LineError::new(
                    at,
                    "canned cycle with G68.2 or G254 active: not supported yet",
                    "cycle in a tilted frame",
                )
                .help("post the holes as G00/G01 moves"));
            }
            match mode {
                MotionMode::Cycle(code) => {
                    self.cycle(line, code, &get, line_no, queue, first)?;
                }
                _ => {
                    let target = self.target(&axis_words, g53);
                    let motion = match mode {
                        MotionMode::Rapid => Motion::Rapid,
                        MotionMode::Linear => Motion::Linear,
                        MotionMode::Arc { clockwise } if self.frame().is_some() => {
                            self.tilted_arc(line, &get, &words, clockwise, target, at.clone())?
                        }
                        MotionMode::Arc { clockwise } => {
                            let center_mm =
                                self.arc_center(line, &get, &words, clockwise, start, target)?;
                            Motion::Arc {
                                clockwise,
                                plane: self.plane,
                                center_mm,
                            }
                        }
                        MotionMode::Cycle(_) => unreachable!("handled above"),
                    };
                    if self.comp.is_some() {
                        self.comp_element(queue, line_no, motion, start, target)
                            .map_err(|m| LineError::new(at, m, "cutter compensation"))?;
                    } else {
                        self.emit(queue, line_no, motion, start, target, self.path);
                    }
                    self.pos = target;
                }
            }
        }
        // 8. Program flow M codes.
        for &(code, w) in m.iter() {
            match code {
                2 | 30 => {
                    self.finish(queue);
                    return Ok(Stop::End);
                }
                98 => {
                    let p = get('P').ok_or_else(|| {
                        LineError::new(
                            w.span(),
                            "M98 without P: expected `M98 P<program number>`",
                            "no P",
                        )
                    })?;
                    if !dialect.is_fanuc_family() {
                        return Err(LineError::new(
                            w.span(),
                            "M98 in a LinuxCNC program: expected `o<name> call`",
                            "Fanuc code",
                        )
                        .help("set dialect = \"fanuc\" for Fanuc programs"));
                    }
                    let repeats = get('L').map_or(1, |l| l.value.round() as u64);
                    return Ok(Stop::Call {
                        label: format!("{}", p.value.round() as u64),
                        repeats,
                        args: Vec::new(),
                        locals: false,
                        span: w.span(),
                    });
                }
                99 => return Ok(Stop::Return { span: w.span() }),
                _ => {}
            }
        }
        Ok(stop)
    }

    /// Fanuc `G65 P<program> [L<count>] <arguments>`: a macro call with its own locals;
    /// argument specification I (A→#1, B→#2, C→#3, I→#4, J→#5, K→#6, D→#7, E→#8, F→#9,
    /// H→#11, M→#13, Q→#17, R→#18, S→#19, T→#20, U→#21, V→#22, W→#23, X→#24, Y→#25, Z→#26).
    fn g65(&mut self, line: &str, words: &[Word], g65: Word) -> LineResult<Stop> {
        let mut args = vec![0.0; 33];
        let mut program = None;
        let mut repeats = 1;
        for w in words {
            let slot = match w.letter {
                'P' => {
                    program = Some(integer(w, line)?);
                    continue;
                }
                'L' => {
                    repeats = integer(w, line)?.max(1);
                    continue;
                }
                'N' => continue,
                'G' if w.span == g65.span => continue,
                'A' => 1,
                'B' => 2,
                'C' => 3,
                'I' => 4,
                'J' => 5,
                'K' => 6,
                'D' => 7,
                'E' => 8,
                'F' => 9,
                'H' => 11,
                'M' => 13,
                'Q' => 17,
                'R' => 18,
                'S' => 19,
                'T' => 20,
                'U' => 21,
                'V' => 22,
                'W' => 23,
                'X' => 24,
                'Y' => 25,
                'Z' => 26,
                _ => {
                    return Err(LineError::new(w.span(), format!("`{}` in a G65 block: expected P, L and arguments A-Z (not G, L, N, O, P)", &line[w.span()]), "not a G65 argument"));
                }
            };
            args[slot - 1] = w.value;
        }
        let Some(p) = program else {
            return Err(LineError::new(
                g65.span(),
                "G65 without P: expected `G65 P<program number>`",
                "no P",
            ));
        };
        Ok(Stop::Call {
            label: p.to_string(),
            repeats,
            args,
            locals: true,
            span: g65.span(),
        })
    }

    /// A word no code of the block (or the modal motion) uses is an error, never dropped.
    fn unused_words<'l>(
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
        let dwell_cycle = matches!(motion, Some(MotionMode::Cycle(820 | 860 | 890)));
        let g10 = has_g(&|c| matches!(c, GCode::NonModal(NonModal::G10)));
        let checks: [(char, bool, &str); 5] = [
            ('P', has_g(&|c| matches!(c, GCode::NonModal(NonModal::Dwell) | GCode::Path(4) | GCode::CoordExtended | GCode::Control(80 | 1030 | 1870))) || g10 || dwell_cycle || has_m(&[19, 50, 51, 52, 53, 62, 63, 64, 65, 66, 98, 99]), "`P` with no code that uses it: expected P only with G04, G10, G64, G54.1, G82/G86/G89, M19, M50-M53, M62-M66 or M98"),
            ('Q', has_g(&|c| matches!(c, GCode::Path(4) | GCode::Control(51))) || peck || has_m(&[19, 61, 66, 67, 68]), "`Q` with no code that uses it: expected Q only with G64, G73/G83, M19, M61 or M66-M68"),
            ('L', g10 || cycle || has_m(&[66, 98]), "`L` with no code that uses it: expected L only with G10, a canned cycle, M66 or M98"),
            ('E', has_m(&[66, 67, 68]) || has_g(&|c| matches!(c, GCode::Control(1870))), "`E` with no code that uses it: expected E only with M66-M68"),
            ('D', has_g(&|c| matches!(c, GCode::CutterComp(1..=4))), "`D` with no code that uses it: expected D only with G41, G42, G41.1 or G42.1"),
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

    /// Dwell time: LinuxCNC P s; Fanuc P ms or X s; Haas P s with a decimal point, ms without.
    fn dwell_seconds(
        &self,
        line: &str,
        g04: &Word,
        p: Option<Word>,
        x: Option<Word>,
    ) -> LineResult<f64> {
        // In LinuxCNC X is an axis word, never a dwell time.
        let x = if self.dialect == Dialect::Linuxcnc {
            None
        } else {
            x
        };
        let (seconds, w) = match (p, x, self.dialect) {
            (Some(p), None, Dialect::Linuxcnc) => (p.value, p),
            (Some(p), None, Dialect::Fanuc) => (p.value / 1000.0, p),
            (Some(p), None, Dialect::Haas) => (
                if p.number.contains('.') {
                    p.value
                } else {
                    p.value / 1000.0
                },
                p,
            ),
            (None, Some(x), d) if d.is_fanuc_family() => (x.value, x),
            (Some(_), Some(x), d) if d.is_fanuc_family() => {
                return Err(LineError::new(
                    x.span(),
                    "G04 with both P and X: expected one dwell time",
                    "second dwell time",
                ));
            }
            _ => {
                let help = if self.dialect.is_fanuc_family() {
                    "e.g. `G04 P500` dwells 0.5 s"
                } else {
                    "e.g. `G4 P0.5` dwells 0.5 s (LinuxCNC: P in seconds)"
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

    /// The machine target of axis words (program coordinates, or machine with G53).
    fn target(&self, axis_words: &[(Axis, Word)], g53: bool) -> AxisVec {
        if let (Some(f), false) = (self.frame(), g53) {
            // Program X Y Z in the feature / table-fixed frame; rotary words as usual.
            let mut p = f.to_program(self.tip(), &self.offset, &self.pos);
            let mut target = self.pos;
            for &(a, w) in axis_words {
                if a.is_rotary() {
                    target[a] = if self.absolute {
                        w.value + self.offset[a]
                    } else {
                        self.pos[a] + w.value
                    };
                } else {
                    let v = w.value * self.scale();
                    let k = a.index();
                    p[k] = if self.absolute { v } else { p[k] + v };
                }
            }
            let m = f.to_machine(p, &self.offset, &target);
            for a in Axis::LINEAR {
                target[a] = m[a.index()];
            }
            target[Axis::Z] += self.tool_length_mm;
            return target;
        }
        let mut target = self.pos;
        for &(a, w) in axis_words {
            let v = if a.is_rotary() {
                w.value
            } else {
                w.value * self.scale()
            };
            target[a] = if g53 {
                v
            } else if self.absolute {
                v + self.offset[a]
                    + if a == Axis::Z {
                        self.tool_length_mm
                    } else {
                        0.0
                    }
            } else {
                self.pos[a] + v
            };
        }
        target
    }

    fn g10<'l>(
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
                if let Some(r) = get('R') {
                    if r.value != 0.0 {
                        return Err(LineError::new(
                            r.span(),
                            "rotated work systems (G10 R) are not supported yet: expected R0",
                            "rotation",
                        ));
                    }
                }
                let coord = if pn == 0.0 { self.coord } else { pn as u32 };
                let base = coord_parameter(coord);
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

    /// Canned cycle in the current plane, expanded as LinuxCNC does (interp_cycles.cc).
    fn cycle<'l>(
        &mut self,
        line: &str,
        code: u32,
        get: &dyn Fn(char) -> Option<Word<'l>>,
        line_no: usize,
        queue: &mut VecDeque<Move>,
        first: std::ops::Range<usize>,
    ) -> LineResult<()> {
        let (u, v, n) = self.plane.axes();
        let scale = self.scale();
        let at = first.clone();
        if let Some(r) = get('R') {
            self.cycle_r = Some(r.value * scale);
        }
        if let Some(z) = get(n.letter()) {
            self.cycle_z = Some(z.value * scale);
        }
        if let Some(q) = get('Q') {
            if q.value <= 0.0 {
                return Err(LineError::new(
                    q.span(),
                    "Q in a peck cycle: expected a peck depth greater than zero",
                    "Q not positive",
                ));
            }
            self.cycle_q = Some(q.value * scale);
        }
        if let Some(p) = get('P') {
            self.cycle_p = Some(p.value);
        }
        let r_prog = self.cycle_r.ok_or_else(|| {
            LineError::new(
                at.clone(),
                "canned cycle without R: expected the retract plane R",
                "no R",
            )
        })?;
        let z_prog = self.cycle_z.ok_or_else(|| {
            LineError::new(
                at.clone(),
                format!(
                    "canned cycle without {}: expected the hole bottom",
                    n.letter()
                ),
                "no bottom",
            )
        })?;
        let repeats = get('L').map_or(1, |l| l.value.round() as u64);
        let tlo = |a: Axis| {
            if a == Axis::Z {
                self.tool_length_mm
            } else {
                0.0
            }
        };
        // Everything in machine coordinates along n, and for u v.
        let old_n = self.pos[n];
        let (r, bottom, du, dv, mut pu, mut pv);
        if self.absolute {
            r = r_prog + self.offset[n] + tlo(n);
            bottom = z_prog + self.offset[n] + tlo(n);
            du = 0.0;
            dv = 0.0;
            pu = get(u.letter()).map_or(self.pos[u], |w| w.value * scale + self.offset[u] + tlo(u));
            pv = get(v.letter()).map_or(self.pos[v], |w| w.value * scale + self.offset[v] + tlo(v));
        } else {
            r = old_n + r_prog;
            bottom = r + z_prog;
            du = get(u.letter()).map_or(0.0, |w| w.value * scale);
            dv = get(v.letter()).map_or(0.0, |w| w.value * scale);
            pu = self.pos[u];
            pv = self.pos[v];
        }
        if r < bottom {
            return Err(LineError::new(
                at,
                format!(
                    "retract plane R below the hole bottom {}: expected R above it",
                    n.letter()
                ),
                "R below bottom",
            ));
        }
        let delta = self.cycle_q.unwrap_or(0.0);
        if matches!(code, 730 | 830) && delta <= 0.0 {
            return Err(LineError::new(
                at,
                "peck cycle without Q: expected the peck depth Q",
                "no Q",
            ));
        }
        let pecks = if matches!(code, 730 | 830) {
            ((r - bottom) / delta.max(1e-9)).min(1e9)
        } else {
            0.0
        };
        if (repeats as f64) * (pecks + 4.0) > 1e7 {
            return Err(LineError::new(at, "canned cycle would make more than 10^7 moves: expected a larger Q or fewer repeats", "too many moves"));
        }
        let dwell = self.cycle_p.unwrap_or(0.0);
        let rapid_delta = 0.010 * MM_PER_INCH; // LinuxCNC's G73/G83 clearance, 0.010 in.
        let exact = PathControl::ExactPath;
        let mut cur = self.pos;
        let go = |me: &mut Interp,
                  queue: &mut VecDeque<Move>,
                  cur: &mut AxisVec,
                  motion: Motion,
                  pu: f64,
                  pv: f64,
                  pn: f64| {
            let mut t = *cur;
            t[u] = pu;
            t[v] = pv;
            t[n] = pn;
            me.emit(queue, line_no, motion, *cur, t, exact);
            *cur = t;
        };
        // The dwell at the hole bottom (G82, G86, G89): P seconds where the tool stands.
        let dwell_at = |me: &mut Interp, queue: &mut VecDeque<Move>, at: AxisVec| {
            me.emit(
                queue,
                line_no,
                Motion::Dwell { seconds: dwell },
                at,
                at,
                exact,
            );
        };
        let mut old = old_n;
        if old < r {
            go(
                self,
                queue,
                &mut cur,
                Motion::Rapid,
                self.pos[u],
                self.pos[v],
                r,
            );
            old = r;
        }
        let clear = if self.retract_r { r } else { old };
        for _ in 0..repeats {
            pu += du;
            pv += dv;
            go(self, queue, &mut cur, Motion::Rapid, pu, pv, old);
            if old != r {
                go(self, queue, &mut cur, Motion::Rapid, pu, pv, r);
            }
            match code {
                810 => {
                    go(self, queue, &mut cur, Motion::Linear, pu, pv, bottom);
                    go(self, queue, &mut cur, Motion::Rapid, pu, pv, clear);
                }
                820 | 860 => {
                    go(self, queue, &mut cur, Motion::Linear, pu, pv, bottom);
                    dwell_at(self, queue, cur);
                    go(self, queue, &mut cur, Motion::Rapid, pu, pv, clear);
                }
                830 | 730 => {
                    let mut depth = r - delta;
                    while depth > bottom {
                        go(self, queue, &mut cur, Motion::Linear, pu, pv, depth);
                        if code == 830 {
                            go(self, queue, &mut cur, Motion::Rapid, pu, pv, r);
                        }
                        go(
                            self,
                            queue,
                            &mut cur,
                            Motion::Rapid,
                            pu,
                            pv,
                            depth + rapid_delta,
                        );
                        depth -= delta;
                    }
                    go(self, queue, &mut cur, Motion::Linear, pu, pv, bottom);
                    go(self, queue, &mut cur, Motion::Rapid, pu, pv, clear);
                }
                850 => {
                    go(self, queue, &mut cur, Motion::Linear, pu, pv, bottom);
                    go(self, queue, &mut cur, Motion::Linear, pu, pv, r);
                    if clear != r {
                        go(self, queue, &mut cur, Motion::Rapid, pu, pv, clear);
                    }
                }
                _ => {
                    // G89
                    go(self, queue, &mut cur, Motion::Linear, pu, pv, bottom);
                    dwell_at(self, queue, cur);
                    // LinuxCNC feeds straight back to the clearance plane (checked with rs274).
                    go(self, queue, &mut cur, Motion::Linear, pu, pv, clear);
                }
            }
            old = clear;
        }
        self.pos = cur;
        let _ = line;
        Ok(())
    }

    /// The end of the program: a held compensated element ends as at G40.
    pub fn finish(&mut self, queue: &mut VecDeque<Move>) {
        self.comp_exit(queue);
    }

    /// Drops the held element (after an error).
    pub fn discard(&mut self) {
        self.held = None;
    }

    /// Pushes a held element ending at `end`, with the moves that wait with it.
    fn release(&mut self, queue: &mut VecDeque<Move>, mut h: comp::Held, end: [f64; 2]) -> AxisVec {
        comp::set_end(&mut h.mv, end);
        let mut last = h.mv.end;
        queue.push_back(h.mv);
        for mut m in h.after {
            comp::set_start(&mut m, end);
            comp::set_end(&mut m, end);
            last = m.end;
            queue.push_back(m);
        }
        last
    }

    /// G40 (or the end): the held element ends at `c + r n(t₁)`.
    fn comp_exit(&mut self, queue: &mut VecDeque<Move>) {
        let Some(h) = self.held.take() else { return };
        let left = self.comp.map_or(h.left, |c| c.0);
        let n = comp::normal(left, h.tangent);
        let end = [h.end[0] + h.radius * n[0], h.end[1] + h.radius * n[1]];
        self.release(queue, h, end);
        self.comp_actual = Some(end);
    }

    /// An X Y move under cutter radius compensation: joins the held element to this one.
    fn comp_element(
        &mut self,
        queue: &mut VecDeque<Move>,
        line_no: usize,
        motion: Motion,
        start: AxisVec,
        target: AxisVec,
    ) -> Result<(), String> {
        let (left, r) = self.comp.expect("compensation on");
        let s = [start[Axis::X], start[Axis::Y]];
        let e = [target[Axis::X], target[Axis::Y]];
        if s == e && matches!(motion, Motion::Arc { .. }) {
            return Err("full circle under cutter radius compensation: not supported yet; expected it split into two arcs".into());
        }
        if s == e {
            // No X Y motion: waits with the held element (or runs at the current point).
            self.emit(queue, line_no, motion, start, target, self.path);
            return Ok(());
        }
        let is_line = !matches!(motion, Motion::Arc { .. });
        let t_start = comp::tangent(&motion, s, e, false);
        let t_end = comp::tangent(&motion, s, e, true);
        if let Motion::Arc {
            clockwise,
            center_mm,
            ..
        } = motion
        {
            let radius = (s[0] - center_mm[0]).hypot(s[1] - center_mm[1]);
            // The tool is inside the arc for G41 counter-clockwise and G42 clockwise.
            let inside = left != clockwise;
            if inside && radius <= r {
                return Err(format!("arc of radius {radius:.4} mm with a tool of radius {r:.4} mm on its inside: expected a tool smaller than the arc (LinuxCNC: tool radius not less than arc radius with comp)"));
            }
        }
        let (feed, feed_mode) = self.feed_out();
        let new_start = match self.held.take() {
            None => {
                if !is_line {
                    return Err("arc as the entry move of cutter radius compensation: expected a straight entry move after G41/G42".into());
                }
                self.comp_actual.take().unwrap_or(s)
            }
            Some(h) => {
                let center = match motion {
                    Motion::Arc { center_mm, .. } => Some([center_mm[0], center_mm[1]]),
                    _ => None,
                };
                let join = comp::join(left, r, h.end, h.tangent, h.center, t_start, center)?;
                let held_end = match join {
                    comp::Join::Meet { end } => end,
                    comp::Join::Arc { p1, .. } => p1,
                };
                let (hs, t) = ([h.mv.start[Axis::X], h.mv.start[Axis::Y]], h.tangent);
                if h.center.is_none()
                    && (held_end[0] - hs[0]) * t[0] + (held_end[1] - hs[1]) * t[1] < -1e-9
                {
                    // As rs274: the compensated line would run backwards.
                    return Err("straight feed in a concave corner cannot be reached by the tool without gouging: expected a line longer than the tool radius".into());
                }
                match join {
                    comp::Join::Meet { end } => {
                        self.release(queue, h, end);
                        end
                    }
                    comp::Join::Arc { p1, p2, corner } => {
                        let last = self.release(queue, h, p1);
                        let mut end = last;
                        end[Axis::X] = p2[0];
                        end[Axis::Y] = p2[1];
                        queue.push_back(Move {
                            line: line_no,
                            motion: Motion::Arc {
                                clockwise: left,
                                plane: Plane::XY,
                                center_mm: [corner[0], corner[1], last[Axis::Z]],
                            },
                            start: last,
                            end,
                            feed,
                            feed_mode,
                            tcp: self.tcp,
                            tool: self.tool,
                            tool_length_mm: self.tool_length_mm,
                            path: self.path,
                        });
                        p2
                    }
                }
            }
        };
        let mut mv = Move {
            line: line_no,
            motion,
            start,
            end: target,
            feed,
            feed_mode,
            tcp: self.tcp,
            tool: self.tool,
            tool_length_mm: self.tool_length_mm,
            path: self.path,
        };
        comp::set_start(&mut mv, new_start);
        self.comp_actual = None;
        self.held = Some(comp::Held {
            mv,
            end: e,
            tangent: t_end,
            center: match motion {
                Motion::Arc { center_mm, .. } => Some([center_mm[0], center_mm[1]]),
                _ => None,
            },
            left,
            radius: r,
            after: Vec::new(),
        });
        Ok(())
    }

    /// An arc in the plane of a G68.2 or G254 frame: the centre is found in program
    /// coordinates, then mapped to the machine plane its normal turns into (the program
    /// plane must map onto G17, G18 or G19 of the machine; clockwise flips when the normal
    /// turns to the machine axis's negative direction).
    fn tilted_arc<'l>(
        &self,
        line: &str,
        get: &dyn Fn(char) -> Option<Word<'l>>,
        words: &[Word],
        clockwise: bool,
        target: AxisVec,
        at: std::ops::Range<usize>,
    ) -> LineResult<Motion> {
        let f = self.frame().expect("called with a frame");
        if Axis::ALL[3..].iter().any(|&a| target[a] != self.pos[a]) {
            return Err(LineError::new(at, "arc that turns a rotary axis with G68.2 or G254 active: expected the rotary axes still during G02/G03", "rotary arc in a tilted frame"));
        }
        let mut tip_end = [target[Axis::X], target[Axis::Y], target[Axis::Z]];
        tip_end[2] -= self.tool_length_mm;
        let ps = f.to_program(self.tip(), &self.offset, &self.pos);
        let pe = f.to_program(tip_end, &self.offset, &target);
        let (mut s, mut e) = (AxisVec::ZERO, AxisVec::ZERO);
        for k in 0..3 {
            s.0[k] = ps[k];
            e.0[k] = pe[k];
        }
        let c = self.arc_center(line, get, words, clockwise, s, e)?;
        let (_, _, n) = self.plane.axes();
        let mut normal = [0.0; 3];
        normal[n.index()] = 1.0;
        let mn = frame::apply(&f.direction_rotation(&target), normal);
        let Some(k) = (0..3).find(|&k| mn[k].abs() > 1.0 - 1e-9) else {
            return Err(LineError::new(at, format!("arc in a tilted plane whose normal is ({:.4}, {:.4}, {:.4}) in machine axes: expected it along X, Y or Z", mn[0], mn[1], mn[2]), "oblique arc plane").help("position the rotary axes with G53.1 first, or post the arc as lines"));
        };
        let plane = [Plane::YZ, Plane::ZX, Plane::XY][k];
        let mut center_mm = f.to_machine(c, &self.offset, &target);
        center_mm[2] += self.tool_length_mm;
        Ok(Motion::Arc {
            clockwise: clockwise != (mn[k] < 0.0),
            plane,
            center_mm,
        })
    }

    /// The absolute arc centre `[X, Y, Z]`, machine mm, from I J K or R.
    ///
    /// For R, with chord length d from s to e and midpoint m, the centre lies at distance
    /// `h = sqrt(R² - (d/2)²)` from m along the chord's normal; it is on the left of the
    /// direction of travel for a counter-clockwise short arc and for a clockwise long arc.
    fn arc_center<'l>(
        &self,
        line: &str,
        get: &dyn Fn(char) -> Option<Word<'l>>,
        words: &[Word],
        clockwise: bool,
        start: AxisVec,
        end: AxisVec,
    ) -> LineResult<[f64; 3]> {
        let scale = self.scale();
        let (u, v, n) = self.plane.axes();
        let letter = |axis: Axis| match axis {
            Axis::X => 'I',
            Axis::Y => 'J',
            _ => 'K',
        };
        let block_span = words
            .iter()
            .fold(None, |acc: Option<(usize, usize)>, w| {
                Some(acc.map_or(w.span, |(a, b)| (a.min(w.span.0), b.max(w.span.1))))
            })
            .map_or(0..line.len(), |(a, b)| a..b);
        if let Some(w) = get(letter(n)) {
            if self.dialect == Dialect::Linuxcnc || w.value != 0.0 {
                return Err(LineError::new(
                    w.span(),
                    format!(
                        "`{}` is not in the arc plane {}: expected {} and {}",
                        &line[w.span()],
                        self.plane.g_code(),
                        letter(u),
                        letter(v)
                    ),
                    "off-plane centre offset",
                )
                .help("select the plane of the arc with G17, G18 or G19"));
            }
        }
        let (su, sv) = (start[u], start[v]);
        let (eu, ev) = (end[u], end[v]);
        let mut center = [start[Axis::X], start[Axis::Y], start[Axis::Z]];
        let offsets = (get(letter(u)), get(letter(v)));
        match (get('R'), offsets) {
            (Some(r), (Some(w), _) | (_, Some(w))) => {
                let first = if r.span.0 < w.span.0 { w } else { r };
                Err(LineError::new(first.span(), "arc with both R and I J K: expected either the radius R or the centre offsets I J K", "second arc definition"))
            }
            (None, (None, None)) => Err(LineError::new(block_span, format!("arc without a centre: expected {} {} (centre offsets from the start) or R (radius)", letter(u), letter(v)), "no centre")),
            (None, (i, j)) => {
                let (cu, cv) = if self.arc_absolute {
                    // In a tilted frame, start and end are program coordinates already.
                    let tilted = self.frame().is_some();
                    let base = |a: Axis| if tilted { 0.0 } else { self.offset[a] + if a == Axis::Z { self.tool_length_mm } else { 0.0 } };
                    (i.map_or(su, |w| w.value * scale + base(u)), j.map_or(sv, |w| w.value * scale + base(v)))
                } else {
                    (su + i.map_or(0.0, |w| w.value * scale), sv + j.map_or(0.0, |w| w.value * scale))
                };
                let r_start = (su - cu).hypot(sv - cv);
                let r_end = (eu - cu).hypot(ev - cv);
                if r_start == 0.0 {
                    return Err(LineError::new(block_span, "arc of radius zero: expected centre offsets that are not all zero", "zero radius"));
                }
                let diff = (r_start - r_end).abs();
                let (ok, rule) = match self.dialect {
                    // LinuxCNC 2.9 (interp_arc.cc): fails when the difference exceeds
                    // 0.001 mm (0.00005 in) and 0.1 % of the radius... see docs/gcode.md.
                    Dialect::Linuxcnc => {
                        // Measured with rs274 2.9 (docs/gcode.md): an error only when the
                        // difference exceeds both 0.02·√2 mm (0.002·√2 in under G20) and
                        // 0.1 % of the start radius.
                        let abs_tol = std::f64::consts::SQRT_2 * if self.inch { 0.002 * MM_PER_INCH } else { 0.02 };
                        (diff <= abs_tol || diff / r_start <= 0.001, format!("{abs_tol:.4} mm or 0.1 % of the radius"))
                    }
                    _ => (diff <= FANUC_ARC_RADIUS_TOLERANCE_MM, format!("{FANUC_ARC_RADIUS_TOLERANCE_MM} mm")),
                };
                if !ok {
                    return Err(LineError::new(block_span, format!("arc radius at the start is {r_start:.6} mm but at the end {r_end:.6} mm: expected them to agree within {rule}"), "inconsistent arc")
                        .help("I J K are incremental from the start point (G91.1); check them and the end point"));
                }
                center[u.index()] = cu;
                center[v.index()] = cv;
                Ok(center)
            }
            (Some(r), (None, None)) => {
                let radius = r.value * scale;
                let (du, dv) = (eu - su, ev - sv);
                let chord = du.hypot(dv);
                if chord < FULL_CIRCLE_TOLERANCE_MM {
                    return Err(LineError::new(r.span(), "R arc whose end is its start: expected an end point away from the start (R cannot describe a full circle)", "R arc with no chord").help("program a full circle with I J K"));
                }
                if radius == 0.0 {
                    return Err(LineError::new(r.span(), "arc of radius zero: expected R other than zero", "zero radius"));
                }
                let half = chord / 2.0;
                let h2 = radius * radius - half * half;
                if h2 < 0.0 && half - radius.abs() > ARC_RADIUS_TOLERANCE_MM {
                    return Err(LineError::new(r.span(), format!("radius {:.6} mm is shorter than half the chord, {half:.6} mm: expected |R| of at least half the distance from start to end", radius.abs()), "radius too small"));
                }
                let h = h2.max(0.0).sqrt();
                let long = radius < 0.0;
                let left = !clockwise != long;
                let side = if left { h } else { -h };
                center[u.index()] = su + du / 2.0 - side * dv / chord;
                center[v.index()] = sv + dv / 2.0 + side * du / chord;
                Ok(center)
            }
        }
    }
}

/// A vector of at most `N` copies, on the stack. Its slots are not initialised until
/// pushed: filling them cost more than the rest of a plain G01 block.
struct Small<T: Copy, const N: usize> {
    items: [std::mem::MaybeUninit<T>; N],
    len: usize,
}

impl<T: Copy, const N: usize> Small<T, N> {
    fn new() -> Self {
        Small {
            items: [const { std::mem::MaybeUninit::uninit() }; N],
            len: 0,
        }
    }
    /// False when full.
    #[inline]
    fn push(&mut self, t: T) -> bool {
        if self.len == N {
            return false;
        }
        self.items[self.len] = std::mem::MaybeUninit::new(t);
        self.len += 1;
        true
    }
    fn remove(&mut self, k: usize) {
        self.items.copy_within(k + 1..self.len, k);
        self.len -= 1;
    }
}

impl<T: Copy, const N: usize> std::ops::Deref for Small<T, N> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        // SAFETY: `push` wrote items 0..len (and `remove` keeps them written), and
        // `MaybeUninit<T>` has the layout of `T`.
        unsafe { std::slice::from_raw_parts(self.items.as_ptr().cast::<T>(), self.len) }
    }
}

/// M-code groups (LinuxCNC's modal groups 4, 6, 7, 8, 9, 10); two of one group may not
/// share a block.
fn m_group(code: u32) -> Option<u8> {
    Some(match code {
        0 | 1 | 2 | 30 | 60 | 98 | 99 => 4,
        6 | 61 => 6,
        3 | 4 | 5 | 19 => 7,
        7 | 8 | 9 => 8,
        48..=53 => 9,
        _ => return None,
    })
}

/// The value of `word` as a non-negative integer.
fn integer(word: &Word, line: &str) -> LineResult<u64> {
    let bad = || {
        LineError::new(
            word.span(),
            format!(
                "`{}`: expected a whole number after `{}`",
                &line[word.span()],
                word.letter
            ),
            "expected a whole number",
        )
    };
    if word.computed() {
        if word.value < 0.0 || (word.value - word.value.round()).abs() > 1e-4 || word.value > 1e15 {
            return Err(bad());
        }
        return Ok(word.value.round() as u64);
    }
    let digits = word.number.strip_prefix('+').unwrap_or(word.number);
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) || digits.len() > 15 {
        return Err(bad());
    }
    Ok(word.value as u64)
}
