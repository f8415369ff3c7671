//! Machines with the secondary linear axes U V W (LinuxCNC `trivkins`): xyuv (a hot-wire
//! foam cutter, sim/axis/foam/axis_foam.ini) and xyzabcuvw (nine world axes,
//! sim/axis/axis_9axis.ini). Their sample machine files converted from the INI files,
//! hand-computed travel and timing of U V moves, the U V W columns of `blocks`, and clear
//! refusals (exit 2) of what these layouts cannot give.

use crate::common;

use std::path::Path;

use common::{linuxcnc_machine, scratch, stdout_json};
use mtsim::input::machine::Machine;
use mtsim::kinematics::{Kinematics, Layout};
use mtsim::{Axis, AxisVec};
use nalgebra::{Point3, Vector3};

fn run(name: &str, machine: &str, program: &str, body: &str, cmd: &[&str]) -> std::process::Output {
    common::run_on_linuxcnc_machine("uvw", name, machine, program, body, cmd)
}

const NO_COLLISIONS: &str = "[check]\ncollisions = false";

/// stderr on one line, miette's gutter removed.
fn stderr(out: &std::process::Output) -> String {
    let err = String::from_utf8_lossy(&out.stderr).replace(['\n', '│'], " ");
    err.split_whitespace().collect::<Vec<_>>().join(" ")
}

#[test]
fn the_u_v_w_layouts_have_their_axes_and_the_tool_tip_is_x_y_z() {
    assert_eq!(Layout::Xyuv.axes(), &[Axis::X, Axis::Y, Axis::U, Axis::V]);
    assert_eq!(Layout::Xyzabcuvw.axes(), &Axis::ALL);
    assert_eq!(Layout::Xyzabc.axes(), &Axis::XYZABC);
    for l in [Layout::Xyuv, Layout::Xyzabcuvw] {
        assert!(l.has_secondary_axes());
        assert!(!l.has_collision_scene());
        assert!(l.tool_pose_unmodelled().is_some());
        assert_eq!((l.tilt_axis(), l.table_axis()), (None, None));
        // U V W (and A B C) do not move the tool tip: it is the world X Y Z.
        let k = Kinematics::new(l, Vector3::zeros());
        let mut q = AxisVec::ZERO;
        q[Axis::X] = 10.0;
        q[Axis::Y] = -20.0;
        q[Axis::U] = 33.0;
        q[Axis::V] = -44.0;
        assert_eq!(k.forward(&q).tip, Point3::new(10.0, -20.0, 0.0));
    }
    for l in [Layout::Xyz, Layout::TrtAc, Layout::Xz, Layout::Xyzabc] {
        assert!(!l.has_secondary_axes());
    }
}

#[test]
fn the_sample_machines_carry_their_ini_values_in_mm() {
    let load = |s: &str| Machine::load(Path::new(&linuxcnc_machine(s))).unwrap();
    // axis_foam.ini: X Y U V -10 .. 10 in, 1.2 in/s, 20 in/s^2.
    let foam = load("axis_foam");
    assert_eq!(foam.kinematics.layout, Layout::Xyuv);
    for a in [Axis::X, Axis::Y, Axis::U, Axis::V] {
        let c = foam.axis(a);
        assert!(
            (c.min + 254.0).abs() < 1e-9 && (c.max - 254.0).abs() < 1e-9,
            "{a}"
        );
        assert!((c.max_velocity - 1.2 * 25.4 * 60.0).abs() < 1e-9, "{a}");
        assert!((c.max_acceleration - 20.0 * 25.4).abs() < 1e-9, "{a}");
    }
    assert!(!foam.has_axis(Axis::Z) && !foam.has_axis(Axis::W));
    // axis_9axis.ini: Z U V W -2 .. 4 in; A B C 90 deg/s, 1200 deg/s^2, no limits.
    let nine = load("axis_9axis");
    assert_eq!(nine.kinematics.layout, Layout::Xyzabcuvw);
    for a in [Axis::Z, Axis::U, Axis::V, Axis::W] {
        assert!((nine.axis(a).min + 50.8).abs() < 1e-9, "{a}");
        assert!((nine.axis(a).max - 101.6).abs() < 1e-9, "{a}");
    }
    for a in [Axis::A, Axis::B, Axis::C] {
        assert!(nine.axis(a).continuous, "{a}");
        assert_eq!(nine.axis(a).max_velocity, 5400.0, "{a}");
        assert_eq!(nine.axis(a).max_acceleration, 1200.0, "{a}");
    }
}

