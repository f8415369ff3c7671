//! The scenario's `[reader]` section reaches the interpreter: dialect, tools (inline and
//! LinuxCNC `.tbl`), `.var` parameters, work offsets, user M codes, and the machine's axes.

use crate::common;

use std::path::Path;

use common::{scratch, trt_ac, write_scenario};
use mtsim::input::scenario::Scenario;
use mtsim::program::file::read_file;
use mtsim::Axis;

fn ends(scenario: &Scenario, program: &Path) -> Result<Vec<[f64; 6]>, String> {
    read_file(program, &scenario.reader)
        .map_err(|e| e.to_string())?
        .map(|m| {
            m.map(|m| Axis::XYZABC.map(|a| m.end[a]))
                .map_err(|e| e.to_string())
        })
        .collect()
}

#[test]
fn work_offsets_tools_and_parameters_come_from_the_scenario() {
    let dir = scratch("reader", "offsets");
    std::fs::write(
        dir.join("tools.tbl"),
        "T1 P1 Z+50.0 D6.0 ;end mill\nT2 P2 Z+80 D10\n",
    )
    .unwrap();
    // #5241-#5243: G55 = (1, 2, 3); #5161-#5163: G28 position (0, 0, 300).
    std::fs::write(dir.join("sim.var"), "5241 1\n5242 2\n5243 3\n5163 300\n").unwrap();
    std::fs::write(
        dir.join("p.ngc"),
        "G21 G90\nT1 M6 G43 H1\nG0 X10 Y20 Z30\nG55 G0 X0 Y0 Z0\nT2 M6 G43\nG0 Z0\nM428\nG28\nM2\n",
    )
    .unwrap();
    let scenario_path = write_scenario(
        &dir,
        &trt_ac(),
        r#"
[program]
file = "p.ngc"

[reader]
dialect = "linuxcnc"
tool_table = "tools.tbl"
var_file = "sim.var"
work_offsets = { G54 = [100.0, 50.0, -200.0, 0.0, 0.0, 0.0] }
user_m_codes = { M428 = "tcp-on" }
"#,
    );
    let scenario = Scenario::load(&scenario_path).unwrap();
    assert_eq!(scenario.reader.dialect, ngc::Dialect::Linuxcnc);
    let got = ends(&scenario, &dir.join("p.ngc")).unwrap();
    assert_eq!(
        got,
        [
            // G54 (100, 50, -200) + tool 1 length 50 on Z.
            [110.0, 70.0, -120.0, 0.0, 0.0, 0.0],
            // G55 (1, 2, 3) + 50.
            [1.0, 2.0, 53.0, 0.0, 0.0, 0.0],
            // Tool 2: 3 + 80.
            [1.0, 2.0, 83.0, 0.0, 0.0, 0.0],
            // G28 with no words: every axis of the machine to the .var position.
            [0.0, 0.0, 300.0, 0.0, 0.0, 0.0],
        ]
    );
}

#[test]
fn a_word_for_an_axis_the_machine_lacks_is_an_error() {
    let dir = scratch("reader", "axes");
    std::fs::write(dir.join("p.nc"), "G0 X1\nG0 B10\n").unwrap();
    let scenario = Scenario::load(&write_scenario(
        &dir,
        &trt_ac(),
        "[program]\nfile = \"p.nc\"\n",
    ))
    .unwrap();
    let err = ends(&scenario, &dir.join("p.nc")).unwrap_err();
    assert!(
        err.contains("p.nc:2:4") && err.contains("no B axis"),
        "{err}"
    );
}

#[test]
fn bad_reader_keys_are_input_errors() {
    let dir = scratch("reader", "bad");
    std::fs::write(dir.join("p.nc"), "G0 X1\n").unwrap();
    let bad = write_scenario(
        &dir,
        &trt_ac(),
        "[program]\nfile = \"p.nc\"\n[reader]\nuser_m_codes = { M5 = \"tcp-on\" }\n",
    );
    let err = Scenario::load(&bad).unwrap_err().to_string();
    assert!(err.contains("user M code of 100 or more"), "{err}");
    let bad = write_scenario(
        &dir,
        &trt_ac(),
        "[program]\nfile = \"p.nc\"\n[reader]\nwork_offsets = { G60 = [0, 0, 0, 0, 0, 0] }\n",
    );
    let err = Scenario::load(&bad).unwrap_err().to_string();
    assert!(err.contains("G54 G55"), "{err}");
    let bad = write_scenario(
        &dir,
        &trt_ac(),
        "[program]\nfile = \"p.nc\"\n[reader]\ndialect = \"mazak\"\n",
    );
    assert!(Scenario::load(&bad).is_err());
}

