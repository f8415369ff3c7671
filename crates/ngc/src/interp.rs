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
use crate::polar::Polar;
use crate::probe;
use crate::notice::Notice;
use crate::units::{ARC_RADIUS_TOLERANCE_MM, FANUC_ARC_RADIUS_TOLERANCE_MM, MM_PER_INCH};
use crate::spline;

/// Lathe codes (G33, G33.1, G76): a child module, so it reads the modal state directly.
#[path = "lathe.rs"]
mod lathe;

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
    /// Lathe motion (LinuxCNC): G33 (330), G33.1 (331), G76 (760); crates/ngc/src/lathe.rs;
    /// G70 (700), G71 (710, 711, 712), G72 (720, 721, 722): crates/ngc/src/g7x.rs.
    Lathe(u32),
    /// Straight probe G38.2-G38.5 (LinuxCNC): the code ×10 (see `probe.rs`).
    Probe(u32),
    /// Splines G5 (50), G5.1 (51), NURBS G5.2 (52) (LinuxCNC, see `spline.rs`).
    Spline(u32),
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
    /// LinuxCNC G7 (true: X words are diameters) and G8 (false: radii).
    Diameter(bool),
    /// LinuxCNC G5.3: the end of a NURBS (G5.2) block sequence; motion group.
    NurbsEnd,
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
    Diameter,
}

impl GCode {
    fn group(self) -> Group {
        match self {
            GCode::Motion(_) | GCode::NurbsEnd => Group::Motion,
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
            GCode::Diameter(_) => Group::Diameter,
        }
    }

    // Inlined: the large result read back from memory after a call stalled every block.
    #[inline(always)]
    fn parse(word: &Word, line: &str, dialect: Dialect) -> LineResult<GCode> {
        // The codes of nearly every block, as written in most programs.
        match word.number {
            "1" | "01" => return Ok(GCode::Motion(Some(MotionMode::Linear))),
            "0" | "00" => return Ok(GCode::Motion(Some(MotionMode::Rapid))),
            _ => {}
        }
        let tenths = word.value * 10.0;
        // `round` without the call to libm: the same code for every value accepted below.
        let code = if tenths >= 0.0 {
            (tenths + 0.5) as i64 as f64
        } else {
            tenths.round()
        };
        let unsupported = |why: &str, help: &str| {
            let text = &line[word.span()];
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
            382..=385 if dialect == Dialect::Linuxcnc => GCode::Motion(Some(Probe(code as u32))),
            50..=52 if dialect == Dialect::Linuxcnc => GCode::Motion(Some(Spline(code as u32))),
            53 if dialect == Dialect::Linuxcnc => GCode::NurbsEnd,
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
            70 | 80 if dialect == Dialect::Linuxcnc => GCode::Diameter(code == 70.0),
            330 | 331 | 760 | 700 | 710 | 711 | 712 | 720 | 721 | 722
                if dialect == Dialect::Linuxcnc =>
            {
                GCode::Motion(Some(Lathe(code as u32)))
            }
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
            330 | 331 | 760 | 70 | 700..=722 => return Err(unsupported(" (G7, G33, G33.1, G70-G72 and G76 are read in the LinuxCNC dialect)", "set dialect = \"linuxcnc\"")),
            840 | 870 | 880 => return Err(unsupported(" (this canned cycle is not supported; G73 G81 G82 G83 G85 G86 G89 are)", "")),
            _ => return Err(unsupported("", "")),
        })
    }
}

