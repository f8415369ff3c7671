//! `[simulate] tcp = true` applies only to programs written for tool-centre-point control:
//! the generated TCP cone and files whose feed moves run under G43.4 (G234, M128, TRAORI).
//! On a joint-space program it is refused with exit code 2 and the reason.

use crate::common;

use common::{mtsim_plain, scratch, trt_ac, write_scenario, CONE_15_10};

/// Standard error with the report's line wrapping and frame undone: words joined by spaces.
fn stderr(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stderr)
        .split_whitespace()
        .filter(|w| *w != "│")
        .collect::<Vec<_>>()
        .join(" ")
}

#[test]
fn tcp_on_a_joint_space_cone_or_circle_is_refused_with_the_reason() {
    let dir = scratch("tcp", "generated");
    let circle = "[program.circle]\nplane = \"XY\"\nradius_mm = 50.0\nfeed_mm_min = 1000.0\ncenter_mm = [0.0, 0.0, 100.0]\n";
    for (name, machine, body, why) in [
        (
            "cone",
            trt_ac(),
            CONE_15_10.to_string(),
            "the generated cone is written in joint space",
        ),
        (
            "circle",
            common::machine("vmc-3axis"),
            circle.to_string(),
            "the circle test is written in machine X Y Z",
        ),
    ] {
        let path = write_scenario(&dir, &machine, &format!("{body}[simulate]\ntcp = true\n"));
        for command in ["check", "simulate"] {
            let out = mtsim_plain(
                &dir,
                &[command, path.to_str().unwrap(), "-o", "out"]
                    [..if command == "check" { 2 } else { 4 }],
            );
            let err = stderr(&out);
            assert_eq!(out.status.code(), Some(2), "{name} {command}: {err}");
            assert!(
                err.contains("applies only to programs written for tool-centre-point control")
                    && err.contains(why),
                "{name} {command}: {err}"
            );
        }
    }
}

#[test]
fn tcp_on_a_joint_space_file_is_refused_at_its_first_feed_move() {
    let dir = scratch("tcp", "file");
    std::fs::write(
        dir.join("joint.nc"),
        "G21 G90 G94\nG0 X0 Y0 Z200 A0 C0\nG1 X10 Y0 Z200 A5 C10 F1000\nM30\n",
    )
    .unwrap();
    let path = write_scenario(
        &dir,
        &trt_ac(),
        "[program]\nfile = \"joint.nc\"\n[simulate]\ntcp = true\n[check]\ncollisions = false\n",
    );
    let out = mtsim_plain(&dir, &["check", path.to_str().unwrap()]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("runs in joint space") && err.contains("joint.nc:3"),
        "{err}"
    );
}

#[test]
fn tcp_on_a_program_written_for_tcp_runs() {
    let dir = scratch("tcp", "accepted");
    // The generated TCP cone, and the same program as a file (G43.4 on every feed move).
    let cone = write_scenario(
        &dir,
        &trt_ac(),
        &format!("{CONE_15_10}tcp = true\n[simulate]\ntcp = true\n[check]\ncollisions = false\n"),
    );
    let out = mtsim_plain(&dir, &["check", cone.to_str().unwrap()]);
    assert!(matches!(out.status.code(), Some(0 | 1)), "{}", stderr(&out));
    let out = mtsim_plain(
        &dir,
        &["cone", cone.to_str().unwrap(), "--tcp", "-o", "tcp.nc"],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let file = dir.join("file.toml");
    std::fs::write(
        &file,
        common::scenario_text(
            &trt_ac(),
            &format!("[program]\nfile = \"tcp.nc\"\n{}[simulate]\ntcp = true\n[check]\ncollisions = false\n",
                CONE_15_10),
        ),
    )
    .unwrap();
    let out = mtsim_plain(&dir, &["check", file.to_str().unwrap()]);
    assert!(matches!(out.status.code(), Some(0 | 1)), "{}", stderr(&out));
}
