//! ISO 230-7 location errors on a general chain's rotaries (the kinematic-chains spec's
//! last section, shared/spec/geometric-errors.md): each rotary line moved by
//! (EX0R, EY0R, EZ0R) µm and turned by (EA0R, EB0R, EC0R) µrad, written out here from the
//! spec (`p + e`, `unit(d + ε × d)`, Rodrigues) and compared with `simulate`'s ball-bar
//! trace on the head machines within 0.01 µm; and one closed form, an offset of the
//! nutating B line.

use crate::common;

use std::path::Path;

use common::{mtsim_plain, scratch};
use mtsim::input::machine::Machine;
use mtsim::{Axis, AxisVec};

use super::chain_cone::{apply, Joint, Spec};
use super::geometric_errors::{add, cross, norm, scale, sub, V};

const L: f64 = 100.0;

/// The machine `rel` with `errors` (key, value) in `[location_errors]`, written into `dir`.
fn machine_with(dir: &Path, rel: &str, errors: &[(&str, f64)]) -> String {
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)).unwrap();
    let mut table = String::from("\n[location_errors]\n");
    for (k, v) in errors {
        table.push_str(&format!("{k} = {v}\n"));
    }
    let path = dir.join("machine.toml");
    std::fs::write(&path, text + &table).unwrap();
    path.display().to_string()
}

