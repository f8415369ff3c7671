//! Poles as controls handle them (the kinematic-chains spec): a cone whose tool direction
//! passes the pole (half apex angle = inclination = 15°, so at θ = 180° the tool stands
//! along the C axis) on the head-table and the nutating-table machine, checked with the
//! spec's forward kinematics written out in chain_cone.rs and the cone geometry in plain
//! numbers here; `analyze` against the written program read back here; a program standing
//! on the pole for 200 blocks; trt-ac written as a chain with A's point anywhere on A's line.

use crate::common;

use std::path::Path;

use common::{mtsim_plain, scratch, stdout_json};
use mtsim::{Axis, AxisVec};

use super::chain_cone::load;
use super::geometric_errors::{dot, norm, sub, V};

/// The cone through the pole: α = β = 15°, L = 100 mm.
const ALPHA: f64 = 15.0;
const BETA: f64 = 15.0;
const L: f64 = 100.0;

fn cone_scenario(dir: &Path, machine: &str, center_z: f64) {
    let m = Path::new(env!("CARGO_MANIFEST_DIR")).join(machine);
    std::fs::write(
        dir.join("s.toml"),
        format!(
            "machine = {:?}\n[program.cone]\nhalf_apex_deg = {ALPHA}\ninclination_deg = {BETA}\ncenter_mm = [0.0, 0.0, {center_z}]\nballbar_length_mm = {L}\nsegments = 360\nfeed_mm_min = 1000.0\n",
            m.display().to_string()
        ),
    )
    .unwrap();
}

/// A workpiece point in the cone frame: Ry(β) (p − O).
fn in_cone_frame(p: V, o: V) -> V {
    let (s, c) = BETA.to_radians().sin_cos();
    let p = sub(p, o);
    [c * p[0] + s * p[2], p[1], -s * p[0] + c * p[2]]
}

/// How far the tool ball at workpiece point `tip` lies from the test circle, mm (the
/// larger of the radial and the height error), and its θ on it, deg.
fn off_the_circle(tip: V, o: V) -> (f64, f64) {
    let (sa, ca) = ALPHA.to_radians().sin_cos();
    let p = in_cone_frame(tip, o);
    let radial = (p[0].hypot(p[1]) - L * ca).abs();
    let height = (p[2] - L * sa).abs();
    (
        radial.max(height),
        p[1].atan2(p[0]).to_degrees().rem_euclid(360.0),
    )
}

/// The axis words of each G00/G01 line of a program text, with its F.
fn blocks(text: &str) -> Vec<(AxisVec, Option<f64>)> {
    let mut q = AxisVec::ZERO;
    text.lines()
        .filter(|l| l.starts_with("G00") || l.starts_with("G01"))
        .map(|l| {
            let code = l.split('(').next().unwrap();
            let mut f = None;
            for word in code.split_whitespace().skip(1) {
                let (letter, value) = word.split_at(1);
                let v: f64 = value.parse().unwrap();
                match letter {
                    "F" => f = Some(v),
                    l => q[Axis::from_letter(l.chars().next().unwrap()).unwrap()] = v,
                }
            }
            (q, f)
        })
        .collect()
}

