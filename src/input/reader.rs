//! `[reader]` of a scenario: how a G-code program file is read (docs/gcode.md), and the
//! reader's options built from it over the machine's defaults and a LinuxCNC configuration.

use std::path::{Path, PathBuf};

use nalgebra::Vector3;
use serde::Deserialize;

use crate::error::{Error, Result};
use crate::input::exact;
use crate::input::machine::Machine;
use crate::input::scene::ToolShape;
use crate::input::toml_text::{resolve, value_error};

/// `[reader]`: how a G-code program file is read (docs/gcode.md).
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ReaderSection {
    /// "linuxcnc", "fanuc", "haas", "heidenhain" or "siemens"; the machine file's `dialect` when absent.
    pub dialect: Option<ngc::Dialect>,
    /// The units the control starts in, over the machine file's `[start] units`.
    pub start_units: Option<ngc::Units>,
    /// G90 or G91 at start, over the machine file's `[start] distance`.
    pub start_distance: Option<ngc::Distance>,
    /// The plane at start, over the machine file's `[start] plane`.
    pub start_plane: Option<ngc::Plane>,
    /// The feed mode at start, over the machine file's `[start] feed_mode`.
    pub start_feed_mode: Option<ngc::StartFeed>,
    /// LinuxCNC tool table (`.tbl`, lengths in mm), relative to the scenario.
    pub tool_table: Option<String>,
    /// Tools given inline: `tools = [{ number = 1, length_mm = 50.0, diameter_mm = 6.0 }]`,
    /// each optionally with its holder and flutes (see [`ToolEntry`]).
    pub tools: Vec<ToolEntry>,
    /// LinuxCNC parameter file (`.var`), relative to the scenario: work offsets, G28/G30.
    pub var_file: Option<String>,
    /// Work offsets by code, X Y Z A B C in mm and deg: `G54 = [100, 50, -200, 0, 0, 0]`.
    #[serde(deserialize_with = "exact::array_map")]
    pub work_offsets: std::collections::BTreeMap<String, [f64; 6]>,
    /// Folders searched for `o<name> call` and `M98 P<n>` subprogram files.
    pub subroutine_path: Vec<String>,
    /// User M codes: `M428 = "tcp-on"`, `M429 = "tcp-off"`, `M101 = "ignore"`.
    pub user_m_codes: std::collections::BTreeMap<String, ngc::UserM>,
    /// Tool-centre-point control on from the start (LinuxCNC TCP kinematics).
    pub tcp: bool,
    /// A LinuxCNC configuration, relative to the scenario: its tool table, parameter file,
    /// subroutine and user M paths and remaps, unless the keys above give them.
    pub linuxcnc_ini: Option<String>,
    /// HAL pin values for `#<_hal[pin.name]>`: `{ "plasmac.cut-feed-rate" = 3000.0 }`.
    pub hal_pins: std::collections::BTreeMap<String, f64>,
    /// Sinumerik system variables' values (machine data, PLC data the program reads):
    /// `{ "$MN_USER_DATA_HEX[0]" = 0.0 }`.
    pub system_variables: std::collections::BTreeMap<String, f64>,
}

/// One inline tool of `[reader] tools`: the tool table's number, length offset (mm, the
/// `.tbl` `Z`) and diameter (mm, `D`), and optionally the collision scene's flute length,
/// shank and holder (docs/scene.md).
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToolEntry {
    pub number: u32,
    pub length_mm: f64,
    pub diameter_mm: f64,
    pub flute_length_mm: Option<f64>,
    pub shank_diameter_mm: Option<f64>,
    pub holder_diameter_mm: Option<f64>,
    pub holder_length_mm: Option<f64>,
}

impl ToolEntry {
    /// The scene geometry this entry gives beyond length and diameter.
    pub fn shape(&self) -> ToolShape {
        ToolShape {
            flute_length_mm: self.flute_length_mm,
            shank_diameter_mm: self.shank_diameter_mm,
            holder_diameter_mm: self.holder_diameter_mm,
            holder_length_mm: self.holder_length_mm,
        }
    }
}

