//! The modal interpreter: one block of words into canonical moves in machine coordinates.
//!
//! Input: a block's words (crate `lex`) and the dialect's tables (crate `dialect`); state:
//! the modal state between blocks ([`Interp`]); output: canonical [`Move`]s queued in
//! order, and a [`Stop`] telling the reader what to do next (end, call, return).
//!
//! Machine position = program position + work offset (G54-G59.3, G54.1 Pn) + G92/G52
//! offset + tool length offset (G43, on Z). The offsets live in LinuxCNC's numbered
//! parameters (5211-5219 G92, 5221+20(n-1) work system n, 5161/5181 G28/G30), so `.var`
//! files, G10 and `#5221 = ...` all act on the same numbers.
//!
//! # Order of execution
//!
//! A block is first read once into its typed words ([`Block`]: G codes by modal group, M
//! codes, one word per letter), then [`Interp::block`] runs the phases in this order, each
//! in its own file:
//!
//! | phase | codes | file |
//! |---|---|---|
//! | 0 | read and check the words | `words.rs`, crate `block` |
//! | 1 | feed mode G93/G94/G95, units G20/G21 (for F), F, S | `modal.rs` |
//! | 2 | T, M6, M61, user M codes, spindle M3/M4/M5 | `tool.rs` |
//! | 3 | M70-M73 save and restore the modal state | `flow.rs` |
//! | 4 | dwell G4 | `non_modal.rs` |
//! | 5 | plane, units, cutter compensation, tool length, work system, path control, distance, retract, G68.2/G53.1, G254 | `modal.rs` |
//! | - | the motion mode, polar and axis words | `motion.rs`, `polar_words.rs` |
//! | 6 | G10, G28/G30, G28.1/G30.1, G52, G92 family | `non_modal.rs` |
//! | 7 | motion: G0-G3, G5.x, G33/G33.1, G38.x, canned cycles, as modified by G53 | `motion.rs`, `arcs.rs`, `splines.rs`, `spindle_sync.rs`, `probing.rs`, `cycles.rs` |
//! | - | notices of the control's settings assumed (G73/G83 pecks, G28 without axes) | `control.rs` |
//! | 8 | stops and program flow: M2/M30, M98/M99 (G65 before phase 0) | `flow.rs` |
//!
//! The order is that of the NIST RS274/NGC interpreter report (version 3, section 3.8,
//! "Order of Execution": feed mode, F, S, T, M6, spindle, coolant, overrides, dwell, plane,
//! units, cutter radius and length compensation, coordinate system, path control,
//! distance mode, retract mode, home/G10/G92, motion, stop) as LinuxCNC's G-code manual
//! extends it ("G Code Order of Execution": M61 with M6, M70-M73 after the spindle, user M
//! codes before the dwell, G52 with G92, G33/G38/G76 with the motion). Where the Fanuc
//! family differs, the dialect's table says so: F is read in the units the block selects
//! (LinuxCNC sets F before G20/G21, so `G20 F60` from metric is 60 mm/min there), G4 may
//! not share a block with a motion code, and G65 is a macro call whose letters are
//! arguments, not words of the block (the Fanuc Series 0i operator's manual, "Custom
//! macro": "simple call").

use std::collections::{HashMap, VecDeque};
use std::path::Path;

use crate::axis::{Axis, AxisVec, Plane};
use crate::block::Block;
use crate::canon::{Move, PathControl};
use crate::code::{FeedRead, GCode, MotionMode};
use crate::comp;
use crate::expr::{Param, Params};
use crate::frame::{Mat3, RotaryTable};
use crate::lex::{LineResult, Word};
use crate::notice::Notice;
use crate::options::{Dialect, Distance, Options, StartFeed, Tool, Units, UserM};
use crate::spline;

mod arcs;
mod bolt;
mod control;
mod coords;
mod cycles;
mod emit;
mod fanuc_g10;
mod flow;
mod lathe_codes;
mod modal;
mod motion;
mod non_modal;
mod params;
mod polar_words;
mod probing;
mod spindle_mode;
mod spindle_sync;
mod splines;
mod stock_removal;
mod system_vars;
mod tool;
mod words;

