//! Poles and solution switches reported by `analyze`, `check` and `simulate` on a fork head
//! (C then A, t = Rz(C) Rx(A) z) and a 45° nutating head over a C table, against the
//! hand-computed lines and swings.
//!
//! Fork head, program below: line 3 ends with A = 0, the tool vertical, along C's line: the
//! pole of A, where C is free; line 4 goes on to A 20 at C 180, so C swings 180° there with
//! the tool standing on the pole. In the inverse kinematics' terms the orientation
//! `Rot(x, A) z = Rot(z, −C) t` meets at `c = Rot(x, A) z = (0, −sin A, cos A)`, whose
//! component along `x × z = −y` is `sin A`: branch 0 for A ≥ 0, 1 for A < 0. Line 5 turns A
//! from 20 to −20 at C 180 in one block: a switch from solution 0 to 1.

use crate::common;

use std::path::Path;

use common::{mtsim_plain, scratch};

const FORK: &str =
    "G21 G90 G94 G17\nG00 X0 Y0 Z100 A20 C0\nG01 A0 F500\nG01 A20 C180\nG01 A-20 C180\nM30\n";

/// The 45° head: B = 0 holds the tool vertical, along the C table's line (line 3); line 4
/// goes on to B 60 at C 180 (a C swing of 180°); line 5 turns B from 60 to −60.
const NUTATING: &str =
    "G21 G90 G94 G17\nG00 X0 Y0 Z100 B60 C0\nG01 B0 F500\nG01 B60 C180\nG01 B-60 C180\nM30\n";

fn scenario(dir: &Path, machine: &str, program: &str) {
    std::fs::write(dir.join("p.nc"), program).unwrap();
    let m = Path::new(env!("CARGO_MANIFEST_DIR")).join(machine);
    std::fs::write(
        dir.join("s.toml"),
        format!(
            "machine = {:?}\n[program]\nfile = \"p.nc\"\n[check]\ncollisions = false\n",
            m.display().to_string()
        ),
    )
    .unwrap();
}

fn events(dir: &Path, command: &str) -> Vec<serde_json::Value> {
    let args: Vec<&str> = match command {
        "simulate" => vec!["simulate", "s.toml", "-o", "run", "--no-timing", "--json"],
        c => vec![c, "s.toml", "--json"],
    };
    let out = mtsim_plain(dir, &args);
    assert!(
        matches!(out.status.code(), Some(0) | Some(1)),
        "{command}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    v["chain_events"]
        .as_array()
        .unwrap_or_else(|| panic!("{command}: no chain_events in {v}"))
        .clone()
}

#[test]
fn a_fork_head_passing_the_pole_reports_the_c_swing_and_the_switch() {
    let dir = scratch("chain-poles", "fork");
    scenario(&dir, "machines/fork-head-ca.toml", FORK);
    for command in ["analyze", "check", "simulate"] {
        let e = events(&dir, command);
        assert_eq!(e.len(), 2, "{command}: {e:?}");
        assert_eq!(e[0]["kind"], "pole");
        assert_eq!(e[0]["line"], 3);
        assert_eq!(e[0]["axis"], "C");
        let swing = e[0]["swing_deg"].as_f64().unwrap();
        assert!((swing - 180.0).abs() < 1e-9, "{command}: swing {swing}");
        assert_eq!(
            e[0]["message"],
            "line 3: pole of A (tool along C): C swings 180.000 deg in one block"
        );
        assert_eq!(e[1]["kind"], "switch");
        assert_eq!(e[1]["line"], 5);
        assert_eq!(
            (e[1]["from"].as_u64(), e[1]["to"].as_u64()),
            (Some(0), Some(1))
        );
    }
    let out = mtsim_plain(&dir, &["analyze", "s.toml"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("  line 3: pole of A (tool along C): C swings 180.000 deg in one block\n"),
        "{text}"
    );
}

#[test]
fn a_nutating_head_passing_the_pole_reports_the_c_swing_and_the_switch() {
    let dir = scratch("chain-poles", "nutating");
    scenario(&dir, "machines/head-table-b45-c.toml", NUTATING);
    let e = events(&dir, "analyze");
    assert_eq!(e.len(), 2, "{e:?}");
    assert_eq!(
        e[0]["message"],
        "line 3: pole of B (tool along C): C swings 180.000 deg in one block"
    );
    assert_eq!(
        (e[1]["kind"].as_str(), e[1]["line"].as_u64()),
        (Some("switch"), Some(5))
    );
    assert_ne!(e[1]["from"], e[1]["to"]);
}

#[test]
fn a_path_off_the_pole_reports_nothing() {
    // C turns a full revolution with the tool tilted 20°: no pole, one branch.
    let dir = scratch("chain-poles", "none");
    scenario(
        &dir,
        "machines/fork-head-ca.toml",
        "G21 G90 G94 G17\nG00 X0 Y0 Z100 A20 C0\nG01 C180 F500\nG01 C360\nM30\n",
    );
    assert!(events(&dir, "analyze").is_empty());
    let out = mtsim_plain(&dir, &["analyze", "s.toml"]);
    assert!(String::from_utf8_lossy(&out.stdout)
        .contains("kinematic chain: no poles or solution switches\n"));
}
