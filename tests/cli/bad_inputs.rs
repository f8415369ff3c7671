//! A generated suite of bad input, through the binary: every key of a machine file and of a
//! scenario that writes every key out, each given values no key can take (NaN, infinities,
//! ±1e308, 5e-324 where a size is expected, the wrong type, arrays of the wrong length or
//! holding a NaN, an unknown key beside it), and G-code nested or looping past the reader's
//! bounds. Every case must exit 2 within its time, name its file with line and column and the
//! key, never panic, and never quote the machine file. `MTSIM_LONG_FAULTS=1` runs each machine
//! and scenario case through `simulate`, `analyze` and `blocks` as well as `check`.

use crate::common;

use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use common::{mtsim_plain, scratch};
use toml::Value;

/// A machine file that writes out every key a machine takes (one linear and one rotary axis
/// in full), and a marker on every line: no message may quote it.
const FULL_MACHINE: &str = r#"
name = "full"
kinematics = "trt-ac"
pivot_mm = [0.0, 0.0, 0.0]
interpolation_period_ms = 1.0
dialect = "fanuc"
g28_mm = [0.0, 0.0, 100.0, 0.0, 0.0, 0.0]
g30_mm = [0.0, 0.0, 100.0, 0.0, 0.0, 0.0]

[axes.X]
min = -400.0
max = 400.0
max_velocity = 30000.0
max_acceleration = 3000.0
max_jerk = 50000.0

[axes.X.servo]
model = "cascade"
kv_per_s = 30.0
velocity_feedforward = 0.5
acceleration_feedforward = 0.5
feedback = "semi-closed"
velocity_bandwidth_hz = 60.0
velocity_integral_time_ms = 10.0
current_time_constant_ms = 0.2
servo_period_ms = 0.25
substeps = 2
following_error_limit_mm = 50.0

[axes.X.drive]
backlash_mm = 0.002
motor_mass_kg = 250.0
table_mass_kg = 500.0
stiffness_n_per_um = 200.0
damping_ratio = 0.05
force_limit_n = 20000.0

[axes.X.friction]
coulomb_n = 150.0
static_ratio = 1.3
stribeck_velocity_mm_per_s = 0.5
viscous_n_s_per_m = 1000.0
presliding_um = 2.0
presliding_damping_ratio = 1.0

[axes.Y]
min = -350.0
max = 350.0
max_velocity = 30000.0
max_acceleration = 3000.0
max_jerk = 50000.0

[axes.Z]
min = -150.0
max = 450.0
max_velocity = 30000.0
max_acceleration = 3000.0
max_jerk = 50000.0

[axes.A]
min = -30.0
max = 120.0
max_velocity = 5400.0
max_acceleration = 3600.0
max_jerk = 60000.0

[axes.A.servo]
model = "first-order"
kv_per_s = 30.0
following_error_limit_deg = 90.0

[axes.A.drive]
backlash_deg = 0.001
motor_inertia_kgm2 = 3.0
table_inertia_kgm2 = 5.0
stiffness_nm_per_rad = 3000000.0
torque_limit_nm = 1200.0

[axes.A.friction]
coulomb_nm = 15.0
stribeck_velocity_deg_per_s = 0.1
viscous_nm_s_per_rad = 5.0
presliding_deg = 0.0001

[axes.C]
min = -360.0
max = 360.0
continuous = true
max_velocity = 9000.0
max_acceleration = 7200.0
max_jerk = 120000.0

[scene]
near_miss_mm = 2.0
engagement_resolution_mm = 1.0
depth_tolerance_mm = 0.01
depth_tolerance_relative = 0.01

[scene.table]
top_z_mm = 0.0
radius_mm = 200.0
thickness_mm = 60.0
axis = "z"

[[scene.cradle]]
name = "floor"
center_mm = [0.0, 0.0, -150.0]
size_mm = [500.0, 400.0, 60.0]

[scene.spindle]
shape = "cylinder"
diameter_mm = 120.0
box_mm = [160.0, 160.0]
length_mm = 250.0