pub(crate) use stock_removal::StockRemoval;

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

/// The modal state of the controller between blocks.
#[derive(Clone)]
pub struct Interp {
    pub params: Params,
    dialect: Dialect,
    axes: [bool; 9],
    /// Machine position of the controlled point, mm and deg.
    pos: AxisVec,
    motion: Option<MotionMode>,
    /// The last G00-G03 mode (Fanuc group 01), in effect again after G80 where the
    /// dialect's table says so.
    interpolation: Option<MotionMode>,
    /// The D word given alone (Fanuc family): the offset a later G41/G42 without D uses.
    d_register: Option<u32>,
    plane: Plane,
    absolute: bool,
    arc_absolute: bool,
    feed_mode: FeedRead,
    inch: bool,
    /// G20/G21 has been read (until then the units are the start state's, a guess the
    /// first move warns about).
    units_stated: bool,
    /// Where the start state's units come from (named in that warning).
    start_units_setting: &'static str,
    /// F as programmed (program units per minute or per revolution, or 1/min).
    feed: Option<f64>,
    spindle_rpm: f64,
    /// G96: the surface speed S stands for (crate `surface_speed`); `None` under G97.
    surface_speed: Option<crate::surface_speed::SurfaceSpeed>,
    /// The spindle speed limit of constant surface speed (G50 S, G92 S, G96 D), rev/min.
    spindle_limit_rpm: Option<f64>,
    /// A feed move of this block needs an endless spindle speed (G96 at X 0, no limit):
    /// the block's refusal.
    surface_speed_fault: Option<String>,
    /// A Fanuc-family lathe's G90, G92 or G94 selected without axis words (its single
    /// cycle, in the motion group): named when a block would run it.
    lathe_cycle: Option<String>,
    /// A feed mode code (G93-G95, a lathe's G98/G99) has been read, or the warning that
    /// a lathe feeds in the start state's mode was given.
    feed_mode_stated: bool,
    /// M3 or M4 in effect (M5, M6, M2/M30 stop it, as rs274 does by default).
    spindle_turning: bool,
    /// G7: X words are diameters (LinuxCNC lathe mode); G8 (default): radii.
    diameter: bool,
    tcp: bool,
    tools: HashMap<u32, Tool>,
    /// Fanuc and Haas tool length wear (G10 L11) by offset number, mm: part of the tool's
    /// length in `tools`, kept apart so G10 L10 can set the geometry alone.
    length_wear: HashMap<u32, f64>,
    /// Lathe tool orientations by tool number (tool table Q).
    orientations: HashMap<u32, u32>,
    table_given: bool,
    tool: u32,
    next_tool: u32,
    /// A T word has selected `next_tool` since the last tool change (`#<_selected_pocket>`
    /// is then its pocket, else -1).
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
    /// Fanuc and Haas G68: the angle (deg) and the centre (work coordinates, mm); it makes
    /// `rotation` ([`Interp::rotate_on`]).
    rotation_2d: Option<(f64, [f64; 2])>,
    /// Fanuc G43.5 is active: I J K are the tool-axis vector, which mtsim refuses.
    tool_vector: bool,
    path: PathControl,
    retract_r: bool,
    cycle_r: Option<f64>,
    cycle_z: Option<f64>,
    cycle_q: Option<f64>,
    cycle_p: Option<f64>,
    /// G87 (Fanuc) / G77 (Haas) back boring: the shift I J (K) off the bore wall, plane
    /// axes u v, mm; modal in the cycle (Q shifts +u instead).
    cycle_shift: Option<(f64, f64)>,
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
    /// G53.1 on a kinematic chain (no [`RotaryTable`]): the caller's inverse kinematics.
    aligner: Option<crate::frame::ToolAligner>,
    /// Cutter radius compensation (G41/G42 to G40) and its queued moves.
    comp: Option<comp::Comp>,
    /// Where the tool is after G40 when it differs from `pos` (the next move starts there).
    comp_out: Option<AxisVec>,
    /// The move after G40 must be straight (LinuxCNC refuses an arc there).
    arc_not_allowed: bool,
    /// G28 / G30 reference positions not given ([`Options::reference_missing`]): the
    /// setting to name when a program goes there; cleared by G28.1 / G30.1.
    reference_missing: [Option<String>; 2],
    /// The axes' positions at a TCP position ([`Options::tcp_axes`]), for a TCP cancel.
    tcp_axes: Option<crate::options::TcpAxes>,
    /// The control's parameters ([`Options::control`]).
    control: crate::options::ControlParameters,
}