#[test]
fn u_and_v_travel_and_time_as_the_program_says() {
    // foam.ngc's square, shortened: U V follow their own path beside X Y. Sampling starts
    // at the first move's end, (0, 0, 0, 0).
    let program = "\
G21 G90 G0 X0 Y0 U0 V0
G1 F600 X10 Y35 U10 V35
G1 X30 Y40 U-5 V0
M2
";
    let v = stdout_json(&run(
        "foam-travel",
        "axis_foam",
        program,
        NO_COLLISIONS,
        &["check", "--json", "--programmed"],
    ));
    assert_eq!(v["violations"].as_array().unwrap().len(), 0, "{v}");
    // `check --programmed` samples the program at its programmed timing every 1 ms: an extreme is met
    // within one sample's travel (U at most 600 mm/min = 0.01 mm per sample).
    for (axis, lo, hi) in [
        ("X", 0.0, 30.0),
        ("Y", 0.0, 40.0),
        ("U", -5.0, 10.0),
        ("V", 0.0, 35.0),
    ] {
        let a = &v["axes"][axis];
        assert!(
            (a["min"].as_f64().unwrap() - lo).abs() < 0.01,
            "{axis}: {a}"
        );
        assert!(
            (a["max"].as_f64().unwrap() - hi).abs() < 0.01,
            "{axis}: {a}"
        );
    }
    // F is the rate along all axes (the mixed-unit length, docs/gcode.md): block 2 is
    // |(10, 35, 10, 35)| = sqrt(2650) mm, block 3 |(20, 5, -15, -35)| = sqrt(1875) mm, each
    // taking its length at 600 mm/min.
    let at_f = (2650f64.sqrt() + 1875f64.sqrt()) / 600.0 * 60.0;
    let t = v["sim_time_s"].as_f64().unwrap();
    assert!((t - at_f).abs() < 1e-3, "{t} s, {at_f} s at F");
    // U's fastest is on block 3: 600 * 15 / sqrt(1875) = 207.85 mm/min.
    let u_peak = v["axes"]["U"]["peak_velocity_per_min"].as_f64().unwrap();
    let u_cruise = 600.0 * 15.0 / 1875f64.sqrt();
    assert!((u_peak - u_cruise).abs() < 1e-6, "U peak {u_peak} mm/min");
    // Beyond axis_foam.ini's U limit (10 in = 254 mm): a violation, exit 1.
    let out = run(
        "foam-beyond",
        "axis_foam",
        "G21 G90\nG1 F600 U300\nG1 U0\nM2\n",
        NO_COLLISIONS,
        &["check"],
    );
    assert_eq!(
        out.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("U"));
}

#[test]
fn a_pure_u_move_takes_its_length_at_f() {
    // One G1 of U alone after the first move: 30 mm at 600 mm/min, 3 s at the programmed
    // timing `check --programmed` samples.
    let v = stdout_json(&run(
        "foam-u",
        "axis_foam",
        "G21 G90 G0 U0\nG1 F600 U30\nM2\n",
        NO_COLLISIONS,
        &["check", "--json", "--programmed"],
    ));
    let t = v["sim_time_s"].as_f64().unwrap();
    assert!((t - 3.0).abs() < 1e-9, "{t} s");
    let u = &v["axes"]["U"];
    assert!((u["max"].as_f64().unwrap() - 30.0).abs() < 1e-9, "{u}");
    assert!(
        (u["peak_velocity_per_min"].as_f64().unwrap() - 600.0).abs() < 1e-6,
        "{u}"
    );
}

