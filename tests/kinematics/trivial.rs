//! The trivial-kinematics layouts (LinuxCNC `trivkins`: each axis its own joint): xz (a
//! lathe), xyza (a fourth axis turning the part about X), xyzabc (a robot's six world
//! coordinates). Hand-computed poses, the sample machine files converted from their INI
//! files, `check` travel equal to the program's, and clear refusals (exit 2) of what a
//! layout cannot give.

use crate::common;

use std::path::Path;

use common::{linuxcnc_machine, stdout_json};
use mtsim::input::machine::Machine;
use mtsim::kinematics::{Branch, Kinematics, Layout, LocationErrors, LocationParam, ToolPose};
use mtsim::{Axis, AxisVec};
use nalgebra::{Point3, Vector3};

fn a(deg: f64) -> AxisVec {
    let mut q = AxisVec::ZERO;
    q[Axis::A] = deg;
    q
}

#[test]
fn a_fourth_axis_turns_a_part_point_about_x_as_rx_of_a() {
    // A point on the part at radius r = 40 on +Y, 15 along X, pivot (5, -3, 100).
    // Rx(A) (15, 40, 0) = (15, 40 cos A, 40 sin A): A = 30 gives (15, 34.641016, 20);
    // A = 90 gives (15, 0, 40); A = 180 gives (15, -40, 0); A = -90 gives (15, 0, -40).
    let pivot = Vector3::new(5.0, -3.0, 100.0);
    let k = Kinematics::new(Layout::Xyza, pivot);
    let p = Point3::new(15.0, 40.0, 0.0);
    for (deg, expected) in [
        (0.0, [15.0, 40.0, 0.0]),
        (30.0, [15.0, 34.64101615137755, 20.0]),
        (90.0, [15.0, 0.0, 40.0]),
        (180.0, [15.0, -40.0, 0.0]),
        (-90.0, [15.0, 0.0, -40.0]),
    ] {
        let m = k.table_to_machine(&a(deg), &p).coords - pivot;
        assert!(
            (m - Vector3::from(expected)).norm() < 1e-12,
            "A {deg}: {m:?}"
        );
        // The collision scene's pose of the part (the actual chain, no errors) agrees.
        let iso = k.actual_table_pose(&a(deg));
        let via_pose = (iso * p).coords - pivot;
        assert!((via_pose - m).norm() < 1e-12, "A {deg}: {via_pose:?}");
    }
}

#[test]
fn a_fourth_axis_line_offset_in_z_moves_a_turned_point_by_twice_the_offset() {
    // EZ0A = 100 um: the A line runs 0.1 mm above the pivot. The pivot point itself,
    // turned 180 deg about that line, lands 0.2 mm above the pivot; at 90 deg it lands at
    // (0, 0.1, 0.1) from the pivot (Rx(90) takes -Z to +Y about the line's point).
    let pivot = Vector3::new(0.0, 0.0, -160.0);
    let k = Kinematics::new(Layout::Xyza, pivot)
        .with_location_errors(LocationErrors::default().with(LocationParam::EZ0A, 100.0));
    let origin = Point3::origin();
    for (deg, expected) in [(180.0, [0.0, 0.0, 0.2]), (90.0, [0.0, 0.1, 0.1])] {
        let m = k.actual_table_to_machine(&a(deg), &origin).coords - pivot;
        assert!(
            (m - Vector3::from(expected)).norm() < 1e-12,
            "A {deg}: {m:?}"
        );
    }
}

