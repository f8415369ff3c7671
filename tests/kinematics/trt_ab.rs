//! The table-dual-rotary layout trt-ab (LinuxCNC's xyzab-tdr): hand-computed poses, the
//! matrix of LinuxCNC's `xyzab_tdr_kins` written out from its source, round trips of the
//! inverse kinematics, the sample machine files, and a location error in closed form.

use crate::common;

use std::path::Path;

use common::{scratch, stdout_json};
use mtsim::input::machine::Machine;
use mtsim::kinematics::{Branch, Kinematics, Layout, LocationErrors, LocationParam, ToolPose};
use mtsim::{Axis, AxisVec};
use nalgebra::{Point3, Vector3};
use proptest::prelude::*;

/// The sample's rotation point (xyzab-tdr.xml initial values), mm.
const ROT_POINT: [f64; 3] = [-50.0, -50.0, -100.0];

fn tdr() -> Kinematics {
    Kinematics::new(Layout::TrtAb, Vector3::from(ROT_POINT))
}

fn q(a: f64, b: f64) -> AxisVec {
    let mut q = AxisVec::ZERO;
    q[Axis::A] = a;
    q[Axis::B] = b;
    q
}

fn close(a: &Vector3<f64>, b: &Vector3<f64>, tol: f64) -> bool {
    (a - b).norm() < tol
}

#[test]
fn a_table_point_turned_by_a_then_b_lands_where_worked_out_by_hand() {
    // p = (10, 20, 30) on the table, pivot (-50, -50, -100).
    // A = 90: Rx(-90) takes +Y to -Z and +Z to +Y: (10, 30, -20).
    // B = 90: Ry(-90) takes +X to +Z and +Z to -X: (-30, 20, 10).
    // A = 90 then B = 90: Ry(-90) (10, 30, -20) = (20, 30, 10).
    let k = tdr();
    let p = Point3::new(10.0, 20.0, 30.0);
    let pivot = Vector3::from(ROT_POINT);
    for (a, b, expected) in [
        (0.0, 0.0, [10.0, 20.0, 30.0]),
        (90.0, 0.0, [10.0, 30.0, -20.0]),
        (0.0, 90.0, [-30.0, 20.0, 10.0]),
        (90.0, 90.0, [20.0, 30.0, 10.0]),
        (180.0, 0.0, [10.0, -20.0, -30.0]),
    ] {
        let m = k.table_to_machine(&q(a, b), &p).coords;
        assert!(
            close(&m, &(pivot + Vector3::from(expected)), 1e-12),
            "A {a} B {b}: {m:?}"
        );
    }
}

/// LinuxCNC's `xyzab_tdr_kins` inverse (work pose to joints) as its source writes it, with
/// its A-axis offsets `dx` (along A) and `dz` (from the B axis) and no tool offset.
fn linuxcnc_tdr_inverse(p: [f64; 3], a: f64, b: f64, rot: [f64; 3], dx: f64, dz: f64) -> [f64; 3] {
    let (sa, ca) = a.to_radians().sin_cos();
    let (sb, cb) = b.to_radians().sin_cos();
    let qx = p[0] - rot[0] - dx;
    let qy = p[1] - rot[1];
    let qz = p[2] - rot[2] - dz;
    [
        cb * qx + sa * sb * qy - ca * sb * qz + cb * dx - sb * dz + rot[0],
        ca * qy + sa * qz + rot[1],
        sb * qx - sa * cb * qy + ca * cb * qz + sb * dx + cb * dz + rot[2],
    ]
}

