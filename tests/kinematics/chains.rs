//! Kinematic chains (the kinematic-chains spec): the forward kinematics against closed
//! forms worked out by hand, round trips of the inverse kinematics on every shipped chain,
//! poles and solution switches, the named layouts written out, and machine-file errors.

use crate::common;

use std::path::Path;

use common::scratch;
use mtsim::input::machine::Machine;
use mtsim::kinematics::chain_events::PoleWatch;
use mtsim::kinematics::chain_inverse::{self, PathEvent};
use mtsim::kinematics::{Chain, Kinematics, Layout, ToolPose};
use mtsim::{Axis, AxisVec};
use nalgebra::{Point3, Vector3};
use proptest::prelude::*;

/// Every machine file shipped with a general chain, relative to the crate root.
pub(crate) const SHIPPED: [&str; 5] = [
    "machines/head-table-b45-c.toml",
    "machines/fork-head-ca.toml",
    "machines/nutating-table-b45-c.toml",
    "machines/linuxcnc/bridgemill.toml",
    "machines/linuxcnc/max5.toml",
];

fn load(rel: &str) -> Machine {
    Machine::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)).unwrap()
}

fn chain_of(m: &Machine) -> Chain {
    m.kinematics.chain().expect("a chain")
}

fn joints(values: &[(Axis, f64)]) -> AxisVec {
    let mut q = AxisVec::ZERO;
    for (a, v) in values {
        q[*a] = *v;
    }
    q
}

fn sin_cos(deg: f64) -> (f64, f64) {
    deg.to_radians().sin_cos()
}

#[test]
fn every_shipped_chain_loads_as_a_general_chain_with_its_axes() {
    for rel in SHIPPED {
        let m = load(rel);
        assert!(matches!(m.kinematics.layout, Layout::Chain(_)), "{rel}");
        let chain = chain_of(&m);
        assert_eq!(chain.axes(), m.axes().to_vec(), "{rel}");
        assert!(
            m.kinematics.describe().starts_with("chain: table "),
            "{rel}"
        );
    }
}

#[test]
fn a_fork_head_points_the_tool_along_rz_c_rx_a_z() {
    // Rx(A) z = (0, −sin A, cos A); Rz(C) of that = (sin A sin C, −sin A cos C, cos A).
    // The tip hangs (200 + l) below the pivot, which sits 200 above the gauge point (X, Y, Z).
    let chain = chain_of(&load("machines/fork-head-ca.toml"));
    for (a, c) in [(30.0, 0.0), (-45.0, 60.0), (90.0, -120.0), (17.0, 233.0)] {
        let q = joints(&[
            (Axis::X, 10.0),
            (Axis::Y, -20.0),
            (Axis::Z, 30.0),
            (Axis::A, a),
            (Axis::C, c),
        ]);
        let (tip, t) = chain.tool_in_machine(&q, 50.0);
        let ((sa, ca), (sc, cc)) = (sin_cos(a), sin_cos(c));
        let expected_t = Vector3::new(sa * sc, -sa * cc, ca);
        assert!((t - expected_t).norm() < 1e-14, "A {a} C {c}: {t:?}");
        let expected_tip = Vector3::new(10.0, -20.0, 230.0) - 250.0 * expected_t;
        assert!(
            (tip.coords - expected_tip).norm() < 1e-12,
            "A {a} C {c}: {tip:?}"
        );
    }
}

#[test]
fn a_45_degree_nutating_head_turned_180_degrees_holds_the_tool_horizontal() {
    // Rot(d, 180°) z = 2 (d·z) d − z = (0, 1, 1) − (0, 0, 1) = +Y for d = (0, 1, 1)/√2.
    let chain = chain_of(&load("machines/head-table-b45-c.toml"));
    let (_, t) = chain.tool_in_machine(&joints(&[(Axis::B, 180.0)]), 0.0);
    assert!((t - Vector3::y()).norm() < 1e-12, "{t:?}");
    // At B = 90° the tool is 60° from the vertical: cos θ = (1 + cos B) / 2 = 1/2.
    let (_, t) = chain.tool_in_machine(&joints(&[(Axis::B, 90.0)]), 0.0);
    assert!((t.z - 0.5).abs() < 1e-12, "{t:?}");
    // A nutating table (d = (0, −1, 1)/√2) turned 180° shows the vertical tool to the
    // workpiece along Rot(d, −180°) z = 2 (d·z) d − z = (0, −1, 0).
    let chain = chain_of(&load("machines/nutating-table-b45-c.toml"));
    let (_, t) = chain.tool_in_workpiece(&joints(&[(Axis::B, 180.0)]), 0.0);
    assert!((t + Vector3::y()).norm() < 1e-12, "{t:?}");
}

