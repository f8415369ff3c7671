//! The two LinuxCNC head samples against their kinematics modules' formulas, written out
//! here by hand (learnt from LinuxCNC's kins(9) page, the samples' files and black-box runs
//! of the samples, see the machine files' headers), both ways: the chain's forward
//! kinematics at joint poses, and `mtsim blocks`' machine coordinates for world poses under
//! TCP (the formulas inverted by hand).
//!
//! 5axiskins (bridgemill), pivot length P = 250 mm (5axisgui's pivot_len), tool length l:
//!   tip = J_xyz + (0, 0, P) + (P + l + W) (sin B cos C, sin B sin C, −cos B),
//!   tool direction (tip → spindle) t = (−sin B cos C, −sin B sin C, cos B).
//! maxkins (max5), pivot length 0: in the table's frame
//!   tip = Rz(C) J_xyz,   t = Rz(C) (−sin B, 0, cos B).

use std::path::Path;

use crate::common::{mtsim, scratch};
use mtsim::input::machine::Machine;
use mtsim::{Axis, AxisVec};
use nalgebra::Vector3;

const PIVOT_MM: f64 = 250.0;

fn chain(rel: &str) -> mtsim::kinematics::Chain {
    let m = Machine::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)).unwrap();
    m.kinematics.chain().expect("a chain")
}

fn sin_cos(deg: f64) -> (f64, f64) {
    deg.to_radians().sin_cos()
}

/// 5axiskins' tip and tool direction for joints [X, Y, Z, B, C, W] and tool length l.
fn bridgemill_formula(q: [f64; 6], l: f64) -> (Vector3<f64>, Vector3<f64>) {
    let [x, y, z, b, c, w] = q;
    let (sb, cb) = sin_cos(b);
    let (sc, cc) = sin_cos(c);
    let reach = PIVOT_MM + l + w;
    let tip = Vector3::new(
        x + reach * sb * cc,
        y + reach * sb * sc,
        z + PIVOT_MM - reach * cb,
    );
    (tip, Vector3::new(-sb * cc, -sb * sc, cb))
}

/// maxkins' tip and tool direction in the table's frame for joints [X, Y, Z, B, C].
fn max5_formula(q: [f64; 5]) -> (Vector3<f64>, Vector3<f64>) {
    let [x, y, z, b, c] = q;
    let (sb, cb) = sin_cos(b);
    let (sc, cc) = sin_cos(c);
    let rz = |v: Vector3<f64>| Vector3::new(cc * v.x - sc * v.y, sc * v.x + cc * v.y, v.z);
    (rz(Vector3::new(x, y, z)), rz(Vector3::new(-sb, 0.0, cb)))
}

const BRIDGEMILL_POSES: [[f64; 6]; 5] = [
    [0.0, 0.0, 0.0, 30.0, 0.0, 0.0],
    [0.0, 0.0, 0.0, 0.0, 0.0, 10.0],
    [10.0, 20.0, 30.0, 30.0, 45.0, 5.0],
    [-40.0, 15.0, -60.0, -75.0, 200.0, -20.0],
    [120.0, -80.0, 10.0, 110.0, -135.0, 40.0],
];

const MAX5_POSES: [[f64; 5]; 4] = [
    [100.0, 0.0, 0.0, 0.0, 30.0],
    [10.0, 20.0, -30.0, 30.0, 45.0],
    [-40.0, 25.0, -100.0, -80.0, 250.0],
    [50.0, -20.0, -5.0, 60.0, -120.0],
];

fn q_of(values: &[(Axis, f64)]) -> AxisVec {
    let mut q = AxisVec::ZERO;
    for (a, v) in values {
        q[*a] = *v;
    }
    q
}

#[test]
fn bridgemill_places_the_tip_as_5axiskins_does() {
    let chain = chain("machines/linuxcnc/bridgemill.toml");
    for p in BRIDGEMILL_POSES {
        for l in [0.0, 100.0] {
            let q = q_of(&[
                (Axis::X, p[0]),
                (Axis::Y, p[1]),
                (Axis::Z, p[2]),
                (Axis::B, p[3]),
                (Axis::C, p[4]),
                (Axis::W, p[5]),
            ]);
            let (tip, t) = chain.tool_in_machine(&q, l);
            let (want_tip, want_t) = bridgemill_formula(p, l);
            assert!(
                (tip.coords - want_tip).norm() < 1e-9,
                "{p:?} l {l}: {tip:?} vs {want_tip:?}"
            );
            assert!((t - want_t).norm() < 1e-12, "{p:?}: {t:?} vs {want_t:?}");
        }
    }
    // The figures: B30 C0 puts the tip 125 mm toward +X; W = 10 extends the tool.
    let (tip, _) = bridgemill_formula([0.0, 0.0, 0.0, 30.0, 0.0, 0.0], 0.0);
    assert!((tip.x - 125.0).abs() < 1e-9);
    let (tip, _) = bridgemill_formula([0.0, 0.0, 0.0, 0.0, 0.0, 10.0], 0.0);
    assert!((tip.z + 10.0).abs() < 1e-12);
}