proptest! {
    /// mtsim's trt-ab is LinuxCNC's xyzab-tdr with the axes crossing (z-offset 0); the
    /// x-offset, along A, changes nothing.
    #[test]
    fn trt_ab_is_linuxcncs_xyzab_tdr_with_crossing_axes(
        x in -200.0..200.0f64, y in -200.0..200.0f64, z in -300.0..300.0f64,
        a in -400.0..400.0f64, b in -180.0..180.0f64, dx in -50.0..50.0f64,
    ) {
        let k = tdr();
        // The work point p is a table point at home: p = pivot + p_table.
        let p = [x, y, z];
        let table = Point3::new(x - ROT_POINT[0], y - ROT_POINT[1], z - ROT_POINT[2]);
        let m = k.table_to_machine(&q(a, b), &table);
        let j = linuxcnc_tdr_inverse(p, a, b, ROT_POINT, dx, 0.0);
        prop_assert!(close(&m.coords, &Vector3::from(j), 1e-9), "{m:?} vs {j:?}");
    }

    /// FK(IK(p, t)) = (p, t) on both branches, with A unwrapped near the reference.
    #[test]
    fn forward_of_inverse_is_identity_on_trt_ab(
        px in -150.0..150.0f64, py in -150.0..150.0f64, pz in -100.0..200.0f64,
        polar in 0.5..179.5f64, azimuth in -180.0..180.0f64, previous_a in -720.0..720.0f64,
        secondary in any::<bool>(),
    ) {
        let k = tdr();
        let (p, az) = (polar.to_radians(), azimuth.to_radians());
        let axis = Vector3::new(p.sin() * az.cos(), p.sin() * az.sin(), p.cos());
        let pose = ToolPose { tip: Point3::new(px, py, pz), axis };
        let branch = if secondary { Branch::Secondary } else { Branch::Primary };
        let q = k.inverse(&pose, branch, previous_a);
        let back = k.forward(&q);
        prop_assert!((back.tip - pose.tip).norm() < 1e-9);
        prop_assert!((back.axis - pose.axis).norm() < 1e-9, "{:?} vs {:?}", back.axis, pose.axis);
        prop_assert!((q[Axis::A] - previous_a).abs() <= 180.0 + 1e-9);
        let b = q[Axis::B];
        let branch_ok = if secondary { b.abs() >= 90.0 - 1e-9 } else { b.abs() <= 90.0 + 1e-9 };
        prop_assert!(branch_ok, "B {} on {:?}", b, branch);
        prop_assert_eq!(q[Axis::C], 0.0);
    }

    /// IK(FK(q)) = q for |B| < 90 (primary branch).
    #[test]
    fn inverse_of_forward_is_identity_on_trt_ab(
        x in -200.0..200.0f64, y in -200.0..200.0f64, z in -300.0..300.0f64,
        a in -400.0..400.0f64, b in -89.0..89.0f64,
    ) {
        let k = tdr();
        let mut q0 = q(a, b);
        q0[Axis::X] = x; q0[Axis::Y] = y; q0[Axis::Z] = z;
        let back = k.inverse(&k.forward(&q0), Branch::Primary, a + 3.0);
        for axis in Layout::TrtAb.axes() {
            prop_assert!((back[*axis] - q0[*axis]).abs() < 1e-9, "{} {} vs {}", axis, back[*axis], q0[*axis]);
        }
    }
}

#[test]
fn the_tool_axis_at_a_90_and_b_90_is_worked_out_by_hand() {
    let k = tdr();
    // B = 90: the tool (+Z in the machine) is the table's +X, since Ry(-90) takes +X to +Z.
    let t = k.forward(&q(0.0, 90.0)).axis;
    assert!(close(&t, &Vector3::x(), 1e-12), "{t:?}");
    // A = 90: Rx(-90) takes -Y to +Z, so the tool is the table's -Y.
    let t = k.forward(&q(90.0, 0.0)).axis;
    assert!(close(&t, &-Vector3::y(), 1e-12), "{t:?}");
    // And back: B = asin(i), A = atan2(-j, k).
    let pose = |axis| ToolPose {
        tip: Point3::origin(),
        axis,
    };
    let back = k.inverse(&pose(-Vector3::y()), Branch::Primary, 0.0);
    assert!((back[Axis::A] - 90.0).abs() < 1e-12 && back[Axis::B].abs() < 1e-12);
    // Along the table's X, A is free and kept at the reference.
    let back = k.inverse(&pose(Vector3::x()), Branch::Primary, 37.0);
    assert!((back[Axis::B] - 90.0).abs() < 1e-12 && back[Axis::A] == 37.0);
}

