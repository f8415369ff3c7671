//! trt-ac, trt-bc and trt-ab written out as `[kinematics]` chains (the spec's table) give
//! the outputs of their named layouts byte for byte: analyze, blocks, check and simulate on
//! the bundled scenarios and on the cone on each machine. The one difference is the
//! scenario hash of a run (test.json, report.html), a fingerprint of the input files'
//! bytes, which differ by construction: it is blanked before comparing.

use crate::common;

use std::path::{Path, PathBuf};

use common::{mtsim_plain, scratch};

/// `machine` (a named-layout machine file's text) with its `kinematics` and `pivot_mm`
/// lines replaced by the chain of the spec: `table` from the bed outward, each rotary with
/// its direction through the pivot.
fn written_out(machine: &str, table: &[(&str, [f64; 3])]) -> String {
    let pivot = machine
        .lines()
        .find_map(|l| l.strip_prefix("pivot_mm = "))
        .expect("the file gives pivot_mm")
        .split('#')
        .next()
        .unwrap()
        .trim()
        .to_string();
    let mut out = String::new();
    for line in machine.lines() {
        if line.starts_with("kinematics = ") || line.starts_with("pivot_mm = ") {
            continue;
        }
        out.push_str(line);
        out.push('\n');
        for (axis, d) in table {
            if line.trim() == format!("[axes.{axis}]") {
                out.push_str(&format!(
                    "direction = [{:?}, {:?}, {:?}]\npoint_mm = {pivot}\n",
                    d[0], d[1], d[2]
                ));
            }
        }
    }
    let names: Vec<String> = table.iter().map(|(a, _)| format!("{a:?}")).collect();
    out.push_str(&format!(
        "\n[kinematics]\ntable = [{}]\nhead = [\"X\", \"Y\", \"Z\"]\ngauge_point_mm = [0.0, 0.0, 0.0]\ntool_direction = [0.0, 0.0, 1.0]\n",
        names.join(", ")
    ));
    assert!(!out.contains("kinematics = "));
    out
}

/// Runs every command of /work/tools/outputs.sh that takes one scenario on `scenario` in
/// `dir`, and returns each output (stdout, stderr and the files a run writes) by name.
fn outputs(dir: &Path, scenario: &str) -> Vec<(String, Vec<u8>)> {
    let runs: [&[&str]; 6] = [
        &["analyze", scenario],
        &["analyze", scenario, "--json"],
        &["blocks", scenario, "--csv"],
        &["check", scenario, "--json"],
        &["check", scenario],
        &["simulate", scenario, "-o", "run", "--no-timing", "--html"],
    ];
    let mut out = Vec::new();
    for args in runs {
        let _ = std::fs::remove_dir_all(dir.join("run"));
        let o = mtsim_plain(dir, args);
        let name = args.join(" ");
        out.push((
            format!("{name}: status"),
            format!("{:?}", o.status.code()).into_bytes(),
        ));
        out.push((format!("{name}: stdout"), o.stdout));
        out.push((format!("{name}: stderr"), o.stderr));
        if args[0] == "simulate" {
            let mut files: Vec<PathBuf> = std::fs::read_dir(dir.join("run"))
                .map(|d| d.map(|e| e.unwrap().path()).collect())
                .unwrap_or_default();
            files.sort();
            for f in files {
                // The manifest holds each file's hash, test.json's with the scenario hash
                // in it: the files themselves are compared instead.
                if f.is_file() && !f.ends_with(".mtsim-run.json") {
                    out.push((
                        format!("run/{}", f.file_name().unwrap().to_string_lossy()),
                        std::fs::read(&f).unwrap(),
                    ));
                }
            }
        }
    }
    // The scenario hash fingerprints the machine file's bytes: blank it.
    let hash = out
        .iter()
        .find(|(n, _)| n == "run/test.json")
        .and_then(|(_, t)| {
            let v: serde_json::Value = serde_json::from_slice(t).ok()?;
            Some(v["scenario_hash"].as_str()?.to_string())
        })
        .expect("test.json has a scenario hash");
    for (_, bytes) in &mut out {
        let text = String::from_utf8_lossy(bytes).replace(&hash, "HASH");
        *bytes = text.into_bytes();
    }
    out
}