#[test]
fn tilted_planes_and_dynamic_work_offsets_use_the_machine_kinematics() {
    use mtsim::kinematics::{Branch, ToolPose};
    use nalgebra::{Point3, Vector3};
    let dir = scratch("reader", "tilted");
    let kin = common::load_trt_ac().kinematics;
    // Haas G254 on the trt-ac machine: the programmed point (10, 5, 2) rides on the table,
    // so after A30 C90 it is where mtsim's own forward chain puts that table point.
    std::fs::write(
        dir.join("g254.nc"),
        "G254\nG0 X10. Y5. Z2.\nA30. C90.\nM30\n",
    )
    .unwrap();
    let scenario = Scenario::load(&write_scenario(
        &dir,
        &trt_ac(),
        "[program]\nfile = \"g254.nc\"\n\n[reader]\ndialect = \"haas\"\n",
    ))
    .unwrap();
    let got = ends(&scenario, &dir.join("g254.nc")).unwrap();
    let mut q = mtsim::AxisVec::ZERO;
    q[Axis::A] = 30.0;
    q[Axis::C] = 90.0;
    let m = kin.table_to_machine(&q, &Point3::new(10.0, 5.0, 2.0));
    for (k, want) in [m.x, m.y, m.z, 30.0, 0.0, 90.0].iter().enumerate() {
        assert!((got[1][k] - want).abs() < 1e-9, "{:?} vs {m:?}", got[1]);
    }
    // Fanuc G68.2 I30 J40 K0 then G53.1: the feature Z axis Rz(30) Rx(40) e_z =
    // (sin30 sin40, -cos30 sin40, cos40) becomes the tool axis, as mtsim's inverse
    // kinematics positions A and C for that tool axis.
    std::fs::write(
        dir.join("g682.nc"),
        "G68.2 X0 Y0 Z0 I30. J40. K0\nG53.1\nM30\n",
    )
    .unwrap();
    let scenario = Scenario::load(&write_scenario(
        &dir,
        &trt_ac(),
        "[program]\nfile = \"g682.nc\"\n\n[reader]\ndialect = \"fanuc\"\n",
    ))
    .unwrap();
    let got = ends(&scenario, &dir.join("g682.nc")).unwrap();
    let (s30, c30, s40, c40) = (
        0.5,
        3f64.sqrt() / 2.0,
        40f64.to_radians().sin(),
        40f64.to_radians().cos(),
    );
    let pose = ToolPose {
        tip: Point3::origin(),
        axis: Vector3::new(s30 * s40, -c30 * s40, c40),
    };
    let want = kin.inverse(&pose, Branch::Primary, 0.0);
    assert!(
        (got[0][3] - want[Axis::A]).abs() < 1e-9,
        "{:?} vs {want:?}",
        got[0]
    );
    assert!(
        (got[0][5] - want[Axis::C]).abs() < 1e-9,
        "{:?} vs {want:?}",
        got[0]
    );
    assert!(
        (got[0][3] - 40.0).abs() < 1e-9,
        "A = J for a tilt about X: {:?}",
        got[0]
    );
}

