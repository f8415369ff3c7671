//! The LinuxCNC sample machines against LinuxCNC itself: each sample configuration run
//! headless (`common::linuxcnc`), its TCP kinematics switched on (`M428`), driven to poses
//! by MDI; the joint positions its kinematics module gives must be the machine coordinates
//! `mtsim blocks` gives for the same program on our machine file, within 1 nm.

use crate::common::{linuxcnc, scratch};
use crate::linuxcnc_formulas::tcp_joints;

/// One sample: its folder and ini below [`linuxcnc::SAMPLES`], our machine file, and the
/// rotary letters in the order of its joints after X Y Z.
struct Sample {
    config: &'static str,
    ini: &'static str,
    machine: &'static str,
    rotaries: [&'static str; 2],
}

/// Poses inside every sample's travel, X Y Z mm and the two rotaries deg: the tilt both
/// ways, the turn past 180 deg, and home.
const POSES: [[f64; 5]; 5] = [
    [10.0, 20.0, 30.0, 30.0, 45.0],
    [0.0, 0.0, 0.0, 0.0, 0.0],
    [-50.0, 15.0, -20.0, -40.0, 200.0],
    [35.0, -25.0, 5.0, 15.0, -120.0],
    [-5.0, 40.0, -35.0, -10.0, 300.0],
];

/// The program of the poses in TCP mode, as `G0` words.
fn moves(s: &Sample) -> Vec<String> {
    POSES
        .iter()
        .map(|p| {
            format!(
                "G0 X{} Y{} Z{} {}{} {}{}",
                p[0], p[1], p[2], s.rotaries[0], p[3], s.rotaries[1], p[4]
            )
        })
        .collect()
}

/// mtsim's machine coordinates (X Y Z and the two rotaries) of each move of the program.
fn mtsim_joints(s: &Sample) -> Vec<[f64; 5]> {
    let r = s.rotaries.map(|a| format!("{}_deg", a.to_lowercase()));
    let cols = ["x_mm", "y_mm", "z_mm", &r[0], &r[1]];
    tcp_joints(s.machine, &moves(s), &cols)
        .into_iter()
        .map(|row| [row[0], row[1], row[2], row[3], row[4]])
        .collect()
}

fn holds_to_linuxcnc(s: &Sample) {
    let dir = scratch("linuxcnc-sample", s.ini);
    let want = mtsim_joints(s);
    assert_eq!(want.len(), POSES.len(), "{want:?}");
    let run = linuxcnc::start(s.config, s.ini, &dir.join("lcnc"));
    let mut commands = vec!["M428".to_string()];
    commands.extend(moves(s));
    let refs: Vec<&str> = commands.iter().map(String::as_str).collect();
    let poses = run.mdi(&refs);
    drop(run);
    for (k, (pose, ours)) in poses[1..].iter().zip(&want).enumerate() {
        eprintln!(
            "{} pose {k}: LinuxCNC {:?}, mtsim {ours:?}",
            s.ini,
            &pose.joints[..5]
        );
        for j in 0..5 {
            assert!(
                (pose.joints[j] - ours[j]).abs() < 1e-6,
                "{} pose {:?}: joint {j} LinuxCNC {} mtsim {}",
                s.ini,
                POSES[k],
                pose.joints[j],
                ours[j]
            );
        }
    }
}

#[test]
fn the_tilting_table_samples_move_their_joints_as_linuxcnc_does() {
    if !linuxcnc::require("linuxcnc_samples") {
        return;
    }
    // One LinuxCNC at a time (it keeps a lock file): the samples in turn.
    for s in [
        Sample {
            config: "table-rotary-tilting",
            ini: "xyzac-trt.ini",
            machine: "machines/linuxcnc/xyzac-trt.toml",
            rotaries: ["A", "C"],
        },
        Sample {
            config: "table-rotary-tilting",
            ini: "xyzbc-trt.ini",
            machine: "machines/linuxcnc/xyzbc-trt.toml",
            rotaries: ["B", "C"],
        },
    ] {
        holds_to_linuxcnc(&s);
    }
}

/// A head sample: our machine file, the MDI that switches its kinematics to world
/// coordinates (none: always in them), HAL commands that stand in for its vismach model,
/// world poses, and mtsim's columns against LinuxCNC's joint numbers.
struct HeadSample {
    config: &'static str,
    ini: &'static str,
    machine: &'static str,
    world_on: Option<&'static str>,
    halcmds: &'static [&'static str],
    /// MDI after each move before its joints are read: max5's simulated motors (limit3
    /// blocks) trail motion's commands, so its joints are read after a dwell.
    settle: Option<&'static str>,
    moves: &'static [&'static str],
    columns: &'static [(&'static str, usize)],
}