#[test]
fn max5_places_the_tip_as_maxkins_does() {
    let chain = chain("machines/linuxcnc/max5.toml");
    for p in MAX5_POSES {
        let q = q_of(&[
            (Axis::X, p[0]),
            (Axis::Y, p[1]),
            (Axis::Z, p[2]),
            (Axis::B, p[3]),
            (Axis::C, p[4]),
        ]);
        let (tip, t) = chain.tool_in_workpiece(&q, 0.0);
        let (want_tip, want_t) = max5_formula(p);
        assert!(
            (tip.coords - want_tip).norm() < 1e-9,
            "{p:?}: {tip:?} vs {want_tip:?}"
        );
        assert!((t - want_t).norm() < 1e-12, "{p:?}: {t:?} vs {want_t:?}");
    }
    // The figure: joints X100 C30 are the workpiece's Y +50.
    let (tip, _) = max5_formula([100.0, 0.0, 0.0, 0.0, 30.0]);
    assert!((tip.y - 50.0).abs() < 1e-9);
}

/// `mtsim blocks`' machine coordinates (columns `cols`) of each move of `moves` under TCP.
pub(crate) fn tcp_joints(machine: &str, moves: &[String], cols: &[&str]) -> Vec<Vec<f64>> {
    let dir = scratch(
        "linuxcnc-formulas",
        Path::new(machine).file_stem().unwrap().to_str().unwrap(),
    );
    std::fs::write(
        dir.join("p.ngc"),
        format!("M428\n{}\nM429\nM2\n", moves.join("\n")),
    )
    .unwrap();
    let scenario = dir.join("s.toml");
    let machine = Path::new(env!("CARGO_MANIFEST_DIR")).join(machine);
    std::fs::write(
        &scenario,
        format!(
            "machine = {:?}\n[program]\nfile = \"p.ngc\"\n[reader]\n\
             user_m_codes = {{ M428 = \"tcp-on\", M429 = \"tcp-off\" }}\n",
            machine.display().to_string()
        ),
    )
    .unwrap();
    let o = mtsim(&["blocks", scenario.to_str().unwrap(), "--csv"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    let mut rows = text.lines();
    let header: Vec<&str> = rows.next().unwrap().split(',').collect();
    let idx: Vec<usize> = cols
        .iter()
        .map(|c| header.iter().position(|h| h == c).unwrap())
        .collect();
    rows.map(|r| {
        let f: Vec<&str> = r.split(',').collect();
        idx.iter().map(|&i| f[i].parse().unwrap()).collect()
    })
    .collect()
}

#[test]
fn under_tcp_the_bridgemill_joints_are_5axiskins_inverse() {
    // World poses (tip X Y Z, B C W): the joints are J = tip − (0, 0, P) − (P + W)(sin B cos C,
    // sin B sin C, −cos B), B C W as written.
    let world = BRIDGEMILL_POSES;
    let moves: Vec<String> = world
        .iter()
        .map(|p| {
            format!(
                "G0 X{} Y{} Z{} B{} C{} W{}",
                p[0], p[1], p[2], p[3], p[4], p[5]
            )
        })
        .collect();
    let got = tcp_joints(
        "machines/linuxcnc/bridgemill.toml",
        &moves,
        &["x_mm", "y_mm", "z_mm", "b_deg", "c_deg", "w_mm"],
    );
    assert_eq!(got.len(), world.len());
    for (p, g) in world.iter().zip(&got) {
        let (sb, cb) = sin_cos(p[3]);
        let (sc, cc) = sin_cos(p[4]);
        let reach = PIVOT_MM + p[5];
        let want = [
            p[0] - reach * sb * cc,
            p[1] - reach * sb * sc,
            p[2] - PIVOT_MM + reach * cb,
            p[3],
            p[4],
            p[5],
        ];
        for k in 0..6 {
            assert!((g[k] - want[k]).abs() < 1e-9, "{p:?}: {g:?} vs {want:?}");
        }
    }
    // LinuxCNC 2.9's 5axiskins, run headless on this sample with 5axisgui's pivot_len 250,
    // gave joints (-80.1561146012848, -70.15611460128478, 0.836477965031861) for the third.
    assert!((got[2][0] + 80.1561146012848).abs() < 1e-9, "{:?}", got[2]);
    assert!((got[2][2] - 0.836477965031861).abs() < 1e-9, "{:?}", got[2]);
}

#[test]
fn under_tcp_the_max5_joints_are_maxkins_inverse() {
    // World poses in the table's frame: the joints are J = Rz(−C) tip, B C as written.
    let moves: Vec<String> = MAX5_POSES
        .iter()
        .map(|p| format!("G0 X{} Y{} Z{} B{} C{}", p[0], p[1], p[2], p[3], p[4]))
        .collect();
    let got = tcp_joints(
        "machines/linuxcnc/max5.toml",
        &moves,
        &["x_mm", "y_mm", "z_mm", "b_deg", "c_deg"],
    );
    assert_eq!(got.len(), MAX5_POSES.len());
    for (p, g) in MAX5_POSES.iter().zip(&got) {
        let (sc, cc) = sin_cos(p[4]);
        let want = [
            cc * p[0] + sc * p[1],
            -sc * p[0] + cc * p[1],
            p[2],
            p[3],
            p[4],
        ];
        for k in 0..5 {
            assert!((g[k] - want[k]).abs() < 1e-9, "{p:?}: {g:?} vs {want:?}");
        }
    }
    // LinuxCNC 2.9's maxkins, run headless on this sample, gave joints (86.60254037844389,
    // -49.999999999999986, 0) for world X100 C30.
    assert!((got[0][1] + 50.0).abs() < 1e-9, "{:?}", got[0]);
}
