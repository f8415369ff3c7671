//! `mtsim fit` on head machines (general `[kinematics]` chains): traces made by `simulate`
//! with known location errors plus 0.1 µm Gaussian noise, fitted with the error-free
//! machine. What the cones separate follows from the rank of the sensitivity matrix and is
//! worked out by hand below; the identifiable errors come back within 1 µm (µrad) or 10 %,
//! and exactly the others are flagged.

use std::path::{Path, PathBuf};

use super::fit::{assert_recovered, machine_with_errors, measure, param, run_fit};
use crate::common::scratch;

/// The bundled `machine` with `errors` ((name, value)) as `dir/<name>.toml`.
fn machine(dir: &Path, machine: &str, name: &str, errors: &[(&str, f64)]) -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    machine_with_errors(
        &root.join(format!("machines/{machine}.toml")),
        dir,
        name,
        errors,
    )
}

/// The cone (α, β) at O = (0, 0, z) in the workpiece frame, both directions, F2000.
fn cone(dir: &Path, name: &str, machine: &Path, alpha: f64, beta: f64, z: f64) -> PathBuf {
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(
        &path,
        format!(
            "machine = {:?}\n[program.cone]\nhalf_apex_deg = {alpha}\ninclination_deg = {beta}\ncenter_mm = [0.0, 0.0, {z}]\nballbar_length_mm = 100.0\nfeed_mm_min = 2000.0\ndirections = [\"ccw\", \"cw\"]\n[simulate]\ntrace_every = 10\n[check]\ncollisions = false\n",
            machine.display().to_string()
        ),
    )
    .unwrap();
    path
}

fn fit_cones(
    name: &str,
    base: &str,
    hidden: &[(&str, f64)],
    cones: &[(f64, f64, f64)],
) -> serde_json::Value {
    let dir = scratch("fit-chain", name);
    let truth = machine(&dir, base, "true", hidden);
    let nominal = machine(&dir, base, "nominal", &[]);
    let mut pairs = Vec::new();
    for (i, (alpha, beta, z)) in cones.iter().enumerate() {
        let s_true = cone(&dir, &format!("t{i}"), &truth, *alpha, *beta, *z);
        let measured = measure(&dir, &format!("m{i}"), &s_true, 0.1, 41 + i as u64);
        pairs.push((
            cone(&dir, &format!("n{i}"), &nominal, *alpha, *beta, *z),
            measured,
        ));
    }
    let refs: Vec<(&Path, &Path)> = pairs
        .iter()
        .map(|(s, m)| (s.as_path(), m.as_path()))
        .collect();
    run_fit(&dir, &refs)
}

fn flagged(fit: &serde_json::Value, name: &str) {
    assert_eq!(
        param(fit, name)["identifiable"],
        false,
        "{name}: {}",
        param(fit, name)
    );
}

/// Head-table (45° nutating B head, C table), the 15/10 and 45/30 cones at O = 0. B's line
/// d = (0, s, s) lies along no machine axis, so of its three offsets only the two across
/// it act: EX0B and (EZ0B − EY0B)/√2 (an offset e along d moves nothing); of its tilts
/// EA0B and (EC0B − EB0B) act, the turn about d does nothing. O lies on C's line at the
/// height of its reference point, so C's tilts turn the table ball about itself: EA0C and
/// EB0C are invisible, and EX0C, EY0C come back. The differences come back in the fragment
/// (one of each pair carries it); a third cone at another height separates C's tilts.
#[test]
fn a_head_table_machine_separates_what_its_nutating_line_and_the_ball_height_allow() {
    let hidden = [
        ("EX0B", 12.0),
        ("EY0B", -7.0),
        ("EZ0B", 5.0),
        ("EA0B", 40.0),
        ("EB0B", 15.0),
        ("EC0B", -25.0),
        ("EX0C", 9.0),
        ("EY0C", -6.0),
        ("EA0C", -20.0),
        ("EB0C", 30.0),
    ];
    let fit = fit_cones(
        "head-table",
        "head-table-b45-c",
        &hidden,
        &[(15.0, 10.0, 0.0), (45.0, 30.0, 0.0)],
    );
    for (name, v) in [
        ("EX0B", 12.0),
        ("EA0B", 40.0),
        ("EX0C", 9.0),
        ("EY0C", -6.0),
    ] {
        assert_recovered(&fit, name, v);
    }
    for name in ["EY0B", "EZ0B", "EB0B", "EC0B", "EA0C", "EB0C"] {
        flagged(&fit, name);
    }
    assert_eq!(fit["null_dimensions"], 4, "{}", fit["unidentifiable"]);
    // The pairs across B's line: their difference is what the traces hold.
    let carried = |n: &str| param(&fit, n)["fragment_value"].as_f64().unwrap();
    let offset = carried("EZ0B") - carried("EY0B");
    let tilt = carried("EC0B") - carried("EB0B");
    assert!((offset - (5.0 + 7.0)).abs() < 1.2, "EZ0B − EY0B = {offset}");
    assert!((tilt - (-25.0 - 15.0)).abs() < 4.0, "EC0B − EB0B = {tilt}");
    // fit says why, for the tilted line.
    let cautions = fit["cautions"].to_string();
    assert!(
        cautions.contains("B's line") && cautions.contains("no machine axis"),
        "{cautions}"
    );

    // A third cone, 100 mm higher: C's tilts now move the ball and are separated.
    let fit = fit_cones(
        "head-table-3",
        "head-table-b45-c",
        &hidden,
        &[(15.0, 10.0, 0.0), (45.0, 30.0, 0.0), (15.0, 10.0, 100.0)],
    );
    for (name, v) in [
        ("EX0C", 9.0),
        ("EY0C", -6.0),
        ("EA0C", -20.0),
        ("EB0C", 30.0),
    ] {
        assert_recovered(&fit, name, v);
    }
    assert_eq!(fit["null_dimensions"], 2, "{}", fit["unidentifiable"]);
}

/// Fork head (C then A, both through (0, 0, 200), fixed table): the tool ball hangs 200 mm
/// below both lines and the table ball does not move, so the two cones at O = 0 separate
/// all eight errors (rank 8 + the bar offsets).
#[test]
fn a_fork_head_machine_separates_all_eight_with_two_cones() {
    let hidden = [
        ("EY0A", 15.0),
        ("EZ0A", -10.0),
        ("EB0A", 50.0),
        ("EC0A", -20.0),
        ("EX0C", 8.0),
        ("EY0C", 6.0),
        ("EA0C", -35.0),
        ("EB0C", 25.0),
    ];
    let fit = fit_cones(
        "fork-head",
        "fork-head-ca",
        &hidden,
        &[(15.0, 10.0, 0.0), (45.0, 30.0, 0.0)],
    );
    for (name, v) in hidden {
        assert_recovered(&fit, name, v);
    }
    assert_eq!(fit["null_dimensions"], 0, "{}", fit["unidentifiable"]);
}