#[test]
fn an_a_axis_line_raised_by_ez0a_carries_the_pivot_point_as_worked_out() {
    // The A line through pivot + (0, 0, d): the point at the pivot, d below the line, turns
    // with the table by -A about +X. At A = 90 the offset (0, 0, -d) becomes (0, -d, 0), so
    // the point lands at pivot + (0, -d, d). At A = 0 it does not move.
    let d_um = 25.0;
    let d = d_um * 1e-3;
    let k = tdr().with_location_errors(LocationErrors::default().with(LocationParam::EZ0A, d_um));
    let pivot = Vector3::from(ROT_POINT);
    let at = |a, b| {
        k.actual_table_to_machine(&q(a, b), &Point3::origin())
            .coords
    };
    assert!(close(&at(0.0, 0.0), &pivot, 1e-12));
    assert!(close(
        &at(90.0, 0.0),
        &(pivot + Vector3::new(0.0, -d, d)),
        1e-12
    ));
    // Then B = 90 turns (0, -d, d) by Ry(-90) about the B line through the pivot: (-d, -d, 0).
    assert!(close(
        &at(90.0, 90.0),
        &(pivot + Vector3::new(-d, -d, 0.0)),
        1e-12
    ));
    // The pose and the point agree.
    let pose = k.actual_table_pose(&q(90.0, 90.0));
    let via_pose = (pose * Point3::origin()).coords;
    assert!(close(&via_pose, &at(90.0, 90.0), 1e-12));
}

fn linuxcnc_machine(stem: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("machines/linuxcnc")
        .join(format!("{stem}.toml"))
        .display()
        .to_string()
}

#[test]
fn the_linuxcnc_sample_machine_files_load_with_the_sample_limits() {
    for (stem, layout, axes) in [
        (
            "xyzab-tdr",
            Some(Layout::TrtAb),
            [(Axis::Y, 200.0), (Axis::Z, 300.0), (Axis::B, 180.0)],
        ),
        (
            "xyzac-trt",
            // Chains: their tilting axes are offset from C (tests/kinematics/linuxcnc_samples.rs).
            None,
            [(Axis::Y, 100.0), (Axis::Z, 120.0), (Axis::A, 50.0)],
        ),
        (
            "xyzbc-trt",
            None,
            [(Axis::Y, 100.0), (Axis::Z, 120.0), (Axis::B, 36000.0)],
        ),
    ] {
        let m = Machine::load(Path::new(&linuxcnc_machine(stem))).unwrap();
        match layout {
            Some(layout) => assert_eq!(m.kinematics.layout, layout, "{stem}"),
            None => assert!(matches!(m.kinematics.layout, Layout::Chain(_)), "{stem}"),
        }
        for (axis, max) in axes {
            assert_eq!(m.axis(axis).max, max, "{stem} {axis}");
        }
    }
    let tdr = Machine::load(Path::new(&linuxcnc_machine("xyzab-tdr"))).unwrap();
    assert_eq!(tdr.kinematics.pivot_mm, Vector3::from(ROT_POINT));
    // 20 mm/s and 30 deg/s in the ini are 1200 mm/min and 1800 deg/min.
    assert_eq!(tdr.axis(Axis::X).max_velocity, 1200.0);
    assert_eq!(tdr.axis(Axis::A).max_velocity, 1800.0);
}

fn check_on_tdr(name: &str, program: &str, reader: &str) -> std::process::Output {
    let dir = scratch("trt-ab", name);
    std::fs::write(dir.join("p.ngc"), program).unwrap();
    std::fs::write(
        dir.join("s.toml"),
        format!(
            "machine = {:?}\n[program]\nfile = \"p.ngc\"\n[reader]\n{reader}\n",
            linuxcnc_machine("xyzab-tdr")
        ),
    )
    .unwrap();
    common::mtsim_plain(&dir, &["check", "s.toml", "--json"])
}

