//! What the reader needs to know about the machine and the job: dialect, axes, tools, work
//! offsets and parameters, subroutine search path, user M codes, limits.
//!
//! Parsers for LinuxCNC's tool table (`.tbl`) and parameter file (`.var`) live here too.

use std::collections::HashMap;
use std::path::PathBuf;

use crate::axis::{Axis, AxisVec, Plane};
use crate::frame::RotaryTable;

/// The control whose G-code language a program is written in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "lowercase"))]
pub enum Dialect {
    /// LinuxCNC 2.9 RS274/NGC: G4 P in s, o-word subroutines, `#<named>` parameters.
    Linuxcnc,
    /// The default (what mtsim writes itself): Fanuc 0i/30i family: G4 P in ms (X in s), M98/M99 O-number subprograms, macro B
    /// (`IF [..] GOTO n`, `WHILE [..] DO m`), G43.4/G43.5 TCP.
    #[default]
    Fanuc,
    /// Haas NGC: Fanuc-style with G4 P in s when it has a decimal point (ms otherwise) and
    /// G234 for TCP.
    Haas,
    /// HEIDENHAIN TNC 640 conversational (Klartext): `BEGIN PGM`, `L`, `CC`/`C`, Q
    /// parameters, `LBL`, `CYCL DEF`, `PLANE` (its own front end, `heidenhain/`).
    Heidenhain,
    /// Siemens Sinumerik 840D: ISO G code plus R parameters, `DEF` variables, structured
    /// control flow, frames and cycles, read by its own front end (crate `siemens`).
    Siemens,
}

impl Dialect {
    /// `linuxcnc`, `fanuc`, `haas`, `heidenhain` or `siemens`.
    pub const fn name(self) -> &'static str {
        match self {
            Dialect::Linuxcnc => "linuxcnc",
            Dialect::Fanuc => "fanuc",
            Dialect::Haas => "haas",
            Dialect::Heidenhain => "heidenhain",
            Dialect::Siemens => "siemens",
        }
    }

    /// True for the Fanuc family (Fanuc, Haas): macro B syntax, M98/M99.
    pub const fn is_fanuc_family(self) -> bool {
        matches!(self, Dialect::Fanuc | Dialect::Haas)
    }
}

/// The unit a control reads lengths in until the program says G20/G21 (G70/G71).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "lowercase"))]
pub enum Units {
    /// G21: millimetres.
    #[default]
    Mm,
    /// G20: inches (Haas setting 9 "Dimensioning" = INCH, Fanuc parameter 0000 bit INI).
    Inch,
}

/// G90 or G91 at power-up (Haas setting 10, Fanuc parameter 3402 bit G91).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "lowercase"))]
pub enum Distance {
    #[default]
    Absolute,
    Incremental,
}

/// G93, G94 or G95 at power-up.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "kebab-case"))]
pub enum StartFeed {
    InverseTime,
    #[default]
    PerMinute,
    PerRevolution,
}

/// The modal state a control powers up in, before the program states any: the machine
/// file's `[start]`, overridden by the scenario's `[reader] start_*` keys. The default is
/// every dialect's factory state: mm, G90, G17, G94.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StartState {
    pub units: Units,
    pub distance: Distance,
    pub plane: Plane,
    pub feed: StartFeed,
}

impl Default for StartState {
    fn default() -> StartState {
        StartState {
            units: Units::Mm,
            distance: Distance::Absolute,
            plane: Plane::XY,
            feed: StartFeed::PerMinute,
        }
    }
}

/// One tool of the tool table, mm.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Tool {
    /// T number.
    pub number: u32,
    /// Length offset along Z, mm (LinuxCNC `Z`).
    pub length_mm: f64,
    /// Diameter, mm (LinuxCNC `D`).
    pub diameter_mm: f64,
}

/// What a user M code (M100-M199, or a remapped code such as M428) does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "kebab-case"))]
pub enum UserM {
    /// Switch tool-centre-point control on (as LinuxCNC's xyzac-trt M428).
    TcpOn,
    /// Switch tool-centre-point control off (M429).
    TcpOff,
    /// Accept and do nothing (no notice).
    Ignore,
}