/// The text of a file a LinuxCNC configuration names, `None` when it does not exist (LinuxCNC
/// then starts empty); a file that is not regular or too large is refused by name, its
/// content never quoted.
fn optional_side_file(p: &Path) -> Result<Option<String>> {
    match ngc::read_side_file(p) {
        Ok(t) => Ok(Some(t)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(Error::Invalid {
            path: p.to_path_buf(),
            message: format!("cannot read {}: {e}", p.display()),
            help: Some(
                "the LinuxCNC configuration names this file: point it at a regular file".into(),
            ),
        }),
    }
}

/// G53.1 (and PLANE, CYCLE800) on a general chain with two rotaries: the rotary solution
/// for the plane's normal as the tool direction ([`chain_inverse::nearest`]: of both, the one
/// whose rotaries move least from where they are, within travel).
fn tool_aligner(machine: &Machine) -> Option<ngc::ToolAligner> {
    use crate::kinematics::{chain_inverse, ToolPose};
    use crate::{Axis, AxisVec};
    let chain = machine
        .kinematics
        .own_chain()
        .filter(|c| c.rotaries().count() == 2)
        .copied()?;
    let travel: Vec<(Axis, bool, f64, f64)> = chain
        .rotaries()
        .map(|(_, l)| {
            let a = machine.axis(l.axis);
            (l.axis, a.continuous, a.min, a.max)
        })
        .collect();
    // `MachineAxis::within_travel`, on copies the closure can own.
    let within = move |axis: Axis, v: f64| {
        travel
            .iter()
            .find(|(a, ..)| *a == axis)
            .is_none_or(|(_, continuous, lo, hi)| *continuous || (*lo..=*hi).contains(&v))
    };
    Some(ngc::ToolAligner(std::sync::Arc::new(
        move |t: [f64; 3], now: &AxisVec| {
            let pose = ToolPose {
                tip: nalgebra::Point3::origin(),
                axis: Vector3::from(t),
            };
            let s = chain_inverse::nearest(&chain, &pose, 0.0, now, &within)
                .map_err(|e| e.to_string())?;
            let mut out = *now;
            for (_, l) in chain.rotaries() {
                out[l.axis] = s.joints[l.axis];
            }
            Ok(out)
        },
    )))
}

/// A LinuxCNC machine starts in its machine units: `[TRAJ]LINEAR_UNITS`, when the
/// configuration gives it, sets the start units over the machine file's `[start] units`
/// (the scenario's `start_units` is applied instead when given).
fn ini_start_units(ini: &ngc::Ini, o: &mut ngc::Options) -> std::result::Result<(), ngc::IniError> {
    if ini.get("TRAJ", "LINEAR_UNITS").is_some() {
        o.start_state.units = match ini.linear_units_inch()? {
            true => ngc::Units::Inch,
            false => ngc::Units::Mm,
        };
        o.start_units_setting =
            "the LinuxCNC configuration's [TRAJ]LINEAR_UNITS ([reader] linuxcnc_ini)";
    }
    Ok(())
}

/// The reader options of a scenario: its `[reader]` over the machine's defaults, in this
/// order (later entries add to or override earlier ones): the machine's start state and
/// reference points, the LinuxCNC configuration of `linuxcnc_ini` and the files it names,
/// then the section's own keys.
pub(crate) fn reader_options(
    path: &Path,
    text: &str,
    r: &ReaderSection,
    machine: &Machine,
) -> Result<ngc::Options> {
    let mut o = machine_options(r, machine);
    let config = match &r.linuxcnc_ini {
        Some(file) => Some(linuxcnc_config(path, file, r, &mut o)?),
        None => None,
    };
    if let Some(c) = &config {
        configuration_files(r, c, &mut o)?;
    }
    section_keys(path, text, r, config.is_some(), &mut o)?;
    Ok(o)
}

/// The options the machine gives: its dialect, axes, table and tool aligner, start state
/// (each entry under the section's own) and reference points.
fn machine_options(r: &ReaderSection, machine: &Machine) -> ngc::Options {
    let mut o = ngc::Options {
        dialect: r.dialect.unwrap_or(machine.dialect),
        axes: machine.axes().to_vec(),
        tcp: r.tcp,
        table: machine
            .kinematics
            .layout
            .tilt_axis()
            .map(|tilt| ngc::RotaryTable {
                tilt,
                pivot_mm: machine.kinematics.pivot_mm.into(),
            }),
        aligner: tool_aligner(machine),
        control: ngc::ControlParameters {
            // A generic machine (no dialect named by the machine or the scenario) reads a
            // dimension without a decimal point in whole units; a named Fanuc or Haas, in
            // its factory setting's increments (docs/gcode.md).
            whole_numbers: machine
                .reader_control
                .whole_numbers
                .or((r.dialect.is_none() && !machine.dialect_named)
                    .then_some(ngc::WholeNumbers::Units)),
            ..machine.reader_control
        },
        ..ngc::Options::default()
    };
    let m = &machine.start;
    let d = ngc::StartState::default();
    o.start_state = ngc::StartState {
        units: r.start_units.or(m.units).unwrap_or(d.units),
        distance: r.start_distance.or(m.distance).unwrap_or(d.distance),
        plane: r.start_plane.or(m.plane).unwrap_or(d.plane),
        feed: r.start_feed_mode.or(m.feed_mode).unwrap_or(d.feed),
    };
    o.start_units_setting = match (r.start_units, m.units) {
        (Some(_), _) => "the scenario's [reader] start_units",
        (None, Some(_)) => "the machine file's [start] units",
        (None, None) => "no setting: the factory default",
    };
    for (k, key) in ["g28_mm", "g30_mm"].iter().enumerate() {
        match machine.reference_mm[k] {
            Some(p) => o.set_reference(k == 1, ngc::AxisVec::xyzabc(p)),
            None => {
                o.reference_missing[k] = Some(format!(
                    "`{key}` in the machine file {}",
                    machine.path.display()
                ))
            }
        }
    }
    let kinematics = machine.kinematics.clone();
    o.tcp_axes = Some(ngc::TcpAxes(std::sync::Arc::new(
        move |q: &ngc::AxisVec, tool_length_mm: f64| kinematics.tcp_axes(q, tool_length_mm),
    )));
    o
}

/// The LinuxCNC configuration `file` (`[reader] linuxcnc_ini`, relative to the scenario):
/// its start units (unless the section gives them) and numeric values (`#<_ini[...]>`) to
/// `o`, and the files and paths it names.
fn linuxcnc_config(
    path: &Path,
    file: &str,
    r: &ReaderSection,
    o: &mut ngc::Options,
) -> Result<ngc::LinuxcncConfig> {
    let p = resolve(path, file);
    let ini_error = |e: ngc::IniError| Error::Invalid {
        path: e.path.clone(),
        message: e.to_string(),
        help: Some(format!(
            "the LinuxCNC configuration given by the scenario's [reader] linuxcnc_ini = {file:?}"
        )),
    };
    let ini = ngc::Ini::read(&p).map_err(ini_error)?;
    if r.start_units.is_none() {
        ini_start_units(&ini, o).map_err(ini_error)?;
    }
    // `#<_ini[section]key>`: the numeric values.
    o.ini_values.extend(ini.entries.iter().filter_map(|e| {
        let v = e.value.parse::<f64>().ok().filter(|v| v.is_finite())?;
        Some((format!("{}]{}", e.section, e.key), v))
    }));
    ini.config().map_err(ini_error)
}

/// What the LinuxCNC configuration `config` names, where the section does not give it: its
/// parameter file and tool table (lengths in the configuration's machine units, to mm),
/// subroutine and user M paths, and remaps (an explicit `user_m_codes` entry replaces the
/// configuration's remap of that code).
fn configuration_files(
    r: &ReaderSection,
    config: &ngc::LinuxcncConfig,
    o: &mut ngc::Options,
) -> Result<()> {
    // Lengths in a configuration's files are in its machine units.
    let units_mm = if config.inch { ngc::MM_PER_INCH } else { 1.0 };
    if let (None, Some(p)) = (&r.var_file, config.parameter_file.as_ref()) {
        // LinuxCNC starts from all zeros when the parameter file does not exist yet.
        if let Some(t) = optional_side_file(p)? {
            let mut params = ngc::parse_var_file(&t).map_err(|(line, m)| Error::Invalid {
                path: p.clone(),
                message: format!("line {line}: {m}"),
                help: Some("a LinuxCNC .var file has lines `number value`".into()),
            })?;
            ngc::scale_parameter_lengths(&mut params, units_mm);
            o.parameters.extend(params);
        }
    }
    if let (None, Some(p)) = (&r.tool_table, config.tool_table.as_ref()) {
        // LinuxCNC starts with an empty tool table when the file does not exist (the
        // sample configurations name tables the configuration picker copies in).
        let t = optional_side_file(p)?.unwrap_or_default();
        o.pockets.extend(ngc::tool_pockets(&t));
        let tools = ngc::parse_tool_table(&t).map_err(|(line, m)| Error::Invalid {
            path: p.clone(),
            message: format!("line {line}: {m}"),
            help: Some("a LinuxCNC tool table has lines `T1 P1 Z+50.0 D6.0 ;comment`".into()),
        })?;
        o.tools.extend(tools.into_iter().map(|t| ngc::Tool {
            length_mm: t.length_mm * units_mm,
            diameter_mm: t.diameter_mm * units_mm,
            ..t
        }));
        // Lathe tools: the orientation Q, for cutter compensation under G18.
        let orientations =
            ngc::parse_tool_orientations(&t).map_err(|(line, m)| Error::Invalid {
                path: p.clone(),
                message: format!("line {line}: {m}"),
                help: Some("a lathe tool's orientation is `Q1` to `Q9`".into()),
            })?;
        o.tool_orientations.extend(orientations);
    }
    o.search_path = config.subroutine_path.clone();
    o.user_m_path = config.user_m_path.clone();
    o.remaps = config
        .remaps
        .iter()
        .filter(|m| {
            !r.user_m_codes
                .keys()
                .any(|k| format!("{}", m.code).eq_ignore_ascii_case(k))
        })
        .cloned()
        .collect();
    Ok(())
}

/// The section's own keys: HAL pins, parameter file, work offsets, tool table and inline
/// tools, subroutine path (over a configuration's when given) and user M codes. Files are
/// relative to the scenario `path`; a bad value is an error at its key in `text`.
fn section_keys(
    path: &Path,
    text: &str,
    r: &ReaderSection,
    has_config: bool,
    o: &mut ngc::Options,
) -> Result<()> {
    let read = |key: &str, file: &str| -> Result<(PathBuf, String)> {
        let p = resolve(path, file);
        match ngc::read_side_file(&p) {
            Ok(t) => Ok((p, t)),
            Err(e) => Err(value_error(
                path,
                text,
                "reader",
                key,
                format!("cannot read {}: {e}", p.display()),
            )),
        }
    };
    for (pin, v) in &r.hal_pins {
        if !v.is_finite() {
            return Err(value_error(
                path,
                text,
                "reader.hal_pins",
                pin,
                "expected a finite number".into(),
            ));
        }
        o.hal_pins.push((pin.clone(), *v));
    }
    for (name, v) in &r.system_variables {
        let upper = name.to_ascii_uppercase();
        let well_formed = upper.starts_with('$')
            && upper.len() > 1
            && upper[1..]
                .bytes()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, b'_' | b'[' | b']' | b','));
        if !v.is_finite() || !well_formed {
            return Err(value_error(
                path,
                text,
                "reader.system_variables",
                name,
                "expected a Sinumerik system variable with its indices (`$MN_USER_DATA_HEX[0]`) and a finite number".into(),
            ));
        }
        o.system_variables.push((upper, *v));
    }
    if let Some(file) = &r.var_file {
        let (p, t) = read("var_file", file)?;
        let params = ngc::parse_var_file(&t).map_err(|(line, m)| Error::Invalid {
            path: p.clone(),
            message: format!("line {line}: {m}"),
            help: Some("a LinuxCNC .var file has lines `number value`".into()),
        })?;
        o.parameters.extend(params);
    }
    work_offsets(path, text, r, o)?;
    if let Some(file) = &r.tool_table {
        let (p, t) = read("tool_table", file)?;
        o.pockets.extend(ngc::tool_pockets(&t));
        let invalid = |(line, m): (usize, String)| Error::Invalid {
            path: p.clone(),
            message: format!("line {line}: {m}"),
            help: Some("a LinuxCNC tool table has lines `T1 P1 Z+50.0 D6.0 ;comment`".into()),
        };
        let tools = ngc::parse_tool_table(&t).map_err(invalid)?;
        o.tools.extend(tools);
        // Lathe tools: the orientation Q, for cutter compensation under G18.
        let orientations = ngc::parse_tool_orientations(&t).map_err(invalid)?;
        o.tool_orientations.extend(orientations);
    }
    o.tools.extend(r.tools.iter().map(|t| ngc::Tool {
        number: t.number,
        length_mm: t.length_mm,
        diameter_mm: t.diameter_mm,
    }));
    if !has_config || !r.subroutine_path.is_empty() {
        o.search_path = r.subroutine_path.iter().map(|d| resolve(path, d)).collect();
    }
    user_m_codes(path, text, r, o)
}