#[test]
fn the_cone_through_the_pole_takes_the_other_branch_and_keeps_the_tip_on_the_path() {
    for (machine, center_z) in [
        ("machines/head-table-b45-c.toml", 0.0),
        ("machines/nutating-table-b45-c.toml", 50.0),
    ] {
        let name = Path::new(machine).file_stem().unwrap().to_str().unwrap();
        let dir = scratch("pole-passage", name);
        cone_scenario(&dir, machine, center_z);
        let o = [0.0, 0.0, center_z];
        let (_, spec) = load(machine);
        // The written program: at every block end the ball on the circle (within the words'
        // 0.1 µm rounding), the tool toward the apex within the pole tolerance (0.1°) and,
        // away from the pole, within 0.01°.
        let out = mtsim_plain(&dir, &["cone", "s.toml"]);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8(out.stdout).unwrap();
        let program = blocks(&text);
        let (sa, _) = ALPHA.to_radians().sin_cos();
        let apex = [0.0, 0.0, L / sa];
        let mut worst_c_step = 0.0f64;
        for (k, (q, _)) in program.iter().enumerate() {
            let (tip, t) = spec.tool_in_workpiece(q);
            let (off, theta) = off_the_circle(tip, o);
            assert!(off < 2e-3, "{name} block {k}: ball {off} mm off the circle");
            let toward = sub(apex, in_cone_frame(tip, o));
            let t_cone = in_cone_frame(t, [0.0; 3]);
            let angle = (dot(toward, t_cone) / norm(toward) / norm(t_cone))
                .clamp(-1.0, 1.0)
                .acos()
                .to_degrees();
            let near_pole = (theta - 180.0).abs() < 2.0;
            let limit = if near_pole { 0.1 } else { 0.01 };
            assert!(
                angle < limit,
                "{name} block {k} θ {theta:.3}: tool {angle} deg off"
            );
            if k > 0 {
                worst_c_step = worst_c_step.max((q[Axis::C] - program[k - 1].0[Axis::C]).abs());
            }
        }
        // C turns by about a degree a block, never 180° (it held through the pole: the 15°
        // cone's tool turns about C at 0.5 to 1.3 deg per deg of θ).
        assert!(worst_c_step < 2.0, "{name}: C step {worst_c_step} deg");
        // B passes through 0 (the other branch) rather than C swinging.
        let b: Vec<f64> = program.iter().map(|(q, _)| q[Axis::B]).collect();
        assert!(
            b.iter().any(|v| *v > 40.0) && b.iter().any(|v| *v < -40.0),
            "{name}: B {b:?}"
        );

        // The run: G under 60 µm, the ball within 20 µm of the path through the passage.
        let out = mtsim_plain(
            &dir,
            &[
                "simulate",
                "s.toml",
                "-o",
                "run",
                "--no-timing",
                "--json",
                "--html",
            ],
        );
        assert!(
            matches!(out.status.code(), Some(0) | Some(1)),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let summary = stdout_json(&out);
        let g = summary["ballbar"]["circular_deviation_um"]
            .as_f64()
            .unwrap();
        assert!(g < 60.0, "{name}: G = {g} µm");
        let trace = common::CsvTable::read(&dir.join("run/trace.csv"));
        let act = |a: &str| {
            trace.col(&format!(
                "{a}_act_{}",
                if a.len() == 1 && "XYZ".contains(a) {
                    "mm"
                } else {
                    "deg"
                }
            ))
        };
        let cols: Vec<(Axis, usize)> = ["X", "Y", "Z", "B", "C"]
            .iter()
            .map(|a| {
                (
                    Axis::from_letter(a.chars().next().unwrap()).unwrap(),
                    act(a),
                )
            })
            .collect();
        let (mut rows, mut worst) = (0, 0.0f64);
        for row in &trace.rows {
            let mut q = AxisVec::ZERO;
            for (a, i) in &cols {
                q[*a] = row[*i];
            }
            let (tip, _) = spec.tool_in_workpiece(&q);
            let (off, theta) = off_the_circle(tip, o);
            if (theta - 180.0).abs() < 5.0 {
                worst = worst.max(off);
                rows += 1;
            }
        }
        assert!(rows > 100, "{name}: {rows} rows through the passage");
        assert!(
            worst < 0.020,
            "{name}: the ball {} µm off the path",
            worst * 1e3
        );
        eprintln!(
            "{name}: G = {g:.2} µm, ball off the path within 5° of the pole {:.2} µm",
            worst * 1e3
        );

        // The passage is reported once, C holding (turning by about a block's worth).
        let events = summary["chain_events"].as_array().expect("chain events");
        let poles: Vec<_> = events.iter().filter(|e| e["kind"] == "pole").collect();
        assert_eq!(poles.len(), 1, "{name}: {events:?}");
        assert!(
            poles[0]["swing_deg"].as_f64().unwrap().abs() < 2.0,
            "{name}: {poles:?}"
        );
        assert!(
            events.iter().all(|e| e["kind"] != "switch"),
            "{name}: {events:?}"
        );
    }
}

#[test]
fn without_travel_on_both_sides_of_zero_the_cone_through_the_pole_is_refused_naming_it() {
    let dir = scratch("pole-passage", "refused");
    let m = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/head-table-b45-c.toml"),
    )
    .unwrap();
    // B from 0 to 180 only: the other branch (B < 0) is out of travel.
    let m = m.replacen("min = -180.0", "min = 0.0", 1);
    assert!(m.contains("min = 0.0"));
    std::fs::write(dir.join("m.toml"), m).unwrap();
    std::fs::write(
        dir.join("s.toml"),
        "machine = \"m.toml\"\n[program.cone]\nhalf_apex_deg = 15.0\ninclination_deg = 15.0\ncenter_mm = [0.0, 0.0, 0.0]\nballbar_length_mm = 100.0\nsegments = 360\nfeed_mm_min = 1000.0\n",
    )
    .unwrap();
    for args in [
        &["cone", "s.toml"][..],
        &["simulate", "s.toml", "-o", "run", "--no-timing"],
    ] {
        let out = mtsim_plain(&dir, args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("passes the pole of B") && err.contains("tool along C"),
            "{err}"
        );
        assert!(!dir.join("run").exists(), "nothing written");
    }
}