#[test]
fn a_fourth_axis_tool_axis_in_the_yz_plane_gives_a_back() {
    // The tool axis (+Z in the machine) seen from the part at A is Rx(-A) z = (0, sin A,
    // cos A); the inverse takes that to A, and the tip to pivot + Rx(A) tip.
    let k = Kinematics::new(Layout::Xyza, Vector3::new(0.0, 0.0, -50.0));
    for deg in [-120.0, -30.0, 0.0, 45.0, 170.0] {
        let r = deg_to_rad(deg);
        let pose = ToolPose {
            tip: Point3::new(1.0, 2.0, 3.0),
            axis: Vector3::new(0.0, r.sin(), r.cos()),
        };
        let q = k.inverse(&pose, Branch::Primary, 0.0);
        assert!((q[Axis::A] - deg).abs() < 1e-9, "{deg}: {}", q[Axis::A]);
        let f = k.forward(&q);
        assert!((f.tip - pose.tip).norm() < 1e-9);
        assert!((f.axis - pose.axis).norm() < 1e-12);
    }
}

fn deg_to_rad(d: f64) -> f64 {
    d.to_radians()
}

#[test]
fn trivial_layouts_have_their_axes_and_no_tilt() {
    assert_eq!(Layout::Xz.axes(), &[Axis::X, Axis::Z]);
    assert_eq!(Layout::Xyza.axes(), &[Axis::X, Axis::Y, Axis::Z, Axis::A]);
    assert_eq!(Layout::Xyzabc.axes().len(), 6);
    for l in [Layout::Xz, Layout::Xyza, Layout::Xyzabc] {
        assert_eq!(l.tilt_axis(), None);
    }
    assert_eq!(Layout::Xyza.table_axis(), Some(Axis::A));
    // xyzabc's tool tip is the world X Y Z whatever A B C are.
    let k = Kinematics::new(Layout::Xyzabc, Vector3::zeros());
    let q = AxisVec::xyzabc([10.0, -20.0, 30.0, 45.0, -60.0, 170.0]);
    assert_eq!(k.forward(&q).tip, Point3::new(10.0, -20.0, 30.0));
}

#[test]
fn the_sample_machines_carry_their_ini_values_in_mm() {
    let load = |s: &str| Machine::load(Path::new(&linuxcnc_machine(s))).unwrap();
    // sim/axis/lathe.ini: X -10 .. 10 in, Z -2 .. 4 in, 3.333333 in/s, 20 in/s^2.
    let lathe = load("lathe");
    assert_eq!(lathe.kinematics.layout, Layout::Xz);
    assert_eq!(lathe.axes(), &[Axis::X, Axis::Z]);
    assert!((lathe.axis(Axis::X).min + 254.0).abs() < 1e-9);
    assert!((lathe.axis(Axis::Z).max - 101.6).abs() < 1e-9);
    assert!((lathe.axis(Axis::Z).max_velocity - 3.333333 * 25.4 * 60.0).abs() < 1e-6);
    assert!((lathe.axis(Axis::X).max_acceleration - 508.0).abs() < 1e-9);
    // plasma-5i20.ini: X -50 .. 51 in, Y 6.75 in/s, Z 50 in/s^2.
    let plasma = load("plasma-5i20");
    assert_eq!(plasma.kinematics.layout, Layout::Xyz);
    assert!((plasma.axis(Axis::X).max - 51.0 * 25.4).abs() < 1e-9);
    assert!((plasma.axis(Axis::Y).max_velocity - 6.75 * 25.4 * 60.0).abs() < 1e-6);
    assert!((plasma.axis(Axis::Z).max_acceleration - 50.0 * 25.4).abs() < 1e-9);
    // millturn.ini (mill mode): Z -240 .. 0 mm, 60 mm/s; A without limits.
    let millturn = load("millturn");
    assert_eq!(millturn.kinematics.layout, Layout::Xyza);
    assert_eq!(millturn.axis(Axis::Z).min, -240.0);
    assert_eq!(millturn.axis(Axis::Z).max, 0.0);
    assert_eq!(millturn.axis(Axis::X).max_velocity, 3600.0);
    assert!(millturn.axis(Axis::A).continuous);
    // puma.ini: X 0 .. 650, B -135 .. 135; melfa.ini: 60 deg/s.
    let puma = load("puma");
    assert_eq!(puma.kinematics.layout, Layout::Xyzabc);
    assert_eq!(puma.axis(Axis::X).min, 0.0);
    assert_eq!(puma.axis(Axis::B).max, 135.0);
    assert_eq!(load("melfa").axis(Axis::C).max_velocity, 3600.0);
    assert_eq!(load("puma_cube").axis(Axis::A).max_velocity, 1800.0);
}