/// `[reader] work_offsets`: G54 to G59.3 by code, finite X Y Z A B C (mm, deg).
fn work_offsets(path: &Path, text: &str, r: &ReaderSection, o: &mut ngc::Options) -> Result<()> {
    for (code, offset) in &r.work_offsets {
        let n = match code.to_ascii_uppercase().as_str() {
            "G54" => 1,
            "G55" => 2,
            "G56" => 3,
            "G57" => 4,
            "G58" => 5,
            "G59" => 6,
            "G59.1" => 7,
            "G59.2" => 8,
            "G59.3" => 9,
            _ => {
                return Err(value_error(
                    path,
                    text,
                    "reader.work_offsets",
                    code,
                    "expected one of G54 G55 G56 G57 G58 G59 G59.1 G59.2 G59.3".into(),
                ))
            }
        };
        if offset.iter().any(|v| !v.is_finite()) {
            return Err(value_error(
                path,
                text,
                "reader.work_offsets",
                code,
                "expected finite numbers".into(),
            ));
        }
        o.set_work_offset(n, ngc::AxisVec::xyzabc(*offset));
    }
    Ok(())
}

/// `[reader] user_m_codes`: each a user M code of 100 or more and its effect.
fn user_m_codes(path: &Path, text: &str, r: &ReaderSection, o: &mut ngc::Options) -> Result<()> {
    for (code, effect) in &r.user_m_codes {
        let n = code
            .trim_start_matches(['M', 'm'])
            .parse::<u32>()
            .ok()
            .filter(|n| *n >= 100);
        let Some(n) = n else {
            return Err(value_error(
                path,
                text,
                "reader.user_m_codes",
                code,
                "expected a user M code of 100 or more, such as M428".into(),
            ));
        };
        o.user_m.insert(n, *effect);
    }
    Ok(())
}
