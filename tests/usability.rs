//! What a new user meets first: right figures by default, clear errors for bad programs,
//! and a command line that behaves as documented.

mod common;

use common::{mtsim, scratch, stdout_json};

fn g_um(v: &serde_json::Value) -> f64 {
    v["ballbar"]["circular_deviation_um"].as_f64().unwrap()
}

#[test]
fn the_file_program_gives_the_g_of_its_generated_twin() {
    // The bundled G-code file is the post-processor's output for the same cone as
    // cone-15-10-yt25.toml, without a lead arc: its start-up transient must not count.
    let dir = scratch("usability", "twin");
    let file = mtsim(&[
        "simulate",
        "scenarios/file-cone-15-10-yt25.toml",
        "-o",
        dir.join("file").to_str().unwrap(),
        "--json",
        "--no-timing",
    ]);
    let twin = mtsim(&[
        "simulate",
        "scenarios/cone-15-10-yt25.toml",
        "-o",
        dir.join("twin").to_str().unwrap(),
        "--json",
        "--no-timing",
    ]);
    let (g_file, g_twin) = (g_um(&stdout_json(&file)), g_um(&stdout_json(&twin)));
    assert!(
        (g_file - g_twin).abs() < 0.10 * g_twin,
        "file G {g_file} um vs twin G {g_twin} um"
    );
    // ... and it says what it did.
    let err = String::from_utf8_lossy(&file.stderr);
    assert!(
        err.contains("start-up transient") && err.contains("measure_lines"),
        "{err}"
    );
    let summary = stdout_json(&file);
    assert!(summary["warnings"][0]
        .as_str()
        .unwrap()
        .contains("deg of the measured revolution"));
}

#[test]
fn measuring_from_the_first_feed_block_warns_that_one_spot_dominates_g() {
    // measure_lines set to the first and last feed block of the lead-less file: the rapid's
    // settling is then measured, as asked, and makes nearly all of G.
    let dir = scratch("usability", "spot");
    let program = std::fs::read_to_string("scenarios/programs/cone-15-10-yt25.nc").unwrap();
    let lines: Vec<&str> = program.lines().collect();
    let first = 1 + lines.iter().position(|l| l.starts_with("G01")).unwrap();
    let last = 1 + lines.iter().rposition(|l| l.starts_with("G01")).unwrap();
    std::fs::write(dir.join("p.nc"), &program).unwrap();
    let scenario = dir.join("s.toml");
    std::fs::write(
        &scenario,
        format!(
            "machine = \"{}\"\n[program]\nfile = \"p.nc\"\n[program.cone]\nhalf_apex_deg = 15.0\n\
             inclination_deg = 10.0\ncenter_mm = [0.0, -25.0, 200.0]\nballbar_length_mm = 100.0\n\
             [simulate]\nmeasure_lines = [{first}, {last}]\n",
            common::trt_ac()
        ),
    )
    .unwrap();
    let out = mtsim(&[
        "simulate",
        scenario.to_str().unwrap(),
        "-o",
        dir.join("out").to_str().unwrap(),
        "--json",
        "--no-timing",
    ]);
    let v = stdout_json(&out);
    assert!(
        g_um(&v) > 500.0,
        "the transient is measured: G {}",
        g_um(&v)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("one spot dominates G"), "{err}");
    assert!(err.contains("θ = 0.0°") || err.contains("θ = 359"), "{err}");
}