/// Parameter of extended work offset P n (G54.1 Pn, G154 Pn), axis X.
fn extended_parameter(n: u32) -> usize {
    // LinuxCNC has none; stored above its range, 7001 + 20 (n - 1).
    7001 + 20 * (n as usize - 1)
}

pub(crate) fn coord_parameter(coord: u32) -> usize {
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
            interpolation: None,
            d_register: None,
            plane: o.start_state.plane,
            absolute: o.start_state.distance == Distance::Absolute,
            arc_absolute: false,
            feed_mode: match o.start_state.feed {
                StartFeed::InverseTime => FeedRead::InverseTime,
                StartFeed::PerMinute => FeedRead::PerMinute,
                StartFeed::PerRevolution => FeedRead::PerRevolution,
            },
            inch: o.start_state.units == Units::Inch,
            units_stated: false,
            start_units_setting: o.start_units_setting,
            feed: None,
            spindle_rpm: 0.0,
            surface_speed: None,
            spindle_limit_rpm: None,
            surface_speed_fault: None,
            lathe_cycle: None,
            feed_mode_stated: false,
            spindle_turning: false,
            diameter: false,
            tcp: o.tcp,
            tools: o.tools.iter().map(|t| (t.number, *t)).collect(),
            length_wear: HashMap::new(),
            orientations: o.tool_orientations.iter().copied().collect(),
            table_given: !o.tools.is_empty(),
            tool: 0,
            next_tool: 0,
            tool_length_mm: 0.0,
            coord: 1,
            offset: AxisVec::ZERO,
            rotation: None,
            rotation_2d: None,
            tool_vector: false,
            path: PathControl::BLEND,
            retract_r: o.dialect.table().start_retract_r,
            cycle_r: None,
            cycle_z: None,
            cycle_q: None,
            cycle_p: None,
            cycle_shift: None,
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
            aligner: o.aligner.clone(),
            comp: None,
            comp_out: None,
            arc_not_allowed: false,
            reference_missing: [0, 1].map(|k| {
                // A parameter file that sets the position gives it.
                let base = [crate::options::G28_PARAMETER, crate::options::G30_PARAMETER][k];
                let given = o
                    .parameters
                    .iter()
                    .any(|(n, _)| (base..base + 9).contains(n));
                o.reference_missing[k].clone().filter(|_| !given)
            }),
            tcp_axes: o.tcp_axes.clone(),
            control: o.control,
        };
        i.parameters_changed();
        i.refuse_unmodelled_system_variables();
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
        if let Some((deg, c)) = self.rotation_2d {
            // G68: machine = rot(p − c) + offset + c, in the tuple's form rot(p + g92) + g5x.
            let o = [self.offset[Axis::X], self.offset[Axis::Y]];
            self.rotation = Some((deg, [o[0] + c[0], o[1] + c[1]], [-c[0], -c[1]]));
        }
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

    /// The pocket of tool `n`: `None` when a tool table is given without it.
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

    /// Interprets the words of one block, queueing its moves: the phases in the order of
    /// the module doc.
    pub fn block(
        &mut self,
        line: &str,
        words: &[Word],
        line_no: usize,
        queue: &mut VecDeque<Move>,
        notices: &mut Vec<Notice>,
        path: &Path,
    ) -> LineResult<Stop> {
        // Most blocks of most programs: a G0/G1 move in a plain modal state.
        if self.plain_move(words, line_no, queue) {
            return Ok(Stop::None);
        }
        // Fanuc G65: a macro call whose letters are its arguments.
        if let Some(g65) = self.macro_call(words) {
            return self.g65(line, words, g65);
        }
        // 0. The block's words, typed and checked.
        let mut b = Block::read(line, words, self.dialect)?;
        self.lathe_codes(&mut b)?;
        self.check_words(&mut b)?;
        // 1. Feed mode, units for F, F, S.
        self.feed_and_speed(&mut b)?;
        // 2. Tool select and change, user M codes, spindle.
        self.tool_and_spindle(&b, line_no, notices, path)?;
        // 3. M70-M73.
        let stop = self.save_and_restore(&b)?;
        // 4. Dwell.
        self.dwell(&b, line_no, queue)?;
        // 5. Plane, units, compensation, tool length, work system, path, distance, retract.
        self.modal_groups(&b, line_no, queue)?;
        self.no_motion_notices(&b, line_no, notices, path);
        // The motion mode, then the axis words (polar words resolved in the new state).
        let previous_motion = self.motion_mode(&b)?;
        self.axis_words(&mut b)?;
        // 6. Non-modal codes that use axis words.
        let queued = queue.len();
        self.non_modal(&mut b, line_no, queue)?;
        // 7. Motion.
        self.motion(&mut b, previous_motion, line_no, queue)?;
        if let Some(fault) = self.surface_speed_fault.take() {
            return Err(crate::lex::LineError::new(
                0..line.len(),
                fault,
                "spindle speed unbounded",
            ));
        }
        if !self.units_stated && queue.len() > queued {
            self.warn_units_assumed(line_no, notices, path);
        }
        if !self.feed_mode_stated && self.is_lathe() {
            self.warn_lathe_feed_mode(queue.iter().skip(queued), line_no, notices, path);
        }
        self.control_notices(&b, line_no, notices, path);
        // 8. Stops and program flow.
        self.program_flow(&b, queue, stop)
    }

    /// A notice, once per code, for each G code of the block that has no effect on the
    /// motion and each machine M code (brakes, chip conveyor, coolant options).
    fn no_motion_notices(
        &mut self,
        b: &Block,
        line_no: usize,
        notices: &mut Vec<Notice>,
        path: &Path,
    ) {
        let table = self.dialect.table();
        // G codes are keyed apart from M codes in `noticed`.
        const G_KEY: u32 = 1 << 20;
        let g = b.g.iter().filter_map(|(c, _)| match c {
            GCode::Control(code) => (table.no_motion_g)(*code).map(|m| (G_KEY + code, m)),
            _ => None,
        });
        let m =
            b.m.iter()
                .filter_map(|(code, _)| (table.machine_m)(*code).map(|m| (*code, m)));
        // Boring with a manual retract (Fanuc G88, Haas G87/G88): the jog out is simulated.
        let manual = b.g.iter().find_map(|(c, _)| match c {
            GCode::Motion(Some(MotionMode::Cycle(code @ (870 | 880))))
                if !self.is_back_bore(*code) =>
            {
                Some(*code)
            }
            _ => None,
        });
        if let Some(code) = manual.filter(|c| !self.noticed.contains(&(G_KEY + c))) {
            self.noticed.push(G_KEY + code);
            notices.push(Notice {
                path: path.to_path_buf(),
                line: line_no,
                message: format!(
                    "G{} bores with a manual retract (the spindle stops and the operator jogs \
                     the tool out): simulated as a rapid straight back to the G98/G99 level \
                     ({} dialect)",
                    code / 10,
                    self.dialect.name()
                ),
                warning: false,
            });
        }
        let found: Vec<(u32, &str)> = g.chain(m).collect();
        for (key, meaning) in found {
            if self.noticed.contains(&key) || self.noticed.len() >= 100 {
                continue;
            }
            self.noticed.push(key);
            notices.push(Notice {
                path: path.to_path_buf(),
                line: line_no,
                message: format!(
                    "{meaning}: accepted with no effect on the motion ({} dialect)",
                    self.dialect.name()
                ),
                warning: false,
            });
        }
    }

    /// The program moves before it states its units: warn once, naming the unit assumed and
    /// the setting that changes it (a program in the other unit is 25.4 times off).
    fn warn_units_assumed(&mut self, line_no: usize, notices: &mut Vec<Notice>, path: &Path) {
        self.units_stated = true;
        let (unit, other) = if self.inch {
            ("inches (G20)", "mm")
        } else {
            ("mm (G21)", "inches")
        };
        notices.push(Notice {
            path: path.to_path_buf(),
            line: line_no,
            message: format!(
                "the program moves before it states its units (no G20/G21 before this line): \
                 read in {unit}, the unit the control starts in ({}); a program written in \
                 {other} is read 25.4 times off: set the scenario's [reader] start_units or \
                 the machine file's [start] units",
                self.start_units_setting
            ),
            warning: true,
        });
    }

    /// A lathe program feeds before it states G98/G99: warn once that F is read in the
    /// start state's mode (a lathe control may power up in G99, Fanuc parameter 3402#4).
    fn warn_lathe_feed_mode<'m>(
        &mut self,
        mut moves: impl Iterator<Item = &'m Move>,
        line_no: usize,
        notices: &mut Vec<Notice>,
        path: &Path,
    ) {
        if !moves.any(|m| {
            matches!(
                m.motion,
                crate::canon::Motion::Linear | crate::canon::Motion::Arc { .. }
            )
        }) {
            return;
        }
        self.feed_mode_stated = true;
        let mode = match self.feed_mode {
            FeedRead::PerRevolution => "per revolution (G99)",
            FeedRead::InverseTime => "inverse time (G93)",
            FeedRead::PerMinute => "per minute (G98)",
        };
        notices.push(Notice {
            path: path.to_path_buf(),
            line: line_no,
            message: format!(
                "a lathe program feeds before it states G98 or G99: F is read {mode}, the \
                 mode the control starts in (the machine file's [start] feed_mode); a lathe \
                 that powers up in the other mode (Fanuc parameter 3402#4) reads F otherwise"
            ),
            warning: true,
        });
    }

    /// The end of the program: the queued compensated moves end as at G40.
    /// The modal state a block's words without a decimal point are scaled in
    /// (crate::decimal_point): the units (the block's own G20/G21 first) and whether a
    /// drilling cycle is in effect.
    pub(crate) fn whole_number_context(
        &self,
        words: &[Word],
    ) -> crate::decimal_point::BlockContext {
        let units = words.iter().rev().find_map(|w| match (w.letter, w.value) {
            ('G', v) if v == 20.0 => Some(true),
            ('G', v) if v == 21.0 => Some(false),
            _ => None,
        });
        crate::decimal_point::BlockContext {
            inch: units.unwrap_or(self.inch),
            cycle_modal: matches!(self.motion, Some(MotionMode::Cycle(_))),
            polar_angle: None,
        }
    }

    /// The modal state the mirror image and scaling map a block's words in
    /// (crate::mirror_scale); the block's own G90/G91 and plane are the map's to read.
    pub(crate) fn mirror_scale_context(&self) -> crate::mirror_scale::Context {
        crate::mirror_scale::Context {
            absolute: self.absolute,
            plane: self.plane,
            arc_modal: matches!(self.motion, Some(MotionMode::Arc { .. })),
            cycle_modal: matches!(self.motion, Some(MotionMode::Cycle(_))),
        }
    }

    /// Cutter radius compensation (G41/G42) is on.
    pub(crate) fn compensating(&self) -> bool {
        self.comp.is_some()
    }

    /// F as programmed (program units per minute or per revolution), when one is.
    pub(crate) fn programmed_feed(&self) -> Option<f64> {
        self.feed
    }

    pub fn finish(&mut self, queue: &mut VecDeque<Move>) {
        // As LinuxCNC's M2: the queue ends at the compensated point; a gouge found there
        // was already reported with the move that made it.
        let _ = self.comp_exit(queue);
    }

    /// Drops the queued compensated moves (after an error).
    pub fn discard(&mut self) {
        self.comp = None;
    }
}