/// Runs the 15/10 cone on `machine` (O = `center`) and returns each sample's actual axes
/// and deviation (µm).
fn trace(dir: &Path, machine: &str, center: V) -> Vec<(AxisVec, f64)> {
    std::fs::write(
        dir.join("s.toml"),
        format!(
            "machine = {machine:?}\n[program.cone]\nhalf_apex_deg = 15.0\ninclination_deg = 10.0\ncenter_mm = {center:?}\nballbar_length_mm = {L}\n[check]\ncollisions = false\n"
        ),
    )
    .unwrap();
    let out = mtsim_plain(dir, &["simulate", "s.toml", "-o", "run", "--no-timing"]);
    assert!(
        matches!(out.status.code(), Some(0 | 1)),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let m = Machine::load(Path::new(machine)).unwrap();
    let text = std::fs::read_to_string(dir.join("run/trace.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let axes: Vec<(Axis, usize)> = m
        .axes()
        .iter()
        .map(|a| (*a, col(&format!("{a}_act_{}", a.unit()))))
        .collect();
    let dev = col("deviation_um");
    lines
        .map(|row| {
            let f: Vec<&str> = row.split(',').collect();
            let mut q = AxisVec::ZERO;
            for (a, i) in &axes {
                q[*a] = f[*i].parse().unwrap();
            }
            (q, f[dev].parse().unwrap())
        })
        .collect()
}

/// The spec's actual line of a rotary: its point moved by e (µm), its direction turned by
/// ε (µrad) about the machine axes, `unit(d + ε × d)`.
fn errored(joint: &Joint, e_um: V, eps_urad: V) -> Joint {
    let (axis, rotary, d, p) = *joint;
    if !rotary {
        return *joint;
    }
    let u = add(d, cross(scale(eps_urad, 1e-6), d));
    (
        axis,
        true,
        scale(u, 1.0 / norm(u)),
        add(p, scale(e_um, 1e-3)),
    )
}

/// `simulate`'s deviation on a head machine with errors on both rotaries equals the
/// written-out actual chain's `|tool − ball| − L` at the trace's actual axes.
#[test]
fn the_ball_bar_of_a_head_machine_reads_its_rotaries_location_errors() {
    let cases: [(&str, [(&str, f64); 6], [(Axis, V, V); 2]); 2] = [
        (
            "machines/head-table-b45-c.toml",
            [
                ("EX0B_um", 12.0),
                ("EY0B_um", -7.0),
                ("EA0B_urad", 40.0),
                ("EC0B_urad", -25.0),
                ("EX0C_um", 9.0),
                ("EB0C_urad", 30.0),
            ],
            [
                (Axis::B, [12.0, -7.0, 0.0], [40.0, 0.0, -25.0]),
                (Axis::C, [9.0, 0.0, 0.0], [0.0, 30.0, 0.0]),
            ],
        ),
        (
            "machines/fork-head-ca.toml",
            [
                ("EY0A_um", 15.0),
                ("EZ0A_um", -10.0),
                ("EB0A_urad", 50.0),
                ("EX0C_um", 8.0),
                ("EY0C_um", 6.0),
                ("EA0C_urad", -35.0),
            ],
            [
                (Axis::A, [0.0, 15.0, -10.0], [0.0, 50.0, 0.0]),
                (Axis::C, [8.0, 6.0, 0.0], [-35.0, 0.0, 0.0]),
            ],
        ),
    ];
    for (rel, keys, errors) in cases {
        let name = Path::new(rel).file_stem().unwrap().to_str().unwrap();
        let dir = scratch("chain-location", name);
        let machine = machine_with(&dir, rel, &keys);
        let nominal = Machine::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)).unwrap();
        let mut spec = Spec::of(&nominal.kinematics.chain().unwrap());
        for (axis, e, eps) in errors {
            for joint in spec.table.iter_mut().chain(spec.head.iter_mut()) {
                if joint.0 == axis {
                    *joint = errored(joint, e, eps);
                }
            }
        }
        let center = [0.0, 0.0, 0.0];
        let (mut worst, mut largest) = (0.0f64, 0.0f64);
        let samples = trace(&dir, &machine, center);
        for (q, got) in &samples {
            let (tool, _) = spec.tool_in_machine(q);
            let ball = apply(&spec.table, q, center, false);
            let expected = (norm(sub(tool, ball)) - L) * 1e3;
            worst = worst.max((got - expected).abs());
            largest = largest.max(expected.abs());
        }
        eprintln!(
            "{name}: {} samples, deviation up to {largest:.2} um, worst difference {worst:.2e} um",
            samples.len()
        );
        assert!(samples.len() > 1000);
        // The errors show: several µm, far above the servo's share on this slow cone.
        assert!(
            largest > 5.0,
            "{name}: the errors do not show ({largest} um)"
        );
        assert!(worst < 0.01, "{name}: {worst} um");
    }
}

/// Closed form: the nutating B line moved by e along X (perpendicular to its direction
/// d = (0, s, s), s = 1/√2) moves the tool by δ(B) = (I − Rot(d, B)) e =
/// e (1 − cos B, −s sin B, s sin B), |δ| = 2 e sin(B/2) (Rodrigues with d·e = 0,
/// d × e = (0, s e, −s e)). The C table's errors are zero, so the deviation changes from
/// the error-free run's by |v + δ| − |v|, v the error-free bar vector: the same servo
/// motion (location errors act after it) read through the two chains.
#[test]
fn an_offset_nutating_b_line_moves_the_tool_by_twice_its_offset_times_sin_half_b() {
    let rel = "machines/head-table-b45-c.toml";
    let e_um = 20.0;
    let dir = scratch("chain-location", "b-offset");
    let errored_dir = dir.join("errored");
    std::fs::create_dir_all(&errored_dir).unwrap();
    let plain = machine_with(&dir, rel, &[]);
    let with_offset = machine_with(&errored_dir, rel, &[("EX0B_um", e_um)]);
    let center = [0.0, 0.0, 0.0];
    let nominal = trace(&dir, &plain, center);
    let offset = trace(&errored_dir, &with_offset, center);
    assert_eq!(nominal.len(), offset.len());
    let spec = Spec::of(
        &Machine::load(Path::new(&plain))
            .unwrap()
            .kinematics
            .chain()
            .unwrap(),
    );
    let s = 0.5f64.sqrt();
    let e = e_um * 1e-3;
    let (mut worst, mut b_range) = (0.0f64, (f64::INFINITY, f64::NEG_INFINITY));
    for ((q, dev0), (q1, dev1)) in nominal.iter().zip(&offset) {
        assert_eq!(q, q1, "the servo motion does not depend on location errors");
        let (sb, cb) = q[Axis::B].to_radians().sin_cos();
        let delta = [e * (1.0 - cb), -e * s * sb, e * s * sb];
        assert!(
            (norm(delta) - 2.0 * e * (0.5 * q[Axis::B].to_radians()).sin().abs()).abs() < 1e-12
        );
        let (tool, _) = spec.tool_in_machine(q);
        let v = sub(tool, apply(&spec.table, q, center, false));
        let expected_change_um = (norm(add(v, delta)) - norm(v)) * 1e3;
        worst = worst.max(((dev1 - dev0) - expected_change_um).abs());
        b_range = (b_range.0.min(q[Axis::B]), b_range.1.max(q[Axis::B]));
    }
    eprintln!("B offset: B over {b_range:?} deg, worst difference {worst:.2e} um");
    assert!(worst < 0.01, "{worst} um");
}

/// A component along a rotary's own line is refused (it moves the line along itself); a
/// named layout keeps the parameters of geometric-errors.md only.
#[test]
fn a_location_error_along_its_own_line_is_refused() {
    let dir = scratch("chain-location", "refused");
    let along = machine_with(&dir, "machines/head-table-b45-c.toml", &[("EZ0C_um", 5.0)]);
    let err = Machine::load(Path::new(&along)).unwrap_err().to_string();
    assert!(err.contains("EZ0C_um") && err.contains("along"), "{err}");
    // The nutating B's line is not along Y: EY0B is a real error there.
    let b = machine_with(&dir, "machines/head-table-b45-c.toml", &[("EY0B_um", 5.0)]);
    assert!(Machine::load(Path::new(&b)).is_ok());
    let trt = machine_with(&dir, "machines/trt-bc.toml", &[("EY0B_um", 5.0)]);
    let err = Machine::load(Path::new(&trt)).unwrap_err().to_string();
    assert!(err.contains("unknown location error"), "{err}");
}