/// Writes `machine` as `m.toml` and `scenario` (machine line pointing at it) in two
/// folders, the named one and the written-out one, and compares all outputs.
fn same_outputs(
    name: &str,
    machine: &str,
    chain: &str,
    scenario_body: &str,
    program: Option<&str>,
) {
    let mut results = Vec::new();
    for (which, text) in [("named", machine), ("chain", chain)] {
        // The same folder name for both, so that paths in the outputs are the same.
        let dir = scratch("written-out", name).join("case");
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("m.toml"), text).unwrap();
        std::fs::write(
            dir.join("s.toml"),
            format!("machine = \"m.toml\"\n{scenario_body}"),
        )
        .unwrap();
        if let Some(p) = program {
            std::fs::create_dir_all(dir.join("programs")).unwrap();
            std::fs::write(
                dir.join("programs").join(Path::new(p).file_name().unwrap()),
                std::fs::read(p).unwrap(),
            )
            .unwrap();
        }
        results.push((which, outputs(&dir, "s.toml")));
    }
    let (named, chain) = (&results[0].1, &results[1].1);
    assert_eq!(named.len(), chain.len(), "{name}: the same outputs");
    assert!(
        named.iter().any(|(n, _)| n.starts_with("run/")),
        "{name}: simulate wrote its run"
    );
    for ((n1, a), (n2, b)) in named.iter().zip(chain) {
        assert_eq!(n1, n2);
        assert!(
            a == b,
            "{name}: {n1} differs:\n{}\n---\n{}",
            String::from_utf8_lossy(a),
            String::from_utf8_lossy(b)
        );
    }
}

fn read(rel: &str) -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)).unwrap()
}

/// The scenario's text after its `machine =` line.
fn body_of(rel: &str) -> String {
    read(rel)
        .lines()
        .filter(|l| !l.starts_with("machine = "))
        .map(|l| format!("{l}\n"))
        .collect()
}

const A: (&str, [f64; 3]) = ("A", [1.0, 0.0, 0.0]);

#[test]
fn trt_ac_written_out_runs_every_bundled_trt_ac_scenario_byte_for_byte() {
    let machine = read("machines/trt-ac.toml");
    let chain = written_out(&machine, &[A, ("C", [0.0, 0.0, 1.0])]);
    for scenario in [
        "scenarios/cone-15-10.toml",
        "scenarios/cone-45-30.toml",
        "scenarios/cone-15-10-offset.toml",
        "scenarios/cone-15-10-yt25.toml",
        "scenarios/file-cone-15-10-yt25.toml",
    ] {
        let program =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/programs/cone-15-10-yt25.nc");
        let name = Path::new(scenario)
            .file_stem()
            .unwrap()
            .to_string_lossy()
            .to_string();
        same_outputs(
            &name,
            &machine,
            &chain,
            &body_of(scenario),
            Some(program.to_str().unwrap()),
        );
    }
}

#[test]
fn trt_bc_and_trt_ab_written_out_run_the_cone_byte_for_byte() {
    let trt_bc = read("machines/trt-bc.toml");
    let chain = written_out(&trt_bc, &[("B", [0.0, 1.0, 0.0]), ("C", [0.0, 0.0, 1.0])]);
    same_outputs("trt-bc", &trt_bc, &chain, common::CONE_15_10, None);
    // trt-ab turns the table by −B and −A: its chain carries the negated directions.
    let tdr = read("machines/linuxcnc/xyzab-tdr.toml");
    let chain = written_out(&tdr, &[("B", [0.0, -1.0, 0.0]), ("A", [-1.0, 0.0, 0.0])]);
    let cone = "[program.cone]\nhalf_apex_deg = 15.0\ninclination_deg = 10.0\ncenter_mm = [-50.0, -50.0, -60.0]\nballbar_length_mm = 40.0\n[workpiece]\nriser = false\n";
    same_outputs("trt-ab", &tdr, &chain, cone, None);
}