/// Reader options. `Options::default()` reads Fanuc-family programs on a six-axis machine
/// (X Y Z A B C: a U V W word is an error until `axes` lists them) from
/// all axes at zero, with no tools, all offsets zero.
#[derive(Clone, Debug)]
pub struct Options {
    pub dialect: Dialect,
    /// The modal state at power-up (units, distance mode, plane, feed mode).
    pub start_state: StartState,
    /// Where [`Options::start_state`]'s units come from, named in the warning given when a
    /// program moves before it states its units.
    pub start_units_setting: &'static str,
    /// The axes the machine has; a word for any other axis is an error.
    pub axes: Vec<Axis>,
    /// Machine position before the program runs, mm and deg.
    pub start: AxisVec,
    /// The tool table. Empty: any T and H is accepted, with length zero.
    pub tools: Vec<Tool>,
    /// Lathe tool orientations (LinuxCNC tool table `Q`, 1-9) by tool number; a tool not
    /// listed is a mill tool (orientation 0). Used by cutter compensation under G18.
    pub tool_orientations: Vec<(u32, u32)>,
    /// Initial numbered parameters (from a `.var` file, work offsets, G28/G30 positions).
    pub parameters: Vec<(u32, f64)>,
    /// Folders searched, in order, for `o<name> call` subroutine files `name.ngc` and Fanuc
    /// `M98 P<n>` programs `O<n>.nc`.
    pub search_path: Vec<PathBuf>,
    /// User M codes mapped to an effect; other M100-M199 are accepted with a notice.
    pub user_m: HashMap<u32, UserM>,
    /// Tool-centre-point control on from the start (LinuxCNC configurations whose
    /// kinematics are always in TCP mode).
    pub tcp: bool,
    /// Blocks executed in one run (crate `budget`): every block counts each time it runs, in
    /// loops, jumps, repeated subprograms, macro calls and repeated sections alike.
    pub max_blocks: u64,
    /// Subroutine nesting allowed.
    pub max_call_depth: usize,
    /// The machine's rotary table (table-table AC or BC), for G68.2/G53.1 and G254; `None`
    /// on a three-axis machine, where G53.1 and G254 are errors.
    pub table: Option<RotaryTable>,
    /// On a machine without such a table (a kinematic chain): how G53.1 turns its rotaries
    /// ([`ToolAligner`]); `None`: G53.1 is an error there.
    pub aligner: Option<crate::frame::ToolAligner>,
    /// LinuxCNC remapped codes (`[RS274NGC]REMAP`, crate::remap).
    pub remaps: Vec<crate::remap::Remap>,
    /// HAL pin values read by `#<_hal[pin.name]>`.
    pub hal_pins: Vec<(String, f64)>,
    /// Sinumerik system variables the program reads, with the values the control holds:
    /// name as written with its indices, upper case (`$MN_USER_DATA_HEX[0]`,
    /// `$A_DBB[10]`); a variable not given is refused by name.
    pub system_variables: Vec<(String, f64)>,
    /// Folders of LinuxCNC user M programs (`M100`-`M199` files); when not empty, a user M
    /// code with no file there is an error, as in LinuxCNC.
    pub user_m_path: Vec<PathBuf>,
    /// Numeric configuration values read by `#<_ini[section]key>`: ("section]key", value).
    pub ini_values: Vec<(String, f64)>,
    /// Tool pockets (tool number, pocket `P` of the tool table), for `#<_current_pocket>`
    /// and `#<_selected_pocket>`.
    pub pockets: Vec<(u32, u32)>,
    /// G28 (`[0]`) and G30 (`[1]`) reference positions the machine does not give: the
    /// setting that would give it (`g28_mm` in the machine file), named when a program
    /// uses G28 or G30 before a G28.1/G30.1 or a parameter file sets it. `None`: the
    /// position is parameters 5161-5169 (5181-5189), zero unless set, as in LinuxCNC.
    pub reference_missing: [Option<String>; 2],
    /// The machine's axis positions at a tool-centre-point position: given the position
    /// under TCP (X Y Z the tip in the table frame, the tool length added to Z, the
    /// rotaries the machine's) and the tool length (mm), the positions the axes are at.
    /// Used when TCP is cancelled, where the control takes the axes' positions as the
    /// current point; `None`: the interpreter refuses a TCP cancel with the rotaries
    /// turned off zero, where it cannot say where the axes are.
    pub tcp_axes: Option<TcpAxes>,
    /// The control's parameters that change a program's moves (a machine file's
    /// `[control]`); what is not given is the dialect's rule.
    pub control: ControlParameters,
}