[tool]
cutter_diameter_mm = 20.0
flute_length_mm = 40.0
shank_diameter_mm = 20.0
shank_length_mm = 60.0
holder_diameter_mm = 50.0
holder_length_mm = 60.0
gauge_length_mm = 140.0

[location_errors]
EX0C_um = 8.0
EZ0A_um = 10.0
EA0C_urad = -15.0
"#;

/// A cone scenario that writes out every key of its tables.
const FULL_CONE_SCENARIO: &str = r#"
machine = "m.toml"

[program.cone]
half_apex_deg = 15.0
inclination_deg = 10.0
center_mm = [0.0, 0.0, 200.0]
ballbar_length_mm = 100.0
segments = 360
feed_mm_min = 1000.0
inverse_time = false
tcp = false
directions = ["ccw"]

[simulate]
tcp = false
trace_every = 1
trace_format = "csv"
lead_deg = 20.0
max_samples = 1000000000
max_trace_rows = 10000000

[ballbar]
pivot_mm = [0.0, 0.0, 200.0]

[workpiece]
kind = "cone-frustum"
riser = true
ball_diameter_mm = 12.7
bar_diameter_mm = 8.0
post_diameter_mm = 10.0

[check]
near_miss_mm = 2.0
collisions = true

[machine_overrides.axes.Y]
max_velocity = 20000.0
"#;

/// A file scenario with every `[reader]` key.
const FULL_FILE_SCENARIO: &str = r#"
machine = "m.toml"

[program]
file = "p.ngc"

[simulate]
measure_lines = [2, 3]

[reader]
dialect = "linuxcnc"
tools = [{ number = 1, length_mm = 50.0, diameter_mm = 6.0 }]
work_offsets = { G54 = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0] }
user_m_codes = { M428 = "tcp-on", M429 = "tcp-off" }
tcp = false
hal_pins = { "a.b" = 1.0 }

[check]
collisions = false
"#;

/// The G-code program of the file scenario.
const PROGRAM: &str = "G21 G90 G17\nG0 X0 Y0 Z100\nG1 X10 F1000\nG1 Y10\nM2\n";

/// Appended to every line of the machine file.
const MARKER: &str = "MARKER-never-quoted-7f3a";

/// One bad input: the files to write and the command's arguments.
struct Case {
    label: String,
    machine: String,
    scenario: String,
    program: String,
    /// Words the message must hold (the file's name, then the key: `a.b.key` or, for a
    /// value that breaks a relation between the keys of one table, any key of `a.b`).
    expect: Vec<String>,
    /// Whether the machine file is the one made bad (its lines must not be quoted).
    machine_is_bad: bool,
    commands: Vec<&'static str>,
}

/// The values no key can take, for a leaf holding `value`.
fn bad_values(value: &Value) -> Vec<(&'static str, Value)> {
    let table = Value::Table(toml::Table::new());
    let text = Value::String("not-a-value".into());
    match value {
        Value::Float(_) | Value::Integer(_) => vec![
            ("nan", Value::Float(f64::NAN)),
            ("inf", Value::Float(f64::INFINITY)),
            ("-inf", Value::Float(f64::NEG_INFINITY)),
            ("1e308", Value::Float(1e308)),
            ("-1e308", Value::Float(-1e308)),
            ("text", text),
            ("bool", Value::Boolean(true)),
            ("array", Value::Array(vec![Value::Float(1.0)])),
            ("table", table),
        ],
        Value::String(_) => vec![
            ("number", Value::Integer(42)),
            ("unknown-name", Value::String("no-such-thing".into())),
            ("bool", Value::Boolean(false)),
            ("array", Value::Array(vec![])),
        ],
        Value::Boolean(_) => vec![
            ("text", Value::String("yes".into())),
            ("number", Value::Integer(1)),
        ],
        Value::Array(items) if items.iter().all(|v| v.is_float() || v.is_integer()) => {
            let mut longer = items.clone();
            longer.push(Value::Float(1.0));
            let mut nan = items.clone();
            if let Some(first) = nan.first_mut() {
                *first = Value::Float(f64::NAN);
            }
            let mut cases = vec![
                ("longer", Value::Array(longer)),
                ("empty", Value::Array(vec![])),
                ("text", text),
            ];
            if items.len() > 1 {
                cases.push(("shorter", Value::Array(items[..items.len() - 1].to_vec())));
            }
            if !items.is_empty() {
                cases.push(("nan-item", Value::Array(nan)));
                cases.push(("huge-item", {
                    let mut huge = items.clone();
                    huge[0] = Value::Float(1e308);
                    Value::Array(huge)
                }));
            }
            cases
        }
        Value::Array(_) => vec![("text", text), ("number", Value::Integer(3))],
        _ => vec![],
    }
}