#[test]
fn analyze_reports_the_written_program_of_the_cone_through_the_pole() {
    let dir = scratch("pole-passage", "analyze");
    cone_scenario(&dir, "machines/head-table-b45-c.toml", 0.0);
    let out = mtsim_plain(&dir, &["cone", "s.toml"]);
    let program = blocks(&String::from_utf8(out.stdout).unwrap());
    let analysis = stdout_json(&mtsim_plain(&dir, &["analyze", "s.toml", "--json"]));
    let axes = ["X", "Y", "Z", "B", "C"];
    for name in axes {
        let a = Axis::from_letter(name.chars().next().unwrap()).unwrap();
        let values: Vec<f64> = program.iter().map(|(q, _)| q[a]).collect();
        let lo = values.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = values.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let got = &analysis["axes"][name];
        let (min, max) = (got["min"].as_f64().unwrap(), got["max"].as_f64().unwrap());
        assert!(
            (min - lo).abs() < 0.01 && (max - hi).abs() < 0.01,
            "{name}: {min}..{max} against {lo}..{hi}"
        );
        // Peak speed of the written blocks: |Δa| F / sqrt(Σ Δ²) (G94, deg counted as mm).
        let mut peak = 0.0f64;
        for w in program.windows(2) {
            let (q0, (q1, f)) = (w[0].0, w[1]);
            let Some(f) = f else { continue };
            let d: Vec<f64> = axes
                .iter()
                .map(|n| {
                    let b = Axis::from_letter(n.chars().next().unwrap()).unwrap();
                    q1[b] - q0[b]
                })
                .collect();
            let norm = d.iter().map(|x| x * x).sum::<f64>().sqrt();
            if norm > 0.0 {
                peak = peak.max((q1[a] - q0[a]).abs() * f / norm);
            }
        }
        let speed = got["peak_speed_per_min"].as_f64().unwrap();
        assert!(
            (speed - peak).abs() <= 1e-3 * peak + 1e-6,
            "{name}: peak {speed} against {peak}"
        );
    }
    // Y runs over the circle's side of the path (not 0 mm), at far below 690,000 mm/min.
    let y = &analysis["axes"]["Y"];
    assert!(y["range"].as_f64().unwrap() > 90.0, "{y}");
}

#[test]
fn a_program_standing_on_the_pole_for_200_blocks_reports_it_once() {
    let dir = scratch("pole-passage", "vertical");
    // Fork head, A = 0 throughout: the tool along C's line at every block end.
    let mut program = String::from("G21 G90 G94 G17\nG00 X0 Y0 Z100 A0 C0\n");
    for k in 0..200 {
        let t = k as f64 * 0.05;
        program.push_str(&format!(
            "G01 X{:.4} Y{:.4} F1000\n",
            50.0 * t.cos(),
            50.0 * t.sin()
        ));
    }
    program.push_str("M30\n");
    std::fs::write(dir.join("p.nc"), program).unwrap();
    let m = Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/fork-head-ca.toml");
    std::fs::write(
        dir.join("s.toml"),
        format!(
            "machine = {:?}\n[program]\nfile = \"p.nc\"\n[check]\ncollisions = false\n",
            m.display().to_string()
        ),
    )
    .unwrap();
    for command in ["analyze", "check"] {
        let out = mtsim_plain(&dir, &[command, "s.toml", "--json"]);
        let v = stdout_json(&out);
        let events = v["chain_events"].as_array().unwrap();
        assert_eq!(events.len(), 1, "{command}: {events:?}");
        // Lines 2 (the G00) to 202 (the last G01) stand on the pole.
        assert_eq!(
            (events[0]["line"].as_u64(), events[0]["last_line"].as_u64()),
            (Some(2), Some(202))
        );
        assert_eq!(
            events[0]["message"],
            "lines 2..202: pole of A (tool along C): C holds"
        );
        let text = mtsim_plain(&dir, &[command, "s.toml"]);
        let text = String::from_utf8_lossy(&text.stdout);
        assert_eq!(text.matches("pole of A").count(), 1, "{text}");
    }
}