/// The control's parameters that change what a program does, in mm: the machine builder's
/// settings, which a program cannot see (docs/gcode.md, "Control parameters").
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ControlParameters {
    /// G73: how far the tool backs off after each peck to break the chip (Fanuc parameter
    /// 5114, Haas Setting 22). `None`: [`PECK_CLEARANCE_MM`], with a notice where the
    /// control takes it from a setting.
    pub g73_retract_mm: Option<f64>,
    /// G83: how far above the previous peck's depth the rapid back down stops (Fanuc
    /// parameter 5115). `None`: [`PECK_CLEARANCE_MM`], with a notice as for G73.
    pub g83_clearance_mm: Option<f64>,
    /// G83: how far above R each peck's retract rises (Haas Setting 52); 0 by default.
    pub g83_above_r_mm: f64,
    /// G28/G30 without axis words: every axis returns (`Some(true)`) or none
    /// (`Some(false)`); `None`: the dialect's rule (LinuxCNC and Haas all, Fanuc none).
    pub reference_all_without_axes: Option<bool>,
    /// Dimension words written without a decimal point (`Z50`): in the least input
    /// increment or in whole units (Fanuc parameter 3401#0, Haas Setting 162). `None`: the
    /// dialect's default (Fanuc and Haas: increments, with a warning), crate::decimal_point.
    pub whole_numbers: Option<crate::WholeNumbers>,
}

/// LinuxCNC's fixed G73 retract and G83 clearance (0.010 in; its G-code manual), the
/// reader's value where another control's setting is not given.
pub const PECK_CLEARANCE_MM: f64 = 0.254;

/// See [`Options::tcp_axes`].
#[derive(Clone)]
pub struct TcpAxes(pub std::sync::Arc<dyn Fn(&AxisVec, f64) -> AxisVec + Send + Sync>);

impl std::fmt::Debug for TcpAxes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("TcpAxes")
    }
}

/// Default limit on executed blocks per program run: 2·10⁶, over 120 times the blocks the
/// longest program of the project's corpus executes, and fewer than the 10⁶ loop passes of
/// a three-line loop the reader allowed before, so an endless loop stops in seconds
/// (docs/gcode.md).
pub const MAX_BLOCKS: u64 = 2_000_000;
/// Default limit on subroutine nesting.
pub const MAX_CALL_DEPTH: usize = 64;

impl Default for Options {
    fn default() -> Options {
        Options {
            dialect: Dialect::Fanuc,
            start_state: StartState::default(),
            start_units_setting: "the default",
            axes: Axis::XYZABC.to_vec(),
            start: AxisVec::ZERO,
            tools: Vec::new(),
            tool_orientations: Vec::new(),
            parameters: Vec::new(),
            search_path: Vec::new(),
            user_m: HashMap::new(),
            tcp: false,
            max_blocks: MAX_BLOCKS,
            max_call_depth: MAX_CALL_DEPTH,
            table: None,
            aligner: None,
            remaps: Vec::new(),
            hal_pins: Vec::new(),
            system_variables: Vec::new(),
            user_m_path: Vec::new(),
            ini_values: Vec::new(),
            pockets: Vec::new(),
            reference_missing: [None, None],
            tcp_axes: None,
            // The library's plain reader takes `Z50` as 50 mm in every dialect (a Fanuc
            // with parameter 3401#0 = 1); a machine file's `[control]` (crate mtsim) leaves
            // it to the dialect's default, the manuals' least input increment.
            control: ControlParameters {
                whole_numbers: Some(crate::WholeNumbers::Units),
                ..ControlParameters::default()
            },
        }
    }
}

/// Parameter number of work coordinate system `n` (1 = G54 ... 9 = G59.3), axis X.
pub const fn work_offset_parameter(n: u32) -> u32 {
    5201 + 20 * n
}

/// Parameter number of the G28 reference position, axis X (machine coordinates).
pub const G28_PARAMETER: u32 = 5161;
/// Parameter number of the G30 reference position, axis X.
pub const G30_PARAMETER: u32 = 5181;

impl Options {
    /// Sets work offset `n` (1 = G54 ... 9 = G59.3), mm and deg.
    pub fn set_work_offset(&mut self, n: u32, offset: AxisVec) {
        let base = work_offset_parameter(n);
        for axis in Axis::ALL {
            self.parameters
                .push((base + axis.index() as u32, offset[axis]));
        }
    }

    /// Sets the G28 (`g30 = false`) or G30 reference position, machine mm and deg.
    pub fn set_reference(&mut self, g30: bool, position: AxisVec) {
        let base = if g30 { G30_PARAMETER } else { G28_PARAMETER };
        for axis in Axis::ALL {
            self.parameters
                .push((base + axis.index() as u32, position[axis]));
        }
    }
}

/// 1-based character column of `word`, a slice of `line`, in `line`.
fn column(line: &str, word: &str) -> usize {
    let at = (word.as_ptr() as usize).saturating_sub(line.as_ptr() as usize);
    line.get(..at)
        .map_or(1, |before| before.chars().count() + 1)
}