#[test]
fn the_head_samples_move_their_joints_as_linuxcnc_does() {
    if !linuxcnc::require("linuxcnc_head_samples") {
        return;
    }
    let samples = [
        HeadSample {
            config: "bridgemill",
            ini: "5axis.ini",
            machine: "machines/linuxcnc/bridgemill.toml",
            world_on: Some("M428"),
            // 5axisgui's pivot_len, 250 by default, which its HAL file adds to the tool's
            // length for 5axiskins.pivot-length.
            halcmds: &["sets :gui-pivot-len 250"],
            settle: None,
            moves: &[
                "G0 X0 Y0 Z0 B30 C0 W0",
                "G0 X0 Y0 Z0 B0 C0 W10",
                "G0 X10 Y20 Z30 B30 C45 W5",
                "G0 X-40 Y15 Z-60 B-75 C200 W-20",
                "G0 X120 Y-80 Z10 B110 C-135 W40",
            ],
            // Joints X Y Z B C W (then the gantry's second Y).
            columns: &[
                ("x_mm", 0),
                ("y_mm", 1),
                ("z_mm", 2),
                ("b_deg", 3),
                ("c_deg", 4),
                ("w_mm", 5),
            ],
        },
        HeadSample {
            config: "max5",
            ini: "max5kins.ini",
            machine: "machines/linuxcnc/max5.toml",
            world_on: None,
            halcmds: &[],
            settle: Some("G4 P5"),
            moves: &[
                "G0 X100 Y0 Z0 B0 C30",
                "G0 X10 Y20 Z-30 B30 C45",
                // Fed slowly: a rapid's turn of C about a point this far off its line
                // asks more than 20 mm/s of the joints X and Y, and LinuxCNC stops.
                "G1 X-40 Y25 Z-60 B-80 C250 F240",
                "G1 X50 Y-20 Z-5 B60 C300 F600",
            ],
            // Joints X Y Z A B C (A is not a coordinate of the sample).
            columns: &[
                ("x_mm", 0),
                ("y_mm", 1),
                ("z_mm", 2),
                ("b_deg", 4),
                ("c_deg", 5),
            ],
        },
    ];
    for s in samples {
        let moves: Vec<String> = s.moves.iter().map(|m| m.to_string()).collect();
        let cols: Vec<&str> = s.columns.iter().map(|c| c.0).collect();
        let want = tcp_joints(s.machine, &moves, &cols);
        let dir = scratch("linuxcnc-head-sample", s.ini);
        let run = linuxcnc::start_with(s.config, s.ini, &dir.join("lcnc"), s.halcmds);
        let mut commands: Vec<&str> = s.world_on.into_iter().collect();
        for m in s.moves {
            commands.push(m);
            commands.extend(s.settle);
        }
        let poses = run.mdi(&commands);
        drop(run);
        let skip = usize::from(s.world_on.is_some());
        let per_move = 1 + usize::from(s.settle.is_some());
        let read = poses[skip..].iter().skip(per_move - 1).step_by(per_move);
        for ((pose, ours), m) in read.zip(&want).zip(s.moves) {
            eprintln!("{} {m}: LinuxCNC {:?}, mtsim {ours:?}", s.ini, pose.joints);
            for (k, (name, joint)) in s.columns.iter().enumerate() {
                assert!(
                    (pose.joints[*joint] - ours[k]).abs() < 1e-6,
                    "{} {m}: {name} LinuxCNC {} mtsim {}",
                    s.ini,
                    pose.joints[*joint],
                    ours[k]
                );
            }
        }
    }
}
