//! Helpers shared by the integration tests (each stage's `tests/<stage>/main.rs` has
//! `#[path = "../common/mod.rs"] mod common;`, and its files `use crate::common;`).

#![allow(dead_code)]

pub mod linuxcnc;
pub mod rs274;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use mtsim::input::machine::Machine;
use mtsim::input::ConeTest;
use nalgebra::Vector3;

/// The body of a scenario (after its `machine =` line) for the 15/10 cone at O = (0, 0, 200), L = 100.
pub const CONE_15_10: &str = "[program.cone]\nhalf_apex_deg = 15.0\ninclination_deg = 10.0\ncenter_mm = [0.0, 0.0, 200.0]\nballbar_length_mm = 100.0\n";

/// The `mtsim` binary with `args`, to be run in folder `dir`.
fn command(dir: &Path, args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_mtsim"));
    c.args(args).current_dir(dir);
    c
}

/// Runs the `mtsim` binary with `args` from the crate root and returns its output.
pub fn mtsim(args: &[&str]) -> Output {
    command(Path::new(env!("CARGO_MANIFEST_DIR")), args)
        .output()
        .expect("the binary runs")
}

/// Runs `mtsim` in `dir` as plain text: NO_COLOR=1, no terminal, no forced colour, links or narration.
pub fn mtsim_plain(dir: &Path, args: &[&str]) -> Output {
    command(dir, args)
        .env("NO_COLOR", "1")
        .env_remove("FORCE_COLOR")
        .env_remove("CLICOLOR_FORCE")
        .env_remove("FORCE_HYPERLINK")
        .env_remove("NO_GRAPHICS")
        .output()
        .expect("the binary runs")
}

/// Asserts the run succeeded and parses its stdout as one JSON object.
pub fn stdout_json(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("stdout is one JSON object")
}

/// A fresh, empty temporary folder for one test: `mtsim-<prefix>-<pid>-<name>`.
pub fn scratch(prefix: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mtsim-{prefix}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Absolute path of the bundled machine `machines/<name>.toml`, as a string.
pub fn machine(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("machines")
        .join(format!("{name}.toml"))
        .display()
        .to_string()
}

/// Absolute path of the bundled trt-ac machine, as a string.
pub fn trt_ac() -> String {
    machine("trt-ac")
}

/// The bundled trt-ac machine, loaded.
pub fn load_trt_ac() -> Machine {
    Machine::load(Path::new(&trt_ac())).unwrap()
}

/// A cone test of half apex `alpha` and inclination `beta` (deg) at O = (0, `yt`, 200), bar `length` mm.
pub fn cone(alpha: f64, beta: f64, yt: f64, length: f64) -> ConeTest {
    ConeTest {
        half_apex_deg: alpha,
        inclination_deg: beta,
        center_mm: Vector3::new(0.0, yt, 200.0),
        ballbar_length_mm: length,
    }
}

/// Scenario text: `machine = "<machine>"` followed by `body`.
pub fn scenario_text(machine: &str, body: &str) -> String {
    format!("machine = {machine:?}\n{body}")
}

/// Writes `dir/p.ngc` (LinuxCNC) and `dir/s.toml` running it on the bundled fork head with
/// no workpiece and exact collision depths (no depth tolerance: the deepest sample is the
/// one a hand computation places); returns the scenario's path.
pub fn fork_head_scenario(dir: &Path, program: &str) -> PathBuf {
    std::fs::write(dir.join("p.ngc"), program).unwrap();
    write_scenario(
        dir,
        &machine("fork-head-ca"),
        "[program]\nfile = \"p.ngc\"\n[reader]\ndialect = \"linuxcnc\"\n\
         [workpiece]\nkind = \"none\"\n\
         [machine_overrides.scene]\ndepth_tolerance_mm = 0.0\ndepth_tolerance_relative = 0.0\n",
    )
}

/// Writes `dir/s.toml` with `machine = "<machine>"` followed by `body`; returns its path.
pub fn write_scenario(dir: &Path, machine: &str, body: &str) -> PathBuf {
    let path = dir.join("s.toml");
    std::fs::write(&path, scenario_text(machine, body)).unwrap();
    path
}

/// Writes the G-code `program` as `dir/p.nc` and a scenario `dir/s.toml` that runs it on the
/// three-axis machine (X -400 .. 400 mm); returns the scenario's path.
pub fn file_scenario(dir: &Path, program: &str) -> String {
    std::fs::write(dir.join("p.nc"), program).unwrap();
    let body = "[program]\nfile = \"p.nc\"\n";
    write_scenario(dir, &machine("vmc-3axis"), body)
        .display()
        .to_string()
}

/// The path of a LinuxCNC sample machine file, `machines/linuxcnc/<stem>.toml`.
pub fn linuxcnc_machine(stem: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("machines/linuxcnc")
        .join(format!("{stem}.toml"))
        .display()
        .to_string()
}

/// Runs `mtsim CMD s.toml ARGS..` (`cmd` = `[CMD, ARGS..]`) in a scratch folder
/// `<prefix>-<name>` holding `program` as `p.ngc` and a scenario on the LinuxCNC sample
/// machine `machine` with the extra TOML `body`.
pub fn run_on_linuxcnc_machine(
    prefix: &str,
    name: &str,
    machine: &str,
    program: &str,
    body: &str,
    cmd: &[&str],
) -> Output {
    let dir = scratch(prefix, name);
    std::fs::write(dir.join("p.ngc"), program).unwrap();
    std::fs::write(
        dir.join("s.toml"),
        format!(
            "machine = {:?}\n[program]\nfile = \"p.ngc\"\n{body}\n",
            linuxcnc_machine(machine)
        ),
    )
    .unwrap();
    let mut args = cmd.to_vec();
    args.insert(1, "s.toml");
    mtsim_plain(&dir, &args)
}

/// A CSV file of numbers with a header (a `trace.csv`): text columns read as NaN.
pub struct CsvTable {
    pub header: Vec<String>,
    pub rows: Vec<Vec<f64>>,
}

impl CsvTable {
    pub fn read(path: &Path) -> CsvTable {
        let text = std::fs::read_to_string(path).unwrap();
        let mut lines = text.lines();
        let header = lines
            .next()
            .unwrap()
            .split(',')
            .map(str::to_string)
            .collect();
        let rows = lines
            .map(|l| {
                l.split(',')
                    .map(|v| v.parse().unwrap_or(f64::NAN))
                    .collect()
            })
            .collect();
        CsvTable { header, rows }
    }

    /// The index of column `name`.
    pub fn col(&self, name: &str) -> usize {
        let found = self.header.iter().position(|h| h == name);
        found.unwrap_or_else(|| panic!("the table has no column {name}"))
    }
}