/// `linuxcnc_ini`: an inch configuration's tool table and parameter file are converted to
/// mm, its subroutine path and remaps apply, its numeric values are `#<_ini[...]>`, HAL
/// pins come from `hal_pins`; an explicit scenario key takes precedence over the ini's.
#[test]
fn a_linuxcnc_configuration_gives_tools_parameters_paths_and_remaps() {
    let dir = scratch("reader", "ini");
    std::fs::create_dir_all(dir.join("cfg/subs")).unwrap();
    std::fs::write(
        dir.join("cfg/mill.ini"),
        "[TRAJ]\nLINEAR_UNITS = inch\n[EMCIO]\nTOOL_TABLE = mill.tbl\n[RS274NGC]\n\
         PARAMETER_FILE = mill.var\nSUBROUTINE_PATH = subs\n\
         REMAP = M401 modalgroup=10 argspec=P ngc=m401\n[PARK]\nZ = 2.5\n",
    )
    .unwrap();
    // Tool 1: 2 in long; G54 X = 1 in (#5221).
    std::fs::write(dir.join("cfg/mill.tbl"), "T1 P1 Z2.0 D0.25\n").unwrap();
    std::fs::write(dir.join("cfg/mill.var"), "5221 1.0\n").unwrap();
    std::fs::write(
        dir.join("cfg/subs/m401.ngc"),
        "o<m401> sub\nG0 Y[#<p> + #<_ini[park]z> + #<_hal[spindle.0.at-speed]>]\no<m401> endsub\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("p.ngc"),
        "G21 G90\nT1 M6 G43 H1\nG0 X0 Y0 Z0\nM401 P4\nM2\n",
    )
    .unwrap();
    let scenario = |extra: &str| {
        let path = write_scenario(
            &dir,
            &trt_ac(),
            &format!(
                "[program]\nfile = \"p.ngc\"\n[reader]\ndialect = \"linuxcnc\"\nlinuxcnc_ini = \"cfg/mill.ini\"\nhal_pins = {{ \"spindle.0.at-speed\" = 1.0 }}\n{extra}"
            ),
        );
        Scenario::load(&path).unwrap()
    };
    let got = ends(&scenario(""), &dir.join("p.ngc")).unwrap();
    // X: G54 1 in = 25.4 mm; Z: tool length 2 in = 50.8 mm; Y: P + 2.5 + 1 (mm, G21).
    assert_eq!(
        got,
        [
            [25.4, 0.0, 50.8, 0.0, 0.0, 0.0],
            [25.4, 7.5, 50.8, 0.0, 0.0, 0.0]
        ]
    );
    // A scenario tool table replaces the configuration's.
    std::fs::write(dir.join("mm.tbl"), "T1 P1 Z10.0\n").unwrap();
    let got = ends(&scenario("tool_table = \"mm.tbl\"\n"), &dir.join("p.ngc")).unwrap();
    assert_eq!(got[0], [25.4, 0.0, 10.0, 0.0, 0.0, 0.0]);
    // The configuration's LINEAR_UNITS = inch is the unit the machine starts in: X1 with no
    // G20/G21 is 1 in = 25.4 mm, plus G54's 25.4 mm; the scenario's start_units = "mm"
    // wins over it (1 mm + 25.4 mm), as it would over the machine file's [start] units.
    std::fs::write(dir.join("p.ngc"), "G90\nG0 X1 Y0 Z0\nM2\n").unwrap();
    let got = ends(&scenario(""), &dir.join("p.ngc")).unwrap();
    assert_eq!(got, [[50.8, 0.0, 0.0, 0.0, 0.0, 0.0]]);
    let got = ends(&scenario("start_units = \"mm\"\n"), &dir.join("p.ngc")).unwrap();
    assert_eq!(got, [[26.4, 0.0, 0.0, 0.0, 0.0, 0.0]]);
    // An unreadable configuration names the file and line.
    std::fs::write(dir.join("cfg/mill.ini"), "[TRAJ]\nthis is not a key\n").unwrap();
    let path = write_scenario(
        &dir,
        &trt_ac(),
        "[program]\nfile = \"p.ngc\"\n[reader]\nlinuxcnc_ini = \"cfg/mill.ini\"\n",
    );
    let err = Scenario::load(&path).unwrap_err().to_string();
    assert!(err.contains("mill.ini:2:"), "{err}");
}