#[test]
fn blocks_prints_u_v_w_on_a_machine_that_has_them() {
    let program = "G21 G90\nG0 X1 Y2 U3 V4\nG1 F100 U5.5\nM2\n";
    let out = run(
        "foam-blocks",
        "axis_foam",
        program,
        NO_COLLISIONS,
        &["blocks", "--csv"],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert_eq!(
        String::from_utf8_lossy(&out.stdout),
        "line,kind,x_mm,y_mm,z_mm,a_deg,b_deg,c_deg,feed_mm_min,dwell_s,tool,u_mm,v_mm,w_mm\n\
         2,rapid,1,2,0,0,0,0,,,0,3,4,0\n\
         3,feed,1,2,0,0,0,0,100,,0,5.5,4,0\n"
    );
    let json = stdout_json(&run(
        "foam-json",
        "axis_foam",
        program,
        NO_COLLISIONS,
        &["blocks", "--json"],
    ));
    assert_eq!(json[1]["u"], 5.5);
    assert_eq!(json[1]["v"], 4.0);
    // A machine without U V W prints the columns it always had.
    let out = run(
        "lathe-blocks",
        "lathe",
        "G21 G90\nG0 X1 Z2\nM2\n",
        NO_COLLISIONS,
        &["blocks", "--csv"],
    );
    assert_eq!(
        String::from_utf8_lossy(&out.stdout),
        "line,kind,x_mm,y_mm,z_mm,a_deg,b_deg,c_deg,feed_mm_min,dwell_s,tool\n\
         2,rapid,1,0,2,0,0,0,,,0\n"
    );
}

#[test]
fn nine_world_axes_read_every_word() {
    let program = "G21 G90\nG1 F600 X10 Y-10 Z20 A30 B-40 C50 U60 V-20 W30\nG0 X0 Y0 Z0 A0 B0 C0 U0 V0 W0\nM2\n";
    let v = stdout_json(&run(
        "nine",
        "axis_9axis",
        program,
        NO_COLLISIONS,
        &["check", "--json"],
    ));
    assert_eq!(v["violations"].as_array().unwrap().len(), 0, "{v}");
    for (axis, lo, hi) in [
        ("U", 0.0, 60.0),
        ("V", -20.0, 0.0),
        ("W", 0.0, 30.0),
        ("C", 0.0, 50.0),
    ] {
        let a = &v["axes"][axis];
        assert!(
            (a["min"].as_f64().unwrap() - lo).abs() < 1e-9,
            "{axis}: {a}"
        );
        assert!(
            (a["max"].as_f64().unwrap() - hi).abs() < 1e-9,
            "{axis}: {a}"
        );
    }
}

#[test]
fn what_the_u_v_w_layouts_cannot_give_is_refused_with_exit_2() {
    let program = "G21 G90\nG1 F600 X10 U10\nM2\n";
    for (machine, name, body, expected) in [
        (
            "axis_foam",
            "tcp",
            "[reader]\ntcp = true\n[check]\ncollisions = false",
            "tool-centre-point control (TCP",
        ),
        ("axis_foam", "collisions", "", "collision scene"),
        (
            "axis_foam",
            "ballbar",
            "[ballbar]\npivot_mm = [0.0, 0.0, 0.0]\n[check]\ncollisions = false",
            "ball bar",
        ),
        ("axis_9axis", "collisions-9", "", "collision scene"),
    ] {
        let out = run(name, machine, program, body, &["check"]);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(expected), "{name}: {err}");
        assert!(err.contains("U V"), "{name}: {err}");
        assert!(!err.contains("panicked"), "{name}: {err}");
    }
    // A word for an axis the machine lacks: the foam cutter has no Z and no W.
    for (word, axis) in [("W1", "W"), ("Z1", "Z")] {
        let out = run(
            "foam-missing",
            "axis_foam",
            &format!("G21 G90\nG1 F600 X1 {word}\nM2\n"),
            NO_COLLISIONS,
            &["check"],
        );
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(
            err.contains(&format!(
                "`{word}`: this machine has no {axis} axis (it has X Y U V)"
            )),
            "{err}"
        );
    }
    // And a machine without U V W refuses them the same way (trt-ac).
    let dir = scratch("uvw", "trt-ac");
    std::fs::write(dir.join("p.ngc"), "G21 G90\nG1 F600 X1 V2\nM2\n").unwrap();
    std::fs::write(
        dir.join("s.toml"),
        format!(
            "machine = {:?}\n[program]\nfile = \"p.ngc\"\n[check]\ncollisions = false\n",
            common::machine("trt-ac")
        ),
    )
    .unwrap();
    let out = common::mtsim_plain(&dir, &["check", "s.toml"]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("`V2`: this machine has no V axis"), "{err}");
}

#[test]
fn rs274_standalone_refuses_u_v_w_so_it_cannot_be_the_reference() {
    // docs/gcode.md and docs/rs274.md rely on this: LinuxCNC's standalone interpreter has
    // the axis mask X Y Z A B C and prints six coordinates per call, so programs with U V
    // W words are checked against hand-worked values, not against rs274.
    let Some(rs274) = common::rs274::require("rs274_standalone_refuses_u_v_w") else {
        return;
    };
    let dir = scratch("uvw", "rs274");
    let (program, tools) = (dir.join("p.ngc"), dir.join("t.tbl"));
    std::fs::write(&program, "G21 G90\nG0 X1 U2\nM2\n").unwrap();
    std::fs::write(&tools, "").unwrap();
    let run = common::rs274::run(
        &rs274,
        &program,
        &tools,
        &dir.join("rs"),
        std::time::Duration::from_secs(30),
    );
    assert!(!run.ok && !run.timed_out, "{}", run.stderr);
    assert!(
        run.stderr.contains("Bad character 'u' used"),
        "{}",
        run.stderr
    );
    assert!(run.moves.is_empty(), "{:?}", run.moves);
}