fn run(name: &str, machine: &str, program: &str, body: &str, cmd: &[&str]) -> std::process::Output {
    common::run_on_linuxcnc_machine("trivial", name, machine, program, body, cmd)
}

const NO_COLLISIONS: &str = "[check]\ncollisions = false";

#[test]
fn a_robots_world_axes_travel_as_far_as_the_program_says() {
    // Six independent world axes: each axis's extremes are the program's words.
    let program = "G21 G90\nG1 F600 X100 Y-50 Z20 A10 B-20 C30\nG1 X300 Y60 Z-80 A-40 B90 C-120\nG0 X200 Y0 Z0 A0 B0 C0\nM2\n";
    let v = stdout_json(&run(
        "puma",
        "puma",
        program,
        NO_COLLISIONS,
        &["check", "--json"],
    ));
    assert_eq!(v["violations"].as_array().unwrap().len(), 0, "{v}");
    // Sampling starts at the first move's end (the position before the program is unknown).
    for (axis, lo, hi) in [
        ("X", 100.0, 300.0),
        ("Y", -50.0, 60.0),
        ("Z", -80.0, 20.0),
        ("A", -40.0, 10.0),
        ("B", -20.0, 90.0),
        ("C", -120.0, 30.0),
    ] {
        let a = &v["axes"][axis];
        // Within a sample (1 ms at 1500 mm/min or less: 0.025) of the programmed ends.
        assert!(
            (a["min"].as_f64().unwrap() - lo).abs() < 0.025,
            "{axis}: {a}"
        );
        assert!(
            (a["max"].as_f64().unwrap() - hi).abs() < 0.025,
            "{axis}: {a}"
        );
    }
    // Beyond puma.ini's B limit (135 deg): a violation, exit 1.
    let out = run(
        "puma-b",
        "puma",
        "G1 F600 B150\nM2\n",
        NO_COLLISIONS,
        &["check"],
    );
    assert_eq!(
        out.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    // analyze, blocks and simulate read it too.
    for cmd in [&["analyze"][..], &["blocks", "--csv"], &["simulate"]] {
        let out = run("puma-cmd", "puma", program, NO_COLLISIONS, cmd);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{cmd:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

#[test]
fn what_a_robots_world_axes_cannot_give_is_refused_with_exit_2() {
    let program = "G21 G90\nG1 F600 X100 A10\nM428\nG1 X200\nM2\n";
    let tcp = "[reader]\nuser_m_codes = { M428 = \"tcp-on\" }\n[check]\ncollisions = false";
    for (name, body, expected) in [
        ("tcp", tcp, "tool-centre-point control (TCP)"),
        (
            "reader-tcp",
            "[reader]\ntcp = true\n[check]\ncollisions = false",
            "tool-centre-point control (TCP",
        ),
        ("collisions", "", "collision scene"),
        (
            "ballbar",
            "[ballbar]\npivot_mm = [0.0, 0.0, 0.0]\n[check]\ncollisions = false",
            "ball bar",
        ),
    ] {
        let out = run(name, "puma", program, body, &["check"]);
        let err = String::from_utf8_lossy(&out.stderr).replace(['\n', '│'], " ");
        let err = err.split_whitespace().collect::<Vec<_>>().join(" ");
        assert_eq!(out.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(expected), "{name}: {err}");
        assert!(err.contains("xyzabc"), "{name}: {err}");
        assert!(!err.contains("panicked"), "{name}: {err}");
    }
}

#[test]
fn a_lathe_reads_x_and_z_refuses_y_and_checks_its_travel() {
    // lathe.ini's Z travel is -50.8 .. 101.6 mm: Z-60 is beyond it.
    let ok = run(
        "lathe",
        "lathe",
        "G21 G18 G90\nG1 F300 X20 Z-30\nG1 X0 Z0\nM2\n",
        NO_COLLISIONS,
        &["check", "--json"],
    );
    let v = stdout_json(&ok);
    assert_eq!(v["violations"].as_array().unwrap().len(), 0, "{v}");
    assert!(
        (v["axes"]["Z"]["min"].as_f64().unwrap() + 30.0).abs() < 1e-9,
        "{v}"
    );
    let beyond = run(
        "lathe-z",
        "lathe",
        "G21 G90\nG1 F300 Z-60\nM2\n",
        NO_COLLISIONS,
        &["check"],
    );
    assert_eq!(beyond.status.code(), Some(1));
    let y = run(
        "lathe-y",
        "lathe",
        "G21 G90\nG1 F300 Y5\nM2\n",
        NO_COLLISIONS,
        &["check"],
    );
    assert_eq!(y.status.code(), Some(2));
    // The collision scene models a milling tool: refused on a lathe.
    let scene = run(
        "lathe-scene",
        "lathe",
        "G21 G90\nG1 F300 X5\nM2\n",
        "",
        &["check"],
    );
    assert_eq!(scene.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&scene.stderr).contains("collisions = false"));
}

#[test]
fn a_fourth_axis_part_point_under_tcp_follows_rx_of_a() {
    // Millturn in mill mode, pivot (-290, 0, -160): under TCP the tip stays on part point
    // (0, 0, 60) while A turns 0 -> 60, so X = -290, Y = -60 sin A (min -51.9615 at
    // A = 60) and Z = -160 + 60 cos A (from -100 to -130).
    let out = run(
        "millturn-tcp",
        "millturn",
        "G21 G90\nG1 F1000 X0 Y0 Z60\nG1 A60\nM2\n",
        "[reader]\ntcp = true\n[check]\ncollisions = false",
        &["check", "--json"],
    );
    let v = stdout_json(&out);
    let (y, z) = (&v["axes"]["Y"], &v["axes"]["Z"]);
    let y_min = -60.0 * 60f64.to_radians().sin();
    assert!((y["min"].as_f64().unwrap() - y_min).abs() < 1e-6, "{y}");
    assert!((z["max"].as_f64().unwrap() + 100.0).abs() < 1e-6, "{z}");
    assert!((z["min"].as_f64().unwrap() + 130.0).abs() < 1e-6, "{z}");
    assert!(
        (v["axes"]["X"]["max"].as_f64().unwrap() + 290.0).abs() < 1e-9,
        "{v}"
    );
}

#[test]
fn a_fourth_axis_chuck_turns_with_a_in_the_collision_scene() {
    // The stand-in chuck: radius 50 about the A line (Y = 0, Z = -160), face at X = -290
    // toward +X, 60 thick. A tool tip 20 mm in front of the face clears it while A turns;
    // a tip on the A line 10 mm behind the face is inside the chuck.
    let clear = run(
        "millturn-clear",
        "millturn",
        "G21 G90\nG0 X-270 Y0 Z-160\nG1 F1000 A90\nM2\n",
        "",
        &["check"],
    );
    assert_eq!(
        clear.status.code(),
        Some(0),
        "{}{}",
        String::from_utf8_lossy(&clear.stdout),
        String::from_utf8_lossy(&clear.stderr)
    );
    let inside = run(
        "millturn-inside",
        "millturn",
        "G21 G90\nG0 X-300 Y0 Z-160\nG1 F1000 A90\nM2\n",
        "",
        &["check"],
    );
    let text = String::from_utf8_lossy(&inside.stdout);
    assert_eq!(inside.status.code(), Some(1), "{text}");
    assert!(text.contains("collision"), "{text}");
}