// max5's and bridgemill's tips against maxkins' and 5axiskins' formulas: linuxcnc_formulas.rs.

#[test]
fn named_layouts_and_their_chains_agree() {
    // The chain's workpiece frame is the layout's table frame shifted by the pivot.
    let pivot = Vector3::new(12.5, -40.0, 80.0);
    for layout in [
        Layout::TrtAc,
        Layout::TrtBc,
        Layout::TrtAb,
        Layout::Xyza,
        Layout::Xyz,
    ] {
        let k = Kinematics::new(layout, pivot);
        let chain = k.chain().unwrap();
        for (i, q6) in [
            [10.0, -20.0, 30.0, 25.0, -35.0, 140.0],
            [-5.0, 7.0, -9.0, -80.0, 60.0, -300.0],
        ]
        .iter()
        .enumerate()
        {
            let q = AxisVec::xyzabc(*q6);
            let pose = k.forward(&q);
            let (tip, t) = chain.tool_in_workpiece(&q, 0.0);
            assert!(
                (tip.coords - pivot - pose.tip.coords).norm() < 1e-11,
                "{layout:?} #{i}"
            );
            assert!((t - pose.axis).norm() < 1e-14, "{layout:?} #{i}");
        }
        // And a chain written exactly as the layout is recognised as it.
        assert_eq!(Kinematics::from_chain(chain).layout, layout);
    }
    assert!(Kinematics::new(Layout::Xyzabc, pivot).chain().is_none());
}

fn within(m: &Machine) -> impl Fn(Axis, f64) -> bool + '_ {
    move |a, v| m.axis(a).within_travel(v)
}

/// A random pose of `m` within its travel from `u` in [0, 1)^6; rotaries kept 2° off
/// their limits and the pole (the tilt away from zero).
fn pose_in_travel(m: &Machine, u: [f64; 6]) -> AxisVec {
    let mut q = AxisVec::ZERO;
    for (i, axis) in m.axes().iter().enumerate() {
        let c = m.axis(*axis);
        let (lo, hi) = if axis.is_rotary() {
            (c.min.max(-400.0) + 2.0, c.max.min(400.0) - 2.0)
        } else {
            (c.min, c.max)
        };
        q[*axis] = lo + (hi - lo) * u[i % 6];
    }
    q
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// IK(FK(q)) = q with the previous pose q itself, and FK(IK(x)) = x from a far
    /// previous pose, on every shipped chain (1e-9 mm, 1e-9 of the direction).
    #[test]
    fn inverse_and_forward_undo_each_other_on_every_shipped_chain(
        which in 0..SHIPPED.len(),
        u in proptest::array::uniform6(0.0..1.0f64),
        tool in 0.0..150.0f64,
    ) {
        let m = load(SHIPPED[which]);
        let chain = chain_of(&m);
        let q = pose_in_travel(&m, u);
        let (tip, t) = chain.tool_in_workpiece(&q, tool);
        // Away from the pole, where the first rotary's angle is free.
        let tilt = t.dot(&chain.tool_direction).clamp(-1.0, 1.0).acos().to_degrees();
        prop_assume!(tilt > 1.0);
        let pose = ToolPose { tip, axis: t };
        let back = chain_inverse::nearest(&chain, &pose, tool, &q, &within(&m)).unwrap();
        for axis in m.axes() {
            prop_assert!((back.joints[*axis] - q[*axis]).abs() < 1e-8,
                "{}: {} {} vs {}", SHIPPED[which], axis, back.joints[*axis], q[*axis]);
        }
        let mut far = AxisVec::ZERO;
        far[Axis::W] = q[Axis::W];
        for s in chain_inverse::solutions(&chain, &pose, tool, &far).unwrap() {
            let (tip2, t2) = chain.tool_in_workpiece(&s.joints, tool);
            prop_assert!((tip2 - tip).norm() < 1e-9, "{}: tip {:?} vs {:?}", SHIPPED[which], tip2, tip);
            prop_assert!((t2 - t).norm() < 1e-9, "{}: direction {:?} vs {:?}", SHIPPED[which], t2, t);
        }
    }
}