/// Every leaf of `table` as (path, value), and every table's path (for an unknown key).
fn leaves(
    table: &toml::Table,
    path: &mut Vec<String>,
    out: &mut Vec<(Vec<String>, Value)>,
    tables: &mut Vec<Vec<String>>,
) {
    tables.push(path.clone());
    for (key, value) in table {
        path.push(key.clone());
        match value {
            Value::Table(t) => leaves(t, path, out, tables),
            Value::Array(items) if items.iter().all(Value::is_table) && !items.is_empty() => {
                for (i, item) in items.iter().enumerate() {
                    path.push(i.to_string());
                    leaves(item.as_table().unwrap(), path, out, tables);
                    path.pop();
                }
            }
            _ => out.push((path.clone(), value.clone())),
        }
        path.pop();
    }
}

/// The value at `path` (table keys and array indices) made mutable.
fn at<'a>(root: &'a mut Value, path: &[String]) -> &'a mut Value {
    path.iter().fold(root, |v, key| match v {
        Value::Table(t) => t.get_mut(key).unwrap(),
        Value::Array(a) => &mut a[key.parse::<usize>().unwrap()],
        _ => unreachable!(),
    })
}

/// The machine file as written: every line carries the marker.
fn machine_text(value: &Value) -> String {
    let text = toml::to_string(value).unwrap();
    text.lines()
        .map(|l| {
            if l.trim().is_empty() {
                String::new()
            } else {
                format!("{l} # {MARKER}")
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
        + "\n"
}

/// The cases made from one base file (`which` "m.toml" or "s.toml").
fn cases_of(
    base_machine: &str,
    base_scenario: &str,
    which: &'static str,
    commands: &[&'static str],
) -> Vec<Case> {
    let machine: Value = toml::from_str(base_machine).unwrap();
    let scenario: Value = toml::from_str(base_scenario).unwrap();
    let target = if which == "m.toml" {
        &machine
    } else {
        &scenario
    };
    let (mut found, mut tables) = (Vec::new(), Vec::new());
    leaves(
        target.as_table().unwrap(),
        &mut Vec::new(),
        &mut found,
        &mut tables,
    );
    let mut cases = Vec::new();
    let mut push = |bad: Value, label: String, key: String| {
        let (m, s) = if which == "m.toml" {
            (machine_text(&bad), toml::to_string(&scenario).unwrap())
        } else {
            (machine_text(&machine), toml::to_string(&bad).unwrap())
        };
        cases.push(Case {
            label,
            machine: m,
            scenario: s,
            program: PROGRAM.into(),
            expect: vec![which.into(), key],
            machine_is_bad: which == "m.toml",
            commands: commands.to_vec(),
        });
    };
    for (path, value) in &found {
        // The scenario's own file names are not values (a missing file is its own test).
        if which == "s.toml" && matches!(path.last().map(String::as_str), Some("machine" | "file"))
        {
            continue;
        }
        for (what, bad) in bad_values(value) {
            // A cradle box's name is free text; a number there is the only bad value.
            if path.last().is_some_and(|k| k == "name") && what == "unknown-name" {
                continue;
            }
            let mut root = target.clone();
            *at(&mut root, path) = bad;
            push(
                root,
                format!("{which} {} = {what}", path.join(".")),
                path.join("."),
            );
        }
    }
    for table in &tables {
        // HAL pins are named freely: any name is one.
        if table.last().is_some_and(|k| k == "hal_pins") {
            continue;
        }
        let mut root = target.clone();
        at(&mut root, table)
            .as_table_mut()
            .unwrap()
            .insert("bogus_key".into(), Value::Float(1.0));
        push(
            root,
            format!("{which} {}.bogus_key", table.join(".")),
            "bogus_key".into(),
        );
    }
    cases
}

/// G-code past the reader's bounds: nesting of brackets, functions and calls, and loops.
fn gcode_cases() -> Vec<Case> {
    let scenario =
        "machine = \"m.toml\"\n[program]\nfile = \"p.ngc\"\n[check]\ncollisions = false\n";
    let nest = |open: &str, close: &str, depth: usize| {
        format!(
            "G0 X0 Y0 Z100\nG1 X{}1{} F1000\nM2\n",
            open.repeat(depth),
            close.repeat(depth)
        )
    };
    let mut programs: Vec<(String, String)> = Vec::new();
    for depth in [101, 150, 1000, 10_000, 20_000] {
        programs.push((format!("brackets {depth}"), nest("[", "]", depth)));
        programs.push((format!("ABS {depth}"), nest("ABS[", "]", depth)));
        programs.push((format!("SIN {depth}"), nest("SIN[", "]", depth)));
        programs.push((format!("unary minus {depth}"), nest("-[", "]", depth)));
    }
    let recursive = "o<r> sub\no<r> call\no<r> endsub\nG0 X0 Y0 Z100\no<r> call\nM2\n";
    programs.push(("endless recursion".into(), recursive.into()));
    let endless = |moves: &str| {
        format!("G21 G90\nG0 X0 Y0 Z100\nF1000\no100 while [1]\n{moves}o100 endwhile\nM2\n")
    };
    programs.push(("endless loop with moves".into(), endless("G1 X10\nG1 X0\n")));
    programs.push((
        "endless loop without moves".into(),
        endless("#1 = [#1 + 1]\n"),
    ));
    programs.push(("endless loop of dwells".into(), endless("G4 P1\n")));
    // (A block left open when M2 ends the program is not bad input: rs274 runs it.)
    for (label, body) in [
        ("endwhile alone", "o1 endwhile\n"),
        ("endif alone", "o1 endif\n"),
        ("else alone", "o1 else\n"),
        ("endsub alone", "o1 endsub\n"),
        ("call of no sub", "o<nowhere> call\n"),
        ("while without condition", "o1 while\no1 endwhile\n"),
        ("if without condition", "o1 if\no1 endif\n"),
        ("unclosed bracket", "G1 X[1 + 2 F1000\n"),
        ("division by zero", "G1 X[1/0] F1000\n"),
        ("unknown function", "G1 X[FOO[1]] F1000\n"),
    ] {
        programs.push((label.into(), format!("G0 X0 Y0 Z100\n{body}M2\n")));
    }
    programs.push((
        "goto without end".into(),
        "G0 X0 Y0 Z100\nF1000\no2 do\nG1 X1\nG1 X0\no2 while [1]\nM2\n".into(),
    ));
    programs
        .into_iter()
        .map(|(label, program)| Case {
            label: format!("p.ngc {label}"),
            machine: machine_text(&toml::from_str::<Value>(FULL_MACHINE).unwrap()),
            scenario: scenario.into(),
            program,
            expect: vec!["p.ngc".into()],
            machine_is_bad: false,
            commands: vec!["check", "analyze", "blocks"],
        })
        .collect()
}

/// Runs one case in `dir`: each command must exit 2, in time, with the file, line, column
/// and key named, no panic, and the machine file unquoted. Returns what went wrong.
fn run_case(dir: &Path, case: &Case) -> Vec<String> {
    std::fs::write(dir.join("m.toml"), &case.machine).unwrap();
    std::fs::write(dir.join("s.toml"), &case.scenario).unwrap();
    std::fs::write(dir.join("p.ngc"), &case.program).unwrap();
    let mut faults = Vec::new();
    for &command in &case.commands {
        let args: Vec<&str> = match command {
            "simulate" => vec![command, "s.toml", "-o", "out", "-q"],
            _ => vec![command, "s.toml"],
        };
        let start = Instant::now();
        let out = mtsim_plain(dir, &args);
        let took = start.elapsed();
        let err = String::from_utf8_lossy(&out.stderr).replace('│', " ");
        let flat = err.split_whitespace().collect::<Vec<_>>().join(" ");
        let mut fault =
            |what: String| faults.push(format!("{} [{command}]: {what}\n    {flat}", case.label));
        match out.status.code() {
            Some(2) => {}
            Some(0) => fault("accepted (exit 0)".into()),
            code => fault(format!("exit {code:?}")),
        }
        if took > Duration::from_secs(30) {
            fault(format!("took {took:?}"));
        }
        if err.contains("panicked") {
            fault("panicked".into());
        }
        if case.machine_is_bad && err.contains(MARKER) {
            fault("quoted the machine file".into());
        }
        if out.status.code() == Some(2) {
            let (file, key) = (&case.expect[0], case.expect.get(1));
            if !flat.contains(file.as_str()) {
                fault(format!("does not name {file:?}"));
            }
            if let Some(key) = key {
                if !names_key(&flat, key) {
                    fault(format!("does not name {key:?}"));
                }
            }
            let located = case.expect[0].as_str();
            let has_location = flat.match_indices(located).any(|(i, _)| {
                let rest = &flat[i + located.len()..];
                rest.starts_with(':') && rest[1..].starts_with(|c: char| c.is_ascii_digit())
            });
            if !has_location {
                fault(format!("no {located}:line:column"));
            }
        }
    }
    faults
}

/// Whether `message` names the dotted `key` (array indices dropped): the key itself, its
/// last part, or, for a relation between the keys of one table, that table.
fn names_key(message: &str, key: &str) -> bool {
    let parts: Vec<&str> = key
        .split('.')
        .filter(|p| p.parse::<usize>().is_err())
        .collect();
    let leaf = parts.last().copied().unwrap_or(key);
    let table = parts[..parts.len().saturating_sub(1)].join(".");
    message.contains(leaf) || (!table.is_empty() && message.contains(&format!("`{table}.")))
}

/// All cases, on two workers (each in its own folder).
fn run_all(cases: &[Case]) -> Vec<String> {
    let next = AtomicUsize::new(0);
    let faults = Mutex::new(Vec::new());
    std::thread::scope(|scope| {
        for worker in 0..2 {
            let (next, faults) = (&next, &faults);
            scope.spawn(move || {
                let dir = scratch("bad-inputs", &format!("w{worker}"));
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(case) = cases.get(i) else { break };
                    let found = run_case(&dir, case);
                    faults.lock().unwrap().extend(found);
                }
            });
        }
    });
    let mut faults = faults.into_inner().unwrap();
    faults.sort();
    faults
}

#[test]
fn a_thousand_generated_bad_inputs_are_each_refused_with_their_file_line_and_key() {
    let long = std::env::var_os("MTSIM_LONG_FAULTS").is_some();
    let commands: &[&'static str] = if long {
        &["check", "simulate", "analyze", "blocks"]
    } else {
        &["check"]
    };
    let mut cases = cases_of(FULL_MACHINE, FULL_CONE_SCENARIO, "m.toml", commands);
    let machine_cases = cases.len();
    cases.extend(cases_of(
        FULL_MACHINE,
        FULL_CONE_SCENARIO,
        "s.toml",
        commands,
    ));
    cases.extend(cases_of(
        FULL_MACHINE,
        FULL_FILE_SCENARIO,
        "s.toml",
        commands,
    ));
    let scenario_cases = cases.len() - machine_cases;
    let gcode = gcode_cases();
    let gcode_cases = gcode.len();
    cases.extend(gcode);
    let runs: usize = cases.iter().map(|c| c.commands.len()).sum();
    eprintln!(
        "bad inputs: {} cases ({machine_cases} machine, {scenario_cases} scenario, {gcode_cases} G-code), {runs} runs",
        cases.len()
    );
    assert!(cases.len() >= 1000, "{} cases", cases.len());
    let faults = run_all(&cases);
    assert!(
        faults.is_empty(),
        "{} of {runs} runs went wrong:\n{}",
        faults.len(),
        faults.join("\n")
    );
}