#[test]
fn a_tool_centre_point_program_on_the_sample_keeps_the_tip_on_the_table_point() {
    // Under TCP X Y Z are the tip in the table frame (origin at the pivot): the tip stays
    // at table (0, 0, 50) while A and B turn, so the axes are `pivot + R (0, 0, 50)`:
    // X = -50 - 50 cos A sin B, Y = -50 + 50 sin A, Z = -100 + 50 cos A cos B. A runs
    // 0 -> 45 -> 90 with |B| <= 60, so Y peaks at 0 and Z bottoms at -100, both at A = 90;
    // X is -67.678 at A = 45, B = 30.
    let out = check_on_tdr(
        "tcp",
        "G21 G90 G17\nG1 F1000 X0 Y0 Z50\nG1 A45 B30\nG1 A90 B-60\nM2\n",
        "tcp = true\n[check]\ncollisions = false",
    );
    let v = stdout_json(&out);
    assert_eq!(v["violations"].as_array().unwrap().len(), 0, "{v}");
    let (y, z) = (&v["axes"]["Y"], &v["axes"]["Z"]);
    assert!((y["max"].as_f64().unwrap() - 0.0).abs() < 1e-6, "{y}");
    assert!((z["min"].as_f64().unwrap() + 100.0).abs() < 1e-6, "{z}");
    assert!((z["max"].as_f64().unwrap() + 50.0).abs() < 1e-6, "{z}");
    let x_corner = -50.0 - 50.0 * 45f64.to_radians().cos() * 30f64.to_radians().sin();
    let x_min = v["axes"]["X"]["min"].as_f64().unwrap();
    // Sampled every 1 ms at 1000 mm/min of tip feed: within 1e-3 mm of the corner.
    assert!((x_min - x_corner).abs() < 1e-3, "{x_min} vs {x_corner}");
}

#[test]
fn a_b_beyond_the_samples_travel_is_a_travel_violation_and_a_c_word_is_refused() {
    let out = check_on_tdr("b-travel", "G21 G90\nG0 X0 Y0 Z0\nG0 B190\nM2\n", "");
    assert_eq!(out.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(
        v["violations"]
            .as_array()
            .unwrap()
            .iter()
            .any(|x| x["kind"] == "travel" && x["axis"] == "B"),
        "{v}"
    );
    // The machine has no C axis: the word is an error, with the axes it has.
    let out = check_on_tdr("c-word", "G21 G90\nG0 X0 Y0 Z0\nG0 C10\nM2\n", "");
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("has no C axis"), "{err}");
}