#[test]
fn a_two_rotary_chain_has_two_solutions_and_the_nearest_is_chosen() {
    // Fork head, tool tilted 30° toward −Y at C = 0 (A = 30), or toward it with C = 180, A = −30.
    let m = load("machines/fork-head-ca.toml");
    let chain = chain_of(&m);
    let (s30, c30) = sin_cos(30.0);
    let pose = ToolPose {
        tip: Point3::new(5.0, 6.0, 7.0),
        axis: Vector3::new(0.0, -s30, c30),
    };
    let all = chain_inverse::solutions(&chain, &pose, 0.0, &AxisVec::ZERO).unwrap();
    assert_eq!(all.len(), 2);
    let mut pairs: Vec<(f64, f64)> = all
        .iter()
        .map(|s| (s.joints[Axis::A], s.joints[Axis::C]))
        .collect();
    pairs.sort_by(|a, b| a.0.partial_cmp(&b.0).unwrap());
    assert!(
        (pairs[0].0 + 30.0).abs() < 1e-12 && (pairs[0].1.abs() - 180.0).abs() < 1e-12,
        "{pairs:?}"
    );
    assert!(
        (pairs[1].0 - 30.0).abs() < 1e-12 && pairs[1].1.abs() < 1e-12,
        "{pairs:?}"
    );
    let near = |c: f64| {
        chain_inverse::nearest(&chain, &pose, 0.0, &joints(&[(Axis::C, c)]), &within(&m)).unwrap()
    };
    assert!((near(10.0).joints[Axis::A] - 30.0).abs() < 1e-12);
    assert!((near(170.0).joints[Axis::A] + 30.0).abs() < 1e-12);
    // With C's travel ±360, a previous C of 350 reaches C = 360 (A = 30), not 180.
    assert!((near(350.0).joints[Axis::C] - 360.0).abs() < 1e-12);
}

/// Poses with the tip at the origin: `(line, tool direction)`.
fn at_origin(directions: &[(usize, Vector3<f64>)]) -> Vec<(usize, ToolPose)> {
    directions
        .iter()
        .map(|(line, axis)| {
            (
                *line,
                ToolPose {
                    tip: Point3::origin(),
                    axis: *axis,
                },
            )
        })
        .collect()
}

/// The joints of a path of poses, each the nearest solution to the one before (from all
/// axes at 0), and the events the pole watch finds on them.
fn follow(m: &Machine, poses: &[(usize, ToolPose)]) -> (Vec<AxisVec>, Vec<PathEvent>) {
    let chain = chain_of(m);
    let mut watch = PoleWatch::new(&chain, 0.1).expect("two rotaries");
    let mut joints: Vec<AxisVec> = Vec::new();
    for (line, pose) in poses {
        let previous = joints.last().copied().unwrap_or(AxisVec::ZERO);
        let s = chain_inverse::nearest(&chain, pose, 0.0, &previous, &within(m)).unwrap();
        watch.push(*line, &s.joints);
        joints.push(s.joints);
    }
    (joints, watch.finish())
}

#[test]
fn a_path_through_the_pole_reports_the_c_swing_and_a_path_over_it_a_switch() {
    // Fork head: the tool tilts 20° toward −Y (A = 20, C = 0), passes the vertical at line 2
    // (C free, kept at 0) and leaves toward +X: t = (sin 20, 0, cos 20) needs C = 90, A = 20,
    // or C = −90, A = −20: either way C swings 90° at the pole.
    let m = load("machines/fork-head-ca.toml");
    let (s, c) = sin_cos(20.0);
    let poses = at_origin(&[
        (1, Vector3::new(0.0, -s, c)),
        (2, Vector3::z()),
        (3, Vector3::new(s, 0.0, c)),
    ]);
    let (q, events) = follow(&m, &poses);
    assert_eq!(q[1][Axis::C], 0.0, "C kept at the pole");
    assert_eq!(events.len(), 1, "{events:?}");
    match events[0] {
        PathEvent::Pole {
            line,
            last_line,
            axis,
            swing_deg,
        } => {
            assert_eq!((line, last_line, axis), (2, 2, Axis::C));
            assert!((swing_deg.abs() - 90.0).abs() < 1e-9, "{swing_deg}");
        }
        ref e => panic!("{e:?}"),
    }
    // Tilting 20° toward −Y, then 20° toward +Y: the nearest solution flips A's sign
    // (A = −20 at C = 0: 40° of A rather than 180° of C), a switch of branch.
    let poses = at_origin(&[(5, Vector3::new(0.0, -s, c)), (6, Vector3::new(0.0, s, c))]);
    let (q, events) = follow(&m, &poses);
    assert!(
        (q[1][Axis::A] + 20.0).abs() < 1e-12 && q[1][Axis::C].abs() < 1e-12,
        "{:?}",
        q[1]
    );
    assert!(
        matches!(events.as_slice(), [PathEvent::Switch { line: 6, .. }]),
        "{events:?}"
    );
}