/// The modal state of the controller between blocks.
pub struct Interp {
    pub params: Params,
    dialect: Dialect,
    axes: [bool; 9],
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
    /// M3 or M4 in effect (M5, M6, M2/M30 stop it, as rs274 does by default).
    spindle_turning: bool,
    /// G7: X words are diameters (LinuxCNC lathe mode); G8 (default): radii.
    diameter: bool,
    /// This block's G7 (true) or G8 (false) when it changed the mode (G76 reads it).
    diameter_switched: Option<bool>,
    /// A G70-G72 block waiting for the reader to read its profile subroutine.
    pub g7x: Option<Box<lathe::G7xRequest>>,
    tcp: bool,
    tools: HashMap<u32, Tool>,
    /// Lathe tool orientations by tool number (tool table Q).
    orientations: HashMap<u32, u32>,
    table_given: bool,
    tool: u32,
    next_tool: u32,
    /// A T word has selected `next_tool` since the last tool change (LinuxCNC's
    /// `selected_pocket >= 0`).
    tool_selected: bool,
    pockets: HashMap<u32, u32>,
    tool_length_mm: f64,
    /// Active work system: 1 = G54 ... 9 = G59.3, 10+ = G54.1 P1...
    coord: u32,
    /// Work offset + G92, machine minus program (before the tool length), cached.
    offset: AxisVec,
    /// LinuxCNC rotation of the active work system about Z (G10 L2 R), deg, cached, with
    /// its work offset and the G92 offset in X Y, mm: machine = rot(program + g92) + g5x.
    rotation: Option<(f64, [f64; 2], [f64; 2])>,
    path: PathControl,
    retract_r: bool,
    cycle_r: Option<f64>,
    cycle_z: Option<f64>,
    cycle_q: Option<f64>,
    cycle_p: Option<f64>,
    /// Initial level of the canned cycles in a row (machine coordinate along the plane's
    /// normal, mm): LinuxCNC keeps it from the first cycle block until a motion that is not
    /// a cycle, so G98 returns there and G91 measures R from it.
    cycle_initial: Option<f64>,
    /// G5: (I, J) for a following G5 without them, -(P, Q) of the last G5 (program units).
    spline_ij: [f64; 2],
    /// G5.2: the NURBS control points so far (program X Y, weight) and the order.
    nurbs: Vec<spline::ControlPoint>,
    nurbs_order: usize,
    user_m: HashMap<u32, UserM>,
    user_m_path: Vec<std::path::PathBuf>,
    noticed: Vec<u32>,
    saved: Option<Box<Saved>>,
    /// G68.2 feature frame: origin in work coordinates (mm) and rotation `R_f`.
    tilt: Option<([f64; 3], Mat3)>,
    /// Haas G254: the work offset follows the rotary table.
    dwo: bool,
    table: Option<RotaryTable>,
    /// Cutter radius compensation (G41/G42 to G40) and its queued moves.
    comp: Option<comp::Comp>,
    /// Where the tool is after G40 when it differs from `pos` (the next move starts there).
    comp_out: Option<AxisVec>,
    /// The move after G40 must be straight (LinuxCNC's `arc_not_allowed`).
    arc_not_allowed: bool,
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
        for (key, v) in &o.ini_values {
            params.set(
                &Param::Named(format!("_ini[{}", key.to_ascii_lowercase())),
                *v,
            );
        }
        for (pin, v) in &o.hal_pins {
            let name: String = pin.chars().filter(|c| !c.is_whitespace()).collect();
            params.set(
                &Param::Named(format!("_hal[{}]", name.to_ascii_lowercase())),
                *v,
            );
        }
        let mut axes = [false; 9];
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
            spindle_turning: false,
            diameter: false,
            diameter_switched: None,
            g7x: None,
            tcp: o.tcp,
            tools: o.tools.iter().map(|t| (t.number, *t)).collect(),
            orientations: o.tool_orientations.iter().copied().collect(),
            table_given: !o.tools.is_empty(),
            tool: 0,
            next_tool: 0,
            tool_length_mm: 0.0,
            coord: 1,
            offset: AxisVec::ZERO,
            rotation: None,
            path: PathControl::BLEND,
            // LinuxCNC starts in G99 (rs274's initial retract mode is the R plane).
            retract_r: o.dialect == Dialect::Linuxcnc,
            cycle_r: None,
            cycle_z: None,
            cycle_q: None,
            cycle_p: None,
            cycle_initial: None,
            spline_ij: [0.0; 2],
            nurbs: Vec::new(),
            nurbs_order: 3,
            user_m: o.user_m.clone(),
            user_m_path: o.user_m_path.clone(),
            tool_selected: false,
            pockets: o.pockets.iter().copied().collect(),
            noticed: Vec::new(),
            saved: None,
            tilt: None,
            dwo: false,
            table: o.table,
            comp: None,
            comp_out: None,
            arc_not_allowed: false,
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
        let r = if self.coord <= 9 {
            self.params.numbered[base + 9]
        } else {
            0.0
        };
        self.rotation = (r != 0.0).then(|| {
            let n = &self.params.numbered;
            let g92 = |k: usize| if g92_on { n[5211 + k] } else { 0.0 };
            (r, [n[base], n[base + 1]], [g92(0), g92(1)])
        });
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
        if self.rotation.is_some() {
            let xy = self.xy_to_program([self.pos[Axis::X], self.pos[Axis::Y]]);
            p[Axis::X] = xy[0];
            p[Axis::Y] = xy[1];
        }
        if let Some(f) = self.frame() {
            let pp = f.to_program(self.tip(), &self.offset, &self.pos);
            for a in Axis::LINEAR {
                p[a] = pp[a.index()];
            }
        }
        for a in Axis::ALL {
            if !a.is_rotary() {
                p[a] /= self.scale();
            }
        }
        p
    }

    /// Program X Y (mm) to machine X Y: `rot(p + g92, R) + g5x` (LinuxCNC
    /// `rotate_and_offset_pos`), or `p + offset` without a rotation.
    fn xy_to_machine(&self, p: [f64; 2]) -> [f64; 2] {
        match self.rotation {
            None => [p[0] + self.offset[Axis::X], p[1] + self.offset[Axis::Y]],
            Some((r, g5x, g92)) => {
                let q = rotate_deg([p[0] + g92[0], p[1] + g92[1]], r);
                [q[0] + g5x[0], q[1] + g5x[1]]
            }
        }
    }

    /// Machine X Y (mm) to program X Y (mm): the inverse of [`Interp::xy_to_machine`].
    fn xy_to_program(&self, m: [f64; 2]) -> [f64; 2] {
        match self.rotation {
            None => [m[0] - self.offset[Axis::X], m[1] - self.offset[Axis::Y]],
            Some((r, g5x, g92)) => {
                let q = rotate_deg([m[0] - g5x[0], m[1] - g5x[1]], -r);
                [q[0] - g92[0], q[1] - g92[1]]
            }
        }
    }

    /// A program X Y increment (mm) as a machine increment.
    fn xy_increment(&self, v: [f64; 2]) -> [f64; 2] {
        match self.rotation {
            None => v,
            Some((r, ..)) => rotate_deg(v, r),
        }
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

    /// LinuxCNC stdglue's `change_prolog` parameters: tool in the spindle, selected tool,
    /// their pockets; `None` when no tool is prepared ("M6: no tool prepared").
    pub fn tool_change_parameters(&mut self) -> Option<[(&'static str, f64); 4]> {
        if !self.tool_selected {
            return None;
        }
        self.refresh_system_parameters();
        let g = &self.params.globals;
        Some([
            ("tool_in_spindle", self.tool as f64),
            ("selected_tool", self.next_tool as f64),
            ("current_pocket", g["_current_pocket"]),
            ("selected_pocket", g["_selected_pocket"]),
        ])
    }

    /// The tool change of stdglue's `change_epilog` (M6 without the G43).
    pub fn complete_tool_change(&mut self) {
        self.tool = self.next_tool;
        self.tool_selected = false;
    }

    /// What LinuxCNC's stdglue handlers read of the interpreter (crate::stdglue).
    pub(crate) fn glue_view(&self) -> crate::stdglue::View {
        crate::stdglue::View {
            plane: self.plane,
            feed_zero: self.feed.is_none(),
            inverse_time: self.feed_mode == FeedRead::InverseTime,
            comp_on: self.comp.is_some(),
        }
    }

    /// The pocket of tool `n` (`find_tool_pocket`): `None` when a tool table is given
    /// without it.
    pub(crate) fn glue_pocket(&self, n: u32) -> Option<f64> {
        (n == 0 || !self.table_given || self.tools.contains_key(&n))
            .then(|| self.pockets.get(&n).map_or(n as f64, |p| *p as f64))
    }

    /// Commits a stdglue epilog (`SELECT_TOOL`, `CHANGE_TOOL_NUMBER`, spindle speed, feed
    /// rate in program units).
    pub(crate) fn glue_commit(&mut self, c: &crate::stdglue::Commit) {
        use crate::stdglue::Commit;
        match *c {
            Commit::SelectTool { tool, prepared } => {
                self.next_tool = tool;
                self.tool_selected = prepared;
            }
            Commit::ChangeTool => self.complete_tool_change(),
            Commit::SetToolNumber(n) => {
                self.tool = n;
                self.next_tool = n;
            }
            Commit::Speed(rpm) => self.spindle_rpm = rpm,
            Commit::Feed(f) => {
                self.feed = (f > 0.0).then(|| match self.feed_mode {
                    FeedRead::InverseTime => f,
                    _ => f * self.scale(),
                })
            }
            Commit::None | Commit::KeepMotion => {}
        }
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
                Some(MotionMode::Cycle(c) | MotionMode::Lathe(c) | MotionMode::Probe(c)) => {
                    c as f64
                }
                Some(MotionMode::Spline(c)) => c as f64,
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
        start: AxisVec,
        end: AxisVec,
        path: PathControl,
    ) {
        let feed = self.feed_out();
        self.emit_with_feed(queue, line, motion, start, end, path, feed);
    }

    /// [`Interp::emit`] with the feed given (spindle-synchronised moves: pitch × S).
    #[allow(clippy::too_many_arguments)]
    fn emit_with_feed(
        &mut self,
        queue: &mut VecDeque<Move>,
        line: usize,
        motion: Motion,
        start: AxisVec,
        end: AxisVec,
        path: PathControl,
        (feed, feed_mode): (Option<f64>, FeedMode),
    ) {
        if self.comp.is_none() && self.comp_out.is_none() {
            // Built in the queue: a move built on the stack in pieces and then copied in
            // (in 64-byte loads) stalled on every block.
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
            return;
        }
        let mut mv = Move {
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
        };
        if let Some(c) = &mut self.comp {
            // A dwell under compensation waits behind the queued moves; any other move
            // made here runs as programmed after them.
            if matches!(motion, Motion::Dwell { .. }) {
                c.dwell(mv, queue);
            } else {
                c.pass(mv, queue);
            }
            return;
        }
        if let Some(p) = self.comp_out {
            // The first move after G40 starts where the compensated path ended.
            mv.start = p;
            if matches!(motion, Motion::Dwell { .. }) {
                mv.end = p;
            } else {
                self.comp_out = None;
            }
        }
        queue.push_back(mv);
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
        if self.plain_move(words, line_no, queue) {
            return Ok(Stop::None);
        }
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
        // Per letter, the index in `words` of its word (`NONE`: not in this block); `@` and
        // `^` after Z (see `slot`).
        const NONE: u8 = u8::MAX;
        let mut single = [NONE; 28];
        // The same as bits (`1 << slot`): a plain `G01 X Y F` block skips each check of a
        // feature whose letters it has not (one test instead of a lookup per letter).
        let mut present = 0u32;
        let mut spindle_select = None;
        for (k, word) in words.iter().enumerate() {
            match word.letter {
                // LinuxCNC `$n`: the spindle M3/M4/M5/M19/S act on (one spindle simulated).
                '$' => {
                    // `$-1`: all spindles (with M5).
                    let ok = word.value.fract() == 0.0 && (-1.0..=8.0).contains(&word.value);
                    if !ok || spindle_select.replace(*word).is_some() {
                        return Err(LineError::new(
                            word.span(),
                            "expected one spindle selector `$-1`-`$8` per block",
                            "spindle selector",
                        ));
                    }
                }
                'G' => {
                    let code = GCode::parse(word, line, dialect)?;
                    // LinuxCNC accepts G80 beside G00/G01 (`G80 G0 Z10`): the cancel is implied.
                    let g80 = GCode::Motion(None);
                    if matches!(code, GCode::Motion(None))
                        && g.iter().any(|(c, _)| matches!(c, GCode::Motion(Some(_))))
                    {
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
                    let slot = &mut single[slot(letter)];
                    if let Some(first) = words.get(*slot as usize) {
                        return Err(LineError::new(word.span(), format!("repeated `{letter}` word (first `{}`): expected each of {EXPECTED_WORDS} at most once per block, apart from G and M", &line[first.span()]), "repeated word"));
                    }
                    *slot = k as u8;
                    present |= 1 << self::slot(letter);
                }
            }
        }
        // G7 (this block's or in effect): X words are diameters, everywhere X is read
        // (motion, G10, G92), as LinuxCNC halves them.
        self.diameter_switched = None;
        for &(c, _) in g.iter() {
            if let GCode::Diameter(d) = c {
                if d != self.diameter {
                    self.diameter_switched = Some(d);
                }
            }
        }
        for &(c, _) in g.iter() {
            if let GCode::Diameter(d) = c {
                self.diameter = d;
            }
        }
        let halve_x = self.diameter;
        let get = |l: char| {
            words.get(single[slot(l)] as usize).copied().map(|mut w| {
                if halve_x && l == 'X' {
                    w.value /= 2.0;
                }
                w
            })
        };
        if let Some(w) = spindle_select {
            if get('S').is_none() && !m.iter().any(|(c, _)| matches!(c, 3 | 4 | 5 | 19)) {
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
        let missing_axes = Axis::ALL
            .iter()
            .filter(|a| !self.axes[a.index()])
            .fold(0, |m, a| m | 1 << slot(a.letter()));
        let check: &[Axis] = if present & missing_axes != 0 {
            &Axis::ALL
        } else {
            &[]
        };
        for &a in check {
            if self.axes[a.index()] {
                continue;
            }
            if let Some(w) = get(a.letter()) {
                let has: Vec<String> = Axis::ALL
                    .iter()
                    .filter(|b| self.axes[b.index()])
                    .map(|b| b.letter().to_string())
                    .collect();
                return Err(LineError::new(w.span(), format!("`{}`: this machine has no {} axis (it has {})", &line[w.span()], a.letter(), has.join(" ")), "axis not on this machine")
                    .help(format!("run the program with a machine whose layout has a {} axis, or check the program is for this machine (a six-axis robot pose X Y Z A B C fits no machine mtsim models); a word for a missing axis is never dropped", a.letter())));
            }
        }
        // G41.1/G42.1 take the diameter itself in D.
        let d_diameter = g.iter().any(|(c, _)| matches!(c, GCode::CutterComp(3 | 4)));
        let block_motion = g
            .iter()
            .find_map(|(c, _)| match c {
                GCode::Motion(mm) => Some(*mm),
                _ => None,
            })
            .unwrap_or(self.motion);
        let g7x_block = matches!(block_motion, Some(MotionMode::Lathe(700..=722)));
        let integers: &[char] = if present & const { letters(&['N', 'T', 'H', 'D', 'L']) } != 0 {
            &['N', 'T', 'H', 'D', 'L']
        } else {
            &[]
        };
        for &letter in integers {
            // D is a length for G70-G72 and for G41.1/G42.1 (a diameter), a number elsewhere.
            let d_length =
                g7x_block || g.iter().any(|(c, _)| matches!(c, GCode::CutterComp(3 | 4)));
            if letter == 'D' && d_length {
                continue;
            }
            if let Some(word) = get(letter).filter(|_| letter != 'D' || !d_diameter) {
                integer(&word, line)?;
            }
        }
        let nonmodal = g.iter().find_map(|(c, w)| match c {
            GCode::NonModal(n) => Some((*n, *w)),
            _ => None,
        });
        if present & const { letters(&['P', 'Q', 'L', 'E', 'D']) } != 0 {
            self.unused_words(line, &g, &m, &get)?;
        }
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
            if f.value < 0.0 {
                return Err(LineError::new(
                    f.span(),
                    format!("`{}`: expected a feed of zero or more", &line[f.span()]),
                    "negative feed",
                ));
            }
            // F0 is accepted, as LinuxCNC does (a subroutine may restore a saved F of 0);
            // a feed move at F0 is then refused like one with no F at all.
            self.feed = (f.value > 0.0).then(|| match self.feed_mode {
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
            self.tool_selected = true;
        }
        let mut tcp_m = None;
        for &(code, w) in m.iter() {
            match code {
                6 if self.comp.is_some() => {
                    return Err(LineError::new(w.span(), "cannot change tools with cutter radius compensation on: expected G40 first", "tool change under compensation"));
                }
                6 => {
                    self.tool = self.next_tool;
                    // rs274's default: the spindle stops for a tool change.
                    self.spindle_turning = false;
                    // LinuxCNC resynchronises after a tool change: the program point
                    // becomes where the tool is (the compensated point after G40).
                    if let Some(p) = self.comp_out.take() {
                        self.pos = p;
                    }
                }
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
                        let file = self
                            .user_m_path
                            .iter()
                            .map(|d| d.join(format!("M{code}")))
                            .find(|p| p.is_file());
                        if file.is_none() && !self.user_m_path.is_empty() {
                            return Err(LineError::new(w.span(), format!("user code `{}` has no program `M{code}` on the configuration's USER_M_PATH or PROGRAM_PREFIX: LinuxCNC refuses it (unknown M code)", &line[w.span()]), "no user M program")
                                .help("add the M program to the configuration, or map the code in the scenario's user_m_codes"));
                        }
                        if !self.noticed.contains(&code) && self.noticed.len() < 100 {
                            self.noticed.push(code);
                            let what = file.map_or(String::new(), |f| {
                                format!(" (runs {}, an external program)", f.display())
                            });
                            notices.push(Notice { path: path.to_path_buf(), line: line_no, message: format!("user code M{code}{what} accepted and ignored (map it in the scenario's user_m_codes to give it an effect)") });
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
        // After M6 (LinuxCNC's order of execution): M3/M4 start the spindle, M5 stops it.
        for &(code, _) in m.iter() {
            match code {
                3 | 4 => self.spindle_turning = true,
                5 => self.spindle_turning = false,
                _ => {}
            }
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
                    self.comp_exit(queue)
                        .map_err(|m| LineError::new(w.span(), m, "cutter compensation"))?;
                }
                GCode::CutterComp(k) => {
                    if self.comp.is_some() {
                        return Err(LineError::new(w.span(), "cutter radius compensation turned on while it is on: expected G40 first", "compensation already on"));
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
                    let d = get('D');
                    let mut orientation = 0;
                    if let (true, Some(l)) = (k >= 3, get('L')) {
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
                        let n = d.map_or(self.tool, |d| d.value.round() as u32);
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
                            // LinuxCNC offsets any axis by its word; mtsim applies a tool
                            // length along Z only, so another axis word is refused, not dropped.
                            if let Some(o) = Axis::ALL
                                .iter()
                                .filter(|a| **a != Axis::Z)
                                .find_map(|a| get(a.letter()))
                            {
                                return Err(LineError::new(
                                    o.span(),
                                    format!("`{}` in a G43.1 block: expected only Z (mtsim applies the tool length offset along Z only)", &line[o.span()]),
                                    "offset not along Z",
                                ));
                            }
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
        if let Some((_, w)) = g.iter().find(|(c, _)| matches!(c, GCode::AlignRotary)) {
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
            }) || g
                .iter()
                .find_map(|(c, _)| match c {
                    GCode::Motion(mm) => Some(*mm),
                    _ => None,
                })
                .unwrap_or(self.motion)
                == Some(MotionMode::Lathe(760));
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
        if let Some((Some(MotionMode::Probe(_)), w)) = motion_code {
            let any_axis = Axis::ALL.iter().any(|a| get(a.letter()).is_some());
            if !any_axis && get('@').is_none() && get('^').is_none() {
                return Err(LineError::new(
                    w.span(),
                    format!("`{}` without axis words: expected the probe point (LinuxCNC: \"All axes missing with motion code\")", &line[w.span()]),
                    "no probe point",
                ));
            }
        }
        let previous_motion = self.motion;
        if let Some((mm, _)) = motion_code {
            if mm != self.motion || !matches!(mm, Some(MotionMode::Cycle(_))) {
                // A new cycle forgets nothing LinuxCNC keeps; G80 ends the cycle.
            }
            self.motion = mm;
            if !matches!(mm, Some(MotionMode::Cycle(_))) {
                self.cycle_initial = None;
            }
        }
        // Polar words `@` `^` become X Y words here, after the block's units and work system
        // took effect; in a G91 canned cycle they step each repeat (see `cycle`).
        let polar_word = if present & const { letters(&['@', '^']) } != 0 {
            get('@').or(get('^'))
        } else {
            None
        };
        let mut polar_cycle = false;
        // Only a polar block builds the pair: even filling it with `None` on every block
        // cost a store-forwarding stall (a 4-byte tag written, 48 bytes read back).
        let mut polar_xy: [Option<Word>; 2];
        let polar = match polar_word {
            Some(pw) => {
                polar_xy = [None, None];
                polar_cycle = self.polar_words(line, &pw, &get, nonmodal, &mut polar_xy)?;
                // By reference: copying the pair into each call cost a tenth of the read.
                Some(&polar_xy)
            }
            None => None,
        };
        let get = |l: char| match (l, polar) {
            ('X', Some([Some(x), _])) => Some(*x),
            ('Y', Some([_, Some(y)])) => Some(*y),
            _ => get(l),
        };
        let dwell_x = dialect.is_fanuc_family() && matches!(nonmodal, Some((NonModal::Dwell, _)));
        // Fixed buffers, no allocation per block. The words are copied from the block's
        // (written long before), not from `get`'s result (a stall per word).
        let mut axis_buf: Small<(Axis, Word), 9> = Small::new();
        for a in Axis::ALL {
            let mut halve = false;
            let k = slot(a.letter());
            // A reference: a value here was assembled in pieces on the stack and read
            // back whole into the buffer, a store-forwarding stall per word.
            let w = match (a, polar) {
                (Axis::X, Some([Some(x), _])) => x,
                (Axis::Y, Some([_, Some(y)])) => y,
                _ if present >> k & 1 == 1 => {
                    // X is a diameter under G7.
                    halve = halve_x && a == Axis::X;
                    &words[single[k] as usize]
                }
                _ => continue,
            };
            if !(dwell_x && a == Axis::X) {
                axis_buf.push_axis(a, w, halve);
            }
        }
        let axis_words = &axis_buf[..];
        // 6. Non-modal codes that use axis words.
        // G43.1 takes its Z as the tool length, not as a move.
        let mut axes_used = g
            .iter()
            .any(|(c, _)| matches!(c, GCode::ToolLength(1) | GCode::Tilt(true)));
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
        // M19 R is the spindle orientation angle, not an arc radius.
        let m19 = m.iter().any(|(c, _)| *c == 19);
        let arc_letters: &[char] = if present & const { letters(&['I', 'J', 'K', 'R']) } != 0 {
            &['I', 'J', 'K', 'R']
        } else {
            &[]
        };
        for &l in arc_letters {
            if l == 'R' && m19 {
                continue;
            }
            if let Some(w) = get(l) {
                arc_buf[n_arc] = w;
                n_arc += 1;
            }
        }
        let arc_words = &arc_buf[..n_arc];
        let g53 = matches!(nonmodal, Some((NonModal::G53, _)));
        // NURBS: G5.2 blocks collect control points, G5.3 moves along them.
        let nurbs_end = g
            .iter()
            .find(|(c, _)| matches!(c, GCode::NurbsEnd))
            .map(|(_, w)| *w);
        if nurbs_end.is_some() || self.motion == Some(MotionMode::Spline(52)) {
            let g52 = motion_code.map(|(_, w)| w);
            if self.nurbs_block(
                line,
                &get,
                nurbs_end,
                g52,
                previous_motion,
                axis_words,
                line_no,
                queue,
            )? {
                axes_used = true;
            }
        }
        if !axes_used
            && (!axis_words.is_empty()
                || polar_cycle
                || (!arc_words.is_empty() && !matches!(self.motion, Some(MotionMode::Cycle(_)))))
        {
            let mut first = polar_word.map_or(usize::MAX..usize::MAX, |w| w.span());
            for w in axis_words.iter().map(|(_, w)| w).chain(arc_words.iter()) {
                if w.span.0 < first.start {
                    first = w.span();
                }
            }
            let Some(mode) = self.motion else {
                return Err(LineError::new(first, "axis word with no motion mode: expected G00, G01, G02 or G03 in this or an earlier block", "no motion mode"));
            };
            if !matches!(mode, MotionMode::Arc { .. }) {
                if let Some(w) = arc_words.iter().find(|w| {
                    !(matches!(mode, MotionMode::Cycle(_)) && w.letter == 'R')
                        && !lathe::takes_arc_word(mode, w.letter)
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
            if let MotionMode::Probe(_) = mode {
                // LinuxCNC's convert_probe checks, in its order.
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
            if !matches!(mode, MotionMode::Rapid | MotionMode::Lathe(_)) {
                match self.feed_mode {
                    FeedRead::InverseTime if feed_word.is_none() => {
                        return Err(LineError::new(at, "feed move in G93 (inverse time) without F: expected an F word in every G01/G02/G03 block", "no F in this block").help("add F = 1 / (block time in minutes) to this block"));
                    }
                    FeedRead::PerRevolution if self.spindle_rpm == 0.0 => {
                        return Err(LineError::new(at, "feed per revolution (G95) with the spindle speed zero: expected an S word", "no S"));
                    }
                    _ if self.feed.is_none() || self.feed == Some(0.0) => {
                        return Err(LineError::new(at, "feed move with no feed programmed (or F0): expected a positive F word (mm/min) in this or an earlier block", "no F in effect").help("add F, e.g. `F1000` for 1000 mm/min"));
                    }
                    _ => {}
                }
            }
            let start = self.pos;
            if self.comp.as_ref().is_some_and(|c| {
                g53 || matches!(
                    mode,
                    MotionMode::Cycle(_) | MotionMode::Lathe(330 | 331 | 760 | 710..=722)
                ) || self.plane != c.plane
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
                && (matches!(mode, MotionMode::Cycle(_) | MotionMode::Lathe(_))
                    || (matches!(mode, MotionMode::Arc { .. }) && self.plane != Plane::XY))
            {
                return Err(LineError::new(
                    at,
                    "canned cycle, or arc outside G17, in a rotated work system (G10 L2 R): not supported yet",
                    "rotated work system",
                )
                .help("cancel the rotation with G10 L2 P0 R0 first"));
            }
            if self.frame().is_some() && matches!(mode, MotionMode::Cycle(_) | MotionMode::Lathe(_))
            {
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
                MotionMode::Lathe(code) => {
                    // G70-G72 first rapid to their X Z read as absolute, even in G91.
                    let absolute = self.absolute;
                    self.absolute |= (700..=722).contains(&code);
                    let target = self.target(&axis_words, g53);
                    self.absolute = absolute;
                    self.lathe(line, code, &get, line_no, queue, at.clone(), target)?;
                }
                MotionMode::Spline(code) => {
                    let target = self.target(&axis_words, g53);
                    self.spline(line, code, &get, line_no, queue, start, target, at)?;
                }
                MotionMode::Probe(code) => {
                    let target = self.target(&axis_words, g53);
                    self.probe(queue, line_no, code, start, target)
                        .map_err(|m| LineError::new(at, m, "probe move"))?;
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
                        MotionMode::Cycle(_)
                        | MotionMode::Lathe(_)
                        | MotionMode::Probe(_)
                        | MotionMode::Spline(_) => {
                            unreachable!("handled above")
                        }
                    };
                    let turns = match motion {
                        Motion::Arc { .. } => match get('P') {
                            Some(p) => turns(line, &p, self.feed_mode)?,
                            None => 1,
                        },
                        _ => 1,
                    };
                    if self.comp.is_some() && turns > 1 {
                        return Err(LineError::new(at, "an arc of several turns (P) under cutter radius compensation: not supported", "turns with compensation"));
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
                        // (Only for several turns: passing the points by value cost a
                        // stall on every block.)
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

    /// The block when it is a plain move: at most one `G0`/`G1` (written `0`, `00`, `1` or
    /// `01`), axis words of this machine's axes, at most one of each, and `F`, in a plain
    /// modal state (no cutter compensation, tilted or rotated frame, or diameter mode; a
    /// modal G0 or G1 when the block has no G word). It is interpreted as
    /// [`Interp::block`] would, step for step (feed, motion mode, target, move), without the
    /// checks and lookups of every other feature: most blocks of most programs. Returns
    /// false, having changed nothing, for any other block, and for one the general path
    /// would refuse (a negative F, a feed move with no feed), which then reports the error.
    fn plain_move(&mut self, words: &[Word], line_no: usize, queue: &mut VecDeque<Move>) -> bool {
        if self.comp.is_some()
            || self.diameter
            || self.rotation.is_some()
            || self.tilt.is_some()
            || self.dwo
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
        self.diameter_switched = None;
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

    /// Emits the pieces of a spline (program coordinates) as feed moves and arcs.
    fn spline_pieces(
        &mut self,
        queue: &mut VecDeque<Move>,
        line_no: usize,
        pieces: &[spline::Piece],
    ) {
        let scale = self.scale();
        for piece in pieces {
            let start = self.pos;
            let mut end = start;
            let e = piece.end();
            let e = self.xy_to_machine([e[0] * scale, e[1] * scale]);
            end[Axis::X] = e[0];
            end[Axis::Y] = e[1];
            let motion = match *piece {
                spline::Piece::Line { .. } => Motion::Linear,
                spline::Piece::Arc { center, ccw, .. } => {
                    let c = self.xy_to_machine([center[0] * scale, center[1] * scale]);
                    Motion::Arc {
                        clockwise: !ccw,
                        plane: Plane::XY,
                        center_mm: [c[0], c[1], start[Axis::Z]],
                    }
                }
            };
            self.emit(queue, line_no, motion, start, end, self.path);
            self.pos = end;
        }
    }

    /// The checks LinuxCNC's `convert_spline` makes, shared by G5, G5.1 and G5.2.
    fn spline_checks<'l>(
        &self,
        get: &dyn Fn(char) -> Option<Word<'l>>,
        at: &std::ops::Range<usize>,
    ) -> LineResult<()> {
        let err = |m: &str| Err(LineError::new(at.clone(), m.to_string(), "spline"));
        if self.comp.is_some() {
            return err("spline with cutter radius compensation on: expected G40 first (LinuxCNC: \"Cannot convert spline with cutter radius compensation\")");
        }
        if self.plane != Plane::XY {
            return err("spline outside G17: expected the XY plane (LinuxCNC: \"Splines must be in the XY plane\")");
        }
        if self.feed_mode == FeedRead::InverseTime {
            return err("spline in G93 (inverse time): not supported, expected G94");
        }
        if let Some(w) = ['Z', 'A', 'B', 'C'].into_iter().find_map(|l| get(l)) {
            return Err(LineError::new(w.span(), "axis word other than X Y in a spline block: expected X and Y only (LinuxCNC: \"Splines may not have motion in Z, A, B, or C\")", "not a spline axis"));
        }
        Ok(())
    }

    /// G5 (cubic) or G5.1 (quadratic) from `start` to `target` (machine coordinates).
    #[allow(clippy::too_many_arguments)]
    fn spline<'l>(
        &mut self,
        line: &str,
        code: u32,
        get: &dyn Fn(char) -> Option<Word<'l>>,
        line_no: usize,
        queue: &mut VecDeque<Move>,
        start: AxisVec,
        target: AxisVec,
        at: std::ops::Range<usize>,
    ) -> LineResult<()> {
        self.spline_checks(get, &at)?;
        let _ = line;
        let scale = self.scale();
        let prog = |p: AxisVec| {
            let q = self.xy_to_program([p[Axis::X], p[Axis::Y]]);
            [q[0] / scale, q[1] / scale]
        };
        let (s, e) = (prog(start), prog(target));
        let (i, j) = (get('I').map(|w| w.value), get('J').map(|w| w.value));
        let err = |m: &str| Err(LineError::new(at.clone(), m.to_string(), "spline"));
        let pieces = if code == 51 {
            let (Some(i), Some(j)) = (i, j) else {
                return err("G5.1 without I and J: expected both (LinuxCNC: \"Must specify both I and J with G5.1\")");
            };
            spline::pieces(&spline::quadratic(s, [i, j], e), 3)
        } else {
            let ij = match (i, j) {
                (Some(i), Some(j)) => [i, j],
                (None, None) => self.spline_ij,
                _ => return err("G5 with only one of I and J: expected both, or neither after a G5 (LinuxCNC: \"Must specify both I and J, or neither\")"),
            };
            let (Some(p), Some(q)) = (get('P').map(|w| w.value), get('Q').map(|w| w.value)) else {
                return err("G5 without P and Q: expected both (LinuxCNC: \"Must specify both P and Q with G5\")");
            };
            self.spline_ij = [-p, -q];
            spline::pieces(&spline::cubic(s, ij, e, [p, q]), 4)
        };
        self.spline_pieces(queue, line_no, &pieces);
        // The end is the programmed point exactly.
        self.pos = target;
        Ok(())
    }

    /// A G5.2 block (a control point) or a G5.3 block (the NURBS move). True when the
    /// block's axis words are used up.
    #[allow(clippy::too_many_arguments)]
    fn nurbs_block<'l>(
        &mut self,
        line: &str,
        get: &dyn Fn(char) -> Option<Word<'l>>,
        nurbs_end: Option<Word<'l>>,
        g52: Option<Word<'l>>,
        previous_motion: Option<MotionMode>,
        axis_words: &[(Axis, Word<'l>)],
        line_no: usize,
        queue: &mut VecDeque<Move>,
    ) -> LineResult<bool> {
        let at = nurbs_end
            .or(g52)
            .or(axis_words.first().map(|(_, w)| *w))
            .map_or(0..0, |w| w.span());
        let err = |m: &str| Err(LineError::new(at.clone(), m.to_string(), "NURBS"));
        if let Some(w) = nurbs_end {
            if previous_motion != Some(MotionMode::Spline(52)) {
                return err("G5.3 without G5.2 first: expected G5.2 control points before it (LinuxCNC: \"Cannot use G5.3 without G5.2 first\")");
            }
            if let Some((_, a)) = axis_words.first() {
                return Err(LineError::new(
                    a.span(),
                    format!("`{}` in a G5.3 block: expected G5.3 alone", &line[a.span()]),
                    "axis word with G5.3",
                ));
            }
            if self.nurbs.len() < self.nurbs_order {
                return Err(LineError::new(w.span(), format!("NURBS with {} control points: expected at least the order L = {} (LinuxCNC: \"You must specify a number of control points at least equal to the order\")", self.nurbs.len(), self.nurbs_order), "too few control points"));
            }
            let cps = std::mem::take(&mut self.nurbs);
            let pieces = spline::pieces(&cps, self.nurbs_order);
            self.spline_pieces(queue, line_no, &pieces);
            self.motion = None;
            return Ok(true);
        }
        if g52.is_none() && axis_words.is_empty() {
            return Ok(false);
        }
        self.spline_checks(get, &at)?;
        let (x, y) = (get('X'), get('Y'));
        if x.is_some() != y.is_some() {
            return err("G5.2 control point with only one of X and Y: expected both (LinuxCNC: \"You must specify both X and Y coordinates for Control Points\")");
        }
        let p = get('P').map(|w| w.value);
        if previous_motion != Some(MotionMode::Spline(52)) {
            self.nurbs.clear();
        }
        if x.is_none() && p.is_some_and(|p| p > 0.0) && !self.nurbs.is_empty() {
            return err("G5.2 with P and no X Y after the first control point (LinuxCNC: \"Can specify P without X and Y only for the first control point\")");
        }
        if x.is_some() && !p.is_some_and(|p| p > 0.0) {
            return err("G5.2 control point without a positive weight P: expected P > 0 (LinuxCNC: \"Must specify positive weight P for every Control Point\")");
        }
        if self.feed.is_none() {
            return err("NURBS with no feed programmed: expected an F word");
        }
        let scale = self.scale();
        if self.nurbs.is_empty() {
            let cur = self.program_position();
            self.nurbs.push(spline::ControlPoint {
                x: cur[Axis::X],
                y: cur[Axis::Y],
                w: if x.is_none() { p.unwrap_or(1.0) } else { 1.0 },
            });
            self.nurbs_order = 3;
        }
        if let Some(l) = get('L') {
            if l.value > 3.0 {
                self.nurbs_order = l.value.round() as usize;
            }
        }
        if x.is_some() {
            let t = self.target(axis_words, false);
            let q = self.xy_to_program([t[Axis::X], t[Axis::Y]]);
            self.nurbs.push(spline::ControlPoint {
                x: q[0] / scale,
                y: q[1] / scale,
                w: p.unwrap_or(1.0),
            });
        }
        if self.nurbs.len() > 10_000 {
            return err("more than 10000 NURBS control points: expected G5.3 before");
        }
        Ok(true)
    }

    /// A straight probe G38.2-G38.5 from `start` to `target` (machine coordinates) as
    /// rs274 standalone runs it: a feed move, the back-off, the probe parameters
    /// (`probe.rs`).
    fn probe(
        &mut self,
        queue: &mut VecDeque<Move>,
        line_no: usize,
        code: u32,
        start: AxisVec,
        target: AxisVec,
    ) -> Result<(), &'static str> {
        if start == target {
            // G38.2/G38.4 must move to make contact; G38.3/G38.5 just do nothing.
            if code == 382 || code == 384 {
                return Err("G38.2/G38.4 to the start point: expected a probe move (LinuxCNC: \"Start point too close to probe point\")");
            }
        } else {
            self.emit(queue, line_no, Motion::Linear, start, target, self.path);
        }
        self.pos = target;
        let at_target = self.program_position();
        for (k, v) in probe::parameters(at_target).into_iter().enumerate() {
            self.params.numbered[probe::FIRST_PARAMETER + k] = v;
        }
        let back = probe::backoff(start, target);
        if back != target {
            self.emit(queue, line_no, Motion::Linear, target, back, self.path);
            self.pos = back;
        }
        Ok(())
    }

    /// Checks the polar words of a block (LinuxCNC `enhance_block`, `find_ends`) and turns
    /// them into X and Y words in `single`. Returns true when they are left for a G91 canned
    /// cycle to apply at each repeat.
    fn polar_words<'l>(
        &self,
        line: &str,
        pw: &Word<'l>,
        get: &dyn Fn(char) -> Option<Word<'l>>,
        nonmodal: Option<(NonModal, Word<'l>)>,
        xy_out: &mut [Option<Word<'l>>; 2],
    ) -> LineResult<bool> {
        let err = |m: &str| LineError::new(pw.span(), m.to_string(), "polar coordinate");
        if self.dialect != Dialect::Linuxcnc {
            return Err(err(
                "polar coordinates `@` `^` in a Fanuc-family program: expected X and Y",
            )
            .help("polar coordinates are a LinuxCNC feature; set dialect = \"linuxcnc\""));
        }
        if let Some(xy) = get('X').or(get('Y')) {
            return Err(LineError::new(
                xy.span(),
                format!(
                    "`{}` with polar coordinates: expected either X Y or `@` `^`",
                    &line[xy.span()]
                ),
                "X or Y with polar",
            ));
        }
        if self.plane != Plane::XY {
            return Err(err(
                "polar coordinates outside G17: expected the XY plane (G17)",
            ));
        }
        if !self.axes[Axis::X.index()] || !self.axes[Axis::Y.index()] {
            return Err(err("polar coordinates on a machine without X and Y axes"));
        }
        if self.frame().is_some() {
            return Err(err(
                "polar coordinates with G68.2 or G254 active: not supported",
            ));
        }
        match nonmodal {
            Some((NonModal::G53, _)) => {
                return Err(err("polar coordinates with G53: expected program coordinates (LinuxCNC: \"Cannot use polar coordinates with G53\")"));
            }
            Some((NonModal::G10 | NonModal::G92 | NonModal::G52, w)) => {
                return Err(err(&format!(
                    "polar coordinates with `{}`: expected `@` `^` only for a move",
                    &line[w.span()]
                )));
            }
            _ => {}
        }
        let polar = Polar {
            radius: get('@').map(|w| w.value),
            angle_deg: get('^').map(|w| w.value),
        };
        if !self.absolute && matches!(self.motion, Some(MotionMode::Cycle(_))) && nonmodal.is_none()
        {
            return Ok(true);
        }
        let p = self.program_position();
        let cur = [p[Axis::X], p[Axis::Y]];
        let xy = if self.absolute {
            polar.absolute(cur)
        } else {
            polar.incremental(cur)
        }
        .map_err(err)?;
        for (k, letter) in ['X', 'Y'].into_iter().enumerate() {
            xy_out[k] = Some(Word {
                letter,
                value: if self.absolute { xy[k] } else { xy[k] - cur[k] },
                number: "",
                span: pw.span,
            });
        }
        Ok(false)
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
        let cubic = matches!(motion, Some(MotionMode::Spline(50)));
        let nurbs = matches!(motion, Some(MotionMode::Spline(52)));
        let dwell_cycle = matches!(motion, Some(MotionMode::Cycle(820 | 860 | 890)));
        // LinuxCNC G2/G3 P<turns>.
        let arc_turns =
            self.dialect == Dialect::Linuxcnc && matches!(motion, Some(MotionMode::Arc { .. }));
        let g10 = has_g(&|c| matches!(c, GCode::NonModal(NonModal::G10)));
        let thread = motion == Some(MotionMode::Lathe(760));
        let g7x = matches!(motion, Some(MotionMode::Lathe(700..=722)));
        // LinuxCNC passes P and Q to user M codes (M100-M199 programs, mapped codes).
        let user = m
            .iter()
            .any(|(c, _)| (100..=199).contains(c) || self.user_m.contains_key(c));
        let checks: [(char, bool, &str); 5] = [
            ('P', thread || g7x || cubic || nurbs || has_g(&|c| matches!(c, GCode::NonModal(NonModal::Dwell) | GCode::Path(4) | GCode::CoordExtended | GCode::Control(80 | 1030 | 1870))) || g10 || dwell_cycle || has_m(&[19, 50, 51, 52, 53, 62, 63, 64, 65, 66, 98, 99]) || user || arc_turns, "`P` with no code that uses it: expected P only with G02/G03 (turns), G04, G5, G5.2, G10, G64, G54.1, G82/G86/G89, G76, M19, M50-M53, M62-M66, M98 or a user M code"),
            ('Q', has_g(&|c| matches!(c, GCode::Path(4) | GCode::Control(51))) || peck || thread || g7x || cubic || has_m(&[19, 61, 66, 67, 68]) || user, "`Q` with no code that uses it: expected Q only with G5, G64, G73/G83, G76, M19, M61, M66-M68 or a user M code"),
            ('L', g10 || cycle || thread || nurbs || has_m(&[66, 98]) || has_g(&|c| matches!(c, GCode::CutterComp(3 | 4))), "`L` with no code that uses it: expected L only with G10, G5.2, a canned cycle, G41.1/G42.1, G76, M66 or M98"),
            ('E', thread || g7x || has_m(&[66, 67, 68]) || has_g(&|c| matches!(c, GCode::Control(1870))), "`E` with no code that uses it: expected E only with G76 and M66-M68"),
            ('D', g7x || has_g(&|c| matches!(c, GCode::CutterComp(1..=4))), "`D` with no code that uses it: expected D only with G41, G42, G41.1 or G42.1"),
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
            // Program X Y Z in the feature / table-fixed frame; rotary (and U V W) words as
            // usual.
            let mut p = f.to_program(self.tip(), &self.offset, &self.pos);
            let mut target = self.pos;
            for &(a, w) in axis_words {
                if a.is_rotary() || a.is_secondary() {
                    let v = if a.is_rotary() {
                        w.value
                    } else {
                        w.value * self.scale()
                    };
                    target[a] = if self.absolute {
                        v + self.offset[a]
                    } else {
                        self.pos[a] + v
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
        if let (Some(_), false) = (self.rotation, g53) {
            // A rotated work system (G10 L2 R): X Y words in the rotated frame.
            let scale = self.scale();
            let word = |l: Axis| {
                axis_words
                    .iter()
                    .find(|(a, _)| *a == l)
                    .map(|(_, w)| w.value * scale)
            };
            let (x, y) = (word(Axis::X), word(Axis::Y));
            if x.is_some() || y.is_some() {
                let xy = if self.absolute {
                    let p = self.xy_to_program([self.pos[Axis::X], self.pos[Axis::Y]]);
                    self.xy_to_machine([x.unwrap_or(p[0]), y.unwrap_or(p[1])])
                } else {
                    let d = self.xy_increment([x.unwrap_or(0.0), y.unwrap_or(0.0)]);
                    [self.pos[Axis::X] + d[0], self.pos[Axis::Y] + d[1]]
                };
                target[Axis::X] = xy[0];
                target[Axis::Y] = xy[1];
            }
        }
        // Axis by axis (constant indices, so `target` stays in registers): stored by each
        // word's axis and returned whole, it was read back in pieces larger than written,
        // a store-forwarding stall on every block. The words are in `Axis::ALL` order, as
        // the block collects them.
        debug_assert!(axis_words
            .windows(2)
            .all(|p| p[0].0.index() < p[1].0.index()));
        let mut words = axis_words.iter().peekable();
        for a in Axis::ALL {
            let Some(&(_, w)) = words.next_if(|(b, _)| *b == a) else {
                continue;
            };
            if self.rotation.is_some() && !g53 && matches!(a, Axis::X | Axis::Y) {
                continue;
            }
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
                let coord = if pn == 0.0 { self.coord } else { pn as u32 };
                let base = coord_parameter(coord);
                if let Some(r) = get('R') {
                    if r.value != 0.0
                        && (self.dialect != Dialect::Linuxcnc || l.value.round() as u32 != 2)
                    {
                        return Err(LineError::new(
                            r.span(),
                            "rotated work systems: expected R only with G10 L2 in the linuxcnc dialect",
                            "rotation",
                        ));
                    }
                    if self.dialect == Dialect::Linuxcnc && coord <= 9 {
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
        // The hole is placed by the plane's axes; another axis word would be lost.
        if let Some(w) = Axis::ALL
            .iter()
            .filter(|a| ![u, v, n].contains(a))
            .find_map(|a| get(a.letter()))
        {
            return Err(LineError::new(
                w.span(),
                format!(
                    "`{}` in a canned cycle: expected only {} {} {} (LinuxCNC: \"Cannot put an A in canned cycle\")",
                    &line[w.span()],
                    u.letter(),
                    v.letter(),
                    n.letter()
                ),
                "axis word in a cycle",
            ));
        }
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
        let old_n = *self.cycle_initial.get_or_insert(self.pos[n]);
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
        // LinuxCNC's CYCLE_MACRO: the first hole is approached at the current level (when
        // above R), the next ones at the clear level.
        let mut current = self.pos[n];
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
            current = r;
        }
        let clear = if self.retract_r { r } else { old };
        let polar = Polar {
            radius: get('@').map(|w| w.value),
            angle_deg: get('^').map(|w| w.value),
        };
        for k in 0..repeats {
            pu += du;
            pv += dv;
            if !self.absolute && polar.is_some() {
                // G91 polar: each repeat turns (and moves out) about the work origin.
                let (ox, oy) = (self.offset[Axis::X], self.offset[Axis::Y]);
                let xy = polar
                    .cycle_step([(pu - ox) / scale, (pv - oy) / scale])
                    .map_err(|m| LineError::new(at.clone(), m, "polar coordinate"))?;
                pu = xy[0] * scale + ox;
                pv = xy[1] * scale + oy;
            }
            if k == 0 && current > r {
                go(self, queue, &mut cur, Motion::Rapid, pu, pv, current);
                go(self, queue, &mut cur, Motion::Rapid, pu, pv, r);
            } else {
                go(self, queue, &mut cur, Motion::Rapid, pu, pv, clear);
                if clear > r {
                    go(self, queue, &mut cur, Motion::Rapid, pu, pv, r);
                }
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
        }
        self.pos = cur;
        let _ = line;
        Ok(())
    }

    /// The end of the program: the queued compensated moves end as at G40.
    pub fn finish(&mut self, queue: &mut VecDeque<Move>) {
        // As LinuxCNC's M2: the queue ends at the compensated point; a gouge found there
        // was already reported with the move that made it.
        let _ = self.comp_exit(queue);
    }

    /// Drops the queued compensated moves (after an error).
    pub fn discard(&mut self) {
        self.comp = None;
    }

    /// G40: the queued moves end at the compensated point, where the next move starts.
    fn comp_exit(&mut self, queue: &mut VecDeque<Move>) -> Result<(), String> {
        let Some(mut c) = self.comp.take() else {
            return Ok(());
        };
        let was_on = c.radius > 0.0 && c.started();
        let out = c.off(queue)?;
        if was_on {
            self.arc_not_allowed = true;
        }
        self.comp_out = (out != self.pos).then_some(out);
        Ok(())
    }

    /// A move under cutter radius compensation, as programmed from `start` to `target`.
    fn comp_element(
        &mut self,
        queue: &mut VecDeque<Move>,
        line_no: usize,
        motion: Motion,
        start: AxisVec,
        target: AxisVec,
    ) -> Result<(), String> {
        let (feed, feed_mode) = self.feed_out();
        let mv = Move {
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
        let c = self.comp.as_mut().expect("compensation on");
        if c.radius == 0.0 {
            // LinuxCNC compensates nothing for a tool of radius zero.
            c.pass(mv, queue);
            return Ok(());
        }
        match motion {
            Motion::Arc { .. } => c.arc(mv, queue),
            _ => c.straight(mv, queue),
        }
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
        if Axis::XYZABC[3..].iter().any(|&a| target[a] != self.pos[a]) {
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
                let (cu, cv) = if self.rotation.is_some() && self.frame().is_none() {
                    // A rotated work system: only G17 arcs (checked by the caller).
                    let c = if self.arc_absolute {
                        let p = self.xy_to_program([su, sv]);
                        self.xy_to_machine([i.map_or(p[0], |w| w.value * scale), j.map_or(p[1], |w| w.value * scale)])
                    } else {
                        let d = self.xy_increment([i.map_or(0.0, |w| w.value * scale), j.map_or(0.0, |w| w.value * scale)]);
                        [su + d[0], sv + d[1]]
                    };
                    (c[0], c[1])
                } else if self.arc_absolute {
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
    #[inline(always)]
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

impl<'l, const N: usize> Small<(Axis, Word<'l>), N> {
    /// Pushes `(axis, *word)`, the value halved when `halve`, written field by field:
    /// a whole tuple built first was assembled on the stack in pieces and read back in
    /// larger ones, a store-forwarding stall per axis word of every block.
    #[inline(always)]
    fn push_axis(&mut self, axis: Axis, word: &Word<'l>, halve: bool) {
        let slot = self.items[self.len].as_mut_ptr();
        // SAFETY: `slot` points to an item of `items` (indexing checked `len` < N); both
        // fields are written here, so the item is initialised before `len` counts it.
        unsafe {
            std::ptr::addr_of_mut!((*slot).0).write(axis);
            std::ptr::addr_of_mut!((*slot).1).write(*word);
            if halve {
                (*slot).1.value /= 2.0;
            }
        }
        self.len += 1;
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
/// `v` turned counter-clockwise by `deg` about the origin.
fn rotate_deg(v: [f64; 2], deg: f64) -> [f64; 2] {
    let (s, c) = deg.to_radians().sin_cos();
    [v[0] * c - v[1] * s, v[0] * s + v[1] * c]
}

/// Index of a word letter in a block's table of single words: A-Z, then `@` and `^`.
const fn slot(letter: char) -> usize {
    match letter {
        '@' => 26,
        '^' => 27,
        l => (l as u8 - b'A') as usize,
    }
}

/// The bits (`1 << slot`) of `letters`.
const fn letters(letters: &[char]) -> u32 {
    let mut mask = 0;
    let mut k = 0;
    while k < letters.len() {
        mask |= 1 << slot(letters[k]);
        k += 1;
    }
    mask
}

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

/// The number of turns of a LinuxCNC `G2`/`G3 ... P<n>` arc: a whole number from 1.
fn turns(line: &str, p: &Word, feed_mode: FeedRead) -> LineResult<u32> {
    if p.value.fract() != 0.0 || !(1.0..=10_000.0).contains(&p.value) {
        return Err(LineError::new(
            p.span(),
            format!(
                "`{}`: expected a whole number of turns from 1",
                &line[p.span()]
            ),
            "turns",
        ));
    }
    if p.value > 1.0 && matches!(feed_mode, FeedRead::InverseTime) {
        return Err(LineError::new(
            p.span(),
            "an arc of several turns under G93 inverse-time feed: not supported",
            "turns under G93",
        ));
    }
    Ok(p.value as u32)
}