#[test]
fn the_cone_test_on_the_dual_rotary_table_tilts_b_by_alpha_plus_and_minus_beta() {
    // 15/10 cone: at θ = 0 the tool leans α + β = 25 deg toward table -X, at θ = 180 deg
    // α - β = 5 deg toward +X. On trt-ab the tool axis t gives B = asin(t_x): -25 and +5.
    // At θ = 90 deg, t = Ry(-β) (0, -sin α, cos α), so A = atan2(sin α, cos β cos α).
    let dir = scratch("trt-ab", "cone");
    std::fs::write(
        dir.join("s.toml"),
        format!(
            "machine = {:?}\n[program.cone]\nhalf_apex_deg = 15.0\ninclination_deg = 10.0\ncenter_mm = [0.0, 0.0, 100.0]\nballbar_length_mm = 100.0\nfeed_mm_min = 500.0\n[check]\ncollisions = false\n",
            linuxcnc_machine("xyzab-tdr")
        ),
    )
    .unwrap();
    let out = common::mtsim_plain(&dir, &["check", "s.toml", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let b = &v["axes"]["B"];
    assert!((b["min"].as_f64().unwrap() + 25.0).abs() < 1e-6, "{b}");
    assert!((b["max"].as_f64().unwrap() - 5.0).abs() < 1e-3, "{b}");
    let (al, be) = (15f64.to_radians(), 10f64.to_radians());
    let a90 = al.sin().atan2(be.cos() * al.cos()).to_degrees();
    let a_max = v["axes"]["A"]["max"].as_f64().unwrap();
    // |A| peaks near θ = 90 deg, a little above its value there.
    assert!(a_max >= a90 - 1e-3 && a_max < a90 + 0.1, "{a_max} vs {a90}");
}

#[test]
fn the_bounded_collision_check_finds_what_the_exhaustive_one_finds_as_the_table_tumbles_about_a() {
    // The tip 130 mm above the pivot while a table about Z (radius 100 mm, 60 mm thick, in
    // place of the sample's faceplate) tumbles about A: its rim comes within 40 mm of the tip twice a turn and recedes. The
    // monitor's motion bound for table parts must count |dA| (the table axis of trt-ab, in
    // place of C): the bounded check then reports exactly the exhaustive check's events.
    use mtsim::check::{check_reference, check_with, CheckOptions, SceneQueries};
    use mtsim::input::scenario::Scenario;
    let dir = scratch("trt-ab", "tumble");
    std::fs::write(
        dir.join("p.ngc"),
        "G21 G90\nG0 X-50 Y-50 Z30\nG1 F1500 A180\nG1 A360 B20\nG1 A200 B-20\nM2\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("s.toml"),
        format!(
            "machine = {:?}\n[program]\nfile = \"p.ngc\"\n[check]\nnear_miss_mm = 40.0\n\
             [machine_overrides.scene]\ncradle = []\n\
             [machine_overrides.scene.table]\naxis = \"z\"\nradius_mm = 100.0\nthickness_mm = 60.0\n",
            linuxcnc_machine("xyzab-tdr")
        ),
    )
    .unwrap();
    let s = Scenario::load(&dir.join("s.toml")).unwrap();
    let options = CheckOptions::default();
    let slow = check_reference(&s, &options).unwrap();
    let near: Vec<_> = slow
        .violations
        .iter()
        .filter(|v| v.bodies.is_some())
        .collect();
    assert!(
        !near.is_empty() && near.iter().all(|v| v.time_start_s > 0.0),
        "the rim must come near mid-run: {:#?}",
        slow.violations
    );
    for mode in [SceneQueries::Bounded, SceneQueries::BoundedRelative] {
        let fast = check_with(&s, &options, mode).unwrap();
        assert!(fast.scene_queries < slow.scene_queries, "{mode:?}");
        assert_eq!(fast.violations.len(), slow.violations.len(), "{mode:?}");
        for (a, b) in fast.violations.iter().zip(&slow.violations) {
            assert_eq!((a.kind, &a.bodies, a.line), (b.kind, &b.bodies, b.line));
            assert_eq!(
                (a.time_start_s, a.time_end_s),
                (b.time_start_s, b.time_end_s)
            );
            assert!((a.worst - b.worst).abs() <= 1e-9, "{a:?} {b:?}");
        }
        let (f, r) = (
            fast.min_clearance_mm.unwrap(),
            slow.min_clearance_mm.unwrap(),
        );
        assert!((f - r).abs() <= 1e-9, "{mode:?}: {f} vs {r}");
    }
    // The nearest approach is the table's bottom rim, the farthest part from the A axis
    // (hypot(100, 60) mm), passing under the tip 130 mm above that axis: 13.381 mm (to the
    // sampling: the A step per 1 ms sample moves the rim by 0.003 mm).
    let r = slow.min_clearance_mm.unwrap();
    let expected = 130.0 - 100f64.hypot(60.0);
    assert!(
        r >= expected - 1e-9 && r < expected + 0.01,
        "{r} vs {expected}"
    );
}

#[test]
fn the_samples_faceplate_stands_below_the_tool_until_b_turns_it_face_up() {
    // The faceplate (radius 50 mm, 18 mm thick, face through the pivot toward +X) and the
    // rotary A base (top at z = 50 mm, out to x = -10 mm) at B = 0; the 20 mm cutter's flat
    // end 80 mm above the pivot, on the pivot's X: both are 80 - 50 = 30 mm below it. B = 90
    // turns the face up to the pivot's height (80 mm below the tip) and the base away.
    let dir = scratch("trt-ab", "faceplate");
    std::fs::write(
        dir.join("p.ngc"),
        "G21 G90\nG0 X-50 Y-50 Z-20\nG4 P0.2\nG1 F1200 B90\nG1 A180\nM2\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("s.toml"),
        format!(
            "machine = {:?}\n[program]\nfile = \"p.ngc\"\n",
            linuxcnc_machine("xyzab-tdr")
        ),
    )
    .unwrap();
    let out = common::mtsim_plain(&dir, &["check", "s.toml", "--json"]);
    let v = stdout_json(&out);
    assert_eq!(v["violations"].as_array().unwrap().len(), 0, "{v}");
    let r = v["min_clearance_mm"].as_f64().unwrap();
    assert!((r - 30.0).abs() < 1e-6, "{r} {}", v["min_clearance_bodies"]);
}

#[test]
fn a_trt_ab_machine_takes_location_errors_of_a_and_b_and_refuses_c() {
    let dir = scratch("trt-ab", "location");
    std::fs::write(dir.join("p.ngc"), "G21 G90\nG0 X0 Y0 Z50\nG0 A90\nM2\n").unwrap();
    let scenario = |keys: &str| {
        std::fs::write(
            dir.join("s.toml"),
            format!(
                "machine = {:?}\n[program]\nfile = \"p.ngc\"\n[machine_overrides.location_errors]\n{keys}\n",
                linuxcnc_machine("xyzab-tdr")
            ),
        )
        .unwrap();
        mtsim::input::scenario::Scenario::load(&dir.join("s.toml"))
    };
    let s = scenario("EZ0A_um = 25.0\nEX0B_um = -10.0").unwrap();
    let e = s.machine.kinematics.location_errors;
    assert_eq!(e.get(LocationParam::EZ0A), 25.0);
    assert_eq!(e.get(LocationParam::EX0B), -10.0);
    let message = scenario("EX0C_um = 5.0").unwrap_err().to_string();
    assert!(message.contains("no C axis"), "{message}");
}

/// The bar's sensitivity to each axis on trt-ab, against a central difference of the bar
/// length written out here: `L(q) = |(X, Y, Z) - (pivot + R(q) p)|`, with `R` the product of
/// LinuxCNC's `xyzab_tdr_kins` rotations (`table_rotation`). The table axis is A on this
/// layout: its sine and cosine go where C's go on trt-ac.
#[test]
fn the_bar_sensitivity_to_a_and_b_is_the_derivative_of_the_bar_length() {
    use mtsim::measure::attribution::bar_sensitivity;
    let kin = tdr();
    let pivot_table = Point3::new(20.0, -30.0, 40.0);
    let mut at = q(25.0, -35.0);
    at[Axis::X] = 60.0;
    at[Axis::Y] = 10.0;
    at[Axis::Z] = 80.0;
    let length = |q: &AxisVec| {
        let pivot = Vector3::from(ROT_POINT) + kin.table_rotation(q) * pivot_table.coords;
        (Vector3::new(q[Axis::X], q[Axis::Y], q[Axis::Z]) - pivot).norm()
    };
    let bar = length(&at);
    let s = bar_sensitivity(
        &kin,
        &[Axis::X, Axis::Y, Axis::Z, Axis::A, Axis::B],
        &at,
        &pivot_table,
        bar,
    );
    for axis in [Axis::X, Axis::Y, Axis::Z, Axis::A, Axis::B] {
        let h = 1e-3;
        let (mut up, mut down) = (at, at);
        up[axis] += h;
        down[axis] -= h;
        let expected = (length(&up) - length(&down)) / (2.0 * h);
        assert!(
            (s[axis] - expected).abs() < 1e-6,
            "{axis}: {} against {expected}",
            s[axis]
        );
        assert!(
            expected.abs() > 1e-3,
            "{axis} must move the bar for the test to bite"
        );
    }
}