#[test]
fn an_orientation_out_of_the_nutating_heads_reach_is_refused() {
    // A 45° nutating head reaches at most 90° of tilt: a tool pointing 120° from the
    // vertical is out of reach.
    let chain = chain_of(&load("machines/head-table-b45-c.toml"));
    let (s, c) = sin_cos(120.0);
    let pose = ToolPose {
        tip: Point3::origin(),
        axis: Vector3::new(s, 0.0, c),
    };
    assert_eq!(
        chain_inverse::solutions(&chain, &pose, 0.0, &AxisVec::ZERO),
        Err(chain_inverse::InverseError::Unreachable)
    );
}

fn write(dir: &Path, text: &str) -> std::process::Output {
    std::fs::write(dir.join("m.toml"), text).unwrap();
    std::fs::write(
        dir.join("s.toml"),
        "machine = \"m.toml\"\n[program]\nfile = \"p.ngc\"\n[check]\ncollisions = false\n",
    )
    .unwrap();
    std::fs::write(dir.join("p.ngc"), "G1 X1 F100\nM2\n").unwrap();
    common::mtsim_plain(dir, &["analyze", "s.toml"])
}

#[test]
fn a_bad_chain_is_refused_with_its_line() {
    let dir = scratch("chains", "bad");
    let axes = |names: &str| {
        names
            .chars()
            .map(|n| format!("[axes.{n}]\nmin = -100.0\nmax = 100.0\nmax_velocity = 1000.0\nmax_acceleration = 100.0\nmax_jerk = 1000.0\n"))
            .collect::<String>()
    };
    let cases = [
        (
            "[kinematics]\ntable = [\"Q\"]\nhead = [\"X\", \"Y\", \"Z\"]\n",
            "XYZ",
            "`Q` is not an axis letter",
            3,
        ),
        (
            "[kinematics]\ntable = [\"C\"]\nhead = [\"X\", \"Y\", \"Z\", \"C\"]\n",
            "XYZC",
            "axis C appears twice",
            4,
        ),
        (
            "[kinematics]\ntable = []\nhead = [\"X\", \"Y\", \"Z\"]\n",
            "XYZC",
            "no axis `C`",
            0,
        ),
        (
            "[kinematics]\ntable = [\"C\"]\nhead = [\"X\", \"Y\", \"Z\"]\n",
            "XYZ",
            "axis C of the chain has no [axes.C]",
            3,
        ),
    ];
    for (kin, names, needle, line) in cases {
        let out = write(&dir, &format!("name = \"m\"\n{kin}{}", axes(names)));
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(err.contains(needle), "{needle}: {err}");
        if line > 0 {
            assert!(
                err.contains(&format!("m.toml:{line}:")),
                "line {line}: {err}"
            );
        }
    }
    let out = write(
        &dir,
        &format!(
            "name = \"m\"\nkinematics = \"xyz\"\n{}direction = [1.0, 0.0, 0.0]\n",
            axes("XYZ")
        ),
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("only a [kinematics] chain takes axis"),
        "{err}"
    );
    // And a good one runs.
    let out = write(
        &dir,
        &format!(
            "name = \"m\"\n[kinematics]\ntable = [\"C\"]\nhead = [\"X\", \"Y\", \"Z\"]\n{}",
            axes("XYZC")
        ),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("C "));
}