/// Parses a LinuxCNC parameter file: lines `number value`, blank lines ignored.
/// Errors give the 1-based line, the column and what was expected, never the file's text.
pub fn parse_var_file(text: &str) -> Result<Vec<(u32, f64)>, (usize, String)> {
    let mut out = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let mut parts = line.split_whitespace();
        let Some(first) = parts.next() else { continue };
        let Some(n) = first.parse::<u32>().ok().filter(|n| (1..=5601).contains(n)) else {
            return Err((
                k + 1,
                format!(
                    "column {}: expected a parameter number 1-5601",
                    column(line, first)
                ),
            ));
        };
        let second = parts.next();
        let Some(v) = second
            .and_then(|v| v.parse::<f64>().ok())
            .filter(|v| v.is_finite())
        else {
            let at = second.map_or(line.chars().count() + 1, |w| column(line, w));
            return Err((
                k + 1,
                format!("column {at}: expected a finite value after the parameter number"),
            ));
        };
        out.push((n, v));
    }
    Ok(out)
}

/// The pockets of a LinuxCNC tool table: (tool `T`, pocket `P`) of each line that has both.
pub fn tool_pockets(text: &str) -> Vec<(u32, u32)> {
    let word = |line: &str, l: char| {
        line.split_whitespace()
            .find(|w| w.starts_with([l, l.to_ascii_lowercase()]))
            .and_then(|w| w[1..].parse::<f64>().ok())
            .filter(|v| *v >= 0.0 && v.fract() == 0.0 && *v < 1e9)
            .map(|v| v as u32)
    };
    text.lines()
        .map(|l| l.split(';').next().unwrap_or(""))
        .filter_map(|l| Some((word(l, 'T')?, word(l, 'P')?)))
        .collect()
}

/// Parses a LinuxCNC tool table: lines `T<n> P<pocket> Z<length> D<diameter> ;comment`,
/// other words (X Y A B C U V W I J Q) accepted and ignored. Lengths are taken in mm.
pub fn parse_tool_table(text: &str) -> Result<Vec<Tool>, (usize, String)> {
    let mut out = Vec::new();
    for (k, raw) in text.lines().enumerate() {
        let line = raw.split(';').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let mut tool = Tool {
            number: u32::MAX,
            length_mm: 0.0,
            diameter_mm: 0.0,
        };
        for word in line.split_whitespace() {
            let mut chars = word.chars();
            let letter = chars.next().unwrap_or(' ').to_ascii_uppercase();
            let value = chars.as_str().parse::<f64>().ok().filter(|v| v.is_finite());
            let bad = || {
                (
                    k + 1,
                    format!(
                        "column {}: expected a word T P Z D X Y A B C U V W I J Q, a letter and \
                         a number such as `Z+10.0`",
                        column(raw, word)
                    ),
                )
            };
            let value = value.ok_or_else(bad)?;
            match letter {
                'T' if value >= 0.0 && value.fract() == 0.0 => tool.number = value as u32,
                'Z' => tool.length_mm = value,
                'D' => tool.diameter_mm = value,
                'P' | 'X' | 'Y' | 'A' | 'B' | 'C' | 'U' | 'V' | 'W' | 'I' | 'J' | 'Q' => {}
                _ => return Err(bad()),
            }
        }
        if tool.number == u32::MAX {
            return Err((
                k + 1,
                format!(
                    "column {}: expected a tool number `T<n>`",
                    column(raw, line)
                ),
            ));
        }
        out.push(tool);
    }
    Ok(out)
}

/// The lathe tool orientations (`Q` words, 1-9) of a LinuxCNC tool table, by tool number;
/// tools without Q are left out. Errors as [`parse_tool_table`], plus a Q outside 0-9.
pub fn parse_tool_orientations(text: &str) -> Result<Vec<(u32, u32)>, (usize, String)> {
    let tools = parse_tool_table(text)?;
    let mut out = Vec::new();
    let mut k = 0;
    for (n, raw) in text.lines().enumerate() {
        let line = raw.split(';').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let number = tools[k].number;
        k += 1;
        for word in line.split_whitespace() {
            if let Some(q) = word.strip_prefix(['Q', 'q']) {
                let q: f64 = q.parse().unwrap_or(f64::NAN);
                if !(0.0..=9.0).contains(&q) || q.fract() != 0.0 {
                    return Err((
                        n + 1,
                        format!(
                            "column {}: expected a lathe tool orientation Q0 to Q9",
                            column(raw, word)
                        ),
                    ));
                }
                if q != 0.0 {
                    out.push((number, q as u32));
                }
            }
        }
    }
    Ok(out)
}