/// G28 on a machine file without `g28_mm` is refused naming the key; on the bundled VMC it
/// goes to the file's Z (the top of Z's travel, 200 mm).
#[test]
fn g28_takes_the_machine_files_reference_or_is_refused_naming_the_key() {
    let dir = scratch("reader", "g28");
    std::fs::write(
        dir.join("p.nc"),
        "G21 G90\nG0 X10. Y20. Z5.\nG91 G28 Z0\nG90\nM30\n",
    )
    .unwrap();
    let body = "[program]\nfile = \"p.nc\"\n[reader]\ndialect = \"fanuc\"\n";
    let scenario =
        Scenario::load(&write_scenario(&dir, &common::machine("vmc-3axis"), body)).unwrap();
    let got = ends(&scenario, &dir.join("p.nc")).unwrap();
    assert_eq!(got.last().unwrap()[..3], [10.0, 20.0, 200.0]);
    // The same machine without its reference positions.
    let text = std::fs::read_to_string(common::machine("vmc-3axis")).unwrap();
    let stripped: String = text
        .lines()
        .filter(|l| !l.starts_with("g28_mm") && !l.starts_with("g30_mm"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(dir.join("m.toml"), stripped).unwrap();
    let machine = dir.join("m.toml").display().to_string();
    let scenario = Scenario::load(&write_scenario(&dir, &machine, body)).unwrap();
    let err = ends(&scenario, &dir.join("p.nc")).unwrap_err();
    assert!(
        err.contains("`g28_mm` in the machine file") && err.contains("not given"),
        "{err}"
    );
}

/// TCP cancel on the bundled trt-ac: after `G49` the current point is where mtsim's own
/// kinematics put the axes, so `G1 Z20` moves Z alone.
#[test]
fn a_tcp_cancel_takes_the_machines_axis_positions() {
    let dir = scratch("reader", "tcp-cancel");
    std::fs::write(
        dir.join("p.nc"),
        "G21 G90\nG0 X0 Y0 Z50. A0 C0\nG43.4\nG1 X5. Y10. Z2. A30. C40. F500\nG49\nG1 Z20.\nM30\n",
    )
    .unwrap();
    let scenario = Scenario::load(&write_scenario(
        &dir,
        &trt_ac(),
        "[program]\nfile = \"p.nc\"\n[reader]\ndialect = \"fanuc\"\n",
    ))
    .unwrap();
    let got = ends(&scenario, &dir.join("p.nc")).unwrap();
    let mut q = mtsim::AxisVec::ZERO;
    q[Axis::A] = 30.0;
    q[Axis::C] = 40.0;
    let m = common::load_trt_ac()
        .kinematics
        .table_to_machine(&q, &nalgebra::Point3::new(5.0, 10.0, 2.0));
    let last = got.last().unwrap();
    assert!(
        (last[0] - m.x).abs() < 1e-9 && (last[1] - m.y).abs() < 1e-9,
        "{last:?} vs {m:?}"
    );
    assert_eq!(last[2], 20.0);
}

/// The machine file's `[control]` reaches the reader: the bundled VMC with Fanuc parameter
/// 5115 set to 1.5 mm brings G83 back down to 1.5 mm above each peck (R2 Q3: pecks at -1
/// and -4, so rapids down to 0.5 and -2.5); a value out of range is refused at its line.
#[test]
fn the_machine_files_control_section_sets_the_g83_clearance() {
    let dir = scratch("reader", "control");
    std::fs::write(
        dir.join("p.nc"),
        "G21 G90 G17\nG0 X0 Y0 Z50.\nG98 G83 X5. Y0 Z-7. R2. Q3. F100\nG80\nM30\n",
    )
    .unwrap();
    let text = std::fs::read_to_string(common::machine("vmc-3axis")).unwrap();
    let machine = dir.join("m.toml");
    std::fs::write(
        &machine,
        format!("{text}\n[control]\ng83_clearance_mm = 1.5\n"),
    )
    .unwrap();
    let body = "[program]\nfile = \"p.nc\"\n[reader]\ndialect = \"fanuc\"\n";
    let scenario =
        Scenario::load(&write_scenario(&dir, &machine.display().to_string(), body)).unwrap();
    let z: Vec<f64> = ends(&scenario, &dir.join("p.nc"))
        .unwrap()
        .iter()
        .map(|e| (e[2] * 1e9).round() / 1e9)
        .collect();
    let after_r = z.iter().position(|&z| z == 2.0).unwrap();
    assert_eq!(
        z[after_r + 1..after_r + 7],
        [-1.0, 2.0, 0.5, -4.0, 2.0, -2.5]
    );
    std::fs::write(
        &machine,
        format!("{text}\n[control]\ng73_retract_mm = -0.5\n"),
    )
    .unwrap();
    let err = Scenario::load(&write_scenario(&dir, &machine.display().to_string(), body))
        .unwrap_err()
        .to_string();
    let line = text.lines().count() + 3;
    assert!(
        err.contains(&format!("m.toml:{line}:")) && err.contains("g73_retract_mm = -0.5"),
        "{err}"
    );
}

/// `Z50` (no decimal point): on the bundled VMC, whose file names no dialect, 50 mm; with
/// the scenario naming the fanuc dialect, 0.050 mm (parameter 3401#0 = 0, the manual's
/// default); with the machine file's `[control] whole_numbers = "units"`, 50 mm again.
#[test]
fn a_whole_number_is_a_least_increment_only_where_a_fanuc_is_named() {
    let dir = scratch("reader", "whole-numbers");
    std::fs::write(dir.join("p.nc"), "G21 G90\nG0 X10 Y20. Z50\nM30\n").unwrap();
    let vmc = common::machine("vmc-3axis");
    let z = |machine: &str, body: &str| {
        let scenario = Scenario::load(&write_scenario(&dir, machine, body)).unwrap();
        let got = ends(&scenario, &dir.join("p.nc")).unwrap();
        (got[0][0], got[0][1], got[0][2])
    };
    let generic = "[program]\nfile = \"p.nc\"\n";
    let fanuc = "[program]\nfile = \"p.nc\"\n[reader]\ndialect = \"fanuc\"\n";
    assert_eq!(z(&vmc, generic), (10.0, 20.0, 50.0));
    let (x, y, zz) = z(&vmc, fanuc);
    assert!((x - 0.010).abs() < 1e-12 && y == 20.0 && (zz - 0.050).abs() < 1e-12);
    let text = std::fs::read_to_string(&vmc).unwrap();
    let units = if text.contains("[control]") {
        text.replace("[control]", "[control]\nwhole_numbers = \"units\"")
    } else {
        format!("{text}\n[control]\nwhole_numbers = \"units\"\n")
    };
    std::fs::write(dir.join("m.toml"), units).unwrap();
    let machine = dir.join("m.toml").display().to_string();
    assert_eq!(z(&machine, fanuc), (10.0, 20.0, 50.0));
}