#[test]
fn trt_ac_as_a_chain_takes_one_branch_wherever_a_point_sits_on_its_line() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let named = std::fs::read_to_string(root.join("machines/trt-ac.toml")).unwrap();
    let chain = |a_point: [f64; 3], c_point: [f64; 3]| {
        let mut out = String::new();
        for line in named.lines() {
            if line.starts_with("kinematics = ") || line.starts_with("pivot_mm = ") {
                continue;
            }
            out.push_str(line);
            out.push('\n');
            match line.trim() {
                "[axes.A]" => out.push_str(&format!(
                    "direction = [1.0, 0.0, 0.0]\npoint_mm = {a_point:?}\n"
                )),
                "[axes.C]" => out.push_str(&format!(
                    "direction = [0.0, 0.0, 1.0]\npoint_mm = {c_point:?}\n"
                )),
                _ => {}
            }
        }
        out.push_str("\n[kinematics]\ntable = [\"A\", \"C\"]\nhead = [\"X\", \"Y\", \"Z\"]\n");
        out
    };
    let run = |machine: &str, case: &str| {
        let dir = scratch("pole-passage", case);
        std::fs::write(dir.join("m.toml"), machine).unwrap();
        std::fs::write(
            dir.join("s.toml"),
            format!("machine = \"m.toml\"\n{}", common::CONE_15_10),
        )
        .unwrap();
        let program = String::from_utf8(mtsim_plain(&dir, &["cone", "s.toml"]).stdout).unwrap();
        let out = mtsim_plain(
            &dir,
            &["simulate", "s.toml", "-o", "run", "--no-timing", "--json"],
        );
        let g = stdout_json(&out)["ballbar"]["circular_deviation_um"]
            .as_f64()
            .unwrap();
        (blocks(&program), g)
    };
    let (reference, g_named) = run(&named, "named");
    // The 15/10 cone on the tilt ≥ 0 branch: A from α − β = 5° to α + β = 25°.
    let a: Vec<f64> = reference.iter().map(|(q, _)| q[Axis::A]).collect();
    let a_max = a.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let a_min = a.iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(
        (a_max - 25.0).abs() < 1e-3 && (a_min - 5.0).abs() < 0.05,
        "A {a_min}..{a_max}"
    );
    for (k, (a_point, c_point)) in [
        ([0.0, 0.0, 0.0], [0.0, 0.0, 0.0]),
        ([-80.0, 0.0, 0.0], [0.0, 0.0, 0.0]),
        ([37.5, 0.0, 0.0], [0.0, 0.0, 0.0]),
        ([250.0, 0.0, 0.0], [0.0, 0.0, -120.0]),
        ([0.0, 0.0, 0.0], [0.0, 0.0, 300.0]),
    ]
    .into_iter()
    .enumerate()
    {
        let (blocks, g) = run(&chain(a_point, c_point), &format!("chain-{k}"));
        assert_eq!(blocks.len(), reference.len());
        for ((q, _), (r, _)) in blocks.iter().zip(&reference) {
            assert_eq!(q[Axis::A], r[Axis::A], "A at {a_point:?}, C at {c_point:?}");
        }
        assert_eq!(g, g_named, "G at A {a_point:?}, C {c_point:?}");
    }
}

#[test]
fn the_pole_tolerance_is_read_and_checked_once() {
    let dir = scratch("pole-passage", "tolerance");
    let m = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/head-table-b45-c.toml"),
    )
    .unwrap();
    for (value, ok) in [
        ("0.5", true),
        ("0.0", false),
        ("-1.0", false),
        ("90.0", false),
    ] {
        let text = m.replacen(
            "tool_direction = [0.0, 0.0, 1.0]",
            &format!("tool_direction = [0.0, 0.0, 1.0]\npole_tolerance_deg = {value}"),
            1,
        );
        std::fs::write(dir.join("m.toml"), text).unwrap();
        cone_scenario(&dir, "machines/head-table-b45-c.toml", 0.0);
        let s = std::fs::read_to_string(dir.join("s.toml")).unwrap();
        let s = s.replacen(
            &format!(
                "{:?}",
                Path::new(env!("CARGO_MANIFEST_DIR"))
                    .join("machines/head-table-b45-c.toml")
                    .display()
                    .to_string()
            ),
            "\"m.toml\"",
            1,
        );
        std::fs::write(dir.join("s.toml"), s).unwrap();
        let out = mtsim_plain(&dir, &["cone", "s.toml"]);
        let err = String::from_utf8_lossy(&out.stderr);
        if ok {
            assert_eq!(out.status.code(), Some(0), "{value}: {err}");
        } else {
            assert_eq!(out.status.code(), Some(2), "{value}: {err}");
            assert!(
                err.contains("pole_tolerance_deg") && err.contains("m.toml"),
                "{value}: {err}"
            );
        }
    }
}
