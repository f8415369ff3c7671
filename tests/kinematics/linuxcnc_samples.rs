//! The LinuxCNC sample machines against LinuxCNC itself: each sample configuration run
//! headless (`common::linuxcnc`), its TCP kinematics switched on (`M428`), driven to poses
//! by MDI; the joint positions its kinematics module gives must be the machine coordinates
//! `mtsim blocks` gives for the same program on our machine file, within 1 nm.

use std::path::Path;

use crate::common::{linuxcnc, mtsim, scratch};

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
fn mtsim_joints(s: &Sample, dir: &Path) -> Vec<[f64; 5]> {
    let program = format!("M428\n{}\nM429\nM2\n", moves(s).join("\n"));
    std::fs::write(dir.join("p.ngc"), program).unwrap();
    let machine = Path::new(env!("CARGO_MANIFEST_DIR")).join(s.machine);
    let scenario = dir.join("s.toml");
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
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut rows = text.lines();
    let header: Vec<&str> = rows.next().unwrap().split(',').collect();
    let col = |name: String| header.iter().position(|h| *h == name).unwrap();
    let cols = [
        col("x_mm".into()),
        col("y_mm".into()),
        col("z_mm".into()),
        col(format!("{}_deg", s.rotaries[0].to_lowercase())),
        col(format!("{}_deg", s.rotaries[1].to_lowercase())),
    ];
    rows.map(|r| {
        let f: Vec<&str> = r.split(',').collect();
        cols.map(|c| f[c].parse::<f64>().unwrap())
    })
    .collect()
}

fn holds_to_linuxcnc(s: &Sample) {
    let dir = scratch("linuxcnc-sample", s.ini);
    let want = mtsim_joints(s, &dir);
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
